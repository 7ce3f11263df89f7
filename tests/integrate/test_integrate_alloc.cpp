// Zero allocations per step: every method, after warm-up, steps without touching the
// heap. This executable replaces the global operator new with a counting one, so it is
// kept apart from the other integrator tests.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

#include "pba/integrate.h"

#include "alloc_count.h"  // counts every operator new in this program

using pba::test_support::g_allocations;

namespace {

struct SpringDrag {
  template <class V>
  void operator()(double, std::span<const V> x, std::span<const V> v, std::span<V> a) const {
    using S = typename V::value_type;
    for (std::size_t i = 0; i < x.size(); ++i) a[i] = x[i] * S(-20) - v[i] * S(0.3);
  }
};

template <class V, class Accel>
long long allocations_in_steady_state(pba::Method m, std::size_t n, Accel accel) {
  pba::Integrator<V> integ(m);
  std::vector<V> x(n, V(1)), v(n, V(0.5));
  // warm-up: scratch arrays (and the dense solver for implicit Euler) are sized here
  for (int k = 0; k < 3; ++k) integ.step(k * 0.01, 0.01, std::span<V>(x), std::span<V>(v), accel);
  const long long before = g_allocations.load();
  for (int k = 3; k < 200; ++k) integ.step(k * 0.01, 0.01, std::span<V>(x), std::span<V>(v), accel);
  return g_allocations.load() - before;
}

TEST(Allocation, CounterSeesAllocations) {
  // the counter works: a direct call of the global operator new, kept alive through a
  // volatile pointer (new-expressions may be elided since C++14, so they are no probe)
  const long long before = g_allocations.load();
  void* volatile p = ::operator new(64);
  ::operator delete(p);
  EXPECT_EQ(g_allocations.load() - before, 1);
}

TEST(Allocation, NoAllocationPerStepForEveryMethod) {
  for (pba::Method m : pba::kAllMethods) {
    SCOPED_TRACE(std::string(pba::name(m)));
    EXPECT_EQ((allocations_in_steady_state<pba::Vec3>(m, 16, SpringDrag{})), 0);
    EXPECT_EQ((allocations_in_steady_state<pba::Vec3f>(m, 16, SpringDrag{})), 0);
    EXPECT_EQ((allocations_in_steady_state<pba::Vec2>(m, 16, SpringDrag{})), 0);
    // a type-erased accel: calling a std::function does not allocate either
    EXPECT_EQ((allocations_in_steady_state<pba::Vec3>(m, 16, pba::AccelFn<pba::Vec3>(SpringDrag{}))), 0);
    auto scalar = [](double, std::span<const double> x, std::span<const double> v, std::span<double> a) {
      for (std::size_t i = 0; i < x.size(); ++i) a[i] = -20 * x[i] - 0.3 * v[i];
    };
    EXPECT_EQ((allocations_in_steady_state<double>(m, 16, scalar)), 0);
  }
}

TEST(Allocation, StepOneDoesNotAllocate) {
  for (pba::Method m : pba::kAllMethods) {
    pba::Integrator<pba::Vec3> integ(m);
    pba::Vec3 x(1, 0, 0), v(0, 1, 0);
    auto f = [](double, const pba::Vec3& x, const pba::Vec3&) { return -x; };
    integ.step_one(0, 0.01, x, v, f);
    const long long before = g_allocations.load();
    for (int k = 1; k < 100; ++k) integ.step_one(k * 0.01, 0.01, x, v, f);
    EXPECT_EQ(g_allocations.load() - before, 0) << pba::name(m);
  }
}

}  // namespace
