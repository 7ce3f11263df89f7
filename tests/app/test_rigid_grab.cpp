// The rigid samples' mouse grab (app/samples/rigid_common.h, RigidGrab) without a window: what
// a press picks, and what a drag and a release give the body.
#include <gtest/gtest.h>

#include <cmath>

#include "pba/rigid.h"
#include "samples/rigid_common.h"

namespace {

using pba::BodyType;
using pba::ColliderShape;
using pba::RigidBodyDef;
using pba::RigidBodyId;
using pba::RigidBodySystem;
using pba::Vec3;
using pba::app::RigidGrab;

RigidBodyId add_box(RigidBodySystem& s, BodyType type, const Vec3& at, const char* name) {
  RigidBodyDef d;
  d.name = name;
  d.type = type;
  d.pose.position = at;
  d.shapes = {{.shape = ColliderShape::box(Vec3(0.5))}};
  return s.create(d);
}

// A press on a static wall or a kinematic paddle grabs nothing, though a dynamic box lies
// behind it on the same ray (the cursor is on the wall; before, the box behind was pulled
// through the wall); a press on a dynamic box in front of the wall grabs that box.
TEST(RigidGrabPress, AShapeInFrontHidesTheBodiesBehindIt) {
  for (const BodyType front : {BodyType::Static, BodyType::Kinematic}) {
    SCOPED_TRACE(static_cast<int>(front));
    RigidBodySystem s;
    add_box(s, front, {0, 0, 0}, "wall");
    const RigidBodyId behind = add_box(s, BodyType::Dynamic, {3, 0, 0}, "behind");
    const RigidBodyId before = add_box(s, BodyType::Dynamic, {-3, 0, 2}, "before");
    RigidGrab g;
    EXPECT_FALSE(g.Press(s, {-10, 0, 0}, {1, 0, 0}));
    EXPECT_FALSE(g.held(s));
    EXPECT_EQ(g.grabs(), 0);
    // from the other side the box is in front
    EXPECT_TRUE(g.Press(s, {10, 0, 0}, {-1, 0, 0}));
    EXPECT_TRUE(g.held(s));
    g.Release();
    EXPECT_TRUE(g.Press(s, {-10, 0, 2}, {1, 0, 0}));
    EXPECT_EQ(g.grabs(), 2);
    (void)behind, (void)before;
  }
}

// A press on a box asleep on the ground wakes it, and it stays awake while held still.
TEST(RigidGrabPress, APressWakesASleepingBody) {
  RigidBodySystem s;
  add_box(s, BodyType::Static, {0, -0.5, 0}, "ground");
  const RigidBodyId b = add_box(s, BodyType::Dynamic, {0, 0.5, 0}, "box");
  for (int i = 0; i < 120; ++i) s.step(1.0 / 60, {0, -9.81, 0});
  ASSERT_FALSE(s.awake(b));
  RigidGrab g;
  ASSERT_TRUE(g.Press(s, {-10, 0.5, 0}, {1, 0, 0}));
  EXPECT_TRUE(s.awake(b));
  for (int i = 0; i < 120; ++i) {
    g.Apply(s);
    s.step(1.0 / 60, {0, -9.81, 0});
    EXPECT_TRUE(s.awake(b)) << i;
  }
}

// Dragged 1 km away at once, the grabbed box speeds up at most by the spring's cap (50 times
// its weight, 490.5 m/s^2 on its centre), and at that rate while the target is far: the throw
// is as fast as the cap allows and no faster (the cap is the only bound on a far drag; a
// faster cursor does not make it faster).
TEST(RigidGrabPress, AFarDragIsBoundByTheCap) {
  const double dt = 1.0 / 60;
  RigidBodySystem s2;
  const RigidBodyId b2 = add_box(s2, BodyType::Dynamic, {0, 0, 0}, "box");
  RigidGrab g2;
  ASSERT_TRUE(g2.Press(s2, {-10, 0, 0}, {1, 0, 0}));
  g2.Move(s2, {-10, 0, 1000}, {1, 0, 0});
  for (int i = 1; i <= 30; ++i) {
    g2.Apply(s2);
    s2.step(dt, {0, 0, 0});
    EXPECT_LE(glm::length(s2.linear_velocity(b2)), 50 * 9.81 * i * dt * (1 + 1e-9)) << i;
  }
  EXPECT_GT(glm::length(s2.linear_velocity(b2)), 0.99 * 50 * 9.81 * 0.5);
}

}  // namespace
