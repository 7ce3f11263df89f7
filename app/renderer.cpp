// OpenGL implementation of pba::DebugDraw: queues per frame, instanced draws per mesh.
#include "renderer.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <imgui.h>

#include "camera.h"
#include "gl.h"
#include "shaders.h"

namespace pba::app {

namespace {

constexpr float kPi = 3.14159265358979f;

// compile one shader stage; on failure append the info log to `error`
unsigned compile(GLenum type, const char* src, std::string* error) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    *error += std::string("shader compile failed: ") + log;
    glDeleteShader(s);
    return 0;
  }
  return s;
}

// link a program from a vertex, optional geometry and fragment shader
unsigned link(const char* vs, const char* gs, const char* fs, std::string* error) {
  const GLuint v = compile(GL_VERTEX_SHADER, vs, error);
  const GLuint g = gs ? compile(GL_GEOMETRY_SHADER, gs, error) : 0;
  const GLuint f = compile(GL_FRAGMENT_SHADER, fs, error);
  if (!v || !f || (gs && !g)) return 0;
  const GLuint p = glCreateProgram();
  glAttachShader(p, v);
  if (g) glAttachShader(p, g);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  if (g) glDeleteShader(g);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    *error += std::string("program link failed: ") + log;
    glDeleteProgram(p);
    return 0;
  }
  return p;
}

// append a vertex (position, normal) to an interleaved float array
void vert(std::vector<float>& v, glm::vec3 p, glm::vec3 n) {
  v.insert(v.end(), {p.x, p.y, p.z, n.x, n.y, n.z});
}

// unit sphere: latitude-longitude grid
void make_sphere(std::vector<float>& v, std::vector<unsigned>& idx) {
  const int slices = 28, stacks = 16;
  for (int i = 0; i <= stacks; ++i) {
    const float th = kPi * i / stacks;
    for (int j = 0; j <= slices; ++j) {
      const float ph = 2 * kPi * j / slices;
      const glm::vec3 p{std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)};
      vert(v, p, p);
    }
  }
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const unsigned a = i * (slices + 1) + j, b = a + slices + 1;
      idx.insert(idx.end(), {a, a + 1, b, b, a + 1, b + 1});
    }
}

// cube with half extents 1: four vertices per face for flat normals
void make_cube(std::vector<float>& v, std::vector<unsigned>& idx) {
  const glm::vec3 n[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int f = 0; f < 6; ++f) {
    const glm::vec3 a = n[f];
    const glm::vec3 u = std::abs(a.y) > 0.5f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    const glm::vec3 w = glm::cross(a, u);
    const unsigned base = static_cast<unsigned>(v.size() / 6);
    vert(v, a - u - w, a);
    vert(v, a + u - w, a);
    vert(v, a + u + w, a);
    vert(v, a - u + w, a);
    idx.insert(idx.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
}

// open cylinder of radius 1 along y from -1 to 1 (capsule body)
void make_cylinder(std::vector<float>& v, std::vector<unsigned>& idx) {
  const int slices = 28;
  for (int j = 0; j <= slices; ++j) {
    const float ph = 2 * kPi * j / slices;
    const glm::vec3 n{std::cos(ph), 0, std::sin(ph)};
    vert(v, n + glm::vec3(0, -1, 0), n);
    vert(v, n + glm::vec3(0, 1, 0), n);
  }
  for (unsigned j = 0; j < static_cast<unsigned>(slices); ++j) {
    const unsigned a = 2 * j;
    idx.insert(idx.end(), {a, a + 1, a + 2, a + 2, a + 1, a + 3});
  }
}

// cone of radius 1 from y = 0 (base, capped) to the apex at y = 1 (arrow heads)
void make_cone(std::vector<float>& v, std::vector<unsigned>& idx) {
  const int slices = 24;
  const float s = 1 / std::sqrt(2.0f);
  for (int j = 0; j <= slices; ++j) {
    const float ph = 2 * kPi * j / slices;
    const glm::vec3 r{std::cos(ph), 0, std::sin(ph)};
    const glm::vec3 n = glm::vec3(r.x * s, s, r.z * s);
    vert(v, r, n);
    vert(v, glm::vec3(0, 1, 0), n);
  }
  for (unsigned j = 0; j < static_cast<unsigned>(slices); ++j) {
    const unsigned a = 2 * j;
    idx.insert(idx.end(), {a, a + 1, a + 2});
  }
  // base disc
  const unsigned c = static_cast<unsigned>(v.size() / 6);
  vert(v, glm::vec3(0), glm::vec3(0, -1, 0));
  for (int j = 0; j <= slices; ++j) {
    const float ph = 2 * kPi * j / slices;
    vert(v, glm::vec3(std::cos(ph), 0, std::sin(ph)), glm::vec3(0, -1, 0));
  }
  for (unsigned j = 0; j < static_cast<unsigned>(slices); ++j) idx.insert(idx.end(), {c, c + 1 + j, c + 2 + j});
}

// unit quad in the xz plane, normal +y (planes, ground, shadows)
void make_quad(std::vector<float>& v, std::vector<unsigned>& idx) {
  const glm::vec3 n{0, 1, 0};
  vert(v, {-1, 0, -1}, n);
  vert(v, {1, 0, -1}, n);
  vert(v, {1, 0, 1}, n);
  vert(v, {-1, 0, 1}, n);
  idx.insert(idx.end(), {0, 2, 1, 0, 3, 2});
}

// rotation taking +y to the unit vector d
glm::quat from_y(const glm::vec3& d) {
  const glm::vec3 y{0, 1, 0};
  const float c = glm::dot(y, d);
  if (c > 0.99999f) return glm::quat(1, 0, 0, 0);
  if (c < -0.99999f) return glm::quat(0, 1, 0, 0);  // 180 degrees about x
  const glm::vec3 axis = glm::normalize(glm::cross(y, d));
  return glm::angleAxis(std::acos(std::clamp(c, -1.0f, 1.0f)), axis);
}

glm::vec3 f3(const Vec3& v) { return glm::vec3(v); }

}  // namespace

Renderer::Renderer() = default;

Renderer::~Renderer() {
  if (!ready_) return;
  for (auto& m : meshes_) {
    glDeleteBuffers(1, &m.vbo);
    glDeleteBuffers(1, &m.ibo);
    glDeleteBuffers(1, &m.instance_vbo);
    glDeleteVertexArrays(1, &m.vao);
  }
  glDeleteBuffers(1, &line_vbo_);
  glDeleteBuffers(1, &point_vbo_);
  glDeleteVertexArrays(1, &line_vao_);
  glDeleteVertexArrays(1, &point_vao_);
  glDeleteVertexArrays(1, &empty_vao_);
  glDeleteBuffers(1, &triangle_vbo_);
  glDeleteVertexArrays(1, &triangle_vao_);
  for (unsigned p : {mesh_program_, line_program_, point_program_, ground_program_, sky_program_, shadow_program_,
                     triangle_program_})
    glDeleteProgram(p);
}

bool Renderer::init(std::string* error) {
  // programs
  mesh_program_ = link(shaders::kMeshVs, nullptr, shaders::kMeshFs, error);
  line_program_ = link(shaders::kLineVs, shaders::kLineGs, shaders::kLineFs, error);
  point_program_ = link(shaders::kPointVs, nullptr, shaders::kPointFs, error);
  ground_program_ = link(shaders::kGroundVs, nullptr, shaders::kGroundFs, error);
  sky_program_ = link(shaders::kSkyVs, nullptr, shaders::kSkyFs, error);
  shadow_program_ = link(shaders::kShadowVs, nullptr, shaders::kShadowFs, error);
  triangle_program_ = link(shaders::kTriangleVs, nullptr, shaders::kMeshFs, error);
  if (!mesh_program_ || !line_program_ || !point_program_ || !ground_program_ || !sky_program_ ||
      !shadow_program_ || !triangle_program_)
    return false;

  // meshes
  std::vector<float> v;
  std::vector<unsigned> i;
  make_sphere(v, i), build_mesh(kSphere, v, i), v.clear(), i.clear();
  make_cube(v, i), build_mesh(kCube, v, i), v.clear(), i.clear();
  make_cylinder(v, i), build_mesh(kCylinder, v, i), v.clear(), i.clear();
  make_cone(v, i), build_mesh(kCone, v, i), v.clear(), i.clear();
  make_quad(v, i), build_mesh(kQuad, v, i);

  // dynamic vertex streams for lines and points share one layout
  auto stream = [](unsigned* vao, unsigned* vbo) {
    glGenVertexArrays(1, vao);
    glGenBuffers(1, vbo);
    glBindVertexArray(*vao);
    glBindBuffer(GL_ARRAY_BUFFER, *vbo);
    const GLsizei stride = sizeof(LineVertex);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(LineVertex, pos)));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(LineVertex, color)));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(LineVertex, width)));
  };
  stream(&line_vao_, &line_vbo_);
  stream(&point_vao_, &point_vbo_);
  // the triangle stream: position, normal, colour
  glGenVertexArrays(1, &triangle_vao_);
  glGenBuffers(1, &triangle_vbo_);
  glBindVertexArray(triangle_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, triangle_vbo_);
  {
    const GLsizei stride = sizeof(TriVertex);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(TriVertex, pos)));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(TriVertex, nrm)));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(TriVertex, color)));
  }
  glGenVertexArrays(1, &empty_vao_);
  glBindVertexArray(0);
  ready_ = true;
  return true;
}

void Renderer::build_mesh(Mesh m, const std::vector<float>& vertices, const std::vector<unsigned>& indices) {
  MeshBuffers& b = meshes_[m];
  glGenVertexArrays(1, &b.vao);
  glGenBuffers(1, &b.vbo);
  glGenBuffers(1, &b.ibo);
  glGenBuffers(1, &b.instance_vbo);
  glBindVertexArray(b.vao);
  // per-vertex position and normal
  glBindBuffer(GL_ARRAY_BUFFER, b.vbo);
  glBufferData(GL_ARRAY_BUFFER, vertices.size() * sizeof(float), vertices.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<void*>(3 * sizeof(float)));
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, b.ibo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, indices.size() * sizeof(unsigned), indices.data(), GL_STATIC_DRAW);
  // per-instance position, scale, rotation, colour
  glBindBuffer(GL_ARRAY_BUFFER, b.instance_vbo);
  const GLsizei stride = sizeof(Instance);
  const std::size_t offs[4] = {offsetof(Instance, pos), offsetof(Instance, scale), offsetof(Instance, quat),
                               offsetof(Instance, color)};
  const int sizes[4] = {3, 3, 4, 4};
  for (int a = 0; a < 4; ++a) {
    glEnableVertexAttribArray(2 + a);
    glVertexAttribPointer(2 + a, sizes[a], GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offs[a]));
    glVertexAttribDivisor(2 + a, 1);
  }
  b.index_count = static_cast<int>(indices.size());
  glBindVertexArray(0);
}

void Renderer::begin_frame() {
  for (auto& q : opaque_) q.clear();
  for (auto& q : transparent_) q.clear();
  shadows_.clear();
  lines_.clear();
  points_.clear();
  labels_.clear();
  triangles_.clear();
  transparent_triangles_.clear();
}

void Renderer::add_instance(Mesh m, const glm::vec3& pos, const glm::vec3& scale, const glm::quat& q, Color c) {
  Instance in{{pos.x, pos.y, pos.z}, {scale.x, scale.y, scale.z}, {q.x, q.y, q.z, q.w}, {c.r, c.g, c.b, c.a}};
  (c.a < 0.999f ? transparent_[m] : opaque_[m]).push_back(in);
}

void Renderer::add_shadow(const glm::vec3& pos, float radius) {
  // shadows fade with height above the ground and vanish below it
  if (!style.ground || !style.shadows || pos.y < -radius) return;
  const float h = std::max(pos.y, 0.0f);
  const float strength = 0.45f * std::clamp(1.0f - h / (8.0f * radius + 4.0f), 0.0f, 1.0f);
  if (strength <= 0.01f) return;
  const float r = radius * (1.3f + 0.15f * h);
  shadows_.push_back(Instance{{pos.x, 0.002f, pos.z}, {r, 1, r}, {0, 0, 0, 1}, {0, 0, 0, strength}});
}

void Renderer::point(const Vec3& p, float size, Color c) {
  points_.push_back(LineVertex{{float(p.x), float(p.y), float(p.z)}, {c.r, c.g, c.b, c.a}, size});
}

void Renderer::line(const Vec3& a, const Vec3& b, Color c) { line(a, b, c, line_width_); }

void Renderer::line(const Vec3& a, const Vec3& b, Color c, float width_px) {
  lines_.push_back(LineVertex{{float(a.x), float(a.y), float(a.z)}, {c.r, c.g, c.b, c.a}, width_px});
  lines_.push_back(LineVertex{{float(b.x), float(b.y), float(b.z)}, {c.r, c.g, c.b, c.a}, width_px});
}

void Renderer::polyline(const std::vector<Vec3>& pts, Color c, float width_px) {
  for (std::size_t k = 1; k < pts.size(); ++k) line(pts[k - 1], pts[k], c, width_px);
}

void Renderer::sphere(const Vec3& center, double radius, Color c) {
  const float r = static_cast<float>(radius);
  add_instance(kSphere, f3(center), glm::vec3(r), glm::quat(1, 0, 0, 0), c);
  add_shadow(f3(center), r);
}

void Renderer::box(const Vec3& center, const Vec3& half, const Quat& rotation, Color c) {
  add_instance(kCube, f3(center), f3(half), glm::quat(rotation), c);
  add_shadow(f3(center), static_cast<float>(std::max(half.x, half.z)));
}

void Renderer::capsule(const Vec3& a, const Vec3& b, double radius, Color c) {
  const glm::vec3 fa = f3(a), fb = f3(b);
  const float r = static_cast<float>(radius);
  const glm::vec3 d = fb - fa;
  const float len = glm::length(d);
  // body cylinder, then the two end spheres
  if (len > 1e-6f)
    add_instance(kCylinder, 0.5f * (fa + fb), glm::vec3(r, 0.5f * len, r), from_y(d / len), c);
  add_instance(kSphere, fa, glm::vec3(r), glm::quat(1, 0, 0, 0), c);
  add_instance(kSphere, fb, glm::vec3(r), glm::quat(1, 0, 0, 0), c);
  add_shadow(0.5f * (fa + fb), r + 0.25f * len);
}

void Renderer::plane(const Vec3& normal, double offset, double half_size, Color c) {
  const glm::vec3 n = glm::normalize(f3(normal));
  const glm::vec3 center = n * static_cast<float>(offset);
  const float h = static_cast<float>(half_size);
  add_instance(kQuad, center, glm::vec3(h, 1, h), from_y(n), c);
  // outline so the patch reads even edge-on
  const glm::quat q = from_y(n);
  const glm::vec3 u = q * glm::vec3(h, 0, 0), w = q * glm::vec3(0, 0, h);
  const Color edge{c.r, c.g, c.b, 1.0f};
  const glm::vec3 corners[4] = {center - u - w, center + u - w, center + u + w, center - u + w};
  for (int k = 0; k < 4; ++k) line(Vec3(corners[k]), Vec3(corners[(k + 1) % 4]), edge, 1.5f);
}

void Renderer::arrow(const Vec3& from, const Vec3& to, double head, Color c) {
  const glm::vec3 a = f3(from), b = f3(to);
  const glm::vec3 d = b - a;
  const float len = glm::length(d);
  if (len < 1e-6f) return;
  const glm::vec3 dir = d / len;
  const float h = std::min(static_cast<float>(head), len);
  // shaft up to the base of the head, then a lit cone
  line(Vec3(a), Vec3(b - dir * h), c, std::max(line_width_, 2.5f));
  add_instance(kCone, b - dir * h, glm::vec3(0.35f * h, h, 0.35f * h), from_y(dir), c);
}

void Renderer::text(const Vec3& p, std::string_view s, Color c) { text(p, s, c, 1.0f, 0.0f); }

void Renderer::triangle(const Vec3& a, const Vec3& b, const Vec3& c, Color col) {
  // one flat normal for the three corners (push_triangle handles degenerate ones)
  const Vec3 n = glm::cross(b - a, c - a);
  const TriangleCorner v[3] = {{a, n, col}, {b, n, col}, {c, n, col}};
  push_triangle(v);
}

void Renderer::triangle(const TriangleCorner& a, const TriangleCorner& b, const TriangleCorner& c) {
  const TriangleCorner v[3] = {a, b, c};
  push_triangle(v);
}

void Renderer::push_triangle(const TriangleCorner (&v)[3]) {
  // a zero normal takes the face normal, a degenerate face points up (never NaN in the shader)
  glm::vec3 face = glm::cross(f3(v[1].p - v[0].p), f3(v[2].p - v[0].p));
  const float fl = glm::length(face);
  face = fl > 0 && std::isfinite(fl) ? face / fl : glm::vec3(0, 1, 0);
  const bool translucent = v[0].c.a < 0.999f || v[1].c.a < 0.999f || v[2].c.a < 0.999f;
  std::vector<TriVertex>& out = translucent ? transparent_triangles_ : triangles_;
  for (const TriangleCorner& k : v) {
    glm::vec3 n = f3(k.n);
    const float nl = glm::length(n);
    n = nl > 0 && std::isfinite(nl) ? n / nl : face;
    out.push_back(TriVertex{{float(k.p.x), float(k.p.y), float(k.p.z)}, {n.x, n.y, n.z}, {k.c.r, k.c.g, k.c.b, k.c.a}});
  }
}

void Renderer::shadow(const Vec3& center, double radius) { add_shadow(f3(center), static_cast<float>(radius)); }

void Renderer::draw_triangles(const std::vector<TriVertex>& list, const glm::vec3& eye, const glm::vec3& key,
                              const glm::vec3& fill) {
  if (list.empty()) return;
  // the solids' lighting, with the surface pushed back a little so lines on it win
  glUseProgram(triangle_program_);
  glUniformMatrix4fv(glGetUniformLocation(triangle_program_, "u_view_proj"), 1, GL_FALSE, glm::value_ptr(view_proj_));
  glUniform3fv(glGetUniformLocation(triangle_program_, "u_eye"), 1, glm::value_ptr(eye));
  glUniform3fv(glGetUniformLocation(triangle_program_, "u_key"), 1, glm::value_ptr(key));
  glUniform3fv(glGetUniformLocation(triangle_program_, "u_fill"), 1, glm::value_ptr(fill));
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.0f, 1.0f);
  glBindVertexArray(triangle_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, triangle_vbo_);
  glBufferData(GL_ARRAY_BUFFER, list.size() * sizeof(TriVertex), list.data(), GL_STREAM_DRAW);
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(list.size()));
  glDisable(GL_POLYGON_OFFSET_FILL);
}

void Renderer::text(const Vec3& p, std::string_view s, Color c, float scale, float align_x) {
  labels_.push_back(Label{p, std::string(s), c, scale, align_x});
}

void Renderer::draw_instances(Mesh m, const std::vector<Instance>& list) {
  if (list.empty()) return;
  const MeshBuffers& b = meshes_[m];
  glBindVertexArray(b.vao);
  glBindBuffer(GL_ARRAY_BUFFER, b.instance_vbo);
  glBufferData(GL_ARRAY_BUFFER, list.size() * sizeof(Instance), list.data(), GL_STREAM_DRAW);
  glDrawElementsInstanced(GL_TRIANGLES, b.index_count, GL_UNSIGNED_INT, nullptr, static_cast<GLsizei>(list.size()));
}

void Renderer::render(const Camera& camera, int width, int height) {
  viewport_ = glm::vec2(std::max(width, 1), std::max(height, 1));
  const glm::mat4 vp = camera.projection(viewport_.x / viewport_.y) * camera.view();
  view_proj_ = vp;
  const glm::vec3 eye = camera.eye();

  // statistics for the profiler
  stats_ = DrawStats{};
  for (int m = 0; m < kMeshCount; ++m) stats_.solids += int(opaque_[m].size() + transparent_[m].size());
  stats_.lines = int(lines_.size() / 2);
  stats_.points = int(points_.size());
  stats_.labels = int(labels_.size());
  stats_.triangles = int((triangles_.size() + transparent_triangles_.size()) / 3);

  glViewport(0, 0, width, height);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_CULL_FACE);
  glClearColor(style.sky_bottom.r, style.sky_bottom.g, style.sky_bottom.b, 1);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

  // background gradient, no depth
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glUseProgram(sky_program_);
  glUniform3fv(glGetUniformLocation(sky_program_, "u_top"), 1, glm::value_ptr(style.sky_top));
  glUniform3fv(glGetUniformLocation(sky_program_, "u_bottom"), 1, glm::value_ptr(style.sky_bottom));
  glBindVertexArray(empty_vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);

  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);

  // ground with its grid; it writes depth so objects below it are hidden
  if (style.ground) {
    glUseProgram(ground_program_);
    glUniformMatrix4fv(glGetUniformLocation(ground_program_, "u_view_proj"), 1, GL_FALSE, glm::value_ptr(vp));
    glUniform1f(glGetUniformLocation(ground_program_, "u_extent"), style.ground_extent);
    glUniform1f(glGetUniformLocation(ground_program_, "u_spacing"), style.grid_spacing);
    glUniform3fv(glGetUniformLocation(ground_program_, "u_eye"), 1, glm::value_ptr(eye));
    glBindVertexArray(meshes_[kQuad].vao);
    glDrawElements(GL_TRIANGLES, meshes_[kQuad].index_count, GL_UNSIGNED_INT, nullptr);

    // blob shadows just above the ground
    if (!shadows_.empty()) {
      glDepthMask(GL_FALSE);
      glUseProgram(shadow_program_);
      glUniformMatrix4fv(glGetUniformLocation(shadow_program_, "u_view_proj"), 1, GL_FALSE, glm::value_ptr(vp));
      draw_instances(kQuad, shadows_);
      glDepthMask(GL_TRUE);
    }
  }

  // opaque solids, lit by a key light above and behind the viewer's left shoulder
  const glm::mat4 view = camera.view();
  const glm::vec3 right{view[0][0], view[1][0], view[2][0]};
  const glm::vec3 forward = glm::normalize(camera.target - eye);
  const glm::vec3 key = glm::normalize(-forward * 0.7f + glm::vec3(0, 1.0f, 0) - right * 0.45f);
  const glm::vec3 fill = glm::normalize(-forward * 0.3f - glm::vec3(0, 0.3f, 0) + right * 0.8f);
  glUseProgram(mesh_program_);
  glUniformMatrix4fv(glGetUniformLocation(mesh_program_, "u_view_proj"), 1, GL_FALSE, glm::value_ptr(vp));
  glUniform3fv(glGetUniformLocation(mesh_program_, "u_eye"), 1, glm::value_ptr(eye));
  glUniform3fv(glGetUniformLocation(mesh_program_, "u_key"), 1, glm::value_ptr(key));
  glUniform3fv(glGetUniformLocation(mesh_program_, "u_fill"), 1, glm::value_ptr(fill));
  for (int m = 0; m < kMeshCount; ++m) draw_instances(static_cast<Mesh>(m), opaque_[m]);
  draw_triangles(triangles_, eye, key, fill);

  // lines as screen-space quads
  if (!lines_.empty()) {
    glUseProgram(line_program_);
    glUniformMatrix4fv(glGetUniformLocation(line_program_, "u_view_proj"), 1, GL_FALSE, glm::value_ptr(vp));
    glUniform2f(glGetUniformLocation(line_program_, "u_viewport"), viewport_.x, viewport_.y);
    glBindVertexArray(line_vao_);
    glBindBuffer(GL_ARRAY_BUFFER, line_vbo_);
    glBufferData(GL_ARRAY_BUFFER, lines_.size() * sizeof(LineVertex), lines_.data(), GL_STREAM_DRAW);
    glDrawArrays(GL_LINES, 0, static_cast<GLsizei>(lines_.size()));
  }

  // round points
  if (!points_.empty()) {
    glEnable(GL_PROGRAM_POINT_SIZE);
    glUseProgram(point_program_);
    glUniformMatrix4fv(glGetUniformLocation(point_program_, "u_view_proj"), 1, GL_FALSE, glm::value_ptr(vp));
    glBindVertexArray(point_vao_);
    glBindBuffer(GL_ARRAY_BUFFER, point_vbo_);
    glBufferData(GL_ARRAY_BUFFER, points_.size() * sizeof(LineVertex), points_.data(), GL_STREAM_DRAW);
    glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(points_.size()));
  }

  // translucent solids last, without depth writes
  glDepthMask(GL_FALSE);
  glUseProgram(mesh_program_);
  for (int m = 0; m < kMeshCount; ++m) draw_instances(static_cast<Mesh>(m), transparent_[m]);
  draw_triangles(transparent_triangles_, eye, key, fill);
  glDepthMask(GL_TRUE);

  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
}

bool Renderer::project(const Vec3& p, glm::vec2* px) const {
  const glm::vec4 c = view_proj_ * glm::vec4(f3(p), 1.0f);
  if (c.w <= 1e-4f) return false;
  const glm::vec2 ndc{c.x / c.w, c.y / c.w};
  *px = glm::vec2((ndc.x * 0.5f + 0.5f) * viewport_.x, (0.5f - ndc.y * 0.5f) * viewport_.y);
  return true;
}

Color Renderer::background_at_row(int y) const {
  // the sky shader interpolates bottom to top over the viewport height
  const float t = 1.0f - (static_cast<float>(y) + 0.5f) / viewport_.y;
  const glm::vec3 c = glm::mix(style.sky_bottom, style.sky_top, t);
  return Color{c.r, c.g, c.b, 1.0f};
}

void Renderer::draw_labels(ImDrawList* list) const {
  ImFont* font = ImGui::GetFont();
  const float base = ImGui::GetFontSize();
  // framebuffer pixels to ImGui's coordinates (they differ on high-DPI screens)
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  const glm::vec2 to_ui(display.x / viewport_.x, display.y / viewport_.y);
  for (const Label& l : labels_) {
    glm::vec2 px;
    if (!project(l.p, &px)) continue;
    px *= to_ui;
    const float size = base * l.scale;
    const ImVec2 ext = font->CalcTextSizeA(size, 1e9f, 0.0f, l.s.c_str());
    // a left-aligned label keeps a small gap from its anchor (usually a shape)
    const float gap = l.align_x == 0.0f ? 6.0f : (l.align_x == 1.0f ? -6.0f : 0.0f);
    px += glm::vec2(gap - l.align_x * ext.x, -0.5f * ext.y);
    // dark outline for contrast on any background
    const ImU32 shadow = IM_COL32(0, 0, 0, 200);
    for (const glm::vec2 o : {glm::vec2(1, 1), glm::vec2(-1, 1), glm::vec2(1, -1), glm::vec2(-1, -1)})
      list->AddText(font, size, ImVec2(px.x + o.x, px.y + o.y), shadow, l.s.c_str());
    list->AddText(font, size, ImVec2(px.x, px.y), ImGui::ColorConvertFloat4ToU32(ImVec4(l.c.r, l.c.g, l.c.b, l.c.a)),
                  l.s.c_str());
  }
}

}  // namespace pba::app
