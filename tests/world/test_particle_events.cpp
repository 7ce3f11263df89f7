// Sensors and particles (issue 10, notifications): a sensor collider reports the particle
// entities that enter and leave it, as it does rigid bodies' entities, and counts the
// particles of each emitter inside it (an emitter's particles are too many, and too
// anonymous, for an event each).
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "pba/world.h"

namespace {

using pba::ColliderShape;
using pba::EntityId;
using pba::Vec3;
using pba::World;

// A particle entity dropped through a sensor box enters once and leaves once. The particle
// stage's semi-implicit Euler puts it, after n ticks of dt from rest at y0, at
//   y_n = y0 - g dt^2 n (n + 1) / 2
// (v_n = -g n dt, y_n = y_{n-1} + v_n dt), so the enter tick is the first n whose sphere
// reaches the box's top (y_n - r <= top) and the leave tick the first whose sphere is below
// its bottom (y_n + r < bottom), to the tick. The continuous fall's times sqrt(2 d / g) lie
// within one tick of them (the scheme runs g dt t / 2 ahead). The sensor pushes nothing.
TEST(ParticleSensors, AParticleEntityEntersAndLeavesOnceAtTheSchemesTicks) {
  const double dt = 1.0 / 60, g = 9.81, y0 = 5, r = 0.1, top = 2.5, bottom = 1.5;
  World w({.stepper = {.fixed_dt = dt}});
  const EntityId sensor = w.create_entity({.name = "gate", .pose = {.position = {0, 2, 0}}});
  w.add_collider(sensor, {.shape = ColliderShape::box({1, 0.5, 1}), .sensor = true});
  const EntityId drop = w.create_entity({.name = "drop", .pose = {.position = {0, y0, 0}}});
  w.add_particle(drop, {.radius = r});
  auto y = [&](int n) { return y0 - g * dt * dt * n * (n + 1) / 2; };
  int n_enter = 1, n_leave = 1;
  while (y(n_enter) - r > top) ++n_enter;
  while (y(n_leave) + r >= bottom) ++n_leave;
  // both far from a tie, so float positions cannot move them by a tick
  ASSERT_GT(y(n_enter - 1) - r - top, 0.01);
  ASSERT_GT(top - (y(n_enter) - r), 0.01);
  ASSERT_GT(bottom - (y(n_leave) + r), 0.01);
  EXPECT_NEAR(n_enter * dt, std::sqrt(2 * (y0 - r - top) / g), dt);
  EXPECT_NEAR(n_leave * dt, std::sqrt(2 * (y0 + r - bottom) / g), dt);
  int enters = 0, leaves = 0;
  for (int n = 1; n <= 60; ++n) {
    w.step();
    for (const pba::SensorEvent& ev : w.sensor_enter_events()) {
      ++enters;
      EXPECT_EQ(ev.sensor, sensor);
      EXPECT_EQ(ev.visitor, drop);
      EXPECT_EQ(n, n_enter);
    }
    for (const pba::SensorEvent& ev : w.sensor_leave_events()) {
      ++leaves;
      EXPECT_EQ(ev.visitor, drop);
      EXPECT_EQ(n, n_leave);
    }
  }
  EXPECT_EQ(enters, 1);
  EXPECT_EQ(leaves, 1);
  // it fell freely through
  EXPECT_NEAR(w.pose(drop).position.y, y(60), 1e-4);
}

// An emitter's particles are counted, not reported one by one: after each tick
// sensor_counts() holds, per sensor and emitter, how many of its live particles overlap the
// sensor, equal to a count over the particles themselves (sphere against box, brute force).
// Two emitters, one aimed through the sensor and one beside it; particle entities are not
// counted (they have their own events).
TEST(ParticleSensors, EmittersAreCountedPerSensor) {
  World w({.stepper = {.fixed_dt = 1.0 / 60}});
  const EntityId sensor = w.create_entity({.name = "gate", .pose = {.position = {0, 2, 0}}});
  w.add_collider(sensor, {.shape = ColliderShape::box({1, 0.5, 1}), .sensor = true});
  const EntityId hose = w.create_entity({.name = "hose", .pose = {.position = {0, 5, 0}}});
  w.add_emitter(hose, {.direction = {0, -1, 0}, .spread = 0.2, .speed = 1, .rate = 120, .lifetime = 3, .radius = 0.02});
  const EntityId other = w.create_entity({.name = "other", .pose = {.position = {4, 5, 0}}});
  w.add_emitter(other, {.direction = {0, -1, 0}, .speed = 1, .rate = 60, .lifetime = 3, .radius = 0.02});
  const EntityId drop = w.create_entity({.name = "drop", .pose = {.position = {0.5, 2, 0}}});
  w.add_particle(drop, {});
  int ticks_with_particles_inside = 0;
  for (int n = 0; n < 150; ++n) {
    w.step();
    // the reference: every emitted particle whose sphere overlaps the box |x| <= (1, 0.5, 1) at (0, 2, 0)
    const pba::ParticleSystem& ps = w.particles();
    std::size_t expected = 0;
    for (std::size_t i = 0; i < ps.size(); ++i) {
      if (ps.source(i) == 0) continue;  // the particle entity
      const Vec3 p = ps.position(i) - Vec3(0, 2, 0), h(1, 0.5, 1);
      const Vec3 q = glm::clamp(p, -h, h);
      if (glm::length(p - q) <= ps.radius(i)) ++expected;
    }
    std::map<std::uint32_t, std::size_t> counted;
    for (const pba::SensorCount& c : w.sensor_counts()) {
      EXPECT_EQ(c.sensor, sensor);
      EXPECT_GT(c.inside, 0u);
      counted[c.emitter.index] += c.inside;
    }
    EXPECT_EQ(counted.count(other.index), 0u) << "tick " << n;
    const std::size_t got = counted.count(hose.index) ? counted[hose.index] : 0;
    EXPECT_EQ(got, expected) << "tick " << n;
    ticks_with_particles_inside += got > 0;
  }
  EXPECT_GT(ticks_with_particles_inside, 50);
}

}  // namespace
