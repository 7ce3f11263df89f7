// Tests for pba/collide/shape.h: factories and validation, bounds, support functions,
// the box hull's half-edge structure and hill-climbing support, mass properties in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "error_of.h"
#include "pba/collide/shape.h"
#include "shape_checks.h"

namespace {

using namespace pba;
using namespace pba::test_support;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();


// ---------------------------------------------------------------------------
// factories and bad input

TEST(CollideShapes, FactoriesRefuseBadValuesByName) {
  EXPECT_EQ(error_of([] { ColliderShape::sphere(0); }), "ColliderShape::sphere.radius: must be finite and > 0, got 0");
  EXPECT_EQ(error_of([] { ColliderShape::sphere(-1); }),
            "ColliderShape::sphere.radius: must be finite and > 0, got -1");
  EXPECT_EQ(error_of([] { ColliderShape::sphere(kNaN); }),
            "ColliderShape::sphere.radius: must be finite and > 0, got nan");
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
  EXPECT_EQ(error_of([&] { c.validate("collider[3]"); }),
            "collider[3].compound: must not be null for a compound shape");
  EXPECT_EQ(error_of([] { ConvexHull::box({1, 1, 0}); }),
            "ConvexHull::box half_extents.z: must be finite and > 0, got 0");
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
            "table.children[0].shape.type: a compound child must be a sphere, box, capsule, hull or compound, "
            "got a plane");
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

// a child is held to the float range every other shape's sizes and poses are held to (the
// bounds, queries and contact rows carry them as floats): beyond it, refused by name; at its
// rim (the largest float), taken
TEST(CollideShapes, CompoundRefusesChildrenBeyondAFloat) {
  const double fmax = std::numeric_limits<float>::max();
  const Pose far{{0, -1e300, 0}, {1, 0, 0, 0}};
  EXPECT_EQ(error_of([&] { CompoundShape::build({{ColliderShape::sphere(1), {}}, {ColliderShape::sphere(1), far}}, "table"); }),
            "table.children[1].pose.position: must fit a float (|component| <= 3.4028234663852886e+38), got (0, -1e+300, 0)");
  EXPECT_EQ(error_of([] { CompoundShape::build({{ColliderShape::sphere(1e200), {}}}, "table"); }),
            "table.children[0].shape.radius: must fit a float (|v| <= 3.4028234663852886e+38), got 1e+200");
  EXPECT_EQ(error_of([] { CompoundShape::build({{ColliderShape::box({1, 1e39, 1}), {}}}, "table"); }),
            "table.children[0].shape.half_extents: must fit a float (|component| <= 3.4028234663852886e+38), got (1, 1e+39, 1)");
  EXPECT_EQ(error_of([] { CompoundShape::build({{ColliderShape::capsule(1e39, 1), {}}}, "table"); }),
            "table.children[0].shape.half_height: must fit a float (|v| <= 3.4028234663852886e+38), got 1e+39");
  // the rim is taken, as a collider's is
  const auto rim = CompoundShape::build({{ColliderShape::sphere(fmax), Pose{{fmax, 0, 0}, {1, 0, 0, 0}}}}, "table");
  EXPECT_EQ(rim->local_bounds.hi.x, 2 * fmax);
  EXPECT_EQ(rim->local_bounds.lo.x, 0.0);
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
  // hulls of up to 64 vertices take every placed vertex's extremes, larger ones climb: both
  // hold every vertex placed as the narrow phase places it (apply(), to the bit), and touch
  // the farthest vertex along each axis placed by another route, brute force over the vertices
  // turned by the rotation's matrix (a pyramid of five; 100 points on a sphere, every one a
  // vertex). The two routes round differently: each world coordinate (under 8 m here) is a few
  // roundings from the exact one either way, each at most half an ulp (2 eps at 4-8 m), so 16
  // roundings, 64 eps, bound their difference (seen: under 6 eps); a bound off by a rounding
  // of its own would still pass, one grown or shrunk by 1e-13 m would not
  const double tol = 64 * std::numeric_limits<double>::epsilon();
  std::vector<Vec3> ball;
  for (int k = 0; k < 100; ++k) {
    const double z = 1 - (2 * k + 1) / 100.0, phi = 2.399963229728653 * k;
    ball.push_back(0.7 * Vec3(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z));
  }
  const std::vector<Vec3> pyramid{{-0.5, 0, -0.5}, {0.5, 0, -0.5}, {0.5, 0, 0.5}, {-0.5, 0, 0.5}, {0, 0.8, 0}};
  for (const auto& points : {pyramid, ball}) {
    const auto h = ConvexHull::build(points);
    ASSERT_EQ(h->vertices().size(), points.size());
    const ColliderShape s = ColliderShape::convex(h);
    for (int k = 0; k < 50; ++k) {
      const Pose p{Vec3(std::uniform_real_distribution<double>(-5, 5)(rng), 1, -2), random_rotation(rng)};
      const Aabb b = bounds(s, p);
      const Mat3 turn = glm::mat3_cast(p.rotation);
      Vec3 lo(INFINITY), hi(-INFINITY);
      for (const Vec3& v : h->vertices()) {
        const Vec3 x = apply(p, v);
        for (int i = 0; i < 3; ++i) EXPECT_TRUE(b.lo[i] <= x[i] && x[i] <= b.hi[i]) << h->vertices().size();
        const Vec3 y = turn * v + p.position;
        lo = glm::min(lo, y), hi = glm::max(hi, y);
      }
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(b.lo[i], lo[i], tol) << h->vertices().size();
        EXPECT_NEAR(b.hi[i], hi[i], tol) << h->vertices().size();
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

namespace {

using namespace pba;
using namespace pba::test_support;


// ---------------------------------------------------------------------------
// mass properties (closed forms; 1e-12 relative is a few hundred roundings)

TEST(CollideMass, SphereAndBoxClosedForms) {
  const MassProperties s = mass_properties(ColliderShape::sphere(0.3), 1000);
  const double m = 1000 * 4.0 / 3.0 * kPi * 0.027;
  EXPECT_NEAR(s.mass, m, 1e-12 * m);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(s.inertia[i][i], 0.4 * m * 0.09, 1e-12 * m * 0.09);
  EXPECT_EQ(s.inertia[0][1], 0.0);
  // box with edges a, b, c: I_xx = m (b^2 + c^2) / 12
  const MassProperties b = mass_properties(ColliderShape::box({0.5, 1, 1.5}), 2);
  const double mb = 2 * 1 * 2 * 3;
  EXPECT_NEAR(b.mass, mb, 1e-12 * mb);
  EXPECT_NEAR(b.inertia[0][0], mb * (4 + 9) / 12, 1e-12 * mb);
  EXPECT_NEAR(b.inertia[1][1], mb * (1 + 9) / 12, 1e-12 * mb);
  EXPECT_NEAR(b.inertia[2][2], mb * (1 + 4) / 12, 1e-12 * mb);
  // the box hull agrees with the box
  const MassProperties bh = mass_properties(ColliderShape::convex(ConvexHull::box({0.5, 1, 1.5})), 2);
  EXPECT_NEAR(bh.mass, b.mass, 1e-12 * mb);
  expect_mat_near(bh.inertia, b.inertia, 1e-12);
}

TEST(CollideMass, CapsuleEqualsItsSliceIntegral) {
  // independent reference: integrate disc slices along the axis. A slice at height y of
  // radius rho has area pi rho^2 and contributes pi rho^2 y^2 + pi rho^4 / 4 to I_xx and
  // pi rho^4 / 2 to I_yy; rho^2 is constant on the cylinder and r^2 - (y - hh)^2 on a cap,
  // so the integrands are polynomials of degree <= 4 and 3-point Gauss-Legendre is exact
  for (const auto& [hh, r] : {std::pair{0.7, 0.2}, std::pair{0.0, 0.5}, std::pair{2.0, 1.5}}) {
    double vol = 0, ixx = 0, iyy = 0;
    auto integrate = [&](double a, double b, auto rho2) {
      const double x[3] = {-std::sqrt(0.6), 0, std::sqrt(0.6)}, w[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
      for (int k = 0; k < 3; ++k) {
        const double y = 0.5 * (a + b) + 0.5 * (b - a) * x[k], s = 0.5 * (b - a) * w[k], p = rho2(y);
        vol += s * kPi * p;
        ixx += s * (kPi * p * y * y + kPi * p * p / 4);
        iyy += s * kPi * p * p / 2;
      }
    };
    integrate(-hh - r, -hh, [&](double y) { return r * r - (y + hh) * (y + hh); });
    if (hh > 0) integrate(-hh, hh, [&](double) { return r * r; });
    integrate(hh, hh + r, [&](double y) { return r * r - (y - hh) * (y - hh); });
    const MassProperties c = mass_properties(ColliderShape::capsule(hh, r), 3);
    EXPECT_NEAR(c.volume, vol, 1e-12 * vol);
    EXPECT_NEAR(c.mass, 3 * vol, 3e-12 * vol);
    EXPECT_NEAR(c.inertia[0][0], 3 * ixx, 3e-12 * ixx);
    EXPECT_NEAR(c.inertia[2][2], 3 * ixx, 3e-12 * ixx);
    EXPECT_NEAR(c.inertia[1][1], 3 * iyy, 3e-12 * iyy);
    EXPECT_EQ(c.center, Vec3(0.0));
  }
  // zero height is the sphere
  const MassProperties c0 = mass_properties(ColliderShape::capsule(0, 0.5), 1);
  const MassProperties s0 = mass_properties(ColliderShape::sphere(0.5), 1);
  EXPECT_NEAR(c0.mass, s0.mass, 1e-15);
  expect_mat_near(c0.inertia, s0.inertia, 1e-14);
}

TEST(CollideMass, CompoundOfTwoBoxesByTheParallelAxisTheorem) {
  // two unit cubes (m = 1 each) at x = -1 and x = +2: centre at x = 0.5; about the common
  // centre I_xx = 2 (1/6), I_yy = I_zz = 2 (1/6) + 1 (1.5^2) + 1 (1.5^2)
  const ColliderShape cube = ColliderShape::box({0.5, 0.5, 0.5});
  ColliderShape c;
  c.type = ShapeType::Compound;
  c.compound = CompoundShape::build({{cube, Pose{{-1, 0, 0}, {1, 0, 0, 0}}}, {cube, Pose{{2, 0, 0}, {1, 0, 0, 0}}}});
  const MassProperties mp = mass_properties(c, 1);
  EXPECT_NEAR(mp.mass, 2, 1e-15);
  EXPECT_NEAR(mp.center.x, 0.5, 1e-15);
  EXPECT_NEAR(mp.inertia[0][0], 2.0 / 6, 1e-14);
  EXPECT_NEAR(mp.inertia[1][1], 2.0 / 6 + 4.5, 1e-14);
  EXPECT_NEAR(mp.inertia[2][2], 2.0 / 6 + 4.5, 1e-14);
  EXPECT_NEAR(mp.inertia[0][1], 0, 1e-14);
}

TEST(CollideMass, CompoundRotatesItsChildren) {
  // one rotated, moved box as a compound equals the hull of its corners
  std::mt19937_64 rng(41);
  for (int k = 0; k < 10; ++k) {
    const Vec3 h(0.2, 0.5, 0.9);
    const Pose p{Vec3(1, -2, 0.5 * k), random_rotation(rng)};
    ColliderShape c;
    c.type = ShapeType::Compound;
    c.compound = CompoundShape::build({{ColliderShape::box(h), p}});
    std::vector<Vec3> corners;
    for (int i = 0; i < 8; ++i)
      corners.push_back(apply(p, Vec3(i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z)));
    const MassProperties a = mass_properties(c, 7), b = ConvexHull::build(corners)->mass_properties(7);
    EXPECT_NEAR(a.mass, b.mass, 1e-12 * b.mass);
    EXPECT_NEAR(glm::length(a.center - b.center), 0, 1e-12 * glm::length(b.center) + 1e-15);
    expect_mat_near(a.inertia, b.inertia, 1e-12);
  }
}

TEST(CollideMass, PlanesMeshesAndBadDensitiesThrow) {
  EXPECT_EQ(error_of([] { mass_properties(ColliderShape::plane({0, 1, 0}, 0), 1, "ground"); }),
            "ground: a plane has no volume, so no mass properties (use it as a static shape)");
  EXPECT_EQ(error_of([] { mass_properties(ColliderShape::sphere(1), 0, "ball"); }),
            "ball.density: must be finite and > 0, got 0");
  EXPECT_EQ(error_of([] { mass_properties(ColliderShape::sphere(1), -3, "ball"); }),
            "ball.density: must be finite and > 0, got -3");
  EXPECT_EQ(error_of([] { mass_properties(ColliderShape::sphere(1), kNaN, "ball"); }),
            "ball.density: must be finite and > 0, got nan");
  ColliderShape bad;
  bad.type = ShapeType::Sphere;
  bad.radius = 0;
  EXPECT_EQ(error_of([&] { mass_properties(bad, 1, "ball"); }), "ball.radius: must be finite and > 0, got 0");
}

}  // namespace
