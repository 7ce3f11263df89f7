// Implementation of pba/time.h: strategy names, settings, clocks and the TimeStepper.
#include "pba/time.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pba {

// ---------------------------------------------------------------------------------------
// strategies

std::string_view strategy_name(Strategy s) {
  switch (s) {
    case Strategy::PerFrame: return "per-frame";
    case Strategy::MaxStep: return "max-step";
    case Strategy::Fixed: return "fixed";
    case Strategy::Threaded: return "threaded";
  }
  return "unknown";
}

std::string_view strategy_description(Strategy s) {
  switch (s) {
    case Strategy::PerFrame: return "N ticks per rendered frame, each frame_dt / N (workbook 3.1.1)";
    case Strategy::MaxStep: return "frame cut into equal ticks of at most max_dt (workbook 3.1.2)";
    case Strategy::Fixed:
      return "ticks of fixed_dt; an accumulator carries the rest to the next frame (workbook 3.1.3)";
    case Strategy::Threaded:
      return "fixed_dt ticks on a physics thread, paced to real time (workbook 3.1.4)";
  }
  return "";
}

Strategy parse_strategy(std::string_view text, std::string_view where) {
  // exact match against the names; the error lists them all
  std::string names;
  for (Strategy s : kStrategies) {
    if (text == strategy_name(s)) return s;
    if (!names.empty()) names += ", ";
    names += strategy_name(s);
  }
  throw Error(std::string(where) + ": unknown time-stepping strategy \"" + std::string(text) +
              "\"; valid: " + names);
}

// ---------------------------------------------------------------------------------------
// settings

void StepperSettings::validate(std::string_view where) const {
  // each field against its documented range, named "<where>.<field>"
  const std::string w(where);
  if (static_cast<unsigned>(strategy) >= kStrategies.size())
    throw Error(w + ".strategy: not a Strategy, got " +
                std::to_string(static_cast<int>(strategy)));
  require_positive(fixed_dt, w + ".fixed_dt");
  require_in_range(fixed_dt, 1e-6, 10.0, w + ".fixed_dt");
  require_count(ticks_per_frame, 1, 10000, w + ".ticks_per_frame");
  require_positive(max_dt, w + ".max_dt");
  require_in_range(max_dt, 1e-6, 10.0, w + ".max_dt");
  require_count(max_ticks_per_frame, 1, 100000, w + ".max_ticks_per_frame");
  require_positive(max_frame_dt, w + ".max_frame_dt");
  require_in_range(max_frame_dt, 0.0, 3600.0, w + ".max_frame_dt");
  require_positive(time_scale, w + ".time_scale");
  require_in_range(time_scale, 0.0, 1000.0, w + ".time_scale");
}

// ---------------------------------------------------------------------------------------
// clocks

std::int64_t SteadyClock::now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::chrono::nanoseconds SteadyClock::wait_hint(std::int64_t deadline_ns) {
  return std::chrono::nanoseconds(std::max<std::int64_t>(0, deadline_ns - now_ns()));
}

SteadyClock& SteadyClock::instance() {
  // stateless, so one shared instance is not global mutable state
  static SteadyClock clock;
  return clock;
}

std::chrono::nanoseconds ManualClock::wait_hint(std::int64_t deadline_ns) {
  // time moves only when someone moves it: poll briefly, never sleep to the deadline
  if (deadline_ns <= now_ns()) return std::chrono::nanoseconds(0);
  return std::chrono::microseconds(200);
}

void ManualClock::advance(double seconds) { advance_ns(seconds_to_ns(seconds, "ManualClock.advance")); }

std::int64_t seconds_to_ns(double seconds, std::string_view where) {
  require_in_range(seconds, 0.0, 1e6, where);
  return std::llround(seconds * 1e9);
}

// ---------------------------------------------------------------------------------------
// tick timings

void TickTimings::add(double seconds) {
  // ring of the latest samples for the median, plus running total and max
  ring_[static_cast<std::size_t>(count_ % kWindow)] = static_cast<float>(seconds);
  ++count_;
  total_ += seconds;
  max_ = std::max(max_, seconds);
}

double TickTimings::median() const {
  // nth_element over a fixed scratch copy: no allocation
  const auto n = static_cast<std::size_t>(std::min<long long>(count_, kWindow));
  if (n == 0) return 0;
  std::copy(ring_.begin(), ring_.begin() + static_cast<std::ptrdiff_t>(n), scratch_.begin());
  auto mid = scratch_.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(scratch_.begin(), mid, scratch_.begin() + static_cast<std::ptrdiff_t>(n));
  double m = *mid;
  if (n % 2 == 0) m = 0.5 * (m + *std::max_element(scratch_.begin(), mid));
  return m;
}

// ---------------------------------------------------------------------------------------
// exact tick lengths

namespace {

// Best rational approximation num/den of x > 0 with den <= 1000, by continued fractions
// (the convergents p_k/q_k satisfy |x - p_k/q_k| < 1/(q_k q_{k+1})). Stops as soon as a
// convergent reproduces x to within 2 ulp, so 1e9/60 = 16666666.666666666 becomes exactly
// 50000000/3 and every tick rate with a small denominator (1/144 s = 62500000/9 ns) is
// exact. Otherwise the error is below 1/1000 ns per tick: simulated time then drifts from
// real time by at most 1e-12 s per tick, i.e. 1e-8 relative at fixed_dt = 1e-4 s.
void to_rational(double x, std::int64_t& num, std::int64_t& den) {
  constexpr std::int64_t kMaxDen = 1000;
  std::int64_t p0 = 0, q0 = 1, p1 = 1, q1 = 0;  // p_{k-2}/q_{k-2}, p_{k-1}/q_{k-1}
  double r = x;
  num = std::max<std::int64_t>(1, std::llround(x));
  den = 1;
  for (int k = 0; k < 64; ++k) {
    // next convergent
    const double a = std::floor(r);
    const auto ai = static_cast<std::int64_t>(a);
    const std::int64_t p2 = ai * p1 + p0, q2 = ai * q1 + q0;
    if (q2 > kMaxDen || p2 <= 0) break;
    num = p2;
    den = q2;
    // close enough to x, or x exhausted
    const double approx = static_cast<double>(p2) / static_cast<double>(q2);
    if (std::fabs(approx - x) <= 2 * std::numeric_limits<double>::epsilon() * x) break;
    const double frac = r - a;
    if (frac <= 0) break;
    r = 1 / frac;
    p0 = p1;
    q0 = q1;
    p1 = p2;
    q1 = q2;
  }
}

// epochs fold into seconds before their unit counts could overflow
constexpr std::int64_t kFoldUnits = 1'000'000'000'000'000'000LL;

}  // namespace

// ---------------------------------------------------------------------------------------
// the stepper

TimeStepper::TimeStepper(const StepperSettings& settings, Clock* clock)
    : settings_(settings), clock_(clock ? clock : &SteadyClock::instance()) {
  settings_.validate("StepperSettings");
  to_rational(settings_.fixed_dt * 1e9, tick_num_, den_);
  to_rational(settings_.max_dt * 1e9, max_num_, max_den_);
}

void TimeStepper::begin_epoch(bool drop_pending) {
  // fold the exact counts of the ending epoch into seconds (under its settings)
  const StepperTotals t = totals();
  base_time_ = t.simulated_time;
  base_frame_ = t.frame_time;
  base_dropped_ = t.dropped_time + (drop_pending ? t.pending_time : 0.0);
  epoch_ticks_ = 0;
  sim_units_ = 0;
  frame_units_ = 0;
  dropped_units_ = 0;
  if (!drop_pending) {
    // keep the accumulator (same unit): count it as frame time of the new epoch
    base_frame_ -= t.pending_time;
    frame_units_ = acc_;
    return;
  }
  // the unit may change: what the accumulator held is dropped (and counted)
  acc_ = 0;
}

void TimeStepper::set_settings(const StepperSettings& settings) {
  // validate first, so a bad change leaves the stepper as it was
  settings.validate("StepperSettings");
  if (settings == settings_) return;
  const bool new_epoch = settings.strategy != settings_.strategy ||
                         settings.fixed_dt != settings_.fixed_dt ||
                         settings.max_dt != settings_.max_dt;
  if (new_epoch) begin_epoch(true);
  settings_ = settings;
  to_rational(settings_.fixed_dt * 1e9, tick_num_, den_);
  to_rational(settings_.max_dt * 1e9, max_num_, max_den_);
}

double TimeStepper::time() const {
  // one rounding of exact counts since the last settings change
  if (settings_.strategy == Strategy::Fixed || settings_.strategy == Strategy::Threaded)
    return base_time_ + static_cast<double>(epoch_ticks_) * settings_.fixed_dt;
  return base_time_ + seconds(sim_units_);
}

double TimeStepper::alpha() const {
  return static_cast<double>(acc_) / static_cast<double>(tick_num_);
}

std::int64_t TimeStepper::ns_until_next_tick() const {
  // (tick - acc) units, rounded up to whole ns
  const std::int64_t missing = tick_num_ - acc_;
  return (missing + den_ - 1) / den_;
}

void TimeStepper::reset() {
  const StepperSettings s = settings_;
  Clock* c = clock_;
  *this = TimeStepper(s, c);
}

StepperTotals TimeStepper::totals() const {
  StepperTotals r;
  r.frames = totals_frames_;
  r.ticks = totals_ticks_;
  r.frames_dropped = totals_frames_dropped_;
  r.dropped_ticks = totals_dropped_ticks_;
  r.frame_time = base_frame_ + seconds(frame_units_);
  r.simulated_time = time();
  r.dropped_time = base_dropped_ + seconds(dropped_units_);
  r.pending_time = seconds(acc_);
  r.stepped_time = stepped_time_;
  r.tick_wall_total = timings_.total();
  r.tick_wall_mean = timings_.count() ? timings_.total() / static_cast<double>(timings_.count()) : 0;
  r.tick_wall_median = timings_.median();
  r.tick_wall_max = timings_.max();
  return r;
}

std::int64_t TimeStepper::frame_units(double frame_ns, std::int64_t exact_ns, FrameStats& f) {
  // the frame in units of 1/den ns; exact when given integer ns at time_scale 1
  const std::int64_t max_ns = std::llround(settings_.max_frame_dt * 1e9);
  const bool exact = exact_ns >= 0 && settings_.time_scale == 1.0;
  if (exact ? exact_ns <= max_ns : frame_ns <= static_cast<double>(max_ns)) {
    f.frame_dt = exact ? static_cast<double>(exact_ns) * 1e-9 : frame_ns * 1e-9;
    return exact ? exact_ns * den_ : std::llround(frame_ns * static_cast<double>(den_));
  }
  // stall guard, part one: simulate at most max_frame_dt; the excess is dropped
  const double excess_s =
      exact ? static_cast<double>(exact_ns - max_ns) * 1e-9 : (frame_ns - static_cast<double>(max_ns)) * 1e-9;
  f.frame_dt = static_cast<double>(max_ns) * 1e-9 + excess_s;
  f.dropped += excess_s;
  f.stalled = true;
  base_frame_ += excess_s;
  base_dropped_ += excess_s;
  return max_ns * den_;
}

FrameStats TimeStepper::advance(double frame_dt, TickRef tick) {
  // validate, scale and convert; then tick
  require_in_range(frame_dt, 0.0, 1e6, "TimeStepper.advance frame_dt (s)");
  if (settings_.strategy == Strategy::Threaded)
    throw Error(
        "TimeStepper.advance: strategy \"threaded\" runs on a PhysicsThread, not on the "
        "caller's thread");
  FrameStats f;
  const std::int64_t units = frame_units(frame_dt * settings_.time_scale * 1e9, -1, f);
  return advance_units(units, f, tick);
}

FrameStats TimeStepper::advance_ns(std::int64_t frame_ns, TickRef tick) {
  // validate, scale and convert; then tick
  if (frame_ns < 0 || frame_ns > 1'000'000'000'000'000LL)
    throw Error("TimeStepper.advance_ns frame_ns: must be an integer in [0, 1e15], got " +
                std::to_string(frame_ns));
  if (settings_.strategy == Strategy::Threaded)
    throw Error(
        "TimeStepper.advance: strategy \"threaded\" runs on a PhysicsThread, not on the "
        "caller's thread");
  FrameStats f;
  const std::int64_t units = frame_units(
      static_cast<double>(frame_ns) * settings_.time_scale, frame_ns, f);
  return advance_units(units, f, tick);
}

FrameStats TimeStepper::advance_units(std::int64_t units, FrameStats f, TickRef tick) {
  // tick by the chosen strategy (stall guard, part two: the tick cap)
  frame_units_ += units;
  switch (settings_.strategy) {
    case Strategy::PerFrame: dropped_units_ += run_per_frame(units, tick, f); break;
    case Strategy::MaxStep: dropped_units_ += run_max_step(units, tick, f); break;
    case Strategy::Fixed:
    case Strategy::Threaded:
      acc_ += units;
      run_fixed(tick, f);
      break;
  }
  // count the frame; fold long epochs before their counts could overflow
  ++totals_frames_;
  if (f.dropped > 0) ++totals_frames_dropped_;
  if (frame_units_ > kFoldUnits) begin_epoch(false);
  last_ = f;
  return f;
}

FrameStats TimeStepper::single_step(TickRef tick) {
  // one nominal frame of fixed_dt, outside real time and the accumulator
  FrameStats f;
  switch (settings_.strategy) {
    case Strategy::PerFrame:
    case Strategy::MaxStep: {
      const std::int64_t units = std::llround(settings_.fixed_dt * 1e9 * static_cast<double>(den_));
      if (settings_.strategy == Strategy::PerFrame)
        run_per_frame(units, tick, f);
      else
        run_max_step(units, tick, f);
      // what the cap left out is not owed: a single step is not real time
      stepped_time_ += f.simulated;
      f.dropped = 0;
      f.stalled = false;
      break;
    }
    case Strategy::Fixed:
    case Strategy::Threaded:
      run_tick(tick, time(), settings_.fixed_dt, f);
      ++epoch_ticks_;
      f.simulated = settings_.fixed_dt;
      f.alpha = alpha();
      stepped_time_ += settings_.fixed_dt;
      break;
  }
  last_ = f;
  return f;
}

void TimeStepper::run_tick(TickRef tick, double t, double dt, FrameStats& f) {
  // time the tick on the injected clock
  const std::int64_t start = clock_->now_ns();
  tick(t, dt);
  const double wall = static_cast<double>(clock_->now_ns() - start) * 1e-9;
  timings_.add(wall);
  f.tick_wall += wall;
  f.tick_dt = dt;
  ++f.ticks;
  ++totals_ticks_;
}

std::int64_t TimeStepper::run_per_frame(std::int64_t units, TickRef tick, FrameStats& f) {
  // split the frame into n parts of q or q + 1 units (they sum to it exactly)
  if (units == 0) return 0;
  const std::int64_t n = settings_.ticks_per_frame;
  const std::int64_t q = units / n, r = units % n;
  const std::int64_t run = std::min<std::int64_t>(n, settings_.max_ticks_per_frame);
  std::int64_t done = 0;
  for (std::int64_t i = 0; i < run; ++i) {
    // the first r parts carry the extra unit; zero-length parts are skipped
    const std::int64_t part = q + (i < r ? 1 : 0);
    if (part == 0) continue;
    run_tick(tick, base_time_ + seconds(sim_units_), seconds(part), f);
    sim_units_ += part;
    done += part;
  }
  f.simulated += seconds(done);
  // parts beyond the tick cap are dropped
  if (done < units) {
    f.dropped += seconds(units - done);
    f.stalled = true;
  }
  return units - done;
}

std::int64_t TimeStepper::run_max_step(std::int64_t units, TickRef tick, FrameStats& f) {
  // fewest ticks n with frame / n <= max_dt + 1 ns (the ns is a clock's resolution, so a
  // frame of 1/60 s measured as 16666667 ns still takes 10 ticks of max_dt = 1/600 s):
  // units / den / n <= (max_num + max_den) / max_den
  if (units == 0) return 0;
  const std::int64_t slack = den_ * (max_num_ + max_den_);
  const std::int64_t n = (units * max_den_ + slack - 1) / slack;
  std::int64_t total = units, count = n;
  if (n > settings_.max_ticks_per_frame) {
    // stall guard: the cap's worth of ticks no longer than max_dt; drop the rest
    count = settings_.max_ticks_per_frame;
    total = count * std::max<std::int64_t>(1, max_num_ * den_ / max_den_);
  }
  // equal parts of q or q + 1 units that sum exactly to total (no sliver of a last tick)
  const std::int64_t q = total / count, r = total % count;
  for (std::int64_t i = 0; i < count; ++i) {
    const std::int64_t part = q + (i < r ? 1 : 0);
    run_tick(tick, base_time_ + seconds(sim_units_), seconds(part), f);
    sim_units_ += part;
  }
  f.simulated += seconds(total);
  if (total < units) {
    f.dropped += seconds(units - total);
    f.stalled = true;
  }
  return units - total;
}

void TimeStepper::run_fixed(TickRef tick, FrameStats& f) {
  // whole ticks the accumulator holds (exact integer arithmetic)
  const std::int64_t due = acc_ / tick_num_;
  const std::int64_t run = std::min<std::int64_t>(due, settings_.max_ticks_per_frame);
  for (std::int64_t i = 0; i < run; ++i) {
    run_tick(tick, base_time_ + static_cast<double>(epoch_ticks_) * settings_.fixed_dt,
             settings_.fixed_dt, f);
    ++epoch_ticks_;
    acc_ -= tick_num_;
  }
  f.simulated += static_cast<double>(run) * settings_.fixed_dt;
  // stall guard: whole ticks beyond the cap are dropped; the sub-tick remainder stays, so
  // alpha keeps moving smoothly
  if (due > run) {
    const std::int64_t drop = due - run;
    acc_ -= drop * tick_num_;
    dropped_units_ += drop * tick_num_;
    totals_dropped_ticks_ += drop;
    f.dropped_ticks = drop;
    f.dropped += seconds(drop * tick_num_);
    f.stalled = true;
  }
  f.alpha = alpha();
}

}  // namespace pba
