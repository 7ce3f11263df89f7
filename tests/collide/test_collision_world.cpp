// The collision world and its point contact, through its clients: no cap on the number of
// shapes, the same bits from a world of many shapes as from each shape alone, flat forms
// that follow the colliders, and an Error naming the collider for a hull, mesh or
// compound without its body.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "pba/collide.h"
#include "pba/particles.h"
#include "pba/soft.h"
#include "pba/world.h"

#include "error_of.h"

namespace {

using pba::Collider;
using pba::CollisionWorld;
using pba::Vec3;
using pba::test_support::error_of;

// where particle j starts: 0.5 m above the top of sphere j (its surface 0.02 m above)
Vec3 start(std::size_t j) { return {static_cast<double>(j / 25), 0.3 + 0.02 + 0.5, static_cast<double>(j % 25)}; }

// 1000 spheres on a 40 x 25 grid, 1 m apart, radius 0.3 m, restitution 0.8
std::vector<Collider> sphere_grid() {
  std::vector<Collider> out;
  for (int i = 0; i < 40; ++i)
    for (int k = 0; k < 25; ++k)
      out.push_back(Collider::sphere({i * 1.0, 0.0, k * 1.0}, 0.3, {.restitution = 0.8, .friction = 0.0}));
  return out;
}

// one particle 0.5 m above the top of each sphere, at rest
pba::ParticleSystem drop_particles(std::size_t n) {
  pba::ParticleSystem ps({.capacity = n});
  for (std::size_t j = 0; j < n; ++j)
    ps.spawn({.position = start(j), .mass = 0.01, .radius = 0.02});
  return ps;
}

}  // namespace

// A thousand colliders (four times the old cap of 256) work: every particle dropped on
// its own sphere rebounds to e^2 h, and the result has the same bits as stepping each
// particle with only its own sphere (the other 999 never reach it), with the fused
// kernel's broad phase on and off.
TEST(CollisionWorld, ThousandCollidersGiveTheBitsOfEachAlone) {
  const std::vector<Collider> spheres = sphere_grid();
  ASSERT_EQ(spheres.size(), 1000u);
  CollisionWorld cw;
  for (std::size_t i = 0; i < spheres.size(); ++i) cw.add(spheres[i], static_cast<std::uint32_t>(i));
  ASSERT_EQ(cw.size(), 1000u);
  const double dt = 1.0 / 1000, h = 0.5, e = 0.8;
  const int steps = 620;  // the fall takes 0.32 s, the rebound 0.26 s up: one bounce, past its apex
  for (bool broad : {true, false}) {
    pba::ParticleSystem all = drop_particles(spheres.size());
    all.set_broad_phase(broad);
    std::vector<double> apex(spheres.size(), -1e9);
    std::vector<bool> bounced(spheres.size(), false);
    for (int s = 0; s < steps; ++s) {
      all.step(s * dt, dt, cw, {});
      for (std::size_t j = 0; j < all.size(); ++j) {
        if (all.velocity(j).y > 0) bounced[j] = true;
        if (bounced[j]) apex[j] = std::max(apex[j], all.position(j).y);
      }
    }
    // the rebound to e^2 h, less what semi-implicit Euler's path loses: its steps fall
    // with v_n = -g n dt while x_n lags the exact parabola by g dt t_n / 2, so at a given
    // drop the speed is short by dt / 2 of a metre of height per m/s (v^2 = 2 g d - g dt v
    // to first order), on the way down (v_in = sqrt(2 g h), then scaled by e^2) and on
    // the way up (v_out = e v_in); the response itself is exact for constant
    // acceleration. What is left is second order, O(g dt^2) = 1e-5 m, and float rounding
    // of positions near 1 m (1e-7 m).
    const double v_in = std::sqrt(2 * 9.81 * h), v_out = e * v_in;
    const double expected = e * e * (h - v_in * dt / 2) - v_out * dt / 2;
    for (std::size_t j = 0; j < spheres.size(); ++j) {
      ASSERT_TRUE(bounced[j]) << j;
      EXPECT_NEAR(apex[j] - 0.32, expected, 2e-5) << "particle " << j;
      EXPECT_NEAR(apex[j] - 0.32, e * e * h, 0.03 * e * e * h) << "particle " << j;  // the 3%
    }
    // the same bits as each particle with its own sphere alone (a sample of 20)
    for (std::size_t j = 0; j < spheres.size(); j += 50) {
      pba::ParticleSystem one({.capacity = 1});
      one.set_broad_phase(broad);
      one.spawn({.position = start(j), .mass = 0.01, .radius = 0.02});
      for (int s = 0; s < steps; ++s) one.step(s * dt, dt, std::span<const Collider>(&spheres[j], 1), {});
      EXPECT_EQ(one.position(0), all.position(j)) << j;
      EXPECT_EQ(one.velocity(0), all.velocity(j)) << j;
    }
  }
}

// The flat forms follow the colliders they were made from, in order, with their owners.
TEST(CollisionWorld, FlatFormsFollowTheColliders) {
  CollisionWorld cw;
  cw.add(Collider::plane({0, 2, 0}, 1.0, {.restitution = 0.25, .friction = 0.5}), 7);
  cw.add(Collider::box({1, 2, 3}, {0.1, 0.2, 0.3}), 9);
  ASSERT_EQ(cw.size(), 2u);
  EXPECT_EQ(cw.owners()[0], 7u);
  EXPECT_EQ(cw.owners()[1], 9u);
  // the plane 2y = 1 is y = 0.5 with a unit normal
  const auto& p = cw.flat_double()[0];
  EXPECT_EQ(p.type, pba::ShapeType::Plane);
  EXPECT_DOUBLE_EQ(p.n1y, 1.0);
  EXPECT_DOUBLE_EQ(p.d1, 0.5);
  EXPECT_FLOAT_EQ(cw.flat_float()[0].mu, 0.5f);
  EXPECT_TRUE(p.is_static);
  const auto& b = cw.flat_float()[1];
  EXPECT_EQ(b.type, pba::ShapeType::Box);
  EXPECT_FLOAT_EQ(b.c1z, 3.0f);
  EXPECT_FLOAT_EQ(b.hy, 0.2f);
  // replacing and clearing
  cw.set(1, Collider::sphere({0, 0, 0}, 2.0), "replacement");
  EXPECT_EQ(cw.flat_double()[1].type, pba::ShapeType::Sphere);
  EXPECT_EQ(cw.owners()[1], 9u);
  cw.clear();
  EXPECT_TRUE(cw.empty());
}

// Shapes without a point contact yet, and bad values, are refused with an Error that
// names the collider, at the collision world, at the particle and soft-body steps and
// at World::add_collider.
// finite doubles that the particle kernel's float form cannot hold are refused by field
TEST(CollisionWorld, RefusesCollidersThatOverflowTheFloatForm) {
  CollisionWorld cw;
  const Collider far = Collider::sphere({1e39, 0, 0}, 1.0);
  std::string msg = error_of([&] { cw.add(far, 0, "moon"); });
  EXPECT_NE(msg.find("moon.position"), std::string::npos) << msg;
  EXPECT_NE(msg.find("float"), std::string::npos) << msg;
  const Collider huge = Collider::box({0, 0, 0}, {1, 1e40, 1});
  EXPECT_NE(error_of([&] { cw.add(huge, 0, "wall"); }).find("wall.half_extents"), std::string::npos);
  pba::ParticleSystem ps;
  ps.spawn({.position = {0, 1, 0}});
  msg = error_of([&] { ps.step(0, 0.01, std::span<const Collider>(&far, 1), {}); });
  EXPECT_NE(msg.find("colliders[0].position"), std::string::npos) << msg;
  EXPECT_EQ(error_of([&] { cw.add(Collider::sphere({3e38, 0, 0}, 1.0), 0, "edge"); }), "");  // still a float
}

TEST(CollisionWorld, RefusesShapesWithoutTheirBodies) {
  // a hull with no polyhedron (every shape type collides; a hull needs its body)
  Collider hull;
  hull.shape.type = pba::ShapeType::Hull;
  CollisionWorld cw;
  EXPECT_NE(error_of([&] { cw.add(hull, 0, "the rock"); }).find("the rock.hull"), std::string::npos);
  EXPECT_TRUE(cw.empty());
  pba::ParticleSystem ps;
  ps.spawn({.position = {0, 1, 0}});
  const std::string particle_error = error_of([&] { ps.step(0, 0.01, std::span<const Collider>(&hull, 1), {}); });
  EXPECT_NE(particle_error.find("colliders[0].hull"), std::string::npos) << particle_error;
  pba::SoftBody rope = pba::SoftBody::rope({});
  EXPECT_NE(error_of([&] { rope.step(0, 0.01, std::span<const Collider>(&hull, 1)); }).find("colliders[0].hull"),
            std::string::npos);
  Collider bad = Collider::sphere({0, 0, 0}, -1.0);
  EXPECT_NE(error_of([&] { cw.add(bad, 0, "ball"); }).find("ball.radius"), std::string::npos);
  Collider pill;
  pill.shape.type = pba::ShapeType::Capsule;
  pill.shape.half_height = -0.5;
  EXPECT_NE(error_of([&] { cw.add(pill, 0, "pill"); }).find("pill.half_height"), std::string::npos);
  pba::World w;
  auto e = w.create_entity({.name = "post"});
  const std::string world_error =
      error_of([&] { w.add_collider(e, {.shape = {.type = pba::ShapeType::Mesh}}); });
  EXPECT_NE(world_error.find("'post'"), std::string::npos) << world_error;
}
