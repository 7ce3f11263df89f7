// Tests for pba/collide/broad_phase.h: every method's pair list equals the all-pairs box
// test (the reference), in the same sorted order, on moving, appearing and vanishing boxes
// and with filters; the dynamic tree keeps its invariants and its queries and ray casts
// equal brute force; bad input is named. Every comparison is exact: the methods decide the
// same predicate (closed boxes overlap) on the same doubles, so no tolerance applies.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <utility>
#include <vector>

#include "error_of.h"
#include "pba/collide/broad_phase.h"
#include "pba/collide/moving_boxes.h"

namespace {

using pba::Aabb;
using pba::BroadPhase;
using pba::BroadPhaseDef;
using pba::BroadPhaseMethod;
using pba::CollisionFilter;
using pba::DynamicTree;
using pba::ProxyId;
using pba::ProxyPair;
using pba::Ray;
using pba::Vec3;
using pba::test_support::error_of;

constexpr BroadPhaseMethod kMethods[] = {BroadPhaseMethod::Tree, BroadPhaseMethod::Grid,
                                         BroadPhaseMethod::SweepAndPrune, BroadPhaseMethod::BruteForce};
constexpr double kDt = 1.0 / 60.0;

// splitmix64, for test-side randomness independent of the library's
struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) { return lo + (hi - lo) * (double(next() >> 11) * 0x1.0p-53); }
  std::uint32_t below(std::uint32_t n) { return static_cast<std::uint32_t>(next() % n); }
};

// The test's own record of the proxies, by slot index: what the reference sees.
struct Mirror {
  std::vector<ProxyId> id;
  std::vector<Aabb> box;
  std::vector<CollisionFilter> filter;
  std::vector<bool> alive;
  void set(ProxyId p, const Aabb& b, const CollisionFilter& f) {
    if (p.index >= id.size()) {
      id.resize(p.index + 1);
      box.resize(p.index + 1);
      filter.resize(p.index + 1);
      alive.resize(p.index + 1, false);
    }
    id[p.index] = p;
    box[p.index] = b;
    filter[p.index] = f;
    alive[p.index] = true;
  }
};

// the reference: every pair of live slots, in index order (a < b, then by b), tested
// directly (the six comparisons without branches, for speed: 5 10^7 pairs a frame at 10^4)
std::vector<ProxyPair> all_pairs(const Mirror& m) {
  std::vector<ProxyPair> out;
  const std::size_t n = m.id.size();
  for (std::size_t a = 0; a < n; ++a) {
    if (!m.alive[a]) continue;
    const Aabb& p = m.box[a];
    for (std::size_t b = a + 1; b < n; ++b) {
      const Aabb& q = m.box[b];
      const bool overlap = (p.lo.x <= q.hi.x) & (q.lo.x <= p.hi.x) & (p.lo.y <= q.hi.y) & (q.lo.y <= p.hi.y) &
                           (p.lo.z <= q.hi.z) & (q.lo.z <= p.hi.z);
      if (overlap && m.alive[b] && pba::should_pair(m.filter[a], m.filter[b])) out.push_back({m.id[a], m.id[b]});
    }
  }
  return out;
}

// the same pairs as all_pairs, found by an interval sweep on x (slots sorted by their boxes'
// lower x; each slot meets the later ones whose lower x is at most its upper x, then the
// other two axes are tested), in the same order: the per-frame reference of the 10^4-box
// test, checked against all_pairs on its first and last frames
std::vector<ProxyPair> all_pairs_by_sweep(const Mirror& m) {
  std::vector<std::uint32_t> order;
  for (std::uint32_t a = 0; a < m.id.size(); ++a)
    if (m.alive[a]) order.push_back(a);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return m.box[a].lo.x < m.box[b].lo.x || (m.box[a].lo.x == m.box[b].lo.x && a < b);
  });
  std::vector<std::pair<std::uint32_t, std::uint32_t>> found;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Aabb& p = m.box[order[i]];
    for (std::size_t j = i + 1; j < order.size() && m.box[order[j]].lo.x <= p.hi.x; ++j) {
      const Aabb& q = m.box[order[j]];
      if (p.lo.y <= q.hi.y && q.lo.y <= p.hi.y && p.lo.z <= q.hi.z && q.lo.z <= p.hi.z &&
          pba::should_pair(m.filter[order[i]], m.filter[order[j]]))
        found.emplace_back(std::min(order[i], order[j]), std::max(order[i], order[j]));
    }
  }
  std::sort(found.begin(), found.end());
  std::vector<ProxyPair> out;
  for (const auto& [a, b] : found) out.push_back({m.id[a], m.id[b]});
  return out;
}

std::vector<ProxyPair> as_vector(std::span<const ProxyPair> s) { return {s.begin(), s.end()}; }

// the first place two pair lists differ, for a readable failure
std::string first_difference(const std::vector<ProxyPair>& got, const std::vector<ProxyPair>& want) {
  const std::size_t n = std::min(got.size(), want.size());
  for (std::size_t i = 0; i < n; ++i)
    if (!(got[i] == want[i]))
      return "at " + std::to_string(i) + ": got (" + std::to_string(got[i].a.index) + ", " +
             std::to_string(got[i].b.index) + "), want (" + std::to_string(want[i].a.index) + ", " +
             std::to_string(want[i].b.index) + ")";
  return "sizes " + std::to_string(got.size()) + " and " + std::to_string(want.size());
}

// --- the pair list -----------------------------------------------------------------------

// 10^4 boxes (10% of them fast enough to leave their fat box every frame) moving for 100
// frames: every method's list equals the all-pairs test (as the interval sweep each frame,
// itself equal to the direct test on the first and last frames), element by element
TEST(BroadPhase, EveryMethodEqualsAllPairsOnTenThousandMovingBoxes) {
  pba::MovingBoxes scene({.count = 10000, .seed = 3});
  std::vector<BroadPhase> bps;
  for (BroadPhaseMethod m : kMethods) bps.emplace_back(BroadPhaseDef{.method = m});
  Mirror mirror;
  for (std::size_t i = 0; i < scene.size(); ++i)
    for (BroadPhase& bp : bps) {
      const ProxyId id = bp.create_proxy(scene.box(i), {}, i);
      mirror.set(id, scene.box(i), {});
    }
  std::size_t total = 0, min_pairs = std::numeric_limits<std::size_t>::max();
  for (int frame = 0; frame < 100; ++frame) {
    scene.step(kDt);
    for (std::size_t i = 0; i < scene.size(); ++i) {
      for (BroadPhase& bp : bps) bp.move_proxy(mirror.id[i], scene.box(i));
      mirror.box[i] = scene.box(i);
    }
    const std::vector<ProxyPair> want = all_pairs_by_sweep(mirror);
    if (frame == 0 || frame == 99) {
      ASSERT_EQ(want, all_pairs(mirror)) << "the sweep reference, frame " << frame;
    }
    for (BroadPhase& bp : bps) {
      // (the brute-force method is the all-pairs test's own algorithm and as slow: every 25th frame)
      if (bp.method() == BroadPhaseMethod::BruteForce && frame % 25 != 24) continue;
      const std::vector<ProxyPair> got = as_vector(bp.update_pairs());
      ASSERT_EQ(got, want) << to_string(bp.method()) << ", frame " << frame << ": " << first_difference(got, want);
      EXPECT_EQ(bp.stats().pairs, want.size());
    }
    total += want.size();
    min_pairs = std::min(min_pairs, want.size());
  }
  // the scene is not trivial: boxes of mean edge 0.7 m at one per 1.6^3 m^3 touch often
  EXPECT_GT(min_pairs, 500u);
  bps[0].tree().validate();
  EXPECT_GT(bps[0].stats().reinserted, 0u);
  std::printf("[          ] %zu pairs per frame on average\n", total / 100);
}

// switching the method between frames (the lab's switch) keeps the same list
TEST(BroadPhase, SwitchingMethodsLiveKeepsTheList) {
  pba::MovingBoxes scene({.count = 3000, .seed = 5});
  BroadPhase bp;
  Mirror mirror;
  for (std::size_t i = 0; i < scene.size(); ++i) mirror.set(bp.create_proxy(scene.box(i)), scene.box(i), {});
  for (int frame = 0; frame < 40; ++frame) {
    scene.step(kDt);
    for (std::size_t i = 0; i < scene.size(); ++i) {
      bp.move_proxy(mirror.id[i], scene.box(i));
      mirror.box[i] = scene.box(i);
    }
    bp.set_method(kMethods[(frame / 3) % 4]);
    const std::vector<ProxyPair> want = all_pairs(mirror);
    ASSERT_EQ(as_vector(bp.update_pairs()), want) << to_string(bp.method()) << ", frame " << frame;
  }
}

// filters: the rule on a hand-made trio, then random layers, masks and owners on moving boxes
TEST(BroadPhase, FiltersByLayersMasksAndOwners) {
  // a (layer 1, sees 2) and b (layer 2, sees 1 and 2) pair; c (layer 2, sees only 2) pairs
  // with b but not with a (a's layer is not in c's mask); d (layer 2, sees 1 and 2) shares
  // a's owner and so never pairs with a, though their layers accept each other
  const CollisionFilter fa{.layer = 1, .mask = 2, .owner = 7}, fb{.layer = 2, .mask = 1 | 2},
      fc{.layer = 2, .mask = 2}, fd{.layer = 2, .mask = 1 | 2, .owner = 7};
  EXPECT_TRUE(pba::should_pair(fa, fb));
  EXPECT_FALSE(pba::should_pair(fa, fc));
  EXPECT_TRUE(pba::should_pair(fb, fc));
  EXPECT_FALSE(pba::should_pair(fa, fd));
  const Aabb unit{{0, 0, 0}, {1, 1, 1}};
  for (BroadPhaseMethod m : kMethods) {
    BroadPhase bp({.method = m});
    const ProxyId a = bp.create_proxy(unit, fa), b = bp.create_proxy(unit, fb), c = bp.create_proxy(unit, fc),
                  d = bp.create_proxy(unit, fd);
    const std::vector<ProxyPair> want{{a, b}, {b, c}, {b, d}, {c, d}};
    EXPECT_EQ(as_vector(bp.update_pairs()), want) << to_string(m);
    // a filter changed mid-run takes effect at the next update, and back again
    bp.set_filter(b, {.layer = 4, .mask = 4});
    EXPECT_EQ(as_vector(bp.update_pairs()), (std::vector<ProxyPair>{{c, d}})) << to_string(m);
    bp.set_filter(b, fb);
    EXPECT_EQ(as_vector(bp.update_pairs()), want) << to_string(m);
  }

  // random filters on 2000 moving boxes
  pba::MovingBoxes scene({.count = 2000, .seed = 11});
  Rng rng{17};
  std::vector<CollisionFilter> filters(scene.size());
  for (CollisionFilter& f : filters)
    f = {.layer = 1ull << rng.below(4), .mask = rng.next() & 0xf, .owner = rng.below(3) == 0 ? 1 + rng.below(50) : 0};
  std::vector<BroadPhase> bps;
  for (BroadPhaseMethod m : kMethods) bps.emplace_back(BroadPhaseDef{.method = m});
  Mirror mirror;
  for (std::size_t i = 0; i < scene.size(); ++i)
    for (BroadPhase& bp : bps) mirror.set(bp.create_proxy(scene.box(i), filters[i]), scene.box(i), filters[i]);
  std::size_t rejected = 0;
  for (int frame = 0; frame < 30; ++frame) {
    scene.step(kDt);
    for (std::size_t i = 0; i < scene.size(); ++i) {
      for (BroadPhase& bp : bps) bp.move_proxy(mirror.id[i], scene.box(i));
      mirror.box[i] = scene.box(i);
    }
    const std::vector<ProxyPair> want = all_pairs(mirror);
    for (BroadPhase& bp : bps) ASSERT_EQ(as_vector(bp.update_pairs()), want) << to_string(bp.method()) << ", frame " << frame;
    // the filters did reject pairs whose boxes overlap (the test would pass vacuously otherwise)
    Mirror open = mirror;
    std::fill(open.filter.begin(), open.filter.end(), CollisionFilter{});
    rejected += all_pairs(open).size() - want.size();
  }
  EXPECT_GT(rejected, 1000u);
}

// proxies created and destroyed every frame (slots reused with new generations), a huge
// ground box (the grid's oversized path) and a grid with a tiny set cell
TEST(BroadPhase, ProxiesCreatedAndDestroyedMidRun) {
  pba::MovingBoxes scene({.count = 3000, .seed = 23});
  const Aabb ground{{-100, -1, -100}, {100, 0.3, 100}};
  std::vector<BroadPhase> bps;
  for (BroadPhaseMethod m : kMethods) bps.emplace_back(BroadPhaseDef{.method = m});
  bps.emplace_back(BroadPhaseDef{.method = BroadPhaseMethod::Grid, .grid_cell = 0.3});
  Mirror mirror;
  std::vector<std::vector<ProxyId>> ids(bps.size());  // per broad phase, per body (null when absent)
  auto add = [&](std::size_t body) {
    ProxyId first{};
    for (std::size_t k = 0; k < bps.size(); ++k) {
      ids[k][body] = bps[k].create_proxy(scene.box(body), {}, body);
      if (k == 0) first = ids[k][body];
      // every broad phase issues the same slots (LIFO reuse): the lists are comparable
      ASSERT_EQ(ids[k][body], first);
    }
    mirror.set(first, scene.box(body), {});
  };
  for (auto& v : ids) v.resize(scene.size() + 1);
  for (std::size_t i = 0; i < scene.size(); ++i) add(i);
  // the ground is body `size()`
  for (std::size_t k = 0; k < bps.size(); ++k) ids[k][scene.size()] = bps[k].create_proxy(ground);
  mirror.set(ids[0][scene.size()], ground, {});

  Rng rng{29};
  for (int frame = 0; frame < 100; ++frame) {
    scene.step(kDt);
    // destroy 30 bodies and bring back 30 absent ones
    for (int r = 0; r < 30; ++r) {
      const std::uint32_t body = rng.below(static_cast<std::uint32_t>(scene.size()));
      if (ids[0][body].is_null()) continue;
      mirror.alive[ids[0][body].index] = false;
      for (std::size_t k = 0; k < bps.size(); ++k) {
        bps[k].destroy_proxy(ids[k][body]);
        EXPECT_FALSE(bps[k].valid(ids[k][body]));
        ids[k][body] = {};
      }
    }
    for (int r = 0; r < 30; ++r) {
      const std::uint32_t body = rng.below(static_cast<std::uint32_t>(scene.size()));
      if (ids[0][body].is_null()) add(body);
    }
    // move the rest
    for (std::size_t i = 0; i < scene.size(); ++i) {
      if (ids[0][i].is_null()) continue;
      for (std::size_t k = 0; k < bps.size(); ++k) bps[k].move_proxy(ids[k][i], scene.box(i));
      mirror.box[ids[0][i].index] = scene.box(i);
    }
    const std::vector<ProxyPair> want = all_pairs(mirror);
    for (BroadPhase& bp : bps) {
      const std::vector<ProxyPair> got = as_vector(bp.update_pairs());
      ASSERT_EQ(got, want) << to_string(bp.method()) << ", frame " << frame << ": " << first_difference(got, want);
    }
    // every reported id is live (the generation is current)
    for (const ProxyPair& p : bps[0].pairs()) ASSERT_TRUE(bps[0].valid(p.a) && bps[0].valid(p.b));
  }
  bps[0].tree().validate();
}

// the same scene twice gives the same lists bit for bit; and the tree's list does not
// depend on the path the boxes took to get where they are
TEST(BroadPhase, DeterministicAndIndependentOfHistory) {
  auto run = [](BroadPhaseMethod m) {
    pba::MovingBoxes scene({.count = 2000, .seed = 31});
    BroadPhase bp({.method = m});
    std::vector<ProxyId> ids;
    for (std::size_t i = 0; i < scene.size(); ++i) ids.push_back(bp.create_proxy(scene.box(i)));
    std::uint64_t h = 0xcbf29ce484222325ULL;
    for (int frame = 0; frame < 30; ++frame) {
      scene.step(kDt);
      for (std::size_t i = 0; i < scene.size(); ++i) bp.move_proxy(ids[i], scene.box(i));
      const auto pairs = bp.update_pairs();
      h = pba::hash_span(pairs, h);
    }
    return h;
  };
  for (BroadPhaseMethod m : kMethods) EXPECT_EQ(run(m), run(m)) << to_string(m);
  EXPECT_EQ(run(BroadPhaseMethod::Tree), run(BroadPhaseMethod::BruteForce));

  // history: one tree gets the final boxes at once, the other wanders there over 20 frames
  pba::MovingBoxes scene({.count = 2000, .seed = 37});
  BroadPhase direct, wandering;
  std::vector<ProxyId> a, b;
  Rng rng{41};
  for (std::size_t i = 0; i < scene.size(); ++i) {
    a.push_back(direct.create_proxy(scene.box(i)));
    const Vec3 off(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5));
    b.push_back(wandering.create_proxy({scene.box(i).lo + off, scene.box(i).hi + off}));
  }
  for (int frame = 20; frame >= 0; --frame) {
    for (std::size_t i = 0; i < scene.size(); ++i) {
      const Vec3 off = double(frame) / 20 * Vec3(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5));
      wandering.move_proxy(b[i], {scene.box(i).lo + off, scene.box(i).hi + off});
    }
    wandering.update_pairs();
  }
  EXPECT_EQ(as_vector(wandering.update_pairs()), as_vector(direct.update_pairs()));
  EXPECT_FALSE(direct.pairs().empty());
}

// --- the dynamic tree ------------------------------------------------------------------

Aabb random_box(Rng& rng, double side) {
  const Vec3 c(rng.uniform(0, side), rng.uniform(0, side), rng.uniform(0, side));
  const Vec3 h(rng.uniform(0.05, 0.6), rng.uniform(0.05, 0.6), rng.uniform(0.05, 0.6));
  return {c - h, c + h};
}

// `count` leaves of random boxes in a cube of `side` (m), users 0 .. count - 1; their nodes
std::vector<std::int32_t> random_leaves(DynamicTree& tree, Rng& rng, double side, std::uint32_t count) {
  std::vector<std::int32_t> node;
  for (std::uint32_t i = 0; i < count; ++i) node.push_back(tree.create_proxy(random_box(rng, side), i));
  return node;
}

// after thousands of moves, teleports, removals and insertions: parents contain their
// children, heights are consistent and within the limit (validate()), and fat boxes hold
// their tight boxes
TEST(DynamicTree, KeepsItsInvariantsAfterManyMoves) {
  Rng rng{43};
  const double side = 30;
  DynamicTree tree(0.1);
  std::vector<std::int32_t> node;
  std::vector<Aabb> box;
  for (int i = 0; i < 5000; ++i) {
    box.push_back(random_box(rng, side));
    node.push_back(tree.create_proxy(box.back(), static_cast<std::uint32_t>(i)));
  }
  tree.validate();
  int reinserted = 0;
  for (int round = 0; round < 200; ++round) {
    for (std::size_t i = 0; i < box.size(); ++i) {
      if (node[i] == DynamicTree::kNull) {
        // bring back a removed leaf
        if (rng.below(4) == 0) {
          box[i] = random_box(rng, side);
          node[i] = tree.create_proxy(box[i], static_cast<std::uint32_t>(i));
        }
        continue;
      }
      const std::uint32_t r = rng.below(100);
      if (r < 2) {
        tree.destroy_proxy(node[i]);
        node[i] = DynamicTree::kNull;
        continue;
      }
      // jitter most, teleport a few
      const Vec3 d = r < 5 ? Vec3(rng.uniform(-side, side), rng.uniform(-side, side), rng.uniform(-side, side)) * 0.5
                           : Vec3(rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05));
      box[i] = {box[i].lo + d, box[i].hi + d};
      reinserted += tree.move_proxy(node[i], box[i]);
    }
    if (round % 10 == 0) tree.validate();
  }
  tree.validate();
  EXPECT_GT(reinserted, 10000);
  std::size_t leaves = 0;
  for (std::size_t i = 0; i < box.size(); ++i) {
    if (node[i] == DynamicTree::kNull) continue;
    ++leaves;
    EXPECT_TRUE(tree.fat_box(node[i]).contains(box[i])) << i;
    EXPECT_EQ(tree.user(node[i]), i);
  }
  EXPECT_EQ(tree.proxy_count(), leaves);
  // the rotations alone keep the tree within twice the height of a perfect one
  EXPECT_LE(tree.height(), 2 * static_cast<int>(std::ceil(std::log2(double(leaves)))));
  const double incremental = tree.area_ratio();
  // the SAH rebuild keeps the invariants and the height limit (validate) and lowers the
  // SAH cost it greedily minimises: the inner nodes' total area
  tree.rebuild();
  tree.validate();
  EXPECT_LT(tree.area_ratio(), incremental);
  std::printf("[          ] %zu leaves: area ratio %.1f incremental, %.1f rebuilt; height %d\n", leaves, incremental,
              tree.area_ratio(), tree.height());
  // a tree of inner nodes the size of the root would have ratio ~ n: SAH insertion does far better
  EXPECT_LT(incremental, 0.05 * double(leaves));
}

// query and ray cast visit exactly the leaves brute force finds
TEST(DynamicTree, QueryAndRayCastEqualBruteForce) {
  Rng rng{47};
  const double side = 25;
  DynamicTree tree(0.1);
  std::vector<std::int32_t> node = random_leaves(tree, rng, side, 4000);
  // move them a little so the tree is not freshly built
  for (std::uint32_t i = 0; i < node.size(); ++i) {
    const Aabb f = tree.fat_box(node[i]);
    const Vec3 d(rng.uniform(-0.5, 0.5), 0, 0);
    tree.move_proxy(node[i], {f.lo + Vec3(0.1) + d, f.hi - Vec3(0.1) + d});
  }
  auto fat = [&](std::uint32_t u) { return tree.fat_box(node[u]); };

  // box queries
  for (int q = 0; q < 500; ++q) {
    const Aabb b = random_box(rng, side);
    std::set<std::uint32_t> got, want;
    tree.query(b, [&](std::uint32_t u) { return got.insert(u).second; });
    for (std::uint32_t u = 0; u < node.size(); ++u)
      if (fat(u).overlaps(b)) want.insert(u);
    ASSERT_EQ(got, want) << "query " << q;
  }

  // 5 m rays from random points: the nearest box entered and every box entered
  int hits = 0;
  for (int q = 0; q < 3000; ++q) {
    Vec3 d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    if (q % 10 == 0) d = Vec3(0, 0, 1);  // axis-aligned rays: two slabs never crossed
    const Ray ray{{rng.uniform(0, side), rng.uniform(0, side), rng.uniform(0, side)}, glm::normalize(d), 5.0};
    const Vec3 inv = 1.0 / ray.direction;
    double want_t = -1;
    std::set<std::uint32_t> want_all;
    for (std::uint32_t u = 0; u < node.size(); ++u) {
      const double t = pba::ray_enter_box(ray, inv, fat(u));
      if (t < 0) continue;
      want_all.insert(u);
      if (want_t < 0 || t < want_t) want_t = t;
    }
    // closest: clip the ray at each box entered
    double got_t = -1;
    tree.ray_cast(ray, [&](std::uint32_t u, const Ray& r) {
      const double t = pba::ray_enter_box(r, inv, fat(u));
      if (t < 0) return r.max_distance;
      got_t = t;
      return t;
    });
    ASSERT_EQ(got_t, want_t) << "ray " << q;
    hits += want_t >= 0;
    // all: never clip
    std::set<std::uint32_t> got_all;
    tree.ray_cast(ray, [&](std::uint32_t u, const Ray& r) {
      got_all.insert(u);
      return r.max_distance;
    });
    ASSERT_EQ(got_all, want_all) << "ray " << q;
  }
  EXPECT_GT(hits, 300);
  EXPECT_LT(hits, 2900);
  // a negative return stops the cast at the first leaf
  int calls = 0;
  tree.ray_cast({{0, 0, 0}, glm::normalize(Vec3(1, 1, 1)), 100}, [&](std::uint32_t, const Ray&) {
    ++calls;
    return -1.0;
  });
  EXPECT_EQ(calls, 1);
}

// leaves given new boxes in place (set_leaf_box: no re-insertion) while they move: a heap of
// boxes falling together, some jittering, a few teleported across the scene. The tree keeps
// its shape (the same nodes and links), every inner box stays the exact union of its
// children's (validate(), and the root equals the union of all leaves), and queries find
// exactly what brute force finds over the fat boxes
TEST(DynamicTree, LeafBoxesSetInPlaceKeepTheTreeExact) {
  Rng rng{53};
  const double side = 25;
  DynamicTree tree(0.1);
  std::vector<std::int32_t> node;
  std::vector<Aabb> box;
  for (std::uint32_t i = 0; i < 3000; ++i) {
    box.push_back(random_box(rng, side));
    node.push_back(tree.create_proxy(box.back(), i));
  }
  tree.rebuild();
  std::vector<Aabb> base = box;
  std::vector<std::int32_t> links;
  for (const DynamicTree::Node& n : tree.nodes()) links.insert(links.end(), {n.parent, n.child1, n.child2, n.height});
  for (int round = 0; round < 30; ++round) {
    for (std::size_t i = 0; i < box.size(); ++i) {
      const std::uint32_t r = rng.below(100);
      const Vec3 d = r < 3    ? Vec3(rng.uniform(-side, side), rng.uniform(-side, side), rng.uniform(-side, side)) * 0.5
                     : r < 50 ? Vec3(rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05))
                              : Vec3(0, -0.3, 0);
      base[i] = {base[i].lo + d, base[i].hi + d};
      // some a little smaller than the box they move with (a fat box made anew smaller):
      // ancestors must shrink with them
      box[i] = r % 7 == 0 ? Aabb{base[i].lo + Vec3(0.02), base[i].hi - Vec3(0.02)} : base[i];
      tree.set_leaf_box(node[i], box[i]);
    }
    tree.validate();
    Aabb all = tree.fat_box(node[0]);
    for (std::size_t i = 0; i < box.size(); ++i) {
      EXPECT_EQ(tree.fat_box(node[i]).lo, box[i].lo - Vec3(0.1)) << i;
      EXPECT_EQ(tree.fat_box(node[i]).hi, box[i].hi + Vec3(0.1)) << i;
      all = all.merged(tree.fat_box(node[i]));
    }
    // the root is the union itself, not a box that merely contains it
    ASSERT_EQ(tree.nodes()[static_cast<std::size_t>(tree.root())].box.lo, all.lo) << "round " << round;
    ASSERT_EQ(tree.nodes()[static_cast<std::size_t>(tree.root())].box.hi, all.hi) << "round " << round;
    for (int q = 0; q < 50; ++q) {
      const Aabb b = random_box(rng, side);
      std::set<std::uint32_t> got, want;
      tree.query(b, [&](std::uint32_t u) { return got.insert(u).second; });
      for (std::uint32_t u = 0; u < node.size(); ++u)
        if (tree.fat_box(node[u]).overlaps(b)) want.insert(u);
      ASSERT_EQ(got, want) << "round " << round << ", query " << q;
    }
  }
  // nothing was re-inserted or rotated
  std::vector<std::int32_t> after;
  for (const DynamicTree::Node& n : tree.nodes()) after.insert(after.end(), {n.parent, n.child1, n.child2, n.height});
  EXPECT_EQ(after, links);
  EXPECT_EQ(tree.proxy_count(), box.size());
}

// leaves given new boxes in place in any order end in the same tree to the bit (the rigid
// bodies' pair phase sets them in the order of their parents' indices, not the bodies'):
// each inner box is the union of its children's whichever leaf below it was set last, and a
// walk up stops only where nothing above can change. The same moves, set in three orders
// (as listed, backwards, by a shuffle), leave every node's box and link equal, round after
// round, and queries find the same leaves
TEST(DynamicTree, LeafBoxesSetInAnyOrderGiveTheSameTree) {
  Rng rng{71};
  const double side = 25;
  std::vector<Aabb> box;
  for (std::uint32_t i = 0; i < 2000; ++i) box.push_back(random_box(rng, side));
  DynamicTree trees[3] = {DynamicTree(0.1), DynamicTree(0.1), DynamicTree(0.1)};
  std::vector<std::int32_t> node;
  for (DynamicTree& t : trees) {
    node.clear();
    for (std::uint32_t i = 0; i < box.size(); ++i) node.push_back(t.create_proxy(box[i], i));
    t.rebuild();
  }
  std::vector<std::size_t> order(box.size());
  for (int round = 0; round < 20; ++round) {
    // a third of the leaves move: most a little, some far, some shrink
    std::vector<std::size_t> movers;
    for (std::size_t i = 0; i < box.size(); ++i) {
      const std::uint32_t r = rng.below(100);
      if (r >= 33) continue;
      const Vec3 d = r < 2 ? Vec3(rng.uniform(-side, side), rng.uniform(-side, side), rng.uniform(-side, side)) * 0.5
                           : Vec3(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3));
      const Vec3 shrink = r % 5 == 0 ? Vec3(0.002) : Vec3(0);
      box[i] = {box[i].lo + d + shrink, box[i].hi + d - shrink};
      movers.push_back(i);
    }
    for (std::size_t k = 0; k < movers.size(); ++k) trees[0].set_leaf_box(node[movers[k]], box[movers[k]]);
    for (std::size_t k = movers.size(); k-- > 0;) trees[1].set_leaf_box(node[movers[k]], box[movers[k]]);
    std::vector<std::size_t> shuffled = movers;
    for (std::size_t k = shuffled.size(); k > 1; --k)
      std::swap(shuffled[k - 1], shuffled[rng.below(static_cast<std::uint32_t>(k))]);
    for (const std::size_t i : shuffled) trees[2].set_leaf_box(node[i], box[i]);
    for (int t = 1; t < 3; ++t) {
      trees[t].validate();
      ASSERT_EQ(trees[t].nodes().size(), trees[0].nodes().size());
      for (std::size_t n = 0; n < trees[0].nodes().size(); ++n) {
        const DynamicTree::Node &a = trees[0].nodes()[n], &b = trees[t].nodes()[n];
        ASSERT_TRUE(a.box.lo == b.box.lo && a.box.hi == b.box.hi && a.parent == b.parent && a.child1 == b.child1 &&
                    a.child2 == b.child2 && a.height == b.height)
            << "round " << round << ", order " << t << ", node " << n;
      }
    }
    for (int q = 0; q < 20; ++q) {
      const Aabb b = random_box(rng, side);
      std::vector<std::uint32_t> got[3];
      for (int t = 0; t < 3; ++t) {
        trees[t].query(b, [&](std::uint32_t u) { return got[t].push_back(u), true; });
        std::sort(got[t].begin(), got[t].end());
      }
      ASSERT_EQ(got[1], got[0]) << "round " << round << ", query " << q;
      ASSERT_EQ(got[2], got[0]) << "round " << round << ", query " << q;
    }
  }
}

// leaves made unplaced and then rebuilt (the rigid bodies' first step of many shapes) give the
// tree a rebuild of inserted leaves gives: the same leaves under the same parents, walked in
// the same order (only the nodes' indices differ: no inner node was made before the rebuild),
// invariants kept, the same leaves found by queries; a tree of only unplaced leaves, no root
// before its rebuild, builds too
TEST(DynamicTree, UnplacedLeavesRebuiltGiveTheInsertedTree) {
  Rng rng{83};
  const double side = 25;
  std::vector<Aabb> box;
  for (std::uint32_t i = 0; i < 3000; ++i) box.push_back(random_box(rng, side));
  for (const std::size_t placed : {std::size_t{0}, std::size_t{16}}) {
    DynamicTree inserted(0.1), unplaced(0.1);
    for (std::uint32_t i = 0; i < box.size(); ++i) {
      inserted.create_proxy(box[i], i);
      if (i < placed) unplaced.create_proxy(box[i], i);
      else unplaced.create_proxy_unplaced(box[i], i);
    }
    EXPECT_EQ(unplaced.proxy_count(), box.size());
    inserted.rebuild();
    unplaced.rebuild();
    unplaced.validate();
    // the two trees walked depth first side by side: the same shape, leaves and boxes
    std::vector<std::pair<std::int32_t, std::int32_t>> stack{{inserted.root(), unplaced.root()}};
    std::size_t leaves = 0;
    while (!stack.empty()) {
      const auto [x, y] = stack.back();
      stack.pop_back();
      const DynamicTree::Node &a = inserted.nodes()[static_cast<std::size_t>(x)];
      const DynamicTree::Node &b = unplaced.nodes()[static_cast<std::size_t>(y)];
      ASSERT_TRUE(a.box.lo == b.box.lo && a.box.hi == b.box.hi && a.height == b.height && a.is_leaf() == b.is_leaf())
          << "placed " << placed << ", nodes " << x << " and " << y;
      if (a.is_leaf()) {
        ASSERT_EQ(a.user, b.user);
        ++leaves;
        continue;
      }
      stack.push_back({a.child1, b.child1});
      stack.push_back({a.child2, b.child2});
    }
    EXPECT_EQ(leaves, box.size());
    for (int q = 0; q < 50; ++q) {
      const Aabb b = random_box(rng, side);
      std::vector<std::uint32_t> got[2];
      inserted.query(b, [&](std::uint32_t u) { return got[0].push_back(u), true; });
      unplaced.query(b, [&](std::uint32_t u) { return got[1].push_back(u), true; });
      ASSERT_EQ(got[1], got[0]) << "placed " << placed << ", query " << q;
    }
  }
}

// query_pairs finds, each once, the pairs that a query of each listed leaf's fat box finds
// (itself left out, a pair of two listed leaves from either side): the rigid bodies' pair
// phase walks the tree against itself this way for its moved proxies. Some leaves listed,
// all of them, one, none; on a tree rebuilt and on one grown by insertions and moves
TEST(DynamicTree, QueryPairsFindTheListedLeavesQueriesPairsOnce) {
  Rng rng{97};
  const double side = 25;
  DynamicTree tree(0.1);
  const std::vector<std::int32_t> node = random_leaves(tree, rng, side, 2500);
  for (int round = 0; round < 8; ++round) {
    if (round == 4) tree.rebuild();
    if (round % 2 == 1)
      for (int k = 0; k < 300; ++k) {
        const std::uint32_t i = rng.below(static_cast<std::uint32_t>(node.size()));
        tree.move_proxy(node[i], random_box(rng, side));
      }
    std::vector<std::int32_t> listed;
    for (std::size_t i = 0; i < node.size(); ++i) {
      const bool all = round % 4 == 2;
      if (all || rng.below(100) < 20) listed.push_back(node[i]);
    }
    if (round == 3) listed.assign(1, node[7]);
    if (round == 7) listed.clear();
    // by queries: the pairs (lower user, higher user)
    std::vector<std::pair<std::uint32_t, std::uint32_t>> want, got;
    for (const std::int32_t n : listed) {
      const std::uint32_t u = tree.user(n);
      tree.query(tree.fat_box(n), [&](std::uint32_t v) {
        if (v != u) want.emplace_back(std::min(u, v), std::max(u, v));
        return true;
      });
    }
    std::sort(want.begin(), want.end());
    want.erase(std::unique(want.begin(), want.end()), want.end());
    tree.query_pairs(listed, [&](std::uint32_t a, std::uint32_t b) {
      ASSERT_NE(a, b);
      got.emplace_back(std::min(a, b), std::max(a, b));
    });
    const std::size_t reported = got.size();
    std::sort(got.begin(), got.end());
    got.erase(std::unique(got.begin(), got.end()), got.end());
    EXPECT_EQ(got.size(), reported) << "round " << round << ": a pair reported twice";
    EXPECT_EQ(got, want) << "round " << round;
    if (round == 2) {
      EXPECT_GT(want.size(), 500u);  // (936 with this seed: every leaf listed)
    }
  }
}

// the slab test against closed forms
TEST(DynamicTree, SlabTestMatchesClosedForms) {
  const Aabb unit{{0, 0, 0}, {1, 1, 1}};
  auto enter = [&](const Vec3& o, const Vec3& d, double len) {
    const Ray r{o, d, len};
    return pba::ray_enter_box(r, 1.0 / d, unit);
  };
  EXPECT_EQ(enter({-2, 0.5, 0.5}, {1, 0, 0}, 5), 2.0);           // straight at a face
  EXPECT_EQ(enter({0.5, 0.5, 0.5}, {0, 1, 0}, 5), 0.0);          // from inside
  EXPECT_LT(enter({-2, 0.5, 0.5}, {1, 0, 0}, 1.5), 0.0);         // too short
  EXPECT_LT(enter({-2, 1.5, 0.5}, {1, 0, 0}, 5), 0.0);           // parallel, outside the y slab
  EXPECT_EQ(enter({-2, 1.0, 0.5}, {1, 0, 0}, 5), 2.0);           // grazing the top face counts
  // along the diagonal from (-1,-1,-1): enters at the corner, distance sqrt(3)
  const Vec3 diag = glm::normalize(Vec3(1, 1, 1));
  EXPECT_NEAR(enter({-1, -1, -1}, diag, 5), std::sqrt(3.0), 1e-15);  // one rounding of 1/sqrt(3)
}

// --- bad input ---------------------------------------------------------------------------

TEST(BroadPhase, BadInputIsNamed) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  BroadPhase bp;
  EXPECT_EQ(error_of([&] { bp.create_proxy({{0, nan, 0}, {1, 1, 1}}); }),
            "BroadPhase.create_proxy(box).lo: must be finite, got (0, nan, 0)");
  EXPECT_EQ(error_of([&] { bp.create_proxy({{0, 0, 0}, {1, 1, inf}}); }),
            "BroadPhase.create_proxy(box).hi: must be finite, got (1, 1, inf)");
  EXPECT_EQ(error_of([&] { bp.create_proxy({{0, 2, 0}, {1, 1, 1}}); }),
            "BroadPhase.create_proxy(box): inverted box, lo (0, 2, 0) > hi (1, 1, 1) on y");
  EXPECT_EQ(bp.size(), 0u);  // nothing was created by the failed calls
  const ProxyId id = bp.create_proxy({{0, 0, 0}, {1, 1, 1}});
  EXPECT_EQ(error_of([&] { bp.move_proxy(id, {{0, 0, 0}, {-1, 1, 1}}); }),
            "BroadPhase.move_proxy(box): inverted box, lo (0, 0, 0) > hi (-1, 1, 1) on x");
  EXPECT_EQ(bp.box(id).hi, Vec3(1, 1, 1));  // a rejected move leaves the box
  bp.destroy_proxy(id);
  EXPECT_EQ(error_of([&] { bp.move_proxy(id, {{0, 0, 0}, {1, 1, 1}}); }),
            "BroadPhase.move_proxy: stale handle (index 0, generation 1; the slot is now at generation 2 and free): "
            "destroyed since, or a handle of another World or system");
  EXPECT_NE(error_of([&] { bp.destroy_proxy(id); }).find("BroadPhase.destroy_proxy: stale handle"), std::string::npos);
  EXPECT_EQ(error_of([&] { bp.set_filter(ProxyId{}, {}); }), "BroadPhase.set_filter: null handle");
  EXPECT_EQ(error_of([&] { (void)bp.user_data(ProxyId{7, 1}); }),
            "BroadPhase.user_data: invalid handle (index 7 was never issued here: a handle of another World or system)");
  // a reused slot does not revive the old id
  const ProxyId reused = bp.create_proxy({{0, 0, 0}, {1, 1, 1}});
  EXPECT_EQ(reused.index, id.index);
  EXPECT_FALSE(bp.valid(id));
  EXPECT_NE(error_of([&] { (void)bp.box(id); }).find("stale handle"), std::string::npos);

  EXPECT_EQ(error_of([] { BroadPhase b({.grid_cell = -1}); }), "BroadPhaseDef.grid_cell: must be finite and > 0, got -1");
  EXPECT_EQ(error_of([] { BroadPhase b({.grid_max_cells_per_box = 0}); }),
            "BroadPhaseDef.grid_max_cells_per_box: must be an integer in [1, 1000000], got 0");
  EXPECT_EQ(error_of([&] { bp.set_grid_cell(nan); }), "BroadPhase.set_grid_cell(cell): must be finite and > 0, got nan");
  EXPECT_EQ(error_of([] { pba::broad_phase_method_from_string("octree", "--option method"); }),
            "--option method: unknown broad-phase method 'octree' (expected tree, grid, sap or brute-force)");
  EXPECT_EQ(pba::broad_phase_method_from_string("sap", "x"), BroadPhaseMethod::SweepAndPrune);
  EXPECT_EQ(error_of([] { DynamicTree t(-0.1); }), "DynamicTree.margin: must be finite and >= 0, got -0.1");
  DynamicTree t;
  const std::int32_t a = t.create_proxy({{0, 0, 0}, {1, 1, 1}}, 0);
  t.create_proxy({{0, 0, 0}, {1, 1, 1}}, 1);
  EXPECT_EQ(error_of([&] { t.destroy_proxy(t.root()); }),
            "DynamicTree.destroy_proxy: node " + std::to_string(t.root()) + " is not a live leaf");
  EXPECT_EQ(error_of([&] { t.set_leaf_box(t.root(), {{0, 0, 0}, {1, 1, 1}}); }),
            "DynamicTree.set_leaf_box: node " + std::to_string(t.root()) + " is not a live leaf");
  EXPECT_EQ(error_of([&] { t.set_leaf_box(a, {{0, nan, 0}, {1, 1, 1}}); }),
            "DynamicTree.set_leaf_box(box).lo: must be finite, got (0, nan, 0)");
  EXPECT_EQ(error_of([&] { t.set_leaf_box(a, {{0, 2, 0}, {1, 1, 1}}); }),
            "DynamicTree.set_leaf_box(box): inverted box, lo (0, 2, 0) > hi (1, 1, 1) on y");
  EXPECT_EQ(t.fat_box(a).hi, Vec3(1.1, 1.1, 1.1));  // a rejected box leaves the leaf's
  t.destroy_proxy(a);
  EXPECT_EQ(error_of([&] { t.destroy_proxy(a); }), "DynamicTree.destroy_proxy: node " + std::to_string(a) + " is not a live leaf");
  EXPECT_EQ(error_of([&] { t.set_leaf_box(a, {{0, 0, 0}, {1, 1, 1}}); }),
            "DynamicTree.set_leaf_box: node " + std::to_string(a) + " is not a live leaf");
  EXPECT_EQ(error_of([] { pba::MovingBoxes m({.count = 0}); }), "MovingBoxesDef.count: must be an integer in [1, 10000000], got 0");
}

}  // namespace
