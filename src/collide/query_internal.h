// Private helpers of the world queries (query.cpp, query_shape.cpp): input checks that build
// a message only for bad input, the tree traversals, and a bounded sorted output.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <string_view>

#include "pba/collide/query.h"
#include "pba/collide/shape.h"

namespace pba::query {

/// True when the shape's parameters are valid (ColliderShape::validate would not throw)
/// and its sizes fit a float (fits_float: the range of the colliders' positions and sizes,
/// within which the squared distances the queries compare cannot overflow; beyond ~1.3e154
/// they would, and the nearest collider would be missed).
bool shape_ok(const ColliderShape& s);
/// Throws Error naming `where` and the field unless shape_ok(s).
void check_shape(const ColliderShape& s, std::string_view where);
/// True when the pose's position fits a float and its rotation is unit (to 1e-6).
bool pose_ok(const Pose& p);
/// Throws Error naming `where`.position or `where`.rotation unless pose_ok(p).
void check_pose(const Pose& p, std::string_view where);
/// `d` / |d| for a finite non-zero d; else an Error naming `where`.
Vec3 unit_direction(const Vec3& d, std::string_view where);
/// The ray with a unit direction; an Error names `where`.origin, .direction or .max_distance.
Ray checked_ray(const Ray& r, std::string_view where);
/// pba::ray_cast() on a ray already checked (checked_ray: finite origin, unit direction,
/// max_distance >= 0), for the world queries' candidates: the same hit, without the check.
RayHit ray_cast_unit(const ColliderShape& s, const Pose& p, const Ray& ray);
/// pba::point_distance() without its checks of the point and the pose, for the library's
/// callers whose points and poses are checked where they come in (the same result).
PointDistance point_distance_unchecked(const ColliderShape& s, const Pose& p, const Vec3& world_point);
/// Throws Error naming `where` unless `s` is a valid convex shape at a valid pose `p`.
void check_convex(const ColliderShape& s, const Pose& p, std::string_view where);

/// Depth of the traversal stacks: above the tree's height limit for any count in memory.
inline constexpr int kStack = 256;

/// The slab test of a ray against boxes (Kay and Kajiya 1986), branch-free: the near and
/// far planes of each axis are chosen once by the direction's sign. On an axis the ray does
/// not move along, 1/d is infinite: the products are -inf or +inf (inside or outside the
/// slab) or NaN exactly on a plane, which the comparisons ignore (touching counts).
struct SlabRay {
  Vec3 o{0, 0, 0}, inv{0, 0, 0};
  bool neg[3] = {false, false, false};
  SlabRay(const Vec3& origin, const Vec3& d) : o(origin), inv(1.0 / d.x, 1.0 / d.y, 1.0 / d.z) {
    for (int k = 0; k < 3; ++k) neg[k] = std::signbit(d[k]);
  }
  /// Entry distance into the box [lo - hi_ext, hi - lo_ext] within [0, t_max], or -1.
  double enter(const Aabb& b, double t_max, const Vec3& lo_ext, const Vec3& hi_ext) const {
    double t0 = 0, t1 = t_max;
    for (int k = 0; k < 3; ++k) {
      const double lo = b.lo[k] - hi_ext[k], hi = b.hi[k] - lo_ext[k];
      const double tn = ((neg[k] ? hi : lo) - o[k]) * inv[k], tf = ((neg[k] ? lo : hi) - o[k]) * inv[k];
      t0 = tn > t0 ? tn : t0;
      t1 = tf < t1 ? tf : t1;
    }
    return t0 <= t1 ? t0 : -1;
  }
};

/// Depth-first through the flat tree (QueryWorld::nodes(), root), the nearer child first:
/// key(box) is a child's distance (negative: skip it), bound() the current limit (a child
/// popped farther than it is skipped), leaf(collider) visits a leaf and returns false to stop.
/// A single-leaf tree visits its leaf. Never allocates.
template <class K, class B, class L>
void descend(std::span<const QueryWorld::Node> nodes, std::int32_t root, K&& key, B&& bound, L&& leaf) {
  if (root == QueryWorld::kEmpty) return;
  if (root < 0) {
    leaf(static_cast<std::uint32_t>(~root));
    return;
  }
  struct Item {
    std::int32_t ref;
    double key;
  };
  Item stack[kStack];
  int top = 0;
  stack[top++] = {root, 0};
  while (top > 0) {
    const Item it = stack[--top];
    // the bound may have shrunk since it was pushed
    if (it.key > bound()) continue;
    if (it.ref < 0) {
      if (!leaf(static_cast<std::uint32_t>(~it.ref))) return;
      continue;
    }
    // both children from the one node, the farther pushed first so the nearer pops first
    const QueryWorld::Node& n = nodes[static_cast<std::size_t>(it.ref)];
    const double k1 = key(n.box[0]), k2 = key(n.box[1]);
    if (k1 >= 0 && k2 >= 0) {
      const bool first = k1 <= k2;
      stack[top++] = first ? Item{n.child[1], k2} : Item{n.child[0], k1};
      stack[top++] = first ? Item{n.child[0], k1} : Item{n.child[1], k2};
    } else if (k1 >= 0) {
      stack[top++] = {n.child[0], k1};
    } else if (k2 >= 0) {
      stack[top++] = {n.child[1], k2};
    }
  }
}

/// Sweeps the box [lo_ext, hi_ext] about the point o + t d, t in [0, max_t], through the
/// flat tree: calls f(collider, max_t) for every leaf whose box the swept box touches,
/// nearest entry first (a ray when both extents are zero); f returns the new max_t (<= the
/// current one, to clip) or a negative value to stop. Never allocates.
template <class F>
void sweep(std::span<const QueryWorld::Node> nodes, std::int32_t root, const Vec3& o, const Vec3& d, double max_t,
           const Vec3& lo_ext, const Vec3& hi_ext, F&& f) {
  const SlabRay ray(o, d);
  descend(
      nodes, root, [&](const Aabb& b) { return ray.enter(b, max_t, lo_ext, hi_ext); }, [&] { return max_t; },
      [&](std::uint32_t i) {
        const double clip = f(i, max_t);
        if (clip < 0) return false;
        if (clip < max_t) max_t = clip;
        return true;
      });
}

/// Calls f(collider) for every leaf of the flat tree whose box overlaps `box` (every
/// leaf of a single-leaf tree). Never allocates.
template <class F>
void overlapping(std::span<const QueryWorld::Node> nodes, std::int32_t root, const Aabb& box, F&& f) {
  if (root == QueryWorld::kEmpty) return;
  if (root < 0) {
    f(static_cast<std::uint32_t>(~root));
    return;
  }
  std::int32_t stack[kStack];
  int top = 0;
  stack[top++] = root;
  while (top > 0) {
    const QueryWorld::Node& n = nodes[static_cast<std::size_t>(stack[--top])];
    for (int k = 1; k >= 0; --k) {
      if (!n.box[k].overlaps(box)) continue;
      if (n.child[k] < 0)
        f(static_cast<std::uint32_t>(~n.child[k]));
      else
        stack[top++] = n.child[k];
    }
  }
}

/// The squared distance between two boxes (m^2; 0 when they overlap).
inline double box_distance2(const Aabb& a, const Aabb& b) {
  const Vec3 g = glm::max(Vec3(0.0), glm::max(a.lo - b.hi, b.lo - a.hi));
  return glm::dot(g, g);
}

/// Visits the leaves of the flat tree whose boxes are within sqrt(bound2()) of `box`,
/// nearer subtrees first: f(collider) is called for each, and bound2() (a squared distance,
/// re-read after every call, so the caller can shrink it) prunes the rest. Never allocates.
template <class B, class F>
void nearest(std::span<const QueryWorld::Node> nodes, std::int32_t root, const Aabb& box, B&& bound2, F&& f) {
  descend(
      nodes, root, [&](const Aabb& b) { return box_distance2(b, box); }, bound2,
      [&](std::uint32_t i) {
        f(i);
        return true;
      });
}

/// Inserts `v` into the sorted run out[0, min(count, out.size())) (count: items offered
/// before this one), keeping the out.size() smallest by `less`; equal items keep their
/// arrival order. Never allocates.
template <class T, class L>
void insert_sorted(std::span<T> out, std::size_t count, const T& v, L&& less) {
  std::size_t n = count < out.size() ? count : out.size();
  if (n == out.size()) {
    if (n == 0 || !less(v, out[n - 1])) return;
    --n;  // the last one drops out
  }
  std::size_t k = n;
  while (k > 0 && less(v, out[k - 1])) {
    out[k] = out[k - 1];
    --k;
  }
  out[k] = v;
}

}  // namespace pba::query
