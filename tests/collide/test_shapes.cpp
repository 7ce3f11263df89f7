// Tests for pba/collide/shape.h: factories and validation, bounds, support functions,
// the box hull's half-edge structure and hill-climbing support, mass properties in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "error_of.h"
#include "hull_check.h"
#include "pba/collide/shape.h"

namespace {

using namespace pba;
using pba::test_support::error_of;
using pba::test_support::expect_valid_hull;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

Quat random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0, 1);
  return glm::normalize(Quat(g(rng), g(rng), g(rng), g(rng)));
}
Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0, 1);
  return glm::normalize(Vec3(g(rng), g(rng), g(rng)));
}

// ---------------------------------------------------------------------------
// factories and bad input

TEST(CollideShapes, FactoriesRefuseBadValuesByName) {
  EXPECT_EQ(error_of([] { ColliderShape::sphere(0); }), "ColliderShape::sphere.radius: must be finite and > 0, got 0");
  EXPECT_EQ(error_of([] { ColliderShape::sphere(-1); }), "ColliderShape::sphere.radius: must be finite and > 0, got -1");
  EXPECT_EQ(error_of([] { ColliderShape::sphere(kNaN); }), "ColliderShape::sphere.radius: must be finite and > 0, got nan");
  EXPECT_EQ(error_of([] { ColliderShape::box({1, 0, 1}); }),
            "ColliderShape::box.half_extents.y: must be finite and > 0, got 0");
  EXPECT_EQ(error_of([] { ColliderShape::box({1, 1, -2}); }),
            "ColliderShape::box.half_extents.z: must be finite and > 0, got -2");
  EXPECT_EQ(error_of([] { ColliderShape::box({kInf, 1, 1}); }),
            "ColliderShape::box.half_extents.x: must be finite and > 0, got inf");
  EXPECT_EQ(error_of([] { ColliderShape::capsule(-0.5, 1); }),
            "ColliderShape::capsule.half_height: must be finite and >= 0, got -0.5");
  EXPECT_EQ(error_of([] { ColliderShape::capsule(0.5, 0); }),
            "ColliderShape::capsule.radius: must be finite and > 0, got 0");
  EXPECT_EQ(error_of([] { ColliderShape::capsule(kNaN, 1); }),
            "ColliderShape::capsule.half_height: must be finite and >= 0, got nan");
  EXPECT_EQ(error_of([] { ColliderShape::convex(nullptr); }),
            "ColliderShape::convex.hull: must not be null for a hull shape");
  EXPECT_EQ(error_of([] { ColliderShape::triangles(nullptr); }),
            "ColliderShape::triangles.mesh: must not be null for a mesh shape");
  EXPECT_EQ(error_of([] { ColliderShape::plane({0, 0, 0}, 1); }),
            "ColliderShape::plane normal: must be non-zero, got (0, 0, 0)");
  EXPECT_NE(error_of([] { ColliderShape::plane({0, kNaN, 0}, 1); }).find("ColliderShape::plane normal: must be finite"),
            std::string::npos);
  EXPECT_NE(error_of([] { ColliderShape::plane({0, 1, 0}, kInf); }).find("ColliderShape::plane offset: must be finite"),
            std::string::npos);
  // a capsule of zero height is a sphere, and valid
  EXPECT_EQ(error_of([] { ColliderShape::capsule(0, 1); }), "");
  ColliderShape c;
  c.type = ShapeType::Compound;
  EXPECT_EQ(error_of([&] { c.validate("collider[3]"); }), "collider[3].compound: must not be null for a compound shape");
  EXPECT_EQ(error_of([] { ConvexHull::box({1, 1, 0}); }), "ConvexHull::box half_extents.z: must be finite and > 0, got 0");
}

TEST(CollideShapes, PlaneIsNormalised) {
  const ColliderShape p = ColliderShape::plane({0, 2, 0}, 3);
  EXPECT_EQ(p.normal, Vec3(0, 1, 0));
  EXPECT_EQ(p.offset, 1.5);
}

TEST(CollideShapes, CompoundRefusesPlanesMeshesAndEmptyLists) {
  EXPECT_EQ(error_of([] { CompoundShape::build({}, "table"); }),
            "table.children: a compound needs at least one child, got 0");
  EXPECT_EQ(error_of([] { CompoundShape::build({{ColliderShape::plane({0, 1, 0}, 0), {}}}, "table"); }),
            "table.children[0].shape.type: a compound child must be a sphere, box, capsule, hull or compound, got a plane");
  ColliderShape bad_sphere;
  bad_sphere.type = ShapeType::Sphere;
  bad_sphere.radius = -1;
  EXPECT_EQ(error_of([&] { CompoundShape::build({{ColliderShape::sphere(1), {}}, {bad_sphere, {}}}, "table"); }),
            "table.children[1].shape.radius: must be finite and > 0, got -1");
  EXPECT_NE(error_of([] {
              CompoundShape::build({{ColliderShape::sphere(1), Pose{{kNaN, 0, 0}, {1, 0, 0, 0}}}}, "table");
            }).find("table.children[0].pose.position: must be finite"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              CompoundShape::build({{ColliderShape::sphere(1), Pose{{0, 0, 0}, {2, 0, 0, 0}}}}, "table");
            }).find("table.children[0].pose.rotation"),
            std::string::npos);
}

// ---------------------------------------------------------------------------
// the box hull and support

TEST(CollideShapes, BoxHullHasAValidHalfEdgeStructure) {
  const auto h = ConvexHull::box({1, 2, 3});
  EXPECT_EQ(h->vertices().size(), 8u);
  EXPECT_EQ(h->edges().size(), 24u);
  EXPECT_EQ(h->faces().size(), 6u);
  expect_valid_hull(*h, 1e-15);
  // the faces are the six axis planes at the half extents
  for (const auto& f : h->faces()) {
    int axis = 0;
    for (int i = 0; i < 3; ++i)
      if (std::abs(f.normal[i]) == 1) axis = i;
    EXPECT_EQ(std::abs(f.normal[axis]), 1.0);
    EXPECT_EQ(f.offset, Vec3(1, 2, 3)[axis]);
  }
  EXPECT_EQ(h->volume(), 48.0);
  EXPECT_EQ(h->centroid(), Vec3(0.0));
  EXPECT_EQ(h->bounds().lo, Vec3(-1, -2, -3));
  EXPECT_EQ(h->bounds().hi, Vec3(1, 2, 3));
}

TEST(CollideShapes, SupportOfEveryConvexShapeIsTheFarthestPoint) {
  // each shape's support value equals its closed-form support function h(d) = max_x d . x:
  // sphere r|d|, box sum h_i |d_i|, capsule hh |d_y| + r |d|; ties aside the point is unique
  std::mt19937_64 rng(7);
  const auto hull = ConvexHull::box({0.3, 0.7, 1.1});
  const ColliderShape sphere = ColliderShape::sphere(0.8), box = ColliderShape::box({0.3, 0.7, 1.1}),
                      capsule = ColliderShape::capsule(0.6, 0.25), hs = ColliderShape::convex(hull);
  for (int k = 0; k < 1000; ++k) {
    const Vec3 d = random_unit(rng) * (0.1 + k * 0.01);
    const double len = glm::length(d);
    EXPECT_NEAR(glm::dot(support(sphere, d), d), 0.8 * len, 1e-12 * len);
    const double hb = 0.3 * std::abs(d.x) + 0.7 * std::abs(d.y) + 1.1 * std::abs(d.z);
    EXPECT_NEAR(glm::dot(support(box, d), d), hb, 1e-12 * len);
    EXPECT_NEAR(glm::dot(support(hs, d), d), hb, 1e-12 * len);
    EXPECT_NEAR(glm::dot(support(capsule, d), d), 0.6 * std::abs(d.y) + 0.25 * len, 1e-12 * len);
  }
  EXPECT_EQ(core_radius(sphere), 0.8);
  EXPECT_EQ(core_radius(capsule), 0.25);
  EXPECT_EQ(core_radius(box), 0.0);
  EXPECT_EQ(core_radius(hs), 0.0);
}

TEST(CollideShapes, BoundsContainTheShapeAndTouchIt) {
  // the world bounds are tight: along each world axis the support point touches them
  std::mt19937_64 rng(11);
  const ColliderShape shapes[] = {ColliderShape::sphere(0.8), ColliderShape::box({0.3, 0.7, 1.1}),
                                  ColliderShape::capsule(0.6, 0.25),
                                  ColliderShape::convex(ConvexHull::box({0.5, 0.2, 0.9}))};
  for (const ColliderShape& s : shapes) {
    for (int k = 0; k < 50; ++k) {
      const Pose p{Vec3(std::uniform_real_distribution<double>(-5, 5)(rng), 1, -2), random_rotation(rng)};
      const Aabb b = bounds(s, p);
      for (int i = 0; i < 3; ++i) {
        Vec3 axis(0.0);
        axis[i] = 1;
        const Vec3 hi = apply(p, support(s, glm::conjugate(p.rotation) * axis));
        const Vec3 lo = apply(p, support(s, glm::conjugate(p.rotation) * -axis));
        EXPECT_NEAR(b.hi[i], hi[i], 1e-12) << to_string(s.type);
        EXPECT_NEAR(b.lo[i], lo[i], 1e-12) << to_string(s.type);
      }
    }
  }
  // a plane's bounds: the half-space below it
  const Aabb pb = bounds(ColliderShape::plane({0, 1, 0}, 2), Pose{{0, 1, 0}, {1, 0, 0, 0}});
  EXPECT_EQ(pb.hi.y, 3.0);
  EXPECT_EQ(pb.lo.y, -kInf);
  EXPECT_EQ(pb.hi.x, kInf);
  // a compound's bounds: the union of its children
  const auto comp = CompoundShape::build({{ColliderShape::sphere(1), Pose{{2, 0, 0}, {1, 0, 0, 0}}},
                                          {ColliderShape::box({1, 2, 3}), Pose{{-2, 0, 0}, {1, 0, 0, 0}}}});
  EXPECT_EQ(comp->local_bounds.lo, Vec3(-3, -2, -3));
  EXPECT_EQ(comp->local_bounds.hi, Vec3(3, 2, 3));
}

}  // namespace
