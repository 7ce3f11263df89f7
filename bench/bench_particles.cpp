// Particle-steps per second (issue 4): N particles under gravity, quadratic drag, gusting
// wind and a ground plane with restitution and friction, one core, semi-implicit Euler,
// float structure of arrays. Goals: >= 800 M particle-steps/s in cache (4k particles) and
// >= 450 M from main memory (16M particles).
//
//   build/release/bin/bench_particles --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true
//
// Rates are per second of the benchmark thread's CPU time. The state hash after the timed
// steps is printed so runs can be compared (DESIGN 6),
// and the per-phase profile of the last step (DESIGN 7).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdint>

#include "pba/particles.h"

namespace {

// Three regimes, each steady for as long as the benchmark runs (so the figure does not
// depend on how long it ran):
//   0  no ground: forces and integration alone
//   1  in flight: the ground plane is there, 100 km below, and nothing reaches it (the
//      plane's cheap first pass runs for every particle, the response for none)
//   2  resting: every particle starts on the ground and stays in contact every step
//      (the worst case: the full contact response, restitution and friction, for all)
enum Regime { kNoGround = 0, kInFlight = 1, kResting = 2 };

// the particles: a box of random positions and velocities (a fixed LCG, so the same N
// always gives the same start)
pba::ParticleSystem make_system(std::size_t n, pba::Method method, int regime) {
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
    ps.spawn({.position = {20 * uniform() - 10, y, 20 * uniform() - 10},
              .velocity = {4 * uniform() - 2, vy, 4 * uniform() - 2},
              .mass = 0.01 + 0.01 * uniform(),
              .radius = r});
  }
  return ps;
}

void BM_ParticleStep(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const auto method = static_cast<pba::Method>(state.range(1));
  const int regime = static_cast<int>(state.range(2));
  pba::ParticleSystem ps = make_system(n, method, regime);
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
  const pba::ParticleProfile& p = ps.profile();
  std::fprintf(stderr, "n=%zu %s regime=%d steps=%lld hash=%016llx profile(ms): integrate+collide %.3f recycle %.3f emit %.3f total %.3f\n",
               n, std::string(pba::name(method)).c_str(), regime, steps, static_cast<unsigned long long>(ps.hash()),
               p.integrate * 1e3, p.recycle * 1e3, p.emit * 1e3, p.total * 1e3);
}

const int kSie = static_cast<int>(pba::Method::SemiImplicitEuler);

// the benchmark: gravity, quadratic drag, gusting wind and a ground plane with
// restitution, semi-implicit Euler, in flight and resting
BENCHMARK(BM_ParticleStep)
    ->ArgNames({"n", "method", "regime"})
    ->Args({4096, kSie, kInFlight})
    ->Args({1 << 20, kSie, kInFlight})
    ->Args({1 << 24, kSie, kInFlight})
    ->Args({4096, kSie, kResting})
    ->Args({1 << 20, kSie, kResting})
    ->Args({1 << 24, kSie, kResting})
    ->Unit(benchmark::kMicrosecond);

// the same without the ground: the cost of forces and integration alone
BENCHMARK(BM_ParticleStep)
    ->ArgNames({"n", "method", "regime"})
    ->Args({4096, kSie, kNoGround})
    ->Args({1 << 20, kSie, kNoGround})
    ->Args({1 << 24, kSie, kNoGround})
    ->Unit(benchmark::kMicrosecond);

// the other integrators through the generic path, in cache, resting, for comparison
BENCHMARK(BM_ParticleStep)
    ->ArgNames({"n", "method", "regime"})
    ->Args({4096, static_cast<int>(pba::Method::ExplicitEuler), kResting})
    ->Args({4096, static_cast<int>(pba::Method::VelocityVerlet), kResting})
    ->Args({4096, static_cast<int>(pba::Method::RK4), kResting})
    ->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
