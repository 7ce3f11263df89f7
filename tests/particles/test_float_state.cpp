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

// ---------------------------------------------------------------------------------------
// values that pass a double check but do not fit the float state

TEST(FloatState, ParticleValuesThatOverflowAFloatAreRefusedByName) {
  ParticleSystem ps;
  auto message = [&](const pba::ParticleDef& d) { return error_of([&] { ps.create(d, "balls[3]"); }); };
  // 1e39 is a finite double and an infinite float: the position would be inf at once
  EXPECT_EQ(message({.position = {0, 1e39, 0}}),
            "balls[3].position: must fit a float (|component| <= 3.4028234663852886e+38), got (0, 1e+39, 0)");
  EXPECT_EQ(message({.velocity = {-4e38, 0, 0}}),
            "balls[3].velocity: must fit a float (|component| <= 3.4028234663852886e+38), got (-4e+38, 0, 0)");
  // the mass is stored as its float inverse: 1 / 1e-39 overflows (NaN at the first tick,
  // inf * 0 in the drag), 1 / 1e38 is below the smallest normal float
  const std::string tiny = message({.mass = 1e-39});
  EXPECT_EQ(tiny.rfind("balls[3].mass: must be in [2.9387", 0), 0u) << tiny;
  EXPECT_NE(tiny.find("8.507059173023462e+37] (its inverse is stored as a normal float), got 1e-39"), std::string::npos)
      << tiny;
  EXPECT_NE(message({.mass = 1e38}).find("balls[3].mass: must be in ["), std::string::npos);
  EXPECT_EQ(message({.radius = 1e39}),
            "balls[3].radius: must fit a float (|v| <= 3.4028234663852886e+38), got 1e+39");
  EXPECT_EQ(ps.size(), 0u);
  // the limits themselves are accepted, and step without turning non-finite
  ps.create({.position = {0, 3e38, 0}, .mass = 8e37});
  ps.create({.mass = 3e-39});
  ps.step(0, 1e-3, {}, {});
  EXPECT_TRUE(std::isfinite(ps.position(0).y));
  EXPECT_TRUE(std::isfinite(ps.velocity(1).y));
  // writes are checked the same way
  EXPECT_NE(error_of([&] { ps.set_position(0, {1e39, 0, 0}); }).find("ParticleSystem::set_position: must fit a float"),
            std::string::npos);
  EXPECT_NE(error_of([&] { ps.set_velocity(0, {0, 0, -1e39}); }).find("ParticleSystem::set_velocity: must fit a float"),
            std::string::npos);
}

// A speed that fits a float can still overflow the float arithmetic: the drag squares the
// speed relative to the wind in float, so above sqrt(3.4e38) = 1.8e19 m/s it is inf, and with
// no drag coefficient 0 * inf is NaN: a particle launched at 1e20 m/s was non-finite after
// the first tick. Speeds (and the wind's) are limited to kMaxParticleSpeed = 9e18 m/s, so
// that their difference squares finite; refused at creation, at set_velocity, for an
// emitter's fastest launch and for the wind.
TEST(FloatState, SpeedsWhoseSquareOverflowsAFloatAreRefusedByName) {
  ParticleSystem ps;
  auto message = [&](const pba::ParticleDef& d) { return error_of([&] { ps.create(d, "balls[3]"); }); };
  const std::string fast = message({.velocity = {0, 0, 1e20}});
  EXPECT_EQ(fast.rfind("balls[3].velocity: a speed of 1e+20 m/s", 0), 0u) << fast;
  EXPECT_NE(fast.find("9e+18 m/s"), std::string::npos) << fast;
  EXPECT_EQ(ps.size(), 0u);
  // the limit itself steps finite, with and without drag, and against the fastest wind
  for (double drag : {0.0, 1e-30}) {
    ParticleSystem s({.forces = {.quadratic_drag = drag, .wind = {.velocity = {-pba::kMaxParticleSpeed, 0, 0}}}});
    s.create({.velocity = {pba::kMaxParticleSpeed, 0, 0}});
    s.step(0, 1e-3, {}, {});
    EXPECT_TRUE(std::isfinite(s.velocity(0).x)) << drag;
    EXPECT_TRUE(std::isfinite(s.position(0).x)) << drag;
  }
  ps.create({});
  EXPECT_NE(error_of([&] { ps.set_velocity(0, {-2e19, 0, 0}); }).find("ParticleSystem::set_velocity: a speed of 2e+19"),
            std::string::npos);
  EXPECT_NE(error_of([&] { ps.add_emitter({.speed = 1e19}, "sparks"); }).find("sparks.speed: the fastest launch"),
            std::string::npos);
  const std::string wind = error_of([&] { ParticleSystem s({.forces = {.wind = {.velocity = {0, 1e19, 0}}}}); });
  EXPECT_NE(wind.find("wind.velocity + wind.gust: a speed of 1e+19 m/s"), std::string::npos) << wind;
}

TEST(FloatState, EmitterAndForceValuesThatOverflowAFloatAreRefusedByName) {
  ParticleSystem ps;
  auto emitter = [&](const pba::EmitterDef& d) { return error_of([&] { ps.add_emitter(d, "sparks"); }); };
  EXPECT_NE(emitter({.pose = {.position = {2e39, 0, 0}}}).find("sparks.position: must fit a float"), std::string::npos);
  EXPECT_NE(emitter({.mass = 1e-39}).find("sparks.mass: must be in ["), std::string::npos);
  EXPECT_NE(emitter({.radius = 5e38}).find("sparks.radius: must fit a float"), std::string::npos);
  // a speed that fits, but not once jittered up
  EXPECT_NE(emitter({.speed = 3e38, .speed_jitter = 0.5}).find("sparks.speed: the fastest launch"), std::string::npos);
  EXPECT_EQ(ps.emitter_count(), 0u);
  // forces are read as floats by the kernels
  auto system = [](const pba::Forces& f) { return error_of([&] { ParticleSystem s({.forces = f}); }); };
  EXPECT_NE(system({.gravity = {0, -1e39, 0}}).find("ParticleSystemDef.forces.gravity: must fit a float"),
            std::string::npos);
  EXPECT_NE(system({.quadratic_drag = 1e39}).find("ParticleSystemDef.forces.quadratic_drag: must fit a float"),
            std::string::npos);
  EXPECT_NE(system({.wind = {.velocity = {3e38, 0, 0}, .gust = 1e38}})
                .find("ParticleSystemDef.forces: |wind.velocity| (3e+38, 0, 0) + wind.gust 1e+38 = "),
            std::string::npos);
  // a wind and a gust each finite whose sum overflows a double: named as the sum of the two,
  // not as a value that "must be finite" (which the caller never gave)
  EXPECT_EQ(system({.wind = {.velocity = {1e308, 0, 0}, .gust = 1e308}}),
            "ParticleSystemDef.forces: |wind.velocity| (1e+308, 0, 0) + wind.gust 1e+308 = (inf, 1e+308, 1e+308) "
            "does not fit a float (|component| <= 3.4028234663852886e+38)");
  // changed between steps: refused at the step
  ps.create({});
  ps.forces().gravity = {0, 1e40, 0};
  EXPECT_NE(error_of([&] { ps.step(0, 0.01, {}, {}); }).find("ParticleSystem.forces.gravity: must fit a float"),
            std::string::npos);
}

}  // namespace
