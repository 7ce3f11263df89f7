// Replaces the global operator new/delete with counting versions (see alloc_count.h).
#include "alloc_count.h"

#include <cstdlib>
#include <new>

namespace pba::test_support {
std::atomic<long long> g_allocations{0};
}

void* operator new(std::size_t n) {
  pba::test_support::g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
