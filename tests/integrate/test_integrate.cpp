// Tests for pba/integrate.h: names and parsing, bad input, the energy behaviour each
// method must show on the harmonic oscillator over 10^6 steps (against closed forms for
// the amplification per step), exactness under constant acceleration, conservation of
// angular momentum on an orbit, implicit Euler's Newton solve, and determinism.
#include <gtest/gtest.h>

#include "error_of.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "pba/integrate.h"

namespace {

using pba::Method;
constexpr double kEps = std::numeric_limits<double>::epsilon();

using pba::test_support::error_of;

// x'' = -omega^2 x for one coordinate, as an array function
struct Spring {
  double w2 = 1;
  void operator()(double, std::span<const double> x, std::span<const double>, std::span<double> a) const {
    for (std::size_t i = 0; i < x.size(); ++i) a[i] = -w2 * x[i];
  }
};

TEST(Methods, NamesOrdersAndParsing) {
  const char* names[] = {"euler", "semi-implicit-euler", "verlet", "velocity-verlet", "rk4", "implicit-euler"};
  const int orders[] = {1, 1, 2, 2, 4, 1};
  for (std::size_t i = 0; i < pba::kAllMethods.size(); ++i) {
    const Method m = pba::kAllMethods[i];
    EXPECT_EQ(pba::name(m), names[i]);
    EXPECT_EQ(pba::order(m), orders[i]);
    EXPECT_FALSE(pba::label(m).empty());
    EXPECT_EQ(pba::parse_method(names[i], "test"), m);
  }
  EXPECT_TRUE(pba::is_symplectic(Method::PositionVerlet));
  EXPECT_FALSE(pba::is_symplectic(Method::Rk4));
}

TEST(Methods, UnknownNameListsValidNames) {
  const std::string msg = error_of([] { pba::parse_method("rk5", "--method"); });
  EXPECT_EQ(msg,
            "--method: unknown integrator 'rk5'; valid names: euler, semi-implicit-euler, verlet, "
            "velocity-verlet, rk4, implicit-euler");
  EXPECT_NE(error_of([] { pba::parse_method("RK4", "scene.json integrator"); }).find("scene.json integrator"),
            std::string::npos);
}

TEST(BadInput, StepRejectsBadDtNamingValueAndArgument) {
  for (Method m : pba::kAllMethods) {
    pba::Integrator<double> integ(m);
    double x = 1, v = 0;
    auto f = [](double, double x, double) { return -x; };
    EXPECT_EQ(error_of([&] { integ.step_one(0, 0.0, x, v, f); }),
              "Integrator::step(dt): must be finite and > 0, got 0");
    EXPECT_EQ(error_of([&] { integ.step_one(0, -1.0, x, v, f); }),
              "Integrator::step(dt): must be finite and > 0, got -1");
    EXPECT_EQ(error_of([&] { integ.step_one(0, std::nan(""), x, v, f); }),
              "Integrator::step(dt): must be finite and > 0, got nan");
    EXPECT_EQ(error_of([&] { integ.step_one(0, std::numeric_limits<double>::infinity(), x, v, f); }),
              "Integrator::step(dt): must be finite and > 0, got inf");
    // the state is untouched by a rejected step
    EXPECT_EQ(x, 1.0);
    EXPECT_EQ(v, 0.0);
  }
}

TEST(BadInput, StepRejectsADtItsPrecisionCannotHold) {
  // a finite positive dt that rounds to 0 or inf in float, or whose square overflows (or a
  // subnormal one in double, whose inverse overflows) gave NaN or a silent no-op step; it is
  // refused, the state untouched
  auto f = [](double, const auto& x, const auto&) { return -x; };
  for (Method m : pba::kAllMethods) {
    pba::Integrator<pba::Vec3f> fi(m);
    pba::Vec3f x(1, 0, 0), v(0, 0, 0);
    for (double dt : {1e300, 1e39, 1e20, 1e-50, 1e-39}) {
      const std::string msg = error_of([&] { fi.step_one(0, dt, x, v, f); });
      EXPECT_EQ(msg, "Integrator::step(dt): must be in [1.1754943508222875e-38, 18446743523953729536] s for an "
                     "integrator of float vectors (the step is used in that precision, divided by and squared), got " +
                         pba::format_value(dt))
          << pba::name(m);
    }
    EXPECT_EQ(x, pba::Vec3f(1, 0, 0));
    EXPECT_EQ(v, pba::Vec3f(0, 0, 0));
    pba::Integrator<double> di(m);
    double xd = 1, vd = 0;
    for (double dt : {1e-320, 1e155})
      EXPECT_NE(error_of([&] { di.step_one(0, dt, xd, vd, f); }).find("double vectors (the step is used in that "
                                                                      "precision, divided by and squared), got " +
                                                                      pba::format_value(dt)),
                std::string::npos);
    EXPECT_EQ(xd, 1.0);
    EXPECT_EQ(vd, 0.0);
    // the ends of the float range step and stay finite (the largest with a force-free object,
    // which the Verlets move by a dt^2 of 3.4e38 times a zero acceleration)
    fi.step_one(0, std::numeric_limits<float>::min(), x, v, f);
    EXPECT_TRUE(pba::is_finite(x) && pba::is_finite(v)) << pba::name(m);
    pba::Vec3f xf(1, 0, 0), vf(0, 0, 0);
    fi.reset_history();
    fi.step_one(0, 1.8e19, xf, vf, [](double, const pba::Vec3f&, const pba::Vec3f&) { return pba::Vec3f(0); });
    EXPECT_EQ(xf, pba::Vec3f(1, 0, 0)) << pba::name(m);
  }
}

TEST(BadInput, MismatchedSizesAndSettings) {
  pba::Integrator<pba::Vec3> integ(Method::Rk4);
  std::vector<pba::Vec3> x(3), v(2);
  auto f = [](double, std::span<const pba::Vec3>, std::span<const pba::Vec3>, std::span<pba::Vec3>) {};
  EXPECT_EQ(error_of([&] { integ.step(0, 0.01, std::span<pba::Vec3>(x), std::span<pba::Vec3>(v), f); }),
            "Integrator::step: x has 3 elements but v has 2; they must be the same size");
  pba::NewtonSettings s;
  s.tolerance = -1;
  EXPECT_EQ(error_of([&] { integ.set_newton(s); }), "NewtonSettings.tolerance: must be in [1e-16, 0.01], got -1");
  s = {};
  s.max_iterations = 0;
  EXPECT_EQ(error_of([&] { integ.set_newton(s); }), "NewtonSettings.max_iterations: must be an integer in [1, 100], got 0");
}

TEST(BadInput, ImplicitEulerRefusesHugeDenseSystems) {
  // a 4-object Vec3 system has 12 unknowns; with a limit of 10 it must refuse, not allocate
  pba::NewtonSettings s;
  s.max_unknowns = 10;
  pba::Integrator<pba::Vec3> integ(Method::ImplicitEuler, s);
  std::vector<pba::Vec3> x(4), v(4);
  auto f = [](double, std::span<const pba::Vec3>, std::span<const pba::Vec3>, std::span<pba::Vec3> a) {
    for (auto& ai : a) ai = pba::Vec3(0, -9.81, 0);
  };
  const std::string msg = error_of([&] { integ.step(0, 0.01, std::span<pba::Vec3>(x), std::span<pba::Vec3>(v), f); });
  EXPECT_NE(msg.find("4 objects x 3 components = 12 unknowns exceeds NewtonSettings.max_unknowns = 10"),
            std::string::npos)
      << msg;
}

// ---- energy over 10^6 steps on x'' = -x at omega dt = z -----------------------------

constexpr double kZ = 0.01;
constexpr long long kSteps = 1000000;

struct EnergyRun {
  std::vector<double> energy;  // every 100th step, E/E0
  double max_dev = 0;          // max |E/E0 - 1| over every step
  bool monotonic_up = true, monotonic_down = true;
  double final_ratio = 1;
  double trend = 0;  // least-squares slope of E/E0 against step, times the step count
};

EnergyRun run_energy(Method m) {
  pba::Integrator<double> integ(m);
  double x = 1, v = 0;
  const double e0 = 0.5;
  double prev = e0;
  EnergyRun r;
  // accumulate a regression of E/E0 - 1 on the step index as we go
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (long long k = 0; k < kSteps; ++k) {
    integ.step(static_cast<double>(k) * kZ, kZ, std::span<double>(&x, 1), std::span<double>(&v, 1), Spring{});
    const double e = (v * v + x * x) / 2;
    r.monotonic_up = r.monotonic_up && e > prev;
    r.monotonic_down = r.monotonic_down && e < prev;
    prev = e;
    const double dev = e / e0 - 1;
    r.max_dev = std::max(r.max_dev, std::abs(dev));
    const double s = static_cast<double>(k + 1) / kSteps;
    sx += s;
    sy += dev;
    sxx += s * s;
    sxy += s * dev;
  }
  r.final_ratio = prev / e0;
  const double n = kSteps;
  r.trend = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  return r;
}

TEST(Energy, ExplicitEulerGrowsByOnePlusZSquaredEveryStep) {
  // amplification matrix [[1, z], [-z, 1]] scales x^2 + v^2 by exactly 1 + z^2 per step
  const EnergyRun r = run_energy(Method::ExplicitEuler);
  EXPECT_TRUE(r.monotonic_up);
  const double expected_log = kSteps * std::log1p(kZ * kZ);  // ~100: E grows by e^100
  // n steps of rounding, a few eps each, bound the difference in log(E)
  EXPECT_NEAR(std::log(r.final_ratio), expected_log, kSteps * 4 * kEps);
  EXPECT_GT(r.final_ratio, 1e40);
}

TEST(Energy, SemiImplicitEulerStaysInItsOrderZBand) {
  // symplectic Euler conserves H~ = v^2 + x^2 - z x v exactly (Hairer, Lubich & Wanner
  // 2006, I.1.2); since |x v| <= E and E0 = H~0/2 (v0 = 0), E/E0 lies in
  // [1/(1 + z/2), 1/(1 - z/2)]: a band of half-width (z/2)/(1 - z/2), O(omega dt)
  const EnergyRun r = run_energy(Method::SemiImplicitEuler);
  const double band = (kZ / 2) / (1 - kZ / 2);
  EXPECT_LE(r.max_dev, band + 1e-12);
  EXPECT_GT(r.max_dev, 0.9 * band);  // the band is really explored: the error is O(z), not smaller
  // no secular trend: the best-fit drift over the run is a tiny fraction of the band
  EXPECT_LT(std::abs(r.trend), 0.01 * band);
}

TEST(Energy, VerletsStayInTheirOrderZSquaredBand) {
  // Verlet conserves H~ = v^2 + x^2 (1 - z^2/4); so E/E0 in [1 - z^2/4, 1/(1 - z^2/4)]
  const double band = (kZ * kZ / 4) / (1 - kZ * kZ / 4);
  for (Method m : {Method::PositionVerlet, Method::VelocityVerlet}) {
    SCOPED_TRACE(std::string(pba::name(m)));
    const EnergyRun r = run_energy(m);
    EXPECT_LE(r.max_dev, band + 1e-12);
    EXPECT_GT(r.max_dev, 0.9 * band);
    EXPECT_LT(std::abs(r.trend), 0.01 * band);
  }
}

TEST(Energy, RK4DecaysSlowlyAtItsAmplificationFactor) {
  // |R(iz)|^2 = 1 - z^6/72 + z^8/576 for classical RK4: a monotonic, tiny decay
  const EnergyRun r = run_energy(Method::Rk4);
  EXPECT_TRUE(r.monotonic_down);
  const double z2 = kZ * kZ;
  const double per_step = 1 - z2 * z2 * z2 / 72 + z2 * z2 * z2 * z2 / 576;
  const double expected_log = kSteps * std::log(per_step);  // ~ -1.39e-8
  EXPECT_NEAR(std::log(r.final_ratio), expected_log, kSteps * 4 * kEps);
  EXPECT_LT(1 - r.final_ratio, 2e-8);  // slow: after 10^6 steps still within 2e-8
}

TEST(Energy, ImplicitEulerDecaysByOnePlusZSquaredEveryStep) {
  // amplification [[1, z], [-z, 1]]^-1: x^2 + v^2 shrinks by exactly 1/(1 + z^2) per step
  const EnergyRun r = run_energy(Method::ImplicitEuler);
  EXPECT_TRUE(r.monotonic_down);
  EXPECT_NEAR(std::log(r.final_ratio), -kSteps * std::log1p(kZ * kZ), kSteps * 4 * kEps);
}

// ---- constant acceleration: the second-order methods and RK4 are exact --------------

TEST(Projectile, SecondOrderMethodsAndRK4AreExactUnderConstantAcceleration) {
  // with constant a the solution is the quadratic x0 + v0 t + a t^2/2. Velocity Verlet's
  // x update is exactly that Taylor polynomial and its trapezoid velocity update is exact
  // for constant a; RK4's weighted sum reduces to the same polynomial; position Verlet's
  // second-order start x_{-1} = x0 - v0 dt + a dt^2/2 and second difference are exact for
  // quadratics. Only rounding remains: about eps |x| per step for the one-step methods,
  // growing like n^2 eps |x| for position Verlet's two-step recurrence.
  const pba::Vec3 g(0, -9.81, 0), x0(1, 2, 3), v0(3, 10, -2);
  const double dt = 0.01;
  const int n = 200;
  auto accel = [g](double, const pba::Vec3&, const pba::Vec3&) { return g; };
  for (Method m : {Method::PositionVerlet, Method::VelocityVerlet, Method::Rk4}) {
    SCOPED_TRACE(std::string(pba::name(m)));
    pba::Integrator<pba::Vec3> integ(m);
    pba::Vec3 x = x0, v = v0;
    for (int k = 0; k < n; ++k) integ.step_one(k * dt, dt, x, v, accel);
    const double t = n * dt;
    const pba::Vec3 xe = x0 + v0 * t + g * (t * t / 2), ve = v0 + g * t;
    const double scale = 25;  // max |x| and |v| over the flight
    const double steps = m == Method::PositionVerlet ? double(n) * n : double(n);
    EXPECT_LE(glm::length(x - xe), 8 * steps * kEps * scale);
    EXPECT_LE(glm::length(v - ve), 8 * steps * kEps * scale / (m == Method::PositionVerlet ? n * dt : 1));
  }
}

TEST(Projectile, ExplicitEulerIsOffByExactlyHalfGTDt) {
  // Euler's x_n = x0 + v0 t - g dt^2 n(n-1)/2, so it lags the parabola by g t dt / 2:
  // first order, not round-off
  const double g = 9.81, dt = 0.01;
  const int n = 200;
  pba::Integrator<double> integ(Method::ExplicitEuler);
  double y = 0, vy = 10;
  for (int k = 0; k < n; ++k) integ.step_one(k * dt, dt, y, vy, [g](double, double, double) { return -g; });
  const double t = n * dt;
  EXPECT_NEAR(y - (10 * t - g * t * t / 2), g * t * dt / 2, 1e-12);
}

// ---- orbit: angular momentum and energy -------------------------------------------

struct Gravity {
  void operator()(double, std::span<const pba::Vec2> x, std::span<const pba::Vec2>, std::span<pba::Vec2> a) const {
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double r = glm::length(x[i]);
      a[i] = -x[i] / (r * r * r);
    }
  }
};

struct OrbitRun {
  double max_dl = 0, max_de_first = 0, max_de_last = 0, max_de = 0;
};

OrbitRun run_orbit(Method m, double dt, long long steps) {
  // Kepler orbit with e = 0.5 from periapsis (GM = 1, a = 1): E = -1/2, L = sqrt(3)/2
  pba::Integrator<pba::Vec2> integ(m);
  std::vector<pba::Vec2> x{{0.5, 0}}, v{{0, std::sqrt(3.0)}};
  const double l0 = x[0].x * v[0].y - x[0].y * v[0].x, e0 = -0.5;
  OrbitRun r;
  for (long long k = 0; k < steps; ++k) {
    integ.step(k * dt, dt, std::span<pba::Vec2>(x), std::span<pba::Vec2>(v), Gravity{});
    const double l = x[0].x * v[0].y - x[0].y * v[0].x;
    const double e = glm::dot(v[0], v[0]) / 2 - 1 / glm::length(x[0]);
    const double de = std::abs(e - e0) / 0.5;
    r.max_dl = std::max(r.max_dl, std::abs(l - l0));
    r.max_de = std::max(r.max_de, de);
    if (k < steps / 10) r.max_de_first = std::max(r.max_de_first, de);
    if (k >= steps - steps / 10) r.max_de_last = std::max(r.max_de_last, de);
  }
  return r;
}

TEST(Orbit, SymplecticMethodsConserveAngularMomentumToRoundOff) {
  // a central force exerts no torque: x x a = 0, and each symplectic update (kick along a,
  // drift along v) preserves x x v exactly in exact arithmetic; only rounding (a couple of
  // eps per step, at most linear accumulation) remains
  const double dt = 2 * std::numbers::pi / 1000;
  const long long steps = 100000;  // 100 orbits
  const double bound = steps * 2 * kEps * std::sqrt(3.0) / 2;
  for (Method m : {Method::SemiImplicitEuler, Method::PositionVerlet, Method::VelocityVerlet}) {
    SCOPED_TRACE(std::string(pba::name(m)));
    const OrbitRun r = run_orbit(m, dt, steps);
    EXPECT_LE(r.max_dl, bound);
  }
  // RK4 is not symplectic: its angular momentum error is truncation, far above round-off
  EXPECT_GT(run_orbit(Method::Rk4, dt, steps).max_dl, 20 * bound);
}

TEST(Orbit, SymplecticEnergyErrorIsBoundedAndScalesWithOrder) {
  // bounded: the last tenth of 100 orbits is no worse than the first tenth (no drift);
  // order: halving dt divides the bound by 2^p (p = 1 for Euler, 2 for Verlet)
  const double dt = 2 * std::numbers::pi / 1000;
  for (Method m : {Method::SemiImplicitEuler, Method::PositionVerlet, Method::VelocityVerlet}) {
    SCOPED_TRACE(std::string(pba::name(m)));
    const OrbitRun a = run_orbit(m, dt, 100000), b = run_orbit(m, dt / 2, 200000);
    EXPECT_LE(a.max_de_last, 1.1 * a.max_de_first);
    const double ratio = a.max_de / b.max_de, expect = std::pow(2.0, pba::order(m));
    EXPECT_GT(ratio, 0.8 * expect);
    EXPECT_LT(ratio, 1.25 * expect);
  }
}

// ---- implicit Euler's Newton solve --------------------------------------------------

TEST(ImplicitEuler, ConvergesToRoundOffOnLinearProblems) {
  // backward Euler on x'' = -w^2 x - c x' is linear: v1 = (v0 - h w^2 x0) / (1 + h c + h^2 w^2)
  const double w2 = 50, c = 3, h = 0.1, x0 = 0.7, v0 = -1.3;
  auto f = [&](double, double x, double v) { return -w2 * x - c * v; };
  const double v1 = (v0 - h * w2 * x0) / (1 + h * c + h * h * w2), x1 = x0 + h * v1;
  // finite-difference Jacobian: one Newton iteration leaves ~1e-8 relative, the second
  // round-off, the third confirms
  pba::Integrator<double> fd(Method::ImplicitEuler);
  double x = x0, v = v0;
  fd.step_one(0, h, x, v, f);
  EXPECT_NEAR(v, v1, 4 * kEps * std::abs(v1));
  EXPECT_NEAR(x, x1, 4 * kEps * std::abs(x1));
  EXPECT_LE(fd.last_newton().iterations, 3);
  // exact Jacobian: Newton is exact in one iteration, the second confirms
  pba::Integrator<double> an(Method::ImplicitEuler);
  an.set_jacobian([&](double, std::span<const double>, std::span<const double>, std::span<double> dadx,
                      std::span<double> dadv) {
    dadx[0] = -w2;
    dadv[0] = -c;
  });
  x = x0;
  v = v0;
  an.step_one(0, h, x, v, f);
  EXPECT_NEAR(v, v1, 4 * kEps * std::abs(v1));
  EXPECT_EQ(an.last_newton().iterations, 2);
}

TEST(ImplicitEuler, StableAtHugeStepsOnAStiffSpring) {
  // omega dt = 1000: explicit methods explode, backward Euler just damps
  pba::Integrator<pba::Vec3> integ(Method::ImplicitEuler);
  pba::Vec3 x(1, 0, 0), v(0, 0, 0);
  for (int k = 0; k < 100; ++k) integ.step_one(k * 1.0, 1.0, x, v, [](double, const pba::Vec3& x, const pba::Vec3&) {
    return -1e6 * x;
  });
  EXPECT_LT(glm::length(x), 1e-10);
  EXPECT_TRUE(pba::is_finite(v));
}

TEST(ImplicitEuler, ReportsNonConvergence) {
  pba::NewtonSettings s;
  s.max_iterations = 1;
  pba::Integrator<double> integ(Method::ImplicitEuler, s);
  double x = 1, v = 0;
  const std::string msg = error_of([&] { integ.step_one(0, 0.1, x, v, [](double, double x, double) { return -x; }); });
  EXPECT_NE(msg.find("implicit Euler: Newton did not converge in 1 iterations at t = 0 s, dt = 0.1 s"),
            std::string::npos)
      << msg;
}

// ---- position Verlet history ---------------------------------------------------------

TEST(PositionVerlet, ChangingDtOrResettingRestartsHistoryFromXAndV) {
  auto f = [](double, double x, double v) { return -x - 0.1 * v; };
  pba::Integrator<double> a(Method::PositionVerlet);
  double x = 1, v = 0;
  for (int k = 0; k < 10; ++k) a.step_one(k * 0.01, 0.01, x, v, f);
  // a new dt must behave exactly like a fresh integrator started from the current state
  pba::Integrator<double> fresh(Method::PositionVerlet);
  double xf = x, vf = v;
  a.step_one(0.1, 0.02, x, v, f);
  fresh.step_one(0.1, 0.02, xf, vf, f);
  EXPECT_EQ(x, xf);
  EXPECT_EQ(v, vf);
  // a teleport without reset_history would carry the old velocity in x - x_prev
  x = 5;
  v = 0;
  a.reset_history();
  xf = 5;
  vf = 0;
  pba::Integrator<double> fresh2(Method::PositionVerlet);
  a.step_one(0.2, 0.02, x, v, f);
  fresh2.step_one(0.2, 0.02, xf, vf, f);
  EXPECT_EQ(x, xf);
  EXPECT_EQ(v, vf);
}

TEST(PositionVerlet, FirstStepMatchesVelocityVerlet) {
  // with x_{-1} = x0 - v0 dt + a0 dt^2/2, the first step is velocity Verlet's, and the
  // velocity estimate (x1 - x0)/dt + a1 dt/2 is velocity Verlet's velocity
  auto f = [](double, double x, double) { return -4 * x; };
  pba::Integrator<double> p(Method::PositionVerlet), q(Method::VelocityVerlet);
  double xp = 1, vp = 0.5, xq = 1, vq = 0.5;
  p.step_one(0, 0.05, xp, vp, f);
  q.step_one(0, 0.05, xq, vq, f);
  EXPECT_NEAR(xp, xq, 4 * kEps);
  EXPECT_NEAR(vp, vq, 16 * kEps / 0.05);
}

// ---- determinism --------------------------------------------------------------------

// a spring to the origin, linear drag and gravity: position- and velocity-dependent
struct SpringDragGravity {
  template <class V>
  void operator()(double, std::span<const V> x, std::span<const V> v, std::span<V> a) const {
    using S = typename V::value_type;
    for (std::size_t i = 0; i < x.size(); ++i) a[i] = x[i] * S(-20) - v[i] * S(0.3) + V(0, -9.81, 0);
  }
};

template <class V>
std::uint64_t run_hash(Method m, std::size_t n, int steps) {
  pba::Integrator<V> integ(m);
  std::vector<V> x(n, V(0.3, 1.2, -0.4)), v(n, V(1.0, 0.5, 0.25));
  for (int k = 0; k < steps; ++k) integ.step(k * 0.01, 0.01, std::span<V>(x), std::span<V>(v), SpringDragGravity{});
  // hash the first object only, so arrays of different length compare
  return pba::hash_span(std::span<const V>(x.data(), 1), pba::hash_span(std::span<const V>(v.data(), 1)));
}

TEST(Determinism, SameInputsSameBitsAndArraysMatchOneObject) {
  for (Method m : pba::kAllMethods) {
    SCOPED_TRACE(std::string(pba::name(m)));
    const auto one = run_hash<pba::Vec3>(m, 1, 300);
    EXPECT_EQ(one, run_hash<pba::Vec3>(m, 1, 300));
    // N identical objects stepped together end in exactly the single object's bits
    EXPECT_EQ(one, run_hash<pba::Vec3>(m, 8, 300));
    EXPECT_EQ(run_hash<pba::Vec3f>(m, 1, 300), run_hash<pba::Vec3f>(m, 8, 300));
  }
}

TEST(Determinism, StepOneMatchesStepOnASpanOfOne) {
  for (Method m : pba::kAllMethods) {
    pba::Integrator<pba::Vec3> a(m), b(m);
    pba::Vec3 xa(1, 2, 3), va(0, 1, 0);
    std::vector<pba::Vec3> xb{xa}, vb{va};
    for (int k = 0; k < 50; ++k) {
      a.step_one(k * 0.01, 0.01, xa, va, [](double, const pba::Vec3& x, const pba::Vec3& v) {
        return -5.0 * x - 0.2 * v;
      });
      b.step(k * 0.01, 0.01, std::span<pba::Vec3>(xb), std::span<pba::Vec3>(vb),
             [](double, std::span<const pba::Vec3> x, std::span<const pba::Vec3> v, std::span<pba::Vec3> acc) {
               acc[0] = -5.0 * x[0] - 0.2 * v[0];
             });
    }
    EXPECT_EQ(pba::hash_span(std::span<const pba::Vec3>(&xa, 1)), pba::hash_span(std::span<const pba::Vec3>(xb)));
  }
}

TEST(Types, FloatAndTypeErasedAccelAgreeWithDouble) {
  // glm::vec3 (float) state tracks the double result to float precision; a std::function
  // accel gives the same bits as a lambda
  pba::AccelFn<pba::Vec3f> erased = SpringDragGravity{};
  pba::Integrator<pba::Vec3f> f1(Method::Rk4), f2(Method::Rk4);
  pba::Integrator<pba::Vec3> d(Method::Rk4);
  std::vector<pba::Vec3f> x1{{0.3f, 1.2f, -0.4f}}, v1{{1, 0.5f, 0.25f}}, x2 = x1, v2 = v1;
  std::vector<pba::Vec3> xd{{0.3, 1.2, -0.4}}, vd{{1, 0.5, 0.25}};
  for (int k = 0; k < 100; ++k) {
    f1.step(k * 0.01, 0.01, std::span<pba::Vec3f>(x1), std::span<pba::Vec3f>(v1), erased);
    f2.step(k * 0.01, 0.01, std::span<pba::Vec3f>(x2), std::span<pba::Vec3f>(v2), SpringDragGravity{});
    d.step(k * 0.01, 0.01, std::span<pba::Vec3>(xd), std::span<pba::Vec3>(vd), SpringDragGravity{});
  }
  EXPECT_EQ(pba::hash_span(std::span<const pba::Vec3f>(x1)), pba::hash_span(std::span<const pba::Vec3f>(x2)));
  EXPECT_LT(glm::length(pba::Vec3(x1[0]) - xd[0]), 1e-5);
  EXPECT_EQ(f1.evaluations(), 400);
}

}  // namespace
