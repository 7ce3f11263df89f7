// Implementation of pba/integrate.h: method names, the Integrator's storage, the dense
// Newton solve (Eigen, kept out of the public header) and the explicit instantiations.
#include "pba/integrate.h"

#include <Eigen/Dense>

#include "core/squarable.h"

namespace pba {

namespace {
struct MethodInfo {
  Method method;
  std::string_view name;
  std::string_view label;
  int order;
  bool symplectic;
  int evaluations;
};
constexpr std::array<MethodInfo, 6> kInfo = {{
    {Method::ExplicitEuler, "euler", "Explicit Euler", 1, false, 1},
    {Method::SemiImplicitEuler, "semi-implicit-euler", "Semi-implicit Euler", 1, true, 1},
    {Method::PositionVerlet, "verlet", "Position Verlet", 2, true, 1},
    {Method::VelocityVerlet, "velocity-verlet", "Velocity Verlet", 2, true, 2},
    {Method::Rk4, "rk4", "RK4", 4, false, 4},
    {Method::ImplicitEuler, "implicit-euler", "Implicit Euler", 1, false, -1},
}};

const MethodInfo& info(Method m) {
  // table lookup; an out-of-range enum value is a programming error
  const auto i = static_cast<std::size_t>(m);
  if (i >= kInfo.size()) throw Error("pba::Method: invalid value " + std::to_string(i));
  return kInfo[i];
}
}  // namespace

std::string_view name(Method m) { return info(m).name; }
std::string_view label(Method m) { return info(m).label; }
int order(Method m) { return info(m).order; }
bool is_symplectic(Method m) { return info(m).symplectic; }
int evaluations_per_step(Method m) { return info(m).evaluations; }

std::string method_names() {
  std::string s;
  for (const auto& i : kInfo) {
    if (!s.empty()) s += ", ";
    s += i.name;
  }
  return s;
}

Method parse_method(std::string_view text, std::string_view where) {
  // exact match against the CLI names
  for (const auto& i : kInfo)
    if (i.name == text) return i.method;
  throw Error(std::string(where) + ": unknown integrator '" + std::string(text) +
              "'; valid names: " + method_names());
}

namespace detail {

class DenseSolver {
 public:
  explicit DenseSolver(std::size_t n) : a(n, n), b(n), x(n), lu(static_cast<Eigen::Index>(n)) {
    a.setZero();
    b.setZero();
  }
  Eigen::MatrixXd a;
  Eigen::VectorXd b, x;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
};

void DenseSolverDeleter::operator()(DenseSolver* s) const { delete s; }

std::unique_ptr<DenseSolver, DenseSolverDeleter> make_dense_solver(std::size_t n) {
  return std::unique_ptr<DenseSolver, DenseSolverDeleter>(new DenseSolver(n));
}
double* dense_matrix(DenseSolver& s) { return s.a.data(); }
double* dense_rhs(DenseSolver& s) { return s.b.data(); }
void dense_solve(DenseSolver& s) {
  // factorise into preallocated storage and solve without temporaries
  s.lu.compute(s.a);
  s.x.noalias() = s.lu.solve(s.b);
  s.b = s.x;
}

namespace {
// check_step's refusals, in its order (kept out of it: their strings gave it a stack frame that
// cost the lab's loop 1.2% more instructions than the checks inline in the header had)
[[noreturn, gnu::noinline, gnu::cold]] void throw_bad_step(double t, double dt, std::size_t nx, std::size_t nv,
                                                            std::size_t scalar_bytes) {
  require_positive(dt, "Integrator::step(dt)");
  require_finite(t, "Integrator::step(t)");
  // the step in the vectors' precision
  constexpr std::string_view why = "the step is used in that precision, divided by and squared";
  if (scalar_bytes == sizeof(float) && !squarable<float>(dt))
    throw_not_squarable<float>(dt, "Integrator::step(dt)", "s for an integrator of float vectors", why);
  if (scalar_bytes != sizeof(float) && !squarable<double>(dt))
    throw_not_squarable<double>(dt, "Integrator::step(dt)", "s for an integrator of double vectors", why);
  throw Error("Integrator::step: x has " + std::to_string(nx) + " elements but v has " + std::to_string(nv) +
              "; they must be the same size");
}
}  // namespace

void check_step(double t, double dt, std::size_t nx, std::size_t nv, std::size_t scalar_bytes) {
  const bool squares = scalar_bytes == sizeof(float) ? squarable<float>(dt) : squarable<double>(dt);
  if (std::isfinite(dt) && dt > 0 && std::isfinite(t) && squares && nx == nv) [[likely]]
    return;
  throw_bad_step(t, dt, nx, nv, scalar_bytes);
}

void throw_newton_failure(int iterations, double update, double t, double dt) {
  throw NewtonFailure("implicit Euler: Newton did not converge in " + std::to_string(iterations) +
              " iterations at t = " + format_value(t) + " s, dt = " + format_value(dt) +
              " s (last update " + format_value(update) +
              " m/s); reduce dt or raise NewtonSettings.max_iterations");
}

void throw_too_many_unknowns(std::size_t n_objects, int dim, std::size_t limit) {
  const double n = static_cast<double>(n_objects) * dim;
  throw Error("implicit Euler: " + std::to_string(n_objects) + " objects x " + std::to_string(dim) +
              " components = " + format_value(n) + " unknowns exceeds NewtonSettings.max_unknowns = " +
              std::to_string(limit) + " (the dense Newton solve needs " +
              format_value(std::round(8 * n * n / 1e6)) +
              " MB and O(N^3) time per iteration); use fewer objects or raise the limit");
}

void throw_singular(double t, double dt) {
  throw NewtonFailure("implicit Euler: singular or non-finite Newton system at t = " + format_value(t) +
              " s, dt = " + format_value(dt) + " s (check the acceleration for NaN)");
}

}  // namespace detail

template <class V>
Integrator<V>::Integrator(Method method, NewtonSettings newton) : method_(method) {
  (void)info(method);
  set_newton(newton);
}

template <class V>
Integrator<V>::~Integrator() = default;
template <class V>
Integrator<V>::Integrator(Integrator&&) noexcept = default;
template <class V>
Integrator<V>& Integrator<V>::operator=(Integrator&&) noexcept = default;

template <class V>
void Integrator<V>::set_method(Method m) {
  (void)info(m);
  method_ = m;
  history_valid_ = false;
  if (n_ > 0) resize(n_);
}

template <class V>
void Integrator<V>::set_newton(const NewtonSettings& s) {
  // validate every field, naming it
  require_in_range(s.tolerance, 1e-16, 1e-2, "NewtonSettings.tolerance");
  require_count(s.max_iterations, 1, 100, "NewtonSettings.max_iterations");
  require_count(static_cast<long long>(s.max_unknowns), 1, 20000, "NewtonSettings.max_unknowns");
  newton_ = s;
  if (n_ > 0) resize(n_);
}

template <class V>
void Integrator<V>::set_jacobian(JacobianFn<V> jacobian) {
  jacobian_ = std::move(jacobian);
  if (n_ > 0) resize(n_);
}

template <class V>
void Integrator<V>::resize(std::size_t n) {
  // size a buffer when the method uses it, release it when it does not
  auto fit = [n](std::vector<V>& buf, bool used) {
    if (!used) {
      std::vector<V>().swap(buf);
    } else if (buf.size() != n) {
      buf.resize(n);
    }
  };
  const Method m = method_;
  const bool implicit = m == Method::ImplicitEuler;
  if (implicit && n * kDim > newton_.max_unknowns)
    detail::throw_too_many_unknowns(n, kDim, newton_.max_unknowns);
  fit(a0_, true);
  fit(a1_, m == Method::VelocityVerlet || implicit);
  fit(xs_, m == Method::Rk4 || implicit);
  fit(vs_, m == Method::Rk4 || m == Method::VelocityVerlet || m == Method::PositionVerlet);
  fit(sum_x_, m == Method::Rk4);
  fit(sum_v_, m == Method::Rk4);
  fit(x_prev_, m == Method::PositionVerlet);
  fit(u_, implicit);
  // implicit euler: dense solver and optional analytic jacobian blocks
  const std::size_t N = n * kDim;
  if (implicit) {
    if (!solver_ || solver_n_ != N) {
      solver_ = detail::make_dense_solver(N);
      solver_n_ = N;
    }
  } else {
    solver_.reset();
    solver_n_ = 0;
  }
  const std::size_t jn = implicit && jacobian_ ? N * N : 0;
  if (dadx_.size() != jn) {
    dadx_.assign(jn, 0.0);
    dadv_.assign(jn, 0.0);
  }
  if (n != n_) history_valid_ = false;
  n_ = n;
}

template class Integrator<double>;
template class Integrator<Vec2>;
template class Integrator<Vec3>;
template class Integrator<Vec3f>;

}  // namespace pba
