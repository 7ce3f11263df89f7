// Rigid-body soaks (release build only: label soak): the full-size scenes.
#include <gtest/gtest.h>

#include "closed_box_check.h"
#include "pba/rigid_scenes.h"

namespace {

// 5000 boxes and spheres of 0.5 m at 250 m/s in a closed box of 20 m with 0.2 m walls:
// none escapes (its centre never crosses a wall's middle plane), under every solver.
TEST(RigidSoak, FiveThousandBodiesAt250MetresPerSecondStayInAClosedBox) { pba::test::expect_none_escapes(5000, 10); }

// ... and at 200 m/s, where under XPBD a 0.5 m box reached a wall at 39 m/s turning at
// 309 rad/s, touching it at the start of the step, and went through it (57 escapes): the
// continuous pass now keeps each fast body's core (a ball of half its smallest extent about
// its centre of mass) from reaching a static shape, also when the body starts touching it.
TEST(RigidSoak, FiveThousandBodiesAt200MetresPerSecondStayInAClosedBox) {
  pba::test::expect_none_escapes(5000, 10, 200.0);
}

// The 1000 boxes dropped from a 10 x 10 x 10 grid (the benchmark's scene, soft step,
// default tolerances: 0.05 m/s and 2 degrees/s over time_to_sleep) are all asleep within 5 s,
// and asleep they cost nothing: no manifold is stepped. They land as columns of ten; what
// keeps the last awake is the sway on the soft contacts, damped mostly where the column
// meets the ground (RigidRocking.ATenStackSwaysAtItsSpringModelsFrequencyAndDecays). With
// that contact at the quarter-substep-rate cap (before 2026-12-02) the sway was damped at a
// fifth of its model's and the time depended on the bits: 3.4-10.2 s, a micrometre's shift of
// the boxes moving it by seconds, with the pair cache on or off. With contacts against bodies
// that cannot move held to one radian a substep: 3.9-4.3 s over 12 such shifts (4.0 s as
// built; docs/benchmarks.md).
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
