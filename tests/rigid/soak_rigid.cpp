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
// Disabled: not met. They land as columns of ten; the rocking on the edges loses Housner's
// share at each impact (RigidRocking.AColumnRockingOnItsEdgesLosesHousnersShareAtEveryImpact-
// AndComesToRest), but the sway on the soft contacts that follows is damped at a fifth of what
// the contacts' spring-damper model gives (RigidRocking.ATenStackSwaysAtItsSpringModels-
// FrequencyAndDecays: damping ratio 0.026 against 0.125 at the defaults), so when the last
// column stills depends on the bits: all asleep at 3.42 s on 9be9fb4, 5.42 s with the contact
// blocks in float, 9.35 s with the pair cache on as well (the defaults now; measured
// 2026-12-02 with bench_rigid --scene fall1000-sleep). Enable it when the soft step damps the
// sway as its model does (docs/rigid-bodies.md, known limits).
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
