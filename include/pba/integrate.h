// pba integrators (workbook 3.2): advance positions and velocities from t to t + dt
// under an acceleration a(t, x, v), for one object or for arrays of many.
//
// Every system that integrates (particles, springs, cloth) uses Integrator<V>: it owns
// the scratch arrays a method needs (allocated in resize() or on first use, never in a
// steady-state step), validates its input, and is deterministic: the same inputs give
// bit-identical results, and N identical objects stepped together give the same bits
// as one object stepped alone. See docs/integration.md for the theory and the lab.
//
//   pba::Integrator<pba::Vec3> integ(pba::Method::VelocityVerlet);
//   integ.step(t, dt, x, v, [](double t, auto x, auto v, auto a) {
//     for (std::size_t i = 0; i < x.size(); ++i) a[i] = pba::Vec3(0, -9.81, 0) - 0.1 * v[i];
//   });
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "pba/core.h"

namespace pba {

/// The integration methods. CLI names in name(); theory orders in order().
enum class Method {
  ExplicitEuler,      ///< "euler": x += v dt (old v), v += a dt. Order 1, gains energy.
  SemiImplicitEuler,  ///< "semi-implicit-euler": v += a dt, then x += v dt. Order 1, symplectic.
  PositionVerlet,     ///< "verlet": x' = 2x - x_prev + a dt^2 (workbook form). Order 2, symplectic.
  VelocityVerlet,     ///< "velocity-verlet": kick-drift-kick form of Verlet. Order 2, symplectic.
  Rk4,                ///< "rk4": classical Runge-Kutta, workbook listing 3.1. Order 4.
  ImplicitEuler,      ///< "implicit-euler": backward Euler by Newton's method. Order 1, damps.
};

/// Every method, in declaration order (for loops, menus and the lab).
inline constexpr std::array<Method, 6> kAllMethods = {
    Method::ExplicitEuler,  Method::SemiImplicitEuler, Method::PositionVerlet,
    Method::VelocityVerlet, Method::Rk4,               Method::ImplicitEuler};

/// The method's command-line name: "euler", "semi-implicit-euler", "verlet",
/// "velocity-verlet", "rk4" or "implicit-euler".
std::string_view name(Method m);
/// A human-readable label for tables, plots and menus, e.g. "Semi-implicit Euler".
std::string_view label(Method m);
/// The method's theoretical order of global accuracy: 1, 1, 2, 2, 4, 1.
int order(Method m);
/// True for the symplectic methods (semi-implicit Euler and both Verlets): their
/// energy error stays bounded on conservative problems instead of drifting.
bool is_symplectic(Method m);
/// Accelerations evaluated per step in steady state (RK4: 4; implicit Euler: varies,
/// returns -1; position Verlet: 1 after the first step).
int evaluations_per_step(Method m);
/// All CLI names joined by ", " (for help texts and error messages).
std::string method_names();
/// Parses a CLI name (exact, case-sensitive). Throws Error naming the bad text, where it
/// came from (e.g. "--method") and the valid names.
Method parse_method(std::string_view text, std::string_view where);

/// Acceleration function for an array of n objects: fill a_out[i] (m/s^2) from the time
/// t (s), positions x (m) and velocities v (m/s). All spans have the same size. It must
/// not keep the spans, and must be a pure function of its inputs for determinism.
template <class V>
using AccelFn = std::function<void(double t, std::span<const V> x, std::span<const V> v,
                                   std::span<V> a_out)>;

/// Optional analytic Jacobian for implicit Euler. With N = n * components(V) scalar
/// unknowns, fill dadx and dadv (each N*N, row-major, already zeroed): entry (r, c) is
/// the derivative of scalar acceleration r with respect to scalar position/velocity c,
/// where scalar index = object * components(V) + component.
template <class V>
using JacobianFn = std::function<void(double t, std::span<const V> x, std::span<const V> v,
                                      std::span<double> dadx, std::span<double> dadv)>;

/// Settings for implicit Euler's Newton solve.
struct NewtonSettings {
  /// Converged when max|delta v| <= tolerance * max(1, max|v|) (infinity norms, so the
  /// test is the same for one object and for N identical objects). Valid: [1e-16, 1e-2].
  /// For float vectors the effective tolerance is never below 1e-6.
  double tolerance = 1e-13;
  /// Iteration cap; if not converged by then step() throws Error. Valid: [1, 100].
  int max_iterations = 20;
  /// Largest number of scalar unknowns (objects x components) the dense solve accepts.
  /// Cost per Newton iteration: N+1 acceleration evaluations (finite differences) and an
  /// O(N^3) LU factorisation on an N x N matrix (8 N^2 bytes). 1536 unknowns is 18 MB
  /// and about 0.2 s per iteration on one core. Valid: [1, 20000].
  std::size_t max_unknowns = 1536;
};

/// Statistics of the last implicit Euler step.
struct NewtonStats {
  int iterations = 0;         ///< Newton iterations taken (>= 1)
  double last_update = 0;     ///< max|delta v| of the final iteration (m/s)
};

/// Thrown by an implicit Euler step when Newton does not converge or its system is singular
/// or non-finite: an Error (its message names t and dt), of its own type so a caller can
/// fall back on Newton's failure alone and let the step's other refusals (a bad dt) through.
class NewtonFailure : public Error {
 public:
  using Error::Error;
};

namespace detail {
// the scalar type and component count of double, glm::vec<L, T>
template <class V>
struct VecTraits {
  using Scalar = typename V::value_type;
  static constexpr int kDim = V::length();
  static Scalar& at(V& v, int k) { return v[k]; }
  static Scalar get(const V& v, int k) { return v[k]; }
};
template <>
struct VecTraits<double> {
  using Scalar = double;
  static constexpr int kDim = 1;
  static double& at(double& v, int) { return v; }
  static double get(double v, int) { return v; }
};

// dense LU solve behind a firewall so Eigen stays out of public headers: owns an N x N
// matrix and an N vector; factorises the matrix and overwrites the vector with the solution
class DenseSolver;
struct DenseSolverDeleter {
  void operator()(DenseSolver* s) const;
};
std::unique_ptr<DenseSolver, DenseSolverDeleter> make_dense_solver(std::size_t n);
double* dense_matrix(DenseSolver& s);  // column-major N x N
double* dense_rhs(DenseSolver& s);     // N
void dense_solve(DenseSolver& s);      // rhs <- matrix^-1 rhs (partial-pivot LU)

// Integrator::step's checks, throwing Error naming the value: dt finite and > 0, t finite, dt
// in the vectors' precision (`scalar_bytes`: 4 for float, 8 for double) normal with a finite
// square (a float integrator rounds 1e-50 to 0 and 1e300 to inf; position Verlet divides by
// it, the Verlets square it), and x and v of the same size (nx, nv)
void check_step(double t, double dt, std::size_t nx, std::size_t nv, std::size_t scalar_bytes);
[[noreturn]] void throw_newton_failure(int iterations, double update, double t, double dt);
[[noreturn]] void throw_too_many_unknowns(std::size_t n_objects, int dim, std::size_t limit);
[[noreturn]] void throw_singular(double t, double dt);
}  // namespace detail

/// Advances arrays of positions x and velocities v by one step with the chosen method.
///
/// V is double, glm::dvec2, glm::dvec3 or glm::vec3. Units are the caller's (SI in pba:
/// metres, m/s, m/s^2, seconds). Time t is always double.
///
/// Scratch memory is allocated by resize(n) or by the first step with n objects; steps
/// with an unchanged n never allocate (implicit Euler included). Changing n, the method
/// or dt resets the position-Verlet history. Not thread-safe: one Integrator per thread.
///
/// step() does not scan for NaN (that would cost a pass over memory every step); a
/// system calls pba::check_finite on its state after stepping (each frame, or every
/// step when debugging) and stops with its message.
template <class V>
class Integrator {
 public:
  using Scalar = typename detail::VecTraits<V>::Scalar;
  /// Scalar components per object (1, 2 or 3).
  static constexpr int kDim = detail::VecTraits<V>::kDim;

  /// An integrator for `method`. No memory is allocated until resize() or step().
  explicit Integrator(Method method = Method::SemiImplicitEuler, NewtonSettings newton = {});
  ~Integrator();
  Integrator(Integrator&&) noexcept;
  Integrator& operator=(Integrator&&) noexcept;
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  /// The current method.
  Method method() const { return method_; }
  /// Switches method; resets history (the next step starts fresh from x and v).
  void set_method(Method m);
  /// Implicit Euler's Newton settings.
  const NewtonSettings& newton() const { return newton_; }
  /// Replaces the Newton settings. Throws Error naming a field outside its valid range.
  void set_newton(const NewtonSettings& s);
  /// Sets (or clears, with an empty function) an analytic Jacobian for implicit Euler.
  /// Without one, the Jacobian is built by forward differences (N+1 evaluations).
  void set_jacobian(JacobianFn<V> jacobian);

  /// Allocates scratch for n objects (and the dense solver for implicit Euler, which
  /// throws Error when n * kDim > newton().max_unknowns). Resets history if n changed.
  void resize(std::size_t n);
  /// Number of objects the scratch arrays are sized for.
  std::size_t size() const { return n_; }

  /// Forgets position Verlet's previous positions and cached acceleration, so the next
  /// step restarts from the current x and v. Call it after teleporting objects or after
  /// writing velocities (position Verlet's velocity lives in x - x_prev, so a write to v
  /// alone is otherwise ignored). A change of dt, n or method does this automatically.
  void reset_history() { history_valid_ = false; }

  /// Advances x and v (same size n) from time t to t + dt (dt finite and > 0, seconds),
  /// calling accel(double t, std::span<const V> x, std::span<const V> v, std::span<V> a)
  /// as often as the method needs. Throws Error for a bad dt or mismatched sizes; dt
  /// must also be a normal number in the vectors' precision with a finite square:
  /// [2.2e-308, 1.3e154] s for double vectors, [1.2e-38, 1.8e19] s for float ones.
  template <class Accel>
  void step(double t, double dt, std::span<V> x, std::span<V> v, Accel&& accel);

  /// One-object convenience: accel(double t, const V& x, const V& v) returns a (m/s^2).
  /// Uses the same scratch and history as step() with n = 1.
  template <class Accel1>
  void step_one(double t, double dt, V& x, V& v, Accel1&& accel);

  /// Acceleration evaluations made so far (for cost comparisons).
  long long evaluations() const { return evaluations_; }
  /// Statistics of the last implicit Euler step.
  const NewtonStats& last_newton() const { return stats_; }

 private:
  template <class Accel>
  void eval(Accel& accel, double t, std::span<const V> x, std::span<const V> v, std::span<V> a) {
    ++evaluations_;
    accel(t, x, v, a);
  }
  void ensure_size(std::size_t n) {
    if (n != n_ || a0_.size() != n) resize(n);
  }

  template <class Accel>
  void step_explicit_euler(double t, Scalar h, std::span<V> x, std::span<V> v, Accel& accel);
  template <class Accel>
  void step_semi_implicit_euler(double t, Scalar h, std::span<V> x, std::span<V> v, Accel& accel);
  template <class Accel>
  void step_position_verlet(double t, double dt, std::span<V> x, std::span<V> v, Accel& accel);
  template <class Accel>
  void step_velocity_verlet(double t, Scalar h, std::span<V> x, std::span<V> v, Accel& accel);
  template <class Accel>
  void step_rk4(double t, Scalar h, std::span<V> x, std::span<V> v, Accel& accel);
  template <class Accel>
  void step_implicit_euler(double t, double dt, std::span<V> x, std::span<V> v, Accel& accel);

  Method method_;
  NewtonSettings newton_;
  JacobianFn<V> jacobian_;
  std::size_t n_ = 0;
  long long evaluations_ = 0;
  NewtonStats stats_;
  // position verlet history: previous positions, the acceleration at the current
  // positions (from the end of the last step), and the dt the history was built with
  bool history_valid_ = false;
  double history_dt_ = 0;
  std::vector<V> x_prev_;
  // scratch: accelerations, trial states and RK4 accumulators
  std::vector<V> a0_, a1_, xs_, vs_, sum_x_, sum_v_;
  // implicit euler: unknown velocities, residual accelerations, jacobian blocks
  std::vector<V> u_;
  std::vector<double> dadx_, dadv_;
  std::unique_ptr<detail::DenseSolver, detail::DenseSolverDeleter> solver_;
  std::size_t solver_n_ = 0;
};

// ---------------------------------------------------------------------------------
// implementation of the templated steps (instantiated in src/integrate/integrate.cpp
// for double, Vec2, Vec3 and Vec3f; kept here so hot loops inline the accel callable)

template <class V>
template <class Accel>
void Integrator<V>::step(double t, double dt, std::span<V> x, std::span<V> v, Accel&& accel) {
  // validate once per step, never per object (one call, behind the header)
  detail::check_step(t, dt, x.size(), v.size(), sizeof(Scalar));
  const Scalar h = static_cast<Scalar>(dt);
  ensure_size(x.size());
  if (x.empty()) return;
  switch (method_) {
    case Method::ExplicitEuler: step_explicit_euler(t, h, x, v, accel); break;
    case Method::SemiImplicitEuler: step_semi_implicit_euler(t, h, x, v, accel); break;
    case Method::PositionVerlet: step_position_verlet(t, dt, x, v, accel); break;
    case Method::VelocityVerlet: step_velocity_verlet(t, h, x, v, accel); break;
    case Method::Rk4: step_rk4(t, h, x, v, accel); break;
    case Method::ImplicitEuler: step_implicit_euler(t, dt, x, v, accel); break;
  }
}

template <class V>
template <class Accel1>
void Integrator<V>::step_one(double t, double dt, V& x, V& v, Accel1&& accel) {
  // wrap the per-object function as an array function over one element
  auto wrapped = [&accel](double tt, std::span<const V> xs, std::span<const V> vs, std::span<V> a) {
    for (std::size_t i = 0; i < xs.size(); ++i) a[i] = accel(tt, xs[i], vs[i]);
  };
  step(t, dt, std::span<V>(&x, 1), std::span<V>(&v, 1), wrapped);
}

// Explicit (forward) Euler, Euler 1768: both updates use the state at the start of the
// step. x uses the OLD velocity. Order 1; on an undamped oscillator each step multiplies
// the energy by 1 + (omega dt)^2, so it is unstable for every dt.
template <class V>
template <class Accel>
void Integrator<V>::step_explicit_euler(double t, Scalar h, std::span<V> x, std::span<V> v,
                                        Accel& accel) {
  // acceleration at the start of the step
  eval(accel, t, x, v, a0_);
  // position with the old velocity, then velocity
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i] += v[i] * h;
    v[i] += a0_[i] * h;
  }
}

// Semi-implicit (symplectic) Euler: kick then drift. Hairer, Lubich & Wanner, "Geometric
// Numerical Integration" (2nd ed. 2006), section I.1.2, eq. (1.9) (the variant with v
// updated first). Order 1, symplectic: energy error bounded by O(omega dt), no drift.
template <class V>
template <class Accel>
void Integrator<V>::step_semi_implicit_euler(double t, Scalar h, std::span<V> x, std::span<V> v,
                                             Accel& accel) {
  // acceleration at the start of the step
  eval(accel, t, x, v, a0_);
  // velocity first, then position with the new velocity
  for (std::size_t i = 0; i < x.size(); ++i) {
    v[i] += a0_[i] * h;
    x[i] += v[i] * h;
  }
}

// Position (Stormer-)Verlet in the workbook's form: x_{n+1} = 2 x_n - x_{n-1} + a_n dt^2.
// Verlet, Phys. Rev. 159 (1967) 98, eq. (4); Hairer, Lubich & Wanner (2006) I.1.4.
// Velocity is not part of the recurrence; it is reported as the second-order estimate
// v_{n+1} = (x_{n+1} - x_n)/dt + a_{n+1} dt/2, which equals velocity Verlet's velocity in
// exact arithmetic, so energy measured with it is Verlet's bounded energy. a_{n+1} needs
// a velocity for velocity-dependent forces: it is evaluated with the predictor
// (x_{n+1} - x_n)/dt + a_n dt/2 and cached for the next step (one evaluation per step).
// History start (after reset, or when dt, n or the method changes) is second order:
// x_{-1} = x_0 - v_0 dt + a_0 dt^2/2.
template <class V>
template <class Accel>
void Integrator<V>::step_position_verlet(double t, double dt, std::span<V> x, std::span<V> v,
                                         Accel& accel) {
  const Scalar h = static_cast<Scalar>(dt);
  const Scalar h2 = h * h;
  const Scalar half_h = h / Scalar(2);
  const Scalar inv_h = Scalar(1) / h;  // one division per step, not two per object
  // (re)start the history from the current x and v when it is missing or stale
  if (!history_valid_ || dt != history_dt_) {
    eval(accel, t, x, v, a0_);
    for (std::size_t i = 0; i < x.size(); ++i) x_prev_[i] = x[i] - v[i] * h + a0_[i] * (h2 / Scalar(2));
    history_valid_ = true;
    history_dt_ = dt;
  }
  // the verlet recurrence with the acceleration at the current positions (in a0_)
  for (std::size_t i = 0; i < x.size(); ++i) {
    const V xn = x[i];
    x[i] = xn * Scalar(2) - x_prev_[i] + a0_[i] * h2;
    x_prev_[i] = xn;
    vs_[i] = (x[i] - xn) * inv_h + a0_[i] * half_h;
  }
  // acceleration at the new positions (predicted velocity), kept for the next step
  eval(accel, t + dt, x, vs_, a0_);
  // second-order velocity estimate
  for (std::size_t i = 0; i < x.size(); ++i) v[i] = (x[i] - x_prev_[i]) * inv_h + a0_[i] * half_h;
}

// Velocity Verlet (kick-drift-kick written as drift with half kick): Swope, Andersen,
// Berens & Wilson, J. Chem. Phys. 76 (1982) 637; Hairer, Lubich & Wanner (2006) I.1.4.
//   x1 = x0 + v0 dt + a0 dt^2/2
//   a1 = a(t + dt, x1, v0 + a0 dt)      (velocity predicted by Euler: exact for forces that
//                                         do not depend on v; keeps order 2 when they do)
//   v1 = v0 + (a0 + a1) dt/2
// a0 is re-evaluated each step from the actual (x, v) rather than reusing a1, so writes to
// v between steps and velocity-dependent forces are always honoured (two evaluations).
template <class V>
template <class Accel>
void Integrator<V>::step_velocity_verlet(double t, Scalar h, std::span<V> x, std::span<V> v,
                                         Accel& accel) {
  const Scalar half_h2 = h * h / Scalar(2);
  const Scalar half_h = h / Scalar(2);
  // acceleration at the start of the step
  eval(accel, t, x, v, a0_);
  // drift with the half kick; predict the velocity for the end-of-step acceleration
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i] += v[i] * h + a0_[i] * half_h2;
    vs_[i] = v[i] + a0_[i] * h;
  }
  // acceleration at the end of the step
  eval(accel, t + static_cast<double>(h), x, vs_, a1_);
  // velocity with the trapezoid of the two accelerations
  for (std::size_t i = 0; i < x.size(); ++i) v[i] += (a0_[i] + a1_[i]) * half_h;
}

// Classical fourth-order Runge-Kutta on the first-order system (x, v)' = (v, a), exactly
// the workbook's listing 3.1. Kutta, Z. Math. Phys. 46 (1901) 435; Hairer, Norsett &
// Wanner, "Solving ODEs I" (1993) II.1, Table 1.2. Order 4, four evaluations. On the
// oscillator each step scales the energy by 1 - (omega dt)^6/72 + (omega dt)^8/576.
template <class V>
template <class Accel>
void Integrator<V>::step_rk4(double t, Scalar h, std::span<V> x, std::span<V> v, Accel& accel) {
  const Scalar half_h = h / Scalar(2);
  const double th = t + static_cast<double>(h) / 2;
  // stage 1 at the start: accumulate, then the half-step state
  eval(accel, t, x, v, a0_);
  for (std::size_t i = 0; i < x.size(); ++i) {
    sum_x_[i] = v[i];
    sum_v_[i] = a0_[i];
    xs_[i] = x[i] + v[i] * half_h;
    vs_[i] = v[i] + a0_[i] * half_h;
  }
  // stage 2 at the midpoint
  eval(accel, th, xs_, vs_, a0_);
  for (std::size_t i = 0; i < x.size(); ++i) {
    sum_x_[i] += vs_[i] * Scalar(2);
    sum_v_[i] += a0_[i] * Scalar(2);
    xs_[i] = x[i] + vs_[i] * half_h;
    vs_[i] = v[i] + a0_[i] * half_h;
  }
  // stage 3 at the midpoint again, with the stage-2 slopes
  eval(accel, th, xs_, vs_, a0_);
  for (std::size_t i = 0; i < x.size(); ++i) {
    sum_x_[i] += vs_[i] * Scalar(2);
    sum_v_[i] += a0_[i] * Scalar(2);
    xs_[i] = x[i] + vs_[i] * h;
    vs_[i] = v[i] + a0_[i] * h;
  }
  // stage 4 at the end, then the weighted sum (1, 2, 2, 1)/6
  eval(accel, t + static_cast<double>(h), xs_, vs_, a0_);
  const Scalar sixth_h = h / Scalar(6);
  for (std::size_t i = 0; i < x.size(); ++i) {
    sum_x_[i] += vs_[i];
    sum_v_[i] += a0_[i];
    x[i] += sum_x_[i] * sixth_h;
    v[i] += sum_v_[i] * sixth_h;
  }
}

// Implicit (backward) Euler: v1 = v0 + dt a(t1, x0 + dt v1, v1), x1 = x0 + dt v1.
// Hairer & Wanner, "Solving ODEs II" (1996) IV.8 (Newton for implicit methods); Baraff &
// Witkin, "Large steps in cloth simulation", SIGGRAPH 1998 (same unknown, v1). Solved for
// v1 by Newton's method on F(u) = u - v0 - dt a(t1, x0 + dt u, u), with Jacobian
// J = I - dt (dt da/dx + da/dv) from forward differences (or the user's callback) and a
// dense partial-pivot LU (Eigen). Starts from u = v0. On linear problems it reaches
// round-off in 2 iterations with an exact Jacobian and 3 with finite differences (whose
// relative error ~1e-8 is squared away by the second update). Order 1, unconditionally stable,
// damps energy by 1/(1 + (omega dt)^2) per step on the oscillator.
template <class V>
template <class Accel>
void Integrator<V>::step_implicit_euler(double t, double dt, std::span<V> x, std::span<V> v,
                                        Accel& accel) {
  using T = detail::VecTraits<V>;
  const std::size_t n = x.size();
  const std::size_t N = n * kDim;
  const Scalar h = static_cast<Scalar>(dt);
  const double t1 = t + dt;
  double* J = detail::dense_matrix(*solver_);
  double* r = detail::dense_rhs(*solver_);
  double tol = newton_.tolerance;
  if constexpr (std::is_same_v<Scalar, float>) tol = tol < 1e-6 ? 1e-6 : tol;
  const double fd_eps = std::sqrt(static_cast<double>(std::numeric_limits<Scalar>::epsilon()));
  // initial guess: the current velocity
  for (std::size_t i = 0; i < n; ++i) u_[i] = v[i];
  stats_ = {};
  for (int iter = 1;; ++iter) {
    // residual at the trial velocity: r = -(u - v0 - dt a(t1, x0 + dt u, u))
    for (std::size_t i = 0; i < n; ++i) xs_[i] = x[i] + u_[i] * h;
    eval(accel, t1, xs_, u_, a0_);
    for (std::size_t i = 0; i < n; ++i)
      for (int k = 0; k < kDim; ++k)
        r[i * kDim + k] = -(static_cast<double>(T::get(u_[i], k)) - static_cast<double>(T::get(v[i], k)) -
                            dt * static_cast<double>(T::get(a0_[i], k)));
    // jacobian J = I - dt (dt da/dx + da/dv), column-major
    if (jacobian_) {
      std::fill(dadx_.begin(), dadx_.end(), 0.0);
      std::fill(dadv_.begin(), dadv_.end(), 0.0);
      jacobian_(t1, std::span<const V>(xs_), std::span<const V>(u_), std::span<double>(dadx_),
                std::span<double>(dadv_));
      for (std::size_t c = 0; c < N; ++c)
        for (std::size_t rr = 0; rr < N; ++rr)
          J[c * N + rr] = (rr == c ? 1.0 : 0.0) - dt * (dt * dadx_[rr * N + c] + dadv_[rr * N + c]);
    } else {
      // forward differences: perturb one scalar of u (and the matching x) per column
      for (std::size_t c = 0; c < N; ++c) {
        const std::size_t i = c / kDim;
        const int k = static_cast<int>(c % kDim);
        const Scalar u_old = T::get(u_[i], k);
        const V x_old = xs_[i];
        const Scalar e = static_cast<Scalar>(fd_eps * std::max(1.0, std::abs(static_cast<double>(u_old))));
        T::at(u_[i], k) = u_old + e;
        const Scalar de = T::get(u_[i], k) - u_old;  // the step actually taken
        T::at(xs_[i], k) = T::get(x[i], k) + T::get(u_[i], k) * h;
        eval(accel, t1, xs_, u_, a1_);
        T::at(u_[i], k) = u_old;
        xs_[i] = x_old;
        for (std::size_t j = 0; j < n; ++j)
          for (int kk = 0; kk < kDim; ++kk) {
            const std::size_t rr = j * kDim + kk;
            const double da = (static_cast<double>(T::get(a1_[j], kk)) - static_cast<double>(T::get(a0_[j], kk))) /
                              static_cast<double>(de);
            J[c * N + rr] = (rr == c ? 1.0 : 0.0) - dt * da;
          }
      }
    }
    // newton update: J delta = r
    detail::dense_solve(*solver_);
    double max_delta = 0, max_u = 1;
    for (std::size_t i = 0; i < n; ++i)
      for (int k = 0; k < kDim; ++k) {
        const double d = r[i * kDim + k];
        if (!std::isfinite(d)) detail::throw_singular(t, dt);
        T::at(u_[i], k) = static_cast<Scalar>(static_cast<double>(T::get(u_[i], k)) + d);
        max_delta = std::max(max_delta, std::abs(d));
        max_u = std::max(max_u, std::abs(static_cast<double>(T::get(u_[i], k))));
      }
    stats_.iterations = iter;
    stats_.last_update = max_delta;
    // converged: the last update is at the tolerance relative to the velocity scale
    if (max_delta <= tol * max_u) break;
    if (iter >= newton_.max_iterations) detail::throw_newton_failure(iter, max_delta, t, dt);
  }
  // commit: x1 = x0 + dt v1
  for (std::size_t i = 0; i < n; ++i) {
    x[i] += u_[i] * h;
    v[i] = u_[i];
  }
}

extern template class Integrator<double>;
extern template class Integrator<Vec2>;
extern template class Integrator<Vec3>;
extern template class Integrator<Vec3f>;

}  // namespace pba
