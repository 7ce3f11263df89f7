// The app's physics loop: drives a sample's Step() through pba's time-stepping module,
// on the render thread (per-frame, max-step, fixed) or on a PhysicsThread (threaded).
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>

#include "pba/time.h"
#include "settings.h"

namespace pba::app {

class Sample;

/// What the profiler shows about the physics of the last frame and on average.
struct PhysicsReadout {
  int ticks = 0;              ///< ticks run in the last frame (thread: since the last frame)
  double tick_dt = 0;         ///< length of the last tick (s)
  double tick_wall = 0;       ///< median wall-clock time per tick over the last 256 ticks (s)
  /// wall-clock time spent in the ticks of the last frame (thread: since the last frame), s:
  /// what the profiler plots (ticks x the median lags a landing's slow steps by 128 ticks)
  double frame_tick_wall = 0;
  double dropped = 0;         ///< time dropped in the last frame (s)
  double dropped_total = 0;   ///< time dropped since the sample started (s)
  double sim_time = 0;        ///< simulated time (s)
  double lag = 0;             ///< threaded: real time owed but not simulated yet (s)
  bool stalled = false;       ///< a stall guard fired in the last frame
};

/// Virtual time for a PhysicsThread paced by `clock`: moves the clock by `frame_dt` seconds
/// one tick at a time (as real time passes while a renderer works) and after each move waits
/// until the thread has run every tick that is due, so frames are reproducible. `fed` keeps
/// the total seconds (after time_scale) fed so far; start it at 0 with the thread.
void AdvanceVirtualClock(PhysicsThread& thread, ManualClock& clock, double frame_dt, double* fed);

/// Runs the current sample's physics with the strategy in Settings::stepper.
class PhysicsLoop {
 public:
  /// `settings` is read every frame (strategy, rates, pause, single step); it must outlive
  /// the loop. With `virtual_time`, a threaded sample is paced by a manual clock that
  /// advance() moves, and advance() waits for the thread to catch up (reproducible frames).
  PhysicsLoop(Settings& settings, bool virtual_time);
  ~PhysicsLoop();
  PhysicsLoop(const PhysicsLoop&) = delete;
  PhysicsLoop& operator=(const PhysicsLoop&) = delete;

  /// Starts driving `sample` (nullptr detaches) from simulated time zero.
  void attach(Sample* sample);
  /// Advances one rendered frame of `frame_dt` seconds of real time. Honours pause and
  /// single step. Switches between the caller's thread and a physics thread when the
  /// strategy changes. Throws pba::Error from the sample's Step (e.g. a Newton failure).
  void advance(double frame_dt);
  /// Interpolation factor for drawing (fixed: the accumulator's alpha; threaded: how far
  /// real time has moved past the latest published tick; otherwise 1).
  double alpha() const { return alpha_; }
  /// Locks the sample's state against the physics thread; hold it while drawing or
  /// checking the sample. Uncontended when no thread runs.
  std::unique_lock<std::mutex> lock_state() { return std::unique_lock<std::mutex>(state_mutex_); }
  /// Physics numbers for the profiler.
  const PhysicsReadout& readout() const { return readout_; }
  /// The error a physics-thread tick threw, empty if none (the thread then pauses).
  std::string take_thread_error();

 private:
  void tick(double t, double dt);
  void start_thread();
  void stop_thread();

  Settings& settings_;
  bool virtual_time_;
  Sample* sample_ = nullptr;
  TimeStepper stepper_;
  std::unique_ptr<ManualClock> manual_clock_;
  std::unique_ptr<PhysicsThread> thread_;
  std::unique_ptr<SnapshotBuffer<TickStamp>> stamps_;  // recreated with each thread
  std::mutex state_mutex_;
  std::mutex error_mutex_;
  std::string thread_error_;
  std::atomic<bool> thread_failed_{false};
  double expected_fed_ = 0;     // virtual seconds (after time_scale) the thread should have seen
  double time_offset_ = 0;      // simulated time before the current stepper or thread began
  double dropped_offset_ = 0;   // dropped time before the current stepper or thread began
  double last_thread_dropped_ = 0;
  long long last_thread_ticks_ = 0;
  double last_thread_wall_ = 0;
  double alpha_ = 1;
  PhysicsReadout readout_;
};

}  // namespace pba::app
