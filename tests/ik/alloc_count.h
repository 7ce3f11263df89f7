// A heap-allocation counter for the IK tests and benchmark: alloc_count.cpp replaces the
// global operator new (in its own translation unit, so no inlined pairing of the
// replacement with library code confuses the compiler's new/delete checks).
#pragma once

#include <atomic>

namespace pba::ik::alloc_counter {
/// Number of calls to the global operator new (and new[]) since program start.
extern std::atomic<long long> g_allocs;
}  // namespace pba::ik::alloc_counter
