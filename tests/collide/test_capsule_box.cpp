// The capsule-box pair's closed form (segment_box_closest): against the brute-force
// feature enumeration and its own separating-plane certificate over random segments in every
// region, exact cases, and collide()'s capsule-box manifolds against GJK and EPA.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "narrow_reference.h"
#include "pba/collide/narrow_phase.h"

namespace {

using namespace pba;
using namespace pba::test_support;

ConvexProxy proxy(const ColliderShape& s, const Pose& p) { return ConvexProxy::of(s, p); }
Quat about(const Vec3& axis, double angle) { return glm::angleAxis(angle, glm::normalize(axis)); }

// Rounding room: the answers are a few dozen operations on coordinates of size L (the
// segment's and the box's reach), each off by half an ulp of L (1.1e-16 L), so 1e-12 L leaves
// some 9,000 ulps: room for the operations' errors and the reference's, none for a wrong piece.
double room(const Vec3& p, const Vec3& q, const Vec3& h) {
  const double l = std::max({glm::length(p), glm::length(q), glm::length(h), 1e-3});
  return 1e-12 * l;
}

// A segment in the box's frame drawn from one of seven families, so every region is met: a
// general segment, one parallel to a face or to an edge (coordinates of the direction exactly
// 0), one with an end inside the slabs of two axes, a long one crossing several slabs, a
// point (a zero-length core: a sphere), and one passing near a corner or an edge.
void random_segment(std::mt19937_64& rng, int family, const Vec3& h, Vec3& p, Vec3& q) {
  std::uniform_real_distribution<double> u(-1, 1);
  auto around = [&](double s) { return Vec3(s * h.x * u(rng), s * h.y * u(rng), s * h.z * u(rng)); };
  switch (family) {
    case 0: p = around(3), q = around(3); break;
    case 1: {  // parallel to a face (one coordinate of the direction 0) or an edge (two)
      p = around(3);
      q = p + around(2);
      const int k = int(rng() % 3);
      q[k] = p[k];
      if (rng() % 2) q[(k + 1) % 3] = p[(k + 1) % 3];
      break;
    }
    case 2: {  // an end inside two slabs, outside the third
      const int k = int(rng() % 3);
      p = around(0.99);
      p[k] = (u(rng) > 0 ? 1 : -1) * h[k] * (1.01 + std::abs(u(rng)));
      q = around(3);
      break;
    }
    case 3: p = around(6), q = -p + around(1.5); break;  // long, across the box's slabs
    case 4: p = q = around(3); break;                     // a point
    default: {  // near a corner or along an edge, just outside
      Vec3 c(h.x * (u(rng) > 0 ? 1 : -1), h.y * (u(rng) > 0 ? 1 : -1), h.z * (u(rng) > 0 ? 1 : -1));
      if (rng() % 2) c[int(rng() % 3)] *= u(rng);
      const Vec3 out = glm::normalize(c) * (0.05 + 0.3 * std::abs(u(rng)));
      const Vec3 along = around(1);
      p = c + out - along, q = c + out + along;
      break;
    }
  }
}

// segment_box_closest against the feature enumeration (narrow_reference.h) to rounding, and
// against its own certificate: its two points are a segment point and the box point nearest
// it (so the distance is attained), and the plane through the box point normal to their
// difference has the whole box on one side and both segment ends on the other, at least that
// distance apart (so no pair is closer). Every region is met: the box point on a face, an
// edge or a corner, the segment point at an end or inside.
TEST(SegmentBox, MatchesTheFeatureEnumerationAndItsCertificateEverywhere) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> size(0.05, 1.5);
  int met = 0, region[4] = {}, ends = 0, inner = 0;
  for (int trial = 0; trial < 7000; ++trial) {
    const Vec3 h(size(rng), size(rng), size(rng));
    Vec3 p, q;
    random_segment(rng, trial % 7, h, p, q);
    const SegmentBoxClosest c = segment_box_closest(p, q, h);
    const double tol = room(p, q, h);
    const double ref = segment_box_distance(p, q, h, Pose{});
    ASSERT_GE(c.t, 0.0);
    ASSERT_LE(c.t, 1.0);
    EXPECT_LE(glm::length(c.on_segment - (p + c.t * (q - p))), tol) << "trial " << trial;
    // (the two fields' definitions, as the header states them: what the checks below read)
    EXPECT_EQ(c.on_box, glm::clamp(c.on_segment, -h, h));
    const double dist = std::sqrt(c.distance2);
    EXPECT_EQ(c.distance2, glm::dot(c.on_segment - c.on_box, c.on_segment - c.on_box));
    EXPECT_NEAR(dist, ref, tol) << "trial " << trial << " family " << trial % 7;
    if (ref == 0) {
      ++met;
      continue;
    }
    if (dist <= tol) continue;
    const Vec3 n = (c.on_segment - c.on_box) / dist;
    const double box_reach = glm::dot(glm::abs(n), h);  // the box's support along n
    EXPECT_NEAR(glm::dot(n, c.on_box), box_reach, tol);
    EXPECT_GE(std::min(glm::dot(n, p), glm::dot(n, q)) - box_reach, dist - tol) << "trial " << trial;
    int clamped = 0;
    for (int k = 0; k < 3; ++k) clamped += std::abs(c.on_box[k]) == h[k] && c.on_box[k] != c.on_segment[k];
    ++region[clamped];
    ++(c.t == 0 || c.t == 1 ? ends : inner);
  }
  EXPECT_GT(met, 300);
  EXPECT_GT(region[1], 700);  // face
  EXPECT_GT(region[2], 800);  // edge
  EXPECT_GT(region[3], 1000);  // corner
  EXPECT_GT(ends, 800);
  EXPECT_GT(inner, 800);
}

TEST(SegmentBox, ExactCases) {
  const Vec3 h(1, 1, 1);
  // parallel to the +y face at height 0.25 over it: distance 0.25, the start's point
  SegmentBoxClosest c = segment_box_closest(Vec3(-0.5, 1.25, 0.25), Vec3(0.5, 1.25, 0.25), h);
  EXPECT_EQ(c.distance2, 0.0625);
  EXPECT_EQ(c.t, 0.0);
  EXPECT_EQ(c.on_box, Vec3(-0.5, 1, 0.25));
  // parallel to the x edge at (y, z) = (1.3, 1.4): distance 0.5 (0.3 and 0.4 to rounding)
  c = segment_box_closest(Vec3(-0.5, 1.3, 1.4), Vec3(0.5, 1.3, 1.4), h);
  EXPECT_NEAR(std::sqrt(c.distance2), 0.5, 1e-15);
  // across the x edge: the line y + z = 3 in the plane x = 0.2, nearest the edge at its middle
  // (1.5, 1.5), 1/sqrt(2) from the edge's point (0.2, 1, 1)
  c = segment_box_closest(Vec3(0.2, 3, 0), Vec3(0.2, 0, 3), h);
  EXPECT_NEAR(std::sqrt(c.distance2), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(c.t, 0.5, 1e-15);
  EXPECT_EQ(c.on_box, Vec3(0.2, 1, 1));
  // at a corner: the segment through (2, 2, 2) across the diagonal, sqrt(3) from (1, 1, 1)
  c = segment_box_closest(Vec3(3, 1, 2), Vec3(1, 3, 2), h);
  EXPECT_NEAR(std::sqrt(c.distance2), std::sqrt(3.0), 1e-15);
  EXPECT_NEAR(c.t, 0.5, 1e-15);
  EXPECT_EQ(c.on_box, Vec3(1, 1, 1));
  // a point (a sphere's centre): the clamp
  c = segment_box_closest(Vec3(1.5, 0.25, -2), Vec3(1.5, 0.25, -2), Vec3(1, 0.5, 1));
  EXPECT_EQ(c.on_box, Vec3(1, 0.25, -1));
  EXPECT_EQ(c.distance2, 0.25 + 1);
  // through the box: distance 0
  c = segment_box_closest(Vec3(-3, 0.5, 0.5), Vec3(3, -0.5, 0.2), h);
  EXPECT_EQ(c.distance2, 0.0);
  // the far end nearest: t = 1 and the end itself
  c = segment_box_closest(Vec3(5, 5, 5), Vec3(1.5, 0.5, 0), h);
  EXPECT_EQ(c.t, 1.0);
  EXPECT_EQ(c.on_segment, Vec3(1.5, 0.5, 0));
  EXPECT_EQ(c.distance2, 0.25);
  // parallel to the +y face from outside its x slab into it, the slope 0 from x = -1 to the
  // end: every point of x in [-1, 0.5] is 0.25 away, and the rule takes the first, t = 0.4
  // (a review found t = 1: the end's zero slope taken as "still falling")
  c = segment_box_closest(Vec3(-2, 1.25, 0.25), Vec3(0.5, 1.25, 0.25), h);
  EXPECT_EQ(c.distance2, 0.0625);
  EXPECT_NEAR(c.t, 0.4, 1e-15);
  EXPECT_NEAR(c.on_segment.x, -1.0, 1e-15);
  EXPECT_EQ(c.on_box.y, 1.0);
}

TEST(SegmentBox, BadInputIsNamed) {
  const Vec3 h(1, 1, 1), p(2, 0, 0), q(3, 0, 0);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] { segment_box_closest(Vec3(nan, 0, 0), q, h); }).find("segment_box_closest: p"),
            std::string::npos);
  EXPECT_NE(message([&] { segment_box_closest(p, Vec3(0, inf, 0), h); }).find("segment_box_closest: q"),
            std::string::npos);
  for (const Vec3 bad : {Vec3(-1, 1, 1), Vec3(1, 0, 1), Vec3(1, 1, nan), Vec3(inf, 1, 1)})
    EXPECT_NE(message([&] { segment_box_closest(p, q, bad); }).find("segment_box_closest: half_extents"),
              std::string::npos)
        << bad.x << " " << bad.y << " " << bad.z;
  EXPECT_EQ(segment_box_closest(p, q, h).distance2, 1.0);
}

// collide()'s capsule-box manifold over random poses (cores apart within a large margin, and
// overlapping): its normal is GJK's to GJK's own bound (GJK stops with its estimate v at most
// kTolerance longer than the distance d; v lies in the Minkowski difference, so it is within
// sqrt(|v|^2 - d^2) of the unique closest point and its direction within that over d), every
// point is no deeper than the radius less the core distance, a one-point manifold's depth is
// exactly that, the box first gives the flipped manifold, and overlapping cores give EPA's
// normal to the bit.
TEST(CapsuleBox, ManifoldsAgreeWithGjkAndEpa) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> size(0.05, 1.2);
  NarrowPhaseSettings wide;
  wide.speculative_margin = 5.0;
  int apart = 0, two = 0, overlapping = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const ColliderShape a = ColliderShape::capsule(size(rng), 0.5 * size(rng)),
                        b = ColliderShape::box(Vec3(size(rng), size(rng), size(rng)));
    // (a quarter of them near the box, most of those with the cores overlapping)
    const Pose pa{random_vec(rng, trial % 4 ? 2.5 : 0.5), random_rotation(rng)};
    const Pose pb{random_vec(rng, 0.5), random_rotation(rng)};
    const Manifold m = collide(a, pa, b, pb, wide);
    const Manifold f = collide(b, pb, a, pa, wide);
    ASSERT_EQ(f.count, m.count);
    EXPECT_EQ(f.normal, -m.normal);
    const Vec3 u = pa.rotation * Vec3(0, a.half_height, 0);
    const double core = segment_box_distance(pa.position - u, pa.position + u, b.half_extents, pb);
    const double tol = 1e-12 * (3 + glm::length(pa.position));
    if (core == 0) {
      const PenetrationResult e = epa_penetration(proxy(a, pa), proxy(b, pb));
      if (!e.ok) continue;
      ++overlapping;
      ASSERT_GE(m.count, 1);
      EXPECT_EQ(m.normal, e.normal) << "trial " << trial;
      continue;
    }
    if (core - a.radius > wide.speculative_margin) continue;
    ++apart;
    ASSERT_GE(m.count, 1) << "trial " << trial;
    const DistanceResult g = gjk_distance(proxy(a, pa), proxy(b, pb));
    ASSERT_FALSE(g.cores_overlap);
    const double bound = std::sqrt(std::max(0.0, g.core_distance * g.core_distance - core * core)) / core;
    EXPECT_LE(glm::length(m.normal - g.normal), bound + tol / core) << "trial " << trial;
    for (int i = 0; i < m.count; ++i) EXPECT_LE(m.points[std::size_t(i)].depth, a.radius - core + tol);
    if (m.count == 1) {
      EXPECT_NEAR(m.points[0].depth, a.radius - core, tol) << "trial " << trial;
    }
    two += m.count == 2;
  }
  EXPECT_GT(apart, 2000);
  EXPECT_GT(overlapping, 400);
  EXPECT_GT(two, 10);
}

// A capsule lying on a turned box's top face, level and tilted by about one degree: two points
// at its core's ends, the normal the face's (down from the capsule into the box), the depths
// the radius less each end's height over the face, the box's points on the face.
TEST(CapsuleBox, LyingOnAFaceGivesTwoPointsAtTheEnds) {
  const Vec3 h(1, 0.5, 0.8);
  const Pose pb{Vec3(0.3, -0.2, 1.1), about(Vec3(1, 2, 3), 0.7)};
  const double r = 0.2;
  // the core's ends in the box's frame: (-0.4, y0, 0.2) and (0.6, y1, 0.2)
  for (const auto& [y0, y1] : {std::pair{0.69, 0.69}, std::pair{0.68, 0.70}}) {
    const Vec3 e0(-0.4, y0, 0.2), e1(0.6, y1, 0.2);
    const Vec3 axis = e1 - e0;
    const double hh = 0.5 * glm::length(axis);
    const Quat local = about(Vec3(0, 0, 1), std::atan2(-axis.x, axis.y));  // +y onto the axis
    const Pose pa{apply(pb, 0.5 * (e0 + e1)), pb.rotation * local};
    const Manifold m = collide(ColliderShape::capsule(hh, r), pa, ColliderShape::box(h), pb);
    ASSERT_EQ(m.count, 2);
    EXPECT_NEAR(glm::length(m.normal - pb.rotation * Vec3(0, -1, 0)), 0.0, 1e-12);
    for (int i = 0; i < 2; ++i) {
      const ContactPoint& c = m.points[std::size_t(i)];
      const Vec3 lb = apply_inverse(pb, c.point_b);
      const bool first = lb.x < 0.1;
      const Vec3 end = first ? e0 : e1;
      EXPECT_NEAR(glm::length(lb - Vec3(end.x, h.y, end.z)), 0.0, 1e-12);
      EXPECT_NEAR(glm::length(apply_inverse(pb, c.point_a) - (end - Vec3(0, r, 0))), 0.0, 1e-12);
      EXPECT_NEAR(c.depth, r - (end.y - h.y), 1e-12);
    }
    EXPECT_NE(m.points[0].id, m.points[1].id);
  }
}

}  // namespace
