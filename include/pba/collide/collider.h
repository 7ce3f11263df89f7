// pba collide, colliders: the flat world-space shape every collision client reads.
//
// A Collider is one surface during one tick: a shape in its own frame, a material, and the
// frame's pose at the start and at the end of the tick (equal for a static surface), with
// the frame's velocities for friction and bounces. Particles, soft bodies (and, later,
// rigid bodies) read colliders from a CollisionWorld (collide/collision_world.h); none of
// them keeps a private copy of the geometry.
//
//   pba::Collider ground = pba::Collider::plane({0, 1, 0}, 0.0, {.restitution = 0.8});
//   pba::Collider ball = pba::Collider::sphere({0, 0.5, 0}, 0.3);
#pragma once

#include <string_view>

#include "pba/collide/shape.h"
#include "pba/core.h"
#include "pba/draw.h"

namespace pba {

/// One collision surface as its clients see it during one tick: its shape, its
/// material, and its pose at the start and the end of the tick (equal for a static
/// surface). The motion in between is taken as linear, so moving surfaces are swept too.
/// Particles and soft bodies collide with every shape type: planes, spheres, boxes and
/// capsules in closed form, convex hulls, triangle meshes and compounds on the generic
/// point contact (collide/point_contact.h).
struct Collider {
  ColliderShape shape{};           ///< shape in the surface's frame
  SurfaceMaterial material{};      ///< restitution and friction
  Pose begin{};                    ///< pose at the start of the step
  Pose end{};                      ///< pose at the end of the step
  Vec3 velocity{0, 0, 0};          ///< linear velocity of the frame origin (m/s), for friction and bounces
  Vec3 angular_velocity{0, 0, 0};  ///< angular velocity (rad/s) about the frame origin

  /// A static world plane { p : normal . p = offset } (normal need not be unit).
  static Collider plane(const Vec3& normal, double offset, SurfaceMaterial m = {});
  /// A static sphere.
  static Collider sphere(const Vec3& center, double radius, SurfaceMaterial m = {});
  /// A static axis-aligned (or rotated) box.
  static Collider box(const Vec3& center, const Vec3& half_extents, SurfaceMaterial m = {},
                      const Quat& rotation = Quat(1, 0, 0, 0));
  /// Throws Error naming `where` and the bad field (non-finite pose, zero normal, radius
  /// or half extent <= 0, restitution outside [0, 1], negative friction, a hull, mesh or
  /// compound without its body).
  void validate(std::string_view where) const;
  /// True when validate() would not throw (no allocation: the hot paths check this first
  /// and build the message only for a bad collider).
  bool ok() const;
  /// True when the shape's parameters and the material pass validate() (the poses and
  /// velocities aside): ok() without a Collider, read in place (no copy of the shape's
  /// shared hull, mesh or compound).
  static bool shape_ok(const ColliderShape& shape, const SurfaceMaterial& material);
  /// Draws the surface at its end pose: the shape when `flags.shapes` (hull faces and
  /// edges, mesh triangles, compound children too), its world bounds when `flags.aabbs`.
  void draw(DebugDraw& draw, Color c, const DrawFlags& flags = {}) const;
};

}  // namespace pba
