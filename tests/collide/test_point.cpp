// Tests for point_distance: every shape against brute force (exact over faces and
// triangles for hulls and meshes; dense surface samples with their covering radius for
// boxes and capsules), the identity x = point + distance * normal, and degenerate points.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "pba/collide/shape.h"
#include "shape_checks.h"
#include "shape_gen.h"

namespace {

using namespace pba;
using namespace pba::test_support;
const double kInf = std::numeric_limits<double>::infinity();


// the nearest point of a triangle, by projection and barycentric areas, else its edges
Vec3 brute_closest_triangle(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = glm::cross(b - a, c - a);
  const double nn = glm::dot(n, n);
  const Vec3 p = x - (glm::dot(n, x - a) / nn) * n;
  const double u = glm::dot(glm::cross(c - b, p - b), n) / nn, v = glm::dot(glm::cross(a - c, p - c), n) / nn;
  if (u >= 0 && v >= 0 && u + v <= 1) return p;
  Vec3 best = a;
  for (const auto& [s, e] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
    const double t = std::clamp(glm::dot(x - s, e - s) / glm::dot(e - s, e - s), 0.0, 1.0);
    const Vec3 q = s + t * (e - s);
    if (glm::length(x - q) < glm::length(x - best)) best = q;
  }
  return best;
}

// the result's own consistency: unit normal, x = point + distance normal
void expect_consistent(const PointDistance& d, const Vec3& x, double tol) {
  EXPECT_NEAR(glm::length(d.normal), 1, 1e-12);
  EXPECT_NEAR(glm::length(d.point + d.distance * d.normal - x), 0, tol);
}

TEST(CollidePoint, SphereAndPlaneClosedForms) {
  std::mt19937_64 rng(1);
  const Pose pose{Vec3(1, 2, 3), random_rotation(rng)};
  for (int k = 0; k < 500; ++k) {
    const Vec3 x = pose.position + random_unit(rng) * (0.01 + 0.01 * k);
    const PointDistance s = point_distance(ColliderShape::sphere(1.5), pose, x);
    EXPECT_NEAR(s.distance, glm::length(x - pose.position) - 1.5, 1e-12);
    EXPECT_NEAR(glm::length(s.point - pose.position), 1.5, 1e-12);
    expect_consistent(s, x, 1e-12);
    const PointDistance p = point_distance(ColliderShape::plane({0, 0, 2}, 1), pose, x);
    const Vec3 n = pose.rotation * Vec3(0, 0, 1);
    EXPECT_NEAR(p.distance, glm::dot(n, x - pose.position) - 0.5, 1e-12);
    EXPECT_NEAR(glm::length(p.normal - n), 0, 1e-15);
    expect_consistent(p, x, 1e-12);
  }
  // the centre: a finite answer (+Y by convention)
  const PointDistance c = point_distance(ColliderShape::sphere(1.5), Pose{}, Vec3(0.0));
  EXPECT_EQ(c.distance, -1.5);
  EXPECT_EQ(c.normal, Vec3(0, 1, 0));
}

// dense surface samples and their covering radius delta (every surface point lies within
// delta of a sample), so the true distance d obeys d_ref - delta <= |d| <= d_ref
struct Samples {
  std::vector<Vec3> p;
  double delta = 0;
};

Samples box_samples(const Vec3& h, int n) {
  Samples s;
  for (int axis = 0; axis < 3; ++axis)
    for (double side : {-1.0, 1.0}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          Vec3 p(0.0);
          p[axis] = side * h[axis];
          p[u] = h[u] * (2.0 * i / n - 1);
          p[v] = h[v] * (2.0 * j / n - 1);
          s.p.push_back(p);
        }
      s.delta = std::max(s.delta, 0.5 * std::hypot(2 * h[u] / n, 2 * h[v] / n));
    }
  return s;
}

Samples capsule_samples(double hh, double r, int n) {
  Samples s;
  const double da = 2 * kPi / n, dy = 2 * hh / n, dt = 0.5 * kPi / n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j <= n; ++j) s.p.push_back(Vec3(r * std::cos(i * da), -hh + j * dy, r * std::sin(i * da)));
  for (double side : {-1.0, 1.0})
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j < n; ++j) {
        const double t = i * dt, a = j * da;  // polar angle from the axis, azimuth
        s.p.push_back(Vec3(0, side * hh, 0) + r * Vec3(std::sin(t) * std::cos(a), side * std::cos(t), std::sin(t) * std::sin(a)));
      }
  s.delta = 0.5 * std::max(std::hypot(r * da, dy), r * std::hypot(dt, da));
  return s;
}

TEST(CollidePoint, BoxAndCapsuleAgainstDenseSurfaceSamples) {
  std::mt19937_64 rng(2);
  const Vec3 h(0.4, 0.7, 1.0);
  const double hh = 0.6, r = 0.3;
  const ColliderShape box = ColliderShape::box(h), capsule = ColliderShape::capsule(hh, r);
  const Samples bs = box_samples(h, 80), cs = capsule_samples(hh, r, 120);
  const Pose pose{Vec3(-1, 0.5, 2), random_rotation(rng)};
  std::uniform_real_distribution<double> u(-1.6, 1.6);
  for (int k = 0; k < 300; ++k) {
    const Vec3 xl(u(rng), u(rng), u(rng));
    const Vec3 x = apply(pose, xl);
    for (int which = 0; which < 2; ++which) {
      const ColliderShape& s = which ? capsule : box;
      const Samples& ss = which ? cs : bs;
      double ref = kInf;
      for (const Vec3& p : ss.p) ref = std::min(ref, glm::length(xl - p));
      const bool inside = which ? glm::length(xl - Vec3(0, std::clamp(xl.y, -hh, hh), 0)) < r
                                : std::abs(xl.x) < h.x && std::abs(xl.y) < h.y && std::abs(xl.z) < h.z;
      const PointDistance d = point_distance(s, pose, x);
      EXPECT_EQ(d.distance < 0, inside) << to_string(s.type) << " point " << k;
      EXPECT_LE(std::abs(d.distance), ref + 1e-12) << to_string(s.type);
      EXPECT_GE(std::abs(d.distance), ref - ss.delta - 1e-12) << to_string(s.type);
      expect_consistent(d, x, 1e-12);
    }
    // the box and its hull agree (two implementations)
    const PointDistance a = point_distance(box, pose, x), b = point_distance(ColliderShape::convex(ConvexHull::box(h)), pose, x);
    EXPECT_NEAR(a.distance, b.distance, 1e-12);
    EXPECT_NEAR(glm::length(a.point - b.point), 0, 1e-12);
    // the face agrees where it is unique: the nearest point inside a face
    const int out = (std::abs(xl.x) > h.x) + (std::abs(xl.y) > h.y) + (std::abs(xl.z) > h.z);
    if (out <= 1) { EXPECT_EQ(a.feature, b.feature); }
  }
  // a point on the capsule's core: finite
  const PointDistance core = point_distance(capsule, Pose{}, Vec3(0, 0.2, 0));
  EXPECT_EQ(core.distance, -r);
  expect_consistent(core, Vec3(0, 0.2, 0), 1e-15);
}

TEST(CollidePoint, HullEqualsBruteForceOverFaces) {
  std::mt19937_64 rng(3);
  std::vector<Vec3> cloud;
  for (int i = 0; i < 80; ++i) cloud.push_back(random_unit(rng) * Vec3(1.0, 0.5, 0.8));
  const auto hull = ConvexHull::build(cloud);
  const Pose pose{Vec3(0.5, 0, -1), random_rotation(rng)};
  const auto e = hull->edges();
  const auto v = hull->vertices();
  std::uniform_real_distribution<double> u(-2, 2);
  for (int k = 0; k < 3000; ++k) {
    const Vec3 xl(u(rng), u(rng), u(rng));
    // inside: the nearest face plane; outside: the nearest point over every fan triangle
    double sep = -kInf;
    for (const auto& f : hull->faces()) sep = std::max(sep, glm::dot(f.normal, xl) - f.offset);
    double want = sep;
    if (sep > 0) {
      want = kInf;
      for (const auto& f : hull->faces())
        for (std::uint32_t i = e[f.edge].next; e[i].next != f.edge; i = e[i].next)
          want = std::min(want, glm::length(xl - brute_closest_triangle(xl, v[e[f.edge].origin], v[e[i].origin],
                                                                        v[e[e[i].next].origin])));
    }
    const PointDistance d = point_distance(ColliderShape::convex(hull), pose, apply(pose, xl));
    EXPECT_NEAR(d.distance, want, 1e-12) << "point " << k;
    expect_consistent(d, apply(pose, xl), 1e-12);
  }
}

TEST(CollidePoint, MeshEqualsBruteForceOverTriangles) {
  const auto t = test_support::terrain(16, 6.0, [](double x, double z) { return 0.4 * std::sin(1.3 * x) * std::cos(z); });
  const auto mesh = TriangleMesh::build(t.vertices, t.triangles);
  std::mt19937_64 rng(4);
  const Pose pose{Vec3(0, 1, 0), random_rotation(rng)};
  std::uniform_real_distribution<double> u(-4, 4);
  for (int k = 0; k < 3000; ++k) {
    const Vec3 xl(u(rng), 0.5 * u(rng), u(rng));
    double want = kInf;
    for (const auto& tr : t.triangles)
      want = std::min(want, glm::length(xl - brute_closest_triangle(xl, t.vertices[tr[0]], t.vertices[tr[1]], t.vertices[tr[2]])));
    const PointDistance d = point_distance(ColliderShape::triangles(mesh), pose, apply(pose, xl));
    EXPECT_NEAR(d.distance, want, 1e-12) << "point " << k;
    EXPECT_GE(d.distance, 0);
    expect_consistent(d, apply(pose, xl), 1e-12);
  }
  // a point on a triangle (to rounding) takes its normal, on the side rounding put it
  const auto& tr = t.triangles[37];
  const Vec3 c = (t.vertices[tr[0]] + t.vertices[tr[1]] + t.vertices[tr[2]]) / 3.0;
  const PointDistance on = point_distance(ColliderShape::triangles(mesh), Pose{}, c);
  EXPECT_NEAR(on.distance, 0, 1e-15);
  EXPECT_EQ(on.feature, 37u);
  EXPECT_NEAR(std::abs(glm::dot(on.normal, mesh->normal(37))), 1, 1e-15);
  // just above and below it: the normal faces the point
  const PointDistance up = point_distance(ColliderShape::triangles(mesh), Pose{}, c + 1e-9 * mesh->normal(37));
  const PointDistance down = point_distance(ColliderShape::triangles(mesh), Pose{}, c - 1e-9 * mesh->normal(37));
  EXPECT_NEAR(glm::length(up.normal - mesh->normal(37)), 0, 1e-15);
  EXPECT_NEAR(glm::length(down.normal + mesh->normal(37)), 0, 1e-15);
}

TEST(CollidePoint, CompoundIsTheNearestChild) {
  ColliderShape comp;
  comp.type = ShapeType::Compound;
  comp.compound = CompoundShape::build({{ColliderShape::sphere(0.5), Pose{{-1, 0, 0}, {1, 0, 0, 0}}},
                                        {ColliderShape::box({0.5, 0.5, 0.5}), Pose{{1, 0, 0}, {1, 0, 0, 0}}}});
  const PointDistance a = point_distance(comp, Pose{}, Vec3(-3, 0, 0));
  EXPECT_NEAR(a.distance, 1.5, 1e-15);
  EXPECT_EQ(a.feature, 0u);
  const PointDistance b = point_distance(comp, Pose{}, Vec3(1, 2, 0));
  EXPECT_NEAR(b.distance, 1.5, 1e-15);
  EXPECT_EQ(b.feature, 1u);
  EXPECT_EQ(b.normal, Vec3(0, 1, 0));
  const PointDistance in = point_distance(comp, Pose{}, Vec3(1.25, 0, 0));
  EXPECT_NEAR(in.distance, -0.25, 1e-15);
}

// A point or a pose that is not a number, beyond a float's range or not a rotation is
// refused by name, as QueryWorld::closest_point() refuses it. Before 2026-12-07 a NaN point
// gave a box's distance as -inf (deep inside it), a NaN pose a NaN distance, and a point at
// 1e300 m an infinite distance with the sphere's centre as its closest point.
TEST(CollidePoint, BadPointsAndPosesAreErrorsNamingTheArgument) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const ColliderShape shapes[] = {ColliderShape::sphere(1), ColliderShape::box(Vec3(1)), ColliderShape::capsule(0.5, 0.5)};
  auto message = [](auto f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  for (const ColliderShape& s : shapes) {
    EXPECT_NE(message([&] { point_distance(s, Pose{}, Vec3(nan, 0, 0)); }).find("point_distance(world_point)"),
              std::string::npos) << to_string(s.type);
    EXPECT_NE(message([&] { point_distance(s, Pose{}, Vec3(1e300, 0, 0)); }).find("point_distance(world_point)"),
              std::string::npos) << to_string(s.type);
    EXPECT_NE(message([&] { point_distance(s, Pose{{nan, 0, 0}}, Vec3(3, 0, 0)); }).find("point_distance(pose).position"),
              std::string::npos) << to_string(s.type);
    EXPECT_NE(message([&] { point_distance(s, Pose{{0, 0, 0}, Quat(2, 0, 0, 0)}, Vec3(3, 0, 0)); })
                  .find("point_distance(pose).rotation"),
              std::string::npos) << to_string(s.type);
    // the float range's edge is still a point: 3e38 m from a unit shape at the origin
    EXPECT_NEAR(point_distance(s, Pose{}, Vec3(3e38, 0, 0)).distance, 3e38, 1e23) << to_string(s.type);
  }
}

}  // namespace
