// The broad phase: proxies in slot arrays, the tree's persistent pair set, and the uniform
// grid, sweep-and-prune and brute-force methods. Every method fills a list of pair keys
// (lower index << 32 | higher index); the keys are sorted once, so the pair list is the
// same whatever method found it and whatever order proxies came in.
#include <algorithm>
#include <bit>
#include <cmath>
#include <string>

#include "pba/collide/broad_phase.h"

namespace pba {

namespace {

// grows a vector's capacity with headroom, so that a list whose length fluctuates from
// frame to frame stops allocating once it has seen its typical size
template <class T>
void ensure_capacity(std::vector<T>& v, std::size_t n) {
  if (v.capacity() < n) v.reserve(n + n / 2 + 16);
}

std::uint64_t pair_key(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
}

}  // namespace

std::string_view to_string(BroadPhaseMethod m) {
  switch (m) {
    case BroadPhaseMethod::Tree: return "tree";
    case BroadPhaseMethod::Grid: return "grid";
    case BroadPhaseMethod::SweepAndPrune: return "sap";
    case BroadPhaseMethod::BruteForce: return "brute-force";
  }
  return "?";
}

BroadPhaseMethod broad_phase_method_from_string(std::string_view name, std::string_view where) {
  for (BroadPhaseMethod m : {BroadPhaseMethod::Tree, BroadPhaseMethod::Grid, BroadPhaseMethod::SweepAndPrune,
                             BroadPhaseMethod::BruteForce})
    if (name == to_string(m)) return m;
  throw Error(std::string(where) + ": unknown broad-phase method '" + std::string(name) +
              "' (expected tree, grid, sap or brute-force)");
}

// --- the grid, sweep-and-prune and brute-force methods ------------------------------------

namespace detail {

struct BroadPhaseMethods {
  // grid: (cell key, proxy) entries scattered into hashed buckets by counting sort
  struct Entry {
    std::uint64_t cell;
    std::uint32_t proxy;
  };
  std::vector<Entry> entries, sorted;
  std::vector<std::uint32_t> bucket_start;
  std::vector<std::uint32_t> oversized;
  std::vector<std::uint8_t> is_oversized;
  // sweep and prune: proxies ordered by lo.x, and their lo.x beside them
  std::vector<std::uint32_t> order;
  std::vector<double> order_lo;
  std::uint64_t order_topology = ~0ull;
  int bucket_bits = 4;  // only grows, so the bucket array stops reallocating

  static constexpr double kCellLimit = 1 << 20;  // cell coordinates fit 21 bits

  static std::uint64_t cell_key(std::int64_t x, std::int64_t y, std::int64_t z) {
    const std::int64_t o = 1 << 20;
    return (std::uint64_t(x + o) << 42) | (std::uint64_t(y + o) << 21) | std::uint64_t(z + o);
  }

  // the uniform grid (Ericson 2005, "Real-Time Collision Detection", 7.1): each box goes
  // into every cell it covers; a pair is reported only in its home cell, the cell of the
  // larger of the two lower corners, which both boxes cover, so it is found exactly once
  static void grid(BroadPhase& bp, std::vector<std::uint64_t>& keys, BroadPhaseStats& st) {
    BroadPhaseMethods& m = *bp.methods_;
    const std::size_t slots = bp.boxes_.size();
    // the cell edge: set, or 1.5 x the mean largest extent
    double h = bp.def_.grid_cell;
    if (h <= 0) {
      double sum = 0;
      std::size_t n = 0;
      for (std::size_t p = 0; p < slots; ++p) {
        if (!bp.alive_[p]) continue;
        const Vec3 d = bp.boxes_[p].hi - bp.boxes_[p].lo;
        sum += std::max(d.x, std::max(d.y, d.z));
        ++n;
      }
      h = n > 0 && sum > 0 ? 1.5 * sum / double(n) : 1.0;
    }
    st.grid_cell = h;
    const double inv_h = 1.0 / h;
    const auto max_cells = static_cast<std::int64_t>(bp.def_.grid_max_cells_per_box);

    // entries for each box's cells; boxes too large (or too far out) are set aside
    m.entries.clear();
    m.oversized.clear();
    m.is_oversized.assign(slots, 0);
    for (std::size_t p = 0; p < slots; ++p) {
      if (!bp.alive_[p]) continue;
      const Aabb& b = bp.boxes_[p];
      const Vec3 c0 = glm::floor(b.lo * inv_h), c1 = glm::floor(b.hi * inv_h);
      bool big = false;
      for (int k = 0; k < 3; ++k) big = big || !(c0[k] > -kCellLimit && c1[k] < kCellLimit);
      std::int64_t n = 1;
      if (!big)
        for (int k = 0; k < 3; ++k) n *= static_cast<std::int64_t>(c1[k] - c0[k]) + 1;
      if (big || n > max_cells) {
        m.oversized.push_back(static_cast<std::uint32_t>(p));
        m.is_oversized[p] = 1;
        continue;
      }
      const auto x0 = static_cast<std::int64_t>(c0.x), y0 = static_cast<std::int64_t>(c0.y),
                 z0 = static_cast<std::int64_t>(c0.z);
      const auto x1 = static_cast<std::int64_t>(c1.x), y1 = static_cast<std::int64_t>(c1.y),
                 z1 = static_cast<std::int64_t>(c1.z);
      for (std::int64_t x = x0; x <= x1; ++x)
        for (std::int64_t y = y0; y <= y1; ++y)
          for (std::int64_t z = z0; z <= z1; ++z)
            m.entries.push_back({cell_key(x, y, z), static_cast<std::uint32_t>(p)});
    }

    // counting sort of the entries into 2^bits buckets (at least twice as many as entries)
    const std::size_t ne = m.entries.size();
    const int bits = std::max(m.bucket_bits, static_cast<int>(std::bit_width(2 * ne)));
    m.bucket_bits = bits;
    const std::size_t nb = std::size_t(1) << bits;
    auto bucket = [bits](std::uint64_t key) {
      return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - bits));
    };
    m.bucket_start.assign(nb + 1, 0);
    for (const Entry& e : m.entries) ++m.bucket_start[bucket(e.cell) + 1];
    for (std::size_t i = 0; i < nb; ++i) m.bucket_start[i + 1] += m.bucket_start[i];
    ensure_capacity(m.sorted, ne);
    m.sorted.resize(ne);
    for (const Entry& e : m.entries) {
      const std::size_t b = bucket(e.cell);
      m.sorted[m.bucket_start[b]++] = e;
    }
    // (the scatter advanced each start to the next bucket's start: shift back)
    for (std::size_t i = nb; i > 0; --i) m.bucket_start[i] = m.bucket_start[i - 1];
    m.bucket_start[0] = 0;

    // pairs within each bucket, in the same cell, reported in their home cell
    std::size_t tests = 0;
    for (std::size_t b = 0; b < nb; ++b) {
      const std::uint32_t s = m.bucket_start[b], e = m.bucket_start[b + 1];
      for (std::uint32_t i = s; i + 1 < e; ++i) {
        const Entry& ei = m.sorted[i];
        const Aabb& bi = bp.boxes_[ei.proxy];
        for (std::uint32_t j = i + 1; j < e; ++j) {
          const Entry& ej = m.sorted[j];
          if (ej.cell != ei.cell) continue;
          ++tests;
          const Aabb& bj = bp.boxes_[ej.proxy];
          if (!bi.overlaps(bj)) continue;
          const Vec3 home = glm::floor(glm::max(bi.lo, bj.lo) * inv_h);
          if (cell_key(static_cast<std::int64_t>(home.x), static_cast<std::int64_t>(home.y),
                       static_cast<std::int64_t>(home.z)) != ei.cell)
            continue;
          if (!should_pair(bp.filters_[ei.proxy], bp.filters_[ej.proxy])) continue;
          keys.push_back(pair_key(ei.proxy, ej.proxy));
        }
      }
    }

    // the oversized boxes against every box (pairs of two oversized ones once)
    for (std::uint32_t o : m.oversized) {
      const Aabb& bo = bp.boxes_[o];
      for (std::uint32_t p = 0; p < slots; ++p) {
        if (!bp.alive_[p] || p == o || (m.is_oversized[p] && p < o)) continue;
        ++tests;
        if (bo.overlaps(bp.boxes_[p]) && should_pair(bp.filters_[o], bp.filters_[p])) keys.push_back(pair_key(o, p));
      }
    }
    st.box_tests = tests;
  }

  // sweep and prune (Baraff 1992, "Dynamic simulation of non-penetrating rigid bodies"; Cohen
  // et al. 1995, I-COLLIDE): the proxies stay sorted by lo.x from frame to frame, so an
  // insertion sort restores the order in nearly linear time when boxes move a little; a
  // sweep then tests each box against the boxes that start before it ends on x
  static void sweep_and_prune(BroadPhase& bp, std::vector<std::uint64_t>& keys, BroadPhaseStats& st) {
    BroadPhaseMethods& m = *bp.methods_;
    // proxies created or destroyed: start the order afresh (a full sort)
    if (m.order_topology != bp.topology_) {
      m.order.clear();
      for (std::uint32_t p = 0; p < bp.boxes_.size(); ++p)
        if (bp.alive_[p]) m.order.push_back(p);
      std::sort(m.order.begin(), m.order.end(), [&](std::uint32_t a, std::uint32_t b) {
        const double la = bp.boxes_[a].lo.x, lb = bp.boxes_[b].lo.x;
        return la < lb || (la == lb && a < b);
      });
      m.order_lo.resize(m.order.size());
      m.order_topology = bp.topology_;
    }
    // refresh the keys and insertion-sort by (lo.x, index)
    const std::size_t n = m.order.size();
    for (std::size_t k = 0; k < n; ++k) m.order_lo[k] = bp.boxes_[m.order[k]].lo.x;
    for (std::size_t k = 1; k < n; ++k) {
      const double key = m.order_lo[k];
      const std::uint32_t p = m.order[k];
      std::size_t j = k;
      while (j > 0 && (m.order_lo[j - 1] > key || (m.order_lo[j - 1] == key && m.order[j - 1] > p))) {
        m.order_lo[j] = m.order_lo[j - 1];
        m.order[j] = m.order[j - 1];
        --j;
      }
      m.order_lo[j] = key;
      m.order[j] = p;
    }
    // sweep
    std::size_t tests = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t a = m.order[i];
      const Aabb& ba = bp.boxes_[a];
      const double end = ba.hi.x;
      for (std::size_t j = i + 1; j < n && m.order_lo[j] <= end; ++j) {
        const std::uint32_t b = m.order[j];
        const Aabb& bb = bp.boxes_[b];
        ++tests;
        if (ba.lo.y <= bb.hi.y && bb.lo.y <= ba.hi.y && ba.lo.z <= bb.hi.z && bb.lo.z <= ba.hi.z &&
            should_pair(bp.filters_[a], bp.filters_[b]))
          keys.push_back(pair_key(a, b));
      }
    }
    st.box_tests = tests;
  }

  // every pair of live proxies: the reference
  static void brute_force(BroadPhase& bp, std::vector<std::uint64_t>& keys, BroadPhaseStats& st) {
    const auto n = static_cast<std::uint32_t>(bp.boxes_.size());
    std::size_t tests = 0;
    for (std::uint32_t a = 0; a < n; ++a) {
      if (!bp.alive_[a]) continue;
      const Aabb& ba = bp.boxes_[a];
      for (std::uint32_t b = a + 1; b < n; ++b) {
        if (!bp.alive_[b]) continue;
        ++tests;
        // all six comparisons without branches: the outcome of each is a coin toss, the
        // outcome of all six is nearly always "apart"
        const Aabb& bb = bp.boxes_[b];
        const bool overlap = (ba.lo.x <= bb.hi.x) & (bb.lo.x <= ba.hi.x) & (ba.lo.y <= bb.hi.y) &
                             (bb.lo.y <= ba.hi.y) & (ba.lo.z <= bb.hi.z) & (bb.lo.z <= ba.hi.z);
        if (overlap && should_pair(bp.filters_[a], bp.filters_[b])) keys.push_back(pair_key(a, b));
      }
    }
    st.box_tests = tests;
  }
};

}  // namespace detail

// --- proxies --------------------------------------------------------------------------------

BroadPhase::BroadPhase(const BroadPhaseDef& def)
    : tree_(def.tree_margin), methods_(std::make_unique<detail::BroadPhaseMethods>()), method_(def.method), def_(def) {
  if (def.grid_cell != 0) require_positive(def.grid_cell, "BroadPhaseDef.grid_cell");
  require_count(def.grid_max_cells_per_box, 1, 1000000, "BroadPhaseDef.grid_max_cells_per_box");
  stats_.method = method_;
}

BroadPhase::~BroadPhase() = default;
BroadPhase::BroadPhase(BroadPhase&&) noexcept = default;
BroadPhase& BroadPhase::operator=(BroadPhase&&) noexcept = default;

void BroadPhase::check(ProxyId id, std::string_view where) const { pool_.require(id, where); }

void BroadPhase::reserve(std::size_t n) {
  pool_.reserve(n);
  boxes_.reserve(n);
  filters_.reserve(n);
  user_.reserve(n);
  node_.reserve(n);
  fat_.reserve(n);
  alive_.reserve(n);
  moved_.reserve(n);
  move_buffer_.reserve(n);
}

ProxyId BroadPhase::create_proxy(const Aabb& box, const CollisionFilter& filter, std::uint64_t user_data) {
  require_valid_box(box, "BroadPhase.create_proxy(box)");
  const ProxyId id = pool_.create();
  const std::uint32_t i = id.index;
  // grow the slot arrays when the pool appended a slot
  if (i >= boxes_.size()) {
    boxes_.resize(i + 1);
    filters_.resize(i + 1);
    user_.resize(i + 1, 0);
    node_.resize(i + 1, DynamicTree::kNull);
    fat_.resize(i + 1);
    alive_.resize(i + 1, 0);
    moved_.resize(i + 1, 0);
  }
  boxes_[i] = box;
  filters_[i] = filter;
  user_[i] = user_data;
  alive_[i] = 1;
  // the tree inserts at once and queries the new proxy at the next update
  if (method_ == BroadPhaseMethod::Tree) {
    node_[i] = tree_.create_proxy(box, i);
    fat_[i] = tree_.fat_box(node_[i]);
    if (!moved_[i]) {
      moved_[i] = 1;
      move_buffer_.push_back(i);
    }
  }
  ++topology_;
  return id;
}

void BroadPhase::destroy_proxy(ProxyId id) {
  check(id, "BroadPhase.destroy_proxy");
  const std::uint32_t i = id.index;
  if (node_[i] != DynamicTree::kNull) {
    tree_.destroy_proxy(node_[i]);
    node_[i] = DynamicTree::kNull;
  }
  alive_[i] = 0;
  pool_.destroy(id, "BroadPhase.destroy_proxy");
  ++topology_;
}

void BroadPhase::move_proxy(ProxyId id, const Aabb& box) {
  // the full checks (which build messages) only when the quick ones fail: this runs for
  // every proxy every frame
  constexpr double kHuge = 1.7976931348623157e308;  // the largest finite double
  const bool box_ok = (box.lo.x <= box.hi.x) & (box.lo.y <= box.hi.y) & (box.lo.z <= box.hi.z) &
                      (std::abs(box.lo.x) <= kHuge) & (std::abs(box.lo.y) <= kHuge) & (std::abs(box.lo.z) <= kHuge) &
                      (std::abs(box.hi.x) <= kHuge) & (std::abs(box.hi.y) <= kHuge) & (std::abs(box.hi.z) <= kHuge);
  if (!(pool_.valid(id) & box_ok)) {
    check(id, "BroadPhase.move_proxy");
    require_valid_box(box, "BroadPhase.move_proxy(box)");
  }
  const std::uint32_t i = id.index;
  boxes_[i] = box;
  // a proxy that left its fat box joins the move buffer (the copy of the fat box beside the
  // tight ones answers the common case without reading the tree's node)
  if (method_ == BroadPhaseMethod::Tree && !fat_[i].contains(box) && tree_.move_proxy(node_[i], box)) {
    fat_[i] = tree_.fat_box(node_[i]);
    if (!moved_[i]) {
      moved_[i] = 1;
      move_buffer_.push_back(i);
    }
  }
}

void BroadPhase::set_filter(ProxyId id, const CollisionFilter& filter) {
  check(id, "BroadPhase.set_filter");
  const std::uint32_t i = id.index;
  filters_[i] = filter;
  if (method_ == BroadPhaseMethod::Tree && !moved_[i]) {
    moved_[i] = 1;
    move_buffer_.push_back(i);
  }
}

void BroadPhase::set_method(BroadPhaseMethod m) {
  if (m == method_) return;
  method_ = m;
  // the tree exists only while it is the method
  if (m == BroadPhaseMethod::Tree) {
    rebuild_tree();
  } else {
    tree_.clear();
    tree_rebuilt_ratio_ = tree_ratio_ = 0;
    reinserted_since_check_ = 0;
    std::fill(node_.begin(), node_.end(), DynamicTree::kNull);
    tree_keys_.clear();
    for (std::uint32_t p : move_buffer_) moved_[p] = 0;
    move_buffer_.clear();
  }
}

void BroadPhase::set_grid_cell(double cell) {
  if (cell != 0) require_positive(cell, "BroadPhase.set_grid_cell(cell)");
  def_.grid_cell = cell;
}

void BroadPhase::rebuild_tree() {
  // insert every live proxy, rebuild for a balanced tree, and query them all next update
  tree_.clear();
  tree_keys_.clear();
  for (std::uint32_t p : move_buffer_) moved_[p] = 0;
  move_buffer_.clear();
  for (std::uint32_t p = 0; p < boxes_.size(); ++p) {
    if (!alive_[p]) continue;
    node_[p] = tree_.create_proxy(boxes_[p], p);
    fat_[p] = tree_.fat_box(node_[p]);
    moved_[p] = 1;
    move_buffer_.push_back(p);
  }
  tree_.rebuild();
  tree_rebuilt_ratio_ = tree_ratio_ = tree_.area_ratio();
  reinserted_since_check_ = 0;
}

const Aabb& BroadPhase::box(ProxyId id) const {
  check(id, "BroadPhase.box");
  return boxes_[id.index];
}
const CollisionFilter& BroadPhase::filter(ProxyId id) const {
  check(id, "BroadPhase.filter");
  return filters_[id.index];
}
ProxyId BroadPhase::id_at(std::uint32_t index) const {
  if (index >= alive_.size() || !alive_[index]) return {};
  return {index, pool_.generation(index)};
}

// --- pairs ----------------------------------------------------------------------------------

void BroadPhase::update_tree_pairs() {
  // keep the tree's quality: rebuild by the SAH when the inner nodes' area has grown half as
  // much again as after the last rebuild (re-inserted leaves drift from the best layout).
  // Measuring the area reads every node, so it is measured once a quarter of the proxies
  // have been re-inserted since the last time; before the queries, so that a batch of
  // insertions (the first update) is queried in the rebuilt tree, not the inserted one
  reinserted_since_check_ += move_buffer_.size();
  if (4 * reinserted_since_check_ >= tree_.proxy_count()) {
    reinserted_since_check_ = 0;
    tree_ratio_ = tree_.area_ratio();
    if (tree_.proxy_count() > 2 && tree_ratio_ > 1.5 * tree_rebuilt_ratio_) {
      tree_.rebuild();
      tree_ratio_ = tree_rebuilt_ratio_ = tree_.area_ratio();
    }
  }

  // query the tree with the fat box of every proxy in the move buffer: the new candidates
  new_keys_.clear();
  std::size_t queried = 0;
  for (std::uint32_t p : move_buffer_) {
    if (!alive_[p]) continue;
    ++queried;
    const CollisionFilter& fp = filters_[p];
    tree_.query(fat_[p], [&](std::uint32_t q) {
      if (q != p && should_pair(fp, filters_[q])) new_keys_.push_back(pair_key(p, q));
      return true;
    });
  }
  stats_.reinserted = queried;

  // the new candidates sorted, without duplicates
  std::sort(new_keys_.begin(), new_keys_.end());
  new_keys_.erase(std::unique(new_keys_.begin(), new_keys_.end()), new_keys_.end());

  // one pass over the persistent set of fat-box pairs merged with the new candidates (both
  // sorted): keep the pairs whose fat boxes still overlap, report those whose tight boxes
  // do. Every pair of overlapping fat boxes is in the merge: a proxy whose fat box changed
  // was queried above, and two unchanged fat boxes overlap as before (so only the pairs of a
  // proxy in the move buffer test their fat boxes again). Tight boxes lie in the fat ones,
  // so no tight overlap is missed. The set holds only pairs the filters allow: a pair enters
  // it from a query, which tests them, and set_filter puts its proxy in the move buffer, so
  // only those pairs test the filters again. Each pair is written at the end of the list,
  // which grows by it only when the tight boxes overlap: no branch on that test, which goes
  // either way (a third of the pairs of fat boxes are apart)
  const std::size_t nt = tree_keys_.size(), nn = new_keys_.size();
  ensure_capacity(merge_keys_, nt + nn);
  merge_keys_.clear();
  // (room for every pair of the merge, made once: the list is the first `touching` of it,
  // and the room is not filled afresh each frame)
  if (pairs_.size() < nt + nn) {
    ensure_capacity(pairs_, nt + nn);
    pairs_.resize(nt + nn);
  }
  std::size_t tests = 0, touching = 0;
  // the higher proxy of each pair is anywhere in the arrays: its tight box is fetched some
  // pairs ahead (the lower one walks the arrays in order)
  constexpr std::size_t kAhead = 12;
  for (std::size_t i = 0, j = 0; i < nt || j < nn;) {
    if (i + kAhead < nt) __builtin_prefetch(&boxes_[static_cast<std::uint32_t>(tree_keys_[i + kAhead])]);
    // the next key of the union (a key in both lists is taken once)
    std::uint64_t key;
    if (j == nn || (i < nt && tree_keys_[i] < new_keys_[j])) {
      key = tree_keys_[i++];
    } else {
      key = new_keys_[j++];
      if (i < nt && tree_keys_[i] == key) ++i;
    }
    const auto a = static_cast<std::uint32_t>(key >> 32), b = static_cast<std::uint32_t>(key);
    if (!alive_[a] || !alive_[b]) continue;
    ++tests;
    if ((moved_[a] | moved_[b]) && !(fat_[a].overlaps(fat_[b]) & should_pair(filters_[a], filters_[b]))) continue;
    merge_keys_.push_back(key);
    pairs_[touching] = {{a, pool_.generation_unchecked(a)}, {b, pool_.generation_unchecked(b)}};
    touching += boxes_[a].overlaps(boxes_[b]);
  }
  pair_count_ = touching;
  tree_keys_.swap(merge_keys_);
  stats_.box_tests = tests;
  for (std::uint32_t p : move_buffer_) moved_[p] = 0;
  move_buffer_.clear();

  stats_.tree_height = tree_.height();
  stats_.tree_area_ratio = tree_ratio_;
}

std::span<const ProxyPair> BroadPhase::update_pairs() {
  const Stopwatch clock;
  pair_count_ = 0;
  stats_ = BroadPhaseStats{};
  stats_.method = method_;
  stats_.proxies = pool_.size();
  if (method_ == BroadPhaseMethod::Tree) {
    update_tree_pairs();
  } else {
    // the other methods give keys in their own order: sort them once
    new_keys_.clear();
    switch (method_) {
      case BroadPhaseMethod::Grid: detail::BroadPhaseMethods::grid(*this, new_keys_, stats_); break;
      case BroadPhaseMethod::SweepAndPrune: detail::BroadPhaseMethods::sweep_and_prune(*this, new_keys_, stats_); break;
      default: detail::BroadPhaseMethods::brute_force(*this, new_keys_, stats_); break;
    }
    std::sort(new_keys_.begin(), new_keys_.end());
    pairs_.clear();
    for (const std::uint64_t key : new_keys_) {
      const auto a = static_cast<std::uint32_t>(key >> 32), b = static_cast<std::uint32_t>(key);
      pairs_.push_back({{a, pool_.generation(a)}, {b, pool_.generation(b)}});
    }
    pair_count_ = pairs_.size();
  }
  // headroom for the next frames' fluctuations
  ensure_capacity(pairs_, pair_count_ + pair_count_ / 4);
  ensure_capacity(new_keys_, new_keys_.size() + new_keys_.size() / 4);
  ensure_capacity(tree_keys_, tree_keys_.size() + tree_keys_.size() / 4);
  ensure_capacity(merge_keys_, tree_keys_.size() + tree_keys_.size() / 4);
  stats_.pairs = pair_count_;
  stats_.seconds = clock.seconds();
  return pairs();
}

}  // namespace pba
