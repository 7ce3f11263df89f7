// Zero heap allocations in the per-query shape functions: bounds, support, ray casts,
// point distances and mesh queries, on every shape, once the shapes are built.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "alloc_count.h"
#include "pba/collide/shape.h"
#include "shape_gen.h"

namespace {

using namespace pba;
using pba::test_support::g_allocations;

TEST(CollideShapesAlloc, QueriesNeverAllocate) {
  // build every shape first (building allocates)
  std::vector<Vec3> cloud;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(0, 1);
  for (int i = 0; i < 300; ++i) cloud.push_back(glm::normalize(Vec3(g(rng), g(rng), g(rng))));
  const auto t = test_support::terrain(16, 6.0, [](double x, double z) { return 0.3 * std::sin(x + z); });
  ColliderShape comp;
  comp.type = ShapeType::Compound;
  comp.compound = CompoundShape::build({{ColliderShape::sphere(0.5), Pose{{-1, 0, 0}, {1, 0, 0, 0}}},
                                        {ColliderShape::box({0.5, 0.5, 0.5}), Pose{{1, 0, 0}, {1, 0, 0, 0}}}});
  const std::vector<ColliderShape> shapes = {ColliderShape::plane({0, 1, 0}, 0), ColliderShape::sphere(0.5),
                                             ColliderShape::box({0.3, 0.4, 0.5}), ColliderShape::capsule(0.5, 0.2),
                                             ColliderShape::convex(ConvexHull::build(cloud)),
                                             ColliderShape::triangles(TriangleMesh::build(t.vertices, t.triangles)),
                                             comp};
  std::vector<Vec3> probes;
  for (int i = 0; i < 200; ++i) probes.push_back(Vec3(g(rng), g(rng), g(rng)) * 2.0);
  // then query: not one allocation
  double sink = 0;
  const Pose pose{Vec3(0.1, 0.2, 0.3), glm::normalize(Quat(1, 0.2, 0.1, 0))};
  const long long before = g_allocations.load();
  for (const ColliderShape& s : shapes)
    for (const Vec3& x : probes) {
      const Aabb b = bounds(s, pose);
      if (s.type != ShapeType::Plane) sink += b.area();  // a plane's bounds are infinite
      if (s.is_convex()) sink += support(s, x).x;
      const RayHit h = ray_cast(s, pose, Ray{x, glm::normalize(-x + Vec3(0.01)), 10});
      sink += h.distance;
      sink += point_distance(s, pose, x).distance;
      if (s.type == ShapeType::Mesh) s.mesh->query(Aabb{x - Vec3(0.5), x + Vec3(0.5)}, [&](std::uint32_t k) { sink += k; });
    }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
