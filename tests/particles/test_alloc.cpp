// Zero allocations per step in steady state, counted by a replaced global operator new.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "pba/particles.h"
#include "pba/world.h"

#include "alloc_count.h"  // counts every operator new in this program

using pba::test_support::g_allocations;

namespace {

// a world with every kind of component: emitter in steady state, moving colliders,
// forcers, a constraint; then count allocations over many ticks
pba::World busy_world(pba::Method m) {
  pba::WorldDef def;
  def.stepper.fixed_dt = 1.0 / 120;
  def.particles.method = m;
  def.particles.capacity = 4096;
  def.particles.forces.quadratic_drag = 0.001;
  def.particles.forces.wind = {.velocity = {1, 0, 0}, .gust = 0.5, .gust_period = 0.4, .seed = 2};
  pba::World w(def);
  auto ground = w.create_entity({.name = "ground"});
  w.add_collider(ground, {.shape = {.type = pba::ShapeType::Plane}, .material = {.restitution = 0.4, .friction = 0.3}});
  auto paddle = w.create_entity({.name = "paddle", .pose = {.position = {0, 0.5, 0}}});
  w.add_collider(paddle, {.shape = {.type = pba::ShapeType::Box, .half_extents = {0.3, 0.05, 0.3}}});
  w.add_kinematic(paddle, {.path = pba::PathType::Circular, .center = {0, 0.5, 0}, .radius = 0.5});
  auto ball = w.create_entity({.name = "ball", .pose = {.position = {0, 1.5, 0}}});
  w.add_collider(ball, {.shape = {.type = pba::ShapeType::Sphere, .radius = 0.2}});
  // a forcer's edge is a discontinuous force where implicit Euler's Newton solve may fail
  // and fall back through the integrator's exception (which allocates): not steady state
  if (m != pba::Method::ImplicitEuler) {
    auto fan = w.create_entity({.name = "fan", .pose = {.position = {0, 1, 0}}});
    w.add_forcer(fan, {.kind = pba::ForcerKind::Vortex, .shape = pba::ForcerShape::Cylinder, .radius = 1,
                       .half_height = 1, .strength = 0.002});
  }
  auto source = w.create_entity({.name = "source", .pose = {.position = {0, 1, 0}}});
  w.add_emitter(source, {.spread = 0.6, .speed = 3, .rate = 600, .lifetime = 1.5, .lifetime_jitter = 0.3,
                         .mass = 0.001, .radius = 0.01});
  auto a = w.create_entity({.name = "a", .pose = {.position = {2, 1, 0}}});
  auto b = w.create_entity({.name = "b", .pose = {.position = {2.5, 1, 0}}});
  w.add_particle(a, {.radius = 0.05});
  w.add_particle(b, {.radius = 0.05});
  w.add_constraint(a, {.other = b});
  return w;
}

TEST(Allocations, NonePerStepInSteadyState) {
  for (pba::Method m : {pba::Method::SemiImplicitEuler, pba::Method::Rk4, pba::Method::PositionVerlet,
                        pba::Method::ImplicitEuler}) {
    pba::World w = busy_world(m);
    // warm up past the longest lifetime so births and deaths balance
    for (int i = 0; i < 400; ++i) w.step();
    ASSERT_GT(w.particles().size(), 500u);
    const long long before = g_allocations.load();
    for (int i = 0; i < 300; ++i) w.step();
    EXPECT_EQ(g_allocations.load() - before, 0) << pba::name(m);
    // the counter works: a direct call of operator new (new-expressions may be elided)
    const long long probe = g_allocations.load();
    void* volatile p = ::operator new(64);
    ::operator delete(p);
    EXPECT_EQ(g_allocations.load() - probe, 1);
  }
}

}  // namespace
