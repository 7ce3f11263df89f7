// collide(), gjk_distance() and epa_penetration() never touch the heap: every pair type and
// both box methods over random poses, counted by the replaced global operator new.
#include <gtest/gtest.h>

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

}  // namespace
