// Rigid bodies: contact pairs and their manifolds, with warm-start matching. Each step the
// shapes' bounds (grown by the speculative distance and the step's motion) are swept for
// pairs, sleeping islands that a moving body reaches are woken, the narrow phase builds each
// pair's manifold, and each point takes last step's impulses from the point with the same
// feature id (or the nearest one). The solver passes are in contact_solver.cpp.
#include "contacts.h"

#include <algorithm>
#include <cmath>

namespace pba::detail {

namespace {

// an orthonormal basis (t1, t2) perpendicular to the unit n, a continuous function of n
// away from n = -z (Duff et al. 2017, "Building an orthonormal basis, revisited")
void tangent_basis(const Vec3& n, Vec3& t1, Vec3& t2) {
  const double sign = std::copysign(1.0, n.z);
  const double a = -1.0 / (sign + n.z), b = n.x * n.y * a;
  t1 = Vec3(1 + sign * n.x * n.x * a, sign * b, -sign * n.x);
  t2 = Vec3(b, sign + n.y * n.y * a, -n.y);
}

double mix(MixRule r, double a, double b) {
  switch (r) {
    case MixRule::GeometricMean: return std::sqrt(a * b);
    case MixRule::Minimum: return std::min(a, b);
    case MixRule::Maximum: return std::max(a, b);
    case MixRule::Average: return 0.5 * (a + b);
    case MixRule::Product: return a * b;
  }
  return a;
}

// the radius that turns a rolling-resistance coefficient into a lever arm (m)
double rolling_radius(const ColliderShape& s) {
  switch (s.type) {
    case ShapeType::Sphere:
    case ShapeType::Capsule: return s.radius;
    default: return 0;
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------
// pairs and manifolds

void RigidContacts::update(RigidBodySystem& s, double dt) {
  const ContactSettings& cs = s.settings_;
  const std::size_t n = s.type_.size();
  // this step's pairs become last step's
  std::swap(pairs, previous);
  pairs.clear();
  // every shape's bounds, grown by the speculative distance and by how far it can move
  proxies.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const Pose body = s.body_pose(i);
    const double reach = cs.speculative_distance + std::min(glm::length(s.v_[i]) * dt, s.extent_[i]);
    for (std::uint32_t k = 0; k < s.shapes_[i].size(); ++k)
      proxies.push_back({bounds(s.shapes_[i][k].shape, compose(body, s.shapes_[i][k].local)).grown(reach),
                         static_cast<std::uint32_t>(i), k});
  }
  // sweep and prune along x (ties broken by owner, so the order is deterministic)
  std::sort(proxies.begin(), proxies.end(), [](const ShapeProxy& a, const ShapeProxy& b) {
    if (a.box.lo.x != b.box.lo.x) return a.box.lo.x < b.box.lo.x;
    if (a.body != b.body) return a.body < b.body;
    return a.shape < b.shape;
  });
  statics.clear();
  for (std::size_t i = 0; i < proxies.size(); ++i)
    if (s.type_[proxies[i].body] == BodyType::Static) statics.push_back(static_cast<std::uint32_t>(i));
  candidates.clear();
  for (std::size_t i = 0; i < proxies.size(); ++i) {
    const ShapeProxy& p = proxies[i];
    for (std::size_t j = i + 1; j < proxies.size() && proxies[j].box.lo.x <= p.box.hi.x; ++j) {
      const ShapeProxy& q = proxies[j];
      if (p.body == q.body || !p.box.overlaps(q.box)) continue;
      // two bodies that cannot move each other make no contact
      if (s.inv_mass_[p.body] == 0 && s.inv_mass_[q.body] == 0) continue;
      // order the pair by body slot so the key (and the normal's direction) is stable
      const bool swap = s.owner_[p.body] > s.owner_[q.body];
      const ShapeProxy& a = swap ? q : p;
      const ShapeProxy& b = swap ? p : q;
      candidates.push_back({s.owner_[a.body], s.owner_[b.body], a.shape, b.shape, a.body, b.body});
    }
  }
  std::sort(candidates.begin(), candidates.end());
  // a body moving faster than the sleep tolerances (or a moving kinematic one) whose bounds
  // reach a sleeping body wakes its island; repeated while waking spreads. A slow awake body
  // does not: it rests on the sleeper as on a static body (waking on any overlap let two
  // slow neighbours wake each other forever)
  auto awake_dynamic = [&](std::uint32_t i) { return s.type_[i] == BodyType::Dynamic && !s.asleep_[i]; };
  const double lin2 = cs.sleep_linear * cs.sleep_linear, ang2 = cs.sleep_angular * cs.sleep_angular;
  auto moving = [&](std::uint32_t i) {
    const double v2 = glm::dot(s.v_[i], s.v_[i]), w2 = glm::dot(s.w_[i], s.w_[i]);
    if (awake_dynamic(i)) return v2 > lin2 || w2 > ang2;
    return s.type_[i] == BodyType::Kinematic && (v2 > 0 || w2 > 0);
  };
  for (bool woke = true; woke;) {
    woke = false;
    for (const PairKey& c : candidates) {
      if (s.asleep_[c.b] && moving(c.a)) s.wake_island(c.b), woke = true;
      if (s.asleep_[c.a] && moving(c.b)) s.wake_island(c.a), woke = true;
    }
  }
  // manifolds, with last step's cache and impulses where the same pair touched
  for (const PairKey& k : candidates) {
    // points are made as far out as the two bodies can close in one step (speculative contacts)
    // (up to each body's size: faster ones are caught by the continuous pass)
    const NarrowPhaseSettings ns{.speculative_margin = cs.speculative_distance +
                                                       std::min(glm::length(s.v_[k.a]) * dt, s.extent_[k.a]) +
                                                       std::min(glm::length(s.v_[k.b]) * dt, s.extent_[k.b])};
    if (!awake_dynamic(k.a) && !awake_dynamic(k.b)) continue;  // asleep, or asleep on a still body
    // the pair's entry, kept only when the manifold has points
    ContactPair& c = pairs.emplace_back();
    c.slot_a = k.slot_a, c.slot_b = k.slot_b, c.shape_a = k.shape_a, c.shape_b = k.shape_b, c.a = k.a, c.b = k.b;
    auto old = std::lower_bound(previous.begin(), previous.end(), c);
    const bool had = old != previous.end() && !(c < *old) && !(*old < c);
    if (had) c.cache = old->cache;
    const RigidShapeDef& sa = s.shapes_[c.a][c.shape_a];
    const RigidShapeDef& sb = s.shapes_[c.b][c.shape_b];
    const Manifold m = collide(sa.shape, compose(s.body_pose(c.a), sa.local), sb.shape,
                               compose(s.body_pose(c.b), sb.local), ns, &c.cache);
    if (m.count == 0) {
      pairs.pop_back();
      continue;
    }
    c.normal = m.normal;
    tangent_basis(c.normal, c.t1, c.t2);
    c.friction = mix(cs.friction_mix, sa.material.friction, sb.material.friction);
    c.restitution = mix(cs.restitution_mix, sa.material.restitution, sb.material.restitution);
    c.rolling = std::max(sa.rolling_resistance * rolling_radius(sa.shape), sb.rolling_resistance * rolling_radius(sb.shape));
    c.count = m.count;
    const bool warm = had && cs.warm_starting;
    c.rolling_impulse = warm ? old->rolling_impulse : Vec3(0);
    // friction carried over, re-projected onto this step's tangents
    c.tangent_impulse[0] = warm ? glm::dot(old->friction_old, c.t1) : 0;
    c.tangent_impulse[1] = warm ? glm::dot(old->friction_old, c.t2) : 0;
    c.twist_impulse = warm ? old->twist_impulse : 0;
    Vec3 centroid(0);
    for (int k = 0; k < m.count; ++k) centroid += m.points[k].position();
    centroid /= static_cast<double>(m.count);
    c.ca = centroid - s.com_[c.a];
    c.cb = centroid - s.com_[c.b];
    c.twist_radius = 0;
    for (int k = 0; k < m.count; ++k) c.twist_radius += glm::length(m.points[k].position() - centroid);
    c.twist_radius /= m.count;
    // a constraint that does not act this step carries nothing (a carried twist impulse on a
    // one-point manifold, never clamped, spun a box on its corner up to 70 rad/s)
    if (c.twist_radius == 0) c.twist_impulse = 0;
    if (c.rolling == 0) c.rolling_impulse = Vec3(0);
    for (int k = 0; k < m.count; ++k) {
      SolverPoint& p = c.points[k];
      p = {};
      const Vec3 at = m.points[k].position();
      p.ra = at - s.com_[c.a];
      p.rb = at - s.com_[c.b];
      p.depth = m.points[k].depth;
      p.id = m.points[k].id;
      // the separation now is -depth; keep it relative to the anchors
      p.sa = m.points[k].point_a - core_radius(sa.shape) * c.normal - s.com_[c.a];
      p.sb = m.points[k].point_b + core_radius(sb.shape) * c.normal - s.com_[c.b];
      p.offset = -p.depth - glm::dot((s.com_[c.b] + p.sb) - (s.com_[c.a] + p.sa), c.normal);
      p.local = glm::conjugate(s.q_[c.a]) * (at - s.com_[c.a]);
      // warm start from the point with the same feature id or, when the features changed
      // (a face-on-face contact whose clipped corners sit on the edges flips their labels
      // under jitter), from the nearest old point within the linear slop in a's frame
      // (Jolt matches contact points by position the same way)
      if (warm) {
        int match = -1;
        double best = cs.linear_slop * cs.linear_slop;
        for (int o = 0; o < old->count && match < 0; ++o)
          if (old->points[o].id == p.id) match = o;
        for (int o = 0; o < old->count && match < 0; ++o) {
          const Vec3 d = old->points[o].local - p.local;
          if (glm::dot(d, d) <= best) best = glm::dot(d, d), match = o;
        }
        if (match >= 0) p.normal_impulse = old->points[match].normal_impulse;
      }
    }
  }
}

}  // namespace pba::detail
