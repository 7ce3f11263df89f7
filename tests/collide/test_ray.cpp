// Tests for ray_cast: analytic hits (distance and normal to 1e-9) on every shape at random
// poses, rays starting inside, misses and max_distance, and hulls and meshes against a
// brute-force loop over faces or triangles for 10^5 random rays.
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

#if defined(__SANITIZE_ADDRESS__)
constexpr int kBruteRays = 10000;  // the sanitizers run ~10x slower
#else
constexpr int kBruteRays = 100000;
#endif


// a random direction entering the surface at a point of outward normal n: d . n < -0.1
Vec3 entering(std::mt19937_64& rng, const Vec3& n) {
  for (;;) {
    const Vec3 d = random_unit(rng);
    if (glm::dot(d, n) < -0.1) return d;
  }
}

// a surface point of a convex shape and its outward normal (local frame), drawn at random
struct SurfacePoint {
  Vec3 p, n;
};
SurfacePoint random_surface_point(const ColliderShape& s, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1), u01(0, 1);
  switch (s.type) {
    case ShapeType::Sphere: {
      const Vec3 n = random_unit(rng);
      return {s.radius * n, n};
    }
    case ShapeType::Box: {
      const int axis = static_cast<int>(u01(rng) * 3) % 3;
      const double side = u(rng) < 0 ? -1 : 1;
      Vec3 p(u(rng) * s.half_extents.x, u(rng) * s.half_extents.y, u(rng) * s.half_extents.z), n(0.0);
      p[axis] = side * s.half_extents[axis];
      n[axis] = side;
      return {p, n};
    }
    case ShapeType::Capsule: {
      if (u01(rng) < 0.5) {  // the side
        const double a = 2 * kPi * u01(rng);
        const Vec3 n(std::cos(a), 0, std::sin(a));
        return {s.radius * n + Vec3(0, u(rng) * s.half_height, 0), n};
      }
      Vec3 n = random_unit(rng);  // a cap
      const double side = n.y < 0 ? -1 : 1;
      return {Vec3(0, side * s.half_height, 0) + s.radius * n, n};
    }
    case ShapeType::Hull: {
      // a random point of a random face's fan triangle
      const auto f = s.hull->faces();
      const auto e = s.hull->edges();
      const auto v = s.hull->vertices();
      const auto& face = f[static_cast<std::size_t>(u01(rng) * f.size()) % f.size()];
      const std::uint32_t e1 = e[face.edge].next;
      const Vec3 a = v[e[face.edge].origin], b = v[e[e1].origin], c = v[e[e[e1].next].origin];
      double x = u01(rng), y = u01(rng);
      if (x + y > 1) x = 1 - x, y = 1 - y;
      return {a + x * (b - a) + y * (c - a), face.normal};
    }
    default: return {};
  }
}

// ---------------------------------------------------------------------------

TEST(CollideRay, ConvexShapesHitAtTheAnalyticPointAndNormal) {
  // a ray aimed at a known surface point p (normal n) from outside enters there: on a convex
  // solid the points before p lie beyond its tangent plane. Distance and normal to 1e-9
  // (rounding of quadratics and transforms at 10 m scale is ~1e-14)
  std::mt19937_64 rng(1);
  std::vector<Vec3> cloud;
  for (int i = 0; i < 60; ++i) cloud.push_back(random_unit(rng) * Vec3(0.5, 1.0, 0.7));
  const ColliderShape shapes[] = {ColliderShape::sphere(0.7), ColliderShape::box({0.3, 0.6, 1.2}),
                                  ColliderShape::capsule(0.8, 0.35), ColliderShape::capsule(0, 0.5),
                                  ColliderShape::convex(ConvexHull::build(cloud)),
                                  ColliderShape::convex(ConvexHull::box({0.4, 0.4, 0.9}))};
  for (const ColliderShape& s : shapes) {
    for (int k = 0; k < 2000; ++k) {
      const Pose pose{Vec3(std::uniform_real_distribution<double>(-5, 5)(rng), 2, -1), random_rotation(rng)};
      const SurfacePoint sp = random_surface_point(s, rng);
      const Vec3 d_local = entering(rng, sp.n);
      const double len = std::uniform_real_distribution<double>(0.01, 6)(rng);
      const Ray ray{apply(pose, sp.p - len * d_local), pose.rotation * d_local, 10};
      const RayHit h = ray_cast(s, pose, ray);
      ASSERT_TRUE(h.hit) << to_string(s.type) << " ray " << k;
      EXPECT_NEAR(h.distance, len, 1e-9) << to_string(s.type);
      EXPECT_NEAR(glm::length(h.point - apply(pose, sp.p)), 0, 1e-9) << to_string(s.type);
      EXPECT_NEAR(glm::length(h.normal - pose.rotation * sp.n), 0, 1e-9) << to_string(s.type);
      // a ray shorter than the distance misses
      EXPECT_FALSE(ray_cast(s, pose, Ray{ray.origin, ray.direction, len * 0.999}).hit);
      // the reverse ray from the same origin misses
      EXPECT_FALSE(ray_cast(s, pose, Ray{ray.origin, -ray.direction, 10}).hit) << to_string(s.type);
    }
  }
}

TEST(CollideRay, RaysStartingInsideHitAtZeroAgainstTheRay) {
  std::mt19937_64 rng(2);
  const ColliderShape shapes[] = {ColliderShape::sphere(0.7), ColliderShape::box({0.3, 0.6, 1.2}),
                                  ColliderShape::capsule(0.8, 0.35),
                                  ColliderShape::convex(ConvexHull::box({0.4, 0.4, 0.9})),
                                  ColliderShape::plane({0, 1, 0}, 0.5)};
  for (const ColliderShape& s : shapes)
    for (int k = 0; k < 200; ++k) {
      const Pose pose{Vec3(1, 2, 3), random_rotation(rng)};
      const Vec3 inside = apply(pose, 0.25 * random_unit(rng));  // every shape holds the ball of 0.3
      const Vec3 d = random_unit(rng);
      const RayHit h = ray_cast(s, pose, Ray{inside, d, 1});
      ASSERT_TRUE(h.hit) << to_string(s.type);
      EXPECT_EQ(h.distance, 0.0);
      EXPECT_EQ(h.point, inside);
      EXPECT_EQ(h.normal, -d);
    }
}

TEST(CollideRay, PlaneMeshAndCompound) {
  // plane y = 2 (rotated frame): distance (y0 - 2) / -d_y
  const Pose tilt{Vec3(0, 1, 0), glm::angleAxis(0.3, Vec3(0, 0, 1))};
  const ColliderShape plane = ColliderShape::plane({0, 1, 0}, 1);
  const Vec3 n = tilt.rotation * Vec3(0, 1, 0);
  const Vec3 o = Vec3(0.5, 6, -1), d = glm::normalize(Vec3(0.2, -1, 0.1));
  const double s0 = glm::dot(n, o - tilt.position) - 1;
  const RayHit hp = ray_cast(plane, tilt, Ray{o, d, 100});
  ASSERT_TRUE(hp.hit);
  EXPECT_NEAR(hp.distance, s0 / -glm::dot(n, d), 1e-12);
  EXPECT_NEAR(glm::length(hp.normal - n), 0, 1e-15);
  EXPECT_FALSE(ray_cast(plane, tilt, Ray{o, -d, 100}).hit);
  // a mesh: the unit icosphere at level 3 hit through its centre at distance L - r_face,
  // with a two-sided normal facing the ray
  const auto ico = test_support::icosphere(3);
  const ColliderShape mesh = ColliderShape::triangles(TriangleMesh::build(ico.vertices, ico.triangles));
  std::mt19937_64 rng(5);
  for (int k = 0; k < 500; ++k) {
    const auto& tr = ico.triangles[static_cast<std::size_t>(k * 7) % ico.triangles.size()];
    const Vec3 c = (ico.vertices[tr[0]] + ico.vertices[tr[1]] + ico.vertices[tr[2]]) / 3.0;  // a face centre
    const Vec3 fn = glm::normalize(glm::cross(ico.vertices[tr[1]] - ico.vertices[tr[0]], ico.vertices[tr[2]] - ico.vertices[tr[0]]));
    const Vec3 dir = entering(rng, fn);
    const RayHit h = ray_cast(mesh, Pose{}, Ray{c - 3.0 * dir, dir, 10});
    ASSERT_TRUE(h.hit);
    EXPECT_NEAR(h.distance, 3.0, 1e-9);
    EXPECT_NEAR(glm::length(h.normal - fn), 0, 1e-9);
    // from inside the mesh the far side is hit, its normal turned to face the ray
    const RayHit in = ray_cast(mesh, Pose{}, Ray{c + 0.01 * dir, -dir, 10});
    ASSERT_TRUE(in.hit);
    EXPECT_NEAR(in.distance, 0.01, 1e-9);
    EXPECT_NEAR(glm::length(in.normal + fn), 0, 1e-9);
  }
  // a compound of two spheres along x: the ray from -x hits the nearer, child 0, at 2 - 0.5
  ColliderShape comp;
  comp.type = ShapeType::Compound;
  comp.compound = CompoundShape::build({{ColliderShape::sphere(0.5), Pose{{-1, 0, 0}, {1, 0, 0, 0}}},
                                        {ColliderShape::sphere(0.5), Pose{{1, 0, 0}, {1, 0, 0, 0}}}});
  const RayHit hc = ray_cast(comp, Pose{{0, 0, 5}, {1, 0, 0, 0}}, Ray{{-3, 0, 5}, {1, 0, 0}, 10});
  ASSERT_TRUE(hc.hit);
  EXPECT_NEAR(hc.distance, 1.5, 1e-12);
  EXPECT_EQ(hc.feature, 0u);
  const RayHit hc2 = ray_cast(comp, Pose{{0, 0, 5}, {1, 0, 0, 0}}, Ray{{3, 0, 5}, {-1, 0, 0}, 10});
  EXPECT_NEAR(hc2.distance, 1.5, 1e-12);
  EXPECT_EQ(hc2.feature, 1u);
}

// brute force for a convex polygon: plane intersection then the inside-all-edges test
double brute_hull(const ConvexHull& h, const Ray& r, Vec3& normal) {
  double best = kInf;
  const auto e = h.edges();
  const auto v = h.vertices();
  for (const auto& f : h.faces()) {
    const double den = glm::dot(f.normal, r.direction);
    if (den >= 0) continue;  // a ray from outside enters through a front face
    const double t = (f.offset - glm::dot(f.normal, r.origin)) / den;
    if (t < 0 || t > r.max_distance || t >= best) continue;
    const Vec3 p = r.origin + t * r.direction;
    bool inside = true;
    std::uint32_t k = f.edge;
    do {
      const Vec3 a = v[e[k].origin], b = v[e[e[k].next].origin];
      inside = inside && glm::dot(glm::cross(b - a, p - a), f.normal) >= -1e-12;
      k = e[k].next;
    } while (k != f.edge);
    if (inside) best = t, normal = f.normal;
  }
  return best;
}

// brute force for a triangle: plane intersection, then barycentric coordinates by areas
double brute_triangle(const Ray& r, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = glm::cross(b - a, c - a);
  const double den = glm::dot(n, r.direction);
  if (den == 0) return kInf;
  const double t = glm::dot(n, a - r.origin) / den;
  if (t < 0 || t > r.max_distance) return kInf;
  const Vec3 p = r.origin + t * r.direction;
  const double nn = glm::dot(n, n);
  const double u = glm::dot(glm::cross(c - b, p - b), n) / nn, v = glm::dot(glm::cross(a - c, p - c), n) / nn;
  return u >= 0 && v >= 0 && u + v <= 1 ? t : kInf;
}

// A direction of any finite non-zero length is the ray along its unit direction: the same
// hit, its distance in metres (the closed forms took |d| = 1: a ray of direction (0, -2, 0)
// straight at a sphere of radius 1 from 5 m above missed it, and a box gave distance 2 for
// its 4 m). Bad rays are Errors naming the field (a NaN origin was a silent miss).
TEST(CollideRay, AnyDirectionLengthHitsAsTheUnitOneAndBadRaysAreErrors) {
  Vec3 corners[8];
  for (int i = 0; i < 8; ++i) corners[i] = Vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
  const ColliderShape shapes[] = {ColliderShape::sphere(1), ColliderShape::box(Vec3(1)),
                                  ColliderShape::capsule(0.5, 0.5), ColliderShape::convex(ConvexHull::build(corners)),
                                  ColliderShape::plane(Vec3(0, 1, 0), 1)};
  const Pose pose{Vec3(0.25, -0.5, 0.125), glm::angleAxis(0.3, glm::normalize(Vec3(1, 2, 3)))};
  for (const ColliderShape& s : shapes) {
    const Vec3 o = pose.position + Vec3(0.1, 5, -0.05);
    const RayHit unit = ray_cast(s, pose, Ray{o, Vec3(0, -1, 0), 10});
    ASSERT_TRUE(unit.hit) << to_string(s.type);
    for (const double len : {2.0, 1e-3, 1e6}) {
      const RayHit h = ray_cast(s, pose, Ray{o, Vec3(0, -len, 0), 10});
      ASSERT_TRUE(h.hit) << to_string(s.type) << " |d| " << len;
      EXPECT_NEAR(h.distance, unit.distance, 1e-12) << to_string(s.type) << " |d| " << len;
      EXPECT_NEAR(glm::length(h.point - unit.point), 0, 1e-12) << to_string(s.type);
      EXPECT_NEAR(glm::length(h.normal - unit.normal), 0, 1e-12) << to_string(s.type);
    }
    // max_distance is in metres too: 0.1 m short of the hit misses
    EXPECT_FALSE(ray_cast(s, pose, Ray{o, Vec3(0, -2, 0), unit.distance - 0.1}).hit) << to_string(s.type);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(ray_cast(s, pose, Ray{Vec3(nan, 0, 0), Vec3(0, -1, 0), 10}), Error);
    EXPECT_THROW(ray_cast(s, pose, Ray{o, Vec3(0), 10}), Error);
    EXPECT_THROW(ray_cast(s, pose, Ray{o, Vec3(0, -kInf, 0), 10}), Error);
    EXPECT_THROW(ray_cast(s, pose, Ray{o, Vec3(0, -1, 0), -1}), Error);
    try {
      ray_cast(s, pose, Ray{o, Vec3(0), 10});
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("ray_cast(ray).direction"), std::string::npos) << e.what();
    }
    // a pose that is not a number or not a rotation is refused by name too (a NaN pose
    // missed silently, a rotation of length 2 scaled the shape, before 2026-12-07)
    for (const Pose& bad : {Pose{Vec3(nan, 0, 0)}, Pose{Vec3(0), Quat(2, 0, 0, 0)}, Pose{Vec3(0), Quat(0, 0, 0, 0)}}) {
      try {
        ray_cast(s, bad, Ray{o, Vec3(0, -1, 0), 10});
        ADD_FAILURE() << to_string(s.type) << ": no error for a bad pose";
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("ray_cast(pose)"), std::string::npos) << e.what();
      }
    }
  }
}

TEST(CollideRay, HullEqualsBruteForceOverFaces) {
  std::mt19937_64 rng(9);
  std::vector<Vec3> cloud;
  for (int i = 0; i < 100; ++i) cloud.push_back(random_unit(rng) * Vec3(1.0, 0.6, 1.4));
  const auto hull = ConvexHull::build(cloud);
  const ColliderShape s = ColliderShape::convex(hull);
  std::uniform_real_distribution<double> u(-3, 3);
  int hits = 0;
  for (int k = 0; k < kBruteRays; ++k) {
    // origins outside the hull's bounding sphere (radius 1.4), aimed near it
    const Vec3 o = 2.5 * random_unit(rng);
    const Vec3 d = glm::normalize(Vec3(u(rng), u(rng), u(rng)) * 0.4 - o);
    const Ray r{o, d, 5};
    Vec3 n(0.0);
    const double want = brute_hull(*hull, r, n);
    const RayHit h = ray_cast(s, Pose{}, r);
    ASSERT_EQ(h.hit, want < kInf) << "ray " << k;
    if (!h.hit) continue;
    ++hits;
    EXPECT_NEAR(h.distance, want, 1e-9);
    EXPECT_NEAR(glm::length(h.normal - n), 0, 1e-9);
  }
  EXPECT_GT(hits, kBruteRays / 4);  // the rays test hits, not only misses
}

TEST(CollideRay, MeshEqualsBruteForceOverTriangles) {
  const auto t = test_support::terrain(12, 8.0, [](double x, double z) { return 0.5 * std::sin(x) * std::cos(z); });
  const auto mesh = TriangleMesh::build(t.vertices, t.triangles);
  const ColliderShape s = ColliderShape::triangles(mesh);
  const Pose pose{Vec3(1, -2, 0.5), glm::angleAxis(0.4, glm::normalize(Vec3(1, 1, 0)))};
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-5, 5);
  int hits = 0;
  for (int k = 0; k < kBruteRays; ++k) {
    const Vec3 o_local(u(rng), 0.6 * u(rng), u(rng));
    const Vec3 d_local = random_unit(rng);
    const double len = std::abs(u(rng)) + 0.5;
    const Ray r{apply(pose, o_local), pose.rotation * d_local, len};
    const Ray rl{o_local, d_local, len};
    double want = kInf;
    std::uint32_t want_t = 0;
    for (std::uint32_t i = 0; i < t.triangles.size(); ++i) {
      const double s_i = brute_triangle(rl, t.vertices[t.triangles[i][0]], t.vertices[t.triangles[i][1]],
                                        t.vertices[t.triangles[i][2]]);
      if (s_i < want) want = s_i, want_t = i;
    }
    const RayHit h = ray_cast(s, pose, r);
    ASSERT_EQ(h.hit, want < kInf) << "ray " << k;
    if (!h.hit) continue;
    ++hits;
    EXPECT_NEAR(h.distance, want, 1e-9);
    Vec3 n = mesh->normal(want_t);
    if (glm::dot(n, d_local) > 0) n = -n;
    EXPECT_NEAR(glm::length(h.normal - pose.rotation * n), 0, 1e-9) << "ray " << k;
  }
  EXPECT_GT(hits, kBruteRays / 10);
}

}  // namespace
