// Rigid bodies, free motion: closed forms for gravity, damping, impulses and forces; the
// torque-free tumbling T-handle against the conservation laws and an RK4 reference; bad
// input by name; determinism.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "pba/rigid.h"
#include "rigid/body_frame.h"  // the identity shortcuts, tested directly
#include "rigid/contacts.h"    // check_finite's call sites, through a seam
#include "rigid/solver.h"      // check_finite's flat test, tested directly

#include "error_of.h"

using pba::BodyType;
using pba::Mat3;
using pba::Quat;
using pba::RigidBodyDef;
using pba::RigidBodySystem;
using pba::RigidMass;
using pba::Vec3;
using pba::test_support::error_of;

namespace {

const Vec3 kG{0, -9.81, 0};
// a shape for bodies whose mass is given: far from everything else, it never collides
const std::vector<pba::RigidShapeDef> kBall{{.shape = pba::ColliderShape::sphere(0.05)}};
const std::vector<pba::RigidShapeDef> kBox{{.shape = pba::ColliderShape::box(Vec3(0.5))}};

// relative difference of two vectors
double rel(const Vec3& a, const Vec3& b) { return glm::length(a - b) / glm::length(b); }

// ---------------------------------------------------------------------------------------
// the body and shape poses' shortcuts by identities

// the bits of a pose, every component's sign of zero included
bool same_bits(const pba::Pose& a, const pba::Pose& b) {
  const double x[7] = {a.position.x, a.position.y, a.position.z, a.rotation.w,
                       a.rotation.x, a.rotation.y, a.rotation.z};
  const double y[7] = {b.position.x, b.position.y, b.position.z, b.rotation.w,
                       b.rotation.x, b.rotation.y, b.rotation.z};
  return std::memcmp(x, y, sizeof x) == 0;
}

// the body frame by its definition: the principal frame (com, q) times the inverse of the
// principal frame's placement in the body frame (com_local, principal)
pba::Pose full_body_frame(const Vec3& com, const Quat& q, const Vec3& com_local, const Quat& principal) {
  const Quat r = glm::normalize(q * glm::conjugate(principal));
  return {com - r * com_local, r};
}

std::string describe(const pba::Pose& p) {
  std::ostringstream o;
  o << std::showpos << p.position.x << ' ' << p.position.y << ' ' << p.position.z << " | " << p.rotation.w << ' '
    << p.rotation.x << ' ' << p.rotation.y << ' ' << p.rotation.z;
  return o.str();
}

TEST(RigidBodyPose, TheIdentityShortcutsGiveTheFullProductsBits) {
  using pba::Pose;
  using pba::detail::body_frame;
  using pba::detail::shape_frame;
  const double z[2] = {0.0, -0.0};
  // the identity, with each sign of zero in its vector part, and a centre at (+-0, +-0, +-0)
  std::vector<Quat> identities;
  std::vector<Vec3> origins;
  for (int m = 0; m < 8; ++m) {
    identities.emplace_back(1, z[m & 1], z[(m >> 1) & 1], z[(m >> 2) & 1]);
    origins.emplace_back(z[m & 1], z[(m >> 1) & 1], z[(m >> 2) & 1]);
  }
  // rotations: random ones (no zero component), turns about one axis with each sign of zero
  // and of the cosine in the other components (a body turning about a world axis), the
  // identity, and a half turn (w = +-0)
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  std::vector<Quat> turns;
  for (int k = 0; k < 40; ++k)
    turns.push_back(glm::normalize(Quat(normal(rng), normal(rng), normal(rng), normal(rng))));
  for (const double c : {0.8, -0.8})
    for (int axis = 0; axis < 3; ++axis)
      for (int m = 0; m < 4; ++m) {
        double v[3];
        for (int i = 0, j = 0; i < 3; ++i) v[i] = i == axis ? 0.6 : z[(m >> j++) & 1];
        turns.emplace_back(c, v[0], v[1], v[2]);
      }
  turns.insert(turns.end(), identities.begin(), identities.end());
  turns.emplace_back(0.0, 0.0, 1.0, 0.0), turns.emplace_back(-0.0, 0.0, -1.0, -0.0);
  // centres of mass: at signed zeros (a body at the origin or on a coordinate plane) and
  // anywhere; offsets of the centre in the body frame: signed zeros and a real one
  std::vector<Vec3> places = origins;
  places.emplace_back(-0.0, 1.5, -0.0), places.emplace_back(3.25, -2, 0.125);
  std::vector<Vec3> offsets = origins;
  offsets.emplace_back(0.1, -0.2, 0.05);
  const Quat tilted = glm::normalize(Quat(0.9, 0.1, -0.3, 0.2));
  std::vector<Quat> principals = identities;
  principals.push_back(tilted);
  // (how many cases each shortcut takes: most, but not all)
  int cases = 0, bodies_short = 0, shapes_short = 0;
  for (const Quat& q : turns)
    for (const Vec3& com : places)
      for (const Vec3& off : offsets)
        for (const Quat& pr : principals) {
          const Pose body = body_frame(com, q, off, pr);
          bodies_short +=
              pr == Quat(1, 0, 0, 0) && pba::detail::positive_zero(off) && pba::detail::exact_times_identity(q);
          ASSERT_TRUE(same_bits(body, full_body_frame(com, q, off, pr)))
              << describe(body) << " against " << describe(full_body_frame(com, q, off, pr));
          // a shape at the body's origin (each signed zero, turned by an identity) and one elsewhere
          for (std::size_t m = 0; m < 10; ++m) {
            const Pose local = m < 8 ? Pose{origins[m], identities[7 - m]}
                                     : Pose{offsets[8], m == 8 ? Quat(1, 0, 0, 0) : tilted};
            shapes_short += pba::detail::positive_zero(local.position) && local.rotation == Quat(1, 0, 0, 0) &&
                            pba::detail::exact_times_identity(body.rotation);
            ASSERT_TRUE(same_bits(shape_frame(body, local), pba::compose(body, local)))
                << describe(shape_frame(body, local)) << " against " << describe(pba::compose(body, local));
            ++cases;
          }
        }
  EXPECT_EQ(cases, 74 * 10 * 9 * 9 * 10);
  EXPECT_EQ(bodies_short, 40 * 10 * 8);  // the random turns, any centre, a +0 offset, an identity
  EXPECT_GT(shapes_short, 0);
  EXPECT_LT(shapes_short, cases / 10);
  // the bit tests read what they say: the identity with either zero, no other quaternion; every
  // component finite and non-zero (a subnormal refused too: it takes the full product); +0 only
  for (const Quat& q : identities) EXPECT_TRUE(pba::detail::is_identity(q));
  for (const Quat& q : {Quat(-1, 0, 0, 0), Quat(1, 4.9e-324, 0, 0), Quat(1, 0, 0, -1e-300), tilted})
    EXPECT_FALSE(pba::detail::is_identity(q));
  EXPECT_TRUE(pba::detail::exact_times_identity(Quat(-0.5, 0.5, 1e-300, -1e300)));
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  for (const double x : {0.0, -0.0, 4.9e-324, inf, -inf, nan})
    EXPECT_FALSE(pba::detail::exact_times_identity(Quat(0.5, 0.5, x, 0.5))) << x;
  EXPECT_TRUE(pba::detail::positive_zero(Vec3(0)));
  for (const Vec3& v : {Vec3(-0.0, 0, 0), Vec3(0, -0.0, 0), Vec3(0, 0, -0.0), Vec3(0, 4.9e-324, 0)})
    EXPECT_FALSE(pba::detail::positive_zero(v));
  // the cases the shortcuts must refuse are among them; each takes another bit than the shortcut would:
  // a turn about one axis whose zero components change sign in the product by the identity,
  const Quat about_x(0.8, 0.6, -0.0, 0.0);
  EXPECT_FALSE(same_bits(Pose{{}, glm::normalize(about_x)}, full_body_frame({}, about_x, Vec3(0), Quat(1, 0, 0, 0))));
  // a centre at -0 moved to +0 by a -0 offset,
  const Quat spun = glm::normalize(Quat(-0.5, 0.3, 0.2, -0.7));
  const Vec3 at(-0.0, -0.0, -0.0), off(-0.0, -0.0, 0.0);
  EXPECT_FALSE(same_bits(Pose{at, glm::normalize(spun)}, full_body_frame(at, spun, off, Quat(1, 0, 0, 0))));
  // a body at -0 whose shape at its origin is at +0
  const Pose body{at, spun};
  EXPECT_FALSE(same_bits(Pose{body.position, glm::normalize(spun)}, pba::compose(body, Pose{})));
  // and the system's shape bounds are those at compose()'s pose (a box at -0 turning about y)
  RigidBodySystem s;
  const auto id = s.create({.pose = {Vec3(-0.0, 2, -0.0), Quat(0.8, -0.0, 0.6, -0.0)}, .shapes = kBox});
  const pba::Aabb made = s.shape_bounds(id)[0];
  const pba::Aabb full = pba::bounds(kBox[0].shape, pba::compose(s.pose(id), kBox[0].local));
  EXPECT_TRUE(std::memcmp(&made.lo, &full.lo, sizeof(Vec3)) == 0 && std::memcmp(&made.hi, &full.hi, sizeof(Vec3)) == 0);
}

// ---------------------------------------------------------------------------------------
// gravity, damping, kinematic bodies

// Semi-implicit Euler with substep h has the closed form v_n = v0 + g n h,
// x_n = x0 + v0 n h + g h^2 n (n + 1) / 2; its distance from the exact parabola is
// g h t / 2, first order in h. Every solver: the substepping ones at h = dt / substeps (XPBD's
// velocity from the position change is exactly v when nothing corrects the position),
// sequential impulses at h = dt. The substeps are taken exactly (auto_substeps off: the soft
// step would halve them a second in, nothing touching; the closed form is the scheme's at h).
TEST(RigidFreeFall, MatchesTheDiscreteSolutionAndConvergesToTheParabola) {
  for (const auto solver : pba::kRigidSolvers)
  for (const double dt : {1.0 / 30, 1.0 / 60, 1.0 / 240}) {
    for (const int substeps : {1, 4}) {
      RigidBodySystem s({.contacts = {.solver = solver, .substeps = substeps, .auto_substeps = false}});
      const Vec3 x0{0, 100, 0}, v0{2, 5, -1};
      auto b =
          s.create({.pose = {x0}, .linear_velocity = v0, .shapes = kBall, .mass = RigidMass::box(3, {0.5, 0.5, 0.5})});
      const int steps = static_cast<int>(std::lround(2.0 / dt));
      for (int i = 0; i < steps; ++i) s.step(dt, kG);
      const int per_step = solver == pba::RigidSolverType::SequentialImpulse ? 1 : substeps;
      const double h = dt / per_step;
      const double n = static_cast<double>(steps) * per_step, t = n * h;
      const Vec3 x_discrete = x0 + v0 * t + kG * (h * h * n * (n + 1) / 2);
      const Vec3 x_exact = x0 + v0 * t + 0.5 * kG * t * t;
      EXPECT_LT(glm::length(s.center_of_mass(b) - x_discrete), 1e-10)
          << to_string(solver) << " " << dt << " " << substeps;
      EXPECT_LT(glm::length(s.linear_velocity(b) - (v0 + kG * t)), 1e-11);
      // the error of the scheme is exactly g h t / 2 below the parabola
      EXPECT_NEAR(glm::length(s.center_of_mass(b) - x_exact), 9.81 * h * t / 2, 1e-9);
      EXPECT_EQ(s.angular_velocity(b), Vec3(0));
    }
  }
}

TEST(RigidFreeFall, GravityScaleAndStaticBodies) {
  RigidBodySystem s;
  auto floating = s.create({.pose = {{0, 1, 0}}, .shapes = kBall, .gravity_scale = 0});
  auto half = s.create({.pose = {{1, 1, 0}}, .shapes = kBall, .gravity_scale = 0.5});
  auto full = s.create({.pose = {{2, 1, 0}}, .shapes = kBall});
  auto ground =
      s.create({.type = BodyType::Static, .pose = {{0, -1, 0}}, .linear_velocity = {1, 0, 0}, .shapes = kBall});
  for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kG);
  EXPECT_EQ(s.center_of_mass(floating), Vec3(0, 1, 0));
  EXPECT_NEAR(s.linear_velocity(half).y, -9.81 / 2, 1e-12);
  EXPECT_NEAR(s.linear_velocity(full).y, -9.81, 1e-12);
  EXPECT_EQ(s.pose(ground).position, Vec3(0, -1, 0));  // static bodies never move
  EXPECT_EQ(s.linear_velocity(ground), Vec3(0));
  EXPECT_TRUE(std::isinf(s.mass(ground)));
}

// A body that touches nothing takes its step in closed form (coast(): no damping or torque, and
// no spin or three equal moments): the sums of the substeps' own semi-implicit Euler, so the
// same as the substeps to rounding, under a scaled gravity and a force, for a flat box that
// does not spin and a ball that does (whose turn about a fixed axis is one exact rotation).
TEST(RigidFreeFall, ACoastingBodysClosedStepIsItsSubsteps) {
  const int substeps = 8;
  RigidBodySystem s({.contacts = {.substeps = substeps, .auto_substeps = false}});
  const std::vector<pba::RigidShapeDef> slab{{.shape = pba::ColliderShape::box({0.4, 0.1, 0.25})}};
  const Vec3 v0{1.5, 4, -0.5}, w0{0.3, -2, 1.1}, force{6, -3, 2};
  const Quat q0 = glm::angleAxis(0.7, glm::normalize(Vec3(1, 2, 3)));
  auto box = s.create({.pose = {{0, 50, 0}, q0}, .linear_velocity = v0, .shapes = slab, .gravity_scale = 0.37});
  auto ball = s.create({.pose = {{5, 50, 0}, q0}, .linear_velocity = v0, .angular_velocity = w0, .shapes = kBall});
  const double dt = 1.0 / 60, h = dt / substeps, m = s.mass(box);
  Vec3 x = s.center_of_mass(box), v = v0, xb = s.center_of_mass(ball), vb = v0;
  for (int step = 0; step < 90; ++step) {
    s.apply_force(box, force);
    s.step(dt, kG);
    for (int k = 0; k < substeps; ++k) {
      v += h * (0.37 * kG + force / m), x += h * v;
      vb += h * kG, xb += h * vb;
    }
  }
  // rounding only: the reference loop's 720 adds a component each round x (45-56 m, ulp 7.1e-15)
  // by at most half an ulp, 2.6e-12 m, the closed form's 4 a step 1.3e-12 m: under 7e-12 m
  // as a length in the worst case (v: its roundings are a fifth of that, and random)
  EXPECT_LT(glm::length(s.center_of_mass(box) - x), 1e-11);
  EXPECT_LT(glm::length(s.linear_velocity(box) - v), 1e-12);
  EXPECT_LT(glm::length(s.center_of_mass(ball) - xb), 1e-11);
  EXPECT_LT(glm::length(s.linear_velocity(ball) - vb), 1e-12);
  // the box does not turn; the ball turns |w| t about w, and keeps w exactly
  EXPECT_LT(std::abs(std::abs(glm::dot(s.pose(box).rotation, q0)) - 1), 1e-14);
  EXPECT_EQ(s.angular_velocity(box), Vec3(0));
  EXPECT_EQ(s.angular_velocity(ball), w0);
  const Quat turned = glm::angleAxis(glm::length(w0) * 90 * dt, glm::normalize(w0)) * q0;
  EXPECT_GT(std::abs(glm::dot(s.pose(ball).rotation, turned)), 1 - 1e-13);
}

// implicit damping: v_n = v0 / (1 + h c)^n, which tends to v0 exp(-c t) as h -> 0 (the
// substeps taken exactly, auto_substeps off: the discrete law is the scheme's at that h)
TEST(RigidDamping, FollowsItsDiscreteLawAndTheExponential) {
  for (const int substeps : {1, 8, 64}) {
    RigidBodySystem s({.contacts = {.substeps = substeps, .auto_substeps = false}});
    auto b = s.create({.linear_velocity = {4, 0, 0},
                       .angular_velocity = {0, 0, 3},
                       .shapes = kBall,
                       .mass = RigidMass::sphere(1, 0.5),
                       .linear_damping = 2,
                       .angular_damping = 0.5});
    for (int i = 0; i < 60; ++i) s.step(1.0 / 60, Vec3(0));
    const double h = 1.0 / 60 / substeps, n = 60.0 * substeps;
    EXPECT_NEAR(s.linear_velocity(b).x, 4 / std::pow(1 + 2 * h, n), 1e-12);
    EXPECT_NEAR(s.angular_velocity(b).z, 3 / std::pow(1 + 0.5 * h, n), 1e-12);
    // first order: |v_n - v0 e^{-ct}| <= v0 c^2 t h / 2 e^{-ct} (1 + O(h))
    EXPECT_NEAR(s.linear_velocity(b).x, 4 * std::exp(-2.0), 4 * 4 * 1 * h / 2 * std::exp(-2.0) * 1.1);
  }
}

TEST(RigidKinematic, MovesAtItsVelocityAndTurnsExactly) {
  RigidBodySystem s;
  auto k = s.create({.type = BodyType::Kinematic,
                     .linear_velocity = {1, 2, 0},
                     .angular_velocity = {0, 0, pba::kPi},
                     .shapes = kBall});
  for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kG);  // gravity ignored
  const pba::Pose p = s.pose(k);
  EXPECT_LT(glm::length(p.position - Vec3(1, 2, 0)), 1e-12);
  // a half turn about z maps x to -x
  EXPECT_LT(glm::length(p.rotation * Vec3(1, 0, 0) - Vec3(-1, 0, 0)), 1e-12);
  EXPECT_TRUE(std::isinf(s.mass(k)));
}

// ---------------------------------------------------------------------------------------
// impulses and forces

TEST(RigidImpulse, ChangesMomentumAndAngularMomentumByTheImpulseAndItsMoment) {
  RigidBodySystem s;
  const RigidMass m = RigidMass::box(2, {0.5, 0.2, 0.1});
  const Quat q = glm::angleAxis(0.7, glm::normalize(Vec3(1, 2, 3)));
  auto b = s.create({.pose = {{1, 2, 3}, q}, .linear_velocity = {0.5, 0, 0}, .angular_velocity = {0.1, 0.2, 0.3},
                     .shapes = kBall, .mass = m});
  const Vec3 p0 = s.linear_velocity(b) * 2.0, l0 = s.angular_momentum(b);
  const Vec3 j{0.3, -1.0, 2.0}, at = Vec3(1, 2, 3) + q * Vec3(0.5, 0.2, -0.1);
  s.apply_impulse(b, j, at);
  EXPECT_LT(glm::length(s.linear_velocity(b) * 2.0 - (p0 + j)), 1e-14);
  EXPECT_LT(glm::length(s.angular_momentum(b) - (l0 + glm::cross(at - Vec3(1, 2, 3), j))), 1e-13);
  // an angular impulse adds to L directly
  s.apply_angular_impulse(b, {0, 0, 1});
  EXPECT_LT(glm::length(s.angular_momentum(b) - (l0 + glm::cross(at - Vec3(1, 2, 3), j) + Vec3(0, 0, 1))), 1e-13);
}

// A sphere (isotropic inertia, no gyroscopic torque) under a constant force at an offset
// point: dv = F t / m and dw = (r x F) t / I, with r fixed in the world only to first order
// (the point turns with the body), so over a short step the moment is checked to O(w t).
TEST(RigidForce, ForceAtAPointGivesLinearAndAngularAcceleration) {
  RigidBodySystem s({.contacts = {.substeps = 1}});
  auto b = s.create({.shapes = kBall, .mass = RigidMass::sphere(2, 0.5)});
  const Vec3 f{0, 0, 4}, r{0.5, 0, 0};
  s.apply_force(b, f, r);
  s.step(0.01, Vec3(0));
  EXPECT_LT(glm::length(s.linear_velocity(b) - f * 0.01 / 2.0), 1e-15);
  const double inertia = 0.4 * 2 * 0.25;
  EXPECT_LT(glm::length(s.angular_velocity(b) - glm::cross(r, f) * 0.01 / inertia), 1e-14);
  // forces last one step
  s.step(0.01, Vec3(0));
  EXPECT_LT(glm::length(s.linear_velocity(b) - f * 0.01 / 2.0), 1e-15);
  s.apply_torque(b, {0, 1, 0});
  const Vec3 w0 = s.angular_velocity(b);
  s.step(0.01, Vec3(0));
  EXPECT_LT(glm::length(s.angular_velocity(b) - w0 - Vec3(0, 0.01 / inertia, 0)), 1e-13);
}

// ---------------------------------------------------------------------------------------
// torque-free tumbling

// A T-handle: a bar along x with a stem along -y. Its principal axes are the body axes.
RigidMass t_handle() {
  RigidMass bar = RigidMass::box(1.0, {0.5, 0.05, 0.05});
  RigidMass stem = RigidMass::box(0.6, {0.05, 0.3, 0.05});
  stem.center = {0, -0.35, 0};
  return bar + stem;
}

// Euler's equations I w' = (I w) x w in the principal frame, by classical RK4.
Vec3 euler_rhs(const Vec3& inertia, const Vec3& w) { return glm::cross(inertia * w, w) / inertia; }

// times at which the body-frame component `axis` of w changes sign (the flips)
std::vector<double> rk4_crossings(const Vec3& inertia, Vec3 w, int axis, double h, double t_end) {
  std::vector<double> out;
  for (double t = 0; t < t_end; t += h) {
    const Vec3 k1 = euler_rhs(inertia, w), k2 = euler_rhs(inertia, w + 0.5 * h * k1);
    const Vec3 k3 = euler_rhs(inertia, w + 0.5 * h * k2), k4 = euler_rhs(inertia, w + h * k3);
    const Vec3 next = w + h / 6 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    if ((w[axis] > 0) != (next[axis] > 0)) out.push_back(t + h * w[axis] / (w[axis] - next[axis]));
    w = next;
  }
  return out;
}

// Under every solver: with no contact they all run the same free motion (XPBD keeps the
// splitting's velocities and adds only the contacts' corrections, src/rigid/xpbd_rigid.cpp).
TEST(RigidTumbling, TheTHandleKeepsAngularMomentumAndEnergyAndFlipsOnTime) {
  const RigidMass m = t_handle();
  // principal moments: x (bar axis) smallest, z largest, y intermediate
  const Vec3 moments{m.inertia[0][0], m.inertia[1][1], m.inertia[2][2]};
  ASSERT_LT(moments.x, moments.y);
  ASSERT_LT(moments.y, moments.z);
  const Vec3 w0{0.1, 10.0, 0.2};  // spin about the unstable intermediate axis, slightly off
  // the reference flip times, converged (h = 1e-4 s; RK4's error is far below 1e-6 s here)
  const std::vector<double> ref = rk4_crossings(moments, w0, 1, 1e-4, 10);
  ASSERT_GE(ref.size(), 4u);
  const double ref_period = 2 * (ref[3] - ref[0]) / 3;
  for (const auto solver : pba::kRigidSolvers)
  for (const double dt : {1.0 / 60, 1.0 / 240}) {
    for (const int substeps : {1, 4}) {
      RigidBodySystem s({.contacts = {.solver = solver, .substeps = substeps}});
      const Quat q0 = glm::angleAxis(0.3, glm::normalize(Vec3(1, -1, 2)));
      auto b = s.create({.pose = {{0, 0, 0}, q0}, .angular_velocity = q0 * w0, .shapes = kBall, .mass = m});
      const Vec3 l0 = s.angular_momentum(b);
      const double e0 = s.kinetic_energy(b);
      double worst_l = 0, worst_e = 0;
      std::vector<double> flips;
      double prev = w0.y, t = 0;
      const int steps = static_cast<int>(std::lround(10 / dt));
      for (int i = 0; i < steps; ++i) {
        s.step(dt, Vec3(0));
        t += dt;
        worst_l = std::max(worst_l, glm::length(s.angular_momentum(b) - l0) / glm::length(l0));
        worst_e = std::max(worst_e, std::abs(s.kinetic_energy(b) - e0) / e0);
        // the body-frame spin about the intermediate axis
        const double wy = (glm::conjugate(s.pose(b).rotation) * s.angular_velocity(b)).y;
        if ((prev > 0) != (wy > 0)) flips.push_back(t - dt * wy / (wy - prev));
        prev = wy;
      }
      EXPECT_LT(worst_l, 1e-3) << to_string(solver) << " " << dt << " x" << substeps;
      EXPECT_LT(worst_e, 0.01) << to_string(solver) << " " << dt << " x" << substeps;
      // the flip period from the first four flips of each
      ASSERT_GE(flips.size(), 4u) << to_string(solver) << " " << dt << " x" << substeps;
      const double period = 2 * (flips[3] - flips[0]) / 3;
      EXPECT_NEAR(period, ref_period, 0.05 * ref_period) << to_string(solver) << " " << dt << " x" << substeps;
    }
  }
}

// The splitting is second order: halving h quarters the energy error of a tumbling body.
TEST(RigidTumbling, EnergyErrorIsSecondOrder) {
  const RigidMass m = t_handle();
  auto worst = [&](double dt) {
    RigidBodySystem s({.contacts = {.substeps = 1}});
    auto b = s.create({.angular_velocity = {3, 8, 1}, .shapes = kBall, .mass = m});
    const double e0 = s.kinetic_energy(b);
    double w = 0;
    for (int i = 0; i < static_cast<int>(std::lround(4 / dt)); ++i) {
      s.step(dt, Vec3(0));
      w = std::max(w, std::abs(s.kinetic_energy(b) - e0) / e0);
    }
    return w;
  };
  const double e1 = worst(1.0 / 120), e2 = worst(1.0 / 240), e3 = worst(1.0 / 480);
  EXPECT_NEAR(std::log2(e1 / e2), 2.0, 0.3);
  EXPECT_NEAR(std::log2(e2 / e3), 2.0, 0.3);
}

// A body whose inertia is not diagonal in its frame: the principal frame is found, the
// world inertia at the start is the one given, and L is kept while it tumbles.
TEST(RigidTumbling, NonDiagonalInertiaIsDiagonalisedAndConserved) {
  RigidMass m = RigidMass::box(2, {0.6, 0.3, 0.1});
  const Mat3 r = glm::mat3_cast(glm::angleAxis(0.5, glm::normalize(Vec3(1, 1, 0))));
  m.inertia = r * m.inertia * glm::transpose(r);
  m.center = {0.1, 0.2, -0.1};
  RigidBodySystem s;
  auto b = s.create({.pose = {{1, 1, 1}}, .angular_velocity = {1, 5, 2}, .shapes = kBall, .mass = m});
  const Mat3 wi = s.world_inertia(b);
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(wi[c][k], m.inertia[c][k], 1e-13);
  EXPECT_LT(glm::length(s.pose(b).position - Vec3(1, 1, 1)), 1e-14);
  EXPECT_LT(glm::length(s.center_of_mass(b) - Vec3(1.1, 1.2, 0.9)), 1e-14);
  const Vec3 l0 = s.angular_momentum(b);
  for (int i = 0; i < 600; ++i) s.step(1.0 / 60, Vec3(0));
  // only rounding: 600 steps x 8 substeps x 5 exact rotations, each ~1e-16 relative
  EXPECT_LT(rel(s.angular_momentum(b), l0), 24000 * 1e-16);
  // the centre of mass, not the body origin, moves with the (zero) momentum
  EXPECT_LT(glm::length(s.center_of_mass(b) - Vec3(1.1, 1.2, 0.9)), 1e-12);
}

// A round body (three equal principal moments I: a cube, a ball) has momentum I w, so no
// gyroscopic term: its world angular velocity w stays as it is and it turns about w at the
// rate |w|, q(t) = (cos(|w| t / 2), sin(|w| t / 2) w / |w|) q0. The free motion takes that turn
// exactly each substep (the splitting's five turns about the principal axes would be off by
// O(h^2) a unit of time: 1e-3 to 1e-2 rad here), so a cube spun about any axis keeps w to the
// bit and stays within rounding of the closed form: each substep's turn and product round to
// a few ulps, under 1e-15 rad, and the closed form's own angle |w| t to |w| t 2^-52.
TEST(RigidTumbling, ARoundBodyTurnsExactlyAboutItsConstantAngularVelocity) {
  const double dt = 1.0 / 60, t = 10;
  const int steps = static_cast<int>(std::lround(t / dt)), substeps = 8;
  // about tilted axes and a principal one; the last beyond the series' pi/8 half turn a
  // substep (the library's sine and cosine)
  for (const Vec3 w0 : {Vec3(0.3, -7, 2), Vec3(0, 0, 5), Vec3(40, 25, -60), Vec3(500, -200, 300)}) {
    for (const auto solver : pba::kRigidSolvers) {
      RigidBodySystem s({.contacts = {.solver = solver, .substeps = substeps}});
      const Quat q0 = glm::angleAxis(0.7, glm::normalize(Vec3(1, 2, -1)));
      auto b = s.create({.pose = {{0, 0, 0}, q0}, .angular_velocity = w0,
                         .shapes = {{.shape = pba::ColliderShape::box(Vec3(0.5))}}});
      for (int i = 0; i < steps; ++i) s.step(dt, Vec3(0));
      const double speed = glm::length(w0);
      const Quat exact = glm::angleAxis(speed * t, w0 / speed) * q0;
      const Quat d = s.pose(b).rotation * glm::conjugate(exact);
      const double angle = 2 * glm::length(Vec3(d.x, d.y, d.z));
      const double bound = steps * substeps * 1e-15 + speed * t * 0x1p-52;
      EXPECT_LT(angle, bound) << to_string(solver) << " w " << w0.x << " " << w0.y << " " << w0.z;
      EXPECT_EQ(s.angular_velocity(b), w0) << to_string(solver);
    }
  }
}

// An axisymmetric body (principal moments I1, I1 and I3 about axis k: a box of two equal sides,
// a capsule) turns exactly too: its world momentum L and body-frame pi_k are constant, and
// R(t) = exp(t [L] / I1) R0 exp(t pi_k (1/I3 - 1/I1) [e_k]), pi(t) = exp(-t pi_k (1/I3 -
// 1/I1) [e_k]) pi0 (the kinetic energy |pi|^2 / 2 I1 + pi_k^2 (1/I3 - 1/I1) / 2 is a sum of
// two commuting exact turns). The free motion takes both each substep, so the body's rotation
// and angular velocity stay within rounding of the closed form (the five-turn splitting is
// off by O(h^2) a unit of time), about each of the three axes, oblate and prolate, slow and
// beyond the series' range.
TEST(RigidTumbling, AnAxisymmetricBodyFollowsItsClosedForm) {
  const double dt = 1.0 / 60, t = 10;
  const int steps = static_cast<int>(std::lround(t / dt)), substeps = 8;
  const Vec3 halves[] = {{0.5, 0.2, 0.2}, {0.2, 0.5, 0.2}, {0.2, 0.2, 0.5}, {0.1, 0.4, 0.4}};
  for (const Vec3& half : halves) {
    for (const Vec3 w0 : {Vec3(0.3, -7, 2), Vec3(40, 25, -60), Vec3(500, -200, 300)}) {
      const RigidMass m = RigidMass::box(1.5, half);
      const Vec3 moments{m.inertia[0][0], m.inertia[1][1], m.inertia[2][2]};
      const int k = moments.y == moments.z ? 0 : moments.x == moments.z ? 1 : 2;
      ASSERT_EQ(moments[(k + 1) % 3], moments[(k + 2) % 3]);
      ASSERT_NE(moments[k], moments[(k + 1) % 3]);
      for (const auto solver : pba::kRigidSolvers) {
        RigidBodySystem s({.contacts = {.solver = solver, .substeps = substeps}});
        const Quat q0 = glm::angleAxis(0.7, glm::normalize(Vec3(1, 2, -1)));
        auto b = s.create({.pose = {{0, 0, 0}, q0}, .angular_velocity = w0, .shapes = kBall, .mass = m});
        for (int i = 0; i < steps; ++i) s.step(dt, Vec3(0));
        // the closed form
        const double i1 = moments[(k + 1) % 3];
        const Vec3 pi0 = moments * (glm::conjugate(q0) * w0);
        const Vec3 l = q0 * pi0;
        Vec3 axis(0);
        axis[k] = 1;
        const double spin = pi0[k] * (1 / moments[k] - 1 / i1) * t, precession = glm::length(l) / i1 * t;
        const Quat body_turn = glm::angleAxis(spin, axis);
        const Quat exact = glm::angleAxis(precession, l / glm::length(l)) * q0 * body_turn;
        const Vec3 w_exact = exact * ((glm::conjugate(body_turn) * pi0) / moments);
        const Quat d = s.pose(b).rotation * glm::conjugate(exact);
        const double angle = 2 * glm::length(Vec3(d.x, d.y, d.z));
        // rounding: each substep rounds pi, and with it the two rates, by a few ulps; a rate
        // off by a relative d turns the body d times the angle turned so far too far, so the
        // error may grow as (substeps so far x a few ulps) x the angles
        const double bound = steps * substeps * 1e-15 * (1 + std::abs(spin) + precession);
        EXPECT_LT(angle, bound) << to_string(solver) << " axis " << k << " w " << w0.x << " " << w0.y << " " << w0.z;
        EXPECT_LT(glm::length(s.angular_velocity(b) - w_exact) / glm::length(w0), bound) << to_string(solver);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------
// handles, bad input, divergence, determinism

TEST(RigidHandles, DestroyKeepsTheOthersAndRejectsStaleHandles) {
  RigidBodySystem s;
  auto a = s.create({.name = "a", .pose = {{1, 0, 0}}, .shapes = kBall});
  auto b = s.create({.name = "b", .pose = {{2, 0, 0}}, .shapes = kBall});
  auto c = s.create({.name = "c", .pose = {{3, 0, 0}}, .shapes = kBall});
  s.destroy(b);
  EXPECT_EQ(s.size(), 2u);
  EXPECT_EQ(s.pose(a).position.x, 1);
  EXPECT_EQ(s.pose(c).position.x, 3);
  EXPECT_EQ(s.name(c), "c");
  EXPECT_NE(error_of([&] { s.pose(b); }).find("stale handle"), std::string::npos);
  EXPECT_NE(error_of([&] { s.apply_impulse(b, {1, 0, 0}, {0, 0, 0}); }).find("stale handle"), std::string::npos);
  // each call names itself (shape_bounds named pose, which it calls first)
  EXPECT_NE(error_of([&] { s.shape_bounds(b); }).find("RigidBodySystem::shape_bounds: stale handle"),
            std::string::npos) << error_of([&] { s.shape_bounds(b); });
  auto d = s.create({.name = "d", .shapes = kBall});  // reuses b's slot at a new generation
  EXPECT_EQ(d.index, b.index);
  EXPECT_FALSE(s.valid(b));
  EXPECT_NE(error_of([&] { s.pose(pba::RigidBodyId{}); }).find("null handle"), std::string::npos);
}

// id_at's index is refused with a pba::Error naming it and the range (a std::out_of_range
// from the vector's at() before, which named neither the call nor the range), at both ends:
// size() is one past the last body, and the largest index is far past it.
TEST(RigidHandles, AnIndexPastTheBodiesIsRefusedByName) {
  RigidBodySystem s;
  EXPECT_EQ(error_of([&] { s.id_at(0); }), "RigidBodySystem::id_at: index 0 out of range [0, 0)");
  const auto a = s.create({.shapes = kBall});
  const auto b = s.create({.pose = {{2, 0, 0}}, .shapes = kBall});
  EXPECT_EQ(s.id_at(0), a);
  EXPECT_EQ(s.id_at(1), b);
  EXPECT_EQ(error_of([&] { s.id_at(2); }), "RigidBodySystem::id_at: index 2 out of range [0, 2)");
  EXPECT_EQ(error_of([&] { s.id_at(SIZE_MAX); }),
            "RigidBodySystem::id_at: index " + std::to_string(SIZE_MAX) + " out of range [0, 2)");
}

// A moved-from system is an empty one that works, as a moved-from std::vector is: its contact
// state went with the move and was left null, so its next create() or step() dereferenced null.
TEST(RigidHandles, AMovedFromSystemIsAnEmptySystemThatWorks) {
  auto fill = [](RigidBodySystem& s) {
    s.create({.type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
    return s.create({.pose = {{0, 0.6, 0}}, .shapes = kBox});
  };
  RigidBodySystem a;
  const auto box = fill(a);
  a.step(1.0 / 60, kG);
  RigidBodySystem b = std::move(a);
  EXPECT_EQ(a.size(), 0u);  // NOLINT(bugprone-use-after-move): the point of the test
  EXPECT_EQ(a.manifold_count(), 0u);
  EXPECT_TRUE(a.contacts().empty());
  EXPECT_FALSE(a.valid(box));
  a.step(1.0 / 60, kG);
  const auto again = fill(a);
  for (int i = 0; i < 60; ++i) a.step(1.0 / 60, kG), b.step(1.0 / 60, kG);
  EXPECT_NEAR(a.pose(again).position.y, 0.5, 1e-3);  // rests on its ground
  EXPECT_NEAR(b.pose(box).position.y, 0.5, 1e-3);    // the moved system carries on
  RigidBodySystem c;
  c = std::move(b);
  EXPECT_EQ(b.manifold_count(), 0u);  // NOLINT(bugprone-use-after-move)
  b.set_lane_reuse(false);
  EXPECT_EQ(b.simd(), c.simd());
  const auto third = fill(b);
  b.step(1.0 / 60, kG);
  EXPECT_TRUE(b.valid(third));
  EXPECT_NEAR(c.pose(box).position.y, 0.5, 1e-3);
}

TEST(RigidBadInput, NamesTheFieldAndTheBody) {
  RigidBodySystem s;
  auto msg = [&](RigidBodyDef d) { return error_of([&] { s.create(d); }); };
  const RigidBodyDef crate{.name = "crate", .shapes = kBall, .mass = RigidMass{}};
  RigidBodyDef d = crate;
  d.mass->mass = 0;
  EXPECT_NE(msg(d).find("'crate'.mass.mass: must be finite and > 0, got 0"), std::string::npos) << msg(d);
  d.mass->mass = -1;
  EXPECT_NE(msg(d).find("mass.mass"), std::string::npos);
  d.mass->mass = NAN;
  EXPECT_NE(msg(d).find("got nan"), std::string::npos);
  d = crate;
  d.mass->inertia[0][0] = -1;
  EXPECT_NE(msg(d).find("mass.inertia: must be positive definite"), std::string::npos) << msg(d);
  d = crate;
  d.mass->inertia[1][0] = 0.5;
  EXPECT_NE(msg(d).find("mass.inertia: must be symmetric"), std::string::npos) << msg(d);
  d = crate;
  d.mass->inertia = Mat3(0.0);
  d.mass->inertia[0][0] = 1, d.mass->inertia[1][1] = 1, d.mass->inertia[2][2] = 3;
  EXPECT_NE(msg(d).find("triangle inequality"), std::string::npos) << msg(d);
  d = crate;
  d.mass->inertia[2][2] = INFINITY;
  EXPECT_NE(msg(d).find("mass.inertia: must be finite, got inf"), std::string::npos) << msg(d);
  // shapes: none, bad ones, densities, a plane on a moving body
  EXPECT_NE(msg({.name = "empty"}).find("'empty'.shapes: a body needs at least one shape, got none"),
            std::string::npos) << msg({.name = "empty"});
  EXPECT_NE(msg({.shapes = {{.shape = pba::ColliderShape{.type = pba::ShapeType::Sphere, .radius = -1}}}})
                .find("shapes[0].shape.radius"), std::string::npos);
  EXPECT_NE(msg({.shapes = {{.shape = pba::ColliderShape::sphere(1), .density = 0}}}).find("shapes[0].density"),
            std::string::npos);
  EXPECT_NE(msg({.shapes = {{.shape = pba::ColliderShape::sphere(1), .material = {.restitution = 2}}}})
                .find("shapes[0].material.restitution"), std::string::npos);
  EXPECT_NE(msg({.shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}}).find("only a static body"),
            std::string::npos);
  EXPECT_NE(msg({.pose = {{NAN, 0, 0}}}).find("pose.position: must be finite"), std::string::npos);
  EXPECT_NE(msg({.pose = {{0, 0, 0}, Quat(2, 0, 0, 0)}}).find("pose.rotation"), std::string::npos);
  EXPECT_NE(msg({.linear_velocity = {0, INFINITY, 0}}).find("linear_velocity"), std::string::npos);
  EXPECT_NE(msg({.angular_velocity = {0, NAN, 0}}).find("angular_velocity"), std::string::npos);
  EXPECT_NE(msg({.linear_damping = -1}).find("linear_damping"), std::string::npos);
  EXPECT_NE(msg({.gravity_scale = NAN}).find("gravity_scale"), std::string::npos);
  // a static body needs no mass, and may be a plane
  RigidBodyDef ground{.type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}},
                      .mass = RigidMass{.mass = 0}};
  EXPECT_EQ(msg(ground), "");
  // runtime calls
  auto b = s.create({.name = "ball", .shapes = kBall});
  EXPECT_NE(error_of([&] { s.apply_force(b, {NAN, 0, 0}); }).find("'ball' apply_force force"), std::string::npos);
  EXPECT_NE(error_of([&] { s.apply_impulse(b, {1, 0, 0}, {0, INFINITY, 0}); }).find("apply_impulse point"),
            std::string::npos);
  EXPECT_NE(error_of([&] { s.set_velocity(b, {0, 0, 0}, {NAN, 0, 0}); }).find("set_velocity angular"),
            std::string::npos);
  EXPECT_NE(error_of([&] { s.set_pose(b, {{0, 0, 0}, Quat(0, 0, 0, 0)}); }).find("set_pose rotation"),
            std::string::npos);
  EXPECT_NE(error_of([&] { s.step(0, kG); }).find("dt: must be finite and > 0, got 0"), std::string::npos);
  EXPECT_NE(error_of([&] { s.step(0.01, {0, NAN, 0}); }).find("gravity"), std::string::npos);
  // a setter's Error names the call and the value (until the fix set_substeps named the
  // settings' field, "ContactSettings.substeps", which the caller never wrote)
  EXPECT_EQ(error_of([&] { s.set_substeps(0); }), "RigidBodySystem::set_substeps(n): must be an integer in [1, 64], got 0");
  EXPECT_EQ(error_of([&] { s.set_substeps(65); }),
            "RigidBodySystem::set_substeps(n): must be an integer in [1, 64], got 65");
  EXPECT_NE(error_of([&] { RigidBodySystem bad({.contacts = {.substeps = 65}}); }).find("contacts.substeps"),
            std::string::npos);
  s.settings().contact_hertz = -1;
  EXPECT_NE(error_of([&] { s.step(0.01, kG); }).find("settings.contact_hertz"), std::string::npos);
  s.settings().contact_hertz = 120;
  for (const double sag : {-0.01, double(NAN), double(INFINITY)}) {
    s.settings().auto_substeps_sag = sag;
    EXPECT_NE(error_of([&] { s.step(0.01, kG); }).find("settings.auto_substeps_sag"), std::string::npos) << sag;
  }
  s.settings().auto_substeps_sag = 0;
  for (const double fraction : {-0.01, 1.5, double(NAN), double(INFINITY)}) {
    s.settings().auto_substeps_sag_fraction = fraction;
    EXPECT_NE(error_of([&] { s.step(0.01, kG); }).find("settings.auto_substeps_sag_fraction"), std::string::npos)
        << fraction;
  }
  s.settings().auto_substeps_sag_fraction = 0.02;
  for (const int least : {0, -3, 65}) {
    s.settings().auto_substeps_least = least;
    EXPECT_NE(error_of([&] { s.step(0.01, kG); }).find("settings.auto_substeps_least"), std::string::npos) << least;
  }
}

// The contact solver's blocks hold masses, inertias and their inverses as floats: a mass or
// principal moment whose inverse is no normal float used to pass and turn the first contact
// into NaN (a 1e39 kg box, a 1e-38 kg ball). Now refused by name, given or from the shapes.
TEST(RigidBadInput, MassesAndMomentsOutsideTheFloatRangeAreRefusedByName) {
  RigidBodySystem s;
  auto msg = [&](RigidBodyDef d) { return error_of([&] { s.create(d); }); };
  const std::vector<pba::RigidShapeDef> cube{{.shape = pba::ColliderShape::box({0.5, 0.5, 0.5})}};
  auto given = [&](double m) {
    return RigidBodyDef{.name = "crate", .shapes = cube, .mass = RigidMass{m, Vec3(0), Mat3(m / 6)}};
  };
  for (double m : {1e39, 1e-40}) {
    const std::string e = msg(given(m));
    EXPECT_NE(e.find("'crate'.mass.mass: must be in [2.9"), std::string::npos) << e;
    EXPECT_NE(e.find("got " + pba::format_value(m)), std::string::npos) << e;
  }
  // a mass in range whose moments are not: 1e-35 kg over a 1 mm ball (I = 4e-42 kg m^2)
  const std::string e = msg({.name = "dust", .shapes = {{.shape = pba::ColliderShape::sphere(1e-3)}},
                             .mass = RigidMass{1e-35, Vec3(0), Mat3(4e-42)}});
  EXPECT_NE(e.find("'dust'.mass.principal moment 0 (kg m^2): must be in [2.9"), std::string::npos) << e;
  // from the shapes: a 1 um cube of water weighs 1e-15 kg, I = 1.7e-28 (fine); at 1e-30 m, not
  EXPECT_EQ(msg({.shapes = {{.shape = pba::ColliderShape::box({1e-6, 1e-6, 1e-6})}}}), "");
  const std::string f = msg({.name = "speck", .shapes = {{.shape = pba::ColliderShape::box({1e-30, 1e-30, 1e-30})}}});
  EXPECT_NE(f.find("'speck'.mass (from the shapes).mass: must be in [2.9"), std::string::npos) << f;
  EXPECT_NE(f.find("the shapes' sizes and densities make the body too small or light"), std::string::npos) << f;
  // a 1 nm ball of water: its mass is a normal float's inverse, its moment (4e-42) is not
  const std::string g = msg({.name = "mote", .shapes = {{.shape = pba::ColliderShape::sphere(1e-9)}}});
  EXPECT_NE(g.find("'mote'.mass (from the shapes).principal moment 0 (kg m^2): must be in [2.9"), std::string::npos)
      << g;
  EXPECT_NE(g.find("scale the shapes or the density, or give the mass and inertia"), std::string::npos) << g;
  EXPECT_EQ(msg(given(8e37)), "");
  EXPECT_EQ(msg(given(3e-39 * 6)), "");
}

// Shapes whose mass properties leave the doubles' range: a 1e-300 m ball weighs 0 kg, a box of
// 1e300 m half extents an infinite mass, a capsule 1e300 m long a NaN inertia. Each was refused
// as "'b'.mass (from the shapes).mass: must be finite and > 0, got 0" (or inf, or a NaN inertia)
// with nothing to say that the shapes' size made it; now with the float range's hint.
TEST(RigidBadInput, ShapesTooSmallOrLargeForAMassSayWhatToChange) {
  RigidBodySystem s;
  const std::string hint = "the shapes' sizes and densities make the body too small or light, or too large or heavy";
  for (const pba::ColliderShape& shape : {pba::ColliderShape::sphere(1e-300), pba::ColliderShape::box({1e-300, 1, 1})}) {
    const std::string m = error_of([&] { s.create({.name = "b", .shapes = {{.shape = shape}}}); });
    const std::string what = std::string(to_string(shape.type)) + ": " + m;
    EXPECT_NE(m.find("'b'.mass (from the shapes)."), std::string::npos) << what;
    EXPECT_NE(m.find(hint), std::string::npos) << what;
  }
  // (sizes past a float's, 1e300 m, are refused before their mass by the colliders' range,
  // naming the size: RigidBadInput.DynamicShapeSizesOutsideTheFloatRangeAreRefusedByName)
  EXPECT_EQ(error_of([&] { s.create({.name = "b", .shapes = {{.shape = pba::ColliderShape::capsule(1e300, 0.2)}}}); }),
            "RigidBodyDef 'b'.shapes[0].shape.half_height: must fit a float (|v| <= 3.4028234663852886e+38), got 1e+300");
  // a density that overflows the mass gets the hint too
  const std::string m = error_of(
      [&] { s.create({.name = "b", .shapes = {{.shape = pba::ColliderShape::sphere(1), .density = 1e308}}}); });
  EXPECT_NE(m.find(hint), std::string::npos) << m;
}

// The largest capacity, 2^26 bodies, reserves some 36 GB of address space up front. Where the
// memory or a limit on it cannot give that (here 2 GiB of address space, in a child process),
// the std::bad_alloc of the first reserve that failed came out unexplained ("pba run:
// unexpected error: std::bad_alloc" for a scene's settings.rigid.capacity); now an Error naming
// the field and the count. (Not under the sanitizers, whose shadow memory needs the space.)
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
// (in the child: the exit code says what the largest system did under 2 GiB)
[[noreturn]] void reserve_under_two_gib() {
  rlimit two_gib{};
  two_gib.rlim_cur = two_gib.rlim_max = rlim_t(1) << 31;
  setrlimit(RLIMIT_AS, &two_gib);
  try {
    RigidBodySystem s(pba::RigidSystemDef{.capacity = std::size_t(1) << 26});
    std::exit(2);  // reserved after all: the limit did not hold
  } catch (const pba::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    std::exit(0);
  } catch (const std::bad_alloc&) {
    std::exit(3);
  }
}

TEST(RigidBadInput, ACapacityTheMemoryCannotHoldIsNamed) {
  EXPECT_EXIT(reserve_under_two_gib(), ::testing::ExitedWithCode(0),
              "RigidSystemDef.capacity: cannot reserve room for 67108864 bodies");
}
#endif

// The shapes' bounds and the contact rows hold positions as floats: a body set beyond the
// float range (1e39 m, finite as a double) was accepted by create and set_pose, and the next
// step against a ground plane turned it to NaN and stopped the system. Refused where it is
// given, as scene files refuse such positions; the largest float position still steps.
TEST(RigidBadInput, PositionsOutsideTheFloatRangeAreRefusedWhereTheyAreGiven) {
  RigidBodySystem s;
  s.create(
      {.name = "ground", .type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
  const std::vector<pba::RigidShapeDef> cube{{.shape = pba::ColliderShape::box({0.5, 0.5, 0.5})}};
  std::string m = error_of([&] { s.create({.name = "far", .pose = {{1e39, 0.5, 0}}, .shapes = cube}); });
  EXPECT_NE(m.find("'far'.pose.position: must fit a float"), std::string::npos) << m;
  EXPECT_NE(m.find("got (1e+39, 0.5, 0)"), std::string::npos) << m;
  m = error_of([&] {
    s.create({.name = "odd", .shapes = {{.shape = pba::ColliderShape::sphere(0.5), .local = {{0, 0, -1e39}}}}});
  });
  EXPECT_NE(m.find("'odd'.shapes[0].local.position: must fit a float"), std::string::npos) << m;
  const double edge = 3.4e38;
  const auto b = s.create({.name = "crate", .pose = {{edge, 0.5, 0}}, .shapes = cube});
  m = error_of([&] { s.set_pose(b, {{-1e39, 0.5, 0}}); });
  EXPECT_NE(m.find("'crate' set_pose position: must fit a float"), std::string::npos) << m;
  EXPECT_EQ(s.pose(b).position, Vec3(edge, 0.5, 0));  // left as it was
  for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kG);
  EXPECT_EQ(s.pose(b).position.x, edge);
  EXPECT_NEAR(s.pose(b).position.y, 0.5, 1e-3);  // rests on the ground
}

// A static (or kinematic) body's shape sizes had no bound but finiteness, as a dynamic body's
// mass bounds them: a ground plane's offset of 1e39 m or a capsule 1e300 m long was taken, and
// the first step stopped naming the ball that touched it ("'ball' became non-finite", its
// angular velocity NaN). Refused at create, naming the shape's field, as the colliders' range
// (a float's) has it; a static shape at the largest float is taken and holds a ball up.
TEST(RigidBadInput, StaticShapeSizesOutsideTheFloatRangeAreRefusedByName) {
  RigidBodySystem s;
  const std::string fit = ": must fit a float (|v| <= 3.4028234663852886e+38), got ";
  EXPECT_EQ(error_of([&] {
              s.create({.name = "ground", .type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 1e39)}}});
            }),
            "RigidBodyDef 'ground'.shapes[0].shape.offset" + fit + "1e+39");
  EXPECT_EQ(error_of([&] {
              s.create({.name = "pole", .type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::capsule(1e300, 1)}}});
            }),
            "RigidBodyDef 'pole'.shapes[0].shape.half_height" + fit + "1e+300");
  EXPECT_EQ(error_of([&] {
              s.create({.name = "moon", .type = BodyType::Kinematic, .shapes = {{.shape = pba::ColliderShape::sphere(1e39)}}});
            }),
            "RigidBodyDef 'moon'.shapes[0].shape.radius" + fit + "1e+39");
  const std::string box = error_of([&] {
    s.create({.name = "slab", .type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::box({1e39, 1, 1})}}});
  });
  EXPECT_EQ(box.rfind("RigidBodyDef 'slab'.shapes[0].shape.half_extents: must fit a float", 0), 0u) << box;
  EXPECT_EQ(s.size(), 0u);
  // the largest float is in the range: a slab that wide and 1 m thick holds a ball on its top
  const double edge = 3.4e38;
  s.create({.name = "slab", .type = BodyType::Static, .pose = {{0, -1, 0}},
            .shapes = {{.shape = pba::ColliderShape::box({edge, 1, edge})}}});
  const auto ball = s.create({.name = "ball", .pose = {{0, 0.5, 0}}, .shapes = {{.shape = pba::ColliderShape::sphere(0.5)}}});
  for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kG);
  EXPECT_NEAR(s.pose(ball).position.y, 0.5, 1e-3);  // rests on the slab's top face at y = 0
}

// A dynamic body's shape sizes were left to its mass to bound ("a dynamic body's such shapes
// are refused by their mass"), which a given mass does not do: a box of half extents
// (1e39, 0.5, 0.5) with `.mass = RigidMass{}` was created, and its first step stopped with the
// narrow phase's "collide: shape_b.half_extents[0] ..." naming no body; a capsule 2e39 m long
// stepped on without a word. Every body type's sizes are refused at create now, by name.
TEST(RigidBadInput, DynamicShapeSizesOutsideTheFloatRangeAreRefusedByName) {
  RigidBodySystem s;
  s.create({.name = "ground", .type = BodyType::Static, .pose = {{0, -1, 0}},
            .shapes = {{.shape = pba::ColliderShape::box({10, 1, 10})}}});
  const std::string fit = ": must fit a float (|v| <= 3.4028234663852886e+38), got 1e+39";
  for (const bool given : {true, false}) {
    const std::optional<RigidMass> mass = given ? std::optional<RigidMass>(RigidMass{}) : std::nullopt;
    EXPECT_EQ(error_of([&] {
                s.create({.name = "rod", .pose = {{0, 0.5, 0}}, .shapes = {{.shape = pba::ColliderShape::capsule(1e39, 0.5)}},
                          .mass = mass});
              }),
              "RigidBodyDef 'rod'.shapes[0].shape.half_height" + fit);
    EXPECT_EQ(error_of([&] {
                s.create({.name = "orb", .pose = {{0, 0.5, 0}}, .shapes = {{.shape = pba::ColliderShape::sphere(1e39)}},
                          .mass = mass});
              }),
              "RigidBodyDef 'orb'.shapes[0].shape.radius" + fit);
    const std::string box = error_of([&] {
      s.create({.name = "beam", .pose = {{0, 0.5, 0}}, .shapes = {{.shape = pba::ColliderShape::box({1e39, 0.5, 0.5})}},
                .mass = mass});
    });
    EXPECT_EQ(box.rfind("RigidBodyDef 'beam'.shapes[0].shape.half_extents: must fit a float", 0), 0u) << box;
  }
  EXPECT_EQ(s.size(), 1u);
  // the largest float is in the range: a beam that long with a given mass is taken
  s.create({.name = "beam", .pose = {{0, 0.5, 0}}, .shapes = {{.shape = pba::ColliderShape::box({3.4e38, 0.5, 0.5})}},
            .mass = RigidMass{}});
  EXPECT_EQ(s.size(), 2u);
}

// A shape's frame in the world is its body's position plus its turned local offset: each was
// held to a float's range, their sum not (a static box at 3e38 m + 1e38 m was created, and
// the ball on it stopped the first step with the narrow phase's "collide: pose_a.position"
// naming no body; a sphere pair stepped). Refused at create and set_pose, naming the pose
// and both terms in one form, as the World refuses an entity's component placed past it; the
// rotation counts.
TEST(RigidBadInput, AShapesFrameOutsideTheFloatRangeIsRefusedAtCreateAndSetPose) {
  RigidBodySystem s;
  const std::vector<pba::RigidShapeDef> off{{.shape = pba::ColliderShape::plane({0, 1, 0}, 0), .local = {{1e38, 0, 0}}}};
  EXPECT_EQ(error_of([&] { s.create({.name = "ground", .type = BodyType::Static, .pose = {{3e38, 0, 0}}, .shapes = off}); }),
            "RigidBodyDef 'ground'.pose: position (3e+38, 0, 0) + rotation * shapes[0].local.position "
            "(1e+38, 0, 0) = (4e+38, 0, 0) does not fit a float (|component| <= 3.4028234663852886e+38)");
  EXPECT_EQ(s.size(), 0u);
  // turned half a turn about y the offset points back: 2e38 m, taken (the plane's normal stays)
  const Quat half(0, 0, 1, 0);
  const auto ground = s.create({.name = "ground", .type = BodyType::Static, .pose = {{3e38, 0, 0}, half}, .shapes = off});
  const auto crate = s.create({.name = "crate", .pose = {{2e38, 0.5, 0}}, .shapes = kBox});
  for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kG);
  EXPECT_NEAR(s.pose(crate).position.y, 0.5, 1e-3);  // rests on the ground
  EXPECT_EQ(error_of([&] { s.set_pose(ground, {{3e38, 0, 0}}); }),
            "rigid body 0 'ground' set_pose: position (3e+38, 0, 0) + rotation * shapes[0].local.position "
            "(1e+38, 0, 0) = (4e+38, 0, 0) does not fit a float (|component| <= 3.4028234663852886e+38)");
  EXPECT_EQ(s.pose(ground).position, Vec3(3e38, 0, 0));  // left as it was
  EXPECT_EQ(s.pose(ground).rotation, half);
}

// RigidMass's box and sphere took a negative or NaN mass or size and returned a negative mass or a
// NaN inertia (create() refused it later, naming the body's mass, not the factory's argument).
TEST(RigidBadInput, TheMassFactoriesRefuseANonPositiveMassOrSizeByName) {
  EXPECT_EQ(error_of([] { RigidMass::box(-1, {0.5, 0.5, 0.5}); }), "RigidMass::box: mass (kg): must be finite and > 0, got -1");
  EXPECT_EQ(error_of([] { RigidMass::box(1, {0.5, 0, 0.5}); }), "RigidMass::box: half.y (m): must be finite and > 0, got 0");
  EXPECT_NE(error_of([] { RigidMass::box(1, {0.5, 0.5, NAN}); }).find("RigidMass::box: half.z (m)"), std::string::npos);
  EXPECT_NE(error_of([] { RigidMass::sphere(1, NAN); }).find("RigidMass::sphere: r (m)"), std::string::npos);
  EXPECT_EQ(error_of([] { RigidMass::sphere(0, 1); }), "RigidMass::sphere: mass (kg): must be finite and > 0, got 0");
  EXPECT_NEAR(RigidMass::sphere(2, 0.5).inertia[1][1], 0.2, 1e-15);  // 2/5 m r^2
}

// A given centre of mass is a position in the body frame like a shape's local one: beyond the
// float range it was taken, and the first step made the body's angular velocity NaN (the
// contact rows' lever arms are floats); now refused at create, by name.
TEST(RigidBadInput, AGivenCentreOfMassOutsideTheFloatRangeIsRefusedByName) {
  RigidBodySystem s;
  s.create({.type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
  const std::vector<pba::RigidShapeDef> ball{{.shape = pba::ColliderShape::sphere(0.5)}};
  for (double c : {1e39, -1e300}) {
    RigidMass m = RigidMass::sphere(1, 0.5);
    m.center = {c, 0, 0};
    const std::string e = error_of([&] {
      s.create({.name = "ball", .pose = {{0, 0.4, 0}}, .shapes = ball, .mass = m});
    });
    EXPECT_NE(e.find("'ball'.mass.center: must fit a float"), std::string::npos) << e;
  }
  EXPECT_EQ(s.size(), 1u);
  // within the range it is taken (an off-centre ball), and it steps
  RigidMass m = RigidMass::sphere(1, 0.5);
  m.center = {0.2, 0, 0};
  const auto b = s.create({.name = "ball", .pose = {{0, 0.4, 0}}, .shapes = ball, .mass = m});
  for (int i = 0; i < 30; ++i) s.step(1.0 / 60, kG);
  EXPECT_TRUE(std::isfinite(s.pose(b).position.y));
}

// A given centre of mass 1e20 m from a 0.5 m ball was within the float range and taken; the
// first step then stopped naming the body as non-finite (the contact rows square the lever
// arms). A centre outside the shapes is legal (a hollow body, a ballast left out of the
// shapes) but not beyond kMaxCenterOfMassOffset of their sizes: refused at create, by name.
TEST(RigidBadInput, AGivenCentreOfMassFarOutsideTheShapesIsRefusedByName) {
  RigidBodySystem s;
  s.create({.type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
  const std::vector<pba::RigidShapeDef> ball{{.shape = pba::ColliderShape::sphere(0.5)}};
  for (double c : {1e20, -1e3, 18.0}) {
    RigidMass m = RigidMass::sphere(1, 0.5);
    m.center = {0, c, 0};
    const std::string e = error_of([&] {
      s.create({.name = "ball", .pose = {{0, 0.4, 0}}, .shapes = ball, .mass = m});
    });
    EXPECT_NE(e.find("'ball'.mass.center: (0, " + pba::format_value(c) + ", 0) m lies"), std::string::npos) << e;
    EXPECT_NE(e.find("at most 10 times their size"), std::string::npos) << e;
  }
  EXPECT_EQ(s.size(), 1u);
  // within ten sizes (the ball's bounds' diagonal is 1.73 m: up to 17.8 m beyond them) it is taken and steps
  RigidMass m = RigidMass::sphere(1, 0.5);
  m.center = {0, 15, 0};
  const auto b = s.create({.name = "ball", .pose = {{0, 0.4, 0}}, .shapes = ball, .mass = m});
  for (int i = 0; i < 30; ++i) s.step(1.0 / 60, kG);
  EXPECT_TRUE(std::isfinite(s.pose(b).position.y));
}

// A body type outside the enum (a cast from a bad integer, a corrupt save) was taken: the body
// was neither static, kinematic nor dynamic, type() said "unknown" and mass() infinity. It is
// refused like an unknown shape type or solver.
TEST(RigidBadInput, AnUnknownBodyTypeIsRefusedByName) {
  RigidBodySystem s;
  const std::string e =
      error_of([&] { s.create({.name = "odd", .type = static_cast<BodyType>(7), .shapes = kBall}); });
  EXPECT_NE(e.find("'odd'.type: unknown body type 7"), std::string::npos) << e;
  EXPECT_EQ(s.size(), 0u);
}

// Soft contacts scale with the body's mass (impulses are effective mass times a velocity
// change), so a box dropped on a plane falls and settles the same way at any mass: at the
// two ends of the accepted range it follows the 1 kg box to float rounding of its masses.
TEST(RigidMassRange, ABoxSettlesTheSameAtTheEndsOfTheMassRange) {
  auto run = [](double m) {
    RigidBodySystem s;
    s.create({.type = BodyType::Static,
              .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0), .material = {.friction = 0.5}}}});
    const double ixx = m * (0.25 * 0.25 + 0.5 * 0.5) / 3, iyy = m * (0.5 * 0.5 + 0.5 * 0.5) / 3;
    Mat3 inertia(0.0);
    inertia[0][0] = ixx, inertia[1][1] = iyy, inertia[2][2] = ixx;
    const auto b =
        s.create({.pose = {{0, 0.6, 0}, glm::angleAxis(0.2, glm::normalize(Vec3(1, 0, 1)))},
                  .shapes = {{.shape = pba::ColliderShape::box({0.5, 0.25, 0.5}), .material = {.friction = 0.5}}},
                  .mass = RigidMass{m, Vec3(0), inertia}});
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kG);
    return s.pose(b);
  };
  const pba::Pose one = run(1);
  EXPECT_NEAR(one.position.y, 0.25, 0.01);  // it landed on a face
  for (double m : {1e-30, 8e37}) {
    const pba::Pose p = run(m);
    EXPECT_LT(glm::length(p.position - one.position), 1e-5) << m;
    EXPECT_LT(std::abs(std::abs(glm::dot(p.rotation, one.rotation)) - 1), 1e-9) << m;
  }
}

// A compound inside a compound is flattened to its leaves at the composed poses (it used to
// stay a compound, which the narrow phase has no pair for: "no narrow phase for the pair
// compound-plane" at the first contact). The nested body moves exactly as one made of the
// leaves at those poses.
TEST(RigidCompound, ANestedCompoundMovesAsItsLeavesAtTheComposedPoses) {
  const Quat turn = glm::angleAxis(0.4, Vec3(0, 0, 1));
  auto inner = pba::CompoundShape::build({{pba::ColliderShape::box({0.3, 0.1, 0.2}), {{0.2, 0, 0}}},
                                          {pba::ColliderShape::sphere(0.15), {{-0.3, 0, 0}}}});
  auto outer = pba::CompoundShape::build(
      {{pba::ColliderShape{.type = pba::ShapeType::Compound, .compound = inner}, {{0, 0.1, 0}, turn}},
       {pba::ColliderShape::capsule(0.2, 0.05), {{0, -0.2, 0.3}}}});
  const pba::ColliderShape nested{.type = pba::ShapeType::Compound, .compound = outer};
  const pba::Pose in{{0, 0.1, 0}, turn};
  const std::vector<pba::RigidShapeDef> leaves{
      {.shape = pba::ColliderShape::box({0.3, 0.1, 0.2}), .local = pba::compose(in, {{0.2, 0, 0}})},
      {.shape = pba::ColliderShape::sphere(0.15), .local = pba::compose(in, {{-0.3, 0, 0}})},
      {.shape = pba::ColliderShape::capsule(0.2, 0.05), .local = {{0, -0.2, 0.3}}}};
  // and a table top (a 2 x 0.2 x 2 m box at y = 0.5) as static geometry, nested the same way,
  // that a ball lands on
  auto top = pba::CompoundShape::build({{pba::ColliderShape::box({1, 0.1, 1}), {{0, 0.3, 0}}}});
  auto table = pba::CompoundShape::build(
      {{pba::ColliderShape{.type = pba::ShapeType::Compound, .compound = top}, {{0, 0.2, 0}}}});
  const std::vector<pba::RigidShapeDef> nested_table{
      {.shape = pba::ColliderShape{.type = pba::ShapeType::Compound, .compound = table}}};
  const std::vector<pba::RigidShapeDef> flat_table{
      {.shape = pba::ColliderShape::box({1, 0.1, 1}), .local = {{0, 0.5, 0}}}};
  auto run = [](const std::vector<pba::RigidShapeDef>& shapes, const std::vector<pba::RigidShapeDef>& fixed) {
    RigidBodySystem s;
    s.create({.type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
    const auto b = s.create({.pose = {{0, 1, 0}}, .angular_velocity = {0.5, 0, 0.3}, .shapes = shapes});
    s.create({.type = BodyType::Static, .pose = {{3, 0, 0}}, .shapes = fixed});
    const auto ball = s.create({.pose = {{3, 1.5, 0}}, .shapes = {{.shape = pba::ColliderShape::sphere(0.1)}}});
    for (int i = 0; i < 90; ++i) s.step(1.0 / 60, kG);
    return std::pair{s.pose(b), s.pose(ball)};
  };
  const auto [a, ball_a] = run({{.shape = nested}}, nested_table);
  const auto [b, ball_b] = run(leaves, flat_table);
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.rotation, b.rotation);
  EXPECT_EQ(ball_a.position, ball_b.position);
  EXPECT_LT(a.position.y, 0.5);                    // it fell and landed
  EXPECT_NEAR(ball_a.position.y, 0.7, 0.01);       // the ball rests on the table top (0.6) by its radius
}

// The body reaches non-finite here by its position only (a finite velocity for an overflowing
// time); a velocity that overflows is RigidDivergence.AnOverflowingVelocityIsReportedNonFinite.
TEST(RigidDivergence, ANonFiniteBodyStopsTheSystemWithItsNameAndTime) {
  RigidBodySystem s({.contacts = {.substeps = 1}});
  s.create({.name = "calm", .pose = {{0.5, 0, 0}}, .shapes = kBall});  // close: a speculative pair
  auto wild = s.create({.name = "wild", .shapes = kBall});
  s.step(0.5, kG);
  // at the speed limit for 1e300 s the position overflows to infinity (a force summing to
  // infinity did this until apply_force refused such a sum: RigidParamsBadInput)
  s.set_velocity(wild, {pba::kMaxRigidSpeed, 0, 0}, Vec3(0));
  const std::string m = error_of([&] { s.step(1e300, Vec3(0)); });
  EXPECT_NE(m.find("rigid body 1 'wild' became non-finite in the step to t = 1e+300 s"), std::string::npos) << m;
  EXPECT_EQ(error_of([&] { s.step(0.5, kG); }), m);  // and refuses to go on
  EXPECT_EQ(s.failed_body(), wild);
}

// gravity times a step that overflows gives an infinite velocity: the step stops the system
// with the body's name, "became non-finite" (not "went faster": infinity is no speed), and its
// velocity
TEST(RigidDivergence, AnOverflowingVelocityIsReportedNonFinite) {
  RigidBodySystem s({.contacts = {.substeps = 1}});
  const auto b = s.create({.name = "stone", .shapes = kBall});
  const std::string m = error_of([&] { s.step(1e300, Vec3(0, -1e10, 0)); });
  EXPECT_NE(m.find("rigid body 0 'stone' became non-finite in the step to t = 1e+300 s"), std::string::npos) << m;
  EXPECT_NE(m.find("velocity (0, -inf, 0)"), std::string::npos) << m;
  EXPECT_EQ(s.failed_body(), b);
}

namespace {
// `test` (path, numbers, count) holds for arrays of 0 to 41 of `good` (a group of 16 lanes,
// two, and the rest past them), on the plain path and on AVX2, and fails with any one of them
// made any of `bad`
template <class Test>
void expect_every_bad_number_found(Test test, const std::vector<double>& good, const std::vector<double>& bad) {
  using pba::detail::SimdPath;
  std::vector<SimdPath> paths{SimdPath::Scalar};
  if (pba::detail::best_simd_path() != SimdPath::Scalar) paths.push_back(SimdPath::Avx2);  // (x86 with AVX2)
  for (const SimdPath path : paths)
    for (std::size_t count = 0; count <= 41; ++count) {
      std::vector<double> x(count);
      for (std::size_t i = 0; i < count; ++i) x[i] = good[i % good.size()];
      EXPECT_TRUE(test(path, x.data(), count)) << count;
      for (std::size_t i = 0; i < count; ++i)
        for (const double b : bad) {
          const double was = x[i];
          x[i] = b;
          EXPECT_FALSE(test(path, x.data(), count)) << count << " " << i << " " << b;
          x[i] = was;
        }
    }
}
}  // namespace

// check_finite's test of the bodies' centres, velocities and frames as flat arrays: every
// infinite or NaN number is found at every place (the lanes' groups of 16 and the rest past
// them, on the plain path and on AVX2), and no finite one is taken for it, however large or
// small (the step's own guards stop most non-finite states first, so the system rarely gets
// there: the test is of the arrays' scan itself).
TEST(RigidDivergence, TheFlatFiniteTestFindsEveryNonFiniteNumberWhereverItIs) {
  const double big = std::numeric_limits<double>::max(), tiny = std::numeric_limits<double>::denorm_min();
  expect_every_bad_number_found(pba::detail::all_finite_wide, {0.0, -0.0, 1.0, -2.5, big, -big, tiny, -tiny, 1e-300, 6.02e23},
                                {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                                 std::numeric_limits<double>::quiet_NaN(), -std::numeric_limits<double>::quiet_NaN()});
}

// check_finite's range test of the centres over the same lanes: -limit <= x <= limit for every
// number (the limit itself passes; the next double beyond it, an infinity or a NaN anywhere
// fails).
TEST(RigidDivergence, TheFlatRangeTestFindsEveryNumberBeyondTheLimitWhereverItIs) {
  const double limit = 3e38, over = std::nextafter(limit, INFINITY);
  auto within = [&](pba::detail::SimdPath path, const double* p, std::size_t count) {
    return pba::detail::all_within_wide(path, p, count, limit);
  };
  expect_every_bad_number_found(within, {0.0, -0.0, 1.0, -2.5, limit, -limit, 1e-300, 6.02e23},
                                {over, -over, 1e300, std::numeric_limits<double>::infinity(),
                                 -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()});
}

// check_finite's call sites: the arrays it scans (the centres, velocities and angular
// velocities, 3 numbers a body, and the frames, 4) and their counts. A NaN or an infinity in
// any number of any of 7 bodies (21 and 28 numbers: a group of 16 and the rest) stops the
// system naming that body; with none, it passes.
TEST(RigidDivergence, CheckFiniteNamesTheBodyOfANonFiniteNumberInEachArray) {
  const int sizes[] = {3, 3, 3, 4};
  for (int which = 0; which < 4; ++which)
    for (std::size_t i = 0; i < 7; ++i)
      for (int c = 0; c < sizes[which]; ++c)
        for (const double bad : {std::numeric_limits<double>::quiet_NaN(), -std::numeric_limits<double>::infinity()}) {
          RigidBodySystem s;
          std::vector<pba::RigidBodyId> ids;
          for (int k = 0; k < 7; ++k)
            ids.push_back(s.create({.name = "b" + std::to_string(k), .pose = {{3.0 * k, 1, 0}}, .shapes = kBall}));
          s.step(1.0 / 60, kG);
          const std::string m = error_of([&] { pba::detail::RigidContacts::poison_and_check(s, which, i, c, bad); });
          const std::string name = "rigid body " + std::to_string(i) + " 'b" + std::to_string(i) + "' became non-finite";
          EXPECT_EQ(m.rfind(name, 0), 0u) << which << " " << i << " " << c << ": " << m;
          EXPECT_EQ(s.failed_body(), ids[i]);
        }
  RigidBodySystem s;
  for (int k = 0; k < 7; ++k) s.create({.pose = {{3.0 * k, 1, 0}}, .shapes = kBall});
  pba::detail::RigidContacts::poison_and_check(s, 0, 6, 2, 3.4e38);  // large, in the float range: passes
  EXPECT_TRUE(s.failed_body().is_null());
  // a centre finite but past the float range (the colliders') stops it too, naming the body
  const std::string m = error_of([&] { pba::detail::RigidContacts::poison_and_check(s, 0, 6, 2, 1e308); });
  EXPECT_EQ(m.rfind("rigid body 6 left the float range", 0), 0u) << m;
}

// check_finite tested finiteness only: a body a step carried past a float's range went on
// (two balls out at 1e39 m then passed through each other without a word; boxes stopped with
// the narrow phase's message, naming no body). Now the step stops naming the body, when its
// centre or one of its shapes' frames has left the range; up to its edge it steps on.
TEST(RigidDivergence, ABodyCarriedPastTheFloatRangeStopsTheSystemNamingIt) {
  {
    RigidBodySystem s;
    const auto a = s.create({.name = "a", .linear_velocity = {1e17, 0, 0}, .shapes = kBall});
    s.create({.name = "b", .pose = {{0, 3, 0}}, .linear_velocity = {1e17, 0, 0}, .shapes = kBall});
    const std::string m = error_of([&] { s.step(1e22, Vec3(0)); });
    EXPECT_EQ(m.rfind("rigid body 0 'a' left the float range (a position's |component| <= 3.4028234663852886e+38 m", 0),
              0u)
        << m;
    EXPECT_NE(m.find("in the step to t = 1e+22 s: position (1e+39, 0, 0)"), std::string::npos) << m;
    EXPECT_EQ(s.failed_body(), a);
  }
  {
    // the centre in the range, a shape's frame 1e38 m from it not: two balls at +-1e38 m
    // about a given centre of mass, carried from 2e38 m to 3e38 m
    RigidBodySystem s;
    s.create({.name = "still", .shapes = kBall});
    const auto pair = s.create({.name = "dumbbell", .pose = {{2e38, 0, 0}}, .linear_velocity = {1e17, 0, 0},
                                .shapes = {{.shape = pba::ColliderShape::sphere(0.5), .local = {{1e38, 0, 0}}},
                                           {.shape = pba::ColliderShape::sphere(0.5), .local = {{-1e38, 0, 0}}}},
                                .mass = RigidMass{}});
    const std::string m = error_of([&] { s.step(1e21, Vec3(0)); });
    EXPECT_EQ(m.rfind("rigid body 1 'dumbbell' left the float range", 0), 0u) << m;
    EXPECT_NE(m.find("in the step to t = 1e+21 s: position (2.9999999999999997e+38, 0, 0)"), std::string::npos) << m;
    EXPECT_EQ(s.failed_body(), pair);
  }
  {
    // to the edge: a ball carried to 3.4e38 m steps on
    RigidBodySystem s;
    const auto a = s.create({.name = "a", .linear_velocity = {1e17, 0, 0}, .shapes = kBall});
    s.step(3.4e21, Vec3(0));
    EXPECT_EQ(s.pose(a).position.x, 3.4e38);
    s.step(1.0 / 60, kG);
    EXPECT_TRUE(s.failed_body().is_null());
  }
}

// Speeds beyond kMaxRigidSpeed would overflow the contacts' float rows and poison the bodies
// a fast one touches: refused where they are given, naming the value and where it came from.
TEST(RigidDivergence, VelocitiesBeyondTheSpeedLimitAreRefusedWhereTheyAreGiven) {
  RigidBodySystem s;
  const double over = 2 * pba::kMaxRigidSpeed;
  RigidBodyDef d{.name = "comet", .linear_velocity = {over, 0, 0}, .shapes = kBall};
  std::string m = error_of([&] { s.create(d); });
  EXPECT_NE(m.find("linear_velocity"), std::string::npos) << m;
  EXPECT_NE(m.find("above the rigid bodies' limit of 1e+18 m/s"), std::string::npos) << m;
  d.linear_velocity = {0, 0, 0}, d.angular_velocity = {0, 0, -over};
  m = error_of([&] { s.create(d); });
  EXPECT_NE(m.find("angular_velocity"), std::string::npos) << m;
  EXPECT_NE(m.find("rad/s"), std::string::npos) << m;
  // at the limit itself a body is accepted, and moves
  d.angular_velocity = {0, 0, 0}, d.linear_velocity = {pba::kMaxRigidSpeed, 0, 0};
  const auto b = s.create(d);
  m = error_of([&] { s.set_velocity(b, {0, over, 0}, {0, 0, 0}); });
  EXPECT_NE(m.find("rigid body 0 'comet' set_velocity linear"), std::string::npos) << m;
  // an impulse is checked by the velocity it gives (1 kg m/s too many on the limit), and
  // leaves the body as it was when refused
  const double mass = s.mass(b);
  m = error_of([&] { s.apply_impulse(b, {0.5 * pba::kMaxRigidSpeed * mass, 0, 0}, s.pose(b).position); });
  EXPECT_NE(m.find("apply_impulse: the linear velocity it gives"), std::string::npos) << m;
  m = error_of([&] { s.apply_angular_impulse(b, {0, over * 10, 0}); });
  EXPECT_NE(m.find("apply_angular_impulse"), std::string::npos) << m;
  EXPECT_EQ(s.linear_velocity(b), Vec3(pba::kMaxRigidSpeed, 0, 0));
  EXPECT_EQ(s.angular_velocity(b), Vec3(0, 0, 0));
  s.step(1.0 / 60, kG);
  EXPECT_NEAR(s.pose(b).position.x, pba::kMaxRigidSpeed / 60, 1e6);
}

// The contact rows square relative speeds in float (3.4e38 at most, so 1.8e19 m/s): a box
// sliding on the ground at 2e19 m/s, or spun at 3e19 rad/s against another, both within the
// limit of 1e20 it had, turned non-finite in its first step of contact under the soft step,
// sequential impulses and TGS. At the limit now (1e18 m/s and rad/s), a box sliding on the
// ground, spinning about the vertical, a ball rolling, a box spinning against a resting one and
// two boxes sliding and spinning past each other stay finite under every solver; two 16 m bars
// doing so (the reach the limit's comment allows) stay finite too, or their impact throws one
// past the limit and the step stops naming it (a review found the 8 m reach untested).
TEST(RigidDivergence, BodiesInContactAtTheSpeedLimitStayFinite) {
  const double top = pba::kMaxRigidSpeed;
  const pba::ColliderShape cube = pba::ColliderShape::box({0.5, 0.5, 0.5});
  for (const pba::RigidSolverType solver : pba::kRigidSolvers)
    for (int mode = 0; mode < 6; ++mode) {
      RigidBodySystem s({.contacts = {.solver = solver}});
      s.create({.type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
      RigidBodyDef a{.name = "a", .pose = {{0, 0.5, 0}}, .shapes = {{.shape = cube}}};
      RigidBodyDef b{.name = "b", .pose = {{1, 0.5, 0}}, .shapes = {{.shape = cube}}};
      if (mode == 0) a.linear_velocity = {0, 0, top};  // sliding along b's face
      if (mode == 1) a.angular_velocity = {0, top, 0};  // spinning on the ground, its corners in b
      if (mode == 2) a.shapes = {{.shape = pba::ColliderShape::sphere(0.5)}}, a.angular_velocity = {0, 0, top};
      if (mode == 3) a.angular_velocity = {top, 0, 0};  // tumbling against b
      if (mode == 4) {
        a.linear_velocity = {0, 0, top}, a.angular_velocity = {0, top, 0};
        b.linear_velocity = {0, 0, -top}, b.angular_velocity = {0, -top, 0};
      }
      if (mode == 5) {
        // the reach kMaxRigidSpeed's comment allows: two bars reaching 7.93 m from their centres
        // side by side, each at the limit in both speeds the other way, their ends meeting at
        // |v| + |w| r = 8.9e18 m/s each (the relative speed squared 3.2e38, under float's 3.4e38)
        const pba::ColliderShape bar = pba::ColliderShape::box({7.9, 0.5, 0.5});
        a.shapes = b.shapes = {{.shape = bar}};
        b.pose.position = {0, 0.5, 1};
        a.linear_velocity = {0, 0, top}, a.angular_velocity = {0, top, 0};
        b.linear_velocity = {0, 0, -top}, b.angular_velocity = {0, -top, 0};
      }
      const auto ia = s.create(a), ib = s.create(b);
      const std::string what = std::string(to_string(solver)) + " case " + std::to_string(mode);
      for (int i = 0; i < 3; ++i) {
        const std::string m = error_of([&] { s.step(1.0 / 60, kG); });
        // the bars' impact may throw one past the limit (an end's speed turned into the
        // centre's): then the step stops naming it, every state still finite
        if (mode == 5 && !m.empty()) {
          EXPECT_NE(m.find("went faster than kMaxRigidSpeed"), std::string::npos) << what << ": " << m;
          break;
        }
        EXPECT_EQ(m, "") << what << " step " << i;
      }
      for (const auto id : {ia, ib}) {
        EXPECT_TRUE(pba::is_finite(s.center_of_mass(id))) << what;
        EXPECT_TRUE(pba::is_finite(s.linear_velocity(id))) << what;
        EXPECT_TRUE(pba::is_finite(s.angular_velocity(id))) << what;
      }
    }
}

// A force that takes a body past the limit stops the step before the contacts run, so the
// body it touches stays finite and the message names the forced body, not its neighbour
// (before, a box at 1e40 m/s turned its resting neighbour to NaN, and the neighbour was named).
TEST(RigidDivergence, AForceBeyondTheSpeedLimitStopsTheStepNamingTheForcedBody) {
  RigidBodySystem s;
  s.create({.type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
  const auto calm = s.create({.name = "calm", .pose = {{0, 0.5, 0}}, .shapes = kBox});
  const auto pushed = s.create({.name = "pushed", .pose = {{0, 1.5, 0}}, .shapes = kBox});
  for (int i = 0; i < 10; ++i) s.step(1.0 / 60, kG);
  s.apply_force(pushed, {1e30 * s.mass(pushed), 0, 0});  // 1e30 m/s^2 for 1/60 s: 1.7e28 m/s
  const std::string m = error_of([&] { s.step(1.0 / 60, kG); });
  EXPECT_NE(m.find("rigid body 2 'pushed' went faster than kMaxRigidSpeed"), std::string::npos) << m;
  EXPECT_EQ(s.failed_body(), pushed);
  EXPECT_TRUE(pba::is_finite(s.pose(calm).position));
  EXPECT_TRUE(pba::is_finite(s.linear_velocity(calm)));
}

// What takes a body past the limit in a step is not always a force: a gravity_scale of 1e300,
// or a step of 1e300 s under plain gravity, were both reported as "a force too large for the
// contacts' float rows". The message names each cause it may be.
TEST(RigidDivergence, TheSpeedLimitsMessageNamesGravityAndTheTimeStepToo) {
  RigidBodySystem scaled;
  scaled.create({.name = "heavy", .shapes = kBall, .gravity_scale = 1e300});
  std::string m = error_of([&] { scaled.step(1.0 / 60, kG); });
  EXPECT_NE(m.find("'heavy' went faster than kMaxRigidSpeed"), std::string::npos) << m;
  EXPECT_NE(m.find("the gravity times the body's gravity_scale"), std::string::npos) << m;
  RigidBodySystem slow;
  slow.create({.name = "slow", .shapes = kBall});
  m = error_of([&] { slow.step(1e300, kG); });
  EXPECT_NE(m.find("'slow' went faster than kMaxRigidSpeed"), std::string::npos) << m;
  EXPECT_NE(m.find("or the time step too large"), std::string::npos) << m;
}

// The soft step keeps the moving bodies' centres and frames in the free motion's lanes over
// its substeps (integrate_wide.cpp) and puts them back at the end: a body that passes the
// speed limit in its second substep is reported, and left, where its first substep took it,
// not where the step began. A force of a = 0.75 limit / h from rest: after the first substep
// v = h a (0.75 of the limit) and x = h v; the second's 1.5 of the limit stops the step.
TEST(RigidDivergence, ABodyPastTheSpeedLimitInALaterSubstepIsLeftWhereItGot) {
  RigidBodySystem s({.contacts = {.substeps = 8, .auto_substeps = false}});
  const auto b = s.create({.name = "rocket", .shapes = kBall});
  const double h = 1.0 / 60 / 8, a = 0.75 * pba::kMaxRigidSpeed / h;
  s.apply_force(b, {a * s.mass(b), 0, 0});
  const std::string m = error_of([&] { s.step(1.0 / 60, kG); });
  EXPECT_NE(m.find("'rocket' went faster than kMaxRigidSpeed"), std::string::npos) << m;
  // (to the products' rounding: a few ulps of each)
  const double x = h * (h * a);
  EXPECT_NEAR(s.pose(b).position.x, x, 1e-14 * x);
  EXPECT_NEAR(s.linear_velocity(b).x, 2 * h * a, 1e-14 * h * a);
}

// The same with the body in a vector block of a triaxial kind's list: 16 boxes of half extents
// 0.3, 0.2, 0.4 m (three different moments), 2 m apart in the air, the force on the 14th (lane
// 5 of the second block of 8; on AVX-512 a lane of the double block), on every SIMD path. The
// message names it and the step's end time; it is left where its first substep took it, and
// every other box where its first substep of free fall did, y = y0 - h (h g) (the lanes'
// centres all put back).
TEST(RigidDivergence, ABodyPastTheSpeedLimitInATriaxialBlockIsNamedAndLeftWhereItGot) {
  for (const pba::RigidSimd path : {pba::RigidSimd::Scalar, pba::RigidSimd::Avx2, pba::RigidSimd::Avx512}) {
    RigidBodySystem s({.contacts = {.substeps = 8, .auto_substeps = false}});
    if (!error_of([&] { s.set_simd(path); }).empty()) continue;  // (a path this CPU lacks)
    std::vector<pba::RigidBodyId> boxes;
    for (int i = 0; i < 16; ++i)
      boxes.push_back(s.create({.name = "box" + std::to_string(i), .pose = {{2.0 * i, 5, 0}},
                                .shapes = {{.shape = pba::ColliderShape::box({0.3, 0.2, 0.4})}}}));
    const double h = 1.0 / 60 / 8, a = 0.75 * pba::kMaxRigidSpeed / h;
    s.apply_force(boxes[13], {a * s.mass(boxes[13]), 0, 0});
    const std::string m = error_of([&] { s.step(1.0 / 60, kG); });
    const std::string what = std::string(to_string(path)) + ": " + m;
    EXPECT_NE(m.find("rigid body 13 'box13' went faster than kMaxRigidSpeed"), std::string::npos) << what;
    EXPECT_NE(m.find("in the step to t = " + pba::format_value(1.0 / 60) + " s"), std::string::npos) << what;
    EXPECT_EQ(s.failed_body(), boxes[13]) << what;
    const double x = h * (h * a);
    EXPECT_NEAR(s.pose(boxes[13]).position.x - 26, x, 1e-14 * x) << what;
    for (int i = 0; i < 16; ++i) {
      if (i == 13) continue;
      EXPECT_NEAR(s.pose(boxes[i]).position.y, 5 - h * (h * 9.81), 1e-14) << what << " box " << i;
    }
  }
}

// The same for bodies the contact lanes hold (the soft step's velocities by rows on AVX2 without
// a torque or damping, integrate_wide.cpp's velocities_rows, whose test passes every component
// within half the limit and leaves the rest to the exact one): 16 triaxial boxes resting on the
// ground (warm starts in their rows), a force on the 14th giving it a = f / m with f = 0.75 or
// 1.5 of the limit times m / dt. Its speed after substep k is k h a (k/8 of that), past half
// the limit from the 6th substep: at 0.75 the step passes and the box leaves at 0.75 of the
// limit (friction and the contacts take under 1 m/s off it), the same bits on every path; at
// 1.5 the 6th substep stops it, naming the box.
TEST(RigidDivergence, ABodyInContactPastHalfTheSpeedLimitPassesAndPastItIsNamed) {
  // (both directions: the AVX2 rows' quick test is on each component's magnitude)
  for (const double over : {0.75, 1.5, -0.75, -1.5}) {
    std::uint64_t first = 0;
    for (const pba::RigidSimd path : {pba::RigidSimd::Scalar, pba::RigidSimd::Avx2, pba::RigidSimd::Avx512}) {
      RigidBodySystem s({.contacts = {.substeps = 8, .auto_substeps = false, .sleep = false}});
      if (!error_of([&] { s.set_simd(path); }).empty()) continue;  // (a path this CPU lacks)
      s.create({.type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
      std::vector<pba::RigidBodyId> boxes;
      for (int i = 0; i < 16; ++i)
        boxes.push_back(s.create({.name = "box" + std::to_string(i), .pose = {{1.0 * i, 0.2, 0}},
                                  .shapes = {{.shape = pba::ColliderShape::box({0.3, 0.2, 0.4})}}}));
      for (int i = 0; i < 20; ++i) s.step(1.0 / 60, kG);
      const pba::RigidBodyId b = boxes[13];
      s.apply_force(b, {over * pba::kMaxRigidSpeed * 60 * s.mass(b), 0, 0});
      const std::string m = error_of([&] { s.step(1.0 / 60, kG); });
      const std::string what = std::string(to_string(path)) + " at " + std::to_string(over) + ": " + m;
      if (std::abs(over) > 1) {
        EXPECT_NE(m.find("rigid body 14 'box13' went faster than kMaxRigidSpeed"), std::string::npos) << what;
        EXPECT_EQ(s.failed_body(), b) << what;
        continue;
      }
      EXPECT_EQ(m, "") << what;
      EXPECT_NEAR(s.linear_velocity(b).x, over * pba::kMaxRigidSpeed, 1.0) << what;
      for (const pba::RigidBodyId id : boxes) {
        EXPECT_TRUE(pba::is_finite(s.linear_velocity(id))) << what;
        EXPECT_TRUE(pba::is_finite(s.angular_velocity(id))) << what;
      }
      if (path == pba::RigidSimd::Scalar) first = s.hash();
      EXPECT_EQ(s.hash(), first) << what;
    }
  }
}

// Nearly round boxes (half sizes 0.2, 0.2, 0.2006: their inertia's spread between kInertiaTurn
// / 4 and kInertiaTurn / sqrt(8)) spinning at 100 and 300 rad/s about y on the ground turn past
// 180 degrees within a step at 300: the test for a turn far enough to refresh the inverse
// inertia takes |q . q_ref|, on every path alike (the AVX2 path's mask once kept the sign, and
// refreshed where the scalar path did not), so every path gives the same bits.
TEST(RigidSimd, NearlyRoundBoxesSpinningPastAHalfTurnAStepGiveTheSameBitsOnEveryPath) {
  for (const double spin : {100.0, 300.0}) {
    std::uint64_t first = 0;
    for (const pba::RigidSimd path : {pba::RigidSimd::Scalar, pba::RigidSimd::Avx2, pba::RigidSimd::Avx512}) {
      RigidBodySystem s({.contacts = {.substeps = 8, .auto_substeps = false, .sleep = false}});
      if (!error_of([&] { s.set_simd(path); }).empty()) continue;  // (a path this CPU lacks)
      s.create({.type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
      for (int i = 0; i < 8; ++i) {
        const pba::RigidBodyId b =
            s.create({.pose = {{1.0 * i, 0.2, 0}}, .shapes = {{.shape = pba::ColliderShape::box({0.2, 0.2, 0.2006})}}});
        s.set_velocity(b, {0, 0, 0}, {0, spin, 0});
      }
      for (int i = 0; i < 30; ++i) s.step(1.0 / 60, kG);
      if (path == pba::RigidSimd::Scalar) first = s.hash();
      EXPECT_EQ(s.hash(), first) << to_string(path) << " at " << spin << " rad/s";
    }
  }
}

// A pile of tumbling boxes and balls on the ground, and a free-flying T-handle: the same
// inputs give the same bits, and each solver's hash is pinned (glibc's sin/cos,
// -ffp-contract=off; a change of these numbers is a change of behaviour).
std::uint64_t pile_hash(pba::RigidSolverType solver) {
  RigidBodySystem s({.contacts = {.solver = solver}});
  s.create({.type = BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
  for (int i = 0; i < 27; ++i) {
    const Vec3 p{(i % 3) * 1.1, 0.6 + (i / 9) * 1.2, ((i / 3) % 3) * 1.1};
    const pba::ColliderShape shape =
        i % 2 ? pba::ColliderShape::sphere(0.45) : pba::ColliderShape::box({0.45, 0.3, 0.4});
    s.create({.pose = {p, glm::angleAxis(0.3 * i, glm::normalize(Vec3(1, 2, 3)))},
              .angular_velocity = {0.1 * i, 0, 0.2}, .shapes = {{.shape = shape, .material = {.restitution = 0.2}}}});
  }
  s.create({.pose = {{0, 10, 0}}, .angular_velocity = {0.1, 10, 0.2}, .shapes = kBall, .mass = t_handle()});
  for (int i = 0; i < 240; ++i) s.step(1.0 / 60, kG);
  return s.hash();
}

TEST(RigidDeterminism, SameInputsSameBitsPinnedPerSolver) {
  const std::uint64_t soft = pile_hash(pba::RigidSolverType::SoftStep);
  const std::uint64_t si = pile_hash(pba::RigidSolverType::SequentialImpulse);
  const std::uint64_t tgs = pile_hash(pba::RigidSolverType::Tgs);
  const std::uint64_t xpbd = pile_hash(pba::RigidSolverType::Xpbd);
  EXPECT_EQ(soft, pile_hash(pba::RigidSolverType::SoftStep));
  EXPECT_EQ(si, pile_hash(pba::RigidSolverType::SequentialImpulse));
  EXPECT_EQ(tgs, pile_hash(pba::RigidSolverType::Tgs));
  EXPECT_EQ(xpbd, pile_hash(pba::RigidSolverType::Xpbd));
  EXPECT_NE(soft, si);
  EXPECT_NE(soft, tgs);
  EXPECT_NE(soft, xpbd);
  EXPECT_NE(tgs, xpbd);
  EXPECT_EQ(soft, 0x02b3ea33af8fd58aull) << std::hex << soft;
  EXPECT_EQ(si, 0xa79c906b21f6e86cull) << std::hex << si;
  EXPECT_EQ(tgs, 0x28634e1bc006c629ull) << std::hex << tgs;
  EXPECT_EQ(xpbd, 0x0f10f3b5996d53fcull) << std::hex << xpbd;
}

}  // namespace
