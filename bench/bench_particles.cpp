// Particle-steps per second (issue 4): N particles under gravity, quadratic drag, gusting
// wind and a ground plane with restitution and friction, one core, semi-implicit Euler,
// float structure of arrays. Goals: >= 800 M particle-steps/s in cache (4k particles) and
// >= 450 M from main memory (16M particles).
//
//   taskset -c 1 build/release/bin/bench_particles --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true
//
// Rates are per second of the benchmark thread's CPU time. The state hash after the timed
// steps is printed so runs can be compared (DESIGN 6): the broad phase on and off, and
// uniform or varied masses at the same step count, must print the same hash (the masses
// differ between the two, so only on/off pairs compare). The per-phase profile of the last
// step is printed too (DESIGN 7).
//
// BM_StreamCeiling measures what one core can move with the kernel's access pattern (six
// float columns read and written in place, one more read) and trivial arithmetic: the
// bandwidth ceiling of the step from main memory, for two layouts of the columns.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdint>
#include <vector>

#include "pba/particles.h"

namespace {

// Three regimes, each steady for as long as the benchmark runs (so the figure does not
// depend on how long it ran):
//   0  no ground: forces and integration alone
//   1  in flight: the ground plane is there, 100 km below, and nothing reaches it (the
//      broad phase skips it; with the broad phase off, the plane's first pass runs for
//      every particle and the response for none)
//   2  resting: every particle starts on the ground and stays in contact every step
//      (the worst case: the full contact response, restitution and friction, for all)
enum Regime { kNoGround = 0, kInFlight = 1, kResting = 2 };

// the particles: a box of random positions and velocities (a fixed LCG, so the same N
// always gives the same start); masses varied in [0.01, 0.02] kg, or all 0.015 kg
pba::ParticleSystem make_system(std::size_t n, pba::Method method, int regime, bool uniform_mass) {
  pba::ParticleSystemDef def;
  def.capacity = n;
  def.method = method;
  def.forces.quadratic_drag = 2e-4;
  def.forces.wind = {.velocity = {3, 0, 1}, .gust = 1.5, .gust_period = 0.5, .seed = 9};
  pba::ParticleSystem ps(def);
  std::uint64_t s = 12345;
  auto uniform = [&s] {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(s >> 11) * 0x1.0p-53;
  };
  const double r = 0.02;
  for (std::size_t i = 0; i < n; ++i) {
    const double y = regime == kResting ? r : 10 * uniform() + 0.1;
    const double vy = regime == kResting ? 0.0 : 6 * uniform() - 1;
    const double m = 0.01 + 0.01 * uniform();
    ps.spawn({.position = {20 * uniform() - 10, y, 20 * uniform() - 10},
              .velocity = {4 * uniform() - 2, vy, 4 * uniform() - 2},
              .mass = uniform_mass ? 0.015 : m,
              .radius = r});
  }
  return ps;
}

void BM_ParticleStep(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const auto method = static_cast<pba::Method>(state.range(1));
  const int regime = static_cast<int>(state.range(2));
  const bool uniform_mass = state.range(3) != 0;
  const bool broad_phase = state.range(4) != 0;
  pba::ParticleSystem ps = make_system(n, method, regime, uniform_mass);
  ps.set_broad_phase(broad_phase);
  const double ground_y = regime == kInFlight ? -1e5 : 0.0;
  const pba::Collider ground =
      pba::Collider::plane({0, 1, 0}, ground_y, {.restitution = 0.6, .friction = 0.3});
  const std::size_t n_colliders = regime == kNoGround ? 0 : 1;
  const double dt = 1.0 / 120;
  double t = 0;
  long long steps = 0;
  for (auto _ : state) {
    ps.step(t, dt, std::span(&ground, n_colliders), {});
    t += dt;
    ++steps;
  }
  // particle-steps per second of this thread's CPU time (robust on a shared machine;
  // the Time column is wall time)
  state.counters["particle_steps_per_s"] =
      benchmark::Counter(static_cast<double>(n) * static_cast<double>(steps), benchmark::Counter::kIsRate);
  state.counters["contacts_last_step"] = static_cast<double>(ps.contacts());
  state.counters["exact_blocks"] = static_cast<double>(ps.exact_blocks());
  const pba::ParticleProfile& p = ps.profile();
  std::fprintf(stderr,
               "n=%zu %s regime=%d masses=%s broad=%d steps=%lld hash=%016llx profile(ms): integrate+collide %.3f "
               "recycle %.3f emit %.3f total %.3f\n",
               n, std::string(pba::name(method)).c_str(), regime, uniform_mass ? "uniform" : "varied",
               broad_phase ? 1 : 0, steps, static_cast<unsigned long long>(ps.hash()), p.integrate * 1e3,
               p.recycle * 1e3, p.emit * 1e3, p.total * 1e3);
}

const int kSie = static_cast<int>(pba::Method::SemiImplicitEuler);

// the benchmark: gravity, quadratic drag, gusting wind and a ground plane with
// restitution, semi-implicit Euler, varied masses; in flight, resting, and without ground
BENCHMARK(BM_ParticleStep)
    ->ArgNames({"n", "method", "regime", "uniform", "broad"})
    ->Args({4096, kSie, kInFlight, 0, 1})
    ->Args({1 << 20, kSie, kInFlight, 0, 1})
    ->Args({1 << 24, kSie, kInFlight, 0, 1})
    ->Args({4096, kSie, kResting, 0, 1})
    ->Args({1 << 20, kSie, kResting, 0, 1})
    ->Args({1 << 24, kSie, kResting, 0, 1})
    ->Args({4096, kSie, kNoGround, 0, 1})
    ->Args({1 << 20, kSie, kNoGround, 0, 1})
    ->Args({1 << 24, kSie, kNoGround, 0, 1})
    ->Unit(benchmark::kMicrosecond);

// the broad phase off (every particle through the plane's test), and uniform masses (the
// inverse-mass column is not read: 48 instead of 52 bytes per particle-step)
BENCHMARK(BM_ParticleStep)
    ->ArgNames({"n", "method", "regime", "uniform", "broad"})
    ->Args({4096, kSie, kInFlight, 0, 0})
    ->Args({1 << 24, kSie, kInFlight, 0, 0})
    ->Args({4096, kSie, kInFlight, 1, 1})
    ->Args({1 << 24, kSie, kInFlight, 1, 1})
    ->Unit(benchmark::kMicrosecond);

// the other integrators through the generic path, in cache, resting, for comparison
BENCHMARK(BM_ParticleStep)
    ->ArgNames({"n", "method", "regime", "uniform", "broad"})
    ->Args({4096, static_cast<int>(pba::Method::ExplicitEuler), kResting, 0, 1})
    ->Args({4096, static_cast<int>(pba::Method::VelocityVerlet), kResting, 0, 1})
    ->Args({4096, static_cast<int>(pba::Method::Rk4), kResting, 0, 1})
    ->Unit(benchmark::kMicrosecond);

// six columns read-modified-written in place and one read, as the step does, with a
// multiply and an add per value: the most one core moves with that pattern
void stream(std::size_t n, float* __restrict__ x, float* __restrict__ y, float* __restrict__ z,
            float* __restrict__ vx, float* __restrict__ vy, float* __restrict__ vz, const float* __restrict__ m) {
  for (std::size_t i = 0; i < n; ++i) {
    vx[i] += m[i] * 0.001f;
    vy[i] += m[i] * 0.001f;
    vz[i] += m[i] * 0.001f;
    x[i] += vx[i] * 0.01f;
    y[i] += vy[i] * 0.01f;
    z[i] += vz[i] * 0.01f;
  }
}

// layout 0: seven separate std::vector columns (each its own allocation, so large ones
// all start at the same offset within a page); layout 1: pba::detail::HotColumns (one
// allocation, columns staggered), as ParticleSystem stores them
void BM_StreamCeiling(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const bool hot = state.range(1) != 0;
  std::vector<std::vector<float>> separate;
  pba::detail::HotColumns columns;
  float* c[7];
  if (hot) {
    columns.reserve(n);
    for (std::size_t i = 0; i < n; ++i) columns.push();
    for (int k = 0; k < 7; ++k) c[k] = columns[k];
  } else {
    separate.resize(7);
    for (int k = 0; k < 7; ++k) {
      separate[k].resize(n);
      c[k] = separate[k].data();
    }
  }
  for (int k = 0; k < 7; ++k)
    for (std::size_t i = 0; i < n; ++i) c[k][i] = 1.0f;
  for (auto _ : state) {
    stream(n, c[0], c[1], c[2], c[3], c[4], c[5], c[6]);
    benchmark::ClobberMemory();
  }
  // 24 bytes read and 24 written in place, 4 more read, per row
  state.counters["GB_per_s"] = benchmark::Counter(52.0 * static_cast<double>(n) * static_cast<double>(state.iterations()),
                                                  benchmark::Counter::kIsRate, benchmark::Counter::kIs1000);
  state.counters["rows_per_s"] = benchmark::Counter(static_cast<double>(n) * static_cast<double>(state.iterations()),
                                                    benchmark::Counter::kIsRate);
}

BENCHMARK(BM_StreamCeiling)
    ->ArgNames({"n", "hot_columns"})
    ->Args({1 << 24, 0})
    ->Args({1 << 24, 1})
    ->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
