// pba collide, world queries: ray casts, shape casts, overlap and distance queries over a
// whole set of colliders.
//
// A QueryWorld is built from a CollisionWorld (or a span of colliders with owners) at the
// colliders' end-of-tick poses. It keeps a copy of each shape and pose, and a dynamic AABB
// tree (broad_phase.h) over their bounds; planes, whose bounds are infinite, sit in a short
// list beside the tree and are tested by every query. Rebuilding it from a world of the same
// size refits the tree (a collider that stayed in its fat box costs nothing) and never
// allocates; a world of another size rebuilds the tree.
//
// Every query takes a QueryFilter (layers and masks as the broad phase's CollisionFilter, an
// owner to ignore, an optional predicate) and reports the collider's index in the world and
// its owner. Results are deterministic: ties in distance go to the lower collider index,
// whatever order the tree visits the leaves in. No query allocates.
//
//   pba::QueryWorld q;
//   q.build(world.collision());
//   pba::QueryRayHit h = q.ray_cast({origin, direction, 10.0});
//   pba::ShapeCastHit s = q.sphere_cast({origin, direction, 10.0}, 0.25);
//
// Conventions: metres, world frame. A direction may have any finite non-zero length: it is
// normalised, and distances are measured along the unit direction. Positions and sizes (the
// colliders', a query point's, a query shape's pose and size) must fit a float (|x| <=
// 3.4e38), the range of the colliders everywhere in pba: the queries compare squared
// distances, which would overflow beyond ~1.3e154 m and miss the nearest collider. A value
// outside it is refused with an Error naming it. A ray's origin may be any finite point.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <string_view>
#include <vector>

#include "pba/collide/broad_phase.h"
#include "pba/collide/collider.h"
#include "pba/collide/collision_world.h"
#include "pba/collide/shape.h"
#include "pba/core.h"

namespace pba {

/// A caller's test on a candidate collider: `fn(context, collider, owner)` returns false to
/// skip it. A plain function pointer and a context pointer (no allocation, no ownership).
struct QueryPredicate {
  bool (*fn)(const void* context, std::uint32_t collider, std::uint32_t owner) = nullptr;  ///< null: accept all
  const void* context = nullptr;  ///< passed to fn; must outlive the query

  /// A predicate that calls `f(collider, owner)`; `f` must outlive the query.
  template <class F>
  static QueryPredicate of(const F& f) {
    return {[](const void* c, std::uint32_t i, std::uint32_t o) {
              return static_cast<bool>((*static_cast<const F*>(c))(i, o));
            },
            &f};
  }
};

/// Which colliders a query sees. Collider i (with the CollisionFilter given at build, by
/// default layer 1 and every mask bit) is accepted when (layer & i.mask) and (i.layer & mask)
/// are both non-zero, its owner is not `ignore_owner`, and the predicate (if any) accepts it.
struct QueryFilter {
  std::uint64_t layer = 1;     ///< the layers the query is in (bits)
  std::uint64_t mask = ~0ull;  ///< the collider layers it accepts (bits)
  /// Skip the colliders of this owner (a character's own capsule); CollisionWorld::kNoOwner
  /// skips nothing.
  std::uint32_t ignore_owner = CollisionWorld::kNoOwner;
  QueryPredicate accept{};  ///< optional last test
};

/// A ray's hit on a collider of the world.
struct QueryRayHit {
  bool hit = false;                                 ///< false: no collider hit (the other fields are unset)
  double distance = 0;                              ///< along the unit direction (m), in [0, max_distance]
  Vec3 point{0, 0, 0};                              ///< hit point (m)
  Vec3 normal{0, 0, 0};                             ///< unit outward normal (-direction for a ray starting inside)
  std::uint32_t feature = 0;                        ///< the shape's face, triangle or child (see ray_cast())
  std::uint32_t collider = 0;                       ///< index of the collider in the world
  std::uint32_t owner = CollisionWorld::kNoOwner;   ///< its owner id
};

/// Where a moving shape first touches a collider.
struct ShapeCastHit {
  bool hit = false;      ///< false: no collider touched within max_distance (the other fields are unset)
  /// Time of impact as a distance along the unit direction (m), in [0, max_distance]; 0 when
  /// the shape overlaps the collider at its start.
  double distance = 0;
  double fraction = 0;   ///< distance / max_distance in [0, 1] (0 when max_distance is 0)
  Vec3 point{0, 0, 0};   ///< contact point on the collider's surface at the time of impact (m)
  /// Unit normal of the collider's surface at the contact, pointing towards the moving shape
  /// (-direction when they overlap at the start).
  Vec3 normal{0, 0, 0};
  std::uint32_t collider = 0;                      ///< index of the collider in the world
  std::uint32_t owner = CollisionWorld::kNoOwner;  ///< its owner id
};

/// The nearest collider to a point or a shape.
struct QueryDistance {
  bool found = false;  ///< false: no collider within max_distance (the other fields are unset)
  /// Point queries: signed distance to the surface (m; negative inside a solid, its depth).
  /// Shape queries: distance between the surfaces (m), 0 when they overlap.
  double distance = 0;
  Vec3 point{0, 0, 0};        ///< closest point on the collider's surface (m)
  Vec3 query_point{0, 0, 0};  ///< closest point on the query shape (m); the query point itself for points
  /// Unit normal of the collider at `point` (outward, towards the query); for a shape that
  /// overlaps the collider (distance 0) it is not a contact normal (use the narrow phase).
  Vec3 normal{0, 1, 0};
  std::uint32_t collider = 0;                      ///< index of the collider in the world
  std::uint32_t owner = CollisionWorld::kNoOwner;  ///< its owner id
};

/// World queries over a set of colliders at their end poses. Build it, then query it; const
/// queries may run concurrently. Every collider shape type is supported by ray casts and
/// point distances; shape casts, overlaps and shape distances take a convex query shape
/// (sphere, capsule, box, hull) against any collider shape (plane, convex, mesh, compound).
class QueryWorld {
 public:
  /// Fat-box margin of the tree (m): a collider that moves less than this between builds
  /// keeps its leaf.
  static constexpr double kTreeMargin = 0.1;

  /// Builds over the colliders of `world` (their owners; every collider in layer 1 with a
  /// full mask). Same size as the last build: refit, no allocation.
  void build(const CollisionWorld& world);
  /// Builds over `colliders` (validated shapes and end poses, within a float's range; an Error
  /// names `where`[i] and the field).
  /// `owners` and `filters` are empty or parallel to `colliders` (an Error names the one
  /// of the wrong length).
  void build(std::span<const Collider> colliders, std::span<const std::uint32_t> owners = {},
             std::span<const CollisionFilter> filters = {}, std::string_view where = "colliders");
  /// Sets collider i's layers (CollisionFilter::layer and mask; its owner field is unused).
  void set_filter(std::size_t i, const CollisionFilter& filter);

  /// Colliders in the query world.
  std::size_t size() const { return shapes_.size(); }
  /// Shape of collider i.
  const ColliderShape& shape(std::size_t i) const { return shapes_[i]; }
  /// Pose of collider i (its end pose).
  const Pose& pose(std::size_t i) const { return poses_[i]; }
  /// Owner of collider i.
  std::uint32_t owner(std::size_t i) const { return owners_[i]; }
  /// World bounds of collider i (infinite for planes).
  const Aabb& bounds(std::size_t i) const { return bounds_[i]; }
  /// The tree over the bounded colliders (leaf user values are collider indices).
  const DynamicTree& tree() const { return tree_; }
  /// A node of the flat copy of the tree that the queries traverse (made at every build, in
  /// depth-first order): both children's boxes side by side, so a step reads one node. The
  /// boxes are tight (the colliders' bounds and their unions), not the tree's fat ones.
  struct Node {
    Aabb box[2];              ///< the children's boxes
    std::int32_t child[2]{};  ///< >= 0: a node index; < 0: the leaf of collider ~child
  };
  /// The flat tree's nodes (empty when it has fewer than two leaves).
  std::span<const Node> nodes() const { return flat_; }
  /// The flat tree's root: a node index, ~collider for a single leaf, or kEmpty.
  std::int32_t root() const { return root_; }
  /// root() of a tree without leaves.
  static constexpr std::int32_t kEmpty = std::numeric_limits<std::int32_t>::max();
  /// True when `filter` accepts collider i.
  bool accepts(const QueryFilter& filter, std::uint32_t i) const;

  // --- ray casts ---
  /// The closest hit of `ray` (origin finite, direction finite and non-zero, max_distance
  /// finite and >= 0; an Error names the bad field), ties to the lower collider index.
  QueryRayHit ray_cast(const Ray& ray, const QueryFilter& filter = {}) const;
  /// Any hit of `ray` (the first one found: stops the traversal there); hit == false when
  /// none. Cheaper than ray_cast() for line-of-sight tests.
  QueryRayHit ray_cast_any(const Ray& ray, const QueryFilter& filter = {}) const;
  /// Every collider `ray` hits (one hit per collider, its closest), sorted by distance, ties
  /// by collider index. Writes the first min(total, out.size()) of that order to `out` and
  /// returns the total.
  std::size_t ray_cast_all(const Ray& ray, std::span<QueryRayHit> out, const QueryFilter& filter = {}) const;
  /// ray_cast() for each ray: hits[i] for rays[i] (equal lengths, else an Error). Returns
  /// how many rays hit.
  std::size_t ray_cast(std::span<const Ray> rays, std::span<QueryRayHit> hits, const QueryFilter& filter = {}) const;

  // --- shape casts ---
  /// Sweeps a sphere of `radius` (finite, > 0) whose centre moves along `path` (origin:
  /// the start, direction and max_distance as for rays); the first collider it touches.
  /// Exact (closed forms) against spheres, capsules, boxes and planes: the ray against the
  /// target grown by the radius; conservative advancement on GJK distance for hulls, mesh
  /// triangles and compound children (see shape_cast()).
  ShapeCastHit sphere_cast(const Ray& path, double radius, const QueryFilter& filter = {}) const;
  /// Sweeps a convex `shape` (sphere, capsule, box or hull) from pose `start` by translation
  /// along `direction` for up to `max_distance`; the first collider it touches. Against a
  /// plane the time of impact is exact (the support point's); against convex shapes, mesh
  /// triangles and compound children it is found by conservative advancement on the GJK
  /// distance (Mirtich 1996; Coumans 2006): each step advances by distance / approach speed,
  /// which never passes the contact, until the gap is below kCastTolerance. A sphere takes
  /// sphere_cast()'s closed forms.
  ShapeCastHit shape_cast(const ColliderShape& shape, const Pose& start, const Vec3& direction, double max_distance,
                          const QueryFilter& filter = {}) const;
  /// Conservative advancement stops when the shapes are closer than this (m). The time of
  /// impact is then within kCastTolerance / (approach speed along the normal) before the
  /// exact one (ill-conditioned only for grazing contacts).
  static constexpr double kCastTolerance = 1e-10;

  // --- overlaps ---
  /// The colliders that the convex `shape` at `pose` overlaps or touches (GJK distance 0;
  /// a plane when the shape's lowest point is on or below it; a mesh when a triangle
  /// does; a compound when a child does), in increasing collider index. Writes the first
  /// min(total, out.size()) to `out` and returns the total.
  std::size_t overlap(const ColliderShape& shape, const Pose& pose, std::span<std::uint32_t> out,
                      const QueryFilter& filter = {}) const;
  /// The colliders whose bounds overlap `box` (finite, lo <= hi), in increasing index.
  /// Writes the first min(total, out.size()) and returns the total.
  std::size_t overlap_bounds(const Aabb& box, std::span<std::uint32_t> out, const QueryFilter& filter = {}) const;

  // --- distances ---
  /// The collider whose surface is nearest `point` (|component| <= 3.4e38) by signed
  /// distance (point_distance()), among those within `max_distance` (finite, >= 0); ties
  /// to the lower index.
  QueryDistance closest_point(const Vec3& point, double max_distance, const QueryFilter& filter = {}) const;
  /// The collider nearest the convex `shape` at `pose` (GJK distance; 0 when overlapping,
  /// the lower index among overlapping ones) within `max_distance`, with the closest
  /// points on both.
  QueryDistance closest_shape(const ColliderShape& shape, const Pose& pose, double max_distance,
                              const QueryFilter& filter = {}) const;

 private:
  void push(const Collider& c, std::uint32_t owner);
  void refit();
  void flatten();
  std::vector<ColliderShape> shapes_;
  std::vector<Pose> poses_;
  std::vector<std::uint32_t> owners_;
  std::vector<CollisionFilter> filters_;
  std::vector<Aabb> bounds_;
  std::vector<std::int32_t> leaf_;        // tree leaf of each collider, kNull for planes
  std::vector<std::uint32_t> unbounded_;  // colliders outside the tree (planes), increasing
  DynamicTree tree_{kTreeMargin};
  std::vector<Node> flat_;                // the tree, flattened for the traversals
  std::int32_t root_ = kEmpty;
};

}  // namespace pba
