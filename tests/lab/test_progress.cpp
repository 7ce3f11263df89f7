// The progress reporter of the command-line tools (tools/support/progress.h): lines at
// the promised period with done, rate and time left; a live line redrawn in place and
// wiped at the end; nothing when quiet. A fake clock makes every time exact.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "progress.h"

namespace {

using pba::tools::Progress;
using pba::tools::ProgressMode;

// everything written to a temporary file
std::string contents(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string s;
  for (int c; (c = std::fgetc(f)) != EOF;) s += static_cast<char>(c);
  return s;
}

int count(const std::string& s, const std::string& what) {
  int n = 0;
  for (auto at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
  return n;
}

TEST(Progress, LinesEveryIntervalWithRateAndTimeLeft) {
  // 1000 steps at 100 steps per fake second over 10 s, a line every 3 s: due at
  // t = 3, 6, 9 (steps 300, 600, 900), rate 100/s, left (1000 - done) / 100 s
  std::FILE* f = std::tmpfile();
  double now = 0;
  {
    Progress p("pba run", "steps", 1000, ProgressMode::Lines, f, 3.0, [&] { return now; });
    for (int s = 1; s <= 1000; ++s) {
      now = s / 100.0;
      p.update(s);
    }
  }
  const std::string out = contents(f);
  std::fclose(f);
  EXPECT_EQ(count(out, "\n"), 3) << out;
  EXPECT_NE(out.find("pba run: 300/1000 steps (30%), 100 steps/s, 7.0 s left\n"), std::string::npos) << out;
  EXPECT_NE(out.find("pba run: 600/1000 steps (60%), 100 steps/s, 4.0 s left\n"), std::string::npos) << out;
  EXPECT_NE(out.find("pba run: 900/1000 steps (90%), 100 steps/s, 1.0 s left\n"), std::string::npos) << out;
  EXPECT_EQ(out.find('\r'), std::string::npos) << "no carriage returns in a log";
}

TEST(Progress, LiveLineRedrawnInPlaceAndWiped) {
  // 2 fake seconds, updates every 0.01 s: a redraw at most every 0.1 s (about 20), each
  // starting with a carriage return and ending with erase-to-end-of-line; finish wipes it
  std::FILE* f = std::tmpfile();
  double now = 0;
  Progress p("pba lab", "measurements", 200, ProgressMode::Live, f, 0, [&] { return now; });
  for (int s = 1; s <= 200; ++s) {
    now = s * 0.01;
    p.update(s);
  }
  p.finish();
  p.finish();  // idempotent
  const std::string out = contents(f);
  std::fclose(f);
  const int draws = count(out, "\033[K");
  EXPECT_GE(draws, 15) << out;
  EXPECT_LE(draws, 21) << out;
  EXPECT_EQ(count(out, "\n"), 0) << "a live line never scrolls";
  EXPECT_EQ(out.rfind("\rpba lab: ", 0), 0u) << out;
  EXPECT_NE(out.find(" measurements/s, "), std::string::npos) << out;
  EXPECT_EQ(p.line(100, 1.0), "pba lab: 100/200 measurements (50%), 100 measurements/s, 1.0 s left");
  EXPECT_EQ(out.substr(out.size() - 4), "\r\033[K") << "finish wipes the line";
}

TEST(Progress, QuietWritesNothing) {
  std::FILE* f = std::tmpfile();
  double now = 0;
  {
    Progress p("pba run", "steps", 100, ProgressMode::Quiet, f, 0.001, [&] { return now; });
    for (int s = 1; s <= 100; ++s) now = s, p.update(s);
  }
  EXPECT_EQ(contents(f), "");
  std::fclose(f);
}

TEST(Progress, AutoIsLinesWhenNotATerminal) {
  // a temporary file is no terminal
  std::FILE* f = std::tmpfile();
  Progress p("x", "steps", 1, ProgressMode::Auto, f);
  EXPECT_EQ(p.mode(), ProgressMode::Lines);
  std::fclose(f);
}

TEST(Progress, DurationsForPeople) {
  EXPECT_EQ(pba::tools::format_duration(3.21), "3.2 s");
  EXPECT_EQ(pba::tools::format_duration(245), "4 min 05 s");
  EXPECT_EQ(pba::tools::format_duration(7380), "2 h 03 min");
}

}  // namespace
