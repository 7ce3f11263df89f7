// The dynamic AABB tree: a pool of nodes, SAH insertion with inherited cost (Catto 2019,
// "Dynamic Bounding Volume Hierarchies", GDC; Bittner, Hapala and Havran 2015, "Incremental
// BVH construction for ray tracing"), AVL rotations on the way back to the root (Adelson-
// Velsky and Landis 1962, as Box2D's b2DynamicTree uses them), and a binned-SAH rebuild.
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>

#include "pba/collide/broad_phase.h"

namespace pba {

void require_valid_box(const Aabb& box, std::string_view where) {
  // (the field paths are built only on failure: this runs for every moved proxy)
  if (!is_finite(box.lo)) require_finite(box.lo, field_path(where, "lo"));
  if (!is_finite(box.hi)) require_finite(box.hi, field_path(where, "hi"));
  static const char* axis[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k)
    if (box.lo[k] > box.hi[k])
      throw Error(std::string(where) + ": inverted box, lo " + format_vec3(box.lo) + " > hi " +
                  format_vec3(box.hi) + " on " + axis[k]);
}

DynamicTree::DynamicTree(double margin) : margin_(margin) {
  require_non_negative(margin, "DynamicTree.margin");
}

std::int32_t DynamicTree::allocate_node() {
  // reuse the free list, or grow the pool
  if (free_ != kNull) {
    const std::int32_t n = free_;
    free_ = at(n).parent;
    at(n) = Node{};
    return n;
  }
  nodes_.push_back(Node{});
  return static_cast<std::int32_t>(nodes_.size() - 1);
}

void DynamicTree::free_node(std::int32_t n) {
  Node& node = at(n);
  node.parent = free_;
  node.child1 = node.child2 = kNull;
  node.height = -1;
  free_ = n;
}

void DynamicTree::reserve(std::size_t leaves) {
  // a tree of n leaves has n - 1 inner nodes; at least doubled, so that a leaf added at a time
  // does not copy the pool each time
  const std::size_t need = leaves > 0 ? 2 * leaves - 1 : 0;
  if (need > nodes_.capacity()) nodes_.reserve(std::max(need, 2 * nodes_.capacity()));
}

void DynamicTree::clear() {
  nodes_.clear();
  root_ = free_ = kNull;
  leaves_ = 0;
}

std::int32_t DynamicTree::new_leaf(const Aabb& box, std::uint32_t user, std::string_view where) {
  require_valid_box(box, where);
  const std::int32_t leaf = allocate_node();
  Node& n = at(leaf);
  n.box = box.grown(margin_);
  n.user = user;
  n.height = 0;  // (a leaf, placed or not: rebuild() gathers every node of height 0)
  ++leaves_;
  return leaf;
}

std::int32_t DynamicTree::create_proxy(const Aabb& box, std::uint32_t user) {
  const std::int32_t leaf = new_leaf(box, user, "DynamicTree.create_proxy(box)");
  insert_leaf(leaf);
  keep_height();
  return leaf;
}

std::int32_t DynamicTree::create_proxy_unplaced(const Aabb& box, std::uint32_t user) {
  return new_leaf(box, user, "DynamicTree.create_proxy_unplaced(box)");
}

void DynamicTree::destroy_proxy(std::int32_t node) {
  if (node < 0 || static_cast<std::size_t>(node) >= nodes_.size() || at(node).height != 0)
    throw Error("DynamicTree.destroy_proxy: node " + std::to_string(node) + " is not a live leaf");
  remove_leaf(node);
  free_node(node);
  --leaves_;
}

bool DynamicTree::move_proxy(std::int32_t node, const Aabb& box) {
  // within the fat box: nothing to do (the common case)
  if (at(node).box.contains(box)) return false;
  // otherwise re-insert with a fresh fat box
  remove_leaf(node);
  at(node).box = box.grown(margin_);
  insert_leaf(node);
  keep_height();
  return true;
}

void DynamicTree::set_leaf_box(std::int32_t node, const Aabb& box) {
  if (node < 0 || static_cast<std::size_t>(node) >= nodes_.size() || at(node).height != 0)
    throw Error("DynamicTree.set_leaf_box: node " + std::to_string(node) + " is not a live leaf");
  require_valid_box(box, "DynamicTree.set_leaf_box(box)");
  at(node).box = box.grown(margin_);
  // each ancestor the union of its children again; one that keeps its box leaves the ones
  // above it as they were (each was the union of boxes that have not changed)
  for (std::int32_t n = at(node).parent; n != kNull; n = at(n).parent) {
    Node& inner = at(n);
    const Aabb joined = at(inner.child1).box.merged(at(inner.child2).box);
    if (joined.lo == inner.box.lo && joined.hi == inner.box.hi) break;
    inner.box = joined;
  }
}

void DynamicTree::insert_leaf(std::int32_t leaf) {
  if (root_ == kNull) {
    root_ = leaf;
    at(leaf).parent = kNull;
    return;
  }
  // descend to the sibling of least cost: making a new parent of a node costs the area of
  // the union, and every ancestor's growth is inherited by the nodes below it
  const Aabb box = at(leaf).box;
  std::int32_t index = root_;
  while (!at(index).is_leaf()) {
    const Node& n = at(index);
    const double area = n.box.area();
    const double combined = n.box.merged(box).area();
    const double cost_here = 2 * combined;
    const double inherited = 2 * (combined - area);
    auto child_cost = [&](std::int32_t c) {
      const Node& cn = at(c);
      const double grown = cn.box.merged(box).area();
      return (cn.is_leaf() ? grown : grown - cn.box.area()) + inherited;
    };
    const double cost1 = child_cost(n.child1), cost2 = child_cost(n.child2);
    if (cost_here < cost1 && cost_here < cost2) break;
    index = cost1 <= cost2 ? n.child1 : n.child2;
  }
  const std::int32_t sibling = index;

  // a new parent takes the sibling's place and holds sibling and leaf
  const std::int32_t old_parent = at(sibling).parent;
  const std::int32_t parent = allocate_node();
  Node& p = at(parent);
  p.parent = old_parent;
  p.box = at(sibling).box.merged(box);
  p.height = at(sibling).height + 1;
  p.child1 = sibling;
  p.child2 = leaf;
  at(sibling).parent = parent;
  at(leaf).parent = parent;
  if (old_parent == kNull) {
    root_ = parent;
  } else if (at(old_parent).child1 == sibling) {
    at(old_parent).child1 = parent;
  } else {
    at(old_parent).child2 = parent;
  }

  // walk back up, rotating and refitting
  refit_up(parent);
}

void DynamicTree::remove_leaf(std::int32_t leaf) {
  if (leaf == root_) {
    root_ = kNull;
    return;
  }
  // the sibling takes the parent's place; the parent is freed
  const std::int32_t parent = at(leaf).parent;
  const std::int32_t grand = at(parent).parent;
  const std::int32_t sibling = at(parent).child1 == leaf ? at(parent).child2 : at(parent).child1;
  if (grand == kNull) {
    root_ = sibling;
    at(sibling).parent = kNull;
    free_node(parent);
    return;
  }
  if (at(grand).child1 == parent) {
    at(grand).child1 = sibling;
  } else {
    at(grand).child2 = sibling;
  }
  at(sibling).parent = grand;
  free_node(parent);
  refit_up(grand);
}

void DynamicTree::refit_up(std::int32_t n) {
  // balance each ancestor, then recompute its box and height from its children
  while (n != kNull) {
    n = balance(n);
    Node& node = at(n);
    const Node& c1 = at(node.child1);
    const Node& c2 = at(node.child2);
    node.box = c1.box.merged(c2.box);
    node.height = 1 + std::max(c1.height, c2.height);
    n = node.parent;
  }
}

std::int32_t DynamicTree::balance(std::int32_t ia) {
  // an AVL rotation when one child is two levels taller than the other: the taller child
  // C becomes the parent, A adopts the shorter of C's children (the same rotation as
  // Box2D's b2DynamicTree::Balance)
  Node& a = at(ia);
  if (a.is_leaf() || a.height < 2) return ia;
  const std::int32_t ib = a.child1, ic = a.child2;
  const int bal = at(ic).height - at(ib).height;
  if (bal >= -1 && bal <= 1) return ia;

  // name the taller child `up` and the other `keep`; `second` says where `up` hangs
  const bool c_taller = bal > 1;
  const std::int32_t iu = c_taller ? ic : ib;
  const std::int32_t ik = c_taller ? ib : ic;
  Node& u = at(iu);
  const std::int32_t f = u.child1, g = u.child2;

  // `up` replaces `a` under a's parent
  u.child1 = ia;
  u.parent = a.parent;
  a.parent = iu;
  if (u.parent == kNull) {
    root_ = iu;
  } else if (at(u.parent).child1 == ia) {
    at(u.parent).child1 = iu;
  } else {
    at(u.parent).child2 = iu;
  }

  // the taller grandchild stays with `up`, the shorter goes to `a` in up's old slot
  const bool f_taller = at(f).height > at(g).height;
  const std::int32_t stay = f_taller ? f : g;
  const std::int32_t move = f_taller ? g : f;
  u.child2 = stay;
  if (c_taller) {
    a.child2 = move;
  } else {
    a.child1 = move;
  }
  at(move).parent = ia;
  a.box = at(ik).box.merged(at(move).box);
  a.height = 1 + std::max(at(ik).height, at(move).height);
  u.box = a.box.merged(at(stay).box);
  u.height = 1 + std::max(a.height, at(stay).height);
  return iu;
}

int DynamicTree::height_limit() const {
  return 2 * static_cast<int>(std::bit_width(leaves_)) + 8;
}

void DynamicTree::keep_height() {
  // single rotations do not bound the height the way full AVL balancing would (insertion
  // follows the SAH, not the balance), so a tree that grew too tall is rebuilt
  if (height() > height_limit()) rebuild();
}

void DynamicTree::rebuild() {
  // (leaves, not the root: leaves made by create_proxy_unplaced may have no tree yet)
  if (leaves_ == 0) return;
  // gather the leaves (with their boxes, and the bounds of their centres) and free every inner
  // node (the pool grown once for the inner nodes the free ones do not cover: a batch of new
  // leaves has none)
  reserve(leaves_);
  build_items_.clear();
  build_items_.reserve(leaves_);
  Vec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    Node& n = nodes_[i];
    if (n.height == 0) {
      build_items_.push_back({n.box, static_cast<std::int32_t>(i), 0});
      const Vec3 c = n.box.lo + n.box.hi;
      lo = glm::min(lo, c);
      hi = glm::max(hi, c);
    } else if (n.height > 0) {
      free_node(static_cast<std::int32_t>(i));
    }
  }
  // build top-down
  root_ = build_range(build_items_.data(), static_cast<std::int32_t>(build_items_.size()), 0, lo, hi);
  at(root_).parent = kNull;
}

std::int32_t DynamicTree::build_range(BuildItem* items, std::int32_t count, int depth, const Vec3& lo,
                                      const Vec3& hi) {
  if (count == 1) return items[0].node;
  // the longest axis of the centres' bounds (box lo + hi, twice the centre: no rounding)
  const Vec3 d = hi - lo;
  const int axis = d.x >= d.y && d.x >= d.z ? 0 : (d.y >= d.z ? 1 : 2);
  auto centre2 = [axis](const BuildItem& x) { return x.box.lo[axis] + x.box.hi[axis]; };

  // binned SAH (Wald 2007, "On fast construction of SAH-based bounding volume
  // hierarchies"): sort the centres into bins along the axis and split at the plane of
  // least area(left) n_left + area(right) n_right; below a depth limit, or when every
  // centre falls in one bin, split at the median instead (balanced: the limit holds). Each
  // bin keeps the bounds of its centres too, so the halves' bounds come from the bins, not a
  // pass over their leaves
  std::int32_t split = -1;
  Vec3 lo1, hi1, lo2, hi2;  // the halves' centres' bounds
  const int median_below = height_limit() - static_cast<int>(std::bit_width(static_cast<std::uint32_t>(count))) - 1;
  if (count > 2 && depth < median_below && d[axis] > 0) {
    constexpr int kBins = 16;
    constexpr double kMax = std::numeric_limits<double>::max();
    struct Bin {
      Aabb box{Vec3(kMax), Vec3(-kMax)};
      Vec3 lo{kMax}, hi{-kMax};  // its centres' bounds
      std::int32_t count = 0;
    };
    Bin bins[kBins];
    const double scale = kBins / d[axis];
    std::uint32_t used = 0;  // the bins that hold a centre, a bit each
    for (std::int32_t i = 0; i < count; ++i) {
      BuildItem& x = items[i];
      const Vec3 c = x.box.lo + x.box.hi;
      x.bin = std::min(kBins - 1, static_cast<int>((c[axis] - lo[axis]) * scale));
      Bin& bin = bins[x.bin];
      bin.box = bin.box.merged(x.box);
      bin.lo = glm::min(bin.lo, c);
      bin.hi = glm::max(bin.hi, c);
      ++bin.count;
      used |= 1u << x.bin;
    }
    // the planes' costs: each plane's left side is the bins below it, its right side the bins
    // from it up. The planes between two bins that hold centres all cost the same (an empty
    // bin's box changes no union), and the first of them wins a tie, so only the plane just
    // above each bin that holds some is costed: the same plane as a sweep of all 15 finds, for
    // the nodes low in the tree (a few leaves in a few bins) without the empty bins' unions
    // and areas, which were most of a rebuild's instructions. From the right: the suffix
    // areas and counts at each used bin; then from the left, the costs
    int order[kBins], m = 0;
    for (std::uint32_t u = used; u != 0; u &= u - 1) order[m++] = std::countr_zero(u);
    double right_area[kBins];
    std::int32_t right_count[kBins];
    Aabb acc = bins[order[m - 1]].box;
    std::int32_t n = 0;
    for (int k = m - 1; k > 0; --k) {
      if (k < m - 1) acc = acc.merged(bins[order[k]].box);
      n += bins[order[k]].count;
      right_area[k] = acc.area();
      right_count[k] = n;
    }
    double best = std::numeric_limits<double>::max();
    int best_plane = -1, best_k = -1;
    Aabb left = bins[order[0]].box;
    std::int32_t nl = 0;
    for (int k = 1; k < m; ++k) {
      if (k > 1) left = left.merged(bins[order[k - 1]].box);
      nl += bins[order[k - 1]].count;
      const double cost = left.area() * nl + right_area[k] * right_count[k];
      if (cost < best) {
        best = cost;
        best_plane = order[k - 1] + 1, best_k = k;
      }
    }
    if (best_plane > 0) {
      lo1 = lo2 = Vec3(kMax), hi1 = hi2 = Vec3(-kMax);
      for (int k = 0; k < m; ++k) {
        Vec3& l = k < best_k ? lo1 : lo2;
        Vec3& h = k < best_k ? hi1 : hi2;
        l = glm::min(l, bins[order[k]].lo), h = glm::max(h, bins[order[k]].hi);
      }
      BuildItem* mid =
          std::partition(items, items + count, [best_plane](const BuildItem& x) { return x.bin < best_plane; });
      split = static_cast<std::int32_t>(mid - items);
    }
  }
  if (split <= 0 || split >= count) {
    // the median centre (ties by node index: a total order, so the result is
    // deterministic); halves of floor and ceil of count / 2 keep the balance within 1
    split = count / 2;
    auto before = [&](const BuildItem& x, const BuildItem& y) {
      const double cx = centre2(x), cy = centre2(y);
      return cx < cy || (cx == cy && x.node < y.node);
    };
    // (two leaves, the most common case, without nth_element's machinery: the lesser first)
    if (count == 2) {
      if (before(items[1], items[0])) std::swap(items[0], items[1]);
    } else {
      std::nth_element(items, items + split, items + count, before);
    }
    auto bounds = [](const BuildItem* first, std::int32_t m, Vec3& l, Vec3& h) {
      l = h = first[0].box.lo + first[0].box.hi;
      for (std::int32_t i = 1; i < m; ++i) {
        const Vec3 c = first[i].box.lo + first[i].box.hi;
        l = glm::min(l, c), h = glm::max(h, c);
      }
    };
    bounds(items, split, lo1, hi1);
    bounds(items + split, count - split, lo2, hi2);
  }
  const std::int32_t c1 = build_range(items, split, depth + 1, lo1, hi1);
  const std::int32_t c2 = build_range(items + split, count - split, depth + 1, lo2, hi2);
  const std::int32_t p = allocate_node();
  Node& node = at(p);
  node.child1 = c1;
  node.child2 = c2;
  node.box = at(c1).box.merged(at(c2).box);
  node.height = 1 + std::max(at(c1).height, at(c2).height);
  at(c1).parent = at(c2).parent = p;
  return p;
}

double DynamicTree::area_ratio() const {
  if (root_ == kNull || at(root_).is_leaf()) return 0;
  // leaves and inner nodes alternate in the pool: a select, not a branch (adding 0 for the
  // others leaves the sum's bits as they were)
  double inner = 0;
  for (const Node& n : nodes_) {
    const double a = n.box.area();
    inner += n.height > 0 ? a : 0.0;
  }
  const double root_area = at(root_).box.area();
  return root_area > 0 ? inner / root_area : 0;
}

void DynamicTree::validate() const {
  auto fail = [](std::int32_t n, const std::string& what) {
    throw Error("DynamicTree.validate: node " + std::to_string(n) + ": " + what);
  };
  // free nodes
  std::size_t free_count = 0;
  for (std::int32_t f = free_; f != kNull; f = at(f).parent) {
    if (at(f).height != -1) fail(f, "on the free list but height " + std::to_string(at(f).height));
    if (++free_count > nodes_.size()) fail(f, "the free list has a cycle");
  }
  // every reachable node, depth first
  if (root_ != kNull && at(root_).parent != kNull) fail(root_, "the root has a parent");
  std::size_t leaves = 0, reached = 0;
  std::vector<std::int32_t> stack;
  if (root_ != kNull) stack.push_back(root_);
  while (!stack.empty()) {
    const std::int32_t i = stack.back();
    stack.pop_back();
    if (++reached > nodes_.size()) fail(i, "the tree has a cycle");
    const Node& n = at(i);
    if (n.is_leaf()) {
      if (n.child2 != kNull) fail(i, "a leaf with a second child");
      if (n.height != 0) fail(i, "a leaf of height " + std::to_string(n.height));
      ++leaves;
      continue;
    }
    const Node& c1 = at(n.child1);
    const Node& c2 = at(n.child2);
    if (c1.parent != i || c2.parent != i) fail(i, "a child does not name it as its parent");
    if (n.height != 1 + std::max(c1.height, c2.height))
      fail(i, "height " + std::to_string(n.height) + " but children of heights " + std::to_string(c1.height) +
                  " and " + std::to_string(c2.height));
    if (!n.box.contains(c1.box) || !n.box.contains(c2.box)) fail(i, "its box does not contain a child's box");
    stack.push_back(n.child1);
    stack.push_back(n.child2);
  }
  if (height() > height_limit())
    fail(root_, "height " + std::to_string(height()) + " above the limit " + std::to_string(height_limit()));
  if (leaves != leaves_)
    fail(root_, std::to_string(leaves) + " leaves reached, " + std::to_string(leaves_) + " expected");
  if (reached + free_count != nodes_.size())
    fail(root_, std::to_string(reached) + " nodes reached and " + std::to_string(free_count) + " free of " +
                    std::to_string(nodes_.size()));
}

}  // namespace pba
