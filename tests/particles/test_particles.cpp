// Particles: closed-form ballistics and drag per integrator, restitution and resting
// contact, swept collisions, emitters, handles, bad input, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "error_of.h"
#include "pba/particles.h"
#include "pba/world.h"

namespace {

using pba::Collider;
using pba::Method;
using pba::ParticleDef;
using pba::ParticleSystem;
using pba::Vec3;

constexpr double kG = 9.81;
constexpr double kFloatEps = 1.1920929e-7;

// round-off allowance for n float steps of a quantity of size `scale`: one rounding per
// step adds up to n ulps; position Verlet's recurrence x' = 2x - x_prev sums the rounding
// errors twice (a double sum), so its bound is n^2 / 2 ulps
double roundoff(long long n, double scale, Method m = Method::SemiImplicitEuler) {
  const double steps = static_cast<double>(n);
  return (m == Method::PositionVerlet ? steps * steps / 2 : steps) * kFloatEps * scale;
}

ParticleSystem make_system(Method m) {
  pba::ParticleSystemDef def;
  def.method = m;
  def.capacity = 16;
  return ParticleSystem(def);
}

// ---------------------------------------------------------------------------------------
// ballistics without drag: for constant acceleration, methods of order >= 2 are exact and
// first-order methods are off by exactly g t h / 2 (semi-implicit and implicit Euler
// above, explicit Euler below); that is the tolerance, plus float round-off.

class Ballistic : public ::testing::TestWithParam<Method> {};

TEST_P(Ballistic, RangeAndApexMatchClosedForm) {
  const Method m = GetParam();
  const double h = 1.0 / 240, speed = 12, angle = 0.9;
  const Vec3 v0(speed * std::cos(angle), speed * std::sin(angle), 0);
  ParticleSystem ps = make_system(m);
  ps.create({.position = {0, 0, 0}, .velocity = v0, .mass = 0.2, .radius = 0.05});
  // closed form: apex height and time, range and flight time
  const double t_apex = v0.y / kG, apex = v0.y * v0.y / (2 * kG);
  const double t_flight = 2 * v0.y / kG, range = v0.x * t_flight;
  const double method_err = pba::order(m) == 1 ? 0.5 * kG * t_flight * h : 0.0;
  // step until the particle comes back down through y = 0
  double best_y = -1, t = 0;
  Vec3 prev = ps.position(0);
  long long n = 0;
  while (true) {
    ps.step(t, h, {}, {});
    t += h;
    ++n;
    const Vec3 p = ps.position(0);
    best_y = std::max(best_y, p.y);
    if (p.y < 0 && prev.y >= 0 && t > t_apex) {
      // linear interpolation of the crossing between the two samples
      const double f = prev.y / (prev.y - p.y);
      const double x_cross = prev.x + f * (p.x - prev.x);
      // crossing shifts by the vertical error over the landing slope; interpolating the
      // parabola linearly adds at most g h^2 / 8 in y
      const double slope = v0.x / v0.y;
      const double tol = slope * (method_err + kG * h * h / 8) + roundoff(n, range, m);
      EXPECT_NEAR(x_cross, range, tol) << pba::name(m);
      break;
    }
    prev = p;
    ASSERT_LT(t, 2 * t_flight);
  }
  // the sampled apex is within g h^2 / 2 below the true one (plus the method error)
  const double tol_apex = 0.5 * kG * t_apex * h * (pba::order(m) == 1 ? 1 : 0) + 0.5 * kG * h * h +
                          roundoff(n, apex, m);
  EXPECT_NEAR(best_y, apex, tol_apex) << pba::name(m);
}

// linear drag: x(t) = x0 + v0 tau (1 - e^{-t/tau}) + g tau (t - tau (1 - e^{-t/tau})).
// Every derivative of order k >= 2 is (v0 - g tau) (-1/tau)^(k-1) e^{-t/tau}, so a method
// of order p has global error below T h^p |v0 - g tau| / tau^p (leading term, constant
// <= 1 for these methods); plus float round-off.
TEST_P(Ballistic, LinearDragMatchesClosedForm) {
  const Method m = GetParam();
  const double h = 1.0 / 120, mass = 0.1, b = 0.1, tau = mass / b, T = 2.0;
  const Vec3 g(0, -kG, 0), v0(10, 10, 0);
  ParticleSystem ps = make_system(m);
  ps.forces().linear_drag = b;
  ps.create({.position = {0, 0, 0}, .velocity = v0, .mass = mass, .radius = 0.05});
  const int p = pba::order(m);
  const double scale = glm::length(v0 - g * tau) * T;
  const double tol = T * std::pow(h, p) * glm::length(v0 - g * tau) / std::pow(tau, p);
  double t = 0, worst = 0;
  const int steps = static_cast<int>(std::lround(T / h));
  for (int i = 0; i < steps; ++i) {
    ps.step(t, h, {}, {});
    t = (i + 1) * h;
    const double e = 1 - std::exp(-t / tau);
    const Vec3 exact = v0 * tau * e + g * tau * (t - tau * e);
    worst = std::max(worst, glm::length(ps.position(0) - exact));
  }
  EXPECT_LE(worst, tol + roundoff(steps, scale, m)) << pba::name(m);
  // and the error is not trivially zero for first-order methods (the test can fail)
  if (p == 1) {
    EXPECT_GT(worst, 0.05 * tol);
  }
}

INSTANTIATE_TEST_SUITE_P(AllMethods, Ballistic, ::testing::ValuesIn(pba::kAllMethods),
                         [](const auto& info) {
                           std::string s(pba::name(info.param));
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s;
                         });

// ---------------------------------------------------------------------------------------
// restitution: a ball dropped from height H rebounds to e^2 H (within 3% at 1/960 s for
// the first-order methods, whose flight misses it by O(h); 1/120 s for the others)

struct BounceCase {
  Method method;
  double e;
};

class Bounce : public ::testing::TestWithParam<BounceCase> {};

TEST_P(Bounce, ReboundsToESquaredHeight) {
  const auto [m, e] = GetParam();
  // the integrator's own error over the fall and the rise must be well inside 3% of
  // e^2 H: first-order methods are off by g t h / 2 per leg (t <= 0.45 s), so they need
  // h <= 1/960 s to stay below 1% at e = 0.3; higher orders are exact for gravity
  const double h = pba::order(m) == 1 ? 1.0 / 960 : 1.0 / 120, r = 0.05, H = 1.0;
  ParticleSystem ps = make_system(m);
  ps.create({.position = {0, H + r, 0}, .mass = 0.1, .radius = r});
  const Collider ground = Collider::plane({0, 1, 0}, 0, {.restitution = e, .friction = 0.2});
  // fall, bounce once, and record the highest point of the first rebound
  double t = 0, apex = -1;
  bool bounced = false;
  for (int i = 0; i < 4000; ++i) {
    ps.step(t, h, std::span(&ground, 1), {});
    t += h;
    const double y = ps.position(0).y - r;
    const double vy = ps.velocity(0).y;
    if (ps.contacts() > 0) bounced = true;
    if (bounced) apex = std::max(apex, y);
    if (bounced && vy < 0 && apex > 0) break;
  }
  EXPECT_NEAR(apex, e * e * H, 0.03 * e * e * H) << pba::name(m) << " e=" << e;
}

// the same on the top face of a box and the top of a sphere (their contact planes)
TEST(Bounce, OnBoxesAndSpheresToo) {
  for (Method m : {Method::SemiImplicitEuler, Method::Rk4}) {
    for (int shape = 0; shape < 2; ++shape) {
      const double e = 0.7, H = 1.0, r = 0.05, top = 0.5;
      const double h = pba::order(m) == 1 ? 1.0 / 960 : 1.0 / 120;
      ParticleSystem ps = make_system(m);
      ps.create({.position = {0, top + H + r, 0}, .mass = 0.1, .radius = r});
      const Collider c = shape == 0 ? Collider::box({0, top - 0.25, 0}, {1, 0.25, 1}, {.restitution = e})
                                    : Collider::sphere({0, top - 2, 0}, 2, {.restitution = e});
      double t = 0, apex = -1;
      bool bounced = false;
      for (int i = 0; i < 4000; ++i, t += h) {
        ps.step(t, h, std::span(&c, 1), {});
        bounced |= ps.contacts() > 0;
        if (bounced) apex = std::max(apex, ps.position(0).y - r - top);
        if (bounced && ps.velocity(0).y < 0 && apex > 0) break;
      }
      EXPECT_NEAR(apex, e * e * H, 0.03 * e * e * H) << pba::name(m) << (shape == 0 ? " box" : " sphere");
    }
  }
}

// The rebound's error is the flight's, not the contact's. A first-order method's fall and
// rise (semi-implicit and implicit Euler: x_n = H - g t_n (t_n + h) / 2, explicit Euler
// with + h) land at the surface a speed g h / 2 slow (fast) and lose (gain) u h / 2 of
// height on the way up from speed u = e sqrt(2 g H), so the apex is
// (e sqrt(2gH) -+ (e + 1) g h / 2)^2 / (2g) = e^2 H -+ (e^2 + e) sqrt(2gH) h / 2 + O(h^2):
// first order in h, with that coefficient. Methods exact on gravity miss the apex only by
// sampling it between steps (<= g h^2 / 8 below the parabola's top) and by the time of
// impact from the chord of the signed distances (the parabola is within g h^2 / 8 of the
// chord, an impact-speed error g (g h^2 / 8) / v, e^2 g h^2 / 8 of rebound), plus the
// float state's rounding (<= 2^-24 m a step on |y| < 2 m, and as much again for the
// velocity's over the flight's < 1 s, so 2^-23 m a step).
TEST(Bounce, ReboundErrorIsTheFlightsOfOrderOneOrExact) {
  const double g = 9.81, H = 1.0, r = 0.05;
  for (Method m : pba::kAllMethods) {
    const double sign = m == Method::ExplicitEuler ? 1 : -1;
    for (double e : {0.3, 0.8}) {
      std::vector<double> dev;
      for (double h : {1.0 / 60, 1.0 / 120, 1.0 / 240, 1.0 / 480, 1.0 / 960}) {
        SCOPED_TRACE(std::string(pba::name(m)) + " e=" + std::to_string(e) + " 1/h=" + std::to_string(1 / h));
        ParticleSystem ps = make_system(m);
        ps.create({.position = {0, H + r, 0}, .mass = 0.1, .radius = r});
        const Collider ground = Collider::plane({0, 1, 0}, 0, {.restitution = e, .friction = 0.2});
        double t = 0, apex = -1;
        bool bounced = false;
        int steps = 0;
        for (; steps < 4000; ++steps) {
          ps.step(t, h, std::span(&ground, 1), {});
          t += h;
          bounced |= ps.contacts() > 0;
          if (bounced) apex = std::max(apex, ps.position(0).y - r);
          if (bounced && ps.velocity(0).y < 0 && apex > 0) break;
        }
        ASSERT_TRUE(bounced && apex > 0);
        dev.push_back(apex - e * e * H);
        if (pba::order(m) >= 2) {
          EXPECT_LE(std::abs(dev.back()), (1 + e * e) * g * h * h / 8 + steps * std::ldexp(1.0, -23));
        } else if (h < 1.0 / 500) {
          // the leading term: its O(h) relative remainder, 8% at 1/60 s (e = 0.3), is 16x
          // smaller at 1/960 s
          const double lead = sign * (e * e + e) * std::sqrt(2 * g * H) * h / 2;
          EXPECT_NEAR(dev.back() / lead, 1.0, 0.02);
        }
      }
      if (pba::order(m) == 1) {
        // first order: each halving of h halves the error, on the three finest
        for (std::size_t i = 2; i + 1 < dev.size(); ++i)
          EXPECT_NEAR(std::log2(dev[i] / dev[i + 1]), 1.0, 0.05) << pba::name(m) << " e=" << e << " level " << i;
      }
    }
  }
}

std::vector<BounceCase> bounce_cases() {
  std::vector<BounceCase> v;
  for (Method m : pba::kAllMethods)
    for (double e : {0.3, 0.5, 0.8, 0.95}) v.push_back({m, e});
  return v;
}

INSTANTIATE_TEST_SUITE_P(MethodsAndRestitution, Bounce, ::testing::ValuesIn(bounce_cases()),
                         [](const auto& info) {
                           std::string s(pba::name(info.param.method));
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s + "_e" + std::to_string(static_cast<int>(std::lround(info.param.e * 100)));
                         });

// e = 0: the ball stays down, does not sink below the plane, does not creep; with e > 0
// it settles without jitter
class Resting : public ::testing::TestWithParam<Method> {};

TEST_P(Resting, StaysDownWithoutSinkingOrJitter) {
  const Method m = GetParam();
  const double h = 1.0 / 60, r = 0.05;
  for (double e : {0.0, 0.6}) {
    ParticleSystem ps = make_system(m);
    ps.create({.position = {0.3, 0.5 + r, -0.2}, .mass = 0.1, .radius = r});
    const Collider ground = Collider::plane({0, 1, 0}, 0, {.restitution = e, .friction = 0.5});
    double t = 0;
    // settle for 4 s, then watch for 2 s
    for (int i = 0; i < 240; ++i, t += h) ps.step(t, h, std::span(&ground, 1), {});
    double lo = 1e9, hi = -1e9;
    for (int i = 0; i < 120; ++i, t += h) {
      ps.step(t, h, std::span(&ground, 1), {});
      lo = std::min(lo, ps.position(0).y);
      hi = std::max(hi, ps.position(0).y);
    }
    // float round-off of the surface position is the only allowed motion
    const double tol = 4 * kFloatEps * (1 + r);
    EXPECT_GE(lo, r - tol) << pba::name(m) << " e=" << e << " sank";
    EXPECT_LE(hi - lo, tol) << pba::name(m) << " e=" << e << " jitters";
    EXPECT_NEAR(ps.position(0).x, 0.3, 1e-6) << "creeps";
    EXPECT_NEAR(ps.position(0).z, -0.2, 1e-6) << "creeps";
  }
}

INSTANTIATE_TEST_SUITE_P(AllMethods, Resting, ::testing::ValuesIn(pba::kAllMethods), [](const auto& info) {
  std::string s(pba::name(info.param));
  for (char& c : s)
    if (c == '-') c = '_';
  return s;
});

// Coulomb friction: a particle sliding on the ground stops after v^2 / (2 mu g)
TEST(Friction, SlidingDistanceMatchesCoulomb) {
  const double h = 1.0 / 240, r = 0.05, mu = 0.4, v0 = 3;
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  ps.create({.position = {0, r, 0}, .velocity = {v0, 0, 0}, .mass = 1, .radius = r});
  const Collider ground = Collider::plane({0, 1, 0}, 0, {.restitution = 0, .friction = mu});
  double t = 0;
  for (int i = 0; i < 480; ++i, t += h) ps.step(t, h, std::span(&ground, 1), {});
  const double expected = v0 * v0 / (2 * mu * kG);
  // first-order in h: the stop is resolved to one step of travel, v0 h
  EXPECT_NEAR(ps.position(0).x, expected, v0 * h + 1e-3);
  EXPECT_EQ(ps.velocity(0).x, 0.0);
}

// ---------------------------------------------------------------------------------------
// no tunnelling: at 300 m/s (5 m per step at 60 Hz) against a 2 cm box and a small sphere

TEST(Tunnelling, FastParticlesAreCaughtByThinBoxesAndSpheres) {
  const double h = 1.0 / 60;
  for (int shape = 0; shape < 3; ++shape) {
    ParticleSystem ps = make_system(Method::SemiImplicitEuler);
    ps.forces().gravity = Vec3(0);
    ps.create({.position = {-3, 0, 0}, .velocity = {300, 0, 0}, .mass = 1, .radius = 0.01});
    Collider c = shape == 0   ? Collider::box({0, 0, 0}, {0.01, 1, 1}, {.restitution = 0})
                 : shape == 1 ? Collider::sphere({0, 0, 0}, 0.05, {.restitution = 0})
                              : Collider::plane({-1, 0, 0}, 0, {.restitution = 0});
    double t = 0;
    for (int i = 0; i < 5; ++i, t += h) ps.step(t, h, std::span(&c, 1), {});
    EXPECT_LT(ps.position(0).x, 0.0) << "shape " << shape;
  }
}

// a moving plane (an elevator) lifts a resting particle and carries it
TEST(MovingSurface, RisingPlaneCarriesParticle) {
  const double h = 1.0 / 120, r = 0.05, speed = 0.5;
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  ps.create({.position = {0, r, 0}, .mass = 1, .radius = r});
  double t = 0;
  for (int i = 0; i < 120; ++i, t += h) {
    Collider floor = Collider::plane({0, 1, 0}, 0, {.restitution = 0});
    floor.begin.position = Vec3(0, speed * t, 0);
    floor.end.position = Vec3(0, speed * (t + h), 0);
    floor.velocity = Vec3(0, speed, 0);
    ps.step(t, h, std::span(&floor, 1), {});
    EXPECT_GE(ps.position(0).y, speed * (t + h) + r - 1e-5);
  }
  EXPECT_NEAR(ps.position(0).y, speed * 1.0 + r, 1e-3);
}

// ---------------------------------------------------------------------------------------
// wind and forcers

TEST(Wind, GustsAreDeterministicAndBounded) {
  pba::Wind w{.velocity = {2, 0, 0}, .gust = 1.5, .gust_period = 0.5, .seed = 7};
  pba::Wind same = w;
  pba::Wind other = w;
  other.seed = 8;
  bool differs = false;
  for (int i = 0; i < 1000; ++i) {
    const double t = i * 0.013;
    const Vec3 a = w.at(t);
    EXPECT_EQ(a, same.at(t));
    EXPECT_LE(glm::length(a - w.velocity), 1.5 * std::sqrt(3.0) + 1e-12);
    differs |= a != other.at(t);
  }
  EXPECT_TRUE(differs);
}

TEST(Wind, LinearDragRelaxesToTheWind) {
  // tau = m / b = 0.5 s; after 10 tau the particle moves with the air
  ParticleSystem ps = make_system(Method::Rk4);
  ps.forces().gravity = Vec3(0);
  ps.forces().linear_drag = 0.2;
  ps.forces().wind.velocity = Vec3(3, 0, -1);
  ps.create({.mass = 0.1});
  double t = 0;
  for (int i = 0; i < 600; ++i, t += 1.0 / 120) ps.step(t, 1.0 / 120, {}, {});
  EXPECT_NEAR(ps.velocity(0).x, 3, 1e-3);
  EXPECT_NEAR(ps.velocity(0).z, -1, 1e-3);
}

TEST(Forcer, FanPushesOnlyInside) {
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  ps.forces().gravity = Vec3(0);
  ps.create({.position = {0, 0, 0}, .mass = 2});
  ps.create({.position = {5, 0, 0}, .mass = 2});
  pba::Forcer fan{.kind = pba::ForcerKind::Fan, .shape = pba::ForcerShape::Box, .half_extents = {1, 1, 1},
                  .direction = {0, 0, 1}, .strength = 4};
  ps.step(0, 0.1, {}, std::span(&fan, 1));
  EXPECT_FLOAT_EQ(static_cast<float>(ps.velocity(0).z), 0.2f);  // a = F / m = 2
  EXPECT_EQ(ps.velocity(1).z, 0.0);
  // the double reference agrees
  EXPECT_EQ(fan.force_at({0, 0, 0}, 0), Vec3(0, 0, 4));
  EXPECT_EQ(fan.force_at({5, 0, 0}, 0), Vec3(0));
}

TEST(Forcer, VortexSpinsAndAttractorPulls) {
  pba::Forcer vortex{.kind = pba::ForcerKind::Vortex, .shape = pba::ForcerShape::Cylinder, .radius = 2,
                     .half_height = 1, .strength = 3, .pull = 1};
  const Vec3 f = vortex.force_at({1, 0, 0}, 0);
  EXPECT_NEAR(f.x, -1, 1e-12);  // inward
  EXPECT_NEAR(f.z, -3, 1e-12);  // tangential: +Y x +X = -Z
  pba::Forcer attractor{.kind = pba::ForcerKind::Attractor, .shape = pba::ForcerShape::Sphere, .radius = 5,
                        .strength = 2, .softening = 0.5};
  EXPECT_NEAR(attractor.force_at({0, 3, 0}, 0).y, -2, 1e-12);
  EXPECT_NEAR(attractor.force_at({0, 0.25, 0}, 0).y, -1, 1e-12);  // faded inside softening
  // air cannon pulse: on for 0.2 s of every second
  pba::Forcer cannon{.pulse_period = 1, .pulse_duration = 0.2};
  EXPECT_TRUE(cannon.active(0.1));
  EXPECT_FALSE(cannon.active(0.5));
  EXPECT_TRUE(cannon.active(3.05));
}

// ---------------------------------------------------------------------------------------
// emitters

TEST(Emitter, CountEqualsRateTimesTimeExactly) {
  for (double rate : {37.5, 100.0, 7.0, 1000.0 / 3}) {
    ParticleSystem ps = make_system(Method::SemiImplicitEuler);
    const auto id = ps.add_emitter({.rate = rate, .lifetime = 100});
    const double h = 1.0 / 60;
    const int steps = 180;  // T = 3 s
    for (int i = 0; i < steps; ++i) ps.step(i * h, h, {}, {});
    EXPECT_EQ(ps.emitted(id), static_cast<long long>(std::floor(rate * 3.0 + 1e-9))) << rate;
    EXPECT_EQ(ps.size(), static_cast<std::size_t>(ps.emitted(id)));
  }
}

TEST(Emitter, LifetimesAreRespectedAndDeadAreRecycled) {
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  const double h = 1.0 / 100, life = 0.5, rate = 200;
  ps.add_emitter({.rate = rate, .lifetime = life, .lifetime_jitter = 0.2});
  for (int i = 0; i < 300; ++i) {
    ps.step(i * h, h, {}, {});
    for (std::size_t k = 0; k < ps.size(); ++k) {
      ASSERT_LT(ps.age(k), ps.lifetime(k) + 1e-9);
      ASSERT_LE(ps.lifetime(k), life * 1.2 + 1e-9);
      ASSERT_GE(ps.lifetime(k), life * 0.8 - 1e-9);
    }
  }
  // steady state: about rate * mean lifetime alive (jitter is symmetric)
  EXPECT_NEAR(static_cast<double>(ps.size()), rate * life, rate * life * 0.15);
}

TEST(Emitter, ColourBlendsOverLife) {
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  ps.add_emitter({.rate = 10, .lifetime = 1, .start_color = pba::Color::rgb(1, 0, 0),
                  .end_color = pba::Color::rgb(0, 0, 1)});
  for (int i = 0; i < 60; ++i) ps.step(i / 60.0, 1 / 60.0, {}, {});
  for (std::size_t k = 0; k < ps.size(); ++k) {
    const float f = static_cast<float>(ps.age(k) / ps.lifetime(k));
    EXPECT_NEAR(ps.color(k).r, 1 - f, 0.01);
    EXPECT_NEAR(ps.color(k).b, f, 0.01);
  }
}

// ---------------------------------------------------------------------------------------
// handles

TEST(Handles, StaleParticleHandleIsRejected) {
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  const auto a = ps.create({.position = {1, 2, 3}});
  const auto b = ps.create({.position = {4, 5, 6}});
  ps.destroy(a);
  EXPECT_FALSE(ps.valid(a));
  EXPECT_TRUE(ps.valid(b));
  // b moved into a's array slot; its handle still finds it
  EXPECT_EQ(ps.position(b), Vec3(4, 5, 6));
  try {
    ps.position(a);
    FAIL() << "stale handle accepted";
  } catch (const pba::Error& e) {
    EXPECT_NE(std::string(e.what()).find("stale handle"), std::string::npos) << e.what();
  }
  // the slot is reused with the next generation
  const auto c = ps.create({});
  EXPECT_EQ(c.index, a.index);
  EXPECT_EQ(c.generation, a.generation + 1);
  EXPECT_FALSE(ps.valid(a));
  EXPECT_THROW(ps.destroy(a), pba::Error);
}

// ---------------------------------------------------------------------------------------
// bad input: a clear Error naming the value and where it came from

TEST(BadInput, ParticleDefinitions) {
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  auto message = [&](const ParticleDef& d) {
    try {
      ps.create(d, "balls[3]");
    } catch (const pba::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message({.mass = 0}), "balls[3].mass: must be finite and > 0, got 0");
  EXPECT_EQ(message({.mass = -1}), "balls[3].mass: must be finite and > 0, got -1");
  EXPECT_EQ(message({.mass = std::nan("")}), "balls[3].mass: must be finite and > 0, got nan");
  EXPECT_EQ(message({.radius = 0}), "balls[3].radius: must be finite and > 0, got 0");
  EXPECT_EQ(message({.radius = -0.5}), "balls[3].radius: must be finite and > 0, got -0.5");
  EXPECT_EQ(message({.position = {0, std::numeric_limits<double>::infinity(), 0}}),
            "balls[3].position: must be finite, got (0, inf, 0)");
  EXPECT_EQ(message({.velocity = {std::nan(""), 0, 0}}), "balls[3].velocity: must be finite, got (nan, 0, 0)");
  EXPECT_EQ(ps.size(), 0u);
}

TEST(BadInput, EmitterWithNegativeRate) {
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  try {
    ps.add_emitter({.rate = -5}, "sparks");
    FAIL();
  } catch (const pba::Error& e) {
    EXPECT_STREQ(e.what(), "sparks.rate: must be finite and >= 0, got -5");
  }
}

// A finite positive dt that rounds to 0 or inf in float, or whose square overflows one,
// passed ParticleSystem::step's check: the semi-implicit Euler kernel and position Verlet
// took it unchecked (1e-50 a silent no-op step), and implicit Euler's refusal was swallowed
// by the Newton fallback (a fallback step with dt 0 or inf, counted as a Newton failure).
// Every method refuses it now, naming dt and the range, with the state untouched.
TEST(BadInput, StepRefusesADtAFloatCannotHold) {
  for (Method m : pba::kAllMethods) {
    ParticleSystem ps = make_system(m);
    const auto a = ps.create({.position = {0, 1, 0}, .velocity = {1, 0, 0}});
    const std::uint64_t h0 = ps.hash();
    for (double dt : {1e-50, 1e-39, 1e20, 1e39, 1e300}) {
      std::string msg = "no error";
      try {
        ps.step(0, dt, {}, {});
      } catch (const pba::Error& e) {
        msg = e.what();
      }
      EXPECT_EQ(msg, "ParticleSystem::step(dt): must be in [1.1754943508222875e-38, 18446743523953729536] s (the "
                     "particles step in float, divide by it and square it), got " + pba::format_value(dt))
          << pba::name(m);
    }
    EXPECT_EQ(ps.hash(), h0) << pba::name(m);
    EXPECT_EQ(ps.steps(), 0) << pba::name(m);
    EXPECT_EQ(ps.newton_fallbacks(), 0) << pba::name(m);
    // an ordinary step is still taken
    ps.step(0, 1e-3, {}, {});
    EXPECT_EQ(ps.steps(), 1) << pba::name(m);
    EXPECT_GT(ps.position(a).x, 0.0) << pba::name(m);
  }
}

// Settings a caller changes between steps, and forcers handed to ParticleSystem::step
// directly (without a World, which validates its own), were used unchecked: a NaN
// restitution threshold made every impact bounce (NaN compares false: no resting contact,
// silently), a forcer with a NaN strength stopped the step naming a particle rather than
// the forcer, a sphere forcer of radius 0 or a zero rotation acted nowhere, silently, and an
// emitter turned by a zero quaternion emitted along its unturned axis (glm normalises it to
// the identity). Each is refused by name now, before the state changes.
TEST(BadInput, StepRefusesBadForcersThresholdAndEmitterRotation) {
  auto message = [](auto&& f) { return pba::test_support::error_of(f); };
  const double nan = std::nan("");
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  ps.create({.position = {0, 1, 0}});
  const std::uint64_t h0 = ps.hash();
  auto step_with = [&](const pba::Forcer& f) {
    return message([&] { ps.step(0, 0.01, {}, std::span<const pba::Forcer>(&f, 1)); });
  };
  pba::Forcer fan;
  EXPECT_EQ(step_with(fan), "");  // the default forcer is valid
  ps = make_system(Method::SemiImplicitEuler);
  ps.create({.position = {0, 1, 0}});
  fan.strength = nan;
  EXPECT_EQ(step_with(fan), "ParticleSystem::step forcers[0].strength: must be finite, got nan");
  pba::Forcer sphere{.shape = pba::ForcerShape::Sphere, .radius = 0};
  EXPECT_EQ(step_with(sphere), "ParticleSystem::step forcers[0].radius: must be finite and > 0, got 0");
  pba::Forcer turned{.pose = {{0, 0, 0}, {0, 0, 0, 0}}};
  EXPECT_EQ(step_with(turned),
            "ParticleSystem::step forcers[0].rotation: must be a finite unit quaternion, got (0, 0, 0, 0)");
  EXPECT_EQ(ps.hash(), h0);
  EXPECT_EQ(ps.steps(), 0);
  ps.collision().restitution_threshold = nan;
  EXPECT_EQ(message([&] { ps.step(0, 0.01, {}, {}); }),
            "ParticleSystem.collision.restitution_threshold: must be finite, got nan");
  ps.collision().restitution_threshold = std::numeric_limits<double>::infinity();
  EXPECT_EQ(message([&] { ps.step(0, 0.01, {}, {}); }),
            "ParticleSystem.collision.restitution_threshold: must be finite, got inf");
  EXPECT_EQ(ps.hash(), h0);
  ps.collision().restitution_threshold = -1;
  EXPECT_EQ(message([&] { ps.step(0, 0.01, {}, {}); }), "");
  // an emitter's rotation: at creation and when its pose is set between steps
  EXPECT_EQ(message([&] { ps.add_emitter({.pose = {{0, 0, 0}, {0, 0, 0, 0}}}, "sparks"); }),
            "sparks.rotation: must be a finite unit quaternion, got (0, 0, 0, 0)");
  const auto e = ps.add_emitter({}, "sparks");
  ps.set_emitter_pose(e, {{0, 0, 0}, {nan, 0, 0, 0}});
  EXPECT_EQ(message([&] { ps.step(0.01, 0.01, {}, {}); }),
            "emitter.rotation: must be a finite unit quaternion, got (nan, 0, 0, 0)");
}

TEST(BadInput, NonFiniteStateStopsWithParticleAndTime) {
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  ps.create({});
  // the fastest speed a particle may have (1e30 m/s is refused at creation now: its square
  // overflows the float drag, kMaxParticleSpeed), and a = -c |v| v / m overflows
  ps.create({.velocity = {pba::kMaxParticleSpeed, 0, 0}, .mass = 1e-30});
  ps.forces().quadratic_drag = 1;
  try {
    ps.step(0.5, 0.01, {}, {});
    FAIL();
  } catch (const pba::Error& e) {
    EXPECT_NE(std::string(e.what()).find("particle 1 became non-finite at t = 0.51 s (step 1)"),
              std::string::npos)
        << e.what();
  }
}

// ---------------------------------------------------------------------------------------
// the fused kernel and the generic integrator path give the same bits

// With uniform masses the kernel reads the inverse mass from one value instead of the
// column; the integrator path (accelerations()) always reads the column: same bits.
TEST(Determinism, FusedKernelEqualsIntegrator) {
  for (bool uniform : {false, true}) {
    pba::ParticleSystemDef def;
    def.capacity = 1000;
    def.forces.quadratic_drag = 0.02;
    def.forces.wind = {.velocity = {1, 0, 0.5}, .gust = 0.7, .gust_period = 0.3, .seed = 3};
    ParticleSystem ps(def);
    std::vector<pba::Vec3f> x, v;
    for (int i = 0; i < 777; ++i) {
      const ParticleDef d{.position = {i * 0.01, 1 + i * 0.003, -i * 0.02},
                          .velocity = {std::sin(i), std::cos(i) * 3, 0.1 * i},
                          .mass = uniform ? 0.3 : 0.05 + 0.001 * i,
                          .radius = 0.01};
      ps.create(d);
      x.emplace_back(static_cast<float>(d.position.x), static_cast<float>(d.position.y),
                     static_cast<float>(d.position.z));
      v.emplace_back(static_cast<float>(d.velocity.x), static_cast<float>(d.velocity.y),
                     static_cast<float>(d.velocity.z));
    }
    pba::Integrator<pba::Vec3f> integ(Method::SemiImplicitEuler);
    const double h = 1.0 / 90;
    for (int s = 0; s < 50; ++s) {
      const double t = s * h;
      ps.step(t, h, {}, {});
      integ.step(t, h, std::span<pba::Vec3f>(x), std::span<pba::Vec3f>(v),
                 [&](double tt, std::span<const pba::Vec3f> xx, std::span<const pba::Vec3f> vv,
                     std::span<pba::Vec3f> a) { ps.accelerations(tt, 0, xx, vv, a); });
    }
    for (std::size_t i = 0; i < x.size(); ++i) {
      ASSERT_EQ(ps.xs()[i], x[i].x) << i;
      ASSERT_EQ(ps.ys()[i], x[i].y) << i;
      ASSERT_EQ(ps.zs()[i], x[i].z) << i;
      ASSERT_EQ(ps.vxs()[i], v[i].x) << i;
      ASSERT_EQ(ps.vys()[i], v[i].y) << i;
      ASSERT_EQ(ps.vzs()[i], v[i].z) << i;
    }
  }
}

TEST(Determinism, SameInputSameHash) {
  auto run = [] {
    ParticleSystem ps = make_system(Method::SemiImplicitEuler);
    ps.forces().wind = {.velocity = {1, 0, 0}, .gust = 1, .gust_period = 0.2, .seed = 5};
    ps.forces().quadratic_drag = 0.001;
    ps.add_emitter({.rate = 500, .lifetime = 1, .seed = 42});
    const Collider c[2] = {Collider::plane({0, 1, 0}, -0.5, {.restitution = 0.5, .friction = 0.3}),
                           Collider::sphere({0, 2, 0}, 0.3, {.restitution = 0.7})};
    for (int i = 0; i < 300; ++i) ps.step(i / 120.0, 1 / 120.0, c, {});
    return ps.hash();
  };
  EXPECT_EQ(run(), run());
}

}  // namespace
