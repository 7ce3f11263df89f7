// Zero heap allocations per frame in steady state: once the arrays have grown, moving every
// proxy and finding the pairs allocates nothing, with every method (the counter replaces
// the global operator new; see tests/support/alloc_count.h).
#include <gtest/gtest.h>

#include <vector>

#include "alloc_count.h"
#include "pba/collide/broad_phase.h"
#include "pba/collide/moving_boxes.h"

namespace {

using pba::BroadPhaseMethod;
using pba::test_support::g_allocations;

TEST(BroadPhaseAlloc, NoAllocationPerFrameInSteadyState) {
  for (BroadPhaseMethod m : {BroadPhaseMethod::Tree, BroadPhaseMethod::Grid, BroadPhaseMethod::SweepAndPrune,
                             BroadPhaseMethod::BruteForce}) {
    // 2000 boxes, a tenth of them fast (they leave their fat boxes every frame)
    pba::MovingBoxes scene({.count = 2000, .seed = 5});
    pba::BroadPhase bp({.method = m});
    std::vector<pba::ProxyId> ids;
    for (std::size_t i = 0; i < scene.size(); ++i) ids.push_back(bp.create_proxy(scene.box(i)));
    auto frame = [&] {
      scene.step(1.0 / 60);
      for (std::size_t i = 0; i < scene.size(); ++i) bp.move_proxy(ids[i], scene.box(i));
      return bp.update_pairs().size();
    };
    // warm up: the arrays grow to the scene's needs
    for (int f = 0; f < 120; ++f) frame();
    const long long before = g_allocations.load();
    std::size_t pairs = 0;
    for (int f = 0; f < 120; ++f) pairs += frame();
    EXPECT_EQ(g_allocations.load() - before, 0) << to_string(m);
    EXPECT_GT(pairs, 0u) << to_string(m);
    // ray casts and queries on the tree allocate nothing either
    if (m == BroadPhaseMethod::Tree) {
      const long long q0 = g_allocations.load();
      std::size_t hits = 0;
      for (std::size_t i = 0; i < 200; ++i) {
        bp.tree().ray_cast({scene.centers()[i], {0, 0, 1}, 5.0}, [&](std::uint32_t, const pba::Ray& r) {
          ++hits;
          return r.max_distance;
        });
        bp.query(scene.box(i), [&](pba::ProxyId) { return ++hits > 0; });
      }
      EXPECT_EQ(g_allocations.load() - q0, 0);
      EXPECT_GT(hits, 200u);
    }
  }
}

}  // namespace
