// The lab's standard problems with their closed-form solutions, and the special
// functions they need (complete elliptic integral, Jacobi elliptic functions).
#include <cmath>
#include <limits>
#include <numbers>

#include "pba/lab.h"

namespace pba::lab {

namespace {

[[noreturn]] void bad_field(const Problem& p, std::string_view field, std::string_view why) {
  throw Error("Problem '" + p.name + "'." + std::string(field) + ": " + std::string(why));
}

// an angular frequency the problems can form in double: omega^2 must be a normal double
// (below 1.5e-154 rad/s it underflows to 0 and the acceleration is silently 0), and at unit
// amplitude the energy v^2 + w2 x^2 reaches 2 w2 and the damped -w2 x - c v up to 3 w2 (c
// = 2 zeta omega): near sqrt(DBL_MAX) = 1.3e154 both overflowed. 1/8 of it (1.7e153) leaves
// 64 / 3 = 21x room for an integrator's growth over the lab's runs (explicit Euler's energy
// grows e-fold over the coarsest convergence run)
void require_omega(double omega, std::string_view where) {
  require_in_range(omega, std::sqrt(std::numeric_limits<double>::min()),
                   std::sqrt(std::numeric_limits<double>::max()) / 8, where);
}
}  // namespace

void Problem::validate() const {
  // every required field, named in the message
  if (name.empty()) throw Error("Problem.name: must not be empty");
  if (name.find(' ') != std::string::npos) bad_field(*this, "name", "must not contain spaces");
  if (x0.empty()) bad_field(*this, "x0", "needs at least one coordinate");
  if (v0.size() != x0.size())
    bad_field(*this, "v0", "has " + std::to_string(v0.size()) + " values but x0 has " +
                               std::to_string(x0.size()));
  for (double x : x0) require_finite(x, "Problem '" + name + "'.x0");
  for (double v : v0) require_finite(v, "Problem '" + name + "'.v0");
  require_positive(t_end, "Problem '" + name + "'.t_end");
  require_positive(dt_coarse, "Problem '" + name + "'.dt_coarse");
  require_positive(energy_dt, "Problem '" + name + "'.energy_dt");
  require_non_negative(omega, "Problem '" + name + "'.omega");
  require_non_negative(model_error, "Problem '" + name + "'.model_error");
  if (!accel) bad_field(*this, "accel", "must be set");
  if (dissipative && !(energy && exact))
    bad_field(*this, "dissipative", "needs both energy and exact to define the reference energy");
}

// Abramowitz & Stegun (1964) 17.6.1-17.6.4: K(m) = pi / (2 AGM(1, sqrt(1 - m))).
double elliptic_k(double m) {
  require_in_range(m, 0.0, 1.0 - 1e-16, "elliptic_k(m)");
  // arithmetic-geometric mean; converges quadratically
  double a = 1, b = std::sqrt(1 - m);
  for (int i = 0; i < 64 && std::abs(a - b) > 1e-16 * a; ++i) {
    const double an = (a + b) / 2;
    b = std::sqrt(a * b);
    a = an;
  }
  return kPi / (2 * a);
}

// Abramowitz & Stegun (1964) 16.4: descending Landen transformation (AGM scale), then
// back-substitution phi_{n-1} = (phi_n + asin(c_n sin(phi_n) / a_n)) / 2.
Jacobi jacobi_elliptic(double u, double m) {
  require_finite(u, "jacobi_elliptic(u)");
  require_in_range(m, 0.0, 1.0 - 1e-16, "jacobi_elliptic(m)");
  if (m < 1e-300) return {std::sin(u), std::cos(u), 1.0};
  // forward: the AGM sequence a_n, c_n
  double a[32], c[32];
  a[0] = 1;
  double b = std::sqrt(1 - m);
  c[0] = std::sqrt(m);
  int n = 0;
  while (n < 30 && std::abs(c[n]) > 1e-16) {
    a[n + 1] = (a[n] + b) / 2;
    c[n + 1] = (a[n] - b) / 2;
    b = std::sqrt(a[n] * b);
    ++n;
  }
  // backward: the amplitude phi_0 = am(u | m)
  double phi = std::ldexp(a[n] * u, n);
  double phi_prev = phi;
  for (int i = n; i > 0; --i) {
    phi_prev = phi;
    phi = (phi + std::asin(c[i] * std::sin(phi) / a[i])) / 2;
  }
  const double sn = std::sin(phi), cn = std::cos(phi);
  return {sn, cn, cn / std::cos(phi_prev - phi)};
}

double pendulum_period(double theta0, double omega0) {
  require_in_range(theta0, 1e-300, kPi - 1e-9, "pendulum_period(theta0)");
  require_positive(omega0, "pendulum_period(omega0)");
  const double k = std::sin(theta0 / 2);
  return 4 * elliptic_k(k * k) / omega0;
}

Problem projectile(double g) {
  require_positive(g, "projectile(g)");
  Problem p;
  p.name = "projectile";
  p.description = "projectile under gravity, no drag (exact: parabola)";
  p.x0 = {0, 0};
  p.v0 = {10, 10};
  p.t_end = 2;
  p.dt_coarse = 0.05;
  p.energy_dt = 0.001;
  p.accel = [g](double, std::span<const double>, std::span<const double>, std::span<double> a) {
    a[0] = 0;
    a[1] = -g;
  };
  p.exact = [g, x0 = p.x0, v0 = p.v0](double t, std::span<double> x, std::span<double> v) {
    x[0] = x0[0] + v0[0] * t;
    x[1] = x0[1] + v0[1] * t - g * t * t / 2;
    v[0] = v0[0];
    v[1] = v0[1] - g * t;
  };
  p.energy = [g](std::span<const double> x, std::span<const double> v) {
    return (v[0] * v[0] + v[1] * v[1]) / 2 + g * x[1];
  };
  return p;
}

Problem projectile_drag(double k, double g) {
  require_positive(k, "projectile_drag(k)");
  require_positive(g, "projectile_drag(g)");
  Problem p;
  p.name = "projectile-drag";
  p.description = "projectile with linear drag a = g - k v (exact: exponential approach)";
  p.x0 = {0, 0};
  p.v0 = {10, 10};
  p.t_end = 2;
  p.dt_coarse = 0.05;
  p.energy_dt = 0.001;
  p.omega = k;
  p.dissipative = true;
  p.accel = [g, k](double, std::span<const double>, std::span<const double> v, std::span<double> a) {
    a[0] = -k * v[0];
    a[1] = -g - k * v[1];
  };
  // v(t) = v_inf + (v0 - v_inf) e^{-kt}, x(t) = x0 + v_inf t + (v0 - v_inf)(1 - e^{-kt})/k
  p.exact = [g, k, x0 = p.x0, v0 = p.v0](double t, std::span<double> x, std::span<double> v) {
    const double vinf[2] = {0, -g / k};
    const double decay = std::exp(-k * t), one_minus = -std::expm1(-k * t);
    for (int i = 0; i < 2; ++i) {
      v[i] = vinf[i] + (v0[i] - vinf[i]) * decay;
      x[i] = x0[i] + vinf[i] * t + (v0[i] - vinf[i]) * one_minus / k;
    }
  };
  p.energy = [g](std::span<const double> x, std::span<const double> v) {
    return (v[0] * v[0] + v[1] * v[1]) / 2 + g * x[1];
  };
  return p;
}

Problem oscillator(double omega) {
  require_omega(omega, "oscillator(omega)");
  Problem p;
  p.name = "oscillator";
  p.description = "undamped harmonic oscillator x'' = -omega^2 x (exact: cosine)";
  p.x0 = {1};
  p.v0 = {0};
  p.t_end = 10 / omega;
  p.dt_coarse = 0.05 / omega;
  p.energy_dt = 0.01 / omega;
  p.omega = omega;
  const double w2 = omega * omega;
  p.accel = [w2](double, std::span<const double> x, std::span<const double>, std::span<double> a) {
    a[0] = -w2 * x[0];
  };
  p.exact = [omega](double t, std::span<double> x, std::span<double> v) {
    x[0] = std::cos(omega * t);
    v[0] = -omega * std::sin(omega * t);
  };
  p.energy = [w2](std::span<const double> x, std::span<const double> v) {
    return (v[0] * v[0] + w2 * x[0] * x[0]) / 2;
  };
  return p;
}

Problem damped_oscillator(double omega, double zeta) {
  require_omega(omega, "damped_oscillator(omega)");
  require_in_range(zeta, 1e-12, 1 - 1e-12, "damped_oscillator(zeta)");
  Problem p;
  p.name = "damped-oscillator";
  p.description = "underdamped oscillator x'' = -w^2 x - 2 zeta w x' (exact: decaying cosine)";
  p.x0 = {1};
  p.v0 = {0};
  p.t_end = 10 / omega;
  p.dt_coarse = 0.1 / omega;
  p.energy_dt = 0.01 / omega;
  p.omega = omega;
  p.dissipative = true;
  const double w2 = omega * omega, c = 2 * zeta * omega;
  p.accel = [w2, c](double, std::span<const double> x, std::span<const double> v, std::span<double> a) {
    a[0] = -w2 * x[0] - c * v[0];
  };
  // x = e^{-zeta w t}(cos wd t + (zeta w / wd) sin wd t), x' = -(w^2/wd) e^{-zeta w t} sin wd t
  const double wd = omega * std::sqrt(1 - zeta * zeta), sigma = zeta * omega;
  p.exact = [wd, sigma, w2](double t, std::span<double> x, std::span<double> v) {
    const double e = std::exp(-sigma * t), s = std::sin(wd * t), co = std::cos(wd * t);
    x[0] = e * (co + sigma / wd * s);
    v[0] = -w2 / wd * e * s;
  };
  p.energy = [w2](std::span<const double> x, std::span<const double> v) {
    return (v[0] * v[0] + w2 * x[0] * x[0]) / 2;
  };
  return p;
}

Problem pendulum(double theta0, bool small_angle, double g_over_l) {
  require_in_range(theta0, 1e-12, kPi - 1e-6, "pendulum(theta0)");
  require_positive(g_over_l, "pendulum(g_over_l)");
  const double w0 = std::sqrt(g_over_l);
  Problem p;
  p.name = small_angle ? "pendulum-small" : "pendulum-large";
  p.x0 = {theta0};
  p.v0 = {0};
  p.omega = w0;
  p.accel = [g_over_l](double, std::span<const double> x, std::span<const double>, std::span<double> a) {
    a[0] = -g_over_l * std::sin(x[0]);
  };
  p.energy = [g_over_l](std::span<const double> x, std::span<const double> v) {
    return v[0] * v[0] / 2 + g_over_l * (1 - std::cos(x[0]));
  };
  // exact at any amplitude (released from rest): sin(theta/2) = k sn(K - w0 t | k^2),
  // theta' = -2 k w0 cn(K - w0 t | k^2)
  const double k = std::sin(theta0 / 2), m = k * k, K = elliptic_k(m);
  auto elliptic = [k, m, K, w0](double t, std::span<double> x, std::span<double> v) {
    const Jacobi j = jacobi_elliptic(K - w0 * t, m);
    x[0] = 2 * std::asin(k * j.sn);
    v[0] = -2 * k * w0 * j.cn;
  };
  if (small_angle) {
    // small-angle closed form, valid while theta0^2/16 * w0 t is negligible; its own
    // error at t_end is measured against the elliptic solution and excluded from fits
    p.description = "pendulum at small amplitude vs the small-angle closed form";
    p.t_end = 2;
    p.dt_coarse = 0.05;
    p.energy_dt = 0.001;
    p.exact = [theta0, w0](double t, std::span<double> x, std::span<double> v) {
      x[0] = theta0 * std::cos(w0 * t);
      v[0] = -theta0 * w0 * std::sin(w0 * t);
    };
    double xs[1], vs[1], xe[1], ve[1];
    p.exact(p.t_end, xs, vs);
    elliptic(p.t_end, xe, ve);
    p.model_error = std::abs(xs[0] - xe[0]);
  } else {
    p.description = "pendulum at large amplitude (exact: Jacobi elliptic functions)";
    p.t_end = 3;
    p.dt_coarse = 0.02;
    p.energy_dt = 0.001;
    p.exact = elliptic;
  }
  return p;
}

Problem kepler(double e) {
  require_in_range(e, 0.0, 0.9, "kepler(e)");
  Problem p;
  p.name = e == 0 ? "orbit-circular" : "orbit";
  p.description = e == 0 ? "circular Kepler orbit (exact: uniform circle)"
                         : "Kepler orbit, e = " + format_value(e) + " (exact: Kepler's equation)";
  // periapsis on +x, moving +y; GM = 1, a = 1, so the period is 2 pi and mean motion 1
  p.x0 = {1 - e, 0};
  p.v0 = {0, std::sqrt((1 + e) / (1 - e))};
  p.t_end = 5;  // not a whole period: there symplectic Euler's O(dt) error cancels
  p.dt_coarse = 2 * kPi / 200;
  p.energy_dt = 2 * kPi / 1000;
  p.omega = 1;
  p.accel = [](double, std::span<const double> x, std::span<const double>, std::span<double> a) {
    const double r2 = x[0] * x[0] + x[1] * x[1];
    const double inv_r3 = 1 / (r2 * std::sqrt(r2));
    a[0] = -x[0] * inv_r3;
    a[1] = -x[1] * inv_r3;
  };
  // Kepler's equation E - e sin E = M (M = t) by Newton, then the ellipse in E
  p.exact = [e](double t, std::span<double> x, std::span<double> v) {
    const double M = std::remainder(t, 2 * kPi);
    double E = e < 0.8 ? M : (M < 0 ? -kPi : kPi);
    for (int i = 0; i < 50; ++i) {
      const double dE = (E - e * std::sin(E) - M) / (1 - e * std::cos(E));
      E -= dE;
      if (std::abs(dE) < 1e-16) break;
    }
    const double b = std::sqrt(1 - e * e), c = std::cos(E), s = std::sin(E), d = 1 - e * c;
    x[0] = c - e;
    x[1] = b * s;
    v[0] = -s / d;
    v[1] = b * c / d;
  };
  p.energy = [](std::span<const double> x, std::span<const double> v) {
    return (v[0] * v[0] + v[1] * v[1]) / 2 - 1 / std::sqrt(x[0] * x[0] + x[1] * x[1]);
  };
  p.invariant = [](std::span<const double> x, std::span<const double> v) {
    return x[0] * v[1] - x[1] * v[0];
  };
  p.invariant_name = "angular momentum";
  return p;
}

std::vector<Problem> standard_problems() {
  std::vector<Problem> ps;
  ps.push_back(projectile());
  ps.push_back(projectile_drag());
  ps.push_back(oscillator());
  ps.push_back(damped_oscillator());
  ps.push_back(pendulum(0.001, true));
  ps.push_back(pendulum(2.5, false));
  ps.push_back(kepler(0.5));
  ps.push_back(kepler(0.0));
  return ps;
}

const Problem& find_problem(const std::vector<Problem>& problems, std::string_view name,
                            std::string_view where) {
  // exact match; the error lists every registered name
  std::string names;
  for (const auto& p : problems) {
    if (p.name == name) return p;
    names += (names.empty() ? "" : ", ") + p.name;
  }
  throw Error(std::string(where) + ": unknown problem '" + std::string(name) + "'; valid names: " +
              names);
}

}  // namespace pba::lab
