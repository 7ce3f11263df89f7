// Rigid bodies on static triangle meshes: a flat mesh of many triangles against the plane it
// lies in (the same scene, the same measures), internal edges without bumps, Coulomb sliding,
// a hull resting on its base, determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "pba/rigid.h"
#include "pba/collide/narrow_phase.h"
#include "pba/rigid_scenes.h"

using pba::BodyType;
using pba::ColliderShape;
using pba::RigidBodySystem;
using pba::Vec3;

namespace {

constexpr double kG = 9.81;
const Vec3 kGravity{0, -kG, 0};

// a flat square grid y = 0 of n x n cells of `cell` metres (two triangles each), centred at
// the origin; `bumps` lifts every vertex by that times a pseudo-random number in [0, 1)
std::shared_ptr<const pba::TriangleMesh> grid(int n, double cell, double bumps = 0) {
  std::vector<Vec3> v;
  std::vector<std::array<std::uint32_t, 3>> t;
  std::uint32_t r = 12345;
  for (int z = 0; z <= n; ++z)
    for (int x = 0; x <= n; ++x) {
      r = r * 1664525u + 1013904223u;
      v.push_back({(x - 0.5 * n) * cell, bumps * (r >> 8) / double(1 << 24), (z - 0.5 * n) * cell});
    }
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x) {
      const std::uint32_t a = z * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      t.push_back({a, c, b});
      t.push_back({b, c, d});
    }
  return pba::TriangleMesh::build(v, t, "grid");
}

// the ground: a plane y = 0, or the same surface as a mesh of 0.7 m cells
void ground(RigidBodySystem& s, bool mesh, double mu = 0.5) {
  const ColliderShape shape = mesh ? ColliderShape::triangles(grid(30, 0.7)) : ColliderShape::plane({0, 1, 0}, 0);
  s.create({.name = mesh ? "mesh" : "plane", .type = BodyType::Static,
            .shapes = {{.shape = shape, .material = {.restitution = 0, .friction = mu}}}});
}

// A unit box resting across several triangles for 10 s sags and drifts as it does on the
// plane: the triangles' manifolds of one normal are merged into the plane's one manifold
TEST(RigidMesh, ABoxRestsOnAFlatMeshAsOnAPlane) {
  for (const auto solver : pba::kRigidSolvers) {
    double sag[2], drift[2];
    for (const bool mesh : {false, true}) {
      RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
      ground(s, mesh);
      const Vec3 p0{0.13, 0.5, 0.27};  // over the corners of four cells
      const auto box = pba::rigid_scenes::box(s, p0, Vec3(0.5));
      for (int i = 0; i < 600; ++i) s.step(1.0 / 60, kGravity);
      const Vec3 p = s.center_of_mass(box);
      sag[mesh] = p0.y - p.y, drift[mesh] = std::hypot(p.x - p0.x, p.z - p0.z);
      if (mesh) {
        EXPECT_EQ(s.manifold_count(), 1u) << to_string(solver);
      }
    }
    // they differ in how the points are computed (clipped against triangles, or projected on
    // the plane), so by rounding: a micrometre, where the soft contact's sag is 17 um
    EXPECT_NEAR(sag[1], sag[0], 1e-6) << to_string(solver);
    EXPECT_LT(drift[1], 1e-6) << to_string(solver);
  }
}

// A box resting across the diagonal of two coplanar triangles gets one manifold whose points
// and depths are those of the same box on one triangle that holds its whole footprint
TEST(RigidMesh, ABoxAcrossTwoCoplanarTrianglesHasTheOneTriangleManifold) {
  std::vector<pba::RigidContactPoint> got[2];
  for (const bool split : {false, true}) {
    const std::vector<Vec3> v = split ? std::vector<Vec3>{{-2, 0, -2}, {2, 0, -2}, {-2, 0, 2}, {2, 0, 2}}
                                      : std::vector<Vec3>{{-3, 0, -3}, {5, 0, -3}, {-3, 0, 5}};
    const std::vector<std::array<std::uint32_t, 3>> t =
        split ? std::vector<std::array<std::uint32_t, 3>>{{0, 2, 1}, {1, 2, 3}} : std::vector<std::array<std::uint32_t, 3>>{{0, 2, 1}};
    RigidBodySystem s({.contacts = {.sleep = false}});
    s.create({.type = BodyType::Static, .shapes = {{.shape = ColliderShape::triangles(pba::TriangleMesh::build(v, t, "floor"))}}});
    // 1 mm into the floor, its corners on both sides of the diagonal x + z = 0
    pba::rigid_scenes::box(s, {0.1, 0.249, -0.05}, Vec3(0.5, 0.25, 0.4));
    s.step(1.0 / 60, kGravity);
    EXPECT_EQ(s.manifold_count(), 1u) << split;
    got[split] = s.contacts();
  }
  ASSERT_EQ(got[1].size(), got[0].size());
  ASSERT_EQ(got[0].size(), 4u);
  for (std::size_t k = 0; k < got[0].size(); ++k) {
    // the same points in some order
    double nearest = INFINITY;
    std::size_t at = 0;
    for (std::size_t j = 0; j < got[1].size(); ++j)
      if (const double d = glm::length(got[1][j].position - got[0][k].position); d < nearest) nearest = d, at = j;
    EXPECT_LT(nearest, 1e-9) << k;
    EXPECT_NEAR(got[1][at].depth, got[0][k].depth, 1e-9) << k;
  }
}

// A box resting across the fold of two triangles (a shallow valley): within 5 degrees of
// each other the triangles' manifolds merge into one of at most four points, along one
// triangle's normal, and the box stays where it was put (1.5 degrees of tilt in the normal
// are held by friction: 0.5 um in 2 s, 0.9 um with a manifold per triangle); at 10 degrees
// each triangle keeps its own manifold
TEST(RigidMesh, ManifoldsOfNearlyEqualNormalsMerge) {
  for (const double degrees : {3.0, 10.0}) {
    // the valley along z: two slopes of half the fold each, meeting at x = 0
    const double slope = std::tan(0.5 * degrees * pba::kPi / 180);
    const std::vector<Vec3> v = {{-2, 2 * slope, -2}, {0, 0, -2}, {2, 2 * slope, -2},
                                 {-2, 2 * slope, 2},  {0, 0, 2},  {2, 2 * slope, 2}};
    const std::vector<std::array<std::uint32_t, 3>> t = {{0, 3, 1}, {1, 3, 4}, {1, 4, 2}, {2, 4, 5}};
    RigidBodySystem s({.contacts = {.sleep = false}});
    s.create({.type = BodyType::Static,
              .shapes = {{.shape = ColliderShape::triangles(pba::TriangleMesh::build(v, t, "valley"))}}});
    // its bottom edges on the two slopes
    const Vec3 p0{0, 0.25 + 0.5 * slope, 0.1};
    const auto box = pba::rigid_scenes::box(s, p0, Vec3(0.5, 0.25, 0.5));
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
    EXPECT_EQ(s.manifold_count(), degrees < 5 ? 1u : 2u) << degrees;
    if (degrees < 5) {
      const Vec3 c = s.center_of_mass(box);
      EXPECT_LT(std::hypot(c.x - p0.x, c.z - p0.z), 1e-5);
      EXPECT_LT(glm::length(s.linear_velocity(box)), 1e-6);
    }
  }
}

// A box resting in a valley of 10 degrees (two slopes of 5, mu 0.6 holds it on either)
// stays: under 0.1 mm in 5 s, under 1 mm/s, with a manifold per slope. It rests on its two
// bottom edges, one on each slope: each edge's two ends are points. With the one deepest
// vertex per slope it was held at one end of the box, which rocked (the deepest vertex
// switching ends from step to step, the reported speed 0.12 m/s while its height stayed)
// and crept along the valley, 18 mm to 72 mm in 5 s by solver. XPBD's box stays
// too (5 um in 5 s) but its reported velocity keeps 1.3 mm/s: what its velocity pass, one
// manifold after the other, leaves between two manifolds 10 degrees apart (not checked)
TEST(RigidMesh, ABoxRestsInATenDegreeValley) {
  for (const auto solver : pba::kRigidSolvers) {
    const double slope = std::tan(5 * pba::kPi / 180);
    const std::vector<Vec3> v = {{-2, 2 * slope, -2}, {0, 0, -2}, {2, 2 * slope, -2},
                                 {-2, 2 * slope, 2},  {0, 0, 2},  {2, 2 * slope, 2}};
    const std::vector<std::array<std::uint32_t, 3>> t = {{0, 3, 1}, {1, 3, 4}, {1, 4, 2}, {2, 4, 5}};
    RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
    s.create({.type = BodyType::Static,
              .shapes = {{.shape = ColliderShape::triangles(pba::TriangleMesh::build(v, t, "valley")),
                          .material = {.friction = 0.6}}}});
    const Vec3 p0{0, 0.25 + 0.5 * slope, 0.1};
    const auto box = s.create({.pose = {p0}, .shapes = {{.shape = ColliderShape::box(Vec3(0.5, 0.25, 0.5)),
                                                         .material = {.friction = 0.6}}}});
    // settled after 3 s (the soft step halves its substeps a second in, and its springs, a
    // quarter as stiff, let the box sink from 0.17 to 0.68 mm; it takes 3 a second later,
    // 1.2 mm), then 5 s
    for (int i = 0; i < 180; ++i) s.step(1.0 / 60, kGravity);
    const Vec3 p1 = s.center_of_mass(box);
    double speed = 0;
    for (int i = 0; i < 300; ++i) {
      s.step(1.0 / 60, kGravity);
      speed = std::max(speed, glm::length(s.linear_velocity(box)));
    }
    EXPECT_EQ(s.manifold_count(), 2u) << to_string(solver);
    EXPECT_LT(glm::length(s.center_of_mass(box) - p1), 1e-4) << to_string(solver);
    if (solver != pba::RigidSolverType::Xpbd) {
      EXPECT_LT(speed, 1e-3) << to_string(solver);
    }
  }
}

// A ball rolling at 3.9 m/s over 0.7 m triangles goes where it goes on the plane, never
// leaving the surface (no ghost contact on the edges between the triangles, and the
// continuous pass does not stop it at them)
TEST(RigidMesh, ABallRollsOverInternalEdgesWithoutBumps) {
  Vec3 end[2];
  for (const bool mesh : {false, true}) {
    RigidBodySystem s({.contacts = {.sleep = false}});
    ground(s, mesh);
    const auto ball = s.create({.pose = {{-5, 0.3, -4}}, .linear_velocity = {3, 0, 2.5},
                                .angular_velocity = {2.5 / 0.3, 0, -3 / 0.3},
                                .shapes = {{.shape = ColliderShape::sphere(0.3), .material = {.friction = 0.5}}}});
    double vy = 0;
    for (int i = 0; i < 150; ++i) {
      s.step(1.0 / 60, kGravity);
      vy = std::max(vy, std::abs(s.linear_velocity(ball).y));
    }
    EXPECT_LT(vy, 1e-6) << (mesh ? "mesh" : "plane");
    end[mesh] = s.center_of_mass(ball);
  }
  EXPECT_LT(glm::length(end[1] - end[0]), 1e-6);  // rounding, over 9.8 m
}

// A box sliding at 4 m/s on the mesh stops after v^2 / (2 mu g) within 2%, in several
// directions across the triangles
TEST(RigidMesh, ASlidingBoxStopsAtTheCoulombDistance) {
  const double v = 4, mu = 0.5, expected = v * v / (2 * mu * kG);
  for (int k = 0; k < 6; ++k) {
    const double a = 2 * pba::kPi * k / 6 + 0.1;
    const Vec3 dir{std::cos(a), 0, std::sin(a)}, p0{0.05, 0.25, 0.07};
    RigidBodySystem s({.contacts = {.sleep = false}});
    ground(s, true, mu);
    const auto box = s.create({.pose = {p0}, .linear_velocity = v * dir,
                               .shapes = {{.shape = ColliderShape::box(Vec3(0.25)), .material = {.friction = mu}}}});
    double vy = 0;
    for (int i = 0; i < 180; ++i) {
      s.step(1.0 / 60, kGravity);
      vy = std::max(vy, std::abs(s.linear_velocity(box).y));
    }
    const Vec3 d = s.center_of_mass(box) - p0;
    EXPECT_NEAR(std::hypot(d.x, d.z), expected, 0.02 * expected) << k;
    EXPECT_LT(glm::length(glm::cross(Vec3(d.x, 0, d.z), dir)), 0.01) << k;  // straight
    EXPECT_LT(vy, 1e-3) << k;  // no hops over the edges
  }
}

// A pyramid hull standing on its base (its origin is the middle of the base, on the mesh)
// and boxes and balls dropped on a bumpy mesh stay on it
TEST(RigidMesh, BodiesStayOnTheMesh) {
  const Vec3 apex[5] = {{0, 1, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 0, 1}, {0, 0, -1}};
  const ColliderShape pyramid = ColliderShape::convex(pba::ConvexHull::build(apex));
  for (const double bumps : {0.0, 0.3}) {
    RigidBodySystem s;
    s.create({.type = BodyType::Static, .shapes = {{.shape = ColliderShape::triangles(grid(20, 1.0, bumps))}}});
    std::vector<pba::RigidBodyId> bodies;
    for (int i = 0; i < 12; ++i) {
      const ColliderShape shape = i % 3 == 0 ? pyramid : i % 3 == 1 ? ColliderShape::box({0.4, 0.3, 0.5}) : ColliderShape::sphere(0.4);
      bodies.push_back(s.create({.pose = {{(i % 4) * 2.5 - 4, 0.3 + bumps + (i / 4) * 1.5, (i / 4) * 2.5 - 2.5}},
                                 .shapes = {{.shape = shape}}}));
    }
    for (int i = 0; i < 300; ++i) s.step(1.0 / 60, kGravity);
    for (std::size_t k = 0; k < bodies.size(); ++k)
      EXPECT_GT(s.center_of_mass(bodies[k]).y, 0.0) << "bumps " << bumps << " body " << k;
  }
}

// The same scene twice gives the same bits
TEST(RigidMesh, MeshContactsAreDeterministic) {
  auto run = [] {
    RigidBodySystem s;
    s.create({.type = BodyType::Static, .shapes = {{.shape = ColliderShape::triangles(grid(12, 0.9, 0.4))}}});
    for (int i = 0; i < 20; ++i)
      s.create({.pose = {{(i % 5) * 1.1 - 2.2, 1.0 + (i / 5) * 1.2, (i % 3) * 0.9 - 0.9}},
                .angular_velocity = {0.3 * i, 0, 0.1},
                .shapes = {{.shape = i % 2 ? ColliderShape::sphere(0.3) : ColliderShape::box({0.3, 0.2, 0.25})}}});
    for (int i = 0; i < 240; ++i) s.step(1.0 / 60, kGravity);
    return s.hash();
  };
  EXPECT_EQ(run(), run());
}

}  // namespace

namespace {

// A concave valley of two triangles meeting along the z axis, its sides rising at 30 degrees
// (the crease between them is internal: a contact on it takes a face normal). Spheres, lying
// capsules and tilted boxes come down into it at 12 m/s (0.2 m a step) over the crease and
// off to either side, where a side's nearest feature can be the crease with the shape's
// deepest point along that side's normal over the other side: the contact there must not be
// dropped, or the shape would come down unseen. Every step no shape's centre comes nearer
// either side's plane than its smallest half size less 1 cm (no sinking, no tunnelling: the
// planes lie under the valley), and EPA finds no shape deeper than 1 cm in either triangle
// (the soft step leaves up to the 5 mm slop, and a fast landing's first step a few mm more);
// the sphere dropped over the crease rests at the bottom touching both sides, its centre
// r / cos 30 degrees above the crease.
TEST(RigidMesh, ShapesComingDownIntoAConcaveValleyStopOnItsSides) {
  const double t = std::tan(pba::kPi / 6), L = 10;
  const std::vector<Vec3> v = {{0, 0, L}, {0, 0, -L}, {-L, L * t, 0}, {L, L * t, 0}};
  const std::vector<std::array<std::uint32_t, 3>> tri = {{0, 1, 2}, {1, 0, 3}};
  const auto mesh = pba::TriangleMesh::build(v, tri, "valley");
  ASSERT_NEAR(glm::length(mesh->normal(0) - Vec3(std::sin(pba::kPi / 6), std::cos(pba::kPi / 6), 0)), 0, 1e-12);
  ASSERT_NEAR(glm::length(mesh->normal(1) - Vec3(-std::sin(pba::kPi / 6), std::cos(pba::kPi / 6), 0)), 0, 1e-12);
  ASSERT_EQ(mesh->edge_flags()[0] & 1, 0);  // the crease is internal
  const ColliderShape shapes[3] = {ColliderShape::sphere(0.3), ColliderShape::capsule(0.5, 0.2),
                                   ColliderShape::box(Vec3(0.3, 0.2, 0.25))};
  const double smallest[3] = {0.3, 0.2, 0.2};
  const pba::SurfaceMaterial m{.restitution = 0, .friction = 0.5};
  for (int k = 0; k < 3; ++k)
    for (const double x0 : {-0.45, -0.15, 0.0, 0.1, 0.2, 0.35, 0.6}) {
      RigidBodySystem s({.contacts = {.sleep = false}});
      s.create({.type = BodyType::Static, .shapes = {{.shape = ColliderShape::triangles(mesh), .material = m}}});
      // the capsule lying across the crease, tilted a little; the box tilted about a skew axis
      const pba::Quat q = k == 1   ? glm::angleAxis(pba::kPi / 2 - 0.2, Vec3(0, 0, 1))
                          : k == 2 ? glm::angleAxis(0.7, glm::normalize(Vec3(0.3, 0.2, 1)))
                                   : pba::Quat(1, 0, 0, 0);
      const auto body = s.create({.pose = {{x0, 2.5, 0.1}, q}, .linear_velocity = {0, -12, 0},
                                  .shapes = {{.shape = shapes[k], .material = m}}});
      double deepest = -INFINITY, nearest = INFINITY;
      for (int i = 0; i < 240; ++i) {
        s.step(1.0 / 60, kGravity);
        const pba::Pose p = s.pose(body);
        const pba::ConvexProxy a = pba::ConvexProxy::of(shapes[k], p);
        for (int j = 0; j < 2; ++j) {
          nearest = std::min(nearest, glm::dot(p.position, mesh->normal(std::uint32_t(j))));
          const Vec3 w[3] = {v[tri[j][0]], v[tri[j][1]], v[tri[j][2]]};
          pba::ConvexProxy b;
          b.type = pba::ShapeType::Mesh;
          b.triangle = w;
          const pba::DistanceResult d = pba::gjk_distance(a, b);
          deepest = std::max(deepest, d.cores_overlap ? pba::epa_penetration(a, b).depth : a.radius - d.core_distance);
        }
      }
      EXPECT_GT(nearest, smallest[k] - 0.01) << "shape " << k << " from x " << x0;
      EXPECT_LT(deepest, 0.01) << "shape " << k << " from x " << x0;
      if (k == 0 && x0 == 0.0) {
        EXPECT_NEAR(s.pose(body).position.x, 0.0, 1e-3);
        EXPECT_NEAR(s.pose(body).position.y, 0.3 / std::cos(pba::kPi / 6), 5e-3);
        EXPECT_LT(glm::length(s.linear_velocity(body)), 1e-2);
      }
    }
}

}  // namespace
