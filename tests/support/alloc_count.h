// A heap-allocation counter for the zero-allocation tests and benchmarks. alloc_count.cpp
// replaces the global operator new and delete with counting versions; link it (the
// pba_alloc_count object library) into an executable and read g_allocations around the
// code under test. It lives in its own translation unit so that no inlined pairing of the
// replacement with library code confuses the compiler's new/delete checks.
#pragma once

#include <atomic>

namespace pba::test_support {
/// Number of calls to the global operator new (and new[]) since program start.
extern std::atomic<long long> g_allocations;
/// Bytes the blocks from the global operator new hold now (each block's malloc_usable_size,
/// added at new and taken off at delete): a heap measure that does not read the C heap's own
/// statistics, which a sanitizer's allocator leaves at 0.
extern std::atomic<long long> g_live_bytes;
}  // namespace pba::test_support
