// The lab's measurements: convergence order, long-run energy error, stability limit;
// the whole-lab driver, CSV output and the summary table.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "pba/lab.h"

namespace pba::lab {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// The error below which a point is round-off or model error, not truncation: a fixed
// floor, the rounding accumulated over n steps with a margin, and 10x the closed form's
// own error. How rounding accumulates depends on what the method carries from step to
// step; each step rounds the state it stores by ~eps |x| (and ~eps |v|):
// - one-step methods carry (x, v): a rounding of x is carried along by the flow, one of v
//   moves x by (t_end - t_k) eps |v| <~ eps scale; n independent roundings walk to
//   sqrt(n) eps scale, floored with a 100x margin;
// - position Verlet carries (x_n, x_{n-1}), its velocity being their difference / dt. The
//   error recurrence e_{k+1} = 2 e_k - e_{k-1} + r_k turns a rounding r_k of the newest
//   position into a velocity error r_k / dt, which reaches t_end as (n - k) r_k: each
//   rounding is integrated twice, and n of them walk to
//   eps scale sqrt(sum_k (n - k)^2) = eps scale sqrt(n (n + 1) (2n + 1) / 6) ~ n^(3/2) / sqrt(3).
//   On the projectile, where position Verlet is exact and this is its whole error, the
//   walk's factor is 0.2 to 1.4 (n = 40 .. 20480). The margin is 10x: at 100x the floor
//   would reach the truncation error of the finest step sizes of problems with a true
//   order (the drag projectile's at n = 5120 is 18x the walk).
double error_floor(Method m, long long steps, double scale, double model_error, const ConvergenceSettings& s) {
  const double eps = std::numeric_limits<double>::epsilon();
  const double n = static_cast<double>(steps);
  const double walk = m == Method::PositionVerlet ? 10 * std::sqrt(n * (n + 1) * (2 * n + 1) / 6)
                                                  : 100 * std::sqrt(n);
  return std::max({s.roundoff_floor * scale, walk * eps * scale, 10 * model_error});
}

// The notes measure_convergence gives a NaN order; the tables show them as one word.
constexpr std::string_view kNoteExact = "error at round-off for every dt (exact for this problem)";
constexpr std::string_view kNoteModel = "error below the closed form's own model error (or round-off)";
constexpr std::string_view kNoteDiverged = "diverged";        // "diverged (non-finite) at k of n dt ..."
constexpr std::string_view kNoteNoFit = "the error does not";  // "... fall with dt ..."
constexpr std::string_view kNoteFew = "too few usable points";  // ": k of n dt, ..."

// One word for a convergence result's order: the order, or why there is none.
std::string order_cell(const ConvergenceResult& c, const char* format) {
  if (!std::isnan(c.observed_order)) return fmt(format, c.observed_order);
  if (c.note.rfind(kNoteDiverged, 0) == 0) return "diverged";
  if (c.note.rfind(kNoteNoFit, 0) == 0) return "no conv.";
  if (c.note.rfind(kNoteFew, 0) == 0) return "too few";
  if (c.note == kNoteModel) return "-";
  return "exact";
}
}  // namespace

void simulate(const Problem& p, Method m, double dt, long long steps, std::vector<double>& x,
              std::vector<double>& v) {
  p.validate();
  require_positive(dt, "simulate(dt)");
  require_count(steps, 0, 1000000000LL, "simulate(steps)");
  Integrator<double> integ(m);
  x = p.x0;
  v = p.v0;
  integ.resize(x.size());
  for (long long k = 0; k < steps; ++k) {
    // time from the step index, not accumulated, so it does not drift
    const double t = static_cast<double>(k) * dt;
    integ.step(t, dt, std::span<double>(x), std::span<double>(v), p.accel);
    // a diverged state stops the run with the object, time and step
    const FiniteCheck c = check_finite<double>(x, v, "coordinate", t + dt, k + 1);
    if (!c.ok) throw Error("problem '" + p.name + "', " + std::string(name(m)) + ": " + c.message);
  }
}

double fit_order(Method m, std::span<const double> dts, std::span<const double> errors,
                 std::span<const long long> steps, double scale, double model_error,
                 const ConvergenceSettings& s, std::vector<bool>& fitted) {
  // usable points: above round-off and above the closed form's model error
  std::vector<bool> usable(dts.size(), false);
  for (std::size_t i = 0; i < dts.size(); ++i)
    usable[i] = std::isfinite(errors[i]) && errors[i] > error_floor(m, steps[i], scale, model_error, s);
  // the fit window: consecutive usable points, each halving shrinking the error by at
  // least 1.5x (any order >= 1 gives 2x; less means round-off or model error has taken
  // over, e.g. position Verlet's round-off growth), choosing among windows of the
  // largest possible size up to fit_points the one whose local slopes agree best (the
  // asymptotic regime: coarse steps are pre-asymptotic, fine ones feel round-off)
  const std::size_t count = dts.size();
  auto local_slope = [&](std::size_t i) {  // between points i and i + 1
    return std::log(errors[i] / errors[i + 1]) / std::log(dts[i] / dts[i + 1]);
  };
  std::size_t best_start = 0, best_size = 0;
  for (std::size_t w = static_cast<std::size_t>(s.fit_points); w >= 3 && best_size == 0; --w) {
    double best_spread = kInf;
    for (std::size_t j = 0; j + w <= count; ++j) {
      bool ok = true;
      double lo = kInf, hi = -kInf;
      for (std::size_t i = j; i < j + w && ok; ++i) {
        ok = usable[i] && (i == j || errors[i] * 1.5 <= errors[i - 1]);
        if (ok && i > j) {
          lo = std::min(lo, local_slope(i - 1));
          hi = std::max(hi, local_slope(i - 1));
        }
      }
      // ties go to the finer window
      if (ok && hi - lo <= best_spread) {
        best_spread = hi - lo;
        best_start = j;
        best_size = w;
      }
    }
  }
  fitted.assign(count, false);
  for (std::size_t i = best_start; i < best_start + best_size; ++i) fitted[i] = true;
  const int used = static_cast<int>(best_size);
  if (used < 3) return kNaN;
  // least-squares slope of log(error) against log(dt)
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < dts.size(); ++i) {
    if (!fitted[i]) continue;
    const double lx = std::log(dts[i]), ly = std::log(errors[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  const double k = used;
  return (k * sxy - sx * sy) / (k * sxx - sx * sx);
}

ConvergenceResult measure_convergence(const Problem& p, Method m, const ConvergenceSettings& s) {
  p.validate();
  require_count(s.levels, 2, 20, "ConvergenceSettings.levels");
  require_in_range(s.roundoff_floor, 0.0, 0.999, "ConvergenceSettings.roundoff_floor");
  require_count(s.fit_points, 3, 20, "ConvergenceSettings.fit_points");
  ConvergenceResult r;
  r.problem = p.name;
  r.method = m;
  const std::size_t n = p.x0.size();
  // the step counts: dt_coarse / 2^k, rounded so that the run lands exactly on t_end;
  // the finest (and an RK4 reference at 8x it) within simulate's 1e9 steps, checked before
  // llround (whose result beyond a long long is unspecified: 1e20 steps became 1)
  const double finest = p.t_end / std::ldexp(p.dt_coarse, -(s.levels - 1)) * (p.exact ? 1 : 8);
  if (!(finest <= 1e9))
    throw Error("Problem '" + p.name + "': t_end / dt_coarse x 2^(levels - 1)" + (p.exact ? "" : " x 8 (the RK4 reference)") +
                " = " + format_value(finest) + " steps at the finest level, more than 1e9 (t_end = " +
                format_value(p.t_end) + " s, dt_coarse = " + format_value(p.dt_coarse) +
                " s, ConvergenceSettings.levels = " + std::to_string(s.levels) + "); raise dt_coarse or lower levels");
  std::vector<long long> counts;
  for (int k = 0; k < s.levels; ++k)
    counts.push_back(std::max(1LL, std::llround(p.t_end / std::ldexp(p.dt_coarse, -k))));
  // the reference at t_end: closed form, or RK4 with 8x the finest step count
  std::vector<double> x_ref(n), v_ref(n), x, v;
  if (p.exact) {
    p.exact(p.t_end, x_ref, v_ref);
  } else {
    const long long ref_steps = counts.back() * 8;
    simulate(p, Method::Rk4, p.t_end / static_cast<double>(ref_steps), ref_steps, x_ref, v_ref);
  }
  double scale = 1;
  for (double xr : x_ref) scale = std::max(scale, std::abs(xr));
  // global error at t_end for each step size
  for (long long steps : counts) {
    const double dt = p.t_end / static_cast<double>(steps);
    double err = kInf;
    try {
      simulate(p, m, dt, steps, x, v);
      err = 0;
      for (std::size_t i = 0; i < n; ++i) err = std::max(err, std::abs(x[i] - x_ref[i]));
    } catch (const Error&) {
      err = kInf;  // diverged at this dt: recorded, never fitted
    }
    r.dts.push_back(dt);
    r.errors.push_back(err);
  }
  // the observed order by the lab's fit rule
  r.observed_order = fit_order(m, r.dts, r.errors, counts, scale, p.model_error, s, r.fitted);
  if (std::isnan(r.observed_order)) {
    // why: every point at round-off (or model error), points that diverged or did not
    // converge (which are not "exact"), or too few usable ones to fit (levels = 2, or
    // only 2 stable step sizes fall: they may well converge, but no order can be fitted)
    std::size_t diverged = 0, above = 0, run = 0, longest = 0;
    for (std::size_t i = 0; i < r.errors.size(); ++i) {
      const bool usable = std::isfinite(r.errors[i]) && r.errors[i] > error_floor(m, counts[i], scale, p.model_error, s);
      if (!std::isfinite(r.errors[i])) ++diverged;
      else if (usable) ++above;
      run = usable ? run + 1 : 0;
      longest = std::max(longest, run);
    }
    const std::size_t total = r.errors.size(), floor = total - diverged - above;
    const std::string of = std::to_string(diverged) + " of " + std::to_string(total) + " dt";
    if (above > 0 && longest < 3) {
      std::string why;
      auto add = [&why](const std::string& part) { why += (why.empty() ? "" : "; ") + part; };
      if (total < 3) add("ConvergenceSettings.levels = " + std::to_string(total));
      if (diverged > 0) add(std::to_string(diverged) + " diverged (non-finite)");
      if (floor > 0) add(std::to_string(floor) + (p.model_error > 0 ? " below the model error" : " at round-off"));
      r.note = std::string(kNoteFew) + ": " + std::to_string(above) + " of " + std::to_string(total) +
               " dt, 3 consecutive are needed to fit an order (" + why + ")";
    } else if (above > 0) {
      r.note = std::string(kNoteNoFit) + " fall with dt (no 3 consecutive dt halvings each shrink it 1.5x)" +
               (diverged > 0 ? "; diverged (non-finite) at " + of : "");
    } else if (diverged > 0) {
      r.note = std::string(kNoteDiverged) + " (non-finite) at " + of +
               (diverged < total ? ", the others at round-off" : ": unstable at these step sizes");
    } else {
      r.note = p.model_error > 0 ? kNoteModel : kNoteExact;
    }
  }
  return r;
}

EnergyResult measure_energy(const Problem& p, Method m, const EnergySettings& s) {
  p.validate();
  if (!p.energy) throw Error("measure_energy: problem '" + p.name + "' has no energy function");
  require_count(s.steps, 1, 1000000000LL, "EnergySettings.steps");
  require_count(s.samples, 2, 1000000, "EnergySettings.samples");
  EnergyResult r;
  r.problem = p.name;
  r.method = m;
  r.dt = p.energy_dt;
  r.steps = s.steps;
  const std::size_t n = p.x0.size();
  std::vector<double> x = p.x0, v = p.v0, xe(n), ve(n);
  const double e0 = p.energy(x, v);
  const double norm = e0 != 0 ? std::abs(e0) : 1.0;
  const double i0 = p.invariant ? p.invariant(x, v) : 0.0;
  const long long stride = std::max(1LL, s.steps / (s.samples - 1));
  r.t.push_back(0);
  r.rel_error.push_back(0);
  Integrator<double> integ(m);
  integ.resize(n);
  for (long long k = 0; k < s.steps; ++k) {
    // one step, then the finite check every system is expected to make
    const double t = static_cast<double>(k) * r.dt, t1 = static_cast<double>(k + 1) * r.dt;
    try {
      integ.step(t, r.dt, std::span<double>(x), std::span<double>(v), p.accel);
    } catch (const Error& e) {
      // e.g. implicit Euler's Newton failing once an orbit has decayed into the centre
      r.failure = "step " + std::to_string(k + 1) + ": " + e.what();
      break;
    }
    const FiniteCheck c = check_finite<double>(x, v, "coordinate", t1, k + 1);
    if (!c.ok) {
      r.failure = c.message;
      break;
    }
    r.steps_done = k + 1;
    // energy against the reference: initial, or the exact solution's for dissipative problems
    double e_ref = e0;
    if (p.dissipative) {
      p.exact(t1, xe, ve);
      e_ref = p.energy(xe, ve);
    }
    const double rel = (p.energy(x, v) - e_ref) / norm;
    r.final_rel_error = rel;
    if (!(std::abs(rel) <= r.max_abs_rel_error)) r.max_abs_rel_error = std::abs(rel);
    if (p.invariant)
      r.invariant_max_abs_error = std::max(r.invariant_max_abs_error, std::abs(p.invariant(x, v) - i0));
    if ((k + 1) % stride == 0 || k + 1 == s.steps) {
      r.t.push_back(t1);
      r.rel_error.push_back(rel);
    }
  }
  return r;
}

double spectral_radius(Method m, double z) {
  require_positive(z, "spectral_radius(z)");
  // the one-step matrix from the basis states (1, 0) and (0, 1) on x'' = -x
  auto accel = [](double, std::span<const double> x, std::span<const double>, std::span<double> a) {
    a[0] = -x[0];
  };
  Integrator<double> integ(m);
  double x = 1, v = 0;
  integ.step(0.0, z, std::span<double>(&x, 1), std::span<double>(&v, 1), accel);
  const double m11 = x, m21 = v;
  integ.reset_history();
  x = 0;
  v = 1;
  integ.step(0.0, z, std::span<double>(&x, 1), std::span<double>(&v, 1), accel);
  const double m12 = x, m22 = v;
  // eigenvalues of the 2x2 matrix
  const double tr = m11 + m22, det = m11 * m22 - m12 * m21;
  const double disc = tr * tr - 4 * det;
  if (disc < 0) return std::sqrt(det);
  const double sq = std::sqrt(disc);
  return std::max(std::abs((tr + sq) / 2), std::abs((tr - sq) / 2));
}

double theory_stability_limit(Method m) {
  switch (m) {
    case Method::ExplicitEuler: return 0;
    case Method::SemiImplicitEuler:
    case Method::PositionVerlet:
    case Method::VelocityVerlet: return 2;
    case Method::Rk4: return 2 * std::numbers::sqrt2;
    case Method::ImplicitEuler: return kInf;
  }
  return kNaN;
}

StabilityResult measure_stability(Method m, const StabilitySettings& s) {
  require_in_range(s.z_max, 1e-9, 100, "StabilitySettings.z_max");
  require_count(s.scan_points, 10, 100000, "StabilitySettings.scan_points");
  require_in_range(s.tolerance, 0, 1e-3, "StabilitySettings.tolerance");
  StabilityResult r;
  r.method = m;
  r.theory = theory_stability_limit(m);
  auto stable = [&](double z) { return spectral_radius(m, z) <= 1 + s.tolerance; };
  // scan for the first unstable point
  double lo = 0, hi = kInf;
  for (int i = 1; i <= s.scan_points; ++i) {
    const double z = s.z_max * i / s.scan_points;
    const double rho = spectral_radius(m, z);
    r.z.push_back(z);
    r.spectral_radius.push_back(rho);
    if (hi == kInf) {
      if (rho <= 1 + s.tolerance) {
        lo = z;
      } else {
        hi = z;
      }
    }
  }
  if (hi == kInf) {
    r.limit = kInf;
    return r;
  }
  // bisection between the last stable and the first unstable scan point
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = (lo + hi) / 2;
    if (mid <= lo || mid >= hi) break;
    (stable(mid) ? lo : hi) = mid;
  }
  r.limit = lo;
  return r;
}

LabReport run_lab(const std::vector<Problem>& problems, const LabOptions& o,
                  const std::function<void(std::string_view)>& progress) {
  Stopwatch watch;
  LabReport rep;
  // the chosen problems, in the order asked (names checked up front)
  std::vector<const Problem*> chosen;
  if (o.problems.empty()) {
    for (const auto& p : problems) chosen.push_back(&p);
  } else {
    for (const auto& n : o.problems) chosen.push_back(&find_problem(problems, n, "--problem"));
  }
  const std::vector<Method> methods =
      o.methods.empty() ? std::vector<Method>(kAllMethods.begin(), kAllMethods.end()) : o.methods;
  // convergence and energy per problem and method
  for (const Problem* p : chosen) {
    p->validate();
    if (progress) progress("problem " + p->name + ": " + p->description);
    for (Method m : methods) {
      rep.convergence.push_back(measure_convergence(*p, m, o.convergence));
      if (p->energy) rep.energy.push_back(measure_energy(*p, m, o.energy));
    }
  }
  // stability on the oscillator
  if (progress) progress("stability on the undamped oscillator");
  for (Method m : methods) rep.stability.push_back(measure_stability(m, o.stability));
  rep.seconds = watch.seconds();
  return rep;
}

namespace {
std::ofstream open_csv(const std::filesystem::path& path) {
  std::ofstream f(path);
  if (!f) throw Error("pba lab: cannot write '" + path.string() + "'");
  return f;
}
std::string num(double v) { return format_value(v); }
// a text field as RFC 4180 has it: in double quotes (inner ones doubled) when it holds a
// comma, a quote or a line break (the notes have commas), or always when asked
std::string text(std::string_view v, bool always_quoted = false) {
  if (!always_quoted && v.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(v);
  std::string out = "\"";
  for (char ch : v) out += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return out + '"';
}
}  // namespace

void write_csv(const LabReport& rep, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error("pba lab: --out '" + dir + "': cannot create directory: " + ec.message());
  const std::filesystem::path d(dir);
  // convergence: every (dt, error) point and whether it was fitted
  {
    auto f = open_csv(d / "convergence.csv");
    f << "problem,method,dt,error,fitted\n";
    for (const auto& c : rep.convergence)
      for (std::size_t i = 0; i < c.dts.size(); ++i)
        f << text(c.problem) << ',' << name(c.method) << ',' << num(c.dts[i]) << ',' << num(c.errors[i]) << ','
          << (c.fitted[i] ? 1 : 0) << '\n';
  }
  // observed orders
  {
    auto f = open_csv(d / "orders.csv");
    f << "problem,method,observed_order,theory_order,note\n";
    for (const auto& c : rep.convergence)
      f << text(c.problem) << ',' << name(c.method) << ',' << num(c.observed_order) << ',' << order(c.method)
        << ',' << text(c.note) << '\n';
  }
  // energy samples
  {
    auto f = open_csv(d / "energy.csv");
    f << "problem,method,dt,t,rel_energy_error\n";
    for (const auto& e : rep.energy)
      for (std::size_t i = 0; i < e.t.size(); ++i)
        f << text(e.problem) << ',' << name(e.method) << ',' << num(e.dt) << ',' << num(e.t[i]) << ','
          << num(e.rel_error[i]) << '\n';
  }
  // stability scan
  {
    auto f = open_csv(d / "stability.csv");
    f << "method,omega_dt,spectral_radius,limit,theory\n";
    for (const auto& s : rep.stability)
      for (std::size_t i = 0; i < s.z.size(); ++i)
        f << name(s.method) << ',' << num(s.z[i]) << ',' << num(s.spectral_radius[i]) << ','
          << num(s.limit) << ',' << num(s.theory) << '\n';
  }
  // per-problem energy summary
  {
    auto f = open_csv(d / "energy_summary.csv");
    f << "problem,method,dt,steps,steps_done,final_rel_error,max_abs_rel_error,invariant_max_abs_error,"
         "failure\n";
    for (const auto& e : rep.energy)
      f << text(e.problem) << ',' << name(e.method) << ',' << num(e.dt) << ',' << e.steps << ',' << e.steps_done
        << ',' << num(e.final_rel_error) << ',' << num(e.max_abs_rel_error) << ','
        << num(e.invariant_max_abs_error) << ',' << text(e.failure, true) << '\n';
  }
}

std::string summary_table(const LabReport& rep) {
  std::string out;
  // the headline problem: the oscillator if it was run, else the first
  std::string head = rep.convergence.empty() ? "" : rep.convergence.front().problem;
  for (const auto& c : rep.convergence)
    if (c.problem == "oscillator") head = "oscillator";
  std::string ehead = rep.energy.empty() ? "" : rep.energy.front().problem;
  for (const auto& e : rep.energy)
    if (e.problem == "oscillator") ehead = "oscillator";
  long long esteps = 0;
  double edt = 0;
  for (const auto& e : rep.energy)
    if (e.problem == ehead) esteps = e.steps, edt = e.dt;
  out += "Order: observed on '" + head + "' (least-squares slope of log error vs log dt) / theory.\n";
  out += "Energy: relative energy error on '" + ehead + "' after " + std::to_string(esteps) +
         " steps of dt = " + format_value(edt) + " s (end of run, and max over the run).\n";
  out += "Stability: largest omega*dt with spectral radius <= 1 on x'' = -x (measured / theory).\n\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-20s %8s %6s %12s %12s %12s %10s\n", "method", "order", "theory",
                "dE/E end", "max |dE/E|", "stab. limit", "theory");
  out += line;
  out += std::string(86, '-') + "\n";
  // collect the methods in the order they were run
  std::vector<Method> methods;
  for (const auto& s : rep.stability) methods.push_back(s.method);
  if (methods.empty())
    for (const auto& c : rep.convergence)
      if (std::find(methods.begin(), methods.end(), c.method) == methods.end()) methods.push_back(c.method);
  auto limit_text = [](double z) {
    if (std::isinf(z)) return std::string("none");
    if (z < 1e-4) return std::string("0 (") + fmt("%.0e", z) + ")";
    return fmt("%.4f", z);
  };
  for (Method m : methods) {
    double ef = kNaN, em = kNaN, lim = kNaN, th = theory_stability_limit(m);
    std::string obs_cell = "-";
    for (const auto& c : rep.convergence)
      if (c.method == m && c.problem == head) obs_cell = order_cell(c, "%.3f");
    for (const auto& e : rep.energy)
      if (e.method == m && e.problem == ehead) ef = e.final_rel_error, em = e.max_abs_rel_error;
    for (const auto& s : rep.stability)
      if (s.method == m) lim = s.limit;
    std::snprintf(line, sizeof line, "%-20s %8s %6d %12s %12s %12s %10s\n", std::string(label(m)).c_str(),
                  obs_cell.c_str(), order(m),
                  fmt("%+.3e", ef).c_str(), fmt("%.3e", em).c_str(),
                  std::isnan(lim) ? "-" : limit_text(lim).c_str(),
                  std::isinf(th) ? "none" : th == 0 ? "0" : fmt("%.4f", th).c_str());
    out += line;
  }
  // the order matrix: problem x method
  std::vector<std::string> probs;
  for (const auto& c : rep.convergence)
    if (std::find(probs.begin(), probs.end(), c.problem) == probs.end()) probs.push_back(c.problem);
  if (!probs.empty()) {
    out += "\nObserved order per problem ('exact' = error at round-off for every dt; '-' = below the\n"
           "closed form's own model error; 'diverged' = non-finite at some dt, the rest at round-off;\n"
           "'no conv.' = the error does not fall with dt; 'too few' = fewer than 3 consecutive usable\n"
           "dt, e.g. only 2 stable or only 2 above the model error):\n";
    std::snprintf(line, sizeof line, "%-18s", "problem");
    out += line;
    for (Method m : methods) {
      std::snprintf(line, sizeof line, " %9.9s", std::string(name(m)).c_str());
      out += line;
    }
    out += "\n";
    for (const auto& pn : probs) {
      std::snprintf(line, sizeof line, "%-18s", pn.c_str());
      out += line;
      for (Method m : methods) {
        std::string cell = " ";
        for (const auto& c : rep.convergence)
          if (c.problem == pn && c.method == m) cell = order_cell(c, "%.2f");
        std::snprintf(line, sizeof line, " %9s", cell.c_str());
        out += line;
      }
      out += "\n";
    }
  }
  // conserved-quantity errors, when measured
  bool any_inv = false;
  for (const auto& e : rep.energy) any_inv = any_inv || e.invariant_max_abs_error > 0;
  if (any_inv) {
    out += "\nMax |angular momentum error| over the long run (orbits):\n";
    for (const auto& e : rep.energy)
      if (e.invariant_max_abs_error > 0 || e.problem.rfind("orbit", 0) == 0) {
        std::snprintf(line, sizeof line, "  %-16s %-20s %.3e\n", e.problem.c_str(),
                      std::string(label(e.method)).c_str(), e.invariant_max_abs_error);
        out += line;
      }
  }
  for (const auto& e : rep.energy)
    if (!e.failure.empty())
      out += "\nnote: " + e.problem + " / " + std::string(name(e.method)) + " stopped: " + e.failure + "\n";
  return out;
}

}  // namespace pba::lab
