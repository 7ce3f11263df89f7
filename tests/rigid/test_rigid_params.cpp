// Rigid bodies at other parameters than the and under every solver: the laws the
// issue's tests hold at its numbers (restitution, Coulomb friction, rolling, tunnelling,
// sleep), at other step rates, substeps, coefficients, sizes and settings, each against its
// closed form with a tolerance from the scheme's error; and mixed scenes a new user would try.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "pba/rigid.h"
#include "pba/rigid_scenes.h"

// inside pba, so the library's names need no using-declarations
namespace pba {
namespace {

constexpr double kG = 9.81;
const Vec3 kGravity{0, -kG, 0};

double deg(double d) { return d * kPi / 180; }

// step rates other than the 60 Hz at 8 substeps: 30, 120 and 240 Hz at the default
// substeps (auto_substeps on), and 60 Hz at 2 and 16 substeps taken exactly
struct Rate {
  double dt;
  int substeps;  // 0: the defaults
};
constexpr Rate kRates[] = {{1.0 / 30, 0}, {1.0 / 120, 0}, {1.0 / 240, 0}, {1.0 / 60, 2}, {1.0 / 60, 16}};

std::string describe(RigidSolverType solver, const Rate& r) {
  return std::string(to_string(solver)) + " at 1/" + std::to_string(std::lround(1 / r.dt)) + " s" +
         (r.substeps ? ", " + std::to_string(r.substeps) + " substeps" : "");
}
RigidBodySystem system_at(RigidSolverType solver, const Rate& r) {
  RigidBodySystem s({.contacts = {.solver = solver}});
  if (r.substeps) s.set_substeps(r.substeps);
  return s;
}
// the time step of the solver's symplectic Euler in the last step: the substep it took, or
// the whole step under sequential impulses
double last_h(const RigidBodySystem& s, double dt) {
  return s.settings().solver == RigidSolverType::SequentialImpulse ? dt : dt / s.profile().substeps;
}
// a static plane through the origin tilted by `angle` about z, with a material
void ground(RigidBodySystem& s, double mu, double e = 0, double angle = 0) {
  s.create({.name = "ground", .type = BodyType::Static,
            .shapes = {{.shape = ColliderShape::plane({-std::sin(angle), std::cos(angle), 0}, 0),
                        .material = {.restitution = e, .friction = mu}}}});
}

}  // namespace

// ---------------------------------------------------------------------------------------
// restitution and elastic collisions

// A ball dropped from h onto a ground of the same e rebounds to e^2 h. The apex is read from
// the state at the end of the bounce step, y + vy^2 / (2 g), in closed form: the rise adds no
// error. The bound is symplectic Euler's at the step h_s of the solver (the substep;
// sequential impulses: the step): the fall reaches the ground with its speed off by at most
// g h_s / 2 of the closed form's v = sqrt(2 g h), so the rebound's by e g h_s / 2 and the apex
// (e v)^2 / (2 g) by e^2 v h_s / 2 to first order; the second order, e^2 g h_s^2 / 8, is
// g h_s / (4 v) of that, at most 2.6% here (0.5 m at 1/30 s). So |apex - e^2 h| <=
// 1.05 e^2 v h_s / 2. Measured: within 0.996 of e^2 v h_s / 2, every solver and rate.
TEST(RigidParamsRestitution, TheApexIsESquaredOfTheDropAtOtherRatesUnderEverySolver) {
  const double r = 0.2;
  for (const Rate& rate : kRates)
  for (const auto solver : kRigidSolvers)
  for (const double e : {0.3, 1.0})
  for (const double h : {0.5, 3.0}) {
    RigidBodySystem s = system_at(solver, rate);
    ground(s, 0, e);
    const auto ball = s.create({.pose = {{0, h + r, 0}}, .shapes = {{.shape = ColliderShape::sphere(r), .material = {.restitution = e}}}});
    double apex = -1, hs = 0;
    for (int i = 0; i < static_cast<int>(2 / rate.dt) && apex < 0; ++i) {
      s.step(rate.dt, kGravity);
      hs = last_h(s, rate.dt);
      const double y = s.center_of_mass(ball).y - r, vy = s.linear_velocity(ball).y;
      if (vy > 0) apex = y + vy * vy / (2 * kG);
    }
    const double v = std::sqrt(2 * kG * h);
    EXPECT_NEAR(apex, e * e * h, 1.05 * e * e * v * hs / 2) << describe(solver, rate) << " e = " << e << " h = " << h;
  }
}

// Head on, masses m_a and m_b (ratios 3 and 100), e = 1 and 0.5: each leaves at
// v_c - e (v - v_c) (v_c the centre of mass's velocity), and the momentum is kept. Balls meet
// at one point through both centres, so no step rate enters (one rate, 1/60 s; measured
// 9.4e-8 m/s and 7.5e-8 at every rate, every solver). What is left is the rounding of the
// contact's float rows, 2^-24 = 6e-8 of the 2 m/s they carry per operation: 1e-6 m/s and
// 1e-6 of the momentum allow a few such roundings and nothing of the scheme.
TEST(RigidParamsRestitution, UnequalMassesLeaveAHeadOnCollisionAtNewtonsVelocities) {
  const Rate rate{1.0 / 60, 0};
  for (const auto solver : kRigidSolvers)
  for (const double ratio : {3.0, 100.0})
  for (const double e : {1.0, 0.5}) {
    RigidBodySystem s = system_at(solver, rate);
    auto ball = [&](double x, double v, double density) {
      return s.create({.pose = {{x, 0, 0}}, .linear_velocity = {v, 0, 0},
                       .shapes = {{.shape = ColliderShape::sphere(0.25), .density = density, .material = {.restitution = e}}}});
    };
    const auto a = ball(-1, 2, 1000 * ratio), b = ball(1, -1, 1000);
    const double ma = s.mass(a), mb = s.mass(b), vc = (ma * 2 + mb * -1) / (ma + mb);
    const Vec3 p0 = ma * s.linear_velocity(a) + mb * s.linear_velocity(b);
    for (int i = 0; i < static_cast<int>(1.5 / rate.dt); ++i) s.step(rate.dt, Vec3(0));
    const std::string what = describe(solver, rate) + " ratio " + std::to_string(ratio) + " e " + std::to_string(e);
    EXPECT_NEAR(s.linear_velocity(a).x, vc - e * (2 - vc), 1e-6) << what;
    EXPECT_NEAR(s.linear_velocity(b).x, vc - e * (-1 - vc), 1e-6) << what;
    const Vec3 p1 = ma * s.linear_velocity(a) + mb * s.linear_velocity(b);
    EXPECT_LT(glm::length(p1 - p0) / glm::length(p0), 1e-6) << what;
  }
}

// ---------------------------------------------------------------------------------------
// friction

// A flat box (0.5 x 0.1 x 0.5 m: it tips only past 79 degrees) on an incline of mu 0.2 and
// 0.9, 4 degrees under the friction angle (stays: under 1 mm in 5 s, the issue's) and 10 over
// it (slides at g (sin - mu cos): the 2%, a chosen bound, not derived), every rate,
// every solver. Symplectic Euler's velocity is exact under a constant force; what is left is
// the contact's settling (measured: within 2.7e-3 at every rate). Sleep is off in the staying
// case, so a creep under the tolerances (2 mm/s) cannot sleep away and pass. XPBD only at substeps of 1/480 s or shorter (found and left,
// docs/rigid-bodies.md, known limits, "XPBD, a sliding box's fresh manifold"): at 1/240 s
// (1/30 s, 8 substeps) the box sank 0.62 mm in the step its plane manifold was made afresh,
// and pushing it out cost mu times that impulse: 5.5% of the acceleration at mu 0.9, 52 deg.
TEST(RigidParamsFriction, ABoxOnAnInclineStaysOrSlidesAtCoulombsRateAtOtherRates) {
  for (const Rate& rate : kRates)
  for (const auto solver : kRigidSolvers)
  for (const double mu : {0.2, 0.9})
  for (const double offset : {-4.0, 10.0}) {
    const double theta = std::atan(mu) + deg(offset);
    RigidBodySystem s = system_at(solver, rate);
    if (solver == RigidSolverType::Xpbd && rate.dt / s.settings().substeps > 1.0 / 480 + 1e-12) continue;
    ground(s, mu, 0, theta);
    const Vec3 n{-std::sin(theta), std::cos(theta), 0}, down{-std::cos(theta), -std::sin(theta), 0};
    const Vec3 half{0.25, 0.05, 0.25};
    const auto box = s.create({.pose = {half.y * n, glm::angleAxis(theta, Vec3(0, 0, 1))},
                               .shapes = {{.shape = ColliderShape::box(half), .material = {.friction = mu}}}});
    const std::string what = describe(solver, rate) + " mu " + std::to_string(mu) + " at " + std::to_string(theta * 180 / kPi);
    const double x0 = glm::dot(s.center_of_mass(box), down);
    if (offset < 0) {
      s.settings().sleep = false;
      for (int i = 0; i < static_cast<int>(5 / rate.dt); ++i) s.step(rate.dt, kGravity);
      EXPECT_LT(std::abs(glm::dot(s.center_of_mass(box), down) - x0), 1e-3) << what;
      continue;
    }
    for (int i = 0; i < static_cast<int>(0.5 / rate.dt); ++i) s.step(rate.dt, kGravity);
    const double v1 = glm::dot(s.linear_velocity(box), down);
    for (int i = 0; i < static_cast<int>(1 / rate.dt); ++i) s.step(rate.dt, kGravity);
    const double a = glm::dot(s.linear_velocity(box), down) - v1, expected = kG * (std::sin(theta) - mu * std::cos(theta));
    EXPECT_NEAR(a, expected, 0.02 * expected) << what;
  }
}

// The same flat box sent at v over level ground stops at v^2 / (2 mu g) less what symplectic
// Euler's steps leave: each changes the velocity before moving by it, so the box stops short
// by the sum of h_s dv / 2 over the steps (h_s the step the solver took, dv the speed lost in
// it; RigidFriction.TheStopDistanceOverTheInputRangeIsTheClosedFormLessHalfASubstepsTravel at
// 60 Hz); it goes straight. mu 0.2 and 0.9, 1 and 6 m/s, every rate and solver, in one
// direction off the axes (RigidFriction.SlidingStopDistanceIsTheSameInTwelveDirections covers
// the directions). Measured short by up to 1.00018 times that sum: the 1.001 covers it.
TEST(RigidParamsFriction, TheStopDistanceIsTheClosedFormLessHalfAStepsTravelAtOtherRates) {
  for (const Rate& rate : kRates)
  for (const auto solver : kRigidSolvers)
  for (const double mu : {0.2, 0.9})
  for (const double v : {1.0, 6.0}) {
    const double a = 2.5;
    RigidBodySystem s = system_at(solver, rate);
    ground(s, mu);
    const Vec3 dir{std::cos(a), 0, std::sin(a)};
    const auto box = s.create({.pose = {{0, 0.05, 0}}, .linear_velocity = v * dir,
                               .shapes = {{.shape = ColliderShape::box({0.25, 0.05, 0.25}), .material = {.friction = mu}}}});
    double short_by = 0;
    for (int i = 0; i < static_cast<int>((v / (mu * kG) + 0.5) / rate.dt); ++i) {
      const double before = glm::length(s.linear_velocity(box));
      s.step(rate.dt, kGravity);
      short_by += last_h(s, rate.dt) * std::max(0.0, before - glm::length(s.linear_velocity(box))) / 2;
    }
    const Vec3 p = s.center_of_mass(box);
    const double d = glm::length(Vec3(p.x, 0, p.z)), expected = v * v / (2 * mu * kG);
    const std::string what = describe(solver, rate) + " mu " + std::to_string(mu) + " v " + std::to_string(v) + " at " + std::to_string(a);
    EXPECT_LE(d, expected) << what;
    EXPECT_GE(d, expected - 1.001 * short_by) << what;
    EXPECT_LT(glm::length(glm::cross(Vec3(p.x, 0, p.z), dir)), 0.01) << what;  // straight, as the test
    EXPECT_LT(glm::length(s.linear_velocity(box)), 1e-3) << what;
  }
}

// A solid ball and a capsule lying across the slope roll without slipping (mu 1, twice what
// rolling needs on 35 degrees) at g sin(theta) / (1 + I / (m r^2)), I the moment about the
// rolling axis (5/7 g sin theta for the ball; the capsule's from its inertia), 10 and 35
// degrees, every rate and solver. Measured from the velocity between 0.5 s and 1.5 s;
// symplectic Euler's velocity is exact at a constant acceleration, and the soft contact's
// sag g cos(theta) / w^2 moves the contact point (measured under 7.5e-4 everywhere): 1e-2, a
// chosen bound, not derived.
TEST(RigidParamsFriction, ABallAndACapsuleRollAtTheirClosedFormAtOtherRates) {
  const double r = 0.3;
  for (const Rate& rate : kRates)
  for (const auto solver : kRigidSolvers)
  for (const double degrees : {10.0, 35.0})
  for (const bool capsule : {false, true}) {
    const double theta = deg(degrees);
    RigidBodySystem s = system_at(solver, rate);
    ground(s, 1.0, 0, theta);
    const Vec3 n{-std::sin(theta), std::cos(theta), 0}, down{-std::cos(theta), -std::sin(theta), 0};
    const auto body = s.create({.pose = {r * n, capsule ? glm::angleAxis(deg(90), Vec3(1, 0, 0)) : Quat(1, 0, 0, 0)},
                                .shapes = {{.shape = capsule ? ColliderShape::capsule(0.4, r) : ColliderShape::sphere(r),
                                            .material = {.friction = 1.0}}}});
    const double expected = kG * std::sin(theta) / (1 + s.world_inertia(body)[2][2] / (s.mass(body) * r * r));
    for (int i = 0; i < static_cast<int>(0.5 / rate.dt); ++i) s.step(rate.dt, kGravity);
    const double v1 = glm::dot(s.linear_velocity(body), down);
    for (int i = 0; i < static_cast<int>(1 / rate.dt); ++i) s.step(rate.dt, kGravity);
    const double a = glm::dot(s.linear_velocity(body), down) - v1;
    EXPECT_NEAR(a, expected, 1e-2 * expected) << describe(solver, rate) << (capsule ? " capsule " : " ball ") << degrees;
  }
}

// A box of width w and height 1 m on a mu = 1.5 slope tips once tan(theta) > w (2 degrees
// either side, w = 0.5 and 0.3), at every rate, under every solver (XPBD since 2026-12-07,
// when the moment its face friction's pressure cannot carry began to turn the box).
TEST(RigidParamsFriction, ABoxTipsPastItsAspectRatioAtOtherRates) {
  for (const Rate& rate : kRates)
  for (const auto solver : kRigidSolvers)
  for (const double w : {0.5, 0.3})
  for (const double offset : {-2.0, 2.0}) {
    const double theta = std::atan(w) + deg(offset);
    RigidBodySystem s = system_at(solver, rate);
    ground(s, 1.5, 0, theta);
    const Vec3 n{-std::sin(theta), std::cos(theta), 0};
    const auto box = s.create({.pose = {0.5 * n, glm::angleAxis(theta, Vec3(0, 0, 1))},
                               .shapes = {{.shape = ColliderShape::box({w / 2, 0.5, 0.25}), .material = {.friction = 1.5}}}});
    for (int i = 0; i < static_cast<int>(3 / rate.dt); ++i) s.step(rate.dt, kGravity);
    const double tilt = std::acos(std::clamp(glm::dot(s.pose(box).rotation * Vec3(0, 1, 0), n), -1.0, 1.0));
    const std::string what = describe(solver, rate) + " w " + std::to_string(w) + " at " + std::to_string(theta * 180 / kPi);
    if (offset < 0) {
      EXPECT_LT(tilt, deg(1)) << what;
    } else {
      EXPECT_GT(tilt, deg(45)) << what;
    }
  }
}

// ---------------------------------------------------------------------------------------
// tunnelling

// A 0.1 m ball at 240 and 1000 m/s at a 2 cm static wall stops on its near side at every rate
// (a step at 1/30 s carries it 33 m past the wall) under every solver.
TEST(RigidParamsContinuous, AFastSmallBallStopsAtAThinWallAtOtherRates) {
  for (const Rate& rate : kRates)
  for (const auto solver : kRigidSolvers)
  for (const double v : {240.0, 1000.0}) {
    RigidBodySystem s = system_at(solver, rate);
    s.create({.name = "wall", .type = BodyType::Static, .pose = {{5, 0, 0}}, .shapes = {{.shape = ColliderShape::box({0.01, 2, 2})}}});
    const auto ball = s.create({.linear_velocity = {v, 0, 0}, .shapes = {{.shape = ColliderShape::sphere(0.05)}}});
    for (int i = 0; i < static_cast<int>(0.25 / rate.dt); ++i) s.step(rate.dt, Vec3(0));
    EXPECT_LT(s.center_of_mass(ball).x, 5 - 0.01 - 0.05 + s.settings().linear_slop) << describe(solver, rate) << " at " << v;
  }
}

// ---------------------------------------------------------------------------------------
// sleep

// time_to_sleep is valid down to 0 ("finite and >= 0"), and at 0 every awake body fell asleep
// at the end of every step: the rest window, time_to_sleep long, allowed no motion, so every
// moving body failed it, and its slow time of 0 still reached time_to_sleep. A ball in free
// fall and a box gliding at 3 m/s stopped where they were, for good (nothing touched them to
// wake them); from a scene file too ("time_to_sleep": 0). The window is now at least the step
// that measures it, so below a step the test is the step's mean speed against the
// tolerances, as RigidSleep.SteadyMotionIsHeldToTheTolerances holds it for the default window:
// a body gliding or turning at 0.9 of the tolerance sleeps after one step, at 1.1 never, and
// a falling ball falls on. Windows of a step or more are as before (the default 0.5 s here).
TEST(RigidParamsSleep, AWindowShorterThanAStepHoldsTheStepsSpeedToTheTolerances) {
  const ContactSettings c{};
  for (const double dt : {1.0 / 60, 1.0 / 240})
  for (const double window : {0.0, 0.25 * dt, 0.5})
  for (const double f : {0.9, 1.1})
  for (const bool turning : {false, true}) {
    RigidBodySystem s({.contacts = {.time_to_sleep = window}});
    const Vec3 v = turning ? Vec3(0) : Vec3(f * c.sleep_linear, 0, 0);
    const Vec3 w = turning ? Vec3(0, f * c.sleep_angular, 0) : Vec3(0);
    const auto b = s.create({.linear_velocity = v, .angular_velocity = w, .shapes = {{.shape = ColliderShape::sphere(0.5)}}});
    int steps = 0;
    const int most = static_cast<int>(2 / dt);
    while (s.awake(b) && steps < most) s.step(dt, Vec3(0)), ++steps;
    const std::string what = "dt " + std::to_string(dt) + " time_to_sleep " + std::to_string(window) + " at " +
                             std::to_string(f) + (turning ? " of the angular tolerance" : " of the linear tolerance");
    if (f < 1) {
      EXPECT_FALSE(s.awake(b)) << what;
      // the window, at least a step, and a step
      EXPECT_LE(steps * dt, std::max(window, dt) + dt * 1.0001) << what;
    } else {
      EXPECT_TRUE(s.awake(b)) << what;
    }
  }
  // a ball in free fall at time_to_sleep 0 falls on: symplectic Euler's closed form after 1 s
  RigidBodySystem s({.contacts = {.substeps = 4, .auto_substeps = false, .time_to_sleep = 0}});
  const auto ball = s.create({.pose = {{0, 100, 0}}, .shapes = {{.shape = ColliderShape::sphere(0.5)}}});
  for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kGravity);
  const double h = 1.0 / 240, n = 240;
  EXPECT_TRUE(s.awake(ball));
  EXPECT_NEAR(s.center_of_mass(ball).y, 100 - kG * h * h * n * (n + 1) / 2, 1e-9);
}

// A window of a step still froze bodies in flight: over a window W a body starting from rest
// moves g W^2 / 2, and one across the apex of a throw or a bounce as little as 0.086 g W^2,
// both within sleep_linear * W for W of a step. At 1/240 s a ball dropped from rest slept
// after its first step (its mean speed g dt / 2 = 0.02 m/s), one thrown up at 3 m/s at 1/60 s
// froze at its apex, and 116 of 120 bouncing balls froze at an apex. A body's window is now
// at least 16 sleep_linear / |g| (82 ms here), so each stays awake in flight at time_to_sleep
// 0 and 0.02 s, on symplectic Euler's closed form; and a ball come to rest on the ground
// still falls asleep, within that window of when it stopped moving.
TEST(RigidParamsSleep, AShortWindowDoesNotFreezeABodyInFlight) {
  for (const double window : {0.0, 0.02}) {
    const std::string what = "time_to_sleep " + std::to_string(window);
    // dropped from rest at 1/240 s (one substep: h = dt) and thrown up at 3 m/s at 1/60 s,
    // through its apex at 0.31 s, each for 1 s: y_n = y0 + v0 n h - g h^2 n (n + 1) / 2
    for (const auto& [dt, v0] : {std::pair{1.0 / 240, 0.0}, std::pair{1.0 / 60, 3.0}}) {
      RigidBodySystem s({.contacts = {.substeps = 1, .auto_substeps = false, .time_to_sleep = window}});
      const auto ball = s.create({.pose = {{0, 100, 0}}, .linear_velocity = {0, v0, 0},
                                  .shapes = {{.shape = ColliderShape::sphere(0.5)}}});
      const int n = static_cast<int>(std::lround(1 / dt));
      int awake = 0;
      for (int i = 0; i < n; ++i) s.step(dt, kGravity), awake += s.awake(ball);
      EXPECT_EQ(awake, n) << what << " v0 " << v0;
      EXPECT_NEAR(s.center_of_mass(ball).y, 100 + v0 * n * dt - kG * dt * dt * n * (n + 1) / 2, 1e-9)
          << what << " v0 " << v0;
    }
    // bouncing balls (e 1, 0.8, 0.5 from 0.3 and 1.7 m) at 1/60 s: none sleeps while more
    // than 1 cm above the ground; the ones that stop bouncing (e < 1) sleep by 8 s
    for (const double e : {1.0, 0.8, 0.5})
    for (const double h : {0.3, 1.7}) {
      RigidBodySystem s({.contacts = {.time_to_sleep = window}});
      ground(s, 0.5, e);
      const auto ball = s.create({.pose = {{0, h + 0.2, 0}}, .shapes = {{.shape = ColliderShape::sphere(0.2), .material = {.restitution = e}}}});
      double frozen_at = -1;
      for (int i = 0; i < 480; ++i) {
        s.step(1.0 / 60, kGravity);
        if (!s.awake(ball) && frozen_at < 0 && s.center_of_mass(ball).y - 0.2 > 0.01) frozen_at = s.center_of_mass(ball).y - 0.2;
      }
      EXPECT_LT(frozen_at, 0) << what << " e " << e << " h " << h << ": asleep at height " << frozen_at;
      if (e < 1) {
        EXPECT_FALSE(s.awake(ball)) << what << " e " << e << " h " << h;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------
// mixed scenes

// What a new user tries, each against what physics says, every solver:
// - a 1 cm cube on a 1 m cube and on the ground rests flat, its centre its half size above
//   (within the slop: a tenth of its half size for a body under 5 cm, docs "Bodies of a
//   millimetre");
// - a box of gravity scale -1 rises and rests under a ceiling; one of scale 0 sliding at 1 m/s
//   on the ground is pressed by nothing, so friction takes nothing: it keeps 1 m/s to 1e-9;
// - a box teleported (set_pose) 0.4 m into the ground mid-contact is pushed out no faster
//   than push_out_speed (1% over under sequential impulses, whose capped push-out stays as
//   velocity: RigidSolvers.OverlappingBodiesArePushedApartNoFasterThanThePushOutSpeed) and
//   rests on the ground, and the box it carried, left hanging, lands on it;
// - the middle of a 3-stack destroyed while touching both others: the top falls onto the
//   bottom and rests there (centre 1.5 m); the bottom destroyed: the top rests on the ground.
// Rest heights within the slop (5 mm) of the closed form. Measured 2026-12-07: within 0.5 mm
// but under sequential impulses, whose teleported box rests sunk the whole slop (its contact
// pushes out only past the slop: y = 0.495000000358, 3.6e-10 m inside the slop), so that box
// is held to [0.5 - slop - 1e-5, 0.5 + 1e-4]: sunk at most the slop (and 10 um of solver
// residual), never floating; push-outs at 0.8 (soft step), 3.0, 1.5 and 1.9 m/s.
TEST(RigidParamsMixed, WhatANewUserTriesRestsWhereStaticsSays) {
  for (const auto solver : kRigidSolvers) {
    const std::string what{to_string(solver)};
    const double slop = ContactSettings{}.linear_slop;
    {
      RigidBodySystem s({.contacts = {.solver = solver}});
      ground(s, 0.5);
      rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
      const auto on_big = rigid_scenes::box(s, {0.2, 1.006, 0.1}, Vec3(0.005));
      const auto on_ground = rigid_scenes::box(s, {2, 0.006, 0}, Vec3(0.005));
      for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
      EXPECT_NEAR(s.center_of_mass(on_big).y, 1.005, 0.1 * 0.005) << what;
      EXPECT_NEAR(s.center_of_mass(on_ground).y, 0.005, 0.1 * 0.005) << what;
      EXPECT_GT(std::abs(glm::dot(s.pose(on_big).rotation * Vec3(0, 1, 0), Vec3(0, 1, 0))), std::cos(0.01)) << what;
    }
    {
      RigidBodySystem s({.contacts = {.solver = solver}});
      ground(s, 0.5);
      s.create({.type = BodyType::Static, .pose = {{0, 3, 0}}, .shapes = {{.shape = ColliderShape::box({5, 0.1, 5})}}});
      const auto up = s.create({.pose = {{0, 1.5, 0}}, .shapes = {{.shape = ColliderShape::box(Vec3(0.25))}}, .gravity_scale = -1});
      const auto floating = s.create({.pose = {{2, 0.25, 0}}, .linear_velocity = {1, 0, 0},
                                      .shapes = {{.shape = ColliderShape::box(Vec3(0.25))}}, .gravity_scale = 0});
      for (int i = 0; i < 180; ++i) s.step(1.0 / 60, kGravity);
      EXPECT_NEAR(s.center_of_mass(up).y, 2.9 - 0.25, slop) << what;
      EXPECT_NEAR(s.linear_velocity(floating).x, 1, 1e-9) << what;
    }
    {
      RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
      const auto stack = rigid_scenes::vertical_stack(s, 2);
      for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kGravity);
      s.set_pose(stack[0], {{0, 0.1, 0}});
      double fastest = 0;
      for (int i = 0; i < 120; ++i) {
        s.step(1.0 / 60, kGravity);
        fastest = std::max(fastest, glm::length(s.linear_velocity(stack[0])));
      }
      const double kept = solver == RigidSolverType::SequentialImpulse ? 1.01 : 1.0;
      EXPECT_LT(fastest, kept * s.settings().push_out_speed) << what;
      EXPECT_GE(s.center_of_mass(stack[0]).y, 0.5 - slop - 1e-5) << what;
      EXPECT_LE(s.center_of_mass(stack[0]).y, 0.5 + 1e-4) << what;
      EXPECT_NEAR(s.center_of_mass(stack[1]).y, 1.5, 2 * slop) << what;
    }
    {
      RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
      const auto stack = rigid_scenes::vertical_stack(s, 3);
      for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kGravity);
      s.destroy(stack[1]);
      for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
      EXPECT_NEAR(s.center_of_mass(stack[2]).y, 1.5, 2 * slop) << what;
      s.destroy(stack[0]);
      for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
      EXPECT_NEAR(s.center_of_mass(stack[2]).y, 0.5, slop) << what;
    }
  }
}

// ---------------------------------------------------------------------------------------
// bad input

// Forces and torques are checked finite one by one, but their sum for the next step, and a
// finite force's moment about a far point, can overflow: 1e308 N applied twice, 1e200 N at
// 1e200 m. Those were taken, and the step then stopped the system for good with the body
// "became non-finite", naming no force. Now the call is refused by name, and the body and the
// system go on as before it (the step runs: free fall, g dt).
TEST(RigidParamsBadInput, AForceOrTorqueSummingPastTheDoublesIsRefusedByName) {
  RigidBodySystem s;
  const auto b = s.create({.name = "crate", .pose = {{0, 5, 0}}, .shapes = {{.shape = ColliderShape::box(Vec3(0.5))}}});
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string twice = message([&] {
    s.apply_force(b, {1e308, 0, 0});
    s.apply_force(b, {1e308, 0, 0});
  });
  EXPECT_NE(twice.find("'crate' apply_force: the force summed for the next step: must be finite"), std::string::npos) << twice;
  const std::string moment = message([&] { s.apply_force(b, {1e200, 0, 0}, {0, 1e200, 0}); });
  EXPECT_NE(moment.find("'crate' apply_force: the force's moment about the centre of mass, or the torque summed for the next step: must be finite"), std::string::npos) << moment;
  const std::string torque = message([&] {
    s.apply_torque(b, {0, 1e308, 0});
    s.apply_torque(b, {0, 1e308, 0});
  });
  EXPECT_NE(torque.find("'crate' apply_torque: the torque summed for the next step: must be finite"), std::string::npos) << torque;
  // the first 1e308 N and 1e308 N m were taken (finite): cancelled, the box falls freely
  s.apply_force(b, {-1e308, 0, 0});
  s.apply_torque(b, {0, -1e308, 0});
  ASSERT_NO_THROW(s.step(1.0 / 60, kGravity));
  EXPECT_NEAR(s.linear_velocity(b).y, -kG / 60, 1e-12);
  EXPECT_EQ(s.linear_velocity(b).x, 0);
}

}  // namespace pba
