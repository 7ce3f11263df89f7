// Private to the library: the lane arithmetic shared by the rigid contact kernels
// (rigid/contact_wide.cpp), the rigid free motion (rigid/integrate_wide.cpp), the batched
// box-box narrow phase (collide/sat_box.cpp), the mesh contacts' and a box's corners on a plane
// (collide/mesh_contact.cpp, collide/manifold.cpp) and the reuse test (rigid/contact_pairs.cpp).
// One template over the lane type runs every SIMD path: a double (scalar), 4 doubles (AVX2) or
// 8 (AVX-512), as GCC vector extensions (the contact kernels' lanes of floats too); each
// lane does the same operations in the same order on every path, so all give the same bits.
// Include it only in files whose wide functions are compiled with per-function targets.
#pragma once

#include <cmath>
#include <cstring>
#include <type_traits>

// PBA_AVX512: 1 where the AVX-512 kernels are compiled (GCC on x86-64), 0 where the build
// leaves them out (CMake's PBA_AVX512=OFF, which the sanitizer presets set: the CI's hosts have
// no AVX-512, so those builds never ran them, and they were the longest compile of the CI).
// Without them best_simd_path() and the batched narrow phase never pick AVX-512: the
// requests fall back to AVX2 or the scalar path as on a CPU without it.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(PBA_NO_AVX512)
#define PBA_AVX512 1
#else
#define PBA_AVX512 0
#endif

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

/// x in every lane (as 0 + x: -0.0 comes out +0, so a sign mask is not made with it).
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

/// The change r - v of v turned by the unit quaternion (qx, qy, qz, qw), lane by lane in glm's
/// operations and order: ((u x v) w + u x (u x v)) 2, u = (qx, qy, qz) (quat_turn adds v to
/// it). Any lane type (GCC vectors of 2, 4, 8 or 16 doubles or floats, __m256d, a double or a
/// float).
template <class V>
PBA_LANES void quat_turn_change(V qx, V qy, V qz, V qw, V vx, V vy, V vz, V& cx, V& cy, V& cz) {
  const V uvx = qy * vz - vy * qz, uvy = qz * vx - vz * qx, uvz = qx * vy - vx * qy;
  const V uuvx = qy * uvz - uvy * qz, uuvy = qz * uvx - uvz * qx, uuvz = qx * uvy - uvx * qy;
  const V two = V{} + 2;  // (2 exactly, in lanes of doubles or floats)
  cx = ((uvx * qw) + uuvx) * two, cy = ((uvy * qw) + uuvy) * two, cz = ((uvz * qw) + uuvz) * two;
}

/// r = v turned by the unit quaternion (qx, qy, qz, qw), lane by lane in glm's operations and
/// order (v + ((u x v) w + u x (u x v)) 2, u = (qx, qy, qz)): the bits of glm's q * v on every
/// path. Any lane type (as quat_turn_change).
template <class V>
PBA_LANES void quat_turn(V qx, V qy, V qz, V qw, V vx, V vy, V vz, V& rx, V& ry, V& rz) {
  V cx, cy, cz;
  quat_turn_change(qx, qy, qz, qw, vx, vy, vz, cx, cy, cz);
  rx = vx + cx, ry = vy + cy, rz = vz + cz;
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

/// The transpose of 8 rows of 8 numbers, doubles or floats (its own inverse): three rounds of
/// two-vector shuffles. Rows of 64 bytes (a body's velocities, its motion) become one vector a
/// field.
template <class V>
PBA_LANES void transpose8x8(V r[8]) {
  using M = decltype(r[0] < r[0]);  // the shuffles' mask: integers of the numbers' width
  V t[8], u[8];
  for (int i = 0; i < 4; ++i) {
    t[2 * i] = __builtin_shuffle(r[2 * i], r[2 * i + 1], M{0, 8, 2, 10, 4, 12, 6, 14});
    t[2 * i + 1] = __builtin_shuffle(r[2 * i], r[2 * i + 1], M{1, 9, 3, 11, 5, 13, 7, 15});
  }
  constexpr int kFirst[4] = {0, 1, 4, 5};
  for (const int i : kFirst) {
    u[i] = __builtin_shuffle(t[i], t[i + 2], M{0, 1, 8, 9, 4, 5, 12, 13});
    u[i + 2] = __builtin_shuffle(t[i], t[i + 2], M{2, 3, 10, 11, 6, 7, 14, 15});
  }
  for (int i = 0; i < 4; ++i) {
    r[i] = __builtin_shuffle(u[i], u[i + 4], M{0, 1, 2, 3, 8, 9, 10, 11});
    r[i + 4] = __builtin_shuffle(u[i], u[i + 4], M{4, 5, 6, 7, 12, 13, 14, 15});
  }
}

}  // namespace pba::detail::lanes
