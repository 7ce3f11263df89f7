// This thread's CPU time, for tests that bound how long a budgeted solve works: unlike the
// wall clock, it does not count the time a loaded machine keeps the test waiting.
#pragma once

#include <time.h>

namespace pba::test {

/// This thread's CPU time in seconds since an arbitrary origin (POSIX
/// CLOCK_THREAD_CPUTIME_ID); differences of two calls are what mean something.
inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace pba::test
