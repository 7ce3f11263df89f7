// Tests for the "threaded" strategy: PhysicsThread and SnapshotBuffer. They run under
// ThreadSanitizer in CI. Assertions never depend on scheduling: a manual clock drives time
// where counts are asserted, and wall-clock timeouts only guard against hangs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "error_of.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "pba/time.h"

namespace {

using pba::PhysicsThread;
using pba::StepperSettings;

constexpr double kHangGuard = 60.0;  // seconds; only ever reached if something hangs

using pba::test_support::error_of;

StepperSettings fixed(double dt) {
  StepperSettings s;
  s.strategy = pba::Strategy::Threaded;
  s.fixed_dt = dt;
  return s;
}

// a state with an invariant that a torn copy would break: value[i] == tick * (i + 1)
struct State {
  std::array<double, 512> value{};
  long long tick = 0;
  bool consistent() const {
    for (std::size_t i = 0; i < value.size(); ++i)
      if (value[i] != static_cast<double>(tick) * static_cast<double>(i + 1)) return false;
    return true;
  }
};

TEST(PhysicsThread, RendererNeverSeesTornSnapshots) {
  // real time, 1 ms ticks; the main thread plays the renderer and checks every snapshot
  State world;  // owned by the physics thread while it runs
  pba::SnapshotBuffer<State> snapshots(world);
  PhysicsThread physics(
      fixed(0.001),
      [&](double, double) {
        ++world.tick;
        for (std::size_t i = 0; i < world.value.size(); ++i)
          world.value[i] = static_cast<double>(world.tick) * static_cast<double>(i + 1);
      },
      [&](const pba::TickStamp& stamp) {
        snapshots.write_slot() = world;
        snapshots.publish(stamp);
      });
  physics.start();
  long long seen = 0, last_tick = 0;
  bool all_consistent = true, monotonic = true, stamps_match = true;
  pba::Stopwatch guard;
  while (last_tick < 150 && guard.seconds() < kHangGuard) {
    if (snapshots.acquire()) {
      ++seen;
      const State& s = snapshots.current();
      all_consistent = all_consistent && s.consistent() && snapshots.previous().consistent();
      stamps_match = stamps_match && snapshots.current_stamp().tick == s.tick &&
                     snapshots.previous_stamp().tick == snapshots.previous().tick;
      monotonic = monotonic && s.tick > last_tick && snapshots.previous().tick < s.tick;
      last_tick = s.tick;
      const double a = snapshots.alpha(pba::SteadyClock::instance().now_ns(), 0.001);
      EXPECT_TRUE(a >= 0 && a <= 1);
    }
    std::this_thread::yield();
  }
  physics.stop();
  EXPECT_GE(last_tick, 150);
  EXPECT_GT(seen, 0);
  EXPECT_TRUE(all_consistent);
  EXPECT_TRUE(stamps_match);
  EXPECT_TRUE(monotonic);
  // after stop() the world is the caller's again, and it matches the thread's count
  const auto st = physics.stats();
  EXPECT_FALSE(st.running);
  EXPECT_EQ(world.tick, st.totals.ticks);
  EXPECT_GE(snapshots.published(), seen);
  EXPECT_LE(snapshots.published(), st.wakes);
}

TEST(PhysicsThread, PacedByTheClockWithTheRemainderPending) {
  // a manual clock frozen at 2.5 ticks: exactly 2 ticks run, half a tick stays pending
  pba::ManualClock clock;
  long long ticks = 0;
  PhysicsThread physics(fixed(0.01), [&](double, double) { ++ticks; }, nullptr, &clock);
  physics.start();
  clock.advance_ns(25'000'000);
  ASSERT_TRUE(physics.wait_for_ticks(2, kHangGuard));
  physics.stop();
  const auto st = physics.stats();
  EXPECT_EQ(ticks, 2);
  EXPECT_EQ(st.totals.ticks, 2);
  EXPECT_NEAR(st.lag, 0.005, 1e-15);
  EXPECT_EQ(st.totals.dropped_time, 0);
  EXPECT_NEAR(st.time, 0.02, 1e-15);
}

TEST(PhysicsThread, PauseStepResumeAndRateChange) {
  pba::ManualClock clock;
  std::vector<double> dts;  // written on the physics thread, read after stop()
  PhysicsThread physics(fixed(0.01), [&](double, double dt) { dts.push_back(dt); }, nullptr,
                        &clock);
  physics.start();
  clock.advance_ns(20'000'000);
  ASSERT_TRUE(physics.wait_for_ticks(2, kHangGuard));

  // paused: a second of real time passes and is not owed; three single steps run
  physics.set_paused(true);
  EXPECT_TRUE(physics.paused());
  clock.advance_ns(1'000'000'000);
  physics.step(3);
  ASSERT_TRUE(physics.wait_for_ticks(5, kHangGuard));

  // resumed at the clock's current time: 10 ms later, exactly one more tick
  physics.set_paused(false);
  clock.advance_ns(10'000'000);
  ASSERT_TRUE(physics.wait_for_ticks(6, kHangGuard));

  // rate change: 5 ms ticks; 20 ms of real time is 4 of them
  physics.set_settings(fixed(0.005));
  clock.advance_ns(20'000'000);
  ASSERT_TRUE(physics.wait_for_ticks(10, kHangGuard));
  physics.stop();

  const auto st = physics.stats();
  EXPECT_EQ(st.totals.ticks, 10);
  EXPECT_EQ(dts.size(), 10u);
  EXPECT_EQ(std::count(dts.begin(), dts.end(), 0.01), 6);
  EXPECT_EQ(std::count(dts.begin(), dts.end(), 0.005), 4);
  EXPECT_EQ(st.totals.dropped_time, 0);  // pausing is not a stall
  EXPECT_NEAR(st.totals.stepped_time, 0.03, 1e-15);
  EXPECT_NEAR(st.time, 0.08, 1e-15);
  EXPECT_EQ(physics.settings().fixed_dt, 0.005);
}

TEST(PhysicsThread, StallGuardDropsTimeWhenTicksAreSlowerThanRealTime) {
  // every tick costs three ticks of real time (the tick moves the manual clock itself), so
  // the ticks due per wake-up would grow 1, 3, 9, 27 ...; the cap holds them at 4 and each
  // later wake-up drops exactly 8 whole ticks. Only the physics thread moves the clock
  // after the first kick, so the sequence does not depend on scheduling.
  pba::ManualClock clock;
  StepperSettings s = fixed(0.01);
  s.max_ticks_per_frame = 4;
  s.max_frame_dt = 3600;
  PhysicsThread physics(s, [&](double, double) { clock.advance_ns(30'000'000); }, nullptr,
                        &clock);
  physics.start();
  clock.advance_ns(10'000'000);
  ASSERT_TRUE(physics.wait_for_ticks(40, kHangGuard));
  physics.stop();

  const auto st = physics.stats();
  const auto& t = st.totals;
  // 1 + 3 + 4m ticks and 5 + 8(m - 1) dropped ticks after m capped wake-ups
  ASSERT_EQ((t.ticks - 4) % 4, 0);
  const long long m = (t.ticks - 4) / 4;
  EXPECT_GE(m, 9);
  EXPECT_EQ(t.dropped_ticks, 5 + 8 * (m - 1));
  EXPECT_EQ(t.frames_dropped, m);
  EXPECT_EQ(st.last_wake.ticks, 4);
  EXPECT_EQ(st.last_wake.dropped_ticks, 8);
  EXPECT_NEAR(t.tick_wall_median, 0.03, 1e-9);
  // every nanosecond of real time is simulated, dropped or pending
  EXPECT_NEAR(t.frame_time, t.simulated_time + t.dropped_time + t.pending_time, 1e-12);
  EXPECT_NEAR(t.dropped_time, 0.01 * static_cast<double>(t.dropped_ticks), 1e-12);
}

TEST(PhysicsThread, StopWakesASleepingThreadAndJoins) {
  // ticks of 10 s on the real clock: the thread sleeps ~10 s between ticks unless stop()
  // wakes it, so stop() returning within a few seconds shows it was woken, not waited out
  std::atomic<long long> ticks{0};
  PhysicsThread physics(fixed(10.0), [&](double, double) { ++ticks; }, nullptr);
  physics.start();
  EXPECT_TRUE(physics.running());
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  pba::Stopwatch w;
  physics.stop();
  EXPECT_LT(w.seconds(), 5.0);
  EXPECT_FALSE(physics.running());
  EXPECT_EQ(ticks.load(), 0);
  physics.stop();  // idempotent

  // a paused thread stops too, and a stopped one restarts
  physics.start(true);
  EXPECT_TRUE(physics.paused());
  physics.step(2);
  ASSERT_TRUE(physics.wait_for_ticks(2, kHangGuard));
  physics.stop();
  EXPECT_EQ(ticks.load(), 2);
}

TEST(PhysicsThread, StopFromInsideATickIsAnErrorNotADeadlock) {
  pba::ManualClock clock;
  PhysicsThread* self = nullptr;
  std::string error;  // written on the physics thread, read after stop() joins
  PhysicsThread physics(
      fixed(0.01), [&](double, double) { error = error_of([&] { self->stop(); }); }, nullptr,
      &clock);
  self = &physics;
  physics.start(true);
  physics.step();
  ASSERT_TRUE(physics.wait_for_ticks(1, kHangGuard));
  physics.stop();
  EXPECT_EQ(error, "PhysicsThread.stop: called from the physics thread (from a tick or publish)");
}

// A tick that throws (a World whose state went non-finite) must not end the process: until
// 2026-12-06 the exception left the thread's function and std::terminate aborted it. Now the
// thread keeps the message, stops ticking, and stop() joins as usual; a restart clears it.
TEST(PhysicsThread, ATickThatThrowsStopsTheThreadWithItsMessage) {
  pba::ManualClock clock;
  std::atomic<long long> ticks{0};
  std::atomic<long long> publishes{0};
  PhysicsThread physics(
      fixed(0.01),
      [&](double t, double) {
        if (++ticks == 3) throw pba::Error("particle 7 became non-finite at t = " + std::to_string(t));
      },
      [&](const pba::TickStamp&) { ++publishes; }, &clock);
  physics.start(true);
  physics.step(10);
  EXPECT_FALSE(physics.wait_for_ticks(10, kHangGuard));  // returns at the failure, not the guard
  EXPECT_TRUE(physics.stats().failed);
  EXPECT_EQ(physics.error().rfind("particle 7 became non-finite at t = 0.02", 0), 0u) << physics.error();
  EXPECT_EQ(ticks.load(), 3);
  EXPECT_EQ(publishes.load(), 2);
  EXPECT_TRUE(physics.running());  // until stop() joins
  physics.stop();
  EXPECT_FALSE(physics.running());
  EXPECT_TRUE(physics.stats().failed);
  // unpaused too, and a throwing publish likewise
  PhysicsThread loud(
      fixed(0.01), [](double, double) {}, [](const pba::TickStamp&) { throw std::runtime_error("publish failed"); },
      &clock);
  loud.start();
  clock.advance(0.05);
  EXPECT_FALSE(loud.wait_for_ticks(1000, kHangGuard));
  EXPECT_EQ(loud.error(), "publish failed");
  loud.stop();
  // a restart clears the failure
  physics.start(true);
  EXPECT_FALSE(physics.stats().failed);
  EXPECT_EQ(physics.error(), "");
  physics.step(1);
  ASSERT_TRUE(physics.wait_for_ticks(3, kHangGuard));
  physics.stop();
  EXPECT_EQ(ticks.load(), 4);
  // unpaused, the ticks a failing wake ran before the throw are counted (the stats were left
  // at the wake before: 0 ticks here, though two had changed the world)
  std::atomic<long long> bursts{0};
  PhysicsThread burst(
      fixed(0.01), [&](double, double) { if (++bursts == 3) throw pba::Error("third tick"); }, nullptr, &clock);
  burst.start();
  clock.advance(0.05);
  EXPECT_FALSE(burst.wait_for_ticks(1000, kHangGuard));
  EXPECT_EQ(burst.error(), "third tick");
  EXPECT_EQ(burst.stats().totals.ticks, 2);
  EXPECT_NEAR(burst.stats().time, 0.02, 1e-12);
  burst.stop();
}

TEST(PhysicsThread, BadInputIsRejected) {
  auto none = [](double, double) {};
  EXPECT_EQ(error_of([&] { PhysicsThread p(fixed(0.0), none, nullptr); }),
            "StepperSettings.fixed_dt: must be finite and > 0, got 0");
  EXPECT_EQ(error_of([&] { PhysicsThread p(fixed(0.01), nullptr, nullptr); }),
            "PhysicsThread: tick function is empty");
  PhysicsThread p(fixed(0.01), none, nullptr);
  EXPECT_EQ(error_of([&] { p.step(0); }),
            "PhysicsThread.step n: must be an integer in [1, 100000], got 0");
  EXPECT_THAT(error_of([&] { p.set_settings(fixed(-1)); }), ::testing::HasSubstr("fixed_dt"));
  EXPECT_EQ(p.settings().fixed_dt, 0.01);
}

TEST(SnapshotBuffer, ManyPublishesAgainstABusyReader) {
  // the lock-free handoff alone, hammered from two threads (TSAN checks the ordering)
  pba::SnapshotBuffer<State> buffer;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (long long k = 1; k <= 20000; ++k) {
      State& s = buffer.write_slot();
      s.tick = k;
      for (std::size_t i = 0; i < s.value.size(); ++i)
        s.value[i] = static_cast<double>(k) * static_cast<double>(i + 1);
      buffer.publish({0.0, k, 0});
    }
    done.store(true, std::memory_order_release);
  });
  long long last = 0, reads = 0;
  bool ok = true;
  for (;;) {
    // read the flag first: once it is set, one more acquire() sees the final publish
    const bool finished = done.load(std::memory_order_acquire);
    if (buffer.acquire()) {
      ++reads;
      ok = ok && buffer.current().consistent() && buffer.current().tick > last;
      last = buffer.current().tick;
    }
    if (finished) break;
  }
  writer.join();
  EXPECT_TRUE(ok);
  EXPECT_EQ(buffer.current().tick, 20000);  // the last publish is never lost
  EXPECT_GT(reads, 0);
}

}  // namespace
