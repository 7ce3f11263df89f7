// Implementation of pba::PhysicsThread: fixed-dt physics on its own thread (workbook 3.1.4).
//
// The loop wakes, measures the real time since its last wake on the Clock, feeds it to a
// TimeStepper in the "fixed" strategy (so the accumulator, the caps and the dropped-time
// accounting are exactly those of strategy (c)), publishes the new state, and sleeps until
// the accumulator will hold the next whole tick. Commands (pause, step, settings, stop)
// arrive under one mutex and a condition variable, so every wait is interruptible.
#include <algorithm>
#include <cmath>
#include <string>

#include "pba/time.h"

namespace pba {

namespace {
// the thread always ticks like "fixed"
StepperSettings as_fixed(StepperSettings s) {
  s.strategy = Strategy::Fixed;
  return s;
}
}  // namespace

PhysicsThread::PhysicsThread(const StepperSettings& settings, TickFn tick, PublishFn publish,
                             Clock* clock)
    : tick_(std::move(tick)),
      publish_(std::move(publish)),
      clock_(clock ? clock : &SteadyClock::instance()),
      settings_(as_fixed(settings)),
      stepper_(as_fixed(settings), clock_) {
  // validation happened in the stepper; the callables must exist
  if (!tick_) throw Error("PhysicsThread: tick function is empty");
  if (!publish_) publish_ = [](const TickStamp&) {};
}

PhysicsThread::~PhysicsThread() { stop(); }

void PhysicsThread::start(bool start_paused) {
  std::lock_guard lock(mutex_);
  if (running_) return;
  // the first wake measures real time from here, read on the caller's thread
  stop_ = false;
  running_ = true;
  paused_ = start_paused;
  steps_ = 0;
  resume_ns_ = clock_->now_ns();
  resumed_ = true;
  stats_.running = true;
  stats_.paused = paused_;
  stats_.failed = false;
  error_.clear();
  thread_ = std::thread([this] { run(); });
}

void PhysicsThread::stop() {
  // ask, wake, join; the flag is read under the mutex by the loop
  {
    std::lock_guard lock(mutex_);
    if (!running_) return;
    // joining itself would never return
    if (std::this_thread::get_id() == thread_.get_id())
      throw Error("PhysicsThread.stop: called from the physics thread (from a tick or publish)");
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::lock_guard lock(mutex_);
  running_ = false;
  stats_.running = false;
  progress_.notify_all();
}

bool PhysicsThread::running() const {
  std::lock_guard lock(mutex_);
  return running_;
}

void PhysicsThread::set_paused(bool paused) {
  {
    std::lock_guard lock(mutex_);
    if (paused_ == paused) return;
    paused_ = paused;
    stats_.paused = paused;
    // resuming: real time is owed from now, not from when the pause began
    if (!paused) {
      resume_ns_ = clock_->now_ns();
      resumed_ = true;
      steps_ = 0;
    }
  }
  wake_.notify_all();
}

bool PhysicsThread::paused() const {
  std::lock_guard lock(mutex_);
  return paused_;
}

void PhysicsThread::step(int n) {
  require_count(n, 1, 100000, "PhysicsThread.step n");
  {
    std::lock_guard lock(mutex_);
    if (!paused_) return;
    steps_ = static_cast<int>(std::min<long long>(100000, static_cast<long long>(steps_) + n));
  }
  wake_.notify_all();
}

void PhysicsThread::set_settings(const StepperSettings& settings) {
  settings.validate("StepperSettings");
  {
    std::lock_guard lock(mutex_);
    settings_ = as_fixed(settings);
    settings_changed_ = true;
  }
  wake_.notify_all();
}

StepperSettings PhysicsThread::settings() const {
  std::lock_guard lock(mutex_);
  return settings_;
}

PhysicsThreadStats PhysicsThread::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

bool PhysicsThread::wait_for_ticks(long long ticks, double timeout_s) const {
  std::unique_lock lock(mutex_);
  return progress_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                            [&] { return stats_.totals.ticks >= ticks || stats_.failed; }) &&
         stats_.totals.ticks >= ticks;
}

std::string PhysicsThread::error() const {
  std::lock_guard lock(mutex_);
  return error_;
}

void PhysicsThread::run() {
  // an exception leaving a thread's function ends the process (std::terminate): a World
  // whose state went non-finite throws from its tick, so keep the message and stop ticking
  std::string what;
  try {
    loop();
    return;
  } catch (const std::exception& e) {
    what = e.what();
  } catch (...) {
    what = "PhysicsThread: a tick or publish threw an exception that is not a std::exception";
  }
  std::lock_guard lock(mutex_);
  error_ = std::move(what);
  stats_.failed = true;
  // the ticks this wake ran before the throw changed the world: count them (the stepper is
  // this thread's alone, and it has stopped)
  stats_.totals = stepper_.totals();
  stats_.time = stepper_.time();
  stats_.lag = stats_.totals.pending_time;
  progress_.notify_all();
}

void PhysicsThread::loop() {
  std::unique_lock lock(mutex_);
  std::int64_t last = resume_ns_;
  while (!stop_) {
    // settings changes apply between wakes (a changed fixed_dt drops the accumulator)
    if (settings_changed_) {
      stepper_.set_settings(settings_);
      settings_changed_ = false;
    }
    if (resumed_) {
      last = resume_ns_;
      resumed_ = false;
    }

    // paused: run requested single steps, otherwise sleep until a command arrives
    if (paused_) {
      if (steps_ > 0) {
        --steps_;
        lock.unlock();
        const FrameStats f = stepper_.single_step(tick_);
        publish_(TickStamp{stepper_.time(), stepper_.tick_count(), clock_->now_ns()});
        const StepperTotals totals = stepper_.totals();
        const double t = stepper_.time();
        lock.lock();
        stats_.totals = totals;
        stats_.last_wake = f;
        stats_.time = t;
        stats_.lag = totals.pending_time;
        progress_.notify_all();
        continue;
      }
      wake_.wait(lock, [&] { return stop_ || !paused_ || steps_ > 0 || settings_changed_; });
      continue;
    }

    // measure the real time since the last wake (read under the lock, so a pause or resume
    // is ordered before or after it) and tick the fixed-step accumulator with it
    const std::int64_t now = clock_->now_ns();
    const std::int64_t frame = std::max<std::int64_t>(0, now - last);
    last = now;
    lock.unlock();
    const FrameStats f = stepper_.advance_ns(frame, tick_);
    if (f.ticks > 0) publish_(TickStamp{stepper_.time(), stepper_.tick_count(), clock_->now_ns()});
    const StepperTotals totals = stepper_.totals();
    const double t = stepper_.time();
    const double scale = stepper_.settings().time_scale;
    const auto until_tick = static_cast<std::int64_t>(
        std::ceil(static_cast<double>(stepper_.ns_until_next_tick()) / scale));
    lock.lock();

    // hand the statistics to readers
    stats_.totals = totals;
    stats_.last_wake = f;
    stats_.time = t;
    stats_.lag = totals.pending_time;
    ++stats_.wakes;
    progress_.notify_all();

    // sleep until the accumulator will hold a whole tick, waking early for any command
    const std::int64_t deadline = last + until_tick;
    while (!stop_ && !paused_ && !settings_changed_ && !resumed_) {
      const auto hint = clock_->wait_hint(deadline);
      if (hint.count() <= 0 || clock_->now_ns() >= deadline) break;
      wake_.wait_for(lock, hint);
    }
  }
}

}  // namespace pba
