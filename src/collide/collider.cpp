// Colliders: construction, validation and drawing of the flat world-space shape.
#include <cmath>
#include <limits>
#include <string>

#include "pba/collide/broad_phase.h"
#include "pba/collide/collider.h"

namespace pba {

namespace {

Pose static_pose(const Vec3& p, const Quat& q = Quat(1, 0, 0, 0)) { return Pose{p, q}; }

// finite, unit to 1e-6 (the tolerance of require_unit_quat)
bool unit_quat(const Quat& q) {
  return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) &&
         std::abs(glm::length(q) - 1.0) <= 1e-6;
}

}  // namespace

Collider Collider::plane(const Vec3& normal, double offset, SurfaceMaterial m) {
  Collider c;
  c.shape.type = ShapeType::Plane;
  const double len = glm::length(normal);
  c.shape.normal = len > 0 ? normal / len : normal;
  c.shape.offset = len > 0 ? offset / len : offset;
  c.material = m;
  return c;
}

Collider Collider::sphere(const Vec3& center, double radius, SurfaceMaterial m) {
  Collider c;
  c.shape.type = ShapeType::Sphere;
  c.shape.radius = radius;
  c.material = m;
  c.begin = c.end = static_pose(center);
  return c;
}

Collider Collider::box(const Vec3& center, const Vec3& half_extents, SurfaceMaterial m, const Quat& rotation) {
  Collider c;
  c.shape.type = ShapeType::Box;
  c.shape.half_extents = half_extents;
  c.material = m;
  c.begin = c.end = static_pose(center, rotation);
  return c;
}

bool Collider::ok() const {
  // motion, then the shape and material
  return fits_float(begin.position) && fits_float(end.position) && unit_quat(begin.rotation) &&
         unit_quat(end.rotation) && fits_float(velocity) && fits_float(angular_velocity) && shape_ok(shape, material);
}

bool Collider::shape_ok(const ColliderShape& s, const SurfaceMaterial& material) {
  const bool good = material.restitution >= 0 && material.restitution <= 1 && std::isfinite(material.friction) &&
                    material.friction >= 0;
  // the shape's parameters (a hull, mesh or compound was validated when it was built)
  switch (s.type) {
    case ShapeType::Plane: return good && fits_float(s.normal) && glm::length(s.normal) > 0 && fits_float(s.offset);
    case ShapeType::Sphere: return good && fits_float(s.radius) && s.radius > 0;
    case ShapeType::Box:
      return good && fits_float(s.half_extents) && s.half_extents.x > 0 && s.half_extents.y > 0 &&
             s.half_extents.z > 0;
    case ShapeType::Capsule:
      return good && fits_float(s.radius) && s.radius > 0 && fits_float(s.half_height) && s.half_height >= 0;
    case ShapeType::Hull: return good && s.hull != nullptr;
    case ShapeType::Mesh: return good && s.mesh != nullptr;
    case ShapeType::Compound: return good && s.compound != nullptr;
  }
  return false;
}

void Collider::validate(std::string_view where) const {
  // shape
  switch (shape.type) {
    case ShapeType::Plane:
      if (!is_finite(shape.normal)) require_finite(shape.normal, field_path(where, "normal"));
      if (glm::length(shape.normal) == 0)
        throw Error(field_path(where, "normal") + ": must be non-zero, got (0, 0, 0)");
      if (!std::isfinite(shape.offset)) require_finite(shape.offset, field_path(where, "offset"));
      break;
    case ShapeType::Sphere:
      if (!(std::isfinite(shape.radius) && (shape.radius) > 0))
        require_positive(shape.radius, field_path(where, "radius"));
      break;
    case ShapeType::Box:
      if (!(std::isfinite(shape.half_extents.x) && (shape.half_extents.x) > 0))
        require_positive(shape.half_extents.x, field_path(where, "half_extents.x"));
      if (!(std::isfinite(shape.half_extents.y) && (shape.half_extents.y) > 0))
        require_positive(shape.half_extents.y, field_path(where, "half_extents.y"));
      if (!(std::isfinite(shape.half_extents.z) && (shape.half_extents.z) > 0))
        require_positive(shape.half_extents.z, field_path(where, "half_extents.z"));
      break;
    case ShapeType::Capsule:
      if (!(std::isfinite(shape.radius) && (shape.radius) > 0))
        require_positive(shape.radius, field_path(where, "radius"));
      if (!(std::isfinite(shape.half_height) && shape.half_height >= 0))
        require_non_negative(shape.half_height, field_path(where, "half_height"));
      break;
    case ShapeType::Hull:
    case ShapeType::Mesh:
    case ShapeType::Compound: shape.validate(where); break;  // the body is there
  }
  // material and motion
  if (!((material.restitution) >= (0) && (material.restitution) <= (1)))
    require_in_range(material.restitution, 0, 1, field_path(where, "restitution"));
  if (!(std::isfinite(material.friction) && (material.friction) >= 0))
    require_non_negative(material.friction, field_path(where, "friction"));
  if (!is_finite(begin.position)) require_finite(begin.position, field_path(where, "position"));
  if (!is_finite(end.position)) require_finite(end.position, field_path(where, "position"));
  require_unit_quat(begin.rotation, field_path(where, "rotation"));
  require_unit_quat(end.rotation, field_path(where, "rotation"));
  if (!is_finite(velocity)) require_finite(velocity, field_path(where, "velocity"));
  if (!is_finite(angular_velocity)) require_finite(angular_velocity, field_path(where, "angular_velocity"));
  // finite doubles that a float cannot hold
  if (!fits_float(begin.position)) require_float(begin.position, field_path(where, "position"));
  if (!fits_float(end.position)) require_float(end.position, field_path(where, "position"));
  if (!fits_float(velocity)) require_float(velocity, field_path(where, "velocity"));
  if (!fits_float(angular_velocity)) require_float(angular_velocity, field_path(where, "angular_velocity"));
  if (!fits_float(shape.normal)) require_float(shape.normal, field_path(where, "normal"));
  if (!fits_float(shape.offset)) require_float(shape.offset, field_path(where, "offset"));
  if (!fits_float(shape.radius)) require_float(shape.radius, field_path(where, "radius"));
  if (!fits_float(shape.half_extents)) require_float(shape.half_extents, field_path(where, "half_extents"));
  if (!fits_float(shape.half_height)) require_float(shape.half_height, field_path(where, "half_height"));
}

namespace {

// a hull's faces as triangle fans, its edges darker on top; a mesh's triangles; a
// compound's children at their poses
void draw_body(DebugDraw& draw, const ColliderShape& s, const Pose& p, Color c) {
  const Color edge = Color::rgb(c.r * 0.5f, c.g * 0.5f, c.b * 0.5f, c.a);
  switch (s.type) {
    case ShapeType::Sphere: draw.sphere(p.position, s.radius, c); break;
    case ShapeType::Box: draw.box(p.position, s.half_extents, p.rotation, c); break;
    case ShapeType::Capsule: {
      const Vec3 axis = p.rotation * Vec3(0, s.half_height, 0);
      draw.capsule(p.position - axis, p.position + axis, s.radius, c);
      break;
    }
    case ShapeType::Hull: {
      const auto v = s.hull->vertices();
      const auto e = s.hull->edges();
      for (const ConvexHull::Face& f : s.hull->faces()) {
        const Vec3 a = apply(p, v[e[f.edge].origin]);
        for (std::uint32_t k = e[f.edge].next; e[k].next != f.edge; k = e[k].next)
          draw.triangle(a, apply(p, v[e[k].origin]), apply(p, v[e[e[k].next].origin]), c);
      }
      for (std::size_t i = 0; i < e.size(); i += 2)
        draw.line(apply(p, v[e[i].origin]), apply(p, v[e[i + 1].origin]), edge);
      break;
    }
    case ShapeType::Mesh: {
      const auto v = s.mesh->vertices();
      for (const auto& t : s.mesh->triangles()) {
        const Vec3 a = apply(p, v[t[0]]), b = apply(p, v[t[1]]), cc = apply(p, v[t[2]]);
        // two-sided: both windings, so a renderer that culls back faces shows it from either side
        draw.triangle(a, b, cc, c);
        draw.triangle(a, cc, b, c);
      }
      break;
    }
    case ShapeType::Compound:
      for (const CompoundChild& ch : s.compound->children) draw_body(draw, ch.shape, compose(p, ch.pose), c);
      break;
    case ShapeType::Plane: break;  // drawn by the caller (a patch about the origin)
  }
}

}  // namespace

void Collider::draw(DebugDraw& draw, Color c, const DrawFlags& flags) const {
  // the shape at its end pose
  if (flags.shapes) {
    switch (shape.type) {
      case ShapeType::Plane: {
        const Vec3 n = glm::normalize(end.rotation * shape.normal);
        draw.plane(n, shape.offset + glm::dot(n, end.position), 10.0, c);
        break;
      }
      default: draw_body(draw, shape, end, c); break;  // the solids
    }
  }
  // world bounds of the solids (a plane's are unbounded)
  if (flags.aabbs && shape.type != ShapeType::Plane) draw_box_edges(draw, bounds(shape, end), c);
}

}  // namespace pba
