// The app's renderer: the OpenGL implementation of pba::DebugDraw.
//
// Every DebugDraw call queues geometry for the current frame; render() draws the
// queues in a few instanced draw calls (one per mesh kind), so hundreds of shapes
// stay cheap even on a software rasteriser (Mesa llvmpipe).
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "pba/draw.h"

struct ImDrawList;

namespace pba::app {

struct Camera;

/// Appearance of the ground and background, set per sample.
struct SceneStyle {
  bool ground = true;              ///< draw the ground plane y = 0 with its grid
  float grid_spacing = 1.0f;       ///< metres between minor grid lines (major lines every 5)
  float ground_extent = 40.0f;     ///< metres from the origin where the ground fades out
  bool shadows = true;             ///< soft blob shadows under solids, on the ground
  glm::vec3 sky_top{0.245f, 0.263f, 0.298f};     ///< background colour at the top of the view
  glm::vec3 sky_bottom{0.137f, 0.145f, 0.161f};  ///< background colour at the bottom
};

/// Number of queued primitives of each kind in the last frame, for the profiler.
struct DrawStats {
  int solids = 0;  ///< sphere, box, cylinder and cone instances
  int lines = 0;   ///< line segments (including arrow shafts and the grid)
  int points = 0;  ///< points
  int labels = 0;  ///< text labels
  int triangles = 0;  ///< filled triangles (triangle(), e.g. cloth)
};

/// One corner of a smooth-shaded triangle (Renderer::triangle): world position (m),
/// normal (any length > 0; zero falls back to the face normal) and colour.
struct TriangleCorner {
  Vec3 p{0, 0, 0};  ///< position (m)
  Vec3 n{0, 0, 0};  ///< normal, not necessarily unit
  Color c{};        ///< colour (alpha < 1: drawn translucent, after the opaque scene)
};

/// OpenGL 3.3 renderer implementing pba::DebugDraw. Create after a GL context is current.
class Renderer final : public pba::DebugDraw {
 public:
  Renderer();
  ~Renderer() override;
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Compiles shaders and builds meshes. Returns false and sets `error` on failure.
  bool init(std::string* error);

  // pba::DebugDraw
  void point(const Vec3& p, float size, Color c) override;
  void line(const Vec3& a, const Vec3& b, Color c) override;
  void sphere(const Vec3& center, double radius, Color c) override;
  void box(const Vec3& center, const Vec3& half, const Quat& rotation, Color c) override;
  void capsule(const Vec3& a, const Vec3& b, double radius, Color c) override;
  void plane(const Vec3& normal, double offset, double half_size, Color c) override;
  void arrow(const Vec3& from, const Vec3& to, double head, Color c) override;
  void text(const Vec3& p, std::string_view s, Color c) override;
  /// A filled, lit, two-sided triangle with the flat normal of its plane (both faces lit
  /// alike; a, b, c counter-clockwise seen from the front). Drawn slightly behind lines
  /// at the same depth, so edges drawn on a surface stay visible.
  void triangle(const Vec3& a, const Vec3& b, const Vec3& c, Color col) override;

  /// A lit, two-sided triangle with a normal and colour per corner (smooth shading, e.g.
  /// cloth with vertex normals); counter-clockwise seen from the side the normals face.
  void triangle(const TriangleCorner& a, const TriangleCorner& b, const TriangleCorner& c);
  /// A soft blob shadow on the ground under `center`, as solids cast (`radius` m, > 0).
  void shadow(const Vec3& center, double radius);

  /// A line `width_px` pixels wide (line() uses the current default width).
  void line(const Vec3& a, const Vec3& b, Color c, float width_px);
  /// A connected polyline through `pts`, `width_px` wide.
  void polyline(const std::vector<Vec3>& pts, Color c, float width_px);
  /// Width in pixels of lines drawn by line(a, b, c), default 1.5.
  void set_line_width(float width_px) { line_width_ = width_px; }
  /// Text with a font scale (1 = the UI font size), aligned on the anchor: align_x 0 puts
  /// the text right of it, 0.5 centres it, 1 ends it there (vertically always centred).
  void text(const Vec3& p, std::string_view s, Color c, float scale, float align_x);

  /// Ground, grid and background of the current sample.
  SceneStyle style;

  /// Drops everything queued; call at the start of each frame.
  void begin_frame();
  /// Draws the background, ground and every queued primitive into the bound framebuffer
  /// of `width` x `height` pixels, seen through `camera`.
  void render(const Camera& camera, int width, int height);
  /// Draws the queued text labels into an ImGui draw list (call between ImGui::NewFrame and
  /// ImGui::Render, after render()). Labels behind the camera are skipped.
  void draw_labels(ImDrawList* list) const;
  /// Projects a world point to pixel coordinates of the last render(); false when behind the eye.
  bool project(const Vec3& p, glm::vec2* px) const;
  /// Background colour at pixel row `y` (0 = top) of the last render.
  Color background_at_row(int y) const;

  /// Primitive counts queued for the last rendered frame.
  const DrawStats& stats() const { return stats_; }

 private:
  struct Instance {   // one solid: transform and colour, uploaded as per-instance attributes
    float pos[3];
    float scale[3];
    float quat[4];    // x, y, z, w
    float color[4];
  };
  struct LineVertex { float pos[3]; float color[4]; float width; };
  struct TriVertex { float pos[3]; float nrm[3]; float color[4]; };
  struct Label { Vec3 p; std::string s; Color c; float scale; float align_x; };
  enum Mesh { kSphere, kCube, kCylinder, kCone, kQuad, kMeshCount };
  struct MeshBuffers { unsigned vao = 0, vbo = 0, ibo = 0, instance_vbo = 0; int index_count = 0; };

  void add_instance(Mesh m, const glm::vec3& pos, const glm::vec3& scale, const glm::quat& q, Color c);
  void add_shadow(const glm::vec3& pos, float radius);
  void build_mesh(Mesh m, const std::vector<float>& vertices, const std::vector<unsigned>& indices);
  void draw_instances(Mesh m, const std::vector<Instance>& list);
  void push_triangle(const TriangleCorner (&v)[3]);
  void draw_triangles(const std::vector<TriVertex>& list, const glm::vec3& eye, const glm::vec3& key,
                      const glm::vec3& fill);

  float line_width_ = 1.5f;
  std::vector<Instance> opaque_[kMeshCount];
  std::vector<Instance> transparent_[kMeshCount];
  std::vector<Instance> shadows_;
  std::vector<LineVertex> lines_;
  std::vector<LineVertex> points_;
  std::vector<Label> labels_;
  std::vector<TriVertex> triangles_;              // opaque filled triangles
  std::vector<TriVertex> transparent_triangles_;  // translucent ones, drawn last
  DrawStats stats_;

  MeshBuffers meshes_[kMeshCount];
  unsigned mesh_program_ = 0, line_program_ = 0, point_program_ = 0, ground_program_ = 0,
           sky_program_ = 0, shadow_program_ = 0, triangle_program_ = 0;
  unsigned line_vao_ = 0, line_vbo_ = 0, point_vao_ = 0, point_vbo_ = 0, empty_vao_ = 0;
  unsigned triangle_vao_ = 0, triangle_vbo_ = 0;
  glm::mat4 view_proj_{1.0f};
  glm::vec2 viewport_{1.0f, 1.0f};
  bool ready_ = false;
};

}  // namespace pba::app
