// Private to the library: the lane arithmetic shared by the rigid contact kernels
// (rigid/contact_wide.cpp), the rigid free motion (rigid/integrate_wide.cpp) and the batched
// box-box narrow phase (collide/sat_box.cpp). One template over the lane type runs every SIMD
// path: a double (scalar), 4 doubles (AVX2) or 8 (AVX-512), as GCC vector extensions; each
// lane does the same operations in the same order on every path, so all give the same bits.
// Include it only in files whose wide functions are compiled with per-function targets.
#pragma once

#include <cmath>
#include <cstring>
#include <type_traits>

// vector arguments of inline helpers: the ABI note does not apply (everything is inlined)
#pragma GCC diagnostic ignored "-Wpsabi"
// GCC 12 takes the lane-by-lane gathers into zeroed vectors for uses of uninitialised ones
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace pba::detail::lanes {

typedef double v4d __attribute__((vector_size(32)));
typedef double v8d __attribute__((vector_size(64)));
typedef long v4l __attribute__((vector_size(32)));
typedef long v8l __attribute__((vector_size(64)));

/// Doubles in a lane type.
template <class V>
constexpr int kWidth = sizeof(V) / sizeof(double);

#define PBA_LANES [[gnu::always_inline]] inline

/// x in every lane.
template <class V>
PBA_LANES V splat(double x) {
  if constexpr (std::is_same_v<V, double>) return x;
  else return V{} + x;
}

/// kWidth<V> consecutive doubles from p (unaligned).
template <class V>
PBA_LANES V load(const double* p) {
  if constexpr (std::is_same_v<V, double>) {
    return *p;
  } else {
    V v;
    std::memcpy(&v, p, sizeof v);
    return v;
  }
}

/// ... and back.
template <class V>
PBA_LANES void store(double* p, const V& v) {
  if constexpr (std::is_same_v<V, double>) *p = v;
  else std::memcpy(p, &v, sizeof v);
}

/// std::max's and std::min's comparisons, lane by lane (a plain number too; any element type).
template <class V>
PBA_LANES V vmax(V a, V b) {
  return a < b ? b : a;
}
template <class V>
PBA_LANES V vmin(V a, V b) {
  return b < a ? b : a;
}

/// The square root of each lane, correctly rounded (the same bits as std::sqrt; with
/// -fno-math-errno the compiler makes it one vector instruction).
template <class V>
PBA_LANES V vsqrt(V x) {
  if constexpr (std::is_arithmetic_v<V>) {
    return std::sqrt(x);
  } else {
    V r = x;
    for (int i = 0; i < static_cast<int>(sizeof(V) / sizeof(x[0])); ++i) r[i] = std::sqrt(x[i]);
    return r;
  }
}

/// Lane i.
template <class V>
PBA_LANES double get(const V& v, int i) {
  if constexpr (std::is_same_v<V, double>) return (void)i, v;
  else return v[i];
}

/// Sets lane i.
template <class V>
PBA_LANES void set(V& v, int i, double x) {
  if constexpr (std::is_same_v<V, double>) (void)i, v = x;
  else v[i] = x;
}

}  // namespace pba::detail::lanes
