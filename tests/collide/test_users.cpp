// The collide module's users against hulls, meshes and compounds: particles (the fused
// kernel and the generic integrator path) caught at 300 m/s, bouncing to e^2 of the drop,
// sliding across a mesh's internal edges without a bump; cloth resting on a hull and a
// mesh; a rope coming to rest over a capsule; a jelly on a mesh bowl.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <vector>

#include "pba/collide.h"
#include "pba/particles.h"
#include "pba/soft.h"
#include "users_shapes.h"

namespace {

using pba::Collider;
using pba::ColliderShape;
using pba::Method;
using pba::ParticleSystem;
using pba::Pose;
using pba::Quat;
using pba::Vec3;
namespace tu = pba::test_users;

constexpr double kFloatEps = 1.1920929e-7;

ParticleSystem make_system(Method m) {
  pba::ParticleSystemDef def;
  def.method = m;
  def.capacity = 16;
  return ParticleSystem(def);
}

// ---------------------------------------------------------------------------------------
// no tunnelling: at 300 m/s (5 m per step at 60 Hz) a 1 cm particle hits a 2 cm hull
// slab, a 5 cm octahedron, a mesh sheet of no thickness, a compound's thin child, and a
// hull moving towards it; with e = 0 it stays on the near side

TEST(UsersTunnelling, FastParticlesAreCaughtByHullsMeshesAndCompounds) {
  const double h = 1.0 / 60;
  const std::vector<pba::CompoundChild> thin = {{ColliderShape::box({0.01, 1, 1}), Pose{{0.5, 0, 0}}}};
  const std::vector<Collider> shapes = {
      tu::place(ColliderShape::convex(pba::ConvexHull::box({0.01, 1, 1})), {0, 0, 0}, {.restitution = 0}),
      tu::place(ColliderShape::convex(tu::octahedron_hull(0.05)), {0, 0, 0}, {.restitution = 0}),
      tu::place(ColliderShape::triangles(tu::sheet_mesh()), {0, 0, 0}, {.restitution = 0}),
      tu::place(tu::compound_shape(pba::CompoundShape::build(thin)), {-0.5, 0, 0}, {.restitution = 0}),
  };
  for (Method m : {Method::SemiImplicitEuler, Method::Rk4}) {
    for (std::size_t k = 0; k < shapes.size(); ++k) {
      ParticleSystem ps = make_system(m);
      ps.forces().gravity = Vec3(0);
      ps.create({.position = {-3, 0, 0}, .velocity = {300, 0, 0}, .mass = 1, .radius = 0.01});
      double t = 0;
      for (int i = 0; i < 5; ++i, t += h) ps.step(t, h, std::span(&shapes[k], 1), {});
      EXPECT_LT(ps.position(0).x, 0.0) << "shape " << k << " " << pba::name(m);
      EXPECT_GT(ps.position(0).x, -0.1) << "shape " << k << " " << pba::name(m);  // it got there
    }
    // a particle at rest and a thin hull slab sweeping through it at 300 m/s: pushed along
    ParticleSystem ps = make_system(m);
    ps.forces().gravity = Vec3(0);
    ps.create({.position = {0, 0, 0}, .mass = 1, .radius = 0.01});
    Collider slab = tu::place(ColliderShape::convex(pba::ConvexHull::box({0.01, 1, 1})), {-3, 0, 0},
                              {.restitution = 0});
    slab.velocity = {300, 0, 0};
    double t = 0;
    for (int i = 0; i < 3; ++i, t += h) {
      slab.begin = slab.end;
      slab.end.position.x += 300 * h;
      ps.step(t, h, std::span(&slab, 1), {});
    }
    EXPECT_GT(ps.position(0).x, slab.end.position.x) << "moving slab " << pba::name(m);
  }
}

// A hull of a box's corners is that box: particles thrown at it from every side follow
// the same paths as against the closed-form box. The hull's contact runs in double and the
// box's in float, so they agree to float rounding: at most an ulp or two of the state per
// step (positions within 2 m: 2.4e-7 m; speeds of 4 m/s: 4.8e-7 m/s) over 90 steps, 2e-5 m
// and 4e-5 m/s (measured: under 1e-7 m)
TEST(UsersHull, BoxHullMatchesTheBox) {
  const Vec3 half(0.4, 0.25, 0.3);
  const Quat q = glm::normalize(Quat(0.9, 0.2, -0.3, 0.1));
  const Collider box = Collider::box({0.1, 0.2, -0.1}, half, {.restitution = 0.7, .friction = 0.1}, q);
  const Collider hull = tu::place(ColliderShape::convex(pba::ConvexHull::box(half)), {0.1, 0.2, -0.1},
                                  {.restitution = 0.7, .friction = 0.1}, q);
  ParticleSystem a = make_system(Method::SemiImplicitEuler), b = make_system(Method::SemiImplicitEuler);
  a.forces().gravity = b.forces().gravity = Vec3(0);  // straight paths: every one hits
  std::uint32_t seed = 12345;
  auto uniform = [&seed] {
    seed = seed * 1664525u + 1013904223u;
    return (seed >> 8) * (1.0 / 16777216.0);
  };
  for (int i = 0; i < 16; ++i) {
    // from a sphere of radius 1.2 about the box, aimed at a point inside it
    const Vec3 d = glm::normalize(Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5));
    const Vec3 from = Vec3(0.1, 0.2, -0.1) + 1.2 * d;
    const Vec3 aim = Vec3(0.1, 0.2, -0.1) + 0.2 * Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5);
    const pba::ParticleDef p{.position = from, .velocity = 4.0 * glm::normalize(aim - from), .mass = 0.1, .radius = 0.02};
    a.create(p);
    b.create(p);
  }
  std::size_t contacts = 0;
  for (int i = 0; i < 90; ++i) {
    a.step(i / 120.0, 1 / 120.0, std::span(&box, 1), {});
    b.step(i / 120.0, 1 / 120.0, std::span(&hull, 1), {});
    contacts += b.contacts();
  }
  EXPECT_GE(contacts, 16u);
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_LT(glm::length(a.position(k) - b.position(k)), 2e-5) << "particle " << k;
    EXPECT_LT(glm::length(a.velocity(k) - b.velocity(k)), 4e-5) << "particle " << k;
  }
}

// Moving surfaces: a hull, a mesh and a compound rising at 0.5 m/s (begin and end poses
// each step, like a kinematic entity's) carry a particle resting on their tops: it is
// never below the top at the end of a step (less float rounding, 1e-5 m at 1 m), and
// after 1 s it is 0.5 m up, moving with the surface.
TEST(UsersMoving, RisingHullMeshAndCompoundCarryAParticle) {
  const double h = 1.0 / 120, r = 0.05, speed = 0.5;
  const std::vector<ColliderShape> shapes = {ColliderShape::convex(tu::frustum_hull()),
                                             ColliderShape::triangles(tu::grid_mesh(8, 0.25)),
                                             tu::compound_shape(tu::table_compound())};
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    ParticleSystem ps = make_system(Method::SemiImplicitEuler);
    ps.create({.position = {0.05, r, 0.1}, .mass = 1, .radius = r});
    double t = 0;
    for (int i = 0; i < 120; ++i, t += h) {
      Collider lift = tu::place(shapes[k], {0, speed * t, 0}, {.restitution = 0});
      lift.end.position = Vec3(0, speed * (t + h), 0);
      lift.velocity = Vec3(0, speed, 0);
      ps.step(t, h, std::span(&lift, 1), {});
      ASSERT_GE(ps.position(0).y, speed * (t + h) + r - 1e-5) << "shape " << k << " step " << i;
    }
    EXPECT_NEAR(ps.position(0).y, speed * 1.0 + r, 1e-3) << "shape " << k;
    EXPECT_NEAR(ps.velocity(0).y, speed, 1e-4) << "shape " << k;
  }
}

// ---------------------------------------------------------------------------------------
// restitution: dropped from H onto a hull's top face, a flat mesh (onto one of its
// internal vertices, where six triangles meet) and a compound's top, the rebound reaches
// e^2 H within 3%. The response splits the step at the time of impact and is exact for
// constant acceleration; what is left is the integrator's error, at most g t h / 2 per
// leg for first-order methods (h = 1/960 s keeps that below 1%) and none for RK4.

TEST(UsersBounce, ReboundsToESquaredHeight) {
  const double H = 1.0, r = 0.05;
  for (Method m : {Method::SemiImplicitEuler, Method::Rk4}) {
    const double h = pba::order(m) == 1 ? 1.0 / 960 : 1.0 / 120;
    for (double e : {0.5, 0.9}) {
      const pba::SurfaceMaterial mat{.restitution = e};
      const std::vector<Collider> shapes = {
          tu::place(ColliderShape::convex(tu::frustum_hull()), {0, 0, 0}, mat),
          tu::place(ColliderShape::triangles(tu::grid_mesh(10, 0.2)), {0, 0, 0}, mat),
          tu::place(tu::compound_shape(tu::table_compound()), {0, 0, 0}, mat),
      };
      for (std::size_t k = 0; k < shapes.size(); ++k) {
        ParticleSystem ps = make_system(m);
        ps.create({.position = {k == 1 ? 0.0 : 0.1, H + r, k == 1 ? 0.0 : -0.2}, .mass = 0.1, .radius = r});
        double t = 0, apex = -1;
        bool bounced = false;
        for (int i = 0; i < 4000; ++i, t += h) {
          ps.step(t, h, std::span(&shapes[k], 1), {});
          bounced |= ps.contacts() > 0;
          if (bounced) apex = std::max(apex, ps.position(0).y - r);
          if (bounced && ps.velocity(0).y < 0 && apex > 0) break;
        }
        EXPECT_NEAR(apex, e * e * H, 0.03 * e * e * H) << pba::name(m) << " e=" << e << " shape " << k;
        // straight up: no normal but the face's (a ghost normal would throw it sideways)
        EXPECT_LT(std::abs(ps.velocity(0).x) + std::abs(ps.velocity(0).z), 1e-6) << "shape " << k;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------
// sliding across internal edges: a particle resting on a flat mesh of 3200 triangles,
// pushed sideways without friction, crosses about 60 internal edges in a second. The
// contact removes the normal velocity gravity adds each step and nothing else, so the
// normal velocity stays 0 and the tangential velocity unchanged, to float rounding; a
// ghost normal at an edge would kick it up and slow it down.

TEST(UsersSliding, AcrossInternalMeshEdgesWithoutABump) {
  const double h = 1.0 / 120, r = 0.02;
  const Collider floor = tu::place(ColliderShape::triangles(tu::grid_mesh(40, 0.05)), {0, 0, 0},
                                   {.restitution = 0.5, .friction = 0});
  for (Method m : {Method::SemiImplicitEuler, Method::Rk4}) {
    ParticleSystem ps = make_system(m);
    const Vec3 v0(1.5, 0, 0.4);
    ps.create({.position = {-0.9, r, 0.013}, .velocity = v0, .mass = 0.1, .radius = r});
    double t = 0, worst_vy = 0, worst_y = 0, worst_vt = 0;
    for (int i = 0; i < 120; ++i, t += h) {
      ps.step(t, h, std::span(&floor, 1), {});
      worst_vy = std::max(worst_vy, std::abs(ps.velocity(0).y));
      worst_y = std::max(worst_y, std::abs(ps.position(0).y - r));
      worst_vt = std::max(worst_vt, glm::length(Vec3(ps.velocity(0).x, 0, ps.velocity(0).z) - v0));
    }
    EXPECT_NEAR(ps.position(0).x, -0.9 + 1.5 * 120 * h, 1e-3) << pba::name(m);
    // the height and the velocity are floats: a few ulps of their size
    EXPECT_LE(worst_vy, 4 * kFloatEps * 9.81 * h) << pba::name(m);
    EXPECT_LE(worst_y, 4 * kFloatEps * 1.0) << pba::name(m);
    EXPECT_LE(worst_vt, 4 * kFloatEps * glm::length(v0)) << pba::name(m);
  }
}

// Wedged: a particle slides down a 20-degree mesh slope into a capsule lying across it
// and rests in the wedge for 30 s. The capsule's response replays the step from its start,
// which lies inside the mesh's thickness when the two push against each other; the mesh,
// resolved last, pushes it out at the end of every step, so it never works its way
// through the two-sided mesh (its signed height above the slope stays >= r less float
// rounding), for the particles and for a rope.
TEST(UsersSliding, WedgedBetweenAMeshAndACapsuleStaysOnTheMesh) {
  const double h = 1.0 / 120, r = 0.05, tilt = 20 * std::numbers::pi / 180;
  const Quat q = glm::angleAxis(tilt, Vec3(0, 0, 1));  // the slope falls towards -x
  const Vec3 n = q * Vec3(0, 1, 0);
  // the mesh first: the order given would have the capsule respond after it
  const std::vector<Collider> shapes = {
      tu::place(ColliderShape::triangles(tu::grid_mesh(16, 0.125)), {0, 0, 0}, {.friction = 0.2}, q),
      tu::place(ColliderShape::capsule(1.0, 0.1), q * Vec3(-0.8, 0.1, 0), {.friction = 0.2},
                glm::angleAxis(std::numbers::pi / 2, Vec3(1, 0, 0))),
  };
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  ps.create({.position = q * Vec3(0.5, r, 0.01), .mass = 0.1, .radius = r});
  pba::SoftBody rope = pba::SoftBody::rope(
      {.from = q * Vec3(0.2, 0.06, -0.4), .to = q * Vec3(0.2, 0.06, 0.4), .segments = 8, .pin_start = false});
  double lowest = 1e9, rope_lowest = 1e9;
  for (int i = 0; i < 3600; ++i) {
    ps.step(i * h, h, shapes, {});
    rope.step(i * h, h, shapes);
    lowest = std::min(lowest, glm::dot(n, ps.position(0)));
    for (std::size_t k = 0; k < rope.size(); ++k) rope_lowest = std::min(rope_lowest, glm::dot(n, rope.position(k)));
  }
  EXPECT_GE(lowest, r - 1e-5);  // float rounding of positions near 1 m, with margin
  EXPECT_GE(rope_lowest, rope.settings().thickness - 1e-5);
  // it did reach the capsule: held against it, up the slope from its axis by R + r
  const Vec3 local = glm::inverse(q) * ps.position(0);
  EXPECT_NEAR(std::hypot(local.x + 0.8, local.y - 0.1), 0.1 + r, 1e-3);
}

// a particle rolling into a mesh bowl stays in it and settles at the bottom (friction)
TEST(UsersSliding, ParticleSettlesInAMeshBowl) {
  const double h = 1.0 / 120, r = 0.03;
  const Collider bowl = tu::place(ColliderShape::triangles(tu::bowl_mesh(16, 1.0, 0.5)), {0, 0, 0},
                                  {.restitution = 0.3, .friction = 0.4});
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  ps.create({.position = {0.6, 1.0, 0.3}, .mass = 0.1, .radius = r});
  double t = 0, lowest = 1e9;
  for (int i = 0; i < 1200; ++i, t += h) {
    ps.step(t, h, std::span(&bowl, 1), {});
    // never below the bowl: y >= k (x^2 + z^2) less the chord's sag (k w^2 / n^2 per cell)
    const Vec3 p = ps.position(0);
    lowest = std::min(lowest, p.y - 0.5 * (p.x * p.x + p.z * p.z));
  }
  EXPECT_GE(lowest, -0.5 * (2.0 / 16) * (2.0 / 16));
  EXPECT_LT(glm::length(Vec3(ps.position(0).x, 0, ps.position(0).z)), 0.15);
  EXPECT_LT(glm::length(ps.velocity(0)), 0.05);
}

// ---------------------------------------------------------------------------------------
// soft bodies

// the signed distance of a point from a collider's surface (point_distance: exact for
// hulls and compounds, unsigned for meshes)
double gap(const Collider& c, const Vec3& p) { return pba::point_distance(c.shape, c.end, p).distance; }

// Cloth dropped on a hull (XPBD and mass-spring): after the last substep's collision
// projection every particle is at least the thickness outside the hull, to float
// rounding (1e-6 m at 1 m); it comes to rest on the top face with the mean strain within
// the 1% the cloth tests hold (Cloth.HangingClothAtRest).
TEST(UsersCloth, RestsOnAHullAndAMesh) {
  const double th = 0.01;
  const std::vector<Collider> shapes = {
      tu::place(ColliderShape::convex(tu::frustum_hull()), {0, 0.5, 0}, {.friction = 0.4}),
      tu::place(ColliderShape::triangles(tu::grid_mesh(12, 0.1)), {0, 0.5, 0}, {.friction = 0.4},
                glm::angleAxis(0.3, Vec3(0, 1, 0))),
      tu::place(tu::compound_shape(tu::table_compound()), {0, 0.5, 0}, {.friction = 0.4}),
  };
  for (pba::SoftSolver solver : {pba::SoftSolver::Xpbd, pba::SoftSolver::MassSpring}) {
    for (std::size_t k = 0; k < shapes.size(); ++k) {
      pba::SoftBodyDef d;
      d.solver = solver;
      d.substeps = 10;
      d.thickness = th;
      d.damping = 1;
      if (solver == pba::SoftSolver::MassSpring) {
        d.stretch_stiffness = d.shear_stiffness = 2000;
        d.bend_stiffness = 1;
        d.spring_damping = 0.2;
        d.substeps = 20;
      }
      pba::SoftBody c = pba::SoftBody::cloth_grid(
          {.origin = {-0.4, 0.8, -0.4}, .edge_u = {0.8, 0, 0}, .edge_v = {0, 0, 0.8}, .nx = 12, .ny = 12,
           .pins = pba::ClothPins::None},
          d);
      double min_gap = 1e9;
      for (int i = 0; i < 180; ++i) {
        c.step(i / 60.0, 1.0 / 60, std::span(&shapes[k], 1));
        for (std::size_t p = 0; p < c.size(); ++p) min_gap = std::min(min_gap, gap(shapes[k], c.position(p)) - th);
      }
      const char* name = solver == pba::SoftSolver::Xpbd ? "xpbd" : "mass-spring";
      EXPECT_GE(min_gap, -1e-6) << name << " shape " << k;
      // it lies on the top (y = 0.5): the centre particle at the thickness above it
      EXPECT_NEAR(c.position(6 * 12 + 6).y, 0.5 + th, 0.01) << name << " shape " << k;
      EXPECT_LE(c.strain_stats().mean, 0.01) << name << " shape " << k;
      EXPECT_LT(c.kinetic_energy(), 1e-3) << name << " shape " << k;
    }
  }
}

// A rope dropped across a horizontal capsule (XPBD and mass-spring) comes to rest over
// it: no particle ever inside the capsule grown by the thickness by more than float
// rounding after a step, and at the end it is still (damping 2/s over 8 s leaves e^-16
// of its energy) with its middle on top of the capsule.
TEST(UsersRope, ComesToRestOverACapsule) {
  const double R = 0.2, th = 0.01, hh = 0.5;
  const Quat along_z = glm::angleAxis(std::numbers::pi / 2, Vec3(1, 0, 0));
  const Collider cap = tu::place(ColliderShape::capsule(hh, R), {0, 0.5, 0}, {.friction = 0.5}, along_z);
  for (pba::SoftSolver solver : {pba::SoftSolver::Xpbd, pba::SoftSolver::MassSpring}) {
    pba::SoftBodyDef d;
    d.solver = solver;
    d.substeps = 20;
    d.thickness = th;
    d.damping = 2;
    if (solver == pba::SoftSolver::MassSpring) {
      d.stretch_stiffness = 3000;
      d.bend_stiffness = 1;
      d.spring_damping = 0.5;
      d.substeps = 40;
    }
    pba::SoftBody rope = pba::SoftBody::rope(
        {.from = {-0.6, 0.9, 0.05}, .to = {0.6, 0.9, 0.05}, .segments = 30, .mass = 0.3, .pin_start = false});
    rope.settings() = d;
    double worst = 0;
    for (int i = 0; i < 480; ++i) {
      rope.step(i / 60.0, 1.0 / 60, std::span(&cap, 1));
      for (std::size_t p = 0; p < rope.size(); ++p) worst = std::min(worst, gap(cap, rope.position(p)) - th);
    }
    const char* name = solver == pba::SoftSolver::Xpbd ? "xpbd" : "mass-spring";
    EXPECT_GE(worst, -1e-6) << name;
    EXPECT_NEAR(rope.position(15).y, 0.5 + R + th, 0.01) << name;
    EXPECT_LT(rope.kinetic_energy(), 1e-4) << name;
  }
}

// A jelly dropped into a mesh bowl stays above the mesh and settles at the bottom.
TEST(UsersJelly, SettlesInAMeshBowl) {
  const Collider bowl = tu::place(ColliderShape::triangles(tu::bowl_mesh(16, 1.0, 0.5)), {0, 0, 0},
                                  {.friction = 0.5});
  pba::SoftBody j = pba::SoftBody::jelly_box({.center = {0, 0.5, 0}, .size = {0.3, 0.3, 0.3}});
  const double th = j.settings().thickness;
  double lowest = 1e9;
  for (int i = 0; i < 240; ++i) {
    j.step(i / 60.0, 1.0 / 60, std::span(&bowl, 1));
    for (std::size_t p = 0; p < j.size(); ++p) {
      const Vec3 x = j.position(p);
      lowest = std::min(lowest, x.y - 0.5 * (x.x * x.x + x.z * x.z));
    }
  }
  // above the bowl's surface (less the chords' sag, k (w/n)^2) by the thickness
  EXPECT_GE(lowest, th - 0.5 * (2.0 / 16) * (2.0 / 16) - 1e-6);
  EXPECT_LT(std::abs(j.center_of_mass().x), 0.05);
  EXPECT_LT(std::abs(j.center_of_mass().z), 0.05);
}

// ---------------------------------------------------------------------------------------
// the collision world: every shape type is taken, and copies stay linked to their own data

TEST(UsersWorld, TakesEveryShapeAndCopiesKeepTheirLinks) {
  pba::CollisionWorld cw;
  cw.add(tu::place(ColliderShape::convex(tu::frustum_hull()), {0, 0, 0}));
  cw.add(tu::place(ColliderShape::triangles(tu::grid_mesh(4, 0.5)), {3, 0, 0}));
  cw.add(tu::place(tu::compound_shape(tu::table_compound()), {-3, 0, 0}));
  pba::CollisionWorld copy = cw;
  cw.clear();
  for (int i = 0; i < 50; ++i) cw.add(Collider::sphere({0, 10.0 + i, 0}, 0.1));  // the old buffers go
  ASSERT_EQ(copy.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(copy.flat_double()[i].source, &copy.colliders()[i]);
    EXPECT_EQ(copy.flat_float()[i].source, &copy.colliders()[i]);
  }
  EXPECT_EQ(copy.flat_double()[2].n_parts, 3u);  // box, capsule and the nested foot's hull
  // a particle dropped on the copy's compound lands on its top
  ParticleSystem ps = make_system(Method::SemiImplicitEuler);
  ps.create({.position = {-3, 0.5, 0}, .mass = 0.1, .radius = 0.05});
  for (int i = 0; i < 120; ++i) ps.step(i / 60.0, 1.0 / 60, copy, {});
  EXPECT_NEAR(ps.position(0).y, 0.05, 1e-5);
  // replacing a compound in place: by one with as many leaves (its parts rewritten) and by
  // one with fewer (appended); the links follow either way
  pba::CollisionWorld one;
  one.add(tu::place(tu::compound_shape(tu::table_compound()), {0, 0, 0}));
  one.set(0, tu::place(tu::compound_shape(tu::table_compound()), {5, 0, 0}));
  EXPECT_EQ(one.flat_double()[0].first_part, 0u);
  EXPECT_EQ(one.flat_double()[0].parts[0].c1x, 5.0);
  const std::vector<pba::CompoundChild> ball = {{ColliderShape::sphere(0.5), Pose{{0, 1, 0}}}};
  one.set(0, tu::place(tu::compound_shape(pba::CompoundShape::build(ball)), {-5, 0, 0}));
  ASSERT_EQ(one.flat_double()[0].n_parts, 1u);
  EXPECT_EQ(one.flat_float()[0].parts[0].type, pba::ShapeType::Sphere);
  EXPECT_EQ(one.flat_float()[0].parts[0].c1y, 1.0);
  EXPECT_EQ(one.flat_float()[0].parts[0].c1x, -5.0);
  // a collider without its body names the field
  Collider bad;
  bad.shape.type = pba::ShapeType::Hull;
  try {
    cw.add(bad, pba::CollisionWorld::kNoOwner, "colliders[7]");
    FAIL() << "no error";
  } catch (const pba::Error& e) {
    EXPECT_NE(std::string(e.what()).find("colliders[7]"), std::string::npos) << e.what();
  }
}

}  // namespace
