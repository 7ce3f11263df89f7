// Zero allocations per tick in steady state: refilling a collision world with as many
// colliders as before, and stepping particles and a soft body against it.
#include <gtest/gtest.h>

#include <vector>

#include "pba/collide.h"
#include "pba/particles.h"
#include "pba/soft.h"

#include "alloc_count.h"  // counts every operator new in this program

using pba::test_support::g_allocations;

TEST(CollisionWorldAlloc, RefillAndStepNeverAllocate) {
  // 300 colliders: more than the particle step used to accept
  std::vector<pba::Collider> shapes;
  shapes.push_back(pba::Collider::plane({0, 1, 0}, 0.0, {.restitution = 0.5, .friction = 0.2}));
  for (int i = 0; i < 299; ++i)
    shapes.push_back(pba::Collider::sphere({0.1 * i - 15, 0.2, 0}, 0.05, {.restitution = 0.5}));
  pba::CollisionWorld cw;
  pba::ParticleSystem ps({.capacity = 512});
  for (int i = 0; i < 512; ++i) ps.spawn({.position = {0.06 * i - 15, 0.5 + 0.001 * i, 0}, .radius = 0.01});
  pba::SoftBody rope = pba::SoftBody::rope({.from = {-1, 0.5, 0}, .to = {1, 0.5, 0}, .segments = 40});
  auto tick = [&](int k) {
    cw.clear();
    for (std::size_t i = 0; i < shapes.size(); ++i) cw.add(shapes[i], static_cast<std::uint32_t>(i));
    ps.step(k / 120.0, 1 / 120.0, cw, {});
    rope.step(k / 120.0, 1 / 120.0, cw);
    ps.step(k / 120.0, 1 / 120.0, shapes, {});  // the span overload refills the system's own world
  };
  // warm up (the arrays grow), then count
  for (int k = 0; k < 10; ++k) tick(k);
  const long long before = g_allocations.load();
  for (int k = 10; k < 130; ++k) tick(k);
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(ps.contacts(), 0u);  // the particles reached the shapes
}
