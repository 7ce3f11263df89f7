// Progress of long command-line work (`pba run`, `pba lab`, headless `pba_samples`):
// a live line on a terminal, a line every few seconds otherwise, nothing when quiet.
// Not physics: it lives beside the tools, in the small pba_tool_support library.
#pragma once

#include <cstdio>
#include <functional>
#include <string>

namespace pba::tools {

/// How a Progress reports.
enum class ProgressMode {
  Auto,   ///< Live when the stream is a terminal, else Lines
  Live,   ///< one line redrawn in place ("\r"), at most every 0.1 s, cleared by finish()
  Lines,  ///< a full line every `interval` seconds (logs, pipes, CI)
  Quiet,  ///< nothing
};

/// A monotonic clock in seconds (tests inject their own).
using ProgressClock = std::function<double()>;

/// Reports `done` of `total` units of work with the rate and the time left.
///
///   Progress p("pba run", "steps", n, quiet ? ProgressMode::Quiet : ProgressMode::Auto);
///   for (long long s = 1; s <= n; ++s) { step(); p.update(s); }
///   p.finish();
///
/// update() only reads the clock unless a report is due, so it may be called every step.
class Progress {
 public:
  /// `what` starts each line (e.g. "pba run"), `unit` names the work ("steps"), `total`
  /// is the amount of work (> 0; 0 or less reports without a total or time left).
  /// `interval` (s, > 0) is the Lines period; <= 0 takes PBA_PROGRESS_INTERVAL from the
  /// environment, else 5 s. Reports go to `out` (stderr by default).
  Progress(std::string what, std::string unit, long long total, ProgressMode mode = ProgressMode::Auto,
           std::FILE* out = stderr, double interval = 0, ProgressClock clock = {});
  /// Calls finish().
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// `done` units are finished (non-decreasing); reports when one is due.
  void update(long long done);
  /// Wipes a live line so other output can be printed; the next report redraws it.
  void clear();
  /// Ends the report: clears a live line (so what follows starts on a clean line).
  /// Idempotent.
  void finish();
  /// The mode in effect (Auto resolved).
  ProgressMode mode() const { return mode_; }
  /// The text of a report after `seconds` with `done` units finished, e.g.
  /// "pba run: 1200/10000 steps (12%), 4.1e+03 steps/s, 2.1 s left".
  std::string line(long long done, double seconds) const;

 private:
  std::string what_, unit_;
  long long total_;
  ProgressMode mode_;
  std::FILE* out_;
  double interval_;
  ProgressClock clock_;
  double start_ = 0, last_ = 0;
  bool drawn_ = false, finished_ = false;
};

/// "3.2 s", "4 min 05 s", "2 h 03 min": a duration for people.
std::string format_duration(double seconds);

}  // namespace pba::tools
