// collide(): closed forms for sphere and capsule pairs, box stacking manifolds and their
// feature ids, the speculative margin, SAT against GJK/EPA, determinism and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <limits>
#include <random>
#include <set>

#include "error_of.h"
#include "narrow_reference.h"
#include "pba/collide/narrow_phase.h"

namespace {

using namespace pba;
using namespace pba::test_support;

ColliderShape sphere(double r) {
  ColliderShape s;
  s.type = ShapeType::Sphere;
  s.radius = r;
  return s;
}
ColliderShape capsule(double hh, double r) {
  ColliderShape s;
  s.type = ShapeType::Capsule;
  s.half_height = hh;
  s.radius = r;
  return s;
}
ColliderShape box(const Vec3& h) {
  ColliderShape s;
  s.type = ShapeType::Box;
  s.half_extents = h;
  return s;
}
ColliderShape plane(const Vec3& n, double offset) {
  ColliderShape s;
  s.type = ShapeType::Plane;
  s.normal = n;
  s.offset = offset;
  return s;
}
Pose at(const Vec3& p, const Quat& q = Quat(1, 0, 0, 0)) { return {p, q}; }
Quat about(const Vec3& axis, double angle) { return glm::angleAxis(angle, glm::normalize(axis)); }

// closed forms: the values are sums and differences of exactly representable lengths, so
// 1e-12 m leaves ~1e4 ulps of room at metre scale
constexpr double kClosed = 1e-12;

TEST(ClosedForm, SphereSphere) {
  const Manifold m = collide(sphere(0.5), at(Vec3(0, 0, 0)), sphere(0.25), at(Vec3(0.3, 0.4, 0)));
  ASSERT_EQ(m.count, 1);
  EXPECT_NEAR(glm::length(m.normal - Vec3(0.6, 0.8, 0)), 0.0, kClosed);
  EXPECT_NEAR(m.points[0].depth, 0.75 - 0.5, kClosed);
  EXPECT_NEAR(glm::length(m.points[0].point_a - Vec3(0.3, 0.4, 0)), 0.0, kClosed);       // 0.5 along n
  EXPECT_NEAR(glm::length(m.points[0].point_b - Vec3(0.15, 0.2, 0)), 0.0, kClosed);      // 0.25 back
  EXPECT_NEAR(glm::dot(m.points[0].point_a - m.points[0].point_b, m.normal), m.points[0].depth, kClosed);
}

TEST(ClosedForm, SphereCapsuleAndReversedOrder) {
  // sphere beside the capsule's core at height 0.2: distance 0.6 to the axis
  const Pose pc = at(Vec3(1, 0, 0), about(Vec3(0, 0, 1), kPi / 2));  // axis along -x ... +x
  const Manifold m = collide(sphere(0.3), at(Vec3(1.2, 0.6, 0)), capsule(0.5, 0.4), pc);
  ASSERT_EQ(m.count, 1);
  EXPECT_NEAR(m.points[0].depth, 0.7 - 0.6, kClosed);
  EXPECT_NEAR(glm::length(m.normal - Vec3(0, -1, 0)), 0.0, kClosed);
  const Manifold r = collide(capsule(0.5, 0.4), pc, sphere(0.3), at(Vec3(1.2, 0.6, 0)));
  ASSERT_EQ(r.count, 1);
  EXPECT_NEAR(glm::length(r.normal - Vec3(0, 1, 0)), 0.0, kClosed);
  EXPECT_NEAR(r.points[0].depth, 0.1, kClosed);
  EXPECT_NEAR(glm::length(r.points[0].point_a - m.points[0].point_b), 0.0, kClosed);
  // beyond the core's end the closest core point is the end cap's centre
  const Manifold e = collide(sphere(0.3), at(Vec3(2.0, 0.0, 0)), capsule(0.5, 0.4), pc);
  ASSERT_EQ(e.count, 1);
  EXPECT_NEAR(e.points[0].depth, 0.7 - 0.5, kClosed);
}

TEST(ClosedForm, CapsuleCapsuleCrossedAndParallel) {
  // crossed axes (x and z) 0.5 apart in y: one point, depth r1 + r2 - 0.5
  const Pose px = at(Vec3(0, 0, 0), about(Vec3(0, 0, 1), kPi / 2));
  const Pose pz = at(Vec3(0.1, 0.5, -0.2), about(Vec3(1, 0, 0), kPi / 2));
  const Manifold c = collide(capsule(1, 0.3), px, capsule(1, 0.25), pz);
  ASSERT_EQ(c.count, 1);
  EXPECT_NEAR(c.points[0].depth, 0.05, kClosed);
  EXPECT_NEAR(glm::length(c.normal - Vec3(0, 1, 0)), 0.0, kClosed);
  // parallel axes 0.5 apart, overlapping over x in [0.4, 1]: two points at the overlap's ends
  const Pose px2 = at(Vec3(1.4, 0.5, 0), about(Vec3(0, 0, 1), kPi / 2));
  const Manifold p = collide(capsule(1, 0.3), px, capsule(1, 0.25), px2);
  ASSERT_EQ(p.count, 2);
  EXPECT_NEAR(glm::length(p.normal - Vec3(0, 1, 0)), 0.0, kClosed);
  std::array<double, 2> xs{p.points[0].point_a.x, p.points[1].point_a.x};
  std::sort(xs.begin(), xs.end());
  EXPECT_NEAR(xs[0], 0.4, kClosed);
  EXPECT_NEAR(xs[1], 1.0, kClosed);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(p.points[std::size_t(i)].depth, 0.05, kClosed);
  EXPECT_NE(p.points[0].id, p.points[1].id);
}

TEST(ClosedForm, SphereBoxFaceEdgeAndInside) {
  const ColliderShape b = box(Vec3(1, 0.5, 2));
  const Pose pb = at(Vec3(0, 0, 0), about(Vec3(0, 1, 0), 0.3));
  // over the top face
  Manifold m = collide(sphere(0.2), at(Vec3(0.1, 0.6, 0.1)), b, pb);
  ASSERT_EQ(m.count, 1);
  EXPECT_NEAR(m.points[0].depth, 0.1, kClosed);
  EXPECT_NEAR(glm::length(m.normal - Vec3(0, -1, 0)), 0.0, kClosed);
  // beside an edge: the local point (1.1, 0.6, 0) is sqrt(0.02) from the edge
  const Vec3 c = apply(pb, Vec3(1.1, 0.6, 0));
  m = collide(sphere(0.2), at(c), b, pb);
  ASSERT_EQ(m.count, 1);
  EXPECT_NEAR(m.points[0].depth, 0.2 - std::sqrt(0.02), kClosed);
  // the centre inside, nearest the top face 0.1 m away: depth r + 0.1
  m = collide(sphere(0.2), at(apply(pb, Vec3(0.2, 0.4, 0.3))), b, pb);
  ASSERT_EQ(m.count, 1);
  EXPECT_NEAR(m.points[0].depth, 0.3, kClosed);
  EXPECT_NEAR(glm::length(m.normal - pb.rotation * Vec3(0, -1, 0)), 0.0, kClosed);
}

TEST(Plane, BoxOnPlaneGivesFourDeepestCornersAndSphereOne) {
  const ColliderShape ground = plane(Vec3(0, 1, 0), 0);
  // a box tilted about z: its two lowest corners at depths 0.01 + ..., all 4 bottom corners below margin
  const Manifold m = collide(box(Vec3(0.5, 0.5, 0.5)), at(Vec3(0, 0.49, 0)), ground, at(Vec3(0, 0, 0)));
  ASSERT_EQ(m.count, 4);
  EXPECT_NEAR(glm::length(m.normal - Vec3(0, -1, 0)), 0.0, kClosed);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[std::size_t(i)].depth, 0.01, kClosed);
  // the plane first: the normal flips, the depths stay
  const Manifold r = collide(ground, at(Vec3(0, 0, 0)), capsule(0.5, 0.2), at(Vec3(0, 0.15, 0), about(Vec3(0, 0, 1), kPi / 2)));
  ASSERT_EQ(r.count, 2);
  EXPECT_NEAR(glm::length(r.normal - Vec3(0, 1, 0)), 0.0, kClosed);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(r.points[std::size_t(i)].depth, 0.05, kClosed);
}

// A box's points on a plane are its corners turned by its rotation (apply()) and their depths
// below the plane, to the bit: convex_plane turns the eight corners two at a time in vector
// lanes, each lane doing the scalar turn's operations in its order. Random boxes, rotations and
// planes, straddling the plane within a margin that takes some of the corners: where at most
// four are taken the manifold is those corners in order, else three or four of them. A ball
// (made without the candidate list) has its lowest point, to the bit.
TEST(Plane, BoxCornersAndABallsLowestPointOnAPlaneToTheBit) {
  std::mt19937_64 rng(20261205);
  std::uniform_real_distribution<double> u(0, 1);
  auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  auto same = [&](const Vec3& x, const Vec3& y) {
    return bits(x.x) == bits(y.x) && bits(x.y) == bits(y.y) && bits(x.z) == bits(y.z);
  };
  NarrowPhaseSettings settings;
  settings.speculative_margin = 0.3;
  int fewer = 0, more = 0, balls = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 h(0.05 + u(rng), 0.05 + u(rng), 0.05 + u(rng));
    const Vec3 normal = glm::normalize(random_vec(rng, 1) + Vec3(0, 1e-3, 0));
    const ColliderShape ground = plane(normal, 2 * u(rng) - 1);
    const Pose pg = at(random_vec(rng, 2), random_rotation(rng));
    const Vec3 np = pg.rotation * normal;
    const double off = ground.offset + glm::dot(np, pg.position);
    // the box's centre over a point of the plane, within its half diagonal of it
    const double lift = (2 * u(rng) - 1) * glm::length(h);
    const Vec3 along = random_vec(rng, 1);
    const Pose pb = at(along - glm::dot(along, np) * np + (off + lift) * np, random_rotation(rng));
    // the reference: each corner (its core point: a box's radius is 0) and its depth, in corner order
    Vec3 a[8], b[8];
    double depth[8];
    int taken[8], n = 0;
    const std::array<Vec3, 8> corners = box_corners(h, pb);
    for (int i = 0; i < 8; ++i) {
      const Vec3 c = corners[std::size_t(i)] - 0.0 * np;
      const double d = off - glm::dot(np, c);
      if (d < -settings.speculative_margin) continue;
      a[n] = c, b[n] = c + d * np, depth[n] = d, taken[n++] = i;
    }
    for (const bool plane_first : {false, true}) {
      const Manifold m =
          plane_first ? collide(ground, pg, box(h), pb, settings) : collide(box(h), pb, ground, pg, settings);
      // (more than four: reduce() keeps the deepest, the farthest from it, the largest triangle
      // and the point adding most area, so three or four)
      if (n <= 4) ASSERT_EQ(m.count, n) << trial;
      else ASSERT_GE(m.count, 3) << trial;
      EXPECT_TRUE(same(m.normal, plane_first ? np : -np)) << trial;
      for (int k = 0; k < m.count; ++k) {
        const ContactPoint& p = m.points[std::size_t(k)];
        // the corner it is: in order when all are kept, else by its id
        int j = k;
        if (n > 4) j = int(std::find(taken, taken + n, int(p.id)) - taken);
        ASSERT_LT(j, n) << trial;
        EXPECT_EQ(p.id, std::uint32_t(taken[j])) << trial;
        EXPECT_TRUE(same(plane_first ? p.point_b : p.point_a, a[j])) << trial << " corner " << taken[j];
        EXPECT_TRUE(same(plane_first ? p.point_a : p.point_b, b[j])) << trial << " corner " << taken[j];
        EXPECT_EQ(bits(p.depth), bits(depth[j])) << trial;
      }
    }
    (n > 4 ? more : fewer) += n > 0;
    // a ball there: its lowest point (its centre less the radius along the plane's normal), alone
    const double radius = h.x;
    const Vec3 low = pb.position - radius * np;
    const double d = off - glm::dot(np, low);
    const Manifold m = collide(sphere(radius), pb, ground, pg, settings);
    ASSERT_EQ(m.count, d < -settings.speculative_margin ? 0 : 1) << trial;
    EXPECT_TRUE(same(m.normal, -np)) << trial;
    if (m.count == 0) continue;
    ++balls;
    EXPECT_TRUE(same(m.points[0].point_a, low)) << trial;
    EXPECT_TRUE(same(m.points[0].point_b, low + d * np)) << trial;
    EXPECT_EQ(bits(m.points[0].depth), bits(d)) << trial;
    EXPECT_EQ(m.points[0].id, 0u) << trial;
  }
  // both kinds were met, many times
  EXPECT_GT(fewer, 300);
  EXPECT_GT(more, 300);
  EXPECT_GT(balls, 300);
}

TEST(Margin, SeparatedBeyondTheMarginGivesNothingWithinItNegativeDepths) {
  NarrowPhaseSettings s;
  s.speculative_margin = 0.02;
  for (const ConvexMethod method : {ConvexMethod::Sat, ConvexMethod::GjkEpa}) {
    s.method = method;
    const ColliderShape b = box(Vec3(0.5, 0.5, 0.5));
    // 0.01 m apart: four speculative points at depth -0.01
    Manifold m = collide(b, at(Vec3(0, 0, 0)), b, at(Vec3(0.3, 1.01, 0.1)), s);
    ASSERT_EQ(m.count, 4) << int(method);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[std::size_t(i)].depth, -0.01, 1e-9);
    EXPECT_NEAR(glm::length(m.normal - Vec3(0, 1, 0)), 0.0, 1e-9);
    // 0.03 m apart: nothing
    m = collide(b, at(Vec3(0, 0, 0)), b, at(Vec3(0.3, 1.03, 0.1)), s);
    EXPECT_EQ(m.count, 0);
  }
  Manifold m = collide(sphere(0.5), at(Vec3(0, 0, 0)), sphere(0.5), at(Vec3(1.01, 0, 0)), s);
  ASSERT_EQ(m.count, 1);
  EXPECT_NEAR(m.points[0].depth, -0.01, kClosed);
  EXPECT_EQ(collide(sphere(0.5), at(Vec3(0, 0, 0)), sphere(0.5), at(Vec3(1.03, 0, 0)), s).count, 0);
  m = collide(capsule(0.5, 0.2), at(Vec3(0, 0.21, 0), about(Vec3(1, 0, 0), kPi / 2)), plane(Vec3(0, 1, 0), 0),
              at(Vec3(0, 0, 0)), s);
  ASSERT_EQ(m.count, 2);
  EXPECT_NEAR(m.points[0].depth, -0.01, kClosed);
}

// Two boxes face to face, apart by more than a few centimetres but within a large margin (the
// rigid pipeline's margin is how far the pair can close in a step: 19 cm for a body falling
// at 11.6 m/s): the manifold is the faces' four points at the gap, by SAT and by GJK, boxes
// and hulls alike, turned about the normal or not. SAT chose an edge pair whose axis is the
// faces' normal (e_x x e_z of two aligned boxes) once the gap passed 2.5 cm, its tolerance
// being 0.9 of a positive separation, and gave one point: a 2 m cube falling on another at
// 11.6 m/s then turned at 5.5 rad/s on that corner and sank 10 cm.
TEST(Margin, FacesApartWithinALargeMarginGiveFourPointsAtTheGap) {
  const Vec3 cube_corners[8] = {{-0.5, -0.5, -0.5}, {0.5, -0.5, -0.5}, {-0.5, 0.5, -0.5}, {0.5, 0.5, -0.5},
                                {-0.5, -0.5, 0.5},  {0.5, -0.5, 0.5},  {-0.5, 0.5, 0.5},  {0.5, 0.5, 0.5}};
  const ColliderShape shapes[2] = {box(Vec3(0.5)), ColliderShape::convex(ConvexHull::build(cube_corners, "cube"))};
  for (const ConvexMethod method : {ConvexMethod::Sat, ConvexMethod::GjkEpa})
  for (const ColliderShape& shape : shapes)
  for (const double gap : {0.01, 0.03, 0.05, 0.3, 1.5})
  for (const double turn : {0.0, 0.3}) {
    const NarrowPhaseSettings s{.speculative_margin = 2.0, .method = method};
    const Manifold m = collide(shape, at(Vec3(0, 0, 0)), shape, at(Vec3(0.1, 1 + gap, -0.05), about(Vec3(0, 1, 0), turn)), s);
    ASSERT_EQ(m.count, 4) << int(method) << " " << to_string(shape.type) << " gap " << gap << " turn " << turn;
    EXPECT_NEAR(glm::length(m.normal - Vec3(0, 1, 0)), 0.0, 1e-9);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[std::size_t(i)].depth, -gap, 1e-9) << gap;
  }
}

// A 1 m box resting 1 cm deep on a 4 m slab, turned 0.3 rad about the vertical: its bottom
// face lies inside the slab's top face, so the manifold is its four bottom corners.
struct Resting {
  ColliderShape ground = box(Vec3(2, 0.5, 2));
  ColliderShape cube = box(Vec3(0.5, 0.5, 0.5));
  Pose pg = at(Vec3(0, 0, 0));
  Pose pc = at(Vec3(0.2, 0.99, -0.1), about(Vec3(0, 1, 0), 0.3));
};

TEST(BoxBox, RestingBoxHasFourPointsWhoseIdsPersistUnderJitter) {
  const Resting s;
  for (const ConvexMethod method : {ConvexMethod::Sat, ConvexMethod::GjkEpa}) {
    NarrowPhaseSettings set;
    set.method = method;
    const Manifold m = collide(s.ground, s.pg, s.cube, s.pc, set);
    ASSERT_EQ(m.count, 4);
    EXPECT_NEAR(glm::length(m.normal - Vec3(0, 1, 0)), 0.0, 1e-12);
    std::set<std::uint32_t> ids;
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(m.points[std::size_t(i)].depth, 0.01, 1e-12);
      ids.insert(m.points[std::size_t(i)].id);
    }
    ASSERT_EQ(ids.size(), 4u);
    // jitter of 1e-4 m and 1e-3 rad: the same four features touch
    std::mt19937_64 rng(1);
    NarrowPhaseCache cache;
    for (int k = 0; k < 200; ++k) {
      const Vec3 axis = random_vec(rng, 1.0);
      const Pose pj{s.pc.position + random_vec(rng, 1e-4),
                    glm::normalize(about(axis, 1e-3 * std::uniform_real_distribution<double>(-1, 1)(rng)) * s.pc.rotation)};
      const Manifold j = collide(s.ground, s.pg, s.cube, pj, set, &cache);
      ASSERT_EQ(j.count, 4) << k;
      std::set<std::uint32_t> jid;
      for (int i = 0; i < 4; ++i) jid.insert(j.points[std::size_t(i)].id);
      EXPECT_EQ(jid, ids) << "jitter " << k << " method " << int(method);
    }
  }
}

TEST(BoxBox, ClippedCornersOfOverlappingFacesHaveStableIds) {
  // two equal boxes, one shifted by half a width and turned 0.2 rad: the contact polygon
  // mixes incident corners, edge/side-plane crossings and reference corners
  const ColliderShape b = box(Vec3(0.5, 0.5, 0.5));
  const Pose pa = at(Vec3(0, 0, 0));
  const Pose pb = at(Vec3(0.5, 0.995, 0.3), about(Vec3(0, 1, 0), 0.2));
  const Manifold m = collide(b, pa, b, pb);
  ASSERT_EQ(m.count, 4);
  std::set<std::uint32_t> ids;
  for (int i = 0; i < 4; ++i) ids.insert(m.points[std::size_t(i)].id);
  ASSERT_EQ(ids.size(), 4u);
  // every point is inside both boxes' footprints and at the common depth 0.005
  for (int i = 0; i < 4; ++i) {
    const ContactPoint& p = m.points[std::size_t(i)];
    EXPECT_NEAR(p.depth, 0.005, 1e-12);
    EXPECT_LE(point_box_distance(p.point_a, Vec3(0.5), pa), 1e-12);
    EXPECT_LE(point_box_distance(p.point_b, Vec3(0.5), pb), 1e-12);
  }
  std::mt19937_64 rng(2);
  for (int k = 0; k < 200; ++k) {
    const Pose pj{pb.position + random_vec(rng, 1e-4),
                  glm::normalize(about(random_vec(rng, 1.0), 1e-3 * std::uniform_real_distribution<double>(-1, 1)(rng)) *
                                 pb.rotation)};
    const Manifold j = collide(b, pa, b, pj);
    ASSERT_EQ(j.count, 4);
    std::set<std::uint32_t> jid;
    for (int i = 0; i < 4; ++i) jid.insert(j.points[std::size_t(i)].id);
    EXPECT_EQ(jid, ids) << k;
  }
}

TEST(BoxBox, SatAndGjkEpaAgreeOnRandomOverlaps) {
  // the deepest point's depth is the penetration depth in both methods; the normals agree
  // where the best axis is unique
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> size(0.2, 1.0);
  NarrowPhaseSettings sat, gjk;
  gjk.method = ConvexMethod::GjkEpa;
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Vec3 ha(size(rng), size(rng), size(rng)), hb(size(rng), size(rng), size(rng));
    const Pose pa{random_vec(rng, 0.2), random_rotation(rng)}, pb{random_vec(rng, 1.2), random_rotation(rng)};
    Vec3 n(0.0);
    double second = 0;
    const double depth = box_box_sat_depth(ha, pa, hb, pb, n, second);
    if (depth <= 1e-6 || second - depth < 1e-3) continue;
    ++checked;
    const Manifold ms = collide(box(ha), pa, box(hb), pb, sat);
    const Manifold mg = collide(box(ha), pa, box(hb), pb, gjk);
    ASSERT_GE(ms.count, 1);
    ASSERT_GE(mg.count, 1);
    EXPECT_NEAR(glm::length(mg.normal - n), 0.0, 1e-7) << trial;
    // SAT prefers a face within 2% + 2.5 mm of the best axis (Gregorius's hysteresis)
    if (glm::length(ms.normal - n) < 1e-9) {
      double deepest = -INFINITY;
      for (int i = 0; i < ms.count; ++i) deepest = std::max(deepest, ms.points[std::size_t(i)].depth);
      EXPECT_NEAR(deepest, depth, 1e-9) << trial;
    }
    double deepest = -INFINITY;
    for (int i = 0; i < mg.count; ++i) deepest = std::max(deepest, mg.points[std::size_t(i)].depth);
    EXPECT_NEAR(deepest, depth, 1e-8) << trial;
  }
  EXPECT_GT(checked, 100);
}

TEST(BoxBox, CachedFeatureGivesTheSameManifold) {
  std::mt19937_64 rng(4);
  NarrowPhaseCache cache;
  const ColliderShape a = box(Vec3(0.5, 0.3, 0.4)), b = box(Vec3(0.2, 0.6, 0.3));
  Pose pa = at(Vec3(0, 0, 0)), pb = at(Vec3(1.5, 0, 0));
  for (int k = 0; k < 500; ++k) {
    // a slow random walk through separated and touching poses
    pb.position += random_vec(rng, 0.02);
    pb.position = glm::clamp(pb.position, Vec3(-1.2), Vec3(1.2));
    pb.rotation = glm::normalize(about(random_vec(rng, 1.0), 0.05) * pb.rotation);
    const Manifold c = collide(a, pa, b, pb, {}, &cache);
    const Manifold u = collide(a, pa, b, pb);
    ASSERT_EQ(c.count, u.count) << k;
    for (int i = 0; i < c.count; ++i) EXPECT_EQ(c.points[std::size_t(i)].id, u.points[std::size_t(i)].id);
  }
}

TEST(Collide, DeterministicBits) {
  auto run = [] {
    std::mt19937_64 rng(12);
    std::uint64_t h = 0xcbf29ce484222325ULL;
    const ColliderShape shapes[] = {sphere(0.4), capsule(0.5, 0.2), box(Vec3(0.5, 0.3, 0.2))};
    for (int k = 0; k < 300; ++k)
      for (const auto& a : shapes)
        for (const auto& b : shapes)
          for (const ConvexMethod mth : {ConvexMethod::Sat, ConvexMethod::GjkEpa}) {
            NarrowPhaseSettings s;
            s.method = mth;
            const Manifold m = collide(a, {random_vec(rng, 0.3), random_rotation(rng)}, b,
                                       {random_vec(rng, 1.0), random_rotation(rng)}, s);
            h = hash_bytes(&m.count, sizeof m.count, h);
            for (int i = 0; i < m.count; ++i) h = hash_bytes(&m.points[std::size_t(i)], sizeof(ContactPoint), h);
            h = hash_bytes(&m.normal, sizeof m.normal, h);
          }
    return h;
  };
  EXPECT_EQ(run(), run());
}

TEST(Collide, BadInputThrowsNamingTheValue) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const ColliderShape b = box(Vec3(0.5));
  EXPECT_NE(error_of([&] { collide(b, at(Vec3(nan, 0, 0)), b, at(Vec3(0))); }).find("pose_a.position"),
            std::string::npos);
  EXPECT_NE(error_of([&] { collide(b, at(Vec3(0)), b, {Vec3(0), Quat(2, 0, 0, 0)}); }).find("pose_b.rotation"),
            std::string::npos);
  EXPECT_NE(error_of([&] { collide(b, at(Vec3(0)), b, {Vec3(0), Quat(nan, 0, 0, 0)}); }).find("pose_b.rotation"),
            std::string::npos);
  EXPECT_NE(error_of([&] { collide(sphere(-1), at(Vec3(0)), b, at(Vec3(0))); }).find("shape_a.radius"),
            std::string::npos);
  NarrowPhaseSettings s;
  s.speculative_margin = -1;
  EXPECT_NE(error_of([&] { collide(b, at(Vec3(0)), b, at(Vec3(0)), s); }).find("speculative_margin"),
            std::string::npos);
  EXPECT_NE(error_of([&] { collide(plane(Vec3(0, 1, 0), 0), at(Vec3(0)), plane(Vec3(0, 1, 0), 0), at(Vec3(0))); })
                .find("plane-plane"),
            std::string::npos);
}

// Planes take the quick input check too (on the normal's squared length): a normal 2e-6 off
// unit length, or a non-finite one or offset, still fails it and is named, as a shape A or B
// with a sphere or a box; one 1e-7 off passes, as the full check (1e-6) lets it
TEST(Collide, BadPlanesThrowNamingTheValue) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const ColliderShape ball = sphere(0.5), b = box(Vec3(0.5));
  const ColliderShape bad[] = {plane(Vec3(0, 1 + 2e-6, 0), 0), plane(Vec3(0, 1 - 2e-6, 0), 0), plane(Vec3(0, 2, 0), 0),
                               plane(Vec3(nan, 1, 0), 0), plane(Vec3(0, 1, 0), inf), plane(Vec3(0, 1, 0), nan)};
  for (const ColliderShape& p : bad)
    for (const ColliderShape* other : {&ball, &b}) {
      EXPECT_NE(error_of([&] { collide(p, at(Vec3(0)), *other, at(Vec3(0, 0.4, 0))); }).find("shape_a.normal/offset"),
                std::string::npos);
      EXPECT_NE(error_of([&] { collide(*other, at(Vec3(0, 0.4, 0)), p, at(Vec3(0))); }).find("shape_b.normal/offset"),
                std::string::npos);
    }
  const Manifold m = collide(ball, at(Vec3(0, 0.4, 0)), plane(Vec3(0, 1 + 1e-7, 0), 0), at(Vec3(0)));
  EXPECT_EQ(m.count, 1);
}

}  // namespace
