// pba collide, broad phase (workbook chapter 5): which pairs of boxes might touch.
//
// The broad phase keeps one axis-aligned box per collider (a proxy) and, once per frame,
// reports every pair of proxies whose boxes overlap and whose filters accept each other.
// Four methods sit behind one interface and give the same pair list, so the lab can switch
// them live and compare their time:
//   - Tree: a dynamic AABB tree of fat boxes (Catto 2019, "Dynamic Bounding Volume
//     Hierarchies", the Box2D b2DynamicTree; Bittner et al. 2015 for the SAH insertion cost),
//     kept balanced by rotations, with a move buffer and a persistent pair set;
//   - Grid: a uniform grid hashed into buckets (cell size from the mean box size or set);
//   - SweepAndPrune: boxes kept sorted on one axis by insertion sort (Baraff 1992), swept;
//   - BruteForce: every pair tested, the reference.
//
// The pair list is sorted by (lower proxy index, higher proxy index) and free of
// duplicates: the same list for every method and every run, whatever the order in which
// proxies were created and moved. Nothing allocates per frame once the arrays have grown.
// Lengths in metres.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <string_view>
#include <vector>

#include "pba/collide/shape.h"
#include "pba/core.h"
#include "pba/draw.h"
#include "pba/handle.h"

namespace pba {

/// Throws Error "<where>: must be finite, got ..." or "<where>: inverted box, lo (...) >
/// hi (...) on x" unless `box` is finite with lo <= hi on every axis.
void require_valid_box(const Aabb& box, std::string_view where);

/// Entry distance of `ray` into `box` (m), or a negative value when the ray misses it
/// within [0, max_distance] (the slab test, Kay and Kajiya 1986; a ray starting inside
/// enters at 0). `inv_direction` is 1 / ray.direction per axis (infinite where it is 0).
inline double ray_enter_box(const Ray& ray, const Vec3& inv_direction, const Aabb& box) {
  double t0 = 0, t1 = ray.max_distance;
  for (int k = 0; k < 3; ++k) {
    // an axis the ray does not move along: inside the slab or a miss
    if (ray.direction[k] == 0) {
      if (ray.origin[k] < box.lo[k] || ray.origin[k] > box.hi[k]) return -1;
      continue;
    }
    // clip [t0, t1] to the slab
    double a = (box.lo[k] - ray.origin[k]) * inv_direction[k];
    double b = (box.hi[k] - ray.origin[k]) * inv_direction[k];
    if (a > b) std::swap(a, b);
    if (a > t0) t0 = a;
    if (b < t1) t1 = b;
    if (t0 > t1) return -1;
  }
  return t0;
}

// --- dynamic AABB tree -------------------------------------------------------------------

/// A dynamic bounding-volume tree over fat boxes (Catto 2019; Box2D's b2DynamicTree). Each
/// leaf holds a proxy's box grown by `margin`; a proxy that moves within its fat box costs
/// nothing, one that leaves it is re-inserted. Insertion descends by the surface-area
/// heuristic with inherited cost (Bittner, Hapala and Havran 2015; Catto 2019); the path
/// back to the root is rebalanced by AVL rotations (single rotations, as Box2D does), and a
/// tree that still grows taller than height_limit() is rebuilt, so the height stays O(log n).
/// Node storage is a pool of contiguous nodes; growth allocates, steady state does not.
class DynamicTree {
 public:
  /// Index of "no node".
  static constexpr std::int32_t kNull = -1;

  /// One node: a leaf (height 0, `user` set) or an inner node with two children.
  struct Node {
    Aabb box{};                   ///< fat box (leaf) or union of the children (inner)
    std::int32_t parent = kNull;  ///< parent node, kNull at the root (next free node when free)
    std::int32_t child1 = kNull;  ///< first child, kNull for a leaf
    std::int32_t child2 = kNull;  ///< second child, kNull for a leaf
    std::int32_t height = 0;      ///< 0 for a leaf, 1 + max of the children otherwise; -1 when free
    std::uint32_t user = 0;       ///< the leaf's user value (a proxy index)
    bool is_leaf() const { return child1 == kNull; }
  };

  /// A tree whose leaves are their boxes grown by `margin` metres (finite, >= 0) on every side.
  explicit DynamicTree(double margin = 0.1);

  /// Adds a leaf for `box` (finite, lo <= hi) carrying `user`; returns its node index.
  std::int32_t create_proxy(const Aabb& box, std::uint32_t user);
  /// Adds a leaf for `box` (finite, lo <= hi) carrying `user` without a place in the tree yet;
  /// returns its node index, which rebuild() keeps. The caller calls rebuild() before the next
  /// query, move, removal, area_ratio() or validate(): until then no query finds the leaf. For
  /// a batch of new leaves that a rebuild follows anyway (the rigid bodies' first step of
  /// 10,000 proxies), whose insertions' searches and rotations would be thrown away.
  std::int32_t create_proxy_unplaced(const Aabb& box, std::uint32_t user);
  /// Removes the leaf `node` (throws Error if it is not a live leaf).
  void destroy_proxy(std::int32_t node);
  /// Updates the leaf `node` to the tight box `box`. Returns false when `box` still lies in
  /// the fat box (nothing changes); otherwise re-inserts the leaf with a new fat box and
  /// returns true.
  bool move_proxy(std::int32_t node, const Aabb& box);
  /// Gives the leaf `node` the fat box of the tight box `box` (finite, lo <= hi; grown by the
  /// margin as create_proxy grows it) where it stands: its ancestors' boxes are made the
  /// union of their children's again up to the first that does not change, and nothing is
  /// re-inserted or rotated, so the tree's shape stays and its quality may wear (watch
  /// area_ratio(), rebuild() when it grew). A query finds the same leaves as after
  /// move_proxy(); the cost is one box a level instead of a search, a removal and two walks
  /// with rotations (many leaves moving together, as bodies falling in a heap, keep their
  /// neighbours, and the shape the tree had still suits them). Throws Error if `node` is not
  /// a live leaf or the box is bad.
  void set_leaf_box(std::int32_t node, const Aabb& box);
  /// Makes room for `leaves` leaves in all (and the inner nodes above them) at once, at least
  /// doubling the pool when it grows: the pool grown once for a batch of new leaves rather than
  /// doubled again and again as they come (the rigid bodies' first step of 10,000 proxies: each
  /// doubling's copy lands on pages the process has not touched yet, and their faults cost
  /// more than the copies).
  void reserve(std::size_t leaves);
  /// Removes every node.
  void clear();
  /// Rebuilds the whole tree top-down over the leaves' fat boxes by the binned surface-area
  /// heuristic (Wald 2007), falling back to median splits deep down so the height stays
  /// within height_limit(): for a batch of insertions or a tree that degraded after many
  /// moves. Leaf node indices are kept. Allocates only the first time (its scratch list).
  void rebuild();

  /// The fat box of leaf `node`.
  const Aabb& fat_box(std::int32_t node) const { return nodes_[static_cast<std::size_t>(node)].box; }
  /// The user value of leaf `node`.
  std::uint32_t user(std::int32_t node) const { return nodes_[static_cast<std::size_t>(node)].user; }
  /// The margin (m).
  double margin() const { return margin_; }
  /// Root node, kNull when empty.
  std::int32_t root() const { return root_; }
  /// The node pool (free nodes have height -1).
  std::span<const Node> nodes() const { return nodes_; }
  /// Number of leaves.
  std::size_t proxy_count() const { return leaves_; }
  /// Height of the root (0 for a single leaf, -1 when empty).
  int height() const { return root_ == kNull ? -1 : nodes_[static_cast<std::size_t>(root_)].height; }
  /// The height above which the tree rebuilds itself: 2 bit_width(leaves) + 8.
  int height_limit() const;
  /// Tree quality: total surface area of the inner nodes over the root's area (the SAH cost
  /// of a traversal, up to a constant; lower is better; 0 for a tree of one leaf).
  double area_ratio() const;
  /// Checks every invariant: parent and child links agree, heights are 1 + the children's
  /// maximum, every inner box contains its children, the height is within height_limit(),
  /// the leaf and free counts add up. Throws Error naming the node and the broken invariant.
  void validate() const;

  /// Calls `f(user)` for every leaf whose fat box overlaps `box`; `f` returns false to stop.
  /// Never allocates.
  template <class F>
  void query(const Aabb& box, F&& f) const;
  /// Calls `f(user_a, user_b)` once for each pair of distinct leaves whose fat boxes overlap
  /// and of which at least one is in `leaves` (live leaf nodes, each once): the set of pairs
  /// that a query() of each listed leaf's fat box finds, each pair once rather than from both
  /// sides, in no set order. One walk of the tree against itself (the subtrees without a
  /// listed leaf skipped, and a subtree's pairs with another found only where their boxes
  /// overlap), where the queries walked the top of the tree once for each listed leaf. Its
  /// scratch grows with the tree; no allocation once grown.
  template <class F>
  void query_pairs(std::span<const std::int32_t> leaves, F&& f);
  /// Casts `ray` through the tree: calls `f(user, ray)` for every leaf whose fat box the ray
  /// enters within its current length, nearest subtrees first; `f` returns the new ray
  /// length (m, <= the current one, to clip), or a negative value to stop. Never allocates.
  template <class F>
  void ray_cast(const Ray& ray, F&& f) const;

 private:
  static constexpr int kStack = 256;  // > height_limit() + 1 for any count that fits memory
  std::int32_t allocate_node();
  // a leaf node for `box` (checked, `where` naming it in the error) counted but not placed
  std::int32_t new_leaf(const Aabb& box, std::uint32_t user, std::string_view where);
  void free_node(std::int32_t n);
  void insert_leaf(std::int32_t leaf);
  void remove_leaf(std::int32_t leaf);
  std::int32_t balance(std::int32_t a);
  void refit_up(std::int32_t n);
  void keep_height();
  // a leaf as a rebuild sorts it: its box copied beside its node (the build's passes read
  // boxes in a row, not a node of the pool each), and its bin in the range's split
  struct BuildItem {
    Aabb box;
    std::int32_t node;
    std::int32_t bin;
  };
  // the subtree over `items` (`count` >= 1 of them, at `depth`, their boxes' centres times 2
  // within [lo, hi]); its root node
  std::int32_t build_range(BuildItem* items, std::int32_t count, int depth, const Vec3& lo, const Vec3& hi);
  Node& at(std::int32_t n) { return nodes_[static_cast<std::size_t>(n)]; }
  const Node& at(std::int32_t n) const { return nodes_[static_cast<std::size_t>(n)]; }

  std::vector<Node> nodes_;
  std::int32_t root_ = kNull;
  std::int32_t free_ = kNull;
  std::size_t leaves_ = 0;
  double margin_ = 0.1;
  std::vector<BuildItem> build_items_;  // rebuild scratch
  std::vector<std::uint8_t> marked_;    // query_pairs scratch: by node, 1 above a listed leaf
  std::vector<std::pair<std::int32_t, std::int32_t>> pair_stack_;  // query_pairs scratch
};

template <class F>
void DynamicTree::query(const Aabb& box, F&& f) const {
  // depth-first with an explicit stack
  if (root_ == kNull) return;
  std::int32_t stack[kStack];
  int top = 0;
  stack[top++] = root_;
  while (top > 0) {
    const Node& n = at(stack[--top]);
    if (!n.box.overlaps(box)) continue;
    if (n.is_leaf()) {
      if (!f(n.user)) return;
    } else {
      // (both children asked for now: the walk reaches child1 only after child2's subtree, and
      // a node's box is where a query waits)
      __builtin_prefetch(&at(n.child1)), __builtin_prefetch(&at(n.child2));
      stack[top++] = n.child1;
      stack[top++] = n.child2;
    }
  }
}

template <class F>
void DynamicTree::query_pairs(std::span<const std::int32_t> leaves, F&& f) {
  if (root_ == kNull || leaves.empty()) return;
  // mark each listed leaf and its ancestors (a walk up stops at the first one marked already)
  marked_.assign(nodes_.size(), 0);
  for (const std::int32_t leaf : leaves)
    for (std::int32_t n = leaf; n != kNull && !marked_[static_cast<std::size_t>(n)]; n = at(n).parent)
      marked_[static_cast<std::size_t>(n)] = 1;
  // a stack of tasks: (a, a) the pairs within subtree a, (a, b) those between subtrees a and b
  pair_stack_.clear();
  pair_stack_.emplace_back(root_, root_);
  while (!pair_stack_.empty()) {
    const auto [ia, ib] = pair_stack_.back();
    pair_stack_.pop_back();
    const Node& a = at(ia);
    if (ia == ib) {
      if (a.is_leaf() || !marked_[static_cast<std::size_t>(ia)]) continue;
      pair_stack_.emplace_back(a.child1, a.child2);
      pair_stack_.emplace_back(a.child2, a.child2);
      pair_stack_.emplace_back(a.child1, a.child1);
      continue;
    }
    const bool marked_a = marked_[static_cast<std::size_t>(ia)], marked_b = marked_[static_cast<std::size_t>(ib)];
    if (!(marked_a | marked_b)) continue;
    const Node& b = at(ib);
    if (!a.box.overlaps(b.box)) continue;
    if (a.is_leaf() && b.is_leaf()) {
      f(a.user, b.user);
      continue;
    }
    // split the marked side down to its listed leaves first, each then a query of the other
    // side (split an unmarked side against a subtree with few listed leaves, and the walk
    // paired all of that subtree's nodes with the other's: more than the queries, in the
    // rain's landing heaps); two marked sides, the taller (a leaf never)
    const bool split_a = marked_a != marked_b ? (marked_a ? !a.is_leaf() : b.is_leaf())
                                              : b.is_leaf() || (!a.is_leaf() && a.height >= b.height);
    if (split_a) {
      pair_stack_.emplace_back(a.child2, ib);
      pair_stack_.emplace_back(a.child1, ib);
    } else {
      pair_stack_.emplace_back(ia, b.child2);
      pair_stack_.emplace_back(ia, b.child1);
    }
  }
}

template <class F>
void DynamicTree::ray_cast(const Ray& ray, F&& f) const {
  if (root_ == kNull) return;
  // 1/d per axis (infinite on axes the ray does not move along)
  const Vec3 inv(1.0 / ray.direction.x, 1.0 / ray.direction.y, 1.0 / ray.direction.z);
  Ray r = ray;
  // the stack holds each node with the distance at which the ray enters its box
  struct Item {
    std::int32_t node;
    double enter;
  };
  Item stack[kStack];
  int top = 0;
  const double t_root = ray_enter_box(r, inv, at(root_).box);
  if (t_root < 0) return;
  stack[top++] = {root_, t_root};
  while (top > 0) {
    const Item it = stack[--top];
    // the ray may have been clipped since this node was pushed
    if (it.enter > r.max_distance) continue;
    const Node& n = at(it.node);
    if (n.is_leaf()) {
      const double clip = f(n.user, static_cast<const Ray&>(r));
      if (clip < 0) return;
      if (clip < r.max_distance) r.max_distance = clip;
      continue;
    }
    // push the farther child first so the nearer one is visited first
    const double t1 = ray_enter_box(r, inv, at(n.child1).box);
    const double t2 = ray_enter_box(r, inv, at(n.child2).box);
    if (t1 >= 0 && t2 >= 0) {
      if (t1 <= t2) {
        stack[top++] = {n.child2, t2};
        stack[top++] = {n.child1, t1};
      } else {
        stack[top++] = {n.child1, t1};
        stack[top++] = {n.child2, t2};
      }
    } else if (t1 >= 0) {
      stack[top++] = {n.child1, t1};
    } else if (t2 >= 0) {
      stack[top++] = {n.child2, t2};
    }
  }
}

// --- broad phase -------------------------------------------------------------------------

/// Tag of broad-phase proxy handles.
struct ProxyTag {};
/// A generation-checked broad-phase proxy id; its `index` orders the pair list.
using ProxyId = Handle<ProxyTag>;

/// Which proxies may pair. A pair (a, b) is reported when (a.layer & b.mask) and
/// (b.layer & a.mask) are both non-zero and the two do not share a non-zero owner
/// (the shapes of one body, the links of one rope).
struct CollisionFilter {
  std::uint64_t layer = 1;       ///< the layers this proxy is in (bits)
  std::uint64_t mask = ~0ull;    ///< the layers it collides with (bits)
  std::uint64_t owner = 0;       ///< 0: no owner; proxies with the same non-zero owner never pair
};

/// True when the filters `a` and `b` accept each other.
inline bool should_pair(const CollisionFilter& a, const CollisionFilter& b) {
  return ((a.layer & b.mask) != 0) & ((b.layer & a.mask) != 0) & ((a.owner == 0) | (a.owner != b.owner));
}

/// The pair-finding methods; every one gives the same pair list.
enum class BroadPhaseMethod : std::uint8_t {
  Tree,           ///< dynamic AABB tree with fat boxes and a persistent pair set
  Grid,           ///< uniform grid hashed into buckets
  SweepAndPrune,  ///< insertion-sorted on x, swept
  BruteForce,     ///< every pair tested
};
/// Lower-case name of a method ("tree", "grid", "sap", "brute-force").
std::string_view to_string(BroadPhaseMethod m);
/// The method named `name` (as to_string gives it); throws Error naming `where` otherwise.
BroadPhaseMethod broad_phase_method_from_string(std::string_view name, std::string_view where);

/// A pair of proxies whose boxes overlap, a.index < b.index.
struct ProxyPair {
  ProxyId a;  ///< the proxy with the lower index
  ProxyId b;  ///< the proxy with the higher index
  bool operator==(const ProxyPair&) const = default;
};

/// Settings of a broad phase.
struct BroadPhaseDef {
  BroadPhaseMethod method = BroadPhaseMethod::Tree;  ///< initial method
  double tree_margin = 0.2;  ///< fat-box margin of the tree (m), finite and >= 0
  /// Grid cell edge (m): 0 picks 1.5 x the mean largest box extent every frame; else
  /// finite and > 0.
  double grid_cell = 0;
  /// Grid: a box covering more cells than this is tested against every other box instead
  /// (ground planes, long walls), in [1, 1e6].
  int grid_max_cells_per_box = 64;
};

/// What one update_pairs() did, for the lab.
struct BroadPhaseStats {
  BroadPhaseMethod method = BroadPhaseMethod::Tree;  ///< the method used
  double seconds = 0;            ///< wall time of update_pairs (s)
  std::size_t pairs = 0;         ///< pairs reported
  std::size_t proxies = 0;       ///< live proxies
  std::size_t box_tests = 0;     ///< box-box overlap tests done
  std::size_t reinserted = 0;    ///< tree: proxies queried this frame (left their fat box, new or refiltered)
  int tree_height = -1;          ///< tree: height of the root
  double tree_area_ratio = 0;    ///< tree: inner-node area over root area (when last measured)
  double grid_cell = 0;          ///< grid: the cell edge used (m)
};

namespace detail {
struct BroadPhaseMethods;  // the per-method state (grid buckets, the SAP order)
}

/// Proxies with boxes, filters and user data, and the list of overlapping pairs. Create,
/// move and destroy proxies at any time; update_pairs() then finds the pairs with the
/// current method. Not thread-safe; deterministic.
class BroadPhase {
 public:
  /// A broad phase with `def`'s settings (throws Error naming the bad field).
  explicit BroadPhase(const BroadPhaseDef& def = {});
  ~BroadPhase();
  BroadPhase(BroadPhase&&) noexcept;
  BroadPhase& operator=(BroadPhase&&) noexcept;

  /// Adds a proxy for `box` (finite, lo <= hi) with `filter` and `user_data`.
  ProxyId create_proxy(const Aabb& box, const CollisionFilter& filter = {}, std::uint64_t user_data = 0);
  /// Removes a proxy (throws Error for a stale or null id).
  void destroy_proxy(ProxyId id);
  /// Sets a proxy's box (finite, lo <= hi; throws Error naming the value or a stale id).
  void move_proxy(ProxyId id, const Aabb& box);
  /// Changes a proxy's filter; its pairs are found afresh at the next update.
  void set_filter(ProxyId id, const CollisionFilter& filter);
  /// Switches the method; the next update_pairs() uses it (builds its structure once).
  void set_method(BroadPhaseMethod m);
  /// Sets the grid cell edge (0: automatic; else finite and > 0).
  void set_grid_cell(double cell);
  /// Reserves room for `n` proxies so that creating them allocates as little as possible.
  void reserve(std::size_t n);

  /// Finds the pairs of the current boxes; returns them sorted by (a.index, b.index).
  std::span<const ProxyPair> update_pairs();
  /// The pairs of the last update_pairs().
  std::span<const ProxyPair> pairs() const { return {pairs_.data(), pair_count_}; }
  /// What the last update_pairs() did.
  const BroadPhaseStats& stats() const { return stats_; }

  /// True when `id` names a live proxy.
  bool valid(ProxyId id) const { return pool_.valid(id); }
  /// The proxy's current (tight) box.
  const Aabb& box(ProxyId id) const;
  /// The proxy's filter.
  const CollisionFilter& filter(ProxyId id) const;
  /// The proxy's user data (inline: a caller asks for it twice per pair).
  std::uint64_t user_data(ProxyId id) const {
    if (!pool_.valid(id)) check(id, "BroadPhase.user_data");
    return user_[id.index];
  }
  /// The live proxy at slot `index` (for a pair's index), null if the slot is free.
  ProxyId id_at(std::uint32_t index) const;
  /// Live proxies.
  std::size_t size() const { return pool_.size(); }
  /// Slots ever used (live + free): every live proxy's index is below it.
  std::size_t slots() const { return boxes_.size(); }
  /// The current method.
  BroadPhaseMethod method() const { return method_; }
  /// The tree (maintained only while the method is Tree; empty otherwise).
  const DynamicTree& tree() const { return tree_; }
  /// The proxies whose boxes `box` overlaps, by brute force or the tree: calls f(ProxyId)
  /// until it returns false. Never allocates.
  template <class F>
  void query(const Aabb& box, F&& f) const;

 private:
  friend struct detail::BroadPhaseMethods;
  void check(ProxyId id, std::string_view where) const;
  void rebuild_tree();
  void update_tree_pairs();

  // per-proxy arrays indexed by the slot index
  HandlePool<ProxyTag> pool_;
  std::vector<Aabb> boxes_;
  std::vector<CollisionFilter> filters_;
  std::vector<std::uint64_t> user_;
  std::vector<std::int32_t> node_;    // tree leaf, kNull unless the method is Tree
  std::vector<Aabb> fat_;             // the tree leaf's fat box (a copy, read without the indirection)
  std::vector<std::uint8_t> alive_;
  std::vector<std::uint8_t> moved_;   // in the move buffer this frame
  // the tree, its move buffer and its persistent pair set (keys a << 32 | b)
  DynamicTree tree_;
  std::vector<std::uint32_t> move_buffer_;
  std::vector<std::uint64_t> tree_keys_, new_keys_, merge_keys_;
  double tree_rebuilt_ratio_ = 0;  // the tree's area ratio after its last rebuild
  double tree_ratio_ = 0;          // ... when it was last measured
  std::size_t reinserted_since_check_ = 0;  // proxies queried since it was last measured
  // the other methods' state, and the output
  std::unique_ptr<detail::BroadPhaseMethods> methods_;
  std::vector<ProxyPair> pairs_;  // the pair list is its first pair_count_ (the tree's merge writes past them)
  std::size_t pair_count_ = 0;
  BroadPhaseMethod method_ = BroadPhaseMethod::Tree;
  BroadPhaseDef def_;
  BroadPhaseStats stats_;
  std::uint64_t topology_ = 0;  // bumped by create and destroy (SAP rebuilds its order)
};

template <class F>
void BroadPhase::query(const Aabb& box, F&& f) const {
  if (method_ == BroadPhaseMethod::Tree) {
    tree_.query(box, [&](std::uint32_t p) {
      if (!boxes_[p].overlaps(box)) return true;
      return static_cast<bool>(f(id_at(p)));
    });
    return;
  }
  for (std::uint32_t p = 0; p < boxes_.size(); ++p)
    if (alive_[p] && boxes_[p].overlaps(box) && !f(id_at(p))) return;
}

/// Draws the broad phase's structure through `dd` when `flags.tree` is set: the tree's
/// inner nodes (coloured by depth, up to `max_depth` levels from the root) or the grid's
/// occupied cells; and every proxy's box when `flags.aabbs` is set.
void draw_broad_phase(const BroadPhase& bp, DebugDraw& dd, const DrawFlags& flags, int max_depth = 8);
/// Draws the 12 edges of `box`.
void draw_box_edges(DebugDraw& dd, const Aabb& box, Color c);

}  // namespace pba
