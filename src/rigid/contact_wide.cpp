// Rigid bodies: the contact solver's scalar path, the dispatch to the SIMD paths and the
// lane-by-lane functions; the kernels are in contact_wide.h, the SIMD paths' entry points in
// contact_wide_avx2.cpp and contact_wide_avx512.cpp.
#include "contact_wide.h"

#include <algorithm>
#include <cmath>

namespace pba::detail {

SimdPath best_simd_path() {
#if PBA_RIGID_HAVE_X86
#if PBA_AVX512
  static const SimdPath best = __builtin_cpu_supports("avx512f") ? SimdPath::Avx512
                               : __builtin_cpu_supports("avx2")  ? SimdPath::Avx2
                                                                 : SimdPath::Scalar;
#else
  // (the AVX-512 kernels are not in this build: lanes.h)
  static const SimdPath best = __builtin_cpu_supports("avx2") ? SimdPath::Avx2 : SimdPath::Scalar;
#endif
  return best;
#else
  return SimdPath::Scalar;
#endif
}

namespace {

template <class B>
void solve_colored_of(SimdPath path, B* blocks, AnchorsOf<B::kPoints>* anchors, std::size_t first, std::size_t last,
                      const PassParams& p, const BodyArrays& bodies) {
#if PBA_RIGID_HAVE_X86
#if PBA_AVX512
  if (path == SimdPath::Avx512) return pass_avx512(blocks, anchors, first, last, p, bodies);
#endif
  if (path == SimdPath::Avx2) return pass_avx2(blocks, anchors, first, last, p, bodies);
#endif
  (void)path;
  pass_any<float, double>(blocks, anchors, first, last, p, bodies);
}

template <class B>
void warm_colored_of(SimdPath path, B* blocks, std::size_t first, std::size_t last, const BodyArrays& bodies) {
#if PBA_RIGID_HAVE_X86
#if PBA_AVX512
  if (path == SimdPath::Avx512) return warm_avx512(blocks, first, last, bodies);
#endif
  if (path == SimdPath::Avx2) return warm_avx2(blocks, first, last, bodies);
#endif
  (void)path;
  warm_blocks<float>(blocks, first, last, bodies);
}

template <class B>
void separation_colored_of(SimdPath path, B* blocks, const AnchorsOf<B::kPoints>* anchors, std::size_t first,
                           std::size_t last, const BodyArrays& bodies) {
#if PBA_RIGID_HAVE_X86
#if PBA_AVX512
  if (path == SimdPath::Avx512) return separation_avx512(blocks, anchors, first, last, bodies);
#endif
  if (path == SimdPath::Avx2) return separation_avx2(blocks, anchors, first, last, bodies);
#endif
  (void)path;
  separation_blocks<double>(blocks, anchors, first, last, bodies);
}

// each of one lane's points' normal velocity at the velocities now (in double)
template <class B>
void normal_velocities_of(const B& block, int lane, const BodyArrays& bodies, double (&vn)[B::kPoints]) {
  B& c = const_cast<B&>(block);
  const SolverBody& a = bodies.bodies[c.a[lane]];
  const SolverBody& b = bodies.bodies[c.b[lane]];
  point_normal_velocities(Lanes<double, B>{c, lane}, a.v, a.w, b.v, b.w, vn);
}

template <class B>
void approaches_scalar(B& c, int filled, const int* count, const BodyArrays& bodies) {
  for (int l = 0; l < filled; ++l) approach_lanes<double>(c, l, filled, count, bodies);
}

template <class B>
void restitution_lane_of(B& c, int lane, double restitution, double threshold, int sweeps, const BodyArrays& bodies) {
  constexpr int P = B::kPoints;
  const Lanes<double, B> L{c, lane};
  // a lane none of whose points approached fast enough and pushed is left as it is, before
  // its frame, masses and arms are read: the sweeps' test reads only the approach speeds and
  // largest impulses, which they do not change. (Most lanes at rest: the terrain's median
  // steps made this function's 5,000 calls a step, some 0.8 M instructions, for few bounces)
  if (!lane_bounces(c, lane, threshold)) return;
  double t1[3], t2[3], n[3], ia[6], ib[6];
  L.frame(t1, t2, n);
  for (int i = 0; i < 6; ++i) ia[i] = L(c.ia[i]), ib[i] = L(c.ib[i]);
  const double ma = L(c.ma), mb = L(c.mb), ca0 = L(c.ca[0]), ca1 = L(c.ca[1]), cb0 = L(c.cb[0]), cb1 = L(c.cb[1]);
  const bool wa = (c.write_a >> lane) & 1, wb = (c.write_b >> lane) & 1;
  for (int sweep = 0; sweep < sweeps; ++sweep)
  for (int k = 0; k < P; ++k) {
    // only points that approached fast enough and actually pushed
    if (L(c.approach[k]) > -threshold || L(c.max_impulse[k]) == 0) continue;
    double vn[P];
    normal_velocities_of(c, lane, bodies, vn);
    const double old = L(c.impulse[k]);
    double j = -L(c.mass[k]) * (vn[k] + restitution * L(c.approach[k]));
    const double total = std::max(old + j, 0.0);
    j = total - old;
    L.put(c.impulse[k], total);
    // along n at the point: -j on a, +j on b, with the moments (ca1 + y, -(ca0 + x), 0) and (cb1 + y, -(cb0 + x), 0)
    double x = 0, y = 0;
    if constexpr (P > 1) x = L(c.x[k]), y = L(c.y[k]);
    double da[3], db[3], daw[3], dbw[3];
    if constexpr (P > 1) {
      sym_mul2(ia, (ca1 + y) * j, -(ca0 + x) * j, da);
      sym_mul2(ib, (cb1 + y) * j, -(cb0 + x) * j, db);
    } else {
      sym_mul2(ia, ca1 * j, -ca0 * j, da);
      sym_mul2(ib, cb1 * j, -cb0 * j, db);
    }
    to_world(t1, t2, n, da, daw);
    to_world(t1, t2, n, db, dbw);
    double* va = bodies.bodies[c.a[lane]].v;
    double* wva = bodies.bodies[c.a[lane]].w;
    double* vb = bodies.bodies[c.b[lane]].v;
    double* wvb = bodies.bodies[c.b[lane]].w;
    for (int i = 0; i < 3; ++i) {
      if (wa) va[i] -= (ma * j) * n[i], wva[i] -= daw[i];
      if (wb) vb[i] += (mb * j) * n[i], wvb[i] += dbw[i];
    }
  }
}

}  // namespace

void solve_colored(SimdPath path, ContactBlock* blocks, AnchorBlock* anchors, std::size_t first, std::size_t last,
                   const PassParams& p, const BodyArrays& bodies) {
  solve_colored_of(path, blocks, anchors, first, last, p, bodies);
}
void solve_colored(SimdPath path, OnePointBlock* blocks, OnePointAnchors* anchors, std::size_t first, std::size_t last,
                   const PassParams& p, const BodyArrays& bodies) {
  solve_colored_of(path, blocks, anchors, first, last, p, bodies);
}

void solve_lane(ContactBlock& block, const AnchorBlock& anchors, int lane, const PassParams& p,
                const BodyArrays& bodies) {
  const FloatParams q(p);
  if (!p.bias) pass<float, double, kRelax>(block, anchors, lane, q, bodies);
  else if (p.soft) pass<float, double, kSoft>(block, anchors, lane, q, bodies);
  else pass<float, double, kRigid>(block, anchors, lane, q, bodies);
}

void warm_colored(SimdPath path, ContactBlock* blocks, std::size_t first, std::size_t last, const BodyArrays& bodies) {
  warm_colored_of(path, blocks, first, last, bodies);
}
void warm_colored(SimdPath path, OnePointBlock* blocks, std::size_t first, std::size_t last, const BodyArrays& bodies) {
  warm_colored_of(path, blocks, first, last, bodies);
}

void warm_lane(ContactBlock& block, int lane, const BodyArrays& bodies) {
  warm<float, false>(Lanes<float>{block, lane}, bodies);
}

void separation_colored(SimdPath path, ContactBlock* blocks, const AnchorBlock* anchors, std::size_t first,
                        std::size_t last, const BodyArrays& bodies) {
  separation_colored_of(path, blocks, anchors, first, last, bodies);
}
void separation_colored(SimdPath path, OnePointBlock* blocks, const OnePointAnchors* anchors, std::size_t first,
                        std::size_t last, const BodyArrays& bodies) {
  separation_colored_of(path, blocks, anchors, first, last, bodies);
}

void separation_lane(ContactBlock& block, const AnchorBlock& anchors, int lane, const BodyArrays& bodies) {
  separations(Lanes<double>{block, lane}, anchors, bodies);
}

template <class B>
void approaches_of(SimdPath path, B& block, const int* count, const BodyArrays& bodies) {
#if PBA_RIGID_HAVE_X86
#if PBA_AVX512
  if (path == SimdPath::Avx512) return approaches_avx512(block, block.lanes, count, bodies);
#endif
  if (path == SimdPath::Avx2) return approaches_avx2(block, block.lanes, count, bodies);
#endif
  (void)path;
  approaches_scalar(block, block.lanes, count, bodies);
}

void approaches(SimdPath path, ContactBlock& block, const int* count, const BodyArrays& bodies) {
  approaches_of(path, block, count, bodies);
}
void approaches(SimdPath path, OnePointBlock& block, const int* count, const BodyArrays& bodies) {
  approaches_of(path, block, count, bodies);
}

Real approach_at(const ContactBlock& block, int lane, int p, const double* va, const double* wa, const double* vb,
                 const double* wb) {
  double vn[ContactBlock::kPoints];
  point_normal_velocities(Lanes<double, ContactBlock>{const_cast<ContactBlock&>(block), lane}, va, wa, vb, wb, vn);
  return static_cast<Real>(vn[p]);
}
Real approach_at(const OnePointBlock& block, int lane, const double* va, const double* wa, const double* vb,
                 const double* wb) {
  double vn[1];
  point_normal_velocities(Lanes<double, OnePointBlock>{const_cast<OnePointBlock&>(block), lane}, va, wa, vb, wb, vn);
  return static_cast<Real>(vn[0]);
}

void restitution_lane(ContactBlock& c, int lane, double restitution, double threshold, int sweeps,
                      const BodyArrays& bodies) {
  restitution_lane_of(c, lane, restitution, threshold, sweeps, bodies);
}
void restitution_lane(OnePointBlock& c, int lane, double restitution, double threshold, const BodyArrays& bodies) {
  restitution_lane_of(c, lane, restitution, threshold, 1, bodies);  // one point: one sweep is all
}

}  // namespace pba::detail
