// The XPBD solver: substeps of predict, constraint projection (distance constraints by
// colour and run, then tetrahedron volumes), collisions and the velocity update. The
// long-range attachments (tethers) it projects after the constraints are in tethers.cpp.
//
// Macklin, Mueller & Chentanez 2016, "XPBD: position-based simulation of compliant
// constrained dynamics", eq. 18 (the multiplier update). Constraint damping is not their
// eq. 26 (a damping term in the same update: with one sweep per substep on a chain of
// strong dampers each damper held the length its constraint started the substep with,
// the unconverged stretch accumulated and the energy rose, +480 J in 1 s on a 1 kg rope)
// but an implicit dashpot impulse per constraint on the velocities at the start of each
// substep, which can only remove energy (damp_sweep);
// Macklin, Storey, Lu, Terdiman, Chentanez, Jeschke & Mueller 2019, "Small steps in
// physics simulation" (substeps with one iteration, multipliers reset each substep).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

#include "core/clones.h"
#include "soft_impl.h"

namespace pba {

namespace {

using detail::Run;
using detail::RunType;

// Everything one substep's projection needs, as plain pointers and values.
struct SolveArgs {
  float* x;
  float* y;
  float* z;
  float* vx;  // velocities (m/s), for the dashpots
  float* vy;
  float* vz;
  const float* w;
  const std::uint32_t* ca;
  const std::uint32_t* cb;
  const float* rest;
  float* lambda;
  const Run* runs;
  std::size_t n_runs;
  float at[3];      // alpha / h^2 per constraint kind
  float inv_ch[3];  // 1 / (c h) per kind, the dashpots' slack (0: infinitely strong); infinity: undamped
  bool avx2;       // use the AVX2 interleaved kernels
};

// One distance constraint C = |x_b - x_a| - l0 (eq. 18):
//   dlambda = (-C - at lambda) / (w_a + w_b + at)
//   x_a -= w_a dlambda n,  x_b += w_b dlambda n,  n = (x_b - x_a)/l.
// Written as s = dlambda / l so one division serves both; masked (s = 0) when the
// constraint is broken (rest <= 0), degenerate (l = 0) or between two pinned particles.
//
// Rigid constraints (alpha = 0) use the squared form C' = (l^2 - l0^2)/(2 l0)
// instead: the same zero set, with the exact gradient d / l0, so one PBD step is
//   s = (l0^2 - l^2) / (2 (w_a + w_b) l^2),  x_a -= w_a s d,  x_b += w_b s d,
// a Newton step that needs one division and no square root (the sqrt-free projection of
// Jakobsen 2001, "Advanced character physics"); it differs from the exact step by the
// factor (l + l0)/(2 l) = 1 + O(strain), and converges to the same l = l0.
template <bool kLambda, bool kRigid = false>
PBA_SOFT_INLINE void project(float& xa, float& ya, float& za, float& xb, float& yb, float& zb, float wa, float wb,
                             float r, float* lam, float at) {
  const float dx = xb - xa, dy = yb - ya, dz = zb - za;
  const float l2 = dx * dx + dy * dy + dz * dz;
  if constexpr (kRigid) {
    (void)lam, (void)at;
    const float q = (wa + wb) * l2;
    const float s = (q > 0.0f && r > 0.0f) ? (r * r - l2) / (q + q) : 0.0f;
    const float sa = wa * s, sb = wb * s;
    xa -= sa * dx, ya -= sa * dy, za -= sa * dz;
    xb += sb * dx, yb += sb * dy, zb += sb * dz;
    return;
  }
  const float l = std::sqrt(l2);
  const float wsum = wa + wb;
  float c = l - r;
  if constexpr (kLambda) c += at * *lam;
  const float q = (wsum + at) * l;
  const float s = (q > 0.0f && r > 0.0f && wsum > 0.0f) ? -c / q : 0.0f;
  if constexpr (kLambda) *lam += s * l;
  const float sa = wa * s, sb = wb * s;
  xa -= sa * dx, ya -= sa * dy, za -= sa * dz;
  xb += sb * dx, yb += sb * dy, zb += sb * dz;
}

// One dashpot of damping c along the constraint: the implicit impulse P = -c h u' on the
// relative velocity u = (v_b - v_a) . n leaves u' = u / (1 + c h (w_a + w_b)). The
// dashpots of a body solve that together, (J M^-1 J^T + 1 / (c h)) P = -J v, by
// Gauss-Seidel sweeps with the impulses accumulated (P = acc l, d = x_b - x_a, W = w_a + w_b,
// `slack` = 1/(c h), 0 for an infinitely strong damper):
//   s = -(d . (v_b - v_a) + slack acc l^2) / ((W + slack) l^2),  acc += s,
//   v_a -= w_a s d,  v_b += w_b s d
// (no square root, one division; the first sweep's acc is 0: u' = u / (1 + c h W)). Each
// step lowers the convex Phi(P) = P^T (J M^-1 J^T + 1/(c h)) P / 2 + P^T J v, from
// Phi(0) = 0, and the kinetic energy after the impulses is KE + Phi(P) - |P|^2 / (2 c h):
// whatever the order and the number of sweeps, the dashpots only remove energy, and they
// never move a particle. Masked as project() is.
PBA_SOFT_INLINE void dashpot(float xa, float ya, float za, float xb, float yb, float zb, float& vxa, float& vya,
                             float& vza, float& vxb, float& vyb, float& vzb, float wa, float wb, float r,
                             float slack, float& acc) {
  const float dx = xb - xa, dy = yb - ya, dz = zb - za;
  const float l2 = dx * dx + dy * dy + dz * dz;
  const float ddot = dx * (vxb - vxa) + dy * (vyb - vya) + dz * (vzb - vza);
  const float wsum = wa + wb;
  const float q = (wsum + slack) * l2;
  const float num = ddot + slack * acc * l2;
  const float s = (q > 0.0f && r > 0.0f && wsum > 0.0f) ? -num / q : 0.0f;
  acc += s;
  const float sa = wa * s, sb = wb * s;
  vxa -= sa * dx, vya -= sa * dy, vza -= sa * dz;
  vxb += sb * dx, vyb += sb * dy, vzb += sb * dz;
}

// a contiguous run: constraint k joins a0 + k and a0 + k + offset; the two index ranges
// are disjoint (a colour touches a particle once), hence the restrict pointers
template <bool kLambda, bool kUniform, bool kRigid>
PBA_SOFT_INLINE void run_contiguous(int n, float* PBA_SOFT_RESTRICT xa, float* PBA_SOFT_RESTRICT ya,
                                    float* PBA_SOFT_RESTRICT za, float* PBA_SOFT_RESTRICT xb,
                                    float* PBA_SOFT_RESTRICT yb, float* PBA_SOFT_RESTRICT zb,
                                    const float* PBA_SOFT_RESTRICT wa, const float* PBA_SOFT_RESTRICT wb,
                                    const float* PBA_SOFT_RESTRICT rest, float ru, float* PBA_SOFT_RESTRICT lam,
                                    float at) {
  for (int k = 0; k < n; ++k) {
    float dummy = 0;
    project<kLambda, kRigid>(xa[k], ya[k], za[k], xb[k], yb[k], zb[k], wa[k], wb[k], kUniform ? ru : rest[k],
                             kLambda ? lam + k : &dummy, at);
  }
}

// an interleaved run: groups of 2L particles, the first L joined to the next L
template <int L, bool kLambda, bool kUniform, bool kRigid>
PBA_SOFT_INLINE void run_interleaved(int groups, float* PBA_SOFT_RESTRICT x, float* PBA_SOFT_RESTRICT y,
                                     float* PBA_SOFT_RESTRICT z, const float* PBA_SOFT_RESTRICT w,
                                     const float* PBA_SOFT_RESTRICT rest, float ru, float* PBA_SOFT_RESTRICT lam,
                                     float at) {
  for (int g = 0; g < groups; ++g) {
    for (int j = 0; j < L; ++j) {
      const int a = g * 2 * L + j, b = a + L, c = g * L + j;
      float dummy = 0;
      project<kLambda, kRigid>(x[a], y[a], z[a], x[b], y[b], z[b], w[a], w[b], kUniform ? ru : rest[c],
                               kLambda ? lam + c : &dummy, at);
    }
  }
}

// the particles (a, b) of constraint k of a run, and its rest length (<= 0: broken)
inline void run_ends(const Run& run, const std::uint32_t* ca, const std::uint32_t* cb, int k, std::uint32_t& a,
                     std::uint32_t& b) {
  const auto kk = static_cast<std::uint32_t>(k);
  switch (run.type) {
    case RunType::Contiguous: a = run.a0 + kk, b = a + run.offset; break;
    case RunType::Interleaved: a = run.a0 + (kk / run.offset) * 2 * run.offset + kk % run.offset, b = a + run.offset; break;
    case RunType::Indexed: a = ca[run.c0 + kk], b = cb[run.c0 + kk]; break;
  }
}

#if defined(__GNUC__) && defined(__x86_64__)
#define PBA_SOFT_HAVE_AVX2 1
#define PBA_SOFT_AVX2_INLINE inline __attribute__((target("avx2"), always_inline))

// The a and b particles of 8 constraints. L = 0 (contiguous runs): 8 consecutive floats
// at a + k and at b + k. L = 1, 2 (interleaved runs): 16 consecutive floats from a + 2k,
// deinterleaved with in-lane shuffles, which leave the constraints in lane order
// [0 1 4 5 2 3 6 7].
template <int L>
PBA_SOFT_AVX2_INLINE void load_ab(const float* base, std::uint32_t a, std::uint32_t b, int k, __m256& va,
                                  __m256& vb) {
  if constexpr (L == 0) {
    va = _mm256_loadu_ps(base + a + k);
    vb = _mm256_loadu_ps(base + b + k);
  } else {
    (void)b;
    const __m256 lo = _mm256_loadu_ps(base + a + 2 * k), hi = _mm256_loadu_ps(base + a + 2 * k + 8);
    va = _mm256_shuffle_ps(lo, hi, L == 1 ? 0x88 : 0x44);
    vb = _mm256_shuffle_ps(lo, hi, L == 1 ? 0xDD : 0xEE);
  }
}
// and back (a's window first: in a contiguous tail, b's window may overlap lanes of a's
// that a does not own, and b's values must be the ones that stay)
template <int L>
PBA_SOFT_AVX2_INLINE void store_ab(float* base, std::uint32_t a, std::uint32_t b, int k, __m256 va, __m256 vb) {
  if constexpr (L == 0) {
    _mm256_storeu_ps(base + a + k, va);
    _mm256_storeu_ps(base + b + k, vb);
  } else if constexpr (L == 1) {
    (void)b;
    _mm256_storeu_ps(base + a + 2 * k, _mm256_unpacklo_ps(va, vb));
    _mm256_storeu_ps(base + a + 2 * k + 8, _mm256_unpackhi_ps(va, vb));
  } else {
    (void)b;
    _mm256_storeu_ps(base + a + 2 * k, _mm256_shuffle_ps(va, vb, 0x44));
    _mm256_storeu_ps(base + a + 2 * k + 8, _mm256_shuffle_ps(va, vb, 0xEE));
  }
}
// per-constraint values in the lanes' constraint order: for interleaved runs swap the
// middle 64-bit halves ([0 1 2 3 4 5 6 7] <-> [0 1 4 5 2 3 6 7]; its own inverse)
template <int L>
PBA_SOFT_AVX2_INLINE __m256 perm(__m256 v) {
  if constexpr (L == 0) return v;
  else return _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(v), 0xD8));
}
// the new value in the lanes the group owns, the loaded one elsewhere (tails only)
template <bool kTail>
PBA_SOFT_AVX2_INLINE __m256 keep(__m256 old, __m256 now, __m256 own) {
  if constexpr (kTail) return _mm256_blendv_ps(old, now, own);
  else return (void)old, (void)own, now;
}

// The two ends of 8 constraints: positions, inverse masses, rest lengths (0 in the lanes a
// tail group does not own, so s = 0 there), d = x_b - x_a and |d|^2.
struct Ends8 {
  __m256 xa, xb, ya, yb, za, zb, wa, wb, r, dx, dy, dz, l2;
};
template <int L, bool kUniform, bool kTail>
PBA_SOFT_AVX2_INLINE Ends8 load_ends(int k, __m256 own, const float* x, const float* y, const float* z,
                                     const float* w, std::uint32_t a, std::uint32_t b, const float* rest, float ru) {
  Ends8 e;
  load_ab<L>(x, a, b, k, e.xa, e.xb);
  load_ab<L>(y, a, b, k, e.ya, e.yb);
  load_ab<L>(z, a, b, k, e.za, e.zb);
  load_ab<L>(w, a, b, k, e.wa, e.wb);
  e.r = kUniform ? _mm256_set1_ps(ru) : perm<L>(_mm256_loadu_ps(rest + k));
  if constexpr (kTail) e.r = _mm256_and_ps(e.r, own);
  else (void)own;
  e.dx = _mm256_sub_ps(e.xb, e.xa), e.dy = _mm256_sub_ps(e.yb, e.ya), e.dz = _mm256_sub_ps(e.zb, e.za);
  e.l2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(e.dx, e.dx), _mm256_mul_ps(e.dy, e.dy)), _mm256_mul_ps(e.dz, e.dz));
  return e;
}
// col_a -= sa d and col_b += sb d in the lanes the group owns, stored back
template <int L, bool kTail>
PBA_SOFT_AVX2_INLINE void move_ends(float* col, std::uint32_t a, std::uint32_t b, int k, __m256 va, __m256 vb, __m256 sa,
                                    __m256 sb, __m256 d, __m256 own) {
  store_ab<L>(col, a, b, k, keep<kTail>(va, _mm256_sub_ps(va, _mm256_mul_ps(sa, d)), own),
              keep<kTail>(vb, _mm256_add_ps(vb, _mm256_mul_ps(sb, d)), own));
}

// 8 constraints k .. k+7 of a contiguous (L = 0) or interleaved (L = 1, 2) run with
// exactly the scalar project()'s operations in the same order (no fused multiply-adds;
// sqrt and division are correctly rounded), so both give the same bits. a and b are the
// first particles of the run's a and b ends (b unused when L > 0). A tail group (kTail)
// owns only the constraint lanes in `own` (in lane order): it still loads and stores
// whole windows (the columns are padded by kSoftPad) but gives s = 0 to the other lanes
// and writes back exactly the values it loaded there, which is much faster than masked
// moves (microcoded on AMD).
template <int L, bool kLambda, bool kUniform, bool kRigid, bool kTail>
PBA_SOFT_AVX2_INLINE void group_avx2(int k, __m256 own, float* x, float* y, float* z, const float* w,
                                     std::uint32_t a, std::uint32_t b, const float* rest, float ru, float* lam,
                                     float at_s) {
  const __m256 zero = _mm256_setzero_ps();
  // the scalar project(), lane by lane
  const Ends8 e = load_ends<L, kUniform, kTail>(k, own, x, y, z, w, a, b, rest, ru);
  const __m256 wa = e.wa, wb = e.wb, r = e.r, l2 = e.l2;
  __m256 s, l = zero, lv = zero;
  if constexpr (kRigid) {
    (void)at_s, (void)lam;
    const __m256 q = _mm256_mul_ps(_mm256_add_ps(wa, wb), l2);
    const __m256 ok = _mm256_and_ps(_mm256_cmp_ps(q, zero, _CMP_GT_OQ), _mm256_cmp_ps(r, zero, _CMP_GT_OQ));
    s = _mm256_blendv_ps(zero, _mm256_div_ps(_mm256_sub_ps(_mm256_mul_ps(r, r), l2), _mm256_add_ps(q, q)), ok);
  } else {
    const __m256 sign = _mm256_set1_ps(-0.0f), at = _mm256_set1_ps(at_s);
    l = _mm256_sqrt_ps(l2);
    const __m256 wsum = _mm256_add_ps(wa, wb);
    __m256 c = _mm256_sub_ps(l, r);
    if constexpr (kLambda) {
      lv = perm<L>(_mm256_loadu_ps(lam + k));
      c = _mm256_add_ps(c, _mm256_mul_ps(at, lv));
    }
    const __m256 q = _mm256_mul_ps(_mm256_add_ps(wsum, at), l);
    const __m256 ok = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(q, zero, _CMP_GT_OQ), _mm256_cmp_ps(r, zero, _CMP_GT_OQ)),
                                    _mm256_cmp_ps(wsum, zero, _CMP_GT_OQ));
    s = _mm256_blendv_ps(zero, _mm256_div_ps(_mm256_xor_ps(c, sign), q), ok);
  }
  if constexpr (kLambda && !kRigid)
    _mm256_storeu_ps(lam + k, perm<L>(keep<kTail>(lv, _mm256_add_ps(lv, _mm256_mul_ps(s, l)), own)));
  const __m256 sa = _mm256_mul_ps(wa, s), sb = _mm256_mul_ps(wb, s);
  move_ends<L, kTail>(x, a, b, k, e.xa, e.xb, sa, sb, e.dx, own);
  move_ends<L, kTail>(y, a, b, k, e.ya, e.yb, sa, sb, e.dy, own);
  move_ends<L, kTail>(z, a, b, k, e.za, e.zb, sa, sb, e.dz, own);
}

// 8 dashpots k .. k+7 of a run, as group_avx2 addresses them, with exactly the scalar
// dashpot()'s operations in the same order: the same bits. Positions are read, only the
// velocities are written (their columns padded by kSoftPad too).
template <int L, bool kUniform, bool kTail>
PBA_SOFT_AVX2_INLINE void dash_group_avx2(int k, __m256 own, const float* x, const float* y, const float* z,
                                          float* vx, float* vy, float* vz, const float* w, std::uint32_t a,
                                          std::uint32_t b, const float* rest, float ru, float slack, float* acc) {
  const __m256 zero = _mm256_setzero_ps();
  const Ends8 e = load_ends<L, kUniform, kTail>(k, own, x, y, z, w, a, b, rest, ru);
  const __m256 wa = e.wa, wb = e.wb, r = e.r, l2 = e.l2, dx = e.dx, dy = e.dy, dz = e.dz;
  __m256 uxa, uxb, uya, uyb, uza, uzb;
  load_ab<L>(vx, a, b, k, uxa, uxb);
  load_ab<L>(vy, a, b, k, uya, uyb);
  load_ab<L>(vz, a, b, k, uza, uzb);
  const __m256 ddot = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, _mm256_sub_ps(uxb, uxa)),
                                                  _mm256_mul_ps(dy, _mm256_sub_ps(uyb, uya))),
                                    _mm256_mul_ps(dz, _mm256_sub_ps(uzb, uza)));
  const __m256 wsum = _mm256_add_ps(wa, wb), sl = _mm256_set1_ps(slack);
  const __m256 q = _mm256_mul_ps(_mm256_add_ps(wsum, sl), l2);
  const __m256 av = perm<L>(_mm256_loadu_ps(acc + k));
  const __m256 num = _mm256_add_ps(ddot, _mm256_mul_ps(_mm256_mul_ps(sl, av), l2));
  const __m256 ok = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(q, zero, _CMP_GT_OQ), _mm256_cmp_ps(r, zero, _CMP_GT_OQ)),
                                  _mm256_cmp_ps(wsum, zero, _CMP_GT_OQ));
  const __m256 s = _mm256_blendv_ps(zero, _mm256_div_ps(_mm256_xor_ps(num, _mm256_set1_ps(-0.0f)), q), ok);
  _mm256_storeu_ps(acc + k, perm<L>(keep<kTail>(av, _mm256_add_ps(av, s), own)));
  const __m256 sa = _mm256_mul_ps(wa, s), sb = _mm256_mul_ps(wb, s);
  move_ends<L, kTail>(vx, a, b, k, uxa, uxb, sa, sb, dx, own);
  move_ends<L, kTail>(vy, a, b, k, uya, uyb, sa, sb, dy, own);
  move_ends<L, kTail>(vz, a, b, k, uza, uzb, sa, sb, dz, own);
}

// the lanes a tail group owns: constraint j < n - k, in lane order for interleaved runs
template <int L>
PBA_SOFT_AVX2_INLINE __m256 tail_lanes(int n, int k) {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  return perm<L>(_mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(n - k), lane)));
}

// A whole run with AVX2: groups of 8, then one tail group for the rest.
template <int L, bool kLambda, bool kUniform, bool kRigid>
__attribute__((target("avx2"))) void run_avx2(int n, float* x, float* y, float* z, const float* w, std::uint32_t a,
                                               std::uint32_t b, const float* rest, float ru, float* lam, float at) {
  int k = 0;
  for (; k + 8 <= n; k += 8)
    group_avx2<L, kLambda, kUniform, kRigid, false>(k, _mm256_setzero_ps(), x, y, z, w, a, b, rest, ru, lam, at);
  if (k < n) group_avx2<L, kLambda, kUniform, kRigid, true>(k, tail_lanes<L>(n, k), x, y, z, w, a, b, rest, ru, lam, at);
}

// A whole run of dashpots with AVX2.
template <int L, bool kUniform>
__attribute__((target("avx2"))) void dash_run_avx2(int n, const float* x, const float* y, const float* z, float* vx,
                                                    float* vy, float* vz, const float* w, std::uint32_t a,
                                                    std::uint32_t b, const float* rest, float ru, float slack,
                                                    float* acc) {
  int k = 0;
  for (; k + 8 <= n; k += 8)
    dash_group_avx2<L, kUniform, false>(k, _mm256_setzero_ps(), x, y, z, vx, vy, vz, w, a, b, rest, ru, slack, acc);
  if (k < n)
    dash_group_avx2<L, kUniform, true>(k, tail_lanes<L>(n, k), x, y, z, vx, vy, vz, w, a, b, rest, ru, slack, acc);
}

// true when the CPU runs AVX2 (asked once)
bool has_avx2() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
}
#else
#define PBA_SOFT_HAVE_AVX2 0
#endif

// an indexed run (any mesh): scalar, through the index arrays
template <bool kLambda>
PBA_SOFT_INLINE void run_indexed(int n, float* x, float* y, float* z, const float* w, const std::uint32_t* ca,
                                 const std::uint32_t* cb, const float* rest, float* lam, float at) {
  for (int k = 0; k < n; ++k) {
    const std::uint32_t a = ca[k], b = cb[k];
    float dummy = 0;
    project<kLambda>(x[a], y[a], z[a], x[b], y[b], z[b], w[a], w[b], rest[k], kLambda ? lam + k : &dummy, at);
  }
}

// one Gauss-Seidel sweep over every run, in solver order
template <bool kLambda, bool kUniform, bool kRigid>
PBA_SOFT_INLINE void solve_run(const SolveArgs& s, const Run& run) {
  const int kind = static_cast<int>(run.kind);
  const float at = s.at[kind], ru = run.rest;
  const float* rest = s.rest + run.c0;
  float* lam = s.lambda + run.c0;
  const int n = static_cast<int>(run.count);
  const std::uint32_t a = run.a0, b = run.a0 + run.offset;
  // contiguous and interleaved runs with AVX2 when the CPU has it, else scalar; the same bits
#if PBA_SOFT_HAVE_AVX2
  if (s.avx2 && run.type != RunType::Indexed) {
    if (run.type == RunType::Contiguous)
      run_avx2<0, kLambda, kUniform, kRigid>(n, s.x, s.y, s.z, s.w, a, b, rest, ru, lam, at);
    else if (run.offset == 1)
      run_avx2<1, kLambda, kUniform, kRigid>(n, s.x, s.y, s.z, s.w, a, b, rest, ru, lam, at);
    else
      run_avx2<2, kLambda, kUniform, kRigid>(n, s.x, s.y, s.z, s.w, a, b, rest, ru, lam, at);
    return;
  }
#endif
  switch (run.type) {
    case RunType::Contiguous:
      run_contiguous<kLambda, kUniform, kRigid>(n, s.x + a, s.y + a, s.z + a, s.x + b, s.y + b, s.z + b, s.w + a,
                                                s.w + b, rest, ru, lam, at);
      break;
    case RunType::Interleaved:
      if (run.offset == 1)
        run_interleaved<1, kLambda, kUniform, kRigid>(n, s.x + a, s.y + a, s.z + a, s.w + a, rest, ru, lam, at);
      else
        run_interleaved<2, kLambda, kUniform, kRigid>(n / 2, s.x + a, s.y + a, s.z + a, s.w + a, rest, ru, lam, at);
      break;
    case RunType::Indexed:
      run_indexed<kLambda>(n, s.x, s.y, s.z, s.w, s.ca + run.c0, s.cb + run.c0, rest, lam, at);
      break;
  }
}

template <bool kLambda>
PBA_SOFT_INLINE void sweep(const SolveArgs& s) {
  for (std::size_t r = 0; r < s.n_runs; ++r) {
    const Run& run = s.runs[r];
    const int kind = static_cast<int>(run.kind);
    const bool rigid = s.at[kind] == 0.0f && run.type != RunType::Indexed;
    const bool uniform = run.rest > 0.0f;
    if (rigid) {
      if (uniform) solve_run<false, true, true>(s, run);
      else solve_run<false, false, true>(s, run);
    } else {
      if (uniform) solve_run<kLambda, true, false>(s, run);
      else solve_run<kLambda, false, false>(s, run);
    }
  }
}

// compiled for AVX2 and for the baseline, same bits: PBA_CLONES (core/clones.h)

PBA_CLONES void sweep_any(const SolveArgs& s, bool lambda) {
  if (lambda) sweep<true>(s);
  else sweep<false>(s);
}

// The dashpots: one Gauss-Seidel sweep, in solver order, over the runs of the damped
// kinds (inv_ch finite), on the velocities at the start of a substep (before gravity and
// the other accelerations: a body at rest has no velocity to damp, so its sag is the
// springs' alone), their impulses accumulated in `lambda` (zeroed before the first).
// Scalar or AVX2, the same bits.
PBA_CLONES void damp_sweep(const SolveArgs& s) {
  for (std::size_t r = 0; r < s.n_runs; ++r) {
    const Run& run = s.runs[r];
    const float slack = s.inv_ch[static_cast<int>(run.kind)];
    if (!(slack < std::numeric_limits<float>::infinity())) continue;
    const int n = static_cast<int>(run.count);
    const float* rest = s.rest + run.c0;
    float* acc = s.lambda + run.c0;
    const float ru = run.rest;
#if PBA_SOFT_HAVE_AVX2
    if (s.avx2 && run.type != RunType::Indexed) {
      const std::uint32_t a = run.a0, b = run.a0 + run.offset;
      const int L = run.type == RunType::Contiguous ? 0 : static_cast<int>(run.offset);
      const bool u = ru > 0.0f;
      if (L == 0) {
        if (u) dash_run_avx2<0, true>(n, s.x, s.y, s.z, s.vx, s.vy, s.vz, s.w, a, b, rest, ru, slack, acc);
        else dash_run_avx2<0, false>(n, s.x, s.y, s.z, s.vx, s.vy, s.vz, s.w, a, b, rest, ru, slack, acc);
      } else if (L == 1) {
        if (u) dash_run_avx2<1, true>(n, s.x, s.y, s.z, s.vx, s.vy, s.vz, s.w, a, b, rest, ru, slack, acc);
        else dash_run_avx2<1, false>(n, s.x, s.y, s.z, s.vx, s.vy, s.vz, s.w, a, b, rest, ru, slack, acc);
      } else {
        if (u) dash_run_avx2<2, true>(n, s.x, s.y, s.z, s.vx, s.vy, s.vz, s.w, a, b, rest, ru, slack, acc);
        else dash_run_avx2<2, false>(n, s.x, s.y, s.z, s.vx, s.vy, s.vz, s.w, a, b, rest, ru, slack, acc);
      }
      continue;
    }
#endif
    for (int k = 0; k < n; ++k) {
      std::uint32_t a = 0, b = 0;
      run_ends(run, s.ca, s.cb, k, a, b);
      dashpot(s.x[a], s.y[a], s.z[a], s.x[b], s.y[b], s.z[b], s.vx[a], s.vy[a], s.vz[a], s.vx[b], s.vy[b], s.vz[b],
              s.w[a], s.w[b], ru > 0.0f ? ru : rest[k], slack, acc[k]);
    }
  }
}

// Predict: the velocity, from the stored one (first substep) or from the last substep's
// displacement, v = ((x - x_prev) / h + r) e^(-damping h) (the velocity update of the
// previous substep, fused here so velocities are stored once per step), then
// (semi-implicit) v += h a, x_prev = x, x += h v, for free particles (w > 0).
// r is what the float positions could not hold of the drift: r = v - (x_new - x) / h
// after rounding, kept in the velocity column between substeps. Without it a drift
// h v under half a float step of x (g h^2 from rest at 300 substeps of 1/60 s, 1.5 m from
// the origin) is lost every substep and the body hangs in the air; with it the velocity
// is exact to float rounding and only the positions are quantised. Linear and quadratic
// drag toward the wind are implicit in v: v' = u_w + (v - u_w + h (g + a_ext)) / (1 + h k)
// with k = (b + c |v - u_w|) w, which damps without ever overshooting the wind; a drag
// beyond a float (k = inf) takes v to the wind's velocity at once, its limit. It is
// evaluated as v - (h k / (1 + h k)) (v - u_w) + h (g + a_ext) / (1 + h k) while h k < 1,
// whose rounding is float's on |v| (as without drag), not on |u_w|. (Written as
// (v + h (g + a_ext + k u_w)) / (1 + h k) until 2026-12-07, whose k u_w overflowed and
// inf 0 made the state NaN at the first step: a drag of 1e35 on a 1 g particle in wind;
// then as the wind's form at every k, which lost v's bits below eps |u_w| per substep.)
struct PredictArgs {
  float* x;
  float* y;
  float* z;
  float* px;
  float* py;
  float* pz;
  float* vx;
  float* vy;
  float* vz;
  const float* w;
  const float* ax;
  const float* ay;
  const float* az;
  std::size_t n;
  float h, inv_h, scale, decay, gx, gy, gz, b, c, wx, wy, wz;  // scale = decay / h
};

template <bool kExt, bool kDrag, bool kFromX>
PBA_SOFT_INLINE void predict_impl(std::size_t n, float* PBA_SOFT_RESTRICT x, float* PBA_SOFT_RESTRICT y,
                                  float* PBA_SOFT_RESTRICT z, float* PBA_SOFT_RESTRICT px,
                                  float* PBA_SOFT_RESTRICT py, float* PBA_SOFT_RESTRICT pz,
                                  float* PBA_SOFT_RESTRICT vx, float* PBA_SOFT_RESTRICT vy,
                                  float* PBA_SOFT_RESTRICT vz, const float* PBA_SOFT_RESTRICT w,
                                  const float* PBA_SOFT_RESTRICT ax, const float* PBA_SOFT_RESTRICT ay,
                                  const float* PBA_SOFT_RESTRICT az, const PredictArgs& p) {
  const float h = p.h, inv_h = p.inv_h, scale = p.scale, decay = p.decay, gx = p.gx, gy = p.gy, gz = p.gz;
  const float b = p.b, c = p.c, wx = p.wx, wy = p.wy, wz = p.wz;
  for (std::size_t i = 0; i < n; ++i) {
    // the velocity at the start of the substep
    float ux, uy, uz;
    if constexpr (kFromX) {
      ux = (x[i] - px[i]) * scale + vx[i] * decay;
      uy = (y[i] - py[i]) * scale + vy[i] * decay;
      uz = (z[i] - pz[i]) * scale + vz[i] * decay;
    } else {
      (void)scale, (void)decay;
      ux = vx[i], uy = vy[i], uz = vz[i];
    }
    // gravity on free particles, held accelerations, drag
    const float m = w[i] > 0.0f ? 1.0f : 0.0f;
    float fx = gx * m, fy = gy * m, fz = gz * m;
    if constexpr (kExt) fx += ax[i], fy += ay[i], fz += az[i];
    float nvx, nvy, nvz;
    if constexpr (kDrag) {
      // (u - t r + h f / (1 + h k) with r = u - u_w and t = h k / (1 + h k) while h k < 1,
      // else u_w + (r + h f) / (1 + h k): each form rounds to the velocity it is nearer,
      // so weak drag keeps u to its own rounding (k = 0 keeps it exactly, not to u_w's)
      // and strong drag gives the wind's (k = inf exactly it); no k u_w to overflow; k =
      // b w + c (|r| w), so a pinned particle's k is 0, never c |r| = inf times 0)
      const float rx = ux - wx, ry = uy - wy, rz = uz - wz;
      const float k = b * w[i] + c * (std::sqrt(rx * rx + ry * ry + rz * rz) * w[i]);
      const float hk = h * k;
      const float inv = 1.0f / (1.0f + hk);
      const float t = hk * inv;  // (NaN at k = inf, where the wind's form is taken)
      const bool weak = hk < 1.0f;
      const float sx = ux - t * rx + h * fx * inv, sy = uy - t * ry + h * fy * inv, sz = uz - t * rz + h * fz * inv;
      const float lx = wx + (rx + h * fx) * inv, ly = wy + (ry + h * fy) * inv, lz = wz + (rz + h * fz) * inv;
      nvx = weak ? sx : lx;
      nvy = weak ? sy : ly;
      nvz = weak ? sz : lz;
    } else {
      (void)b, (void)c, (void)wx, (void)wy, (void)wz;
      nvx = ux + h * fx, nvy = uy + h * fy, nvz = uz + h * fz;
    }
    // drift, and what of it the positions could not hold
    const float x0 = x[i], y0 = y[i], z0 = z[i];
    px[i] = x0, py[i] = y0, pz[i] = z0;
    x[i] = x0 + h * nvx, y[i] = y0 + h * nvy, z[i] = z0 + h * nvz;
    vx[i] = nvx - (x[i] - x0) * inv_h, vy[i] = nvy - (y[i] - y0) * inv_h, vz[i] = nvz - (z[i] - z0) * inv_h;
  }
}

PBA_CLONES void predict(const PredictArgs& p, bool ext, bool drag, bool from_x) {
#define PBA_SOFT_PREDICT(E, D, F) \
  predict_impl<E, D, F>(p.n, p.x, p.y, p.z, p.px, p.py, p.pz, p.vx, p.vy, p.vz, p.w, p.ax, p.ay, p.az, p)
  const int variant = (ext ? 4 : 0) + (drag ? 2 : 0) + (from_x ? 1 : 0);
  switch (variant) {
    case 0: PBA_SOFT_PREDICT(false, false, false); break;
    case 1: PBA_SOFT_PREDICT(false, false, true); break;
    case 2: PBA_SOFT_PREDICT(false, true, false); break;
    case 3: PBA_SOFT_PREDICT(false, true, true); break;
    case 4: PBA_SOFT_PREDICT(true, false, false); break;
    case 5: PBA_SOFT_PREDICT(true, false, true); break;
    case 6: PBA_SOFT_PREDICT(true, true, false); break;
    default: PBA_SOFT_PREDICT(true, true, true); break;
  }
#undef PBA_SOFT_PREDICT
}

// Velocity update v = (x - x_prev) scale + r decay, with scale = decay / h, decay =
// exp(-damping h) and r the drift's rounding left in v by predict.
PBA_CLONES void update_velocities(std::size_t n, const float* PBA_SOFT_RESTRICT x, const float* PBA_SOFT_RESTRICT y,
                                       const float* PBA_SOFT_RESTRICT z, const float* PBA_SOFT_RESTRICT px,
                                       const float* PBA_SOFT_RESTRICT py, const float* PBA_SOFT_RESTRICT pz,
                                       float* PBA_SOFT_RESTRICT vx, float* PBA_SOFT_RESTRICT vy,
                                       float* PBA_SOFT_RESTRICT vz, float scale, float decay) {
  for (std::size_t i = 0; i < n; ++i) {
    vx[i] = (x[i] - px[i]) * scale + vx[i] * decay;
    vy[i] = (y[i] - py[i]) * scale + vy[i] * decay;
    vz[i] = (z[i] - pz[i]) * scale + vz[i] * decay;
  }
}

// Tetrahedron volume constraints C = V - V0 (Macklin et al. 2016 eq. 18; gradients as in
// Mueller, Macklin, Chentanez, Jeschke & Kim 2020, "Detailed rigid body simulation with
// extended position based dynamics", section 5.1): grad_d V = (b-a)x(c-a)/6 and cyclic,
// grad_a V = -(grad_b + grad_c + grad_d). With G_j = 6 grad_j V the update
//   dlambda = -(C + at lambda) / (sum w |G|^2 / 36 + at),  dx_j = w_j dlambda G_j / 6
// is written with one division: dx_j = w_j G_j s, s = -6 (C + at lambda) / (sum w |G|^2
// + 36 at), dlambda = 6 s.
void solve_volumes(SoftBody::Impl& s, float at, bool use_lambda) {
  float* x = s.x.data();
  float* y = s.y.data();
  float* z = s.z.data();
  const float* w = s.w.data();
  for (std::size_t k = 0; k < s.tets.size(); ++k) {
    const SoftTet& t = s.tets[k];
    const std::uint32_t id[4] = {t.a, t.b, t.c, t.d};
    // edges from a, the scaled gradients and the volume
    const Vec3f p0(x[t.a], y[t.a], z[t.a]);
    const Vec3f e1 = Vec3f(x[t.b], y[t.b], z[t.b]) - p0, e2 = Vec3f(x[t.c], y[t.c], z[t.c]) - p0,
                e3 = Vec3f(x[t.d], y[t.d], z[t.d]) - p0;
    Vec3f g[4];
    g[1] = glm::cross(e2, e3);
    g[2] = glm::cross(e3, e1);
    g[3] = glm::cross(e1, e2);
    g[0] = -(g[1] + g[2] + g[3]);
    const float vol = glm::dot(e3, g[3]) * (1.0f / 6.0f);
    // the multiplier update, one division
    float den = 36.0f * at;
    for (int j = 0; j < 4; ++j) den += w[id[j]] * glm::dot(g[j], g[j]);
    if (!(den > 0.0f)) continue;
    float c = vol - s.tet_rest[k];
    if (use_lambda) c += at * s.tet_lambda[k];
    const float sc = -6.0f * c / den;
    if (use_lambda) s.tet_lambda[k] += 6.0f * sc;
    for (int j = 0; j < 4; ++j) {
      const float f = w[id[j]] * sc;
      x[id[j]] += f * g[j].x, y[id[j]] += f * g[j].y, z[id[j]] += f * g[j].z;
    }
  }
}

// The largest alpha / h^2 the update is given (stored as float). Past it the update is its
// limit to float precision: the constraint value it leaves out beside alpha lambda / h^2
// weighs under 1e-15 of what is kept. Without it a compliance so large that alpha / h^2
// overflowed the float made the multipliers' 0 inf NaN. Far above any compliance in use:
// no result below it moves.
constexpr double kMaxScaled = 1e15;

}  // namespace

void SoftBody::Impl::step_xpbd(double t, double dt) {
  const int S = def.substeps;
  const double h = dt / S;
  // per-kind alpha / h^2, and the dashpots' 1 / (c h) on the compliant kinds (infinity:
  // undamped; 0 where c h is beyond a float, an infinitely strong damper)
  const double alpha[3] = {def.stretch_compliance, def.shear_compliance, def.bend_compliance};
  SolveArgs a{x.data(), y.data(), z.data(), vx.data(), vy.data(), vz.data(), w.data(), ca.data(), cb.data(),
              rest.data(), lambda.data(), runs.data(), runs.size(), {}, {}, false};
#if PBA_SOFT_HAVE_AVX2
  a.avx2 = simd && has_avx2();
#endif
  constexpr float kUndamped = std::numeric_limits<float>::infinity();
  bool damp = false;
  for (int k = 0; k < 3; ++k) {
    a.at[k] = static_cast<float>(std::min(alpha[k] / (h * h), kMaxScaled));
    a.inv_ch[k] = alpha[k] > 0 && def.spring_damping > 0 ? static_cast<float>(1 / (def.spring_damping * h)) : kUndamped;
    damp = damp || a.inv_ch[k] < kUndamped;
  }
  const bool use_lambda = def.iterations > 1;
  const float at_volume = static_cast<float>(std::min(def.volume_compliance / (h * h), kMaxScaled));
  // predict's inputs: gravity, held external accelerations, drag toward the wind
  const Vec3 wind = def.forces.wind.at(t);
  const bool drag = def.forces.linear_drag > 0 || def.forces.quadratic_drag > 0;
  const float vscale = static_cast<float>(std::exp(-def.damping * h) / h);
  const float decay = static_cast<float>(std::exp(-def.damping * h));
  const PredictArgs pa{x.data(), y.data(), z.data(), px.data(), py.data(), pz.data(), vx.data(), vy.data(),
                       vz.data(), w.data(), ax.data(), ay.data(), az.data(), n, static_cast<float>(h),
                       static_cast<float>(1 / h), vscale, decay,
                       static_cast<float>(def.forces.gravity.x), static_cast<float>(def.forces.gravity.y),
                       static_cast<float>(def.forces.gravity.z), static_cast<float>(def.forces.linear_drag),
                       static_cast<float>(def.forces.quadratic_drag), static_cast<float>(wind.x),
                       static_cast<float>(wind.y), static_cast<float>(wind.z)};
  // tethers: on unless tearing, recomputed after the pins changed; their anchors'
  // positions are copied again in every substep where a pin moves, and after any step
  // that skipped the tether pass (a mass-spring step, tethers off)
  const bool tethered = def.tethers && !(def.tear_strain > 0) && !pins.empty();
  bool copy = false;
  if (tethered) {
    copy = tethers_dirty || anchors_step != steps - 1;
    anchors_step = steps;
    if (tethers_dirty) update_tethers();
    for (std::size_t k = 0; k < pins.size() && !copy; ++k) copy = pin_from[k] != pin_to[k];
  }
  double collide_s = 0;  // the collisions' time (s)
  for (int sub = 1; sub <= S; ++sub) {
    // predict (with the previous substep's velocity update), then the pins slide toward
    // their targets (exactly there at the last substep); with constraint damping the
    // velocity update is a pass of its own, and the dashpots act on its velocities
    if (damp) {
      if (sub > 1)
        update_velocities(n, x.data(), y.data(), z.data(), px.data(), py.data(), pz.data(), vx.data(), vy.data(),
                          vz.data(), vscale, decay);
      std::fill(lambda.begin(), lambda.end(), 0.f);
      for (int it = 0; it < def.iterations; ++it) damp_sweep(a);
      predict(pa, has_aext, drag, false);
    } else {
      predict(pa, has_aext, drag, sub > 1);
    }
    const double f = static_cast<double>(sub) / S;
    for (std::size_t k = 0; k < pins.size(); ++k) {
      const Vec3 p = sub == S ? pin_to[k] : pin_from[k] + (pin_to[k] - pin_from[k]) * f;
      const std::uint32_t i = pins[k];
      x[i] = static_cast<float>(p.x), y[i] = static_cast<float>(p.y), z[i] = static_cast<float>(p.z);
    }
    // constraint iterations, multipliers reset each substep ("small steps")
    if (use_lambda) {
      std::fill(lambda.begin(), lambda.end(), 0.f);
      std::fill(tet_lambda.begin(), tet_lambda.end(), 0.f);
    }
    for (int it = 0; it < def.iterations; ++it) {
      sweep_any(a, use_lambda);
      if (!tets.empty()) solve_volumes(*this, at_volume, use_lambda);
    }
    // long-range attachments, after the constraints (Kim et al. 2012)
    if (tethered) detail::project_all_tethers(*this, a.avx2, copy);
    // collisions, timed in every substep (two clock reads, 40 ns, against the substep's
    // sweeps: the first substep's time counted S times, as before 2026-12-03, exceeded the
    // whole solve when that substep was preempted, and the profile's phases overran its total)
    if (!colliders.empty()) {
      const Stopwatch sw;
      detail::collide_particles(*this, f, h, 1.0 / S);
      collide_s += sw.seconds();
    }
  }
  // velocities from the last substep's displacement
  update_velocities(n, x.data(), y.data(), z.data(), px.data(), py.data(), pz.data(), vx.data(), vy.data(), vz.data(),
                    vscale, decay);
  profile.collide = collide_s;
}

}  // namespace pba
