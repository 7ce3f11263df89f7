// Point queries: the signed distance from a point to every shape's surface, the closest
// point and its normal (the point-contact clients: particles, cloth, soft bodies).
#include <algorithm>
#include <cmath>
#include <limits>

#include "hull_face.h"
#include "narrow_internal.h"
#include "pba/collide/shape.h"
#include "query_internal.h"

namespace pba {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// the sphere of radius r about c: the normal from the centre (+Y at the centre)
PointDistance ball_distance(const Vec3& x, const Vec3& c, double r) {
  const Vec3 v = x - c;
  const double len = glm::length(v);
  const Vec3 n = len > 0 ? v / len : Vec3(0, 1, 0);
  return {len - r, c + r * n, n, 0};
}

PointDistance box_distance(const Vec3& x, const Vec3& h) {
  // the most separating face: largest |x_i| - h_i
  int axis = 0;
  double sep = -kInf;
  for (int i = 0; i < 3; ++i)
    if (std::abs(x[i]) - h[i] > sep) sep = std::abs(x[i]) - h[i], axis = i;
  PointDistance r;
  r.feature = static_cast<std::uint32_t>(2 * axis + (x[axis] < 0 ? 1 : 0));
  if (sep <= 0) {
    // inside: out through the nearest face
    r.distance = sep;
    r.point = x;
    r.point[axis] = x[axis] < 0 ? -h[axis] : h[axis];
    r.normal[axis] = x[axis] < 0 ? -1 : 1;
    r.normal[(axis + 1) % 3] = r.normal[(axis + 2) % 3] = 0;
    return r;
  }
  // outside: the clamped point
  r.point = glm::clamp(x, -h, h);
  const Vec3 v = x - r.point;
  r.distance = glm::length(v);
  r.normal = v / r.distance;
  return r;
}

Vec3 closest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return a + t * ab;
}

PointDistance hull_distance(const Vec3& x, const ConvexHull& h) {
  const auto faces = h.faces();
  const auto e = h.edges();
  const auto v = h.vertices();
  // inside: the nearest face plane (its foot lies on that face)
  std::uint32_t best_face = 0;
  double sep = -kInf;
  for (std::uint32_t f = 0; f < faces.size(); ++f) {
    const double s = glm::dot(faces[f].normal, x) - faces[f].offset;
    if (s > sep) sep = s, best_face = f;
  }
  if (sep <= 0) return {sep, x - sep * faces[best_face].normal, faces[best_face].normal, best_face};
  // outside: the nearest point over the faces the point is in front of, each face's being
  // the projection when it falls inside the polygon, else the nearest on its edges
  PointDistance r;
  r.distance = kInf;
  for (std::uint32_t f = 0; f < faces.size(); ++f) {
    const Vec3 n = faces[f].normal;
    const double s = glm::dot(n, x) - faces[f].offset;
    if (s <= 0) continue;
    const Vec3 proj = x - s * n;
    Vec3 q = proj;
    if (!detail::on_hull_face(h, f, proj)) {
      double bd = kInf;
      std::uint32_t k = faces[f].edge;
      do {
        const Vec3 c = closest_on_segment(x, v[e[k].origin], v[e[e[k].next].origin]);
        if (glm::dot(x - c, x - c) < bd) bd = glm::dot(x - c, x - c), q = c;
        k = e[k].next;
      } while (k != faces[f].edge);
    }
    const double dist = glm::length(x - q);
    if (dist < r.distance) r.distance = dist, r.point = q, r.feature = f;
  }
  r.normal = (x - r.point) / r.distance;
  return r;
}

// squared distance from p to a box (0 inside)
double box_distance2(const Vec3& p, const Aabb& b) {
  const Vec3 d = glm::max(glm::max(b.lo - p, p - b.hi), Vec3(0.0));
  return glm::dot(d, d);
}

PointDistance mesh_distance(const Vec3& x, const TriangleMesh& m) {
  // depth-first through the BVH, nearer child first, pruning by box distance
  const auto nodes = m.nodes();
  const auto tris = m.triangles();
  const auto v = m.vertices();
  double best = kInf;
  std::uint32_t tri = 0;
  Vec3 q(0.0);
  bool on_face = false;
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const TriangleMesh::Node& n = nodes[stack[--top]];
    if (box_distance2(x, n.box) > best) continue;
    if (n.count > 0) {
      for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
        const std::uint32_t t = m.triangle_order()[i];
        bool interior;
        const Vec3 c = narrow::closest_on_triangle(x, v[tris[t][0]], v[tris[t][1]], v[tris[t][2]], interior);
        const double d2 = glm::dot(x - c, x - c);
        // ties to the lower index: the answer does not depend on the tree
        if (d2 < best || (d2 == best && t < tri)) best = d2, tri = t, q = c, on_face = interior;
      }
      continue;
    }
    const double dl = box_distance2(x, nodes[n.first].box), dr = box_distance2(x, nodes[n.first + 1].box);
    if (dl <= dr) {
      stack[top++] = n.first + 1;
      stack[top++] = n.first;
    } else {
      stack[top++] = n.first;
      stack[top++] = n.first + 1;
    }
  }
  PointDistance r;
  r.distance = std::sqrt(best);
  r.point = q;
  r.feature = tri;
  // nearest inside the face: the face normal turned towards x (exact even at distance
  // ~0); nearest on an edge or corner: the direction to x
  const Vec3 tn = m.normal(tri);
  if (on_face || !(r.distance > 0)) r.normal = glm::dot(tn, x - q) < 0 ? -tn : tn;
  else r.normal = (x - q) / r.distance;
  return r;
}

}  // namespace

PointDistance point_distance(const ColliderShape& s, const Pose& p, const Vec3& world_point) {
  // a NaN point gave a box's distance as -inf (deep inside), a NaN pose NaN, a point beyond
  // a float's range an infinite distance at the shape's centre: refused by name, as the
  // QueryWorld's closest_point() refuses them (the library's own callers, whose points and
  // poses are checked where they come in, take the unchecked query::point_distance_unchecked)
  if (!fits_float(world_point)) require_float(world_point, "point_distance(world_point)");
  query::check_pose(p, "point_distance(pose)");
  return query::point_distance_unchecked(s, p, world_point);
}

PointDistance query::point_distance_unchecked(const ColliderShape& s, const Pose& p, const Vec3& world_point) {
  if (s.type == ShapeType::Compound) {
    // the nearest child; the feature is the child's index
    const auto& ch = s.compound->children;
    PointDistance best;
    best.distance = kInf;
    for (std::uint32_t i = 0; i < ch.size(); ++i) {
      PointDistance d = point_distance_unchecked(ch[i].shape, compose(p, ch[i].pose), world_point);
      if (d.distance < best.distance) best = d, best.feature = i;
    }
    return best;
  }
  // in the shape's frame
  const Vec3 x = apply_inverse(p, world_point);
  PointDistance r;
  switch (s.type) {
    case ShapeType::Plane: {
      const double len = glm::length(s.normal);
      const Vec3 n = s.normal / len;
      const double d = glm::dot(n, x) - s.offset / len;
      r = {d, x - d * n, n, 0};
      break;
    }
    case ShapeType::Sphere: r = ball_distance(x, Vec3(0.0), s.radius); break;
    case ShapeType::Capsule:
      r = ball_distance(x, Vec3(0, std::clamp(x.y, -s.half_height, s.half_height), 0), s.radius);
      break;
    case ShapeType::Box: r = box_distance(x, s.half_extents); break;
    case ShapeType::Hull: r = hull_distance(x, *s.hull); break;
    case ShapeType::Mesh: r = mesh_distance(x, *s.mesh); break;
    case ShapeType::Compound: break;
  }
  // back to the world
  r.point = apply(p, r.point);
  r.normal = p.rotation * r.normal;
  return r;
}

}  // namespace pba
