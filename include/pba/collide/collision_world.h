// pba collide, the collision world: the world-space shapes of one tick, for every client.
//
// A CollisionWorld holds the colliders of the tick in order (each with the id of the
// entity that owns it, its material, and its begin and end poses) and, computed once when
// a collider is added, the flat per-shape form that the point contact reads
// (detail::FlatShape, in float for the vectorised particle kernel and in double for the
// soft-body solvers). Particles and soft bodies query it instead of taking their own
// spans of colliders and flattening them again each step. There is no cap on the number
// of shapes; the arrays grow geometrically and are reused, so a world refilled each tick
// with the same count never allocates.
//
//   pba::CollisionWorld cw;
//   cw.add(pba::Collider::plane({0, 1, 0}, 0.0), ground_id);
//   particles.step(t, dt, cw, forcers);
//   cloth.step(t, dt, cw);
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "pba/collide/collider.h"

namespace pba {

namespace detail {

/// A collider flattened for the point contact over one tick (collide/point_contact.h):
/// scalars in T (float for the particle kernel, double for the soft bodies), all of them
/// computed in double from the Collider and rounded once.
template <class T>
struct FlatShape {
  ShapeType type = ShapeType::Plane;
  T e = 0, mu = 0;                           ///< restitution and friction of the surface
  T n0x = 0, n0y = 1, n0z = 0, d0 = 0;       ///< plane at the start of the tick (unit normal, offset)
  T n1x = 0, n1y = 1, n1z = 0, d1 = 0;       ///< plane at the end
  T c0x = 0, c0y = 0, c0z = 0;               ///< frame origin (sphere or box centre) at the start
  T c1x = 0, c1y = 0, c1z = 0;               ///< and at the end (m)
  T radius = 0;                              ///< sphere and capsule radius (m)
  T hh = 0;                                  ///< capsule: half the core segment's length along local +Y (m)
  T hx = 0, hy = 0, hz = 0;                  ///< box half extents (m)
  T r0[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};     ///< rotation at the start, column-major (column j = local axis j)
  T r1[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};     ///< rotation at the end
  T vx = 0, vy = 0, vz = 0;                  ///< linear velocity of the frame origin (m/s)
  T wx = 0, wy = 0, wz = 0;                  ///< angular velocity (rad/s)
  bool is_static = true;                     ///< same pose at start and end, no velocity
};

/// The flat form of a valid collider (planes, spheres, boxes and capsules).
template <class T>
FlatShape<T> flatten(const Collider& c);

}  // namespace detail

/// The world-space shapes of one tick. Fill it (clear() then add(), or assign()), then
/// hand it to the clients. Not thread-safe to fill; const access may be shared.
class CollisionWorld {
 public:
  /// Owner id of a shape that belongs to no entity.
  static constexpr std::uint32_t kNoOwner = 0xffffffffu;

  /// Removes every shape; keeps the capacity (no allocation on refill).
  void clear();
  /// Adds a collider for this tick and returns its index. Validates it: an Error names
  /// `where` and the bad field, or the shape type that particles and soft bodies cannot
  /// collide with yet. `owner` is the client's id (the World passes the entity index).
  std::size_t add(const Collider& c, std::uint32_t owner = kNoOwner, std::string_view where = "collider");
  /// Replaces every shape by `colliders` (no owners); an Error names `where`[i].
  void assign(std::span<const Collider> colliders, std::string_view where = "colliders");
  /// Replaces shape i (same validation as add(); the owner is kept).
  void set(std::size_t i, const Collider& c, std::string_view where = "collider");

  /// Shapes this tick.
  std::size_t size() const { return colliders_.size(); }
  /// True when there are no shapes.
  bool empty() const { return colliders_.empty(); }
  /// The colliders, in the order added.
  std::span<const Collider> colliders() const { return colliders_; }
  /// The owner id of each collider (parallel to colliders()).
  std::span<const std::uint32_t> owners() const { return owners_; }
  /// The flat forms in float (parallel to colliders()), for the particle kernel.
  std::span<const detail::FlatShape<float>> flat_float() const { return flat_f_; }
  /// The flat forms in double (parallel to colliders()), for the soft bodies.
  std::span<const detail::FlatShape<double>> flat_double() const { return flat_d_; }

  /// A counter bumped by every change (clear, add, assign, set): a client caching something
  /// built from the world (a QueryWorld) rebuilds when it differs from the one it saw.
  std::uint64_t revision() const { return revision_; }

  /// Draws every shape at its end pose (DrawFlags::shapes, DrawFlags::aabbs).
  void draw(DebugDraw& draw, Color c, const DrawFlags& flags = {}) const;

 private:
  std::size_t push(const Collider& c, std::uint32_t owner);  // add() after validation
  std::vector<Collider> colliders_;
  std::vector<std::uint32_t> owners_;
  std::vector<detail::FlatShape<float>> flat_f_;
  std::vector<detail::FlatShape<double>> flat_d_;
  std::uint64_t revision_ = 0;
};

}  // namespace pba
