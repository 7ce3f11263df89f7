// Overhead of the time-stepping machinery itself (workbook 3.1): what one rendered frame
// costs beyond the ticks, and what one snapshot handoff costs. Ticks here do almost nothing,
// so the numbers are the stepper's own bookkeeping (two clock reads per tick dominate).
#include <benchmark/benchmark.h>

#include <vector>

#include "pba/time.h"

namespace {

// one 60 Hz frame per iteration, with the strategy's ticks (1, 10 or 1 of them)
void BM_Advance(benchmark::State& state) {
  pba::StepperSettings s;
  s.strategy = static_cast<pba::Strategy>(state.range(0));
  pba::TimeStepper stepper(s);
  double sink = 0;
  auto tick = [&](double t, double dt) { sink += t * dt; };
  for (auto _ : state) {
    stepper.advance_ns(16'666'667, tick);
    benchmark::DoNotOptimize(sink);
  }
  state.counters["ticks/frame"] =
      static_cast<double>(stepper.tick_count()) / static_cast<double>(state.iterations());
  state.SetLabel(std::string(pba::strategy_name(s.strategy)));
}
BENCHMARK(BM_Advance)->Arg(0)->Arg(1)->Arg(2);

// the readout: totals() computes a median of 256 tick timings
void BM_Totals(benchmark::State& state) {
  pba::TimeStepper stepper;
  for (int i = 0; i < 1000; ++i) stepper.advance(1.0 / 60, [](double, double) {});
  for (auto _ : state) benchmark::DoNotOptimize(stepper.totals());
}
BENCHMARK(BM_Totals);

// publish + acquire of a snapshot of n particles (positions), single-threaded: the cost of
// the copies the threaded strategy adds per publication
void BM_SnapshotHandoff(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<pba::Vec3> world(n, pba::Vec3(1.0));
  pba::SnapshotBuffer<std::vector<pba::Vec3>> buffer(world);
  long long k = 0;
  for (auto _ : state) {
    buffer.write_slot() = world;
    buffer.publish({0.0, ++k, 0});
    buffer.acquire();
    benchmark::DoNotOptimize(buffer.current().data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<long long>(n * sizeof(pba::Vec3)) * 2);
}
BENCHMARK(BM_SnapshotHandoff)->Arg(1000)->Arg(100000);

}  // namespace

BENCHMARK_MAIN();
