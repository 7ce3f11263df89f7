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
  // beyond a float's range (the colliders')
  bad[2].y = -1e39;
  EXPECT_EQ(error_of([&] { TriangleMesh::build(bad, one, "floor"); }),
            "floor.vertices[2]: must fit a float (|component| <= 3.4028234663852886e+38), got (0, -1e+39, 0)");
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

// query() walks a float copy of the tree whose boxes are rounded outwards: it must give
// what a walk of nodes() in double gives, the same triangles in the same order, even for
// boxes that only touch a triangle's bounds, on a mesh far from the origin where float
// rounding is coarser than the triangles' spacing (2e-3 m cells at 3e4 m: float steps 2e-3)
TEST(CollideMesh, QueryWalksTheTreeInOrderWhereFloatRounds) {
  for (const double offset : {0.0, 3e4}) {
    auto t = test_support::terrain(40, 0.08, [](double x, double z) { return 1e-3 * std::sin(300 * x) * std::cos(200 * z); });
    for (Vec3& v : t.vertices) v += Vec3(offset, offset, -offset);
    const auto m = TriangleMesh::build(t.vertices, t.triangles);
    const auto nodes = m->nodes();
    auto walk = [&](const Aabb& box, std::vector<std::uint32_t>& out) {
      std::vector<std::uint32_t> stack{0};
      while (!stack.empty()) {
        const auto& n = nodes[stack.back()];
        stack.pop_back();
        if (!n.box.overlaps(box)) continue;
        if (n.count == 0) {
          stack.push_back(n.first + 1);
          stack.push_back(n.first);
          continue;
        }
        for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
          const auto& tri = t.triangles[m->triangle_order()[i]];
          const Vec3 a = t.vertices[tri[0]], b = t.vertices[tri[1]], c = t.vertices[tri[2]];
          if (Aabb{glm::min(a, glm::min(b, c)), glm::max(a, glm::max(b, c))}.overlaps(box)) out.push_back(m->triangle_order()[i]);
        }
      }
    };
    std::mt19937_64 rng(11);
    std::uniform_int_distribution<std::size_t> pick(0, t.vertices.size() - 1);
    std::uniform_real_distribution<double> w(0, 0.01);
    std::vector<std::uint32_t> got, want;
    std::size_t hits = 0;
    for (int k = 0; k < 2000; ++k) {
      // a box with a corner or a face exactly on a vertex (so on some triangles' bounds)
      const Vec3 v = t.vertices[pick(rng)];
      const Vec3 h(w(rng), w(rng), w(rng));
      const Aabb box = k % 2 ? Aabb{v, v + h} : Aabb{v - h, v};
      got.clear();
      want.clear();
      m->query(box, [&](std::uint32_t tri) { got.push_back(tri); });
      walk(box, want);
      EXPECT_EQ(got, want) << "offset " << offset << ", box " << k;
      hits += want.size();
    }
    EXPECT_GT(hits, 2000u);  // the boxes reach triangles
  }
}

TEST(CollideMesh, SameInputSameTree) {
  const auto t = test_support::terrain(20, 5.0, [](double x, double z) { return 0.1 * x * z; });
  const auto a = TriangleMesh::build(t.vertices, t.triangles), b = TriangleMesh::build(t.vertices, t.triangles);
  EXPECT_EQ(hash_span(a->nodes()), hash_span(b->nodes()));
  EXPECT_EQ(hash_span(a->triangle_order()), hash_span(b->triangle_order()));
}

}  // namespace

namespace {

TEST(CollideMesh, HasNoMassProperties) {
  const auto b = pba::test_support::box_mesh({1, 1, 1});
  const auto s = pba::ColliderShape::triangles(pba::TriangleMesh::build(b.vertices, b.triangles));
  EXPECT_EQ(pba::test_support::error_of([&] { pba::mass_properties(s, 1000, "floor"); }),
            "floor: a mesh has no volume, so no mass properties (use it as a static shape)");
}

}  // namespace
