// The particles' float state: position Verlet keeps what float positions cannot hold
// (a drift below half a float step is not lost), and values that pass a double check but
// do not fit a float (a position of 1e39, a mass whose inverse overflows) are refused at
// creation with the field named.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "error_of.h"
#include "pba/particles.h"

namespace {

using pba::Method;
using pba::ParticleSystem;
using pba::test_support::error_of;

// ---------------------------------------------------------------------------------------
// free fall with position Verlet against y(t) = y0 - g t^2 / 2
//
// Verlet is exact for a constant acceleration (the second difference of a quadratic is
// a h^2, and the second-order start x_-1 = x0 - v0 h + a h^2 / 2 lies on the parabola),
// so what remains is round-off:
//   * the start height and the gravity the kernels apply are the floats nearest the
//     given values: the closed form uses them;
//   * each stored position is rounded to float once: half an ulp, <= 2^-24 |y|;
//   * the recurrence in double rounds each step by at most 4 units of 2^-53 of the
//     largest |y| (three operations), and position Verlet sums local errors twice, so
//     after n steps the position is off by n^2 / 2 of that and the velocity (a
//     difference over h) by n of it over h;
//   * each stored velocity is rounded to float once: <= 2^-24 |v|.
// Before the fix the recurrence ran in float: a drift g h^2 under half an ulp of y was
// lost every step (from y = 2.02 at dt = 1e-4 the particle hung in the air).

TEST(VerletFloatState, FreeFallMatchesTheClosedFormForEveryStepAndHeight) {
  const double g = static_cast<double>(static_cast<float>(9.81));
  const double t_end = 0.6;
  for (double dt : {1e-4, 3e-4, 1e-3, 3e-3, 1e-2}) {
    for (double y0 : {2.0, 2.02, 0.37, 100.5, 1000.25}) {
      ParticleSystem ps({.capacity = 16, .method = Method::PositionVerlet});
      ps.create({.position = {0, y0, 0}, .mass = 0.1, .radius = 0.01});
      const long long n = std::llround(t_end / dt);
      for (long long i = 0; i < n; ++i) ps.step(static_cast<double>(i) * dt, dt, {}, {});
      const double t = static_cast<double>(n) * dt;
      const double y = static_cast<float>(y0) - g * t * t / 2, vy = -g * t;
      const double local = 4 * 0x1p-53 * std::max(std::abs(y0), std::abs(y));
      const double nn = static_cast<double>(n);
      const double tol_y = 0x1p-24 * std::abs(y) + nn * nn / 2 * local;
      const double tol_v = 0x1p-24 * std::abs(vy) + nn * local / dt;
      EXPECT_NEAR(ps.position(0).y, y, tol_y) << "dt " << dt << " y0 " << y0;
      EXPECT_NEAR(ps.velocity(0).y, vy, tol_v) << "dt " << dt << " y0 " << y0;
      EXPECT_EQ(ps.position(0).x, 0.0);
    }
  }
}

// the scene: y0 = 2.02, dt = 1e-4, 0.6 s (y = 0.254, vy = -5.886), with a
// horizontal velocity too (the drift h vx is also below half a float step)
TEST(VerletFloatState, TheHangingParticleFalls) {
  const double g = static_cast<double>(static_cast<float>(9.81));
  const double dt = 1e-4;
  ParticleSystem ps({.method = Method::PositionVerlet});
  ps.create({.position = {3.5, 2.02, 0}, .velocity = {1e-3, 0, 0}});
  for (int i = 0; i < 6000; ++i) ps.step(i * dt, dt, {}, {});
  // bounds as in the test above, with n = 6000: 2^-24 |y| + n^2 / 2 4 2^-53 2.02
  EXPECT_NEAR(ps.position(0).y, static_cast<float>(2.02) - g * 0.18, 0x1p-24 * 0.26 + 1.8e7 * 4 * 0x1p-53 * 2.02);
  EXPECT_NEAR(ps.velocity(0).y, -g * 0.6, 0x1p-24 * 5.9 + 6000 * 4 * 0x1p-53 * 2.02 / dt);
  // x = 3.5 + 6e-4: 6 ulps of 3.5 covered by drifts of a fortieth of an ulp each
  EXPECT_NEAR(ps.position(0).x, 3.5 + static_cast<float>(1e-3) * 0.6, 0x1p-24 * 4 + 1.8e7 * 4 * 0x1p-53 * 3.5);
}

// a velocity written between steps restarts the history from the written value
TEST(VerletFloatState, WrittenVelocityIsHonoured) {
  const double dt = 1e-3;
  ParticleSystem ps({.method = Method::PositionVerlet, .forces = {.gravity = {0, 0, 0}}});
  ps.create({.position = {0, 5, 0}});
  for (int i = 0; i < 10; ++i) ps.step(i * dt, dt, {}, {});
  EXPECT_EQ(ps.position(0).y, 5.0);
  ps.set_velocity(0, {0, 2, 0});
  for (int i = 10; i < 110; ++i) ps.step(i * dt, dt, {}, {});
  // 100 steps at 2 m/s: 0.2 m, to float rounding of y and of the 100 double steps
  EXPECT_NEAR(ps.position(0).y, 5.2, 0x1p-24 * 5.2 + 1e4 / 2 * 4 * 0x1p-53 * 5.2);
  EXPECT_NEAR(ps.velocity(0).y, 2.0, 0x1p-24 * 2 + 100 * 4 * 0x1p-53 * 5.2 / dt);
}

}  // namespace
