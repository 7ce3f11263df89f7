// Rigid-body soaks (release build only: label soak): the full-size scenes.
#include <gtest/gtest.h>

#include "closed_box_check.h"
#include "pba/rigid_scenes.h"

namespace {

// 5000 boxes and spheres of 0.5 m at 250 m/s in a closed box of 20 m with 0.2 m walls:
// none escapes (its centre never crosses a wall's middle plane), under every solver.
TEST(RigidSoak, FiveThousandBodiesAt250MetresPerSecondStayInAClosedBox) { pba::test::expect_none_escapes(5000, 10); }

// The 1000 boxes dropped from a 10 x 10 x 10 grid (the benchmark's scene, soft step,
// default tolerances: 0.05 m/s and 2 degrees/s over time_to_sleep) are all asleep within 5 s,
// and asleep they cost nothing: no manifold is stepped. Measured 2026-12-02 at 9be9fb4: all
// asleep at 3.42 s (the 5.78 s of an earlier run was measured on other bits: bench_rigid's
// hash of the scene was dee777842ce1b22a then, f7469df798a7dc85 now). They land as columns of ten whose rocking on
// their edges loses Housner's share of its energy at each impact
// (RigidRocking.AColumnRockingOnItsEdgesLosesHousnersShareAtEveryImpactAndComesToRest).
TEST(RigidSoak, ThousandDroppedBoxesAreAllAsleepWithinFiveSeconds) {
  pba::RigidBodySystem s({.capacity = 1024});
  pba::rigid_scenes::falling_boxes(s, 10);
  int steps = 0;
  while (s.awake_count() > 0 && steps < 300) s.step(1.0 / 60, {0, -9.81, 0}), ++steps;
  EXPECT_EQ(s.awake_count(), 0u) << "after " << steps / 60.0 << " s";
  s.step(1.0 / 60, {0, -9.81, 0});
  EXPECT_EQ(s.manifold_count(), 0u);
}

}  // namespace
