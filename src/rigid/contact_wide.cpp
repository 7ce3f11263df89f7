// Rigid bodies: the contact solver's kernels over blocks of manifolds (src/rigid/solver.h).
//
// One template over the lane type runs every path: double (the scalar path, and the overflow
// lane by lane), 4 doubles (AVX2) and 8 doubles (AVX-512), as GCC vector extensions; the
// blocks' floats are widened to double on loading and rounded back on storing. Each lane
// does the same operations in the same order on every path (the build has -ffp-contract=off,
// so no fused multiply-add; division and square root are correctly rounded; min, max and the
// selections are the same comparisons), so the three paths give the same bits
// (RigidSimd.EveryPathGivesTheSameBits).
//
// A manifold is solved in its contact frame (t1, t2, n), as in Box2D v3's contact_solver.c but
// in 3D: the relative linear velocity and each body's angular velocity are turned into the
// frame, the normal points are swept `sweeps` times by projected Gauss-Seidel on the manifold's
// own K = J M^-1 J^T (a point's impulse changes the others' normal velocities through K, the
// bodies are not touched in between), then Coulomb friction at the centroid and the twist
// about the normal, and the change goes back to the two bodies once.
#include "solver.h"

#include <cmath>

#include "lanes.h"

namespace pba::detail {

namespace {

using namespace lanes;

// std::max and std::min's comparisons, lane by lane
template <class V>
PBA_LANES V vmax(V a, V b) {
  return a < b ? b : a;
}
template <class V>
PBA_LANES V vmin(V a, V b) {
  return b < a ? b : a;
}
// std::clamp(v, lo, hi)
template <class V>
PBA_LANES V vclamp(V v, V lo, V hi) {
  return v < lo ? lo : (hi < v ? hi : v);
}

template <class V>
PBA_LANES V vsqrt(V x) {
  if constexpr (std::is_same_v<V, double>) {
    return std::sqrt(x);
  } else {
    V r = x;
    for (int i = 0; i < kWidth<V>; ++i) r[i] = std::sqrt(x[i]);
    return r;
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

// kWidth<V> consecutive floats from p as doubles (exact), and doubles rounded to the nearest
// floats (the same rounding on every path)
template <class V>
PBA_LANES V widen(const float* p) {
  if constexpr (std::is_same_v<V, double>) {
    return static_cast<double>(*p);
  } else {
    typedef float F __attribute__((vector_size(sizeof(V) / 2)));
    F f;
    std::memcpy(&f, p, sizeof f);
    return __builtin_convertvector(f, V);
  }
}
template <class V>
PBA_LANES void narrow(float* p, const V& v) {
  if constexpr (std::is_same_v<V, double>) {
    *p = static_cast<float>(v);
  } else {
    typedef float F __attribute__((vector_size(sizeof(V) / 2)));
    const F f = __builtin_convertvector(v, F);
    std::memcpy(p, &f, sizeof f);
  }
}

// ---------------------------------------------------------------------------------------
// the block's lanes [l0, l0 + width)

template <class V>
struct Lanes {
  ContactBlock& c;
  int l0;
  // a field's lanes widened to double, and rounded back
  PBA_LANES V operator()(const Real (&f)[kLanes]) const { return widen<V>(f + l0); }
  PBA_LANES void put(Real (&f)[kLanes], const V& v) const { narrow<V>(f + l0, v); }
  // the frame
  PBA_LANES void frame(V t1[3], V t2[3], V n[3]) const {
    for (int i = 0; i < 3; ++i) t1[i] = (*this)(c.t1[i]), t2[i] = (*this)(c.t2[i]), n[i] = (*this)(c.n[i]);
  }
};

// the transpose of 4 rows of 4 doubles, and of 8 rows of 8 (each its own inverse)
PBA_LANES void transpose(v4d r[4]) {
  const v4d t0 = __builtin_shuffle(r[0], r[1], v4l{0, 4, 2, 6}), t1 = __builtin_shuffle(r[0], r[1], v4l{1, 5, 3, 7});
  const v4d t2 = __builtin_shuffle(r[2], r[3], v4l{0, 4, 2, 6}), t3 = __builtin_shuffle(r[2], r[3], v4l{1, 5, 3, 7});
  r[0] = __builtin_shuffle(t0, t2, v4l{0, 1, 4, 5}), r[2] = __builtin_shuffle(t0, t2, v4l{2, 3, 6, 7});
  r[1] = __builtin_shuffle(t1, t3, v4l{0, 1, 4, 5}), r[3] = __builtin_shuffle(t1, t3, v4l{2, 3, 6, 7});
}

PBA_LANES void transpose(v8d r[8]) {
  v8d t[8], u[8];
  for (int i = 0; i < 4; ++i) {
    t[2 * i] = __builtin_shuffle(r[2 * i], r[2 * i + 1], v8l{0, 8, 2, 10, 4, 12, 6, 14});
    t[2 * i + 1] = __builtin_shuffle(r[2 * i], r[2 * i + 1], v8l{1, 9, 3, 11, 5, 13, 7, 15});
  }
  constexpr int kFirst[4] = {0, 1, 4, 5};
  for (const int i : kFirst) {
    u[i] = __builtin_shuffle(t[i], t[i + 2], v8l{0, 1, 8, 9, 4, 5, 12, 13});
    u[i + 2] = __builtin_shuffle(t[i], t[i + 2], v8l{2, 3, 10, 11, 6, 7, 14, 15});
  }
  for (int i = 0; i < 4; ++i) {
    r[i] = __builtin_shuffle(u[i], u[i + 4], v8l{0, 1, 2, 3, 8, 9, 10, 11});
    r[i + 4] = __builtin_shuffle(u[i], u[i + 4], v8l{4, 5, 6, 7, 12, 13, 14, 15});
  }
}

// each lane's 64-byte row (base + 8 index), as 8 vectors of one double a lane
template <class V>
PBA_LANES void load_rows(const double* base, const std::uint32_t* index, V out[8]) {
  if constexpr (std::is_same_v<V, double>) {
    const double* p = base + 8 * static_cast<std::size_t>(index[0]);
    for (int k = 0; k < 8; ++k) out[k] = p[k];
  } else if constexpr (std::is_same_v<V, v4d>) {
    for (int i = 0; i < 4; ++i) {
      const double* p = base + 8 * static_cast<std::size_t>(index[i]);
      out[i] = load<v4d>(p), out[4 + i] = load<v4d>(p + 4);
    }
    transpose(out), transpose(out + 4);
  } else {
    for (int i = 0; i < 8; ++i) out[i] = load<v8d>(base + 8 * static_cast<std::size_t>(index[i]));
    transpose(out);
  }
}

// and back: every lane's row is written (a lane that may not change its body writes back what
// it read; empty lanes point at the spare last row)
template <class V>
PBA_LANES void store_rows(double* base, const std::uint32_t* index, V in[8]) {
  if constexpr (std::is_same_v<V, double>) {
    double* p = base + 8 * static_cast<std::size_t>(index[0]);
    for (int k = 0; k < 8; ++k) p[k] = in[k];
  } else if constexpr (std::is_same_v<V, v4d>) {
    transpose(in), transpose(in + 4);
    for (int i = 0; i < 4; ++i) {
      double* p = base + 8 * static_cast<std::size_t>(index[i]);
      store<v4d>(p, in[i]), store<v4d>(p + 4, in[4 + i]);
    }
  } else {
    transpose(in);
    for (int i = 0; i < 8; ++i) store<v8d>(base + 8 * static_cast<std::size_t>(index[i]), in[i]);
  }
}

// lane i of these is set when bit i of `bits` is
template <class V>
PBA_LANES auto lane_mask(std::uint32_t bits) {
  if constexpr (std::is_same_v<V, double>) {
    return static_cast<int>(bits & 1);
  } else if constexpr (std::is_same_v<V, v4d>) {
    return ((v4l{} + static_cast<long>(bits)) >> v4l{0, 1, 2, 3} & 1) != 0;
  } else {
    return ((v8l{} + static_cast<long>(bits)) >> v8l{0, 1, 2, 3, 4, 5, 6, 7} & 1) != 0;
  }
}

// a body's rows with the first six doubles (velocities or their changes) replaced by `now`
// where the lane may write, then stored
template <class V>
PBA_LANES void write_rows(double* base, const std::uint32_t* index, std::uint32_t bits, V row[8], const V now[6]) {
  const auto may = lane_mask<V>(bits);
  for (int k = 0; k < 6; ++k) row[k] = may ? now[k] : row[k];
  store_rows(base, index, row);
}

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

// K's upper triangle by rows: (0,0) (0,1) (0,2) (0,3) (1,1) (1,2) (1,3) (2,2) (2,3) (3,3)
constexpr int kK[4][4] = {{0, 1, 2, 3}, {1, 4, 5, 6}, {2, 5, 7, 8}, {3, 6, 8, 9}};

// the separations at the poses now: base + n.(dp_b - dp_a) + n.(turn_b sb) - n.(turn_a sa),
// with n.(turn s) = (turn^-1 n).s taken in the frame
template <class V>
PBA_LANES void separations(const Lanes<V>& L, const AnchorBlock& g, const BodyArrays& r) {
  ContactBlock& c = L.c;
  V t1[3], t2[3], n[3];
  L.frame(t1, t2, n);
  V ma[8], mb[8];  // dp, then the turn (w, x, y, z)
  load_rows(r.motion, c.a + L.l0, ma);
  load_rows(r.motion, c.b + L.l0, mb);
  const V dp[3] = {mb[0] - ma[0], mb[1] - ma[1], mb[2] - ma[2]};
  const V dpn = dot(dp, n);
  // turn^-1 n = n + 2 (w (-u x n) + (-u) x ((-u) x n)), in the frame
  auto turned_normal = [&](const V* m, V out[3]) {
    const V u[3] = {-m[4], -m[5], -m[6]};
    const V uv[3] = {u[1] * n[2] - u[2] * n[1], u[2] * n[0] - u[0] * n[2], u[0] * n[1] - u[1] * n[0]};
    const V uuv[3] = {u[1] * uv[2] - u[2] * uv[1], u[2] * uv[0] - u[0] * uv[2], u[0] * uv[1] - u[1] * uv[0]};
    V w[3];
    for (int i = 0; i < 3; ++i) w[i] = n[i] + (uv[i] * m[3] + uuv[i]) * 2.0;
    to_frame(t1, t2, n, w, out);
  };
  V na[3], nb[3];
  turned_normal(ma, na);
  turned_normal(mb, nb);
  const V d0 = L(c.d[0]), d1 = L(c.d[1]);
  for (int k = 0; k < 4; ++k) {
    const V x = L(c.x[k]), y = L(c.y[k]), ex = L(g.ex[k]), ey = L(g.ey[k]);
    const V sb = nb[0] * (x + d0 + ex) + nb[1] * (y + d1 + ey) + nb[2] * L(g.zb[k]);
    const V sa = na[0] * (x - ex) + na[1] * (y - ey) + na[2] * L(g.za[k]);
    L.put(c.sep[k], L(g.base[k]) + dpn + sb - sa);
  }
}

// the passes: a biased one with soft contacts (the soft step), a biased one with rigid contacts
// and Baumgarte (sequential impulses, TGS), a relax pass without bias
enum Mode : int { kSoft, kRigid, kRelax };

// one pass of the block's lanes: normal points, friction, twist
template <class V, int kMode>
PBA_LANES void solve(const Lanes<V>& L, const PassParams& p, const BodyArrays& r) {
  constexpr bool kBias = kMode != kRelax;
  ContactBlock& c = L.c;
  const int l0 = L.l0;
  const V zero = splat<V>(0), one = splat<V>(1);
  // the bodies, and their velocities in the frame: the relative linear one, each angular one
  double* const base = r.bodies[0].v;
  V rowa[8], rowb[8];
  load_rows(base, c.a + l0, rowa);
  load_rows(base, c.b + l0, rowb);
  V* const va = rowa;
  V* const wa = rowa + 3;
  V* const vb = rowb;
  V* const wb = rowb + 3;
  V t1[3], t2[3], n[3];
  L.frame(t1, t2, n);
  V rel[3], oa[3], ob[3];
  {
    const V dv[3] = {vb[0] - va[0], vb[1] - va[1], vb[2] - va[2]};
    to_frame(t1, t2, n, dv, rel);
  }
  to_frame(t1, t2, n, wa, oa);
  to_frame(t1, t2, n, wb, ob);
  V dwa[3] = {zero, zero, zero}, dwb[3] = {zero, zero, zero}, impulse[3] = {zero, zero, zero};
  const V ma = L(c.ma), mb = L(c.mb), msum = ma + mb;
  V ia[6], ib[6];
  for (int i = 0; i < 6; ++i) ia[i] = L(c.ia[i]), ib[i] = L(c.ib[i]);
  const V d[3] = {L(c.d[0]), L(c.d[1]), L(c.d[2])};
  // turning a by -Ia ta and b by Ib tb (frame torques with no third component)
  auto turn2 = [&](const V ta0, const V ta1, const V tb0, const V tb1) {
    V da[3], db[3];
    sym_mul2(ia, ta0, ta1, da);
    sym_mul2(ib, tb0, tb1, db);
    for (int i = 0; i < 3; ++i) oa[i] = oa[i] - da[i], dwa[i] = dwa[i] - da[i], ob[i] = ob[i] + db[i], dwb[i] = dwb[i] + db[i];
  };

  // each point's bias, mass scale and impulse scale for this pass: speculative points (apart)
  // close the gap in this substep and no more, and the relax pass leaves them alone; touching
  // ones are pushed out by the soft spring (up to push_out) or by Baumgarte beyond the slop
  const auto fixed = (ma == zero) | (mb == zero);
  V x[4], y[4], lambda[4], lambda0[4], vn[4], bias[4], mscale[4], iscale[4], approach[4], largest[4];
  std::remove_const_t<decltype(fixed)> skip[4];
  for (int k = 0; k < 4; ++k) {
    x[k] = L(c.x[k]), y[k] = L(c.y[k]);
    lambda[k] = lambda0[k] = L(c.impulse[k]);
    approach[k] = L(c.approach[k]), largest[k] = L(c.max_impulse[k]);
    const V sep = L(c.sep[k]);
    const auto apart = sep > zero;
    skip[k] = fixed != fixed;  // none
    if constexpr (kMode == kSoft) {
      const V rate = fixed ? splat<V>(p.bias_rate[1]) : splat<V>(p.bias_rate[0]);
      bias[k] = apart ? sep * p.inv_h : vmax(rate * sep, splat<V>(-p.push_out));
      mscale[k] = apart ? one : (fixed ? splat<V>(p.mass_scale[1]) : splat<V>(p.mass_scale[0]));
      iscale[k] = apart ? zero : (fixed ? splat<V>(p.impulse_scale[1]) : splat<V>(p.impulse_scale[0]));
    } else if constexpr (kMode == kRigid) {
      bias[k] = apart ? sep * p.inv_h
                      : vmax(splat<V>(p.baumgarte_h) * vmin(zero, sep + p.slop), splat<V>(-p.push_out));
      mscale[k] = one, iscale[k] = zero;
    } else {
      bias[k] = zero, mscale[k] = one, iscale[k] = zero;
      skip[k] = apart;
    }
  }
  // the normal velocities: (vb + wb x rb - va - wa x ra).n with (w x r).n = w.(r x n), and
  // r x n = (y, -x, 0) in the frame (rb = ra + d)
  {
    const V g = rel[2] + d[1] * ob[0] - d[0] * ob[1];
    const V p1 = ob[0] - oa[0], p2 = ob[1] - oa[1];
    for (int k = 0; k < 4; ++k) vn[k] = g + y[k] * p1 - x[k] * p2;
  }
  V kk[10];
  for (int i = 0; i < 10; ++i) kk[i] = L(c.k[i]);
  // non-penetration, swept over the points `sweeps` times (Gauss-Seidel on the manifold's
  // problem: one sweep leaves a torque imbalance between the points that rocks tall stacks)
  V total = zero;
  for (int it = 0; it < p.sweeps; ++it) {
    total = zero;
    for (int k = 0; k < 4; ++k) {
      if constexpr (kBias) approach[k] = vmin(approach[k], vn[k]);
      const V j = -L(c.mass[k]) * mscale[k] * (vn[k] + bias[k]) - iscale[k] * lambda[k];
      V next = vmax(lambda[k] + j, zero);
      if constexpr (!kBias) next = skip[k] ? lambda[k] : next;
      const V dl = next - lambda[k];
      lambda[k] = next;
      largest[k] = vmax(largest[k], dl);
      total = total + next;
      for (int m = 0; m < 4; ++m) vn[m] = vn[m] + kk[kK[m][k]] * dl;
    }
  }
  // the points' impulses to the bodies: along n, and the moments (sum dl (y, -x, 0) on a,
  // with rb = ra + d on b)
  {
    V sl = zero, sx = zero, sy = zero;
    for (int k = 0; k < 4; ++k) {
      const V dl = lambda[k] - lambda0[k];
      sl = sl + dl, sx = sx + dl * x[k], sy = sy + dl * y[k];
    }
    rel[2] = rel[2] + msum * sl;
    impulse[2] = impulse[2] + sl;
    turn2(sy, -sx, sy + d[1] * sl, -(sx + d[0] * sl));
  }
  // Coulomb friction at the centroid: the tangential impulse stays inside the disc of radius
  // mu * (total normal impulse)
  const V ca[3] = {L(c.ca[0]), L(c.ca[1]), L(c.ca[2])};
  const V cb[3] = {ca[0] + d[0], ca[1] + d[1], ca[2] + d[2]};
  const V mu = L(c.friction);
  {
    const V r0 = rel[0] + (ob[1] * cb[2] - ob[2] * cb[1]) - (oa[1] * ca[2] - oa[2] * ca[1]);
    const V r1 = rel[1] + (ob[2] * cb[0] - ob[0] * cb[2]) - (oa[2] * ca[0] - oa[0] * ca[2]);
    const V old0 = L(c.tangent_impulse[0]), old1 = L(c.tangent_impulse[1]);
    V j0 = old0 - L(c.tangent_mass[0]) * r0;
    V j1 = old1 - L(c.tangent_mass[1]) * r1;
    const V limit = mu * total, len = vsqrt(j0 * j0 + j1 * j1);
    const auto over = len > limit;
    const V scale = over ? limit / len : one;
    j0 = over ? j0 * scale : j0;
    j1 = over ? j1 * scale : j1;
    L.put(c.tangent_impulse[0], j0);
    L.put(c.tangent_impulse[1], j1);
    const V e0 = j0 - old0, e1 = j1 - old1;
    rel[0] = rel[0] + msum * e0, rel[1] = rel[1] + msum * e1;
    impulse[0] = impulse[0] + e0, impulse[1] = impulse[1] + e1;
    // the moments c x (e0, e1, 0) = (-c2 e1, c2 e0, c0 e1 - c1 e0)
    V da[3], db[3];
    const V ta[3] = {-ca[2] * e1, ca[2] * e0, ca[0] * e1 - ca[1] * e0};
    const V tb[3] = {-cb[2] * e1, cb[2] * e0, cb[0] * e1 - cb[1] * e0};
    sym_mul(ia, ta, da);
    sym_mul(ib, tb, db);
    for (int i = 0; i < 3; ++i) oa[i] = oa[i] - da[i], dwa[i] = dwa[i] - da[i], ob[i] = ob[i] + db[i], dwb[i] = dwb[i] + db[i];
  }
  // twist friction about the normal, up to mu * total normal * mean lever arm
  {
    const V radius = L(c.twist_radius);
    const V old = L(c.twist_impulse), limit = mu * total * radius;
    V j = vclamp(old - L(c.twist_mass) * (ob[2] - oa[2]), -limit, limit);
    j = radius > zero ? j : old;
    L.put(c.twist_impulse, j);
    // the turns e I^-1 n: the inverse inertias' third columns (xz, yz, zz)
    const V e = j - old;
    constexpr int kColumn[3] = {2, 4, 5};
    for (int i = 0; i < 3; ++i) dwa[i] = dwa[i] - e * ia[kColumn[i]], dwb[i] = dwb[i] + e * ib[kColumn[i]];
  }
  for (int k = 0; k < 4; ++k) {
    L.put(c.impulse[k], lambda[k]);
    L.put(c.max_impulse[k], largest[k]);
    if constexpr (kBias) L.put(c.approach[k], approach[k]);
  }
  // the change back to the bodies, in world axes
  V pw[3], dwaw[3], dwbw[3];
  to_world(t1, t2, n, impulse, pw);
  to_world(t1, t2, n, dwa, dwaw);
  to_world(t1, t2, n, dwb, dwbw);
  V na[6], nb[6];
  for (int i = 0; i < 3; ++i) {
    na[i] = va[i] - ma * pw[i], na[3 + i] = wa[i] + dwaw[i];
    nb[i] = vb[i] + mb * pw[i], nb[3 + i] = wb[i] + dwbw[i];
  }
  write_rows(base, c.a + l0, c.write_a >> l0, rowa, na);
  write_rows(base, c.b + l0, c.write_b >> l0, rowb, nb);
}

// the lanes' accumulated impulses added to the warm-start accumulators
template <class V>
PBA_LANES void warm(const Lanes<V>& L, const BodyArrays& r) {
  ContactBlock& c = L.c;
  const int l0 = L.l0;
  const V zero = splat<V>(0);
  V t1[3], t2[3], n[3];
  L.frame(t1, t2, n);
  V sl = zero, sx = zero, sy = zero;
  for (int k = 0; k < 4; ++k) {
    const V l = L(c.impulse[k]);
    sl = sl + l, sx = sx + l * L(c.x[k]), sy = sy + l * L(c.y[k]);
  }
  const V j0 = L(c.tangent_impulse[0]), j1 = L(c.tangent_impulse[1]), tw = L(c.twist_impulse);
  const V d[3] = {L(c.d[0]), L(c.d[1]), L(c.d[2])};
  const V ca[3] = {L(c.ca[0]), L(c.ca[1]), L(c.ca[2])};
  const V cb[3] = {ca[0] + d[0], ca[1] + d[1], ca[2] + d[2]};
  // the moments in the frame: the points', the friction's at the centroid, the twist
  const V ta[3] = {sy - ca[2] * j1, -sx + ca[2] * j0, ca[0] * j1 - ca[1] * j0 + tw};
  const V tb[3] = {sy + d[1] * sl - cb[2] * j1, -(sx + d[0] * sl) + cb[2] * j0, cb[0] * j1 - cb[1] * j0 + tw};
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
  double* const base = r.warm[0].v;
  V rowa[8], rowb[8], na[6], nb[6];
  load_rows(base, c.a + l0, rowa);
  load_rows(base, c.b + l0, rowb);
  for (int i = 0; i < 3; ++i) {
    na[i] = rowa[i] - ma * pw[i], na[3 + i] = rowa[3 + i] - daw[i];
    nb[i] = rowb[i] + mb * pw[i], nb[3 + i] = rowb[3 + i] + dbw[i];
  }
  write_rows(base, c.a + l0, c.write_a >> l0, rowa, na);
  write_rows(base, c.b + l0, c.write_b >> l0, rowb, nb);
}

template <class V, int kMode>
PBA_LANES void pass(ContactBlock& c, const AnchorBlock& g, int l0, const PassParams& p, const BodyArrays& r) {
  const Lanes<V> L{c, l0};
  if (p.update_sep) separations(L, g, r);
  solve<V, kMode>(L, p, r);
  if (p.warm_next) warm(L, r);
}

// blocks [first, last) on lanes of V (several parts of a block when V is narrower). No software
// prefetch: the blocks of a colour lie one after another and the hardware's streamer fetches
// them; asking for all 48 lines of the next block at once stalled the loop on the full fill
// buffers (measured on the 2870-box pyramid: the whole run 7-8% faster without)
template <class V, int kMode>
PBA_LANES void pass_blocks(ContactBlock* blocks, const AnchorBlock* anchors, std::size_t first, std::size_t last,
                           const PassParams& p, const BodyArrays& r) {
  for (std::size_t i = first; i < last; ++i) {
    // a block of one lane (a colour of one manifold: a stack's) by the scalar lane, one of
    // up to four by the 4-wide lanes (the same arithmetic in every lane, so the same bits)
    const int lanes = blocks[i].lanes;
    if constexpr (std::is_same_v<V, double>) {
      for (int l = 0; l < lanes; ++l) pass<double, kMode>(blocks[i], anchors[i], l, p, r);
    } else if (lanes == 1) {
      pass<double, kMode>(blocks[i], anchors[i], 0, p, r);
    } else if (kWidth<V> == 8 && lanes <= 4) {
      pass<v4d, kMode>(blocks[i], anchors[i], 0, p, r);
    } else {
      for (int l = 0; l < lanes; l += kWidth<V>) pass<V, kMode>(blocks[i], anchors[i], l, p, r);
    }
  }
}

template <class V>
PBA_LANES void pass_any(ContactBlock* blocks, const AnchorBlock* anchors, std::size_t first, std::size_t last,
                        const PassParams& p, const BodyArrays& r) {
  if (!p.bias) pass_blocks<V, kRelax>(blocks, anchors, first, last, p, r);
  else if (p.soft) pass_blocks<V, kSoft>(blocks, anchors, first, last, p, r);
  else pass_blocks<V, kRigid>(blocks, anchors, first, last, p, r);
}

// ---------------------------------------------------------------------------------------
// the paths

#if defined(__GNUC__) && defined(__x86_64__)
#define PBA_RIGID_HAVE_X86 1
__attribute__((target("avx512f"))) void pass_avx512(ContactBlock* blocks, const AnchorBlock* anchors, std::size_t first, std::size_t last,
                                                   const PassParams& p, const BodyArrays& r) {
  pass_any<v8d>(blocks, anchors, first, last, p, r);
}
__attribute__((target("avx2"))) void pass_avx2(ContactBlock* blocks, const AnchorBlock* anchors, std::size_t first, std::size_t last,
                                              const PassParams& p, const BodyArrays& r) {
  pass_any<v4d>(blocks, anchors, first, last, p, r);
}
__attribute__((target("avx512f"))) void warm_avx512(ContactBlock* blocks, std::size_t first, std::size_t last,
                                                   const BodyArrays& r) {
  for (std::size_t i = first; i < last; ++i) warm(Lanes<v8d>{blocks[i], 0}, r);
}
__attribute__((target("avx2"))) void warm_avx2(ContactBlock* blocks, std::size_t first, std::size_t last,
                                              const BodyArrays& r) {
  for (std::size_t i = first; i < last; ++i) {
    warm(Lanes<v4d>{blocks[i], 0}, r);
    if (blocks[i].lanes > 4) warm(Lanes<v4d>{blocks[i], 4}, r);
  }
}
__attribute__((target("avx512f"))) void separation_avx512(ContactBlock* blocks, const AnchorBlock* anchors, std::size_t first, std::size_t last,
                                                         const BodyArrays& r) {
  for (std::size_t i = first; i < last; ++i) separations(Lanes<v8d>{blocks[i], 0}, anchors[i], r);
}
__attribute__((target("avx2"))) void separation_avx2(ContactBlock* blocks, const AnchorBlock* anchors, std::size_t first, std::size_t last,
                                                    const BodyArrays& r) {
  for (std::size_t i = first; i < last; ++i) {
    separations(Lanes<v4d>{blocks[i], 0}, anchors[i], r);
    if (blocks[i].lanes > 4) separations(Lanes<v4d>{blocks[i], 4}, anchors[i], r);
  }
}
#else
#define PBA_RIGID_HAVE_X86 0
#endif

}  // namespace

SimdPath best_simd_path() {
#if PBA_RIGID_HAVE_X86
  static const SimdPath best = __builtin_cpu_supports("avx512f") ? SimdPath::Avx512
                               : __builtin_cpu_supports("avx2")  ? SimdPath::Avx2
                                                                 : SimdPath::Scalar;
  return best;
#else
  return SimdPath::Scalar;
#endif
}

void solve_colored(SimdPath path, ContactBlock* blocks, AnchorBlock* anchors, std::size_t first, std::size_t last,
                   const PassParams& p, const BodyArrays& bodies) {
#if PBA_RIGID_HAVE_X86
  if (path == SimdPath::Avx512) return pass_avx512(blocks, anchors, first, last, p, bodies);
  if (path == SimdPath::Avx2) return pass_avx2(blocks, anchors, first, last, p, bodies);
#endif
  (void)path;
  pass_any<double>(blocks, anchors, first, last, p, bodies);
}

void solve_lane(ContactBlock& block, const AnchorBlock& anchors, int lane, const PassParams& p, const BodyArrays& bodies) {
  if (!p.bias) pass<double, kRelax>(block, anchors, lane, p, bodies);
  else if (p.soft) pass<double, kSoft>(block, anchors, lane, p, bodies);
  else pass<double, kRigid>(block, anchors, lane, p, bodies);
}

void warm_colored(SimdPath path, ContactBlock* blocks, std::size_t first, std::size_t last, const BodyArrays& bodies) {
#if PBA_RIGID_HAVE_X86
  if (path == SimdPath::Avx512) return warm_avx512(blocks, first, last, bodies);
  if (path == SimdPath::Avx2) return warm_avx2(blocks, first, last, bodies);
#endif
  (void)path;
  for (std::size_t i = first; i < last; ++i)
    for (int l = 0; l < blocks[i].lanes; ++l) warm(Lanes<double>{blocks[i], l}, bodies);
}

void warm_lane(ContactBlock& block, int lane, const BodyArrays& bodies) { warm(Lanes<double>{block, lane}, bodies); }

void separation_colored(SimdPath path, ContactBlock* blocks, const AnchorBlock* anchors, std::size_t first,
                        std::size_t last, const BodyArrays& bodies) {
#if PBA_RIGID_HAVE_X86
  if (path == SimdPath::Avx512) return separation_avx512(blocks, anchors, first, last, bodies);
  if (path == SimdPath::Avx2) return separation_avx2(blocks, anchors, first, last, bodies);
#endif
  (void)path;
  for (std::size_t i = first; i < last; ++i)
    for (int l = 0; l < blocks[i].lanes; ++l) separations(Lanes<double>{blocks[i], l}, anchors[i], bodies);
}

void separation_lane(ContactBlock& block, const AnchorBlock& anchors, int lane, const BodyArrays& bodies) {
  separations(Lanes<double>{block, lane}, anchors, bodies);
}

void normal_velocities(const ContactBlock& block, int lane, const BodyArrays& bodies, double vn[4]) {
  ContactBlock& c = const_cast<ContactBlock&>(block);
  const Lanes<double> L{c, lane};
  double t1[3], t2[3], n[3], rel[3], oa[3], ob[3];
  const double* va = bodies.bodies[c.a[lane]].v;
  const double* wa = bodies.bodies[c.a[lane]].w;
  const double* vb = bodies.bodies[c.b[lane]].v;
  const double* wb = bodies.bodies[c.b[lane]].w;
  L.frame(t1, t2, n);
  const double dv[3] = {vb[0] - va[0], vb[1] - va[1], vb[2] - va[2]};
  to_frame(t1, t2, n, dv, rel);
  to_frame(t1, t2, n, wa, oa);
  to_frame(t1, t2, n, wb, ob);
  const double g = rel[2] + L(c.d[1]) * ob[0] - L(c.d[0]) * ob[1];
  for (int k = 0; k < 4; ++k) vn[k] = g + L(c.y[k]) * (ob[0] - oa[0]) - L(c.x[k]) * (ob[1] - oa[1]);
}

void restitution_lane(ContactBlock& c, int lane, double restitution, double threshold, const BodyArrays& bodies) {
  const Lanes<double> L{c, lane};
  double t1[3], t2[3], n[3], ia[6], ib[6];
  L.frame(t1, t2, n);
  for (int i = 0; i < 6; ++i) ia[i] = L(c.ia[i]), ib[i] = L(c.ib[i]);
  const double ma = L(c.ma), mb = L(c.mb), d0 = L(c.d[0]), d1 = L(c.d[1]);
  const bool wa = (c.write_a >> lane) & 1, wb = (c.write_b >> lane) & 1;
  for (int k = 0; k < 4; ++k) {
    // only points that approached fast enough and actually pushed
    if (L(c.approach[k]) > -threshold || L(c.max_impulse[k]) == 0) continue;
    double vn[4];
    normal_velocities(c, lane, bodies, vn);
    const double old = L(c.impulse[k]);
    double j = -L(c.mass[k]) * (vn[k] + restitution * L(c.approach[k]));
    const double total = std::max(old + j, 0.0);
    j = total - old;
    L.put(c.impulse[k], total);
    // along n at the point: -j on a, +j on b, with the moments (y, -x, 0) and (y + d1, -(x + d0), 0)
    const double x = L(c.x[k]), y = L(c.y[k]);
    double da[3], db[3], daw[3], dbw[3];
    sym_mul2(ia, y * j, -x * j, da);
    sym_mul2(ib, (y + d1) * j, -(x + d0) * j, db);
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

}  // namespace pba::detail
