// pba integrator accuracy lab (workbook 3.2.4: "implement a method for measuring the
// accuracy of each integration method").
//
// A Problem is an initial-value problem x'' = a(t, x, x') on a flat array of generalised
// coordinates (metres or radians), with an optional closed-form solution and energy. The
// lab measures, per method: the global error at t_end against dt and the observed order
// of convergence; the energy error over a long run; and the stability limit omega*dt on
// the undamped oscillator. Users add their own problems (the workbook's "additional
// acceleration functions") by filling in a Problem. `pba lab` drives all of this.
#pragma once

#include <functional>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pba/core.h"
#include "pba/integrate.h"

namespace pba::lab {

/// Closed-form state at time t: fill x and v (sizes as the problem's x0).
using ExactFn = std::function<void(double t, std::span<double> x, std::span<double> v)>;
/// A scalar function of the state, e.g. energy per unit mass (J/kg) or angular momentum.
using StateFn = std::function<double(std::span<const double> x, std::span<const double> v)>;

/// An initial-value problem for the lab. Fill it in to add your own.
struct Problem {
  std::string name;         ///< CLI name, e.g. "oscillator" (non-empty, no spaces)
  std::string description;  ///< one line for tables and plots
  std::vector<double> x0;   ///< initial coordinates (m or rad); at least one
  std::vector<double> v0;   ///< initial rates (m/s or rad/s); same size as x0
  double t_end = 1;         ///< end time of the convergence runs (s), > 0
  AccelFn<double> accel;    ///< a(t, x, v) for all coordinates (required)
  ExactFn exact;            ///< closed-form solution; empty: an RK4 reference at a tiny step
  StateFn energy;           ///< energy per unit mass (J/kg); empty: no energy run
  StateFn invariant;        ///< another conserved quantity (e.g. angular momentum); optional
  std::string invariant_name;  ///< its name for tables, e.g. "angular momentum"
  /// Largest step of the convergence study (s), > 0; the study halves it `levels` times.
  double dt_coarse = 0.01;
  /// Step of the long energy run (s), > 0.
  double energy_dt = 0.01;
  /// Characteristic angular frequency (rad/s) for reporting omega*dt; 0 if none.
  double omega = 0;
  /// Known error of `exact` itself at t_end (e.g. the small-angle approximation); errors
  /// below 10x this are not used for the order fit. 0 for a true closed form.
  double model_error = 0;
  /// True when the problem loses energy physically (drag, damping): its energy error is
  /// then measured against energy(exact(t)) instead of the initial energy.
  bool dissipative = false;

  /// Throws Error naming the first invalid field ("Problem 'x'.t_end: ...").
  void validate() const;
};

/// Projectile under constant gravity g (m/s^2, > 0), no drag, 2D (x right, y up).
Problem projectile(double g = 9.81);
/// Projectile with linear drag a = g - k v (k in 1/s, > 0); closed form with e^{-kt}.
Problem projectile_drag(double k = 0.5, double g = 9.81);
/// Undamped harmonic oscillator x'' = -omega^2 x, x0 = 1, v0 = 0; omega (rad/s) in
/// [1.5e-154, 1.7e153]: omega^2 a normal double, with room for the energy (2 omega^2) and
/// the damped acceleration (up to 3 omega^2) to grow 21x in double.
Problem oscillator(double omega = 1.0);
/// Underdamped oscillator x'' = -omega^2 x - 2 zeta omega x', 0 < zeta < 1, omega as above.
Problem damped_oscillator(double omega = 1.0, double zeta = 0.1);
/// Pendulum theta'' = -(g/L) sin theta released from rest at theta0 (rad, in (0, pi)).
/// With small_angle, `exact` is the small-angle closed form theta0 cos(omega0 t) and
/// model_error is its true error at t_end (from the Jacobi elliptic solution); otherwise
/// `exact` is the Jacobi elliptic solution, exact at any amplitude.
Problem pendulum(double theta0, bool small_angle, double g_over_l = 9.81);
/// Kepler orbit x'' = -GM x/|x|^3 (GM = 1), eccentricity e in [0, 0.9], semi-major axis 1,
/// starting at periapsis. Exact via Kepler's equation; period 2 pi; energy -1/2 per unit
/// mass; angular momentum sqrt(1 - e^2).
Problem kepler(double e = 0.5);
/// The standard set: projectile, projectile-drag, oscillator, damped-oscillator,
/// pendulum-small, pendulum-large, orbit (e = 0.5), orbit-circular.
std::vector<Problem> standard_problems();
/// The problem called `name`, or Error naming `where`, the text and the valid names.
const Problem& find_problem(const std::vector<Problem>& problems, std::string_view name,
                            std::string_view where);

/// Complete elliptic integral of the first kind K(m), parameter m = k^2 in [0, 1), by the
/// arithmetic-geometric mean: K = pi / (2 AGM(1, sqrt(1 - m))) (Abramowitz & Stegun 17.6).
double elliptic_k(double m);
/// Jacobi elliptic functions of u with parameter m in [0, 1).
struct Jacobi {
  double sn, cn, dn;
};
/// sn, cn, dn by the descending Landen / AGM method (Abramowitz & Stegun 16.4).
Jacobi jacobi_elliptic(double u, double m);
/// Exact period (s) of a pendulum released from rest at theta0 (rad, in (0, pi)):
/// T = 4 K(sin^2(theta0/2)) / omega0 with omega0 = sqrt(g/L) (rad/s).
double pendulum_period(double theta0, double omega0);

/// Runs `steps` steps of size dt from the problem's initial state; x and v receive the
/// final state. Throws Error if the state becomes non-finite (naming time and step).
void simulate(const Problem& p, Method m, double dt, long long steps, std::vector<double>& x,
              std::vector<double>& v);

/// Settings for the convergence study.
struct ConvergenceSettings {
  int levels = 10;  ///< number of step sizes: dt_coarse / 2^k, k = 0..levels-1; [2, 20]
  /// Errors below max(roundoff_floor * scale, w(n) eps scale, 10 model_error)
  /// (scale = max(1, |x_exact|), n steps) are round-off or model error, not truncation,
  /// and are not fitted. w(n) is how n steps' roundings accumulate in x, with a margin:
  /// 100 sqrt(n) for the methods that carry x and v; 10 sqrt(n (n + 1) (2n + 1) / 6)
  /// ~ 10 n^(3/2) / sqrt(3) for position Verlet, whose velocity is a difference of
  /// positions (each rounding is integrated twice). The fit window is fit_points (at least 3) consecutive usable points whose
  /// every halving shrinks the error by >= 1.5x, chosen where the local slopes agree best.
  /// Valid: [0, 1).
  double roundoff_floor = 1e-13;
  int fit_points = 4;  ///< the order is fitted on the finest this many usable points; [3, 20]
};

/// Error against step size for one problem and method.
struct ConvergenceResult {
  std::string problem;
  Method method = Method::ExplicitEuler;
  std::vector<double> dts;     ///< step sizes (s), coarse to fine
  std::vector<double> errors;  ///< max |x - x_exact| over coordinates at t_end (m or rad)
  std::vector<bool> fitted;    ///< whether each point was used in the fit
  /// Least-squares slope of log(error) against log(dt) over the fitted points; NaN when no
  /// window of 3 consecutive usable points shrinks 1.5x per halving: exact (all at
  /// round-off), below the model error, diverged, no convergence or too few usable points
  /// (`note` says which; NaN alone does not mean "exact").
  double observed_order = std::numeric_limits<double>::quiet_NaN();
  /// Why the order is NaN, if it is: every error at round-off ("exact"), below the model
  /// error, "diverged" (non-finite) at some dt with the rest at round-off, "the error does
  /// not fall with dt", or "too few usable points: k of n dt, ..." (fewer than 3
  /// consecutive usable points, with why: levels < 3, diverged or at round-off); the tables
  /// show "exact", "-", "diverged", "no conv." and "too few".
  std::string note;
};

/// Measures the global error at t_end for each dt (the step count is t_end/dt rounded to
/// an integer and dt adjusted to land exactly on t_end).
ConvergenceResult measure_convergence(const Problem& p, Method m, const ConvergenceSettings& s = {});

/// The lab's rule for the observed order of convergence, for callers that measure the
/// points themselves (the samples app fills them in a few per frame). m is the method that
/// made the points (its round-off floor depends on it, see ConvergenceSettings). dts (s), errors and
/// steps are coarse to fine, one entry per measured point; scale = max(1, |x_exact|) at
/// t_end; model_error is the reference's own error (Problem::model_error). Usable points
/// and the fit window follow ConvergenceSettings. Sets fitted[i] for the points used.
/// Returns the least-squares slope of log(error) against log(dt), or NaN when fewer than
/// 3 points are usable.
double fit_order(Method m, std::span<const double> dts, std::span<const double> errors,
                 std::span<const long long> steps, double scale, double model_error,
                 const ConvergenceSettings& s, std::vector<bool>& fitted);

/// Settings for the long energy run.
struct EnergySettings {
  long long steps = 1000000;  ///< steps of size energy_dt; [1, 1e9]
  int samples = 2000;         ///< points recorded for plotting; [2, 1e6]
};

/// Energy error over a long run. The reference energy is the initial energy, or for a
/// dissipative problem the exact solution's energy at each time (its true decay).
struct EnergyResult {
  std::string problem;
  Method method = Method::ExplicitEuler;
  double dt = 0;                  ///< step (s)
  long long steps = 0;            ///< steps requested
  long long steps_done = 0;       ///< steps taken (fewer if the state became non-finite)
  std::vector<double> t;          ///< sample times (s)
  std::vector<double> rel_error;  ///< (E - E_ref) / |E_0| at the sample times
  double max_abs_rel_error = 0;   ///< over every step, not only samples
  double final_rel_error = 0;     ///< at the last step taken
  double invariant_max_abs_error = 0;  ///< max |I - I_0| of problem.invariant, if any
  std::string failure;            ///< check_finite's message if the state blew up
};

/// Runs the long energy run for a problem with an energy function (Error otherwise).
EnergyResult measure_energy(const Problem& p, Method m, const EnergySettings& s = {});

/// Stability on the undamped oscillator x'' = -x (omega = 1, so dt = omega*dt).
///
/// Definition: the method is linear on this problem, so one step is a 2x2 matrix M(z),
/// z = omega*dt, measured by stepping the basis states (1, 0) and (0, 1). It is stable
/// when the spectral radius rho(M) <= 1 + tolerance (no mode grows). The limit is the
/// largest z such that every z' <= z is stable, found by a scan then bisection.
/// Theory: explicit Euler rho = sqrt(1 + z^2) > 1 for every z > 0 (limit 0); semi-implicit
/// Euler and Verlet |trace| = |2 - z^2| <= 2 gives 2; RK4 2 sqrt(2); implicit Euler never.
struct StabilitySettings {
  double z_max = 4.0;         ///< largest omega*dt examined; (0, 100]
  int scan_points = 400;      ///< scan resolution before bisection; [10, 1e5]
  double tolerance = 1e-12;   ///< growth per step regarded as round-off; [0, 1e-3]
};

/// Measured stability of one method.
struct StabilityResult {
  Method method = Method::ExplicitEuler;
  /// Largest stable omega*dt; +inf when stable over all of (0, z_max]. For explicit
  /// Euler this is the resolution sqrt(2 tolerance) ~ 1.4e-6, i.e. 0 (see theory).
  double limit = 0;
  double theory = 0;                    ///< theory_stability_limit(method)
  std::vector<double> z;                ///< scan points omega*dt
  std::vector<double> spectral_radius;  ///< rho(M(z)) at the scan points
};

/// Spectral radius of one step of `m` on x'' = -x at dt = z (> 0).
double spectral_radius(Method m, double z);
/// Theoretical limit: 0, 2, 2, 2, 2 sqrt(2), +inf.
double theory_stability_limit(Method m);
/// Measures the stability limit (see StabilitySettings for the definition).
StabilityResult measure_stability(Method m, const StabilitySettings& s = {});

/// What `pba lab` runs.
struct LabOptions {
  std::vector<std::string> problems;  ///< names; empty: all
  std::vector<Method> methods;        ///< empty: all
  ConvergenceSettings convergence;
  EnergySettings energy;
  StabilitySettings stability;
};

/// Everything the lab measured.
struct LabReport {
  std::vector<ConvergenceResult> convergence;
  std::vector<EnergyResult> energy;
  std::vector<StabilityResult> stability;
  double seconds = 0;  ///< wall-clock time of the run
};

/// Runs every measurement for the chosen problems and methods. `progress`, if set, is
/// called with a short line before each problem.
LabReport run_lab(const std::vector<Problem>& problems, const LabOptions& options,
                  const std::function<void(std::string_view)>& progress = {});

/// Writes convergence.csv, energy.csv, stability.csv and summary.csv into dir (created
/// if missing). Throws Error naming the file if it cannot be written.
void write_csv(const LabReport& report, const std::string& dir);

/// A plain-text summary: per method, the observed order on the oscillator (or the first
/// problem run), theory order, energy drift and error, stability limit and theory; then
/// the observed order of every method on every problem.
std::string summary_table(const LabReport& report);

}  // namespace pba::lab
