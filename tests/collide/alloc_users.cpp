// Zero allocations per tick in steady state with hulls, meshes and compounds: refilling a
// collision world with them each tick (the compounds' parts too), and stepping particles
// (the fused kernel and the generic integrator path), a cloth and a rope against it.
#include <gtest/gtest.h>

#include <span>
#include <vector>

#include "pba/collide.h"
#include "pba/particles.h"
#include "pba/soft.h"
#include "users_shapes.h"

#include "alloc_count.h"  // counts every operator new in this program

using pba::test_support::g_allocations;
namespace tu = pba::test_users;

TEST(UsersAlloc, HullsMeshesAndCompoundsNeverAllocatePerTick) {
  const std::vector<pba::Collider> shapes = {
      pba::Collider::plane({0, 1, 0}, -2.0),
      tu::place(pba::ColliderShape::convex(tu::frustum_hull()), {-1.5, 0, 0}, {.restitution = 0.5}),
      tu::place(pba::ColliderShape::triangles(tu::grid_mesh(20, 0.1)), {0, 0, 0}, {.friction = 0.3}),
      tu::place(tu::compound_shape(tu::table_compound()), {1.5, 0, 0}, {.restitution = 0.2}),
  };
  pba::CollisionWorld cw;
  pba::ParticleSystem fused({.capacity = 600});
  pba::ParticleSystem generic({.capacity = 600, .method = pba::Method::Rk4});
  for (int i = 0; i < 600; ++i) {
    const pba::ParticleDef p{.position = {0.005 * i - 1.5, 0.3 + 0.002 * i, 0.1}, .radius = 0.01};
    fused.spawn(p);
    generic.spawn(p);
  }
  pba::SoftBody cloth = pba::SoftBody::cloth_grid({.origin = {-0.4, 0.3, -0.4}, .edge_u = {0.8, 0, 0},
                                                   .edge_v = {0, 0, 0.8}, .nx = 10, .ny = 10,
                                                   .pins = pba::ClothPins::None});
  pba::SoftBody rope = pba::SoftBody::rope({.from = {1.0, 0.4, 0}, .to = {2.0, 0.4, 0}, .segments = 20});
  auto tick = [&](int k) {
    cw.clear();
    for (std::size_t i = 0; i < shapes.size(); ++i) cw.add(shapes[i], static_cast<std::uint32_t>(i));
    fused.step(k / 120.0, 1 / 120.0, cw, {});
    generic.step(k / 120.0, 1 / 120.0, cw, {});
    cloth.step(k / 120.0, 1 / 120.0, cw);
    rope.step(k / 120.0, 1 / 120.0, cw);
  };
  // warm up (the arrays grow), then count
  for (int k = 0; k < 10; ++k) tick(k);
  const long long before = g_allocations.load();
  for (int k = 10; k < 130; ++k) tick(k);
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(fused.contacts(), 0u);  // the particles reached the shapes
  EXPECT_GT(generic.contacts(), 0u);
}
