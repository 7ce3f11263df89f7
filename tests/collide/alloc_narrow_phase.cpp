// collide(), gjk_distance() and epa_penetration() never touch the heap: every pair type and
// both box methods over random poses, counted by the replaced global operator new.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "alloc_count.h"
#include "narrow_reference.h"
#include "pba/collide/narrow_phase.h"

namespace {

using namespace pba;
using pba::test_support::g_allocations;

TEST(NarrowPhaseAlloc, CollideAllocatesNothing) {
  std::vector<ColliderShape> shapes(5);
  shapes[0].type = ShapeType::Sphere;
  shapes[0].radius = 0.4;
  shapes[1].type = ShapeType::Capsule;
  shapes[1].half_height = 0.5;
  shapes[1].radius = 0.2;
  shapes[2].type = ShapeType::Box;
  shapes[2].half_extents = Vec3(0.5, 0.3, 0.2);
  shapes[3].type = ShapeType::Box;
  shapes[3].half_extents = Vec3(1, 0.2, 0.7);
  shapes[4].type = ShapeType::Plane;
  std::mt19937_64 rng(8);
  std::vector<Vec3> cloud(40);
  for (Vec3& p : cloud) p = test_support::random_vec(rng, 0.5);
  shapes.push_back(ColliderShape::convex(ConvexHull::build(cloud)));
  std::vector<Pose> poses(4000);
  for (auto& p : poses) p = {test_support::random_vec(rng, 0.8), test_support::random_rotation(rng)};
  NarrowPhaseCache cache;
  int contacts = 0;
  const long long before = g_allocations.load();
  for (std::size_t k = 0; k + 1 < poses.size(); k += 2)
    for (std::size_t i = 0; i < shapes.size(); ++i)
      for (std::size_t j = 0; j < shapes.size(); ++j) {
        if (i == 4 && j == 4) continue;  // plane-plane has no narrow phase
        for (const ConvexMethod m : {ConvexMethod::Sat, ConvexMethod::GjkEpa}) {
          NarrowPhaseSettings s;
          s.method = m;
          contacts += collide(shapes[i], poses[k], shapes[j], poses[k + 1], s, &cache).count;
        }
      }
  const long long after = g_allocations.load();
  EXPECT_EQ(after - before, 0);
  EXPECT_GT(contacts, 1000);  // the poses overlap often: the contact paths ran
}

TEST(NarrowPhaseAlloc, CollideBatchAllocatesNothing) {
  // box pairs among other pairs, every path, with caches: the lanes' state lives on the stack
  std::mt19937_64 rng(9);
  const ColliderShape a = ColliderShape::box(Vec3(0.5, 0.3, 0.2)), b = ColliderShape::box(Vec3(1, 0.2, 0.7)),
                      s = ColliderShape::sphere(0.4);
  std::vector<PairQuery> q(3000);
  std::vector<NarrowPhaseCache> caches(q.size());
  for (std::size_t k = 0; k < q.size(); ++k)
    q[k] = {k % 7 == 3 ? &s : &a, {test_support::random_vec(rng, 0.3), test_support::random_rotation(rng)}, &b,
            {test_support::random_vec(rng, 1.0), test_support::random_rotation(rng)}, 0.02, &caches[k]};
  std::vector<Manifold> out(q.size());
  int contacts = 0;
  const long long before = g_allocations.load();
  for (const BatchPath path : {BatchPath::Scalar, BatchPath::Avx2, BatchPath::Avx512, BatchPath::Best}) {
    collide_batch(q, out, ConvexMethod::Sat, path);
    for (const Manifold& m : out) contacts += m.count;
  }
  const long long after = g_allocations.load();
  EXPECT_EQ(after - before, 0);
  EXPECT_GT(contacts, 1000);
}

TEST(NarrowPhaseAlloc, CollideMeshAllocatesNothing) {
  // a bumpy 8 x 8 grid, every convex shape dropped on it at random poses
  std::vector<Vec3> v;
  std::vector<std::array<std::uint32_t, 3>> t;
  for (int j = 0; j <= 8; ++j)
    for (int i = 0; i <= 8; ++i) v.push_back({0.5 * i - 2, 0.05 * std::sin(1.3 * i + 0.7 * j), 0.5 * j - 2});
  for (std::uint32_t j = 0; j < 8; ++j)
    for (std::uint32_t i = 0; i < 8; ++i) {
      t.push_back({j * 9 + i, (j + 1) * 9 + i, j * 9 + i + 1});
      t.push_back({j * 9 + i + 1, (j + 1) * 9 + i, (j + 1) * 9 + i + 1});
    }
  const ColliderShape mesh = ColliderShape::triangles(TriangleMesh::build(v, t));
  std::mt19937_64 rng(9);
  std::vector<Vec3> cloud(30);
  for (Vec3& p : cloud) p = test_support::random_vec(rng, 0.4);
  const ColliderShape shapes[] = {ColliderShape::sphere(0.3), ColliderShape::capsule(0.3, 0.2),
                                  ColliderShape::box(Vec3(0.4, 0.2, 0.3)), ColliderShape::convex(ConvexHull::build(cloud))};
  std::vector<Pose> poses(500);
  for (auto& p : poses) p = {test_support::random_vec(rng, 1.5) * Vec3(1, 0.15, 1), test_support::random_rotation(rng)};
  std::array<Manifold, 32> out;
  int manifolds = 0;
  const long long before = g_allocations.load();
  for (const Pose& p : poses)
    for (const ColliderShape& s : shapes) manifolds += collide_mesh(s, p, mesh, {}, out);
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(manifolds, 500);
}

}  // namespace
