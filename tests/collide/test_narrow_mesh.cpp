// Convex shapes against triangle meshes: no ghost contacts on the internal edges of a flat
// grid, the same contact as against a plane, a convex (flagged) edge keeping its own normal.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "error_of.h"
#include "pba/collide/narrow_phase.h"

namespace {

using namespace pba;

// a flat n x n grid of 1 m cells at y = 0 over [-n/2, n/2]^2, two triangles per cell,
// wound so the normals point up; every edge inside is flat (flags clear)
ColliderShape flat_grid(int n) {
  std::vector<Vec3> v;
  std::vector<std::array<std::uint32_t, 3>> t;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) v.push_back({i - 0.5 * n, 0, j - 0.5 * n});
  auto id = [&](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      t.push_back({id(i, j), id(i, j + 1), id(i + 1, j)});
      t.push_back({id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)});
    }
  return ColliderShape::triangles(TriangleMesh::build(v, t, "grid"));
}

TEST(Mesh, GridHasUpNormalsAndFlatInternalEdges) {
  const ColliderShape g = flat_grid(4);
  for (std::uint32_t k = 0; k < g.mesh->triangles().size(); ++k) EXPECT_NEAR(g.mesh->normal(k).y, 1.0, 1e-15);
}

TEST(Mesh, BoxSlidingOverInternalEdgesHasNoGhostContacts) {
  // a 1 m box 1 cm deep in the grid, slid across the internal edges x = 0 and the
  // diagonals: every manifold's normal is the face normal, every point 1 cm deep, as on
  // a plane; a ghost contact would show as a tilted normal or a depth of the sliver
  const ColliderShape grid = flat_grid(4);
  const ColliderShape box = ColliderShape::box(Vec3(0.5));
  std::array<Manifold, 16> out;
  for (int k = 0; k <= 40; ++k) {
    const double x = -0.6 + 0.03 * k;  // crosses x = 0, with slivers of 5 mm and less
    const Pose p{Vec3(x + 0.005, 0.49, 0.013), Quat(1, 0, 0, 0)};
    const int n = collide_mesh(box, p, grid, {}, out);
    ASSERT_GT(n, 0);
    int points = 0;
    for (int m = 0; m < n; ++m) {
      EXPECT_NEAR(glm::length(out[std::size_t(m)].normal - Vec3(0, -1, 0)), 0.0, 1e-12) << "x " << x;
      for (int i = 0; i < out[std::size_t(m)].count; ++i) {
        EXPECT_NEAR(out[std::size_t(m)].points[std::size_t(i)].depth, 0.01, 1e-12) << "x " << x;
        ++points;
      }
    }
    EXPECT_GE(points, 4);
  }
}

TEST(Mesh, SphereAndCapsuleOnTheGridMatchThePlane) {
  const ColliderShape grid = flat_grid(4);
  const ColliderShape ground = ColliderShape::plane(Vec3(0, 1, 0), 0);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  std::array<Manifold, 16> out;
  for (int k = 0; k < 100; ++k) {
    const Pose ps{Vec3(u(rng), 0.27, u(rng)), Quat(1, 0, 0, 0)};
    const ColliderShape s = ColliderShape::sphere(0.3);
    const int n = collide_mesh(s, ps, grid, {}, out);
    const Manifold ref = collide(s, ps, ground, {});
    ASSERT_EQ(ref.count, 1);
    ASSERT_GE(n, 1);
    for (int m = 0; m < n; ++m) {
      EXPECT_NEAR(glm::length(out[std::size_t(m)].normal - ref.normal), 0.0, 1e-12);
      EXPECT_NEAR(out[std::size_t(m)].points[0].depth, ref.points[0].depth, 1e-12);
    }
    // a lying capsule: two points per manifold at the plane's depth
    const Pose pc{Vec3(u(rng), 0.18, u(rng)), glm::angleAxis(kPi / 2, Vec3(0, 0, 1))};
    const ColliderShape c = ColliderShape::capsule(0.4, 0.2);
    const int nc = collide_mesh(c, pc, grid, {}, out);
    ASSERT_GE(nc, 1);
    for (int m = 0; m < nc; ++m) {
      EXPECT_NEAR(glm::length(out[std::size_t(m)].normal - Vec3(0, -1, 0)), 0.0, 1e-12);
      for (int i = 0; i < out[std::size_t(m)].count; ++i)
        EXPECT_NEAR(out[std::size_t(m)].points[std::size_t(i)].depth, 0.02, 1e-12);
    }
  }
}

TEST(Mesh, ConvexRidgeKeepsItsEdgeNormal) {
  // two triangles folded into a ridge along x (a roof, convex edge flagged): a sphere
  // right above the ridge line touches the edge, whose normal points straight up, and a
  // sphere off to the side at the edge's end gets the edge-to-centre direction
  const std::vector<Vec3> v = {{-1, 0, -1}, {1, 0, -1}, {-1, 0.5, 0}, {1, 0.5, 0}, {-1, 0, 1}, {1, 0, 1}};
  const std::vector<std::array<std::uint32_t, 3>> t = {{0, 2, 1}, {1, 2, 3}, {2, 4, 3}, {3, 4, 5}};
  const ColliderShape roof = ColliderShape::triangles(TriangleMesh::build(v, t, "roof"));
  std::array<Manifold, 8> out;
  const ColliderShape s = ColliderShape::sphere(0.2);
  const int n = collide_mesh(s, {Vec3(0.1, 0.69, 0), Quat(1, 0, 0, 0)}, roof, {}, out);
  ASSERT_GE(n, 1);
  for (int m = 0; m < n; ++m) {
    EXPECT_NEAR(glm::length(out[std::size_t(m)].normal - Vec3(0, -1, 0)), 0.0, 1e-9);
    EXPECT_NEAR(out[std::size_t(m)].points[0].depth, 0.01, 1e-9);
  }
}

TEST(Mesh, BadInputAndNoAllocationOfResults) {
  const ColliderShape grid = flat_grid(2);
  std::array<Manifold, 2> out;
  const double nan = std::nan("");
  EXPECT_NE(test_support::error_of([&] { collide_mesh(ColliderShape::sphere(0.5), {Vec3(nan, 0, 0), Quat(1, 0, 0, 0)}, grid, {}, out); })
                .find("pose_a.position"),
            std::string::npos);
  EXPECT_NE(test_support::error_of([&] { collide_mesh(grid, {}, grid, {}, out); }).find("convex"), std::string::npos);
  // at most out.size() manifolds are written
  EXPECT_LE(collide_mesh(ColliderShape::box(Vec3(0.9, 0.5, 0.9)), {Vec3(0, 0.45, 0), Quat(1, 0, 0, 0)}, grid, {}, out),
            2);
}

}  // namespace
