// Particles riding the World's moving rigid bodies (a new user's checks, 2026-12-07): a
// particle on a conveyor body (a kinematic box on a linear path) and on a turntable (a
// kinematic box spun by a motor) is carried by friction to the surface's velocity, with the
// catch-up distance and the radial drift of a first-order step in closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "pba/world.h"

namespace {

using pba::BodyType;
using pba::ColliderShape;
using pba::EntityId;
using pba::RigidBodyDef;
using pba::Vec3;
using pba::World;

constexpr double kG = 9.81;  // m/s^2, the World's default gravity

// a kinematic box (half extents `half`) with friction mu on the entity, driven by `path`
EntityId kinematic_box(World& w, const Vec3& half, double mu, const pba::KinematicDef& path) {
  const EntityId e = w.create_entity({.name = "carrier"});
  RigidBodyDef d;
  d.type = BodyType::Kinematic;
  d.shapes = {{.shape = ColliderShape::box(half), .material = {.restitution = 0, .friction = mu}}};
  w.add_rigid_body(e, d);
  w.add_kinematic(e, path);
  return e;
}

// A particle set at rest on a belt moving at v is accelerated by kinetic friction mu g until
// it moves with the belt, then rides it at exactly the belt's velocity: it ends
// v^2 / (2 mu g) behind a point painted on the belt under it (within one tick of travel,
// v dt, for the step that starts the slide and the one that ends it).
TEST(ParticlesOnBodies, AParticleRidesAConveyorBodyAfterSlippingTheClosedFormDistance) {
  for (const double mu : {0.5, 1.0}) {
    SCOPED_TRACE(mu);
    const double dt = 1.0 / 120, v = 1.0, r = 0.05, top = 0.1;
    World w({.stepper = {.fixed_dt = dt}});
    const EntityId belt = kinematic_box(w, {5, top, 1}, mu, {.path = pba::PathType::Linear, .velocity = {v, 0, 0}});
    const EntityId p = w.create_entity({.name = "parcel"});
    w.add_particle(p, {.position = {0, top + r, 0}, .radius = r});
    for (int i = 0; i < 120; ++i) w.step();
    const double slip = w.pose(belt).position.x - w.pose(p).position.x;
    EXPECT_NEAR(slip, v * v / (2 * mu * kG), v * dt);
    EXPECT_NEAR(w.velocity(p).x, v, 1e-6);
    EXPECT_NEAR(w.pose(p).position.y, top + r, 1e-6);  // on the belt's top, not in it
  }
}

// On a turntable spinning at omega a riding particle moves at the surface's velocity,
// omega r, but straight for the tick: a chord of a circle ends farther out, by
// (omega r dt)^2 / (2 r) a tick, so the particle spirals out at omega^2 r dt / 2 (static
// friction would hold it at r: the drift is the step's, first order in dt). At omega = 2
// rad/s, r = 0.5 m, dt = 1/120 s: 8.3 mm/s; half the tick, half the drift.
TEST(ParticlesOnBodies, AParticleOnATurntableRidesItAndDriftsOutAtTheFirstOrderRate) {
  const double omega = 2, r0 = 0.5, r = 0.05, top = 0.1;
  double drift[2] = {};
  for (int k = 0; k < 2; ++k) {
    const double dt = k == 0 ? 1.0 / 120 : 1.0 / 240;
    World w({.stepper = {.fixed_dt = dt}});
    kinematic_box(w, {1, top, 1}, 1.0, {.path = pba::PathType::Motor, .spin = {0, omega, 0}});
    const EntityId p = w.create_entity({.name = "bead"});
    w.add_particle(p, {.position = {r0, top + r, 0}, .radius = r});
    const int half_second = static_cast<int>(std::lround(0.5 / dt));
    for (int i = 0; i < half_second; ++i) w.step();  // caught up by 0.5 s (omega r0 / (mu g) = 0.1 s)
    const Vec3 a = w.pose(p).position;
    for (int i = 0; i < 2 * half_second; ++i) w.step();
    const Vec3 b = w.pose(p).position;
    const double ra = std::hypot(a.x, a.z), rb = std::hypot(b.x, b.z);
    drift[k] = (rb - ra) / 1.0;
    // it goes round with the table: its speed is the surface's there
    EXPECT_NEAR(glm::length(w.velocity(p)), omega * rb, 1e-3 * omega * rb) << dt;
    EXPECT_NEAR(b.y, top + r, 1e-6) << dt;
    // the drift is the chord's, within 5% (the radius grows over the second: 1.7%)
    EXPECT_NEAR(drift[k], omega * omega * ra * dt / 2, 0.05 * omega * omega * ra * dt / 2) << dt;
  }
  EXPECT_NEAR(drift[0] / drift[1], 2.0, 0.1);  // first order in dt
}

}  // namespace
