// Rigid bodies: debug drawing through the library's DebugDraw (the app and any client).
#include <cmath>

#include "contacts.h"
#include "pba/collide/collider.h"

namespace pba {

namespace {

Color fade(Color c, float amount) {
  // toward a mid grey, keeping the hue readable
  const float g = 0.55f;
  return {c.r + (g - c.r) * amount, c.g + (g - c.g) * amount, c.b + (g - c.b) * amount, c.a};
}

}  // namespace

void RigidBodySystem::draw(DebugDraw& draw, const DrawFlags& flags, const RigidDrawOptions& options) const {
  for (std::size_t i = 0; i < type_.size(); ++i) {
    Color c = type_[i] == BodyType::Static ? options.fixed
              : type_[i] == BodyType::Kinematic ? options.kinematic
              : options.palette.empty() ? options.dynamic
                                        : options.palette[i % options.palette.size()];
    if (options.highlight.index == owner_[i] && ids_.valid(options.highlight)) c = options.highlight_color;
    if (asleep_[i]) c = fade(c, options.sleep_fade);
    draw_shapes(draw, i, c, flags, options);
  }
  draw_contacts(draw, flags);
}

void RigidBodySystem::draw_body(DebugDraw& draw, RigidBodyId id, Color color, const DrawFlags& flags,
                                const RigidDrawOptions& options) const {
  draw_shapes(draw, index(id, "RigidBodySystem::draw_body"), color, flags, options);
}

void RigidBodySystem::draw_shapes(DebugDraw& draw, std::size_t i, Color c, const DrawFlags& flags,
                                  const RigidDrawOptions& options) const {
  // each shape at the body's pose, through the colliders' drawing (one switch over shapes)
  const Pose body = body_pose(i);
  for (const RigidShapeDef& d : shapes_[i]) {
    Collider shape;
    shape.shape = d.shape;
    shape.begin = shape.end = detail::shape_frame(body, d.local);
    if (d.shape.type == ShapeType::Plane) {
      // a plane through the body's frame, drawn `plane_half_size` wide
      if (!flags.shapes) continue;
      const Vec3 n = glm::normalize(shape.end.rotation * d.shape.normal);
      if (!options.horizontal_planes && std::abs(n.y) > 0.999) continue;
      draw.plane(n, d.shape.offset / glm::length(d.shape.normal) + glm::dot(n, shape.end.position),
                 options.plane_half_size, c);
      continue;
    }
    shape.draw(draw, c, flags);
  }
}

void RigidBodySystem::draw_contacts(DebugDraw& draw, const DrawFlags& flags) const {
  // contact points of the last step and their normals
  if (!(flags.contacts || flags.normals) || !contacts_) return;  // (none in a moved-from system)
  for (const detail::ContactPair& cp : contacts_->pairs)
    for (int k = 0; k < cp.count; ++k) {
      const Vec3& at = cp.points[k].at;
      if (flags.contacts) draw.point(at, 6.0f, cp.depth[k] > 0 ? colors::red : colors::green);
      if (flags.normals) draw.arrow(at, at + 0.3 * cp.normal, 0.06, colors::orange);
    }
}

}  // namespace pba
