// Ray casts against every shape, in the shape's frame: spheres and capsules by their
// quadratics, boxes by slabs, hulls by clipping against face planes (Cyrus and Beck 1978),
// meshes through the BVH with Moller and Trumbore's (1997) triangle test, compounds by child.
#include <algorithm>
#include <cmath>
#include <limits>

#include "pba/collide/shape.h"
#include "query_internal.h"

namespace pba {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// a local-frame hit: distance, local normal and feature; t < 0 is a miss
struct LocalHit {
  double t = -1;
  Vec3 n{0, 0, 0};
  std::uint32_t feature = 0;
  bool inside = false;  // the origin is inside the solid: the normal is minus the ray
};

// the entry distance of the ray o + t d into the ball |x - c| <= r, for an origin outside
// it; the discriminant from the perpendicular offset keeps its precision for far origins
double ball_entry(const Vec3& o, const Vec3& d, const Vec3& c, double r) {
  const Vec3 m = o - c;
  const double b = glm::dot(m, d);
  if (b > 0) return -1;
  const Vec3 f = m - b * d;
  const double disc = r * r - glm::dot(f, f);
  if (disc < 0) return -1;
  return -b - std::sqrt(disc);
}

LocalHit ray_sphere(const Vec3& o, const Vec3& d, double r) {
  LocalHit h;
  if (glm::dot(o, o) <= r * r) return {0, -d, 0, true};
  h.t = ball_entry(o, d, Vec3(0.0), r);
  if (h.t >= 0) h.n = (o + h.t * d) / r;
  return h;
}

LocalHit ray_capsule(const Vec3& o, const Vec3& d, double hh, double r) {
  // inside: within r of the core segment
  const Vec3 core(0, std::clamp(o.y, -hh, hh), 0);
  if (glm::dot(o - core, o - core) <= r * r) return {0, -d, 0, true};
  // the first entry into the union of the side cylinder and the two end balls
  LocalHit h;
  h.t = kInf;
  const double a = d.x * d.x + d.z * d.z;
  if (a > 0) {
    const double b = o.x * d.x + o.z * d.z, c = o.x * o.x + o.z * o.z - r * r;
    const double disc = b * b - a * c;
    if (disc >= 0) {
      const double t = (-b - std::sqrt(disc)) / a;
      const double y = o.y + t * d.y;
      if (t >= 0 && std::abs(y) <= hh) h.t = t, h.n = Vec3(o.x + t * d.x, 0, o.z + t * d.z) / r;
    }
  }
  for (double s : {-hh, hh}) {
    const double t = ball_entry(o, d, Vec3(0, s, 0), r);
    if (t >= 0 && t < h.t) h.t = t, h.n = (o + t * d - Vec3(0, s, 0)) / r;
  }
  if (h.t == kInf) h.t = -1;
  return h;
}

// slabs; the feature is the face in ConvexHull::box order (+x, -x, +y, -y, +z, -z)
LocalHit ray_box(const Vec3& o, const Vec3& d, const Vec3& hx) {
  if (std::abs(o.x) <= hx.x && std::abs(o.y) <= hx.y && std::abs(o.z) <= hx.z) return {0, -d, 0, true};
  double t0 = -kInf, t1 = kInf;
  int axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0) {
      if (std::abs(o[i]) > hx[i]) return {};
      continue;
    }
    const double inv = 1 / d[i];
    double a = (-hx[i] - o[i]) * inv, b = (hx[i] - o[i]) * inv;
    if (a > b) std::swap(a, b);
    if (a > t0) t0 = a, axis = i;
    t1 = std::min(t1, b);
  }
  if (axis < 0 || t0 > t1 || t0 < 0) return {};
  LocalHit h;
  h.t = t0;
  h.n[axis] = d[axis] < 0 ? 1 : -1;
  h.feature = static_cast<std::uint32_t>(2 * axis + (d[axis] < 0 ? 0 : 1));
  return h;
}

LocalHit ray_plane(const Vec3& o, const Vec3& d, const Vec3& normal, double offset) {
  const double len = glm::length(normal);
  const Vec3 n = normal / len;
  const double s = glm::dot(n, o) - offset / len, den = glm::dot(n, d);
  if (s <= 0) return {0, -d, 0, true};
  if (den >= 0) return {};
  return {-s / den, n, 0};
}

// clip the ray against every face's half-space; the last entering face is hit
LocalHit ray_hull(const Vec3& o, const Vec3& d, const ConvexHull& hull, double max_t) {
  double t0 = 0, t1 = max_t;
  std::uint32_t face = UINT32_MAX;
  const auto faces = hull.faces();
  for (std::uint32_t f = 0; f < faces.size(); ++f) {
    const double num = faces[f].offset - glm::dot(faces[f].normal, o), den = glm::dot(faces[f].normal, d);
    if (den == 0) {
      if (num < 0) return {};
      continue;
    }
    const double t = num / den;
    if (den < 0) {
      if (t > t0) t0 = t, face = f;
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 > t1) return {};
  }
  if (face == UINT32_MAX) return {0, -d, 0, true};  // no plane ahead to enter: the origin is inside
  return {t0, faces[face].normal, face};
}

// Moller-Trumbore, two-sided; the distance or -1
double ray_triangle(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (det == 0) return -1;
  const double inv = 1 / det;
  const Vec3 s = o - a;
  const double u = glm::dot(s, p) * inv;
  if (u < 0 || u > 1) return -1;
  const Vec3 q = glm::cross(s, e1);
  const double v = glm::dot(d, q) * inv;
  if (v < 0 || u + v > 1) return -1;
  return glm::dot(e2, q) * inv;
}

// the entry distance into a box, or +inf when the ray misses it within [0, max_t]
double ray_aabb(const Vec3& o, const Vec3& inv, const Aabb& b, double max_t) {
  double t0 = 0, t1 = max_t;
  for (int i = 0; i < 3; ++i) {
    if (std::isinf(inv[i])) {
      if (o[i] < b.lo[i] || o[i] > b.hi[i]) return kInf;
      continue;
    }
    double a = (b.lo[i] - o[i]) * inv[i], c = (b.hi[i] - o[i]) * inv[i];
    if (a > c) std::swap(a, c);
    t0 = std::max(t0, a);
    t1 = std::min(t1, c);
    if (t0 > t1) return kInf;
  }
  return t0;
}

// closest hit through the BVH: nearer child first, nodes beyond the best hit skipped
LocalHit ray_mesh(const Vec3& o, const Vec3& d, const TriangleMesh& m, double max_t) {
  LocalHit h;
  double best = max_t;
  const Vec3 inv(1 / d.x, 1 / d.y, 1 / d.z);
  const auto nodes = m.nodes();
  const auto tris = m.triangles();
  const auto v = m.vertices();
  std::uint32_t stack[64];
  int top = 0;
  if (ray_aabb(o, inv, nodes[0].box, best) < kInf) stack[top++] = 0;
  while (top > 0) {
    const TriangleMesh::Node& n = nodes[stack[--top]];
    if (n.count > 0) {
      for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
        const std::uint32_t t = m.triangle_order()[i];
        const double s = ray_triangle(o, d, v[tris[t][0]], v[tris[t][1]], v[tris[t][2]]);
        // ties go to the lower triangle index, so the result is independent of the tree
        if (s >= 0 && (s < best || (s == best && h.t >= 0 && t < h.feature))) best = s, h.t = s, h.feature = t;
      }
      continue;
    }
    const double tl = ray_aabb(o, inv, nodes[n.first].box, best), tr = ray_aabb(o, inv, nodes[n.first + 1].box, best);
    // push the farther first so the nearer is searched first
    if (tl <= tr) {
      if (tr < kInf) stack[top++] = n.first + 1;
      if (tl < kInf) stack[top++] = n.first;
    } else {
      if (tl < kInf) stack[top++] = n.first;
      if (tr < kInf) stack[top++] = n.first + 1;
    }
  }
  // the normal faces the ray (two-sided)
  if (h.t >= 0) h.n = glm::dot(m.normal(h.feature), d) > 0 ? -m.normal(h.feature) : m.normal(h.feature);
  return h;
}

}  // namespace

namespace query {

RayHit ray_cast_unit(const ColliderShape& s, const Pose& p, const Ray& ray) {
  RayHit out;
  if (s.type == ShapeType::Compound) {
    // the closest child; the feature is the child's index
    const auto& ch = s.compound->children;
    for (std::uint32_t i = 0; i < ch.size(); ++i) {
      RayHit h = ray_cast_unit(ch[i].shape, compose(p, ch[i].pose), ray);
      if (h.hit && (!out.hit || h.distance < out.distance)) out = h, out.feature = i;
    }
    return out;
  }
  // into the shape's frame
  const Vec3 o = apply_inverse(p, ray.origin);
  const Vec3 d = glm::conjugate(p.rotation) * ray.direction;
  LocalHit h;
  switch (s.type) {
    case ShapeType::Plane: h = ray_plane(o, d, s.normal, s.offset); break;
    case ShapeType::Sphere: h = ray_sphere(o, d, s.radius); break;
    case ShapeType::Box: h = ray_box(o, d, s.half_extents); break;
    case ShapeType::Capsule: h = ray_capsule(o, d, s.half_height, s.radius); break;
    case ShapeType::Hull: h = ray_hull(o, d, *s.hull, ray.max_distance); break;
    case ShapeType::Mesh: h = ray_mesh(o, d, *s.mesh, ray.max_distance); break;
    case ShapeType::Compound: break;
  }
  if (!(h.t >= 0) || h.t > ray.max_distance) return out;
  // back to the world
  out.hit = true;
  out.distance = h.t;
  out.point = ray.origin + h.t * ray.direction;
  out.normal = h.inside ? -ray.direction : p.rotation * h.n;
  out.feature = h.feature;
  return out;
}

}  // namespace query

// The closed forms above take |direction| = 1 (the sphere's and the capsule's quadratics, the
// distances they return): a ray of direction (0, -2, 0) straight at a sphere missed it, and
// a box's or a hull's distance came back in units of the direction's length. The ray is
// checked as the world queries check theirs (which then test their candidates with
// ray_cast_unit, unchecked): a unit direction (to 4 ulps) is used as it is, so the hits equal
// the world queries' bit for bit; another finite non-zero one is normalised; a non-finite
// origin or direction, a zero direction or a negative max_distance is an Error (a NaN origin
// used to be a silent miss).
RayHit ray_cast(const ColliderShape& s, const Pose& p, const Ray& ray) {
  // a NaN pose missed silently, a non-unit rotation scaled the shape: refused by name
  query::check_pose(p, "ray_cast(pose)");
  return query::ray_cast_unit(s, p, query::checked_ray(ray, "ray_cast(ray)"));
}

}  // namespace pba
