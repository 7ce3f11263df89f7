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
// and asleep they cost nothing: no manifold is stepped.
// Disabled: under the present solver the last of them fall asleep at 5.78 s (measured
// 2026-12-02; 5.30 s with the pair cache on). They land as columns of ten that rock about
// their bases: the top box of the
// last columns sways at 1.4 Hz, 3.3 cm peak to peak at 2.6 s decaying to 2.5 cm at 4.7 s,
// more than the rest window allows (sleep_linear * time_to_sleep = 2.5 cm from where the
// window began), and warm-started friction keeps such rocking going (a built 5-stack kicked
// at 0.02 rad/s rocks without end; without friction warm starting it stops at once, but boxes
// then creep on slopes): see docs/rigid-bodies.md, islands and sleeping. Enable it when the
// solver damps the rocking.
TEST(RigidSoak, DISABLED_ThousandDroppedBoxesAreAllAsleepWithinFiveSeconds) {
  pba::RigidBodySystem s({.capacity = 1024});
  pba::rigid_scenes::falling_boxes(s, 10);
  int steps = 0;
  while (s.awake_count() > 0 && steps < 300) s.step(1.0 / 60, {0, -9.81, 0}), ++steps;
  EXPECT_EQ(s.awake_count(), 0u) << "after " << steps / 60.0 << " s";
  s.step(1.0 / 60, {0, -9.81, 0});
  EXPECT_EQ(s.manifold_count(), 0u);
}

}  // namespace
