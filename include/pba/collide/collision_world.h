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
  /// Hull, mesh, compound: the largest distance from the frame origin to a corner of the
  /// shape's local bounds (m), for the clients' broad phases.
  T reach = 0;
  /// Hull, mesh, compound: the collider itself (held by the CollisionWorld), whose double
  /// poses and shape body the generic point contact reads (collide/point_contact.h).
  const Collider* source = nullptr;
  /// Compound: its leaf children (spheres, boxes, capsules, hulls; nested compounds
  /// flattened), each flattened in double at its composed pose, held by the CollisionWorld.
  const FlatShape<double>* parts = nullptr;
  std::uint32_t first_part = 0;  ///< compound: index of parts[0] in the world's part list
  std::uint32_t n_parts = 0;     ///< compound: number of leaf children
};

/// The flat form of a valid collider. For a hull, mesh or compound the links (source,
/// parts) are left null: the CollisionWorld that holds the collider sets them.
template <class T>
FlatShape<T> flatten(const Collider& c);

}  // namespace detail

/// The world-space shapes of one tick. Fill it (clear() then add(), or assign()), then
/// hand it to the clients. Not thread-safe to fill; const access may be shared.
/// Hulls, meshes and compounds are held by their shared bodies; a compound's children are
/// flattened into a part list kept beside the shapes (reused on refill, like the shapes).
class CollisionWorld {
 public:
  CollisionWorld() = default;
  /// A copy links its flat forms to its own colliders and parts.
  CollisionWorld(const CollisionWorld& o);
  /// A copy links its flat forms to its own colliders and parts.
  CollisionWorld& operator=(const CollisionWorld& o);
  CollisionWorld(CollisionWorld&&) noexcept = default;             ///< the buffers (and links) move along
  CollisionWorld& operator=(CollisionWorld&&) noexcept = default;  ///< the buffers (and links) move along

  /// Owner id of a shape that belongs to no entity.
  static constexpr std::uint32_t kNoOwner = 0xffffffffu;

  /// Removes every shape; keeps the capacity (no allocation on refill).
  void clear();
  /// Adds a collider for this tick and returns its index. Validates it: an Error names
  /// `where` and the bad field. Every shape type is taken (planes, spheres, boxes,
  /// capsules, hulls, meshes, compounds). `owner` is the client's id (the World passes
  /// the entity index).
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
  void add_parts(const ColliderShape& s, const Collider& parent, const Pose& begin, const Pose& end);
  void link(std::size_t i);  // points flat form i at its collider and parts
  void relink();             // every flat form (after a buffer moved)
  std::vector<Collider> colliders_;
  std::vector<Collider> parts_;                       // compounds' leaf children, world poses
  std::vector<detail::FlatShape<double>> part_flat_;  // and their flat forms
  std::vector<std::uint32_t> owners_;
  std::vector<detail::FlatShape<float>> flat_f_;
  std::vector<detail::FlatShape<double>> flat_d_;
  std::uint64_t revision_ = 0;
};

}  // namespace pba
