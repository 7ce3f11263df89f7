// The capsule-box pair's closed form (segment_box_closest): against the brute-force
// feature enumeration and its own separating-plane certificate over random segments in every
// region, and exact cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "narrow_reference.h"
#include "pba/collide/narrow_phase.h"

namespace {

using namespace pba;
using namespace pba::test_support;

// Rounding room: the answers are a few dozen operations on coordinates of size L (the
// segment's and the box's reach), each off by half an ulp, so 1e-12 L leaves ~1e3 ulps.
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
}

}  // namespace
