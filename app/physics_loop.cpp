// The app's physics loop over pba::TimeStepper and pba::PhysicsThread.
#include "physics_loop.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "sample.h"

namespace pba::app {

void AdvanceVirtualClock(PhysicsThread& thread, ManualClock& clock, double frame_dt, double* fed) {
  const StepperSettings s = thread.settings();
  double remaining = frame_dt;
  while (remaining > 1e-12) {
    const double chunk = std::min(remaining, s.fixed_dt);
    remaining -= chunk;
    clock.advance(chunk);
    *fed += chunk * s.time_scale;
    // done when the thread has seen all the time, or when what it has not seen plus its
    // accumulator is less than a tick (it sleeps until the clock moves again)
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
    while (std::chrono::steady_clock::now() < deadline) {
      const PhysicsThreadStats st = thread.stats();
      const double unseen = *fed - st.totals.frame_time;
      if (unseen < 1e-9 || unseen + st.lag < s.fixed_dt - 1e-7) break;
      std::this_thread::sleep_for(std::chrono::microseconds(50));
    }
  }
}

PhysicsLoop::PhysicsLoop(Settings& settings, bool virtual_time)
    : settings_(settings), virtual_time_(virtual_time), stepper_(settings.stepper) {}

PhysicsLoop::~PhysicsLoop() { stop_thread(); }

void PhysicsLoop::attach(Sample* sample) {
  // the thread must stop before the sample it ticks goes away
  stop_thread();
  sample_ = sample;
  stepper_.reset();
  time_offset_ = 0;
  dropped_offset_ = 0;
  alpha_ = 1;
  readout_ = {};
  thread_failed_ = false;
}

void PhysicsLoop::tick(double t, double dt) {
  // one tick is `substeps` calls to the sample's Step, under the state lock
  const int n = settings_.substeps < 1 ? 1 : settings_.substeps;
  const double h = dt / n;
  std::lock_guard<std::mutex> lock(state_mutex_);
  for (int k = 0; k < n; ++k) sample_->Step(t + k * h, h);
}

void PhysicsLoop::start_thread() {
  // continue the simulated time where the caller-thread stepper left it
  time_offset_ += stepper_.time();
  dropped_offset_ += stepper_.totals().dropped_time;
  stepper_.reset();
  last_thread_ticks_ = 0;
  last_thread_dropped_ = 0;
  last_thread_wall_ = 0;
  expected_fed_ = 0;
  stamps_ = std::make_unique<SnapshotBuffer<TickStamp>>();
  if (virtual_time_) manual_clock_ = std::make_unique<ManualClock>(0);
  const double offset = time_offset_;
  thread_ = std::make_unique<PhysicsThread>(
      settings_.stepper,
      [this, offset](double t, double dt) {
        // an exception must not escape the thread: record it and stop ticking
        if (thread_failed_) return;
        try {
          tick(t + offset, dt);
        } catch (const std::exception& e) {
          std::lock_guard<std::mutex> lock(error_mutex_);
          thread_error_ = e.what();
          thread_failed_ = true;
        }
      },
      [this](const TickStamp& stamp) {
        stamps_->write_slot() = stamp;
        stamps_->publish(stamp);
      },
      manual_clock_.get());
  thread_->start(settings_.paused);
}

void PhysicsLoop::stop_thread() {
  if (!thread_) return;
  thread_->stop();
  const PhysicsThreadStats st = thread_->stats();
  time_offset_ += st.time;
  dropped_offset_ += st.totals.dropped_time;
  thread_.reset();
  stepper_.reset();
}

std::string PhysicsLoop::take_thread_error() {
  std::lock_guard<std::mutex> lock(error_mutex_);
  std::string e;
  e.swap(thread_error_);
  return e;
}

void PhysicsLoop::advance(double frame_dt) {
  if (!sample_) return;
  const StepperSettings& s = settings_.stepper;
  const bool threaded = s.strategy == Strategy::Threaded;
  if (threaded && !thread_) start_thread();
  if (!threaded && thread_) stop_thread();

  if (!threaded) {
    // strategies (a)-(c) on this thread
    if (!(stepper_.settings() == s)) stepper_.set_settings(s);
    const double offset = time_offset_;
    auto run = [this, offset](double t, double dt) { tick(t + offset, dt); };
    FrameStats f;
    if (settings_.paused) {
      if (settings_.single_step) f = stepper_.single_step(run);
    } else {
      f = stepper_.advance(frame_dt, run);
    }
    settings_.single_step = false;
    alpha_ = s.strategy == Strategy::Fixed ? stepper_.alpha() : 1.0;
    const StepperTotals tot = stepper_.totals();
    readout_.ticks = f.ticks;
    readout_.tick_dt = f.ticks ? f.tick_dt : readout_.tick_dt;
    readout_.tick_wall = tot.tick_wall_median;
    readout_.frame_tick_wall = f.tick_wall;
    readout_.dropped = f.dropped;
    readout_.dropped_total = dropped_offset_ + tot.dropped_time;
    readout_.sim_time = time_offset_ + stepper_.time();
    readout_.lag = 0;
    readout_.stalled = f.stalled;
    return;
  }

  // strategy (d): the thread owns the ticks; keep it in line with the settings
  if (!(thread_->settings() == s)) thread_->set_settings(s);
  if (thread_->paused() != settings_.paused) thread_->set_paused(settings_.paused);
  if (settings_.paused && settings_.single_step) {
    const long long before = thread_->stats().totals.ticks;
    thread_->step(1);
    if (virtual_time_) thread_->wait_for_ticks(before + 1, 2.0);
  }
  settings_.single_step = false;
  if (virtual_time_ && !settings_.paused) {
    AdvanceVirtualClock(*thread_, *manual_clock_, frame_dt, &expected_fed_);
  }
  // interpolation factor from the published tick stamps
  stamps_->acquire();
  const std::int64_t now = virtual_time_ ? manual_clock_->now_ns() : SteadyClock::instance().now_ns();
  alpha_ = stamps_->alpha(now, s.fixed_dt);
  const PhysicsThreadStats st = thread_->stats();
  readout_.ticks = static_cast<int>(st.totals.ticks - last_thread_ticks_);
  last_thread_ticks_ = st.totals.ticks;
  readout_.tick_dt = s.fixed_dt;
  readout_.tick_wall = st.totals.tick_wall_median;
  readout_.frame_tick_wall = st.totals.tick_wall_total - last_thread_wall_;
  last_thread_wall_ = st.totals.tick_wall_total;
  readout_.dropped = st.totals.dropped_time - last_thread_dropped_;
  last_thread_dropped_ = st.totals.dropped_time;
  readout_.dropped_total = dropped_offset_ + st.totals.dropped_time;
  readout_.sim_time = time_offset_ + st.time;
  readout_.lag = st.lag;
  readout_.stalled = readout_.dropped > 0;
}

}  // namespace pba::app
