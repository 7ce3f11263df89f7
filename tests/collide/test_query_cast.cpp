// Tests for the world's shape casts (collide/query.h): sphere casts against spheres, planes,
// boxes and capsules equal their closed forms and an independent root finding on the exact
// point distance; convex casts (box, capsule, hull) and sphere casts against every shape in
// a random world equal a fine bisection on the GJK distance to 1e-6; exact face, edge and
// corner hits of a rounded box.
//
// Tolerances. The closed forms and the reference root finding are both exact up to rounding
// (a few 1e-15 relative on 10 m), so they agree to 1e-9. Conservative advancement stops at
// a gap of kCastTolerance = 1e-10 m, and the reference bisection on the GJK distance (whose
// own accuracy is GjkStepper::kTolerance = 1e-10 m) resolves the same gap, so both times of
// impact are within about 2e-10 / s of the exact one, s being the approach speed (the
// slope of the distance along the path, per metre of travel). Contacts with s < 1e-3
// (grazing: the time of impact is ill-conditioned, a 1e-10 m error in distance moves it by
// more than 1e-7) and paths that pass within 1e-6 m of a target without touching it are
// counted and left out; they must stay a small fraction.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "pba/collide/query.h"
#include "query_scene.h"

namespace {

using namespace pba;
using namespace pba::test_support;

#if defined(__SANITIZE_ADDRESS__)
constexpr int kScale = 10;  // the sanitizers run ~10x slower: a tenth of the cases
#else
constexpr int kScale = 1;
#endif

// --- references ---------------------------------------------------------------------------

struct Toi {
  bool hit = false;
  bool ill = false;  // grazing or a near miss: left out
  double t = 0;
};

// the first t in [0, max_t] where gap(t) <= tol, for a gap convex in t (the distance between
// a translating convex shape and a fixed convex one, or a signed point distance): golden
// section for the minimum, then bisection between 0 and it
template <class G>
Toi first_root(G&& gap, double max_t, double tol) {
  Toi r;
  if (gap(0.0) <= tol) return {true, false, 0};
  double a = 0, b = max_t;
  const double phi = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = b - phi * (b - a), x2 = a + phi * (b - a), f1 = gap(x1), f2 = gap(x2);
  for (int i = 0; i < 120 && b - a > 1e-13; ++i) {
    if (f1 <= tol || f2 <= tol) break;  // found a point inside: enough for the bisection
    if (f1 < f2)
      b = x2, x2 = x1, f2 = f1, x1 = b - phi * (b - a), f1 = gap(x1);
    else
      a = x1, x1 = x2, f1 = f2, x2 = a + phi * (b - a), f2 = gap(x2);
  }
  double hi = f1 <= tol ? x1 : x2;
  const double fmin = std::min(f1, f2);
  if (fmin > tol) {
    // no contact; within 1e-6 m it is a near miss
    r.ill = fmin < 1e-6;
    return r;
  }
  double lo = 0;
  for (int i = 0; i < 200 && hi - lo > 1e-14; ++i) {
    const double m = 0.5 * (lo + hi);
    (gap(m) <= tol ? hi : lo) = m;
  }
  r.hit = true;
  r.t = hi;
  // the approach speed: the gap's slope just before the contact
  const double back = std::min(1e-3, hi);
  r.ill = back > 0 && (gap(hi - back) - gap(hi)) / back < 1e-3;
  return r;
}

// the moving convex `a` (at its start) translated along unit d against one convex part `b`
Toi reference_part(ConvexProxy a, const Vec3& d, double max_t, const ConvexProxy& b) {
  const Vec3 start = a.pose.position;
  return first_root(
      [&](double t) {
        a.pose.position = start + t * d;
        return gjk_distance(a, b).distance;
      },
      max_t, QueryWorld::kCastTolerance);
}

// against a whole collider: a plane in closed form, otherwise the earliest of its parts
Toi reference_collider(const ConvexProxy& a, const Vec3& d, double max_t, const Collider& c) {
  if (c.shape.type == ShapeType::Plane) {
    const double gap = plane_gap(a, c.shape, c.end);
    const Vec3 n = c.end.rotation * glm::normalize(c.shape.normal);
    if (gap <= 0) return {true, false, 0};
    const double speed = -glm::dot(n, d);
    if (speed <= 0 || gap > speed * max_t) return {};
    return {true, speed < 1e-3, gap / speed};
  }
  Toi best;
  brute_parts(c.shape, c.end, [&](const ConvexProxy& b) {
    const Toi r = reference_part(a, d, max_t, b);
    best.ill = best.ill || r.ill;
    if (r.hit && (!best.hit || r.t < best.t)) best.hit = true, best.t = r.t;
  });
  return best;
}

QueryWorld single(const Collider& c) {
  QueryWorld q;
  q.build(std::vector<Collider>{c});
  return q;
}

// a start outside the target at distance 2..8 m and a direction towards a point near it
Ray aimed_path(std::mt19937_64& rng, const Vec3& target, double spread) {
  std::uniform_real_distribution<double> dist(2, 8), off(-spread, spread), len(0, 12);
  const Vec3 o = target + dist(rng) * random_unit(rng);
  const Vec3 aim = target + Vec3(off(rng), off(rng), off(rng));
  return {o, glm::normalize(aim - o), len(rng)};
}

// --- sphere casts against single targets --------------------------------------------------

TEST(QueryCast, SphereCastEqualsClosedForms) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> size(0.2, 1.5), off(-3, 3);
  int hits[4] = {0, 0, 0, 0}, skipped = 0, total = 0;
  for (int k = 0; k < 20000 / kScale; ++k) {
    const int kind = k % 4;
    const Pose p{Vec3(off(rng), off(rng), off(rng)), random_rotation(rng)};
    ColliderShape s;
    switch (kind) {
      case 0: s = ColliderShape::sphere(size(rng)); break;
      case 1: s = ColliderShape::plane(random_unit(rng), off(rng)); break;
      case 2: s = ColliderShape::box(Vec3(size(rng), size(rng), size(rng))); break;
      default: s = ColliderShape::capsule(size(rng), size(rng));
    }
    Collider c;
    c.shape = s;
    c.begin = c.end = p;
    const QueryWorld q = single(c);
    const double r = 0.5 * size(rng);
    const Ray path = aimed_path(rng, p.position, 2.5);
    const ShapeCastHit h = q.sphere_cast(path, r);
    // the reference
    Toi ref;
    if (kind == 0) {
      // |o + t d - c| = R + r
      const Vec3 m = path.origin - p.position;
      const double b = glm::dot(m, path.direction), cc = glm::dot(m, m) - (s.radius + r) * (s.radius + r);
      const double disc = b * b - cc;
      if (cc <= 0) ref = {true, false, 0};
      else if (disc >= 0 && -b - std::sqrt(disc) >= 0 && -b - std::sqrt(disc) <= path.max_distance)
        ref = {true, false, -b - std::sqrt(disc)};
      ref.ill = cc > 0 && std::abs(disc) < 1e-6;
    } else if (kind == 1) {
      // n . (o + t d) = offset + r
      const Vec3 n = p.rotation * s.normal;
      const double off0 = s.offset + glm::dot(n, p.position);
      const double gap = glm::dot(n, path.origin) - off0 - r, speed = -glm::dot(n, path.direction);
      if (gap <= 0) ref = {true, false, 0};
      else if (speed > 0 && gap <= speed * path.max_distance) ref = {true, speed < 1e-3, gap / speed};
    } else {
      // the first root of the exact signed point distance minus r
      ref = first_root([&](double t) { return point_distance(s, p, path.origin + t * path.direction).distance - r; },
                       path.max_distance, 0.0);
    }
    ++total;
    if (ref.ill) {
      ++skipped;
      continue;
    }
    ASSERT_EQ(h.hit, ref.hit) << "case " << k << " kind " << kind;
    if (!h.hit) continue;
    ++hits[kind];
    ASSERT_NEAR(h.distance, ref.t, 1e-9) << "case " << k << " kind " << kind;
    EXPECT_NEAR(h.fraction, h.distance / path.max_distance, 1e-15);
    if (h.distance == 0) continue;
    // the contact: on the target's surface, r from the centre, along the normal
    const Vec3 centre = path.origin + h.distance * path.direction;
    EXPECT_NEAR(point_distance(s, p, h.point).distance, 0, 1e-9);
    EXPECT_NEAR(glm::length(centre - h.point), r, 1e-9);
    EXPECT_NEAR(glm::length(centre - r * h.normal - h.point), 0, 1e-9);
    EXPECT_LE(glm::dot(h.normal, path.direction), 1e-12);
  }
  for (int kind = 0; kind < 4; ++kind) EXPECT_GT(hits[kind], 1000 / kScale) << kind;
  EXPECT_LT(skipped, total / 100);
}

TEST(QueryCast, RoundedBoxFaceEdgeAndCorner) {
  // a unit-half-extent box at the origin, a sphere of 0.5 falling along -y
  const QueryWorld q = single(Collider::box(Vec3(0.0), Vec3(1)));
  const Vec3 down(0, -1, 0);
  // face: the centre stops 0.5 above y = 1
  ShapeCastHit h = q.sphere_cast({Vec3(0, 5, 0), down, 10}, 0.5);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 3.5, 1e-12);
  EXPECT_NEAR(glm::length(h.normal - Vec3(0, 1, 0)), 0, 1e-15);
  // edge x = 1, y = 1 at x offset 0.3: (y - 1)^2 = 0.25 - 0.09
  h = q.sphere_cast({Vec3(1.3, 5, 0), down, 10}, 0.5);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 4 - 0.4, 1e-12);
  EXPECT_NEAR(glm::length(h.point - Vec3(1, 1, 0)), 0, 1e-12);
  EXPECT_NEAR(glm::length(h.normal - glm::normalize(Vec3(0.3, 0.4, 0))), 0, 1e-12);
  // corner (1, 1, 1) at offsets 0.2, 0.2: (y - 1)^2 = 0.25 - 0.08
  h = q.sphere_cast({Vec3(1.2, 5, 1.2), down, 10}, 0.5);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 4 - std::sqrt(0.17), 1e-12);
  EXPECT_NEAR(glm::length(h.point - Vec3(1)), 0, 1e-12);
  // past the corner's rounding (0.36^2 + 0.36^2 > 0.25): a miss, though the grown box is hit
  EXPECT_FALSE(q.sphere_cast({Vec3(1.36, 5, 1.36), down, 10}, 0.5).hit);
  // starting within r of the box: distance 0, normal -direction
  h = q.sphere_cast({Vec3(0, 1.4, 0), down, 10}, 0.5);
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.distance, 0);
  EXPECT_EQ(h.normal, -down);
  // too short to reach
  EXPECT_FALSE(q.sphere_cast({Vec3(0, 5, 0), down, 3.49}, 0.5).hit);
}

// --- convex casts ---------------------------------------------------------------------------

TEST(QueryCast, ConvexCastsEqualBisectionOnGjkDistance) {
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> size(0.2, 1.2), off(-2, 2);
  const IcoSphere ico = icosphere(1, 1.0);
  const auto mesh = TriangleMesh::build(ico.vertices, ico.triangles);
  int hits = 0, skipped = 0, total = 0, steps_hit[3] = {0, 0, 0};
  for (int k = 0; k < 6000 / kScale; ++k) {
    // a target of each kind
    Collider c;
    switch (k % 6) {
      case 0: c.shape = ColliderShape::sphere(size(rng)); break;
      case 1: c.shape = ColliderShape::box(Vec3(size(rng), size(rng), size(rng))); break;
      case 2: c.shape = ColliderShape::capsule(size(rng), size(rng)); break;
      case 3: c.shape = ColliderShape::convex(random_hull(rng, 1.5)); break;
      case 4: c.shape = ColliderShape::triangles(mesh); break;
      default: c.shape = ColliderShape::plane(random_unit(rng), off(rng));
    }
    c.begin = c.end = {Vec3(off(rng), off(rng), off(rng)), random_rotation(rng)};
    const QueryWorld q = single(c);
    // a moving box, capsule or hull
    ColliderShape m;
    const int mk = (k / 6) % 3;
    if (mk == 0) m = ColliderShape::box(Vec3(size(rng), size(rng), size(rng)));
    else if (mk == 1) m = ColliderShape::capsule(size(rng), 0.5 * size(rng));
    else m = ColliderShape::convex(random_hull(rng, 1.0));
    const Ray path = aimed_path(rng, c.end.position, 2.0);
    const Pose start{path.origin, random_rotation(rng)};
    const ShapeCastHit h = q.shape_cast(m, start, path.direction, path.max_distance + 4);
    const Toi ref = reference_collider(ConvexProxy::of(m, start), path.direction, path.max_distance + 4, c);
    ++total;
    if (ref.ill) {
      ++skipped;
      continue;
    }
    ASSERT_EQ(h.hit, ref.hit) << "case " << k;
    if (!h.hit) continue;
    ++hits;
    ++steps_hit[mk];
    ASSERT_NEAR(h.distance, ref.t, 1e-6) << "case " << k;
    if (h.distance == 0) continue;
    // the contact point is on the target; the normal faces the moving shape
    EXPECT_NEAR(point_distance(c.shape, c.end, h.point).distance, 0, 1e-6) << "case " << k;
    EXPECT_LE(glm::dot(h.normal, path.direction), 1e-9) << "case " << k;
    EXPECT_NEAR(glm::length(h.normal), 1, 1e-12);
  }
  EXPECT_GT(hits, total / 4);
  for (int n : steps_hit) EXPECT_GT(n, 300 / kScale);
  EXPECT_LT(skipped, total / 20);
}

TEST(QueryCast, WorldCastsEqualBruteForce) {
  // sphere, box, capsule and hull casts through a random world of every shape type: the
  // first collider and its time of impact equal the brute-force reference over every collider
  QueryScene s = make_query_scene(120, 12, 23);
  std::mt19937_64 rng(24);
  std::uniform_real_distribution<double> pos(-1, s.side + 1), size(0.1, 0.6), len(0, 10);
  const QueryFilter filters[3] = {{}, {.layer = 1, .mask = 5}, {.ignore_owner = 3}};
  int hits = 0, skipped = 0, total = 0, filtered = 0;
  for (int k = 0; k < 1200 / kScale; ++k) {
    ColliderShape m;
    switch (k % 4) {
      case 0: m = ColliderShape::sphere(size(rng)); break;
      case 1: m = ColliderShape::box(Vec3(size(rng), size(rng), size(rng))); break;
      case 2: m = ColliderShape::capsule(size(rng), size(rng)); break;
      default: m = ColliderShape::convex(random_hull(rng, 0.6));
    }
    const Pose start{Vec3(pos(rng), pos(rng), pos(rng)), random_rotation(rng)};
    const Vec3 d = random_unit(rng);
    const double max_t = len(rng);
    const QueryFilter& f = filters[k % 3];
    const ShapeCastHit h = m.type == ShapeType::Sphere ? s.world.sphere_cast({start.position, d, max_t}, m.radius, f)
                                                        : s.world.shape_cast(m, start, d, max_t, f);
    // brute force: the earliest accepted collider (skipping what the swept bounds rule out)
    const ConvexProxy a = ConvexProxy::of(m, start);
    const Aabb b0 = bounds(m, start), swept = b0.merged({b0.lo + max_t * d, b0.hi + max_t * d});
    Toi best, second;
    std::uint32_t best_i = 0;
    bool ill = false;
    for (std::size_t i = 0; i < s.colliders.size(); ++i) {
      if (!s.world.bounds(i).overlaps(swept)) continue;
      if (!brute_accepts(s, f, i)) {
        ++filtered;
        continue;
      }
      const Toi r = reference_collider(a, d, max_t, s.colliders[i]);
      ill = ill || r.ill;
      if (!r.hit) continue;
      if (!best.hit || r.t < best.t) second = best, best = r, best_i = std::uint32_t(i);
      else if (!second.hit || r.t < second.t) second = r;
    }
    ++total;
    if (ill) {
      ++skipped;
      continue;
    }
    ASSERT_EQ(h.hit, best.hit) << "cast " << k;
    if (!h.hit) continue;
    ++hits;
    ASSERT_NEAR(h.distance, best.t, 1e-6) << "cast " << k;
    // the collider, unless two are hit within the tolerance of each other
    if (!second.hit || second.t - best.t > 2e-6) {
      ASSERT_EQ(h.collider, best_i) << "cast " << k;
    }
    EXPECT_EQ(h.owner, s.owners[h.collider]);
  }
  EXPECT_GT(hits, total / 4);
  EXPECT_GT(filtered, 100 / kScale);
  EXPECT_LT(skipped, total / 20);
}

}  // namespace
