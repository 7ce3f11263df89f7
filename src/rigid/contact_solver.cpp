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

namespace pba::detail {

Softness make_soft(double hertz, double zeta, double h) {
  if (hertz == 0) return {0, 1, 0};
  const double omega = 2 * kPi * hertz;
  const double a1 = 2 * zeta + h * omega, a2 = h * omega * a1, a3 = 1 / (1 + a2);
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
void clear_lane(ContactBlock& b, AnchorBlock& g, int l, std::uint32_t spare) {
  auto zero = [&](Real (&f)[kLanes]) { f[l] = 0; };
  for (int i = 0; i < 3; ++i) zero(b.t1[i]), zero(b.t2[i]), zero(b.n[i]), zero(b.ca[i]), zero(b.cb[i]);
  for (int i = 0; i < 6; ++i) zero(b.ia[i]), zero(b.ib[i]);
  for (int i = 0; i < 10; ++i) zero(b.k[i]);
  for (int k = 0; k < 4; ++k) {
    zero(b.x[k]), zero(b.y[k]), zero(b.mass[k]), zero(b.impulse[k]), zero(b.sep[k]);
    zero(b.approach[k]), zero(b.max_impulse[k]);
    zero(g.za[k]), zero(g.zb[k]), zero(g.base[k]), zero(g.ex[k]), zero(g.ey[k]);
  }
  zero(b.ma), zero(b.mb), zero(b.tangent_mass[0]), zero(b.tangent_mass[1]), zero(b.twist_mass);
  zero(b.friction), zero(b.twist_radius), zero(b.tangent_impulse[0]), zero(b.tangent_impulse[1]);
  b.unit[l] = 1;
  zero(b.twist_impulse);
  b.a[l] = b.b[l] = spare;
  b.pair[l] = kNoPair;
}

// pairs ahead that build() and store() ask for while they work on one
constexpr std::size_t kPrefetchAhead = 4;

// the lines of a pair the solver reads and writes: the header and the four points a block holds
void prefetch_pair(const ContactPair& c) {
  const char* p = reinterpret_cast<const char*>(&c);
  constexpr std::size_t kUsed = offsetof(ContactPair, points) + 4 * sizeof(SolverPoint);
  for (std::size_t line = 0; line < kUsed; line += 64) __builtin_prefetch(p + line);
}

// 1 / k, or 0 when nothing can move (effective_mass's convention)
double inverse(double k) { return k > 0 ? 1 / k : 0; }

// u^T M v for the inverse inertia m (xx, xy, xz, yy, yz, zz) and frame vectors u, v whose
// component z is zero (the points' arms and the centroid's tangent arms in the frame): M v's
// rows, then their dot with u, each sum in component order without the terms of z. Those
// terms are exact zeros, so leaving them out changes a sum only where it is itself zero (at
// most its sign); fill() adds each form to ma + mb, which is never -0, so the masses and K it
// stores have the bits of the full products. (M v)'s row z is left zero.
template <int z>
void product_skipping(const double m[6], const double v[3], double out[3]) {
  static constexpr int kAt[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  constexpr int i = z == 0 ? 1 : 0, j = z == 2 ? 1 : 2;  // the components kept
  out[i] = m[kAt[i][i]] * v[i] + m[kAt[i][j]] * v[j];
  out[j] = m[kAt[j][i]] * v[i] + m[kAt[j][j]] * v[j];
  out[z] = 0;
}

template <int z>
double dot_skipping(const double u[3], const double mv[3]) {
  constexpr int i = z == 0 ? 1 : 0, j = z == 2 ? 1 : 2;
  return u[i] * mv[i] + u[j] * mv[j];
}

template <int z>
double quadratic_skipping(const double m[6], const double u[3], const double v[3]) {
  double mv[3];
  product_skipping<z>(m, v, mv);
  return dot_skipping<z>(u, mv);
}

}  // namespace

// ---------------------------------------------------------------------------------------
// prepare: inverse inertias, colours, blocks, the first warm start

void RigidContacts::prepare(RigidBodySystem& s) {
  const std::size_t n = s.type_.size();
  inv_inertia.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Mat3 r = glm::mat3_cast(s.q_[i]);
    Mat3 d(0.0);
    d[0][0] = s.inv_inertia_[i].x, d[1][1] = s.inv_inertia_[i].y, d[2][2] = s.inv_inertia_[i].z;
    // a sleeping body holds still like a static one until something wakes it
    inv_inertia[i] = s.asleep_[i] ? Mat3(0.0) : r * d * glm::transpose(r);
  }
  built = has_colors = lanes_valid = false;
  backward = !backward;
  pairs_same = pairs_same && pairs.size() == last_count;
  // (room for as many pairs as `pairs` has, so steady state does not allocate)
  if (rolling_mass.size() < pairs.size()) rolling_mass.reserve(pairs.capacity()), rolling_mass.resize(pairs.size());
  if (s.settings_.solver == RigidSolverType::Xpbd) {  // its own passes on the pairs
    colored_once = false;  // (the colours stay those of an earlier step's pairs)
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
  motion.assign(8 * (n + 1), 0.0);
  for (std::size_t i = 0; i <= n; ++i) motion[8 * i + 3] = 1;
  warm.assign(n + 1, SolverBody{});
  color(s);
  build(s);
  built = has_colors = lanes_valid = true;
  if (s.settings_.warm_starting) accumulate_warm(s);
}

void RigidContacts::finish_velocities(RigidBodySystem& s) {
  const std::size_t n = s.type_.size();
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
// colours first to last, of odd steps last to first. Manifolds with rolling resistance, and
// those whose body has kBandColors in the band already, go to the overflow, solved one at a
// time after the colours.
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
  for (auto* v : {&adjacency, &band_of, &by_band, &color_of, &by_color, &color_count}) v->reserve(2 * room);
  for (auto* v : {&level, &queue, &mask_band, &band_start, &band_colors, &adjacency_start}) v->reserve(n + 3);
  mask.reserve(n + 3);
  cursor.reserve(std::max(n, room) + 3);
  offset.reserve(room + 3);
  color_block.reserve(room + 3);
  restitution_lanes.reserve(room);
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
    if (same) return;
    colored_once = true;
  }
  // the dynamic pairs as adjacency lists
  adjacency_start.assign(n + 1, 0);
  for (const ContactPair& c : pairs)
    if (moving(c.a) && moving(c.b)) ++adjacency_start[c.a + 1], ++adjacency_start[c.b + 1];
  for (std::size_t i = 0; i < n; ++i) adjacency_start[i + 1] += adjacency_start[i];
  adjacency.resize(adjacency_start[n]);
  cursor.assign(adjacency_start.begin(), adjacency_start.end() - 1);
  for (const ContactPair& c : pairs)
    if (moving(c.a) && moving(c.b)) adjacency[cursor[c.a]++] = c.b, adjacency[cursor[c.b]++] = c.a;
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
  for (const ContactPair& c : pairs) {
    const bool da = moving(c.a), db = moving(c.b);
    if (da == db) continue;
    const std::uint32_t x = da ? c.a : c.b;
    if (level[x] == kUnset) level[x] = 0, queue.push_back(x);
  }
  std::size_t head = spread(0);
  for (std::uint32_t i = 0; i < n; ++i)
    if (moving(i) && level[i] == kUnset) level[i] = 0, queue.push_back(i), head = spread(head);
  // bands, and the pairs sorted by band (stable: pair order within a band)
  band_of.resize(m);
  std::uint32_t bands = 0;
  for (std::size_t i = 0; i < m; ++i) {
    const ContactPair& c = pairs[i];
    band_of[i] = moving(c.a) && moving(c.b) ? std::min(level[c.a], level[c.b]) : kUnset;
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
    const ContactPair& c = pairs[i];
    if (band_of[i] != band) {
      base += width, width = 0, band = band_of[i];
      band_colors.push_back(base);
    }
    // (empty bands leave no colours)
    const bool da = moving(c.a), db = moving(c.b);
    std::uint64_t used = 0;
    if (da && mask_band[c.a] == band) used |= mask[c.a];
    if (db && mask_band[c.b] == band) used |= mask[c.b];
    if (c.rolling != 0 || ~used == 0 || s.settings_.solver == RigidSolverType::Tgs) {
      color_of[i] = kOverflow;
      ++overflow_count;
      continue;
    }
    const std::uint32_t k = static_cast<std::uint32_t>(std::countr_zero(~used));
    width = std::max(width, k + 1);
    color_of[i] = base + k;
    if (color_count.size() <= base + k) color_count.resize(base + k + 1, 0);
    ++color_count[base + k];
    for (const std::uint32_t x : {c.a, c.b}) {
      if (!moving(x)) continue;
      if (mask_band[x] != band) mask_band[x] = band, mask[x] = 0;
      mask[x] |= std::uint64_t{1} << k;
    }
  }
  band_colors.push_back(static_cast<std::uint32_t>(color_count.size()));
}

void RigidContacts::build(RigidBodySystem& s) {
  // the blocks: each colour's manifolds in pair order, kLanes to a block, then the overflow's
  const std::size_t colors = color_count.size();
  color_block.resize(colors + 2);
  std::size_t next = 0;
  for (std::size_t c = 0; c < colors; ++c) color_block[c] = next, next += (color_count[c] + kLanes - 1) / kLanes;
  color_block[colors] = next;
  colored_blocks = next;
  next += (overflow_count + kLanes - 1) / kLanes;
  color_block[colors + 1] = next;
  // (grown by half again when a new peak needs more, so a scene that moves does not allocate every step)
  if (blocks.size() < next) {
    blocks.reserve(next + next / 2), anchors.reserve(next + next / 2);
    blocks.resize(next), anchors.resize(next);
  }
  block_count = next;
  const auto spare = static_cast<std::uint32_t>(s.type_.size());
  for (std::size_t c = 0; c <= colors; ++c) {
    std::uint32_t left = c < colors ? color_count[c] : overflow_count;
    for (std::size_t b = color_block[c]; b < color_block[c + 1]; ++b) {
      ContactBlock& k = blocks[b];
      k.lanes = static_cast<int>(std::min<std::uint32_t>(left, kLanes));
      left -= static_cast<std::uint32_t>(k.lanes);
      k.write_a = k.write_b = 0;
      for (int l = k.lanes; l < kLanes; ++l) clear_lane(k, anchors[b], l, spare);
    }
  }
  // each colour's pairs in pair order (the overflow's last), then the blocks filled one after
  // another (a block's lines stay in cache while its lanes are written)
  offset.assign(colors + 2, 0);
  for (std::size_t c = 0; c < colors; ++c) offset[c + 1] = offset[c] + color_count[c];
  offset[colors + 1] = offset[colors] + overflow_count;
  cursor.assign(offset.begin(), offset.end() - 1);
  by_color.resize(pairs.size());
  lane_of.reserve(pairs.capacity());
  lane_of.resize(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const std::size_t c = color_of[i] == kOverflow ? colors : color_of[i];
    by_color[cursor[c]++] = static_cast<std::uint32_t>(i);
  }
  restitution_lanes.clear();
  for (std::size_t c = 0; c <= colors; ++c)
    for (std::uint32_t slot = 0; slot < offset[c + 1] - offset[c]; ++slot) {
      const std::size_t b = color_block[c] + slot / kLanes;
      const int l = static_cast<int>(slot % kLanes);
      const std::uint32_t i = by_color[offset[c] + slot];
      // a pair a few ahead on its way from the outer caches (colour order visits the pairs out
      // of order): its header and points
      if (offset[c] + slot + kPrefetchAhead < by_color.size()) prefetch_pair(pairs[by_color[offset[c] + slot + kPrefetchAhead]]);
      fill(s, blocks[b], anchors[b], l, i);
      lane_of[i] = static_cast<std::uint32_t>(b * kLanes + static_cast<std::size_t>(l));
      if (pairs[i].restitution != 0)
        restitution_lanes.push_back({static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(l), pairs[i].restitution});
    }
}

// One manifold into lane l of block k, in its contact frame (t1, t2, n).
void RigidContacts::fill(RigidBodySystem& s, ContactBlock& k, AnchorBlock& g, int l, std::uint32_t index) {
  ContactPair& c = pairs[index];
  set_rolling_mass(index);  // here, where the pair is read anyway, rather than in a pass of its own
  const bool da = moves(s, c.a, s.type_, s.asleep_), db = moves(s, c.b, s.type_, s.asleep_);
  k.a[l] = c.a, k.b[l] = c.b, k.pair[l] = index;
  if (da) k.write_a |= 1u << l;
  if (db) k.write_b |= 1u << l;
  const Vec3 t[3] = {c.t1, c.t2, c.normal};
  for (int i = 0; i < 3; ++i) k.t1[i][l] = c.t1[i], k.t2[i][l] = c.t2[i], k.n[i][l] = c.normal[i];
  const double ma = s.asleep_[c.a] ? 0 : s.inv_mass_[c.a], mb = s.asleep_[c.b] ? 0 : s.inv_mass_[c.b];
  // the lane's impulse unit: the power of two u that puts u (ma + mb) in [0.5, 1), so that the
  // float kernels see masses near 1 kg whatever the bodies weigh (exact: a power of two scales
  // every product and quotient without rounding, so it changes no bits unless a float would
  // leave its range); the block keeps impulses and effective masses divided by u, inverse
  // masses, inverse inertias and K times u
  int exponent = 0;
  if (ma + mb > 0) std::frexp(ma + mb, &exponent);
  const double unit = std::ldexp(1.0, -exponent);
  k.unit[l] = static_cast<Real>(unit);
  k.ma[l] = ma * unit, k.mb[l] = mb * unit;
  // the inverse inertias in the frame, t_i . (I^-1 t_j)
  double ia[6], ib[6];
  {
    const Vec3 at[3] = {inv_inertia[c.a] * t[0], inv_inertia[c.a] * t[1], inv_inertia[c.a] * t[2]};
    const Vec3 bt[3] = {inv_inertia[c.b] * t[0], inv_inertia[c.b] * t[1], inv_inertia[c.b] * t[2]};
    constexpr int kRow[6] = {0, 0, 0, 1, 1, 2}, kCol[6] = {0, 1, 2, 1, 2, 2};
    for (int e = 0; e < 6; ++e) {
      ia[e] = glm::dot(t[kRow[e]], at[kCol[e]]);
      ib[e] = glm::dot(t[kRow[e]], bt[kCol[e]]);
      k.ia[e][l] = ia[e] * unit, k.ib[e][l] = ib[e] * unit;
    }
  }
  auto frame = [&](const Vec3& v, double out[3]) {
    out[0] = glm::dot(v, c.t1), out[1] = glm::dot(v, c.t2), out[2] = glm::dot(v, c.normal);
  };
  double d[3], ca[3];
  frame(s.com_[c.a] - s.com_[c.b], d);
  frame(c.ca, ca);
  for (int i = 0; i < 3; ++i) k.ca[i][l] = ca[i], k.cb[i][l] = ca[i] + d[i];
  // the points; the normal rows' angular parts are r x n = (y, -x, 0) in the frame
  double x[4] = {}, y[4] = {};
  // K's entries ma + mb + ra_i^T Ia ra_j + rb_i^T Ib rb_j for the points' arms in the frame,
  // ra = (y, -x, 0) and rb = ra + (d1, -d0, 0): the arms' third component is zero (so the
  // products skip it, product_skipping), and each column's I r is formed once, with
  // the point (in the loop that finds its arm, so nothing is stored and read back)
  double ra[4][3], rb[4][3], ira[4][3], irb[4][3];
  const double base = glm::dot(s.com_[c.b] - s.com_[c.a], c.normal);
  for (int p = 0; p < 4; ++p) {
    if (p < c.count) {
      const SolverPoint& q = c.points[p];
      const Vec3 arm = q.at - s.com_[c.a];  // the anchor from a's centre (com_ is where the step started)
      x[p] = glm::dot(arm, c.t1), y[p] = glm::dot(arm, c.t2);
      ra[p][0] = y[p], ra[p][1] = -x[p], ra[p][2] = 0;
      rb[p][0] = y[p] + d[1], rb[p][1] = -(x[p] + d[0]), rb[p][2] = 0;
      product_skipping<2>(ia, ra[p], ira[p]);
      product_skipping<2>(ib, rb[p], irb[p]);
      g.za[p][l] = glm::dot(q.sa, c.normal);
      g.zb[p][l] = glm::dot(q.sb, c.normal);
      // the core anchors' tangential offsets from the contact point (half the step from a's
      // surface point to b's; zero where the narrow phase puts them on one normal)
      const Vec3 e = 0.5 * ((q.sb + (s.com_[c.b] - s.com_[c.a])) - q.sa);
      g.ex[p][l] = glm::dot(e, c.t1), g.ey[p][l] = glm::dot(e, c.t2);
      // the separation at the start of the step (the kernels add the bodies' motion since)
      k.sep[p][l] = g.base[p][l] = base + q.offset + glm::dot(q.sb, c.normal) - glm::dot(q.sa, c.normal);
      k.impulse[p][l] = c.normal_impulse[p] / unit;
    } else {
      g.za[p][l] = g.zb[p][l] = g.base[p][l] = k.sep[p][l] = k.impulse[p][l] = 0;
      g.ex[p][l] = g.ey[p][l] = 0;
    }
    k.x[p][l] = x[p] - ca[0], k.y[p][l] = y[p] - ca[1];
    k.max_impulse[p][l] = 0;
  }
  static constexpr int kPairs[10][2] = {{0, 0}, {0, 1}, {0, 2}, {0, 3}, {1, 1}, {1, 2}, {1, 3}, {2, 2}, {2, 3}, {3, 3}};
  double diag[4] = {};
  for (int e = 0; e < 10; ++e) {
    const int i = kPairs[e][0], j = kPairs[e][1];
    double v = 0;
    if (i < c.count && j < c.count) v = ma + mb + dot_skipping<2>(ra[i], ira[j]) + dot_skipping<2>(rb[i], irb[j]);
    k.k[e][l] = v * unit;
    if (i == j) diag[i] = v;
  }
  for (int p = 0; p < 4; ++p) k.mass[p][l] = inverse(diag[p]) / unit;
  // friction at the centroid: the tangents' angular parts c x t1 = (0, c2, -c1), c x t2 = (-c2, 0, c0)
  {
    const double cb[3] = {ca[0] + d[0], ca[1] + d[1], ca[2] + d[2]};
    const double a1[3] = {0, ca[2], -ca[1]}, b1[3] = {0, cb[2], -cb[1]};
    const double a2[3] = {-ca[2], 0, ca[0]}, b2[3] = {-cb[2], 0, cb[0]};
    k.tangent_mass[0][l] = inverse(ma + mb + quadratic_skipping<0>(ia, a1, a1) + quadratic_skipping<0>(ib, b1, b1)) / unit;
    k.tangent_mass[1][l] = inverse(ma + mb + quadratic_skipping<1>(ia, a2, a2) + quadratic_skipping<1>(ib, b2, b2)) / unit;
    k.twist_mass[l] = inverse(ia[5] + ib[5]) / unit;
  }
  k.friction[l] = c.friction, k.twist_radius[l] = c.twist_radius;
  k.tangent_impulse[0][l] = c.tangent_impulse[0] / unit, k.tangent_impulse[1][l] = c.tangent_impulse[1] / unit;
  k.twist_impulse[l] = c.twist_impulse / unit;
  // the normal velocities before the solve
  double vn[4];
  normal_velocities(k, l, arrays(s), vn);
  for (int p = 0; p < 4; ++p) k.approach[p][l] = p < c.count ? vn[p] : 0;
}

// rolling resistance acts on the relative angular velocity: its mass, for a pair that rolls
void RigidContacts::set_rolling_mass(std::uint32_t index) {
  const ContactPair& c = pairs[index];
  if (!(c.rolling > 0)) return;
  const Mat3 k = inv_inertia[c.a] + inv_inertia[c.b];
  rolling_mass[index] = glm::determinant(k) > 0 ? glm::inverse(k) : Mat3(0.0);
}

bool RigidContacts::solver_report(std::size_t k, int p, double& approach, double& max_impulse) const {
  if (!lanes_valid || k >= lane_of.size()) return false;
  const ContactBlock& b = blocks[lane_of[k] / kLanes];
  const std::uint32_t l = lane_of[k] % kLanes;
  approach = b.approach[p][l];
  max_impulse = static_cast<double>(b.max_impulse[p][l]) * b.unit[l];
  return true;
}

BodyArrays RigidContacts::arrays(RigidBodySystem& s) {
  (void)s;
  return {rows.data(), motion.data(), warm.data()};
}

// ---------------------------------------------------------------------------------------
// passes

void RigidContacts::accumulate_warm(RigidBodySystem& s) {
  const BodyArrays r = arrays(s);
  warm_colored(simd, blocks.data(), 0, colored_blocks, r);
  for (std::size_t b = colored_blocks; b < block_count; ++b)
    for (int l = 0; l < blocks[b].lanes; ++l) {
      warm_lane(blocks[b], l, r);
      warm_rolling(s, blocks[b], l);
    }
}

// the rolling resistance's carried impulse, for a lane of the overflow
void RigidContacts::warm_rolling(RigidBodySystem& s, const ContactBlock& k, int l) {
  const ContactPair& c = pairs[k.pair[l]];
  if (c.rolling == 0) return;
  (void)s;
  const Vec3 da = inv_inertia[c.a] * c.rolling_impulse, db = inv_inertia[c.b] * c.rolling_impulse;
  for (int i = 0; i < 3; ++i) {
    if ((k.write_a >> l) & 1) warm[c.a].w[i] -= da[i];
    if ((k.write_b >> l) & 1) warm[c.b].w[i] += db[i];
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
  const double hertz = std::min(cs.contact_hertz, 0.25 / h);
  const Softness dynamic_soft = make_soft(hertz, cs.damping_ratio, h);
  const Softness static_soft = make_soft(std::min(2 * hertz, kStaticStepAngle / (2 * kPi * h)), cs.damping_ratio, h);
  p.bias_rate[0] = dynamic_soft.bias_rate, p.mass_scale[0] = dynamic_soft.mass_scale;
  p.impulse_scale[0] = dynamic_soft.impulse_scale;
  p.bias_rate[1] = static_soft.bias_rate, p.mass_scale[1] = static_soft.mass_scale;
  p.impulse_scale[1] = static_soft.impulse_scale;
  p.push_out = cs.push_out_speed;
  p.baumgarte_h = cs.baumgarte / h;
  p.slop = cs.linear_slop;
  p.sweeps = cs.manifold_iterations;
  p.bias = bias, p.soft = soft, p.update_sep = update_sep, p.warm_next = warm_next;
  const BodyArrays r = arrays(s);
  // the overflow, one manifold at a time; rolling resistance after its manifold's friction
  auto overflow = [&](std::size_t b, int l) {
    PassParams q = p;
    q.warm_next = false;
    solve_lane(blocks[b], anchors[b], l, q, r);
    roll(s, blocks[b], l);
    if (warm_next) {
      warm_lane(blocks[b], l, r);
      warm_rolling(s, blocks[b], l);
    }
  };
  // the bands bottom up; within each, its colours first to last on even steps and last to
  // first on odd ones
  if (!backward) {
    solve_colored(simd, blocks.data(), anchors.data(), 0, colored_blocks, p, r);
  } else {
    for (std::size_t b = 0; b + 1 < band_colors.size(); ++b)
      for (std::uint32_t c = band_colors[b + 1]; c-- > band_colors[b];)
        if (color_block[c + 1] > color_block[c]) solve_colored(simd, blocks.data(), anchors.data(), color_block[c], color_block[c + 1], p, r);
  }
  for (std::size_t b = colored_blocks; b < block_count; ++b)
    for (int l = 0; l < blocks[b].lanes; ++l) overflow(b, l);
}

// rolling resistance: an angular impulse against the relative spin, up to rolling * normal
void RigidContacts::roll(RigidBodySystem& s, const ContactBlock& k, int l) {
  ContactPair& c = pairs[k.pair[l]];
  if (c.rolling == 0) return;
  double total = 0;
  for (int p = 0; p < 4; ++p) total += k.impulse[p][l];
  total *= k.unit[l];
  (void)s;
  double* wa = rows[c.a].w;
  double* wb = rows[c.b].w;
  const Vec3 old = c.rolling_impulse;
  Vec3 j = old - rolling_mass[k.pair[l]] * (Vec3(wb[0], wb[1], wb[2]) - Vec3(wa[0], wa[1], wa[2]));
  const double limit = c.rolling * total, len = glm::length(j);
  if (len > limit) j *= limit / len;
  c.rolling_impulse = j;
  const Vec3 da = inv_inertia[c.a] * (j - old), db = inv_inertia[c.b] * (j - old);
  for (int i = 0; i < 3; ++i) {
    if ((k.write_a >> l) & 1) wa[i] -= da[i];
    if ((k.write_b >> l) & 1) wb[i] += db[i];
  }
}

void RigidContacts::update_separations(RigidBodySystem& s) {
  const BodyArrays r = arrays(s);
  separation_colored(simd, blocks.data(), anchors.data(), 0, colored_blocks, r);
  for (std::size_t b = colored_blocks; b < block_count; ++b)
    for (int l = 0; l < blocks[b].lanes; ++l) separation_lane(blocks[b], anchors[b], l, r);
}

void RigidContacts::restitution(RigidBodySystem& s) {
  const double threshold = s.settings_.restitution_threshold;
  const BodyArrays r = arrays(s);
  for (const LaneRef& x : restitution_lanes) {
    ContactBlock& k = blocks[x.block];
    restitution_lane(k, static_cast<int>(x.lane), x.restitution, threshold, r);
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
      for (int j = 0; j < m.count; ++j) m.points[j].normal_impulse *= k;
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
  for (std::size_t b = 0; b < block_count; ++b) {
    const ContactBlock& k = blocks[b];
    if (b + 1 < block_count)
      for (int l = 0; l < blocks[b + 1].lanes; ++l) __builtin_prefetch(pairs[blocks[b + 1].pair[l]].normal_impulse, 1);
    for (int l = 0; l < k.lanes; ++l) {
      ContactPair& c = pairs[k.pair[l]];
      const double unit = k.unit[l];
      // (all four: a lane's unused points hold zeros, and writing them spares reading the count)
      for (int p = 0; p < 4; ++p) c.normal_impulse[p] = k.impulse[p][l] * unit;
      c.tangent_impulse[0] = k.tangent_impulse[0][l] * unit, c.tangent_impulse[1] = k.tangent_impulse[1][l] * unit;
      c.twist_impulse = k.twist_impulse[l] * unit;
    }
  }
  built = false;
}

long RigidContacts::color_of_pair(std::size_t k) const {
  if (!has_colors || k >= color_of.size()) return -1;
  return color_of[k] == kOverflow ? static_cast<long>(color_count.size()) : static_cast<long>(color_of[k]);
}

}  // namespace pba::detail
