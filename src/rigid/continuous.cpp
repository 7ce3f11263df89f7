// Rigid bodies: time of impact for fast bodies against static geometry, and for bullets also
// against moving bodies (continuous collision).
//
// The discrete step makes speculative contacts as far out as a body can move in one step,
// but only up to the body's own size (larger margins fill the pair list: a body at 250 m/s
// would pair with everything within 4 m). A body that moves farther than half its smallest
// extent in a step, or one flagged as a bullet, is then swept from its pose at the start of
// the step to its pose at the end against every static shape its path's bounds reach, and
// put back at the first time of impact with its velocity there (the step's end velocity less
// what gravity and the applied force add over the part of the step not travelled): the next
// step's contact stops it (Box2D v3's continuous pass also puts bodies back at their time of
// impact). Times of impact come from conservative advancement (Mirtich 1996): at time t the
// shapes are d apart; no point of the moving shape closes faster than the centre's velocity
// along the normal plus the angular speed times the body's bounding radius times the sine of
// the angle between the rotation axis and the normal, so t can safely advance by d over that
// bound. It stops when the shapes are within the
// linear slop, so the body arrives touching, not overlapping.
// A body flagged as a bullet is swept last, after every other body's put-back, against the
// static shapes and also against the dynamic and kinematic non-bullet bodies its path's bounds
// reach, each held at its pose at the step's end (as Box2D v3 sweeps its bullets): a 5 cm ball
// at 1000 m/s stops at a 1 cm plate that moves, where a non-bullet passes through it (its
// speculative contact reaches no farther than its own size). Bullets are not swept against
// each other.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>

#include <glm/gtc/quaternion.hpp>

#include "collide/shape_bounds.h"
#include "contacts.h"
#include "rows_avx2.h"

namespace pba::detail {

namespace {

// One body's motion over the step: the centre of mass and the principal frame at the start
// and end, and how to turn them into a shape's pose at any fraction t in [0, 1].
struct Sweep {
  Vec3 c0, c1;
  Quat q0, q1;
  Quat principal;   // principal frame in the body frame
  Vec3 com_local;   // centre of mass in the body frame
  double angle = 0;  // rotation over the step (rad)
  double reach = 0;  // bounding radius about the centre of mass (m)
  Vec3 axis{0, 0, 0};  // unit axis of that rotation in the world (slerp turns about it); 0 when none

  Pose body(double t) const {
    const Vec3 c = c0 + t * (c1 - c0);
    const Quat q = glm::normalize(glm::slerp(q0, q1, t));
    const Quat r = glm::normalize(q * glm::conjugate(principal));
    return {c - r * com_local, r};
  }
};

// Distance (m) between the moving convex shape at fraction t and one static piece, and
// the unit normal from the moving shape to the piece.
struct Gap {
  double distance;
  Vec3 normal;
};

// A bound (m per step) on how fast any point of the swept shape closes on another along the
// unit normal n: a point at r from the centre moves along n at angle (axis x r) . n <= angle
// |axis x n| |r| per step (turning about n moves nothing along n)
double closing_along(const Sweep& w, const Vec3& n) {
  return glm::dot(w.c1 - w.c0, n) + w.angle * w.reach * glm::length(glm::cross(w.axis, n));
}

// advance()'s bound on its passes (see there)
double advance_limit(const Sweep& w, double tol) {
  // (kMaxAdvances: see advance())
  constexpr double kMaxAdvances = 1e6;
  return tol > 0 ? std::min((glm::length(w.c1 - w.c0) + w.angle * w.reach) / tol + 2, kMaxAdvances) : 50;
}

// Whether advance() from the gap g at t = 0 (above target + tol) ends at its first pass with
// 1, no contact in the step: the gap's closing bound carries t past the step's end. The same
// operations as that pass, so the same answer to the bit (the loop runs once unless its
// bound is not above 0, a NaN's)
bool ends_at_first_pass(const Sweep& w, const Gap& g, double target, double tol) {
  if (!(0 < advance_limit(w, tol))) return false;
  const double closing = closing_along(w, g.normal);
  return closing <= 0 || 0 + (g.distance - target) / closing >= 1;
}

// Conservative advancement of `gap` (a function of t) to within `target` (+ tol) of contact.
// Returns the fraction of impact, or 1 when the shapes never come that close in the step.
// A pair already that close at the start is left to the discrete contact (a box sliding on
// the ground must not be stopped by it).
template <class GapAt>
double advance(const Sweep& w, GapAt gap_at, double target, double tol) {
  double t = 0;
  Gap g = gap_at(0.0);
  if (g.distance <= target + tol) return 1;
  // An advance that does not converge had a gap above target + tol, and no closing speed
  // exceeds |dc| + angle reach, so each moves t by more than tol / (|dc| + angle reach): past
  // the step's end within that many. A fixed cap (it was 50) stopped slow approaches short of
  // it instead, a ball spinning just above the ground among them, and put the body back to a
  // time before a contact that never came. (A zero slop has no such bound: 50 then.)
  // Far from the origin the bound fails by rounding: a body at 1e14 m (positions 1.6 cm apart
  // there) closing 4e14 m in a step advanced t by less than its rounding, and the loop, whose
  // bound was then 3e17 passes, never ended. So it also ends when t stops moving (t is still a
  // time before contact) and after kMaxAdvances passes (more than any approach the slop bounds
  // below 1.2 km a step needs).
  const double limit = advance_limit(w, tol);
  for (double it = 0; it < limit; ++it) {
    const double closing = closing_along(w, g.normal);
    if (closing <= 0) return 1;
    const double next = t + (g.distance - target) / closing;
    if (next >= 1) return 1;
    if (!(next > t)) return t;  // the advance is below t's rounding
    t = next;
    g = gap_at(t);
    if (g.distance <= target + tol) return t;
  }
  return t;  // not converged (zero slop only): t is still a time before contact (each advance is safe)
}

// True when the point q on triangle t (both in the mesh frame) lies inside the face, or on an
// edge or a vertex whose edges are all internal (flag clear: flat or concave; bits ab = 1,
// bc = 2, ca = 4, as TriangleMesh::edge_flags gives them).
bool internal_feature(const Vec3 t[3], const Vec3& q, std::uint8_t flags) {
  const Vec3 n = glm::cross(t[1] - t[0], t[2] - t[0]);
  const double nn = glm::dot(n, n);
  // barycentric weights: u for a, v for b, w for c; a weight near 0 puts q on the opposite edge
  const double v = glm::dot(glm::cross(q - t[0], t[2] - t[0]), n) / nn;
  const double w = glm::dot(glm::cross(t[1] - t[0], q - t[0]), n) / nn;
  const double u = 1 - v - w;
  constexpr double kOn = 1e-9;
  std::uint8_t on = 0;
  if (w <= kOn) on |= 1;
  if (u <= kOn) on |= 2;
  if (v <= kOn) on |= 4;
  return (on & flags) == 0;
}

// How far (m) from the body's centre of mass `com` (body frame) the core of shape `d` reaches:
// its centre (sphere), segment (capsule) or corners (box, hull). Turning the body moves a
// rounded shape's surface within itself, so only the core's points bound how fast the shape
// closes on another along a normal: a ball turning about its centre closes no faster than
// the centre moves.
double core_reach(const RigidShapeDef& d, const Vec3& com) {
  const double centre = glm::length(d.local.position - com);
  switch (d.shape.type) {
    case ShapeType::Sphere: return centre;
    case ShapeType::Capsule: return centre + d.shape.half_height;
    case ShapeType::Box: return centre + glm::length(d.shape.half_extents);
    default: {
      const Aabb b = bounds(d.shape, Pose{});
      return centre + glm::length(glm::max(glm::abs(b.lo), glm::abs(b.hi)));
    }
  }
}

// True when the ball of `radius` about the body-frame point `p` lies inside shape `d` (a body
// whose centre of mass lies outside its shapes has no core there)
bool holds_ball(const RigidShapeDef& d, const Vec3& p, double radius) {
  const Vec3 q = apply_inverse(d.local, p);
  const ColliderShape& c = d.shape;
  switch (c.type) {
    case ShapeType::Sphere: return glm::length(q) <= c.radius - radius;
    case ShapeType::Capsule:
      return glm::length(Vec3(q.x, q.y - std::clamp(q.y, -c.half_height, c.half_height), q.z)) <= c.radius - radius;
    case ShapeType::Box:
      return std::abs(q.x) <= c.half_extents.x - radius && std::abs(q.y) <= c.half_extents.y - radius &&
             std::abs(q.z) <= c.half_extents.z - radius;
    case ShapeType::Hull: {
      const std::span<const double> f = c.hull->face_soa();
      const std::size_t m = f.size() / 4;
      for (std::size_t k = 0; k < m; ++k)
        if (f[k] * q.x + f[m + k] * q.y + f[2 * m + k] * q.z - f[3 * m + k] > -radius) return false;
      return true;
    }
    default: return false;
  }
}

// a plane shape's offset (m) along its world normal `nw` (unit) at pose `pb`: its points x
// are those with dot(nw, x) = this (the normal given need not be unit)
double plane_offset(const ColliderShape& plane, const Pose& pb, const Vec3& nw) {
  return plane.offset / glm::length(plane.normal) + glm::dot(nw, pb.position);
}

#if PBA_ROWS_AVX2
// The first test of continuous() below (slow by the bound on the angle) for four bodies (their
// rotations, centres of mass now and at the step's start, reaches and smallest half sizes),
// each lane the scalar code's operations in its order (glm's product of q and q0's conjugate,
// its vector part's length, |w|, the centre's shift, the bound), so the same outcome: bit k set
// when body k is slow by it. (The type, sleep and bullet tests stay the caller's; in the rain
// the scalar test was some 100 instructions a body, 10,000 bodies a step.)
static_assert(offsetof(Quat, x) == 0 && offsetof(Quat, w) == 24, "slow4_avx2 loads a quaternion as one row (x, y, z, w)");
__attribute__((target("avx2"))) int slow4_avx2(const Quat* q, const Quat* q0, const Vec3* com, const Vec3* com0,
                                               const double* extent_of, const double* thin_of) {
  using V = __m256d;
  V p[4], r[4], c[4], c0[4];  // q (x, y, z, w), q0 (x, y, z, w), com, com0 (x, y, z, -)
  columns4(_mm256_loadu_pd(&q[0].x), _mm256_loadu_pd(&q[1].x), _mm256_loadu_pd(&q[2].x), _mm256_loadu_pd(&q[3].x), p);
  columns4(_mm256_loadu_pd(&q0[0].x), _mm256_loadu_pd(&q0[1].x), _mm256_loadu_pd(&q0[2].x), _mm256_loadu_pd(&q0[3].x),
           r);
  columns4(row3(com[0]), row3(com[1]), row3(com[2]), row3(com[3]), c);
  columns4(row3(com0[0]), row3(com0[1]), row3(com0[2]), row3(com0[3]), c0);
  const V sign = _mm256_set1_pd(-0.0);
  // dq = q * conjugate(q0) (glm's product, its second factor (w, -x, -y, -z))
  const V pw = p[3], px = p[0], py = p[1], pz = p[2];
  const V qw = r[3], qx = _mm256_xor_pd(r[0], sign), qy = _mm256_xor_pd(r[1], sign), qz = _mm256_xor_pd(r[2], sign);
  const V w = pw * qw - px * qx - py * qy - pz * qz;
  const V x = pw * qx + px * qw + py * qz - pz * qy;
  const V y = pw * qy + py * qw + pz * qx - px * qz;
  const V z = pw * qz + pz * qw + px * qy - py * qx;
  const V sine = _mm256_sqrt_pd(x * x + y * y + z * z), cosine = _mm256_andnot_pd(sign, w);
  const V dx = c[0] - c0[0], dy = c[1] - c0[1], dz = c[2] - c0[2];
  const V shift = _mm256_sqrt_pd(dx * dx + dy * dy + dz * dz);
  const V extent = _mm256_loadu_pd(extent_of), thin = _mm256_loadu_pd(thin_of);
  const V bound = shift + _mm256_set1_pd(2.0) * (sine / cosine) * _mm256_set1_pd(1 + 1e-12) * extent;
  return _mm256_movemask_pd(_mm256_cmp_pd(bound, _mm256_set1_pd(0.5) * thin, _CMP_LE_OQ));
}
#endif

// a moving target's box at the step's end, as the bullets' search takes it: its centre of mass
// `c` with its reach `r` on every side (m)
Aabb end_box(const Vec3& c, double r) { return {c - Vec3(r), c + Vec3(r)}; }

// how far (m) box `b` sticks out of box `fat` on its farthest side (0 when inside). A NaN
// coordinate does not carry through: std::max keeps the first of the largest, and no comparison
// with a NaN is true, so the NaN sides are skipped. That changes no target: a box with a NaN
// corner overlaps() nothing, so neither the tree's way nor the scan takes its body.
double sticks_out(const Aabb& b, const Aabb& fat) {
  const Vec3 lo = fat.lo - b.lo, hi = b.hi - fat.hi;
  return std::max({0.0, lo.x, lo.y, lo.z, hi.x, hi.y, hi.z});
}

// A body whose end box sticks out of its fat boxes by more than this (m) is tested by each
// bullet directly instead of through the tree (see prepare_targets): the tree's query grows by
// the most any other body sticks out, and one fast or long body would grow every bullet's query.
// Any value gives the same targets; this one keeps the queries near their paths' size.
constexpr double kTargetSlack = 0.5;

}  // namespace

// The tree's fat boxes were made at the step's start from the poses then (grown by the
// speculative distance and the step's travel at the velocity then, and stretched along it),
// but the bullets' targets are taken at their poses at the step's end: a body that sped up
// in the step, or moved farther than its size, or a sleeper whose fat box was made before
// its last step of motion, may end outside its boxes. So each moving body's end box is
// measured once a step against its shapes' fat boxes: how far it sticks out of the one it
// sticks out of least. Those within kTargetSlack count in target_excess, the most of them;
// the others (and bodies with no shape in the tree) are listed in loose_targets.
void RigidContacts::prepare_targets(const RigidBodySystem& s) {
  loose_targets.clear();
  target_excess = 0;
  for (std::size_t j = 0; j < s.type_.size(); ++j) {
    if (s.type_[j] == BodyType::Static || s.bullet_[j]) continue;
    const std::uint32_t slot = s.owner_[j];
    double least = INFINITY;
    if (slot < body_proxies.size())
      for (const std::uint32_t q : body_proxies[slot])
        if (proxies[q].node >= 0) least = std::min(least, sticks_out(end_box(s.com_[j], s.extent_[j]), tree.fat_box(proxies[q].node)));
    if (least <= kTargetSlack)
      target_excess = std::max(target_excess, least);
    else
      loose_targets.push_back(static_cast<std::uint32_t>(j));
  }
}

// Bullet i's moving targets whose end boxes its path reaches, into bullet_targets by dense
// index, ascending, each once: the list the scan of every body made (the same sweeps in the
// same order, so the same bits), from a query of the tree and the loose list. A body whose end
// box overlaps the path lies within target_excess of one of its fat boxes, which then overlaps
// the path grown by that much: the query is grown by it and by a margin for the rounding of
// the excess and of the growth (1e-12 of the coordinates, some 4,500 ulps), and its hits are
// held to the scan's own test.
void RigidContacts::find_targets(const RigidBodySystem& s, std::size_t i, const Aabb& path) {
  auto take = [&](std::uint32_t j) {
    if (s.type_[j] != BodyType::Static && !s.bullet_[j] && end_box(s.com_[j], s.extent_[j]).overlaps(path)) bullet_targets.push_back(j);
  };
  Aabb query = path.grown(target_excess);
  const Vec3 round = 1e-12 * (glm::max(glm::abs(query.lo), glm::abs(query.hi)) + Vec3(1.0));
  query.lo -= round, query.hi += round;
  tree.query(query, [&](std::uint32_t q) {
    take(proxies[q].body);
    return true;
  });
  for (const std::uint32_t j : loose_targets) take(j);
  std::sort(bullet_targets.begin(), bullet_targets.end());
  bullet_targets.erase(std::unique(bullet_targets.begin(), bullet_targets.end()), bullet_targets.end());
  if (!check_bullet_targets) return;
  std::uint32_t at = 0;
  for (std::uint32_t j = 0; j < s.type_.size(); ++j) {
    if (s.type_[j] == BodyType::Static || s.bullet_[j] || !end_box(s.com_[j], s.extent_[j]).overlaps(path)) continue;
    if (at >= bullet_targets.size() || bullet_targets[at] != j)
      throw Error("continuous: the broad phase's tree missed " + s.describe(j) + " as a target of the bullet " +
                  s.describe(i));
    ++at, ++checked_targets;
  }
  if (at != bullet_targets.size())
    throw Error("continuous: the broad phase's tree gave " + s.describe(bullet_targets[at]) +
                ", which the scan does not, as a target of the bullet " + s.describe(i));
}

void RigidContacts::continuous(RigidBodySystem& s) {
  const ContactSettings& cs = s.settings_;
  s.profile_.put_back = 0;
  const std::size_t n = s.type_.size();
  // on AVX2 the first test four bodies at a time (slow4_avx2): `slow` holds its outcome for
  // the bodies from `base` up to `tested`
  [[maybe_unused]] std::size_t base = 0, tested = 0;
  [[maybe_unused]] int slow = 0;
  // Bullets go last (as Box2D v3's continuous pass takes them after the other bodies have
  // moved): each is swept against the static shapes and against the moving non-bullet bodies
  // at their poses at the step's end, every other body's put-back made by then. No bullet is
  // swept against another, and none against a pose a bullet sets, so the outcome does not
  // depend on the bullets' order. (A bench scene has none: its bodies go as before, bit for bit.)
  late_bullets.clear();
  for (std::size_t k = 0; k < n + late_bullets.size(); ++k) {
    const bool late = k >= n;
    const std::size_t i = late ? late_bullets[k - n] : k;
    // once a step with bullets, before the first of them, whatever it skips
    if (k == n) prepare_targets(s);
    if (s.type_[i] != BodyType::Dynamic || s.asleep_[i]) continue;
    if (!late && s.bullet_[i]) {
      late_bullets.push_back(static_cast<std::uint32_t>(i));
      continue;
    }
#if PBA_ROWS_AVX2
    if (simd == SimdPath::Avx2 && !late) {
      if (i >= tested && i + 4 <= n) {
        base = i, tested = i + 4;
        slow = slow4_avx2(&s.q_[i], &s.q0_[i], &s.com_[i], &s.com0_[i], &s.extent_[i], &s.min_extent_[i]);
      }
      if (i < tested && (slow >> (i - base) & 1) && !s.bullet_[i]) continue;
    }
#endif
    // fast: moved more than half its smallest extent, or flagged
    const Quat dq = s.q_[i] * glm::conjugate(s.q0_[i]);
    const double sine = glm::length(Vec3(dq.x, dq.y, dq.z)), cosine = std::abs(dq.w);
    const double shift = glm::length(s.com_[i] - s.com0_[i]);
    // most bodies are slow: atan2(s, c) <= s / c bounds the angle from above (by more than the
    // library's and the division's rounding), so one that stays within half its extent even
    // by the bound skips the arc tangent, as the test below would skip it (rounding is monotone)
    // (from the arrays: the sweep, zeroed and filled, was a fifth of this pass's time in the
    // rain's landing, for the bodies this skips)
    // (`travel`: the points' travel bounded so, used again by the statics' scan below)
    const double travel = shift + 2 * (sine / cosine) * (1 + 1e-12) * s.extent_[i];
    if (!s.bullet_[i] && travel <= 0.5 * s.min_extent_[i]) continue;
    // stopped within its slop of what it hits (pair_slop: less for a small body)
    const double target = pair_slop(cs, s.min_extent_[i]), tol = 0.25 * target;
    // everything the body can touch on its way: its centre's path grown by its reach (the
    // sweep's, below, made from the same values)
    const Aabb path = Aabb{glm::min(s.com0_[i], s.com_[i]), glm::max(s.com0_[i], s.com_[i])}.grown(s.extent_[i] + target);
    // A fast body whose path reaches no static shape's bounds is swept against nothing, and
    // one whose only such shape is a plane it stays above by more than its points can travel
    // is swept against it for nothing (the core's and every shape's first advance would jump
    // past the step's end: see below): the time of impact stays 1 and nothing is written. So
    // the statics are scanned first, before the arc tangent, the sweep and the cores: in the
    // 10,000-body rain every falling body is fast, and its sweeps came to 3-4 M instructions
    // a step. The points' travel is bounded from above as in the test above (the angle by
    // 2 s / c); a margin of 1e-9 (relative and in m) stands for the sweeps' rounding.
    {
      std::size_t near = 0;
      for (; near < statics.size(); ++near) {
        const std::uint32_t k = statics[near];
        const ShapeProxy& other = proxies[k];
        if (!other.box.overlaps(path)) continue;
        const RigidShapeDef& sb = s.shapes_[other.body][other.shape];
        if (sb.shape.type != ShapeType::Plane) break;
        const Pose& pb = shape_pose(s, k, other.body, other.shape);
        // (as the sweep below measures the plane)
        const Vec3 nw = glm::normalize(pb.rotation * sb.shape.normal);
        const double off = plane_offset(sb.shape, pb, nw);
        // the centre's height at the start less the reach: no point of the body lower
        const double low = glm::dot(nw, s.com0_[i]) - off - s.extent_[i];
        if (!(low - (target + tol) > travel * (1 + 1e-9) + 1e-9)) break;
      }
      // a bullet's moving targets: the non-bullet dynamic and kinematic bodies (asleep too)
      // whose bounding boxes about their centres of mass at the step's end (reach on every
      // side) the path reaches, found through the broad phase's tree (see find_targets)
      bullet_targets.clear();
      if (late) find_targets(s, i, path);
      if (near == statics.size() && bullet_targets.empty()) continue;
    }
    // (every field in the braces, none written twice: made with zeros for the angle and the
    // axis and these set after, the whole 26 quadwords were zeroed first)
    const double angle = 2 * std::atan2(sine, cosine);
    const Vec3 axis = sine > 0 ? Vec3(dq.x, dq.y, dq.z) / sine : Vec3(0.0);
    const Sweep w{s.com0_[i], s.com_[i], s.q0_[i], s.q_[i], s.principal_[i], s.com_local_[i],
                  angle,      s.extent_[i], axis};
    // (the farthest any point of the body travels in the step, m)
    const double moved = shift + w.angle * w.reach;
    if (!s.bullet_[i] && moved <= 0.5 * s.min_extent_[i]) continue;
    // ... or rather the farthest its shapes' cores travel: a ball that rolls or spins moves
    // its surface within itself (see core_reach)
    // (each convex shape's core reach made once for the body, for this test and every
    // static's sweeps below: a hull's, from its vertices' bounds, was made again per static)
    const std::vector<RigidShapeDef>& shapes = s.shapes_[i];
    constexpr std::size_t kReaches = 8;
    double reach_of[kReaches];
    for (std::size_t j = 0; j < std::min(kReaches, shapes.size()); ++j)
      if (shapes[j].shape.is_convex()) reach_of[j] = core_reach(shapes[j], w.com_local);
    auto shape_reach = [&](std::size_t j) { return j < kReaches ? reach_of[j] : core_reach(shapes[j], w.com_local); };
    if (!s.bullet_[i]) {
      double core = 0;
      for (std::size_t j = 0; j < shapes.size(); ++j)
        core = std::max(core, shapes[j].shape.is_convex() ? shape_reach(j) : w.reach);
      if (shift + w.angle * std::min(core, w.reach) <= 0.5 * s.min_extent_[i]) continue;
    }
    double toi = 1;
    // the direction (unit, world) of a static shape that the body's core started the step
    // touching and moved on into, when one did; the body then keeps none of its speed along it
    Vec3 into(0.0);
    // the body's core: a ball of half its smallest extent about the centre of mass, moving
    // with the centre only (see below)
    Sweep core = w;
    core.angle = 0, core.reach = 0;
    // (its proxy made directly, once for the body, moved to each time asked: a ColliderShape
    // for it, 26 quadwords zeroed, and a proxy made of it each time were work nothing read)
    const double core_radius = 0.5 * s.min_extent_[i];
    ConvexProxy core_ball{.type = ShapeType::Sphere, .radius = core_radius};
    auto core_at = [&](double t) -> const ConvexProxy& {
      core_ball.pose.position = core.c0 + t * (core.c1 - core.c0);
      return core_ball;
    };
    // (the centre of mass inside one of the body's shapes: its core ball may reach out of a
    // thin hull, which is then stopped up to that much short of the face, never through it)
    auto core_inside = [&] {
      for (const RigidShapeDef& d : shapes)
        if (holds_ball(d, w.com_local, 0.0)) return true;
      return false;
    };
    // A body whose centre of mass lies outside its shapes (a dumbbell, a ring, a U) has no
    // core: a ball there is not part of it, and swept against what passes through its gap it
    // put the body back as if that had hit it (a dumbbell at 50 m/s past a rail between its
    // balls was set 0.8 m back, and caught on a mesh strip). Its shapes' own sweeps still hold.
    const bool has_core = core_inside();
    // the core against one static convex piece (gap_at: its gap at fraction t): the time it
    // comes within the slop; or, when it starts the step within the slop and its centre's path
    // goes on into the piece, the start of the step, moving no more into it (only a body with
    // a core: a T-handle's centre of mass below its ball rests within the slop of the ground)
    // (`keep_out` false: a moving target, whose contact shares the momentum, sets no `into`)
    auto core_against = [&](auto gap_at, bool keep_out = true) {
      const Gap g0 = gap_at(0.0);
      // (the advance's first gap is this one: made again there, it was a GJK run a triangle
      // for nothing, 36 of the terrain's landing steps' 1,350 a step)
      if (g0.distance > target + tol)
        toi = std::min(toi, advance(core, [&](double t) { return t == 0.0 ? g0 : gap_at(t); }, target, tol));
      else if (keep_out && glm::dot(core.c1 - core.c0, g0.normal) > g0.distance + target)
        toi = 0, into = g0.normal;
    };
    // a convex shape sa of the body, swept with ws, against a convex piece pbx that stays put:
    // the fraction of the step at which they come within the slop (1: not in the step)
    auto shape_against = [&](const Sweep& ws, const RigidShapeDef& sa, const ConvexProxy& pbx) {
      return advance(ws, [&](double t) {
        const DistanceResult r = gjk_distance(ConvexProxy::of(sa.shape, compose(w.body(t), sa.local)), pbx);
        return Gap{r.cores_overlap ? 0.0 : r.distance, r.normal};
      }, target, tol);
    };
    // the path's bounds in the frame of a mesh posed at pb
    // (a box's bounds, as bounds() makes them, without a ColliderShape made and checked for
    // it: 26 quadwords zeroed per body and mesh; the path's half extents are finite and > 0)
    auto mesh_box = [&](const Pose& pb) {
      const Pose in = compose(inverse(pb), Pose{0.5 * (path.hi + path.lo)});
      const Vec3 h = detail::rotated_half(in.rotation, 0.5 * (path.hi - path.lo));
      return Aabb{in.position - h, in.position + h};
    };
    // a mesh's triangle as a convex piece, for the core's and the shapes' sweeps: made once for
    // the body, its pose set per mesh and its corners per triangle (made per triangle, it was
    // 15 quadwords zeroed 57k times in the terrain's run; per mesh, 32k)
    Vec3 corners[3];
    ConvexProxy piece{.type = ShapeType::Mesh, .triangle = corners};
    // The triangles a mesh's tree gives for the path's bounds, listed by the first sweep that
    // asks (the core's, then each shape's): the same triangles in the same order for each
    // (query() has no state), without a walk of the tree per sweep. The tree's walk, repeated
    // for the core and the shape, was some 0.3 M instructions of a landing step's 7 M in this
    // pass on the terrain. More than the list holds: the tree is walked each time, as before.
    constexpr std::uint32_t kListed = 128;
    std::uint32_t listed[kListed];
    std::uint32_t listed_count = 0;  // kListed + 1: more than that
    const TriangleMesh* listed_mesh = nullptr;
    auto each_triangle = [&](const TriangleMesh& mesh, const Aabb& box, auto&& visit) {
      if (listed_mesh != &mesh) {
        listed_mesh = &mesh, listed_count = 0;
        mesh.query(box, [&](std::uint32_t tri) {
          if (listed_count < kListed) listed[listed_count++] = tri;
          else listed_count = kListed + 1;
        });
      }
      if (listed_count > kListed) return mesh.query(box, visit);
      for (std::uint32_t j = 0; j < listed_count; ++j) visit(listed[j]);
    };
    for (const std::uint32_t k : statics) {
      const ShapeProxy& other = proxies[k];
      if (!other.box.overlaps(path)) continue;
      const RigidShapeDef& sb = s.shapes_[other.body][other.shape];
      const Pose& pb = shape_pose(s, k, other.body, other.shape);  // (static: as at the step's start)
      // a plane's unit normal and offset in the world (its solid on the negative side)
      const bool plane = sb.shape.type == ShapeType::Plane;
      const Vec3 nw = plane ? glm::normalize(pb.rotation * sb.shape.normal) : Vec3(0.0);
      const double off = plane ? plane_offset(sb.shape, pb, nw) : 0.0;
      // a mesh's: the path's bounds in its frame (the core's sweep and the shapes' query the same box)
      const Aabb in_mesh = sb.shape.type == ShapeType::Mesh ? mesh_box(pb) : Aabb{};
      listed_mesh = nullptr;  // (a mesh static's triangles listed afresh: each static its own box)
      piece.pose = pb;
      // A body that starts the step touching a static shape is left to the discrete contact
      // (advance() returns 1 for it). Turning fast, the manifold made at the start of the step
      // holds corners that turn away within a substep while others come in, and the contact
      // may not stop it: under XPBD a 0.5 m box reaching a 0.2 m wall at 39 m/s and 309 rad/s
      // went through it (the closed box at 200 m/s). So the core must not reach a static shape
      // along the centre's path either (Box2D v3's continuous pass keeps a core out the same
      // way): where it would, the body goes back to that time. A core that starts the step
      // within the slop of the shape, and whose centre's path goes on into it, stays where it
      // started and stops moving into it (below, `into`): the manifold made at the start of
      // the step could not stop it (its points turned away), and left to it a capsule thrown
      // at 100 m/s and spinning at 430 rad/s went through a 0.2 m wall at 40 m/s.
      if (!has_core) {
        // no core to keep out (above); the shapes' sweeps below
      } else if (plane) {
        auto gap_at = [&](double t) {
          return Gap{glm::dot(nw, core.c0 + t * (core.c1 - core.c0)) - off - core_radius, -nw};
        };
        const Gap g0 = gap_at(0.0);
        if (g0.distance > target + tol)
          toi = std::min(toi, advance(core, gap_at, target, tol));
        else if (gap_at(1.0).distance < std::min(g0.distance, 0.0) - target)
          toi = 0, into = -nw;
      } else if (sb.shape.is_convex()) {
        const ConvexProxy pbx = ConvexProxy::of(sb.shape, pb);
        auto gap_at = [&](double t) {
          const DistanceResult r = gjk_distance(core_at(t), pbx);
          return Gap{r.cores_overlap ? 0.0 : r.distance, r.normal};
        };
        core_against(gap_at);
      } else if (sb.shape.type == ShapeType::Mesh) {
        // each triangle the path reaches, as for the shapes below; one whose plane the core
        // stays farther from, on one side, than its radius and the slop is skipped
        const TriangleMesh& mesh = *sb.shape.mesh;
        each_triangle(mesh, in_mesh, [&](std::uint32_t tri) {
          for (int c = 0; c < 3; ++c) corners[c] = mesh.vertices()[mesh.triangles()[tri][c]];
          const Vec3 face = pb.rotation * mesh.normal(tri);
          const double plane = glm::dot(face, apply(pb, corners[0]));
          const double h0 = glm::dot(face, core.c0) - plane, h1 = glm::dot(face, core.c1) - plane;
          const double clear = core_radius + target + tol;
          if ((h0 > clear && h1 > clear) || (h0 < -clear && h1 < -clear)) return;
          core_against([&](double t) {
            const DistanceResult r = gjk_distance(core_at(t), piece);
            return Gap{r.cores_overlap ? 0.0 : r.distance, r.normal};
          });
        });
      }
      for (std::size_t j = 0; j < shapes.size(); ++j) {
        const RigidShapeDef& sa = shapes[j];
        if (!sa.shape.is_convex()) continue;
        auto pose_a = [&](double t) { return compose(w.body(t), sa.local); };
        // the shape's own sweep: the body's, turning its core's reach (never more than the body's)
        Sweep ws = w;
        ws.reach = std::min(w.reach, shape_reach(j));
        const double moved_a = shift + ws.angle * ws.reach;  // the farthest its core travels (m)
        // A swept hit matters only when the step left the shape deeper than the slop: one that
        // ends on its side of the surface, within the slop, was stopped by the discrete
        // (speculative) contact, and putting it back to the time of impact would set it down
        // the slop above the surface, moving as the solver left it (a 5 cm ball dropped 30 cm
        // with e = 0.2 bounced from 5 mm up and rose to 1.65 cm instead of e^2 h = 1.2 cm)
        if (plane) {
          // the gap is the height of the shape's lowest point along the normal (signed: a
          // plane is a half-space, so the end pose tells whether the shape went in)
          auto gap_at = [&](double t) {
            const Pose pa = pose_a(t);
            const Vec3 low = apply(pa, support(sa.shape, glm::conjugate(pa.rotation) * -nw));
            return Gap{glm::dot(nw, low) - off, -nw};
          };
          // (the end pose first: only a shape that ends deeper than the slop is swept at all.
          // The same outcome as sweeping first, as the gaps have no side effects; in the rain's
          // landing the bodies turning fast just above the ground, whose advances take small
          // steps, made some eight gaps each for a hit that was then not taken)
          if (gap_at(1.0).distance < -target) toi = std::min(toi, advance(ws, gap_at, target, tol));
        } else if (sb.shape.type == ShapeType::Mesh) {
          // each triangle the path reaches, as a convex piece in the mesh frame
          const TriangleMesh& mesh = *sb.shape.mesh;
          // the shape at the step's start, once for all the triangles (the advances' first gap too)
          const Pose p0 = pose_a(0.0);
          const Quat p0_inv = glm::conjugate(p0.rotation);
          // the shape at the step's end and its centre at the start, for the end pose's test:
          // made when a triangle first asks (in the terrain's landing steps most bodies'
          // triangles end before it, and the pose's slerp was made for nothing)
          Pose p1;
          Vec3 centre0;
          bool ends_made = false;
          each_triangle(mesh, in_mesh, [&](std::uint32_t tri) {
            for (int c = 0; c < 3; ++c) corners[c] = mesh.vertices()[mesh.triangles()[tri][c]];
            const Vec3 face = pb.rotation * mesh.normal(tri), corner = apply(pb, corners[0]);
            const std::uint8_t flags = mesh.edge_flags()[tri];
            // a shape farther from the triangle's plane, on its side, than any of its points
            // can travel in the step never reaches the triangle (the first advance would
            // jump past the step's end): two support points instead of GJK
            const double plane = glm::dot(face, corner);
            const double above = glm::dot(face, apply(p0, support(sa.shape, p0_inv * -face))) - plane;
            const double below = plane - glm::dot(face, apply(p0, support(sa.shape, p0_inv * face)));
            if (std::max(above, below) - target > moved_a * (1 + 1e-12) + 1e-12) return;
            auto gap_at = [&](double t) {
              const Pose pa = t == 0.0 ? p0 : pose_a(t);
              const DistanceResult r = gjk_distance(ConvexProxy::of(sa.shape, pa), piece);
              if (r.cores_overlap) return Gap{0.0, r.normal};
              // nearest the face or an internal (flat or concave) edge or vertex: the gap is the
              // one to the triangle's plane, on the side of the shape's centre, as the contact
              // takes it (collide_mesh); else a body rolling over a flat mesh was stopped at each
              // edge between its triangles. The plane is never farther than the triangle, so
              // the advance stays safe
              if (internal_feature(corners, apply_inverse(pb, r.point_b), flags)) {
                const Vec3 centre =
                    sa.shape.type == ShapeType::Hull ? apply(pa, sa.shape.hull->centroid()) : pa.position;
                const Vec3 n = glm::dot(centre - corner, face) >= 0 ? face : -face;
                const Vec3 low = apply(pa, support(sa.shape, glm::conjugate(pa.rotation) * -n));
                return Gap{glm::dot(n, low - corner), -n};
              }
              return Gap{r.distance, r.normal};
            };
            // A hit is taken only when the shape did not end the step on its side of the
            // triangle within the slop (below). The advance is made in parts around that test,
            // with the same outcome as the advance first: its first gap (a shape already that
            // close at the start gets no hit: advance() returns 1), its first pass on that gap,
            // then the end pose, then the rest of the advance from that first gap. On the
            // terrain 45% of the triangles swept ended on their side, and their advances took
            // four or five gaps (GJK) each.
            const Gap g0 = gap_at(0.0);
            if (g0.distance <= target + tol) return;
            // Where the first pass's bound on the shapes' closing speed carries t past the
            // step's end, the advance gives 1 whatever the end pose: the end pose's GJK is not
            // run for it. On the terrain's landing steps (130-159) 348 of the 520 triangles a
            // step that came this far ended so (of the pass's some 1,350 GJK runs a step)
            if (ends_at_first_pass(ws, g0, target, tol)) return;
            // the end pose (as for the plane above): nearest the face or an internal feature,
            // on the side the shape's centre started on and within the slop of the plane, it
            // did not go through (a shape that crossed the triangle ends on its other side)
            if (!ends_made) {
              p1 = pose_a(1.0);
              centre0 = sa.shape.type == ShapeType::Hull ? apply(p0, sa.shape.hull->centroid()) : p0.position;
              ends_made = true;
            }
            const DistanceResult r1 = gjk_distance(ConvexProxy::of(sa.shape, p1), piece);
            if (!r1.cores_overlap && internal_feature(corners, apply_inverse(pb, r1.point_b), flags)) {
              const Vec3 n = glm::dot(centre0 - corner, face) >= 0 ? face : -face;
              const Vec3 low = apply(p1, support(sa.shape, glm::conjugate(p1.rotation) * -n));
              if (glm::dot(n, low - corner) >= -target) return;
            }
            // (the first gap as made above: the gaps have no side effects)
            const double hit = advance(ws, [&](double t) { return t == 0.0 ? g0 : gap_at(t); }, target, tol);
            if (hit < toi) toi = hit;
          });
        } else if (sb.shape.is_convex()) {
          toi = std::min(toi, shape_against(ws, sa, ConvexProxy::of(sb.shape, pb)));
        }
      }
    }
    // A bullet against each moving body its path reaches, that body held at its pose at the
    // step's end (its own put-back made): the core and each convex shape swept against each
    // of its convex shapes, as against a static convex shape above. A pair within the slop at
    // the start is left to the discrete contact (no `into`: the target moves, and the contact
    // between them shares the momentum). (A target that crosses the bullet's path within the
    // step is seen where it ends: as Box2D v3, a bullet is stopped at a body it would pass
    // through, not at every body its path crossed in the course of the step.)
    for (const std::uint32_t j : bullet_targets) {
      const Pose body_b = s.body_pose(j);
      for (const RigidShapeDef& sb : s.shapes_[j]) {
        if (!sb.shape.is_convex()) continue;
        const ConvexProxy pbx = ConvexProxy::of(sb.shape, shape_frame(body_b, sb.local));
        if (has_core)
          core_against([&](double t) {
            const DistanceResult r = gjk_distance(core_at(t), pbx);
            return Gap{r.cores_overlap ? 0.0 : r.distance, r.normal};
          }, false);
        for (std::size_t a = 0; a < shapes.size(); ++a) {
          if (!shapes[a].shape.is_convex()) continue;
          Sweep ws = w;
          ws.reach = std::min(w.reach, shape_reach(a));
          toi = std::min(toi, shape_against(ws, shapes[a], pbx));
        }
      }
    }
    if (toi >= 1) continue;
    // back to the first contact, moving as it moved there (but not on into a shape its core
    // started the step touching: the next step's contact would not stop it either). The
    // solver left it the step's end velocity, which holds what gravity and the applied force
    // and torque added over the whole step; at the time of impact only toi of the step had
    // passed, so the rest, (1 - toi) dt of them, is taken back. Kept, a body falling at v
    // gained m g v (1 - toi) dt a put-back (its weight times the height it went back up, at
    // the end speed): thin elastic rods rose 3-10% over their drop under XPBD. Taken back,
    // the free flight's energy at the time of impact (the centre at c0 + toi (c1 - c0) after
    // n symplectic Euler substeps, velocity v0 + toi g dt) is the step's start energy plus
    // m g^2 dt^2 (toi^2 / 2 - toi (n + 1) / (2 n)) <= 0: never more than the step began with
    // (RigidContinuous.AFastElasticDropCaughtByTheContinuousPassGainsNoEnergy).
    // (the angular velocity turned back with the body, as its frame's: kept in world axes, a
    // rod spinning 84 rad/s about its long axis put back 0.17 rad gained 36% of its energy)
    const double rest = (1 - toi) * s.last_dt_;  // the part of the step not travelled (s)
    s.v_[i] -= rest * (s.gravity_scale_[i] * s.gravity_ + s.inv_mass_[i] * s.force_[i]);
    const Vec3 w_end = s.w_[i] - rest * (s.q_[i] * (s.inv_inertia_[i] * (glm::conjugate(s.q_[i]) * s.torque_[i])));
    const Quat back = glm::normalize(glm::slerp(w.q0, w.q1, toi));
    s.com_[i] = w.c0 + toi * (w.c1 - w.c0);
    s.w_[i] = back * (glm::conjugate(s.q_[i]) * w_end);
    s.q_[i] = back;
    if (toi == 0) s.v_[i] -= std::max(0.0, glm::dot(s.v_[i], into)) * into;
    ++continuous_hits, ++s.profile_.put_back;
  }
}

}  // namespace pba::detail
