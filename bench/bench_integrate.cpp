// Body-steps per second for every integrator on arrays of 1k and 1M bodies under gravity
// plus linear drag, in double (glm::dvec3) and float (glm::vec3). Implicit Euler is
// measured on 100 bodies only: its dense Newton solve is O(N^3) by design (see
// docs/integration.md), so 1k bodies would need a 3000 x 3000 LU per iteration.
//
//   build/<dir>/bin/bench_integrate [--benchmark_filter=rk4]
//
// The counter "body_steps/s" is what to compare; the state hash after the run is printed
// as a label so a changed result is visible next to a changed speed.
#include <benchmark/benchmark.h>

#include <vector>

#include "pba/integrate.h"

namespace {

// gravity plus linear drag, a = g - k v: velocity-dependent, so every method's
// velocity handling is exercised
struct GravityDrag {
  template <class V>
  void operator()(double, std::span<const V>, std::span<const V> v, std::span<V> a) const {
    using S = typename V::value_type;
    const V g(S(0), S(-9.81), S(0));
    const S k = S(0.1);
    for (std::size_t i = 0; i < v.size(); ++i) a[i] = g - v[i] * k;
  }
};

template <class V>
void BM_Integrate(benchmark::State& state) {
  const auto m = static_cast<pba::Method>(state.range(0));
  const auto n = static_cast<std::size_t>(state.range(1));
  pba::Integrator<V> integ(m);
  std::vector<V> x(n), v(n);
  // spread initial states so no two bodies are identical
  for (std::size_t i = 0; i < n; ++i) {
    using S = typename V::value_type;
    x[i] = V(S(i % 100), S(10 + i % 7), S(i % 13));
    v[i] = V(S(1 + i % 5), S(5), S(-1));
  }
  integ.resize(n);
  double t = 0;
  const double dt = 1.0 / 240;
  for (auto _ : state) {
    integ.step(t, dt, std::span<V>(x), std::span<V>(v), GravityDrag{});
    t += dt;
    benchmark::DoNotOptimize(x.data());
    benchmark::ClobberMemory();
  }
  state.counters["body_steps/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n), benchmark::Counter::kIsRate);
  state.SetLabel(std::string(pba::name(m)) + " hash=" +
                 std::to_string(pba::hash_span(std::span<const V>(x)) % 1000000));
}

void Args(benchmark::internal::Benchmark* b) {
  // every explicit method at 1k and 1M bodies; implicit Euler at 100 (dense solve)
  for (pba::Method m : pba::kAllMethods) {
    if (m == pba::Method::ImplicitEuler) {
      b->Args({static_cast<long>(m), 100});
      continue;
    }
    b->Args({static_cast<long>(m), 1000});
    b->Args({static_cast<long>(m), 1000000});
  }
  b->ArgNames({"method", "bodies"});
}

BENCHMARK_TEMPLATE(BM_Integrate, pba::Vec3)->Apply(Args)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Integrate, pba::Vec3f)->Apply(Args)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
