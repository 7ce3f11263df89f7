// Zero allocations per frame in steady state for the world queries: rebuilding the query
// world from a refilled collision world of the same size (a refit), and every kind of query
// on it (closest, any, all and batched rays; sphere and convex casts; overlaps; distances).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "pba/collide.h"

#include "alloc_count.h"  // counts every operator new in this program

using pba::test_support::g_allocations;

TEST(QueryAlloc, RebuildAndQueryNeverAllocate) {
  // 1000 boxes, spheres and capsules in a 16 m cube and a ground plane, all moving
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> pos(0, 16), step(-0.05, 0.05), u(-1, 1);
  std::vector<pba::Collider> shapes;
  shapes.push_back(pba::Collider::plane({0, 1, 0}, -0.5));
  for (int i = 0; i < 1000; ++i) {
    const pba::Vec3 p(pos(rng), pos(rng), pos(rng));
    pba::Collider c = i % 3 == 0   ? pba::Collider::box(p, pba::Vec3(0.5))
                      : i % 3 == 1 ? pba::Collider::sphere(p, 0.5)
                                   : pba::Collider::box(p, pba::Vec3(0.2, 0.6, 0.3));
    if (i % 3 == 2) c.shape = pba::ColliderShape::capsule(0.5, 0.25);
    shapes.push_back(c);
  }
  std::vector<pba::Ray> rays(64);
  std::vector<pba::QueryRayHit> hits(64), all(32);
  std::uint32_t overlaps[32];
  const auto hull = pba::ConvexHull::box(pba::Vec3(0.3, 0.2, 0.4));
  const pba::ColliderShape probe_box = pba::ColliderShape::box(pba::Vec3(0.3)),
                           probe_hull = pba::ColliderShape::convex(hull);
  const auto skip_even = [](std::uint32_t i, std::uint32_t) { return i % 2 == 1; };
  const pba::QueryFilter filter{.layer = 1, .mask = ~0ull, .ignore_owner = 5, .accept = pba::QueryPredicate::of(skip_even)};
  pba::CollisionWorld cw;
  pba::QueryWorld q;
  std::size_t found = 0;
  auto frame = [&]() {
    // move, refill, rebuild (a refit)
    cw.clear();
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      if (i > 0) shapes[i].begin.position = shapes[i].end.position += pba::Vec3(step(rng), step(rng), step(rng));
      cw.add(shapes[i], static_cast<std::uint32_t>(i));
    }
    q.build(cw);
    // every query
    for (pba::Ray& r : rays) r = {pba::Vec3(pos(rng), pos(rng), pos(rng)), pba::Vec3(u(rng), u(rng), u(rng)), 5};
    found += q.ray_cast(rays, hits);
    found += q.ray_cast(rays[0], filter).hit;
    found += q.ray_cast_any(rays[1]).hit;
    found += q.ray_cast_all(rays[2], all);
    const pba::Pose at{pba::Vec3(pos(rng), pos(rng), pos(rng)), pba::Quat(1, 0, 0, 0)};
    found += q.sphere_cast({at.position, pba::Vec3(0, 0, 1), 10}, 0.25).hit;
    found += q.shape_cast(probe_box, at, pba::Vec3(1, 0, 0), 10).hit;
    found += q.shape_cast(probe_hull, at, pba::Vec3(0, -1, 0), 10, filter).hit;
    found += q.overlap(probe_box, at, overlaps);
    found += q.overlap_bounds({at.position - 2.0, at.position + 2.0}, overlaps);
    found += q.closest_point(at.position, 3).found;
    found += q.closest_shape(probe_hull, at, 3).found;
  };
  // warm up (the arrays and the tree grow), then count
  for (int k = 0; k < 5; ++k) frame();
  const long long before = g_allocations.load();
  for (int k = 0; k < 100; ++k) frame();
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(found, 1000u);  // the queries found things
}
