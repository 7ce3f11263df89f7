// Test helpers: structural checks of a ConvexHull (half edges, Euler, planarity, convexity),
// matrix comparison and random rotations.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "pba/collide/shape.h"

namespace pba::test_support {

/// Checks everything a valid hull promises, with `tol` (m) the planarity/convexity slack:
/// twins at 2i / 2i + 1 with opposite directions, closed face loops with consistent faces,
/// V - E + F = 2, unit normals, every face vertex on its plane, every hull vertex on or
/// below every face plane (convexity), faces counter-clockwise from outside (the loop's
/// Newell normal agrees with the stored one) and every vertex in some face.
inline void expect_valid_hull(const ConvexHull& h, double tol) {
  const auto v = h.vertices();
  const auto e = h.edges();
  const auto f = h.faces();
  ASSERT_EQ(e.size() % 2, 0u);
  EXPECT_EQ(static_cast<long>(v.size()) - static_cast<long>(e.size() / 2) + static_cast<long>(f.size()), 2);
  for (std::uint32_t i = 0; i < e.size(); ++i) {
    ASSERT_EQ(e[i].twin, i ^ 1u) << "edge " << i;
    ASSERT_LT(e[i].origin, v.size());
    ASSERT_LT(e[i].next, e.size());
    ASSERT_LT(e[i].face, f.size());
    // the twin runs the other way: its origin is this edge's end
    EXPECT_EQ(e[e[i].twin].origin, e[e[i].next].origin) << "edge " << i;
    EXPECT_NE(e[e[i].twin].face, e[i].face) << "edge " << i;
    EXPECT_EQ(e[e[i].next].face, e[i].face) << "edge " << i;
  }
  std::vector<int> on_face(e.size(), 0), vertex_used(v.size(), 0);
  for (std::uint32_t fi = 0; fi < f.size(); ++fi) {
    EXPECT_NEAR(glm::length(f[fi].normal), 1.0, 1e-12);
    std::uint32_t k = f[fi].edge, count = 0;
    Vec3 newell(0.0);
    do {
      ASSERT_EQ(e[k].face, fi);
      ++on_face[k];
      ++vertex_used[e[k].origin];
      const Vec3 a = v[e[k].origin], b = v[e[e[k].next].origin];
      EXPECT_NEAR(glm::dot(f[fi].normal, a), f[fi].offset, tol) << "face " << fi << " not planar";
      newell += glm::cross(a, b);
      k = e[k].next;
      ASSERT_LE(++count, e.size());
    } while (k != f[fi].edge);
    EXPECT_GE(count, 3u);
    EXPECT_GT(glm::dot(newell, f[fi].normal), 0) << "face " << fi << " is not counter-clockwise from outside";
    for (std::uint32_t j = 0; j < v.size(); ++j)
      EXPECT_LE(glm::dot(f[fi].normal, v[j]) - f[fi].offset, tol) << "vertex " << j << " above face " << fi;
  }
  for (std::uint32_t i = 0; i < e.size(); ++i) EXPECT_EQ(on_face[i], 1) << "edge " << i << " in no or two loops";
  for (std::uint32_t j = 0; j < v.size(); ++j) EXPECT_GE(vertex_used[j], 3) << "vertex " << j << " in fewer than 3 faces";
}

/// Expects a == b elementwise within rel times b's largest element.
inline void expect_mat_near(const Mat3& a, const Mat3& b, double rel) {
  double scale = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) scale = std::max(scale, std::abs(b[i][j]));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(a[i][j], b[i][j], rel * scale) << "(" << i << ", " << j << ")";
}

/// A uniformly random rotation (a normalised Gaussian quaternion).
inline Quat random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0, 1);
  return glm::normalize(Quat(g(rng), g(rng), g(rng), g(rng)));
}

}  // namespace pba::test_support
