// Rigid bodies at other parameters than the and under every solver: the laws the
// issue's tests hold at its numbers (restitution, Coulomb friction, rolling, tunnelling,
// sleep), at other step rates, substeps, coefficients, sizes and settings, each against its
// closed form with a tolerance from the scheme's error; and mixed scenes a new user would try.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "pba/rigid.h"
#include "pba/rigid_scenes.h"

// inside pba, so the library's names need no using-declarations
namespace pba {
namespace {

constexpr double kG = 9.81;
const Vec3 kGravity{0, -kG, 0};

}  // namespace

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

}  // namespace pba
