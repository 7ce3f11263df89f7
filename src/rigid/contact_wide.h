// Rigid bodies: the contact solver's kernels over blocks of manifolds (src/rigid/solver.h).
// Private to the library: included by the files that compile the paths' entry points, a path
// and a block kind a file (contact_wide_avx2.cpp, contact_wide_avx2_one.cpp and the two
// avx512 ones; the scalar path, the dispatch and the lane-by-lane functions in
// contact_wide.cpp), so that the build compiles them side by side (in one file they were the
// asan build's slowest compile: 255 s of CPU, now 129 s for the longest part).
//
// One template over the lane type runs every path: float (the scalar path, and the overflow
// lane by lane), 8 floats (AVX2, and AVX-512 on blocks of up to 8 manifolds) and 16 floats
// (AVX-512), as GCC vector extensions. The blocks hold floats and the kernels compute in
// float (as Box2D v3 and Box3D do); the bodies' velocities and warm-start accumulators stay in
// double: a kernel reads them rounded to float and adds its float changes back to the doubles.
// Each lane does the same operations in the same order on every path (the build has
// -ffp-contract=off, so no fused multiply-add; division and square root are correctly
// rounded; min, max and the selections are the same comparisons; the pass's settings are
// rounded to float once), so the three paths give the same bits
// (RigidSimd.EveryPathGivesTheSameBits).
//
// A manifold is solved in its contact frame (t1, t2, n), as in Box2D v3's contact_solver.c but
// in 3D: the relative linear velocity and each body's angular velocity are turned into the
// frame, the normal points are swept `sweeps` times by projected Gauss-Seidel on the manifold's
// own K = J M^-1 J^T (a point's impulse changes the others' normal velocities through K, the
// bodies are not touched in between), then Coulomb friction at the centroid and the twist
// about the normal, and the change goes back to the two bodies once.
#pragma once

#include "solver.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <type_traits>
#include <utility>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

#include "core/lanes.h"

namespace pba::detail {

namespace {

using lanes::v4d;
using lanes::v4l;
using lanes::v8d;
using lanes::v8l;
using lanes::vmax;
using lanes::vmin;
using lanes::vsqrt;

typedef float v8f __attribute__((vector_size(32)));
typedef float v16f __attribute__((vector_size(64)));
typedef int v8i __attribute__((vector_size(32)));
typedef int v16i __attribute__((vector_size(64)));

// a lane type's number: float or double
template <class V>
struct ElementOf {
  using type = std::remove_cvref_t<decltype(std::declval<V>()[0])>;
};
template <class V>
  requires std::is_arithmetic_v<V>
struct ElementOf<V> {
  using type = V;
};
template <class V>
using Element = typename ElementOf<V>::type;

// lanes in a lane type
template <class V>
constexpr int kWidth = static_cast<int>(sizeof(V) / sizeof(Element<V>));
// a bit for each lane of a lane type (a block's masks, e.g. write_a, shifted to its first lane)
template <class V>
constexpr std::uint32_t kLaneBits = kWidth<V> >= 32 ? ~0u : (1u << kWidth<V>) - 1;

#define PBA_LANES [[gnu::always_inline]] inline

// x in every lane
template <class V>
PBA_LANES V splat(float x) {
  if constexpr (std::is_arithmetic_v<V>) return x;
  else return V{} + x;
}

// 8 floats widened to 8 doubles (exactly). kZmm: on the AVX-512 path, one vcvtps2pd; GCC 12
// makes __builtin_convertvector of v8f to v8d four instructions there (two halves converted
// apart, then joined), and the passes widen some 180 rows and fields a block each substep
template <bool kZmm>
PBA_LANES v8d widen(const v8f& f) {
  // (the builtin under _mm512_cvtps_pd, which as an always-inline function of its own target
  // cannot be inlined into these templates; the builtin is checked where it lands)
#if defined(__GNUC__) && defined(__x86_64__)
  if constexpr (kZmm) return __builtin_ia32_cvtps2pd512_mask(f, v8d{}, -1, _MM_FROUND_CUR_DIRECTION);
#endif
  return __builtin_convertvector(f, v8d);
}

// kWidth<V> consecutive floats from p, and back (lanes of doubles: widened, exactly, and
// rounded to the nearest floats)
template <class V>
PBA_LANES V load(const float* p) {
  if constexpr (std::is_arithmetic_v<V>) {
    return static_cast<V>(*p);
  } else if constexpr (std::is_same_v<Element<V>, float>) {
    V v;
    std::memcpy(&v, p, sizeof v);
    return v;
  } else if constexpr (std::is_same_v<V, v8d>) {  // lanes of 8 doubles: the AVX-512 path only
    v8f f;
    std::memcpy(&f, p, sizeof f);
    return widen<true>(f);
  } else {
    typedef float F __attribute__((vector_size(sizeof(V) / 2)));
    F f;
    std::memcpy(&f, p, sizeof f);
    return __builtin_convertvector(f, V);
  }
}
template <class V>
PBA_LANES void store(float* p, const V& v) {
  if constexpr (std::is_arithmetic_v<V>) {
    *p = static_cast<float>(v);
  } else if constexpr (std::is_same_v<Element<V>, float>) {
    std::memcpy(p, &v, sizeof v);
  } else {
    typedef float F __attribute__((vector_size(sizeof(V) / 2)));
    const F f = __builtin_convertvector(v, F);
    std::memcpy(p, &f, sizeof f);
  }
}

// std::clamp(v, lo, hi)
template <class V>
PBA_LANES V vclamp(V v, V lo, V hi) {
  return v < lo ? lo : (hi < v ? hi : v);
}

// vmax(x, 0), the same bits on every path; on the AVX2 path (kYmm) one vmaxps: max(0, x)
// returns x unless 0 > x, the lanes of x < 0 ? 0 : x with -0 and NaN, where GCC makes a
// compare and an and-not, a cycle longer in the sweep's chain from point to point
template <bool kYmm, class V>
PBA_LANES V vmax0(V x, V zero) {
#if defined(__GNUC__) && defined(__x86_64__)
  if constexpr (kYmm) return __builtin_ia32_maxps256(zero, x);
#endif
  return lanes::vmax(x, zero);
}

// whether any lane of a comparison's mask is set
template <class M>
PBA_LANES bool any_lane(const M& m) {
  if constexpr (std::is_arithmetic_v<M>) {
    return m != 0;
  } else {
    // (as words: the lanes one by one were extracted one by one)
    std::uint64_t w[sizeof(M) / 8], any = 0;
    std::memcpy(w, &m, sizeof m);
    for (std::size_t i = 0; i < sizeof(M) / 8; ++i) any |= w[i];
    return any != 0;
  }
}


template <class V>
PBA_LANES V dot(const V a[3], const V b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// a symmetric matrix (xx, xy, xz, yy, yz, zz) times v
template <class V>
PBA_LANES void sym_mul(const V m[6], const V v[3], V out[3]) {
  out[0] = m[0] * v[0] + m[1] * v[1] + m[2] * v[2];
  out[1] = m[1] * v[0] + m[3] * v[1] + m[4] * v[2];
  out[2] = m[2] * v[0] + m[4] * v[1] + m[5] * v[2];
}

// the same for a v with no third component
template <class V>
PBA_LANES void sym_mul2(const V m[6], const V v0, const V v1, V out[3]) {
  out[0] = m[0] * v0 + m[1] * v1;
  out[1] = m[1] * v0 + m[3] * v1;
  out[2] = m[2] * v0 + m[4] * v1;
}

// ---------------------------------------------------------------------------------------
// the block's lanes [l0, l0 + width)

// (B: ContactBlock or OnePointBlock)
template <class V, class B = ContactBlock>
struct Lanes {
  B& c;
  int l0;
  // a field's lanes, and back
  PBA_LANES V operator()(const Real (&f)[kLanes]) const { return load<V>(f + l0); }
  PBA_LANES void put(Real (&f)[kLanes], const V& v) const { store<V>(f + l0, v); }
  // the same lanes of the same block, for reading fields again where they are used (the same
  // numbers): the block's address passes through an empty asm, so the compiler cannot reuse
  // the loads made through this one. Kept from the start of solve(), the frame, the inverse
  // masses and inertias, the arms, the points and K outlived the 32 registers, and each was
  // stored to the stack and read back (the AVX-512 pass's code: 273 such stores, 132 after);
  // the block is in L1, and a load folds into the instruction that uses it
  PBA_LANES Lanes again() const {
    B* p = &c;
    asm volatile("" : "+r"(p));
    return Lanes{*p, l0};
  }
  // the frame
  PBA_LANES void frame(V t1[3], V t2[3], V n[3]) const {
    for (int i = 0; i < 3; ++i) t1[i] = (*this)(c.t1[i]), t2[i] = (*this)(c.t2[i]), n[i] = (*this)(c.n[i]);
  }
  // the inverse inertias, a's and b's
  PBA_LANES void inertias(V ia[6], V ib[6]) const {
    for (int i = 0; i < 6; ++i) ia[i] = (*this)(c.ia[i]), ib[i] = (*this)(c.ib[i]);
  }
  // the centroid's arms, from a and from b
  PBA_LANES void arms(V ca[3], V cb[3]) const {
    for (int i = 0; i < 3; ++i) ca[i] = (*this)(c.ca[i]), cb[i] = (*this)(c.cb[i]);
  }
};

// the transpose of 8 rows of 8 floats, in the shuffles AVX2 has: unpcklps and unpckhps of row
// pairs, shufps of those, vperm2f128 of the 128-bit halves (24 shuffles). core/lanes.h's
// transpose8x8 pairs the rows' even and odd elements first, one instruction each for doubles
// (AVX-512's vunpcklpd) but two for floats (vpermilps and vblendps: 32 shuffles); the passes
// transpose each body row gathered and each change written back, 12 times a half-block and
// substep in the four-point pair. Only data moves: the same numbers as transpose8x8's
PBA_LANES void transpose(v8f r[8]) {
  v8f t[8], u[8];
  for (int i = 0; i < 4; ++i) {
    t[2 * i] = __builtin_shuffle(r[2 * i], r[2 * i + 1], v8i{0, 8, 1, 9, 4, 12, 5, 13});
    t[2 * i + 1] = __builtin_shuffle(r[2 * i], r[2 * i + 1], v8i{2, 10, 3, 11, 6, 14, 7, 15});
  }
  // u[4 h + j]: rows 4 h to 4 h + 3 of columns j (low half) and j + 4 (high half)
  for (int h = 0; h < 2; ++h) {
    const v8f* s = t + 4 * h;
    u[4 * h] = __builtin_shuffle(s[0], s[2], v8i{0, 1, 8, 9, 4, 5, 12, 13});
    u[4 * h + 1] = __builtin_shuffle(s[0], s[2], v8i{2, 3, 10, 11, 6, 7, 14, 15});
    u[4 * h + 2] = __builtin_shuffle(s[1], s[3], v8i{0, 1, 8, 9, 4, 5, 12, 13});
    u[4 * h + 3] = __builtin_shuffle(s[1], s[3], v8i{2, 3, 10, 11, 6, 7, 14, 15});
  }
  for (int j = 0; j < 4; ++j) {
    r[j] = __builtin_shuffle(u[j], u[j + 4], v8i{0, 1, 2, 3, 8, 9, 10, 11});
    r[j + 4] = __builtin_shuffle(u[j], u[j + 4], v8i{4, 5, 6, 7, 12, 13, 14, 15});
  }
}

// ... in 16 floats, of the two halves apart (rows i and i + 8 share vector i)
PBA_LANES void transpose(v16f r[8]) {
  v16f t[8], u[8];
  for (int i = 0; i < 4; ++i) {
    t[2 * i] =
        __builtin_shuffle(r[2 * i], r[2 * i + 1], v16i{0, 16, 2, 18, 4, 20, 6, 22, 8, 24, 10, 26, 12, 28, 14, 30});
    t[2 * i + 1] =
        __builtin_shuffle(r[2 * i], r[2 * i + 1], v16i{1, 17, 3, 19, 5, 21, 7, 23, 9, 25, 11, 27, 13, 29, 15, 31});
  }
  constexpr int kFirst[4] = {0, 1, 4, 5};
  for (const int i : kFirst) {
    u[i] = __builtin_shuffle(t[i], t[i + 2], v16i{0, 1, 16, 17, 4, 5, 20, 21, 8, 9, 24, 25, 12, 13, 28, 29});
    u[i + 2] = __builtin_shuffle(t[i], t[i + 2], v16i{2, 3, 18, 19, 6, 7, 22, 23, 10, 11, 26, 27, 14, 15, 30, 31});
  }
  for (int i = 0; i < 4; ++i) {
    r[i] = __builtin_shuffle(u[i], u[i + 4], v16i{0, 1, 2, 3, 16, 17, 18, 19, 8, 9, 10, 11, 24, 25, 26, 27});
    r[i + 4] = __builtin_shuffle(u[i], u[i + 4], v16i{4, 5, 6, 7, 20, 21, 22, 23, 12, 13, 14, 15, 28, 29, 30, 31});
  }
}

// the transpose of 4 rows of 4 doubles (its own inverse)
PBA_LANES void transpose(v4d r[4]) {
  const v4d t0 = __builtin_shuffle(r[0], r[1], v4l{0, 4, 2, 6}), t1 = __builtin_shuffle(r[0], r[1], v4l{1, 5, 3, 7});
  const v4d t2 = __builtin_shuffle(r[2], r[3], v4l{0, 4, 2, 6}), t3 = __builtin_shuffle(r[2], r[3], v4l{1, 5, 3, 7});
  r[0] = __builtin_shuffle(t0, t2, v4l{0, 1, 4, 5}), r[2] = __builtin_shuffle(t0, t2, v4l{2, 3, 6, 7});
  r[1] = __builtin_shuffle(t1, t3, v4l{0, 1, 4, 5}), r[3] = __builtin_shuffle(t1, t3, v4l{2, 3, 6, 7});
}

PBA_LANES void transpose(v8d r[8]) { pba::detail::lanes::transpose8x8(r); }

// a body's 64-byte row of 8 doubles rounded to 8 floats
PBA_LANES v8f row_floats(const double* base, std::uint32_t index) {
  v8d d;
  std::memcpy(&d, base + 8 * static_cast<std::size_t>(index), sizeof d);
  return __builtin_convertvector(d, v8f);
}

// each lane's row (base + 8 index) as 8 vectors of one number a lane (rounded to float in
// lanes of floats)
template <class V>
PBA_LANES void load_rows(const double* base, const std::uint32_t* index, V out[8]) {
  if constexpr (std::is_arithmetic_v<V>) {
    const double* p = base + 8 * static_cast<std::size_t>(index[0]);
    for (int k = 0; k < 8; ++k) out[k] = static_cast<V>(p[k]);
  } else if constexpr (std::is_same_v<V, v4d>) {
    for (int i = 0; i < 4; ++i) {
      const double* p = base + 8 * static_cast<std::size_t>(index[i]);
      std::memcpy(&out[i], p, sizeof(v4d)), std::memcpy(&out[4 + i], p + 4, sizeof(v4d));
    }
    transpose(out), transpose(out + 4);
  } else if constexpr (std::is_same_v<V, v8d>) {
    for (int i = 0; i < 8; ++i) std::memcpy(&out[i], base + 8 * static_cast<std::size_t>(index[i]), sizeof(v8d));
    transpose(out);
  } else if constexpr (std::is_same_v<V, v8f>) {
    for (int i = 0; i < 8; ++i) out[i] = row_floats(base, index[i]);
    transpose(out);
  } else {
    for (int i = 0; i < 8; ++i)
      out[i] = __builtin_shufflevector(row_floats(base, index[i]), row_floats(base, index[i + 8]), 0, 1, 2, 3, 4, 5, 6,
                                       7, 8, 9, 10, 11, 12, 13, 14, 15);
    transpose(out);
  }
}

// whether the kWidth<V> lanes from `index` name one body (on a one-point block's side a, the
// terrain's mesh under the 16 balls on its triangles: half the terrain's one-point blocks)
template <class V>
PBA_LANES bool one_body(const std::uint32_t* index) {
  if constexpr (std::is_arithmetic_v<V>) {
    return true;
  } else {
    typedef std::uint32_t U4 __attribute__((vector_size(16)));
    typedef std::uint32_t U8 __attribute__((vector_size(32)));
    typedef std::uint32_t U16 __attribute__((vector_size(64)));
    using U = std::conditional_t<kWidth<V> == 4, U4, std::conditional_t<kWidth<V> == 8, U8, U16>>;
    static_assert(sizeof(U) == 4 * kWidth<V>);
    U u;
    std::memcpy(&u, index, sizeof u);
    const U d = u ^ index[0];
    std::uint64_t w[sizeof(U) / 8], any = 0;
    std::memcpy(w, &d, sizeof d);
    for (std::size_t i = 0; i < sizeof(U) / 8; ++i) any |= w[i];
    return any == 0;
  }
}

// load_rows for a one-point block's side a (bits: the lanes' write bits from the first): when
// no lane writes it and every lane names the same body (a static or kinematic one), that body's
// one row, each number in every lane (the numbers load_rows gives: each rounded alone, and
// x - 0 keeps a -0), not a gather of the same row kWidth<V> times and its transpose. Side a is
// the shape of the lower slot, so a ground or mesh made before the bodies on it (the terrain's
// mesh) is there; side b is not tested. Only the one-point kernels call it (`if constexpr`, so
// that the four-point kernel compiles to the same code without it): in the four-point kernel
// the tests cost the piles more than they saved (fall1000's pass +3%, pyramid1240's +5%)
template <class V>
PBA_LANES void load_side(const double* base, const std::uint32_t* index, std::uint32_t bits, V out[8]) {
  if constexpr (!std::is_arithmetic_v<V>) {
    if ((bits & kLaneBits<V>) == 0 && one_body<V>(index)) {
      const double* p = base + 8 * static_cast<std::size_t>(index[0]);
      for (int k = 0; k < 8; ++k) out[k] = static_cast<Element<V>>(p[k]) - V{};
      return;
    }
  }
  load_rows(base, index, out);
}

// a lane's changes (8 floats) added to its body's row of doubles
template <bool kZmm>
PBA_LANES void add_row(double* base, std::uint32_t index, v8f change) {
  double* p = base + 8 * static_cast<std::size_t>(index);
  v8d d;
  std::memcpy(&d, p, sizeof d);
  d = d + widen<kZmm>(change);
  std::memcpy(p, &d, sizeof d);
}

// the first six of each lane's row (velocities, or their changes) plus `change`, widened to
// double, for the lanes whose bit of `bits` is set (the others write nothing: empty lanes, and
// bodies the solver does not move); kZmm on the AVX-512 path
template <class V, bool kZmm>
PBA_LANES void add_rows(double* base, const std::uint32_t* index, std::uint32_t bits, const V change[6]) {
  if constexpr (std::is_same_v<V, float>) {
    if (!(bits & 1)) return;
    double* p = base + 8 * static_cast<std::size_t>(index[0]);
    for (int k = 0; k < 6; ++k) p[k] = p[k] + static_cast<double>(change[k]);
  } else {
    V t[8] = {change[0], change[1], change[2], change[3], change[4], change[5], V{}, V{}};
    transpose(t);
    // (every: all the lanes write, as in most blocks of a pile, and no lane's bit is tested)
    auto rows = [&](auto every) {
      constexpr bool kEvery = decltype(every)::value;
      for (int i = 0; i < 8; ++i) {
        if constexpr (std::is_same_v<V, v8f>) {
          if (kEvery || ((bits >> i) & 1)) add_row<kZmm>(base, index[i], t[i]);
        } else {
          if (kEvery || ((bits >> i) & 1))
            add_row<kZmm>(base, index[i], __builtin_shufflevector(t[i], t[i], 0, 1, 2, 3, 4, 5, 6, 7));
          if (kEvery || ((bits >> (i + 8)) & 1))
            add_row<kZmm>(base, index[i + 8], __builtin_shufflevector(t[i], t[i], 8, 9, 10, 11, 12, 13, 14, 15));
        }
      }
    };
    if ((bits & kLaneBits<V>) == kLaneBits<V>) rows(std::true_type{});
    else rows(std::false_type{});
  }
}

// the pass's settings in float (rounded once, the same on every path)
struct FloatParams {
  float inv_h, bias_rate[2], mass_scale[2], impulse_scale[2], push_out, baumgarte_h, carry_speed;
  int sweeps;
  bool update_sep, warm_next, cap_carry, cap_total, defer;
  explicit FloatParams(const PassParams& p)
      : inv_h(static_cast<float>(p.inv_h)),
        bias_rate{static_cast<float>(p.bias_rate[0]), static_cast<float>(p.bias_rate[1])},
        mass_scale{static_cast<float>(p.mass_scale[0]), static_cast<float>(p.mass_scale[1])},
        impulse_scale{static_cast<float>(p.impulse_scale[0]), static_cast<float>(p.impulse_scale[1])},
        push_out(static_cast<float>(p.push_out)),
        baumgarte_h(static_cast<float>(p.baumgarte_h)),
        carry_speed(static_cast<float>(p.carry_speed)),
        sweeps(p.sweeps),
        update_sep(p.update_sep),
        warm_next(p.warm_next),
        cap_carry(p.cap_carry && p.update_sep),
        cap_total(p.cap_total),
        defer(p.one_colour) {}
};

// world = x0 t1 + x1 t2 + x2 n
template <class V>
PBA_LANES void to_world(const V t1[3], const V t2[3], const V n[3], const V x[3], V out[3]) {
  for (int i = 0; i < 3; ++i) out[i] = x[0] * t1[i] + x[1] * t2[i] + x[2] * n[i];
}

// the frame's coordinates of world vector v
template <class V>
PBA_LANES void to_frame(const V t1[3], const V t2[3], const V n[3], const V v[3], V out[3]) {
  out[0] = dot(v, t1), out[1] = dot(v, t2), out[2] = dot(v, n);
}

// the soft step's cap on the carried normal impulse: at most this times the last substep's
// (see pass(); a resting contact's impulse changes by far less a substep, a swaying column's
// by less than this, which the sway tests hold)
constexpr float kCarryGrowth = 1.5f;

// TGS's (on the manifold's total): at most this times the last substep's. A resting manifold's
// total changes by far less; a landing manifold, which held nothing the substep before, still
// carries only what holds it against gravity; the loaded manifolds below it carry more of the
// impulse the landing passed down, which pushes back out the overlap the landing's substep
// left them within the slop (TGS's bias only acts beyond it). Measured on Jolt's pyramid
// (TGS, 100 steps; its sag is left by the landings, the same at 500 steps) and the dropped
// column of ten (asleep after): 1.5, its top sags 24.8 mm, the column asleep at 2.03 s; 3,
// 14.7 mm; 6, 9.4 mm; 8, 3.4 mm (1.87 s); 10, 1.5 mm (1.72 s, its boxes within 1.5 cm of
// their line); 20, 1.8 mm. Carried whole (before 2026-12-07) it sagged 0.6 mm and the
// columns never slept (docs/rigid-bodies.md, "What a substep carries to the next")
constexpr float kCarryGrowthTgs = 10.0f;

// the separation (m) below which a point counts as touching (see solve())
constexpr float kTouching = 1e-6f;

// K's upper triangle by rows: (0,0) (0,1) (0,2) (0,3) (1,1) (1,2) (1,3) (2,2) (2,3) (3,3)
constexpr int kK[4][4] = {{0, 1, 2, 3}, {1, 4, 5, 6}, {2, 5, 7, 8}, {3, 6, 8, 9}};

// the separations at the poses now: base + n.(dp_b - dp_a) + n.(turn_b sb - sb) - n.(turn_a sa -
// sa), with n.(turn s - s) = (turn^-1 n - n).s taken in the frame
template <class V, class B>
PBA_LANES void separations(const Lanes<V, B>& L, const AnchorsOf<B::kPoints>& g, const BodyArrays& r) {
  constexpr int P = B::kPoints;
  B& c = L.c;
  V t1[3], t2[3], n[3];
  L.frame(t1, t2, n);
  V ma[8], mb[8];  // dp, then the turn (w, x, y, z)
  if constexpr (P == 1) {  // a static or kinematic side a's row loaded once (see load_side)
    load_side(r.motion, c.a + L.l0, c.write_a >> L.l0, ma);
    load_rows(r.motion, c.b + L.l0, mb);
  } else {
    load_rows(r.motion, c.a + L.l0, ma);
    load_rows(r.motion, c.b + L.l0, mb);
  }
  const V dp[3] = {mb[0] - ma[0], mb[1] - ma[1], mb[2] - ma[2]};
  const V dpn = dot(dp, n);
  // turn^-1 n - n = 2 (w (-u x n) + (-u) x ((-u) x n)) (the conjugate's quat_turn_change), in
  // the frame
  auto turned_normal = [&](const V* m, V out[3]) {
    V w[3];
    lanes::quat_turn_change(-m[4], -m[5], -m[6], m[3], n[0], n[1], n[2], w[0], w[1], w[2]);
    to_frame(t1, t2, n, w, out);
  };
  V na[3], nb[3];
  turned_normal(ma, na);
  turned_normal(mb, nb);
  const V ca0 = L(c.ca[0]), ca1 = L(c.ca[1]), cb0 = L(c.cb[0]), cb1 = L(c.cb[1]);
  for (int k = 0; k < P; ++k) {
    const V ex = L(g.ex[k]), ey = L(g.ey[k]);
    V sb, sa;
    if constexpr (P > 1) {
      const V x = L(c.x[k]), y = L(c.y[k]);
      sb = nb[0] * (cb0 + x + ex) + nb[1] * (cb1 + y + ey) + nb[2] * L(g.zb[k]);
      sa = na[0] * (ca0 + x - ex) + na[1] * (ca1 + y - ey) + na[2] * L(g.za[k]);
    } else {  // the point is the centroid (x = y = 0)
      sb = nb[0] * (cb0 + ex) + nb[1] * (cb1 + ey) + nb[2] * L(g.zb[k]);
      sa = na[0] * (ca0 - ex) + na[1] * (ca1 - ey) + na[2] * L(g.za[k]);
    }
    L.put(c.sep[k], L(g.base[k]) + dpn + sb - sa);
  }
}

// the passes: a biased one with soft contacts (the soft step), a biased one with rigid contacts
// and Baumgarte (sequential impulses, TGS), a relax pass without bias
enum Mode : int { kSoft, kRigid, kRelax };

// a lane mask of V (bool for a single float)
template <class V>
using MaskOf = decltype(std::declval<V>() == std::declval<V>());

// how many lanes of an AVX2 comparison's mask (M: MaskOf<v8f>) are set (its lanes are 0 or -1:
// the sign bits)
template <class M>
PBA_LANES int lanes_set(const M& m) {
#if defined(__GNUC__) && defined(__x86_64__)
  return __builtin_popcount(static_cast<unsigned>(__builtin_ia32_movmskps256(reinterpret_cast<v8f>(m))));
#else
  int n = 0;
  for (int i = 0; i < 8; ++i) n += m[i] != 0;
  return n;
#endif
}

// what solve() hands the rounds when a lane lands sliding: its state after the pass's sweeps
// and friction (in the frame), from which the rounds go on (they solved the pass again from
// the block, to the same numbers, before: a quarter of their instructions on the terrain and
// the 1240 pyramid)
template <class V, int P>
struct Carried {
  V rel[3], oa[3], ob[3], dwa[3], dwb[3], impulse[3];
  V lambda[P], largest[P], bias[P], iscale[P], negm[P], tj[2], total;
  MaskOf<V> skip[P], impact;
};

// the AVX2 path's state of a half-block between the set-up and the sweeps, and between the
// sweeps and the finish (see pass_pair): the two halves' sweeps run interleaved, point by point
template <class V, int P>
struct Swept {
  V rel[3], oa[3], ob[3];
  V lambda[P], largest[P], vn[P], bias[P], iscale[P], negm[P];
  MaskOf<V> skip[P];
};

// solve()'s parts: the whole pass, its set-up up to the sweeps (into a Swept), or from after
// the sweeps (from a Swept)
enum Part : int { kWhole, kSetUp, kFinish };

// point k of a sweep (see solve()): its impulse, and the normal speeds of the points it moves
// (last: the sweep before the friction, which updates only the points still to come)
template <int kMode, bool kYmm, bool kLast, class V, class B, int P>
PBA_LANES void sweep_point(const Lanes<V, B>& F, int k, V (&vn)[P], V (&lambda)[P], V (&largest)[P],
                           const V (&negm)[P], const V (&bias)[P], const V (&iscale)[P],
                           const MaskOf<V> (&skip)[P]) {
  const V zero = splat<V>(0);
  V j;
  if constexpr (kMode == kSoft) j = negm[k] * (vn[k] + bias[k]) - iscale[k] * lambda[k];
  else if constexpr (kMode == kRigid) j = negm[k] * (vn[k] + bias[k]);
  else if constexpr (kYmm) j = negm[k] * vn[k];  // (the + 0 left out: see solve())
  else j = negm[k] * (vn[k] + zero);
  V next = vmax0<kYmm>(lambda[k] + j, zero);
  if constexpr (kMode == kRelax) next = skip[k] ? lambda[k] : next;
  const V dl = next - lambda[k];
  lambda[k] = next;
  largest[k] = vmax(largest[k], dl);
#pragma GCC unroll 4
  for (int m = kLast ? k + 1 : 0; m < P; ++m) vn[m] = vn[m] + F(F.c.k[kK[m][k]]) * dl;
}

// one pass of the block's lanes: normal points, friction, twist
// the rounds (below), for lanes of which one lands sliding, from the pass's state: out of
// line, in a function of its path's target, so that the common pass keeps its registers
// (inline, with the mask's lanes tested one by one, the passes of the 1240 pyramid's first 100
// steps took 9.6% more instructions with the rounds never run; out of line, 1.9%)
template <class V, int kMode, bool kZmm, class B>
void solve_rounds(const Lanes<V, B>& L, const FloatParams& p, const BodyArrays& r, const Carried<V, B::kPoints>& from);

// The AVX2 pass's lanes that land sliding, gathered from the halves of one colour's blocks into
// the eight lanes of one rounds' call (DeferredRounds below). In the rain's landing a one-point
// half that calls the rounds has 1.3 such lanes on average (one lane in 78% of the calls), and
// the rounds (five iterations of a chain of some 140 cycles over all eight lanes, the others
// only selected back) were a third of the one-point passes' instructions; the four-point
// rounds were 6.7 M instructions of a landing step against the four-point pass's 11.4 M. A
// lane's arithmetic is the same in any lane of any call, and the lanes of one colour share no
// body that moves, so solving a lane's rounds, its row write-back, cap and warm start later in
// the colour, next to other blocks' lanes, changes no bit. (AVX2 only: the AVX-512 code stays
// as it is. Only within a call over one colour's blocks, FloatParams::defer: the ContactBlocks
// of all colours are passed in one call when no lane rolls, and theirs could not wait past
// their colour)
template <class B>
struct DeferredRounds;
#if defined(__GNUC__) && defined(__x86_64__)
#define PBA_DEFER_TARGET __attribute__((target("avx2")))
#else
#define PBA_DEFER_TARGET
#endif
template <int kMode, class B>
[[gnu::noinline]] PBA_DEFER_TARGET void defer_rounds(DeferredRounds<B>& d, B& c, int l0, const FloatParams& p,
                                                     const BodyArrays& r, const Carried<v8f, B::kPoints>& state);

// kRounds: the rounds' instance, which starts from `from` (the pass's state when a lane lands
// sliding) instead of from the block. defer (the AVX2 pass only): where its lanes that land
// sliding wait for their rounds (the others go on as they would)
// kPart: the whole pass, or one of the AVX2 path's two parts around the sweeps (through `mid`)
template <class V, int kMode, bool kZmm, class B, bool kRounds = false, int kPart = kWhole>
PBA_LANES void solve(const Lanes<V, B>& L, const FloatParams& p, const BodyArrays& r,
                     const Carried<V, B::kPoints>* from = nullptr, Swept<V, B::kPoints>* mid = nullptr,
                     DeferredRounds<B>* defer = nullptr) {
  constexpr bool kBias = kMode != kRelax;
  // (the set-up, up to the sweeps, and what follows them)
  constexpr bool kStart = !kRounds && kPart != kFinish;
  // the AVX2 path (8 floats on 16 ymm registers): its own scheduling where the AVX-512 code
  // must stay as it is
  constexpr bool kYmm = std::is_same_v<V, v8f> && !kZmm;
  // the points of a lane: a one-point lane's is its centroid (x = y = 0), and it has no twist;
  // what the four-point kernel adds or multiplies by those zeros is left out (it changes at
  // most a zero's sign)
  constexpr int P = B::kPoints;
  B& c = L.c;
  const int l0 = L.l0;
  const V zero = splat<V>(0), one = splat<V>(1);
  double* const base = r.bodies[0].v;
  V t1[3], t2[3], n[3];
  V rel[3], oa[3], ob[3], dwa[3], dwb[3], impulse[3];
  if constexpr (kStart) {
    // the bodies, and their velocities in the frame: the relative linear one, each angular one
    V rowa[8], rowb[8];
    if constexpr (P == 1) {  // a static or kinematic side a's row loaded once (see load_side)
      load_side(base, c.a + l0, c.write_a >> l0, rowa);
      load_rows(base, c.b + l0, rowb);
    } else {
      load_rows(base, c.a + l0, rowa);
      load_rows(base, c.b + l0, rowb);
    }
    V* const va = rowa;
    V* const wa = rowa + 3;
    V* const vb = rowb;
    V* const wb = rowb + 3;
    L.frame(t1, t2, n);
    {
      const V dv[3] = {vb[0] - va[0], vb[1] - va[1], vb[2] - va[2]};
      to_frame(t1, t2, n, dv, rel);
    }
    to_frame(t1, t2, n, wa, oa);
    to_frame(t1, t2, n, wb, ob);
    for (int i = 0; i < 3; ++i) dwa[i] = zero, dwb[i] = zero, impulse[i] = zero;
  } else if constexpr (kPart == kFinish) {
    for (int i = 0; i < 3; ++i) rel[i] = mid->rel[i], oa[i] = mid->oa[i], ob[i] = mid->ob[i];
    for (int i = 0; i < 3; ++i) dwa[i] = zero, dwb[i] = zero, impulse[i] = zero;
  } else {
    for (int i = 0; i < 3; ++i) {
      rel[i] = from->rel[i], oa[i] = from->oa[i], ob[i] = from->ob[i];
      dwa[i] = from->dwa[i], dwb[i] = from->dwb[i], impulse[i] = from->impulse[i];
    }
  }
  // (the inverse masses and inertias, the arms, the points, K and the frame are read from the
  // block again where they are used: Lanes::again)
  // turning a by -Ia ta and b by Ib tb (frame torques with no third component)
  auto turn2 = [&](const V ta0, const V ta1, const V tb0, const V tb1) __attribute__((always_inline)) {
    V da[3], db[3], ia[6], ib[6];
    L.again().inertias(ia, ib);
    sym_mul2(ia, ta0, ta1, da);
    sym_mul2(ib, tb0, tb1, db);
    for (int i = 0; i < 3; ++i)
      oa[i] = oa[i] - da[i], dwa[i] = dwa[i] - da[i], ob[i] = ob[i] + db[i], dwb[i] = dwb[i] + db[i];
  };

  // each point's bias, mass scale and impulse scale for this pass: speculative points (apart)
  // close the gap in this substep and no more, and the relax pass leaves them alone; touching
  // ones are pushed out by the soft spring (up to push_out) or by Baumgarte beyond the lane's
  // slop (pair_slop: less for a small body).
  // A point within kTouching of contact is touching: a gap closed in the last substep measures
  // zero up to the rounding of float velocities (in double it is exactly zero for a face
  // meeting a face), and that rounding must not pick between the two (with `sep > 0` a body
  // passed a wall of the 250 m/s closed box in 28 of 29 slightly perturbed runs, the double
  // kernels before in 9 of 34; with this margin in none of 13: docs/benchmarks.md)
  V lambda[P], vn[P], bias[P], iscale[P], largest[P], negm[P];
  MaskOf<V> skip[P];
  if constexpr (kRounds) {
    for (int k = 0; k < P; ++k) {
      lambda[k] = from->lambda[k], largest[k] = from->largest[k], bias[k] = from->bias[k];
      iscale[k] = from->iscale[k], negm[k] = from->negm[k], skip[k] = from->skip[k];
    }
  } else if constexpr (kPart == kFinish) {
    // (the sweeps' bias, scales and skips only for a landing's rounds, read from `mid` there:
    // copied here, GCC loaded and stored all sixteen each finish, some 40 instructions)
    for (int k = 0; k < P; ++k) lambda[k] = mid->lambda[k], largest[k] = mid->largest[k];
  }
  V mscale[P];
  const V ma = L(c.ma), mb = L(c.mb);
  const auto fixed = (ma == zero) | (mb == zero);
  if constexpr (kStart) {
    for (int k = 0; k < P; ++k) {
      lambda[k] = L(c.impulse[k]);
      largest[k] = L(c.max_impulse[k]);
      const V sep = L(c.sep[k]);
      const auto apart = sep > splat<V>(kTouching);
      skip[k] = fixed != fixed;  // none
      if constexpr (kMode == kSoft) {
        const V rate = fixed ? splat<V>(p.bias_rate[1]) : splat<V>(p.bias_rate[0]);
        bias[k] = apart ? sep * splat<V>(p.inv_h) : vmax(rate * sep, splat<V>(-p.push_out));
        mscale[k] = apart ? one : (fixed ? splat<V>(p.mass_scale[1]) : splat<V>(p.mass_scale[0]));
        iscale[k] = apart ? zero : (fixed ? splat<V>(p.impulse_scale[1]) : splat<V>(p.impulse_scale[0]));
      } else if constexpr (kMode == kRigid) {
        bias[k] = apart ? sep * splat<V>(p.inv_h)
                        : vmax(splat<V>(p.baumgarte_h) * vmin(zero, sep + L(c.slop)), splat<V>(-p.push_out));
        mscale[k] = one, iscale[k] = zero;
      } else {
        bias[k] = zero, mscale[k] = one, iscale[k] = zero;
        skip[k] = apart;
      }
    }
  }
  // the normal velocities: (vb + wb x rb - va - wa x ra).n with (w x r).n = w.(r x n), and
  // r x n = (r1, -r0, 0) in the frame: the centroid's, and each point's (ra = ca + p, rb = cb + p)
  auto normal_speeds = [&]() __attribute__((always_inline)) {
    V ca[3], cb[3];
    const auto F = L.again();
    F.arms(ca, cb);
    const V g = rel[2] + (ob[0] * cb[1] - ob[1] * cb[0]) - (oa[0] * ca[1] - oa[1] * ca[0]);
    if constexpr (P > 1) {
      const V p1 = ob[0] - oa[0], p2 = ob[1] - oa[1];
      for (int k = 0; k < P; ++k) vn[k] = g + F(F.c.y[k]) * p1 - F(F.c.x[k]) * p2;
    } else {
      vn[0] = g;
    }
  };
  // the approach speeds, from the velocities before this pass's impulses: read inside the
  // sweep, a point's took the turn the points before it gave the body, and a box landing flat
  // recorded corners approaching at 7.0 to 7.7 m/s, which the restitution pass bounced unevenly
  // (written now: nothing below reads them, and held to the end they took four registers)
  if constexpr (kStart) {
    normal_speeds();
    if constexpr (kBias)
      for (int k = 0; k < P; ++k) L.put(c.approach[k], vmin(L(c.approach[k]), vn[k]));
  }
  // non-penetration, swept over the points `sweeps` times (Gauss-Seidel on the manifold's
  // problem: one sweep leaves a torque imbalance between the points that rocks tall stacks)
  // (a sweep's last point updates no normal velocity: the sweeps after the friction start
  // from the speeds again; before it, the last sweep updates only the points still to come)
  // (each point's -mass * mass scale formed once for the sweeps: the same product each sweep
  // formed before. The rigid and relax passes' impulse scale is zero and their mass scale one:
  // their `- 0 * lambda` is left out, which changes no bit, since no impulse is ever -0: they
  // start at +0 or above (the fill's carried impulses, `on ? x : 0` and cap_carry's vmin of two
  // non-negative values), and vmax(lambda + j, 0) gives -0 only from -0 + -0. For the same
  // reason the AVX2 relax pass leaves out its + 0, which turns a -0 speed into +0 and so flips
  // the sign of a zero j, which lambda + j then drops: an add less a point in its chain)
  if constexpr (kStart)
    for (int k = 0; k < P; ++k) negm[k] = kMode == kSoft ? -L(c.mass[k]) * mscale[k] : -L(c.mass[k]);
  if constexpr (kPart == kSetUp) {
    // (the sweeps are pass_pair's, the two halves' points interleaved)
    for (int i = 0; i < 3; ++i) mid->rel[i] = rel[i], mid->oa[i] = oa[i], mid->ob[i] = ob[i];
    for (int k = 0; k < P; ++k) {
      mid->lambda[k] = lambda[k], mid->largest[k] = largest[k], mid->vn[k] = vn[k], mid->bias[k] = bias[k];
      mid->iscale[k] = iscale[k], mid->negm[k] = negm[k], mid->skip[k] = skip[k];
    }
    return;
  }
  // (the same arithmetic as sweep_point's, written out here: through that function the AVX-512
  // kernels' code changed, GCC 12 allocating their registers otherwise)
  auto sweep = [&](auto last) __attribute__((always_inline)) {
    const auto F = L.again();
    for (int k = 0; k < P; ++k) {
      V j;
      if constexpr (kMode == kSoft) j = negm[k] * (vn[k] + bias[k]) - iscale[k] * lambda[k];
      else if constexpr (kMode == kRigid) j = negm[k] * (vn[k] + bias[k]);
      else if constexpr (kYmm) j = negm[k] * vn[k];  // (the + 0 left out: above)
      else j = negm[k] * (vn[k] + zero);
      V next = vmax0<kYmm>(lambda[k] + j, zero);
      if constexpr (!kBias) next = skip[k] ? lambda[k] : next;
      const V dl = next - lambda[k];
      lambda[k] = next;
      largest[k] = vmax(largest[k], dl);
      for (int m = last ? k + 1 : 0; m < P; ++m) vn[m] = vn[m] + F(F.c.k[kK[m][k]]) * dl;
    }
  };
  if constexpr (!kRounds && kPart == kWhole) {
    for (int it = 1; it < p.sweeps; ++it) sweep(std::false_type{});
    sweep(std::true_type{});
  }
  // the points' impulses since `from` to the bodies: along n, and the moments sum dl (ca1 + y,
  // -(ca0 + x), 0) on a, the same with cb on b
  auto push = [&](const V (&from)[P]) __attribute__((always_inline)) {
    V sl = zero, sx = zero, sy = zero;
    const auto F = L.again();
    for (int k = 0; k < P; ++k) {
      const V dl = lambda[k] - from[k];
      // (a one-point lane on the AVX2 path: its step, not 0 + step, the same number, since no
      // step is -0: x - y is -0 only for x = -0, and no impulse is -0, see the sweeps. An add
      // less in the chain from the sweeps to the friction, in the pass and each round)
      if constexpr (kYmm && P == 1) sl = dl;
      else sl = sl + dl;
      if constexpr (P > 1) sx = sx + dl * F(F.c.x[k]), sy = sy + dl * F(F.c.y[k]);
    }
    V ca[3], cb[3];
    F.arms(ca, cb);
    rel[2] = rel[2] + (F(F.c.ma) + F(F.c.mb)) * sl;
    impulse[2] = impulse[2] + sl;
    if constexpr (P > 1) turn2(ca[1] * sl + sy, -(ca[0] * sl + sx), cb[1] * sl + sy, -(cb[0] * sl + sx));
    else turn2(ca[1] * sl, -(ca[0] * sl), cb[1] * sl, -(cb[0] * sl));
  };
  V before[P], total = zero;
  if constexpr (!kRounds) {
    for (int k = 0; k < P; ++k)
      before[k] = L(c.impulse[k]);  // (the block's impulses are the pass's start's until the end)
    push(before);
    if constexpr (kYmm && P == 1) total = lambda[0];  // (as sl in push: no impulse is -0)
    else
      for (int k = 0; k < P; ++k) total = total + lambda[k];
  } else {
    total = from->total;
  }
  // Coulomb friction at the centroid: the tangential impulse stays inside the disc of radius
  // mu * (total normal impulse). Sticking (the rows' step stays in the disc), each row with its
  // own mass. Sliding (beyond it), the step is along the slip r with the effective mass along
  // it, r^2 / (r^T K r) (K the tangent rows' block), which takes out the slip along r, and the
  // sum is scaled back to the disc: its fixed point on the edge opposes the slip (Coulomb).
  // With a mass each, a sliding impulse kept the direction of (m0 r0, m1 r1), not of r, and a
  // box whose footprint is not square curved off its line (1 x 0.5 x 0.6 m sent at 45 degrees
  // over mu = 0.5: 3.6-4.7 degrees, 0.2-0.3 m aside in 3.7 m)
  const V mu = L(c.friction);
  V tj[2];
  if constexpr (!kRounds) tj[0] = L(c.tangent_impulse[0]), tj[1] = L(c.tangent_impulse[1]);
  else tj[0] = from->tj[0], tj[1] = from->tj[1];
  auto friction = [&]() __attribute__((always_inline)) {
    V ca[3], cb[3], ia[6], ib[6];
    const auto F = L.again();
    F.arms(ca, cb);
    const V msum = F(F.c.ma) + F(F.c.mb);
    const V r0 = rel[0] + (ob[1] * cb[2] - ob[2] * cb[1]) - (oa[1] * ca[2] - oa[2] * ca[1]);
    const V r1 = rel[1] + (ob[2] * cb[0] - ob[0] * cb[2]) - (oa[2] * ca[0] - oa[0] * ca[2]);
    const V old0 = tj[0], old1 = tj[1];
    V j0 = old0 - L(c.tangent_mass[0]) * r0;
    V j1 = old1 - L(c.tangent_mass[1]) * r1;
    const V limit = mu * total;
    V len = vsqrt(j0 * j0 + j1 * j1);
    {
      const V k11 = L(c.tangent_k[0]), k12 = L(c.tangent_k[1]), k22 = L(c.tangent_k[2]);
      const V rr = r0 * r0 + r1 * r1;
      const V rkr = r0 * (k11 * r0 + k12 * r1) + r1 * (k12 * r0 + k22 * r1);
      const V m = rkr > zero ? rr / rkr : zero;  // (no slip: no step)
      const auto sliding = len > limit;
      if constexpr (kYmm) {
        // (the sliding step's length from the step itself, not from the selection: the same
        // lanes, and its square root no longer waits for the first one and the compare)
        const V s0 = old0 - m * r0, s1 = old1 - m * r1;
        const V slen = vsqrt(s0 * s0 + s1 * s1);
        j0 = sliding ? s0 : j0;
        j1 = sliding ? s1 : j1;
        len = sliding ? slen : len;
      } else {
        j0 = sliding ? old0 - m * r0 : j0;
        j1 = sliding ? old1 - m * r1 : j1;
        len = sliding ? vsqrt(j0 * j0 + j1 * j1) : len;
      }
    }
    const auto over = len > limit;
    const V scale = over ? limit / len : one;
    j0 = over ? j0 * scale : j0;
    j1 = over ? j1 * scale : j1;
    tj[0] = j0, tj[1] = j1;
    const V e0 = j0 - old0, e1 = j1 - old1;
    rel[0] = rel[0] + msum * e0, rel[1] = rel[1] + msum * e1;
    impulse[0] = impulse[0] + e0, impulse[1] = impulse[1] + e1;
    // the moments c x (e0, e1, 0) = (-c2 e1, c2 e0, c0 e1 - c1 e0)
    V da[3], db[3];
    const V ta[3] = {-ca[2] * e1, ca[2] * e0, ca[0] * e1 - ca[1] * e0};
    const V tb[3] = {-cb[2] * e1, cb[2] * e0, cb[0] * e1 - cb[1] * e0};
    L.again().inertias(ia, ib);
    sym_mul(ia, ta, da);
    sym_mul(ib, tb, db);
    for (int i = 0; i < 3; ++i)
      oa[i] = oa[i] - da[i], dwa[i] = dwa[i] - da[i], ob[i] = ob[i] + db[i], dwb[i] = dwb[i] + db[i];
    // (whether the friction's change moved the bodies more than gravity does in a substep)
    const V dv = msum * msum * (e0 * e0 + e1 * e1);
    return dv > splat<V>(p.carry_speed) * splat<V>(p.carry_speed);
  };
  MaskOf<V> impact;
  if constexpr (!kRounds) {
    impact = friction();
    // A landing while sliding: a manifold that comes into the pass sliding, whose friction then
    // changed the bodies' velocity by more than gravity does in a substep, is swept again
    // `sweeps` times, its points then its friction, and its points last (Gauss-Seidel over all
    // its rows, as sequential impulses iterate them; the disc each time mu times the points'
    // impulse then). The friction acts at the contact plane, below the body's centre: its moment
    // must be held by the points (the front ones taking more of the load), and friction and
    // points solved once each, in either order, left it to the positions: a 1 m box landing
    // flat at 7.4 m/s while sliding at 6 m/s tipped onto its leading edge, hopped at up to 1.8
    // m/s (TGS: 3.1) and slid 0.41 m (0.48) beyond Coulomb's bound, and with the friction first
    // (the disc of the impulse the pass starts from) it missed the part of the landing the relax
    // pass takes (RigidFriction.ABoxLandingFlatWhileSlidingStopsWhereCoulombSays). Sweeping
    // every manifold so cost 16% of fall1000's and 24% of pyramid1240's instructions, and a
    // cube landing straight on the corner of four (no slip: the friction only answers the
    // points' turn) went 7 mm aside: the manifolds' own problems solved further each, the
    // colour solved first took more of the landing. Lanes that do not land sliding keep the
    // one pass's values (selected), so that every path gives the same bits
    if (any_lane(impact)) {
      // the slip the pass started from: the velocities now less the pass's changes so far
      V ca[3], cb[3], va[3], vb[3];
      const auto F = L.again();
      F.arms(ca, cb);
      const V msum = F(F.c.ma) + F(F.c.mb);
      for (int i = 0; i < 3; ++i) va[i] = oa[i] - dwa[i], vb[i] = ob[i] - dwb[i];
      const V s0 = rel[0] - msum * impulse[0] + (vb[1] * cb[2] - vb[2] * cb[1]) - (va[1] * ca[2] - va[2] * ca[1]);
      const V s1 = rel[1] - msum * impulse[1] + (vb[2] * cb[0] - vb[0] * cb[2]) - (va[2] * ca[0] - va[0] * ca[2]);
      impact = impact & (s0 * s0 + s1 * s1 > splat<V>(p.carry_speed) * splat<V>(p.carry_speed));
    }
    if (any_lane(impact)) {
      // (nothing is written yet that the rounds, from this state, would not write the same)
      Carried<V, P> state;
      for (int i = 0; i < 3; ++i) {
        state.rel[i] = rel[i], state.oa[i] = oa[i], state.ob[i] = ob[i];
        state.dwa[i] = dwa[i], state.dwb[i] = dwb[i], state.impulse[i] = impulse[i];
      }
      for (int k = 0; k < P; ++k) {
        state.lambda[k] = lambda[k], state.largest[k] = largest[k];
        if constexpr (kPart == kFinish) {
          state.bias[k] = mid->bias[k], state.iscale[k] = mid->iscale[k];
          state.negm[k] = mid->negm[k], state.skip[k] = mid->skip[k];
        } else {
          state.bias[k] = bias[k], state.iscale[k] = iscale[k], state.negm[k] = negm[k], state.skip[k] = skip[k];
        }
      }
      state.tj[0] = tj[0], state.tj[1] = tj[1], state.total = total, state.impact = impact;
      if constexpr (kYmm) {
        // (those lanes' write bits cleared until their rounds: the rest of this half's pass
        // writes nothing of theirs that their rounds will not write again, or put back. A
        // four-point half with more than kDeferLanes such lanes has its rounds now: copying
        // a four-point lane to wait costs some 400 instructions, a rounds' call some 2,400,
        // and the 1240 pyramid's first steps land whole halves, whose waiting cost it 2.3%)
        constexpr int kDeferLanes = P == 1 ? 8 : 3;
        const bool wait = defer && (kDeferLanes >= 8 || lanes_set(impact) <= kDeferLanes);
        if (wait) defer_rounds<kMode>(*defer, c, l0, p, r, state);
        if (!wait) {
          solve_rounds<V, kMode, kZmm>(L, p, r, state);
          return;
        }
      } else {
        solve_rounds<V, kMode, kZmm>(L, p, r, state);
        return;
      }
    }
  } else {
    impact = from->impact;
    V keep_l[P], keep_big[P], keep_o[12], keep_rel[3], keep_imp[3], keep_tj[2] = {tj[0], tj[1]};
    const V keep_total = total;
    for (int k = 0; k < P; ++k) keep_l[k] = lambda[k], keep_big[k] = largest[k];
    for (int i = 0; i < 3; ++i) {
      keep_o[i] = oa[i], keep_o[3 + i] = ob[i], keep_o[6 + i] = dwa[i], keep_o[9 + i] = dwb[i];
      keep_rel[i] = rel[i], keep_imp[i] = impulse[i];
    }
    for (int it = 0; it <= p.sweeps; ++it) {
      normal_speeds();
      for (int k = 0; k < P; ++k) before[k] = lambda[k];
      sweep(std::true_type{});
      push(before);
      total = zero;
      if constexpr (kYmm && P == 1) total = lambda[0];  // (as above)
      else
        for (int k = 0; k < P; ++k) total = total + lambda[k];
      if (it < p.sweeps) friction();
    }
    for (int k = 0; k < P; ++k)
      lambda[k] = impact ? lambda[k] : keep_l[k], largest[k] = impact ? largest[k] : keep_big[k];
    for (int i = 0; i < 3; ++i) {
      oa[i] = impact ? oa[i] : keep_o[i], ob[i] = impact ? ob[i] : keep_o[3 + i];
      dwa[i] = impact ? dwa[i] : keep_o[6 + i], dwb[i] = impact ? dwb[i] : keep_o[9 + i];
      rel[i] = impact ? rel[i] : keep_rel[i], impulse[i] = impact ? impulse[i] : keep_imp[i];
    }
    for (int i = 0; i < 2; ++i) tj[i] = impact ? tj[i] : keep_tj[i];
    total = impact ? total : keep_total;
  }
  L.put(c.tangent_impulse[0], tj[0]);
  L.put(c.tangent_impulse[1], tj[1]);
  // twist friction about the normal, up to mu * total normal * mean lever arm (none for one point)
  if constexpr (P > 1) {
    const V radius = L(c.twist_radius);
    const V old = L(c.twist_impulse), limit = mu * total * radius;
    V j = vclamp(old - L(c.twist_mass) * (ob[2] - oa[2]), -limit, limit);
    j = radius > zero ? j : old;
    L.put(c.twist_impulse, j);
    // the turns e I^-1 n: the inverse inertias' third columns (xz, yz, zz)
    const V e = j - old;
    constexpr int kColumn[3] = {2, 4, 5};
    const auto F = L.again();
    for (int i = 0; i < 3; ++i)
      dwa[i] = dwa[i] - e * F(F.c.ia[kColumn[i]]), dwb[i] = dwb[i] + e * F(F.c.ib[kColumn[i]]);
  }
  // a one-point lane's rolling resistance, right after its friction (RigidContacts::roll's
  // arithmetic in the frame): an angular impulse against the relative turning, up to rolling *
  // total normal. Lanes that do not roll keep their velocities (selected, so that skipping
  // blocks in which no lane rolls changes no bits)
  if constexpr (P == 1) {
    if ((c.rolls >> l0) & kLaneBits<V>) {
      const V coefficient = L(c.rolling);
      const auto on = coefficient > zero;
      V m[6], old[3], rel[3], j[3];
      for (int i = 0; i < 6; ++i) m[i] = L(c.rolling_mass[i]);
      for (int i = 0; i < 3; ++i) old[i] = L(c.rolling_impulse[i]), rel[i] = ob[i] - oa[i];
      V mr[3];
      sym_mul(m, rel, mr);
      for (int i = 0; i < 3; ++i) j[i] = old[i] - mr[i];
      const V limit = coefficient * total, len = vsqrt(j[0] * j[0] + j[1] * j[1] + j[2] * j[2]);
      const auto over = len > limit;
      const V scale = over ? limit / len : one;
      V e[3], da[3], db[3], ia[6], ib[6];
      L.again().inertias(ia, ib);
      for (int i = 0; i < 3; ++i) {
        j[i] = over ? j[i] * scale : j[i];
        L.put(c.rolling_impulse[i], on ? j[i] : old[i]);
        e[i] = j[i] - old[i];
      }
      if constexpr (kYmm) {
        // (AVX2: side a's turn only where a lane writes side a: after the rolling nothing reads
        // oa, and dwa only side a's write-back)
        sym_mul(ib, e, db);
        for (int i = 0; i < 3; ++i)
          ob[i] = on ? ob[i] + db[i] : ob[i], dwb[i] = on ? dwb[i] + db[i] : dwb[i];
        if ((c.write_a >> l0) & kLaneBits<V>) {
          sym_mul(ia, e, da);
          for (int i = 0; i < 3; ++i)
            oa[i] = on ? oa[i] - da[i] : oa[i], dwa[i] = on ? dwa[i] - da[i] : dwa[i];
        }
      } else {
        sym_mul(ia, e, da);
        sym_mul(ib, e, db);
        for (int i = 0; i < 3; ++i) {
          oa[i] = on ? oa[i] - da[i] : oa[i], dwa[i] = on ? dwa[i] - da[i] : dwa[i];
          ob[i] = on ? ob[i] + db[i] : ob[i], dwb[i] = on ? dwb[i] + db[i] : dwb[i];
        }
      }
    }
  }
  for (int k = 0; k < P; ++k) {
    L.put(c.impulse[k], lambda[k]);
    L.put(c.max_impulse[k], largest[k]);
  }
  if constexpr (P == 1) {
    if (((c.write_a >> l0) & kLaneBits<V>) == 0) {
      // side a, which no lane writes (a static or kinematic body's), not formed: the
      // write-back below is left whole for the blocks that write both sides (a branch inside
      // it made the one-point kernel's registers worse: pyramid1240's one-point pass +4%)
      V pw[3], dwbw[3], nb[6];
      const auto F = L.again();
      F.frame(t1, t2, n);
      to_world(t1, t2, n, impulse, pw);
      to_world(t1, t2, n, dwb, dwbw);
      const V mb2 = F(F.c.mb);
      for (int i = 0; i < 3; ++i) nb[i] = mb2 * pw[i], nb[3 + i] = dwbw[i];
      add_rows<V, kZmm>(base, c.b + l0, c.write_b >> l0, nb);
      return;
    }
  }
  // the change back to the bodies, in world axes
  V pw[3], dwaw[3], dwbw[3];
  const auto F = L.again();
  F.frame(t1, t2, n);
  to_world(t1, t2, n, impulse, pw);
  to_world(t1, t2, n, dwa, dwaw);
  to_world(t1, t2, n, dwb, dwbw);
  V na[6], nb[6];
  const V ma2 = F(F.c.ma), mb2 = F(F.c.mb);
  for (int i = 0; i < 3; ++i) na[i] = -(ma2 * pw[i]), na[3 + i] = dwaw[i], nb[i] = mb2 * pw[i], nb[3 + i] = dwbw[i];
  add_rows<V, kZmm>(base, c.a + l0, c.write_a >> l0, na);
  add_rows<V, kZmm>(base, c.b + l0, c.write_b >> l0, nb);
}

template <class V, int kMode, bool kZmm, class B>
[[gnu::noinline]] void solve_rounds_plain(const Lanes<V, B>& L, const FloatParams& p, const BodyArrays& r,
                                          const Carried<V, B::kPoints>& from) {
  solve<V, kMode, kZmm, B, true>(L, p, r, &from);
}
#if defined(__GNUC__) && defined(__x86_64__)
template <class V, int kMode, bool kZmm, class B>
[[gnu::noinline]] __attribute__((target("avx2"))) void solve_rounds_avx2(const Lanes<V, B>& L, const FloatParams& p,
                                                                          const BodyArrays& r,
                                                                          const Carried<V, B::kPoints>& from) {
  solve<V, kMode, kZmm, B, true>(L, p, r, &from);
}
#endif
#if PBA_AVX512
template <class V, int kMode, bool kZmm, class B>
[[gnu::noinline]] __attribute__((target("avx512f"))) void solve_rounds_avx512(const Lanes<V, B>& L,
                                                                              const FloatParams& p,
                                                                              const BodyArrays& r,
                                                                              const Carried<V, B::kPoints>& from) {
  solve<V, kMode, kZmm, B, true>(L, p, r, &from);
}
#endif

template <class V, int kMode, bool kZmm, class B>
void solve_rounds(const Lanes<V, B>& L, const FloatParams& p, const BodyArrays& r, const Carried<V, B::kPoints>& from) {
#if defined(__GNUC__) && defined(__x86_64__)
  if constexpr (kZmm || std::is_same_v<V, v16f>) {
#if PBA_AVX512  // (else only the AVX-512 kernels, not built, would take this branch)
    solve_rounds_avx512<V, kMode, kZmm>(L, p, r, from);
    return;
#endif
  } else if constexpr (!std::is_arithmetic_v<V>) {
    solve_rounds_avx2<V, kMode, kZmm>(L, p, r, from);
    return;
  }
#endif
  solve_rounds_plain<V, kMode, kZmm>(L, p, r, from);
}

// the lanes' accumulated impulses added to the warm-start accumulators
template <class V, bool kZmm, class B>
PBA_LANES void warm(const Lanes<V, B>& L, const BodyArrays& r) {
  constexpr int P = B::kPoints;
  B& c = L.c;
  const int l0 = L.l0;
  const V zero = splat<V>(0);
  V t1[3], t2[3], n[3];
  L.frame(t1, t2, n);
  V sl = zero, sx = zero, sy = zero;
  for (int k = 0; k < P; ++k) {
    const V l = L(c.impulse[k]);
    sl = sl + l;
    if constexpr (P > 1) sx = sx + l * L(c.x[k]), sy = sy + l * L(c.y[k]);
  }
  const V j0 = L(c.tangent_impulse[0]), j1 = L(c.tangent_impulse[1]);
  const V ca[3] = {L(c.ca[0]), L(c.ca[1]), L(c.ca[2])}, cb[3] = {L(c.cb[0]), L(c.cb[1]), L(c.cb[2])};
  // the moments in the frame: the points', the friction's at the centroid, the twist (a
  // one-point lane: its point is the centroid, and it has no twist)
  V ta[3], tb[3];
  if constexpr (P > 1) {
    const V tw = L(c.twist_impulse);
    ta[0] = ca[1] * sl + sy - ca[2] * j1, ta[1] = -(ca[0] * sl + sx) + ca[2] * j0, ta[2] = ca[0] * j1 - ca[1] * j0 + tw;
    tb[0] = cb[1] * sl + sy - cb[2] * j1, tb[1] = -(cb[0] * sl + sx) + cb[2] * j0, tb[2] = cb[0] * j1 - cb[1] * j0 + tw;
  } else {
    ta[0] = ca[1] * sl - ca[2] * j1, ta[1] = -(ca[0] * sl) + ca[2] * j0, ta[2] = ca[0] * j1 - ca[1] * j0;
    tb[0] = cb[1] * sl - cb[2] * j1, tb[1] = -(cb[0] * sl) + cb[2] * j0, tb[2] = cb[0] * j1 - cb[1] * j0;
    // and the rolling resistance's angular impulse (lanes that roll)
    const auto on = L(c.rolling) > zero;
    for (int i = 0; i < 3; ++i) {
      const V roll = L(c.rolling_impulse[i]);
      ta[i] = on ? ta[i] + roll : ta[i], tb[i] = on ? tb[i] + roll : tb[i];
    }
  }
  if constexpr (P == 1) {
    if (((c.write_a >> l0) & kLaneBits<V>) == 0) {
      // side a, which no lane writes (a static or kinematic body's), not formed
      V ib[6], db[3], dbw[3], pw[3];
      for (int i = 0; i < 6; ++i) ib[i] = L(c.ib[i]);
      sym_mul(ib, tb, db);
      to_world(t1, t2, n, db, dbw);
      const V pf[3] = {j0, j1, sl};
      to_world(t1, t2, n, pf, pw);
      const V mb = L(c.mb);
      V nb[6];
      for (int i = 0; i < 3; ++i) nb[i] = mb * pw[i], nb[3 + i] = dbw[i];
      add_rows<V, kZmm>(r.warm[0].v, c.b + l0, c.write_b >> l0, nb);
      return;
    }
  }
  V ia[6], ib[6];
  for (int i = 0; i < 6; ++i) ia[i] = L(c.ia[i]), ib[i] = L(c.ib[i]);
  V da[3], db[3], daw[3], dbw[3], pw[3];
  sym_mul(ia, ta, da);
  sym_mul(ib, tb, db);
  to_world(t1, t2, n, da, daw);
  to_world(t1, t2, n, db, dbw);
  const V pf[3] = {j0, j1, sl};
  to_world(t1, t2, n, pf, pw);
  const V ma = L(c.ma), mb = L(c.mb);
  V na[6], nb[6];
  for (int i = 0; i < 3; ++i) na[i] = -(ma * pw[i]), na[3 + i] = -daw[i], nb[i] = mb * pw[i], nb[3 + i] = dbw[i];
  add_rows<V, kZmm>(r.warm[0].v, c.a + l0, c.write_a >> l0, na);
  add_rows<V, kZmm>(r.warm[0].v, c.b + l0, c.write_b >> l0, nb);
}

// the separations of the block's lanes [l0, l0 + width) in lanes of doubles D (outside the
// passes: TGS without relax iterations; the passes measure theirs in float, see pass())
template <class D, class B>
PBA_LANES void separations_of(B& c, const AnchorsOf<B::kPoints>& g, int l0, int width, const BodyArrays& r) {
  for (int l = l0; l < l0 + width; l += kWidth<D>) separations(Lanes<D, B>{c, l}, g, r);
}

// kPart: the whole pass, or the AVX2 path's part of it before the sweeps or after them (see
// pass_pair; the state between them in `mid`)
// (defer: solve()'s; kRounds: the rounds of lanes that waited, from `from`, then the rest of the
// pass: flush_rounds)
template <class V, class D, int kMode, class B, bool kRounds = false, int kPart = kWhole>
PBA_LANES void pass(B& c, const AnchorsOf<B::kPoints>& g, int l0, const FloatParams& p, const BodyArrays& r,
                    DeferredRounds<B>* defer = nullptr, const Carried<V, B::kPoints>* from = nullptr,
                    Swept<V, B::kPoints>* mid = nullptr) {
  const Lanes<V, B> L{c, l0};
  // the separations in float, on the pass's own lanes. Each is base + n.dp + the turned
  // anchors' terms, every term small (the step's overlap or gap, and the step's motion), so
  // float's rounding of it is about 2^-24 of those (1e-9 m for a resting box, 2.4e-7 m for the
  // 4 m step of a 250 m/s body), under the kTouching margin that already absorbs the float
  // velocities' rounding; the doubles cost two or four extra halves of a block and the
  // conversions to them (AVX2: 17.6% of the kernel's instructions, docs/benchmarks.md)
  if constexpr (!kRounds && kPart != kFinish)
    if (p.update_sep) separations(L, g, r);
  // (the AVX-512 path: kZmm widens rows with its one-instruction conversion)
  constexpr bool kZmm = std::is_same_v<D, v8d>;
  if constexpr (!kRounds) solve<V, kMode, kZmm, B, false, kPart>(L, p, r, nullptr, mid, defer);
  else solve_rounds<V, kMode, kZmm>(L, p, r, *from);
  if constexpr (kPart == kSetUp) return;
  // the soft step's and TGS's relax pass (cap_carry): a point carries to the next substep at most
  // kCarryGrowth times the impulse it solved the substep before, plus what holds its effective
  // mass against gravity for a substep. More is an impact's: the substep's impulse that
  // stopped a body landing (and the impulses that passed it down a pile) is no guess for the
  // next substep's, and the next substep's passes, one Gauss-Seidel sweep each over the
  // manifolds, cannot take it back: a 2 m cube landing at 3.1 m/s on the corners of four on
  // the ground rebounded at 0.43 m/s (e = 0; 0.27 m/s on four fixed ones), and the levels of
  // Jolt's pyramid were knocked sideways by up to 0.54 m. 1.5 and 2 times both hold the
  // stacking, sway and rocking tests (1 does not: a rocking column's impacts). The friction
  // and twist carried shrink with the normal impulse, so they stay within its cone. `last`
  // keeps the impulse as solved, before the cap
  if constexpr (kMode == kRelax)
    if (p.cap_carry) {
      const V zero = splat<V>(0);
      V all = zero, kept = zero;
      if (p.cap_total) {
        // TGS: the manifold's total, its points' shares kept. Its rigid contacts hold a load
        // by the carried impulse alone within the slop, and the one sweep a substep moves
        // the load between a face's corners: capped point by point, a corner that took none
        // in one substep carried almost none to the next, and Jolt's pyramid sank 3.4 cm.
        // Growing up to kCarryGrowthTgs times a substep (1.5 sank it 2.5 cm by its landings)
        V before = zero, hold = zero;
        for (int k = 0; k < B::kPoints; ++k) {
          const V l = L(c.impulse[k]);
          all = all + l, before = before + L(g.last[k]), hold = hold + L(c.mass[k]);
          L.put(g.last[k], l);
        }
        kept = vmin(all, before * splat<V>(kCarryGrowthTgs) + hold * splat<V>(p.carry_speed));
        const V share = all > zero ? kept / all : splat<V>(1);
        for (int k = 0; k < B::kPoints; ++k) L.put(c.impulse[k], L(c.impulse[k]) * share);
      } else {
        for (int k = 0; k < B::kPoints; ++k) {
          const V l = L(c.impulse[k]), before = L(g.last[k]);
          const V carried = vmin(l, before * splat<V>(kCarryGrowth) + L(c.mass[k]) * splat<V>(p.carry_speed));
          all = all + l, kept = kept + carried;
          L.put(c.impulse[k], carried);
          L.put(g.last[k], l);
        }
      }
      const V scale = all > zero ? kept / all : splat<V>(1);
      L.put(c.tangent_impulse[0], L(c.tangent_impulse[0]) * scale);
      L.put(c.tangent_impulse[1], L(c.tangent_impulse[1]) * scale);
      if constexpr (B::kPoints > 1) L.put(c.twist_impulse, L(c.twist_impulse) * scale);
    }
  if (p.warm_next) warm<V, kZmm>(L, r);
}

// the lines of a block that the start of its pass reads and the hardware's streamer does not
// foresee: the frame at the block's start, then the arms in its middle and the bodies' indices
// at its end (17 of its 84 lines). On the 2870-box pyramid, whose blocks come from beyond the
// L2, those loads held the most samples of the paired kernel over what the 1240-box pyramid's
// took; asked for one block ahead the kernel took 2-3% less time there, and about the same on
// the 1240 pyramid. Asking for the points and the anchors too (45 lines) gained nothing on the
// one and lost on the other (docs/benchmarks.md)
template <class B>
PBA_LANES void ask_set_up(const B& c) {
  auto lines = [](const void* from, std::size_t bytes) __attribute__((always_inline)) {
    for (std::size_t o = 0; o < bytes; o += 64) __builtin_prefetch(static_cast<const char*>(from) + o);
  };
  lines(c.t1, sizeof c.t1 + sizeof c.t2 + sizeof c.n);
  lines(c.ca, sizeof c.ca + sizeof c.cb);
  lines(c.a, sizeof c.a + sizeof c.b);
}

// the same for both halves of a block of 9 to 16 lanes on the AVX2 path: the set-up of each,
// then their sweeps interleaved point by point (two independent chains of some 22 cycles a
// point, which one after the other left the core idle), then the finish of each. Each lane
// does what pass() does, in the same order (the halves' manifolds share no body that either
// writes: they are of one colour)
// (`next`: the block after this one in the pass, or null; its first lines are asked for while
// the sweeps' chains leave the loads idle. defer: pass()'s)
template <class D, int kMode, class B>
PBA_LANES void pass_pair(B& c, const AnchorsOf<B::kPoints>& g, const FloatParams& p, const BodyArrays& r,
                         const B* next, DeferredRounds<B>* defer) {
  constexpr int P = B::kPoints;
  const Lanes<v8f, B> L[2] = {{c, 0}, {c, 8}};
  Swept<v8f, P> mid[2];
  for (int h = 0; h < 2; ++h) pass<v8f, D, kMode, B, false, kSetUp>(c, g, 8 * h, p, r, nullptr, nullptr, &mid[h]);
  if (next) ask_set_up(*next);
  // (the chains' numbers in arrays of their own, indexed by constants once the loops are
  // unrolled, so that they can live in registers: in the structs, GCC kept the loops and
  // every update went through memory)
  v8f vn[2][P], lambda[2][P], largest[2][P];
  for (int h = 0; h < 2; ++h)
    for (int k = 0; k < P; ++k) vn[h][k] = mid[h].vn[k], lambda[h][k] = mid[h].lambda[k], largest[h][k] = mid[h].largest[k];
  auto sweep = [&](auto last) __attribute__((always_inline)) {
    const Lanes<v8f, B> F[2] = {L[0].again(), L[1].again()};
#pragma GCC unroll 4
    for (int k = 0; k < P; ++k)
#pragma GCC unroll 2
      for (int h = 0; h < 2; ++h)
        sweep_point<kMode, true, decltype(last)::value>(F[h], k, vn[h], lambda[h], largest[h], mid[h].negm,
                                                        mid[h].bias, mid[h].iscale, mid[h].skip);
  };
  for (int it = 1; it < p.sweeps; ++it) sweep(std::false_type{});
  sweep(std::true_type{});
  for (int h = 0; h < 2; ++h)
    for (int k = 0; k < P; ++k) mid[h].lambda[k] = lambda[h][k], mid[h].largest[k] = largest[h][k];
  for (int h = 0; h < 2; ++h) pass<v8f, D, kMode, B, false, kFinish>(c, g, 8 * h, p, r, defer, nullptr, &mid[h]);
}

// which blocks the AVX2 path passes in interleaved halves (pass_pair)
template <class B>
constexpr bool kPairs = B::kPoints > 1;

#if defined(__GNUC__) && defined(__x86_64__)
// The lanes of a colour that land sliding, waiting for their rounds (see defer_rounds): each
// one's block fields and anchors' `last` as at its pass's friction, and its pass's state, copied
// into lane `count` of `block` and `state`; where each came from; its block's write bits, which
// are cleared there until the rounds write the lane back (set by pass_blocks, none of it zeroed
// there: it is made once a colour and pass, 1,800 times a step in pyramid1240, whose one-point
// lanes never land sliding)
template <class B>
struct DeferredRounds {
  B* blocks;
  const AnchorsOf<B::kPoints>* anchors;
  int count;
  bool clean;                          // block, anchors and state zeroed (at the first lane)
  std::uint32_t from[8];               // block index * kLanes + lane
  B block;                             // lanes [0, count); write_a, write_b (rolls): their bits
  AnchorsOf<B::kPoints> lasts;         // (`last` only)
  Carried<v8f, B::kPoints> state;
};

// lane `lane`'s 4-byte fields of kRows rows of kWidth (a block's or a Carried state's) into lane
// `at` (unrolled: a load and a store a row)
template <std::size_t kRows, std::size_t kWidth>
PBA_LANES void copy_lane(void* to, int at, const void* from, int lane) {
  unsigned char* const t = static_cast<unsigned char*>(to) + 4 * static_cast<std::size_t>(at);
  const unsigned char* const f = static_cast<const unsigned char*>(from) + 4 * static_cast<std::size_t>(lane);
#pragma GCC unroll 128
  for (std::size_t row = 0; row < kRows; ++row) std::memcpy(t + 4 * kWidth * row, f + 4 * kWidth * row, 4);
}
// (a block's rows of kLanes 4-byte fields up to its write bits; Carried's rows of 8)
template <class B>
inline constexpr std::size_t kBlockRows = offsetof(B, write_a) / (4 * kLanes);
// the row of a block's field at byte `offset`
constexpr std::size_t block_row(std::size_t offset) { return offset / (4 * kLanes); }
// Whether a waiting lane's rounds, cap and warm start read row r of its block (see
// defer_rounds): not impulse, tangent_impulse and max_impulse (the rounds write them before
// anything reads them), sep, slop and approach (only the set-up reads them), pair and unit (no
// kernel reads them), nor a one-point lane's k (its sweep updates no other point): 48 of a
// one-point lane's 58 rows, 62 of a four-point lane's 83
template <class B>
constexpr bool rounds_read(std::size_t r) {
  auto in = [r](std::size_t offset, std::size_t bytes) { return r >= block_row(offset) && r < block_row(offset + bytes); };
  if (in(offsetof(B, impulse), sizeof(B::impulse)) || in(offsetof(B, sep), sizeof(B::sep)) ||
      in(offsetof(B, slop), sizeof(B::slop)) || in(offsetof(B, tangent_impulse), sizeof(B::tangent_impulse)) ||
      in(offsetof(B, approach), sizeof(B::approach)) || in(offsetof(B, max_impulse), sizeof(B::max_impulse)) ||
      in(offsetof(B, pair), sizeof(B::pair)) || in(offsetof(B, unit), sizeof(B::unit)))
    return false;
  return B::kPoints > 1 || !in(offsetof(B, k), sizeof(B::k));
}
// (a field added to a block: say above whether a waiting lane's rounds read it)
static_assert(kBlockRows<OnePointBlock> == 58 && kBlockRows<ContactBlock> == 83);
// lane `lane`'s rows of its block that rounds_read names into lane `at` of `to`
template <class B, std::size_t... R>
PBA_LANES void copy_waiting_lane(B* to, int at, const B* from, int lane, std::index_sequence<R...>) {
  auto row = [&](auto r) __attribute__((always_inline)) {
    constexpr std::size_t kRow = decltype(r)::value;
    if constexpr (rounds_read<B>(kRow))
      copy_lane<1, kLanes>(reinterpret_cast<unsigned char*>(to) + 4 * kLanes * kRow, at,
                           reinterpret_cast<const unsigned char*>(from) + 4 * kLanes * kRow, lane);
  };
  (row(std::integral_constant<std::size_t, R>{}), ...);
}
static_assert(offsetof(OnePointBlock, write_a) % (4 * kLanes) == 0);
static_assert(offsetof(ContactBlock, write_a) % (4 * kLanes) == 0);
static_assert(sizeof(Carried<v8f, 1>) % sizeof(v8f) == 0 && sizeof(MaskOf<v8f>) == sizeof(v8f));
static_assert(sizeof(Carried<v8f, 4>) % sizeof(v8f) == 0);

// the waiting lanes' rounds, as solve_rounds would have run them in their own halves, then
// their relax pass's cap and their warm start; their fields put back into their blocks
template <int kMode, class B>
[[gnu::noinline]] PBA_DEFER_TARGET void flush_rounds(DeferredRounds<B>& d, const FloatParams& p, const BodyArrays& r) {
  constexpr int P = B::kPoints;
  if (d.count == 0) return;
  B& t = d.block;
  // (the lanes left select their own; a lane compare, not impact[m] = 0: GCC 12's sanitizer
  // build made a vector's element at a variable index element 0, see defer_rounds)
  const v8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
  d.state.impact = d.state.impact & (lane < d.count);
  pass<v8f, v4d, kMode, B, true>(t, d.lasts, 0, p, r, nullptr, &d.state);
  for (int m = 0; m < d.count; ++m) {
    B& c = d.blocks[d.from[m] / kLanes];
    const int l = static_cast<int>(d.from[m] % kLanes);
    for (int k = 0; k < P; ++k) {
      c.impulse[k][l] = t.impulse[k][m], c.max_impulse[k][l] = t.max_impulse[k][m];
      d.anchors[d.from[m] / kLanes].last[k][l] = d.lasts.last[k][m];
    }
    c.tangent_impulse[0][l] = t.tangent_impulse[0][m], c.tangent_impulse[1][l] = t.tangent_impulse[1][m];
    if constexpr (P == 1)
      for (int i = 0; i < 3; ++i) c.rolling_impulse[i][l] = t.rolling_impulse[i][m];
    else
      c.twist_impulse[l] = t.twist_impulse[m];  // (its half's pass went on to write one from before the rounds)
    c.write_a |= ((t.write_a >> m) & 1u) << l, c.write_b |= ((t.write_b >> m) & 1u) << l;
  }
  t.write_a = t.write_b = 0;
  if constexpr (P == 1) t.rolls = 0;
  d.count = 0;
}

template <int kMode, class B>
[[gnu::noinline]] PBA_DEFER_TARGET void defer_rounds(DeferredRounds<B>& d, B& c, int l0, const FloatParams& p,
                                                     const BodyArrays& r, const Carried<v8f, B::kPoints>& state) {
  constexpr int P = B::kPoints;
  // the waiting lanes' bits: the mask's sign bits (its lanes are 0 or -1). Not state.impact[q]
  // in a loop: the asan+UBSan build (GCC 12, -O2) read element 0 for every q, so that a half
  // whose first lane landed sent all eight to wait and one whose first did not sent none
  // (their rounds skipped): other bits than the scalar path's there, the release build's right
  const std::uint32_t bits = static_cast<std::uint32_t>(__builtin_ia32_movmskps256(reinterpret_cast<v8f>(state.impact)));
  if (d.count + __builtin_popcount(bits) > 8) flush_rounds<kMode>(d, p, r);
  if (!d.clean) {
    std::memset(static_cast<void*>(&d.block), 0, sizeof d.block);
    std::memset(static_cast<void*>(&d.lasts), 0, sizeof d.lasts);
    std::memset(static_cast<void*>(&d.state), 0, sizeof d.state);
    d.clean = true;
  }
  const std::size_t index = static_cast<std::size_t>(&c - d.blocks);
  // (the waiting lanes by their bits: a half that calls this has 1.3 such lanes on average in
  // the rain's landing, and the test of all eight bits took as long as a lane's bookkeeping)
  for (std::uint32_t left = bits; left != 0; left &= left - 1) {
    const int q = std::countr_zero(left);
    const int m = d.count++, l = l0 + q;
    copy_waiting_lane(&d.block, m, &c, l, std::make_index_sequence<kBlockRows<B>>{});
    copy_lane<sizeof state / sizeof(v8f), 8>(&d.state, m, &state, q);
    for (int k = 0; k < P; ++k) d.lasts.last[k][m] = d.anchors[index].last[k][l];
    d.from[m] = static_cast<std::uint32_t>(index * kLanes + static_cast<std::size_t>(l));
    const std::uint32_t lane = 1u << l;
    d.block.write_a |= ((c.write_a & lane) ? 1u : 0u) << m, d.block.write_b |= ((c.write_b & lane) ? 1u : 0u) << m;
    if constexpr (P == 1) d.block.rolls |= ((c.rolls & lane) ? 1u : 0u) << m;
    c.write_a &= ~lane, c.write_b &= ~lane;
  }
}
#endif

// blocks [first, last) on lanes of V, the separations on lanes of D (several parts of a block
// when they are narrower). No prefetch of the blocks' fields: the blocks of a colour lie one after another
// and the hardware's streamer fetches them; asking for all the lines of the next block at once
// stalled the loop on the full fill buffers (measured on the 2870-box pyramid: the whole run
// 7-8% faster without; the AVX2 path asks for one line of the next block, below, and its
// paired blocks for the 17 lines that start the next one's pass: ask_set_up)
template <class V, class D, int kMode, class B>
PBA_LANES void pass_blocks(B* blocks, const AnchorsOf<B::kPoints>* anchors, std::size_t first, std::size_t last,
                           const FloatParams& p, const BodyArrays& r) {
  // (the AVX2 pass over one colour's blocks: its lanes that land sliding solved eight at a time)
  constexpr bool kDefer = std::is_same_v<V, v8f>;
  struct None {};
  [[maybe_unused]] std::conditional_t<kDefer, DeferredRounds<B>, None> rounds;  // (not zeroed: see `clean`)
  DeferredRounds<B>* defer = nullptr;
  if constexpr (kDefer)
    if (p.defer) rounds.blocks = blocks, rounds.anchors = anchors, rounds.count = 0, rounds.clean = false, defer = &rounds;
  for (std::size_t i = first; i < last; ++i) {
    // a block of one lane (a colour of one manifold: a stack's) by the scalar lane, one of up
    // to eight by 8 floats (the same arithmetic in every lane, so the same bits)
    const int lanes = blocks[i].lanes;
    // (AVX2: the next block's count of lanes asked for, the one line read before the block's
    // fields from its start: the wait for it held 3.7% of the four-point kernel's samples on
    // pyramid1240, 0.7% with this)
    if constexpr (std::is_same_v<V, v8f>)
      if (i + 1 < last) __builtin_prefetch(&blocks[i + 1].lanes);
    if constexpr (std::is_same_v<V, float>) {
      for (int l = 0; l < lanes; ++l) pass<float, double, kMode>(blocks[i], anchors[i], l, p, r);
    } else if (lanes == 1) {
      pass<float, double, kMode>(blocks[i], anchors[i], 0, p, r);
    } else if (kWidth<V> == 16 && lanes <= 8) {
      pass<v8f, D, kMode>(blocks[i], anchors[i], 0, p, r);
    } else if constexpr (std::is_same_v<V, v8f> && kPairs<B>) {
      if (lanes > 8) pass_pair<D, kMode>(blocks[i], anchors[i], p, r, i + 1 < last ? &blocks[i + 1] : nullptr, defer);
      else pass<V, D, kMode>(blocks[i], anchors[i], 0, p, r, defer);
    } else {
      for (int l = 0; l < lanes; l += kWidth<V>) pass<V, D, kMode>(blocks[i], anchors[i], l, p, r, defer);
    }
  }
  if constexpr (kDefer)
    if (defer && rounds.count > 0) flush_rounds<kMode>(rounds, p, r);
}

template <class V, class D, class B>
PBA_LANES void pass_any(B* blocks, const AnchorsOf<B::kPoints>* anchors, std::size_t first, std::size_t last,
                        const PassParams& params, const BodyArrays& r) {
  const FloatParams p(params);
  if (!params.bias) pass_blocks<V, D, kRelax>(blocks, anchors, first, last, p, r);
  else if (params.soft) pass_blocks<V, D, kSoft>(blocks, anchors, first, last, p, r);
  else pass_blocks<V, D, kRigid>(blocks, anchors, first, last, p, r);
}

// each lane of the blocks [first, last): the warm start's accumulators on lanes of V, the
// separations on lanes of D
template <class V, class B>
PBA_LANES void warm_blocks(B* blocks, std::size_t first, std::size_t last, const BodyArrays& r) {
  for (std::size_t i = first; i < last; ++i) {
    const int lanes = blocks[i].lanes;
    if constexpr (kWidth<V> == 16) {  // AVX-512
      if (lanes <= 8) {
        warm<v8f, true>(Lanes<v8f, B>{blocks[i], 0}, r);
        continue;
      }
    }
    for (int l = 0; l < lanes; l += kWidth<V>) warm<V, kWidth<V> == 16>(Lanes<V, B>{blocks[i], l}, r);
  }
}
template <class D, class B>
PBA_LANES void separation_blocks(B* blocks, const AnchorsOf<B::kPoints>* anchors, std::size_t first, std::size_t last,
                                 const BodyArrays& r) {
  for (std::size_t i = first; i < last; ++i) separations_of<D>(blocks[i], anchors[i], 0, blocks[i].lanes, r);
}

// each point's normal relative velocity in the lanes of L (m/s), from the lanes' bodies'
// velocities va, vb and angular velocities wa, wb (world), into vn: the one formula of the
// approach speeds before the solve (approach_lanes) and the restitution pass's
// (normal_velocities_of), so both give the same bits
template <class V, class B>
PBA_LANES void point_normal_velocities(const Lanes<V, B>& L, const V* va, const V* wa, const V* vb, const V* wb,
                                       V (&vn)[B::kPoints]) {
  constexpr int P = B::kPoints;
  const B& c = L.c;
  V t1[3], t2[3], n[3], rel[3], oa[3], ob[3];
  L.frame(t1, t2, n);
  const V dv[3] = {vb[0] - va[0], vb[1] - va[1], vb[2] - va[2]};
  to_frame(t1, t2, n, dv, rel);
  to_frame(t1, t2, n, wa, oa);
  to_frame(t1, t2, n, wb, ob);
  const V g = rel[2] + (ob[0] * L(c.cb[1]) - ob[1] * L(c.cb[0])) - (oa[0] * L(c.ca[1]) - oa[1] * L(c.ca[0]));
  if constexpr (P > 1)
    for (int k = 0; k < P; ++k) vn[k] = g + L(c.y[k]) * (ob[0] - oa[0]) - L(c.x[k]) * (ob[1] - oa[1]);
  else
    vn[0] = g;
}

// the approach speeds of the lanes [l0, l0 + width) of the lane type V at once
// (point_normal_velocities' operations in its order on each lane: the same bits on every path), into the block's
// approach speeds for the lanes below `filled` and the points below each lane's count (0 past
// it; the lanes past `filled` keep clear_lane's zeros)
template <class V, class B>
PBA_LANES void approach_lanes(B& c, int l0, int filled, const int* count, const BodyArrays& bodies) {
  constexpr int P = B::kPoints;
  V ra[8], rb[8];
  // each lane's bodies' rows: v, then w (SolverBody)
  const double* rows = bodies.bodies[0].v;
  load_rows<V>(rows, c.a + l0, ra);
  load_rows<V>(rows, c.b + l0, rb);
  V vn[P];
  point_normal_velocities(Lanes<V, B>{c, l0}, ra, ra + 3, rb, rb + 3, vn);
  if constexpr (std::is_same_v<V, v4d>) {
    // a whole four (AVX2): each point's four speeds rounded to floats at once, +0 past each
    // lane's count, the values of the loop below (which took some 16 instructions a manifold,
    // a lane and a point at a time, in the pyramids' prepare)
    if (l0 + 4 <= filled) {
      typedef float F __attribute__((vector_size(16)));
      typedef int I __attribute__((vector_size(16)));
      I points;
      std::memcpy(&points, count + l0, sizeof points);
      for (int k = 0; k < P; ++k) {
        const F speed = __builtin_convertvector(vn[k], F);
        const F out = std::bit_cast<F>(std::bit_cast<I>(speed) & (points > k));
        std::memcpy(c.approach[k] + l0, &out, sizeof out);
      }
      return;
    }
  }
  for (int j = 0; j < kWidth<V> && l0 + j < filled; ++j)
    for (int k = 0; k < P; ++k) c.approach[k][l0 + j] = k < count[l0 + j] ? static_cast<Real>(lanes::get(vn[k], j)) : 0;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// the paths' entry points: templates over the block kind, B (ContactBlock or OnePointBlock),
// each instantiated in a file of its own, a path and a block kind a file
// (contact_wide_avx2.cpp, contact_wide_avx2_one.cpp, contact_wide_avx512.cpp,
// contact_wide_avx512_one.cpp), so that the build compiles them side by side

#if defined(__GNUC__) && defined(__x86_64__)
#define PBA_RIGID_HAVE_X86 1
#if PBA_AVX512
/// One pass over the blocks [first, last) with 16 floats (8 on blocks of up to 8 lanes).
template <class B>
__attribute__((target("avx512f"))) void pass_avx512(B* blocks, const AnchorsOf<B::kPoints>* anchors, std::size_t first,
                                                   std::size_t last, const PassParams& p, const BodyArrays& r) {
  pass_any<v16f, v8d>(blocks, anchors, first, last, p, r);
}
/// The warm start's accumulators of the blocks [first, last) with 16 floats.
template <class B>
__attribute__((target("avx512f"))) void warm_avx512(B* blocks, std::size_t first, std::size_t last,
                                                    const BodyArrays& r) {
  warm_blocks<v16f>(blocks, first, last, r);
}
/// The separations of the blocks [first, last) with 8 doubles.
template <class B>
__attribute__((target("avx512f"))) void separation_avx512(B* blocks, const AnchorsOf<B::kPoints>* anchors,
                                                         std::size_t first, std::size_t last, const BodyArrays& r) {
  separation_blocks<v8d>(blocks, anchors, first, last, r);
}
/// The approach speeds (m/s) of the block's first `filled` lanes with 8 doubles.
template <class B>
__attribute__((target("avx512f"))) void approaches_avx512(B& c, int filled, const int* count, const BodyArrays& r) {
  for (int l0 = 0; l0 < filled; l0 += 8) approach_lanes<v8d>(c, l0, filled, count, r);
}
#endif
/// One pass over the blocks [first, last) with 8 floats.
template <class B>
__attribute__((target("avx2"))) void pass_avx2(B* blocks, const AnchorsOf<B::kPoints>* anchors, std::size_t first,
                                              std::size_t last, const PassParams& p, const BodyArrays& r) {
  pass_any<v8f, v4d>(blocks, anchors, first, last, p, r);
}
/// The warm start's accumulators of the blocks [first, last) with 8 floats.
template <class B>
__attribute__((target("avx2"))) void warm_avx2(B* blocks, std::size_t first, std::size_t last, const BodyArrays& r) {
  warm_blocks<v8f>(blocks, first, last, r);
}
/// The separations of the blocks [first, last) with 4 doubles.
template <class B>
__attribute__((target("avx2"))) void separation_avx2(B* blocks, const AnchorsOf<B::kPoints>* anchors, std::size_t first,
                                                    std::size_t last, const BodyArrays& r) {
  separation_blocks<v4d>(blocks, anchors, first, last, r);
}
/// The approach speeds (m/s) of the block's first `filled` lanes with 4 doubles.
template <class B>
__attribute__((target("avx2"))) void approaches_avx2(B& c, int filled, const int* count, const BodyArrays& r) {
  for (int l0 = 0; l0 < filled; l0 += 4) approach_lanes<v4d>(c, l0, filled, count, r);
}

// a path's four entry points for one block kind B with anchors A: `extern` here (no file that
// includes this header instantiates them), nothing in the path's file (there, once)
#define PBA_CONTACT_PATH(EXTERN, PATH, B, A)                                                                     \
  EXTERN template void pass_##PATH(B*, const A*, std::size_t, std::size_t, const PassParams&, const BodyArrays&); \
  EXTERN template void warm_##PATH(B*, std::size_t, std::size_t, const BodyArrays&);                               \
  EXTERN template void separation_##PATH(B*, const A*, std::size_t, std::size_t, const BodyArrays&);              \
  EXTERN template void approaches_##PATH(B&, int, const int*, const BodyArrays&)
PBA_CONTACT_PATH(extern, avx2, ContactBlock, AnchorBlock);
PBA_CONTACT_PATH(extern, avx2, OnePointBlock, OnePointAnchors);
#if PBA_AVX512
PBA_CONTACT_PATH(extern, avx512, ContactBlock, AnchorBlock);
PBA_CONTACT_PATH(extern, avx512, OnePointBlock, OnePointAnchors);
#endif
#else
#define PBA_RIGID_HAVE_X86 0
#endif

}  // namespace pba::detail
