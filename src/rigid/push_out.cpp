// Rigid bodies: the soft step's position pass for deep contacts (heavy bodies on light ones).
//
// A soft contact is a spring sized by the effective mass of its two bodies, so a light body
// under a heavy load deflects by load / (m w^2): at the defaults (8 substeps, 120 Hz) a 400:1
// stack overlapped 2.6 cm and a 2 cm ball under a 432 kg box rested with its centre under the
// ground. Stiffer springs for loaded contacts make tall stacks jitter (docs/rigid-bodies.md,
// "What we tried for tall stacks"). This pass leaves the springs' stiffness alone. After the
// substeps, when some point overlaps more than the linear slop (which no contact of a stack
// of equal boxes reaches: their deflections are under a millimetre), it moves the bodies of
// those contacts apart until they overlap at most half the slop (non-linear Gauss-Seidel on
// positions, as Box2D v2.4's position solver and Jolt's position iterations), and shifts the
// springs' rest separation by as much (the manifold's `preload`), so that the springs still
// see the overlap they hold the load at. Without the shift the springs, now short of their
// deflection, let the bodies sink into each other again every step: the 400:1 stack's heavy
// cube kept 0.46 m/s of sinking velocity while the pass held its place, and the column
// buckled within 3 s. With it, what the velocity passes see does not change; a manifold
// shallower than a quarter of the slop gives its shift back (a body whose load went away
// settles onto its contact again). The bodies are moved without turning, so all points of a
// manifold move alike and one shift per manifold undoes it. And the approach along the normal
// of the bodies the pass moved apart is taken away (kinetic energy removed, never added):
// lifted while it kept falling, the cube bounced on its springs higher every time.
//
// Plain Gauss-Seidel on rigid effective masses does not carry a large mass ratio: a ball
// pressed between the ground and a box 800 times heavier moves back and forth, the box going
// up by 1/800 of the overlap a sweep. So the pass propagates the correction upward
// (Guendelman, Bridson and Fedkiw 2003, "shock propagation"): a contact whose normal is
// within 60 degrees of the vertical treats its lower body as fixed when the upper one can
// move, and the contacts run in order of the height of their lower body, the ground's first:
// a stack is put right in one sweep whatever its masses. Other contacts (sideways, or without
// gravity) share the correction by the bodies' effective masses.
#include <algorithm>
#include <type_traits>

#include "contacts.h"

namespace pba::detail {

namespace {

// cos of the largest angle between a contact's normal and the vertical at which its lower
// body is taken as the support (60 degrees)
constexpr double kSupportCos = 0.5;
// sweeps over the contacts
constexpr int kPushOutSweeps = 4;
// the overlap the pass leaves, and under which a manifold gives its shift back, in slops
constexpr double kLeave = 0.5, kGiveBack = 0.25;

}  // namespace

bool RigidContacts::push_out(RigidBodySystem& s, const Vec3& gravity) {
  const ContactSettings& cs = s.settings_;
  // the settings' slop, and a smaller one for a pair with a body under kSlopPerHalfSize of it
  // (`thinnest` says whether there may be one: else every pair's is the setting's)
  const double slop = cs.linear_slop;
  const bool small = kSlopPerHalfSize * thinnest < slop;
  // the deep manifolds, from the separations the last relax pass measured at the poses now
  // (those of the springs: a shifted manifold is listed in `preloaded` anyway)
  deep.clear();
  auto scan = [&](const auto* array, std::size_t count) {
    for (std::size_t b = 0; b < count; ++b) {
      const auto& k = array[b];
      constexpr int P = std::remove_reference_t<decltype(k)>::kPoints;
      for (int l = 0; l < k.lanes; ++l) {
        Real least = 0;
        for (int p = 0; p < P; ++p) least = std::min(least, k.sep[p][l]);
        if (k.pair[l] == kNoPair || least >= 0) continue;
        if (least < -slop || (small && least < -slop_of(s, k.a[l], k.b[l]))) deep.push_back(k.pair[l]);
      }
    }
  };
  const std::size_t room = pairs.capacity() + 1;
  deep.reserve(room);
  scan(blocks.data(), block_count);
  scan(ones.data(), one_blocks);
  if (deep.empty() && preloaded.empty()) return false;
  // their dynamic bodies, and every manifold that touches one (pushing a body out of one
  // contact may press it into another)
  const std::size_t n = s.type_.size();
  auto moving = [&](std::uint32_t i) { return s.type_[i] == BodyType::Dynamic && !s.asleep_[i]; };
  pushed.reserve(n + 1);
  pushed.assign(n, 0);
  for (const auto* list : {&deep, &preloaded})
    for (const std::uint32_t k : *list) {
      const ContactPair& c = pairs[k];
      if (moving(c.a)) pushed[c.a] = 1;
      if (moving(c.b)) pushed[c.b] = 1;
    }
  const double g = glm::length(gravity);
  const Vec3 up = g > 0 ? -gravity / g : Vec3(0);
  // the true separation of point p of `c` at the poses now (m): the springs' (offset) plus
  // the shift they were given; `turn_a`, `turn_b`: the bodies' turns since the step's start
  // (made once for the pair's points: made again for each point, the separations were a
  // third of this pass's instructions in the rain's landing)
  auto separation = [&](const ContactPair& c, const Quat& turn_a, const Quat& turn_b, int p, double shift) {
    const SolverPoint& pt = c.points[p];
    return glm::dot(s.com_[c.b] + turn_b * pt.sb - s.com_[c.a] - turn_a * pt.sa, c.normal) + pt.offset + shift;
  };
  // Every manifold touching a pushed body, with its lower body's height (the ground's
  // contacts first; ties in pair order), its deepest point's separation now and its bodies'
  // inverse masses for the pass: the lower body of a contact near the vertical holds still
  // while the upper one moves. (Found from the blocks' bodies, a few lines a block, not from
  // the pairs, ten lines each: the pass runs in most steps of the 10,000-body rain's landing.)
  // (In two rounds: the blocks give the pairs first (into `deep`, read no more), then each
  // pair is read with the lines of the pair some places ahead asked for, and of the
  // manifold's preload a few places ahead, its record read from those lines by then. Read as
  // the blocks gave them, each pair's and manifold's lines were waited on in turn: on the
  // terrain, where the pass runs every step, the wait for the preload alone was a quarter of
  // this function's time. The sort below orders them by height and pair alone)
  deep.clear();
  auto listed = [&](const auto* array, std::size_t count) {
    for (std::size_t b = 0; b < count; ++b) {
      const auto& k = array[b];
      for (int l = 0; l < k.lanes; ++l)
        if (k.pair[l] != kNoPair && (pushed[k.a[l]] || pushed[k.b[l]])) deep.push_back(k.pair[l]);
    }
  };
  listed(blocks.data(), block_count);
  listed(ones.data(), one_blocks);
  // a pair's lines that the gather reads: the key (its record and bodies), the normal, the
  // count, and the points (a one-point lane's, the first two of a face's)
  constexpr std::size_t kPairsAhead = 8, kRecordsAhead = 4;
  // (the lines from the layout: a face's first two points span three lines from `points`)
  static constexpr std::size_t kPoints = offsetof(ContactPair, points);
  static_assert(kPoints % 64 == 0 && 2 * sizeof(SolverPoint) <= 3 * 64);
  static constexpr std::size_t kLines[] = {0, offsetof(ContactPair, normal) / 64 * 64,
                                           offsetof(ContactPair, count) / 64 * 64, kPoints, kPoints + 64,
                                           kPoints + 128};
  auto ask_pair = [&](std::uint32_t k) {
    const char* at = reinterpret_cast<const char*>(&pairs[k]);
    for (const std::size_t line : kLines) __builtin_prefetch(at + line);
  };
  order.reserve(room);
  order.clear();
  const std::size_t listed_count = deep.size();
  for (std::size_t i = 0; i < std::min(kPairsAhead, listed_count); ++i) ask_pair(deep[i]);
  for (std::size_t i = 0; i < listed_count; ++i) {
    if (i + kPairsAhead < listed_count) ask_pair(deep[i + kPairsAhead]);
    if (i + kRecordsAhead < listed_count) {
      const std::uint32_t ahead = pairs[deep[i + kRecordsAhead]].record;
      if (ahead != kNoIndex) __builtin_prefetch(&manifolds[ahead].preload);
    }
    const ContactPair& c = pairs[deep[i]];
    if (c.record == kNoIndex) continue;
    // (every field written: not zeroed first)
    Ordered o;
    o.pair = deep[i], o.record = c.record, o.a = c.a, o.b = c.b, o.n = c.normal;
    o.slop = slop_of(s, c.a, c.b);
    const bool ma = moving(c.a), mb = moving(c.b);
    o.height = std::min(ma ? glm::dot(s.com_[c.a], up) : -1e300, mb ? glm::dot(s.com_[c.b], up) : -1e300);
    o.ma = ma ? s.inv_mass_[c.a] : 0, o.mb = mb ? s.inv_mass_[c.b] : 0;
    o.held = false;
    const double rise = glm::dot(c.normal, up);  // > 0: b is above a
    if (rise > kSupportCos && o.mb > 0 && o.ma > 0) o.ma = 0, o.held = true;
    if (rise < -kSupportCos && o.ma > 0 && o.mb > 0) o.mb = 0, o.held = true;
    const double shift = manifolds[c.record].preload;
    const Quat turn_a = s.q_[c.a] * glm::conjugate(s.q0_[c.a]), turn_b = s.q_[c.b] * glm::conjugate(s.q0_[c.b]);
    o.before = separation(c, turn_a, turn_b, 0, shift);
    for (int p = 1; p < c.count; ++p) o.before = std::min(o.before, separation(c, turn_a, turn_b, p, shift));
    o.after = 0;
    order.push_back(o);
  }
  std::sort(order.begin(), order.end(), [](const Ordered& x, const Ordered& y) {
    return x.height != y.height ? x.height < y.height : x.pair < y.pair;
  });
  // The pass moves the bodies without turning them: every point of a manifold then moves by
  // the same distance along its normal, which one shift of the springs' rest undoes exactly
  // (turned about a corner, a cube landed tilted on its springs, and the spring's torque and
  // friction walked the 400:1 stack's heavy cube off the column at 0.1 m/s). So a manifold's
  // deepest point stays its deepest, at its separation before plus the bodies' moves.
  lift.reserve(n + 1);
  lift.assign(n, Vec3(0));
  auto now = [&](const Ordered& o) { return o.before + glm::dot(lift[o.b] - lift[o.a], o.n); };
  for (int sweep = 0; sweep < kPushOutSweeps; ++sweep) {
    for (const Ordered& o : order) {
      if (o.ma + o.mb == 0) continue;
      // only a manifold deeper than the slop (in the first sweep), then whatever the pass
      // left deeper than half of it
      const double sep = now(o), leave = kLeave * o.slop;
      if (sep >= (sweep == 0 && o.before >= -o.slop ? -o.slop : -leave)) continue;
      // the overlap beyond what the pass leaves, at most push_out_speed over the step
      const double push = std::min(-leave - sep, cs.push_out_speed * s.last_dt_);
      const Vec3 d = (push / (o.ma + o.mb)) * o.n;
      lift[o.a] -= o.ma * d;
      lift[o.b] += o.mb * d;
    }
  }
  // (only the bodies moved: adding a zero would turn a -0 coordinate into +0)
  for (std::uint32_t i = 0; i < n; ++i)
    if (lift[i] != Vec3(0)) s.com_[i] += lift[i];
  // A small body (one with its own slop under the settings') lifted against gravity while it
  // moves away along the lift pays the lift's potential energy out of that motion: within a
  // smaller slop the pass lifts bodies that bounce off the ground (restitution already gave
  // them their speed back), and a 2 cm thick rod bouncing at e = 1 rose 1.5% above its start
  // (RigidSoak.PerturbedRodDropsGainNoEnergyAndJumpNowhere)
  if (small)
    for (std::uint32_t i = 0; i < n; ++i) {
      if (lift[i] == Vec3(0) || !(kSlopPerHalfSize * s.min_extent_[i] < slop)) continue;
      const double rise = -glm::dot(s.gravity_scale_[i] * gravity, lift[i]);  // potential energy per mass (J/kg)
      const double length = glm::length(lift[i]);
      const Vec3 along = lift[i] / length;
      const double v = glm::dot(s.v_[i], along);
      if (!(rise > 0) || !(v > 0)) continue;
      s.v_[i] += (std::sqrt(std::max(0.0, v * v - 2 * rise)) - v) * along;
    }
  for (Ordered& o : order) o.after = now(o);
  // the manifolds the pass moved apart stop closing: the approach of their bodies' centres
  // along the normal is taken away (bottom up, the supports holding still as above), so that
  // a body falling onto a light one is stopped as by a rigid contact instead of being lifted
  // while it keeps its speed (with the springs' rest shifted below, that fed a 400:1 stack's
  // bounce on its springs until it fell over)
  for (int sweep = 0; sweep < kPushOutSweeps; ++sweep) {
    for (const Ordered& o : order) {
      if (!(o.after > o.before) || o.ma + o.mb == 0) continue;
      const double vn = glm::dot(s.v_[o.b] - s.v_[o.a], o.n);
      if (vn >= 0) continue;
      // a body on a support held still is stopped, not thrown: it loses at most its own
      // speed toward the support (a light body thrown up into a heavy one must not give the
      // heavy one its speed)
      double stop = -vn;
      if (o.held) stop = std::min(stop, std::max(0.0, o.mb > 0 ? -glm::dot(s.v_[o.b], o.n) : glm::dot(s.v_[o.a], o.n)));
      const Vec3 d = (stop / (o.ma + o.mb)) * o.n;
      s.v_[o.a] -= o.ma * d;
      s.v_[o.b] += o.mb * d;
    }
  }
  // the springs' rest shifted by as much as the pass moved each manifold's deepest point, so
  // the velocity passes see what they saw; a manifold shallower than a quarter of the slop
  // gives back the shift it has beyond that
  for (const Ordered& o : order) {
    float& shift = manifolds[o.record].preload;
    double next = shift + (o.after - o.before);
    if (o.after > -kGiveBack * o.slop) next -= o.after + kGiveBack * o.slop;
    shift = static_cast<float>(std::max(0.0, next));
  }
  return true;
}

}  // namespace pba::detail
