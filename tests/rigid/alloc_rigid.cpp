// Zero allocations per rigid-body step in steady state, counted by a replaced operator new.
#include <gtest/gtest.h>

#include <vector>

#include "pba/rigid.h"

#include "alloc_count.h"

using pba::test_support::g_allocations;

// 100 bodies resting in contact (boxes on the ground, balls on the boxes, a kinematic
// paddle sliding under none of them), under forces and impulses: once the contact pairs
// have been seen, stepping allocates nothing, for every solver, with and without sleeping
TEST(RigidAlloc, StepsWithContactsNeverAllocate) {
  for (const bool sleep : {false, true})
  for (const auto solver : pba::kRigidSolvers) {
    pba::RigidBodySystem s({.capacity = 128, .contacts = {.solver = solver, .sleep = sleep}});
    s.create({.type = pba::BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
    std::vector<pba::RigidBodyId> ids;
    for (int i = 0; i < 50; ++i) {
      const double x = (i % 10) * 1.5, z = (i / 10) * 1.5;
      ids.push_back(s.create({.pose = {{x, 0.25, z}}, .shapes = {{.shape = pba::ColliderShape::box({0.5, 0.25, 0.5})}}}));
      ids.push_back(s.create({.pose = {{x, 0.75, z}}, .shapes = {{.shape = pba::ColliderShape::sphere(0.25)}}}));
    }
    s.create({.type = pba::BodyType::Kinematic, .pose = {{-5, 3, 0}}, .linear_velocity = {0.1, 0, 0},
              .shapes = {{.shape = pba::ColliderShape::box({0.5, 0.1, 0.5})}}});
    for (int k = 0; k < 120; ++k) s.step(1.0 / 60, {0, -9.81, 0});
    const long long before = g_allocations.load();
    for (int k = 0; k < 200; ++k) {
      s.apply_force(ids[k % 100], {0, 1, 0}, {0, 0, 0});
      s.apply_impulse(ids[(k * 7) % 100], {1e-3, 0, 0}, {0, 2, 0});
      s.step(1.0 / 60, {0, -9.81, 0});
    }
    EXPECT_EQ(g_allocations.load() - before, 0) << to_string(solver) << (sleep ? " sleep on" : "");
    // with sleeping off every contact is live; with it on, islands sleep and wake under the forces
    if (!sleep) EXPECT_GE(s.manifold_count(), 100u);
  }
}
