// Tests for pba/time.h on the caller's thread: the per-frame, max-step and fixed strategies,
// the stall guard and its accounting, determinism across render rates, and bad input.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "error_of.h"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "pba/time.h"

// count every allocation in this test program, to prove advance() makes none
#include "alloc_count.h"

using pba::test_support::g_allocations;

namespace {

using pba::StepperSettings;
using pba::Strategy;
using pba::TimeStepper;
using ::testing::HasSubstr;

using pba::test_support::error_of;

// records every tick's start time and length
struct TickLog {
  std::vector<double> t, dt;
  void operator()(double time, double step) {
    t.push_back(time);
    dt.push_back(step);
  }
  double sum() const {
    double s = 0;
    for (double d : dt) s += d;
    return s;
  }
};

StepperSettings with(Strategy s) {
  StepperSettings st;
  st.strategy = s;
  return st;
}

// frame_time + stepped == simulated + dropped + pending; each total is one or two roundings
// of exact integer counts, so a few ulps of the total is the right tolerance
void expect_balanced(const pba::StepperTotals& t) {
  const double tol = 1e-13 * (1 + t.frame_time);
  EXPECT_NEAR(t.frame_time + t.stepped_time, t.simulated_time + t.dropped_time + t.pending_time,
              tol);
}

// ---------------------------------------------------------------------------------------
// names and bad input

TEST(TimeStrategy, NamesRoundTripAndUnknownNamesAreListed) {
  for (Strategy s : pba::kStrategies) {
    EXPECT_EQ(pba::parse_strategy(pba::strategy_name(s), "--strategy"), s);
    EXPECT_FALSE(pba::strategy_description(s).empty());
  }
  EXPECT_EQ(pba::strategy_name(Strategy::MaxStep), "max-step");
  EXPECT_EQ(error_of([] { pba::parse_strategy("Fixed-Step", "--strategy"); }),
            "--strategy: unknown time-stepping strategy \"Fixed-Step\"; valid: per-frame, "
            "max-step, fixed, threaded");
  EXPECT_THAT(error_of([] { pba::parse_strategy("", "scene.json:3"); }),
              HasSubstr("scene.json:3: unknown time-stepping strategy \"\""));
}

TEST(TimeSettings, BadValuesNameTheFieldAndTheValue) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  auto bad = [](auto&& edit) {
    StepperSettings s;
    edit(s);
    return error_of([&] { TimeStepper stepper(s); });
  };
  EXPECT_EQ(bad([](auto& s) { s.fixed_dt = 0; }),
            "StepperSettings.fixed_dt: must be finite and > 0, got 0");
  EXPECT_EQ(bad([](auto& s) { s.fixed_dt = -0.01; }),
            "StepperSettings.fixed_dt: must be finite and > 0, got -0.01");
  EXPECT_EQ(bad([&](auto& s) { s.fixed_dt = nan; }),
            "StepperSettings.fixed_dt: must be finite and > 0, got nan");
  EXPECT_EQ(bad([&](auto& s) { s.max_dt = inf; }),
            "StepperSettings.max_dt: must be finite and > 0, got inf");
  EXPECT_EQ(bad([](auto& s) { s.fixed_dt = 1e-9; }),
            "StepperSettings.fixed_dt: must be in [1e-06, 10], got 1e-09");
  EXPECT_EQ(bad([](auto& s) { s.ticks_per_frame = 0; }),
            "StepperSettings.ticks_per_frame: must be an integer in [1, 10000], got 0");
  EXPECT_EQ(bad([](auto& s) { s.max_ticks_per_frame = -1; }),
            "StepperSettings.max_ticks_per_frame: must be an integer in [1, 100000], got -1");
  EXPECT_EQ(bad([](auto& s) { s.max_frame_dt = -0.25; }),
            "StepperSettings.max_frame_dt: must be finite and > 0, got -0.25");
  EXPECT_EQ(bad([](auto& s) { s.max_frame_dt = 1e9; }),
            "StepperSettings.max_frame_dt: must be in [0, 3600], got 1e+09");
  EXPECT_EQ(bad([](auto& s) { s.time_scale = 0; }),
            "StepperSettings.time_scale: must be finite and > 0, got 0");
  EXPECT_EQ(bad([](auto& s) { s.strategy = static_cast<Strategy>(7); }),
            "StepperSettings.strategy: not a Strategy, got 7");
  EXPECT_EQ(bad([](auto&) {}), "");

  // validate() takes the caller's prefix, e.g. a config file section
  StepperSettings s;
  s.fixed_dt = -1;
  EXPECT_EQ(error_of([&] { s.validate("--dt"); }), "--dt.fixed_dt: must be finite and > 0, got -1");

  // a rejected change leaves the stepper as it was
  TimeStepper stepper;
  EXPECT_THAT(error_of([&] { stepper.set_settings(s); }), HasSubstr("fixed_dt"));
  EXPECT_EQ(stepper.settings().fixed_dt, 1.0 / 60);
}

TEST(TimeSettings, BadFrameTimesAreRejectedWithTheirValue) {
  TimeStepper stepper;
  auto none = [](double, double) {};
  EXPECT_EQ(error_of([&] { stepper.advance(-0.016, none); }),
            "TimeStepper.advance frame_dt (s): must be in [0, 1e+06], got -0.016");
  EXPECT_EQ(error_of([&] { stepper.advance(std::numeric_limits<double>::quiet_NaN(), none); }),
            "TimeStepper.advance frame_dt (s): must be in [0, 1e+06], got nan");
  EXPECT_EQ(error_of([&] { stepper.advance(std::numeric_limits<double>::infinity(), none); }),
            "TimeStepper.advance frame_dt (s): must be in [0, 1e+06], got inf");
  EXPECT_EQ(error_of([&] { stepper.advance_ns(-5, none); }),
            "TimeStepper.advance_ns frame_ns: must be an integer in [0, 1e15], got -5");
  // the threaded strategy is a PhysicsThread's job
  stepper.set_settings(with(Strategy::Threaded));
  EXPECT_THAT(error_of([&] { stepper.advance(0.016, none); }), HasSubstr("PhysicsThread"));
  EXPECT_FALSE(TimeStepper::runs_on_caller(Strategy::Threaded));
  EXPECT_TRUE(TimeStepper::runs_on_caller(Strategy::Fixed));
  // nothing was counted by the rejected calls
  EXPECT_EQ(stepper.totals().frames, 0);
}

// ---------------------------------------------------------------------------------------
// (a) per-frame

TEST(TimePerFrame, OneTickPerFrameFollowsTheFrameTime) {
  TimeStepper stepper(with(Strategy::PerFrame));
  TickLog log;
  const double frames[] = {1.0 / 30, 1.0 / 60, 0.05, 0.0, 1.0 / 144};
  double total = 0;
  for (double f : frames) {
    const auto s = stepper.advance(f, log);
    EXPECT_EQ(s.ticks, f > 0 ? 1 : 0);
    // dt is the frame rounded to the stepper's unit (1/3 ns for fixed_dt = 1/60)
    if (f > 0) {
      EXPECT_NEAR(s.tick_dt, f, 0.2e-9);
    }
    total += f;
  }
  ASSERT_EQ(log.dt.size(), 4u);
  // each tick starts where the previous ended
  for (std::size_t i = 1; i < log.t.size(); ++i)
    EXPECT_NEAR(log.t[i], log.t[i - 1] + log.dt[i - 1], 1e-15);
  EXPECT_NEAR(stepper.time(), total, 1e-9);
  expect_balanced(stepper.totals());
}

TEST(TimePerFrame, NTicksSplitTheFrameExactly) {
  StepperSettings s = with(Strategy::PerFrame);
  s.ticks_per_frame = 4;
  TimeStepper stepper(s);
  TickLog log;
  for (int i = 0; i < 30; ++i) {
    const auto f = stepper.advance(1.0 / 30, log);
    EXPECT_EQ(f.ticks, 4);
    EXPECT_EQ(f.dropped, 0);
  }
  // 1/30 s is exactly 1e8 units of 1/3 ns: four equal parts, each 1/120 s to one rounding
  for (double dt : log.dt) EXPECT_NEAR(dt, 1.0 / 120, 1e-17);
  EXPECT_NEAR(stepper.time(), 1.0, 1e-14);
  EXPECT_EQ(stepper.tick_count(), 120);
  expect_balanced(stepper.totals());
}

TEST(TimePerFrame, StallGuardClampsTheFrameAndCapsTheTicks) {
  StepperSettings s = with(Strategy::PerFrame);
  s.ticks_per_frame = 50;
  s.max_ticks_per_frame = 8;
  s.max_frame_dt = 0.1;
  TimeStepper stepper(s);
  TickLog log;
  // a 10 s frame: clamped to 0.1 s, split into 50 parts, of which only 8 run
  const auto f = stepper.advance(10.0, log);
  EXPECT_EQ(f.ticks, 8);
  EXPECT_TRUE(f.stalled);
  for (double dt : log.dt) EXPECT_NEAR(dt, 0.1 / 50, 1e-15);
  EXPECT_NEAR(f.simulated, 0.1 * 8 / 50, 1e-15);
  EXPECT_NEAR(f.dropped, 10.0 - 0.1 * 8 / 50, 1e-13);
  const auto t = stepper.totals();
  EXPECT_EQ(t.frames_dropped, 1);
  EXPECT_NEAR(t.dropped_time, 10.0 - 0.016, 1e-13);
  expect_balanced(t);
}

// ---------------------------------------------------------------------------------------
// (b) max-step

TEST(TimeMaxStep, SubdividesIntoEqualTicksNoLongerThanMaxDt) {
  TimeStepper stepper(with(Strategy::MaxStep));  // max_dt = 1/600 s, as in workbook 3.1.2
  struct Case {
    double frame;
    int ticks;
  };
  // 1/60 -> 10 ticks exactly; a hair more -> 11; 1e-4 -> 1; 0.05 -> 30
  const Case cases[] = {{1.0 / 60, 10}, {1.0 / 60 + 1e-6, 11}, {1e-4, 1}, {0.05, 30}, {0.0, 0}};
  for (const Case& c : cases) {
    TickLog log;
    const auto f = stepper.advance(c.frame, log);
    EXPECT_EQ(f.ticks, c.ticks) << "frame " << c.frame;
    if (c.ticks == 0) continue;
    // no tick longer than max_dt (plus the one-nanosecond clock resolution), no sliver
    for (double dt : log.dt) {
      EXPECT_LE(dt, 1.0 / 600 + 1e-9);
      EXPECT_NEAR(dt, c.frame / c.ticks, 1e-9 / 3);
    }
    // the parts sum exactly (in integer units) to the frame; as doubles, to a few ulps
    EXPECT_NEAR(f.simulated, c.frame, 1e-17 + 0.2e-9);
    EXPECT_NEAR(log.sum(), f.simulated, 1e-16 * c.ticks);
    EXPECT_EQ(f.dropped, 0);
  }
  // a measured frame of 16666667 ns is still 10 ticks (1 ns is within the clock resolution)
  TickLog log;
  EXPECT_EQ(stepper.advance_ns(16'666'667, log).ticks, 10);
  expect_balanced(stepper.totals());
}

TEST(TimeMaxStep, StallGuardRunsTheCapOfFullTicksAndDropsTheRest) {
  StepperSettings s = with(Strategy::MaxStep);
  s.max_dt = 0.001;
  s.max_ticks_per_frame = 32;
  TimeStepper stepper(s);
  TickLog log;
  // 0.25 s would need 250 ticks of 1 ms: 32 run, each exactly 1 ms, 0.218 s dropped
  const auto f = stepper.advance(0.25, log);
  EXPECT_EQ(f.ticks, 32);
  for (double dt : log.dt) EXPECT_EQ(dt, 0.001);
  EXPECT_NEAR(f.simulated, 0.032, 1e-15);
  EXPECT_NEAR(f.dropped, 0.218, 1e-15);
  EXPECT_TRUE(f.stalled);
  expect_balanced(stepper.totals());
}

// ---------------------------------------------------------------------------------------
// (c) fixed

TEST(TimeFixed, ThirtyHertzFramesRunTwoSixtyHertzTicks) {
  TimeStepper stepper(with(Strategy::Fixed));  // fixed_dt = 1/60
  TickLog log;
  for (int i = 0; i < 300; ++i) {
    const auto f = stepper.advance(1.0 / 30, log);
    ASSERT_EQ(f.ticks, 2) << "frame " << i;
    EXPECT_EQ(f.alpha, 0.0);
  }
  EXPECT_EQ(stepper.tick_count(), 600);
  for (double dt : log.dt) EXPECT_EQ(dt, 1.0 / 60);
  // t of tick k is k * fixed_dt, one rounding, no accumulated error
  for (std::size_t k = 0; k < log.t.size(); ++k) EXPECT_EQ(log.t[k], static_cast<double>(k) * (1.0 / 60));
  EXPECT_EQ(stepper.time(), 600 * (1.0 / 60));
}

TEST(TimeFixed, RemainderIsCarriedAndAlphaIsTheFraction) {
  StepperSettings s = with(Strategy::Fixed);
  s.fixed_dt = 0.01;
  TimeStepper stepper(s);
  auto none = [](double, double) {};
  // frames of 25 ms against 10 ms ticks: 2, 3, 2, 3 ... with alpha 0.5, 0, 0.5, 0
  for (int i = 0; i < 10; ++i) {
    const auto f = stepper.advance(0.025, none);
    EXPECT_EQ(f.ticks, i % 2 == 0 ? 2 : 3) << "frame " << i;
    EXPECT_EQ(f.alpha, i % 2 == 0 ? 0.5 : 0.0) << "frame " << i;
    EXPECT_EQ(stepper.alpha(), f.alpha);
  }
  // frames shorter than a tick only accumulate
  const auto a = stepper.advance(0.004, none);
  const auto b = stepper.advance(0.004, none);
  const auto c = stepper.advance(0.004, none);
  EXPECT_EQ(a.ticks + b.ticks, 0);
  EXPECT_DOUBLE_EQ(b.alpha, 0.8);
  EXPECT_EQ(c.ticks, 1);
  EXPECT_NEAR(c.alpha, 0.2, 1e-15);
  EXPECT_NEAR(stepper.totals().pending_time, 0.002, 1e-15);
  EXPECT_EQ(stepper.ns_until_next_tick(), 8'000'000);
  expect_balanced(stepper.totals());
}

TEST(TimeFixed, TickCountDependsOnlyOnTotalRealTime) {
  // frames from clock timestamps (as a game loop measures them): after exactly 10 s of
  // frames at 30, 60, 144 Hz or with jitter, exactly 600 ticks of 1/60 s have run
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::int64_t> jitter(2'000'000, 45'000'000);
  const std::int64_t end = 10'000'000'000;
  for (int hz : {30, 60, 144, 0}) {
    for (double fixed : {1.0 / 60, 1.0 / 144, 1.0 / 90, 0.001}) {
      StepperSettings s = with(Strategy::Fixed);
      s.fixed_dt = fixed;
      s.max_ticks_per_frame = 1000;
      TimeStepper stepper(s);
      std::int64_t prev = 0;
      for (std::int64_t k = 1; prev < end; ++k) {
        std::int64_t now = hz ? (k * end) / (10 * hz) : prev + jitter(rng);
        if (now > end) now = end;
        stepper.advance_ns(now - prev, [](double, double) {});
        prev = now;
      }
      EXPECT_EQ(stepper.tick_count(), std::llround(10 / fixed)) << hz << " Hz, dt " << fixed;
      EXPECT_EQ(stepper.alpha(), 0.0);
      EXPECT_EQ(stepper.totals().dropped_time, 0.0);
    }
  }
}

// a small deterministic world: a hanging chain of particles joined by damped springs,
// stepped by semi-implicit Euler (inline, independent of the integrator module)
struct Chain {
  static constexpr int kN = 12;
  std::vector<pba::Vec3> x, v;
  Chain() : x(kN), v(kN) {
    for (int i = 0; i < kN; ++i) x[i] = pba::Vec3(0.1 * i, -0.05 * i * i, 0.02 * (i % 3));
  }
  void step(double dt) {
    // forces: gravity, springs to neighbours (rest length 0.1 m), linear damping
    std::vector<pba::Vec3>& f = force_;
    f.assign(kN, pba::Vec3(0, -9.81, 0));
    for (int i = 0; i + 1 < kN; ++i) {
      const pba::Vec3 d = x[i + 1] - x[i];
      const double len = glm::length(d);
      const pba::Vec3 fs = 400.0 * (len - 0.1) * d / len;
      f[i] += fs;
      f[i + 1] -= fs;
    }
    for (int i = 0; i < kN; ++i) f[i] -= 0.5 * v[i];
    // semi-implicit Euler; particle 0 is pinned
    for (int i = 1; i < kN; ++i) {
      v[i] += dt * f[i];
      x[i] += dt * v[i];
    }
  }
  std::uint64_t hash() const {
    return pba::hash_span<pba::Vec3>(v, pba::hash_span<pba::Vec3>(x));
  }
  std::vector<pba::Vec3> force_;
};

TEST(TimeFixed, StateIsBitIdenticalWhateverTheRenderRate) {
  // the test: after K ticks of the fixed-step accumulator, the state hash is the
  // same for render loops at 30, 60 and 144 Hz, with jittery frame times, and with hitches
  // that trip the stall guard; it equals K plain steps with no stepper at all
  constexpr long long K = 900;
  const double dt = 1.0 / 120;
  Chain reference;
  for (long long k = 0; k < K; ++k) reference.step(dt);
  const std::uint64_t expected = reference.hash();

  struct Run {
    const char* name;
    std::function<double(int)> frame;  // seconds of frame i
  };
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0.004, 0.040);
  std::vector<double> jitter(4000), hitchy(4000);
  for (auto& j : jitter) j = u(rng);
  for (std::size_t i = 0; i < hitchy.size(); ++i) hitchy[i] = i % 97 == 50 ? 0.6 : jitter[i];
  const Run runs[] = {
      {"30 Hz", [](int) { return 1.0 / 30; }},
      {"60 Hz", [](int) { return 1.0 / 60; }},
      {"144 Hz", [](int) { return 1.0 / 144; }},
      {"jitter 4-40 ms", [&](int i) { return jitter[static_cast<std::size_t>(i)]; }},
      {"hitches of 0.6 s", [&](int i) { return hitchy[static_cast<std::size_t>(i)]; }},
  };
  for (const Run& run : runs) {
    StepperSettings s = with(Strategy::Fixed);
    s.fixed_dt = dt;
    s.max_ticks_per_frame = 20;
    TimeStepper stepper(s);
    Chain world;
    std::uint64_t hash_at_k = 0;
    std::vector<double> times;
    auto tick = [&](double t, double h) {
      times.push_back(t);
      world.step(h);
      if (static_cast<long long>(times.size()) == K) hash_at_k = world.hash();
    };
    for (int i = 0; stepper.tick_count() < K; ++i) stepper.advance(run.frame(i), tick);
    EXPECT_EQ(hash_at_k, expected) << run.name;
    EXPECT_EQ(times[K - 1], static_cast<double>(K - 1) * dt) << run.name;
    if (std::string(run.name) == "hitches of 0.6 s") {
      EXPECT_GT(stepper.totals().dropped_time, 0);
    }
    expect_balanced(stepper.totals());
  }
}

TEST(TimeFixed, StallGuardDropsExactlyWhatItDoesNotSimulate) {
  // a 10 s frame: clamped to 0.25 s (9.75 s dropped), 15 ticks due, 8 run, 7 dropped
  StepperSettings s = with(Strategy::Fixed);
  s.max_ticks_per_frame = 8;
  TimeStepper stepper(s);
  auto none = [](double, double) {};
  const auto f = stepper.advance(10.0, none);
  EXPECT_EQ(f.ticks, 8);
  EXPECT_EQ(f.dropped_ticks, 7);
  EXPECT_EQ(f.alpha, 0.0);
  EXPECT_NEAR(f.dropped, 9.75 + 7.0 / 60, 1e-14);
  EXPECT_NEAR(f.simulated, 8.0 / 60, 1e-15);
  // a normal frame afterwards is not punished
  const auto g = stepper.advance(1.0 / 60, none);
  EXPECT_EQ(g.ticks, 1);
  EXPECT_FALSE(g.stalled);
  const auto t = stepper.totals();
  EXPECT_EQ(t.frames_dropped, 1);
  EXPECT_EQ(t.dropped_ticks, 7);
  EXPECT_EQ(t.ticks, 9);
  EXPECT_NEAR(t.frame_time, 10.0 + 1.0 / 60, 1e-14);
  expect_balanced(t);

  // without the frame clamp: 600 ticks due, 8 run, exactly 592 whole ticks dropped
  s.max_frame_dt = 3600;
  TimeStepper unclamped(s);
  const auto h = unclamped.advance(10.0, none);
  EXPECT_EQ(h.ticks, 8);
  EXPECT_EQ(h.dropped_ticks, 592);
  EXPECT_NEAR(h.dropped, 592.0 / 60, 1e-13);
  expect_balanced(unclamped.totals());
}

TEST(TimeFixed, SlowTicksCannotSpiral) {
  // each tick takes three ticks' worth of real time (a manual clock moved by the tick
  // itself): without a cap the ticks per frame would grow 1, 3, 9, 27 ...; with a cap of 4
  // they settle at 4 and 8 whole ticks are dropped every frame
  pba::ManualClock clock;
  StepperSettings s = with(Strategy::Fixed);
  s.fixed_dt = 0.01;
  s.max_ticks_per_frame = 4;
  s.max_frame_dt = 3600;
  TimeStepper stepper(s, &clock);
  auto slow_tick = [&](double, double) { clock.advance_ns(30'000'000); };
  std::int64_t last = clock.now_ns();
  clock.advance_ns(10'000'000);
  const int expect_ticks[] = {1, 3, 4, 4, 4, 4};
  const int expect_dropped[] = {0, 0, 5, 8, 8, 8};
  for (int i = 0; i < 6; ++i) {
    const std::int64_t now = clock.now_ns();
    const auto f = stepper.advance_ns(now - last, slow_tick);
    last = now;
    EXPECT_EQ(f.ticks, expect_ticks[i]) << "frame " << i;
    EXPECT_EQ(f.dropped_ticks, expect_dropped[i]) << "frame " << i;
    // the wall time of the ticks is measured on the injected clock
    EXPECT_NEAR(f.tick_wall, 0.03 * f.ticks, 1e-12);
  }
  const auto t = stepper.totals();
  EXPECT_EQ(t.frames_dropped, 4);
  EXPECT_NEAR(t.tick_wall_median, 0.03, 1e-9);
  EXPECT_NEAR(t.tick_wall_mean, 0.03, 1e-12);
  EXPECT_NEAR(t.tick_wall_max, 0.03, 1e-12);
  expect_balanced(t);
}

TEST(TimeFixed, SingleStepRunsOneTickOutsideRealTime) {
  StepperSettings s = with(Strategy::Fixed);
  s.fixed_dt = 0.01;
  TimeStepper stepper(s);
  TickLog log;
  stepper.advance(0.015, log);
  const auto f = stepper.single_step(log);
  EXPECT_EQ(f.ticks, 1);
  EXPECT_EQ(log.dt.back(), 0.01);
  EXPECT_EQ(log.t.back(), 0.01);
  EXPECT_EQ(stepper.alpha(), 0.5);  // the accumulator is untouched
  EXPECT_NEAR(stepper.totals().stepped_time, 0.01, 1e-15);
  expect_balanced(stepper.totals());

  // per-frame and max-step step one nominal frame of fixed_dt
  s.strategy = Strategy::MaxStep;
  s.max_dt = 0.004;
  stepper.set_settings(s);
  EXPECT_EQ(stepper.single_step(log).ticks, 3);
  expect_balanced(stepper.totals());
}

TEST(TimeStepperSettings, ChangingStrategyKeepsTimeAndCountsThePendingRemainder) {
  StepperSettings s = with(Strategy::Fixed);
  s.fixed_dt = 0.01;
  TimeStepper stepper(s);
  auto none = [](double, double) {};
  stepper.advance(0.025, none);  // 2 ticks, 5 ms pending
  EXPECT_NEAR(stepper.time(), 0.02, 1e-15);
  s.strategy = Strategy::MaxStep;
  stepper.set_settings(s);
  // the pending 5 ms is dropped and counted; simulated time carries on
  auto t = stepper.totals();
  EXPECT_NEAR(t.dropped_time, 0.005, 1e-15);
  EXPECT_EQ(t.pending_time, 0);
  EXPECT_NEAR(stepper.time(), 0.02, 1e-15);
  TickLog log;
  stepper.advance(0.01, log);
  EXPECT_NEAR(log.t.front(), 0.02, 1e-15);
  EXPECT_NEAR(stepper.time(), 0.03, 1e-15);
  expect_balanced(stepper.totals());
  // setting the same settings again is a no-op
  stepper.set_settings(s);
  EXPECT_NEAR(stepper.time(), 0.03, 1e-15);
  // reset returns to zero and keeps the settings
  stepper.reset();
  EXPECT_EQ(stepper.time(), 0);
  EXPECT_EQ(stepper.totals().frames, 0);
  EXPECT_EQ(stepper.settings().strategy, Strategy::MaxStep);
}

TEST(TimeStepperSettings, TimeScaleSlowsSimulatedTime) {
  StepperSettings s = with(Strategy::Fixed);
  s.fixed_dt = 0.01;
  s.time_scale = 0.5;
  TimeStepper stepper(s);
  for (int i = 0; i < 100; ++i) stepper.advance_ns(10'000'000, [](double, double) {});
  EXPECT_EQ(stepper.tick_count(), 50);
  EXPECT_NEAR(stepper.totals().frame_time, 0.5, 1e-12);  // frame time is after scaling
  expect_balanced(stepper.totals());
}

TEST(TimeStepperTotals, BalanceHoldsForEveryStrategyUnderRandomFrames) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 0.05);
  for (Strategy strategy : {Strategy::PerFrame, Strategy::MaxStep, Strategy::Fixed}) {
    StepperSettings s = with(strategy);
    s.ticks_per_frame = 3;
    s.max_ticks_per_frame = 12;
    TimeStepper stepper(s);
    long long dropped_frames = 0, ticks = 0;
    for (int i = 0; i < 2000; ++i) {
      const double frame = i % 150 == 7 ? 2.0 : u(rng);
      const auto f = stepper.advance(frame, [&](double, double) { ++ticks; });
      EXPECT_LE(f.ticks, 12);
      dropped_frames += f.dropped > 0;
    }
    const auto t = stepper.totals();
    EXPECT_EQ(t.ticks, ticks);
    EXPECT_EQ(t.frames, 2000);
    EXPECT_EQ(t.frames_dropped, dropped_frames);
    EXPECT_GE(dropped_frames, 14) << pba::strategy_name(strategy);
    expect_balanced(t);
  }
}

TEST(TimeStepper, AdvanceNeverAllocates) {
  // zero allocations per frame in steady state, for every caller-thread strategy
  for (Strategy strategy : {Strategy::PerFrame, Strategy::MaxStep, Strategy::Fixed}) {
    StepperSettings s = with(strategy);
    s.ticks_per_frame = 4;
    TimeStepper stepper(s);
    double sum = 0;
    auto tick = [&](double t, double dt) { sum += t * dt; };
    stepper.advance(0.016, tick);
    const long long before = g_allocations.load();
    double readout = 0;
    for (int i = 0; i < 1000; ++i) {
      stepper.advance(i % 10 == 0 ? 0.5 : 0.016 + 1e-4 * (i % 7), tick);
      readout += stepper.totals().tick_wall_median;  // the readout does not allocate either
    }
    EXPECT_EQ(g_allocations.load(), before) << pba::strategy_name(strategy);
    EXPECT_GT(sum, 0);
    EXPECT_GE(readout, 0);
  }
}

// ---------------------------------------------------------------------------------------
// the workbook's experiment (3.1.6): an artificial render delay (doWork) grows

// A game loop on a manual clock: each frame costs `delay` seconds of rendering plus
// `tick_cost` seconds per physics tick, and the next frame's frame_dt is what that took.
struct LoopResult {
  double ticks_per_frame = 0;  // mean over the measured frames
  double dropped_fraction = 0; // dropped time / frame time over the measured frames
  double mean_tick_dt = 0;     // mean simulated seconds per tick
  double frame = 0;            // mean frame time (s)
};

LoopResult run_loop(const StepperSettings& s, double delay, double tick_cost) {
  pba::ManualClock clock;
  TimeStepper stepper(s, &clock);
  const std::int64_t cost_ns = std::llround(tick_cost * 1e9);
  auto tick = [&](double, double) { clock.advance_ns(cost_ns); };
  std::int64_t last = clock.now_ns();
  constexpr int kWarmup = 100, kFrames = 200;
  pba::StepperTotals before;
  for (int i = 0; i < kWarmup + kFrames; ++i) {
    if (i == kWarmup) before = stepper.totals();
    clock.advance(delay);  // render: the workbook's doWork()
    const std::int64_t now = clock.now_ns();
    stepper.advance_ns(now - last, tick);
    last = now;
  }
  const pba::StepperTotals after = stepper.totals();
  LoopResult r;
  const double ticks = static_cast<double>(after.ticks - before.ticks);
  const double frame = after.frame_time - before.frame_time;
  r.ticks_per_frame = ticks / kFrames;
  r.dropped_fraction = (after.dropped_time - before.dropped_time) / frame;
  r.mean_tick_dt = ticks > 0 ? (after.simulated_time - before.simulated_time) / ticks : 0;
  r.frame = frame / kFrames;
  return r;
}

TEST(TimeStall, RenderDelaySweepShowsEachStrategysAnswer) {
  // ticks cost 4 ms of wall time; fixed_dt = max_dt = 1/60 s; at most 4 ticks per frame
  StepperSettings base;
  base.fixed_dt = 1.0 / 60;
  base.max_dt = 1.0 / 60;
  base.max_ticks_per_frame = 4;
  const double tick_cost = 0.004;
  const char* csv_path = std::getenv("PBA_TIME_SWEEP_CSV");
  FILE* csv = csv_path ? std::fopen(csv_path, "w") : nullptr;
  if (csv) std::fprintf(csv, "strategy,delay_ms,ticks_per_frame,dropped_fraction,tick_dt_ms,frame_ms\n");
  for (Strategy strategy : {Strategy::PerFrame, Strategy::MaxStep, Strategy::Fixed}) {
    StepperSettings s = base;
    s.strategy = strategy;
    LoopResult first, last;
    for (int delay_ms = 1; delay_ms <= 300; delay_ms += delay_ms < 5 ? 4 : 5) {
      const LoopResult r = run_loop(s, delay_ms * 1e-3, tick_cost);
      if (delay_ms == 1) first = r;
      last = r;
      EXPECT_LE(r.ticks_per_frame, 4.0);
      if (csv)
        std::fprintf(csv, "%s,%d,%.6f,%.6f,%.6f,%.6f\n",
                     std::string(pba::strategy_name(strategy)).c_str(), delay_ms,
                     r.ticks_per_frame, r.dropped_fraction, r.mean_tick_dt * 1e3, r.frame * 1e3);
    }
    const auto name = pba::strategy_name(strategy);
    // with a 1 ms render delay every strategy keeps up (nothing dropped)
    EXPECT_EQ(first.dropped_fraction, 0.0) << name;
    if (strategy == Strategy::PerFrame) {
      // one tick per frame whatever happens; the tick simply grows with the frame until
      // the 0.25 s clamp: 304 ms frames, so 54 ms of each is dropped
      EXPECT_EQ(last.ticks_per_frame, 1.0);
      EXPECT_NEAR(last.mean_tick_dt, 0.25, 1e-12);
      EXPECT_NEAR(last.dropped_fraction, 0.054 / 0.304, 1e-9);
    } else {
      // the tick stays 1/60 s; the cap holds the ticks at 4 per frame, and with a 300 ms
      // render delay (316 ms frames) all but 4/60 s of every frame is dropped
      EXPECT_NEAR(last.mean_tick_dt, 1.0 / 60, 1e-12) << name;
      EXPECT_EQ(last.ticks_per_frame, 4.0) << name;
      EXPECT_NEAR(last.dropped_fraction, 1 - (4.0 / 60) / 0.316, 1e-6) << name;
    }
  }
  if (csv) std::fclose(csv);
}

TEST(TimeStall, WithoutTheCapSlowTicksSpiral) {
  // ticks cost 20 ms of wall time but simulate only 16.7 ms: each frame owes more ticks
  // than the last (the death spiral); the cap of 4 ticks holds frames at 5 + 4 * 20 ms
  const char* csv_path = std::getenv("PBA_TIME_SPIRAL_CSV");
  FILE* csv = csv_path ? std::fopen(csv_path, "w") : nullptr;
  if (csv) std::fprintf(csv, "cap,frame,frame_ms,ticks,dropped_ms\n");
  for (int cap : {100000, 4}) {
    StepperSettings s = with(Strategy::Fixed);
    s.max_ticks_per_frame = cap;
    s.max_frame_dt = 3600;  // only the tick cap guards here
    pba::ManualClock clock;
    TimeStepper stepper(s, &clock);
    auto tick = [&](double, double) { clock.advance_ns(20'000'000); };
    std::int64_t last = clock.now_ns();
    double first_long = 0, frame_s = 0;
    for (int i = 0; i < 40; ++i) {
      clock.advance_ns(5'000'000);  // render
      const std::int64_t now = clock.now_ns();
      const auto f = stepper.advance_ns(now - last, tick);
      last = now;
      frame_s = f.frame_dt;
      if (i == 10) first_long = f.frame_dt;
      if (csv)
        std::fprintf(csv, "%d,%d,%.6f,%d,%.6f\n", cap, i, f.frame_dt * 1e3, f.ticks,
                     f.dropped * 1e3);
    }
    if (cap == 4) {
      EXPECT_NEAR(frame_s, 0.085, 1e-12);  // 5 ms render + 4 ticks of 20 ms
      EXPECT_GT(stepper.totals().dropped_time, 0);
    } else {
      // frame time grows by 20/16.7 = 1.2x per frame: 30 frames later, >200x longer
      EXPECT_GT(frame_s, 200 * first_long);
      EXPECT_EQ(stepper.totals().dropped_time, 0);
    }
  }
  if (csv) std::fclose(csv);
}

// ---------------------------------------------------------------------------------------
// helpers

TEST(TickTimings, MedianOfTheLatestWindow) {
  pba::TickTimings t;
  EXPECT_EQ(t.median(), 0);
  for (double v : {5.0, 1.0, 4.0, 2.0, 3.0}) t.add(v);
  EXPECT_EQ(t.median(), 3.0);
  t.add(10.0);
  EXPECT_EQ(t.median(), 3.5);  // even count: mean of the two middle values
  EXPECT_EQ(t.max(), 10.0);
  EXPECT_EQ(t.total(), 25.0);
  // only the latest 256 ticks count towards the median
  for (int i = 0; i < pba::TickTimings::kWindow; ++i) t.add(0.5);
  EXPECT_EQ(t.median(), 0.5);
  EXPECT_EQ(t.count(), 6 + pba::TickTimings::kWindow);
}

TEST(ManualClock, MovesOnlyWhenTold) {
  pba::ManualClock clock(100);
  EXPECT_EQ(clock.now_ns(), 100);
  clock.advance(0.5);
  EXPECT_EQ(clock.now_ns(), 500'000'100);
  EXPECT_EQ(clock.wait_hint(0).count(), 0);
  EXPECT_GT(clock.wait_hint(1'000'000'000).count(), 0);
  EXPECT_THAT(error_of([&] { clock.advance(-1); }), HasSubstr("ManualClock.advance"));
  pba::SteadyClock& steady = pba::SteadyClock::instance();
  const auto a = steady.now_ns();
  EXPECT_LE(a, steady.now_ns());
}

TEST(SnapshotBuffer, ReaderSeesLatestPublishedAndPrevious) {
  pba::SnapshotBuffer<int> buffer(-1);
  EXPECT_FALSE(buffer.acquire());
  EXPECT_EQ(buffer.current(), -1);
  // two publishes before a read: the reader gets the latest only
  for (int i = 1; i <= 2; ++i) {
    buffer.write_slot() = i;
    buffer.publish({0.1 * i, i, 1000LL * i});
  }
  EXPECT_TRUE(buffer.acquire());
  EXPECT_FALSE(buffer.acquire());
  EXPECT_EQ(buffer.current(), 2);
  EXPECT_EQ(buffer.current_stamp().tick, 2);
  EXPECT_EQ(buffer.previous(), -1);
  buffer.write_slot() = 3;
  buffer.publish({0.3, 3, 3000});
  EXPECT_TRUE(buffer.acquire());
  EXPECT_EQ(buffer.current(), 3);
  EXPECT_EQ(buffer.previous(), 2);
  EXPECT_EQ(buffer.published(), 3);
  // alpha: publications 1000 ns apart; halfway through the next interval -> 0.5
  EXPECT_DOUBLE_EQ(buffer.alpha(3500, 1.0), 0.5);
  EXPECT_EQ(buffer.alpha(2000, 1.0), 0.0);
  EXPECT_EQ(buffer.alpha(9000, 1.0), 1.0);
}

}  // namespace
