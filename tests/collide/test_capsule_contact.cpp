// Particles and soft bodies against capsules, through the collide module's point
// contact: the rebound of a dropped particle, no tunnelling at 300 m/s through the side
// or into an end cap, and cloth resting on a capsule stays outside it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "pba/collide.h"
#include "pba/particles.h"
#include "pba/soft.h"

namespace {

using pba::Collider;
using pba::Quat;
using pba::Vec3;

// a static capsule: core segment of half length hh along `axis` through `center`
Collider capsule(const Vec3& center, const Quat& rotation, double hh, double radius, double e = 0.5) {
  Collider c;
  c.shape.type = pba::ShapeType::Capsule;
  c.shape.half_height = hh;
  c.shape.radius = radius;
  c.material = {.restitution = e, .friction = 0.0};
  c.begin = c.end = {center, rotation};
  return c;
}

// distance from p to the core segment of a capsule (the closed form of its surface)
double core_distance(const Collider& c, const Vec3& p) {
  const Vec3 q = glm::conjugate(c.end.rotation) * (p - c.end.position);
  const double y = std::clamp(q.y, -c.shape.half_height, c.shape.half_height);
  return glm::length(q - Vec3(0, y, 0));
}

}  // namespace

// A particle dropped from h onto the top of a lying capsule rebounds to e^2 h: within 3%
// (the bound), and within 2e-5 m of the semi-implicit Euler closed form (the
// path's steps lose dt / 2 of height per m/s on each leg, as for the sphere in
// test_collision_world.cpp; the response is exact for constant acceleration).
TEST(Capsule, DroppedParticleReboundsToESquaredH) {
  const double e = 0.7, h = 0.6, dt = 1.0 / 1000, r = 0.02, R = 0.15;
  // lying along x: the local +Y axis turned onto the world x axis
  const Quat lying = glm::angleAxis(pba::kPi / 2, Vec3(0, 0, 1));
  const Collider cap = capsule({0, 0, 0}, lying, 0.5, R, e);
  for (double x0 : {0.0, 0.3}) {  // over the middle, and nearer an end (still on the side)
    pba::ParticleSystem ps({.capacity = 1});
    ps.spawn({.position = {x0, R + r + h, 0}, .mass = 0.01, .radius = r});
    double apex = -1;
    bool up = false;
    for (int s = 0; s < 700; ++s) {
      ps.step(s * dt, dt, std::span<const Collider>(&cap, 1), {});
      if (ps.velocity(0).y > 0) up = true;
      if (up) apex = std::max(apex, ps.position(0).y - (R + r));
    }
    ASSERT_TRUE(up);
    const double v_in = std::sqrt(2 * 9.81 * h), v_out = e * v_in;
    EXPECT_NEAR(apex, e * e * h, 0.03 * e * e * h) << x0;
    EXPECT_NEAR(apex, e * e * (h - v_in * dt / 2) - v_out * dt / 2, 2e-5) << x0;
    // it stays on the vertical through its start: the normal at the top of the side is +y
    EXPECT_NEAR(ps.position(0).x, x0, 1e-5);
  }
}

// No tunnelling at 300 m/s: at 60 Hz a particle moves 5 m per step, 17 times the
// capsule's diameter, yet it bounces off the side (shot across the axis) and off an end
// cap (shot along the axis), and ends outside on the side it came from.
TEST(Capsule, NoTunnellingAt300MetresPerSecond) {
  const double dt = 1.0 / 60, R = 0.15, hh = 0.4, r = 0.01;
  const Collider upright = capsule({0, 1, 0}, Quat(1, 0, 0, 0), hh, R, 0.5);
  struct Shot {
    Vec3 from, velocity;
  };
  // across the side at mid height, and down the axis onto the top cap
  for (const Shot& shot : {Shot{{-2.0, 1.1, 0.0}, {300, 0, 0}}, Shot{{0.0, 3.0, 0.0}, {0, -300, 0}}}) {
    pba::ParticleSystemDef def;
    def.capacity = 1;
    def.forces.gravity = Vec3(0);
    pba::ParticleSystem ps(def);
    ps.spawn({.position = shot.from, .velocity = shot.velocity, .mass = 0.01, .radius = r});
    for (int s = 0; s < 3; ++s) ps.step(s * dt, dt, std::span<const Collider>(&upright, 1), {});
    // reversed with restitution 0.5, and never inside
    const Vec3 dir = glm::normalize(shot.velocity);
    EXPECT_NEAR(glm::dot(ps.velocity(0), dir), -0.5 * 300, 1e-3 * 300) << shot.from.x;
    EXPECT_GT(core_distance(upright, ps.position(0)), R + r - 1e-6);
    EXPECT_LT(glm::dot(ps.position(0) - upright.end.position, dir), 0.0);  // on the side it came from
  }
}

// A cloth dropped onto a lying capsule comes to rest draped over it: every particle stays
// outside the capsule grown by the cloth's thickness (less the solver's penetration
// allowance: one substep of gravity, g h^2), and the cloth's middle rests on its top.
TEST(Capsule, ClothRestsOnACapsule) {
  const double R = 0.2, th = 0.01;
  const Quat lying = glm::angleAxis(pba::kPi / 2, Vec3(0, 0, 1));
  const Collider cap = capsule({0, 0.5, 0}, lying, 0.6, R);
  pba::SoftBodyDef d;
  d.solver = pba::SoftSolver::Xpbd;
  d.thickness = th;
  d.friction = 0.5;
  d.substeps = 20;
  pba::SoftBody cloth = pba::SoftBody::cloth_grid(
      {.origin = {-0.5, 0.9, -0.5}, .edge_u = {1, 0, 0}, .edge_v = {0, 0, 1}, .nx = 21, .ny = 21, .pins = pba::ClothPins::None},
      d);
  pba::CollisionWorld cw;
  cw.add(cap);
  const double dt = 1.0 / 60, h = dt / d.substeps;
  for (int s = 0; s < 180; ++s) cloth.step(s * dt, dt, cw);
  double closest = 1e9;
  for (std::size_t i = 0; i < cloth.size(); ++i) closest = std::min(closest, core_distance(cap, cloth.position(i)));
  EXPECT_GT(closest, R + th - 9.81 * h * h - 1e-6);
  // the middle particle (10, 10) lies on the top of the side
  const Vec3 mid = cloth.position(10 * 21 + 10);
  EXPECT_NEAR(mid.y, 0.5 + R + th, 2e-3);
}
