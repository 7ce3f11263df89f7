// Zero allocations per rigid-body step in steady state, counted by a replaced operator new.
#include <gtest/gtest.h>

#include "pba/rigid.h"

#include "alloc_count.h"

using pba::test_support::g_allocations;

TEST(RigidAlloc, StepsAndImpulsesNeverAllocate) {
  pba::RigidBodySystem s({.capacity = 128});
  std::vector<pba::RigidBodyId> ids;
  for (int i = 0; i < 100; ++i)
    ids.push_back(s.create({.type = i % 10 == 0 ? pba::BodyType::Kinematic : pba::BodyType::Dynamic,
                            .pose = {{i * 1.0, 2, 0}}, .angular_velocity = {0.1 * i, 1, 0},
                            .mass = pba::RigidMass::box(1, {0.5, 0.2, 0.1}), .angular_damping = 0.1}));
  s.step(1.0 / 60, {0, -9.81, 0});
  const long long before = g_allocations.load();
  for (int k = 0; k < 200; ++k) {
    s.apply_force(ids[k % 100], {0, 1, 0}, {0, 0, 0});
    s.apply_impulse(ids[(k * 7) % 100], {0.1, 0, 0}, {0, 2, 0});
    s.step(1.0 / 60, {0, -9.81, 0});
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
}
