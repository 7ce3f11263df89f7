// Rigid bodies, continuous collision: fast bodies stop at static walls instead of passing
// through them, and the continuous pass leaves slow bodies alone.
#include <gtest/gtest.h>

#include <cmath>

#include "pba/rigid.h"
#include "closed_box_check.h"
#include "pba/rigid_scenes.h"

using pba::BodyType;
using pba::ColliderShape;
using pba::RigidBodySystem;
using pba::RigidSolverType;
using pba::Vec3;

namespace {

// 400 bodies in 10 m (the 5000 in 20 m run in the soak suite, soak_rigid.cpp)
TEST(RigidContinuous, BodiesAt250MetresPerSecondStayInAClosedBox) { pba::test::expect_none_escapes(400, 5); }

// A body flagged as a bullet, or simply fast, arrives at the wall touching it: at the first
// time of impact, within the linear slop of contact, not stopped short of it.
TEST(RigidContinuous, AFastBoxArrivesAtTheWallWithinTheSlop) {
  RigidBodySystem s;
  s.create({.name = "wall", .type = BodyType::Static, .pose = {{10, 0, 0}}, .shapes = {{.shape = ColliderShape::box({0.05, 2, 2})}}});
  const auto box = s.create({.name = "fast", .linear_velocity = {300, 0, 0}, .shapes = {{.shape = ColliderShape::box(Vec3(0.1))}}});
  // 5 m per step: the step from x = 5 would end at 10, past the face at 9.95; the box
  // stops with its face at 9.95 - slop (and the discrete contact holds it there after)
  double closest_gap = 1e9;
  for (int i = 0; i < 10; ++i) {
    s.step(1.0 / 60, Vec3(0));
    closest_gap = std::min(closest_gap, 9.95 - (s.center_of_mass(box).x + 0.1));
  }
  const double slop = s.settings().linear_slop;
  EXPECT_GE(closest_gap, -slop);  // never more than the slop into the wall
  EXPECT_LT(s.center_of_mass(box).x + 0.1, 9.95 + slop);
  EXPECT_GT(s.center_of_mass(box).x + 0.1, 9.95 - 2 * slop);  // and it got there
  EXPECT_LT(std::abs(s.linear_velocity(box).x), 1.0);  // stopped by the contact (e = 0)
}

// A box sliding fast along the ground (touching it all the way) is not stopped by the
// continuous pass: the ground is left to the discrete contact, and the box decelerates at
// mu g as Coulomb friction says.
TEST(RigidContinuous, AFastBoxSlidingOnTheGroundIsNotPaused) {
  RigidBodySystem s;
  pba::rigid_scenes::ground(s, 0.5);
  const auto box = pba::rigid_scenes::box(s, {0, 0.1, 0}, Vec3(0.1));
  s.set_velocity(box, {60, 0, 0}, Vec3(0));  // 1 m per step: ten times its half size
  const double t = 0.5;
  for (int i = 0; i < 30; ++i) s.step(1.0 / 60, Vec3(0, -9.81, 0));
  // x = v t - mu g t^2 / 2 (symplectic Euler's O(h) difference is v h / 2 = 0.5 m at most)
  const double expected = 60 * t - 0.5 * 0.5 * 9.81 * t * t;
  EXPECT_NEAR(s.center_of_mass(box).x, expected, 0.6);
  EXPECT_NEAR(s.linear_velocity(box).x, 60 - 0.5 * 9.81 * t, 0.05 * 60);
}

}  // namespace
