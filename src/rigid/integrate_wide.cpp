// Rigid bodies: free motion of the awake dynamic bodies, several bodies at a time (the same
// template over the lane type as the contact kernels, contact_wide.cpp: double, 4 or 8
// doubles; every lane does the same arithmetic on every path).
//
// Velocities: gravity, applied force and torque, then implicit damping, then the contacts'
// warm start. Rotation: the symmetric splitting of Dullweber, Leimkuhler and McLachlan (1997,
// J. Chem. Phys. 107, eq. 3.7): the kinetic energy is a sum of three terms pi_k^2 / (2 I_k),
// each of whose flows is an exact rotation about principal axis k; composed as 1/2 1/2 1 1/2
// 1/2 (axes x, y, z, y, x) it is symmetric, so second order, and every sub-flow keeps the world
// angular momentum exactly. Each sub-flow turns the body by `angle` about axis k (the
// quaternion by the half angle) and its body-frame momentum by -angle: one sine and cosine of
// the half angle give both (cos = 1 - 2 sin^2(angle/2), sin = 2 sin(angle/2) cos(angle/2)),
// by a polynomial for half angles within pi/8 (Taylor to degree 13 and 14, truncation under
// 1e-18 relative; more than 375 rad/s at a 480 Hz substep is needed to leave it), else by
// the library. Bodies with equal principal moments (the caller lists them apart by kind,
// FreeRotation) have an exact free rotation, which they take instead: round ones (three equal)
// one turn about their constant world angular velocity (positions_round), axisymmetric ones
// (two equal) a turn about their momentum and one about their axis (positions).
//
// Cost (fall1000, all cubes, spent a sixth of its step here under the splitting, half that
// with the exact turn): 8 bodies in a row, the common case, load and store their fields as
// whole vectors and a few permutes, and the 64-byte rows of velocities, warm-start changes and
// motion by whole rows and a transpose on AVX-512 (on AVX2 half rows of four and two 4x4
// transposes); the all-lanes tests use the targets'
// compare-to-mask instructions; on AVX-512 the positions run two blocks of 8 at once, as the
// splitting's five sub-flows are one long chain of dependent operations per block, and on AVX2
// two of 4 (v4x2), the round bodies' too; on AVX2 each block of 8 asks for the lines of the
// block two on (prefetch_block: the lanes and rows are past the L2 in the rain).
//
// The soft step's and TGS's substeps read and write the bodies' own fields in the free motion's lanes
// (solver.h, FreeLine): copied once a step into blocks of 8 of each kind's list (gather), what
// stays the same over the substeps formed there once, the centres and frames put back after
// the last substep (scatter). The rain's boxes and balls alternate, so each kind's list steps
// by 2 and every block's fields went lane by lane, eight substeps a step; in lanes they are
// whole vectors (docs/benchmarks.md, "The free motion in lanes"). Only where the numbers live
// changes: the same bits.
#include "solver.h"

#include <bit>
#include <cassert>
#include <cmath>
#include <limits>

#include <immintrin.h>

#include "core/lanes.h"

namespace pba::detail {

namespace {

using namespace lanes;

// the half angles beyond which the library computes the sine and cosine (rad)
constexpr double kSmall = 0.39269908169872414;  // pi / 8

// two blocks of 8 at once: two independent chains the core interleaves (the sub-flows are
// sequential, so one block alone waits on its own latencies)
typedef double v16d __attribute__((vector_size(128)));

// Two AVX2 blocks of 4 at once (lanes 0-3 in lo, 4-7 in hi), as AVX-512's v16d is two of 8:
// every operation is the same one on both halves, so each lane's arithmetic and order are
// v4d's. The triaxial splitting's five sub-flows are one chain of dependent multiplies and
// adds per block (the sines' and cosines' series on each), and a round body's turn one nearly
// as long for its fewer instructions; too long for the core to reach the next block's loads
// and chain while one block's waits. Two independent chains side by side fill those latencies
// (with 16 ymm registers the pair spills more, which costs less: docs/benchmarks.md, "The free
// motion on AVX2, again").
struct v4x2 {
  v4d lo, hi;
  // lane i (GCC's vectors alias their element type)
  PBA_LANES double& operator[](int i) { return reinterpret_cast<double*>(this)[i]; }
  PBA_LANES double operator[](int i) const { return reinterpret_cast<const double*>(this)[i]; }
};
static_assert(sizeof(v4x2) == 8 * sizeof(double));
PBA_LANES v4x2 operator+(const v4x2& a, const v4x2& b) { return {a.lo + b.lo, a.hi + b.hi}; }
PBA_LANES v4x2 operator-(const v4x2& a, const v4x2& b) { return {a.lo - b.lo, a.hi - b.hi}; }
PBA_LANES v4x2 operator*(const v4x2& a, const v4x2& b) { return {a.lo * b.lo, a.hi * b.hi}; }
PBA_LANES v4x2 operator/(const v4x2& a, const v4x2& b) { return {a.lo / b.lo, a.hi / b.hi}; }
PBA_LANES v4x2 operator-(const v4x2& a) { return {-a.lo, -a.hi}; }
PBA_LANES v4x2 operator+(const v4x2& a, double b) { return {a.lo + b, a.hi + b}; }
PBA_LANES v4x2 operator+(double a, const v4x2& b) { return {a + b.lo, a + b.hi}; }
PBA_LANES v4x2 operator-(double a, const v4x2& b) { return {a - b.lo, a - b.hi}; }
PBA_LANES v4x2 operator*(const v4x2& a, double b) { return {a.lo * b, a.hi * b}; }
PBA_LANES v4x2 operator*(double a, const v4x2& b) { return {a * b.lo, a * b.hi}; }
PBA_LANES v4x2 operator/(double a, const v4x2& b) { return {a / b.lo, a / b.hi}; }

// the lane types of the AVX2 path
template <class V>
constexpr bool kAvx2Lanes = std::is_same_v<V, v4d> || std::is_same_v<V, v4x2>;

// Tests and square roots over all lanes, by the targets' instructions (GCC's generic vectors
// compare into a mask that plain AVX-512F turns back into a vector lane by lane). The
// AVX-512 ones are out of line: GCC does not inline a target's intrinsics into a template.

// true when every lane of x is within [-limit, limit] (false for a NaN lane)
PBA_LANES bool all_within(double x, double limit) { return std::abs(x) <= limit; }
// the square root of each lane (IEEE: correctly rounded, the same bits as std::sqrt)
PBA_LANES double sqrt_lanes(double x) { return std::sqrt(x); }
#if defined(__GNUC__) && defined(__x86_64__)
// (AVX2's by the builtins under the intrinsics, which do inline into the templates: out of
// line, their bodies alone were 7.0 M of fall1000's 908 M instructions in 120 steps)
PBA_LANES bool all_within(v4d x, double limit) {
  const v4l le = reinterpret_cast<v4l>(__builtin_ia32_cmppd256(x, splat<v4d>(limit), _CMP_LE_OQ));
  const v4l ge = reinterpret_cast<v4l>(__builtin_ia32_cmppd256(x, splat<v4d>(-limit), _CMP_GE_OQ));
  return __builtin_ia32_movmskpd256(reinterpret_cast<v4d>(le & ge)) == 0xf;
}
PBA_LANES v4d sqrt_lanes(v4d x) { return __builtin_ia32_sqrtpd256(x); }
PBA_LANES bool all_within(const v4x2& x, double limit) {
  const v4d hi = splat<v4d>(limit), lo = splat<v4d>(-limit);
  const v4l in_lo = reinterpret_cast<v4l>(__builtin_ia32_cmppd256(x.lo, hi, _CMP_LE_OQ)) &
                    reinterpret_cast<v4l>(__builtin_ia32_cmppd256(x.lo, lo, _CMP_GE_OQ));
  const v4l in_hi = reinterpret_cast<v4l>(__builtin_ia32_cmppd256(x.hi, hi, _CMP_LE_OQ)) &
                    reinterpret_cast<v4l>(__builtin_ia32_cmppd256(x.hi, lo, _CMP_GE_OQ));
  return __builtin_ia32_movmskpd256(reinterpret_cast<v4d>(in_lo & in_hi)) == 0xf;
}
PBA_LANES v4x2 sqrt_lanes(const v4x2& x) { return {__builtin_ia32_sqrtpd256(x.lo), __builtin_ia32_sqrtpd256(x.hi)}; }
#endif
#if PBA_AVX512
[[gnu::target("avx512f")]] [[gnu::noinline]] bool all_within(v8d x, double limit) {
  return (_mm512_cmp_pd_mask(x, _mm512_set1_pd(limit), _CMP_LE_OQ) &
          _mm512_cmp_pd_mask(x, _mm512_set1_pd(-limit), _CMP_GE_OQ)) == 0xff;
}
[[gnu::target("avx512f")]] [[gnu::noinline]] v8d sqrt_lanes(v8d x) { return _mm512_mask_sqrt_pd(x, 0xff, x); }
[[gnu::target("avx512f")]] PBA_LANES void halves(const v16d x, v8d h[2]) { std::memcpy(h, &x, sizeof x); }
[[gnu::target("avx512f")]] [[gnu::noinline]] bool all_within(v16d x, double limit) {
  v8d h[2];
  halves(x, h);
  const __m512d hi = _mm512_set1_pd(limit), lo = _mm512_set1_pd(-limit);
  return (_mm512_cmp_pd_mask(h[0], hi, _CMP_LE_OQ) & _mm512_cmp_pd_mask(h[0], lo, _CMP_GE_OQ) &
          _mm512_cmp_pd_mask(h[1], hi, _CMP_LE_OQ) & _mm512_cmp_pd_mask(h[1], lo, _CMP_GE_OQ)) == 0xff;
}
[[gnu::target("avx512f")]] [[gnu::noinline]] v16d sqrt_lanes(v16d x) {
  v8d h[2];
  halves(x, h);
  h[0] = _mm512_mask_sqrt_pd(h[0], 0xff, h[0]), h[1] = _mm512_mask_sqrt_pd(h[1], 0xff, h[1]);
  std::memcpy(&x, h, sizeof x);
  return x;
}
#endif

// The Taylor series' tails for |x| <= kSmall, in x2 = x^2 (Horner): sin x = x + x sin_tail(x2),
// cos x = 1 + cos_tail(x2)
template <class V>
PBA_LANES V sin_tail(const V x2) {
  constexpr double s1 = -1.0 / 6, s2 = 1.0 / 120, s3 = -1.0 / 5040, s4 = 1.0 / 362880, s5 = -1.0 / 39916800,
                   s6 = 1.0 / 6227020800.0;
  return x2 * (s1 + x2 * (s2 + x2 * (s3 + x2 * (s4 + x2 * (s5 + x2 * s6)))));
}
template <class V>
PBA_LANES V cos_tail(const V x2) {
  constexpr double c1 = -1.0 / 2, c2 = 1.0 / 24, c3 = -1.0 / 720, c4 = 1.0 / 40320, c5 = -1.0 / 3628800,
                   c6 = 1.0 / 479001600, c7 = -1.0 / 87178291200.0;
  return x2 * (c1 + x2 * (c2 + x2 * (c3 + x2 * (c4 + x2 * (c5 + x2 * (c6 + x2 * c7))))));
}

// sin and cos of x for |x| <= kSmall
template <class V>
PBA_LANES void sincos_small(const V x, V& s, V& c) {
  const V x2 = x * x;
  s = x + x * sin_tail(x2);
  c = 1.0 + cos_tail(x2);
}

// sin and cos of the half angle h, each lane by the polynomial or, beyond kSmall, the library
template <class V>
PBA_LANES void sincos_half(const V h, V& s, V& c) {
  sincos_small(h, s, c);
  if (all_within(h, kSmall)) return;  // one test for all lanes: the steady case
  for (int i = 0; i < kWidth<V>; ++i) {
    const double x = get(h, i);
    if (!(std::abs(x) <= kSmall)) set(s, i, std::sin(x)), set(c, i, std::cos(x));
  }
}

// q v q^-1 (glm's formula: v + 2 (w (u x v) + u x (u x v))); `sign` -1 turns by q^-1
template <class V>
PBA_LANES void rotate(const V q[4], double sign, const V v[3], V out[3]) {
  const V u[3] = {sign * q[1], sign * q[2], sign * q[3]};
  const V uv[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const V uuv[3] = {u[1] * uv[2] - u[2] * uv[1], u[2] * uv[0] - u[0] * uv[2], u[0] * uv[1] - u[1] * uv[0]};
  for (int i = 0; i < 3; ++i) out[i] = v[i] + (uv[i] * q[0] + uuv[i]) * 2.0;
}

// Loads of 8 bodies in a row (the awake bodies mostly are: `moving` is in index order): whole
// vectors and a few two-vector permutes instead of a lane at a time. idx ascends, so the 8 are
// consecutive when the last is 7 past the first.
PBA_LANES bool in_a_row(const std::uint32_t* idx) { return idx[7] == idx[0] + 7; }

// the transpose of 4 rows of 4 doubles (its own inverse): two rounds of two-vector shuffles
PBA_LANES void transpose4x4(v4d r[4]) {
  const v4d t0 = __builtin_shuffle(r[0], r[1], v4l{0, 4, 2, 6}), t1 = __builtin_shuffle(r[0], r[1], v4l{1, 5, 3, 7});
  const v4d t2 = __builtin_shuffle(r[2], r[3], v4l{0, 4, 2, 6}), t3 = __builtin_shuffle(r[2], r[3], v4l{1, 5, 3, 7});
  r[0] = __builtin_shuffle(t0, t2, v4l{0, 1, 4, 5}), r[2] = __builtin_shuffle(t0, t2, v4l{2, 3, 6, 7});
  r[1] = __builtin_shuffle(t1, t3, v4l{0, 1, 4, 5}), r[3] = __builtin_shuffle(t1, t3, v4l{2, 3, 6, 7});
}

// x, y, z of 8 consecutive Vec3 (24 doubles from p)
PBA_LANES void rows3(const double* p, v8d out[3]) {
  const v8d a = load<v8d>(p), b = load<v8d>(p + 8), c = load<v8d>(p + 16);
  out[0] = __builtin_shuffle(__builtin_shuffle(a, b, v8l{0, 3, 6, 9, 12, 15, 0, 0}), c, v8l{0, 1, 2, 3, 4, 5, 10, 13});
  out[1] = __builtin_shuffle(__builtin_shuffle(a, b, v8l{1, 4, 7, 10, 13, 0, 0, 0}), c, v8l{0, 1, 2, 3, 4, 8, 11, 14});
  out[2] = __builtin_shuffle(__builtin_shuffle(a, b, v8l{2, 5, 8, 11, 14, 0, 0, 0}), c, v8l{0, 1, 2, 3, 4, 9, 12, 15});
}

// the components at memory offsets m[0..3] of 8 consecutive 4-double records (32 doubles from p)
PBA_LANES void rows4(const double* p, const int m[4], v8d out[4]) {
  const v8d a = load<v8d>(p), b = load<v8d>(p + 8), c = load<v8d>(p + 16), d = load<v8d>(p + 24);
  for (int k = 0; k < 4; ++k) {
    const long j = m[k];
    const v8l pick{j, j + 4, j + 8, j + 12, 0, 0, 0, 0};
    out[k] =
        __builtin_shuffle(__builtin_shuffle(a, b, pick), __builtin_shuffle(c, d, pick), v8l{0, 1, 2, 3, 8, 9, 10, 11});
  }
}

// where glm keeps a quaternion's w, x, y, z (x, y, z, w unless told otherwise), in doubles
static_assert(sizeof(Quat) == 4 * sizeof(double));
#ifdef GLM_FORCE_QUAT_DATA_WXYZ
constexpr int kQuatAt[4] = {0, 1, 2, 3};
#else
constexpr int kQuatAt[4] = {3, 0, 1, 2};
#endif

// ... and back: 8 consecutive Vec3 from their x, y, z
PBA_LANES void unrows3(double* p, const v8d in[3]) {
  const v8d &x = in[0], &y = in[1], &z = in[2];
  store<v8d>(p,
             __builtin_shuffle(__builtin_shuffle(x, y, v8l{0, 8, 0, 1, 9, 0, 2, 10}), z, v8l{0, 1, 8, 3, 4, 9, 6, 7}));
  store<v8d>(p + 8, __builtin_shuffle(__builtin_shuffle(x, y, v8l{0, 3, 11, 0, 4, 12, 0, 5}), z,
                                      v8l{10, 1, 2, 11, 4, 5, 12, 7}));
  store<v8d>(p + 16, __builtin_shuffle(__builtin_shuffle(x, y, v8l{13, 0, 6, 14, 0, 7, 15, 0}), z,
                                       v8l{0, 13, 2, 3, 14, 5, 6, 15}));
}

// 8 consecutive 4-double records whose memory offset m[k] holds in[k]
PBA_LANES void unrows4(double* p, const int m[4], const v8d in[4]) {
  v8d at[4];
  for (int k = 0; k < 4; ++k) at[m[k]] = in[k];
  const v8d lo01 = __builtin_shuffle(at[0], at[1], v8l{0, 8, 1, 9, 2, 10, 3, 11});
  const v8d lo23 = __builtin_shuffle(at[2], at[3], v8l{0, 8, 1, 9, 2, 10, 3, 11});
  const v8d hi01 = __builtin_shuffle(at[0], at[1], v8l{4, 12, 5, 13, 6, 14, 7, 15});
  const v8d hi23 = __builtin_shuffle(at[2], at[3], v8l{4, 12, 5, 13, 6, 14, 7, 15});
  store<v8d>(p, __builtin_shuffle(lo01, lo23, v8l{0, 1, 8, 9, 2, 3, 10, 11}));
  store<v8d>(p + 8, __builtin_shuffle(lo01, lo23, v8l{4, 5, 12, 13, 6, 7, 14, 15}));
  store<v8d>(p + 16, __builtin_shuffle(hi01, hi23, v8l{0, 1, 8, 9, 2, 3, 10, 11}));
  store<v8d>(p + 24, __builtin_shuffle(hi01, hi23, v8l{4, 5, 12, 13, 6, 7, 14, 15}));
}

// a wide store as two blocks of 8
template <class Store>
PBA_LANES void store_twice(const std::uint32_t* idx, int n, const v16d* in, Store store8) {
  v8d lo[8], hi[8];
  for (int k = 0; k < n; ++k) {
    std::memcpy(&lo[k], &in[k], sizeof(v8d));
    std::memcpy(&hi[k], reinterpret_cast<const char*>(&in[k]) + sizeof(v8d), sizeof(v8d));
  }
  store8(idx, lo);
  store8(idx + 8, hi);
}

// a wide load as two blocks of 8 (the first 8 lanes, then the next)
template <class Load>
PBA_LANES void load_twice(const std::uint32_t* idx, int n, v16d* out, Load load8) {
  v8d lo[8], hi[8];
  load8(idx, lo);
  load8(idx + 8, hi);
  for (int k = 0; k < n; ++k) {
    std::memcpy(&out[k], &lo[k], sizeof(v8d));
    std::memcpy(reinterpret_cast<char*>(&out[k]) + sizeof(v8d), &hi[k], sizeof(v8d));
  }
}

template <class V>
PBA_LANES void load3(const Vec3* a, const std::uint32_t* idx, V out[3]) {
  if constexpr (std::is_same_v<V, v16d>) {
    return load_twice(idx, 3, out, [&](const std::uint32_t* i, v8d* o) { load3<v8d>(a, i, o); });
  } else if constexpr (std::is_same_v<V, v8d>) {
    if (in_a_row(idx)) return rows3(&a[idx[0]].x, out);
  }
  for (int k = 0; k < 3; ++k) out[k] = splat<V>(0);
  for (int i = 0; i < kWidth<V>; ++i) {
    const Vec3& x = a[idx[i]];
    set(out[0], i, x.x), set(out[1], i, x.y), set(out[2], i, x.z);
  }
}

template <class V>
PBA_LANES void load_strided(const double* a, std::size_t stride, const std::uint32_t* idx, V out[3]) {
  for (int k = 0; k < 3; ++k) out[k] = splat<V>(0);
  for (int i = 0; i < kWidth<V>; ++i)
    for (int k = 0; k < 3; ++k) set(out[k], i, a[stride * idx[i] + k]);
}

template <class V>
PBA_LANES void store_strided(double* a, std::size_t stride, const std::uint32_t* idx, const V in[3]) {
  for (int i = 0; i < kWidth<V>; ++i)
    for (int k = 0; k < 3; ++k) a[stride * idx[i] + k] = get(in[k], i);
}

template <class V>
PBA_LANES void load_quat(const Quat* a, const std::uint32_t* idx, V out[4]) {
  if constexpr (std::is_same_v<V, v16d>) {
    return load_twice(idx, 4, out, [&](const std::uint32_t* i, v8d* o) { load_quat<v8d>(a, i, o); });
  } else if constexpr (std::is_same_v<V, v8d>) {
    if (in_a_row(idx)) return rows4(reinterpret_cast<const double*>(&a[idx[0]]), kQuatAt, out);
  } else if constexpr (std::is_same_v<V, v4d>) {
    // (each quaternion one load, and a 4 by 4 transpose: lane by lane, a load and an insert a number)
    v4d t[4];
    for (int i = 0; i < 4; ++i) t[i] = load<v4d>(reinterpret_cast<const double*>(&a[idx[i]]));
    transpose4x4(t);
    for (int k = 0; k < 4; ++k) out[k] = t[kQuatAt[k]];
    return;
  }
  for (int k = 0; k < 4; ++k) out[k] = splat<V>(0);
  for (int i = 0; i < kWidth<V>; ++i) {
    const Quat& q = a[idx[i]];
    set(out[0], i, q.w), set(out[1], i, q.x), set(out[2], i, q.y), set(out[3], i, q.z);
  }
}

template <class V>
PBA_LANES void store3(Vec3* a, const std::uint32_t* idx, const V in[3]) {
  if constexpr (std::is_same_v<V, v16d>) {
    return store_twice(idx, 3, in, [&](const std::uint32_t* i, const v8d* x) { store3<v8d>(a, i, x); });
  } else if constexpr (std::is_same_v<V, v8d>) {
    if (in_a_row(idx)) return unrows3(&a[idx[0]].x, in);
  }
  for (int i = 0; i < kWidth<V>; ++i) a[idx[i]] = Vec3(get(in[0], i), get(in[1], i), get(in[2], i));
}

template <class V>
PBA_LANES void store_quat(Quat* a, const std::uint32_t* idx, const V in[4]) {
  if constexpr (std::is_same_v<V, v16d>) {
    return store_twice(idx, 4, in, [&](const std::uint32_t* i, const v8d* x) { store_quat<v8d>(a, i, x); });
  } else if constexpr (std::is_same_v<V, v8d>) {
    if (in_a_row(idx)) return unrows4(reinterpret_cast<double*>(&a[idx[0]]), kQuatAt, in);
  }
  for (int i = 0; i < kWidth<V>; ++i) a[idx[i]] = Quat(get(in[0], i), get(in[1], i), get(in[2], i), get(in[3], i));
}

template <class V>
PBA_LANES V load1(const double* a, const std::uint32_t* idx) {
  if constexpr (std::is_same_v<V, v8d>) {
    if (in_a_row(idx)) return load<v8d>(a + idx[0]);
  }
  V out = splat<V>(0);
  for (int i = 0; i < kWidth<V>; ++i) set(out, i, a[idx[i]]);
  return out;
}

// The free motion's lanes (solver.h, FreeLine): n fields from line `line` on of the block
// whose lanes start at `at` (a v16d's 16 lanes are two blocks), each a whole vector
template <class V>
PBA_LANES void load_lines(const double* at, int line, int n, V out[]) {
  // a vector fills part of one block's line, whole (never two blocks'), or v16d: two blocks' lines
  static_assert(std::is_same_v<V, v16d> ? sizeof(V) == 2 * kFreeLaneWidth * sizeof(double)
                                        : kFreeLaneWidth * sizeof(double) % sizeof(V) == 0);
  for (int k = 0; k < n; ++k) {
    const double* p = at + static_cast<std::size_t>(line + k) * kFreeLaneWidth;
    if constexpr (std::is_same_v<V, v16d>) {
      const v8d lo = load<v8d>(p), hi = load<v8d>(p + kFreeBlock);
      std::memcpy(&out[k], &lo, sizeof lo);
      std::memcpy(reinterpret_cast<char*>(&out[k]) + sizeof lo, &hi, sizeof hi);
    } else if constexpr (std::is_same_v<V, v4x2>) {
      // (by halves: a copy of the whole went through the stack in 16-byte pieces)
      out[k] = {load<v4d>(p), load<v4d>(p + 4)};
    } else {
      out[k] = load<V>(p);
    }
  }
}

template <class V>
PBA_LANES void store_lines(double* at, int line, int n, const V in[]) {
  // a vector fills part of one block's line, whole (never two blocks'), or v16d: two blocks' lines
  static_assert(std::is_same_v<V, v16d> ? sizeof(V) == 2 * kFreeLaneWidth * sizeof(double)
                                        : kFreeLaneWidth * sizeof(double) % sizeof(V) == 0);
  if constexpr (std::is_same_v<V, v4d>) {
    // (unrolled: the positions' frame, 4 lines, went through the stack, a loop of 16-byte copies)
#pragma GCC unroll 4
    for (int k = 0; k < n; ++k) store<v4d>(at + static_cast<std::size_t>(line + k) * kFreeLaneWidth, in[k]);
    return;
  } else if constexpr (std::is_same_v<V, v4x2>) {
#pragma GCC unroll 4
    for (int k = 0; k < n; ++k) {
      double* p = at + static_cast<std::size_t>(line + k) * kFreeLaneWidth;
      store<v4d>(p, in[k].lo), store<v4d>(p + 4, in[k].hi);
    }
    return;
  }
  for (int k = 0; k < n; ++k) {
    double* p = at + static_cast<std::size_t>(line + k) * kFreeLaneWidth;
    if constexpr (std::is_same_v<V, v16d>) {
      v8d lo, hi;
      std::memcpy(&lo, &in[k], sizeof lo);
      std::memcpy(&hi, reinterpret_cast<const char*>(&in[k]) + sizeof lo, sizeof hi);
      store<v8d>(p, lo), store<v8d>(p + kFreeBlock, hi);
    } else {
      store<V>(p, in[k]);
    }
  }
}

// Rows of 8 doubles a body (the contact solver's velocities and warm-start accumulators, the
// motion): the lanes' rows at base + 8 idx as 8 vectors of one number a lane. On AVX-512 a
// block loads and stores whole rows and transposes them; on AVX2 each half row (4 numbers) of
// its 4 bodies, two 4 by 4 transposes (lane by lane, GCC made each number a load and an insert,
// and kept the vectors it merged them into on the stack); the plain path goes lane by lane.
// Only the first n numbers of a row are stored but on AVX-512 (the whole-row store writes
// in[n..7] back too, so they must hold what the rows hold).
template <class V>
PBA_LANES void load_rows(const double* base, const std::uint32_t* idx, V out[8]) {
  if constexpr (std::is_same_v<V, v16d>) {
    return load_twice(idx, 8, out, [&](const std::uint32_t* i, v8d* o) { load_rows<v8d>(base, i, o); });
  } else if constexpr (std::is_same_v<V, v8d>) {
    for (int i = 0; i < 8; ++i) out[i] = load<v8d>(base + 8 * static_cast<std::size_t>(idx[i]));
    return transpose8x8(out);
  } else if constexpr (std::is_same_v<V, v4x2>) {
    v4d lo[8], hi[8];
    load_rows<v4d>(base, idx, lo), load_rows<v4d>(base, idx + 4, hi);
#pragma GCC unroll 8
    for (int k = 0; k < 8; ++k) out[k] = {lo[k], hi[k]};
    return;
  } else if constexpr (std::is_same_v<V, v4d>) {
#pragma GCC unroll 4
    for (int i = 0; i < 4; ++i) {
      const double* row = base + 8 * static_cast<std::size_t>(idx[i]);
      out[i] = load<v4d>(row), out[4 + i] = load<v4d>(row + 4);
    }
    return transpose4x4(out), transpose4x4(out + 4);
  }
  for (int k = 0; k < 8; ++k) out[k] = splat<V>(0);
  for (int i = 0; i < kWidth<V>; ++i)
    for (int k = 0; k < 8; ++k) set(out[k], i, base[8 * static_cast<std::size_t>(idx[i]) + k]);
}

template <class V>
PBA_LANES void store_rows(double* base, const std::uint32_t* idx, const V in[8], int n) {
  if constexpr (std::is_same_v<V, v16d>) {
    return store_twice(idx, 8, in, [&](const std::uint32_t* i, const v8d* x) { store_rows<v8d>(base, i, x, n); });
  } else if constexpr (std::is_same_v<V, v8d>) {
    v8d r[8];
    for (int k = 0; k < 8; ++k) r[k] = in[k];
    transpose8x8(r);
    for (int i = 0; i < 8; ++i) store<v8d>(base + 8 * static_cast<std::size_t>(idx[i]), r[i]);
    return;
  } else if constexpr (std::is_same_v<V, v4x2>) {
    v4d lo[8], hi[8];
#pragma GCC unroll 8
    for (int k = 0; k < 8; ++k) lo[k] = in[k].lo, hi[k] = in[k].hi;
    store_rows<v4d>(base, idx, lo, n), store_rows<v4d>(base, idx + 4, hi, n);
    return;
  } else if constexpr (std::is_same_v<V, v4d>) {
    v4d r[8];
    for (int k = 0; k < 8; ++k) r[k] = in[k];
    transpose4x4(r), transpose4x4(r + 4);
    assert(n >= 4 && n <= 8);
    // (n is a constant where this is inlined, 6 to 8: whole first halves, the second's first n -
    // 4; unrolled, or GCC stored the transposed rows on the stack and copied them from there)
#pragma GCC unroll 4
    for (int i = 0; i < 4; ++i) {
      double* row = base + 8 * static_cast<std::size_t>(idx[i]);
      store<v4d>(row, r[i]);
      std::memcpy(row + 4, &r[4 + i], static_cast<std::size_t>(n - 4) * sizeof(double));
    }
    return;
  }
  for (int i = 0; i < kWidth<V>; ++i)
    for (int k = 0; k < n; ++k) base[8 * static_cast<std::size_t>(idx[i]) + k] = get(in[k], i);
}

// The lanes' velocities v and w in r[0..2] and r[3..5]: from the contact solver's rows (stride
// 8, w 3 past v; r[6], r[7] hold the rows' spare numbers) or the system's arrays (stride 3)
template <class V>
PBA_LANES void load_velocities(const FreeMotionArrays& f, const std::uint32_t* idx, V r[8]) {
  if (f.stride == 8) return load_rows(f.v, idx, r);
  load_strided(f.v, f.stride, idx, r);
  load_strided(f.w, f.stride, idx, r + 3);
  r[6] = r[7] = splat<V>(0);
}

template <class V>
PBA_LANES void store_velocities(const FreeMotionArrays& f, const std::uint32_t* idx, const V r[8]) {
  if (f.stride == 8) return store_rows(f.v, idx, r, 6);
  store_strided(f.v, f.stride, idx, r);
  store_strided(f.w, f.stride, idx, r + 3);
}

// What stays the same over a step's substeps of h (s): the change of v, h (gravity scale g +
// inverse mass force); a round body's change of w, h I^-1 torque (Round), else the torque and
// h I^-1 per principal axis; the damping's divisors 1 + h c. Formed once a step for the free
// motion's lanes (gather), or in each substep's velocities without them: the same expressions,
// so the same bits.
template <class V, bool Round>
PBA_LANES void step_changes(const std::uint32_t* idx, const FreeMotionArrays& f, double h, const Vec3& g,
                            V linear[3], V angular[3], V hinv[3], V damp[2]) {
  V force[3], inv[3];
  load3(f.force, idx, force);
  load3(f.torque, idx, angular);
  load3(f.inv_inertia, idx, inv);
  const V m = load1<V>(f.inv_mass, idx), gs = load1<V>(f.gravity_scale, idx);
  const double gk[3] = {g.x, g.y, g.z};
  for (int k = 0; k < 3; ++k) linear[k] = h * (gs * gk[k] + m * force[k]);
  if constexpr (Round) {
    for (int k = 0; k < 3; ++k) angular[k] = h * inv[0] * angular[k];
  } else {
    for (int k = 0; k < 3; ++k) hinv[k] = h * inv[k];
  }
  if (f.damped) damp[0] = 1.0 + h * load1<V>(f.lin_damp, idx), damp[1] = 1.0 + h * load1<V>(f.ang_damp, idx);
}

// A force too large for the contacts' float rows (or for a double) stops here, before contacts
// can spread it to others: whether the lanes' velocities r (v, then w) are within
// kMaxRigidSpeed (a NaN fails); else false, and the first body past it in *bad
template <class V>
PBA_LANES bool speeds_within(const std::uint32_t* idx, const V r[8], std::uint32_t* bad) {
  const V v2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2], w2 = r[3] * r[3] + r[4] * r[4] + r[5] * r[5];
  constexpr double limit2 = kMaxRigidSpeed * kMaxRigidSpeed;
  if (all_within(v2, limit2) && all_within(w2, limit2)) return true;
  for (int i = 0; i < kWidth<V>; ++i)
    if (!(get(v2, i) <= limit2 && get(w2, i) <= limit2)) return *bad = idx[i], false;
  return true;
}

// The lanes' velocities; false (and the first bad body in *bad) when one is not finite. Round
// bodies (Round: all three principal moments equal) take the torque's change of w as h torque
// / I, without turning it into the principal frame and back. Lanes: what stays the same over
// the substeps (step_changes) and the frames from the free motion's lanes at `at`, else from
// the bodies' arrays.
//
// Without a torque (f.torqued false: every moving body's is +0, the rain's and most scenes'),
// the torque's change of w is exactly +0 whatever the frame and moments: rotate() of +0 is
// v + (+-0) = +0 in every component, and h / I >= 0 keeps it +0. So on the AVX2 and plain paths,
// from the lanes, its lines, the frame and the two turns are left out (Torqued false) and +0 is
// added (x + 0 is x, and -0 + 0 is +0 as before): the same bits. (The rain's landing:
// velocities_avx2 5.35 -> 4.39 M instructions a step. AVX-512's code is kept as it was: always
// Torqued.)
template <class V, bool Round, bool Lanes, bool Torqued = true>
PBA_LANES bool velocities(const std::uint32_t* idx, const FreeMotionArrays& f, const double* at, double h,
                          const Vec3& g, std::uint32_t* bad) {
  V r[8], linear[3], angular[3], hinv[3], damp[2], q[4];
  load_velocities(f, idx, r);
  if constexpr (Lanes) {
    load_lines(at, kLineLinear, 3, linear);
    if constexpr (Torqued) {
      load_lines(at, kLineAngular, 3, angular);
      if constexpr (!Round) load_lines(at, kLineHInv, 3, hinv), load_lines(at, kLineQ, 4, q);
    }
    if (f.damped) load_lines(at, kLineDamp, 2, damp);
  } else {
    step_changes<V, Round>(idx, f, h, g, linear, angular, hinv, damp);
    if constexpr (!Round && Torqued) load_quat(f.q, idx, q);
  }
  // gravity, applied force and torque (in the principal frame), then implicit damping
  V dw[3];
  if constexpr (!Torqued) {
    for (int k = 0; k < 3; ++k) dw[k] = splat<V>(0);
  } else if constexpr (Round) {
    for (int k = 0; k < 3; ++k) dw[k] = angular[k];
  } else {
    V tb[3];
    rotate(q, -1, angular, tb);
    for (int k = 0; k < 3; ++k) tb[k] = hinv[k] * tb[k];
    rotate(q, 1, tb, dw);
  }
  for (int k = 0; k < 3; ++k) r[k] = r[k] + linear[k], r[3 + k] = r[3 + k] + dw[k];
  // (x / (1 + h c) is x when c = 0: the divisions, the costliest operations here, only when
  // some body is damped)
  if (f.damped) {
    for (int k = 0; k < 3; ++k) r[k] = r[k] / damp[0], r[3 + k] = r[3 + k] / damp[1];
  }
  // the contacts' carried impulses (the warm start), taken once
  if (f.warm) {
    double* warm = f.warm[0].v;
    V add[8], zero[8];
    load_rows(warm, idx, add);
    for (int k = 0; k < 6; ++k) r[k] = r[k] + add[k];
    for (int k = 0; k < 8; ++k) zero[k] = splat<V>(0);
    store_rows(warm, idx, zero, 8);
  }
  store_velocities(f, idx, r);
  return speeds_within(idx, r, bad);
}

// The velocities of the 4 bodies idx[0..3] from the lanes at `at` on AVX2 without a torque or
// damping, into the contact solver's rows (f.stride 8), by whole half rows: each body's (v, w0)
// and (w1, w2, spare) plus the change of v with +0 for w, then its warm start (whose row is then
// zeroed, spares too). These are velocities<v4d, ..., Torqued = false>'s additions, lane for
// lane and in its order, with its transposes left out (the rows' two 4x4 each way and the warm
// start's, ~50 instructions a body of a velocities substep): only the change of v, 3 lines, is
// turned into rows. The speed limit's test: with every component within kMaxRigidSpeed / 2,
// |v|^2 and |w|^2 are at most 3/4 of the limit's square (their three roundings far within), so
// they pass; else (a large, infinite or NaN number) the lanes' test, on the rows as stored.
#if defined(__GNUC__) && defined(__x86_64__)
PBA_LANES bool velocities_rows(const std::uint32_t* idx, const FreeMotionArrays& f, const double* at,
                               std::uint32_t* bad) {
  v4d change[4];
  load_lines(at, kLineLinear, 3, change);
  change[3] = splat<v4d>(0);
  transpose4x4(change);  // (body b's (x, y, z, +0))
  const v4d zero = splat<v4d>(0), half = splat<v4d>(0.5 * kMaxRigidSpeed);
  // (the sign bit alone: splat(-0.0) is 0 + -0.0 = +0, no mask)
  const v4l sign = v4l{} + std::numeric_limits<long long>::min();
  const auto magnitude = [&](v4d x) { return reinterpret_cast<v4d>(reinterpret_cast<v4l>(x) & ~sign); };
  const v4l spares = {0, 0, -1, -1};  // (a second half's last two numbers are not tested)
  v4l within = ~v4l{};
#pragma GCC unroll 4
  for (int b = 0; b < 4; ++b) {
    double* row = f.v + 8 * static_cast<std::size_t>(idx[b]);
    v4d lo = load<v4d>(row) + change[b], hi = load<v4d>(row + 4) + zero;
    if (f.warm) {
      double* warm = f.warm[0].v + 8 * static_cast<std::size_t>(idx[b]);
      lo = lo + load<v4d>(warm), hi = hi + load<v4d>(warm + 4);
      store<v4d>(warm, zero), store<v4d>(warm + 4, zero);
    }
    store<v4d>(row, lo);
    std::memcpy(row + 4, &hi, 2 * sizeof(double));
    within &= reinterpret_cast<v4l>(__builtin_ia32_cmppd256(magnitude(lo), half, _CMP_LE_OQ)) &
              (reinterpret_cast<v4l>(__builtin_ia32_cmppd256(magnitude(hi), half, _CMP_LE_OQ)) | spares);
  }
  if (__builtin_ia32_movmskpd256(reinterpret_cast<v4d>(within)) == 0xf) return true;
  v4d r[8];
  load_rows(f.v, idx, r);
  return speeds_within(idx, r, bad);
}
#endif

// The lanes of a kind from the bodies' arrays, once a step
template <class V, bool Round>
PBA_LANES void gather(const std::uint32_t* idx, const FreeMotionArrays& f, double h, const Vec3& g, double* at) {
  V x[4], inv[3], linear[3], angular[3], hinv[3], damp[2];
  // the pose now is the step's start too: step() copies com_ and q_ into com0_ and q0_ and
  // nothing moves a body before the substeps (the pairs, manifolds and prepare() read poses
  // only), so its lines are filled from the same registers, not loaded again lane by lane
  load3(f.com, idx, x), store_lines(at, kLineCom, 3, x), store_lines(at, kLineCom0, 3, x);
  load_quat(f.q, idx, x), store_lines(at, kLineQ, 4, x), store_lines(at, kLineQ0, 4, x);
  step_changes<V, Round>(idx, f, h, g, linear, angular, hinv, damp);
  store_lines(at, kLineLinear, 3, linear), store_lines(at, kLineAngular, 3, angular);
  // (a round body's turn and velocities read neither its moments nor its spread)
  if constexpr (!Round) {
    load3(f.inertia, idx, x), store_lines(at, kLineInertia, 3, x);
    load3(f.inv_inertia, idx, inv), store_lines(at, kLineInv, 3, inv);
    store_lines(at, kLineHInv, 3, hinv);
    // (refresh_inertia's measure, by the same template off the lanes)
    const V spread = solver_inertia_spread(inv[0], inv[1], inv[2]);
    store_lines(at, kLineSpread, 1, &spread);
  }
  if (f.damped) store_lines(at, kLineDamp, 2, damp);
}

// ... and the centres and frames back
template <class V>
PBA_LANES void scatter(const std::uint32_t* idx, const FreeMotionArrays& f, const double* at) {
  V x[4];
  load_lines(at, kLineCom, 3, x), store3(f.com, idx, x);
  load_lines(at, kLineQ, 4, x), store_quat(f.q, idx, x);
}

// One exact sub-flow of the splitting: the turn about principal axis K for the time whose
// half is `half_time` (s; the flow's fraction of h, halved), of frame q and body-frame momentum pi
template <int K, class V>
PBA_LANES void subflow(double half_time, const V inv[3], V q[4], V pi[3]) {
  const V half = half_time * pi[K] * inv[K];
  V hs, hc;
  sincos_half(half, hs, hc);
  const V c = 1.0 - 2.0 * hs * hs, sn = 2.0 * hs * hc;
  // the body turns by +angle about its axis K: q (cos(angle/2), sin(angle/2) e_K)
  const V qw = q[0], qx = q[1], qy = q[2], qz = q[3];
  if constexpr (K == 0)
    q[0] = qw * hc - qx * hs, q[1] = qw * hs + qx * hc, q[2] = qy * hc + qz * hs, q[3] = qz * hc - qy * hs;
  if constexpr (K == 1)
    q[0] = qw * hc - qy * hs, q[1] = qx * hc - qz * hs, q[2] = qw * hs + qy * hc, q[3] = qz * hc + qx * hs;
  if constexpr (K == 2)
    q[0] = qw * hc - qz * hs, q[1] = qx * hc + qy * hs, q[2] = qy * hc - qx * hs, q[3] = qw * hs + qz * hc;
  // its momentum, seen from the body, by -angle
  constexpr int a = (K + 1) % 3, b = (K + 2) % 3;
  const V pa = pi[a], pb = pi[b];
  pi[a] = c * pa + sn * pb;
  pi[b] = -sn * pa + c * pb;
}

// q kept unit (glm::normalize's arithmetic)
template <class V>
PBA_LANES void normalize(V q[4]) {
  const V len = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  const V one_over = 1.0 / sqrt_lanes(len);
  for (int k = 0; k < 4; ++k) q[k] = q[k] * one_over;
}

// The lanes' centres and frames (now, or at the start of the step: line kLineCom or
// kLineCom0, each with its frame 3 lines on), from the free motion's lanes (Lanes) or the
// bodies' arrays
static_assert(kLineQ == kLineCom + 3 && kLineQ0 == kLineCom0 + 3);
template <bool Lanes, class V>
PBA_LANES void load_vec3(const Vec3* a, const std::uint32_t* idx, const double* at, int line, V out[3]) {
  if constexpr (Lanes) load_lines(at, line, 3, out);
  else load3(a, idx, out);
}

template <bool Lanes, class V>
PBA_LANES void load_pose(const Vec3* com, const Quat* frame, const std::uint32_t* idx, const double* at, int line,
                         V x[3], V q[4]) {
  load_vec3<Lanes>(com, idx, at, line, x);
  if constexpr (Lanes) load_lines(at, line + 3, 4, q);
  else load_quat(frame, idx, q);
}

// the lanes' motion since the start of the step, for the contacts' separations: dp, and the
// turn q q0^-1 (glm's product with the conjugate), a row of 8 a body (the last zero)
template <class V, bool Lanes>
PBA_LANES void store_motion(const std::uint32_t* idx, const FreeMotionArrays& f, const double* at, const V x[3],
                            const V q[4]) {
  if (!f.motion) return;
  V x0[3], q0[4];
  load_pose<Lanes>(f.com0, f.q0, idx, at, kLineCom0, x0, q0);
  const V bw = q0[0], bx = -q0[1], by = -q0[2], bz = -q0[3];
  const V m[8] = {x[0] - x0[0],
                  x[1] - x0[1],
                  x[2] - x0[2],
                  q[0] * bw - q[1] * bx - q[2] * by - q[3] * bz,
                  q[0] * bx + q[1] * bw + q[2] * bz - q[3] * by,
                  q[0] * by + q[2] * bw + q[3] * bx - q[1] * bz,
                  q[0] * bz + q[3] * bw + q[1] * by - q[2] * bx,
                  splat<V>(0)};
  // (on AVX2 all 8, a whole half row one store, not a pair and a single: the last is zero in
  // every row, as prepare() makes them and AVX-512's whole rows store it)
  store_rows(f.motion, idx, m, kAvx2Lanes<V> ? 8 : 7);
}

// ... and back, with the motion since the start of the step
template <bool Lanes, class V>
PBA_LANES void store_pose(const FreeMotionArrays& f, const std::uint32_t* idx, double* at, const V x[3],
                          const V q[4]) {
  if constexpr (Lanes) {
    store_lines(at, kLineCom, 3, x);
    store_lines(at, kLineQ, 4, q);
  } else {
    store3(f.com, idx, x);
    store_quat(f.q, idx, q);
  }
  store_motion<V, Lanes>(idx, f, at, x, q);
}

// the product a b of quaternions (w, x, y, z)
template <class V>
PBA_LANES void multiply(const V a[4], const V b[4], V out[4]) {
  out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
  out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
  out[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
  out[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

// The turn t = (cos(|a|), sin(|a|) a / |a|) by the angle 2 |a|: cos and sin(|a|) / |a| are
// series in y = |a|^2 (the sub-flows' tails, no square root) within kSmall, else the library
template <class V>
PBA_LANES void turn_of(const V a[3], V t[4]) {
  const V y = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
  V c = 1.0 + cos_tail(y), sinc = 1.0 + sin_tail(y);
  if (!all_within(y, kSmall * kSmall)) {
    for (int i = 0; i < kWidth<V>; ++i) {
      const double half = std::sqrt(get(y, i));
      if (!(half <= kSmall)) set(c, i, std::cos(half)), set(sinc, i, std::sin(half) / half);
    }
  }
  t[0] = c, t[1] = sinc * a[0], t[2] = sinc * a[1], t[3] = sinc * a[2];
}

// The lanes' positions and rotations, and their motion since the start of the step. Bodies of
// three different principal moments (Triaxial) take the five sub-flows. Axisymmetric ones (two
// equal moments I1 about axes a and b, I3 about axis K) take their exact free rotation: the
// kinetic energy |pi|^2 / (2 I1) + pi_K^2 (1/I3 - 1/I1) / 2 is a sum of two terms whose flows
// commute (each keeps |pi| and pi_K), both exact turns: the body about its momentum by h |pi| /
// I1 (pi stays as it is), and the splitting's sub-flow about axis K by h pi_K (1/I3 - 1/I1)
// (pi turns by minus that); two turns instead of five.
template <FreeRotation R, class V, bool Lanes>
PBA_LANES void positions(const std::uint32_t* idx, const FreeMotionArrays& f, double* at, double h) {
  V r[8], x[3], q[4], inertia[3], inv[3];
  load_velocities(f, idx, r);
  load_pose<Lanes>(f.com, f.q, idx, at, kLineCom, x, q);
  load_vec3<Lanes>(f.inertia, idx, at, kLineInertia, inertia);
  load_vec3<Lanes>(f.inv_inertia, idx, at, kLineInv, inv);
  // symplectic Euler for the centre
  for (int k = 0; k < 3; ++k) x[k] = x[k] + h * r[k];
  // body-frame angular momentum pi = I w_body, then the exact turns
  V pi[3];
  rotate(q, -1, r + 3, pi);
  for (int k = 0; k < 3; ++k) pi[k] = inertia[k] * pi[k];
  if constexpr (R == FreeRotation::Triaxial) {
    subflow<0>(0.5 * 0.5 * h, inv, q, pi);
    subflow<1>(0.5 * 0.5 * h, inv, q, pi);
    subflow<2>(0.5 * 1.0 * h, inv, q, pi);
    subflow<1>(0.5 * 0.5 * h, inv, q, pi);
    subflow<0>(0.5 * 0.5 * h, inv, q, pi);
  } else {
    constexpr int K = static_cast<int>(R) - static_cast<int>(FreeRotation::AxialX), a = (K + 1) % 3;
    // q t: the turn about pi, in the body frame
    const V scale = (0.5 * h) * inv[a];
    const V half[3] = {scale * pi[0], scale * pi[1], scale * pi[2]};
    V t[4];
    turn_of(half, t);
    const V was[4] = {q[0], q[1], q[2], q[3]};
    multiply(was, t, q);
    // the turn about K at the rate pi_K (1/I3 - 1/I1)
    const V rate = inv[K] - inv[a];
    const V rates[3] = {rate, rate, rate};
    subflow<K>(0.5 * h, rates, q, pi);
  }
  // kept unit, and the world angular velocity back
  normalize(q);
  for (int k = 0; k < 3; ++k) pi[k] = pi[k] * inv[k];
  rotate(q, 1, pi, r + 3);
  store_velocities(f, idx, r);
  store_pose<Lanes>(f, idx, at, x, q);
}

// The same for round bodies (all three principal moments equal, I): the momentum is I w, so
// there is no gyroscopic term, the world angular velocity w stays as it is, and the free
// rotation over h is exactly the turn by the angle h |w| about w: q <- (cos(|a|), sin(|a|) a /
// |a|) q with a = h w / 2 (turn_of).
template <class V, bool Lanes>
PBA_LANES void positions_round(const std::uint32_t* idx, const FreeMotionArrays& f, double* at, double h) {
  V r[8], x[3], q[4];
  load_velocities(f, idx, r);
  load_pose<Lanes>(f.com, f.q, idx, at, kLineCom, x, q);
  for (int k = 0; k < 3; ++k) x[k] = x[k] + h * r[k];
  const double hh = 0.5 * h;
  const V a[3] = {hh * r[3], hh * r[4], hh * r[5]};
  V t[4];
  turn_of(a, t);
  const V was[4] = {q[0], q[1], q[2], q[3]};
  multiply(t, was, q);
  normalize(q);
  store_pose<Lanes>(f, idx, at, x, q);
}

// where position i of a kind's list keeps its lanes (nullptr without them)
template <bool Lanes, class P>
PBA_LANES P* lane_at(P* lanes, std::size_t i) {
  if constexpr (Lanes) return lanes + free_lane_at(i);
  else return (void)lanes, (void)i, nullptr;
}

// AVX2: the cache lines a block of 8 bodies `ahead` positions on will read, asked for now (a
// prefetch: no effect on any result). The lanes are 2 KB a block of 8 and the rows 64 bytes a
// body, the rain's 10,000 bodies 2.5 MB and 640 KB each, past the 512 KB L2; the lines a
// substep reads are a few of each block's 32, which the core's own prefetch does not follow
// (positions and velocities waited on their first loads). Lines [first, first + n) of the
// block and the rows of `rows` and `rows2` (nullptr: none) by body, `stride` doubles a body.
constexpr std::size_t kAhead = 16;
PBA_LANES void prefetch_block(const std::uint32_t* idx, std::size_t i, std::size_t count, const double* lanes,
                              int first, int n, const double* rows, const double* rows2, std::size_t stride = 8) {
  if (i + kAhead + kFreeLaneWidth > count) return;
  const double* at = lanes + free_lane_at(i + kAhead);
  // (n is a constant where this is inlined: unrolled, a prefetch a line at its offset, not a
  // loop of four instructions a line, 80 of a triaxial block's ~1,500)
#pragma GCC unroll 32
  for (int k = 0; k < n; ++k) __builtin_prefetch(at + static_cast<std::size_t>(first + k) * kFreeLaneWidth);
  for (std::size_t b = 0; b < kFreeLaneWidth; ++b) {
    const std::size_t body = idx[i + kAhead + b];
    if (rows) __builtin_prefetch(rows + stride * body);
    if (rows2) __builtin_prefetch(rows2 + stride * body);
  }
}

template <class V, bool Round, bool Lanes, bool Torqued>
PBA_LANES bool velocities_all(const std::uint32_t* idx, std::size_t count, const FreeMotionArrays& f,
                              const double* lanes, double h, const Vec3& g, std::uint32_t* bad) {
  std::size_t i = 0;
  // (AVX2 without a torque or damping: by rows, velocities_rows)
  [[maybe_unused]] const bool rows = f.stride == 8 && !f.damped;
  for (; i + kWidth<V> <= count; i += kWidth<V>) {
    if constexpr (Lanes && std::is_same_v<V, v4d>) {
      // (kLineQ's 4 lines, then kLineLinear on: 3 + 3 (+ 3 h / I), and the damping's 2; without a
      // torque the change of v's 3 lines and the damping's)
      if (i % kFreeLaneWidth == 0) {
        if constexpr (!Round && Torqued) prefetch_block(idx, i, count, lanes, kLineQ, 4, nullptr, nullptr);
        prefetch_block(idx, i, count, lanes, kLineLinear, !Torqued ? 3 : Round ? 6 : 9, f.stride == 8 ? f.v : nullptr,
                       f.warm ? f.warm[0].v : nullptr);
        if (f.damped) prefetch_block(idx, i, count, lanes, kLineDamp, 2, nullptr, nullptr);
      }
    }
#if defined(__GNUC__) && defined(__x86_64__)
    if constexpr (Lanes && !Torqued && std::is_same_v<V, v4d>) {
      if (rows) {
        if (!velocities_rows(idx + i, f, lane_at<Lanes>(lanes, i), bad)) return false;
        continue;
      }
    }
#endif
    if (!velocities<V, Round, Lanes, Torqued>(idx + i, f, lane_at<Lanes>(lanes, i), h, g, bad)) return false;
  }
  for (; i < count; ++i)
    if (!velocities<double, Round, Lanes, Torqued>(idx + i, f, lane_at<Lanes>(lanes, i), h, g, bad)) return false;
  return true;
}

template <class V>
PBA_LANES bool velocities_kind(bool round, const std::uint32_t* idx, std::size_t count, const FreeMotionArrays& f,
                               const double* lanes, double h, const Vec3& g, std::uint32_t* bad) {
  // (AVX-512 always as Torqued: its code kept as it was)
  if constexpr (!std::is_same_v<V, v8d>) {
    if (!f.torqued && lanes) {
      return round ? velocities_all<V, true, true, false>(idx, count, f, lanes, h, g, bad)
                   : velocities_all<V, false, true, false>(idx, count, f, lanes, h, g, bad);
    }
  }
  if (lanes) {
    return round ? velocities_all<V, true, true, true>(idx, count, f, lanes, h, g, bad)
                 : velocities_all<V, false, true, true>(idx, count, f, lanes, h, g, bad);
  }
  return round ? velocities_all<V, true, false, true>(idx, count, f, nullptr, h, g, bad)
               : velocities_all<V, false, false, true>(idx, count, f, nullptr, h, g, bad);
}

template <FreeRotation R, class V, bool Lanes>
PBA_LANES void positions_of(const std::uint32_t* idx, const FreeMotionArrays& f, double* at, double h) {
  if constexpr (R == FreeRotation::Round) positions_round<V, Lanes>(idx, f, at, h);
  else positions<R, V, Lanes>(idx, f, at, h);
}

template <FreeRotation R, class V, class W, bool Lanes>
PBA_LANES void positions_all(const std::uint32_t* idx, std::size_t count, const FreeMotionArrays& f, double* lanes,
                             double h) {
  std::size_t i = 0;
  // (AVX2's pairs only from the lanes: by body, their loads and stores went lane by lane)
  if constexpr (Lanes && std::is_same_v<W, v4x2>) {
    for (; i + kWidth<W> <= count; i += kWidth<W>) {
      // (the pose now and at the step's start, 14 lines, then the moments and their inverses)
      prefetch_block(idx, i, count, lanes, kLineCom, R == FreeRotation::Round ? 14 : 20,
                     f.stride == 8 ? f.v : nullptr, f.motion);
      positions_of<R, W, Lanes>(idx + i, f, lane_at<Lanes>(lanes, i), h);
    }
  } else if constexpr (!std::is_same_v<W, v4x2>) {
    for (; i + kWidth<W> <= count; i += kWidth<W>) positions_of<R, W, Lanes>(idx + i, f, lane_at<Lanes>(lanes, i), h);
  }
  for (; i + kWidth<V> <= count; i += kWidth<V>) positions_of<R, V, Lanes>(idx + i, f, lane_at<Lanes>(lanes, i), h);
  for (; i < count; ++i) positions_of<R, double, Lanes>(idx + i, f, lane_at<Lanes>(lanes, i), h);
}

template <FreeRotation R, class V, class W = V>
PBA_LANES void positions_lanes(const std::uint32_t* idx, std::size_t count, const FreeMotionArrays& f, double* lanes,
                               double h) {
  if (lanes) positions_all<R, V, W, true>(idx, count, f, lanes, h);
  else positions_all<R, V, W, false>(idx, count, f, nullptr, h);
}

// the pairs of blocks the round bodies take too: AVX2's (their turn's series, square root and
// divide are a chain as long as the splitting's per instruction; on AVX-512 one block)
template <class V, class W>
using Paired = std::conditional_t<std::is_same_v<W, v4x2>, W, V>;

// the kinds' kernels on a path: two blocks at once where W is wider (the splitting's long chain)
template <class V, class W>
PBA_LANES void positions_kind(FreeRotation kind, const std::uint32_t* idx, std::size_t count, const FreeMotionArrays& f,
                              double h, double* lanes) {
  switch (kind) {
    case FreeRotation::Triaxial: return positions_lanes<FreeRotation::Triaxial, V, W>(idx, count, f, lanes, h);
    case FreeRotation::Round: return positions_lanes<FreeRotation::Round, V, Paired<V, W>>(idx, count, f, lanes, h);
    case FreeRotation::AxialX: return positions_lanes<FreeRotation::AxialX, V>(idx, count, f, lanes, h);
    case FreeRotation::AxialY: return positions_lanes<FreeRotation::AxialY, V>(idx, count, f, lanes, h);
    case FreeRotation::AxialZ: return positions_lanes<FreeRotation::AxialZ, V>(idx, count, f, lanes, h);
  }
}

// the lanes of a kind filled and emptied a block at a time, the last few bodies one by one
template <class V, bool Round>
PBA_LANES void gather_all(const std::uint32_t* idx, std::size_t count, const FreeMotionArrays& f, double h,
                          const Vec3& g, double* lanes) {
  std::size_t i = 0;
  for (; i + kWidth<V> <= count; i += kWidth<V>) gather<V, Round>(idx + i, f, h, g, lanes + free_lane_at(i));
  for (; i < count; ++i) gather<double, Round>(idx + i, f, h, g, lanes + free_lane_at(i));
}

template <class V>
PBA_LANES void gather_kind(bool round, const std::uint32_t* idx, std::size_t count, const FreeMotionArrays& f, double h,
                           const Vec3& g, double* lanes) {
  if (round) gather_all<V, true>(idx, count, f, h, g, lanes);
  else gather_all<V, false>(idx, count, f, h, g, lanes);
}

template <class V>
PBA_LANES void scatter_kind(const std::uint32_t* idx, std::size_t count, const FreeMotionArrays& f,
                            const double* lanes) {
  std::size_t i = 0;
  for (; i + kWidth<V> <= count; i += kWidth<V>) scatter<V>(idx + i, f, lanes + free_lane_at(i));
  for (; i < count; ++i) scatter<double>(idx + i, f, lanes + free_lane_at(i));
}

#if defined(__GNUC__) && defined(__x86_64__)
#define PBA_RIGID_HAVE_X86 1
#if PBA_AVX512
__attribute__((target("avx512f"))) bool velocities_avx512(bool round, const std::uint32_t* idx, std::size_t count,
                                                         const FreeMotionArrays& f, double h, const Vec3& g,
                                                         const double* lanes, std::uint32_t* bad) {
  return velocities_kind<v8d>(round, idx, count, f, lanes, h, g, bad);
}
#endif
__attribute__((target("avx2"))) bool velocities_avx2(bool round, const std::uint32_t* idx, std::size_t count,
                                                    const FreeMotionArrays& f, double h, const Vec3& g,
                                                    const double* lanes, std::uint32_t* bad) {
  return velocities_kind<v4d>(round, idx, count, f, lanes, h, g, bad);
}
#if PBA_AVX512
__attribute__((target("avx512f"))) void positions_avx512(FreeRotation kind, const std::uint32_t* idx,
                                                        std::size_t count, const FreeMotionArrays& f, double h,
                                                        double* lanes) {
  positions_kind<v8d, v16d>(kind, idx, count, f, h, lanes);
}
#endif
__attribute__((target("avx2"))) void positions_avx2(FreeRotation kind, const std::uint32_t* idx, std::size_t count,
                                                   const FreeMotionArrays& f, double h, double* lanes) {
  positions_kind<v4d, v4x2>(kind, idx, count, f, h, lanes);
}
#if PBA_AVX512
__attribute__((target("avx512f"))) void gather_avx512(bool round, const std::uint32_t* idx, std::size_t count,
                                                     const FreeMotionArrays& f, double h, const Vec3& g,
                                                     double* lanes) {
  gather_kind<v8d>(round, idx, count, f, h, g, lanes);
}
#endif
__attribute__((target("avx2"))) void gather_avx2(bool round, const std::uint32_t* idx, std::size_t count,
                                                const FreeMotionArrays& f, double h, const Vec3& g, double* lanes) {
  gather_kind<v4d>(round, idx, count, f, h, g, lanes);
}
#if PBA_AVX512
__attribute__((target("avx512f"))) void scatter_avx512(const std::uint32_t* idx, std::size_t count,
                                                      const FreeMotionArrays& f, const double* lanes) {
  scatter_kind<v8d>(idx, count, f, lanes);
}
#endif
__attribute__((target("avx2"))) void scatter_avx2(const std::uint32_t* idx, std::size_t count,
                                                 const FreeMotionArrays& f, const double* lanes) {
  scatter_kind<v4d>(idx, count, f, lanes);
}
// refresh_inertia's test (contact_solver.cpp) over 4 lanes at a time, its arithmetic lane by
// lane (glm::dot's order for quaternions: (w w' + x x') + (y y' + z z'))
__attribute__((target("avx2"))) std::size_t turned_far_avx2(const std::uint32_t* idx, std::size_t count,
                                                            const double* lanes, const Quat* inertia_q,
                                                            std::uint32_t* far, std::size_t& tested) {
  constexpr double limit = kInertiaTurn * kInertiaTurn;
  std::size_t n = 0, j = 0;
  for (; j + 4 <= count; j += 4) {
    const double* at = lanes + free_lane_at(j);
    if (j % kFreeLaneWidth == 0) {
      // (the frame's 4 lines and the spread's of the block two on, and its bodies' frames of
      // the inertia, 32 bytes each: the positions' reasons)
      prefetch_block(idx, j, count, lanes, kLineQ, 4, nullptr, nullptr);
      prefetch_block(idx, j, count, lanes, kLineSpread, 1, reinterpret_cast<const double*>(inertia_q), nullptr,
                     sizeof(Quat) / sizeof(double));
    }
    v4d q[4], r[4];
    load_lines(at, kLineQ, 4, q);
    load_quat(inertia_q, idx + j, r);
    const v4d spread = load<v4d>(at + kLineSpread * kFreeLaneWidth);
    const v4d dot = (q[0] * r[0] + q[1] * r[1]) + (q[2] * r[2] + q[3] * r[3]);
    // |dot| as the scalar test's std::abs: the sign bit cleared (splat(-0.0) is +0, no mask)
    const v4d c = reinterpret_cast<v4d>(reinterpret_cast<v4l>(dot) & ~(v4l{} + std::numeric_limits<long long>::min()));
    const v4d turn = 8.0 * (1.0 - c) * spread * spread;
    // (a NaN is not within, as in the scalar test)
    int out = ~__builtin_ia32_movmskpd256(__builtin_ia32_cmppd256(turn, splat<v4d>(limit), _CMP_LE_OQ)) & 0xf;
    for (; out != 0; out &= out - 1) {
      const auto lane = static_cast<std::uint32_t>(std::countr_zero(static_cast<unsigned>(out)));
      far[n++] = static_cast<std::uint32_t>(j) + lane;
    }
  }
  tested = j;
  return n;
}
#else
#define PBA_RIGID_HAVE_X86 0
#endif

}  // namespace

bool integrate_velocities_wide(SimdPath path, bool round, const std::uint32_t* bodies, std::size_t count,
                               const FreeMotionArrays& f, double h, const Vec3& gravity, const double* lanes,
                               std::uint32_t* bad) {
#if PBA_RIGID_HAVE_X86
#if PBA_AVX512
  if (path == SimdPath::Avx512) return velocities_avx512(round, bodies, count, f, h, gravity, lanes, bad);
#endif
  if (path == SimdPath::Avx2) return velocities_avx2(round, bodies, count, f, h, gravity, lanes, bad);
#endif
  (void)path;
  return velocities_kind<double>(round, bodies, count, f, lanes, h, gravity, bad);
}

void integrate_positions_wide(SimdPath path, FreeRotation kind, const std::uint32_t* bodies, std::size_t count,
                              const FreeMotionArrays& f, double h, double* lanes) {
#if PBA_RIGID_HAVE_X86
#if PBA_AVX512
  if (path == SimdPath::Avx512) return positions_avx512(kind, bodies, count, f, h, lanes);
#endif
  if (path == SimdPath::Avx2) return positions_avx2(kind, bodies, count, f, h, lanes);
#endif
  (void)path;
  positions_kind<double, double>(kind, bodies, count, f, h, lanes);
}

void gather_free_motion_wide(SimdPath path, FreeRotation kind, const std::uint32_t* bodies, std::size_t count,
                             const FreeMotionArrays& f, double h, const Vec3& gravity, double* lanes) {
  const bool round = kind == FreeRotation::Round;
#if PBA_RIGID_HAVE_X86
#if PBA_AVX512
  if (path == SimdPath::Avx512) return gather_avx512(round, bodies, count, f, h, gravity, lanes);
#endif
  if (path == SimdPath::Avx2) return gather_avx2(round, bodies, count, f, h, gravity, lanes);
#endif
  (void)path;
  gather_kind<double>(round, bodies, count, f, h, gravity, lanes);
}

std::size_t turned_far_wide(SimdPath path, const std::uint32_t* bodies, std::size_t count, const double* lanes,
                            const Quat* inertia_q, std::uint32_t* far, std::size_t& tested) {
#if PBA_RIGID_HAVE_X86
  if (path == SimdPath::Avx2) return turned_far_avx2(bodies, count, lanes, inertia_q, far, tested);
#endif
  // (the other paths leave all of them to the caller's scalar test; AVX-512's code is kept as
  // it was, untimed on the AVX2 hosts this was made on)
  (void)path, (void)bodies, (void)count, (void)lanes, (void)inertia_q, (void)far;
  tested = 0;
  return 0;
}

void scatter_free_motion_wide(SimdPath path, const std::uint32_t* bodies, std::size_t count, const FreeMotionArrays& f,
                              const double* lanes) {
#if PBA_RIGID_HAVE_X86
#if PBA_AVX512
  if (path == SimdPath::Avx512) return scatter_avx512(bodies, count, f, lanes);
#endif
  if (path == SimdPath::Avx2) return scatter_avx2(bodies, count, f, lanes);
#endif
  (void)path;
  scatter_kind<double>(bodies, count, f, lanes);
}

}  // namespace pba::detail
