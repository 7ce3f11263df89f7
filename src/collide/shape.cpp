// Shapes: names, construction, validation, bounds and support functions (hulls, meshes,
// mass properties and ray casts live in their own files).
#include "pba/collide/shape.h"

#include <cmath>
#include <limits>
#include <string>

#include "query_internal.h"
#include "shape_bounds.h"

namespace pba {

std::string_view to_string(ShapeType t) {
  switch (t) {
    case ShapeType::Plane: return "plane";
    case ShapeType::Sphere: return "sphere";
    case ShapeType::Box: return "box";
    case ShapeType::Capsule: return "capsule";
    case ShapeType::Hull: return "hull";
    case ShapeType::Mesh: return "mesh";
    case ShapeType::Compound: return "compound";
  }
  return "unknown";
}

ColliderShape ColliderShape::plane(const Vec3& n, double offset) {
  ColliderShape s;
  s.type = ShapeType::Plane;
  // normalise (n . p = offset scales with n), refusing a zero or non-finite normal
  require_finite(n, "ColliderShape::plane normal");
  require_finite(offset, "ColliderShape::plane offset");
  const double len = glm::length(n);
  if (!(len > 0)) throw Error("ColliderShape::plane normal: must be non-zero, got " + format_vec3(n));
  s.normal = n / len;
  s.offset = offset / len;
  return s;
}

ColliderShape ColliderShape::sphere(double r) {
  ColliderShape s;
  s.type = ShapeType::Sphere;
  s.radius = r;
  s.validate("ColliderShape::sphere");
  return s;
}

ColliderShape ColliderShape::box(const Vec3& h) {
  ColliderShape s;
  s.type = ShapeType::Box;
  s.half_extents = h;
  s.validate("ColliderShape::box");
  return s;
}

ColliderShape ColliderShape::capsule(double half_height, double r) {
  ColliderShape s;
  s.type = ShapeType::Capsule;
  s.half_height = half_height;
  s.radius = r;
  s.validate("ColliderShape::capsule");
  return s;
}

namespace {
// a hull, mesh or compound shape around its body, validated (a null body throws)
template <class T>
ColliderShape with_body(ShapeType t, std::shared_ptr<const T> ColliderShape::*field, std::shared_ptr<const T> body,
                        std::string_view where) {
  ColliderShape s;
  s.type = t;
  s.*field = std::move(body);
  s.validate(where);
  return s;
}
}  // namespace

ColliderShape ColliderShape::convex(std::shared_ptr<const ConvexHull> h) {
  return with_body(ShapeType::Hull, &ColliderShape::hull, std::move(h), "ColliderShape::convex");
}

ColliderShape ColliderShape::triangles(std::shared_ptr<const TriangleMesh> m) {
  return with_body(ShapeType::Mesh, &ColliderShape::mesh, std::move(m), "ColliderShape::triangles");
}

void ColliderShape::validate(std::string_view where) const {
  switch (type) {
    case ShapeType::Plane: {
      require_finite(normal, field_path(where, "normal"));
      // zero is refused; any other length is accepted (queries normalise, as plane() does)
      if (!(glm::length(normal) > 0)) throw Error(field_path(where, "normal") + ": must be non-zero, got " + format_vec3(normal));
      require_finite(offset, field_path(where, "offset"));
      return;
    }
    case ShapeType::Sphere: require_positive(radius, field_path(where, "radius")); return;
    case ShapeType::Box:
      require_positive(half_extents.x, field_path(where, "half_extents.x"));
      require_positive(half_extents.y, field_path(where, "half_extents.y"));
      require_positive(half_extents.z, field_path(where, "half_extents.z"));
      return;
    case ShapeType::Capsule:
      require_non_negative(half_height, field_path(where, "half_height"));
      require_positive(radius, field_path(where, "radius"));
      return;
    case ShapeType::Hull:
      if (!hull) throw Error(field_path(where, "hull") + ": must not be null for a hull shape");
      return;
    case ShapeType::Mesh:
      if (!mesh) throw Error(field_path(where, "mesh") + ": must not be null for a mesh shape");
      return;
    case ShapeType::Compound:
      if (!compound) throw Error(field_path(where, "compound") + ": must not be null for a compound shape");
      return;
  }
  throw Error(field_path(where, "type") + ": unknown shape type " + std::to_string(static_cast<int>(type)));
}

std::shared_ptr<const CompoundShape> CompoundShape::build(std::vector<CompoundChild> children, std::string_view where) {
  if (children.empty()) throw Error(field_path(where, "children") + ": a compound needs at least one child, got 0");
  auto c = std::make_shared<CompoundShape>();
  // validate each child and its pose, then grow the bounds
  for (std::size_t i = 0; i < children.size(); ++i) {
    const std::string at = field_path(where, "children[" + std::to_string(i) + "]");
    const CompoundChild& ch = children[i];
    if (ch.shape.type == ShapeType::Plane || ch.shape.type == ShapeType::Mesh)
      throw Error(field_path(at, "shape.type") + ": a compound child must be a sphere, box, capsule, hull or compound, got a " +
                  std::string(to_string(ch.shape.type)));
    // held to a float's range as every other shape's sizes and poses are (a collider's, a
    // body's shape): the bounds, the queries and the contact rows carry them as floats
    query::check_shape(ch.shape, field_path(at, "shape"));
    query::check_pose(ch.pose, field_path(at, "pose"));
    const Aabb b = pba::bounds(ch.shape, ch.pose);
    c->local_bounds = i == 0 ? b : c->local_bounds.merged(b);
  }
  c->children = std::move(children);
  return c;
}

Aabb bounds(const ColliderShape& s, const Pose& p) {
  switch (s.type) {
    case ShapeType::Plane: {
      // the half-space below the plane: infinite unless the normal is an axis
      const double inf = std::numeric_limits<double>::infinity();
      Aabb b{Vec3(-inf), Vec3(inf)};
      const double len = glm::length(s.normal);
      const Vec3 n = p.rotation * (s.normal / len);
      const double d = s.offset / len + glm::dot(n, p.position);
      for (int i = 0; i < 3; ++i) {
        if (n[i] == 1 && n[(i + 1) % 3] == 0 && n[(i + 2) % 3] == 0) b.hi[i] = d;
        if (n[i] == -1 && n[(i + 1) % 3] == 0 && n[(i + 2) % 3] == 0) b.lo[i] = -d;
      }
      return b;
    }
    case ShapeType::Sphere:
    case ShapeType::Box: return detail::shape_bounds(s, p);
    case ShapeType::Capsule: {
      const Vec3 axis = p.rotation * Vec3(0, s.half_height, 0);
      const Vec3 h = glm::abs(axis) + Vec3(s.radius);
      return {p.position - h, p.position + h};
    }
    case ShapeType::Hull: {
      // exact: the support point along each world axis. A hull of up to 64 vertices (a
      // pyramid's five) places them all and keeps each coordinate's extremes: the vertex a
      // climb along an axis finds is among them, placed the same way, so the box is the
      // climbs' to the bit unless two vertices tie along the axis to rounding (then it is
      // the larger of the two), for less than half the instructions: six climbs, each with
      // its axis turned into the hull's frame, made `bounds` 1.7% of the terrain scene's
      // resting steps (0.8% now)
      const ConvexHull& h = *s.hull;
      if (const std::span<const Vec3> v = h.vertices(); v.size() <= 64) {
        Vec3 lo = apply(p, v[0]), hi = lo;
        for (std::size_t i = 1; i < v.size(); ++i) {
          const Vec3 x = apply(p, v[i]);
          lo = glm::min(lo, x), hi = glm::max(hi, x);
        }
        return {lo, hi};
      }
      // larger: climbing from the last one
      const Quat qi = glm::conjugate(p.rotation);
      Aabb b;
      std::uint32_t hint = 0;
      for (int i = 0; i < 3; ++i) {
        Vec3 axis(0.0);
        axis[i] = 1;
        hint = h.support_index(qi * axis, hint);
        b.hi[i] = apply(p, h.vertices()[hint])[i];
        hint = h.support_index(qi * -axis, hint);
        b.lo[i] = apply(p, h.vertices()[hint])[i];
      }
      return b;
    }
    case ShapeType::Mesh: {
      const Aabb l = s.mesh->bounds();
      const Vec3 c = apply(p, l.center());
      const Vec3 h = detail::rotated_half(p.rotation, 0.5 * (l.hi - l.lo));
      return {c - h, c + h};
    }
    case ShapeType::Compound: {
      const CompoundShape& c = *s.compound;
      Aabb b = bounds(c.children[0].shape, compose(p, c.children[0].pose));
      for (std::size_t i = 1; i < c.children.size(); ++i)
        b = b.merged(bounds(c.children[i].shape, compose(p, c.children[i].pose)));
      return b;
    }
  }
  return {};
}

Vec3 support(const ColliderShape& s, const Vec3& d) {
  switch (s.type) {
    case ShapeType::Sphere: {
      const double len = glm::length(d);
      return len > 0 ? d * (s.radius / len) : Vec3(0.0);
    }
    case ShapeType::Box:
      return {d.x < 0 ? -s.half_extents.x : s.half_extents.x, d.y < 0 ? -s.half_extents.y : s.half_extents.y,
              d.z < 0 ? -s.half_extents.z : s.half_extents.z};
    case ShapeType::Capsule: {
      const double len = glm::length(d);
      const Vec3 core(0, d.y < 0 ? -s.half_height : s.half_height, 0);
      return len > 0 ? core + d * (s.radius / len) : core;
    }
    case ShapeType::Hull: return s.hull->support(d);
    default: return Vec3(0.0);
  }
}

double core_radius(const ColliderShape& s) {
  return s.type == ShapeType::Sphere || s.type == ShapeType::Capsule ? s.radius : 0.0;
}

}  // namespace pba
