// Zero allocations per step in steady state, counted by a replaced global operator new.
#include <gtest/gtest.h>

#include <vector>

#include "alloc_count.h"  // counts every operator new in this program
#include "pba/soft.h"
#include "pba/world.h"

using pba::test_support::g_allocations;

namespace {

// runs `steps` steps after a warm-up and returns the allocations made during them
long long allocations_per_run(pba::SoftBody& b, std::span<const pba::Collider> colliders, int steps,
                              bool drag = false) {
  double t = 0;
  for (int i = 0; i < 20; ++i, t += 1.0 / 60) b.step(t, 1.0 / 60, colliders);
  const long long before = g_allocations.load();
  for (int i = 0; i < steps; ++i, t += 1.0 / 60) {
    if (drag && b.grabbed() != pba::kNoParticle) b.move_grab(b.position(b.grabbed()) + pba::Vec3(0.01, 0, 0));
    b.step(t, 1.0 / 60, colliders);
  }
  return g_allocations.load() - before;
}

}  // namespace

TEST(SoftAllocations, NonePerXpbdStep) {
  // a tearing cloth in gusting wind, grabbed and dragged, over a ball and a box on the ground
  pba::SoftBodyDef d;
  d.substeps = 6;
  d.iterations = 2;
  d.spring_damping = 0.01;
  d.tear_strain = 0.3;
  d.aero = {.drag = 1, .lift = 0.3};
  d.forces.wind = {.velocity = {3, 0, 0}, .gust = 1, .gust_period = 0.3};
  d.forces.linear_drag = 0.001;
  pba::SoftBody c = pba::SoftBody::cloth_grid({.origin = {-0.5, 1.2, -0.5}, .nx = 20, .ny = 20}, d);
  c.grab(399, c.position(399));
  const std::vector<pba::Collider> cs = {pba::Collider::sphere({0, 0.6, 0}, 0.3),
                                         pba::Collider::plane({0, 1, 0}, 0, {.friction = 0.4}),
                                         pba::Collider::box({0.6, 0.2, 0}, {0.2, 0.2, 0.2})};
  EXPECT_EQ(allocations_per_run(c, cs, 200, true), 0);
  EXPECT_GT(c.broken_constraints(), 0u);  // tearing happened during the counted steps or before
  // a jelly with volume constraints
  pba::SoftBodyDef j;
  j.stretch_compliance = 1e-4;
  pba::SoftBody jelly = pba::SoftBody::jelly_box({.nx = 3, .ny = 3, .nz = 3}, j);
  EXPECT_EQ(allocations_per_run(jelly, cs, 200), 0);
}

TEST(SoftAllocations, NonePerMassSpringStep) {
  for (pba::Method m : {pba::Method::ExplicitEuler, pba::Method::SemiImplicitEuler, pba::Method::PositionVerlet,
                        pba::Method::VelocityVerlet, pba::Method::Rk4, pba::Method::ImplicitEuler}) {
    pba::SoftBodyDef d;
    d.solver = pba::SoftSolver::MassSpring;
    d.method = m;
    d.substeps = 4;
    d.spring_damping = 0.05;
    // soft springs and velocity damping so that even explicit Euler stays bounded: its
    // amplification |1 + h (-c + i omega)|^2 <= 1 needs c >= omega^2 h / 2 = 8.5 1/s
    // for the fastest mode (4 sqrt(k/m) = 63 rad/s at h = 1/240 s)
    d.stretch_stiffness = 10;
    d.shear_stiffness = 10;
    d.damping = 10;
    d.aero = {.drag = 1};
    pba::SoftBody c = pba::SoftBody::cloth_grid({.nx = 5, .ny = 5}, d);
    const pba::Collider ground = pba::Collider::plane({0, 1, 0}, 0.8);
    EXPECT_EQ(allocations_per_run(c, std::span(&ground, 1), 100), 0) << pba::name(m);
  }
}

// Through the World: the SoftSystem steps bodies with the world's colliders each tick.
TEST(SoftAllocations, NonePerWorldTick) {
  pba::World w;
  const pba::EntityId ground = w.create_entity({.name = "ground"});
  w.add_collider(ground, {.shape = {.type = pba::ShapeType::Plane}, .material = {.friction = 0.3}});
  const pba::EntityId cloth = w.create_entity({.name = "cloth"});
  pba::soft_system(w).add(w, cloth, pba::SoftBody::cloth_grid({.origin = {-0.5, 0.8, -0.5}, .nx = 12, .ny = 12,
                                                                .pins = pba::ClothPins::None}));
  const pba::EntityId rope = w.create_entity({.name = "rope"});
  pba::soft_system(w).add(w, rope, pba::SoftBody::rope({.segments = 10}));
  for (int i = 0; i < 30; ++i) w.step();
  const long long before = g_allocations.load();
  for (int i = 0; i < 200; ++i) w.step();
  EXPECT_EQ(g_allocations.load() - before, 0);
}

// Tethers (on by default, off in the tearing cloth above): re-anchoring after unpin()
// and grab() writes preallocated columns, so stepping through pin changes allocates nothing.
TEST(SoftAllocations, NonePerTetheredStepThroughPinChanges) {
  pba::SoftBodyDef d;
  d.substeps = 4;
  pba::SoftBody c = pba::SoftBody::cloth_grid({.nx = 16, .ny = 16}, d);
  double t = 0;
  for (int i = 0; i < 20; ++i, t += 1.0 / 60) c.step(t, 1.0 / 60);
  const long long before = g_allocations.load();
  for (int i = 0; i < 100; ++i, t += 1.0 / 60) {
    if (i == 10) c.unpin(3);
    if (i == 30) c.grab(255, c.position(255));
    if (i == 50) c.release();
    if (i == 70) c.pin(3);
    c.step(t, 1.0 / 60);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  // a solid is not a convex sheet: its tethers run along its edges (Dijkstra's scratch
  // is sized at build)
  pba::SoftBody jelly = pba::SoftBody::jelly_box({.nx = 3, .ny = 3, .nz = 3}, d);
  for (int i = 0; i < 5; ++i, t += 1.0 / 60) jelly.step(t, 1.0 / 60);
  const long long before_jelly = g_allocations.load();
  for (int i = 0; i < 60; ++i, t += 1.0 / 60) {
    if (i == 10) jelly.grab(63, jelly.position(63));
    if (i == 20) jelly.pin(0);
    if (i == 40) jelly.release();
    jelly.step(t, 1.0 / 60);
  }
  EXPECT_EQ(g_allocations.load() - before_jelly, 0);
}
