// Tests for TriangleMesh::build: bad input, normals, edge flags (boundary and convex set,
// flat and concave clear), the BVH's structure and query() against brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "error_of.h"
#include "pba/collide/shape.h"
#include "shape_gen.h"

namespace {

using namespace pba;
using pba::test_support::error_of;
using Tri = std::array<std::uint32_t, 3>;

TEST(CollideMesh, BadInputThrowsNamingTheValue) {
  const std::vector<Vec3> v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}};
  EXPECT_EQ(error_of([&] { TriangleMesh::build(v, {}, "floor"); }),
            "floor.triangles: a mesh needs at least one triangle, got 0");
  const std::vector<Tri> out = {{0, 1, 2}, {0, 2, 4}};
  EXPECT_EQ(error_of([&] { TriangleMesh::build(v, out, "floor"); }),
            "floor.triangles[1][2]: must be a vertex index in [0, 3], got 4");
  const std::vector<Tri> repeated = {{0, 1, 1}};
  EXPECT_EQ(error_of([&] { TriangleMesh::build(v, repeated, "floor"); }),
            "floor.triangles[0]: degenerate triangle (zero area), vertices 0, 1, 1");
  const std::vector<Tri> collinear = {{0, 1, 2}, {0, 1, 3}};
  EXPECT_EQ(error_of([&] { TriangleMesh::build(v, collinear, "floor"); }),
            "floor.triangles[1]: degenerate triangle (zero area), vertices 0, 1, 3");
  std::vector<Vec3> bad = v;
  bad[2].y = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Tri> one = {{0, 1, 2}};
  EXPECT_EQ(error_of([&] { TriangleMesh::build(bad, one, "floor"); }), "floor.vertices[2]: must be finite, got (0, nan, 0)");
  EXPECT_EQ(error_of([&] { TriangleMesh::build(std::span<const Vec3>(v.data(), 2), one, "floor"); }),
            "floor.vertices.size: must be an integer in [3, 268435456], got 2");
  // an absurd count is refused before any vertex is read
  EXPECT_EQ(error_of([&] { TriangleMesh::build(std::span<const Vec3>(v.data(), std::size_t(1) << 30), one, "floor"); }),
            "floor.vertices.size: must be an integer in [3, 268435456], got 1073741824");
}

TEST(CollideMesh, NormalsAreTheNormalisedCrossProducts) {
  const auto s = test_support::icosphere(2);
  const auto m = TriangleMesh::build(s.vertices, s.triangles);
  for (std::uint32_t t = 0; t < s.triangles.size(); ++t) {
    const Vec3 a = s.vertices[s.triangles[t][0]], b = s.vertices[s.triangles[t][1]], c = s.vertices[s.triangles[t][2]];
    EXPECT_NEAR(glm::length(m->normal(t) - glm::normalize(glm::cross(b - a, c - a))), 0, 1e-15);
    EXPECT_GT(glm::dot(m->normal(t), a), 0);  // outward
  }
}

TEST(CollideMesh, EdgeFlagsMarkConvexAndBoundaryEdgesOnly) {
  // a flat grid: boundary edges set, every internal edge clear
  const auto flat = test_support::terrain(4, 2.0, [](double, double) { return 0.0; });
  const auto fm = TriangleMesh::build(flat.vertices, flat.triangles);
  int boundary = 0;
  for (std::uint32_t t = 0; t < flat.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3 a = flat.vertices[flat.triangles[t][k]], b = flat.vertices[flat.triangles[t][(k + 1) % 3]];
      const bool on_rim = (std::abs(a.x) == 1 && a.x == b.x) || (std::abs(a.z) == 1 && a.z == b.z);
      EXPECT_EQ((fm->edge_flags()[t] >> k) & 1, on_rim ? 1 : 0) << "triangle " << t << " edge " << k;
      boundary += on_rim;
    }
  EXPECT_EQ(boundary, 16);
  // a closed convex icosphere: every edge convex
  const auto s = test_support::icosphere(1);
  const auto sm = TriangleMesh::build(s.vertices, s.triangles);
  for (std::uint8_t f : sm->edge_flags()) EXPECT_EQ(f, 7);
  // a box: the 12 cube edges set, the 6 face diagonals clear
  const auto b = test_support::box_mesh({1, 2, 3});
  const auto bm = TriangleMesh::build(b.vertices, b.triangles);
  for (std::uint32_t t = 0; t < 12; ++t) EXPECT_EQ(bm->edge_flags()[t], t % 2 == 0 ? 0b011 : 0b110) << t;
  // a valley (concave) and a ridge (convex) of two triangles: edge ab is shared
  const std::vector<Vec3> valley = {{0, 0, -1}, {0, 0, 1}, {-1, 0.5, 0}, {1, 0.5, 0}};
  const std::vector<Tri> two = {{0, 1, 3}, {1, 0, 2}};
  const auto vm = TriangleMesh::build(valley, two);
  EXPECT_EQ(vm->edge_flags()[0] & 1, 0);
  EXPECT_EQ(vm->edge_flags()[1] & 1, 0);
  EXPECT_EQ(vm->edge_flags()[0], 0b110);  // its other two edges are boundary
  std::vector<Vec3> ridge = valley;
  ridge[2].y = ridge[3].y = -0.5;
  const auto rm = TriangleMesh::build(ridge, two);
  EXPECT_EQ(rm->edge_flags()[0], 7);
  EXPECT_EQ(rm->edge_flags()[1], 7);
}

TEST(CollideMesh, BvhCoversEveryTriangleOnceAndNestsItsBoxes) {
  const auto t = test_support::terrain(48, 20.0, [](double x, double z) { return std::sin(x) * std::cos(0.7 * z); });
  const auto m = TriangleMesh::build(t.vertices, t.triangles);
  const auto nodes = m->nodes();
  std::vector<int> seen(t.triangles.size(), 0);
  for (const auto& n : nodes) {
    if (n.count == 0) {
      ASSERT_LT(n.first + 1, nodes.size());
      EXPECT_TRUE(n.box.contains(nodes[n.first].box));
      EXPECT_TRUE(n.box.contains(nodes[n.first + 1].box));
    } else {
      for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
        const std::uint32_t tri = m->triangle_order()[i];
        ++seen[tri];
        for (std::uint32_t k : t.triangles[tri]) EXPECT_TRUE(n.box.contains({t.vertices[k], t.vertices[k]}));
      }
    }
  }
  for (int s : seen) EXPECT_EQ(s, 1);
  // reached from the root only (no orphan nodes): 2 leaves - 1 inner nodes
  std::size_t leaves = 0;
  for (const auto& n : nodes) leaves += n.count > 0;
  EXPECT_EQ(nodes.size(), 2 * leaves - 1);
}

TEST(CollideMesh, QueryEqualsBruteForce) {
  const auto t = test_support::terrain(48, 20.0, [](double x, double z) { return std::sin(x) * std::cos(0.7 * z); });
  const auto m = TriangleMesh::build(t.vertices, t.triangles);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-11, 11), w(0, 3);
  std::vector<std::uint32_t> got, want;
  for (int k = 0; k < 500; ++k) {
    const Vec3 c(u(rng), 0.3 * u(rng), u(rng)), h(w(rng), w(rng), w(rng));
    const Aabb box{c - h, c + h};
    got.clear();
    want.clear();
    m->query(box, [&](std::uint32_t tri) { got.push_back(tri); });
    for (std::uint32_t tri = 0; tri < t.triangles.size(); ++tri) {
      const Vec3 a = t.vertices[t.triangles[tri][0]], b = t.vertices[t.triangles[tri][1]], cc = t.vertices[t.triangles[tri][2]];
      if (Aabb{glm::min(a, glm::min(b, cc)), glm::max(a, glm::max(b, cc))}.overlaps(box)) want.push_back(tri);
    }
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, want) << "box " << k;
  }
}

TEST(CollideMesh, SameInputSameTree) {
  const auto t = test_support::terrain(20, 5.0, [](double x, double z) { return 0.1 * x * z; });
  const auto a = TriangleMesh::build(t.vertices, t.triangles), b = TriangleMesh::build(t.vertices, t.triangles);
  EXPECT_EQ(hash_span(a->nodes()), hash_span(b->nodes()));
  EXPECT_EQ(hash_span(a->triangle_order()), hash_span(b->triangle_order()));
}

}  // namespace
