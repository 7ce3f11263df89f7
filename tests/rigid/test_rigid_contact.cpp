// Rigid contacts: restitution, elastic collisions, Coulomb friction on inclines, rolling,
// tipping and stacking, each against its closed form, under every solver the physics applies to
// (the substepping ones: soft step, TGS and XPBD; sequential impulses where it meets it).
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "pba/rigid.h"
#include "pba/rigid_scenes.h"
#include "rigid/contacts.h"  // the tree order's sort, tested directly
#include "pile_motion.h"
#include "rod_drops.h"

using pba::ContactSettings;
using pba::BodyType;
using pba::ColliderShape;
using pba::Quat;
using pba::RigidBodySystem;
using pba::RigidShapeDef;
using pba::Vec3;

namespace {

constexpr double kG = 9.81;
const Vec3 kGravity{0, -kG, 0};

double deg(double d) { return d * pba::kPi / 180; }

// the solvers that substep (the soft step, TGS, XPBD), and every solver
constexpr pba::RigidSolverType kSubstepping[] = {pba::RigidSolverType::SoftStep, pba::RigidSolverType::Tgs,
                                                 pba::RigidSolverType::Xpbd};
constexpr auto kAll = pba::kRigidSolvers;
pba::RigidSystemDef with(pba::RigidSolverType solver) { return {.contacts = {.solver = solver}}; }

// a static ground plane y = 0 (or tilted by `angle` about z), with a material
pba::RigidBodyId ground(RigidBodySystem& s, double friction = 0.5, double restitution = 0, double angle = 0) {
  const Vec3 n{-std::sin(angle), std::cos(angle), 0};
  return s.create({.name = "ground", .type = BodyType::Static,
                   .shapes = {{.shape = ColliderShape::plane(n, 0),
                               .material = {.restitution = restitution, .friction = friction}}}});
}

RigidShapeDef box_shape(const Vec3& half, double friction = 0.5, double density = 1000) {
  return {.shape = ColliderShape::box(half), .density = density, .material = {.restitution = 0, .friction = friction}};
}

// ---------------------------------------------------------------------------------------
// restitution

// A sphere dropped from rest with its bottom h above the ground rebounds to e^2 h. The
// ball's bottom height at the top of the bounce is measured as the largest height after the
// first contact. Symplectic Euler's flight costs O(g h / v) of it: 1.6% for e = 1 and 2.5%
// for e = 0.5 at 240 Hz (the soft step's 4 substeps of a 60 Hz step), and 4-8% at 60 Hz,
// so the one-step sequential-impulse solver runs at 240 Hz here to compare like with like.
TEST(RigidRestitution, ASphereReboundsToESquaredOfItsHeight) {
  const double h = 1.0, r = 0.1;
  for (const auto solver : kAll) {
    for (const double e : {0.0, 0.5, 0.9, 1.0}) {
      RigidBodySystem s({.contacts = {.solver = solver}});
      ground(s, 0.0, e);
      auto ball = s.create({.name = "ball", .pose = {{0, h + r, 0}},
                            .shapes = {{.shape = ColliderShape::sphere(r), .material = {.restitution = e}}}});
      bool bounced = false;
      double peak = 0;
      const int per_frame = solver == pba::RigidSolverType::SequentialImpulse ? 4 : 1;
      for (int i = 0; i < 240 * per_frame; ++i) {
        s.step(1.0 / 60 / per_frame, kGravity);
        const double y = s.center_of_mass(ball).y - r, vy = s.linear_velocity(ball).y;
        if (!bounced && vy > 0) bounced = true;
        if (bounced) peak = std::max(peak, y);
        if (bounced && vy < 0 && y < peak - 0.05) break;  // on the way down again
      }
      if (e == 0) {
        EXPECT_LT(peak, 0.01) << to_string(solver);
      } else {
        EXPECT_NEAR(peak, e * e * h, 0.03 * e * e * h) << to_string(solver) << " e = " << e;
      }
    }
  }
}

// The same over the input range: e from 0.2 to 1, drops of 0.2 to 2 m, balls of 5 cm to 1 m,
// the three substepping solvers. The apex is read from the state at the end of the bounce
// step, y + vy^2 / (2 g), not sampled at 60 Hz (a sampled peak misses the apex by up to
// g dt^2 / 8 = 0.34 mm, 4% of a 0.2 m drop at e = 0.2). The bound is symplectic Euler's: the
// fall and the rise each lose at most v h / 2 of height at the substep h, and XPBD bounces
// within the step, then rises for the rest of it (measured: soft step and TGS within 0.4%
// of e^2 h, XPBD within 0.55 of the bound). The 5 cm ball drops at most 0.5 m: faster, it
// outruns its speculative margin (its size) and the continuous pass puts it back to its time
// of impact (docs/rigid-bodies.md): from 3 m, 0.86% over e^2 h with the step's end velocity
// kept, 0.09% since it takes the velocity at the time of impact (e = 1: 0.27% under, where
// the fall's own loss, e^2 v h / 2, adds to this bound's).
TEST(RigidRestitution, TheApexIsESquaredOfTheDropOverTheInputRange) {
  for (const auto solver : kSubstepping)
  for (const double e : {0.2, 0.5, 0.8, 1.0})
  for (const double r : {0.05, 0.5})
  for (const double h : {0.2, 0.5, 2.0}) {
    if (r < 0.1 && h > 0.5) continue;
    RigidBodySystem s(with(solver));
    ground(s, 0.0, e);
    auto ball = s.create({.pose = {{0, h + r, 0}}, .shapes = {{.shape = ColliderShape::sphere(r), .material = {.restitution = e}}}});
    double apex = -1;
    for (int i = 0; i < 120 && apex < 0; ++i) {
      s.step(1.0 / 60, kGravity);
      const double y = s.center_of_mass(ball).y - r, vy = s.linear_velocity(ball).y;
      if (vy > 0) apex = y + vy * vy / (2 * kG);
    }
    const double v = e * std::sqrt(2 * kG * h), substep = 1.0 / 60 / s.settings().substeps;
    EXPECT_NEAR(apex, e * e * h, v * substep / 2)
        << to_string(solver) << " e = " << e << " r = " << r << " h = " << h;
  }
}

// A 2 m cube falling face down at 11.6 m/s (the top of Jolt's pyramid lands so) onto a cube,
// static or resting on the ground, e = 0: face on face, it has no reason to turn or slide,
// and its speculative contact (made 5 cm above, the step closing 19 cm) stops it on the face.
// Its manifold was one point (an edge pair tying with the face axis, collide's Margin test):
// the cube turned at 5.5 rad/s on a corner, sank 10 cm, bounced at 1.6 m/s and ended 16 cm
// aside. Bounds: turning under 0.05 rad/s, overlap under 1 cm (on the dynamic cube the
// impact's impulse passes to the ground's soft contact within the step: 8 mm measured,
// 0 on the static one), and the cube within 1 cm of the axis at the end.
TEST(RigidRestitution, AFastCubeLandingFaceOnOnACubeStopsWithoutTurning) {
  for (const BodyType below : {BodyType::Static, BodyType::Dynamic}) {
    RigidBodySystem s({.contacts = {.sleep = false}});
    ground(s, 0.5);
    const RigidShapeDef cube = box_shape(Vec3(1), 0.5);
    s.create({.type = below, .pose = {{0, 1, 0}}, .shapes = {cube}});
    auto top = s.create({.pose = {{0, 3.05, 0}}, .linear_velocity = {0, -11.6, 0}, .shapes = {cube}});
    double turn = 0, deepest = 0;
    for (int i = 0; i < 60; ++i) {
      s.step(1.0 / 60, kGravity);
      turn = std::max(turn, glm::length(s.angular_velocity(top)));
      deepest = std::max(deepest, 3 - s.center_of_mass(top).y);
    }
    const char* what = below == BodyType::Static ? "on a static cube" : "on a cube on the ground";
    EXPECT_LT(turn, 0.05) << what;
    EXPECT_LT(deepest, 0.01) << what;
    const Vec3 p = s.center_of_mass(top);
    EXPECT_LT(std::hypot(p.x, p.z), 0.01) << what;
    EXPECT_NEAR(p.y, 3, 0.01) << what;
  }
}

// A cube dropped face down onto a bouncy ground (e = 0.5 and 1) has no reason to turn: its
// four corners approach at the same speed and the restitution pass should give each the same
// impulse. It rebounds at e times the impact speed, straight up. The pass swept the
// manifold's points once, in order: the first corner's impulse turned the cube, which took
// approach from the next ones, and the approach speeds it bounces were read inside the
// solve's sweep, after the points before had turned the cube (7.0 to 7.7 m/s at the four
// corners): the cube left the ground turning at 1.8 to 4.5 rad/s, tumbled and landed metres aside (found dropping a box from 3 m in a
// scene file whose ground collider had the default restitution 0.5). Bounds: turning under
// 0.05 rad/s, as a face-on landing above; the rebound e sqrt(2 g H) from the drop H = 2.5 m
// within e g dt / 2 (the step's gravity puts the speed at the ground within half a step's
// of the closed form). Measured: turning 0.003 to 0.008 rad/s, rebounds within 0.4%.
TEST(RigidRestitution, ACubeBouncingFaceDownLeavesWithoutTurning) {
  for (const auto solver : kAll)
  for (const double e : {0.5, 1.0}) {
    RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
    ground(s, 0.5, e);
    const RigidShapeDef cube{.shape = ColliderShape::box(Vec3(0.5)),
                             .material = {.restitution = e, .friction = 0.5}};
    auto box = s.create({.pose = {{0, 3, 0}}, .shapes = {cube}});
    const double dt = 1.0 / 60, impact = std::sqrt(2 * kG * 2.5);
    double rebound = 0, turn = 0;
    for (int i = 0; i < 120 && rebound == 0; ++i) {
      s.step(dt, kGravity);
      if (s.linear_velocity(box).y > 0) rebound = s.linear_velocity(box).y;
      turn = std::max(turn, glm::length(s.angular_velocity(box)));
    }
    ASSERT_GT(rebound, 0) << to_string(solver) << " e = " << e;
    EXPECT_LT(turn, 0.05) << to_string(solver) << " e = " << e;
    EXPECT_NEAR(rebound, e * impact, e * kG * dt / 2) << to_string(solver) << " e = " << e;
  }
}

// Two frictionless boxes tumbling into each other with e = 1 in zero gravity: an elastic
// collision keeps the kinetic energy, and no restitution pass may add to it. XPBD bounced the
// manifold's points that had not pushed (corners not yet touching) at e times their approach,
// and the boxes left with 25% more energy than they met with (over 200 such collisions the
// largest gain is now 3.7% under XPBD, 3% under the others: Newton's law at several points at
// once is not energy-exact, as at this pair's second touch, 2.1% under the soft step). This
// pair's first impact, a corner on a face: XPBD gained 9.9% in it, now loses 3.6%; the impulse
// solvers gain 0.02%. Bound: 0.1%, far above the free rotation's O(h^2) energy error (1e-6).
TEST(RigidRestitution, AnElasticCollisionOfTumblingBoxesAddsNoEnergy) {
  const RigidShapeDef box{.shape = ColliderShape::box({0.5, 0.3, 0.2}), .material = {.restitution = 1, .friction = 0}};
  for (const auto solver : kAll) {
    RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
    auto a = s.create({.pose = {{-1.5, 0.1273350276847752, 0.15379792988290511},
                                glm::normalize(Quat(-0.061982843963711919, 0.14574301342083226, -0.62833976882255482,
                                                    -0.76164705474990424))},
                       .linear_velocity = {3, 0, 0},
                       .angular_velocity = {0.8214837048146173, -0.60022696544497112, -0.8912074876138345},
                       .shapes = {box}});
    auto b = s.create({.pose = {{1.5, 0, 0}, glm::normalize(Quat(0.89664843022352569, 0.068728207226389157,
                                                                 0.42561212379081842, 0.10075885167767108))},
                       .linear_velocity = {-3, 0, 0},
                       .angular_velocity = {0.22380134494508996, 0.059093216542212446, -0.31662011134632195},
                       .shapes = {box}});
    const double e0 = s.kinetic_energy(a) + s.kinetic_energy(b);
    // up to the end of the step in which they meet (a's velocity changes by metres a second)
    int steps = 0;
    while (glm::length(s.linear_velocity(a) - Vec3(3, 0, 0)) < 1 && steps < 60) s.step(1.0 / 60, Vec3(0)), ++steps;
    ASSERT_LT(steps, 60) << to_string(solver);
    EXPECT_LT(s.kinetic_energy(a) + s.kinetic_energy(b), e0 * (1 + 1e-3)) << to_string(solver);
  }
}

// Equal masses, e = 1, head on: the velocities swap and the momentum is kept.
TEST(RigidRestitution, EqualMassesSwapVelocitiesInAnElasticHeadOnCollision) {
  for (const auto solver : kAll) {
    RigidBodySystem s({.contacts = {.solver = solver}});
    const std::vector<RigidShapeDef> ball{{.shape = ColliderShape::sphere(0.25), .material = {.restitution = 1}}};
    auto a = s.create({.name = "a", .pose = {{-1, 0, 0}}, .linear_velocity = {2, 0, 0}, .shapes = ball});
    auto b = s.create({.name = "b", .pose = {{1, 0, 0}}, .linear_velocity = {-1, 0, 0}, .shapes = ball});
    const Vec3 p0 = s.mass(a) * s.linear_velocity(a) + s.mass(b) * s.linear_velocity(b);
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, Vec3(0));
    EXPECT_NEAR(s.linear_velocity(a).x, -1, 1e-3) << to_string(solver);
    EXPECT_NEAR(s.linear_velocity(b).x, 2, 1e-3) << to_string(solver);
    const Vec3 p1 = s.mass(a) * s.linear_velocity(a) + s.mass(b) * s.linear_velocity(b);
    EXPECT_LT(glm::length(p1 - p0) / glm::length(p0), 1e-5) << to_string(solver);
  }
}

// A glancing elastic impact (docs/rigid-bodies.md, "Oblique impacts of fast bodies"): a 1 kg
// ball (r = 0.1 m) on the x axis at 3 m/s, spinning at `spin` (rad/s), strikes a resting 10 kg
// ball of the same size (of type `type_b`) whose centre is `offset` off that line; e = 1, mu = 0,
// no gravity. Returns the bodies' velocities after they part, their spins and the angular
// momentum about the origin (kg m^2/s, 0 before without spin).
struct Glance {
  Vec3 va, vb, wa, wb;
  double momentum_z = 0;
};
Glance glance(pba::RigidSolverType solver, double dt, double offset, double start_x = -0.5,
              BodyType type_b = BodyType::Dynamic, Vec3 spin = Vec3(0)) {
  RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
  const RigidShapeDef ball{.shape = ColliderShape::sphere(0.1), .material = {.restitution = 1, .friction = 0}};
  const auto a = s.create({.pose = {{start_x, 0, 0}}, .linear_velocity = {3, 0, 0}, .angular_velocity = spin,
                           .shapes = {ball}, .mass = pba::RigidMass::sphere(1, 0.1)});
  const auto b = s.create(
      {.type = type_b, .pose = {{0, offset, 0}}, .shapes = {ball}, .mass = pba::RigidMass::sphere(10, 0.1)});
  for (int i = 0; i < static_cast<int>(0.5 / dt); ++i) s.step(dt, Vec3(0));
  Glance g{s.linear_velocity(a), s.linear_velocity(b), s.angular_velocity(a), s.angular_velocity(b)};
  for (const auto body : {a, b})
    if (body == a || type_b == BodyType::Dynamic)
      g.momentum_z += (s.mass(body) * glm::cross(s.center_of_mass(body), s.linear_velocity(body)) +
                       s.angular_momentum(body)).z;
  return g;
}

// Off line, the balls touch with their centres R = 0.2 m apart along n = (sqrt(R^2 - b^2), b) / R
// (b the offset: 48.6 degrees from the striker's path at b = 0.15 m), and the closed form
// gives the struck ball J n / m_b, J = (1 + e) m_a m_b / (m_a + m_b) v . n, the striker
// v - J n / m_a. The speculative point of the step in which they touch is made along that n
// (touch_normal in src/rigid/contact_pairs.cpp; the line of centres of the step's start, 3.6
// degrees off at 60 Hz, 11.7 at 30, was main's: the struck ball left at 36.9 degrees at 30 Hz).
// Each ball's lever arm goes from its centre along n (ContactPair::balls), so the push turns
// neither ball (FrictionlessBallsTurnNeitherBallInAGlancingImpact) and J is the closed form's
// (with the one shared point midway, off the centres' line by up to v_perp dt / 2, J fell short
// by the share its lever added to the effective mass, 1.1% at 60 Hz, and the balls turned).
// The impulse acts on the bodies where they are at the step's start, whose centres lie off
// that n by the path still to go to the touch, v_perp t (t up to the step; v_perp = |v x n|),
// so the angular momentum about the origin (0 before) takes its moment there, and the bounce
// comes at the end of the step, not at the touch, so the bodies end it v . n (dt - t) short
// along n: |L| <= J v_perp t + mu v . n v_perp (dt - t) <= J v_perp dt (J = 2 mu v . n, mu
// the reduced mass; main's -0.0916 at 60 Hz, the same late parting along its own normal).
// 1e-6 of the direction (rad), of the speeds (m/s) and of J (N s) allow the contact's float
// rows' rounding (2^-24 of the 3 m/s they carry, a few operations), as the head-on test in
// test_rigid_params.cpp.
TEST(RigidRestitution, AGlancingImpactPushesAlongTheLineOfCentresAtTheTouch) {
  const double ma = 1, mb = 10, r = 0.2;
  for (const auto solver : kAll)
    for (const double hz : {30.0, 60.0, 240.0})
      for (const double offset : {0.0, 0.15}) {
        const double dt = 1 / hz;
        const Glance g = glance(solver, dt, offset);
        const Vec3 n{std::sqrt(r * r - offset * offset) / r, offset / r, 0};
        const double along = 3 * n.x, across = 3 * n.y;  // v . n and |v x n| (m/s)
        const double j = 2 * ma * mb / (ma + mb) * along;
        const std::string what = std::string(to_string(solver)) + " at " + std::to_string(hz) + " Hz, offset " +
                                 std::to_string(offset);
        // the struck ball along n with J; the striker by the momentum
        const double jb = mb * glm::length(g.vb);
        EXPECT_LT(std::abs(std::atan2(glm::cross(n, g.vb).z, glm::dot(n, g.vb))), 1e-6) << what;
        EXPECT_NEAR(jb, j, 1e-6) << what;
        EXPECT_LT(glm::length(g.va - (Vec3(3, 0, 0) - jb / ma * n)), 1e-6) << what;
        // the angular momentum about the origin
        EXPECT_LE(std::abs(g.momentum_z), j * across * dt + 1e-9) << what;
      }
}

// Smooth balls push each other along the normal through both centres, so a frictionless
// impact turns neither ball and leaves a striker's own spin as it was: the glancing impact
// above (b = 0.15 m, touching along n at 48.6 degrees) against a resting ball of 10 kg and
// against a static one, the striker not spinning and spinning at 50 rad/s about z (the axis the
// off-line push turned it about), under every solver at 30, 60 and 240 Hz. The closed form:
// the struck ball leaves at J n / m_b, the striker at v - J n / m_a, J = (1 + e) v . n over
// 1 / m_a + 1 / m_b (1 / m_a against the static ball: the striker reflected about the plane
// of n), and with e = 1 the kinetic energy, spin included, is kept. The solver's lever arms from
// the one shared point, midway between the balls at the step's start and off the line of
// centres by up to v_perp dt / 2 when the normal is the touch's, gave the push a moment about
// each centre (the soft step at 30 Hz against the static ball: the striker spun at -21.7 rad/s,
// 0.94 J of its 4.5 J; a 50 rad/s spin fell to 17.7 rad/s); each ball's arm now goes from its
// centre along n (ContactPair::balls). The spins to 1e-9 rad/s and 1e-9 of the spin: the arms'
// remaining rounding (a scalar times n, crossed with n) gives about 1e-16; the velocities to
// 1e-6 m/s and the energy to 1e-6 of it (the float rows' rounding, as the test above).
TEST(RigidRestitution, FrictionlessBallsTurnNeitherBallInAGlancingImpact) {
  const double ma = 1, mb = 10, ia = 0.4 * ma * 0.01, ib = 0.4 * mb * 0.01, r = 0.2, offset = 0.15;
  const Vec3 n{std::sqrt(r * r - offset * offset) / r, offset / r, 0};
  for (const auto solver : kAll)
    for (const double hz : {30.0, 60.0, 240.0})
      for (const BodyType type_b : {BodyType::Dynamic, BodyType::Static})
        for (const double spin : {0.0, 50.0}) {
          const Glance g = glance(solver, 1 / hz, offset, -0.5, type_b, Vec3(0, 0, spin));
          const bool moves = type_b == BodyType::Dynamic;
          const double j = 2 * 3 * n.x / (1 / ma + (moves ? 1 / mb : 0));
          const std::string what = std::string(to_string(solver)) + " at " + std::to_string(hz) + " Hz, " +
                                   (moves ? "dynamic" : "static") + ", spin " + std::to_string(spin);
          EXPECT_LE(glm::length(g.wa - Vec3(0, 0, spin)), 1e-9 * std::max(spin, 1.0)) << what;
          EXPECT_LE(glm::length(g.wb), 1e-9) << what;
          EXPECT_LT(glm::length(g.va - (Vec3(3, 0, 0) - j / ma * n)), 1e-6) << what;
          EXPECT_LT(glm::length(g.vb - (moves ? j / mb * n : Vec3(0))), 1e-6) << what;
          const double before = 0.5 * ma * 9 + 0.5 * ia * spin * spin;
          const double after = 0.5 * ma * glm::dot(g.va, g.va) + 0.5 * ia * glm::dot(g.wa, g.wa) +
                               (moves ? 0.5 * mb * glm::dot(g.vb, g.vb) + 0.5 * ib * glm::dot(g.wb, g.wb) : 0);
          EXPECT_NEAR(after, before, 1e-6 * before) << what;
        }
}

// A ball that passes a resting one at 3 mm and 1 cm of clearance (b = 0.203 and 0.21 m, the
// balls 0.2 m across their centres) never touches it: no impulse, the velocities as they were,
// under every solver at 30, 60 and 240 Hz. The speculative point along the line of centres of
// the step's start made a plane the passing ball crossed though the ball did not (main
// deflected it by 2.16 m/s at 30 Hz with 3 mm to spare and 0.63 m/s at 60 Hz); along the line
// of centres of the closest approach (touch_normal) the ball's path stays at the same distance
// from the plane all step. 1e-12 m/s: nothing acts.
TEST(RigidRestitution, ABallPassingCloseByIsNotDeflected) {
  for (const auto solver : kAll)
    for (const double hz : {30.0, 60.0, 240.0})
      for (const double offset : {0.203, 0.21}) {
        const Glance g = glance(solver, 1 / hz, offset);
        const std::string what = std::string(to_string(solver)) + " at " + std::to_string(hz) + " Hz, offset " +
                                 std::to_string(offset);
        EXPECT_LT(glm::length(g.va - Vec3(3, 0, 0)), 1e-12) << what;
        EXPECT_LT(glm::length(g.vb), 1e-12) << what;
        EXPECT_LT(glm::length(g.wa) + glm::length(g.wb), 1e-12) << what;
      }
}


// A ball or a capsule glancing off a capsule at 10 m/s (docs/rigid-bodies.md, "Oblique impacts
// of fast bodies"), no gravity, mu = 0, restitution `e`: a striker of 1 kg (isotropic inertia
// 0.004 kg m^2) on the x axis, a ball of radius 0.1 m or a capsule of radius 0.1 m and core
// half length 0.3 m along z; the struck body a capsule of the same size, 10 kg (isotropic
// inertia 0.04 kg m^2), dynamic or static. `cap` false: the struck capsule lies along z at
// (0, offset, 0) and a ball strikes its side (its cylinder); true: it stands along y with its
// lower end ball's centre at (0, offset, 0), struck by the capsule along z. Returns the
// velocities and spins after 0.5 s.
struct CapsuleGlance {
  Vec3 va, vb, wa, wb;
};
CapsuleGlance capsule_glance(pba::RigidSolverType solver, double dt, double offset, bool cap, double e,
                             BodyType type_b) {
  RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
  const pba::SurfaceMaterial smooth{.restitution = e, .friction = 0};
  const Quat along_z = glm::angleAxis(std::acos(0.0), Vec3(1, 0, 0));  // local +y to z
  const RigidShapeDef ball{.shape = ColliderShape::sphere(0.1), .material = smooth};
  const RigidShapeDef capsule{.shape = ColliderShape::capsule(0.3, 0.1), .material = smooth};
  const auto a = s.create({.pose = {{-0.5, 0, 0}, cap ? along_z : Quat(1, 0, 0, 0)},
                           .linear_velocity = {10, 0, 0},
                           .shapes = {cap ? capsule : ball},
                           .mass = pba::RigidMass{.mass = 1, .inertia = pba::Mat3(0.004)}});
  const auto b = s.create({.type = type_b,
                           .pose = {cap ? Vec3(0, offset + 0.3, 0) : Vec3(0, offset, 0), cap ? Quat(1, 0, 0, 0) : along_z},
                           .shapes = {capsule},
                           .mass = pba::RigidMass{.mass = 10, .inertia = pba::Mat3(0.04)}});
  for (int i = 0; i < static_cast<int>(0.5 / dt); ++i) s.step(dt, Vec3(0));
  return {s.linear_velocity(a), s.linear_velocity(b), s.angular_velocity(a), s.angular_velocity(b)};
}

// The closed form: the bodies touch with the ball's centre (the capsule striker's core point at
// its middle) R = 0.2 m from the struck capsule's core along n = (sqrt(R^2 - b^2), b, 0) / R (b
// the offset), perpendicular to the struck capsule's axis on its side. The frictionless
// impulse J n acts along the line through the striker's centre, so the striker does not turn;
// on the side the line passes through the struck capsule's axis at its centre of mass, so it
// does not turn either (no moment about its axis or any other); at the end ball it passes
// through that ball's centre, h = 0.3 m below the centre of mass, r_b = (0, -h, 0), and turns
// it at J (r_b x n) / I_b = J h n_x / I_b about z. J = (1 + e) v . n / k, k = 1 / m_a + 1 / m_b
// + |r_b x n|^2 / I_b (1 / m_a against a static body). Under every solver at 30, 60 and 240 Hz,
// e = 1 and 0, b = 0.15 m: velocities to 1e-6 m/s, spins to 1e-6 rad/s, energy at e = 1 to 1e-6
// of it, the momentum kept (the float rows' rounding of 10 m/s, as the balls' tests above).
TEST(RigidRestitution, AGlancingImpactOnACapsuleTakesTheNormalAtTheTouch) {
  const double ma = 1, mb = 10, ia = 0.004, ib = 0.04, r = 0.2, offset = 0.15, h = 0.3;
  const Vec3 n{std::sqrt(r * r - offset * offset) / r, offset / r, 0};
  for (const auto solver : kAll)
    for (const double hz : {30.0, 60.0, 240.0})
      for (const bool cap : {false, true})
        for (const double e : {1.0, 0.0})
          for (const BodyType type_b : {BodyType::Dynamic, BodyType::Static}) {
            const bool moves = type_b == BodyType::Dynamic;
            // (not covered, measured: sequential impulses at e = 0 fall short of J on the side and
            // the end ball, 1.24 m/s of the striker's velocity against the static capsule's side at
            // 30-240 Hz; at the dynamic end ball with e = 0 the soft step and TGS are 3.4e-3 m/s off
            // and sequential impulses 0.65; XPBD at the end ball, whose push turns the struck
            // capsule during the step, 0.074 / 0.070 / 0.020 m/s off at 30 / 60 / 240 Hz)
            const bool covered = cap ? e == 1 && solver != pba::RigidSolverType::Xpbd
                                     : e == 1 || solver != pba::RigidSolverType::SequentialImpulse;
            if (!covered) continue;
            const double arm = cap ? h * n.x : 0;  // |r_b x n| (m)
            const double k = 1 / ma + (moves ? 1 / mb + arm * arm / ib : 0);
            const double j = (1 + e) * 10 * n.x / k;
            const CapsuleGlance g = capsule_glance(solver, 1 / hz, offset, cap, e, type_b);
            const std::string what = std::string(to_string(solver)) + " at " + std::to_string(hz) + " Hz, " +
                                     (cap ? "capsule on the end ball" : "ball on the side") + ", e " +
                                     std::to_string(e) + (moves ? ", dynamic" : ", static");
            EXPECT_LT(glm::length(g.va - (Vec3(10, 0, 0) - j / ma * n)), 1e-6) << what << " va " << g.va.x << " " << g.va.y;
            EXPECT_LT(glm::length(g.vb - (moves ? j / mb * n : Vec3(0))), 1e-6) << what << " vb " << g.vb.x << " " << g.vb.y;
            // (the end ball's spin J h n_x / I_b, 31.5 rad/s, to 1e-7 of it: the float rows' 2^-24
            // of J, a few operations; no spin to 1e-9 rad/s, as the balls' test above)
            const double wb = moves ? j * arm / ib : 0;
            EXPECT_LT(glm::length(g.wa), 1e-9) << what << " wa " << g.wa.z;
            EXPECT_LT(glm::length(g.wb - Vec3(0, 0, wb)), 1e-9 + 1e-7 * wb) << what << " wb " << g.wb.z;
            if (moves) EXPECT_LT(glm::length(ma * g.va + mb * g.vb - Vec3(10 * ma, 0, 0)), 1e-6) << what;
            if (e == 1) {
              const double after = 0.5 * ma * glm::dot(g.va, g.va) + 0.5 * ia * glm::dot(g.wa, g.wa) +
                                   (moves ? 0.5 * mb * glm::dot(g.vb, g.vb) + 0.5 * ib * glm::dot(g.wb, g.wb) : 0);
              EXPECT_NEAR(after, 50 * ma, 1e-6 * 50 * ma) << what;
            }
          }
}

// A ball passing a capsule's side, or a capsule passing a capsule's end ball, 3 mm and 1 cm wide
// of touching (b = 0.203, 0.21 m) at 10 m/s never touches it: no impulse, the velocities as they
// were, under every solver at 30, 60 and 240 Hz. 1e-12 m/s: nothing acts.
TEST(RigidRestitution, ABodyPassingCloseByACapsuleIsNotDeflected) {
  for (const auto solver : kAll)
    for (const double hz : {30.0, 60.0, 240.0})
      for (const bool cap : {false, true})
        for (const double offset : {0.203, 0.21}) {
          const CapsuleGlance g = capsule_glance(solver, 1 / hz, offset, cap, 1, BodyType::Dynamic);
          const std::string what = std::string(to_string(solver)) + " at " + std::to_string(hz) + " Hz, " +
                                   (cap ? "capsule by the end ball" : "ball by the side") + ", offset " +
                                   std::to_string(offset);
          EXPECT_LT(glm::length(g.va - Vec3(10, 0, 0)), 1e-12) << what << " va.y " << g.va.y;
          EXPECT_LT(glm::length(g.vb), 1e-12) << what << " vb.y " << g.vb.y;
          EXPECT_LT(glm::length(g.wa) + glm::length(g.wb), 1e-12) << what << " wa " << g.wa.z << " wb " << g.wb.z;
        }
}
// The threshold is the least approach speed that bounces (ContactSettings: speeds below it
// lose their bounce): a ball meeting a wall at exactly the threshold, 1 m/s, e = 0.5, no
// gravity, leaves at e times it, 0.5 m/s, under every solver. XPBD tested `approach <
// -threshold` and stopped it dead (0 m/s) where the other three bounced at `<=`. The approach
// is -1 exactly (the ball's velocity is exact and the normal axis-aligned); the bounce is
// checked to 1e-3, as the head-on collision above.
TEST(RigidRestitution, ABallMeetingAWallAtExactlyTheThresholdBounces) {
  for (const auto solver : kAll) {
    RigidBodySystem s({.contacts = {.solver = solver, .restitution_threshold = 1, .sleep = false}});
    s.create({.name = "wall", .type = BodyType::Static,
              .shapes = {{.shape = ColliderShape::plane({-1, 0, 0}, -2), .material = {.restitution = 0.5, .friction = 0}}}});
    const auto ball = s.create({.linear_velocity = {1, 0, 0},
                                .shapes = {{.shape = ColliderShape::sphere(0.25), .material = {.restitution = 0.5, .friction = 0}}}});
    for (int i = 0; i < 180; ++i) s.step(1.0 / 60, Vec3(0));
    EXPECT_NEAR(s.linear_velocity(ball).x, -0.5, 1e-3) << to_string(solver);
  }
}

// Slender bodies bouncing on a static ground (docs/rigid-bodies.md, "Thin rods that bounce"):
// a collision with a body that does not move cannot raise a body's mechanical energy
// (kinetic + m g y, the ground at y = 0). A body dropped from rest with its lowest point 0.5 m
// above the ground, 10 s at 60 Hz: its largest energy after the start and in the last second.
// (`points`: the shape's extreme points in the body frame, `radius` about them,
// to place its lowest point.)
struct Fall {
  double start = 0, most = 0;  // mechanical energy at the start and the largest after it (J)
  double last = 0;             // the largest in the last second (J)
  double allowance = 0;        // m g v h: the bounce's discretisation (see the tests) (J)
};
Fall fall(pba::RigidSolverType solver, const pba::ColliderShape& shape, const std::vector<Vec3>& points,
          double radius, const Quat& q, double e) {
  RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
  ground(s, 0.5, e);
  double lowest = 0;
  for (const Vec3& p : points) lowest = std::min(lowest, (q * p).y - radius);
  const double drop = 0.5;
  auto body = s.create({.pose = {{0, drop - lowest, 0}, q},
                        .shapes = {{.shape = shape, .material = {.restitution = e, .friction = 0.5}}}});
  const double m = s.mass(body);
  auto energy = [&] { return s.kinetic_energy(body) + m * kG * s.center_of_mass(body).y; };
  Fall f;
  f.start = energy();
  f.most = -1;
  for (int i = 0; i < 600; ++i) {
    s.step(1.0 / 60, kGravity);
    f.most = std::max(f.most, energy());
    if (i >= 540) f.last = std::max(f.last, energy());
  }
  const double h = solver == pba::RigidSolverType::SequentialImpulse ? 1.0 / 60 : 1.0 / 60 / s.settings().substeps;
  f.allowance = m * kG * std::sqrt(2 * kG * drop) * h;
  return f;
}

std::vector<Vec3> box_corners(const Vec3& half) {
  std::vector<Vec3> c;
  for (int i = 0; i < 8; ++i)
    c.push_back({(i & 1 ? 1 : -1) * half.x, (i & 2 ? 1 : -1) * half.y, (i & 4 ? 1 : -1) * half.z});
  return c;
}

// a square rod t thick and `length` long (m) dropped `angle` degrees from upright (fall())
Fall rod_fall(pba::RigidSolverType solver, double t, double length, double e, double angle) {
  const Vec3 half{t / 2, length / 2, t / 2};
  return fall(solver, ColliderShape::box(half), box_corners(half), 0, glm::angleAxis(deg(angle), Vec3(0, 0, 1)), e);
}
std::string rod_case(pba::RigidSolverType solver, double t, double length, double e, double angle) {
  return std::string(to_string(solver)) + " t = " + std::to_string(t) + " L = " + std::to_string(length) +
         " e = " + std::to_string(e) + " angle = " + std::to_string(angle);
}

// Square rods 1 mm to 2 cm thick (principal moments 8,000,000 to 5,000 : 1), 2 and 4 m long,
// dropped 0 to 60 degrees from upright, e = 0.2 and 0.5, every solver. The bound is the
// bounce's discretisation: the restitution gives back the approach speed v of the substep h
// in which the rod meets the ground, having fallen less than v h in it, so a bounce may keep
// up to m g v h more than it had (v = sqrt(2 g 0.5 m), the landing's speed; symplectic
// Euler's flight loses energy). And in the last second each is down: under 2% of its start (a
// rod lying on the ground has m g t / 2, at most 0.7% of it here; TGS leaves the 2 cm rods
// rocking on the ground at up to 0.2 m/s, 0.2% of it); dropped upright, a rod may stay standing
// on its end, an equilibrium. Measured after the fix: none rises
// above its start, each is down by 10 s (the last second under 0.7%). Before (main at 0d7ff98): 340 of 512 such drops (e 0.2 to 1) rose, the worst
// by 1e13, and every solver blew some up (the soft step 2 mm x 4 m at e = 0.5: 1e5 within 92
// steps). Three causes (docs/rigid-bodies.md): the float passes' inverse inertia, the
// restitution's Newton law at a manifold's four points, and the continuous pass's rewind.
TEST(RigidRestitution, ThinRodsBouncingOnTheGroundGainNoEnergy) {
  for (const auto solver : kAll)
  for (const double t : {0.001, 0.002, 0.006, 0.02})
  for (const double length : {2.0, 4.0})
  for (const double e : {0.2, 0.5})
  for (const double angle : {0.0, 10.0, 30.0, 60.0}) {
    const Fall f = rod_fall(solver, t, length, e, angle);
    const std::string what = rod_case(solver, t, length, e, angle);
    EXPECT_LT(f.most, f.start + f.allowance) << what;
    if (angle > 0) {  // (upright, it may stand: XPBD's 2 cm rods do)
      EXPECT_LT(f.last, 0.02 * f.start) << what;
    }
  }
}

// Other slender bodies, the same bound: a 4 m x 4 m x 2 mm plate landing on an edge and on a
// corner, a needle capsule (1 mm radius, 4 m) and a needle cylinder (an octagonal hull of 1 mm
// radius, 4 m), e = 0.2 and 0.5, every solver.
TEST(RigidRestitution, ThinPlatesAndNeedlesBouncingOnTheGroundGainNoEnergy) {
  std::vector<Vec3> octagon;
  for (int k = 0; k < 16; ++k) {
    const double a = 2 * pba::kPi * (k % 8) / 8;
    octagon.push_back({0.001 * std::cos(a), k < 8 ? -2.0 : 2.0, 0.001 * std::sin(a)});
  }
  const Vec3 plate{2, 0.001, 2};
  struct Case {
    const char* name;
    ColliderShape shape;
    std::vector<Vec3> points;
    double radius;
    Quat q;
  };
  const Quat upright10 = glm::angleAxis(deg(10), Vec3(0, 0, 1));
  const Case cases[] = {
      {"plate on an edge", ColliderShape::box(plate), box_corners(plate), 0, glm::angleAxis(deg(80), Vec3(1, 0, 0))},
      {"plate on a corner", ColliderShape::box(plate), box_corners(plate), 0,
       glm::angleAxis(deg(30), Vec3(0, 0, 1)) * glm::angleAxis(deg(45), Vec3(1, 0, 0))},
      {"needle capsule", ColliderShape::capsule(2, 0.001), {{0, -2, 0}, {0, 2, 0}}, 0.001, upright10},
      {"needle cylinder", ColliderShape::convex(pba::ConvexHull::build(octagon, "needle")), octagon, 0, upright10},
  };
  for (const auto solver : kAll)
  for (const Case& c : cases)
  for (const double e : {0.2, 0.5}) {
    const Fall f = fall(solver, c.shape, c.points, c.radius, c.q, e);
    EXPECT_LT(f.most, f.start + f.allowance) << to_string(solver) << " " << c.name << " e = " << e;
    EXPECT_LT(f.last, 0.02 * f.start) << to_string(solver) << " " << c.name << " e = " << e;
  }
}

// e = 0.9 and 1: the rods of the test above no longer gain without bound (before: up to 1e13,
// most of them). Some rose above their start by more than a bounce's discretisation (worst
// measured: 21% for a 1 mm x 2 m rod at e = 1 under the soft step, 4.5% at e = 0.9) until the
// blocks' inverse inertia followed a body that turns (RigidContacts::refresh_inertia): since,
// none does (the worst 1.0039 of the start, TGS at e = 1; docs/rigid-bodies.md). This guarded
// the bound that held before, not a law, 1.25 times the start, until the continuous pass
// put bodies back with their velocity at the time of impact (2026-12-04): they are now held
// to the bound of the tests above, the start plus the bounce's allowance m g v h.
TEST(RigidRestitution, ElasticThinRodsStayBounded) {
  for (const auto solver : kAll)
  for (const double t : {0.001, 0.002, 0.006, 0.02})
  for (const double length : {2.0, 4.0})
  for (const double e : {0.9, 1.0})
  for (const double angle : {0.0, 10.0, 30.0, 60.0}) {
    const Fall f = rod_fall(solver, t, length, e, angle);
    EXPECT_LT(f.most, f.start + f.allowance) << rod_case(solver, t, length, e, angle) << ": " << f.most / f.start << " of the start, allowance " << f.allowance / f.start;
  }
}

// The same physics from other heights: the rods of the tests above that gained most, dropped
// from heights moved by k 1e-7 m, every solver (the release soak, RigidSoak.
// PerturbedRodDropsGainNoEnergyAndJumpNowhere, sweeps 960 such drops a solver). Neither
// their energy nor a step's displacement may exceed what the physics allows (rod_drops.h
// derives both bounds). Before the blocks' inverse inertias followed the bodies that turn
// (main at 4b1ad80; RigidContacts::refresh_inertia): 53 of these 160 drops' checks failed, all
// at e = 1: the soft step's 1 mm rod rose to 1.33 times its start and its centre moved 0.46 m
// beyond the bound in one step, TGS's 2 mm rod to 1.14. After: none (the soft step and TGS
// keep exactly their start). 2 s.
TEST(RigidRestitution, PerturbedRodDropsGainNoEnergyAndJumpNowhere) {
  for (const auto solver : kAll)
  for (const double t : {0.001, 0.002})
  for (const double e : {0.5, 1.0})
  for (int k = 0; k < 10; ++k) {
    const auto r = pba::test::rod_drop(solver, t, 2.0, e, 10.0, k * 1e-7);
    const std::string what = pba::test::rod_drop_case(solver, t, 2.0, e, 10.0, k);
    EXPECT_LE(r.most, r.start + r.allowance) << what << ": " << r.most / r.start << " of the start";
    EXPECT_LE(r.excess, 0) << what << ": " << r.excess << " m beyond the bound in step " << r.excess_step;
  }
}

// Elastic 2 cm rods landing on an end or flat while turning, the soft step: a bounce off the
// ground cannot give back more than the rod had at the step's start plus what gravity did
// along the step's path. With the sliding friction along the slip (the rods take other
// trajectories), a 4 m rod at 60 degrees (raised 3e-7 m) was pushed 2 cm up by the substeps
// of its landing step, and the restitution pass then gave back 10.85 of the 10.87 J/kg it
// approached with: 1.0049 of its start (the allowance 1.0043). With the smaller-mass friction
// tried before (an audit's unmerged branch), a 2 m rod at 10 degrees (4e-7 m) landing flat while
// tumbling was held only at its free motion over the whole step, m g v dt above: 1.024. Now
// RigidContacts::bound_bounce_work keeps each at that energy (the worst 1.000000).
TEST(RigidRestitution, ElasticRodsLandingWhileTurningGainNoEnergy) {
  for (const double length : {2.0, 4.0})
  for (const double angle : {10.0, 60.0})
  for (int k = 0; k < 10; ++k) {
    const auto solver = pba::RigidSolverType::SoftStep;
    const auto r = pba::test::rod_drop(solver, 0.02, length, 1.0, angle, k * 1e-7);
    const std::string what = pba::test::rod_drop_case(solver, 0.02, length, 1.0, angle, k);
    EXPECT_LE(r.most, r.start + r.allowance) << what << ": " << r.most / r.start << " of the start";
    EXPECT_LE(r.excess, 0) << what << ": " << r.excess << " m beyond the bound in step " << r.excess_step;
  }
}

// ---------------------------------------------------------------------------------------
// friction

// A box (half extents `half`, a 0.5 m cube by default) resting on a plane tilted by theta
// about z, both of friction mu (the tests below: 0.5, tan theta* = 0.5 at 26.57 deg).
struct Incline {
  RigidBodySystem s;
  pba::RigidBodyId box;
  Vec3 down;  // unit vector down the slope
  Incline(double theta, double mu, pba::RigidSolverType solver = pba::RigidSolverType::SoftStep,
          const Vec3& half = Vec3(0.25))
      : s(with(solver)) {
    ground(s, mu, 0, theta);
    const Quat q = glm::angleAxis(theta, Vec3(0, 0, 1));
    const Vec3 n{-std::sin(theta), std::cos(theta), 0};
    down = Vec3(-std::cos(theta), -std::sin(theta), 0);
    box = s.create({.name = "box", .pose = {half.y * n, q}, .shapes = {box_shape(half, mu)}});
  }
  double along() const { return glm::dot(s.center_of_mass(box), down); }
};

TEST(RigidFriction, ABoxStaysPutBelowTheFrictionAngle) {
  for (const auto solver : kSubstepping) {
    Incline in(deg(25), 0.5, solver);
    const double x0 = in.along();
    for (int i = 0; i < 300; ++i) in.s.step(1.0 / 60, kGravity);
    EXPECT_LT(std::abs(in.along() - x0), 1e-3) << to_string(solver);
  }
}

// Above it, the box slides with a = g (sin theta - mu cos theta); measured from the
// velocity between 0.5 s and 2 s, after the contact has settled.
TEST(RigidFriction, ABoxSlidesAboveTheFrictionAngleAtTheCoulombAcceleration) {
  const double theta = deg(30), mu = 0.5;
  for (const auto solver : kSubstepping) {
    Incline in(theta, mu, solver);
    auto speed = [&] { return glm::dot(in.s.linear_velocity(in.box), in.down); };
    for (int i = 0; i < 30; ++i) in.s.step(1.0 / 60, kGravity);
    const double v1 = speed();
    for (int i = 0; i < 90; ++i) in.s.step(1.0 / 60, kGravity);
    const double a = (speed() - v1) / 1.5;
    const double expected = kG * (std::sin(theta) - mu * std::cos(theta));
    EXPECT_NEAR(a, expected, 0.02 * expected) << to_string(solver);
  }
}

// The incline over the input range: mu 0.1-1.0, 4 degrees under the friction angle (stays
// put: under 1 mm in 5 s, as the issue asks) and 4 and 15 degrees over it (slides at
// g (sin - mu cos)), a flat box (0.5 x 0.1 x 0.5 m: it tips only past 79 degrees), the three
// substepping solvers. Symplectic Euler's velocity is exact under a constant force and the
// contact has settled by 0.5 s, so the measured acceleration is the closed form's to 1e-3
// (measured: 1.6e-4; the stay, 1e-5 m).
TEST(RigidFriction, AFlatBoxOnAnInclineStaysOrSlidesOverTheInputRange) {
  for (const auto solver : kSubstepping)
  for (const double mu : {0.1, 0.3, 0.6, 1.0})
  for (const double offset : {-deg(4), deg(4), deg(15)}) {
    const double theta = std::atan(mu) + offset;
    Incline in(theta, mu, solver, {0.25, 0.05, 0.25});
    const double x0 = in.along();
    const std::string what = std::string(to_string(solver)) + " mu = " + std::to_string(mu) + " theta = " +
                             std::to_string(theta * 180 / pba::kPi);
    if (offset < 0) {
      for (int i = 0; i < 300; ++i) in.s.step(1.0 / 60, kGravity);
      EXPECT_LT(std::abs(in.along() - x0), 1e-3) << what;
      continue;
    }
    auto speed = [&] { return glm::dot(in.s.linear_velocity(in.box), in.down); };
    for (int i = 0; i < 30; ++i) in.s.step(1.0 / 60, kGravity);
    const double v1 = speed();
    for (int i = 0; i < 60; ++i) in.s.step(1.0 / 60, kGravity);
    const double a = speed() - v1;
    const double expected = kG * (std::sin(theta) - mu * std::cos(theta));
    EXPECT_NEAR(a, expected, 1e-3 * expected) << what;
  }
}

// A 0.2 m cube set down at rest, touching, on a slope half a degree and 10 degrees past
// atan(mu) (mu 0.2 and 0.8), sleeping off, under the soft step and TGS: it slides at
// a = g (sin - mu cos) from its first substep. Each substep of h adds a h to the velocity and
// then moves by it (symplectic Euler), so after steps 1, 2, 3 the velocity is a t exactly (held
// to 1% of a dt: the float passes' rounding), and after n substeps the distance is
// a t^2 / 2 (n + 1) / n: held between the closed form a t^2 / 2 and the scheme's
// a t^2 / 2 (n + 2) / n at 3 s. The soft step and TGS gave the cube a slide of its own in its
// first step, 1.6-8.1 mm/s, which friction at its limit never took back, so the distance ran
// 1.3-5% ahead at 3 s (docs/rigid-bodies.md, "A start-up slide on a slope"): a manifold's
// friction, acting below the centre, turns the cube, and the first step carried no converged
// impulses in. Now such a manifold starts from the impulses that hold it (carry_fresh_slides).
// (The soft step half a degree over keeps 0.04-0.30 mm/s, the cube's settling into the soft
// contacts' springs, not the friction's start: left out here, docs/rigid-bodies.md)
TEST(RigidFriction, ACubeSetDownOnASlopeSlidesAtTheCoulombAccelerationFromItsFirstStep) {
  const double dt = 1.0 / 60;
  for (const auto solver : {pba::RigidSolverType::SoftStep, pba::RigidSolverType::Tgs})
  for (const double mu : {0.2, 0.8})
  for (const double offset : {0.5, 10.0}) {
    if (solver == pba::RigidSolverType::SoftStep && offset < 1) continue;
    const double theta = std::atan(mu) + deg(offset);
    const double a = kG * (std::sin(theta) - mu * std::cos(theta));
    Incline in(theta, mu, solver, Vec3(0.1));
    in.s.settings().sleep = false;
    const std::string what = std::string(to_string(solver)) + " mu " + std::to_string(mu) + " theta = atan(mu) + " +
                             std::to_string(offset) + " deg";
    const double x0 = in.along();
    int n = 0;  // the substeps taken
    for (int i = 1; i <= 180; ++i) {
      in.s.step(dt, kGravity);
      n += in.s.profile().substeps;
      if (i <= 3) {
        const double speed = glm::dot(in.s.linear_velocity(in.box), in.down);
        EXPECT_NEAR(speed, a * i * dt, 1e-2 * a * dt) << what << " step " << i;
      }
    }
    const double t = 180 * dt, closed = a * t * t / 2;
    EXPECT_GT(in.along() - x0, closed) << what;
    EXPECT_LT(in.along() - x0, closed * (n + 2) / n) << what;
  }
}

// A box sliding at v on level ground stops after v^2 / (2 mu g), whatever the direction.
TEST(RigidFriction, SlidingStopDistanceIsTheSameInTwelveDirections) {
  const double v = 4, mu = 0.5, expected = v * v / (2 * mu * kG);
  for (const auto solver : kSubstepping)
  for (int k = 0; k < 12; ++k) {
    const double a = 2 * pba::kPi * k / 12;
    const Vec3 dir{std::cos(a), 0, std::sin(a)};
    RigidBodySystem s(with(solver));
    ground(s, mu);
    auto box = s.create({.pose = {{0, 0.25, 0}}, .linear_velocity = v * dir,
                         .shapes = {box_shape({0.25, 0.25, 0.25}, mu)}});
    for (int i = 0; i < 180; ++i) s.step(1.0 / 60, kGravity);
    const Vec3 p = s.center_of_mass(box);
    EXPECT_NEAR(glm::length(Vec3(p.x, 0, p.z)), expected, 0.02 * expected) << to_string(solver) << " " << k;
    EXPECT_LT(glm::length(glm::cross(Vec3(p.x, 0, p.z), dir)), 0.01) << to_string(solver) << " " << k;  // straight
  }
}

// A box whose footprint is not square slides straight too, in any direction and turned any way
// about the vertical: Coulomb friction opposes the slip. The friction's two tangent rows had
// each its own effective mass (1 / K, K holding the turn the centroid's lever arm gives about
// the box's two horizontal axes, which differ when its sides do), and the pair clamped to the
// disc kept the direction of (m1 v1, m2 v2), not of v: a 1 x 0.5 x 0.6 m box sent at 45
// degrees over mu = 0.5 ended 3.7 m away at 48.6-49.7 degrees, 0.2-0.3 m off its line, under
// the soft step, sequential impulses and TGS (XPBD went straight).
TEST(RigidFriction, ABoxWithAnOblongFootprintSlidesStraightInEveryDirection) {
  const double v = 6, mu = 0.5, expected = v * v / (2 * mu * kG);
  for (const auto solver : kAll)
  for (const double turn : {0.0, 20.0, 67.0})
  for (const double a : {10.0, 45.0, 137.0, 200.0}) {
    const Vec3 dir{std::cos(deg(a)), 0, std::sin(deg(a))};
    RigidBodySystem s(with(solver));
    ground(s, mu);
    auto box = s.create({.pose = {{0, 0.25, 0}, glm::angleAxis(deg(turn), Vec3(0, 1, 0))}, .linear_velocity = v * dir,
                         .shapes = {box_shape({0.5, 0.25, 0.3}, mu)}});
    for (int i = 0; i < 110; ++i) s.step(1.0 / 60, kGravity);
    const Vec3 p = s.center_of_mass(box);
    const std::string what = std::string(to_string(solver)) + " turned " + std::to_string(turn) + " deg, sent at " + std::to_string(a) + " deg";
    EXPECT_NEAR(glm::length(Vec3(p.x, 0, p.z)), expected, 0.02 * expected) << what;
    EXPECT_LT(glm::length(glm::cross(Vec3(p.x, 0, p.z), dir)), 0.01) << what;  // straight
  }
}

// The same over the input range: mu 0.1-1.5, speeds 0.5-10 m/s, three directions, the three
// substepping solvers, a flat box (0.5 x 0.1 x 0.5 m: it cannot tip below mu = 5). Each
// substep changes the velocity before moving by it (symplectic Euler), so with the speed
// falling linearly the box stops between v^2 / (2 mu g) - v h / 2 and v^2 / (2 mu g), h the
// substep (measured: 0.64-1.0 of v h / 2 short; 1 mm at 1 m/s, 1.6% of the distance at
// mu = 0.8, which the 2% of the test above would not hold at 0.5 m/s and mu = 1.5). Where the
// substeps change during the slide (the soft step halves them a second in at the defaults) the
// shortfall is the sum of h dv / 2 over the steps, each at the h it took.
TEST(RigidFriction, TheStopDistanceOverTheInputRangeIsTheClosedFormLessHalfASubstepsTravel) {
  for (const auto solver : kSubstepping)
  for (const double mu : {0.1, 0.3, 0.6, 1.0, 1.5})
  for (const double v : {0.5, 1.0, 4.0, 10.0})
  for (const double a : {0.0, 0.7, 1.4}) {
    RigidBodySystem s(with(solver));
    ground(s, mu);
    const Vec3 dir{std::cos(a), 0, std::sin(a)};
    auto box = s.create({.pose = {{0, 0.05, 0}}, .linear_velocity = v * dir, .shapes = {box_shape({0.25, 0.05, 0.25}, mu)}});
    const int steps = static_cast<int>(v / (mu * kG) * 60) + 30;  // until it stopped, and half a second
    // the shortfall, h dv / 2 over each step's speed lost dv at the substep h it took (the
    // soft step halves its substeps a second into a long slide: v h / 2 at one h)
    double short_by = 0;
    for (int i = 0; i < steps; ++i) {
      const double before = glm::length(s.linear_velocity(box));
      s.step(1.0 / 60, kGravity);
      const double h = 1.0 / 60 / s.profile().substeps;
      short_by += h * std::max(0.0, before - glm::length(s.linear_velocity(box))) / 2;
    }
    const Vec3 p = s.center_of_mass(box);
    const double expected = v * v / (2 * mu * kG);
    const double d = glm::length(Vec3(p.x, 0, p.z));
    EXPECT_LE(d, expected) << to_string(solver) << " mu = " << mu << " v = " << v << " a = " << a;
    EXPECT_GE(d, expected - 1.001 * short_by) << to_string(solver) << " mu = " << mu << " v = " << v << " a = " << a;
    EXPECT_LT(glm::length(s.linear_velocity(box)), 1e-6) << to_string(solver) << " mu = " << mu << " v = " << v;
  }
}

// A 1 m box dropped flat (from 1.5 m, thrown down at 0, 2 or 5 m/s) while moving sideways at
// vx (1 to 8 m/s, along x and at 40 degrees), mu = 0.5, e = 0. Coulomb's law at the landing:
// the ground stops the fall, an impulse of m v_l (v_l the landing speed, sqrt(vy^2 + 2 g 1.5 m)),
// and friction takes up to mu m v_l of the sideways momentum, all of it while the box slips;
// then the box slides to a stop at mu g. From where it touches, x_touch = vx t_touch, it
// travels v'^2 / (2 mu g), v' = max(vx - mu v_l, 0), and a box (mu = 0.5 < its width over its
// height) does not tip. The steps' share: the contact takes the landing in the step the box
// would go through the ground in, within a step of the touch, and symplectic Euler falls
// ahead of the closed form by up to half a step's time: 1.5 vx dt either way; gravity adds up
// to g dt to the landing speed within that step, and the slide stops short by up to half a
// substep's travel (TheStopDistanceOverTheInputRangeIsTheClosedFormLessHalfASubstepsTravel).
// Under XPBD the dynamic friction was held to mu lambda / h, the position solve's share of
// the landing, which a speculative contact leaves a fraction of, and it was applied after
// the points' rows, so its moment tipped the box onto its leading edge: landing at 5.8 m/s
// while moving at 6 m/s it hopped at 1.5 m/s and slid 2.73 m (Coulomb: 0.99 m); now 0.98 m
// (22 of these 30 landings broke a bound before, none now).
// The soft step and TGS broke these bounds too (5 and 8 of these 30 drops): their boxes hopped
// on landing (the soft step: up to 1.8 m/s, TGS 3.1 m/s) and travelled up to 0.41 m (soft
// step) and 0.48 m (TGS) beyond the upper bound, landing at 7.4 m/s at 6 m/s, or stopped
// short of the lower one (the soft step by 0.06 m; TGS moved 5 cm back at 1 m/s). Their
// passes solved the friction once, after the points, and the positions took its moment
// (src/rigid/contact_wide.h, solve()); now a manifold whose friction changes the
// velocity by more than gravity does in a substep (an impact's) is swept again, points and
// friction together, and none of the 30 breaks a bound under any solver.
TEST(RigidFriction, ABoxLandingFlatWhileSlidingStopsWhereCoulombSays) {
  const double mu = 0.5, y0 = 2.0, dt = 1.0 / 60;
  for (const auto solver : kAll)
  for (const double vy : {0.0, 2.0, 5.0})
  for (const double vx : {1.0, 2.5, 4.0, 6.0, 8.0})
  for (const double a : {0.0, deg(40)}) {
    RigidBodySystem s(with(solver));
    ground(s, mu);
    const Vec3 dir{std::cos(a), 0, std::sin(a)};
    auto box = s.create({.pose = {{0, y0, 0}}, .linear_velocity = vx * dir + Vec3(0, -vy, 0), .shapes = {box_shape(Vec3(0.5), mu)}});
    // the closed form: the touch (the bottom falls y0 - 0.5), the landing speed, the slide
    const double t = (-vy + std::sqrt(vy * vy + 2 * kG * (y0 - 0.5))) / kG, land = vy + kG * t;
    const double h = solver == pba::RigidSolverType::SequentialImpulse ? dt : dt / s.settings().substeps;
    const double slide = std::pow(std::max(vx - mu * land, 0.0), 2) / (2 * mu * kG);
    const double least = std::pow(std::max(vx - mu * (land + kG * dt), 0.0), 2) / (2 * mu * kG) - vx * h / 2;
    for (int i = 0; i < 180; ++i) s.step(dt, kGravity);
    const Vec3 p = s.center_of_mass(box);
    const double travel = glm::dot(Vec3(p.x, 0, p.z), dir) - vx * t;
    const std::string what = std::string(to_string(solver)) + " vy " + std::to_string(vy) + " vx " + std::to_string(vx) +
                             " at " + std::to_string(a);
    EXPECT_LE(travel, slide + 1.5 * vx * dt) << what;
    EXPECT_GE(travel, least - 1.5 * vx * dt) << what;
    EXPECT_NEAR(p.y, 0.5, 0.01) << what;  // on its face, not tipped
    EXPECT_LT(glm::length(s.linear_velocity(box)), 1e-3) << what;
  }
}

// A solid sphere that rolls without slipping accelerates at (5/7) g sin theta (mu large
// enough: it needs mu >= (2/7) tan theta).
TEST(RigidFriction, ASphereRollsAtFiveSeventhsOfGSinTheta) {
  const double theta = deg(20);
  for (const auto solver : kSubstepping) {
    RigidBodySystem s(with(solver));
    ground(s, 1.0, 0, theta);
    const Vec3 n{-std::sin(theta), std::cos(theta), 0}, down{-std::cos(theta), -std::sin(theta), 0};
    auto ball = s.create({.pose = {0.2 * n}, .shapes = {{.shape = ColliderShape::sphere(0.2), .material = {.friction = 1}}}});
    for (int i = 0; i < 30; ++i) s.step(1.0 / 60, kGravity);
    const double v1 = glm::dot(s.linear_velocity(ball), down);
    for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kGravity);
    const double a = (glm::dot(s.linear_velocity(ball), down) - v1) / 1.0;
    const double expected = 5.0 / 7 * kG * std::sin(theta);
    EXPECT_NEAR(a, expected, 0.02 * expected) << to_string(solver);
    if (solver != pba::RigidSolverType::SoftStep) continue;
  // rolling: the material point at the contact is at rest. The solver holds it at rest at
  // the contact's midpoint, which the soft contact (a spring of w = 2 pi f) keeps
  // delta = g cos(theta) / w^2 deep, so the surface point below the centre slips at
  // |w| delta / 2. Against the static ground w is twice contact_hertz's but at most one
  // radian a substep: 1 / h = 480 rad/s at 8 substeps of 1/60 s, 240 at the 4 the defaults
  // halve to for this 40 cm ball a second in (the substeps the last step took)
  const int taken = s.profile().substeps;
  const double w = std::min(2 * 2 * pba::kPi * 15 * taken, taken * 60.0), delta = kG * std::cos(theta) / (w * w);
  const Vec3 slip = s.linear_velocity(ball) + glm::cross(s.angular_velocity(ball), -0.2 * n);
  EXPECT_LT(glm::length(slip), glm::length(s.angular_velocity(ball)) * delta);
  }
}

// Rolling over the input range: slopes of 5-40 degrees, balls of 5 cm to 1 m, mu half as
// much again as rolling needs, the three substepping solvers: (5/7) g sin(theta) to 1e-3
// (measured 2.4e-4 under the soft step and TGS, 6e-9 under XPBD; XPBD's static friction
// braked a 5 cm ball on 40 degrees by 4.2e-3 while it took the contact point's displacement
// over a substep for its slip, src/rigid/xpbd_rigid.cpp).
TEST(RigidFriction, ABallRollsAtFiveSeventhsOfGSinThetaOverTheInputRange) {
  for (const auto solver : kSubstepping)
  for (const double degrees : {5.0, 20.0, 40.0})
  for (const double r : {0.05, 0.3, 1.0}) {
    const double theta = deg(degrees), mu = 1.5 * 2.0 / 7 * std::tan(theta) + 0.05;
    RigidBodySystem s(with(solver));
    ground(s, mu, 0, theta);
    const Vec3 n{-std::sin(theta), std::cos(theta), 0}, down{-std::cos(theta), -std::sin(theta), 0};
    auto ball = s.create({.pose = {r * n}, .shapes = {{.shape = ColliderShape::sphere(r), .material = {.friction = mu}}}});
    for (int i = 0; i < 30; ++i) s.step(1.0 / 60, kGravity);
    const double v1 = glm::dot(s.linear_velocity(ball), down);
    for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kGravity);
    const double a = glm::dot(s.linear_velocity(ball), down) - v1, expected = 5.0 / 7 * kG * std::sin(theta);
    EXPECT_NEAR(a, expected, 1e-3 * expected) << to_string(solver) << " " << degrees << " deg, r = " << r;
  }
}

// Rolling resistance c on a solid sphere of radius r rolling on level ground: a torque
// c r m g against its spin, which the friction at the contact turns into a deceleration.
// With m a = f and I dw/dt = -(c r m g) - f r, rolling (a = r dw/dt) and I = (2/5) m r^2:
// a = -(5/7) c g (friction needed: |f| = (5/7) c m g, below mu m g). Then it stops and stays.
// Under the soft step the ball's ground manifold is coloured (its rolling resistance solved
// in its one-point block, in float), under TGS it is in the overflow (solved with its
// manifold, in double).
// Tolerances: the soft contact sinks the ball g / w^2 = 4e-5 m (w = 480 rad/s against the
// ground), 1.4e-4 of its radius: 0.1% on a (measured 3e-5). The distance: the substeps
// change the velocity before moving by it (symplectic Euler), so with v falling linearly the
// ball stops v0 h / 2 short of v0^2 / (2 a) (h = 1/480 s, the substep: 2.1 mm); within 2e-4
// of that for the soft contact's first steps, while the ball settles into the ground
// (measured 6e-5 under the soft step, 1e-6 under TGS).
TEST(RigidFriction, RollingResistanceSlowsASphereAtFiveSeventhsOfCG) {
  const double r = 0.3, c = 0.1, v0 = 2;
  const double expected = 5.0 / 7 * c * kG;  // 0.70 m/s^2: stops in v0 / a = 2.9 s
  for (const auto solver : {pba::RigidSolverType::SoftStep, pba::RigidSolverType::Tgs}) {
    RigidBodySystem s(with(solver));
    ground(s, 0.5);
    auto ball = s.create({.pose = {{0, r, 0}}, .linear_velocity = {v0, 0, 0}, .angular_velocity = {0, 0, -v0 / r},
                          .shapes = {{.shape = ColliderShape::sphere(r), .material = {.friction = 0.5},
                                      .rolling_resistance = c}}});
    double short_by = 0;  // the sum of h dv / 2 over the steps (below)
    auto step = [&] {
      const double before = s.linear_velocity(ball).x;
      s.step(1.0 / 60, kGravity);
      short_by += 1.0 / 60 / s.profile().substeps * (before - s.linear_velocity(ball).x) / 2;
    };
    for (int i = 0; i < 30; ++i) step();
    const double v1 = s.linear_velocity(ball).x;
    for (int i = 0; i < 60; ++i) step();
    const double a = (v1 - s.linear_velocity(ball).x) / 1.0;
    EXPECT_NEAR(a, expected, 1e-3 * expected) << to_string(solver);
    // still rolling: the contact point at rest (within the soft contact's slip)
    const Vec3 slip = s.linear_velocity(ball) + glm::cross(s.angular_velocity(ball), Vec3(0, -r, 0));
    EXPECT_LT(glm::length(slip), 1e-3) << to_string(solver);
    // stopped after v0 / a, where it came to rest: x = v0^2 / (2 a) - v0 h / 2 = 2.85 m, or
    // where h changes (the soft step halves its substeps a second in at the defaults) less
    // the sum of h dv / 2 over the steps, each at the h it took
    for (int i = 0; i < 150; ++i) step();
    EXPECT_LT(glm::length(s.linear_velocity(ball)), 1e-3) << to_string(solver);
    const double stop = v0 * v0 / (2 * expected) - short_by;
    EXPECT_NEAR(s.center_of_mass(ball).x, stop, 2e-4 * stop) << to_string(solver);
  }
}

// A box of width w and height h on a high-friction incline tips over once tan theta > w / h,
// under the substepping solvers. XPBD joined on 2026-12-07: its static friction on a face
// translates, and the part of its moment the face's pressure cannot carry now turns the box
// (src/rigid/xpbd_rigid.cpp, tipping()); before, it stood at 28.6 degrees (tilt 2e-5 rad).
TEST(RigidFriction, ABoxTipsWhenTheSlopeExceedsItsAspectRatio) {
  const double w = 0.5, h = 1.0, critical = std::atan(w / h);  // 26.57 deg
  for (const auto solver : kSubstepping)
  for (const double offset : {-deg(2), deg(2)}) {
    const double theta = critical + offset;
    RigidBodySystem s(with(solver));
    ground(s, 1.5, 0, theta);
    const Quat q = glm::angleAxis(theta, Vec3(0, 0, 1));
    const Vec3 n{-std::sin(theta), std::cos(theta), 0};
    auto box = s.create({.pose = {0.5 * h * n, q}, .shapes = {box_shape({w / 2, h / 2, 0.25}, 1.5)}});
    for (int i = 0; i < 180; ++i) s.step(1.0 / 60, kGravity);
    // the angle between the box's up axis and the slope normal
    const double tilt = std::acos(std::clamp(glm::dot(s.pose(box).rotation * Vec3(0, 1, 0), n), -1.0, 1.0));
    if (offset < 0) {
      EXPECT_LT(tilt, deg(1)) << to_string(solver) << " should stand at " << theta * 180 / pba::kPi;
    } else {
      EXPECT_GT(tilt, deg(45)) << to_string(solver) << " should tip at " << theta * 180 / pba::kPi;
    }
  }
}

// The same under XPBD at substep_iterations = 4 (tipping() turns the box once a substep, after
// the last iteration): the box tips 2 and 10 degrees past atan(w / h), and 2 degrees below it
// stands where it was put (mu 1.5 > tan theta: it sticks; a slip of 1 mm over 3 s would be
// sliding). Until 2026-12-07 the turn was given after each iteration, the later iterations'
// blocks undid it, and the box stood past the angle and slid 0.11-0.14 m down the slope.
TEST(RigidFriction, AnXpbdBoxTipsAndDoesNotSlideWithSeveralIterations) {
  const double w = 0.5, h = 1.0, critical = std::atan(w / h);
  for (const double offset : {-deg(2), deg(2), deg(10)}) {
    const double theta = critical + offset;
    RigidBodySystem s({.contacts = {.solver = pba::RigidSolverType::Xpbd, .substep_iterations = 4}});
    ground(s, 1.5, 0, theta);
    const Quat q = glm::angleAxis(theta, Vec3(0, 0, 1));
    const Vec3 n{-std::sin(theta), std::cos(theta), 0}, down{-std::cos(theta), -std::sin(theta), 0};
    auto box = s.create({.pose = {0.5 * h * n, q}, .shapes = {box_shape({w / 2, h / 2, 0.25}, 1.5)}});
    for (int i = 0; i < 180; ++i) s.step(1.0 / 60, kGravity);
    const double tilt = std::acos(std::clamp(glm::dot(s.pose(box).rotation * Vec3(0, 1, 0), n), -1.0, 1.0));
    if (offset < 0) {
      EXPECT_LT(tilt, deg(1)) << "should stand at " << theta * 180 / pba::kPi;
      EXPECT_LT(std::abs(glm::dot(s.center_of_mass(box) - 0.5 * h * n, down)), 1e-3)
          << "should not slide at " << theta * 180 / pba::kPi;
    } else {
      EXPECT_GT(tilt, deg(45)) << "should tip at " << theta * 180 / pba::kPi;
    }
  }
}

// A box on a square footing (0.5 x 1 x 0.5 m) turned 30 degrees about the slope's normal
// (mu 1.5): the pressure's centre leaves the footing down the slope through the middle of an
// edge, 0.25 / cos 30 = 0.289 m from the centre, so it tips once tan theta > 0.289 / 0.5
// (30 degrees), whatever the corner farther along the slope (0.342 m, 34.3 degrees). Under
// XPBD, whose tipping() measured the face to that corner until 2026-12-07 (it tipped at 35).
TEST(RigidFriction, ATurnedBoxTipsWhereItsFootingEndsDownTheSlope) {
  const double critical = std::atan(0.25 / std::cos(deg(30)) / 0.5);  // 30 degrees
  for (const double offset : {-deg(2), deg(2)}) {
    const double theta = critical + offset;
    RigidBodySystem s({.contacts = {.solver = pba::RigidSolverType::Xpbd, .sleep = false}});
    ground(s, 1.5, 0, theta);
    const Quat q = glm::angleAxis(theta, Vec3(0, 0, 1)) * glm::angleAxis(deg(30), Vec3(0, 1, 0));
    const Vec3 n{-std::sin(theta), std::cos(theta), 0};
    auto box = s.create({.pose = {0.5 * n, q}, .shapes = {box_shape({0.25, 0.5, 0.25}, 1.5)}});
    for (int i = 0; i < 300; ++i) s.step(1.0 / 60, kGravity);
    const double tilt = std::acos(std::clamp(glm::dot(s.pose(box).rotation * Vec3(0, 1, 0), n), -1.0, 1.0));
    if (offset < 0) {
      EXPECT_LT(tilt, deg(1)) << "should stand at " << theta * 180 / pba::kPi;
    } else {
      EXPECT_GT(tilt, deg(45)) << "should tip at " << theta * 180 / pba::kPi;
    }
  }
}

// ---------------------------------------------------------------------------------------
// stacking

struct Stack {
  RigidBodySystem s{{.contacts = {.sleep = false}}};  // the issue's stacks stand awake
  std::vector<pba::RigidBodyId> boxes;
  explicit Stack(int n) {
    ground(s, 0.5);
    for (int i = 0; i < n; ++i)
      boxes.push_back(s.create({.pose = {{0, 0.5 + i, 0}}, .shapes = {box_shape({0.5, 0.5, 0.5}, 0.5, 1000)}}));
  }
};

// 20 one-metre cubes, mu = 0.5, 60 Hz, 60 s: the top box drifts and sags under 1 cm.
TEST(RigidStacking, TwentyCubesStandForAMinute) {
  Stack st(20);
  for (int i = 0; i < 3600; ++i) st.s.step(1.0 / 60, kGravity);
  const Vec3 top = st.s.center_of_mass(st.boxes.back());
  EXPECT_LT(std::hypot(top.x, top.z), 0.01);
  EXPECT_LT(19.5 - top.y, 0.01);
}

// The soft contact is a spring of stiffness m_eff w^2 (w = 2 pi contact_hertz): a stack of n
// cubes sags by its static deflection n^2 g / w^2 (the contact under k cubes carries k m g on
// an effective mass near m / 2: 2k - 1 g / w^2 each). The 40-stack takes 16 substeps and
// the quarter-substep-rate hertz (240 Hz at 60 Hz): at the defaults (8, 120 Hz) it sags
// 2.8 cm and is past its buckling load (it leans over,
// RigidStacking.AFortyStackOnTheDefaultContactsLeansOverAtItsSpringModelsBucklingRate).
ContactSettings stiff_contacts() {
  ContactSettings c;
  c.sleep = false;
  c.substeps = 16;
  c.contact_hertz = 240;
  return c;
}

// 40 one-metre cubes, mu = 0.5, 60 Hz, 20 s, no sleep: the stack stands (its top drifts
// under 1 cm) and sags by the closed-form static deflection 40^2 g / w^2 = 6.9 mm within 10%.
TEST(RigidStacking, FortyCubesStandTwentySeconds) {
  RigidBodySystem s({.capacity = 64, .contacts = stiff_contacts()});
  const auto boxes = pba::rigid_scenes::vertical_stack(s, 40);
  double drift = 0;
  for (int i = 0; i < 1200; ++i) {
    s.step(1.0 / 60, kGravity);
    const Vec3 top = s.center_of_mass(boxes.back());
    drift = std::max(drift, std::hypot(top.x, top.z));
  }
  const double w = 2 * pba::kPi * 240;
  const double sag = 39.5 - s.center_of_mass(boxes.back()).y;
  EXPECT_LT(drift, 0.01);
  EXPECT_NEAR(sag, 40 * 40 * 9.81 / (w * w), 0.1 * 40 * 40 * 9.81 / (w * w));
}

// Small cubes buckle sooner: a face contact's resistance to leaning goes as its half width
// squared, the overturning moment above it as the half width (docs/rigid-bodies.md, "Why 8
// substeps and 120 Hz"). At the defaults a column of 10 cm cubes stands 17 high and a 20-stack
// falls (measured 2026-12-04: 20 cm cubes 21, 50 cm 30); at 16 substeps and 240 Hz, the
// setting the docs give for such scenes, 20-stacks of 10 cm and 20 cm cubes stand 30 s, their
// tops within 1% of a cube's size of the axis, and sag by the closed form n^2 g / w^2 (the same
// for every size) within 10%, as the 40-stack above.
TEST(RigidStacking, TwentySmallCubesStandAtSixteenSubsteps) {
  for (const double half : {0.05, 0.1}) {
    RigidBodySystem s({.capacity = 64, .contacts = stiff_contacts()});
    const auto boxes = pba::rigid_scenes::vertical_stack(s, 20, half);
    double drift = 0;
    for (int i = 0; i < 1800; ++i) {
      s.step(1.0 / 60, kGravity);
      const Vec3 top = s.center_of_mass(boxes.back());
      drift = std::max(drift, std::hypot(top.x, top.z));
    }
    const double w = 2 * pba::kPi * 240, closed = 20 * 20 * 9.81 / (w * w);
    const double sag = 39 * half - s.center_of_mass(boxes.back()).y;
    EXPECT_LT(drift, 0.01 * 2 * half) << "cubes of " << 2 * half << " m";
    EXPECT_NEAR(sag, closed, 0.1 * closed) << "cubes of " << 2 * half << " m";
  }
}

// At the defaults the soft step takes more substeps for a column too tall for its springs
// (ContactSettings::auto_substeps, src/rigid/columns.cpp): it doubles the substeps and
// contact_hertz together while a column's n^3 g / (w^2 s) (n cubes of side s on springs of w;
// a column buckles near 0.8-0.93 of it, Greenhill's 0.98 for the spring model) is over 0.5.
// 40 one-metre cubes carry 1.10 of it at 120 Hz (past their buckling load: they lean over,
// RigidStacking.AFortyStackOnTheDefaultContactsLeansOverAtItsSpringModelsBucklingRate) and
// 0.28 at 240 Hz: every step takes 16 substeps, and the stack stands as at stiff_contacts():
// sleeping off, 30 s, its top drifts under 1 cm and it sags by the closed form 40^2 g / w^2 =
// 6.9 mm at 240 Hz within 10%.
TEST(RigidStacking, FortyCubesStandAtTheDefaults) {
  RigidBodySystem s({.capacity = 64, .contacts = {.sleep = false}});
  const auto boxes = pba::rigid_scenes::vertical_stack(s, 40);
  double drift = 0;
  int fewest = 64, most = 0;
  for (int i = 0; i < 1800; ++i) {
    s.step(1.0 / 60, kGravity);
    fewest = std::min(fewest, s.profile().substeps), most = std::max(most, s.profile().substeps);
    const Vec3 top = s.center_of_mass(boxes.back());
    drift = std::max(drift, std::hypot(top.x, top.z));
  }
  EXPECT_EQ(fewest, 16);
  EXPECT_EQ(most, 16);
  EXPECT_EQ(s.profile().column, 40);
  const double w = 2 * pba::kPi * 240, closed = 40 * 40 * kG / (w * w);
  const double sag = 39.5 - s.center_of_mass(boxes.back()).y;
  EXPECT_LT(drift, 0.01);
  EXPECT_NEAR(sag, closed, 0.1 * closed);
}

// The same for 20 cubes of 10 cm and of 20 cm (n^3 g / (w^2 s) at 120 Hz: 1.38 and 0.69; a
// column of 10 cm cubes stands 17 high at 8 substeps, RigidStacking.TwentySmallCubesStandAtSixteenSubsteps):
// at the defaults they take 16 substeps and 240 Hz and stand 30 s, their tops within 1% of a
// cube's size of the axis, and sag by the closed form n^2 g / w^2 within 10%.
TEST(RigidStacking, TwentySmallCubesStandAtTheDefaults) {
  for (const double half : {0.05, 0.1}) {
    RigidBodySystem s({.capacity = 64, .contacts = {.sleep = false}});
    const auto boxes = pba::rigid_scenes::vertical_stack(s, 20, half);
    double drift = 0;
    int most = 0;
    for (int i = 0; i < 1800; ++i) {
      s.step(1.0 / 60, kGravity);
      most = std::max(most, s.profile().substeps);
      const Vec3 top = s.center_of_mass(boxes.back());
      drift = std::max(drift, std::hypot(top.x, top.z));
    }
    const double w = 2 * pba::kPi * 240, closed = 20 * 20 * kG / (w * w);
    const double sag = 39 * half - s.center_of_mass(boxes.back()).y;
    EXPECT_EQ(most, 16) << "cubes of " << 2 * half << " m";
    EXPECT_LT(drift, 0.01 * 2 * half) << "cubes of " << 2 * half << " m";
    EXPECT_NEAR(sag, closed, 0.1 * closed) << "cubes of " << 2 * half << " m";
  }
}

// What stands on the 8 substeps keeps them, and its bits: a 20-stack of one-metre cubes (0.14
// of the bound's n^3 g / (w^2 s)), a 10-level square pyramid (10 levels: 0.017) and the same
// pyramid's boxes dropped from a grid (falling_boxes: columns of 10 as they land) step every
// step at 8 substeps, to the same hash as with auto_substeps off. The measure sees the columns
// (the 20-stack's is 20 cubes, the pyramid's 10). The raise alone: the halving's budget
// (auto_substeps_sag_fraction, on by default) is 0 here, since the pyramid, resting, halves a
// second in (RigidStacking.AtTheDefaultsARestingPileOfOneMetreCubesTakesFourSubstepsThenThree).
// (Left out of the asan test preset by name: 89 s under the address and undefined
// sanitizers; CMakePresets.json. The code it runs is run there by the smaller tests.)
TEST(RigidStacking, WhatStandsAtEightSubstepsKeepsThemAndItsBits) {
  struct Case {
    const char* name;
    int column;  // the tallest column at the end (-1: not checked)
    std::vector<pba::RigidBodyId> (*build)(RigidBodySystem&);
  };
  const Case cases[] = {
      {"20-stack", 20, [](RigidBodySystem& s) { return pba::rigid_scenes::vertical_stack(s, 20); }},
      {"pyramid", 10, [](RigidBodySystem& s) { return pba::rigid_scenes::square_pyramid(s, 10); }},
      {"falling boxes", -1, [](RigidBodySystem& s) { return pba::rigid_scenes::falling_boxes(s, 6); }},
  };
  for (const Case& c : cases) {
    std::uint64_t hash[2] = {0, 0};
    for (const bool automatic : {true, false}) {
      RigidBodySystem s({.capacity = 1024,
                         .contacts = {.auto_substeps = automatic, .auto_substeps_sag_fraction = 0, .sleep = false}});
      c.build(s);
      for (int i = 0; i < 240; ++i) {
        s.step(1.0 / 60, kGravity);
        ASSERT_EQ(s.profile().substeps, 8) << c.name << " at step " << i;
      }
      if (automatic && c.column >= 0) {
        EXPECT_EQ(s.profile().column, c.column) << c.name;
      }
      hash[automatic] = s.hash();
    }
    EXPECT_EQ(hash[0], hash[1]) << c.name;
  }
}

// The substeps come down again once the columns fit fewer with room: a 40-stack at the
// defaults (16 substeps) whose top 20 boxes are taken away carries 0.14 of the bound at 8
// substeps, under half of it, and returns to 8 after a second (kCalmTime: 59 more steps at 16);
// with only its top 10 taken away (30 boxes, 0.47) it fits 8 substeps but not with that room,
// and keeps 16 (no switching back and forth about the bound).
TEST(RigidStacking, TheSubstepsComeDownASecondAfterTheColumnFitsFewerWithRoom) {
  for (const int removed : {20, 10}) {
    RigidBodySystem s({.capacity = 64, .contacts = {.sleep = false}});
    auto boxes = pba::rigid_scenes::vertical_stack(s, 40);
    for (int i = 0; i < 30; ++i) s.step(1.0 / 60, kGravity);
    ASSERT_EQ(s.profile().substeps, 16);
    for (int k = 0; k < removed; ++k) s.destroy(boxes[boxes.size() - 1 - static_cast<std::size_t>(k)]);
    std::vector<int> taken;
    for (int i = 0; i < 180; ++i) s.step(1.0 / 60, kGravity), taken.push_back(s.profile().substeps);
    EXPECT_EQ(s.profile().column, 40 - removed);
    if (removed == 20) {
      for (int i = 0; i < 59; ++i) EXPECT_EQ(taken[static_cast<std::size_t>(i)], 16) << "step " << i << " after";
      for (int i = 61; i < 180; ++i) EXPECT_EQ(taken[static_cast<std::size_t>(i)], 8) << "step " << i << " after";
    } else {
      for (int i = 0; i < 180; ++i) EXPECT_EQ(taken[static_cast<std::size_t>(i)], 16) << "step " << i << " after";
    }
  }
}

// With ContactSettings::auto_substeps_sag the soft step also halves the substeps and
// contact_hertz (8 -> 4, 120 -> 60 Hz; the ground's contacts 38 Hz, one radian a substep)
// where a column fits with room: n^3 g / (w^2 s) at 60 Hz at most half the bound (0.25: cubes
// of 1 m up to 15 high, of 10 cm up to 7), and the sag predicted from the carried loads at
// 60 Hz at most half the budget. A column of n cubes (of any size) sags by n g / w_g^2 on the
// ground and k g / ((m / 2) w^2) under k cubes between two, n g / w_g^2 + n (n - 1) g / w^2 in
// all: at 4 substeps 2.2 mm for 5 cubes, 5.2 mm for 8, 7.9 mm for 10, 29.6 mm for 20 (at 8
// substeps a quarter of it). Sleeping off, 10 s: with a budget of 1 cm the 5-stack of one-metre
// cubes takes 8 substeps for the first second (kCalmTime) and 4 from then on, stands (its top
// within 1% of a cube of the axis) and sags by the closed form at 4 substeps within 10%; the 10-stack
// (its load 0.069 fits, its sag does not) and the 20-stack (0.55: neither) keep 8 and sag by
// the closed form at 8. With 2 cm the 10-stack takes 4 after its second and sags by its
// closed form at 4; 8 cubes of 10 cm (sag 5.2 mm fits, load 0.35 does not) keep 8. Below the
// halving, the next rung (3 substeps, 45 Hz, the ground's contacts 180 rad/s) comes on the
// same conditions at its rate, a second after the column came to rest at 4 (pile_motion.h's
// next_rung_step): the 5-stack, whose sag at 3 (4.0 mm) fits half of 1 cm, takes it and sags
// by its closed form at 3; the 10-stack at 2 cm (14.1 mm at 3) keeps 4.
TEST(RigidStacking, FewerSubstepsWhereTheColumnsAllowIt) {
  struct Case {
    int boxes;
    double half;    // the cubes' half size (m)
    double budget;  // m
    int substeps;   // after the first second
    int then;       // after the next rung's second (the ladder's floor at the defaults: 3)
  };
  for (const Case k : {Case{5, 0.5, 0.01, 4, 3}, Case{10, 0.5, 0.01, 8, 8}, Case{20, 0.5, 0.01, 8, 8},
                       Case{10, 0.5, 0.02, 4, 4}, Case{8, 0.05, 0.02, 8, 8}}) {
    RigidBodySystem s({.capacity = 64, .contacts = {.auto_substeps_sag = k.budget, .sleep = false}});
    const auto boxes = pba::rigid_scenes::vertical_stack(s, k.boxes, k.half);
    double drift = 0;
    std::vector<int> taken;
    pba::test::Lowering lowering;
    for (int i = 0; i < 600; ++i) {
      s.step(1.0 / 60, kGravity);
      taken.push_back(s.profile().substeps);
      lowering.record(i, s.profile().substeps, pba::test::any_unsettled(s, boxes));
      const Vec3 top = s.center_of_mass(boxes.back());
      drift = std::max(drift, std::hypot(top.x, top.z));
    }
    const std::string name = std::to_string(k.boxes) + " cubes of " + std::to_string(2 * k.half) + " m, budget " +
                             std::to_string(k.budget) + " m";
    const std::size_t next = k.then == k.substeps ? taken.size() : static_cast<std::size_t>(lowering.third);
    if (k.then != k.substeps) {
      ASSERT_GE(lowering.third, 0) << name;
      EXPECT_EQ(lowering.third, pba::test::next_rung_step(lowering.halved, lowering.unsettled_at_4)) << name;
    }
    for (std::size_t i = 0; i < 59; ++i) EXPECT_EQ(taken[i], 8) << name << " at step " << i;
    for (std::size_t i = 61; i < next; ++i) ASSERT_EQ(taken[i], k.substeps) << name << " at step " << i;
    for (std::size_t i = next; i < taken.size(); ++i) ASSERT_EQ(taken[i], k.then) << name << " at step " << i;
    const double n = k.boxes, h = 1.0 / (60 * k.then);
    const double w = 2 * pba::kPi * 15 * k.then, ground = std::min(2 * w, 1 / h);
    const double closed = n * kG / (ground * ground) + n * (n - 1) * kG / (w * w);
    EXPECT_LT(drift, 0.01 * 2 * k.half) << name;
    const double sag = (2 * n - 1) * k.half - s.center_of_mass(boxes.back()).y;
    EXPECT_NEAR(sag, closed, 0.1 * closed) << name;
    std::printf("%s: %d substeps (from step %d), sag %.2f mm (closed form %.2f), drift %.3f mm\n", name.c_str(), k.then,
                k.then == k.substeps ? lowering.halved : lowering.third, 1e3 * sag, 1e3 * closed, 1e3 * drift);
  }
}

// Below the setting's substeps the halving also waits for the contacts to stay the same pairs
// for its second: a pile still landing carries impact loads, not its rest's (the Jolt pyramid
// halved while its upper levels landed settled with its top 3.6 cm aside, against 1.0 cm at 8
// substeps). A 5-stack (which takes 4 substeps a second in when alone) with a ball of 20 cm
// dropped from 1 m beside it every half second for 3 s keeps 8 substeps while they land,
// takes 4 a second after the last has come to rest on the ground (pile_motion.h's
// halving_step) and 3 a second after everything came to rest at 4 (next_rung_step; the
// 5-stack's sag at 3 substeps, 4.0 mm, fits half the budget).
TEST(RigidStacking, APileStillLandingIsNotHalved) {
  RigidBodySystem s({.capacity = 64, .contacts = {.auto_substeps_sag = 0.01, .sleep = false}});
  auto bodies = pba::rigid_scenes::vertical_stack(s, 5);
  std::vector<int> taken;
  pba::test::Lowering lowering;
  for (int i = 0; i < 420; ++i) {
    if (i % 30 == 0 && i < 180)
      bodies.push_back(
          s.create({.pose = {{3 + 0.5 * (i / 30), 1, 0}}, .shapes = {{.shape = ColliderShape::sphere(0.2)}}}));
    s.step(1.0 / 60, kGravity);
    taken.push_back(s.profile().substeps);
    lowering.record(i, s.profile().substeps, pba::test::any_unsettled(s, bodies));
  }
  for (std::size_t i = 0; i < 180; ++i) ASSERT_EQ(taken[i], 8) << "step " << i;
  ASSERT_GE(lowering.halved, 180);
  ASSERT_GE(lowering.third, 0);
  EXPECT_EQ(lowering.halved, pba::test::halving_step(lowering.unsettled)) << "last unsettled at " << lowering.unsettled;
  EXPECT_EQ(lowering.third, pba::test::next_rung_step(lowering.halved, lowering.unsettled_at_4))
      << "last unsettled at 4 at " << lowering.unsettled_at_4;
  for (auto i = static_cast<std::size_t>(lowering.halved); i < taken.size(); ++i)
    ASSERT_EQ(taken[i], static_cast<int>(i) < lowering.third ? 4 : 3) << "step " << i;
}

// At the defaults the halving's budget is a fraction of each body's size
// (ContactSettings::auto_substeps_sag_fraction, 2%): halved where every body's predicted sag at
// 4 substeps is at most 1% of its size, so a column of one-metre cubes halves exactly where its
// sag at 4 substeps, n g / w_g^2 + n (n - 1) g / w^2 (w = 2 pi 60 Hz, w_g = 1 / h = 240 rad/s),
// stays under the issue's 1 cm: up to 11 cubes (9.5 mm; 12 would sag 11.2 mm). Sleeping off,
// 10 s: stacks of 5, 10 and 11 take 4 substeps from a second in (kCalmTime), 12, 15 (whose
// load at 60 Hz, 0.23, would allow it) and 20 keep 8; the next rung, 3 substeps (45 Hz, the
// ground's contacts at 180 rad/s), likewise where the sag at 3 stays under 1 cm: the 5-stack
// (4.0 mm) takes it a second after it came to rest at 4 (next_rung_step) to the end, the 10-
// and 11-stacks (14.1 and 16.8 mm at 3) keep 4 to the end; each stands (its top within 1% of a
// cube of the axis), sags under 1 cm and by the closed form at the substeps taken within 10%.
TEST(RigidStacking, AtTheDefaultsColumnsOfOneMetreCubesHalveOnlyUnderOneCentimetreOfSag) {
  for (const int n : {5, 10, 11, 12, 15, 20}) {
    RigidBodySystem s({.capacity = 64, .contacts = {.sleep = false}});
    const auto boxes = pba::rigid_scenes::vertical_stack(s, n);
    auto closed = [&](int substeps) {
      const double h = 1.0 / (60 * substeps), w = 2 * pba::kPi * 15 * substeps, ground = std::min(2 * w, 1 / h);
      return n * kG / (ground * ground) + n * (n - 1.0) * kG / (w * w);
    };
    const int halved = closed(4) <= 0.01 ? 4 : 8, expected = halved == 4 && closed(3) <= 0.01 ? 3 : halved;
    double drift = 0;
    pba::test::Lowering lowering;
    for (int i = 0; i < 600; ++i) {
      s.step(1.0 / 60, kGravity);
      lowering.record(i, s.profile().substeps, pba::test::any_unsettled(s, boxes));
      if (i < 59) {
        ASSERT_EQ(s.profile().substeps, 8) << n << " cubes at step " << i;
      }
      if (i > 61 && (lowering.third < 0 || i < lowering.third)) {
        ASSERT_EQ(s.profile().substeps, halved) << n << " cubes at step " << i;
      }
      if (lowering.third >= 0) {
        ASSERT_EQ(s.profile().substeps, 3) << n << " cubes at step " << i;
      }
      const Vec3 top = s.center_of_mass(boxes.back());
      drift = std::max(drift, std::hypot(top.x, top.z));
    }
    if (expected == 3) {
      EXPECT_EQ(lowering.third, pba::test::next_rung_step(lowering.halved, lowering.unsettled_at_4)) << n << " cubes";
    } else {
      EXPECT_LT(lowering.third, 0) << n << " cubes";
    }
    const double sag = n - 0.5 - s.center_of_mass(boxes.back()).y;
    EXPECT_LT(drift, 0.01) << n << " cubes";
    EXPECT_LT(sag, 0.01) << n << " cubes";
    EXPECT_NEAR(sag, closed(expected), 0.1 * closed(expected)) << n << " cubes";
    std::printf("%d cubes: %d substeps, sag %.2f mm (closed form %.2f), drift %.3f mm\n", n, expected, 1e3 * sag,
                1e3 * closed(expected), 1e3 * drift);
  }
}

// A resting pile of one-metre cubes takes 4 substeps at the defaults, and then 3: a square
// pyramid of 8 levels (204 cubes, each on four; load at 60 Hz 0.035, predicted sag 1.1 mm at
// most at 4 substeps, 2.0 mm at 3, under 1% of a cube), sleeping off, 10 s. It halves a second
// after it came to rest (its cubes all under the sleep tolerances from the first step: at step
// 60, pile_motion.h's halving_step), takes 3 a second after it came to rest at 4
// (next_rung_step), keeps 3 to the end and stands: no cube moves more than 1 cm from where it
// was built or faster than the sleep tolerance at the end. Its springs sink it as they go: each
// contact's deflection goes as 1 / w^2, and the ground's and the cubes' rates both go with the
// substeps (38 and 60 Hz at 4, 29 and 45 Hz at 3), so the top's sag at 3 is (4 / 3)^2 = 16 / 9
// of its sag at 4, and at 4 four times its sag at 8 (each within 10%, the accuracy of the
// columns' closed forms above).
TEST(RigidStacking, AtTheDefaultsARestingPileOfOneMetreCubesTakesFourSubstepsThenThree) {
  RigidBodySystem s({.capacity = 256, .contacts = {.sleep = false}});
  const auto boxes = pba::rigid_scenes::square_pyramid(s, 8);
  std::vector<Vec3> start;
  for (auto b : boxes) start.push_back(s.center_of_mass(b));
  std::vector<int> taken;
  pba::test::Lowering lowering;
  std::vector<double> top;  // the top cube's sag at each step (m)
  for (int i = 0; i < 600; ++i) {
    s.step(1.0 / 60, kGravity), taken.push_back(s.profile().substeps);
    lowering.record(i, s.profile().substeps, pba::test::any_unsettled(s, boxes));
    top.push_back(start.back().y - s.center_of_mass(boxes.back()).y);
  }
  EXPECT_EQ(taken.front(), 8);
  ASSERT_GE(lowering.halved, 0);
  ASSERT_GT(lowering.third, lowering.halved);
  for (auto i = static_cast<std::size_t>(lowering.halved); i < taken.size(); ++i)
    ASSERT_EQ(taken[i], static_cast<int>(i) < lowering.third ? 4 : 3) << "step " << i;
  // a second after it came to rest (kCalmTime), to the step, at each rung
  EXPECT_EQ(lowering.halved, pba::test::halving_step(lowering.unsettled))
      << "last unsettled at step " << lowering.unsettled;
  EXPECT_EQ(lowering.third, pba::test::next_rung_step(lowering.halved, lowering.unsettled_at_4))
      << "last unsettled at 4 at step " << lowering.unsettled_at_4;
  // the sag at rest on each rung's springs: the last step before the next rung, and the end
  const double at8 = top[static_cast<std::size_t>(lowering.halved - 1)];
  const double at4 = top[static_cast<std::size_t>(lowering.third - 1)], at3 = top.back();
  EXPECT_NEAR(at4, 4 * at8, 0.1 * 4 * at8);
  EXPECT_NEAR(at3, 16.0 / 9 * at4, 0.1 * 16.0 / 9 * at4);
  const pba::test::PileMotion m = pba::test::pile_motion(s, boxes, start);
  EXPECT_LT(m.moved, 0.01);
  EXPECT_LT(m.fastest, s.settings().sleep_linear);
  std::printf("halved at step %d, 3 from step %d; top sags %.3f mm at 8, %.3f at 4, %.3f at 3; most moved %.2f mm\n",
              lowering.halved, lowering.third, 1e3 * at8, 1e3 * at4, 1e3 * at3, 1e3 * m.moved);
}

// A pile on the ladder's lowest rung goes back up at once when a bound is passed, to the
// fewest substeps whose whole bounds it fits (columns.cpp, step_substeps): the 5-stack of
// one-metre cubes at the defaults rests at 3 substeps (4.0 mm of sag predicted, under 1% of a
// cube: half the 2% budget); gravity six times as strong loads it to 23.8 mm at 3 (past the
// whole 2 cm) and 13.4 mm at 4 (within it), and the step under it takes 4; back at g it stays
// at 4 (lowered only after a calm second); twelve times gravity, 26.8 mm at 4, takes the
// setting's 8 in that step. Sleeping off.
TEST(RigidStacking, APileAtThreeSubstepsGoesBackUpAtOnceWhenABoundIsPassed) {
  RigidBodySystem s({.capacity = 16, .contacts = {.sleep = false}});
  pba::rigid_scenes::vertical_stack(s, 5);
  for (int i = 0; i < 300; ++i) s.step(1.0 / 60, kGravity);
  ASSERT_EQ(s.profile().substeps, 3);
  s.step(1.0 / 60, 6.0 * kGravity);
  EXPECT_EQ(s.profile().substeps, 4);
  s.step(1.0 / 60, kGravity);
  EXPECT_EQ(s.profile().substeps, 4);
  s.step(1.0 / 60, 12.0 * kGravity);
  EXPECT_EQ(s.profile().substeps, 8);
}

// The braced model (columns.cpp, "Braced piles") on a free column of cubes is the column's
// tilt chain: each cube a level, tilted t_i on springs k_p of m_eff w^2 over a face's four
// points (s / 2 from the axis), under the P-delta of the weight on it and its own. At 4
// substeps w = 2 pi 60 rad/s between cubes (m_eff = m / 2) and the ground's w_g = 240 rad/s
// (one radian a substep, m_eff = m), so a joint's tilt stiffness is k = m w^2 s^2 / 8 and the
// foot's k_g = m w_g^2 s^2 / 4; gravity G_i = m g s (cubes above + 1/2). The load is Greenhill's
// 7.837 / 8 over the least factor on gravity the chain does not stand. Closed forms: one cube,
// k_g = lambda m g s / 2; two, det [[k_g + k - 3/2 lambda m g s, -k], [-k, k - 1/2 lambda m g s]]
// = 0. Within 0.2% (the points where the manifold puts them, the loads the contacts carried at
// rest two seconds in, the bisection's 2e-5). Taller, the chain tends to Greenhill's column: its load over
// n^3 g / (w^2 s) is over 1 (the discrete chain and the softer foot carry less than the
// clamped beam) by a part first order in 1 / n (0.24 at 10, 0.115 at 20, 0.056 at 40), so on
// a free column the braced model asks what the column model asks, and more. The part is a
// series in 1 / n, over(n) = a / n + b / n^2 + c / n^3 ...: a and b from 10 and 20 predict 40,
// and what they leave out, the third-order term, is under the second-order term b / 40^2 there
// (measured: 4.4e-5 against 1.25e-3; a = 2.20, b = 1.99).
TEST(RigidStacking, TheBracedModelOfAFreeColumnIsItsTiltChain) {
  const double w = 2 * pba::kPi * 60, wg = 240, s_ = 1, m = 1000, greenhill = 7.837 / 8;
  const double k = m * w * w * s_ * s_ / 8, kg = m * wg * wg * s_ * s_ / 4, c = m * kG * s_;
  // the smaller root of (kg + k - 3/2 c x)(k - 1/2 c x) - k^2 = 0
  const double qa = 0.75 * c * c, qb = -(1.5 * c * k + 0.5 * c * (kg + k)), qc = (kg + k) * k - k * k;
  const double two = (-qb - std::sqrt(qb * qb - 4 * qa * qc)) / (2 * qa);
  const double expected[] = {greenhill / (kg / (0.5 * c)), greenhill / two};
  double over[3] = {0, 0, 0};  // at 10, 20, 40
  for (const int n : {1, 2, 10, 20, 40}) {
    RigidBodySystem s({.capacity = 64, .contacts = {.sleep = false}});
    pba::rigid_scenes::vertical_stack(s, n);
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
    const double load = s.profile().half_load, column = n * n * n * kG / (w * w * s_);
    std::printf("%2d cubes: braced load %.6g, column model %.6g (ratio %.4f)\n", n, load, column, load / column);
    if (n <= 2) {
      EXPECT_NEAR(load, expected[n - 1], 2e-3 * expected[n - 1]) << n << " cubes";
    } else {
      double& o = over[n == 10 ? 0 : n == 20 ? 1 : 2];
      o = load / column - 1;
      EXPECT_GT(o, 0) << n << " cubes";
    }
  }
  // n over(n) = a + b / n at 10 and 20
  const double b = 20 * (10 * over[0] - 20 * over[1]), a = 20 * over[1] - b / 20, predicted = (a + b / 40) / 40;
  std::printf("a %.4f, b %.4f: at 40 predicted %.6f, measured %.6f\n", a, b, predicted, over[2]);
  EXPECT_GT(a, 0);
  EXPECT_LT(std::abs(over[2] - predicted), std::abs(b) / (40.0 * 40));
}

// A two-wide braced pile: two cubes side by side on the ground carrying a plank (2 x 1 x 1,
// twice a cube's mass) are one level (a common load), the plank another. Along the plank the
// level tilts its cubes (t1, each about its centre), turns as a level (psi, lifting one cube
// and lowering the other by psi / 2) and the plank tilts (t2); the lifts stand apart by
// symmetry. The springs: the ground's k_g = m w_g^2 / 4 a point and the plank's on a cube
// k = (2m / 3) w^2 / 4, a point at x from the plank's centre and x -+ 1/2 from its cube's.
// Summed over the points (s = 1): D = [[2 k_g + 2 k, 0, -2 k], [0, 2 k_g + 2 k, -2 k],
// [-2 k, -2 k, 4 k]] less lambda diag(3 m g, 0, m g) (each cube carries half the plank's
// weight at its top and its own from its centre: 3/2 m g each; the plank its own at 1/2).
// Across it, each body tilts alone: [[2 k_g + 2 k - 3 lambda m g, -2 k], [-2 k, 2 k - lambda
// m g]]. The model's load is the larger of the two directions' (their least factors); within
// 0.2% as above. It carries less than the column of a cube and its plank would (the turn
// braces the tilt along the plank).
TEST(RigidStacking, TheBracedModelOfTwoCubesUnderAPlankIsItsClosedForm) {
  const double w = 2 * pba::kPi * 60, wg = 240, m = 1000, greenhill = 7.837 / 8;
  const double k = (2 * m / 3) * w * w / 4, kg = m * wg * wg / 4, c = m * kG;
  // the least lambda at which a symmetric matrix of lambda stops being positive definite
  auto least = [](auto stands) {
    double lo = 0, hi = 1e9;
    for (int i = 0; i < 200; ++i) (stands(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
    return lo;
  };
  const double along = least([&](double x) {
    const double a = 2 * kg + 2 * k - 3 * x * c, b = 2 * kg + 2 * k, d = 4 * k - x * c;
    // leading minors of [[a, 0, -2k], [0, b, -2k], [-2k, -2k, d]]
    return a > 0 && a * b > 0 && a * (b * d - 4 * k * k) - 4 * k * k * b > 0;
  });
  const double across = least([&](double x) {
    const double a = 2 * kg + 2 * k - 3 * x * c, d = 2 * k - x * c;
    return a > 0 && a * d - 4 * k * k > 0;
  });
  const double expected = greenhill / std::min(along, across);
  RigidBodySystem s({.capacity = 16, .contacts = {.sleep = false}});
  ground(s);
  for (const double x : {-0.5, 0.5}) s.create({.pose = {Vec3(x, 0.5, 0)}, .shapes = {box_shape(Vec3(0.5))}});
  s.create({.pose = {Vec3(0, 1.5, 0)}, .shapes = {box_shape(Vec3(1, 0.5, 0.5))}});
  for (int i = 0; i < 30; ++i) s.step(1.0 / 60, kGravity);
  std::printf("braced load %.6g, closed form %.6g (along %.6g, across %.6g)\n", s.profile().half_load, expected,
              greenhill / along, greenhill / across);
  EXPECT_NEAR(s.profile().half_load, expected, 2e-3 * expected);
}

// The 20-level square pyramid of one-metre cubes (the issue's 2870) is braced: each cube rests
// on four and carries four, so a level's cubes share supports and loads, and a cube tilting
// in its level stretches its springs by the offset from its supports (half a cube) whatever
// the levels below do. The braced model's load at 4 substeps is about 1e-3 (the column
// model's for 20 cubes: 0.55), so it halves at rest, a second after it settled
// (RigidProfile::substeps 4), and takes 3 a second later (its load at 45 Hz 2.5e-3 and its sag
// 6.8 mm within their bounds there), while a 3 x 3 block of free columns of 20 cubes side by side,
// touching (their side contacts carry no load: no level joins them), keeps 8 (each a chain
// of 20: 0.62), and so does a 10-level square pyramid with a free column of 20 cubes on its
// top (the column's chain on the pyramid rules: the weakest part). Sleeping off, 3 s.
// (Left out of the asan test preset by name: 227 s under the address and undefined
// sanitizers; CMakePresets.json. The code it runs is run there by the smaller tests.)
TEST(RigidStacking, ABracedPyramidHalvesAndFreeColumnsDoNot) {
  struct Case {
    const char* name;
    int substeps;  // at the end
    double least, most;  // RigidProfile::half_load
    std::vector<pba::RigidBodyId> (*build)(RigidBodySystem&);
  };
  const Case cases[] = {
      {"pyramid of 20 levels", 3, 0, 0.01, [](RigidBodySystem& s) { return pba::rigid_scenes::square_pyramid(s, 20); }},
      {"3 x 3 columns of 20", 8, 0.5, 0.8,
       [](RigidBodySystem& s) {
         ground(s, 0.5);
         std::vector<pba::RigidBodyId> out;
         for (int a = -1; a <= 1; ++a)
           for (int b = -1; b <= 1; ++b)
             for (int i = 0; i < 20; ++i) out.push_back(pba::rigid_scenes::box(s, {a, 0.5 + i, b}, Vec3(0.5)));
         return out;
       }},
      {"pyramid of 10 under a column of 20", 8, 0.5, 0.8,
       [](RigidBodySystem& s) {
         auto out = pba::rigid_scenes::square_pyramid(s, 10);
         for (int i = 0; i < 20; ++i) out.push_back(pba::rigid_scenes::box(s, {0, 10.5 + i, 0}, Vec3(0.5), 0.6));
         return out;
       }},
  };
  for (const Case& c : cases) {
    RigidBodySystem s({.capacity = 4096, .contacts = {.sleep = false}});
    c.build(s);
    std::vector<int> taken;
    for (int i = 0; i < 180; ++i) s.step(1.0 / 60, kGravity), taken.push_back(s.profile().substeps);
    std::printf("%s: load at half the substeps %.4g, substeps at the end %d\n", c.name, s.profile().half_load,
                taken.back());
    EXPECT_EQ(taken.back(), c.substeps) << c.name;
    if (c.substeps == 8) {
      EXPECT_TRUE(std::all_of(taken.begin(), taken.end(), [](int k) { return k == 8; })) << c.name;
    }
    EXPECT_GT(s.profile().half_load, c.least) << c.name;
    EXPECT_LT(s.profile().half_load, c.most) << c.name;
  }
}

// The halving sees a body's size: a ball's ground springs sink it g / w^2 whatever its size,
// 0.17 mm at 4 substeps (w = 1 / h = 240 rad/s), a sixth of a 1 mm ball's radius, which
// slowed a 1 mm ball's roll by 0.9% where the issue's test of small balls asks for 0.1%
// (RigidSmallBodies.SmallBallsRollAtTheirClosedForm, with the halving forced on before it
// waited for rest). That is over 1% of the size of balls of 1, 2 and 5 mm (8.5%, 4.3%, 1.7%),
// so at the defaults, at rest on the ground, they keep 8 substeps every step for 3 s; a ball of
// 5 cm (0.17%) takes 4 from a second in and 3 from a second later (0.30 mm at 180 rad/s,
// 0.3%); and rolling down 20 degrees none is at rest: 8.
// (Sleeping off: asleep, a body is not stepped and not measured, so a ball asleep lets the rest
// halve; woken, it is measured again with its pairs, at the latest kMeasureEvery steps on.)
TEST(RigidSmallBodies, BallsOfAFewMillimetresKeepEightSubstepsAtTheDefaults) {
  for (const double theta : {0.0, deg(20)})
  for (const double r : {0.001, 0.002, 0.005, 0.05}) {
    RigidBodySystem s({.contacts = {.sleep = false}});
    ground(s, 1.0, 0, theta);
    const Vec3 n{-std::sin(theta), std::cos(theta), 0};
    s.create({.pose = {r * n}, .shapes = {{.shape = ColliderShape::sphere(r), .material = {.friction = 1}}}});
    const int expected = r < 0.01 || theta > 0 ? 8 : 4;
    for (int i = 0; i < 180; ++i) {
      s.step(1.0 / 60, kGravity);
      if (i < 59 || expected == 8) {
        ASSERT_EQ(s.profile().substeps, 8) << "r = " << r << " on " << theta << " rad at step " << i;
      }
      if (i > 61 && i < 119) {
        ASSERT_EQ(s.profile().substeps, expected) << "r = " << r << " on " << theta << " rad at step " << i;
      }
      if (i > 121) {
        ASSERT_EQ(s.profile().substeps, expected == 4 ? 3 : 8)
            << "r = " << r << " on " << theta << " rad at step " << i;
      }
    }
  }
}

// Substeps set by hand are taken exactly: set_substeps (which turns auto_substeps off) keeps
// a 40-stack at 8 substeps.
TEST(RigidStacking, SubstepsSetByHandAreTakenExactly) {
  RigidBodySystem s({.capacity = 64, .contacts = {.sleep = false}});
  pba::rigid_scenes::vertical_stack(s, 40);
  s.set_substeps(8);
  EXPECT_FALSE(s.settings().auto_substeps);
  for (int i = 0; i < 60; ++i) {
    s.step(1.0 / 60, kGravity);
    ASSERT_EQ(s.profile().substeps, 8);
  }
  EXPECT_EQ(s.profile().column, 0);  // (not measured when off)
}

// A 400:1 mass ratio: a one-metre cube of 50 t on a column of three 0.5 m cubes of 125 kg,
// 10 s, sleep off: no contact overlaps 1 cm or more at any step, and the heavy cube stays on
// the column (its centre within 1 cm of the axis, at most 2 cm under its resting height of
// 2 m). At the defaults the soft springs alone let it overlap 2.6 cm (each carries the load on
// a light cube's effective mass, load / (m w^2)); the soft step's position pass
// (src/rigid/push_out.cpp) holds every contact to the linear slop. At 16 substeps and 240 Hz
// the springs alone hold it to 6.5 mm.
struct HeavyOnLight {
  RigidBodySystem s;
  std::vector<pba::RigidBodyId> column;
  pba::RigidBodyId heavy;
  explicit HeavyOnLight(const ContactSettings& c, double ratio = 400)
      : s({.capacity = 16, .contacts = c}), column(pba::rigid_scenes::heavy_on_light(s, ratio)), heavy(column.back()) {}
  double deepest() const {
    double d = 0;
    for (const auto& c : s.contacts()) d = std::max(d, c.depth);
    return d;
  }
  // the deepest overlap along the column from the centres' heights (ground and each box with
  // the one below; asleep too, when there are no manifolds), as the sample plots it
  double column_overlap() const {
    double d = 0, below = 0;
    for (std::size_t i = 0; i < column.size(); ++i) {
      const double half = i + 1 == column.size() ? 0.5 : 0.25, y = s.center_of_mass(column[i]).y;
      d = std::max(d, below - (y - half));
      below = y + half;
    }
    return d;
  }
};

TEST(RigidStacking, AFourHundredToOneStackOverlapsUnderOneCentimetre) {
  ContactSettings defaults;
  defaults.sleep = false;
  for (const ContactSettings& c : {defaults, stiff_contacts()}) {
    HeavyOnLight st(c);
    ASSERT_NEAR(st.s.mass(st.heavy), 400 * 125.0, 1e-6);
    double deepest = 0;
    for (int i = 0; i < 600; ++i) {
      st.s.step(1.0 / 60, kGravity);
      deepest = std::max(deepest, st.deepest());
    }
    const Vec3 p = st.s.center_of_mass(st.heavy);
    EXPECT_LT(deepest, 0.01) << c.substeps << " substeps";
    EXPECT_LT(std::hypot(p.x, p.z), 0.01) << c.substeps << " substeps";
    EXPECT_GT(p.y, 2.0 - 0.02) << c.substeps << " substeps";
  }
}

// The position pass must not feed the stack it holds: the 400:1 stack at the defaults, once
// settled (6 s; it moves by micrometres until then), rests for 4 s: every contact overlaps at
// most the linear slop at every step, the heavy cube moves under 1 mm/s, and the column's
// energy (kinetic plus potential) never rises above what it had at 6 s by more than 0.05 J
// (the cube's weight over 0.1 um). A pass that lifts
// the cube without stopping its fall (velocities kept) bounced it on its springs, gaining
// energy every bounce, until the column fell over; one that moves it without shifting the
// springs' rest kept it sinking at 0.46 m/s while held in place.
TEST(RigidStacking, AFourHundredToOneStackRestsWithinTheSlopWithoutGainingEnergy) {
  ContactSettings c;
  c.sleep = false;
  HeavyOnLight st(c);
  const double slop = c.linear_slop;
  auto energy = [&] {
    double e = 0;
    for (std::uint32_t i = 0; i < st.s.size(); ++i) {
      const pba::RigidBodyId b = st.s.id_at(i);
      if (st.s.type(b) == BodyType::Dynamic) e += st.s.kinetic_energy(b) + st.s.mass(b) * kG * st.s.center_of_mass(b).y;
    }
    return e;
  };
  for (int i = 0; i < 360; ++i) st.s.step(1.0 / 60, kGravity);
  const double e0 = energy();
  double deepest = 0, fastest = 0, gain = -1e300;
  for (int i = 0; i < 240; ++i) {
    st.s.step(1.0 / 60, kGravity);
    deepest = std::max(deepest, st.deepest());
    fastest = std::max(fastest, glm::length(st.s.linear_velocity(st.heavy)));
    gain = std::max(gain, energy() - e0);
  }
  EXPECT_LE(deepest, slop * (1 + 1e-6));
  EXPECT_LT(fastest, 1e-3);
  EXPECT_LT(gain, 0.05);
}

// The Mass ratio sample's column stands at the largest ratio the sample offers
// (rigid_scenes::kHeavyOnLightMaxRatio), awake as when the mouse holds or pushes it: 60 s at
// the defaults with sleep off, no contact overlapping 1 cm at any step (the issue's 400:1
// criterion), the heavy cube within 1 mm of the axis at the end. The sample offered up to
// 10,000:1, where the column stood only because it fell asleep first: awake, it buckled on the
// soft contacts' springs (run at 10,000:1 this test gave a deepest overlap of 66 cm, 5.8 s in,
// the heavy cube ending on the ground; at 1000:1, 90 cm at 6.6 s; the bound's comment says
// why). With sleep on it stands too.
TEST(RigidStacking, TheMassRatioSamplesColumnStandsAtItsLargestRatio) {
  for (const bool sleep : {false, true}) {
    SCOPED_TRACE(sleep ? "sleep on" : "sleep off");
    ContactSettings c;
    c.sleep = sleep;
    HeavyOnLight st(c, pba::rigid_scenes::kHeavyOnLightMaxRatio);
    double deepest = 0;
    for (int i = 0; i < 3600; ++i) {
      st.s.step(1.0 / 60, kGravity);
      deepest = std::max(deepest, st.column_overlap());
    }
    const Vec3 p = st.s.center_of_mass(st.heavy);
    EXPECT_LT(deepest, 0.01);
    EXPECT_LT(std::hypot(p.x, p.z), 0.001);
    EXPECT_GT(p.y, 2.0 - 0.02);
  }
}

// A light body under a heavy one rests within the linear slop of its size at the defaults
// (docs/rigid-bodies.md, known limits): a 5 cm ball (0.52 kg) and a 2 cm ball (34 g) on the
// ground, a 432 kg box (0.9 x 0.6 x 0.8 m) dropped 0.5 m onto each and a 382 kg ball 1.6 m
// onto that, 10 s: the small ball's centre ends at least its radius less the slop above the
// ground (the soft springs alone left the 5 cm ball 2.9 cm deep and the 2 cm ball's centre
// 8.5 mm under the ground). And a 1e6 kg box on a 1 g box of 10 cm (a ratio of 1e9): the
// light box's centre at least its half size less the slop up (it was crushed to -2.1 cm).
TEST(RigidStacking, ALightBodyUnderAHeavyOneRestsWithinTheSlop) {
  const double slop = ContactSettings{}.linear_slop;
  for (const double r : {0.05, 0.02}) {
    RigidBodySystem s;
    pba::rigid_scenes::ground(s);
    auto ball = [&](const Vec3& p, double radius) {
      return s.create({.pose = {p}, .shapes = {{.shape = ColliderShape::sphere(radius), .density = 1000,
                                                 .material = {.restitution = 0, .friction = 0.5}}}});
    };
    const auto small = ball({0, r, 0}, r);
    const auto box = pba::rigid_scenes::box(s, {0, 2 * r + 0.3 + 0.5, 0}, Vec3(0.45, 0.3, 0.4));
    ball({0, 2 * r + 0.6 + 0.45 + 1.6, 0}, 0.45);
    ASSERT_NEAR(s.mass(box), 432, 1e-9);
    for (int i = 0; i < 600; ++i) s.step(1.0 / 60, kGravity);
    EXPECT_GT(s.center_of_mass(small).y, r - slop) << "ball of radius " << r;
  }
  RigidBodySystem s;
  pba::rigid_scenes::ground(s);
  const auto light = pba::rigid_scenes::box(s, {0, 0.05, 0}, Vec3(0.05), 0.5, 1.0);
  const auto heavy = pba::rigid_scenes::box(s, {0, 0.6, 0}, Vec3(0.5), 0.5, 1e6);
  ASSERT_NEAR(s.mass(heavy) / s.mass(light), 1e9, 1);
  for (int i = 0; i < 600; ++i) s.step(1.0 / 60, kGravity);
  EXPECT_GT(s.center_of_mass(light).y, 0.05 - slop);
}

}  // namespace

namespace {

// A column of five one-metre cubes tilted rigidly by 0.02 rad about an edge of its base and
// let go rocks about its two base edges. Housner (1963, "The behavior of inverted pendulum
// structures during earthquakes") for a rigid block of half width b and half height h
// (tan alpha = b / h, R = sqrt(b^2 + h^2)): each impact keeps at most r = (1 - 3/2 sin^2 alpha)^2
// of the energy (the angular momentum about the new edge is conserved, nothing bounces), and
// from rest at tilt theta it reaches the upright in t(theta) = acosh(1 / (1 - theta / alpha)) / p,
// p^2 = 3 g / (4 R). A contact solver must not feed energy in: over the rocking, the energy
// (kinetic plus potential, from the final rest) at each turning point is at most r times the
// one before, and between turning points never above the last one by more than the springs
// hold under the column's weight (the soft contacts store energy Housner's rigid block has
// not; bound: the energy the column's sag released at rest, m g times each box's sag, 14 J
// against the 480 J of the tilt); and since the rocking
// ends no later than the sum of Housner's swings (finite: the swings shorten geometrically),
// the column is still (every box under the sleep tolerances, 0.05 m/s and 2 degrees/s) for a
// whole time_to_sleep before that sum has run out. Soft step at the defaults, sleeping off.
// The defaults halve the substeps only where every body is at rest for a second (the sag they
// predict is a rest's): the rocking runs at 8 substeps, and the column takes 4 a second after it
// stopped, sinking onto springs a quarter as stiff (they hold 82 J there, 18% of the tilt's;
// halved while it rocked, at 1 s, it fed that into the rocking). The energies are measured from
// the rest the rocking came to, on the springs it rocked on.
TEST(RigidRocking, AColumnRockingOnItsEdgesLosesHousnersShareAtEveryImpactAndComesToRest) {
  constexpr int kBoxes = 5;
  constexpr double kTilt = 0.02, kDt = 1.0 / 60;
  const double b = 0.5, h = 0.5 * kBoxes, radius = std::hypot(b, h), alpha = std::atan(b / h);
  const double sa = std::sin(alpha), r = std::pow(1 - 1.5 * sa * sa, 2), p = std::sqrt(3 * kG / (4 * radius));
  const double mass = 1000.0 * kBoxes;
  auto energy_at = [&](double theta) { return mass * kG * radius * (std::cos(alpha - theta) - std::cos(alpha)); };
  auto swing = [&](double theta) { return std::acosh(1 / (1 - theta / alpha)) / p; };
  // Housner's time to rest: to the first impact, then out and back at each smaller amplitude
  double housner = swing(kTilt);
  for (double theta = kTilt; theta > 1e-12;) {
    const double target = r * energy_at(theta);
    double lo = 0, hi = theta;  // energy_at rises with theta on [0, alpha)
    for (int i = 0; i < 60; ++i) (energy_at(0.5 * (lo + hi)) < target ? lo : hi) = 0.5 * (lo + hi);
    theta = lo;
    housner += 2 * swing(theta);
  }
  ASSERT_GT(housner, 5.0);  // (9.3 s)
  ASSERT_LT(housner, 12.0);

  RigidBodySystem s({.capacity = 16, .contacts = {.sleep = false}});
  ground(s, 0.5);
  const Quat q = glm::angleAxis(-kTilt, Vec3(0, 0, 1));  // towards +x, about the edge x = 0.5, y = 0
  const Vec3 pivot(b, 0, 0);
  std::vector<pba::RigidBodyId> boxes;
  for (int i = 0; i < kBoxes; ++i)
    boxes.push_back(s.create({.pose = {pivot + q * (Vec3(0, 0.5 + i, 0) - pivot), q},
                              .shapes = {box_shape({0.5, 0.5, 0.5}, 0.5, 1000)}}));
  auto potential = [&] {
    double e = 0;
    for (auto x : boxes) e += s.mass(x) * kG * s.center_of_mass(x).y;
    return e;
  };
  const double released = potential();
  const auto& cs = s.settings();
  const int steps = static_cast<int>(housner / kDt);
  std::vector<double> energy(steps), top_vx(steps);
  std::vector<int> taken(steps);
  double moving_until = 0;
  for (int i = 0; i < steps; ++i) {
    s.step(kDt, kGravity);
    double e = potential(), v = 0, w = 0;
    for (auto x : boxes) {
      e += s.kinetic_energy(x);
      v = std::max(v, glm::length(s.linear_velocity(x)));
      w = std::max(w, glm::length(s.angular_velocity(x)));
    }
    energy[i] = e;
    top_vx[i] = s.linear_velocity(boxes.back()).x;
    taken[i] = s.profile().substeps;
    if (v >= cs.sleep_linear || w >= cs.sleep_angular) moving_until = s.time();
  }
  EXPECT_LT(moving_until, housner - cs.time_to_sleep) << "Housner's rocking ends by " << housner << " s";
  // the rocking ran on the springs of 8 substeps: the defaults halve them only for bodies at
  // rest (a second after the column stopped; it sinks then onto springs a quarter as stiff,
  // and a second later, still at rest, onto those of 3 substeps)
  const auto halved = std::find(taken.begin(), taken.end(), 4);
  for (auto k = taken.begin(); k != halved; ++k) ASSERT_EQ(*k, 8) << "step " << (k - taken.begin());
  const std::size_t end = static_cast<std::size_t>(halved - taken.begin());
  ASSERT_GT(end, 0u);
  if (halved != taken.end()) {
    EXPECT_GE(static_cast<double>(end) * kDt, moving_until + 1.0) << "halved while it rocked";
    const auto third = std::find(halved, taken.end(), 3);
    EXPECT_TRUE(std::all_of(halved, third, [](int k) { return k == 4; }));
    EXPECT_TRUE(std::all_of(third, taken.end(), [](int k) { return k == 3; }));
  }
  // energies from the rest the rocking came to, on its springs (their sag puts it a little
  // under the undeformed column's)
  const double rest = energy[end - 1];
  double upright = 0;  // the undeformed column's potential
  for (int i = 0; i < kBoxes; ++i) upright += 1000.0 * kG * (0.5 + i);
  const double springs = upright - rest;
  ASSERT_GT(springs, 0);
  ASSERT_LT(springs, 0.05 * energy_at(kTilt));
  double last = released - rest;
  ASSERT_NEAR(last, energy_at(kTilt), 0.05 * energy_at(kTilt));
  int turns = 0;
  for (int i = 1; i < steps && last > 0.1 * (released - rest); ++i) {
    const double e = energy[i] - rest;
    EXPECT_LE(e, last + springs) << "at " << (i + 1) * kDt << " s";
    if ((top_vx[i] > 0) != (top_vx[i - 1] > 0)) {  // a turning point: the top's sway reverses
      EXPECT_LE(e, r * last) << "turning point " << turns << " at " << (i + 1) * kDt << " s";
      last = e, ++turns;
    }
  }
  EXPECT_GE(turns, 8);  // it did rock (Housner: 9 turning points above a tenth of the energy)
}

// A column of ten cubes on the soft contacts, settled for two seconds (the defaults halve its
// substeps a second in: 4 substeps, 60 Hz, its sag 7.9 mm under 1% of a cube) and kicked as a
// rigid body about its base at 0.02 rad/s, sways on the contacts' springs without lifting an
// edge (about 0.66 Hz at 4 substeps, 1.4 at 8), for 12 s. A passive system's energy can only
// go down: once the kick's mix of modes
// has settled into the sway (after a second), the energy (kinetic plus potential, both
// measured from the settled column) at each of its maxima, where the column passes upright and
// the springs are back at their static load, is below the one before. Soft step at the
// defaults, sleeping off, over the sway's life: its maxima above a thousandth of the kick's
// energy (below, by about 4.5 s, what is left is the settled column's sub-millimetre motions,
// 0.002-0.013 J of the kick's 64). (Measured: each half swing keeps 0.53 of it, a damping
// ratio near 0.1; 0.84-0.86 before the ground's contacts were held to one radian a substep;
// a relax pass solving the column top down instead of bottom up gained energy every swing.)
TEST(RigidRocking, ATenStackSwayingOnItsContactsLosesEnergyEverySwing) {
  constexpr int kBoxes = 10;
  constexpr double kDt = 1.0 / 60;
  Stack st(kBoxes);
  for (int i = 0; i < 120; ++i) st.s.step(kDt, kGravity);
  auto energy = [&] {
    double e = 0;
    for (auto x : st.boxes) e += st.s.kinetic_energy(x) + st.s.mass(x) * kG * st.s.center_of_mass(x).y;
    return e;
  };
  const double settled = energy();
  for (auto x : st.boxes) {
    const Vec3 w(0, 0, 0.02);
    st.s.set_velocity(x, glm::cross(w, st.s.center_of_mass(x)), w);
  }
  std::vector<double> e;
  for (int i = 0; i < 720; ++i) st.s.step(kDt, kGravity), e.push_back(energy() - settled);
  int maxima = 0;
  double last = INFINITY;
  const double floor = 1e-3 * e.front();
  for (std::size_t i = 60; i + 1 < e.size(); ++i)
    if (e[i] >= e[i - 1] && e[i] > e[i + 1] && e[i] > floor) {
      EXPECT_LT(e[i], last) << "the maximum at " << (i + 1) * kDt << " s";
      last = e[i], ++maxima;
    }
  EXPECT_GE(maxima, 8);  // it swayed: two maxima a period, 0.66 Hz, for over 6 s
  EXPECT_GT(last, 0);
}

// The soft contacts' spring-damper model of a column of n one-metre cubes (1000 kg) rocking
// about z on its contacts, linearised about the upright. The unknowns are the boxes' turns
// theta_k (k = 0 at the bottom). Friction sticks, so each box turns about the centre of the
// face it stands on: its centre is at x_k = -(theta_0 + ... + theta_{k-1} + theta_k / 2),
// height y_k = cos theta_0 + ... + cos theta_{k-1} + cos(theta_k) / 2. Each of a contact's four
// points, half a metre from the axis, is a spring m_p w^2 and a damper 2 zeta m_p w along the
// normal (w = 2 pi hertz), m_p the point's normal effective mass 1 / K_pp: m / 4 on the ground
// (1/m + 0.5 * 6/m, the cube's inertia being m / 6) and m / 8 between two cubes. So a contact
// is a torsion spring 4 * 0.25 * m_p w^2 on the relative turn of its two boxes, with a torsion
// damper 2 zeta / w times that. Mass matrix: m J^T J + m / 6 (J the x_k above); stiffness: the
// springs, less m g (1/2 + the boxes above k) on the diagonal (gravity: m g sum y_k, second
// order); damping: the dampers.
struct ColumnMode {
  double lambda = 0;  // the lowest mode's omega^2 (1/s^2): negative when the column buckles
  double hertz = 0;   // its frequency (Hz) when it stands
  double zeta = 0;    // its damping ratio, to first order in the dampers
  double growth = 0;  // when it buckles: the rate (1/s) at which its lean grows, dampers in
};

ColumnMode column_mode(int n, double ground_hertz, double hertz, double zeta) {
  const double m = 1000, wg = 2 * pba::kPi * ground_hertz, w = 2 * pba::kPi * hertz;
  const auto un = static_cast<std::size_t>(n);
  std::vector<double> M(un * un), K(un * un), C(un * un);
  auto at = [n](std::vector<double>& a, int i, int j) -> double& { return a[static_cast<std::size_t>(i * n + j)]; };
  for (int k = 0; k < n; ++k)
    for (int i = 0; i <= k; ++i)
      for (int j = 0; j <= k; ++j) at(M, i, j) += m * (i < k ? -1 : -0.5) * (j < k ? -1 : -0.5);
  for (int k = 0; k < n; ++k) at(M, k, k) += m / 6;
  at(K, 0, 0) += m / 4 * wg * wg, at(C, 0, 0) += 2 * zeta * m / 4 * wg;
  for (int k = 0; k + 1 < n; ++k) {
    const double spring = m / 8 * w * w, damper = 2 * zeta * m / 8 * w;
    for (int i = k; i <= k + 1; ++i)
      for (int j = k; j <= k + 1; ++j) at(K, i, j) += (i == j ? 1 : -1) * spring, at(C, i, j) += (i == j ? 1 : -1) * damper;
  }
  for (int k = 0; k < n; ++k) at(K, k, k) -= m * kG * (0.5 + (n - 1 - k));
  // the lowest mode: inverse iteration shifted below every eigenvalue ((K - sigma M) x' = M x
  // converges to the eigenvalue nearest sigma); sigma is below them all when K - sigma M has
  // positive pivots (checked)
  const double sigma = -1;
  std::vector<double> A(un * un);
  for (std::size_t i = 0; i < un * un; ++i) A[i] = K[i] - sigma * M[i];
  for (int c = 0; c < n; ++c) {  // LU without pivoting (symmetric positive definite)
    EXPECT_GT(at(A, c, c), 0) << "the shift is not below the column's eigenvalues";
    for (int r = c + 1; r < n; ++r) {
      at(A, r, c) /= at(A, c, c);
      for (int j = c + 1; j < n; ++j) at(A, r, j) -= at(A, r, c) * at(A, c, j);
    }
  }
  std::vector<double> x(un, 1.0), y(un);
  for (int it = 0; it < 2000; ++it) {
    for (int i = 0; i < n; ++i) {
      y[i] = 0;
      for (int j = 0; j < n; ++j) y[i] += at(M, i, j) * x[j];
    }
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < i; ++j) y[i] -= at(A, i, j) * y[j];
    for (int i = n; i-- > 0;) {
      for (int j = i + 1; j < n; ++j) y[i] -= at(A, i, j) * y[j];
      y[i] /= at(A, i, i);
    }
    double norm = 0;
    for (const double v : y) norm += v * v;
    for (int i = 0; i < n; ++i) x[i] = y[i] / std::sqrt(norm);
  }
  auto form = [&](std::vector<double>& a) {
    double q = 0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) q += x[i] * at(a, i, j) * x[j];
    return q;
  };
  const double mm = form(M), kk = form(K), cc = form(C);
  ColumnMode r;
  r.lambda = kk / mm;
  if (r.lambda > 0) {
    r.hertz = std::sqrt(r.lambda) / (2 * pba::kPi);
    r.zeta = cc / (2 * std::sqrt(r.lambda) * mm);
  } else {
    r.growth = (-cc + std::sqrt(cc * cc - 4 * mm * kk)) / (2 * mm);
  }
  return r;
}

// The contacts' spring rates at a system's settings: contact_hertz up to a quarter of the
// substep rate, twice that on a body that cannot move but no more than one radian a substep
// (h w <= 1; contact_solver.cpp).
std::pair<double, double> ground_and_box_hertz(const ContactSettings& c, double dt) {
  const double cap = 0.25 * c.substeps / dt, hertz = std::min(c.contact_hertz, cap);
  return {std::min(2 * hertz, c.substeps / dt / (2 * pba::kPi)), hertz};
}

// the settings as the last step took them: the soft step's auto_substeps scales the substeps
// and contact_hertz together (RigidProfile::substeps)
ContactSettings taken_settings(const RigidBodySystem& s) {
  ContactSettings c = s.settings();
  c.contact_hertz *= static_cast<double>(s.profile().substeps) / c.substeps;
  c.substeps = s.profile().substeps;
  return c;
}

// A cube on the ground under a steady torque about z (sleeping off) tilts until its contact
// springs balance it: four points half a metre either side of the axis, each a spring
// m_p w^2 with m_p = m / 4 (1 / K_pp: 1/m + 0.5 * 6/m) and w the ground's rate (twice
// contact_hertz, but at most one radian a substep: 1 / h = 480 rad/s at 8 substeps, 240 at
// the 4 the defaults halve to a second in, 180 at the 3 they take a second later; with
// ContactSettings::auto_substeps_least 4 the cube keeps 4), so a tilt stiffness of m w^2 / 4
// less gravity's overturning m g / 2, within 1% (measured 0.07% at 8 substeps).
TEST(RigidRocking, AGroundContactsTiltStiffnessIsItsSprings) {
  constexpr double kDt = 1.0 / 60, kTorque = 2000;  // N m, well below tipping (m g / 2 = 4905)
  for (const int least : {4, 3}) {
    Stack st(1);
    st.s.settings().auto_substeps_least = least;
    for (int i = 0; i < 180; ++i) st.s.step(kDt, kGravity);
    const auto [ground_hz, box_hz] = ground_and_box_hertz(taken_settings(st.s), kDt);
    ASSERT_EQ(st.s.profile().substeps, least);
    ASSERT_NEAR(ground_hz, 60.0 * least / (2 * pba::kPi), 1e-9);
    const Quat before = st.s.pose(st.boxes[0]).rotation;
    for (int i = 0; i < 240; ++i) {
      st.s.apply_torque(st.boxes[0], {0, 0, kTorque}), st.s.step(kDt, kGravity);
      ASSERT_EQ(st.s.profile().substeps, least) << "step " << i;
    }
    const Quat turn = st.s.pose(st.boxes[0]).rotation * glm::conjugate(before);
    const double m = 1000, w = 2 * pba::kPi * ground_hz, stiffness = m * w * w / 4 - m * kG / 2;
    EXPECT_NEAR(kTorque / (2 * turn.z), stiffness, 0.01 * stiffness) << least << " substeps";
  }
}

// A 10-stack kicked as in the test above sways at a frequency between its spring model's
// (column_mode: 1.29 Hz at 8 substeps, the ground's contacts at 76 Hz, the others at 120; at
// the 4 substeps the defaults halve to a second in, as here, 0.623 Hz, 38 and 60 Hz) and the
// same model's on a rigid ground (1.64 Hz; 0.801 at 4): the ground's contact is a spring in the
// biased pass, but the relax pass, which solves it last, leaves box 0 with no normal velocity
// against the ground at the end of every substep, as a rigid support would (measured 1.36 Hz
// at 8 substeps, 0.662 at 4; 1.51 against 1.47 when the ground's contacts were at 120 Hz like
// the others). Settled 2 s (past the halving), kicked, 16 s (five periods at 4). The springs
// themselves are the model's to 0.1% (RigidRocking.AGroundContactsTiltStiffnessIsItsSprings).
// Its damping: at least half the model's (the dampers at damping ratio 10 give the sway 0.134)
// and at most 1.2 times it; measured 0.10 at 8 substeps and 0.106 at 4 (model 0.138; the mean
// log decrement of the top box's velocity over its half swings from 1 s until the sway has
// died, about 4.5 s at 8). The soft step's passes
// are one Gauss-Seidel sweep each per substep (as Box2D's), and the contact against the ground
// is solved last in each: as it nears the cap of a quarter of the substep rate, that sweep
// stops damping the sway (0.030 with the ground at 120 Hz, 0.052 at 100 Hz, 0.068 at 90 Hz,
// 0.10 at 76 Hz, 0.12 at 70 Hz), so contacts against a body that cannot move are held to one
// radian a substep (contact_solver.cpp; docs/rigid-bodies.md, "A column's sway").
TEST(RigidRocking, ATenStackSwaysAtItsSpringModelsFrequencyAndDecays) {
  constexpr int kBoxes = 10;
  constexpr double kDt = 1.0 / 60;
  Stack st(kBoxes);
  for (int i = 0; i < 120; ++i) st.s.step(kDt, kGravity);
  const auto [ground_hz, box_hz] = ground_and_box_hertz(taken_settings(st.s), kDt);
  const ColumnMode model = column_mode(kBoxes, ground_hz, box_hz, st.s.settings().damping_ratio);
  const ColumnMode rigid_ground = column_mode(kBoxes, 1e6, box_hz, st.s.settings().damping_ratio);
  ASSERT_GT(model.lambda, 0);
  ASSERT_EQ(st.s.profile().substeps, 4);
  ASSERT_NEAR(model.hertz, 0.623, 0.01);
  ASSERT_NEAR(model.zeta, 0.138, 0.005);
  ASSERT_NEAR(rigid_ground.hertz, 0.801, 0.01);
  for (auto x : st.boxes) {
    const Vec3 w(0, 0, 0.02);
    st.s.set_velocity(x, glm::cross(w, st.s.center_of_mass(x)), w);
  }
  std::vector<double> v;  // the top box's sway velocity, after each step
  for (int i = 0; i < 960; ++i) st.s.step(kDt, kGravity), v.push_back(st.s.linear_velocity(st.boxes.back()).x);
  // its extremes after the first second, where the kick's higher modes have died out
  std::vector<std::pair<double, double>> peaks;
  for (std::size_t i = 60; i + 1 < v.size(); ++i)
    if ((v[i] > v[i - 1] && v[i] >= v[i + 1]) || (v[i] < v[i - 1] && v[i] <= v[i + 1]))
      peaks.push_back({static_cast<double>(i + 1) * kDt, v[i]});
  ASSERT_GE(peaks.size(), 10u);  // five periods
  double decrement = 0;
  for (std::size_t k = 1; k < peaks.size(); ++k) {
    ASSERT_LT(peaks[k].second * peaks[k - 1].second, 0) << "the extremes alternate, at " << peaks[k].first << " s";
    decrement += std::log(std::abs(peaks[k - 1].second / peaks[k].second));
  }
  const double delta = 2 * decrement / static_cast<double>(peaks.size() - 1);  // per period
  const double zeta = delta / std::sqrt(4 * pba::kPi * pba::kPi + delta * delta);
  const double hertz = 0.5 * static_cast<double>(peaks.size() - 1) / (peaks.back().first - peaks.front().first);
  EXPECT_GT(hertz, model.hertz) << "softer than its springs";
  EXPECT_LT(hertz, rigid_ground.hertz) << "stiffer than on a rigid ground";
  EXPECT_GE(zeta, 0.5 * model.zeta) << "damped at under half the spring-damper model's " << model.zeta;
  EXPECT_LE(zeta, 1.2 * model.zeta) << "damped beyond the spring-damper model's " << model.zeta;
  std::printf("10-stack sway: %.3f Hz (model %.3f, on a rigid ground %.3f), damping ratio %.4f (model %.4f)\n", hertz,
              model.hertz, rigid_ground.hertz, zeta, model.zeta);
}

// The same model for 40 cubes on the default contacts (8 substeps, auto_substeps off: 120 Hz
// between the cubes, 76 Hz on the ground)
// has a negative stiffness: gravity's overturning outgrows the contacts' springs between 37
// and 38 cubes (38 and 39 with the ground at 120 Hz),
// so a 40-stack cannot stand on them, however they are damped. Kicked at 0.01 mrad/s after a
// settling second, its lean grows at the model's rate (measured 0.235/s from 10 s to 20 s,
// the model 0.243/s) within 20%: so near the buckling load the rate is sensitive to the
// springs (1.7% stiffer ones give 7% less). At 16 substeps (240 Hz between the cubes, 153 Hz
// on the ground) the model stands, its lowest mode at 0.15 Hz
// (RigidStacking.FortyCubesStandTwentySeconds).
TEST(RigidStacking, AFortyStackOnTheDefaultContactsLeansOverAtItsSpringModelsBucklingRate) {
  constexpr int kBoxes = 40;
  constexpr double kDt = 1.0 / 60;
  ContactSettings c;
  c.sleep = false;
  c.auto_substeps = false;  // (the default contacts: 8 substeps and 120 Hz, not more for the column)
  const auto [ground_hz, box_hz] = ground_and_box_hertz(c, kDt);
  const ColumnMode model = column_mode(kBoxes, ground_hz, box_hz, c.damping_ratio);
  ASSERT_LT(model.lambda, 0);
  ASSERT_GT(column_mode(kBoxes - 3, ground_hz, box_hz, c.damping_ratio).lambda, 0);
  ASSERT_LT(column_mode(kBoxes - 2, ground_hz, box_hz, c.damping_ratio).lambda, 0);
  ContactSettings sixteen = c;
  sixteen.substeps = 16, sixteen.contact_hertz = 240;
  const auto [ground16, box16] = ground_and_box_hertz(sixteen, kDt);
  ASSERT_GT(column_mode(kBoxes, ground16, box16, c.damping_ratio).lambda, 0);
  RigidBodySystem s({.capacity = 64, .contacts = c});
  const auto boxes = pba::rigid_scenes::vertical_stack(s, kBoxes);
  for (int i = 0; i < 60; ++i) s.step(kDt, kGravity);
  for (auto x : boxes) {
    const Vec3 w(0, 0, 1e-5);
    s.set_velocity(x, glm::cross(w, s.center_of_mass(x)), w);
  }
  auto lean = [&] { return std::abs(s.center_of_mass(boxes.back()).x); };
  for (int i = 0; i < 600; ++i) s.step(kDt, kGravity);
  const double at10 = lean();
  for (int i = 0; i < 600; ++i) s.step(kDt, kGravity);
  const double rate = std::log(lean() / at10) / 10;
  EXPECT_NEAR(rate, model.growth, 0.2 * model.growth);
}

// ---------------------------------------------------------------------------------------
// fast bodies

// A 0.1 m sphere at 240 m/s (4 m per step) stops at a 10 cm wall: the pair is found by the
// bounds grown by the step's motion and the speculative point stops it at the surface.
TEST(RigidContinuous, AFastSphereStopsAtAThinWall) {
  for (const auto solver : kAll) {
    RigidBodySystem s({.contacts = {.solver = solver}});
    s.create({.name = "wall", .type = BodyType::Static, .pose = {{10, 0, 0}}, .shapes = {box_shape({0.05, 2, 2})}});
    auto ball = s.create({.name = "bullet", .pose = {{0, 0, 0}}, .linear_velocity = {240, 0, 0},
                          .shapes = {{.shape = ColliderShape::sphere(0.1)}}, .bullet = true});
    double farthest = 0;
    for (int i = 0; i < 60; ++i) {
      s.step(1.0 / 60, Vec3(0));
      farthest = std::max(farthest, s.center_of_mass(ball).x);
    }
    EXPECT_LT(farthest, 10 - 0.05 - 0.1 + 0.01) << to_string(solver);
    EXPECT_LT(s.center_of_mass(ball).x, 10) << to_string(solver);
  }
}

}  // namespace

namespace {

// ---------------------------------------------------------------------------------------
// the pair cache

// A manifold carried over from an earlier step (ContactSettings::reuse_distance, Jolt's body
// pair cache) measures the separations a fresh one would, to within the reuse distance: its
// points ride with the bodies, so they are off only by how far the bodies moved against each
// other since it was made. A 4 m plank lies tilted on the ground, one bottom edge 1 mm up and
// the other 22 mm up (outside the 2 cm speculative distance, so not in the manifold). Turned
// about its centre by 0.9 degrees (under the 1 degree reuse angle, its centre not moved at
// all), the high edge comes down 31 mm into the ground: a fresh manifold has it 9 mm deep.
// The corners moved 2 r sin(0.45 deg) = 33 mm (r = 2.08 m, the plank's reach), so the
// carried manifold, which knows only the other edge, must be made afresh; turned by 0.01
// degrees (0.36 mm at the corners) it is carried over and still within 1 mm of a fresh one.
TEST(RigidPairCache, ACarriedOverManifoldSeparatesAsAFreshOneToTheReuseDistance) {
  const Vec3 half{2, 0.25, 0.5};
  const double rise = 0.022, sin_a = (rise - 0.001) / (2 * half.x), tilt = std::asin(sin_a);
  const double height = 0.001 + half.x * sin_a + half.y * std::cos(tilt);  // the low edge 1 mm up
  for (const double turn : {deg(0.9), deg(0.01)}) {
    double deepest[2];
    std::size_t reused[2];
    for (const double reuse : {0.0, 0.001}) {
      RigidBodySystem s({.contacts = {.reuse_distance = reuse, .reuse_angle = deg(1)}});
      ground(s);
      const auto plank = s.create({.name = "plank", .pose = {{0, height, 0}, glm::angleAxis(tilt, Vec3(0, 0, 1))},
                                   .shapes = {box_shape(half)}});
      s.step(1.0 / 60, Vec3(0));  // the manifold: the low edge's two points
      ASSERT_EQ(s.contacts().size(), 2u);
      s.set_pose(plank, {{0, height, 0}, glm::angleAxis(tilt - turn, Vec3(0, 0, 1))});
      s.step(1.0 / 60, Vec3(0));
      const int k = reuse > 0;
      deepest[k] = -INFINITY;
      for (const pba::RigidContactPoint& c : s.contacts()) deepest[k] = std::max(deepest[k], c.depth);
      reused[k] = s.profile().reused;
    }
    // a fresh manifold's deepest point: the high edge's overlap after the turn about the centre
    if (turn > deg(0.5)) {
      EXPECT_NEAR(deepest[0], -(height + half.x * std::sin(tilt - turn) - half.y * std::cos(tilt - turn)), 1e-9);
    }
    EXPECT_NEAR(deepest[1], deepest[0], 0.001) << "turned " << turn * 180 / pba::kPi << " degrees";
    EXPECT_EQ(reused[1], turn > deg(0.5) ? 0u : 1u) << "turned " << turn * 180 / pba::kPi << " degrees";
  }
}

// The reuse angle never binds above 2 asin(0.01 / sqrt(3)) = 0.662 degrees, whatever the
// reuse distance: the distance test counts the chord 2 r sin(angle / 2) a turn moves the
// body's reach r through, r is at least sqrt(3) times the body's thinnest half size t (r
// reaches a corner of the shapes' bounds), and the pair's reuse distance is at most 0.02 t
// (pair_reuse), so no body keeps its manifold past that turn. Turned in place about the
// vertical on the ground, 1 mm up, at a reuse distance of 1 mm: a 1 m cube (r = 0.866 m) by
// 1.5 degrees (its corners 22.7 mm) gets a fresh manifold whatever the angle allows (1,
// Jolt's 2, 180: the test off), by 0.05 degrees (0.76 mm) it keeps it; a 5 cm ball (r = 86.6
// mm) keeps it at 0.6 degrees (0.91 mm) and not at 0.7 (1.06 mm) with the angle test off;
// a 1 cm ball (reuse 0.2 mm, r = 17.3 mm) keeps it at 0.65 degrees (0.197 mm) and not at 0.68
// (0.206 mm). At a reuse distance of 10 mm the 1 m cube (reuse 10 mm) keeps it at 0.65
// degrees (9.8 mm) and not at 0.68 (10.3 mm). (On a static slab, not a plane: a body's manifold
// with a plane is carried whatever it turns while its points stay the narrow phase's, the next
// test.)
TEST(RigidPairCache, TheReuseAngleNeverBindsAboveTwoThirdsOfADegree) {
  struct Case {
    double half;  // the cube's half size, or the ball's radius (m)
    bool ball;
    double reuse, turn, angle;
    std::size_t reused;
  };
  const Case cases[] = {
      {0.5, false, 0.001, deg(1.5), deg(1), 0},   {0.5, false, 0.001, deg(1.5), deg(2), 0},
      {0.5, false, 0.001, deg(1.5), deg(180), 0}, {0.5, false, 0.001, deg(0.05), deg(1), 1},
      {0.05, true, 0.001, deg(0.6), deg(180), 1}, {0.05, true, 0.001, deg(0.7), deg(180), 0},
      {0.01, true, 0.001, deg(0.65), deg(180), 1}, {0.01, true, 0.001, deg(0.68), deg(180), 0},
      {0.5, false, 0.01, deg(0.65), deg(180), 1}, {0.5, false, 0.01, deg(0.68), deg(180), 0},
  };
  for (const Case& c : cases) {
    const std::string what = std::string(c.ball ? "ball " : "cube ") + std::to_string(c.half) + " m, reuse " +
                             std::to_string(c.reuse) + " m, turned " + std::to_string(c.turn * 180 / pba::kPi) +
                             " degrees, reuse angle " + std::to_string(c.angle * 180 / pba::kPi);
    RigidBodySystem s({.contacts = {.reuse_distance = c.reuse, .reuse_angle = c.angle}});
    s.create({.name = "slab", .type = BodyType::Static, .pose = {{0, -1, 0}}, .shapes = {box_shape(Vec3(20, 1, 20))}});
    const double up = 0.001;  // within the speculative distance (0.4 of the half size for the 1 cm ball)
    const auto body = s.create({.name = "body", .pose = {{0, c.half + up, 0}},
                                .shapes = {{.shape = c.ball ? ColliderShape::sphere(c.half) : ColliderShape::box(Vec3(c.half))}}});
    s.step(1.0 / 60, Vec3(0));  // the manifold
    ASSERT_EQ(s.contacts().size(), c.ball ? 1u : 4u) << what;
    s.set_pose(body, {{0, c.half + up, 0}, glm::angleAxis(c.turn, Vec3(0, 1, 0))});
    s.step(1.0 / 60, Vec3(0));
    EXPECT_EQ(s.profile().reused, c.reused) << what;
    EXPECT_EQ(s.profile().built + s.profile().reused, 1u) << what;
  }
}

// A ball's or a box's manifold with a plane is carried, whatever the body slid, turned or rose,
// while the narrow phase would make the same points (a ball within the reach; a box's corners
// within the reach the manifold's), the plane's points made again under the body's: its contacts
// are a fresh manifold's to rounding. A 0.3 m ball and a 0.5 m cube 1 mm up, the plane made
// before them (its pairs' a) and after (b), slid 7 cm, turned 20 degrees about a tilted axis
// (the ball) or the vertical (the cube) and raised 5 mm: carried, and each point's position and
// depth within 1e-12 m of a system that made it afresh at that pose. Raised 3 cm, past the
// 2 cm speculative distance, the ball is made afresh (no point), the plane made first or last
// (the manifold's normal then points into the plane: the height is measured against it); the cube tilted by 10 degrees
// brings other corners within the reach and is made afresh too.
TEST(RigidPairCache, ABodysManifoldWithAPlaneIsCarriedWhileItsPointsStayTheNarrowPhases) {
  struct Case {
    bool ball, plane_first;
    Vec3 shift;
    Quat turn;
    bool carried;
  };
  const Quat spin = glm::angleAxis(deg(20), glm::normalize(Vec3(0.3, 1, 0.2)));
  const Quat yaw = glm::angleAxis(deg(20), Vec3(0, 1, 0)), tilt = glm::angleAxis(deg(10), Vec3(1, 0, 0));
  const Case cases[] = {
      {true, true, {0.07, 0.005, 0}, spin, true},    {true, false, {0.07, 0.005, 0}, spin, true},
      {true, true, {0.07, 0.03, 0}, spin, false},    {true, false, {0.07, 0.03, 0}, spin, false},
      {false, true, {0.05, 0.005, 0.05}, yaw, true},
      {false, false, {0.05, 0.005, 0.05}, yaw, true}, {false, true, {0, 0, 0}, tilt, false},
  };
  for (const Case& c : cases) {
    const std::string what = std::string(c.ball ? "ball" : "cube") + (c.plane_first ? ", plane first" : ", plane last") +
                             ", shift y " + std::to_string(c.shift.y);
    const RigidShapeDef shape = c.ball ? RigidShapeDef{.shape = ColliderShape::sphere(0.3)} : box_shape(Vec3(0.5));
    const double half = c.ball ? 0.3 : 0.5, up = 0.001;
    const Vec3 start{1, half + up, 2};
    const pba::Pose moved{start + c.shift, c.turn};
    // (the turned cube's lowest corners lower by the tilt: raised so that the nearest stays 1 mm up)
    const pba::Pose end = c.ball || c.carried ? moved
                                              : pba::Pose{moved.position + Vec3(0, half * (std::cos(deg(10)) + std::sin(deg(10))) - half, 0),
                                                          c.turn};
    auto make = [&](RigidBodySystem& s, const pba::Pose& pose) {
      if (c.plane_first) ground(s);
      const auto body = s.create({.name = "body", .pose = pose, .shapes = {shape}});
      if (!c.plane_first) ground(s);
      return body;
    };
    RigidBodySystem carried;
    const auto body = make(carried, {start});
    carried.step(1.0 / 60, Vec3(0));  // the manifold
    ASSERT_EQ(carried.contacts().size(), c.ball ? 1u : 4u) << what;
    carried.set_pose(body, end);
    carried.step(1.0 / 60, Vec3(0));
    EXPECT_EQ(carried.profile().reused, c.carried ? 1u : 0u) << what;
    RigidBodySystem fresh;
    make(fresh, end);
    fresh.step(1.0 / 60, Vec3(0));
    EXPECT_EQ(fresh.profile().built, fresh.contacts().empty() ? 0u : 1u) << what;
    const std::vector<pba::RigidContactPoint> kept = carried.contacts(), made = fresh.contacts();  // (copies)
    ASSERT_EQ(kept.size(), made.size()) << what;
    for (std::size_t k = 0; k < made.size(); ++k) {
      const pba::RigidContactPoint& x = kept[k];
      const pba::RigidContactPoint& y = made[k];
      EXPECT_EQ(x.id, y.id) << what;
      EXPECT_NEAR(glm::length(x.position - y.position), 0, 1e-12) << what << ", point " << k;
      EXPECT_NEAR(x.depth, y.depth, 1e-12) << what << ", point " << k;
    }
  }
}

// A ball's one-point manifold with a mesh is carried, whatever the ball slid along a triangle's
// face, turned or rose, while the narrow phase would make the same point: the ball over that
// triangle's interior within the reach of its plane, every other triangle beyond the reach (the
// triangle's point made again under the ball's centre, as on a plane). Two triangles meeting at
// a ridge of some 20 degrees, the mesh's body turned 10 degrees and moved, made before the ball
// (its pairs' a) and after (b); a 0.3 m ball 1 mm over the first triangle's middle, slid 7 cm
// along it, raised 5 mm and turned 20 degrees: carried, its contact's position and depth within
// 1e-12 m of a system that made it afresh at that pose. Raised 3 cm, past the 2 cm speculative
// distance: made afresh (no point). Slid from 15 cm to 5 cm off the ridge, where the second
// triangle comes within the reach: made afresh too.
TEST(RigidPairCache, ABallsManifoldWithAMeshIsCarriedWhileItsPointStaysTheNarrowPhases) {
  // the mesh in its frame: triangle abc, and bdc over the ridge bc, tilted down from it
  const Vec3 a{0, 0, 0}, b{4, 0, 0.3}, c{0.5, 0.2, 4};
  const Vec3 n = glm::normalize(glm::cross(b - a, c - a));
  Vec3 out = glm::normalize(glm::cross(c - b, n));
  if (glm::dot(out, a - b) > 0) out = -out;
  const Vec3 d = 0.5 * (b + c) + 3.0 * out - 1.0 * n;
  const std::vector<Vec3> v{a, b, c, d};
  const std::vector<std::array<std::uint32_t, 3>> t{{0, 1, 2}, {1, 3, 2}};
  const auto mesh = pba::TriangleMesh::build(v, t, "ridge");
  const pba::Pose mesh_pose{{1, -0.5, 2}, glm::angleAxis(deg(10), glm::normalize(Vec3(1, 0, 1)))};
  auto world = [&](const Vec3& x) { return mesh_pose.position + mesh_pose.rotation * x; };
  const Vec3 up = mesh_pose.rotation * n, along = mesh_pose.rotation * glm::normalize(b - a);
  const Vec3 inward = mesh_pose.rotation * -out;
  const double radius = 0.3;
  // over the middle of abc, or `off` m off the ridge (the middle of bc), `gap` m from the plane
  auto middle = [&](double gap) { return world((a + b + c) / 3.0) + (radius + gap) * up; };
  auto by_ridge = [&](double off, double gap) { return world(0.5 * (b + c)) + off * inward + (radius + gap) * up; };
  struct Case {
    bool mesh_first;
    Vec3 start;
    pba::Pose end;
    bool carried;
  };
  const Quat spin = glm::angleAxis(deg(20), glm::normalize(Vec3(0.3, 1, 0.2)));
  std::vector<Case> cases;
  for (const bool first : {true, false}) {
    cases.push_back({first, middle(0.001), {middle(0.006) + 0.07 * along, spin}, true});
    cases.push_back({first, middle(0.001), {middle(0.031), spin}, false});
    cases.push_back({first, by_ridge(0.15, 0.001), {by_ridge(0.05, 0.001)}, false});
  }
  for (const Case& k : cases) {
    const std::string what = std::string(k.mesh_first ? "mesh first" : "mesh last") + ", carried " +
                             (k.carried ? "yes" : "no") + ", end " + std::to_string(k.end.position.x) + " " +
                             std::to_string(k.end.position.y) + " " + std::to_string(k.end.position.z);
    auto make = [&](RigidBodySystem& s, const pba::Pose& pose) {
      auto ground = [&] {
        s.create({.name = "ridge", .type = BodyType::Static, .pose = mesh_pose,
                  .shapes = {{.shape = ColliderShape::triangles(mesh)}}});
      };
      if (k.mesh_first) ground();
      const auto body = s.create({.name = "ball", .pose = pose, .shapes = {{.shape = ColliderShape::sphere(radius)}}});
      if (!k.mesh_first) ground();
      return body;
    };
    RigidBodySystem carried;
    const auto body = make(carried, {k.start});
    carried.step(1.0 / 60, Vec3(0));  // the manifold
    ASSERT_EQ(carried.contacts().size(), 1u) << what;
    carried.set_pose(body, k.end);
    carried.step(1.0 / 60, Vec3(0));
    EXPECT_EQ(carried.profile().reused, k.carried ? 1u : 0u) << what;
    RigidBodySystem fresh;
    make(fresh, k.end);
    fresh.step(1.0 / 60, Vec3(0));
    const std::vector<pba::RigidContactPoint> kept = carried.contacts(), made = fresh.contacts();  // (copies)
    if (!k.carried && k.end.position == by_ridge(0.05, 0.001)) {
      EXPECT_EQ(made.size(), 2u) << what;  // the premise
    }
    EXPECT_EQ(kept.size(), made.size()) << what;
    if (kept.size() != made.size()) continue;
    for (std::size_t j = 0; j < made.size(); ++j) {
      EXPECT_EQ(kept[j].id, made[j].id) << what;
      EXPECT_NEAR(glm::length(kept[j].position - made[j].position), 0, 1e-12) << what << ", point " << j;
      EXPECT_NEAR(kept[j].depth, made[j].depth, 1e-12) << what << ", point " << j;
    }
  }
}

// ---------------------------------------------------------------------------------------
// sleeping

// 25 boxes (1 m cubes, mu 0.5) dropped from 2 m + `raise` onto the ground, `spacing` apart
// on a 5 x 5 grid, each turned by its own angle, stepped until all are asleep (at most 5 s)
struct DroppedBoxes {
  RigidBodySystem s;
  pba::RigidBodyId ground;
  std::vector<pba::RigidBodyId> boxes;
  int steps = 0;
  int touching = 0;  // the box-box contact points seen over the steps, speculative included
  DroppedBoxes(pba::RigidSolverType solver, double spacing, double raise = 0)
      : s({.capacity = 64, .contacts = {.solver = solver}}), ground(pba::rigid_scenes::ground(s, 0.5)) {
    for (int i = 0; i < 25; ++i)
      boxes.push_back(pba::rigid_scenes::box(s, {(i % 5) * spacing, 2.0 + raise, (i / 5) * spacing}, Vec3(0.5), 0.5,
                                             1000, glm::angleAxis(0.2 * i, glm::normalize(Vec3(1, 1, 0)))));
    while (s.awake_count() > 0 && steps < 300) {
      s.step(1.0 / 60, kGravity), ++steps;
      for (const pba::RigidContactPoint& c : s.contacts()) touching += c.a != ground && c.b != ground;
    }
  }
  // all asleep, and not a bit moved over a second more, none sunk
  void expect_asleep_and_put(const std::string& what) {
    EXPECT_EQ(s.awake_count(), 0u) << what << " after " << steps / 60.0 << " s";
    const std::uint64_t h = s.hash();
    for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kGravity);
    EXPECT_EQ(s.hash(), h) << what;
    for (auto b : boxes) EXPECT_GT(s.center_of_mass(b).y, 0.45) << what;
  }
};

// 25 boxes dropped from 2 m onto the ground, each by itself, are all asleep within 5 s under
// each substepping solver, and sleeping bodies do not move at all. (The issue's 1000 boxes from
// a 10 x 10 x 10 grid, which land in columns that rock on their edges, are the soak test
// RigidSoak.ThousandDroppedBoxesAreAllAsleepWithinFiveSeconds.) Each by itself: the boxes
// are 5 m apart, and none touches another. They were 1.5 m apart until 2026-12-04, less than
// two of these cubes turned span (up to sqrt(3) m): 13 pairs overlapped by up to 13 cm as
// created, and more leaned on each other once down, which is the next test's case. How far
// a box travels from under where it was dropped (8 drops 1e-4 m apart, 200 boxes; median and
// largest): soft step 0.46 and 0.66 m, sequential impulses 0.45 and 0.65, TGS 0.56 and 0.70,
// XPBD 0.46 and 0.73 (0.83 and 1.88 m until its dynamic friction took the landing's whole
// normal impulse and was solved with the points, 2026-12-04:
// RigidFriction.ABoxLandingFlatWhileSlidingStopsWhereCoulombSays); Bullet 3.24 (the same
// drops, a throwaway program; mu 0.5 per body, which Bullet multiplies to 0.25: 0.22 and
// 0.80; 0.707 each, 0.5: 0.14 and 0.73). A turned box lands on a corner or an edge, and the
// landing's impulse there turns it and sends it over: travel of about half its size is the
// tumble (a box dropped flat travels nothing under every solver).
TEST(RigidSleep, DroppedBoxesFallAsleepAndStayPut) {
  for (const auto solver : kSubstepping) {
    DroppedBoxes d(solver, 5.0);
    EXPECT_EQ(d.touching, 0) << to_string(solver);  // the premise: each by itself
    d.expect_asleep_and_put(std::string(to_string(solver)));
  }
}

// The same boxes 1.5 m apart (the test above's scene before 2026-12-04): created overlapping
// and down leaning on each other, on edges and corners, from four heights 1e-7 m apart; all
// asleep within 5 s and then not a bit moved, as above. XPBD's static friction held by the
// velocity the substep ends with at every contact (a fix for small rolling balls tried first,
// src/rigid/xpbd_rigid.cpp, material_motion) left two leaning boxes rocking at up to 0.25 m/s
// in 38 of 40 such drops (main then: none).
TEST(RigidSleep, BoxesLeaningOnEachOtherFallAsleepAndStayPut) {
  for (const auto solver : kSubstepping)
  for (int k = 0; k < 4; ++k) {
    DroppedBoxes d(solver, 1.5, k * 1e-7);
    const std::string what = std::string(to_string(solver)) + " raised " + std::to_string(k) + "e-7 m";
    EXPECT_GT(d.touching, 0) << what;  // the premise: they lean on each other
    d.expect_asleep_and_put(what);
  }
}

// A column of the issue's 1000 dropped boxes (falling_boxes: ten unit cubes, mu 0.5, 1.5 m
// apart from 2 m up, landing one on another) is all asleep within 5 s under every solver,
// standing where it was dropped. Dropped straight, nothing pushes a box sideways, and each
// lands within a few millimetres of under where it fell from (largest at the end: soft step
// 1.4 mm, sequential impulses 0.25, XPBD 0.007, TGS 11). Under TGS the landing's impulse was
// carried whole to the next substep (now capped as the soft step's: contact_wide.h, pass()), which
// knocked the boxes sideways by up to 0.32 m; the zigzag column then rocked on its edges,
// its top at up to 0.6 m/s, for as long as it was stepped (never asleep in 15 s), and so did
// all 1000 boxes of bench_rigid's fall1000-sleep. Now TGS's column is asleep after 1.72 s (2.03 s
// with its carry capped at 1.5 times, before kCarryGrowthTgs)
// (soft step 1.73, sequential impulses 1.97, XPBD 1.83).
TEST(RigidSleep, ADroppedColumnOfTenFallsAsleepStandingUnderEverySolver) {
  for (const auto solver : kAll) {
    RigidBodySystem s(with(solver));
    pba::rigid_scenes::ground(s, 0.5);
    std::vector<pba::RigidBodyId> boxes;
    for (int i = 0; i < 10; ++i) boxes.push_back(pba::rigid_scenes::box(s, {0, 2.0 + 1.5 * i, 0}, Vec3(0.5), 0.5));
    int steps = 0;
    while (s.awake_count() > 0 && steps < 300) s.step(1.0 / 60, kGravity), ++steps;
    EXPECT_EQ(s.awake_count(), 0u) << to_string(solver) << " after " << steps / 60.0 << " s";
    for (int i = 0; i < 10; ++i) {
      const Vec3 c = s.center_of_mass(boxes[i]);
      EXPECT_LT(std::hypot(c.x, c.z), 0.05) << to_string(solver) << " box " << i;
      EXPECT_NEAR(c.y, 0.5 + i, 0.05) << to_string(solver) << " box " << i;  // standing, one on another
    }
  }
}

// The rest test looks at how far a body moved over the rest window, not at its speed of the
// moment: a steady motion is held to the tolerances exactly (a free body at 0.9 times the
// linear or angular tolerance falls asleep after time_to_sleep, one at 1.1 times never does).
TEST(RigidSleep, SteadyMotionIsHeldToTheTolerances) {
  const pba::ContactSettings c{};
  for (const double f : {0.9, 1.1})
    for (const bool turning : {false, true}) {
      RigidBodySystem s;
      const Vec3 v = turning ? Vec3(0) : Vec3(f * c.sleep_linear, 0, 0);
      const Vec3 w = turning ? Vec3(0, f * c.sleep_angular, 0) : Vec3(0);
      const auto b = s.create({.linear_velocity = v, .angular_velocity = w, .shapes = {{.shape = ColliderShape::sphere(0.5)}}});
      int steps = 0;
      while (s.awake(b) && steps < 600) s.step(1.0 / 60, Vec3(0)), ++steps;
      if (f < 1) {
        EXPECT_FALSE(s.awake(b)) << f << (turning ? " turning" : " moving");
        // the window's time and a step
        EXPECT_LE(steps / 60.0, c.time_to_sleep + 2.0 / 60) << f << (turning ? " turning" : " moving");
      } else {
        EXPECT_TRUE(s.awake(b)) << f << (turning ? " turning" : " moving");
      }
    }
}

// Far from the origin a step's motion is lost in the position's rounding (at y = 1e17 m the
// doubles are 16 m apart): a ball falling there stayed put, passed the rest window's test and
// fell asleep mid-air after time_to_sleep. Where the positions cannot show a step's motion at
// the linear tolerance, the body must also be slower than the tolerances to rest: the ball
// falls on, awake, with its speed growing, while one at rest or gliding slower than the
// tolerance out there still sleeps.
TEST(RigidSleep, ABodyFallingFarOutWherePositionsCannotShowItsMotionStaysAwake) {
  const pba::ContactSettings c{};
  for (const double y : {1e13, 1e17, -1e17}) {
    RigidBodySystem s;
    const auto falling = s.create({.pose = {{0, y, 0}}, .shapes = {{.shape = ColliderShape::sphere(0.5)}}});
    const auto resting = s.create({.pose = {{10, y, 0}}, .shapes = {{.shape = ColliderShape::sphere(0.5)}}, .gravity_scale = 0});
    const auto gliding = s.create({.pose = {{20, y, 0}}, .linear_velocity = {0.5 * c.sleep_linear, 0, 0},
                                   .shapes = {{.shape = ColliderShape::sphere(0.5)}}, .gravity_scale = 0});
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
    EXPECT_TRUE(s.awake(falling)) << y;
    EXPECT_NEAR(s.linear_velocity(falling).y, 2 * kGravity.y, 1e-9) << y;
    EXPECT_FALSE(s.awake(resting)) << y;
    EXPECT_FALSE(s.awake(gliding)) << y;
  }
}

// The same far out for a body that moves a substep at a time (a spinning box coasts through
// the substeps, as a body in contact does): its substep's motion at twice the tolerance,
// 2.1e-4 m at x = 3e12 m, is under half the doubles' spacing there (4.9e-4 m) and rounds
// away, though a whole step's would not. It stays awake; at rest out there it sleeps.
TEST(RigidSleep, ABodyCoastingFarOutWhereASubstepsMotionRoundsAwayStaysAwake) {
  const pba::ContactSettings c{};
  RigidBodySystem s;
  const auto shape = ColliderShape::box({0.5, 0.3, 0.2});
  const auto coasting = s.create({.pose = {{3e12, 0, 0}}, .linear_velocity = {2 * c.sleep_linear, 0, 0},
                                  .angular_velocity = {0, 0.5 * c.sleep_angular, 0}, .shapes = {{.shape = shape}},
                                  .gravity_scale = 0});
  const auto resting = s.create({.pose = {{3e12, 10, 0}}, .shapes = {{.shape = shape}}, .gravity_scale = 0});
  for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
  EXPECT_TRUE(s.awake(coasting));
  EXPECT_FALSE(s.awake(resting));
}

// A force, an impulse, a new velocity or pose, or an awake body landing on it wakes a
// sleeping body and its island (the boxes it rests on), and nothing else, under every solver
// (until 2026-12-07 the soft step's only: XPBD's, whose velocities come from its position
// corrections, is now checked to wake and fall asleep again the same way).
TEST(RigidSleep, ForcesImpulsesPosesAndContactsWakeIslands) {
  for (const auto solver : kAll) {
    SCOPED_TRACE(std::string(to_string(solver)));
    RigidBodySystem s(with(solver));
    pba::rigid_scenes::ground(s, 0.5);
    auto low = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
    auto high = pba::rigid_scenes::box(s, {0, 1.5, 0}, Vec3(0.5));
    auto apart = pba::rigid_scenes::box(s, {5, 0.5, 0}, Vec3(0.5));
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
    ASSERT_FALSE(s.awake(low) || s.awake(high) || s.awake(apart));
    // a force on the top box wakes the stack it stands on, not the box apart
    s.apply_force(high, {0, 1, 0});
    EXPECT_TRUE(s.awake(high));
    EXPECT_TRUE(s.awake(low));
    EXPECT_FALSE(s.awake(apart));
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
    ASSERT_FALSE(s.awake(high));
    s.apply_impulse(apart, {0, 0, 1}, {5, 1, 0});
    EXPECT_TRUE(s.awake(apart));
    EXPECT_FALSE(s.awake(low));
    for (int i = 0; i < 180; ++i) s.step(1.0 / 60, kGravity);
    ASSERT_FALSE(s.awake(apart));
    s.set_velocity(low, {0, 0, 0}, {0, 0.1, 0});
    EXPECT_TRUE(s.awake(high));
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
    // a ball dropped on the sleeping box wakes it when they touch
    ASSERT_FALSE(s.awake(apart));
    auto ball = s.create({.pose = {{5, 3, 0}}, .shapes = {{.shape = ColliderShape::sphere(0.2)}}});
    bool woke = false;
    for (int i = 0; i < 60 && !woke; ++i) s.step(1.0 / 60, kGravity), woke = s.awake(apart);
    EXPECT_TRUE(woke);
    EXPECT_GT(s.center_of_mass(ball).y, 1.0 + 0.15);  // it landed on the box, not in it
  }
  // with sleeping off nothing sleeps
  RigidBodySystem t({.contacts = {.sleep = false}});
  pba::rigid_scenes::vertical_stack(t, 3);
  for (int i = 0; i < 120; ++i) t.step(1.0 / 60, kGravity);
  EXPECT_EQ(t.awake_count(), 3u);
}

// Turning sleeping off wakes the sleepers, as Box2D's b2World_EnableSleeping(false) does:
// nothing else would ever wake a pile asleep far from anything moving, and it stayed frozen
// with `sleep` false (in the air, with the gravity turned sideways). Moving a static body
// wakes what rests on it: the ground lowered 0.3 m under a sleeping stack left it floating.
TEST(RigidSleep, TurningSleepingOffAndMovingAStaticBodyWakeTheSleepers) {
  RigidBodySystem s;
  const auto ground = pba::rigid_scenes::ground(s, 0.5);
  auto low = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
  auto high = pba::rigid_scenes::box(s, {0, 1.5, 0}, Vec3(0.5));
  for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
  ASSERT_FALSE(s.awake(low) || s.awake(high));
  // the ground lowered: the stack wakes and falls 0.3 m onto it (at rest within 1 mm)
  s.set_pose(ground, {{0, -0.3, 0}});
  EXPECT_TRUE(s.awake(low) && s.awake(high));
  for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
  EXPECT_NEAR(s.center_of_mass(high).y, 1.2, 1e-3);
  ASSERT_FALSE(s.awake(low) || s.awake(high));
  // sleeping off: the next step wakes them, and under gravity along x (nothing presses them
  // on the ground, so no friction holds them) they fall sideways at g (within 1% in this
  // first step, where the resting contacts' carried impulses still act: measured 0.08%)
  s.settings().sleep = false;
  s.step(1.0 / 60, {kG, 0, 0});
  EXPECT_EQ(s.awake_count(), 2u);
  EXPECT_NEAR(s.linear_velocity(high).x, kG / 60, 0.01 * kG / 60);
}

// A change of gravity wakes the sleepers it acts on: a two-box stack asleep on the ground
// under g down, with gravity turned along +x, falls sideways at g (nothing presses the boxes
// on the ground, so no friction holds them: from the second step on, once the carried
// impulses of the resting contacts, which let friction act in the first, are gone, each box
// gains g dt a step, within 1%) instead of hanging asleep under the old gravity. A sleeping
// body with gravity_scale 0 feels no change and sleeps on. Gravity held constant wakes nobody.
TEST(RigidSleep, AChangeOfGravityWakesTheSleepers) {
  for (const auto solver : kAll) {
    SCOPED_TRACE(std::string(pba::to_string(solver)));
    RigidBodySystem s(with(solver));
    pba::rigid_scenes::ground(s, 0.5);
    auto low = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
    auto high = pba::rigid_scenes::box(s, {0, 1.5, 0}, Vec3(0.5));
    auto floating = s.create({.pose = {{5, 3, 0}}, .shapes = {box_shape(Vec3(0.5))}, .gravity_scale = 0});
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
    ASSERT_FALSE(s.awake(low) || s.awake(high) || s.awake(floating));
    s.step(1.0 / 60, kGravity);
    ASSERT_FALSE(s.awake(low) || s.awake(high));
    s.step(1.0 / 60, {kG, 0, 0});
    EXPECT_TRUE(s.awake(low) && s.awake(high));
    EXPECT_FALSE(s.awake(floating));
    const double high1 = s.linear_velocity(high).x, low1 = s.linear_velocity(low).x;
    for (int i = 0; i < 30; ++i) s.step(1.0 / 60, {kG, 0, 0});
    EXPECT_NEAR(s.linear_velocity(high).x - high1, kG / 2, 0.01 * kG / 2);
    EXPECT_NEAR(s.linear_velocity(low).x - low1, kG / 2, 0.01 * kG / 2);
  }
}

// A kinematic body moved by set_pose (a teleport, no velocity) wakes the sleepers its shapes
// reach before or after the move, as a static body does: a box asleep on a kinematic platform
// lowered 0.3 m falls onto it (its centre 0.3 m lower, within 1 mm, once at rest), and a box
// asleep on the ground is pushed ahead of a kinematic wall stepped into it 2 cm a step
// (1.2 m/s, under push_out_speed) instead of sleeping on with the wall through it.
TEST(RigidSleep, AKinematicBodyMovedBySetPoseWakesWhatItReaches) {
  for (const auto solver : kAll) {
    SCOPED_TRACE(std::string(pba::to_string(solver)));
    RigidBodySystem s(with(solver));
    auto platform = s.create({.type = BodyType::Kinematic, .pose = {{0, -0.1, 0}}, .shapes = {box_shape({2, 0.1, 2})}});
    auto box = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
    ASSERT_FALSE(s.awake(box));
    const double y0 = s.center_of_mass(box).y;
    s.set_pose(platform, {{0, -0.4, 0}});
    EXPECT_TRUE(s.awake(box));
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
    EXPECT_NEAR(s.center_of_mass(box).y, y0 - 0.3, 1e-3);

    RigidBodySystem w(with(solver));
    pba::rigid_scenes::ground(w, 0.5);
    auto wall = w.create({.type = BodyType::Kinematic, .pose = {{-2, 1, 0}}, .shapes = {box_shape({0.1, 1, 1})}});
    auto pushed = pba::rigid_scenes::box(w, {0, 0.5, 0}, Vec3(0.5));
    for (int i = 0; i < 120; ++i) w.step(1.0 / 60, kGravity);
    ASSERT_FALSE(w.awake(pushed));
    double worst = 0;  // the box's back face behind the wall's face, most (m)
    for (int i = 1; i <= 150; ++i) {
      const double face = -2 + 0.02 * i + 0.1;  // the wall's leading face (m)
      w.set_pose(wall, {{face - 0.1, 1, 0}});
      w.step(1.0 / 60, kGravity);
      worst = std::max(worst, face - (w.center_of_mass(pushed).x - 0.5));
    }
    // the wall's face moved 3 m, 1.6 m of them pushing the box: the box is ahead of it, behind
    // by at most the overlap at which the push-out keeps pace, largest for sequential impulses,
    // whose Baumgarte factor removes 0.2 of it a step: 0.02 / 0.2 + the 5 mm slop = 0.105 m
    // (measured 0.085; soft step 0.044, TGS 0.009, XPBD 0). Before, the box slept at x = 0.
    EXPECT_LT(worst, 0.02 / 0.2 + 0.005);
  }
}

// A force wakes a sleeping body and acts on it at once: a box asleep on the ground pulled up
// by three times its weight leaves it, and once off the ground it gains (F / m - g) dt per
// step exactly (no contact left to act; the closed form of the velocity under constant
// acceleration, which symplectic Euler reproduces).
TEST(RigidSleep, AForceWakesASleepingBodyAndActs) {
  RigidBodySystem s;
  pba::rigid_scenes::ground(s, 0.5);
  const auto box = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
  for (int i = 0; i < 120 && s.awake(box); ++i) s.step(1.0 / 60, kGravity);
  ASSERT_FALSE(s.awake(box));
  const double m = s.mass(box), g = -kGravity.y, dt = 1.0 / 60;
  const double y0 = s.center_of_mass(box).y;
  s.apply_force(box, {0, 3 * m * g, 0});
  EXPECT_TRUE(s.awake(box));
  s.step(dt, kGravity);
  for (int i = 0; i < 9; ++i) s.apply_force(box, {0, 3 * m * g, 0}), s.step(dt, kGravity);
  EXPECT_GT(s.center_of_mass(box).y, y0 + 0.01);
  const double v10 = s.linear_velocity(box).y;
  for (int i = 0; i < 20; ++i) s.apply_force(box, {0, 3 * m * g, 0}), s.step(dt, kGravity);
  EXPECT_NEAR(s.linear_velocity(box).y - v10, 2 * g * 20 * dt, 1e-9 * g);
}

// A dynamic body teleported (set_pose) wakes at the next step the sleepers it touches (a
// contact closer than the speculative distance begins, as Box2D v3 wakes them), not those
// whose bounds it only reaches: a ball put by a sleeping box's top edge, 6.6 cm off it (its
// bounds overlap the box's), leaves it asleep; put 7.6 cm into it, it wakes the box (and not
// a box apart). Until 2026-12-07 any overlap of the bounds woke the sleeper.
TEST(RigidSleep, ATeleportedBodyWakesOnlyTheSleepersItTouches) {
  RigidBodySystem s;
  pba::rigid_scenes::ground(s, 0.5);
  const auto box = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
  const auto apart = pba::rigid_scenes::box(s, {5, 0.5, 0}, Vec3(0.5));
  // weightless, so it stays where it is put
  const auto ball = s.create({.pose = {{20, 5, 0}}, .shapes = {{.shape = ColliderShape::sphere(0.5)}}, .gravity_scale = 0});
  for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
  ASSERT_FALSE(s.awake(box) || s.awake(apart));
  const Vec3 edge = s.center_of_mass(box) + Vec3(0.5, 0.5, 0);  // the top edge nearest the ball
  // the ball's centre sqrt(0.32) = 0.566 m out from the edge: its surface 6.6 cm off it
  s.set_pose(ball, {edge + Vec3(0.4, 0.4, 0)});
  ASSERT_GT(std::sqrt(0.32) - 0.5, 3 * s.settings().speculative_distance);
  ASSERT_TRUE(s.shape_bounds(ball)[0].overlaps(s.shape_bounds(box)[0]));  // the premise
  for (int i = 0; i < 10; ++i) s.step(1.0 / 60, kGravity);
  EXPECT_FALSE(s.awake(box));
  EXPECT_EQ(s.linear_velocity(ball), Vec3(0));  // nothing touched it either
  // into the box: 7.6 cm deep at the edge
  s.set_pose(ball, {edge + Vec3(0.3, 0.3, 0)});
  EXPECT_FALSE(s.awake(box));  // at the next step's pairs
  s.step(1.0 / 60, kGravity);
  EXPECT_TRUE(s.awake(box));
  EXPECT_FALSE(s.awake(apart));
}

// A body moved away by set_pose wakes what rested on it, in its island or not. A box that
// came to rest on a sleeping box (a slow awake body rests on a sleeper as on a static body,
// so each slept in its own island) hung in the air when the box under it was teleported
// away; now it wakes and falls to the ground (its centre 1 m lower, within the contacts' sag).
// So does a box asleep on a kinematic platform teleported sideways (kinematic and static
// bodies join no island).
TEST(RigidSleep, ABodyMovedAwayWakesWhatRestedOnItInAnyIsland) {
  RigidBodySystem s;
  pba::rigid_scenes::ground(s, 0.5);
  const auto low = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
  for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
  ASSERT_FALSE(s.awake(low));
  const auto high = pba::rigid_scenes::box(s, s.center_of_mass(low) + Vec3(0, 1, 0), Vec3(0.5));
  for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
  ASSERT_FALSE(s.awake(low) || s.awake(high));  // the premise: both asleep, the top one on the low one
  const double y_high = s.center_of_mass(high).y;
  ASSERT_NEAR(y_high, 1.5, 1e-3);
  s.set_pose(low, {{5, 0.5, 0}});
  EXPECT_TRUE(s.awake(high));
  for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity);
  EXPECT_NEAR(s.center_of_mass(high).y, y_high - 1, 1e-3);

  RigidBodySystem k;
  const auto platform = k.create({.type = BodyType::Kinematic, .pose = {{0, -0.1, 0}}, .shapes = {box_shape({2, 0.1, 2})}});
  const auto rider = pba::rigid_scenes::box(k, {0, 0.5, 0}, Vec3(0.5));
  for (int i = 0; i < 120; ++i) k.step(1.0 / 60, kGravity);
  ASSERT_FALSE(k.awake(rider));
  k.set_pose(platform, {{10, -0.1, 0}});
  EXPECT_TRUE(k.awake(rider));
  for (int i = 0; i < 30; ++i) k.step(1.0 / 60, kGravity);
  EXPECT_NEAR(k.linear_velocity(rider).y, kGravity.y * 0.5, 1e-9);  // in free fall: g t
}

// With speculative_distance 0 (valid) a body moved from under a sleeper still wakes it: the
// touch test's margin was the speculative distance alone, and a body rests at a gap of
// exactly 0 (XPBD) or 1.4e-11 m (sequential impulses), not closer than 0, so a ball asleep on
// a box teleported away, or on a kinematic platform moved sideways, hung in the air. The
// margin is now the speculative distance or the linear slop, whichever is larger, plus 1 um.
TEST(RigidSleep, ABodyMovedAwayWakesWhatRestedOnItAtSpeculativeDistanceZero) {
  const double dt = 1.0 / 60;
  for (const auto solver : kAll) {
    SCOPED_TRACE(std::string(pba::to_string(solver)));
    for (const double slop : {0.0, 0.005}) {
      SCOPED_TRACE(slop);
      pba::RigidSystemDef def = with(solver);
      def.contacts.speculative_distance = 0, def.contacts.linear_slop = slop;
      RigidBodySystem s(def);
      pba::rigid_scenes::ground(s, 0.5);
      const auto box = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
      for (int i = 0; i < 600 && s.awake_count() > 0; ++i) s.step(dt, kGravity);
      const auto ball = s.create({.pose = {s.center_of_mass(box) + Vec3(0, 0.8, 0)}, .shapes = {{.shape = ColliderShape::sphere(0.3)}}});
      for (int i = 0; i < 600 && s.awake_count() > 0; ++i) s.step(dt, kGravity);
      ASSERT_FALSE(s.awake(box) || s.awake(ball));  // the premise: the ball asleep on the box
      s.set_pose(box, {{5, 0.5, 0}});
      EXPECT_TRUE(s.awake(ball));
      for (int i = 0; i < 120; ++i) s.step(dt, kGravity);
      EXPECT_NEAR(s.center_of_mass(ball).y, 0.3, 0.01);  // on the ground, within the sag

      RigidBodySystem k(def);
      const auto platform = k.create({.type = BodyType::Kinematic, .pose = {{0, -0.1, 0}}, .shapes = {box_shape({2, 0.1, 2})}});
      const auto rider = k.create({.pose = {{0, 0.3, 0}}, .shapes = {{.shape = ColliderShape::sphere(0.3)}}});
      for (int i = 0; i < 600 && k.awake(rider); ++i) k.step(dt, kGravity);
      ASSERT_FALSE(k.awake(rider));
      k.set_pose(platform, {{10, -0.1, 0}});
      EXPECT_TRUE(k.awake(rider));
    }
  }
}

// A chain of sleepers each in its own island (C came to rest on sleeping B, B on sleeping A)
// wakes up the chain when A is teleported away: B wakes at once, and each woken body wakes
// what it touches at the next step. Before, C waited for B to move faster than sleep_linear,
// so with sleep_linear 1 m/s B fell 1 m below C, asleep in the air. Both come to rest 1 m
// lower (on the ground, within the contacts' sag).
TEST(RigidSleep, AChainOfSleepingIslandsWakesWhenItsBaseIsMovedAway) {
  const double dt = 1.0 / 60;
  RigidBodySystem s({.contacts = {.sleep_linear = 1.0}});
  pba::rigid_scenes::ground(s, 0.5);
  auto settle = [&] {
    for (int i = 0; i < 900 && s.awake_count() > 0; ++i) s.step(dt, kGravity);
  };
  const auto a = pba::rigid_scenes::box(s, {0, 0.5, 0}, Vec3(0.5));
  settle();
  const auto b = pba::rigid_scenes::box(s, s.center_of_mass(a) + Vec3(0, 1, 0), Vec3(0.5));
  settle();
  const auto c = pba::rigid_scenes::box(s, s.center_of_mass(b) + Vec3(0, 1, 0), Vec3(0.5));
  settle();
  ASSERT_FALSE(s.awake(a) || s.awake(b) || s.awake(c));  // the premise
  const double yb = s.center_of_mass(b).y, yc = s.center_of_mass(c).y;
  ASSERT_NEAR(yc, 2.5, 1e-3);
  s.set_pose(a, {{5, 0.5, 0}});
  EXPECT_TRUE(s.awake(b));
  s.step(dt, kGravity);
  EXPECT_TRUE(s.awake(c));  // one island a step
  for (int i = 0; i < 180; ++i) s.step(dt, kGravity);
  EXPECT_NEAR(s.center_of_mass(b).y, yb - 1, 1e-3);
  EXPECT_NEAR(s.center_of_mass(c).y, yc - 1, 2e-3);
}

// A kinematic body teleported by set_pose wakes the sleepers its bounds reach before the move
// and those they reach after it, not every sleeper in the box spanning both poses: a platform
// jumped diagonally across a row of sleeping boxes (each its own island, 2 m apart) woke the
// whole row; now only the box by its old pose and the box by its new one wake.
TEST(RigidSleep, AKinematicTeleportWakesOnlyWhatItReachesAtEitherEnd) {
  RigidBodySystem s;
  pba::rigid_scenes::ground(s, 0.5);
  std::vector<pba::RigidBodyId> row;
  for (int i = -5; i <= 5; ++i) row.push_back(pba::rigid_scenes::box(s, {2.0 * i, 0.5, 0}, Vec3(0.5)));
  const auto by_start = pba::rigid_scenes::box(s, {-20, 0.5, -8.6}, Vec3(0.5));
  const auto by_end = pba::rigid_scenes::box(s, {20, 0.5, 8.6}, Vec3(0.5));
  // a wall by by_start's +z face, 1 cm off it (within the speculative distance)
  const auto wall = s.create({.type = BodyType::Kinematic, .pose = {{-20, 1, -10}}, .shapes = {box_shape({1, 1, 0.89})}});
  for (int i = 0; i < 300; ++i) s.step(1.0 / 60, kGravity);
  for (const auto id : row) ASSERT_FALSE(s.awake(id));
  ASSERT_FALSE(s.awake(by_start) || s.awake(by_end));
  s.set_pose(wall, {{20, 1, 10}});
  EXPECT_TRUE(s.awake(by_start));
  EXPECT_TRUE(s.awake(by_end));
  for (const auto id : row) EXPECT_FALSE(s.awake(id));
}

// A body pushed by a force or torque in a step does not rest in it (pba's own rule: a force
// means the caller is moving it). With time_to_sleep 0 and no gravity on the body (so
// its rest window is the step), a box pushed from rest by a steady force moved within the
// window each step, fell asleep at the step's end with its velocity zeroed, and the next
// force woke it from rest again: it never gathered speed. Now it gains F / m dt a step, the
// closed form of constant acceleration (v = a t, which symplectic Euler gives exactly), and
// a ball under a steady torque tau / I dt.
TEST(RigidSleep, ASteadyForceFromRestIsNotLostToSleep) {
  RigidBodySystem s({.contacts = {.time_to_sleep = 0}});
  const auto box = s.create({.shapes = {box_shape(Vec3(0.5))}, .gravity_scale = 0});
  const auto ball = s.create({.pose = {{5, 0, 0}}, .shapes = {{.shape = ColliderShape::sphere(0.5)}}, .gravity_scale = 0});
  const double a = 1, alpha = 1, dt = 1.0 / 60;  // m/s^2, rad/s^2, s
  const double inertia = s.world_inertia(ball)[1][1];
  for (int i = 0; i < 60; ++i) {
    s.apply_force(box, {s.mass(box) * a, 0, 0});
    s.apply_torque(ball, {0, inertia * alpha, 0});
    s.step(dt, kGravity);
  }
  EXPECT_TRUE(s.awake(box) && s.awake(ball));
  EXPECT_NEAR(s.linear_velocity(box).x, a * 60 * dt, 1e-12);
  EXPECT_NEAR(s.angular_velocity(ball).y, alpha * 60 * dt, 1e-12);
  // left alone, they coast at well above the tolerances and stay awake
  s.step(dt, kGravity);
  EXPECT_TRUE(s.awake(box) && s.awake(ball));
}

// A body speeding up is not at rest (RigidBodySystem::update_sleep). A 0.2 m cube on a plane
// half a degree steeper than atan(mu) slides from rest at a = g (sin theta - mu cos theta),
// 0.087 m/s^2 at mu 0.2 and 0.11 at 0.8: it moved a t^2 / 2 = 1.2 cm over the 0.5 s window,
// within the window's reach (sleep_linear x time_to_sleep, 2.5 cm), fell asleep at 0.54 s and
// never woke (at 3 s it had covered 3.2-3.8% of a t^2 / 2) under every solver. Now it never
// falls asleep, so with sleeping on it takes the path it takes with sleeping off to the bit,
// and that path is the closed form's: symplectic Euler's velocity is exact under a constant
// force once the contact has settled (0.5 s; the soft step's and TGS's first step leaves it
// 1.6e-3-8.1e-3 m/s ahead, a constant), so the acceleration from the velocities at 0.5 and
// 3 s is a to 1e-3 (the incline tests above; measured: 5e-6), and the distance between them
// is v(0.5) T + a T^2 / 2 plus the integrator's lead a T h / 2, h the step or the substep
// (at most dt), to that 1e-3 of a T^2 / 2.
// the cube on a slope `past` (rad) steeper than atan(mu), from rest, sleeping on against
// sleeping off: the same bits every step, awake at 3 s, and the closed form's path from 0.5 s
void expect_slides_as_with_sleeping_off(pba::RigidSolverType solver, double mu, double past) {
  const double dt = 1.0 / 60, T = 2.5;
  const double theta = std::atan(mu) + past;
  const double a = kG * (std::sin(theta) - mu * std::cos(theta));
  Incline on(theta, mu, solver, Vec3(0.1)), off(theta, mu, solver, Vec3(0.1));
  off.s.settings().sleep = false;
  const std::string what = std::string(to_string(solver)) + " mu " + std::to_string(mu) + " " +
                           std::to_string(past * 180 / pba::kPi) + " degrees past";
  auto speed = [&] { return glm::dot(on.s.linear_velocity(on.box), on.down); };
  double v0 = 0, x0 = 0;
  for (int i = 1; i <= 180; ++i) {
    on.s.step(dt, kGravity), off.s.step(dt, kGravity);
    ASSERT_EQ(on.s.hash(), off.s.hash()) << what << " at step " << i << (on.s.awake(on.box) ? "" : ", asleep");
    if (i == 30) v0 = speed(), x0 = on.along();
  }
  EXPECT_TRUE(on.s.awake(on.box)) << what;
  EXPECT_NEAR((speed() - v0) / T, a, 1e-3 * a) << what;
  const double free = v0 * T + a * T * T / 2, moved = on.along() - x0;
  EXPECT_GE(moved, free - 1e-3 * a * T * T / 2) << what;
  EXPECT_LE(moved, free + a * T * dt / 2 + 1e-3 * a * T * T / 2) << what;
}

TEST(RigidSleep, ABoxSlidingSlowlyFromRestDoesNotFallAsleep) {
  for (const auto solver : kAll)
    for (const double mu : {0.2, 0.8}) expect_slides_as_with_sleeping_off(solver, mu, deg(0.5));
}

// Slower still: the speeding-up test sees an acceleration only above sleep_linear / (4 W),
// 0.025 m/s^2 at the defaults, and the same cube 0.1 degrees past atan(mu) (a = 0.018 m/s^2
// at mu 0.2, 0.022 at 0.8) still fell asleep at 0.6 s after 3 mm and never woke, 0.05 degrees
// past (a = 0.0087, 0.011) too. Its manifold's friction sits at its Coulomb limit (it
// slides), which keeps it awake at any acceleration: with sleeping on it takes the path it
// takes with sleeping off to the bit, the closed form's as above; and 2 degrees past
// (a = 0.35, 0.44 m/s^2), where it slid before too, the same. The acceleration to 1e-3 of a:
// from 0.5 to 3 s the velocity changes by a T, 0.022 m/s at the slowest. (At 0.02 degrees the
// soft step's cube at mu 0.8 runs 1e-4 m past the distance's bound with sleeping off as well:
// its start-up slide's 7.8 mm/s, 1.8 times a T, is not yet steady at 0.5 s; not the sleep's)
TEST(RigidSleep, ABoxSlidingAtItsFrictionLimitDoesNotFallAsleep) {
  for (const auto solver : kAll)
    for (const double mu : {0.2, 0.8})
      for (const double past : {0.05, 0.1, 2.0}) expect_slides_as_with_sleeping_off(solver, mu, deg(past));
}

// And held by static friction it still falls asleep: 1 degree under atan(mu) its manifold's
// friction needs tan(theta) / mu of the limit (0.91 at mu 0.2, 0.96 at 0.8), not all of it,
// so the cube set down at rest (the soft step's and TGS's start-up slide at mu 0.8 reaches
// the limit for two steps, then stops) falls asleep once its window is full, within a second,
// and stays where it stopped (it moved less than 0.2 mm: measured 0-0.17 mm)
TEST(RigidSleep, ABoxHeldByStaticFrictionOnASlopeFallsAsleep) {
  for (const auto solver : kAll)
  for (const double mu : {0.2, 0.8}) {
    const double theta = std::atan(mu) - deg(1);
    Incline in(theta, mu, solver, Vec3(0.1));
    const std::string what = std::string(to_string(solver)) + " mu " + std::to_string(mu);
    const double x0 = in.along();
    int i = 0;
    while (in.s.awake(in.box) && i < 60) in.s.step(1.0 / 60, kGravity), ++i;
    EXPECT_FALSE(in.s.awake(in.box)) << what;
    for (int k = 0; k < 120; ++k) in.s.step(1.0 / 60, kGravity);
    EXPECT_FALSE(in.s.awake(in.box)) << what;
    EXPECT_LT(std::abs(in.along() - x0), 2e-4) << what;
  }
}

// Creep is rest, though friction sits at its limit (RigidBodySystem::update_sleep): the rule
// above kept a manifold's bodies awake when one was faster than its window began by more than
// the rounding of a step's fall (1.6e-7 m/s), and soft-step square pyramids of 6 and 10
// levels, set down at rest, slept at 5.35 and 5.48 s (sequential impulses' 10 levels at 0.92
// s), where before that rule they slept at 0.52 s, one window (time_to_sleep, 0.5 s) and a
// step; with sleeping off they move 1 mm in all after it. The gain must now show at least
// sleep_linear / (64 W) of acceleration (1.6e-3 m/s^2). So each sleeps within two windows
// (1 s: one in which the pile settles, one in which it rests), and sleeps on. XPBD's pyramid
// of 6 levels did not sleep in 20 s before the rule either (91 of its boxes awake): not
// this rule's, left out.
TEST(RigidSleep, ACreepingPyramidFallsAsleepWithinTwoWindows) {
  const double dt = 1.0 / 60;
  const long steps = std::lround(2 * ContactSettings{}.time_to_sleep / dt);  // two windows
  for (const auto solver : {pba::RigidSolverType::SoftStep, pba::RigidSolverType::SequentialImpulse,
                            pba::RigidSolverType::Tgs})
    for (const int levels : {6, 10}) {
      RigidBodySystem s(with(solver));
      const auto boxes = pba::rigid_scenes::square_pyramid(s, levels);
      const std::string what = std::string(to_string(solver)) + " " + std::to_string(levels) + " levels";
      auto awake = [&] {
        return std::count_if(boxes.begin(), boxes.end(), [&](pba::RigidBodyId b) { return s.awake(b); });
      };
      long i = 0;
      while (awake() > 0 && i < steps) s.step(dt, kGravity), ++i;
      EXPECT_EQ(awake(), 0) << what << " at " << i * dt << " s";
      for (int k = 0; k < 120; ++k) s.step(dt, kGravity);
      EXPECT_EQ(awake(), 0) << what << " 2 s later";
    }
}

// The same for a box set down at rest on a slope at exactly atan(mu): its friction sits at the
// limit and, with sleeping off, it does not speed up: it coasts, slowing, at the speed its first
// step gave it (at mu 0.5: 4.8 mm/s under the soft step, 0.44 mm/s under sequential
// impulses). Under the rule's first floor it slept at 5.7 s (soft step) and 5.3 s (TGS) and
// never under sequential impulses (0.52 s before the rule). Now it sleeps within two windows
// under every solver, and sleeps on, within the window's reach (sleep_linear x time_to_sleep,
// 2.5 cm) of where it was set down.
TEST(RigidSleep, ABoxSetDownAtItsFrictionAngleFallsAsleepWithinTwoWindows) {
  const ContactSettings defaults;
  const double dt = 1.0 / 60;
  const long steps = std::lround(2 * defaults.time_to_sleep / dt);  // two windows
  const double reach = defaults.sleep_linear * defaults.time_to_sleep;
  for (const auto solver : kAll)
    for (const double mu : {0.2, 0.5, 0.8}) {
      Incline in(std::atan(mu), mu, solver, Vec3(0.1));
      const std::string what = std::string(to_string(solver)) + " mu " + std::to_string(mu);
      const double x0 = in.along();
      long i = 0;
      while (in.s.awake(in.box) && i < steps) in.s.step(dt, kGravity), ++i;
      EXPECT_FALSE(in.s.awake(in.box)) << what << " at " << i * dt << " s";
      for (int k = 0; k < 120; ++k) in.s.step(dt, kGravity);
      EXPECT_FALSE(in.s.awake(in.box)) << what << " 2 s later";
      EXPECT_LT(std::abs(in.along() - x0), reach) << what;
    }
}

// The same for the turn: a box of width w and height h on a high-friction slope (mu 1.5) a
// quarter and half a degree past its critical angle atan(w / h) tips from rest about its lower
// edge as an inverted pendulum, I phi'' = m g r sin(delta + phi) (r the half diagonal, I =
// 4/3 m r^2 about the edge), turning by delta (cosh(lambda t) - 1) at first, lambda^2 = 3 g / (4 r):
// about 1 degree over the first 0.5 s, within the window's turn (sleep_angular x
// time_to_sleep, 1 degree). XPBD's box with sleeping on still stood at 27.2 degrees after 30 s
// (it tips at 26.6). With sleeping on it takes the path it takes with sleeping off to the bit
// and tips past 45 degrees; the closed form's time to 45 degrees, from the pendulum's energy,
// is 1.63 s at a quarter degree and 1.44 s at a half (the solvers: 1.53-1.85 s and 1.40-1.55 s,
// XPBD the slowest), checked by 3 s as the test of the tipping above (past 45 degrees it lands
// on its side and may rest there).
TEST(RigidSleep, ABoxTippingSlowlyFromRestDoesNotFallAsleep) {
  const double w = 0.5, h = 1.0, critical = std::atan(w / h);
  for (const auto solver : kAll)
  for (const double offset : {deg(0.25), deg(0.5)}) {
    const double theta = critical + offset;
    const Vec3 n{-std::sin(theta), std::cos(theta), 0};
    const std::string what = std::string(to_string(solver)) + " at " + std::to_string(theta * 180 / pba::kPi);
    RigidBodySystem on(with(solver)), off(with(solver));
    off.settings().sleep = false;
    pba::RigidBodyId box;
    for (RigidBodySystem* s : {&on, &off}) {
      ground(*s, 1.5, 0, theta);
      box = s->create({.pose = {0.5 * h * n, glm::angleAxis(theta, Vec3(0, 0, 1))},
                       .shapes = {box_shape({w / 2, h / 2, 0.25}, 1.5)}});
    }
    // (until it is past 45 degrees: it then lands on its side and may rest there)
    auto tilt = [&] { return std::acos(std::clamp(glm::dot(on.pose(box).rotation * Vec3(0, 1, 0), n), -1.0, 1.0)); };
    for (int i = 1; i <= 180 && tilt() <= deg(45); ++i) {
      on.step(1.0 / 60, kGravity), off.step(1.0 / 60, kGravity);
      ASSERT_EQ(on.hash(), off.hash()) << what << " at step " << i << (on.awake(box) ? "" : ", asleep");
    }
    EXPECT_GT(tilt(), deg(45)) << what;
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------
// small bodies

namespace {

// the contact tolerances a body of smallest half size `half` (m) gets at the defaults: the
// linear slop, ContactSettings::linear_slop or a tenth of the half size (src/rigid/contacts.h)
double slop_of(double half) { return std::min(ContactSettings{}.linear_slop, 0.1 * half); }

// the steps a 60 Hz frame takes for a cube of half size `half` (m) under the one-manifold-a-step
// rigid solvers (sequential impulses, TGS): a cube rocks on an edge at about sqrt(g / half)
// rad/s, and a step must turn it by at most 1.2 rad of that (a 2 mm cube at 60 Hz: 1.17; a
// 1 mm one: 1.65, where sequential impulses sank it to 0.17 of its half size and TGS rocked it
// on two edges for ever)
int steps_a_frame(pba::RigidSolverType solver, double half) {
  if (solver == pba::RigidSolverType::SoftStep || solver == pba::RigidSolverType::Xpbd) return 1;
  return static_cast<int>(std::ceil(std::sqrt(kG / half) / (1.2 * 60)));
}

// a cube's tilt (rad): the angle of its axis nearest the vertical from it
double tilt_of(const RigidBodySystem& s, pba::RigidBodyId b) {
  const Quat q = s.pose(b).rotation;
  double up = 0;
  for (const Vec3& e : {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}) up = std::max(up, std::abs((q * e).y));
  return std::acos(std::min(1.0, up));
}

// the lowest of a cube's corners (m), in the world
double lowest_corner(const RigidBodySystem& s, pba::RigidBodyId b, double half) {
  double low = 1e300;
  for (const Vec3& c : box_corners(Vec3(half))) low = std::min(low, pba::apply(s.pose(b), c).y);
  return low;
}

}  // namespace

// Small cubes, 0.5 mm to 5 cm half size, dropped tilted (three orientations), spinning about
// the vertical at 0 and 5 rad/s, from their lowest corner at 0, 5 and 10 cm above the ground (mu
// = 0.5), the defaults, 3 s: each rests on a face. The contacts leave overlap within the
// slop s alone (the rigid passes' Baumgarte, the soft step's position pass), so every corner
// is at most s deep (and one touches) and a face can lean by at most atan(2 s / (2 sqrt(2) half)), one corner
// s deep and the opposite one s up across the face's diagonal (measured: 4.07 degrees under
// sequential impulses for a 2 mm cube, s = 0.1 half); 5% over s for a step's drift. The soft
// step's springs and XPBD hold every corner of a face at the same depth: they lean by no more
// than a sleeping body may still have turned in its rest window (sleep_angular x
// time_to_sleep, 1 degree). Still: at most sleep_angular, and the centre then at most a
// corner's speed at it. Before (main at 72937a9: linear_slop 5 mm and speculative_distance
// 2 cm for every size) a 1 mm cube rested 45.7 degrees over, its centre at 0.44 of its half
// size, and spinning at 5.2 rad/s (the speculative points reached its top face's corners, the
// warm start matched every point with every other within the slop, and the slop let a corner
// sink 5 half sizes). Before the reuse distance was scaled too (pair_reuse: at 1 mm the
// manifold of a 0.5 mm cube was made past its top face) 53 of the 54 0.5 mm cases under the
// soft step, sequential impulses and TGS failed: up to 50 degrees over (soft step; sequential
// impulses 46, TGS 9), flipping between two poses.
TEST(RigidSmallBodies, SmallCubesComeToRestOnAFace) {
  const ContactSettings defaults;
  const double sleep_turn = defaults.sleep_angular * defaults.time_to_sleep;
  const Quat tilts[] = {glm::quat(Vec3(deg(20), deg(10), deg(30))), glm::quat(Vec3(deg(40), deg(0), deg(15))),
                        glm::quat(Vec3(deg(5), deg(60), deg(-25)))};
  for (const auto solver : kAll)
  for (const double half : {0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05})
  for (const Quat& q : tilts)
  for (const double spin : {0.0, 5.0})
  for (const double drop : {0.0, 0.05, 0.1}) {
    RigidBodySystem s(with(solver));
    ground(s, 0.5);
    const auto box = s.create({.pose = {{0, half * std::sqrt(3.0) + drop, 0}, q}, .angular_velocity = {0, spin, 0},
                               .shapes = {box_shape(Vec3(half), 0.5)}});
    const int n = steps_a_frame(solver, half);
    for (int i = 0; i < 180 * n; ++i) s.step(1.0 / 60 / n, kGravity);
    const double slop = 1.05 * slop_of(half), tilt = tilt_of(s, box);
    const bool flat = solver == pba::RigidSolverType::SoftStep || solver == pba::RigidSolverType::Xpbd;
    const std::string what = std::string(to_string(solver)) + " half " + std::to_string(half) + " spin " +
                             std::to_string(spin) + " drop " + std::to_string(drop) + " tilt " +
                             std::to_string(&q - tilts);
    EXPECT_LT(tilt, flat ? sleep_turn : std::atan(slop / (std::sqrt(2.0) * half))) << what;
    const double low = lowest_corner(s, box, half);
    EXPECT_GT(low, -slop) << what;
    EXPECT_LT(low, 0.01 * slop) << what;  // touching
    EXPECT_LE(glm::length(s.angular_velocity(box)), defaults.sleep_angular) << what;
    EXPECT_LE(glm::length(s.linear_velocity(box)), defaults.sleep_angular * std::sqrt(3.0) * half) << what;
  }
}

// A small cube dropped onto one of the same size resting on the ground, 0.3 half sizes off its
// axis, turned and spinning at 2 rad/s, 1 mm to 5 cm half size, 3 s: both rest on a face, the
// upper one on the lower: each within the slop's lean (above), and the upper one's centre
// within two slops under 3 half sizes (each contact overlaps at most the slop).
TEST(RigidSmallBodies, ASmallCubeRestsFlatOnASmallCube) {
  for (const auto solver : kAll)
  for (const double half : {0.001, 0.002, 0.005, 0.01, 0.05}) {
    RigidBodySystem s(with(solver));
    ground(s, 0.5);
    const auto lower = s.create({.pose = {{0, half, 0}}, .shapes = {box_shape(Vec3(half), 0.5)}});
    const auto upper = s.create({.pose = {{0.3 * half, 3.2 * half, 0}, glm::quat(Vec3(deg(8), deg(20), deg(5)))},
                                 .angular_velocity = {0, 2, 0}, .shapes = {box_shape(Vec3(half), 0.5)}});
    const int n = steps_a_frame(solver, half);
    for (int i = 0; i < 180 * n; ++i) s.step(1.0 / 60 / n, kGravity);
    const double slop = 1.05 * slop_of(half), lean = std::atan(slop / (std::sqrt(2.0) * half));
    const std::string what = std::string(to_string(solver)) + " half " + std::to_string(half);
    EXPECT_LT(tilt_of(s, lower), lean) << what;
    EXPECT_LT(tilt_of(s, upper), lean) << what;
    EXPECT_GT(s.center_of_mass(upper).y, 3 * half - 2 * slop) << what;
    EXPECT_LT(s.center_of_mass(upper).y, 3 * half + 0.01 * slop) << what;
  }
}

// The acceleration down a slope of theta (rad) of a ball of radius r (m) set on it at rest,
// both of friction 1, from its velocity at 0.5 s and at 1.5 s, 60 Hz (m/s^2)
// (with `taken`: the substeps of the measured second's steps, -1 if they changed in it)
double rolling_acceleration(const pba::RigidSystemDef& def, double r, double theta, int settle = 30,
                            int* taken = nullptr) {
  RigidBodySystem s(def);
  ground(s, 1.0, 0, theta);
  const Vec3 n{-std::sin(theta), std::cos(theta), 0}, down{-std::cos(theta), -std::sin(theta), 0};
  auto ball = s.create({.pose = {r * n}, .shapes = {{.shape = ColliderShape::sphere(r), .material = {.friction = 1}}}});
  for (int i = 0; i < settle; ++i) s.step(1.0 / 60, kGravity);
  const double v1 = glm::dot(s.linear_velocity(ball), down);
  const int first = s.profile().substeps;
  bool same = true;
  for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kGravity), same = same && s.profile().substeps == first;
  if (taken) *taken = same ? first : -1;
  return glm::dot(s.linear_velocity(ball), down) - v1;
}

// A speculative distance far past the bodies' sizes reaches no further than their pairs can
// use (pair_speculative: 0.4 of the thinner body's smallest half size plus the turn; a plane,
// never the thinner, adds only its turn): a 6 x 6 x 6 grid of cubes of 0.3 m half size 1 m
// apart, 1 m over the ground, has no pair whatever the setting (each cube's box reaches 0.12 m,
// the tree's fat boxes 0.1 m more). Grown by the setting, every body's box made a pair with
// every other one (here 1,976 pairs at 1 m; 1,728 such cubes at 1000 m took 1.3 s a step, not
// one manifold with a point).
TEST(RigidSmallBodies, AHugeSpeculativeDistanceMakesNoPairsPastTheBodiesReach) {
  for (const double reach : {0.02, 1.0, 1e3, 1e300}) {
    pba::RigidSystemDef def;
    def.contacts.speculative_distance = reach;
    RigidBodySystem s(def);
    ground(s, 0.5);
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j)
        for (int k = 0; k < 6; ++k)
          s.create({.pose = {{i * 1.6, 1.3 + k * 1.6, j * 1.6}}, .shapes = {box_shape(Vec3(0.3), 0.5)}});
    for (int step = 0; step < 2; ++step) {
      s.step(1.0 / 60, kGravity);
      EXPECT_EQ(s.profile().shape_pairs, 0u) << "speculative_distance " << reach << " step " << step;
    }
  }
}

// Small balls (1 mm to 5 cm) rolling down a 20 degree slope, mu = 1: TGS and XPBD at (5/7) g
// sin theta to 1e-3, the soft step at the rate of a ball rolling on the point its springs hold
// at rest, delta / 2 deep (delta = g cos theta / w^2, w = 1 / h against the static ground:
// RigidFriction.ASphereRollsAtFiveSeventhsOfGSinTheta): g sin theta / (1 + (2/5) r^2 /
// (r - delta / 2)^2), 0.988 of the closed form for a 1 mm ball, to 1e-3. A ball of 1 mm turns
// up to 7.5 rad a substep by the end (8 substeps of 1/60 s): XPBD's static friction, when it
// took the contact point's displacement over the substep (a cycloid's) for its slip, braked
// it to 0.21 of the closed form (5 mm: 0.82, 1 cm: 0.97; src/rigid/xpbd_rigid.cpp). A rolling
// ball is not at rest, so the soft step at the defaults keeps its 8 substeps all the way (w at
// the substeps taken; RigidSmallBodies.BallsOfAFewMillimetresKeepEightSubstepsAtTheDefaults for
// balls at rest).
TEST(RigidSmallBodies, SmallBallsRollAtTheirClosedForm) {
  const double theta = deg(20);
  for (const auto solver : {pba::RigidSolverType::SoftStep, pba::RigidSolverType::Tgs, pba::RigidSolverType::Xpbd})
  for (const double r : {0.001, 0.002, 0.005, 0.01, 0.05}) {
    const bool soft = solver == pba::RigidSolverType::SoftStep;
    int taken = 0;
    const double a = rolling_acceleration(with(solver), r, theta, 30, &taken);
    ASSERT_EQ(taken, 8) << to_string(solver) << " r = " << r;
    const double w = taken * 60.0, delta = soft ? kG * std::cos(theta) / (w * w) : 0;
    const double expected = kG * std::sin(theta) / (1 + 0.4 * r * r / ((r - delta / 2) * (r - delta / 2)));
    EXPECT_NEAR(a, expected, 1e-3 * expected) << to_string(solver) << " r = " << r;
  }
}

// XPBD's balls over the range of sizes and substeps: 1 mm to 0.5 m, 4 to 32 substeps of 1/60 s
// (up to 15 rad a substep for the 1 mm ball at 4), the same slope: (5/7) g sin theta to 1e-3
// (measured: within 6e-5). Main before 2026-12-04, whose static friction held the contact's
// material point by its displacement (a cycloid's, src/rigid/xpbd_rigid.cpp material_motion),
// rolled the 1 mm ball at 0.067, 0.21 and 0.66 of it at 4, 8 and 32 substeps, the 5 mm one
// at 0.21 at 4.
TEST(RigidSmallBodies, XpbdBallsRollAtTheirClosedFormAtAnySubsteps) {
  const double theta = deg(20);
  for (const int substeps : {4, 8, 32})
  for (const double r : {0.001, 0.005, 0.05, 0.5}) {
    const double a = rolling_acceleration({.contacts = {.solver = pba::RigidSolverType::Xpbd, .substeps = substeps}}, r, theta);
    const double expected = 5.0 / 7 * kG * std::sin(theta);
    EXPECT_NEAR(a, expected, 1e-3 * expected) << substeps << " substeps, r = " << r;
  }
}

// RigidContacts::tree_order's sort (sort_by_high_word): the moved proxies by their leaves'
// parents' node indices, the entries in the low word (bit 31: a leaf to get a new box), planes
// under the key `last` (the node count, above every parent). 70,000 entries, keys below
// 100,000 (17 bits: three 8-bit passes), about 23 entries a key and 300 planes: the order is
// std::stable_sort's by key (entries of one key in their first order), the planes last in
// theirs, the flags carried.
TEST(RigidPairs, TheTreeOrdersSortIsStableOverThreePassesWithThePlanesLast) {
  constexpr std::uint64_t kLast = 100'000;
  std::mt19937_64 rng(11);
  std::vector<std::uint64_t> keys;
  for (std::uint64_t i = 0; i < 70'000; ++i) {
    const std::uint64_t parent = i % 233 == 0 ? kLast : rng() % 3'000 * 33;  // (33 x 2,999 < kLast)
    keys.push_back(parent << 32 | (rng() % 2) << 31 | i);
  }
  std::vector<std::uint64_t> expected = keys, spare;
  std::stable_sort(expected.begin(), expected.end(),
                   [](std::uint64_t a, std::uint64_t b) { return a >> 32 < b >> 32; });
  pba::detail::sort_by_high_word(keys, spare, static_cast<int>(std::bit_width(kLast)));
  EXPECT_EQ(std::bit_width(kLast), 17);
  EXPECT_TRUE(keys == expected);
  const std::size_t planes = 70'000 / 233 + 1;
  for (std::size_t k = 0; k < keys.size(); ++k) EXPECT_EQ(keys[k] >> 32 == kLast, k >= keys.size() - planes) << k;
  for (std::size_t k = keys.size() - planes + 1; k < keys.size(); ++k)
    EXPECT_LT(keys[k - 1] & 0x7fffffffu, keys[k] & 0x7fffffffu);
}

// Two free 0.6 m cubes without gravity, one turned (0-45 degrees by 5 about z, then about x)
// and thrown at the other at 20, 25 and 30 m/s (a third to a half metre a step): the pairs that
// meet edge first. The speculative contact stops every point of its manifold at the surface,
// so a box can only sink into the other where its manifold has no point: with the edges'
// closest points alone (the one point an edge axis gave) the box turned about it and its
// face closed a step's travel deep (the deepest 0.11, 0.14 and 0.28 m, 8, 8 and 18 of the 100
// tilts over 3 cm: docs/rigid-bodies.md). With the faces clipped along the edge axis no pair
// starts a step deeper than 3 cm (a twentieth of the cube, under a tenth of a step's
// travel), and edge-axis manifolds of several points occur (their normal along no face axis).
// The bound is measured, not derived: it parts the one-point manifolds (0.11 m and deeper)
// from the cure's, the deepest now 7.3, 19.5 and 20.9 mm (28.7 mm at 30 m/s with the cube
// centred, no 5 cm offset; 0.12 m at 40 m/s, a step's travel of 0.67 m, beyond the bound's
// range): what remains is the turning within a step about points the manifold holds, which
// grows with the speed, so a change that lets 30 m/s go past 3 cm has lost some of the cure.
TEST(RigidPairs, CubesMeetingEdgeFirstWhileTurningStayWithinAFewCentimetres) {
  const double h = 0.3;
  int several_on_edge_axis = 0;
  for (const double v : {20.0, 25.0, 30.0}) {
    double deepest = 0;
    for (int t1 = 0; t1 <= 45; t1 += 5)
      for (int t2 = 0; t2 <= 45; t2 += 5) {
        RigidBodySystem s;
        const auto a = s.create({.shapes = {{.shape = ColliderShape::box({h, h, h})}}});
        const Quat q = glm::angleAxis(deg(t1), Vec3(0, 0, 1)) * glm::angleAxis(deg(t2), Vec3(1, 0, 0));
        const auto b = s.create({.pose = {{0.05, 2.0, 0.03}, q},
                                 .linear_velocity = {0, -v, 0},
                                 .shapes = {{.shape = ColliderShape::box({h, h, h})}}});
        for (int i = 0; i < 30; ++i) {
          // the manifolds are made at the step's start: the faces' axes then
          const pba::Mat3 axes[2] = {glm::mat3_cast(s.pose(a).rotation), glm::mat3_cast(s.pose(b).rotation)};
          s.step(1.0 / 60, {0, 0, 0});
          for (std::size_t k = 0; k < s.manifold_count(); ++k) {
            const pba::RigidManifoldInfo m = s.manifold(k);
            deepest = std::max(deepest, m.depth);
            if (m.points < 2) continue;
            double along_face = 0;
            for (const pba::Mat3& r : axes)
              for (int c = 0; c < 3; ++c) along_face = std::max(along_face, std::abs(glm::dot(r[c], m.normal)));
            several_on_edge_axis += along_face < 0.999;
          }
        }
      }
    EXPECT_LT(deepest, 0.03) << v << " m/s";
  }
  EXPECT_GT(several_on_edge_axis, 100);
}
