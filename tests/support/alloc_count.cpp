// Replaces the global operator new/delete with counting versions (see alloc_count.h).
#include "alloc_count.h"

#include <malloc.h>

#include <cstdlib>
#include <new>

namespace pba::test_support {
std::atomic<long long> g_allocations{0};
std::atomic<long long> g_live_bytes{0};
}

void* operator new(std::size_t n) {
  pba::test_support::g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) {
    pba::test_support::g_live_bytes.fetch_add(static_cast<long long>(malloc_usable_size(p)), std::memory_order_relaxed);
    return p;
  }
  throw std::bad_alloc();
}
namespace {
void release(void* p) noexcept {
  if (p) pba::test_support::g_live_bytes.fetch_sub(static_cast<long long>(malloc_usable_size(p)), std::memory_order_relaxed);
  std::free(p);
}
}  // namespace
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { release(p); }
void operator delete[](void* p) noexcept { release(p); }
void operator delete(void* p, std::size_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t) noexcept { release(p); }
