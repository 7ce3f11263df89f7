// Progress lines for the command-line tools (see progress.h).
#include "progress.h"

#include <chrono>
#include <cmath>
#include <cstdlib>

#include <unistd.h>

namespace pba::tools {

namespace {

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// the Lines period: the argument, else PBA_PROGRESS_INTERVAL, else 5 s
double lines_interval(double asked) {
  if (asked > 0) return asked;
  if (const char* env = std::getenv("PBA_PROGRESS_INTERVAL")) {
    char* end = nullptr;
    const double v = std::strtod(env, &end);
    if (end != env && *end == '\0' && std::isfinite(v) && v > 0) return v;
  }
  return 5.0;
}

}  // namespace

std::string format_duration(double seconds) {
  char buf[64];
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  if (seconds < 60) {
    std::snprintf(buf, sizeof buf, "%.1f s", seconds);
  } else if (seconds < 3600) {
    const long long s = std::llround(seconds);
    std::snprintf(buf, sizeof buf, "%lld min %02lld s", s / 60, s % 60);
  } else {
    const long long m = std::llround(seconds / 60);
    std::snprintf(buf, sizeof buf, "%lld h %02lld min", m / 60, m % 60);
  }
  return buf;
}

Progress::Progress(std::string what, std::string unit, long long total, ProgressMode mode, std::FILE* out,
                   double interval, ProgressClock clock)
    : what_(std::move(what)),
      unit_(std::move(unit)),
      total_(total),
      mode_(mode),
      out_(out),
      interval_(lines_interval(interval)),
      clock_(clock ? std::move(clock) : ProgressClock(steady_seconds)) {
  // auto: live on a terminal, lines elsewhere
  if (mode_ == ProgressMode::Auto) mode_ = ::isatty(::fileno(out_)) ? ProgressMode::Live : ProgressMode::Lines;
  start_ = last_ = clock_();
}

Progress::~Progress() { finish(); }

std::string Progress::line(long long done, double seconds) const {
  // done (of total, percent), rate, time left
  char buf[256];
  const double rate = seconds > 0 ? static_cast<double>(done) / seconds : 0;
  std::string s = what_ + ": ";
  if (total_ > 0) {
    std::snprintf(buf, sizeof buf, "%lld/%lld %s (%.0f%%)", done, total_, unit_.c_str(),
                  100.0 * static_cast<double>(done) / static_cast<double>(total_));
  } else {
    std::snprintf(buf, sizeof buf, "%lld %s", done, unit_.c_str());
  }
  s += buf;
  if (rate > 0) {
    std::snprintf(buf, sizeof buf, ", %.3g %s/s", rate, unit_.c_str());
    s += buf;
    if (total_ > 0) s += ", " + format_duration(static_cast<double>(total_ - done) / rate) + " left";
  }
  return s;
}

void Progress::update(long long done) {
  if (mode_ == ProgressMode::Quiet || finished_) return;
  // a report is due every 0.1 s live, every interval_ as lines
  const double now = clock_();
  const double period = mode_ == ProgressMode::Live ? 0.1 : interval_;
  if (now - last_ < period) return;
  last_ = now;
  const std::string text = line(done, now - start_);
  if (mode_ == ProgressMode::Live) {
    std::fprintf(out_, "\r%s\033[K", text.c_str());
    drawn_ = true;
  } else {
    std::fprintf(out_, "%s\n", text.c_str());
  }
  std::fflush(out_);
}

void Progress::clear() {
  if (!drawn_) return;
  drawn_ = false;
  std::fputs("\r\033[K", out_);
  std::fflush(out_);
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  // a live line is wiped so the summary starts at the left margin
  clear();
}

}  // namespace pba::tools
