// Zero allocations per World tick with rigid bodies in steady state: the rigid stage (paths
// driving kinematic bodies, the colliders' stand-ins, the step, the entities' poses and the
// colliders on them, the bodies' shapes in the collision world) and particles landing on the bodies, counted by a
// replaced operator new.
#include <gtest/gtest.h>

#include "pba/world.h"

#include "alloc_count.h"

using pba::test_support::g_allocations;

TEST(WorldRigidAlloc, TicksWithBodiesNeverAllocate) {
  pba::World w;
  const pba::EntityId ground = w.create_entity({.name = "ground"});
  w.add_collider(ground, {.shape = pba::ColliderShape::plane({0, 1, 0}, 0)});
  // a kinematic collider (its stand-in is a kinematic body) and a kinematic body on paths
  const pba::EntityId sweeper = w.create_entity({.name = "sweeper", .pose = {{-6, 0.2, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_collider(sweeper, {.shape = pba::ColliderShape::box({0.1, 0.2, 3})});
  w.add_kinematic(sweeper, {.path = pba::PathType::Circular, .center = {0, 0.2, 0}, .radius = 6, .angular_speed = 0.3});
  const pba::EntityId paddle = w.create_entity({.name = "paddle", .pose = {{0, 3, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_kinematic(paddle, {.path = pba::PathType::Motor, .spin = {0, 1, 0}});
  w.add_rigid_body(paddle, {.type = pba::BodyType::Kinematic, .shapes = {{.shape = pba::ColliderShape::box({1, 0.1, 0.2})}}});
  // boxes and balls, and particles over them
  for (int i = 0; i < 20; ++i) {
    const pba::EntityId e = w.create_entity({.pose = {{(i % 5) * 1.2 - 2.4, 0.5 + (i / 5) * 1.1, 0}, pba::Quat(1, 0, 0, 0)}});
    w.add_rigid_body(e, {.shapes = {{.shape = i % 2 ? pba::ColliderShape::sphere(0.4) : pba::ColliderShape::box({0.4, 0.4, 0.4})}}});
    // some carry a World collider too, which the rigid stage moves with them
    if (i % 7 == 0) w.add_collider(e, {.shape = pba::ColliderShape::sphere(0.45)});
    const pba::EntityId p = w.create_entity({});
    w.add_particle(p, {.position = {(i % 5) * 1.2 - 2.4, 6, 0.1}, .radius = 0.03});
  }
  for (int k = 0; k < 120; ++k) w.step();
  const long long before = g_allocations.load();
  for (int k = 0; k < 240; ++k) w.step();
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(w.body_colliders().size(), 20u);
}

// Sensors seeing particles allocate nothing once warm: a fountain through a sensor (counted
// per emitter) and particle entities falling through it (enter and leave events).
TEST(WorldSensorAlloc, SensorsOverParticlesNeverAllocate) {
  pba::World w({.particles = {.capacity = 4096}});
  const pba::EntityId gate = w.create_entity({.name = "gate", .pose = {{0, 2, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_collider(gate, {.shape = pba::ColliderShape::box({1, 0.5, 1}), .sensor = true});
  const pba::EntityId hose = w.create_entity({.name = "hose", .pose = {{0, 5, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_emitter(hose, {.direction = {0, -1, 0}, .speed = 1, .rate = 300, .lifetime = 1.5});
  for (int i = 0; i < 10; ++i) {
    // high enough that some pass the gate inside the counted ticks
    const pba::EntityId p = w.create_entity({.pose = {{0.1 * i - 0.5, 10 + 8 * i, 0}, pba::Quat(1, 0, 0, 0)}});
    w.add_particle(p, {.radius = 0.05});
  }
  for (int k = 0; k < 120; ++k) w.step();
  const long long before = g_allocations.load();
  std::size_t counted = 0, events = 0;
  for (int k = 0; k < 240; ++k) {
    w.step();
    events += w.sensor_enter_events().size() + w.sensor_leave_events().size();
    for (const pba::SensorCount& c : w.sensor_counts()) counted += c.inside;
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(counted, 0u);
  // the particles from 26 m up (i = 2..9) reach the gate after the 2 s warm-up, at
  // sqrt(2 (10 + 8 i - 2.5) / g) = 2.2 ... 4.0 s: one enter and one leave each
  EXPECT_EQ(events, 16u);
}
