// Zero allocations per World tick with particle entities touching colliders in steady state:
// the kernels' contact records, the touching pairs and the begin and end events, counted by a
// replaced operator new.
#include <gtest/gtest.h>

#include "pba/world.h"

#include "alloc_count.h"

using pba::test_support::g_allocations;

TEST(WorldParticleTouchAlloc, BouncingParticleEntitiesNeverAllocate) {
  pba::World w({.particles = {.capacity = 4096}});
  const pba::EntityId ground = w.create_entity({.name = "ground"});
  w.add_collider(ground, {.shape = pba::ColliderShape::plane({0, 1, 0}, 0), .material = {.restitution = 0.9}});
  const pba::EntityId block = w.create_entity({.name = "block", .pose = {.position = {1, 0.25, 0}}});
  w.add_collider(block, {.shape = pba::ColliderShape::box({0.5, 0.25, 0.5}), .material = {.restitution = 0.9}});
  const pba::EntityId crate = w.create_entity({.name = "crate", .pose = {.position = {-1, 0.3, 0}}});
  w.add_rigid_body(crate, {.shapes = {{.shape = pba::ColliderShape::box({0.3, 0.3, 0.3})}}});
  // a fountain (no events) and particle entities bouncing for the whole count (e = 0.9 from
  // up to 3 m: each keeps bouncing for minutes), some resting
  const pba::EntityId hose = w.create_entity({.name = "hose", .pose = {.position = {0, 2, 0}}});
  w.add_emitter(hose, {.rate = 300, .lifetime = 1.5});
  for (int i = 0; i < 30; ++i) {
    const pba::EntityId p = w.create_entity({.pose = {.position = {0.1 * (i % 10) - 1.2 + (i / 10) * 0.9, 1 + 0.07 * i, 0.05}}});
    w.add_particle(p, {.radius = 0.03});
  }
  for (int k = 0; k < 240; ++k) w.step();
  const long long before = g_allocations.load();
  std::size_t begins = 0, ends = 0;
  for (int k = 0; k < 240; ++k) {
    w.step();
    begins += w.touch_begin_events().size();
    ends += w.touch_end_events().size();
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(begins, 30u);
  EXPECT_GT(ends, 30u);
}
