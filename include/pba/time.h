// pba time stepping (workbook 3.1): when to tick the physics, and how far.
//
// Four strategies, selectable at run time through one settings struct:
//
//   per-frame  (3.1.1)  N ticks per rendered frame, each frame_dt / N long.
//   max-step   (3.1.2)  the frame is cut into the fewest equal ticks no longer than max_dt.
//   fixed      (3.1.3)  ticks of exactly fixed_dt; an accumulator carries the remainder
//                       across frames and gives the renderer an interpolation factor alpha.
//   threaded   (3.1.4)  physics on its own thread at fixed_dt, paced to real time, handing
//                       whole snapshots to the renderer (PhysicsThread + SnapshotBuffer).
//
// Every strategy guards against the physics stall (the "death spiral", 3.1.5): a frame is
// clamped to max_frame_dt and at most max_ticks_per_frame ticks run per frame. Time that is
// not simulated because of either cap is counted as dropped, per frame and in totals, so
// frame time == simulated + dropped (+ what the fixed accumulator still holds).
//
// Time is counted in exact integers: the fixed tick length is held as a rational number of
// nanoseconds num/den (1/60 s is exactly 50'000'000/3 ns, den <= 1000) and real time in
// units of 1/den ns, so how many ticks have run after a given stretch of real time never
// depends on how that stretch was cut into frames, and no rounding error accumulates.
// See docs/time-stepping.md.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <type_traits>
#include <utility>

#include "pba/core.h"

namespace pba {

// ---------------------------------------------------------------------------------------
// strategies

/// When and how far the physics ticks. Names for the command line and the UI are
/// "per-frame", "max-step", "fixed" and "threaded" (strategy_name / parse_strategy).
enum class Strategy {
  PerFrame,  ///< ticks_per_frame ticks per frame, each frame_dt / ticks_per_frame (3.1.1)
  MaxStep,   ///< fewest equal ticks of at most max_dt per frame (3.1.2)
  Fixed,     ///< ticks of fixed_dt, remainder carried by an accumulator (3.1.3)
  Threaded,  ///< fixed_dt ticks on a PhysicsThread, decoupled from rendering (3.1.4)
};

/// Every strategy, in the order the UI lists them.
inline constexpr std::array<Strategy, 4> kStrategies = {Strategy::PerFrame, Strategy::MaxStep,
                                                         Strategy::Fixed, Strategy::Threaded};

/// The strategy's name for the command line and the UI, e.g. "max-step".
std::string_view strategy_name(Strategy s);

/// A one-line human description of the strategy, for UI tooltips.
std::string_view strategy_description(Strategy s);

/// Parses "per-frame", "max-step", "fixed" or "threaded" (exact, lowercase). Throws Error
/// naming the text, `where` it came from (e.g. "--strategy") and the valid names.
Strategy parse_strategy(std::string_view text, std::string_view where);

// ---------------------------------------------------------------------------------------
// settings

/// Settings shared by every strategy; each field says which strategies read it.
/// Start from the defaults and change what you need; validate() names any bad field.
struct StepperSettings {
  /// Which strategy TimeStepper::advance uses. PhysicsThread ignores it (it is always
  /// "threaded", which ticks like "fixed").
  Strategy strategy = Strategy::Fixed;
  /// fixed, threaded: length of every tick in seconds; valid [1e-6, 10].
  double fixed_dt = 1.0 / 60.0;
  /// per-frame: ticks per frame, each frame_dt / ticks_per_frame long; valid [1, 10000].
  int ticks_per_frame = 1;
  /// max-step: longest tick in seconds; valid [1e-6, 10]. Workbook 3.1.2 uses 1/600.
  double max_dt = 1.0 / 600.0;
  /// all: stall guard, most ticks per frame (per wake-up on a PhysicsThread); valid [1, 100000].
  /// Ticks beyond it are dropped and counted.
  int max_ticks_per_frame = 32;
  /// all: stall guard, longest frame in seconds of real time (after time_scale) that is
  /// simulated; the excess is dropped and counted. Valid (0, 3600]. A debugger break or a
  /// window drag then costs one bounded frame, not a burst of catch-up ticks.
  double max_frame_dt = 0.25;
  /// all: simulated seconds per real second (slow motion < 1, fast forward > 1); valid (0, 1000].
  double time_scale = 1.0;

  /// Throws Error naming the first bad field, prefixed by `where`, e.g.
  /// "StepperSettings.fixed_dt: must be finite and > 0, got 0".
  void validate(std::string_view where = "StepperSettings") const;

  /// Field-wise equality (used to detect a change of settings).
  bool operator==(const StepperSettings&) const = default;
};

// ---------------------------------------------------------------------------------------
// clocks

/// The source of real time, injectable so tests can drive time by hand. Monotonic.
/// Implementations must be safe to call from several threads at once.
class Clock {
 public:
  virtual ~Clock() = default;
  /// Current time in nanoseconds since an arbitrary fixed epoch; never decreases.
  virtual std::int64_t now_ns() = 0;
  /// How long (real time) a waiter aiming for `deadline_ns` should block before reading
  /// now_ns() again. A real clock answers deadline - now; a manual clock, whose time moves
  /// only when someone moves it, answers a short poll.
  virtual std::chrono::nanoseconds wait_hint(std::int64_t deadline_ns) = 0;
};

/// std::chrono::steady_clock as a Clock. Stateless; one shared instance is enough.
class SteadyClock final : public Clock {
 public:
  std::int64_t now_ns() override;
  std::chrono::nanoseconds wait_hint(std::int64_t deadline_ns) override;
  /// A process-wide instance (stateless, so sharing it is safe).
  static SteadyClock& instance();
};

/// A clock that moves only when told to: for deterministic tests. Thread-safe.
class ManualClock final : public Clock {
 public:
  /// Starts at `start_ns` nanoseconds.
  explicit ManualClock(std::int64_t start_ns = 0) : now_(start_ns) {}
  std::int64_t now_ns() override { return now_.load(std::memory_order_acquire); }
  std::chrono::nanoseconds wait_hint(std::int64_t deadline_ns) override;
  /// Moves time forward by `ns` >= 0 nanoseconds.
  void advance_ns(std::int64_t ns) { now_.fetch_add(ns, std::memory_order_acq_rel); }
  /// Moves time forward by `seconds` >= 0 (rounded to the nearest nanosecond).
  void advance(double seconds);

 private:
  std::atomic<std::int64_t> now_;
};

/// Seconds (finite, >= 0, at most 1e6) to nanoseconds, rounded to nearest. Throws Error
/// naming `where` otherwise.
std::int64_t seconds_to_ns(double seconds, std::string_view where);

// ---------------------------------------------------------------------------------------
// the tick callable

/// A non-owning reference to a callable `void(double t, double dt)`: t is the simulated
/// time (s) at the start of the tick and dt its length (s). It never allocates; the
/// callable must outlive the call it is passed to (pass a lambda directly to advance()).
class TickRef {
 public:
  template <class F>
    requires(!std::is_same_v<std::remove_cvref_t<F>, TickRef> &&
             std::is_invocable_v<F&, double, double>)
  TickRef(F&& f) noexcept  // NOLINT: implicit by design, like std::function_ref
      : obj_(const_cast<void*>(static_cast<const void*>(std::addressof(f)))),
        call_([](void* o, double t, double dt) {
          (*static_cast<std::remove_reference_t<F>*>(o))(t, dt);
        }) {}
  /// Runs the tick.
  void operator()(double t, double dt) const { call_(obj_, t, dt); }

 private:
  void* obj_;
  void (*call_)(void*, double, double);
};

// ---------------------------------------------------------------------------------------
// statistics

/// What one call to TimeStepper::advance (one rendered frame) did. Times in seconds.
struct FrameStats {
  int ticks = 0;               ///< ticks run this frame
  double frame_dt = 0;         ///< real frame time fed in, after time_scale (s)
  double simulated = 0;        ///< simulated time advanced this frame (s)
  double dropped = 0;          ///< time not simulated because of the stall guard (s)
  long long dropped_ticks = 0; ///< fixed: whole ticks dropped by the tick cap this frame
  double tick_dt = 0;          ///< length of the last tick run (s), 0 when none ran
  double alpha = 0;            ///< fixed: accumulator / fixed_dt in [0, 1); 0 otherwise
  double tick_wall = 0;        ///< wall-clock seconds spent inside the ticks this frame
  bool stalled = false;        ///< true when a stall guard (frame clamp or tick cap) fired
};

/// Running totals since construction or reset(). Times in seconds.
struct StepperTotals {
  long long frames = 0;          ///< frames advanced
  long long ticks = 0;           ///< ticks run
  long long frames_dropped = 0;  ///< frames in which the stall guard dropped time
  long long dropped_ticks = 0;   ///< fixed/threaded: whole ticks dropped by the tick cap
  double frame_time = 0;         ///< real time fed in, after time_scale (s)
  double simulated_time = 0;     ///< simulated time (s)
  double dropped_time = 0;       ///< time dropped by the stall guard (s)
  double pending_time = 0;       ///< fixed: time held in the accumulator, not yet simulated (s)
  double stepped_time = 0;       ///< real time single_step() pretended had passed (s)
  double tick_wall_total = 0;    ///< wall-clock seconds spent in ticks
  double tick_wall_mean = 0;     ///< mean wall-clock seconds per tick
  double tick_wall_median = 0;   ///< median wall-clock seconds per tick over the last 256 ticks
  double tick_wall_max = 0;      ///< longest tick, wall-clock seconds
};
// frame_time + stepped_time == simulated_time + dropped_time + pending_time, to rounding
// (each total is one or two roundings of exact integer counts, ~1e-15 relative).

/// Wall-clock tick timings: total, max and a ring of the last 256 for the median.
/// Fixed size; never allocates.
class TickTimings {
 public:
  static constexpr int kWindow = 256;  ///< ticks kept for the median
  /// Records one tick that took `seconds` of wall-clock time.
  void add(double seconds);
  /// Median of the last min(count, 256) ticks, 0 when none.
  double median() const;
  long long count() const { return count_; }  ///< ticks recorded
  double total() const { return total_; }     ///< seconds in all recorded ticks
  double max() const { return max_; }         ///< longest recorded tick (s)
  void reset() { *this = TickTimings{}; }     ///< forgets everything

 private:
  std::array<float, kWindow> ring_{};
  mutable std::array<float, kWindow> scratch_{};
  long long count_ = 0;
  double total_ = 0, max_ = 0;
};

// ---------------------------------------------------------------------------------------
// the stepper: strategies (a)-(c) on the caller's thread

/// Decides how many ticks each rendered frame runs and how long they are, for the
/// "per-frame", "max-step" and "fixed" strategies, on the caller's thread.
///
///     pba::TimeStepper stepper({.strategy = pba::Strategy::Fixed, .fixed_dt = 1.0 / 120});
///     while (running) {
///       auto f = stepper.advance(frame_seconds, [&](double t, double dt) { world.step(dt); });
///       render(world, f.alpha);   // blend previous and current state by alpha
///     }
///
/// advance() never allocates. The "threaded" strategy needs a PhysicsThread; advance()
/// with it throws (check TimeStepper::runs_on_caller(strategy) first).
class TimeStepper {
 public:
  /// Validates `settings` (throws Error naming the bad field). `clock` measures the wall
  /// time of ticks; nullptr means SteadyClock. The clock must outlive the stepper.
  explicit TimeStepper(const StepperSettings& settings = {}, Clock* clock = nullptr);

  /// Advances one rendered frame of `frame_dt` seconds of real time (finite, >= 0, <= 1e6),
  /// calling tick(t, dt) for each tick. Throws Error naming frame_dt if it is invalid, and
  /// if the strategy is "threaded". The frame is rounded to the stepper's exact time unit
  /// (1/den ns, where fixed_dt = num/den ns; 1/3 ns for fixed_dt = 1/60 s), so
  /// advance(1.0 / 30) with fixed_dt = 1.0 / 60 runs exactly 2 ticks every frame.
  FrameStats advance(double frame_dt, TickRef tick);
  /// As above with the frame in exact integer nanoseconds (e.g. a steady_clock difference):
  /// tick counts then depend only on the sum of the frames, never on how real time was cut
  /// into frames. frame_ns in [0, 1e15].
  FrameStats advance_ns(std::int64_t frame_ns, TickRef tick);

  /// Single step for a paused simulation: advances as if one nominal frame of fixed_dt
  /// seconds had passed, without touching the accumulator. fixed/threaded: exactly one tick
  /// of fixed_dt; per-frame: ticks_per_frame ticks; max-step: that frame subdivided.
  /// Counted in totals as stepped_time, not frame_time.
  FrameStats single_step(TickRef tick);

  /// Replaces the settings (validated first). Changing nothing is a no-op. Changing the
  /// strategy or fixed_dt drops what the accumulator held (counted as dropped time); the
  /// simulated time and totals carry on.
  void set_settings(const StepperSettings& settings);
  /// The current settings.
  const StepperSettings& settings() const { return settings_; }

  /// Simulated time (s) since construction or reset().
  double time() const;
  /// Ticks run since construction or reset().
  long long tick_count() const { return totals_ticks_; }
  /// fixed: interpolation factor in [0, 1) after the last advance; 0 for other strategies.
  double alpha() const;
  /// Statistics of the last advance().
  const FrameStats& last_frame() const { return last_; }
  /// Running totals (computes the median; no allocation).
  StepperTotals totals() const;
  /// fixed: real time (ns, rounded up) until the accumulator holds one whole tick.
  std::int64_t ns_until_next_tick() const;
  /// Back to time zero with empty totals; keeps the settings.
  void reset();

  /// True for strategies that advance() runs on the caller's thread (all but threaded).
  static bool runs_on_caller(Strategy s) { return s != Strategy::Threaded; }

 private:
  void begin_epoch(bool drop_pending);
  std::int64_t frame_units(double frame_ns, std::int64_t exact_ns, FrameStats& f);
  FrameStats advance_units(std::int64_t units, FrameStats f, TickRef tick);
  std::int64_t run_per_frame(std::int64_t units, TickRef tick, FrameStats& f);  // -> dropped
  std::int64_t run_max_step(std::int64_t units, TickRef tick, FrameStats& f);   // -> dropped
  void run_fixed(TickRef tick, FrameStats& f);
  void run_tick(TickRef tick, double t, double dt, FrameStats& f);
  double seconds(std::int64_t units) const {
    return static_cast<double>(units) / static_cast<double>(den_) * 1e-9;
  }

  StepperSettings settings_;
  Clock* clock_;
  // exact time unit of this epoch: 1/den_ ns; a fixed tick is tick_num_ units
  std::int64_t tick_num_ = 1, den_ = 1;
  // max-step's longest tick as an exact rational: max_num_ / max_den_ ns
  std::int64_t max_num_ = 1, max_den_ = 1;
  // fixed: the accumulator, in units; always < tick_num_ between frames
  std::int64_t acc_ = 0;
  // exact counts since the last settings change (the epoch) ...
  long long epoch_ticks_ = 0;          // fixed: ticks
  std::int64_t sim_units_ = 0;         // per-frame, max-step: simulated units
  std::int64_t frame_units_ = 0;       // frame time fed in, after clamping
  std::int64_t dropped_units_ = 0;     // dropped by the tick caps
  // ... and seconds folded in at each change (plus clamped excess, which is rare)
  double base_time_ = 0, base_frame_ = 0, base_dropped_ = 0, stepped_time_ = 0;
  // totals
  long long totals_frames_ = 0, totals_ticks_ = 0, totals_frames_dropped_ = 0;
  long long totals_dropped_ticks_ = 0;
  TickTimings timings_;
  FrameStats last_;
};

// ---------------------------------------------------------------------------------------
// strategy (d): the handoff between a physics thread and the renderer

/// Identifies a published state: simulated time (s), tick count, and the Clock time (ns)
/// at which it was published.
struct TickStamp {
  double t = 0;               ///< simulated time of the state (s)
  long long tick = 0;         ///< ticks run to reach it
  std::int64_t wall_ns = 0;   ///< Clock::now_ns() when it was published
};

/// A lock-free triple buffer of `State` between one writer thread (physics) and one reader
/// thread (renderer). The writer fills write_slot() and publish()es it; the reader calls
/// acquire() and then reads current() (and previous(), for interpolation) until its next
/// acquire(). Neither side ever waits, and the reader never sees a half-written state: a
/// slot is owned by exactly one side at any time, and ownership moves by one atomic
/// exchange (release on publish, acquire on take).
/// State must be copy-assignable; copies happen only on the reader side (previous()) and
/// do not allocate if State's copy-assignment reuses capacity (std::vector of equal size).
template <class State>
class SnapshotBuffer {
 public:
  /// All three slots and previous() start as `initial` with stamp {}.
  explicit SnapshotBuffer(const State& initial = State{})
      : slots_{Slot{initial, {}}, Slot{initial, {}}, Slot{initial, {}}}, previous_(initial) {}
  SnapshotBuffer(const SnapshotBuffer&) = delete;
  SnapshotBuffer& operator=(const SnapshotBuffer&) = delete;

  // ---- writer side (one thread) ----

  /// The slot only the writer may touch until publish(). Fill it completely: it holds
  /// whatever state was published two or three publishes ago.
  State& write_slot() { return slots_[back_].state; }
  /// Makes write_slot() the latest state, stamped `stamp`, and hands the writer a free slot.
  void publish(const TickStamp& stamp) {
    // stamp the back slot, then swap it into the middle, marking it fresh
    slots_[back_].stamp = stamp;
    const unsigned old = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
    back_ = old & kIndexMask;
    published_.fetch_add(1, std::memory_order_relaxed);
  }

  // ---- reader side (one thread) ----

  /// Takes the most recently published state if there is a new one; returns true then.
  /// The state it replaces becomes previous().
  bool acquire() {
    // nothing new: keep reading the same front slot
    if (!(middle_.load(std::memory_order_relaxed) & kFresh)) return false;
    // keep the old front as the interpolation start, then swap the middle to the front
    previous_ = slots_[front_].state;
    previous_stamp_ = slots_[front_].stamp;
    const unsigned old = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = old & kIndexMask;
    return true;
  }
  /// The latest acquired state (the initial state before the first acquire()).
  const State& current() const { return slots_[front_].state; }
  /// Stamp of current().
  const TickStamp& current_stamp() const { return slots_[front_].stamp; }
  /// The state current() replaced (the initial state until two acquires).
  const State& previous() const { return previous_; }
  /// Stamp of previous().
  const TickStamp& previous_stamp() const { return previous_stamp_; }
  /// Interpolation factor in [0, 1] from previous() to current() for a frame drawn at
  /// Clock time `now_ns`: how far real time has moved past current()'s publication, as a
  /// fraction of the real time between the two publications (or of `fallback_interval_s`
  /// seconds when that is unknown). Drawing lerp(previous, current, alpha) lags the physics
  /// by about one publication interval and moves smoothly.
  double alpha(std::int64_t now_ns, double fallback_interval_s) const {
    // real time between the two latest publications, or the fallback
    const auto& c = current_stamp();
    double interval = static_cast<double>(c.wall_ns - previous_stamp_.wall_ns) * 1e-9;
    if (!(interval > 0) || previous_stamp_.tick == c.tick) interval = fallback_interval_s;
    if (!(interval > 0)) return 1.0;
    // fraction of it elapsed since the current state was published, clamped
    const double a = static_cast<double>(now_ns - c.wall_ns) * 1e-9 / interval;
    return a < 0 ? 0.0 : (a > 1 ? 1.0 : a);
  }

  /// Number of publish() calls so far (any thread; a relaxed counter for statistics).
  long long published() const { return published_.load(std::memory_order_relaxed); }

 private:
  static constexpr unsigned kFresh = 4u, kIndexMask = 3u;
  struct Slot {
    State state;
    TickStamp stamp;
  };
  std::array<Slot, 3> slots_;
  unsigned back_ = 0;                  // writer-owned
  std::atomic<unsigned> middle_{1u};   // shared: index | kFresh
  unsigned front_ = 2;                 // reader-owned
  State previous_;                     // reader-owned
  TickStamp previous_stamp_{};         // reader-owned
  std::atomic<long long> published_{0};
};

// ---------------------------------------------------------------------------------------
// strategy (d): the physics thread

/// A consistent copy of a PhysicsThread's state, for the UI readout.
struct PhysicsThreadStats {
  StepperTotals totals;        ///< ticks, simulated, dropped and pending time, tick timings
  FrameStats last_wake;        ///< what the latest wake-up did
  long long wakes = 0;         ///< times the thread woke and advanced
  double time = 0;             ///< simulated time (s)
  double lag = 0;              ///< real time (after time_scale, s) owed but not yet simulated
  bool paused = false;         ///< paused right now
  bool running = false;        ///< thread started and not stopped
  /// A tick or publish threw (a World whose state went non-finite): the thread stopped
  /// ticking and waits for stop(); PhysicsThread::error() has the message.
  bool failed = false;
};

/// Physics on its own thread (workbook 3.1.4): ticks of fixed_dt, paced to real time by a
/// Clock, with the same accumulator and stall guard as the "fixed" strategy (the cap is per
/// wake-up). After each wake-up that ticked, `publish(stamp)` runs on the physics thread;
/// copy the simulation state into a SnapshotBuffer there and the renderer reads it with
/// SnapshotBuffer::acquire(). Real time spent paused is not owed and not dropped.
///
///     pba::SnapshotBuffer<Particles> snapshots(world.particles);
///     pba::PhysicsThread physics(settings,
///         [&](double t, double dt) { world.step(dt); },                       // physics thread
///         [&](const pba::TickStamp& s) { snapshots.write_slot() = world.particles;
///                                        snapshots.publish(s); });          // physics thread
///     physics.start();
///     ... each frame: snapshots.acquire(); draw(snapshots.previous(), snapshots.current(),
///                     snapshots.alpha(clock.now_ns(), settings.fixed_dt));
///     physics.stop();   // joins; the world is the caller's again
///
/// While running, the tick and publish callables own the simulation state; touch it from
/// another thread only after stop(). Control calls (pause, step, set_settings, stop, stats)
/// are thread-safe and return at once (stop() waits for the current tick to end).
class PhysicsThread {
 public:
  /// Runs one tick: t is the simulated time at its start (s), dt == fixed_dt (s).
  using TickFn = std::function<void(double t, double dt)>;
  /// Publishes the state reached after a wake-up's ticks.
  using PublishFn = std::function<void(const TickStamp& stamp)>;

  /// Validates `settings` (throws Error naming the bad field; `strategy` is ignored).
  /// `clock` paces the loop; nullptr means SteadyClock; it must outlive this object.
  PhysicsThread(const StepperSettings& settings, TickFn tick, PublishFn publish,
                Clock* clock = nullptr);
  /// Stops and joins.
  ~PhysicsThread();
  PhysicsThread(const PhysicsThread&) = delete;
  PhysicsThread& operator=(const PhysicsThread&) = delete;

  /// Starts the thread (time continues from where a previous stop() left it). Calling it
  /// while running does nothing. If start_paused, the thread waits for step() or resume.
  void start(bool start_paused = false);
  /// Asks the thread to finish its current tick and exit, then joins. Idempotent. Throws
  /// Error if called from the physics thread itself (a tick or publish callable).
  void stop();
  /// True between start() and stop().
  bool running() const;

  /// Pauses (true) or resumes (false). Resuming does not owe the paused time.
  void set_paused(bool paused);
  /// True while paused.
  bool paused() const;
  /// While paused: runs `n` more ticks (n in [1, 100000]) and publishes after each.
  /// Ignored while running unpaused.
  void step(int n = 1);
  /// Changes fixed_dt, caps or time_scale at the next wake-up (validated here). A changed
  /// fixed_dt drops what the accumulator held (counted).
  void set_settings(const StepperSettings& settings);
  /// The settings last set.
  StepperSettings settings() const;
  /// Statistics, copied under the lock.
  PhysicsThreadStats stats() const;
  /// Blocks until at least `ticks` ticks have run in total, or `timeout_s` seconds of real
  /// time pass (a hang guard), or the thread failed; returns true if reached. For tests and
  /// tools.
  bool wait_for_ticks(long long ticks, double timeout_s) const;
  /// The message of the exception a tick or publish threw, empty while none has (since the
  /// last start()). The exception does not escape the thread (that would end the process):
  /// it is kept here, the thread stops ticking, stats().failed turns true, and stop() joins
  /// as usual; a World that threw refuses later ticks with the same message.
  std::string error() const;

 private:
  void run();
  void loop();

  TickFn tick_;
  PublishFn publish_;
  Clock* clock_;
  mutable std::mutex mutex_;
  mutable std::condition_variable wake_;      // commands for the physics thread
  mutable std::condition_variable progress_;  // ticks ran (wait_for_ticks)
  StepperSettings settings_;                  // guarded by mutex_
  bool settings_changed_ = false;             // guarded
  bool stop_ = false;                         // guarded
  bool paused_ = false;                       // guarded
  bool running_ = false;                      // guarded
  int steps_ = 0;                             // guarded: ticks requested while paused
  std::int64_t resume_ns_ = 0;                // guarded: clock time of start() or resume
  bool resumed_ = false;                      // guarded: resume_ns_ is new
  PhysicsThreadStats stats_;                  // guarded: published copy
  std::string error_;                         // guarded: what a tick or publish threw
  TimeStepper stepper_;                       // physics thread only while running
  std::thread thread_;
};

}  // namespace pba
