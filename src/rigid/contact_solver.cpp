// Rigid bodies: the contact solver passes shared by the soft-step, sequential-impulse and TGS
// solvers (src/rigid/tgs.cpp; XPBD has its own passes, src/rigid/xpbd_rigid.cpp). The pairs
// and their manifolds come from contact_pairs.cpp.
//
// The soft step follows Catto's Solver2D / Box2D v3 (contact_solver.c) in 3D: per substep
// the bodies' velocities are integrated, the carried impulses applied, the contacts solved
// as soft constraints (implicit springs of contact_hertz, pushing out no faster than
// push_out_speed), the positions integrated, and the contacts solved again without
// position bias (the relax pass) so no push-out velocity survives into the next substep.
// Restitution is one pass after the substeps. Sequential impulses (Catto 2005; Bullet and
// Jolt's baseline) are the same passes at one substep, with rigid constraints and a
// Baumgarte bias, iterated.
//
// The layout (src/rigid/solver.h): prepare() colours the constraint graph (Box2D v3's
// constraint_graph.c: each manifold takes a colour in which neither of its dynamic bodies has
// a manifold yet; static, kinematic and sleeping bodies do not count, as the solver never
// writes them) and copies each manifold into a lane of a block of its colour, in the contact
// frame; the passes run over the blocks with SIMD, the overflow lane by lane. The warm start
// of a substep is folded into the relax pass of the one before (each manifold adds its
// impulses to its bodies' accumulators, which the next velocity integration adds), and the
// separations are measured in the relax pass too, so a substep streams the blocks twice.
#include "contacts.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/lanes.h"
#include "rows_avx2.h"

namespace pba::detail {

Softness make_soft(double hertz, double zeta, double h) {
  if (hertz == 0) return {0, 1, 0};
  const double omega = 2 * kPi * hertz;
  const double a1 = 2 * zeta + h * omega, a2 = h * omega * a1, a3 = 1 / (1 + a2);
  // an overdamped spring beyond the doubles (damping_ratio 1e308: a2 = inf) is its limit, a
  // rigid contact without bias (inf * 0 made the mass scale NaN)
  if (!std::isfinite(a2)) return {omega / a1, 1, 0};
  return {omega / a1, a2 * a3, a3};
}

namespace {

// a body the solver changes: dynamic and awake
bool moves(const RigidBodySystem& s, std::uint32_t i, const std::vector<BodyType>& type,
           const std::vector<std::uint8_t>& asleep) {
  (void)s;
  return type[i] == BodyType::Dynamic && !asleep[i];
}

// an empty lane: zeros everywhere (no mass, no effect), its bodies the spare last row, no pair
// (B: ContactBlock or OnePointBlock)
template <class B>
void clear_lane(B& b, AnchorsOf<B::kPoints>& g, int l, std::uint32_t spare) {
  constexpr int P = B::kPoints;
  auto zero = [&](Real (&f)[kLanes]) { f[l] = 0; };
  for (int i = 0; i < 3; ++i) zero(b.t1[i]), zero(b.t2[i]), zero(b.n[i]), zero(b.ca[i]), zero(b.cb[i]);
  for (int i = 0; i < 6; ++i) zero(b.ia[i]), zero(b.ib[i]);
  for (int i = 0; i < P * (P + 1) / 2; ++i) zero(b.k[i]);
  if constexpr (P == 1) {
    zero(b.rolling);
    for (int i = 0; i < 6; ++i) zero(b.rolling_mass[i]);
    for (int i = 0; i < 3; ++i) zero(b.rolling_impulse[i]);
  }
  for (int k = 0; k < P; ++k) {
    if constexpr (P > 1) zero(b.x[k]), zero(b.y[k]);
    zero(b.mass[k]), zero(b.impulse[k]), zero(b.sep[k]);
    zero(b.approach[k]), zero(b.max_impulse[k]);
    zero(g.za[k]), zero(g.zb[k]), zero(g.base[k]), zero(g.ex[k]), zero(g.ey[k]), zero(g.last[k]);
  }
  zero(b.ma), zero(b.mb), zero(b.slop), zero(b.tangent_mass[0]), zero(b.tangent_mass[1]);
  for (int i = 0; i < 3; ++i) zero(b.tangent_k[i]);
  zero(b.friction), zero(b.tangent_impulse[0]), zero(b.tangent_impulse[1]);
  if constexpr (P > 1) zero(b.twist_mass), zero(b.twist_radius), zero(b.twist_impulse);
  b.unit[l] = 1;
  b.a[l] = b.b[l] = spare;
  b.pair[l] = kNoPair;
}

// pairs ahead (in by_color, the order the blocks are filled in) that fill_block asks for while
// it works on one: a block's worth, as gather_fill_avx2 reads a block's pairs together (at 4,
// with the lane loop no longer reading them, it waited on the last lanes' lines)
constexpr std::size_t kPrefetchAhead = kLanes;

// the lines of a pair the fill reads: the header (without the key's line for a kept lane of a
// ContactBlock, from_frame, which does not read it) and the points a block holds (P: four for
// a ContactBlock, one for a OnePointBlock, whose pairs' other points are not read); the loop's
// count known, so it unrolls
template <int P>
void prefetch_pair(const ContactPair& c, bool from_frame) {
  const char* p = reinterpret_cast<const char*>(&c);
  constexpr std::size_t kUsed = offsetof(ContactPair, points) + P * sizeof(SolverPoint);
  if (!from_frame) __builtin_prefetch(p);
  for (std::size_t line = kPairFillStart; line < kUsed; line += 64) __builtin_prefetch(p + line);
}

// lane l's share of the kLines lines at `p`, to be written: lines l, l + kLanes, ... (l < kLanes)
// (addresses made only for lines inside the kLines: lane l of a smaller block has none)
template <std::size_t kLines>
void ask_lines(const void* p, int l) {
  const char* base = static_cast<const char*>(p);
  const auto lane = static_cast<std::size_t>(l);
  for (std::size_t line = 0; line + kLanes <= kLines; line += kLanes) __builtin_prefetch(base + 64 * (line + lane), 1);
  if constexpr (kLines % kLanes != 0)
    if (lane < kLines % kLanes) __builtin_prefetch(base + 64 * (kLines / kLanes * kLanes + lane), 1);
}

}  // namespace

// ---------------------------------------------------------------------------------------
// fill: a block's manifolds into its lanes, in their contact frames (t1, t2, n)

namespace {

using lanes::v4d;
using lanes::v8d;
typedef float v4f __attribute__((vector_size(16)));
typedef float v8f __attribute__((vector_size(32)));

// What filling a block reads of its manifolds, by field and lane (doubles, as the pairs and the
// bodies hold them; lanes past the block's manifolds and points past a manifold's count hold
// zeros): gathered from the pairs (RigidContacts::fill_block: lane by lane, on AVX2 a ContactBlock's
// whole fours by gather_fill_avx2), then computed a
// lane type at a time (fill_lanes), so the arithmetic runs on 8 lanes (AVX-512) or 4 (AVX2)
// at once; the pairs' gather, not the arithmetic, is what is left of its time (it waits on
// memory: a block's 16 pairs are 16 scattered 640-byte records).
struct FillInput {
  double t[3][3][kLanes];               // t1, t2, n by component
  double ma[kLanes], mb[kLanes];        // inverse masses (1/kg; 0 for a body that does not move)
  double unit[kLanes];                  // the lane's impulse unit (fill_lanes)
  double ia[9][kLanes], ib[9][kLanes];  // the world inverse inertias, column by column (glm's order)
  double dab[3][kLanes], dba[3][kLanes];  // com_a - com_b, com_b - com_a (m)
  double ca[3][kLanes];                 // the centroid from a's centre, world axes (m)
  double active[4][kLanes];             // 1 for the manifold's points, else 0
  double arm[4][3][kLanes];             // each point from a's centre (m)
  double sa[4][3][kLanes], sb[4][3][kLanes];  // the core anchors (SolverPoint)
  double offset[4][kLanes], impulse[4][kLanes];
  double friction[kLanes], twist_radius[kLanes], tangent_impulse[2][kLanes], twist_impulse[kLanes];
  double rolling[kLanes], rolling_impulse[3][kLanes];  // rolling resistance (one-point blocks' lanes)
  double balls[kLanes];  // 1 for two balls (ContactPair::balls), else 0
};
// A lane's impulse unit from its bodies' inverse masses' sum (1/kg): 2^-e where the sum is
// f 2^e with f in [0.5, 1) (std::frexp's exponent), 1 for a sum of 0. Read from the sum's
// exponent bits where the sum and the unit are normal numbers (std::frexp and std::ldexp were
// library calls of about 80 instructions a lane, 7% of the 1240 pyramid's prepare); by them
// otherwise. The same value either way.
double impulse_unit(double sum) {
  if (!(sum > 0)) return 1.0;
  std::uint64_t bits;
  std::memcpy(&bits, &sum, sizeof bits);
  const auto biased = static_cast<int>((bits >> 52) & 0x7ff);  // sum = 1.f 2^(biased - 1023) = 0.1f 2^(biased - 1022)
  if (biased == 0 || biased >= 2045) {  // (a subnormal, infinite or NaN sum, or a unit below the normals)
    int exponent = 0;
    std::frexp(sum, &exponent);
    return std::ldexp(1.0, -exponent);
  }
  // 2^-(biased - 1022): the biased exponent 1023 - (biased - 1022), no fraction
  const std::uint64_t unit = static_cast<std::uint64_t>(2045 - biased) << 52;
  double out;
  std::memcpy(&out, &unit, sizeof out);
  return out;
}

// (rows of kLanes doubles, so a lane is cleared row by row)
constexpr std::size_t kInputRows = sizeof(FillInput) / sizeof(double[kLanes]);
static_assert(sizeof(FillInput) % sizeof(double[kLanes]) == 0, "FillInput is rows of kLanes doubles");

// the floats of a lane type of doubles
template <class V>
struct FloatsOf {
  using type = float;
};
template <>
struct FloatsOf<v4d> {
  using type = v4f;
};
template <>
struct FloatsOf<v8d> {
  using type = v8f;
};

// lanes [l0, l0 + width) of input row f
template <class V>
PBA_LANES V from(const double (&f)[kLanes], int l0) {
  return lanes::load<V>(f + l0);
}

// v rounded to floats into lanes [l0, l0 + width) of a block's field
template <class V>
PBA_LANES void put(Real (&f)[kLanes], int l0, V v) {
  using F = typename FloatsOf<V>::type;
  if constexpr (std::is_same_v<V, double>) {
    f[l0] = static_cast<F>(v);
  } else {
    const F x = __builtin_convertvector(v, F);
    std::memcpy(f + l0, &x, sizeof x);
  }
}

// 1 / k, or 0 when nothing can move (effective_mass's convention)
template <class V>
PBA_LANES V inverse(V k) {
  const V zero = lanes::splat<V>(0.0);
  return k > zero ? lanes::splat<V>(1.0) / k : zero;
}

// x where the mask m (a comparison's result) is set, else +0
template <class V, class M>
PBA_LANES V keep(M m, V x) {
  return m ? x : lanes::splat<V>(0.0);
}

// dot(u, v) of lanes of 3-vectors, as glm sums it: (u0 v0 + u1 v1) + u2 v2
template <class V>
PBA_LANES V dot3(const V u[3], const V v[3]) {
  return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

// An inverse inertia in the frame t (t1, t2, n), t_i . (I^-1 t_j), upper triangle (xx, xy,
// xz, yy, yz, zz), from the world one's rows `world` (column by column, glm's order), I^-1 t_j
// summed as glm's matrix product sums it (1/(kg m^2))
template <class V>
PBA_LANES void in_frame(const double (&world)[9][kLanes], const V t[3][3], int l0, V out[6]) {
  V it[3][3];
  for (int j = 0; j < 3; ++j)
    for (int r = 0; r < 3; ++r)
      it[j][r] =
          from<V>(world[r], l0) * t[j][0] + from<V>(world[3 + r], l0) * t[j][1] + from<V>(world[6 + r], l0) * t[j][2];
  constexpr int kRow[6] = {0, 0, 0, 1, 1, 2}, kCol[6] = {0, 1, 2, 1, 2, 2};
  for (int e = 0; e < 6; ++e) out[e] = dot3(t[kRow[e]], it[kCol[e]]);
}

// The rows a lane's bodies' inverse inertias enter, made by fill_lanes and, for a body that
// turned, by refresh_lanes with the same operations in the same order (so the same bits): the
// normal rows' K (upper triangle, times u) and effective masses (over u), the friction's K at
// the centroid and its two rows' masses, and a ContactBlock's twist mass, into `k` (a block or
// a RefreshOutput). ia, ib: the inverse inertias in the frame (1/(kg m^2)); ma, mb: the
// inverse masses (1/kg); unit: the lane's impulse unit u; x, y: each point's offset from a's
// centre in the frame (m), `on` where the point is in use; d: b's centre from a's in the frame
// (m); ca, cb: the centroid from a's centre and from b's (m).
template <class V, int P, class Rows, class M>
PBA_LANES void inertia_rows(Rows& k, int l0, const V (&ia)[6], const V (&ib)[6], V ma, V mb, V unit, const V (&x)[P],
                            const V (&y)[P], const M (&on)[P], const V (&d)[3], const V (&ca)[3], const V (&cb)[3]) {
  // the normal rows' angular parts are r x n = (y, -x, 0) in the frame, a's arm ra = (y, -x)
  // and b's rb = ra + (d1, -d0); their third components are zero, so the products with the
  // inverse inertias leave those terms out (exact zeros: a sum changes at most a zero's sign,
  // and each form is added to ma + mb, never -0), and each point's I r is formed once, for K's
  // entries ma + mb + ra_i^T Ia ra_j + rb_i^T Ib rb_j
  V ra[P][2], rb[P][2], ira[P][2], irb[P][2];
  for (int p = 0; p < P; ++p) {
    ra[p][0] = y[p], ra[p][1] = -x[p];
    rb[p][0] = y[p] + d[1], rb[p][1] = -(x[p] + d[0]);
    ira[p][0] = ia[0] * ra[p][0] + ia[1] * ra[p][1];
    ira[p][1] = ia[1] * ra[p][0] + ia[3] * ra[p][1];
    irb[p][0] = ib[0] * rb[p][0] + ib[1] * rb[p][1];
    irb[p][1] = ib[1] * rb[p][0] + ib[3] * rb[p][1];
  }
  static constexpr int kPairs[10][2] = {{0, 0}, {0, 1}, {0, 2}, {0, 3}, {1, 1}, {1, 2}, {1, 3}, {2, 2}, {2, 3}, {3, 3}};
  // (K's entries: unrolled on AVX2, where GCC left the loop rolled, the points' rows indexed on
  // the stack; the other paths' loop as it was, for their code's sake: AVX-512's cannot be timed
  // here)
  if constexpr (std::is_same_v<V, v4d>) {
#pragma GCC unroll 10
    for (int e = 0; e < P * (P + 1) / 2; ++e) {
      const int i = kPairs[e][0], j = kPairs[e][1];
      const V v = keep(on[i] & on[j], ma + mb + (ra[i][0] * ira[j][0] + ra[i][1] * ira[j][1]) +
                                          (rb[i][0] * irb[j][0] + rb[i][1] * irb[j][1]));
      put(k.k[e], l0, v * unit);
      if (i == j) put(k.mass[i], l0, inverse(v) / unit);
    }
  } else {
    for (int e = 0; e < P * (P + 1) / 2; ++e) {
      const int i = kPairs[e][0], j = kPairs[e][1];
      const V v = keep(on[i] & on[j], ma + mb + (ra[i][0] * ira[j][0] + ra[i][1] * ira[j][1]) +
                                          (rb[i][0] * irb[j][0] + rb[i][1] * irb[j][1]));
      put(k.k[e], l0, v * unit);
      if (i == j) put(k.mass[i], l0, inverse(v) / unit);
    }
  }
  // friction at the centroid: the tangents' angular parts c x t1 = (0, c2, -c1) and
  // c x t2 = (-c2, 0, c0), their quadratic forms again without the zero component
  auto form1 = [](const V m[6], V u1, V u2) { return u1 * (m[3] * u1 + m[4] * u2) + u2 * (m[4] * u1 + m[5] * u2); };
  auto form2 = [](const V m[6], V u0, V u2) { return u0 * (m[0] * u0 + m[2] * u2) + u2 * (m[2] * u0 + m[5] * u2); };
  // (c x t1)^T m (c x t2), the off-diagonal entry (no linear part: t1 . t2 = 0)
  auto form12 = [](const V m[6], V u1, V u2, V w0, V w2) {
    return u1 * (m[1] * w0 + m[4] * w2) + u2 * (m[2] * w0 + m[5] * w2);
  };
  const V k11 = ma + mb + form1(ia, ca[2], -ca[1]) + form1(ib, cb[2], -cb[1]);
  const V k22 = ma + mb + form2(ia, -ca[2], ca[0]) + form2(ib, -cb[2], cb[0]);
  const V k12 = form12(ia, ca[2], -ca[1], -ca[2], ca[0]) + form12(ib, cb[2], -cb[1], -cb[2], cb[0]);
  put(k.tangent_mass[0], l0, inverse(k11) / unit);
  put(k.tangent_mass[1], l0, inverse(k22) / unit);
  put(k.tangent_k[0], l0, k11 * unit), put(k.tangent_k[1], l0, k12 * unit), put(k.tangent_k[2], l0, k22 * unit);
  if constexpr (P > 1) put(k.twist_mass, l0, inverse(ia[5] + ib[5]) / unit);
}

// Lanes [l0, l0 + width) of a block and its anchors from the gathered input. Every lane type
// does the same operations in the same order (the build has -ffp-contract=off, division is
// correctly rounded), so the scalar, AVX2 and AVX-512 paths give the same bits.
template <class V, class B>
PBA_LANES void fill_lanes(const FillInput& in, B& k, AnchorsOf<B::kPoints>& g, int l0) {
  // the points a lane holds: a one-point lane's is its centroid (its x, y are zero; the
  // block keeps neither them nor a twist)
  constexpr int P = B::kPoints;
  const V zero = lanes::splat<V>(0.0);
  V t[3][3];
  for (int r = 0; r < 3; ++r)
    for (int i = 0; i < 3; ++i) t[r][i] = from<V>(in.t[r][i], l0);
  for (int i = 0; i < 3; ++i) put(k.t1[i], l0, t[0][i]), put(k.t2[i], l0, t[1][i]), put(k.n[i], l0, t[2][i]);
  // the lane's impulse unit u, a power of two that puts u (ma + mb) in [0.5, 1) (so that the
  // float kernels see masses near 1 kg whatever the bodies weigh; exact: a power of two scales
  // every product and quotient without rounding, so it changes no bits unless a float would
  // leave its range): the block keeps impulses and effective masses divided by u, inverse
  // masses, inverse inertias and K times u
  const V ma = from<V>(in.ma, l0), mb = from<V>(in.mb, l0), unit = from<V>(in.unit, l0);
  put(k.unit, l0, unit);
  put(k.ma, l0, ma * unit), put(k.mb, l0, mb * unit);
  // the inverse inertias in the frame, t_i . (I^-1 t_j) (upper triangle: xx, xy, xz, yy, yz, zz)
  V ia[6], ib[6];
  in_frame(in.ia, t, l0, ia), in_frame(in.ib, t, l0, ib);
  for (int e = 0; e < 6; ++e) put(k.ia[e], l0, ia[e] * unit), put(k.ib[e], l0, ib[e] * unit);
  // the centres' offset d and the centroid in the frame (b's centroid is ca + d)
  V dab[3], dba[3], cw[3], d[3], ca[3];
  for (int i = 0; i < 3; ++i)
    dab[i] = from<V>(in.dab[i], l0), dba[i] = from<V>(in.dba[i], l0), cw[i] = from<V>(in.ca[i], l0);
  for (int i = 0; i < 3; ++i) d[i] = dot3(dab, t[i]), ca[i] = dot3(cw, t[i]);
  // two balls (a lane of one point): each body's arm goes from its own ball's centre along n,
  // so its tangential part is the ball's centre's from the centre of mass (the point's sa, sb
  // in the frame; 0 for a ball on its body's centre), not the shared point's, which is off the
  // line of centres when the normal is the touch's (touch_normal): a frictionless push then has
  // no moment about either centre. a's centroid there, b's (ca + d) at sb's
  const auto balls = from<V>(in.balls, l0) > zero, plain = from<V>(in.balls, l0) == zero;
  V core_a[3], core_b[3], ball_a[2];
  for (int i = 0; i < 3; ++i) core_a[i] = from<V>(in.sa[0][i], l0), core_b[i] = from<V>(in.sb[0][i], l0);
  for (int i = 0; i < 2; ++i) {
    ball_a[i] = dot3(core_a, t[i]);
    d[i] = balls ? dot3(core_b, t[i]) - ball_a[i] : d[i];
    ca[i] = balls ? ball_a[i] : ca[i];
  }
  for (int i = 0; i < 3; ++i) put(k.ca[i], l0, ca[i]), put(k.cb[i], l0, ca[i] + d[i]);
  // the points (their arms, anchors, separations and carried impulses), then the rows their
  // bodies' inverse inertias enter (inertia_rows)
  V px[P], py[P];
  decltype(zero < zero) on[P];
  const V base = dot3(dba, t[2]);  // the centres' separation along n
  for (int p = 0; p < P; ++p) {
    on[p] = from<V>(in.active[p], l0) > zero;
    V arm[3], sa[3], sb[3];
    for (int i = 0; i < 3; ++i)
      arm[i] = from<V>(in.arm[p][i], l0), sa[i] = from<V>(in.sa[p][i], l0), sb[i] = from<V>(in.sb[p][i], l0);
    V x = dot3(arm, t[0]), y = dot3(arm, t[1]);
    if (p == 0) x = balls ? ball_a[0] : x, y = balls ? ball_a[1] : y;  // (two balls: at the centroid)
    x = keep(on[p], x), y = keep(on[p], y);
    px[p] = x, py[p] = y;
    const V za = dot3(sa, t[2]), zb = dot3(sb, t[2]);
    put(g.za[p], l0, keep(on[p], za)), put(g.zb[p], l0, keep(on[p], zb));
    // the core anchors' tangential offsets from the contact point (half the step from a's
    // surface point to b's; zero where the narrow phase puts them on one normal, and for two
    // balls, whose arms are their cores' already)
    V e[3];
    for (int i = 0; i < 3; ++i) e[i] = lanes::splat<V>(0.5) * ((sb[i] + dba[i]) - sa[i]);
    put(g.ex[p], l0, keep(on[p], keep(plain, dot3(e, t[0])))), put(g.ey[p], l0, keep(on[p], keep(plain, dot3(e, t[1]))));
    // the separation at the start of the step (the kernels add the bodies' motion since)
    const V sep = keep(on[p], base + from<V>(in.offset[p], l0) + zb - za);
    put(k.sep[p], l0, sep), put(g.base[p], l0, sep);
    const V carried = keep(on[p], from<V>(in.impulse[p], l0) / unit);
    put(k.impulse[p], l0, carried), put(g.last[p], l0, carried);
    if constexpr (P > 1) put(k.x[p], l0, x - ca[0]), put(k.y[p], l0, y - ca[1]);
    put(k.max_impulse[p], l0, zero);
  }
  const V cb[3] = {ca[0] + d[0], ca[1] + d[1], ca[2] + d[2]};
  inertia_rows<V, P>(k, l0, ia, ib, ma, mb, unit, px, py, on, d, ca, cb);
  put(k.friction, l0, from<V>(in.friction, l0));
  put(k.tangent_impulse[0], l0, from<V>(in.tangent_impulse[0], l0) / unit);
  put(k.tangent_impulse[1], l0, from<V>(in.tangent_impulse[1], l0) / unit);
  if constexpr (P > 1) {
    put(k.twist_radius, l0, from<V>(in.twist_radius, l0));
    put(k.twist_impulse, l0, from<V>(in.twist_impulse, l0) / unit);
  } else {
    // the rolling resistance of a lane that rolls: its mass (Ia^-1 + Ib^-1)^-1 in the frame,
    // the adjugate over the determinant (0 when singular, as set_rolling_mass), and its
    // carried impulse in the frame
    const V coefficient = from<V>(in.rolling, l0);
    const auto rolls = coefficient > zero;
    put(k.rolling, l0, keep(rolls, coefficient));
    const V a = ia[0] + ib[0], b = ia[1] + ib[1], c = ia[2] + ib[2], d = ia[3] + ib[3], e = ia[4] + ib[4],
            f = ia[5] + ib[5];
    const V adj[6] = {d * f - e * e, c * e - b * f, b * e - c * d, a * f - c * c, b * c - a * e, a * d - b * b};
    const V det = a * adj[0] + b * adj[1] + c * adj[2];
    const auto invertible = rolls & (det > zero);
    for (int i = 0; i < 6; ++i) put(k.rolling_mass[i], l0, keep(invertible, adj[i] / det / unit));
    V impulse[3];
    for (int i = 0; i < 3; ++i) impulse[i] = from<V>(in.rolling_impulse[i], l0);
    for (int i = 0; i < 3; ++i) put(k.rolling_impulse[i], l0, keep(rolls, dot3(impulse, t[i]) / unit));
  }
}

#if PBA_AVX512
template <class B>
__attribute__((target("avx512f"))) void fill_avx512(const FillInput& in, B& k, AnchorsOf<B::kPoints>& g, int lanes) {
  for (int l0 = 0; l0 < lanes; l0 += 8) fill_lanes<v8d>(in, k, g, l0);
}
#endif
// (next, next_anchors: the block filled after this one and its anchors, or null: their lines
// asked for to be written, a quarter with each group of four lanes. A group writes 16 bytes of
// each of a block's rows, so the first wrote to every one of its lines while none was in the
// cache, the store queue full)
template <class B>
__attribute__((target("avx2"))) void fill_avx2(const FillInput& in, B& k, AnchorsOf<B::kPoints>& g, int lanes,
                                              const B* next, const AnchorsOf<B::kPoints>* next_anchors) {
  constexpr std::size_t kLines = sizeof(B) / 64, kAnchorLines = sizeof(AnchorsOf<B::kPoints>) / 64;
  for (int l0 = 0; l0 < lanes; l0 += 4) {
    if (next) {
      const std::size_t q = static_cast<std::size_t>(l0 / 4);
      for (std::size_t line = q * kLines / 4; line < (q + 1) * kLines / 4; ++line)
        __builtin_prefetch(reinterpret_cast<const char*>(next) + 64 * line, 1);
      for (std::size_t line = q * kAnchorLines / 4; line < (q + 1) * kAnchorLines / 4; ++line)
        __builtin_prefetch(reinterpret_cast<const char*>(next_anchors) + 64 * line, 1);
    }
    fill_lanes<v4d>(in, k, g, l0);
  }
}
template <class B>
void fill_scalar(const FillInput& in, B& k, AnchorsOf<B::kPoints>& g, int lanes) {
  for (int l = 0; l < lanes; ++l) fill_lanes<double>(in, k, g, l);
}

#if PBA_ROWS_AVX2
static_assert(offsetof(ContactPair, t1) == 88 && offsetof(ContactPair, friction) == 112 &&
                  offsetof(ContactPair, tangent_impulse) == 160 && offsetof(ContactPair, twist_impulse) == 176 &&
                  offsetof(ContactPair, rolling) == 184 && offsetof(ContactPair, t2) == 192 &&
                  offsetof(ContactPair, ca) == 216 && offsetof(ContactPair, twist_radius) == 240 &&
                  offsetof(ContactPair, count) == 248 && sizeof(ContactPair::count) == 4 &&
                  offsetof(ContactPair, balls) == 252 && sizeof(ContactPair::balls) == 4 &&
                  sizeof(Mat3) == 9 * sizeof(double),
              "gather_fill_avx2 reads a pair's header as six rows of four doubles from its normal (the count and "
              "the balls' flag in the last double), a point as 4 + 4 + 2");
static_assert(offsetof(SolverPoint, sa) == 24 && offsetof(SolverPoint, sb) == 48 &&
                  offsetof(SolverPoint, offset) == 72 && sizeof(SolverPoint) == 80 && Manifold::kMaxPoints == 4,
              "gather_fill_avx2 reads a point's at, sa, sb and offset as rows at these places, four points a pair");

// What fill_block's lane loop copies into `in` for a block's lanes [0, lanes) (a multiple of
// four; P: the block's points a lane, 4 or 1), four lanes at a time: rows of four doubles from
// the four pairs (by_color's `index`), their bodies' centres and inverse inertias (`body_a`,
// `body_b`), turned into columns; the
// points past a pair's count masked to +0, as the loop's `on ? x : 0` makes them; the centres'
// differences and the arms by the same subtractions. The same values, so the same bits. A
// double at a time, the loop's copies took about 250 instructions a lane (the pyramids'
// fill_block), these about 110. And what the lane loop read of the pairs for its bookkeeping:
// each lane's count (`count`, and in.active), its restitution (`restitution`) and bit l of
// `rolls` where its pair rolls, of `bounces` where its restitution is not 0, so that the lane
// loop reads no line of these pairs: its reads waited on them (44% of fill_block's samples in
// the 2870 pyramid, each pair asked for only four lanes ahead), while here the lines come in
// together, a block ahead.
template <int P>
__attribute__((target("avx2"))) void gather_fill_avx2(FillInput& in, const ContactPair* pairs,
                                                      const std::uint32_t* index, const std::uint32_t* body_a,
                                                      const std::uint32_t* body_b, const Mat3* inv_inertia,
                                                      const Vec3* com, int lanes, int* count, double* restitution,
                                                      std::uint32_t& rolls, std::uint32_t& bounces) {
  using V = __m256d;
  const __m256i low = _mm256_set1_epi64x(0xffffffff);
  const __m256i low_words = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
  for (int l0 = 0; l0 < lanes; l0 += 4) {
    const char* p[4];
    for (int j = 0; j < 4; ++j) p[j] = reinterpret_cast<const char*>(&pairs[index[l0 + j]]);
    auto put = [&](double (&row)[kLanes], V v) __attribute__((target("avx2"))) { _mm256_storeu_pd(row + l0, v); };
    // the four pairs' rows of four doubles at byte `at`, as columns
    auto rows = [&](std::size_t at, V (&out)[4]) __attribute__((target("avx2"))) {
      columns4(_mm256_loadu_pd(reinterpret_cast<const double*>(p[0] + at)),
               _mm256_loadu_pd(reinterpret_cast<const double*>(p[1] + at)),
               _mm256_loadu_pd(reinterpret_cast<const double*>(p[2] + at)),
               _mm256_loadu_pd(reinterpret_cast<const double*>(p[3] + at)), out);
    };
    V r[4], impulse[4];
    rows(offsetof(ContactPair, normal), r);  // n, t1.x
    put(in.t[2][0], r[0]), put(in.t[2][1], r[1]), put(in.t[2][2], r[2]), put(in.t[0][0], r[3]);
    rows(offsetof(ContactPair, normal) + 32, r);  // t1.y, t1.z, friction, restitution
    put(in.t[0][1], r[0]), put(in.t[0][2], r[1]), put(in.friction, r[2]);
    _mm256_storeu_pd(restitution + l0, r[3]);
    // (the loop's `restitution != 0`: true for a NaN too)
    bounces |= static_cast<std::uint32_t>(_mm256_movemask_pd(_mm256_cmp_pd(r[3], _mm256_setzero_pd(), _CMP_NEQ_UQ)))
               << l0;
    rows(offsetof(ContactPair, normal_impulse), impulse);
    rows(offsetof(ContactPair, tangent_impulse), r);  // the tangents', the twist's, rolling
    put(in.tangent_impulse[0], r[0]), put(in.tangent_impulse[1], r[1]), put(in.twist_impulse, r[2]);
    put(in.rolling, r[3]);
    rolls |= static_cast<std::uint32_t>(_mm256_movemask_pd(_mm256_cmp_pd(r[3], _mm256_setzero_pd(), _CMP_GT_OQ)))
             << l0;
    rows(offsetof(ContactPair, t2), r);  // t2, ca.x
    put(in.t[1][0], r[0]), put(in.t[1][1], r[1]), put(in.t[1][2], r[2]), put(in.ca[0], r[3]);
    rows(offsetof(ContactPair, ca) + 8, r);  // ca.y, ca.z, twist_radius, count
    put(in.ca[1], r[0]), put(in.ca[2], r[1]), put(in.twist_radius, r[2]);
    // the count: the low half of its row's last double
    const __m256i points = _mm256_and_si256(_mm256_castpd_si256(r[3]), low);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(count + l0),
                     _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(points, low_words)));
    // two balls: the high half of that double, not 0
    const __m256i balls = _mm256_srli_epi64(_mm256_castpd_si256(r[3]), 32);
    put(in.balls, _mm256_andnot_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(balls, _mm256_setzero_si256())),
                                   _mm256_set1_pd(1.0)));
    if constexpr (P == 1) {  // a one-point lane's rolling impulse (fill_lanes reads it for those only)
      rows(offsetof(ContactPair, rolling_impulse), r);
      for (int i = 0; i < 3; ++i) put(in.rolling_impulse[i], r[i]);
    }
    // the bodies: centres, their differences, and the inverse inertias column by column (glm's
    // order: 4 + 4 + 1 doubles)
    V ca[4], cb[4];
    auto centres = [&](const std::uint32_t* body, V (&out)[4]) __attribute__((target("avx2"))) {
      columns4(row3(com[body[l0]]), row3(com[body[l0 + 1]]), row3(com[body[l0 + 2]]), row3(com[body[l0 + 3]]), out);
    };
    centres(body_a, ca), centres(body_b, cb);
    for (int i = 0; i < 3; ++i) put(in.dab[i], ca[i] - cb[i]), put(in.dba[i], cb[i] - ca[i]);
    auto inertia = [&](const std::uint32_t* body, double (&out)[9][kLanes]) __attribute__((target("avx2"))) {
      const double* m[4];
      for (int j = 0; j < 4; ++j) m[j] = &inv_inertia[body[l0 + j]][0][0];
      for (int half = 0; half < 2; ++half) {
        columns4(_mm256_loadu_pd(m[0] + 4 * half), _mm256_loadu_pd(m[1] + 4 * half), _mm256_loadu_pd(m[2] + 4 * half),
                 _mm256_loadu_pd(m[3] + 4 * half), r);
        for (int i = 0; i < 4; ++i) put(out[4 * half + i], r[i]);
      }
      put(out[8], _mm256_setr_pd(m[0][8], m[1][8], m[2][8], m[3][8]));
    };
    inertia(body_a, in.ia), inertia(body_b, in.ib);
    // the points: (at, sa.x), (sa.y, sa.z, sb.x, sb.y), (sb.z, offset), past the count +0 (the
    // masks from the lanes' counts, one comparison a point); a block's P (fill_lanes reads no more)
    for (int k = 0; k < P; ++k) {
      // (in.active: 1 for the points below the count, written here for the gathered lanes)
      const V on = _mm256_castsi256_pd(_mm256_cmpgt_epi64(points, _mm256_set1_epi64x(k)));
      put(in.active[k], _mm256_and_pd(on, _mm256_set1_pd(1.0)));
      const std::size_t at = offsetof(ContactPair, points) + static_cast<std::size_t>(k) * sizeof(SolverPoint);
      rows(at, r);
      for (int i = 0; i < 3; ++i) put(in.arm[k][i], _mm256_and_pd(on, r[i] - ca[i]));
      put(in.sa[k][0], _mm256_and_pd(on, r[3]));
      rows(at + 32, r);
      put(in.sa[k][1], _mm256_and_pd(on, r[0])), put(in.sa[k][2], _mm256_and_pd(on, r[1]));
      put(in.sb[k][0], _mm256_and_pd(on, r[2])), put(in.sb[k][1], _mm256_and_pd(on, r[3]));
      auto half = [&](int j) __attribute__((target("avx2"))) {
        return _mm_loadu_pd(reinterpret_cast<const double*>(p[j] + at + 64));
      };
      const V even = _mm256_insertf128_pd(_mm256_castpd128_pd256(half(0)), half(2), 1);  // lanes 0, 2
      const V odd = _mm256_insertf128_pd(_mm256_castpd128_pd256(half(1)), half(3), 1);   // lanes 1, 3
      put(in.sb[k][2], _mm256_and_pd(on, _mm256_unpacklo_pd(even, odd)));
      put(in.offset[k], _mm256_and_pd(on, _mm256_unpackhi_pd(even, odd)));
      put(in.impulse[k], _mm256_and_pd(on, impulse[k]));
    }
  }
}
#endif

}  // namespace

// ---------------------------------------------------------------------------------------
// prepare: inverse inertias, colours, blocks, the first warm start

namespace {

// What making bodies' world inverse inertias reads, gathered a body a lane: the orientation
// and the principal inverse moments (already held to kSolverInertiaRatio where asked)
struct InertiaInput {
  double q[4][kLanes];  // w, x, y, z
  double m[3][kLanes];  // (1/(kg m^2))
};

// Lanes [l0, l0 + width): R diag(m) R^T into out (column by column, glm's order), R being
// glm::mat3_cast(q), by glm's arithmetic: mat3_cast's, and the two products summed as glm's
// mat3 product sums them, the diagonal matrix's zeros included (they set zeros' signs), so
// every lane type gives the bits of `glm::mat3_cast(q) * d * glm::transpose(...)` in double.
template <class V>
PBA_LANES void world_inertia_lanes(const InertiaInput& in, double (&out)[9][kLanes], int l0) {
  const V w = from<V>(in.q[0], l0), x = from<V>(in.q[1], l0), y = from<V>(in.q[2], l0), z = from<V>(in.q[3], l0);
  const V xx = x * x, yy = y * y, zz = z * z, xz = x * z, xy = x * y, yz = y * z, wx = w * x, wy = w * y, wz = w * z;
  const V r[3][3] = {{1.0 - 2.0 * (yy + zz), 2.0 * (xy + wz), 2.0 * (xz - wy)},
                     {2.0 * (xy - wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz + wx)},
                     {2.0 * (xz + wy), 2.0 * (yz - wx), 1.0 - 2.0 * (xx + yy)}};
  const V zero = lanes::splat<V>(0.0);
  V d[3][3];
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) d[j][k] = j == k ? from<V>(in.m[j], l0) : zero;
  V rd[3][3];
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) rd[j][i] = r[0][i] * d[j][0] + r[1][i] * d[j][1] + r[2][i] * d[j][2];
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      lanes::store(out[3 * j + i] + l0, rd[0][i] * r[0][j] + rd[1][i] * r[1][j] + rd[2][i] * r[2][j]);
}

#if PBA_AVX512
__attribute__((target("avx512f"))) void world_inertia_avx512(const InertiaInput& in, double (&out)[9][kLanes],
                                                             int lanes) {
  for (int l0 = 0; l0 < lanes; l0 += 8) world_inertia_lanes<v8d>(in, out, l0);
}
#endif
__attribute__((target("avx2"))) void world_inertia_avx2(const InertiaInput& in, double (&out)[9][kLanes], int lanes) {
  for (int l0 = 0; l0 < lanes; l0 += 4) world_inertia_lanes<v4d>(in, out, l0);
}
void world_inertia_scalar(const InertiaInput& in, double (&out)[9][kLanes], int lanes) {
  for (int l = 0; l < lanes; ++l) world_inertia_lanes<double>(in, out, l);
}

}  // namespace

void RigidContacts::world_inv_inertias(const RigidBodySystem& s, const std::uint32_t* bodies, std::size_t count) {
  // the float solvers (not XPBD, which solves in double) see inverse moments at most
  // kSolverInertiaRatio times the smallest: a frame's inverse inertia in float holds the
  // rounding of the largest in every entry (2^-24 of it), and a 2 mm x 4 m rod's 2,000,000 : 1
  // buried its transverse inverse moments under it (12%), the passes' impulses no longer
  // matched their K, and the rod's spin grew tenfold a pass (docs/rigid-bodies.md)
  const bool clamp = s.settings_.solver != RigidSolverType::Xpbd;
  InertiaInput in{};  // (zeros in the lanes past the last body)
  double world[9][kLanes];
  // the awake bodies' frames, kLanes at a time (a sleeping body holds still like a static one
  // until something wakes it: its inverse inertia is zero, and its frame is not made; the
  // lanes are independent, so which bodies share a group moves no bit)
  std::uint32_t group[kLanes];
  int lanes = 0;
  auto flush = [&] {
#if PBA_AVX512
    if (simd == SimdPath::Avx512)
      world_inertia_avx512(in, world, lanes);
    else
#endif
    if (simd == SimdPath::Avx2)
      world_inertia_avx2(in, world, lanes);
    else
      world_inertia_scalar(in, world, lanes);
    for (int l = 0; l < lanes; ++l) {
      Mat3& o = inv_inertia[group[l]];
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) o[c][r] = world[3 * c + r][l];
    }
    lanes = 0;
  };
  for (std::size_t j = 0; j < count; ++j) {
    const std::uint32_t i = bodies ? bodies[j] : static_cast<std::uint32_t>(j);
    const Quat& q = s.q_[i];
    inertia_q[i] = q;
    if (s.asleep_[i]) {
      inv_inertia[i] = Mat3(0.0);
      continue;
    }
    Vec3 m = s.inv_inertia_[i];
    if (clamp) m = glm::min(m, Vec3(kSolverInertiaRatio * std::min({m.x, m.y, m.z})));
    const auto l = static_cast<std::size_t>(lanes);
    group[l] = i;
    in.q[0][l] = q.w, in.q[1][l] = q.x, in.q[2][l] = q.y, in.q[3][l] = q.z;
    in.m[0][l] = m.x, in.m[1][l] = m.y, in.m[2][l] = m.z;
    if (++lanes == kLanes) flush();
  }
  if (lanes > 0) flush();
}

void RigidContacts::prepare(RigidBodySystem& s) {
  const std::size_t n = s.type_.size();
  inv_inertia.resize(n);
  inertia_q.resize(n);
  refreshed.resize(n + 4, 0);  // (3 spare bytes: refreshed_lanes_avx2 reads 4 at a time)
  refresh_list.reserve(n);  // (so that a first refresh later does not allocate)
  world_inv_inertias(s, nullptr, n);
  built = has_colors = lanes_valid = false;
  s.profile_.one_point = s.profile_.lanes_kept = 0;  // (build() counts them)
  backward = !backward;
  pairs_same = pairs_same && pairs.size() == last_count;
  // (room for as many pairs as `pairs` has, so steady state does not allocate)
  if (rolling_mass.size() < pairs.size()) rolling_mass.reserve(pairs.capacity()), rolling_mass.resize(pairs.size());
  // (room for every body in the energy bound's lists, so a first bounce later does not allocate)
  bounces.reserve(n), shared.reserve(n);
  if (s.settings_.solver == RigidSolverType::Xpbd) {  // its own passes on the pairs
    colored_once = false;  // (the colours stay those of an earlier step's pairs)
    lanes_filled = false;  // (and the blocks those of an earlier step's layout)
    for (std::uint32_t i = 0; i < pairs.size(); ++i) set_rolling_mass(i);
    return;
  }
  // the velocities, the motion since the start of the step (none yet), the colours and the
  // blocks, and the carried impulses, which the first velocity integration applies (the
  // bodies' arrays each with a spare last row)
  rows.resize(n + 1);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& v = s.v_[i];
    const Vec3& w = s.w_[i];
    rows[i] = {{v.x, v.y, v.z}, {w.x, w.y, w.z}, {0, 0}};
  }
  rows[n] = {};
  start_kept = false;  // (until finish_velocities keeps this step's)
  // (each body's row written once, not zeroed and then its turn's w set in a second sweep:
  // the rain's 640 KB of rows, past the L2, were read back for that)
  motion.resize(8 * (n + 1));
  static constexpr double kStill[8] = {0, 0, 0, 1, 0, 0, 0, 0};  // dp 0, the identity turn
  for (std::size_t i = 0; i <= n; ++i) std::memcpy(&motion[8 * i], kStill, sizeof kStill);
  warm.assign(n + 1, SolverBody{});
  if (s.settings_.solver != RigidSolverType::SequentialImpulse) carry_fresh_slides(s);
  color(s);
  build(s);
  built = has_colors = lanes_valid = true;
  // (the coloured blocks' impulses build() added as it filled them)
  if (s.settings_.warm_starting) accumulate_warm(s, false);
}

void RigidContacts::finish_velocities(RigidBodySystem& s) {
  for (const Rolling& x : rolls) pairs[x.pair].rolling_impulse = x.impulse;
  const std::size_t n = s.type_.size();
  // the step's starting velocities kept for solver_report (the rows were made of them, and
  // nothing in the step writes a lane body's), the arrays written anew below
  start_v.swap(s.v_), start_w.swap(s.w_);
  // (with the room reserve() made for bodies, whichever buffer they hold: once the two have
  // it, a step allocates nothing)
  if (s.v_.capacity() < start_v.capacity()) s.v_.reserve(start_v.capacity());
  if (s.w_.capacity() < start_w.capacity()) s.w_.reserve(start_w.capacity());
  s.v_.resize(n), s.w_.resize(n);
  start_kept = true;
  for (std::size_t i = 0; i < n; ++i) {
    const SolverBody& r = rows[i];
    s.v_[i] = Vec3(r.v[0], r.v[1], r.v[2]);
    s.w_[i] = Vec3(r.w[0], r.w[1], r.w[2]);
  }
}

// The colours, in the order of the contact graph's levels (the bottom-up order of Guendelman,
// Bridson and Fedkiw 2003's shock propagation). Each dynamic body's level is its distance in
// contacts from a body that does not move (breadth first in pair order; a group touching none
// starts at 0). A manifold between two dynamic bodies goes to the band of its lower body's
// level, one against a fixed body to a last band (Box2D v3 solves those last too: they have
// the last word, so nothing is pushed through the ground or a wall). The bands are solved in
// order, each by its own colours, greedy in pair order (a manifold takes the lowest colour of
// its band in which neither of its dynamic bodies has one yet; static, kinematic and sleeping
// bodies do not count, the solver never writes them). The passes of even steps run each band's
// colours first to last, of odd steps last to first. Manifolds whose body has 64 colours in the
// band already go to the overflow, solved one at a time after the colours. Manifolds with
// rolling resistance are coloured like the others, and their rolling resistance is solved lane
// by lane after their colour's blocks (until 2026-12-02 they went to the overflow: in the
// 10,000-body rain, half spheres, that put most manifolds there, and the landing's steps spent
// three quarters of their contact passes solving them one at a time).
//
// Measured on the square pyramids under the soft step (mu 0.6, 120 Hz contacts): with one set
// of colours for all manifolds, ground contacts last (Box2D v3's constraint graph), pyramids
// of 13 levels or more sheared apart (the top of the 15-level one walked 42 cm in 5 s; with
// 30 Hz contacts it stood, with 60 Hz it did not); the levels alone did not change that, and
// alternating the colours by substep (or by pass) instead of by step left the 20-level
// pyramid's top jittering at 0.1-0.2 m/s and threw a dropped column of ten apart. With levels,
// the ground last and the order alternating by step: the 15-level top moves 1.4 mm and the
// 20-level 2 mm in 5 s, and columns of ten land standing under the soft step and TGS. Sweeping
// in pair order (as before the colours) held them too, but one manifold at a time.
//
// TGS does not use the colours: all its manifolds go to the overflow and are solved one at a
// time in pair order (the same kernel, one lane). With colours (the fixed bodies last, as the
// soft step, or first) a body of the closed box at 250 m/s left it under TGS: in the 400-body
// unit test with the fixed bodies first, in the 5000-body soak with them last once the pipeline's
// pair cache was in; in pair order both hold. TGS takes one rigid iteration per substep, and the
// order of that one pass decides whether a body spun up by collisions is held by the wall.
void RigidContacts::color(RigidBodySystem& s) {
  const std::size_t n = s.type_.size(), m = pairs.size();
  // room for as many pairs as the pairs have room for (so steady state does not allocate
  // when the colours or the levels reach a new peak: the counts below are bounded by them)
  const std::size_t room = pairs.capacity() + 1;
  for (auto* v : {&adjacency, &band_of, &by_band, &color_of, &by_color, &color_count, &ones_of_color, &one_cursor})
    v->reserve(2 * room);
  one_of.reserve(room);
  color_ones.reserve(room + 3);
  roll_start.reserve(room + 3);
  for (auto* v : {&level, &queue, &mask_band, &band_start, &band_colors, &adjacency_start}) v->reserve(n + 3);
  mask.reserve(n + 3);
  cursor.reserve(std::max(n, room) + 3);
  offset.reserve(room + 3);
  color_block.reserve(room + 3);
  restitution_lanes.reserve(room);
  rolls.reserve(room);
  color_key.reserve(2 * room);
  constexpr std::uint32_t kUnset = std::numeric_limits<std::uint32_t>::max();
  auto moving = [&](std::uint32_t i) { return s.type_[i] == BodyType::Dynamic && !s.asleep_[i]; };
  // the colours depend only on the pairs' bodies in order, which of them roll, which bodies move
  // and the solver: when none of that changed since the last colouring (a pile at rest, a
  // pyramid), the last colours stand. Whether the pairs changed, emit() found as it rewrote
  // them (pairs_same: each entry's bodies and rolling as last step's, which the colours were
  // made from or kept for), so the pairs are not read again here
  {
    color_moving.reserve(n + 3);
    const bool tgs = s.settings_.solver == RigidSolverType::Tgs;
    bool same = colored_once && pairs_same && color_moving.size() == n && color_tgs == tgs;
    color_moving.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint8_t x = moving(i);
      same = same && color_moving[i] == x;
      color_moving[i] = x;
    }
    color_tgs = tgs;
    colors_kept = same;
    if (same) return;
    colored_once = true;
  }
  // the pairs' bodies copied once into color_key, 8 bytes a pair in order, and read from there
  // rather than from the pairs (a line or two each) by the passes below, and whether a body
  // moves from color_moving: the colouring's samples -18% in the rain's landing, where it runs
  // every step
  color_key.resize(2 * m);
  for (std::size_t i = 0; i < m; ++i) color_key[2 * i] = pairs[i].a, color_key[2 * i + 1] = pairs[i].b;
  auto moving_now = [&](std::uint32_t i) { return color_moving[i] != 0; };
  auto body_a = [&](std::size_t i) { return color_key[2 * i]; };
  auto body_b = [&](std::size_t i) { return color_key[2 * i + 1]; };
  // the dynamic pairs as adjacency lists
  adjacency_start.assign(n + 1, 0);
  for (std::size_t i = 0; i < m; ++i) {
    const std::uint32_t a = body_a(i), b = body_b(i);
    if (moving_now(a) && moving_now(b)) ++adjacency_start[a + 1], ++adjacency_start[b + 1];
  }
  for (std::size_t i = 0; i < n; ++i) adjacency_start[i + 1] += adjacency_start[i];
  adjacency.resize(adjacency_start[n]);
  cursor.assign(adjacency_start.begin(), adjacency_start.end() - 1);
  for (std::size_t i = 0; i < m; ++i) {
    const std::uint32_t a = body_a(i), b = body_b(i);
    if (moving_now(a) && moving_now(b)) adjacency[cursor[a]++] = b, adjacency[cursor[b]++] = a;
  }
  // levels, breadth first from the bodies on fixed ones, then from any body not reached
  level.assign(n, kUnset);
  queue.clear();
  auto spread = [&](std::size_t head) {
    for (; head < queue.size(); ++head) {
      const std::uint32_t x = queue[head];
      for (std::uint32_t e = adjacency_start[x]; e < adjacency_start[x + 1]; ++e)
        if (level[adjacency[e]] == kUnset) level[adjacency[e]] = level[x] + 1, queue.push_back(adjacency[e]);
    }
    return head;
  };
  for (std::size_t i = 0; i < m; ++i) {
    const std::uint32_t a = body_a(i), b = body_b(i);
    const bool da = moving_now(a), db = moving_now(b);
    if (da == db) continue;
    const std::uint32_t x = da ? a : b;
    if (level[x] == kUnset) level[x] = 0, queue.push_back(x);
  }
  std::size_t head = spread(0);
  for (std::uint32_t i = 0; i < n; ++i)
    if (moving_now(i) && level[i] == kUnset) level[i] = 0, queue.push_back(i), head = spread(head);
  // bands, and the pairs sorted by band (stable: pair order within a band)
  band_of.resize(m);
  std::uint32_t bands = 0;
  for (std::size_t i = 0; i < m; ++i) {
    const std::uint32_t a = body_a(i), b = body_b(i);
    band_of[i] = moving_now(a) && moving_now(b) ? std::min(level[a], level[b]) : kUnset;
    if (band_of[i] != kUnset) bands = std::max(bands, band_of[i] + 1);
  }
  for (std::size_t i = 0; i < m; ++i)
    if (band_of[i] == kUnset) band_of[i] = bands;
  ++bands;
  band_start.assign(bands + 1, 0);
  for (std::size_t i = 0; i < m; ++i) ++band_start[band_of[i] + 1];
  for (std::uint32_t b = 0; b < bands; ++b) band_start[b + 1] += band_start[b];
  by_band.resize(m);
  cursor.assign(band_start.begin(), band_start.end() - 1);
  for (std::size_t i = 0; i < m; ++i) by_band[cursor[band_of[i]]++] = static_cast<std::uint32_t>(i);
  // greedy colours, band by band (band_colors: each band's first colour, and the end)
  mask_band.assign(n, kUnset);
  mask.resize(n);
  color_of.resize(m);
  color_count.clear();
  band_colors.assign(1, 0);
  overflow_count = 0;
  std::uint32_t base = 0, width = 0, band = 0;
  for (const std::uint32_t i : by_band) {
    const std::uint32_t a = body_a(i), b = body_b(i);
    if (band_of[i] != band) {
      base += width, width = 0, band = band_of[i];
      band_colors.push_back(base);
    }
    // (empty bands leave no colours)
    const bool da = moving_now(a), db = moving_now(b);
    std::uint64_t used = 0;
    if (da && mask_band[a] == band) used |= mask[a];
    if (db && mask_band[b] == band) used |= mask[b];
    if (~used == 0 || s.settings_.solver == RigidSolverType::Tgs) {
      color_of[i] = kOverflow;
      ++overflow_count;
      continue;
    }
    const std::uint32_t k = static_cast<std::uint32_t>(std::countr_zero(~used));
    width = std::max(width, k + 1);
    color_of[i] = base + k;
    if (color_count.size() <= base + k) color_count.resize(base + k + 1, 0);
    ++color_count[base + k];
    for (const std::uint32_t x : {a, b}) {
      if (!moving_now(x)) continue;
      if (mask_band[x] != band) mask_band[x] = band, mask[x] = 0;
      mask[x] |= std::uint64_t{1} << k;
    }
  }
  band_colors.push_back(static_cast<std::uint32_t>(color_count.size()));
}

void RigidContacts::build(RigidBodySystem& s) {
  // the blocks: each colour's manifolds in pair order, kLanes to a block, its manifolds of more
  // than one point in ContactBlocks and those of one point in OnePointBlocks (src/rigid/solver.h;
  // decided here each step, as a pair's points come and go while its colour stays), then the
  // overflow's, all in ContactBlocks. Only whole OnePointBlocks: a colour's one-point manifolds
  // beyond a multiple of kLanes (its last ones in pair order) stay in its ContactBlocks, where
  // they fill the last block's empty lanes, so a colour takes no more blocks than before (with
  // a partial block of each kind per colour, the 2870 pyramid's 1,337 one-point manifolds over
  // its colours made the passes' samples 2-3% more, not fewer)
  const std::size_t colors = color_count.size();
  ones_of_color.assign(colors, 0);
  // (whether the layout stands: see lanes_kept)
  bool kept = reuse_lanes && lanes_filled && colors_kept && one_of.size() == pairs.size() &&
              kept_slop == s.settings_.linear_slop && kept_thinnest == thinnest;
  one_of.resize(pairs.size());
  const bool counted = pair_points.size() >= pairs.size();  // (emit() wrote every pair's)
  {
    // (through local pointers: the byte stores to one_of may alias any vector's members, and
    // the loop read them back each pair, 27 instructions a pair on pyramid1240 at rest)
    const std::size_t m = pairs.size();
    const std::uint32_t* colour = color_of.data();
    const std::uint8_t* points = pair_points.data();
    std::uint8_t* one_out = one_of.data();
    std::uint32_t* ones_in = ones_of_color.data();
    bool same = true;
    for (std::size_t i = 0; i < m; ++i) {
      const bool one = colour[i] != kOverflow && (counted ? points[i] : pairs[i].count) == 1;
      same &= one_out[i] == one;
      one_out[i] = one;
      if (one) ++ones_in[colour[i]];
    }
    kept = kept && same;
  }
  lanes_kept = kept;
  lanes_filled = false;  // (until the blocks are filled below)
  kept_slop = s.settings_.linear_slop, kept_thinnest = thinnest;
  for (std::size_t c = 0; c < colors; ++c) ones_of_color[c] -= ones_of_color[c] % kLanes;
  color_block.resize(colors + 2);
  color_ones.resize(colors + 1);
  std::size_t next = 0, next_one = 0;
  for (std::size_t c = 0; c < colors; ++c) {
    color_block[c] = next, next += (color_count[c] - ones_of_color[c] + kLanes - 1) / kLanes;
    color_ones[c] = next_one, next_one += (ones_of_color[c] + kLanes - 1) / kLanes;
  }
  color_block[colors] = next;
  color_ones[colors] = next_one;
  colored_blocks = next;
  next += (overflow_count + kLanes - 1) / kLanes;
  color_block[colors + 1] = next;
  // (grown by half again when a new peak needs more, so a scene that moves does not allocate every step)
  if (blocks.size() < next) {
    blocks.reserve(next + next / 2), anchors.reserve(next + next / 2), block_masses.reserve(next + next / 2);
    blocks.resize(next), anchors.resize(next), block_masses.resize(next);
  }
  if (ones.size() < next_one) {
    ones.reserve(next_one + next_one / 2), one_anchors.reserve(next_one + next_one / 2);
    one_masses.reserve(next_one + next_one / 2);
    ones.resize(next_one), one_anchors.resize(next_one), one_masses.resize(next_one);
  }
  block_count = next;
  one_blocks = next_one;
  for (std::size_t c = 0; c < colors; ++c) s.profile_.one_point += ones_of_color[c];
  const auto spare = static_cast<std::uint32_t>(s.type_.size());
  // the empty lanes past a block's lane type's last group: those below it, fill_block's lane
  // type writes and then clears itself (by the same clear_lane, so the same bits), and nothing
  // reads them in between; cleared here as well, they were written twice a step
  const int width = simd == SimdPath::Avx512 ? 8 : simd == SimdPath::Avx2 ? 4 : 1;
  auto lay_out = [&](auto* array, auto* anchor_array, std::size_t from, std::size_t to, std::uint32_t left) {
    for (std::size_t b = from; b < to; ++b) {
      auto& k = array[b];
      k.lanes = static_cast<int>(std::min<std::uint32_t>(left, kLanes));
      left -= static_cast<std::uint32_t>(k.lanes);
      if (!kept) k.write_a = k.write_b = 0;  // (kept: last step's, which fill_block leaves)
      for (int l = std::min((k.lanes + width - 1) / width * width, kLanes); l < kLanes; ++l)
        clear_lane(k, anchor_array[b], l, spare);
    }
  };
  for (std::size_t c = 0; c <= colors; ++c) {
    const std::uint32_t all = c < colors ? color_count[c] : overflow_count, one = c < colors ? ones_of_color[c] : 0;
    lay_out(blocks.data(), anchors.data(), color_block[c], color_block[c + 1], all - one);
    if (c < colors) lay_out(ones.data(), one_anchors.data(), color_ones[c], color_ones[c + 1], one);
  }
  // each colour's pairs in pair order, those of more points first (the overflow's last), then
  // the blocks filled one after another (a block's lines stay in cache while its lanes are written)
  offset.assign(colors + 2, 0);
  for (std::size_t c = 0; c < colors; ++c) offset[c + 1] = offset[c] + color_count[c];
  offset[colors + 1] = offset[colors] + overflow_count;
  cursor.assign(offset.begin(), offset.end() - 1);
  one_cursor.resize(colors);
  for (std::size_t c = 0; c < colors; ++c) one_cursor[c] = static_cast<std::uint32_t>(offset[c + 1] - ones_of_color[c]);
  by_color.resize(pairs.size());
  lane_of.reserve(pairs.capacity());
  lane_of.resize(pairs.size());
  // (kept: by_color is last step's, made from the same colours and kinds of block)
  for (std::size_t i = 0; i < (kept ? 0 : pairs.size()); ++i) {
    const std::size_t c = color_of[i] == kOverflow ? colors : color_of[i];
    // (one_cursor[c] reaches offset[c + 1] when the colour's whole one-point blocks are full)
    if (one_of[i] && one_cursor[c] < offset[c + 1]) by_color[one_cursor[c]++] = static_cast<std::uint32_t>(i);
    else by_color[cursor[c]++] = static_cast<std::uint32_t>(i);
  }
  restitution_lanes.clear();
  rolls.clear();
  roll_start.resize(colors + 1);
  // the lanes that roll: what their rolling resistance reads, copied in lane order
  // (a one-point lane's rolling resistance is its block's: OnePointBlock)
  // (the lanes that roll as fill_block found them: its result)
  auto collect_rolls = [&](const ContactBlock& k, std::size_t b, std::uint32_t rolling_lanes) {
    for (std::uint32_t left = rolling_lanes; left != 0; left &= left - 1) {
      const int l = std::countr_zero(left);
      const std::uint32_t i = k.pair[l];
      const ContactPair& p = pairs[i];
      rolls.push_back({.mass = rolling_mass[i], .ia = inv_inertia[p.a], .ib = inv_inertia[p.b],
                       .impulse = p.rolling_impulse, .rolling = p.rolling,
                       .key = static_cast<std::uint32_t>(b * kLanes + static_cast<std::size_t>(l)), .pair = i, .a = p.a,
                       .b = p.b, .write_a = ((k.write_a >> l) & 1) != 0, .write_b = ((k.write_b >> l) & 1) != 0});
    }
  };
  // the first warm start of a coloured block (with warm starting: accumulate_warm's part for
  // it), added as soon as the block is filled, while its lines are in L1: the blocks filled in
  // colour order, a colour's ContactBlocks then its one-point blocks, are the order in which
  // accumulate_warm adds them, so each body's accumulators sum the same terms in the same order
  // (the same bits); read again after the fill, the blocks streamed from L3 once more
  const bool warm_now = s.settings_.warm_starting;
  const BodyArrays bodies = arrays(s);
  // (colour `colors` is the overflow)
  auto fill_blocks = [&](std::size_t c) {
    for (std::size_t b = color_block[c]; b < color_block[c + 1]; ++b) {
      const std::size_t first = offset[c] + (b - color_block[c]) * kLanes;  // the block's first slot of by_color
      collect_rolls(blocks[b], b, fill_block(s, blocks.data(), anchors.data(), block_count, b, first));
      if (warm_now && c < colors) warm_colored(simd, blocks.data(), b, b + 1, bodies);
    }
  };
  for (std::size_t c = 0; c < colors; ++c) {
    roll_start[c] = rolls.size();
    fill_blocks(c);
    const std::size_t first_one = offset[c + 1] - ones_of_color[c];
    for (std::size_t b = color_ones[c]; b < color_ones[c + 1]; ++b) {
      fill_block(s, ones.data(), one_anchors.data(), one_blocks, b, first_one + (b - color_ones[c]) * kLanes);
      if (warm_now) warm_colored(simd, ones.data(), b, b + 1, bodies);
    }
  }
  colored_rolls = rolls.size();
  roll_start[colors] = colored_rolls;
  fill_blocks(colors);
  lanes_filled = true;
  if (kept) s.profile_.lanes_kept = pairs.size();
}

// Block b's manifolds (by_color from `first`) into its lanes: what they need gathered lane by
// lane (FillInput), the frames, masses and anchors a lane type at a time (fill_lanes), then
// each lane's normal velocities before the solve.
template <class B>
std::uint32_t RigidContacts::fill_block(RigidBodySystem& s, B* block_array, AnchorsOf<B::kPoints>* anchor_array,
                               std::size_t count_in_use, std::size_t b, std::size_t first) {
  constexpr int P = B::kPoints;
  constexpr bool kOne = P == 1;
  B& k = block_array[b];
  AnchorsOf<P>& g = anchor_array[b];
  const int width = simd == SimdPath::Avx512 ? 8 : simd == SimdPath::Avx2 ? 4 : 1;
  const int used = (k.lanes + width - 1) / width * width;
  const auto spare = static_cast<std::uint32_t>(s.type_.size());
  FillInput in;
  auto* rows_of_input = reinterpret_cast<double(*)[kLanes]>(&in);
  int count[kLanes] = {};
  std::uint32_t rolling_lanes = 0;  // (bit l: lane l's pair rolls; the result)
  // bit l: lane l's pair has a restitution, restitution[l] (restitution_lanes takes them in lane
  // order after the gather)
  std::uint32_t bounces = 0;
  double restitution[kLanes];
  // the lanes' bodies, write masks, inverse masses, units and slop: last step's while the
  // layout stands (lanes_kept), else gathered below and kept for the next step
  const bool kept = lanes_kept;
  // (kept, a lane of more than one point reads its bodies from the block, not the pair's key:
  // the fill does not read the pair's first line; a rolling lane's roll still does)
  const bool from_frame = kept && !kOne;
  // the lanes [0, gathered) whose copies gather_fill_avx2 makes four at a time (a block's whole
  // fours on the AVX2 path, of either kind: a OnePointBlock's lane loop made about 315
  // instructions a lane in the rain's landing, 7,500 lanes a step; the AVX-512 path's
  // fill_block is as it was)
  int gathered = 0;
#if PBA_ROWS_AVX2
  if (simd == SimdPath::Avx2) gathered = k.lanes / 4 * 4;
#endif
  LaneMasses& masses = (kOne ? one_masses : block_masses)[b];
  if (kept) {
    std::memcpy(in.ma, masses.ma, sizeof in.ma);
    std::memcpy(in.mb, masses.mb, sizeof in.mb);
    std::memcpy(in.unit, masses.unit, sizeof in.unit);
  }
  for (int l = 0; l < used; ++l) {
    if (l >= k.lanes) {  // past the block's manifolds: zeros, unit 1 (clear_lane's values)
      for (std::size_t r = 0; r < kInputRows; ++r) rows_of_input[r][l] = 0;
      in.unit[l] = 1;
      continue;
    }
    const std::uint32_t index = by_color[first + static_cast<std::size_t>(l)];
    if (first + l + kPrefetchAhead < by_color.size())
      prefetch_pair<P>(pairs[by_color[first + l + kPrefetchAhead]], from_frame);
    // and the next block's lines, to be written (the passes left them in the outer caches),
    // spread over this block's lanes: lane l asks for lines l, l + kLanes, ... of the block and
    // of its anchors, the whole strides of kLanes lines without a test (the counts known, so
    // the loops unroll), then the lanes below the rest (a select and a loop a line were some
    // 45 instructions a lane, a twelfth of prepare's on pyramid1240 at rest)
    if (b + 1 < count_in_use) {
      ask_lines<sizeof(B) / 64>(&block_array[b + 1], l);
      ask_lines<sizeof(AnchorsOf<P>) / 64>(&anchor_array[b + 1], l);
    }
    const ContactPair& c = pairs[index];
    if (!kept) {
      const bool da = moves(s, c.a, s.type_, s.asleep_), db = moves(s, c.b, s.type_, s.asleep_);
      k.a[l] = c.a, k.b[l] = c.b, k.pair[l] = index;
      if (da) k.write_a |= 1u << l;
      if (db) k.write_b |= 1u << l;
      const double ma = s.asleep_[c.a] ? 0 : s.inv_mass_[c.a], mb = s.asleep_[c.b] ? 0 : s.inv_mass_[c.b];
      in.ma[l] = ma, in.mb[l] = mb, in.unit[l] = impulse_unit(ma + mb);  // the lane's impulse unit (fill_lanes)
      // the overlap the rigid passes leave alone: the settings' slop, less for a small body
      k.slop[l] = static_cast<Real>(slop_of(s, c.a, c.b));
      lane_of[index] = static_cast<std::uint32_t>(b * kLanes + static_cast<std::size_t>(l)) | (kOne ? kOneLane : 0u);
    }
    // (the rest of a gathered lane: gather_fill_avx2's, after this loop)
    if (l < gathered) continue;
    count[l] = c.count;
    const Vec3 t[3] = {c.t1, c.t2, c.normal};
    const std::uint32_t body_a = k.a[l], body_b = k.b[l];  // (c.a, c.b: written above when not kept)
    const Mat3& ia = inv_inertia[body_a];
    const Mat3& ib = inv_inertia[body_b];
    const Vec3& com_a = s.com_[body_a];
    const Vec3& com_b = s.com_[body_b];
    const Vec3 dab = com_a - com_b, dba = com_b - com_a;
    for (int i = 0; i < 3; ++i) {
      for (int r = 0; r < 3; ++r)
        in.t[r][i][l] = t[r][i], in.ia[3 * i + r][l] = ia[i][r], in.ib[3 * i + r][l] = ib[i][r];
      in.dab[i][l] = dab[i], in.dba[i][l] = dba[i], in.ca[i][l] = c.ca[i];
    }
    for (int p = 0; p < P; ++p) {
      const bool on = p < c.count;
      const SolverPoint& q = c.points[p];
      const Vec3 arm = on ? q.at - com_a : Vec3(0);
      in.active[p][l] = on ? 1 : 0;
      for (int i = 0; i < 3; ++i)
        in.arm[p][i][l] = arm[i], in.sa[p][i][l] = on ? q.sa[i] : 0, in.sb[p][i][l] = on ? q.sb[i] : 0;
      in.offset[p][l] = on ? q.offset : 0;
      in.impulse[p][l] = on ? c.normal_impulse[p] : 0;
    }
    in.friction[l] = c.friction, in.twist_radius[l] = c.twist_radius;
    in.tangent_impulse[0][l] = c.tangent_impulse[0], in.tangent_impulse[1][l] = c.tangent_impulse[1];
    in.twist_impulse[l] = c.twist_impulse;
    in.rolling[l] = c.rolling;
    in.balls[l] = c.balls != 0 ? 1 : 0;
    // (a one-point lane's: fill_lanes reads it for those only, and it sits in the key's line)
    if constexpr (kOne)
      for (int i = 0; i < 3; ++i) in.rolling_impulse[i][l] = c.rolling_impulse[i];
    if (c.rolling > 0) rolling_lanes |= 1u << l;
    if (c.restitution != 0) bounces |= 1u << l, restitution[l] = c.restitution;
  }
#if PBA_ROWS_AVX2
  if (gathered > 0)
    gather_fill_avx2<P>(in, pairs.data(), &by_color[first], k.a, k.b, inv_inertia.data(), s.com_.data(), gathered,
                        count, restitution, rolling_lanes, bounces);
#endif
  // (a one-point lane's rolling mass is fill_lanes')
  if constexpr (kOne) k.rolls = rolling_lanes;
  else
    for (std::uint32_t left = rolling_lanes; left != 0; left &= left - 1)
      set_rolling_mass(by_color[first + static_cast<std::size_t>(std::countr_zero(left))]);
  for (std::uint32_t left = bounces; left != 0; left &= left - 1) {
    const int l = std::countr_zero(left);
    restitution_lanes.push_back({static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(l), restitution[l], kOne});
  }
  if (!kept) {
    std::memcpy(masses.ma, in.ma, sizeof in.ma);
    std::memcpy(masses.mb, in.mb, sizeof in.mb);
    std::memcpy(masses.unit, in.unit, sizeof in.unit);
  }
#if PBA_AVX512
  if (simd == SimdPath::Avx512)
    fill_avx512(in, k, g, k.lanes);
  else
#endif
  if (simd == SimdPath::Avx2)
    fill_avx2(in, k, g, k.lanes, b + 1 < count_in_use ? &block_array[b + 1] : nullptr,
              b + 1 < count_in_use ? &anchor_array[b + 1] : nullptr);
  else
    fill_scalar(in, k, g, k.lanes);
  for (int l = k.lanes; l < used; ++l) clear_lane(k, g, l, spare);
  // the normal velocities before the solve (a lane type at a time), of a block with a lane that
  // has a restitution: the restitution pass reads them. The other blocks' are made when asked
  // for (solver_report, from the step's starting velocities), and the biased passes' running
  // minimum of the points' normal velocities starts from +inf there: the minimum of both is
  // the number the minimum from them gives, to the bit (a min that keeps the first of equal
  // numbers, a NaN first included; see solver_report). Made for every block, they were 3% of
  // the 1240 pyramid's resting step and 2% of the 1000 fallen boxes', read by no one
  if (bounces != 0) {
    approaches(simd, k, count, arrays(s));
  } else {
    for (int p = 0; p < P; ++p) std::fill_n(k.approach[p], k.lanes, std::numeric_limits<Real>::infinity());
  }
  return rolling_lanes;
}

// rolling resistance acts on the relative angular velocity: its mass, for a pair that rolls
void RigidContacts::set_rolling_mass(std::uint32_t index) {
  const ContactPair& c = pairs[index];
  if (!(c.rolling > 0)) return;
  const Mat3 k = inv_inertia[c.a] + inv_inertia[c.b];
  rolling_mass[index] = glm::determinant(k) > 0 ? glm::inverse(k) : Mat3(0.0);
}

namespace {

// What refreshing a lane's rows that depend on its bodies' inverse inertias reads
// (refresh_inertia): its block's frame, masses and arms as filled, and the bodies' world
// inverse inertias at their poses now, gathered lane by lane from the lanes that need it (a
// compact list: in the rain's landing about one lane in seven of the blocks, scattered), so
// that the arithmetic runs a lane type at a time as fill_lanes' does.
struct RefreshInput {
  double t[3][3][kLanes];               // t1, t2, n by component (the block's floats)
  double ma[kLanes], mb[kLanes];        // the block's inverse masses times u (1/kg)
  double unit[kLanes];                  // the lane's impulse unit u
  double ca[3][kLanes], cb[3][kLanes];  // the centroid from a's centre and from b's, in the frame (m)
  double x[4][kLanes], y[4][kLanes];    // a ContactBlock's points from the centroid (m)
  double on[4][kLanes];                 // 1 where the point's effective mass is not zero (in use)
  double ia[9][kLanes], ib[9][kLanes];  // the world inverse inertias, column by column (glm's order)
};
// ... and the rows it makes, rounded to the block's floats, to be put back into the lanes
struct RefreshOutput {
  Real ia[6][kLanes], ib[6][kLanes];  // the inverse inertias in the frame times u
  Real k[10][kLanes], mass[4][kLanes];
  Real tangent_mass[2][kLanes], tangent_k[3][kLanes], twist_mass[kLanes];
  Real rolling_mass[6][kLanes];       // a one-point lane's (written back where it rolls)
};

// Lanes [l0, l0 + width) of `out` from `in` (P: the normal points of the lanes' block type):
// the inverse inertias in the frame, K, the normal, tangent and twist effective masses and a
// one-point lane's rolling mass, by fill_lanes' arithmetic in double from the block's floats.
// The operations and their order are the same on every lane type (and were those of the
// lane-by-lane refresh before it), so every path gives the same bits.
template <class V, int P>
PBA_LANES void refresh_lanes(const RefreshInput& in, RefreshOutput& out, int l0) {
  const V zero = lanes::splat<V>(0.0);
  const V unit = from<V>(in.unit, l0);
  V t[3][3];
  for (int r = 0; r < 3; ++r)
    for (int i = 0; i < 3; ++i) t[r][i] = from<V>(in.t[r][i], l0);
  const V ma = from<V>(in.ma, l0) / unit, mb = from<V>(in.mb, l0) / unit;
  // the inverse inertias in the frame
  V ia[6], ib[6];
  in_frame(in.ia, t, l0, ia), in_frame(in.ib, t, l0, ib);
  for (int e = 0; e < 6; ++e) put(out.ia[e], l0, ia[e] * unit), put(out.ib[e], l0, ib[e] * unit);
  // the points' offsets from a's centre in the frame, and the rows the inverse inertias enter
  V ca[3], cb[3], d[3];
  for (int i = 0; i < 3; ++i) ca[i] = from<V>(in.ca[i], l0), cb[i] = from<V>(in.cb[i], l0), d[i] = cb[i] - ca[i];
  V x[P], y[P];
  decltype(zero < zero) on[P];
  for (int p = 0; p < P; ++p) {
    on[p] = from<V>(in.on[p], l0) > zero;
    x[p] = ca[0], y[p] = ca[1];
    if constexpr (P > 1) x[p] = x[p] + from<V>(in.x[p], l0), y[p] = y[p] + from<V>(in.y[p], l0);
  }
  inertia_rows<V, P>(out, l0, ia, ib, ma, mb, unit, x, y, on, d, ca, cb);
  // a one-point lane's rolling mass
  if constexpr (P == 1) {
    const V a = ia[0] + ib[0], b = ia[1] + ib[1], c = ia[2] + ib[2], dd = ia[3] + ib[3], e = ia[4] + ib[4],
            f = ia[5] + ib[5];
    const V adj[6] = {dd * f - e * e, c * e - b * f, b * e - c * dd, a * f - c * c, b * c - a * e, a * dd - b * b};
    const V det = a * adj[0] + b * adj[1] + c * adj[2];
    for (int i = 0; i < 6; ++i) put(out.rolling_mass[i], l0, keep(det > zero, adj[i] / det / unit));
  }
}

#if PBA_AVX512
template <int P>
__attribute__((target("avx512f"))) void refresh_avx512(const RefreshInput& in, RefreshOutput& out, int lanes) {
  for (int l0 = 0; l0 < lanes; l0 += 8) refresh_lanes<v8d, P>(in, out, l0);
}
#endif
template <int P>
__attribute__((target("avx2"))) void refresh_avx2(const RefreshInput& in, RefreshOutput& out, int lanes) {
  for (int l0 = 0; l0 < lanes; l0 += 4) refresh_lanes<v4d, P>(in, out, l0);
}
template <int P>
void refresh_scalar(const RefreshInput& in, RefreshOutput& out, int lanes) {
  for (int l = 0; l < lanes; ++l) refresh_lanes<double, P>(in, out, l);
}

// The lanes [0, lanes) of each of blocks [0, count) whose body a or b was refreshed
// (`refreshed`, by body), as bit l of mask[block]. On AVX2 by gathers, 8 lanes at a time: each
// lane's byte read as the low byte of 4 (so `refreshed` has 3 spare bytes past its last row).
// Lane by lane, the test was ~8 instructions and a branch taken at random (about 1 lane in 5
// in the rain's landing) a lane, 11,000 lanes a landing step's substep.
template <class B>
void refreshed_lanes_scalar(const B* blocks, std::size_t count, const std::uint8_t* refreshed, std::uint32_t* mask) {
  for (std::size_t k = 0; k < count; ++k) {
    const B& block = blocks[k];
    mask[k] = 0;
    for (int l = 0; l < block.lanes; ++l)
      mask[k] |= static_cast<std::uint32_t>(refreshed[block.a[l]] | refreshed[block.b[l]]) << l;
  }
}
#if PBA_ROWS_AVX2
static_assert(kLanes == 16);
template <class B>
__attribute__((target("avx2"))) void refreshed_lanes_avx2(const B* blocks, std::size_t count,
                                                          const std::uint8_t* refreshed, std::uint32_t* mask) {
  const int* bytes = reinterpret_cast<const int*>(refreshed);
  const __m256i low = _mm256_set1_epi32(0xff), zero = _mm256_setzero_si256();
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (std::size_t k = 0; k < count; ++k) {
    const B& block = blocks[k];
    const int lanes = block.lanes;
    std::uint32_t m = 0;
    for (int h = 0; h < lanes; h += 8) {
      // (lanes past `lanes` not read: their bodies may be anything)
      const __m256i in_use = _mm256_cmpgt_epi32(_mm256_set1_epi32(lanes - h), lane);
      const __m256i ia = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(block.a + h));
      const __m256i ib = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(block.b + h));
      const __m256i ra = _mm256_mask_i32gather_epi32(zero, bytes, ia, in_use, 1);
      const __m256i rb = _mm256_mask_i32gather_epi32(zero, bytes, ib, in_use, 1);
      const __m256i none = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_or_si256(ra, rb), low), zero);
      m |= (~static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(none))) & 0xffu) << h;
    }
    mask[k] = m & ((1u << lanes) - 1);
  }
}
#endif
template <class B>
void refreshed_lanes(SimdPath simd, const B* blocks, std::size_t count, const std::uint8_t* refreshed,
                     std::uint32_t* mask) {
#if PBA_ROWS_AVX2
  if (simd != SimdPath::Scalar) return refreshed_lanes_avx2(blocks, count, refreshed, mask);
#endif
  refreshed_lanes_scalar(blocks, count, refreshed, mask);
}

// The lanes of blocks [0, count) with a body whose inverse inertia was refreshed (`refreshed`,
// by body) made again from the world inverse inertias `inv_inertia` (by body): up to kLanes
// of them at a time gathered into a RefreshInput, computed, and put back lane by lane.
template <class B>
void refresh_blocks(SimdPath simd, B* blocks, std::size_t count, const std::uint8_t* refreshed,
                    const Mat3* inv_inertia) {
  constexpr int P = B::kPoints;
  // (not zeroed: a flush reads only the lanes up to its count rounded up to the kernels' width,
  // and the lanes past the count, whose results are not put back, are zeroed at the last flush
  // (the only partial one); zeroing the whole input was 769 quadwords a call)
  RefreshInput in;
  RefreshOutput out;
  std::uint32_t at[kLanes];  // each gathered lane's block * kLanes + lane
  int n = 0;
  auto flush = [&] {
    if (n < kLanes) {
      const int to = std::min(kLanes, (n + 7) & ~7);  // (8 double lanes, the widest kernel's)
      auto clear = [&](double* row) { std::fill(row + n, row + to, 0.0); };
      for (auto& c : in.t)
        for (double* row : c) clear(row);
      clear(in.ma), clear(in.mb), clear(in.unit);
      for (int i = 0; i < 3; ++i) clear(in.ca[i]), clear(in.cb[i]);
      for (int p = 0; p < 4; ++p) clear(in.x[p]), clear(in.y[p]), clear(in.on[p]);
      for (int e = 0; e < 9; ++e) clear(in.ia[e]), clear(in.ib[e]);
    }
#if PBA_AVX512
    if (simd == SimdPath::Avx512)
      refresh_avx512<P>(in, out, n);
    else
#endif
    if (simd == SimdPath::Avx2)
      refresh_avx2<P>(in, out, n);
    else
      refresh_scalar<P>(in, out, n);
    for (int i = 0; i < n; ++i) {
      B& k = blocks[at[i] / kLanes];
      const int l = static_cast<int>(at[i] % kLanes);
      for (int e = 0; e < 6; ++e) k.ia[e][l] = out.ia[e][i], k.ib[e][l] = out.ib[e][i];
      for (int e = 0; e < P * (P + 1) / 2; ++e) k.k[e][l] = out.k[e][i];
      for (int p = 0; p < P; ++p) k.mass[p][l] = out.mass[p][i];
      k.tangent_mass[0][l] = out.tangent_mass[0][i], k.tangent_mass[1][l] = out.tangent_mass[1][i];
      for (int e = 0; e < 3; ++e) k.tangent_k[e][l] = out.tangent_k[e][i];
      if constexpr (P > 1) {
        k.twist_mass[l] = out.twist_mass[i];
      } else if (k.rolling[l] > 0) {
        for (int e = 0; e < 6; ++e) k.rolling_mass[e][l] = out.rolling_mass[e][i];
      }
    }
    n = 0;
  };
  // (the lanes to refresh found for a chunk of blocks at a time)
  constexpr std::size_t kChunk = 64;
  std::uint32_t lanes_of[kChunk];
  for (std::size_t b = 0; b < count; ++b) {
    if (b % kChunk == 0) refreshed_lanes(simd, blocks + b, std::min(kChunk, count - b), refreshed, lanes_of);
    const B& k = blocks[b];
    for (std::uint32_t lanes = lanes_of[b % kChunk]; lanes != 0; lanes &= lanes - 1) {
      const int l = std::countr_zero(lanes);
      at[n] = static_cast<std::uint32_t>(b * kLanes + static_cast<std::size_t>(l));
      in.t[0][0][n] = k.t1[0][l], in.t[0][1][n] = k.t1[1][l], in.t[0][2][n] = k.t1[2][l];
      in.t[1][0][n] = k.t2[0][l], in.t[1][1][n] = k.t2[1][l], in.t[1][2][n] = k.t2[2][l];
      in.t[2][0][n] = k.n[0][l], in.t[2][1][n] = k.n[1][l], in.t[2][2][n] = k.n[2][l];
      in.ma[n] = k.ma[l], in.mb[n] = k.mb[l], in.unit[n] = k.unit[l];
      for (int i = 0; i < 3; ++i) in.ca[i][n] = k.ca[i][l], in.cb[i][n] = k.cb[i][l];
      for (int p = 0; p < P; ++p) {
        in.on[p][n] = k.mass[p][l] != 0 ? 1 : 0;
        if constexpr (P > 1) in.x[p][n] = k.x[p][l], in.y[p][n] = k.y[p][l];
      }
      const Mat3& ia = inv_inertia[k.a[l]];
      const Mat3& ib = inv_inertia[k.b[l]];
      for (int i = 0; i < 3; ++i)
        for (int r = 0; r < 3; ++r) in.ia[3 * i + r][n] = ia[i][r], in.ib[3 * i + r][n] = ib[i][r];
      if (++n == kLanes) flush();
    }
  }
  if (n > 0) flush();
}

}  // namespace

void RigidContacts::refresh_inertia(RigidBodySystem& s) {
  // the bodies that turned too far from their inverse inertia's orientation: (r - 1) a >
  // kInertiaTurn, a the angle between the orientations, cos(a / 2) = |q . q_ref|, taken as
  // 8 (1 - cos(a / 2)) = a^2 (its small-angle form; larger angles only refresh sooner)
  // (in the soft step's and TGS's substeps the frames now are in the free motion's lanes: a refreshed
  // body's is put into q_, where world_inv_inertias reads it)
  refresh_list.clear();
  for (std::size_t kind = 0; kind < moving.size(); ++kind) {
    if (static_cast<FreeRotation>(kind) == FreeRotation::Round) continue;
    const double* lanes = free_lanes_of(kind);  // (nullptr unless live)
    const std::vector<std::uint32_t>& list = moving[kind];
    auto frame_at = [&](std::size_t j) {
      const double* at = lanes + free_lane_at(j) + kLineQ * kFreeLaneWidth;
      return Quat(at[0], at[kFreeLaneWidth], at[2 * kFreeLaneWidth], at[3 * kFreeLaneWidth]);
    };
    std::size_t j = 0;
    if (lanes && simd == SimdPath::Avx2) {
      // on AVX2 4 bodies at a time, the test's arithmetic in lanes (its 49 instructions a body
      // were 2.5% of the terrain's); the positions it leaves, below (the other paths' kernels
      // are not written: all their bodies go by the loop after this, and the list is not
      // grown and zeroed for nothing)
      const std::size_t was = refresh_list.size();
      refresh_list.resize(was + list.size());  // (within what prepare() reserved)
      const std::size_t far = turned_far_wide(simd, list.data(), list.size(), lanes, inertia_q.data(),
                                              refresh_list.data() + was, j);
      for (std::size_t e = was; e < was + far; ++e) {
        const std::uint32_t i = list[refresh_list[e]];
        s.q_[i] = frame_at(refresh_list[e]);
        refreshed[i] = 1;
        refresh_list[e] = i;
      }
      refresh_list.resize(was + far);
    }
    for (; j < list.size(); ++j) {
      const std::uint32_t i = list[j];
      double spread;
      Quat q;
      if (lanes) {  // (the spread formed once a step by the arithmetic below, integrate_wide.cpp's gather)
        spread = lanes[free_lane_at(j) + kLineSpread * kFreeLaneWidth];
        q = frame_at(j);
      } else {
        const Vec3& m = s.inv_inertia_[i];
        spread = solver_inertia_spread(m.x, m.y, m.z);
        q = s.q_[i];
      }
      const double c = std::abs(glm::dot(q, inertia_q[i]));
      if (8 * (1 - c) * spread * spread <= kInertiaTurn * kInertiaTurn) continue;
      s.q_[i] = q;
      refreshed[i] = 1;
      refresh_list.push_back(i);
    }
  }
  if (refresh_list.empty()) return;
  world_inv_inertias(s, refresh_list.data(), refresh_list.size());
  refresh_blocks(simd, blocks.data(), block_count, refreshed.data(), inv_inertia.data());
  refresh_blocks(simd, ones.data(), one_blocks, refreshed.data(), inv_inertia.data());
  for (Rolling& x : rolls) {
    if (!(refreshed[x.a] | refreshed[x.b])) continue;
    set_rolling_mass(x.pair);
    x.mass = rolling_mass[x.pair];
    x.ia = inv_inertia[x.a], x.ib = inv_inertia[x.b];
  }
  for (const std::uint32_t i : refresh_list) refreshed[i] = 0;
}

bool RigidContacts::solver_report(std::size_t k, int p, double& approach, double& max_impulse) const {
  if (!lanes_valid || k >= lane_of.size()) return false;
  const std::uint32_t lane = lane_of[k] & ~kOneLane, l = lane % kLanes;
  // the approach speed before the solve: its number at the velocities the step started from,
  // then the biased passes' running minimum from there (vmin keeps the first of equal numbers:
  // a zero's sign and a NaN as the running minimum kept them). A lane of a block that bounces
  // has it from prepare already, and the minimum of it and that number is itself. (A step
  // that stopped before finish_velocities kept no velocities: the passes' minimum alone.)
  auto before = [&](const auto& b, Real passes, auto at) {
    if (!start_kept) return passes;
    const std::uint32_t a = b.a[l], c = b.b[l];
    return lanes::vmin(at(&start_v[a].x, &start_w[a].x, &start_v[c].x, &start_w[c].x), passes);
  };
  if (lane_of[k] & kOneLane) {  // a one-point lane: its other points are none (zeros, as a ContactBlock's)
    const OnePointBlock& b = ones[lane / kLanes];
    auto at = [&](auto... v) { return approach_at(b, static_cast<int>(l), v...); };
    approach = p == 0 ? before(b, b.approach[0][l], at) : 0;
    max_impulse = p == 0 ? static_cast<double>(b.max_impulse[0][l]) * b.unit[l] : 0;
    return true;
  }
  const ContactBlock& b = blocks[lane / kLanes];
  approach = before(b, b.approach[p][l], [&](auto... v) { return approach_at(b, static_cast<int>(l), p, v...); });
  max_impulse = static_cast<double>(b.max_impulse[p][l]) * b.unit[l];
  return true;
}

BodyArrays RigidContacts::arrays(RigidBodySystem& s) {
  (void)s;
  return {rows.data(), motion.data(), warm.data()};
}

// ---------------------------------------------------------------------------------------
// passes

void RigidContacts::accumulate_warm(RigidBodySystem& s, bool colored) {
  const BodyArrays r = arrays(s);
  // colour by colour when there are one-point blocks, so that each body's accumulators add its
  // manifolds' impulses in colour order, as they do from the ContactBlocks alone (build() adds
  // them in the same order as it fills the blocks)
  if (colored && one_blocks == 0) {
    warm_colored(simd, blocks.data(), 0, colored_blocks, r);
  } else if (colored) {
    for (std::size_t c = 0; c + 1 < color_ones.size(); ++c) {
      warm_colored(simd, blocks.data(), color_block[c], color_block[c + 1], r);
      warm_colored(simd, ones.data(), color_ones[c], color_ones[c + 1], r);
    }
  }
  for (std::size_t x = 0; x < colored_rolls; ++x) warm_rolling(rolls[x]);
  std::size_t x = colored_rolls;  // the overflow's lanes that roll, in lane order
  for (std::size_t b = colored_blocks; b < block_count; ++b)
    for (int l = 0; l < blocks[b].lanes; ++l) {
      warm_lane(blocks[b], l, r);
      if (x < rolls.size() && rolls[x].key == b * kLanes + l) warm_rolling(rolls[x++]);
    }
}

// the rolling resistance's carried impulse
void RigidContacts::warm_rolling(const Rolling& x) {
  const Vec3 da = x.ia * x.impulse, db = x.ib * x.impulse;
  for (int i = 0; i < 3; ++i) {
    if (x.write_a) warm[x.a].w[i] -= da[i];
    if (x.write_b) warm[x.b].w[i] += db[i];
  }
}

void RigidContacts::pass(RigidBodySystem& s, double h, bool bias, bool soft, bool update_sep, bool warm_next) {
  const ContactSettings& cs = s.settings_;
  PassParams p;
  p.inv_h = 1 / h;
  // stiffness at most a quarter of the substep rate (stiffer contacts rock a stack: measured
  // with 120 Hz at 240 Hz substeps); a contact with a body that cannot move gets twice the
  // stiffness (Box2D's static softness), but no more than one radian a substep (h w <= 1,
  // 76 Hz at the defaults' 480 Hz substeps): that contact is solved last in every pass, and
  // nearer the quarter its one sweep stops damping the slow sway of what stands on it (a
  // 10-stack's damping ratio 0.030 with it at 120 Hz, 0.10 at 76 Hz, its spring-damper
  // model's 0.13; docs/rigid-bodies.md, "A column's sway"). It carries a stack's load
  // once, not once per box, so the sag barely changes (6.9 -> 7.4 mm for the 20-stack)
  const double hertz = std::min(cs.contact_hertz * hertz_scale, 0.25 / h);
  const Softness dynamic_soft = make_soft(hertz, cs.damping_ratio, h);
  const Softness static_soft = make_soft(std::min(2 * hertz, kStaticStepAngle / (2 * kPi * h)), cs.damping_ratio, h);
  p.bias_rate[0] = dynamic_soft.bias_rate, p.mass_scale[0] = dynamic_soft.mass_scale;
  p.impulse_scale[0] = dynamic_soft.impulse_scale;
  p.bias_rate[1] = static_soft.bias_rate, p.mass_scale[1] = static_soft.mass_scale;
  p.impulse_scale[1] = static_soft.impulse_scale;
  p.push_out = cs.push_out_speed;
  p.baumgarte_h = cs.baumgarte / h;
  // the relax passes sweep three quarters as often (rounded up: 4 -> 3): they start from the
  // biased pass's impulses and only take back its push-out velocity. Measured: a box pushed by
  // a kinematic paddle keeps 0.05 mm/s of push-out at 3 relax sweeps, 0.02 at 4, 6.7 at 2
  // (docs/rigid-bodies.md, "Fewer sweeps"); the pass kernel 3-8% cheaper
  p.sweeps = bias ? cs.manifold_iterations : cs.manifold_iterations - cs.manifold_iterations / 4;
  p.bias = bias, p.soft = soft, p.update_sep = update_sep, p.warm_next = warm_next;
  // the relax pass (the soft step's, and TGS's first of a substep, which carries at the
  // default one) caps what each point carries to the next substep: an impact's impulse is no
  // guess for the next substep's (contact_wide.h, pass()). Under TGS too since 2026-12-07:
  // carried whole, a box's landing impulse pushed it off the next one down, the columns of
  // the 1000 dropped boxes landed zigzag by up to 0.32 m and rocked for as long as they were
  // stepped (all 1000 awake after 10 s; asleep after 2.03 s with the cap). TGS caps a
  // manifold's total (docs/rigid-bodies.md, "What a substep carries to the next")
  p.cap_carry = !bias;
  p.cap_total = !soft;
  p.carry_speed = gravity_speed * h;
  p.one_colour = true;  // (colour() passes a colour's blocks, or some of them, a call)
  const BodyArrays r = arrays(s);
  // the overflow, one manifold at a time; rolling resistance after its manifold's friction
  std::size_t next_roll = colored_rolls;  // the overflow's lanes that roll, in lane order
  auto overflow = [&](std::size_t b, int l) {
    PassParams q = p;
    q.warm_next = false;
    solve_lane(blocks[b], anchors[b], l, q, r);
    Rolling* x = next_roll < rolls.size() && rolls[next_roll].key == b * kLanes + l ? &rolls[next_roll++] : nullptr;
    if (x) roll(*x, blocks[b], l);
    if (warm_next) {
      warm_lane(blocks[b], l, r);
      if (x) warm_rolling(*x);
    }
  };
  // a colour's blocks with SIMD, its ContactBlocks then its one-point blocks (no two of a
  // colour's manifolds share a body that moves, so their order within it changes nothing).
  // The rolling resistance of a ContactBlock's lanes that roll follows its block (each lane's
  // comes right after its manifold's friction, as in the overflow; a one-point lane's is in
  // its block), a few blocks at a time so that the lanes' impulses and bodies are still in
  // cache (roll's samples -25% in the rain's landing)
  auto colour = [&](std::uint32_t c) {
    const std::size_t first = color_block[c], last = color_block[c + 1];
    auto x = rolls.begin() + static_cast<std::ptrdiff_t>(roll_start[c]);
    const auto end = rolls.begin() + static_cast<std::ptrdiff_t>(roll_start[c + 1]);
    if (x == end) {
      solve_colored(simd, blocks.data(), anchors.data(), first, last, p, r);
    } else {
      constexpr std::size_t kChunk = 8;  // blocks (about 50 KB)
      for (std::size_t from = first; from < last; from += kChunk) {
        const std::size_t to = std::min(last, from + kChunk);
        solve_colored(simd, blocks.data(), anchors.data(), from, to, p, r);
        for (; x != end && x->key < to * kLanes; ++x) {
          roll(*x, blocks[x->key / kLanes], static_cast<int>(x->key % kLanes));
          if (warm_next) warm_rolling(*x);
        }
      }
    }
    solve_colored(simd, ones.data(), one_anchors.data(), color_ones[c], color_ones[c + 1], p, r);
  };
  // the bands bottom up; within each, its colours first to last on even steps and last to
  // first on odd ones
  if (!backward && colored_rolls == 0 && one_blocks == 0) {
    PassParams all = p;  // (every colour's blocks in one call)
    all.one_colour = false;
    solve_colored(simd, blocks.data(), anchors.data(), 0, colored_blocks, all, r);
  } else if (!backward) {
    for (std::uint32_t c = 0; c < color_count.size(); ++c) colour(c);
  } else {
    for (std::size_t b = 0; b + 1 < band_colors.size(); ++b)
      for (std::uint32_t c = band_colors[b + 1]; c-- > band_colors[b];) colour(c);
  }
  for (std::size_t b = colored_blocks; b < block_count; ++b)
    for (int l = 0; l < blocks[b].lanes; ++l) overflow(b, l);
}

// rolling resistance: an angular impulse against the relative spin, up to rolling * normal
void RigidContacts::roll(Rolling& x, const ContactBlock& k, int l) {
  double total = 0;
  for (int p = 0; p < 4; ++p) total += k.impulse[p][l];
  total *= k.unit[l];
  double* wa = rows[x.a].w;
  double* wb = rows[x.b].w;
  const Vec3 old = x.impulse;
  Vec3 j = old - x.mass * (Vec3(wb[0], wb[1], wb[2]) - Vec3(wa[0], wa[1], wa[2]));
  const double limit = x.rolling * total, len = glm::length(j);
  if (len > limit) j *= limit / len;
  x.impulse = j;
  const Vec3 da = x.ia * (j - old), db = x.ib * (j - old);
  for (int i = 0; i < 3; ++i) {
    if (x.write_a) wa[i] -= da[i];
    if (x.write_b) wb[i] += db[i];
  }
}

void RigidContacts::update_separations(RigidBodySystem& s) {
  const BodyArrays r = arrays(s);
  separation_colored(simd, blocks.data(), anchors.data(), 0, colored_blocks, r);
  separation_colored(simd, ones.data(), one_anchors.data(), 0, one_blocks, r);
  for (std::size_t b = colored_blocks; b < block_count; ++b)
    for (int l = 0; l < blocks[b].lanes; ++l) separation_lane(blocks[b], anchors[b], l, r);
}

namespace {

// kinetic energy of a body of inverse mass im and principal moments `inertia` with velocity v
// and angular velocity wb in its principal frame (J)
double kinetic(double im, const Vec3& inertia, const Vec3& v, const Vec3& wb) {
  return 0.5 * glm::dot(v, v) / im + 0.5 * glm::dot(wb, inertia * wb);
}

// the largest f in [0, 1] with E(f) = bound, E(f) = E0 + f B + f^2 A the kinetic energy at the
// velocities (v, wb) + f (dv, dwb) (E0 <= bound < E(1)): the root of the quadratic
double fraction_at(double im, const Vec3& inertia, const Vec3& v, const Vec3& wb, const Vec3& dv, const Vec3& dwb,
                   double bound) {
  const double a = kinetic(im, inertia, dv, dwb);
  const double bb = glm::dot(v, dv) / im + glm::dot(wb, inertia * dwb);
  const double c = kinetic(im, inertia, v, wb) - bound;  // <= 0
  return std::clamp((-bb + std::sqrt(std::max(bb * bb - 4 * a * c, 0.0))) / (2 * a), 0.0, 1.0);
}

}  // namespace

void RigidContacts::restitution(RigidBodySystem& s, double dt, const Vec3& gravity) {
  const double threshold = s.settings_.restitution_threshold;
  const BodyArrays r = arrays(s);
  if (restitution_lanes.empty()) return;
  // the bodies that bounce off fixed bodies only, with their velocities before the bounces
  // (s.v_, s.w_ and s.q0_ still hold the step's start: finish_velocities has not run)
  find_bounces(s, dt, gravity, true, s.v_.data(), s.w_.data(), s.q0_.data());
  for (Bounce& b : bounces) {
    const SolverBody& row = rows[b.body];
    b.pre_v = Vec3(row.v[0], row.v[1], row.v[2]), b.pre_w = Vec3(row.w[0], row.w[1], row.w[2]);
  }
  // (the lanes that bounce: the test restitution_lane makes first, made here, without the
  // call for each of the terrain's 5,000 lanes at rest a median step)
  for (const LaneRef& x : restitution_lanes) {
    const int lane = static_cast<int>(x.lane);
    if (x.one) {
      if (lane_bounces(ones[x.block], lane, threshold))
        restitution_lane(ones[x.block], lane, x.restitution, threshold, r);
    } else if (lane_bounces(blocks[x.block], lane, threshold)) {
      restitution_lane(blocks[x.block], lane, x.restitution, threshold, s.settings_.manifold_iterations, r);
    }
  }
  bound_bounces(s, true);
  bound_bounce_work(s, gravity);
}

void RigidContacts::bound_bounce_work(RigidBodySystem& s, const Vec3& gravity) {
  for (const Bounce& b : bounces) {
    const std::uint32_t i = b.body;
    if (s.torque_[i] != Vec3(0)) continue;  // (a torque's work over the step is not tracked)
    const double im = s.inv_mass_[i];
    const Vec3& inertia = s.inertia_[i];
    const Quat& q = s.q_[i];
    const Vec3 v(rows[i].v[0], rows[i].v[1], rows[i].v[2]), w(rows[i].w[0], rows[i].w[1], rows[i].w[2]);
    const Vec3 wb = glm::conjugate(q) * w, pre = glm::conjugate(q) * b.pre_w;
    const double now = kinetic(im, inertia, v, wb);
    // the start's kinetic energy plus the work of gravity and force along the step's path
    const double start = kinetic(im, inertia, s.v_[i], glm::conjugate(s.q0_[i]) * s.w_[i]);
    const double work = path_work(s, i, gravity, s.com0_[i]);
    const double before = kinetic(im, inertia, b.pre_v, pre);
    const double bound = std::max(before, start + work);
    if (!(now > bound * (1 + 1e-6))) continue;
    // from the velocities before the bounces (their energy `before` <= bound) along the
    // bounces' change
    const Vec3 dv = v - b.pre_v, dwb = wb - pre;
    const double f = fraction_at(im, inertia, b.pre_v, pre, dv, dwb, bound);
    const Vec3 vf = b.pre_v + f * dv, wf = q * (pre + f * dwb);
    for (int k = 0; k < 3; ++k) rows[i].v[k] = vf[k], rows[i].w[k] = wf[k];
  }
}

double RigidContacts::path_work(const RigidBodySystem& s, std::uint32_t i, const Vec3& gravity, const Vec3& from) {
  return glm::dot(s.gravity_scale_[i] * gravity / s.inv_mass_[i] + s.force_[i], s.com_[i] - from);
}

void RigidContacts::bound_bounces_to_work(RigidBodySystem& s, const Vec3& gravity, const Vec3* x_start) {
  for (Bounce& b : bounces) {
    if (s.torque_[b.body] != Vec3(0)) continue;  // (a torque's work is not tracked)
    b.bound = std::max(b.free, std::min(b.bound, b.start + path_work(s, b.body, gravity, x_start[b.body])));
  }
}

void RigidContacts::find_bounces(RigidBodySystem& s, double h, const Vec3& gravity, bool from_lanes, const Vec3* v,
                                 const Vec3* w, const Quat* q) {
  bounces.clear();
  if (!from_lanes && std::none_of(pairs.begin(), pairs.end(), [](const ContactPair& c) { return c.restitution != 0; }))
    return;
  const std::size_t n = s.type_.size();
  auto dynamic = [&](std::uint32_t i) { return s.type_[i] == BodyType::Dynamic && !s.asleep_[i]; };
  auto moves = [&](std::uint32_t i) { return s.type_[i] == BodyType::Kinematic || dynamic(i); };
  // the bodies that touch a body that moves (by any manifold, with restitution or not)
  shared.assign(n, 0);
  auto mark = [&](std::uint32_t a, std::uint32_t b) __attribute__((always_inline)) {
    if (moves(a) && moves(b)) shared[a] = shared[b] = 1;
  };
  if (from_lanes) {
    // every pair is a lane of a block (build()), which holds its bodies (a lane past `lanes`,
    // empty, holds the spare row n; the loop stops before them): read there, two lines a block that the lanes' loop below reads again, not the
    // pairs' first lines, one a pair (the terrain's median steps: 5,000 pairs, their lines
    // long out of the cache after the fill)
    auto mark_blocks = [&](const auto* array, std::size_t count) {
      for (std::size_t k = 0; k < count; ++k)
        for (int l = 0; l < array[k].lanes; ++l)
          mark(array[k].a[l], array[k].b[l]);
    };
    mark_blocks(blocks.data(), block_count);
    mark_blocks(ones.data(), one_blocks);
  } else {
    for (const ContactPair& c : pairs) mark(c.a, c.b);
  }
  // (the body's record made apart from the test below, which is inlined where it is called:
  // as one lambda it was a call for each of a lane's two bodies, 10,000 a step on the
  // terrain's median steps, nearly all of them for the terrain itself or a body already listed)
  auto record = [&](std::uint32_t i) __attribute__((noinline)) {
    shared[i] = 2;
    // the free motion: the velocity under gravity and force, the angular velocity with the
    // torque's turn in the body frame (the free rotation keeps the energy of the rest; damping
    // only takes energy, so it is left out)
    const double im = s.inv_mass_[i];
    const Vec3& inertia = s.inertia_[i];
    const Vec3 vf = v[i] + h * (s.gravity_scale_[i] * gravity + im * s.force_[i]);
    const Vec3 wb = glm::conjugate(q[i]) * w[i];
    const Vec3 wf = wb + h * (s.inv_inertia_[i] * (glm::conjugate(q[i]) * s.torque_[i]));
    const double start = kinetic(im, inertia, v[i], wb), free = kinetic(im, inertia, vf, wf);
    bounces.push_back({i, std::max(start, free), start, free, vf, wf, Vec3(0), Vec3(0)});
  };
  auto add = [&](std::uint32_t i) __attribute__((always_inline)) {
    if (i < n && dynamic(i) && shared[i] == 0) record(i);
  };
  if (from_lanes) {
    for (const LaneRef& x : restitution_lanes) {
      if (x.one) add(ones[x.block].a[x.lane]), add(ones[x.block].b[x.lane]);
      else add(blocks[x.block].a[x.lane]), add(blocks[x.block].b[x.lane]);
    }
  } else {
    for (const ContactPair& c : pairs)
      if (c.restitution != 0) add(c.a), add(c.b);
  }
}

void RigidContacts::bound_bounces(RigidBodySystem& s, bool from_rows) {
  for (const Bounce& b : bounces) {
    const std::uint32_t i = b.body;
    const Vec3 v = from_rows ? Vec3(rows[i].v[0], rows[i].v[1], rows[i].v[2]) : s.v_[i];
    const Vec3 w = from_rows ? Vec3(rows[i].w[0], rows[i].w[1], rows[i].w[2]) : s.w_[i];
    const double im = s.inv_mass_[i];
    const Vec3& inertia = s.inertia_[i];
    const Quat& q = s.q_[i];
    const Vec3 wb = glm::conjugate(q) * w;
    const double now = kinetic(im, inertia, v, wb);
    // (above the bound by more than rounding and the free rotation's energy error, 1e-6 of it:
    // at the bound itself, a body touching nothing that stops it, the step's own integration
    // and this one's differ in the last bits)
    if (!(now > b.bound * (1 + 1e-6))) continue;
    // E(f) = E0 + f B + f^2 A from the free motion (E0 <= bound) along the contacts' change
    // (dv, dwb); the largest f in [0, 1] with E(f) = bound (E(1) = now > bound)
    const Vec3 dv = v - b.v, dwb = wb - b.wb;
    const double f = fraction_at(im, inertia, b.v, b.wb, dv, dwb, b.bound);
    const Vec3 vf = b.v + f * dv, wf = q * (b.wb + f * dwb);
    if (from_rows) {
      for (int k = 0; k < 3; ++k) rows[i].v[k] = vf[k], rows[i].w[k] = wf[k];
    } else {
      s.v_[i] = vf, s.w_[i] = wf;
    }
  }
}

void RigidContacts::carry_fresh_slides(const RigidBodySystem& s) {
  // A manifold's friction acts at the contact plane, below the centres, so it turns the bodies
  // too, and its normal points hold that turn; solved once each a pass, friction and points
  // converge by about 0.6 a pass from what they carry in. A cube set down at rest on a slope
  // past atan(mu) carried nothing into its first step, slid 1.6-8.1 mm/s ahead of a t in it,
  // and friction at its limit never took that back (docs/rigid-bodies.md). Where the manifold
  // must slide (gravity's pull along the plane over mu times its press), the converged
  // impulses are known before the step: the press stopped, the friction at the cone against
  // the pull; within the cone the friction sticks and the later steps take back what the
  // first leaves, so nothing is carried there (a pile on level ground keeps its bits).
  // Only gravity is counted, on a manifold between a moving body and one that does not.
  const double h = impulse_h;
  if (!(h > 0)) return;
  auto pull = [&](std::uint32_t i) {
    return moves(s, i, s.type_, s.asleep_) ? s.gravity_ * (s.gravity_scale_[i] * h) : Vec3(0);
  };
  auto velocity = [&](std::uint32_t i, const Vec3& at) {
    return moves(s, i, s.type_, s.asleep_) ? s.v_[i] + glm::cross(s.w_[i], at - s.com_[i]) : Vec3(0);
  };
  constexpr double kTouchingGap = 1e-6;  // (m: the kernels' kTouching, contact_wide.h)
  // (a body held by more than one manifold shares its weight among them as the passes find:
  // one's share is not known before, so those carry nothing; each body's pairs, up to 2)
  pairs_of.assign(s.type_.size(), 0);
  for (const ContactPair& c : pairs) {
    pairs_of[c.a] = static_cast<std::uint8_t>(std::min(pairs_of[c.a] + 1, 2));
    pairs_of[c.b] = static_cast<std::uint8_t>(std::min(pairs_of[c.b] + 1, 2));
  }
  for (ContactPair& c : pairs) {
    const std::uint32_t held = moves(s, c.b, s.type_, s.asleep_) ? c.b : c.a;
    if (pairs_of[held] != 1) continue;
    if (!(c.friction > 0) || c.count == 0 || c.tangent_impulse[0] != 0 || c.tangent_impulse[1] != 0) continue;
    int touching = 0;
    bool carried = false;
    for (int k = 0; k < c.count; ++k)
      carried = carried || c.normal_impulse[k] != 0, touching += -c.depth[k] <= kTouchingGap ? 1 : 0;
    if (carried || touching == 0) continue;
    const double ma = moves(s, c.a, s.type_, s.asleep_) ? s.inv_mass_[c.a] : 0;
    const double mb = moves(s, c.b, s.type_, s.asleep_) ? s.inv_mass_[c.b] : 0;
    const Vec3 dv = pull(c.b) - pull(c.a);
    const double press = -glm::dot(dv, c.normal);  // (b onto a: > 0)
    if (!(press > 0) || !((ma > 0) != (mb > 0))) continue;  // (one body moves: `held`)
    const Vec3 slide = dv + press * c.normal;
    const double along = glm::length(slide);
    if (!(along > c.friction * press)) continue;  // within the cone: sticks
    // at rest: the bodies' relative velocity at the centroid no more than a substep's pull
    const Vec3 at = s.com_[c.a] + c.ca;
    if (glm::length(velocity(c.b, at) - velocity(c.a, at)) > glm::length(dv)) continue;
    const double normal = press / (ma + mb), friction = c.friction * normal / along;
    const Vec3 f = -friction * slide;
    c.tangent_impulse[0] = glm::dot(f, c.t1);
    c.tangent_impulse[1] = glm::dot(f, c.t2);
    // the press shared out so that it and the friction turn the moving body by nothing (a
    // sliding box slides without turning): from an even share over the touching points, plus
    // the least change that holds the turn, d_k = q_k . l with q_k = (p_k - m) x n (m the
    // touching points' mean, so the changes sum to none) and sum_k q_k q_k^T l = -(the even
    // share's and the friction's moment about the centre); an even share where the points lie
    // on a line or a point would pull (the body tips: the passes find its share)
    bool on[Manifold::kMaxPoints];
    Vec3 m(0);
    for (int k = 0; k < c.count; ++k)
      if ((on[k] = -c.depth[k] <= kTouchingGap)) m += c.points[k].at;
    m /= touching;
    const Vec3& com = s.com_[held];
    const double even = normal / touching;
    Vec3 moment = glm::cross(at - com, f);  // (the friction acts at the centroid)
    double q[Manifold::kMaxPoints][2] = {}, mm[3] = {0, 0, 0};
    for (int k = 0; k < c.count; ++k) {
      if (!on[k]) continue;
      const Vec3 qk = glm::cross(c.points[k].at - m, c.normal);
      moment += glm::cross(c.points[k].at - com, c.normal) * even;
      q[k][0] = glm::dot(qk, c.t1), q[k][1] = glm::dot(qk, c.t2);
      mm[0] += q[k][0] * q[k][0], mm[1] += q[k][0] * q[k][1], mm[2] += q[k][1] * q[k][1];
    }
    const double det = mm[0] * mm[2] - mm[1] * mm[1];
    const double r0 = -glm::dot(moment, c.t1), r1 = -glm::dot(moment, c.t2);
    const double l0 = det > 0 ? (mm[2] * r0 - mm[1] * r1) / det : 0;
    const double l1 = det > 0 ? (mm[0] * r1 - mm[1] * r0) / det : 0;
    bool pushes = det > 0;
    for (int k = 0; k < c.count; ++k) pushes = pushes && (!on[k] || even + q[k][0] * l0 + q[k][1] * l1 >= 0);
    for (int k = 0; k < c.count; ++k)
      c.normal_impulse[k] = !on[k] ? 0 : pushes ? even + q[k][0] * l0 + q[k][1] * l1 : even;
  }
}

void RigidContacts::carry_impulses(double h) {
  // an impulse per step of impulse_h is a force times impulse_h: the same force over h
  if (impulse_h > 0 && impulse_h != h) {
    const double k = h / impulse_h;
    for (ContactPair& c : pairs) {
      for (int j = 0; j < c.count; ++j) c.normal_impulse[j] *= k;
      c.tangent_impulse[0] *= k, c.tangent_impulse[1] *= k;
      c.twist_impulse *= k;
      c.rolling_impulse *= k;
    }
    // and the manifolds that hold their own impulses (sleeping pairs, pairs not stepped): a
    // pair asleep while the solver, the substeps or the step changed wakes with the same force
    for (CachedManifold& m : manifolds) {
      if (m.last != kNoIndex) continue;  // its impulses are in `pairs`, scaled above
      for (int j = 0; j < m.count; ++j) m.normal_impulse[j] *= k;
      m.friction *= k, m.twist *= k, m.rolling *= k;
    }
  }
  impulse_h = h;
}

void RigidContacts::store() {
  // the blocks' impulses back to their pairs (warm starting, contacts()): one cache line of
  // each pair, fetched a block ahead (every pair is in a block when they are built; the
  // approach speeds and largest impulses stay in the blocks for manifold(), solver_report)
  if (!built) return;
  auto store_blocks = [&](const auto* array, std::size_t count) {
    constexpr int P = std::remove_cvref_t<decltype(*array)>::kPoints;
    for (std::size_t b = 0; b < count; ++b) {
      const auto& k = array[b];
      if (b + 1 < count)
        for (int l = 0; l < array[b + 1].lanes; ++l) __builtin_prefetch(pairs[array[b + 1].pair[l]].normal_impulse, 1);
      for (int l = 0; l < k.lanes; ++l) {
        ContactPair& c = pairs[k.pair[l]];
        const double unit = k.unit[l];
        // (all four: a lane's unused points hold zeros, and writing them spares reading the
        // count; a one-point lane's others are zeros)
        for (int p = 0; p < 4; ++p) c.normal_impulse[p] = p < P ? k.impulse[p < P ? p : 0][l] * unit : 0.0;
        c.tangent_impulse[0] = k.tangent_impulse[0][l] * unit, c.tangent_impulse[1] = k.tangent_impulse[1][l] * unit;
        if constexpr (P > 1) {
          c.twist_impulse = k.twist_impulse[l] * unit;
        } else {
          c.twist_impulse = 0;
          if ((k.rolls >> l) & 1) {  // the rolling impulse, from the frame to world axes
            const double j0 = k.rolling_impulse[0][l] * unit, j1 = k.rolling_impulse[1][l] * unit;
            const double j2 = k.rolling_impulse[2][l] * unit;
            c.rolling_impulse = j0 * c.t1 + j1 * c.t2 + j2 * c.normal;
          }
        }
      }
    }
  };
  store_blocks(blocks.data(), block_count);
  store_blocks(ones.data(), one_blocks);
  built = false;
}

long RigidContacts::color_of_pair(std::size_t k) const {
  if (!has_colors || k >= color_of.size()) return -1;
  return color_of[k] == kOverflow ? static_cast<long>(color_count.size()) : static_cast<long>(color_of[k]);
}

}  // namespace pba::detail
