// Rigid-body soaks (release build only: label soak): the full-size scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "closed_box_check.h"
#include "pba/rigid_scenes.h"
#include "pile_motion.h"
#include "rod_drops.h"

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
// built; docs/benchmarks.md). The same under every solver, since the lab switches them live:
// TGS's were all awake after 10 s (its columns knocked askew on landing and rocking: the
// landing's impulse was carried whole to the next substep;
// RigidSleep.ADroppedColumnOfTenFallsAsleepStandingUnderEverySolver), now asleep after 1.72 s (2.03 s with
// the carry capped at 1.5 times; soft step 1.73, sequential impulses 1.97, XPBD 1.83).
TEST(RigidSoak, ThousandDroppedBoxesAreAllAsleepWithinFiveSeconds) {
  for (const auto solver : pba::kRigidSolvers) {
    pba::RigidBodySystem s({.capacity = 1024, .contacts = {.solver = solver}});
    pba::rigid_scenes::falling_boxes(s, 10);
    int steps = 0;
    while (s.awake_count() > 0 && steps < 300) s.step(1.0 / 60, {0, -9.81, 0}), ++steps;
    EXPECT_EQ(s.awake_count(), 0u) << to_string(solver) << " after " << steps / 60.0 << " s";
    s.step(1.0 / 60, {0, -9.81, 0});
    EXPECT_EQ(s.manifold_count(), 0u) << to_string(solver);
  }
}

// The 20-level square pyramid of 2870 one-metre cubes (the benchmark's pyramid2870,
// soft step at the defaults, sleeping off) takes 4 substeps once it rests and 3 a second
// later: braced, each cube on four and under four, its load at half the substeps is about
// 1e-3 of the Greenhill bound's measure (the column model said 0.55 for its 20 levels;
// docs/rigid-bodies.md, "Braced piles"), and its sag predicted at 3 substeps (45 Hz) within
// 1% of a cube. It halves a second after its cubes last moved at the sleep tolerances (step
// 82; pile_motion.h's halving_step), takes 3 a second after its sag predicted at 3 fits half
// the budget at rest at 4 (step 155, below) and keeps 3 to the end of a minute (the floor,
// auto_substeps_least), standing: its top sags under 1 cm (the bound for the 20-stack)
// and under Bullet's on the same scene (16.0 mm at 500 steps, bench_rigid --scene pyramid2870
// --peer bullet --steps 500, 2026-12-04), drifts under 1 cm, and no cube moves 1 cm from where
// it was built or faster than the sleep tolerance at the end. (The top's drift, 3.6 mm at 500
// steps, is the 8 substeps' settling of the first steps: the same 3.6 mm with the halving off;
// Bullet's 3.0 mm in that run.)
TEST(RigidSoak, TheSquarePyramidOf2870CubesHalvesAndStandsAMinute) {
  pba::RigidBodySystem s({.capacity = 4096, .contacts = {.sleep = false}});
  const auto boxes = pba::rigid_scenes::square_pyramid(s, 20);
  std::vector<pba::Vec3> start;
  for (const auto b : boxes) start.push_back(s.center_of_mass(b));
  pba::test::Lowering lowering;
  for (int i = 0; i < 3600; ++i) {
    s.step(1.0 / 60, {0, -9.81, 0});
    lowering.record(i, s.profile().substeps, pba::test::any_unsettled(s, boxes));
    if (lowering.halved >= 0) {
      ASSERT_EQ(s.profile().substeps, lowering.third < 0 ? 4 : 3) << "at step " << i << ", halved at "
                                                                   << lowering.halved;
    }
    if (i % 600 == 599) {
      const pba::Vec3 top = s.center_of_mass(boxes.back());
      std::printf("%2d s: top sags %.2f mm, drifts %.2f mm; load at half the substeps %.3g\n", (i + 1) / 60,
                  1e3 * (start.back().y - top.y), 1e3 * std::hypot(top.x - start.back().x, top.z - start.back().z),
                  s.profile().half_load);
    }
  }
  const int first = lowering.halved, third = lowering.third;
  EXPECT_GE(first, 0);
  EXPECT_GE(third, 0);
  // a second after it came to rest (kCalmTime; its cubes settle under the sleep tolerances
  // by step 22 of the 8 substeps' start), to the step
  EXPECT_EQ(first, pba::test::halving_step(lowering.unsettled)) << "last unsettled at step " << lowering.unsettled;
  // and at 4 not before a second at rest
  // (next_rung_step), nor later than two measures (kMeasureEvery, 8 steps each) after it: the
  // sag predicted at 3 from the loads the contacts carry rings down as the pile sinks onto the
  // halved springs (10.9 and 10.5 mm at the first two measures after the halving, past half
  // the budget, 1 cm; 9.7 mm at the third, then 8.9-9.0 at rest), so the calm at 4 counts from
  // the first measure within it, unseen from outside (measured: step 155, the rule at rest 142)
  const int rule = pba::test::next_rung_step(first, lowering.unsettled_at_4);
  EXPECT_GE(third, rule) << "last unsettled at 4 at step " << lowering.unsettled_at_4;
  EXPECT_LE(third, rule + 2 * 8) << "last unsettled at 4 at step " << lowering.unsettled_at_4;
  const pba::Vec3 top = s.center_of_mass(boxes.back());
  const double sag = start.back().y - top.y, drift = std::hypot(top.x - start.back().x, top.z - start.back().z);
  EXPECT_LT(sag, 0.01);  // the bound, under Bullet's 16 mm (above)
  EXPECT_LT(drift, 0.01);
  const pba::test::PileMotion m = pba::test::pile_motion(s, boxes, start);
  EXPECT_LT(m.moved, 0.01);
  EXPECT_LT(m.fastest, s.settings().sleep_linear);
  std::printf("halved at step %d, 3 substeps from step %d; top: sag %.2f mm, drift %.2f mm; most moved %.2f mm\n",
              first, third, 1e3 * sag, 1e3 * drift, 1e3 * m.moved);
}

// Thin rods dropped tilted with restitution, the full sweep of test_rigid_contact.cpp's
// RigidRestitution.PerturbedRodDropsGainNoEnergyAndJumpNowhere: rods 1 mm to 2 cm thick, 2 and
// 4 m long, 10 to 60 degrees from upright, e = 0.5 and 1, each dropped from 20 heights 1e-7 m
// apart, every solver (rod_drops.h: the bounds), 40 s. Before the blocks' inverse inertias
// followed the bodies that turn (main at 4b1ad80), 246 of the 3840 drops broke a bound: the
// soft step's rods rose to 1.40 times their start (107 drops) and 25 jumped, up to 0.46 m
// beyond the bound in a step; TGS's rose to 1.24 (106), sequential impulses' to 1.08 (24).
// After: the soft step and TGS 1.000000 (none rises), sequential impulses 1.0022 (within
// the allowance of its one 60 Hz step), none jumps. Since a bounce off fixed bodies gives
// back no more than the step's start energy plus gravity's work along its path
// (RigidContacts::bound_bounce_work; the sliding friction along the slip had let 2 cm rods
// at e = 1 rise to 1.0049 and, with the smaller-mass friction tried first, 1.024): all
// three 1.000000. XPBD (which solves in double at each substep's poses) rose up to 2.5% above
// its start at e = 1 (9 of its 480 such drops beyond the allowance): for it at e = 1 this guards
// 1.05 times the start, the bound that holds, not a law. Since the rods' slop is a tenth of
// their half thickness (2026-12-04, src/rigid/contacts.h, pair_slop): sequential impulses
// 1.0119, XPBD 1.0448 (13 drops). Since a bounce under XPBD keeps no more than the substep's
// start plus gravity's work along its path (RigidContacts::bound_bounces_to_work): XPBD 1.0303
// (11 drops); with its static friction on a round surface held by the end velocity
// (xpbd_rigid.cpp, material_motion) 1.0161 (13 drops). What was left came from the continuous
// pass's put-backs, which kept the step's end velocity at the time of impact, and XPBD was
// held to 1.05 times its start at e = 1, a guard, not a law. Since a put-back takes the
// velocity at the time of impact (2026-12-04, continuous.cpp; it then never raises the
// energy, RigidContinuous.AFastElasticDropCaughtByTheContinuousPassGainsNoEnergy): every
// solver 1.000000 of its start (sequential impulses 1.0119 before), XPBD included, so all
// are held to the allowance (docs/rigid-bodies.md, "The elastic bound").
TEST(RigidSoak, PerturbedRodDropsGainNoEnergyAndJumpNowhere) {
  for (const auto solver : pba::kRigidSolvers) {
    double worst = 0, jump = -1e300;
    for (const double t : {0.001, 0.002, 0.006, 0.02})
    for (const double length : {2.0, 4.0})
    for (const double e : {0.5, 1.0})
    for (const double angle : {10.0, 30.0, 60.0})
    for (int k = 0; k < 20; ++k) {
      const auto r = pba::test::rod_drop(solver, t, length, e, angle, k * 1e-7);
      const std::string what = pba::test::rod_drop_case(solver, t, length, e, angle, k);
      EXPECT_LE(r.most, r.start + r.allowance) << what << ": " << r.most / r.start << " of the start";
      EXPECT_LE(r.excess, 0) << what << ": " << r.excess << " m beyond the bound in step " << r.excess_step;
      worst = std::max(worst, r.most / r.start), jump = std::max(jump, r.excess);
    }
    std::printf("%s: the largest energy %.6f of the start, the largest step beyond the bound %.3g m\n",
                std::string(to_string(solver)).c_str(), worst, jump);
  }
}

}  // namespace
