// Private helpers of the world queries (query.cpp, query_shape.cpp): input checks that build
// a message only for bad input, the tree traversals, and a bounded sorted output.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>

#include "pba/collide/broad_phase.h"
#include "pba/collide/shape.h"

namespace pba::query {

/// True when the shape's parameters are valid (ColliderShape::validate would not throw).
bool shape_ok(const ColliderShape& s);
/// True when the pose is finite with a unit rotation (to 1e-6).
bool pose_ok(const Pose& p);
/// Throws Error naming `where`.position or `where`.rotation unless pose_ok(p).
void check_pose(const Pose& p, std::string_view where);
/// `d` / |d| for a finite non-zero d; else an Error naming `where`.
Vec3 unit_direction(const Vec3& d, std::string_view where);
/// The ray with a unit direction; an Error names `where`.origin, .direction or .max_distance.
Ray checked_ray(const Ray& r, std::string_view where);
/// Throws Error naming `where` unless `s` is a valid convex shape at a valid pose `p`.
void check_convex(const ColliderShape& s, const Pose& p, std::string_view where);

/// Depth of the traversal stacks: above the tree's height limit for any count in memory.
inline constexpr int kStack = 256;

/// Sweeps the box [lo_ext, hi_ext] about the point o + t d, t in [0, max_t], through the
/// tree: calls f(user, max_t) for every leaf whose fat box the swept box touches, nearest
/// entry first (a ray when both extents are zero). f returns the new max_t (<= the current
/// one, to clip) or a negative value to stop. The leaf box grown by the Minkowski sum
/// (lo - hi_ext, hi - lo_ext) is tested with the slab test. Never allocates.
template <class F>
void sweep(const DynamicTree& tree, const Vec3& o, const Vec3& d, double max_t, const Vec3& lo_ext,
           const Vec3& hi_ext, F&& f) {
  if (tree.root() == DynamicTree::kNull) return;
  const auto nodes = tree.nodes();
  const Vec3 inv(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
  Ray r{o, d, max_t};
  auto enter = [&](std::int32_t n) {
    const Aabb& b = nodes[static_cast<std::size_t>(n)].box;
    return ray_enter_box(r, inv, {b.lo - hi_ext, b.hi - lo_ext});
  };
  // the stack holds each node with the distance at which the swept box enters it
  struct Item {
    std::int32_t node;
    double enter;
  };
  Item stack[kStack];
  int top = 0;
  const double t_root = enter(tree.root());
  if (t_root < 0) return;
  stack[top++] = {tree.root(), t_root};
  while (top > 0) {
    const Item it = stack[--top];
    // clipped since it was pushed
    if (it.enter > r.max_distance) continue;
    const DynamicTree::Node& n = nodes[static_cast<std::size_t>(it.node)];
    if (n.is_leaf()) {
      const double clip = f(n.user, r.max_distance);
      if (clip < 0) return;
      if (clip < r.max_distance) r.max_distance = clip;
      continue;
    }
    // the farther child first, so the nearer one is visited first
    const double t1 = enter(n.child1), t2 = enter(n.child2);
    if (t1 >= 0 && t2 >= 0) {
      const bool first = t1 <= t2;
      stack[top++] = first ? Item{n.child2, t2} : Item{n.child1, t1};
      stack[top++] = first ? Item{n.child1, t1} : Item{n.child2, t2};
    } else if (t1 >= 0) {
      stack[top++] = {n.child1, t1};
    } else if (t2 >= 0) {
      stack[top++] = {n.child2, t2};
    }
  }
}

/// The squared distance between two boxes (m^2; 0 when they overlap).
inline double box_distance2(const Aabb& a, const Aabb& b) {
  const Vec3 g = glm::max(Vec3(0.0), glm::max(a.lo - b.hi, b.lo - a.hi));
  return glm::dot(g, g);
}

/// Visits the leaves whose fat boxes are within sqrt(bound2()) of `box`, nearer subtrees
/// first: f(user) is called for each, and bound2() (a squared distance, re-read after every
/// call, so the caller can shrink it) prunes the rest. Never allocates.
template <class B, class F>
void nearest(const DynamicTree& tree, const Aabb& box, B&& bound2, F&& f) {
  if (tree.root() == DynamicTree::kNull) return;
  const auto nodes = tree.nodes();
  auto dist2 = [&](std::int32_t n) { return box_distance2(nodes[static_cast<std::size_t>(n)].box, box); };
  struct Item {
    std::int32_t node;
    double d2;
  };
  Item stack[kStack];
  int top = 0;
  stack[top++] = {tree.root(), dist2(tree.root())};
  while (top > 0) {
    const Item it = stack[--top];
    if (it.d2 > bound2()) continue;
    const DynamicTree::Node& n = nodes[static_cast<std::size_t>(it.node)];
    if (n.is_leaf()) {
      f(n.user);
      continue;
    }
    // the farther child first
    const double d1 = dist2(n.child1), d2 = dist2(n.child2);
    const bool first = d1 <= d2;
    stack[top++] = first ? Item{n.child2, d2} : Item{n.child1, d1};
    stack[top++] = first ? Item{n.child1, d1} : Item{n.child2, d2};
  }
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
