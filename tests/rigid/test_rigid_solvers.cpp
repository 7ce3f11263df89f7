// Rigid contact solvers: names and settings by name, stacks under each solver, switching
// solvers live, free motion shared by the substepping solvers, and XPBD's compliance against
// the static deflection of a spring.
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <string>
#include <vector>

#include "pba/rigid.h"
#include "pba/rigid_scenes.h"

#include "error_of.h"

using pba::RigidBodySystem;
using pba::RigidSolverType;
using pba::Vec3;
using pba::test_support::error_of;

namespace {

constexpr double kG = 9.81;
const Vec3 kGravity{0, -kG, 0};

// ---------------------------------------------------------------------------------------
// names and settings

TEST(RigidSolvers, NamesRoundTripAndUnknownNamesAreRefused) {
  for (const RigidSolverType t : pba::kRigidSolvers)
    EXPECT_EQ(pba::parse_rigid_solver(pba::to_string(t), "test"), t) << pba::to_string(t);
  EXPECT_EQ(pba::to_string(RigidSolverType::Tgs), "tgs");
  EXPECT_EQ(pba::to_string(RigidSolverType::Xpbd), "xpbd");
  const std::string m = error_of([] { pba::parse_rigid_solver("tgz", "--solver"); });
  EXPECT_EQ(m, "--solver: unknown rigid solver \"tgz\"; valid: soft-step, sequential-impulse, tgs, xpbd");
}

TEST(RigidSolvers, NewSettingsAreValidatedByName) {
  auto msg = [](pba::ContactSettings c) { return error_of([&] { RigidBodySystem s({.contacts = c}); }); };
  EXPECT_NE(msg({.substep_iterations = 0}).find("contacts.substep_iterations"), std::string::npos);
  EXPECT_NE(msg({.substep_iterations = 101}).find("contacts.substep_iterations"), std::string::npos);
  EXPECT_NE(msg({.relax_iterations = -1}).find("contacts.relax_iterations"), std::string::npos);
  EXPECT_EQ(msg({.relax_iterations = 0}), "");  // TGS without relax is allowed
  EXPECT_NE(msg({.contact_compliance = -1e-6}).find("contacts.contact_compliance: must be finite and >= 0"),
            std::string::npos) << msg({.contact_compliance = -1e-6});
  EXPECT_NE(msg({.contact_compliance = NAN}).find("contact_compliance"), std::string::npos);
  EXPECT_NE(msg({.solver = static_cast<RigidSolverType>(9)}).find("contacts.solver: unknown solver 9"),
            std::string::npos);
  // a mix rule outside the enum (a cast from a number) is refused by name, at construction
  // and between steps; it mixed as the first shape's coefficient before 2026-12-07
  EXPECT_NE(msg({.friction_mix = static_cast<pba::MixRule>(42)}).find("contacts.friction_mix: unknown mix rule 42"),
            std::string::npos);
  EXPECT_NE(msg({.restitution_mix = static_cast<pba::MixRule>(5)}).find("contacts.restitution_mix: unknown mix rule 5"),
            std::string::npos);
  EXPECT_EQ(msg({.friction_mix = pba::MixRule::Product, .restitution_mix = pba::MixRule::Product}), "");
  {
    RigidBodySystem m;
    m.settings().restitution_mix = static_cast<pba::MixRule>(200);
    EXPECT_NE(error_of([&] { m.step(1.0 / 60, kGravity); }).find("settings.restitution_mix: unknown mix rule 200"),
              std::string::npos);
  }
  // and between steps, by the settings' name
  RigidBodySystem s;
  s.settings().solver = RigidSolverType::Xpbd;
  s.settings().contact_compliance = INFINITY;
  EXPECT_NE(error_of([&] { s.step(1.0 / 60, kGravity); }).find("settings.contact_compliance"), std::string::npos);
}

// The largest values the settings take run without a non-finite state: the soft step's
// damping_ratio 1e308 (>= 0) and XPBD's contact_compliance 1e308 (>= 0). The soft step's
// spring coefficients overflowed (a1 = 2 zeta + h w = inf, mass scale inf * 0 = NaN) and
// XPBD's alpha / h^2 did (inf * 0 in the projection): a box resting on the ground became NaN
// in its first contact (at t = 0.33 s, dropped from 1 m). An infinitely damped spring holds
// like a rigid contact; an infinitely compliant contact corrects no overlap, and XPBD's
// velocity pass still stops the box (measured 1.2 cm deep).
TEST(RigidSolvers, TheLargestDampingRatioAndComplianceKeepTheStateFinite) {
  RigidBodySystem soft({.contacts = {.solver = RigidSolverType::SoftStep, .damping_ratio = 1e308}});
  RigidBodySystem xpbd({.contacts = {.solver = RigidSolverType::Xpbd, .contact_compliance = 1e308}});
  pba::rigid_scenes::ground(soft);
  pba::rigid_scenes::ground(xpbd);
  const pba::RigidBodyId a = pba::rigid_scenes::box(soft, {0, 1, 0}, Vec3(0.5));
  const pba::RigidBodyId b = pba::rigid_scenes::box(xpbd, {0, 1, 0}, Vec3(0.5));
  for (int i = 0; i < 60; ++i) {
    ASSERT_NO_THROW(soft.step(1.0 / 60, kGravity)) << "soft step, step " << i;
    ASSERT_NO_THROW(xpbd.step(1.0 / 60, kGravity)) << "XPBD, step " << i;
  }
  EXPECT_NEAR(soft.center_of_mass(a).y, 0.5, 0.01);  // resting on the ground
  EXPECT_TRUE(std::isfinite(xpbd.center_of_mass(b).y));
  EXPECT_NEAR(xpbd.center_of_mass(b).y, 0.5, 0.05);
}

// ---------------------------------------------------------------------------------------
// stacks

// the top box's sag and horizontal drift (m) after `steps` 60 Hz steps of an n-stack of
// one-metre cubes (mu 0.5, no sleep) under `solver` at its defaults
struct SagDrift {
  double sag, drift;
};
SagDrift stack_after(RigidSolverType solver, int n, int steps) {
  RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
  const auto boxes = pba::rigid_scenes::vertical_stack(s, n);
  const Vec3 top0 = s.center_of_mass(boxes.back());
  for (int i = 0; i < steps; ++i) s.step(1.0 / 60, kGravity);
  const Vec3 top = s.center_of_mass(boxes.back());
  return {top0.y - top.y, std::hypot(top.x - top0.x, top.z - top0.z)};
}

// A 10-stack stands for 10 s under each substepping solver at its defaults, within the
// issue's 1 cm of sag and drift. The soft step's sag is the static deflection
// n^2 g / (2 pi f)^2 = 1.7 mm; TGS and XPBD have rigid contacts and sag by what their
// iterations leave (measured 1.0 and 2.3 mm).
TEST(RigidSolvers, ATenStackStandsTenSecondsUnderEachSubsteppingSolver) {
  for (const auto solver : {RigidSolverType::SoftStep, RigidSolverType::Tgs, RigidSolverType::Xpbd}) {
    const SagDrift r = stack_after(solver, 10, 600);
    EXPECT_LT(r.drift, 0.01) << to_string(solver);
    EXPECT_LT(r.sag, 0.01) << to_string(solver);
    EXPECT_GT(r.sag, -0.001) << to_string(solver);  // not pushed up either
  }
}

// Macklin et al. (2019): many small steps beat many iterations. TGS's 8 substeps of one
// biased and one relax iteration, and XPBD's 8 substeps of one projection, hold 20 cubes
// for a minute within the 1 cm, where sequential impulses at the same 16 passes per
// step let them fall (docs/rigid-bodies.md; measured sag and drift: TGS 4.1 and 0.2 mm, XPBD
// 8.9 and 4.5 mm).
TEST(RigidSolvers, TgsAndXpbdHoldTwentyCubesForAMinute) {
  for (const auto solver : {RigidSolverType::Tgs, RigidSolverType::Xpbd}) {
    const SagDrift r = stack_after(solver, 20, 3600);
    EXPECT_LT(r.drift, 0.01) << to_string(solver);
    EXPECT_LT(r.sag, 0.01) << to_string(solver);
  }
}

// Ten cubes dropped 1.5 m apart onto each other (a column of the falling-boxes
// scene) land one on another and end standing as a 10-stack: the top box within 1 cm of 9.5 m.
// (Where the column ends sideways depends on rounding through ten impacts: 5-12 cm.) Not TGS:
// its column still rocks at 10 s (the top box at 0.5 m/s, tilted 0.01-0.03 rad, on both the
// branch that added the test and after the normal impulses' rounding changed), so its top is
// within 1 cm of 9.5 m or not by the phase of the rocking; see the known limits in
// docs/rigid-bodies.md.
TEST(RigidSolvers, AFallingColumnOfTenLandsAsAStack) {
  for (const auto solver : {RigidSolverType::SoftStep, RigidSolverType::Xpbd}) {
    RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
    pba::rigid_scenes::ground(s);
    std::vector<pba::RigidBodyId> boxes;
    for (int y = 0; y < 10; ++y) boxes.push_back(pba::rigid_scenes::box(s, {0, 2.0 + y * 1.5, 0}, Vec3(0.5)));
    for (int i = 0; i < 600; ++i) s.step(1.0 / 60, kGravity);
    EXPECT_NEAR(s.center_of_mass(boxes.back()).y, 9.5, 0.01) << to_string(solver);
  }
}

// ---------------------------------------------------------------------------------------
// switching live

// A 5-stack and a bouncing ball, the solver switched every 20 steps through all four for
// 10 s: the state stays finite, the stack stands, and no switch kicks it: the stack's bodies
// stay slower than one step of free fall gives (g dt = 0.16 m/s; measured 0.05). The
// carried impulses are rescaled to each solver's time step (per substep or per step).
TEST(RigidSolvers, SwitchingSolversLiveKeepsTheStateValid) {
  RigidBodySystem s({.contacts = {.sleep = false}});
  const auto boxes = pba::rigid_scenes::vertical_stack(s, 5);
  auto ball = s.create({.pose = {{3, 1, 0}},
                        .shapes = {{.shape = pba::ColliderShape::sphere(0.2), .material = {.restitution = 0.5}}}});
  const Vec3 top0 = s.center_of_mass(boxes.back());
  double fastest = 0;
  for (int i = 0; i < 600; ++i) {
    s.settings().solver = pba::kRigidSolvers[(i / 20) % 4];
    s.step(1.0 / 60, kGravity);
    for (const auto b : boxes) {
      ASSERT_TRUE(pba::is_finite(s.center_of_mass(b)) && pba::is_finite(s.linear_velocity(b))) << i;
      fastest = std::max(fastest, glm::length(s.linear_velocity(b)) + 0.5 * glm::length(s.angular_velocity(b)));
    }
  }
  EXPECT_LT(fastest, kG / 60);
  const Vec3 top = s.center_of_mass(boxes.back());
  EXPECT_LT(std::hypot(top.x - top0.x, top.z - top0.z), 0.01);
  EXPECT_LT(std::abs(top0.y - top.y), 0.01);
  // the ball came to rest on the ground, not in it
  EXPECT_NEAR(s.center_of_mass(ball).y, 0.2, 0.01);
}

// A column of `boxes` of half size `half` (m) resting on the ground, switched to XPBD and
// stepped 60 steps of 1/60 s (its top woken after the first when `wake_top`): its fastest body
// (m/s), how far the top rose at most (m), and how far the top had sunk at the switch from
// where the boxes touch (m; the overlaps under it added up)
struct AfterSwitch {
  double fastest = 0, rise = 0, sunk = 0;
};
AfterSwitch switch_column_to_xpbd(RigidBodySystem& s, const std::vector<pba::RigidBodyId>& boxes, double half,
                                  bool wake_top) {
  AfterSwitch out;
  const double y0 = s.center_of_mass(boxes.back()).y;
  out.sunk = (2.0 * static_cast<double>(boxes.size()) - 1) * half - y0;
  s.settings().solver = RigidSolverType::Xpbd;
  for (int i = 0; i < 60; ++i) {
    s.step(1.0 / 60, kGravity);
    if (wake_top && i == 0) s.wake(boxes.back());
    for (const auto b : boxes) out.fastest = std::max(out.fastest, glm::length(s.linear_velocity(b)));
    out.rise = std::max(out.rise, s.center_of_mass(boxes.back()).y - y0);
  }
  return out;
}

// Stacks of 5, 10, 15 and 20 boxes of 1 m and 0.1 m resting under each other solver,
// switched to XPBD: they stay resting. XPBD's contacts are rigid, and it rests at overlaps of
// its own (a contact carrying k boxes about k g h^2 deep: n (n + 1) / 2 g h^2 summed under the
// top of an n-stack, 2.3 mm at 10 and 8.9 mm at 20), not at the ones the others leave (the
// soft step's spring deflection, sequential impulses' slop, TGS's Baumgarte fixed point). The
// overlap beyond XPBD's own it pushed out a substep's correction at a time and made it a
// velocity (a 10-stack of 1 m boxes from sequential impulses at 0.46 m/s); pushed out to none
// at the switch, the taller stacks fell back into XPBD's own (0.22 m/s at 15, 0.30 m/s at 20).
// Bounds: every body slower than one step of free fall gives, g dt = 0.16 m/s (a fall into
// the whole of XPBD's own overlap at 20 gives 0.30 m/s), and the top rises by no more than
// the overlaps under it add up to, how far it had sunk from where the boxes touch (pushing
// them out lifts it by that; more is a hop).
// Measured now: at most 0.073 m/s (TGS, 0.1 m boxes, 20-stack), 0.059 m/s from sequential
// impulses. Sequential impulses at their default 10 iterations do not hold a stack of 0.1 m
// boxes 10 high (it moves at 1.9 m/s before any switch): those start from the soft step and
// TGS alone. Each stack must rest before the switch (slower than g dt / 10 over half a second).
// A column of 10 or 20 against a fixed wall 1 mm in: the wall was taken for a support under
// every box (the 0.46 m/s jump back, 0.52 m/s at 20 from sequential impulses, 0.165 m/s from
// TGS); measured now at most 0.058 m/s (sequential impulses, 10).
TEST(RigidSolvers, SwitchingToXpbdLeavesARestingStackResting) {
  // rest the column 3.5 s under its solver, switch, check
  auto rest_and_switch = [](RigidBodySystem& s, const std::vector<pba::RigidBodyId>& boxes, double half) {
    double before = 0;
    for (int i = 0; i < 210; ++i) {
      s.step(1.0 / 60, kGravity);
      if (i >= 180)
        for (const auto b : boxes) before = std::max(before, glm::length(s.linear_velocity(b)));
    }
    ASSERT_LT(before, kG / 600);
    const AfterSwitch after = switch_column_to_xpbd(s, boxes, half, false);
    EXPECT_LT(after.fastest, kG / 60);
    EXPECT_LE(after.rise, after.sunk);
  };
  for (const double half : {0.5, 0.05})
    for (const int n : {5, 10, 15, 20})
      for (const auto from : {RigidSolverType::SoftStep, RigidSolverType::SequentialImpulse, RigidSolverType::Tgs}) {
        if (from == RigidSolverType::SequentialImpulse && half < 0.5 && n >= 10) continue;  // (does not rest)
        SCOPED_TRACE(testing::Message() << to_string(from) << ", " << n << " boxes of half size " << half << " m");
        RigidBodySystem s({.contacts = {.solver = from, .sleep = false}});
        rest_and_switch(s, pba::rigid_scenes::vertical_stack(s, n, half), half);
      }
  // the same beside a fixed wall 1 mm into the column's side: it touches every box and holds
  // none up (its normal is level), so the weight still goes down the column
  for (const int n : {10, 20})
    for (const auto from : {RigidSolverType::SoftStep, RigidSolverType::SequentialImpulse, RigidSolverType::Tgs}) {
      SCOPED_TRACE(testing::Message() << to_string(from) << ", " << n << " boxes of 1 m against a wall");
      RigidBodySystem s({.contacts = {.solver = from, .sleep = false}});
      const auto boxes = pba::rigid_scenes::vertical_stack(s, n);
      s.create({.name = "wall", .type = pba::BodyType::Static,
                .shapes = {{.shape = pba::ColliderShape::plane({-1, 0, 0}, -0.499)}}});
      rest_and_switch(s, boxes, 0.5);
    }
}

// The same for a stack asleep at the switch (sleep on, the default): asleep, its pairs reach
// no solver, so the switch step did not bring its overlap to XPBD's own, and woken a step
// later (here by a touch on its top) XPBD pushed out what sequential impulses had left as a
// velocity (a 10-stack of 1 m boxes jumped to 0.45 m/s, its top up 19 mm where it had sunk
// 11 mm). The switch wakes it (measured 0.059 m/s). Bounds as above.
TEST(RigidSolvers, SwitchingToXpbdLeavesASleepingStackResting) {
  RigidBodySystem s({.contacts = {.solver = RigidSolverType::SequentialImpulse}});
  const auto boxes = pba::rigid_scenes::vertical_stack(s, 10);
  for (int i = 0; i < 600; ++i) s.step(1.0 / 60, kGravity);
  ASSERT_EQ(s.awake_count(), 0u);
  const AfterSwitch after = switch_column_to_xpbd(s, boxes, 0.5, true);
  ASSERT_GT(after.sunk, 0.0);
  EXPECT_LT(after.fastest, kG / 60);
  EXPECT_LE(after.rise, after.sunk);
}

// Bodies that start overlapping are pushed apart no faster than push_out_speed under every
// solver: two unit boxes side by side on the ground, 0.8 m into each other, and a 0.3 m ball
// on the ground with its centre inside a third. XPBD projected the whole overlap in one
// substep and made it a velocity (0.8 m in 2 ms): the boxes flew 90 m apart. Bounds: every
// body slower than push_out_speed across the ground (the push is horizontal) throughout, 1%
// over it for sequential impulses, which have no relax pass and keep the capped push-out as
// velocity (measured 3.0005 m/s: the cap is on each point's normal speed, and the points of a
// manifold turn the box a little); and at the end no overlap deeper than the linear slop, to
// the contact kernels' float resolution there: TGS's Baumgarte bias, baumgarte / h *
// min(0, sep + slop), has its fixed point at an overlap of exactly the slop and approaches it
// from deeper (the excess times 1 - baumgarte a substep: nothing of 0.8 m is left after the
// 960 substeps), and the kernels measure the separation in float, each of its few terms (the
// overlap at the step's start, about the slop, and the step's motion, about zero at rest)
// rounded by at most 2^-24 of it; so the overlap ends within a few of float's steps of the
// slop (2^-24 slop = 3e-10 m), on either side: slop (1 + 4 FLT_EPSILON) bounds it (measured:
// 1.0e-11 m over the slop, the two boxes under TGS).
TEST(RigidSolvers, OverlappingBodiesArePushedApartNoFasterThanThePushOutSpeed) {
  for (const auto solver : pba::kRigidSolvers) {
    RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
    pba::rigid_scenes::ground(s);
    std::vector<pba::RigidBodyId> bodies{pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5)),
                                         pba::rigid_scenes::box(s, {0.2, 0.5, 0}, Vec3(0.5)),
                                         pba::rigid_scenes::box(s, {4, 0.5, 0}, Vec3(0.5))};
    bodies.push_back(s.create({.pose = {{4.2, 0.3, 0}}, .shapes = {{.shape = pba::ColliderShape::sphere(0.3)}}}));
    double fastest = 0;
    for (int i = 0; i < 240; ++i) {
      s.step(1.0 / 60, kGravity);
      for (const auto b : bodies) fastest = std::max(fastest, std::hypot(s.linear_velocity(b).x, s.linear_velocity(b).z));
    }
    const double kept = solver == RigidSolverType::SequentialImpulse ? 1.01 : 1.0;
    EXPECT_LT(fastest, kept * s.settings().push_out_speed) << to_string(solver);
    const double slop = s.settings().linear_slop;
    for (const auto& c : s.contacts()) EXPECT_LE(c.depth, slop * (1 + 4 * FLT_EPSILON)) << to_string(solver);
  }
}

// A pair asleep while the solver changes wakes with its carried impulses in the new solver's
// units: two boxes stacked fall asleep under sequential impulses (impulses per 60 Hz step),
// the solver becomes the soft step (per substep, 8 a step) and the top box is woken: it stays
// put (rises under 0.1 mm, where impulses eight times too large lifted it 1.1 mm at 1.3 mm/s).
TEST(RigidSolvers, ASleepingPairWakesUnderANewSolverWithoutAKick) {
  RigidBodySystem s({.contacts = {.solver = RigidSolverType::SequentialImpulse}});
  pba::rigid_scenes::ground(s);
  const auto bottom = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
  const auto top = pba::rigid_scenes::box(s, {0, 1.5, 0}, Vec3(0.5));
  int steps = 0;
  while (s.awake(top) && steps < 600) s.step(1.0 / 60, kGravity), ++steps;
  ASSERT_FALSE(s.awake(top));
  ASSERT_FALSE(s.awake(bottom));
  s.settings().solver = RigidSolverType::SoftStep;
  s.step(1.0 / 60, kGravity);  // asleep: the pairs are not stepped, their impulses stay cached
  s.set_velocity(top, Vec3(0), Vec3(0));
  ASSERT_TRUE(s.awake(top));
  const double y0 = s.center_of_mass(top).y;
  double highest = y0;
  for (int i = 0; i < 30; ++i) {
    s.step(1.0 / 60, kGravity);
    highest = std::max(highest, s.center_of_mass(top).y);
  }
  EXPECT_LT(highest - y0, 1e-4);
}

// ---------------------------------------------------------------------------------------
// free motion and compliance

// Without contacts the soft step, TGS and XPBD run the same substeps of free motion, bit for
// bit (XPBD adds only the contacts' corrections to the velocities). The same substeps: the
// soft step's taken exactly (auto_substeps off; on, it halves them a second in, nothing
// touching, and its free motion is then the scheme's at h = 1/240 s, not the others').
TEST(RigidSolvers, FreeMotionIsTheSameBitsUnderTheSubsteppingSolvers) {
  auto run = [](RigidSolverType solver) {
    RigidBodySystem s({.contacts = {.solver = solver, .auto_substeps = false}});
    pba::RigidMass m = pba::RigidMass::box(2, {0.5, 0.1, 0.2});
    s.create({.pose = {{0, 5, 0}}, .linear_velocity = {1, 2, 3}, .angular_velocity = {0.3, 8, 0.1},
              .shapes = {{.shape = pba::ColliderShape::sphere(0.05)}}, .mass = m, .linear_damping = 0.1});
    s.create({.pose = {{10, 5, 0}}, .angular_velocity = {4, 0, 1}, .shapes = {{.shape = pba::ColliderShape::box({0.2, 0.3, 0.4})}}});
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
    return s.hash();
  };
  const std::uint64_t soft = run(RigidSolverType::SoftStep);
  EXPECT_EQ(run(RigidSolverType::Tgs), soft);
  EXPECT_EQ(run(RigidSolverType::Xpbd), soft);
}

// XPBD with contact compliance alpha: a contact is a spring of stiffness 1 / alpha, so a box
// of mass m on its four corner points sinks m g alpha / 4 (one XPBD iteration per substep
// reaches it: the multiplier update -alpha~ lambda makes the fixed point the compliant one).
TEST(RigidSolvers, XpbdComplianceGivesTheStaticDeflection) {
  for (const double alpha : {1e-7, 1e-6}) {
    RigidBodySystem s({.contacts = {.solver = RigidSolverType::Xpbd, .contact_compliance = alpha, .sleep = false}});
    pba::rigid_scenes::ground(s);
    auto box = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
    for (int i = 0; i < 300; ++i) s.step(1.0 / 60, kGravity);
    const double expected = s.mass(box) * kG * alpha / 4;
    EXPECT_NEAR(0.5 - s.center_of_mass(box).y, expected, 0.01 * expected) << alpha;
  }
}

}  // namespace

// Found by a fuzzer (thin boxes, kicks up to 300 m/s): a thin box (0.094 x 1 x 0.049 m) at
// 120 m/s, tumbling, strikes a box turning at 36 rad/s over the ground. XPBD took its contacts'
// inverse inertias at the step's start for all eight substeps while the thin box turned up
// to 100 rad a substep: each correction's turn, made a velocity by step 3, came out along a
// light axis, the spin grew some fiftyfold a substep, and within the one 60 Hz step of the
// strike the box went past kMaxRigidSpeed (2e8 rad/s, the energy 1e11 times the start's).
// XPBD now takes them again after each substep's free motion, as the other solvers do
// (refresh_inertia). The bound: the free rotation's splitting keeps the body's angular
// momentum and can carry it onto the lightest axis, raising the energy by up to the ratio
// of the principal moments (89 here; what the contacts give stays below it): measured
// 2026-12-07 over one second, the peak of the two bodies' energy (kinetic + potential) over
// the start's is 1.26 soft step, 12.4 sequential impulses, 7.6 TGS, 28.1 XPBD (1e11 before).
// (All four gain energy here: docs/rigid-bodies.md, known limits, "A thin box tumbling
// fast".)
TEST(RigidSolvers, AThinBoxTumblingIntoABoxDoesNotSpinUp) {
  using pba::ColliderShape, pba::Quat, pba::BodyType;
  const Vec3 thin_half(0.04712874248449532, 0.499589813851471, 0.024672910325769223);
  const double ix = thin_half.y * thin_half.y + thin_half.z * thin_half.z,
               iy = thin_half.x * thin_half.x + thin_half.z * thin_half.z,
               iz = thin_half.x * thin_half.x + thin_half.y * thin_half.y;
  const double ratio = std::max({ix, iy, iz}) / std::min({ix, iy, iz});
  for (const RigidSolverType solver : pba::kRigidSolvers) {
    RigidBodySystem s({.contacts = {.solver = solver}});
    s.create({.name = "ground", .type = BodyType::Static, .pose = {Vec3(0, -0.1, 0)},
              .shapes = {{.shape = ColliderShape::box(Vec3(5, 0.1, 5))}}});
    const auto block = s.create(
        {.name = "block",
         .pose = {Vec3(1.7419917656729078, 2.9270091462694623, -1.666496389934693),
                  glm::normalize(Quat(0.75433677525803666, -0.32889622813566566, 0.5641498013223849, -0.067366922739219973))},
         .linear_velocity = Vec3(0.78871401437822541, 1.958590691696571, 0.25002602458784057),
         .angular_velocity = Vec3(-16.766814990892943, -25.047748601614423, -19.027825065305819),
         .shapes = {{.shape = ColliderShape::box(Vec3(0.2947467223790049, 0.28901950095098339, 0.61597171669087869))}}});
    const auto thin = s.create(
        {.name = "thin",
         .pose = {Vec3(3.0996820770492741, 3.2679935438326364, -0.88371982898755963),
                  glm::normalize(Quat(0.44588928813609052, -0.65686541699764311, -0.49530441121974328, -0.35268131068184838))},
         .linear_velocity = Vec3(-50.838257656267544, -78.953406410256392, -73.372458421229595),
         .angular_velocity = Vec3(10.060491230182294, -9.3780912949505897, 26.831266912945132),
         .shapes = {{.shape = ColliderShape::box(thin_half)}}});
    const Vec3 g(0, -9.81, 0);
    auto energy = [&] {
      double e = 0;
      for (const auto id : {block, thin}) e += s.kinetic_energy(id) - s.mass(id) * glm::dot(g, s.center_of_mass(id));
      return e;
    };
    const double start = energy();
    double most = 0;
    for (int i = 0; i < 60; ++i) {
      ASSERT_NO_THROW(s.step(1.0 / 60, g)) << pba::to_string(solver) << " step " << i;
      most = std::max(most, energy() / start);
    }
    EXPECT_LT(most, ratio) << pba::to_string(solver);
  }
}
