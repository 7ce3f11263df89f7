// The World's RigidBody component: handles and lifetimes, the rigid stage under the World's
// gravity, the World's colliders as the bodies' static geometry, particles on this tick's
// bodies, Kinematic paths driving kinematic bodies, and a non-finite body stopping the world.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "error_of.h"
#include "pba/soft.h"
#include "pba/world.h"
#include "pba/world_scenes.h"

namespace {

using pba::BodyType;
using pba::ColliderShape;
using pba::EntityId;
using pba::RigidBodyDef;
using pba::RigidBodyId;
using pba::Vec3;
using pba::World;

RigidBodyDef box_def(const Vec3& half, BodyType type = BodyType::Dynamic) {
  RigidBodyDef d;
  d.type = type;
  d.shapes = {{.shape = ColliderShape::box(half)}};
  return d;
}

// a ground plane at y = 0 as a World collider (no body of its own)
EntityId ground(World& w, double friction = 0.6) {
  const EntityId g = w.create_entity({.name = "ground"});
  w.add_collider(g, {.shape = ColliderShape::plane({0, 1, 0}, 0), .material = {.restitution = 0, .friction = friction}});
  return g;
}

using pba::test_support::error_of;

TEST(RigidComponent, HandlesPosesAndLifetime) {
  World w;
  const EntityId e = w.create_entity({.name = "crate", .pose = {{1, 2, 3}, pba::Quat(1, 0, 0, 0)}});
  RigidBodyDef d = box_def({0.5, 0.5, 0.5});
  d.pose.position = {0, 1, 0};  // relative to the entity
  const RigidBodyId b = w.add_rigid_body(e, d);
  EXPECT_TRUE(w.valid(b));
  EXPECT_EQ(w.rigid_body_id(e), b);
  EXPECT_EQ(w.owner(b), e);
  EXPECT_EQ(w.rigid().pose(b).position, Vec3(1, 3, 3));
  EXPECT_EQ(w.pose(e).position, Vec3(1, 3, 3));
  EXPECT_EQ(w.rigid().name(b), "crate");  // an unnamed body takes its entity's name
  // one body per entity
  EXPECT_NE(error_of([&] { w.add_rigid_body(e, box_def({1, 1, 1})); }).find("already has a rigid body"),
            std::string::npos);
  // set_pose moves the body
  w.set_pose(e, {{5, 5, 5}, pba::Quat(1, 0, 0, 0)});
  EXPECT_EQ(w.rigid().pose(b).position, Vec3(5, 5, 5));
  // destroying the entity removes the body; the handle goes stale
  w.destroy_entity(e);
  EXPECT_FALSE(w.valid(b));
  EXPECT_EQ(w.rigid().size(), 0u);
  EXPECT_EQ(error_of([&] { w.owner(b); }),
            "World::owner(RigidBodyId): rigid body: stale handle (index 0, generation 1; the slot is now at "
            "generation 2 and free): destroyed since, or a handle of another World or system");
  EXPECT_TRUE(w.body_colliders().empty());
}

// World::owner(RigidBodyId) named every handle it refused "stale", also one this World never
// issued (an index beyond its bodies', a generation beyond the slot's, another World's body):
// it tells them apart as every other World call does (HandlePool::require).
TEST(RigidComponent, OwnerNamesAHandleNeverIssuedHereAsSuch) {
  World w, other;
  const EntityId e = w.create_entity({.name = "crate"});
  const RigidBodyId b = w.add_rigid_body(e, box_def({0.5, 0.5, 0.5}));
  EXPECT_EQ(w.owner(b), e);
  const RigidBodyId foreign = other.add_rigid_body(other.create_entity({}), box_def({0.5, 0.5, 0.5}));
  for (int i = 0; i < 2; ++i) other.add_rigid_body(other.create_entity({}), box_def({0.5, 0.5, 0.5}));
  EXPECT_EQ(error_of([&] { w.owner(RigidBodyId{2, 1}); }),
            "World::owner(RigidBodyId): rigid body: invalid handle (index 2 was never issued here: a handle of "
            "another World or system)");
  EXPECT_EQ(error_of([&] { w.owner(RigidBodyId{0, 5}); }),
            "World::owner(RigidBodyId): rigid body: invalid handle (index 0 at generation 5 was never issued here, "
            "the slot is at generation 1: a handle of another World or system)");
  EXPECT_EQ(error_of([&] { w.owner(RigidBodyId{}); }), "World::owner(RigidBodyId): rigid body: null handle");
  EXPECT_EQ(w.owner(foreign), e);  // the same index and generation: no handle tells its World
}

// The colliders' stand-ins are made once an entity has a body. When the last entity body went
// (destroyed in rigid() directly, then its entity destroyed), the World's count of entity
// bodies fell to 0 and the stand-ins stopped following their entities (a wall moved by
// set_pose stayed where it was among the bodies) and World::hash left out the rigid bodies.
TEST(RigidComponent, StandInsFollowTheirEntitiesAfterTheLastEntityBodyIsGone) {
  World w;
  const EntityId wall = w.create_entity({.name = "wall"});
  w.add_collider(wall, {.shape = ColliderShape::box({0.5, 2, 2})});
  const EntityId crate = w.create_entity({.name = "crate", .pose = {.position = {5, 1, 0}}});
  w.rigid().destroy(w.add_rigid_body(crate, box_def({0.5, 0.5, 0.5})));
  w.step();
  ASSERT_EQ(w.rigid().size(), 1u);  // the wall's stand-in alone
  const RigidBodyId stand_in = w.rigid().id_at(0);
  w.destroy_entity(crate);
  w.step();
  const std::uint64_t h = w.hash();
  w.set_pose(wall, {.position = {3, 0, 0}});
  w.step();
  EXPECT_EQ(w.rigid().pose(stand_in).position, Vec3(3, 0, 0));
  EXPECT_NE(w.hash(), h);  // the stand-in moved: the world's state did
}

// Bodies are made and destroyed through the World, but rigid() lets a program destroy an
// entity's body directly. The World knew bodies by slot alone: the next body made in rigid()
// took the freed slot and became the entity's (owner() named the crate, valid() said it had
// an entity, and each tick wrote the new body's pose into the crate's). A body is the entity's
// only while the entity holds that very handle.
TEST(RigidComponent, ABodyDestroyedInRigidDirectlyLeavesItsSlotToNoEntity) {
  World w;
  ground(w);
  const EntityId crate = w.create_entity({.name = "crate"});
  RigidBodyDef d = box_def({0.5, 0.5, 0.5});
  d.pose.position = {0, 0.5, 0};
  const RigidBodyId b = w.add_rigid_body(crate, d);
  for (int i = 0; i < 10; ++i) w.step();
  const Vec3 at = w.pose(crate).position;
  w.rigid().destroy(b);
  EXPECT_TRUE(w.rigid_body_id(crate).is_null());
  RigidBodyDef ball;
  ball.pose.position = {6, 5, 0};
  ball.shapes = {{.shape = ColliderShape::sphere(0.5)}};
  const RigidBodyId lone = w.rigid().create(ball);
  ASSERT_EQ(lone.index, b.index);  // the premise: the freed slot
  EXPECT_FALSE(w.valid(lone));
  EXPECT_NE(error_of([&] { w.owner(lone); }).find("belongs to no entity"), std::string::npos);
  for (int i = 0; i < 30; ++i) w.step();
  EXPECT_EQ(w.pose(crate).position, at);  // the crate's pose is not the ball's
  EXPECT_LT(w.rigid().pose(lone).position.y, 5);  // the ball falls
  w.destroy_entity(crate);
  EXPECT_TRUE(w.rigid().valid(lone));  // and stays when the crate goes
}

// A dynamic body teleported (set_pose) into a sleeping one: a teleport has no velocity, and a
// slow awake body does not wake a sleeper, so the sleeper held still like a static body through
// the next step while the solver pushed the teleported body alone out of it (the sleeper woke a
// step later, when that push made the other fast). Box2D v3 wakes a sleeping body when a
// contact with it begins; the sleeper now wakes at the next step and takes its share of the push.
TEST(RigidComponent, ABodyTeleportedIntoASleepingOneWakesItAtTheNextStep) {
  World w;
  ground(w);
  RigidBodyDef d = box_def({0.5, 0.5, 0.5});
  d.pose.position = {0, 0.5, 0};
  const RigidBodyId a = w.add_rigid_body(w.create_entity({.name = "sleeper"}), d);
  d.pose.position = {5, 0.5, 0};
  const EntityId mover = w.create_entity({.name = "mover"});
  const RigidBodyId b = w.add_rigid_body(mover, d);
  for (int i = 0; i < 600 && (w.rigid().awake(a) || w.rigid().awake(b)); ++i) w.step();
  ASSERT_FALSE(w.rigid().awake(a));
  ASSERT_FALSE(w.rigid().awake(b));
  const Vec3 a0 = w.rigid().pose(a).position;
  // 0.4 m into the sleeper, from the side
  w.set_pose(mover, {.position = a0 + Vec3(0.6, 0, 0)});
  EXPECT_TRUE(w.rigid().awake(b));
  EXPECT_FALSE(w.rigid().awake(a));  // woken through the next step's pairs, not here
  w.step();
  EXPECT_TRUE(w.rigid().awake(a));
  // pushed apart, both moved: the sleeper is no wall
  for (int i = 0; i < 120; ++i) w.step();
  const Vec3 pa = w.rigid().pose(a).position, pb = w.rigid().pose(b).position;
  EXPECT_GT(pb.x - pa.x, 1 - 0.01) << pa.x << " " << pb.x;
  EXPECT_LT(pa.x, a0.x - 0.01);
}

// A moved-from World took a rigid body and stepped it (its RigidBodySystem's contact state had
// gone with the move and add_rigid_body dereferenced null).
TEST(RigidComponent, AMovedFromWorldTakesBodiesAgain) {
  World w;
  ground(w);
  World v = std::move(w);
  ground(w);  // NOLINT(bugprone-use-after-move): the point of the test
  const EntityId e = w.create_entity({.name = "crate", .pose = {{0, 0.6, 0}, pba::Quat(1, 0, 0, 0)}});
  const RigidBodyId b = w.add_rigid_body(e, box_def({0.5, 0.5, 0.5}));
  for (int i = 0; i < 60; ++i) w.tick(i / 60.0, 1.0 / 60);
  EXPECT_NEAR(w.rigid().pose(b).position.y, 0.5, 1e-3);
}

// A self-move (x = std::move(x), here through a reference) keeps the object as it was. Member
// by member, each vector moved into itself gave up its elements under the counts and handles
// that still named them: the World and the RigidBodySystem lost their bodies' arrays, and a
// ParticleSystem's next step read the broad phase's blocks that were gone (UBSan: reference
// binding to null of type 'BlockBounds').
TEST(RigidComponent, ASelfMoveKeepsTheWorldAndItsSystems) {
  World w;
  ground(w);
  const EntityId e = w.create_entity({.name = "crate", .pose = {{0, 0.6, 0}, pba::Quat(1, 0, 0, 0)}});
  const RigidBodyId b = w.add_rigid_body(e, box_def({0.5, 0.5, 0.5}));
  World& same_world = w;
  w = std::move(same_world);
  for (int i = 0; i < 60; ++i) w.tick(i / 60.0, 1.0 / 60);
  EXPECT_TRUE(w.valid(e));
  EXPECT_NEAR(w.rigid().pose(b).position.y, 0.5, 1e-3);
  pba::RigidBodySystem& r = w.rigid();
  pba::RigidBodySystem& same_rigid = r;
  r = std::move(same_rigid);
  EXPECT_EQ(r.size(), 2u);  // the ground and the crate
  r.step(1.0 / 60, {0, -9.81, 0});
  EXPECT_NEAR(r.pose(b).position.y, 0.5, 1e-3);
  pba::ParticleSystem p;
  p.create({.position = {0, 1, 0}});
  pba::ParticleSystem& same_particles = p;
  p = std::move(same_particles);
  ASSERT_EQ(p.size(), 1u);
  p.step(0, 0.01, std::span<const pba::Collider>{}, {});
  EXPECT_LT(p.position(std::size_t{0}).y, 1.0);  // it falls
}

// A kinematic path faster than a rigid body may move (kMaxRigidSpeed) was refused with the
// body's own words, "rigid body 0 set_velocity linear: ...": no entity, no path (a scene
// file's "kinematic": {"path": "linear", "velocity": [1e30, 0, 0]}). The tick names both.
TEST(RigidComponent, AKinematicPathTooFastForABodyNamesItsEntity) {
  World w;
  ground(w);
  const EntityId e = w.create_entity({.name = "paddle", .pose = {{0, 1, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_rigid_body(e, box_def({0.5, 0.5, 0.5}, BodyType::Kinematic));
  w.add_kinematic(e, {.path = pba::PathType::Linear, .velocity = {1e30, 0, 0}});
  std::string m = error_of([&] { w.tick(0, 1.0 / 60); });
  EXPECT_NE(m.find("World::tick: the kinematic path of entity 1 'paddle' cannot drive its rigid body in the "
                   "tick to t = 0.016666666666666666 s (rigid body"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("1e+30 m/s, above the rigid bodies' limit"), std::string::npos) << m;
  // a collider on such a path: its stand-in body
  World c;
  const EntityId g = c.create_entity({.name = "pusher"});
  c.add_collider(g, {.shape = ColliderShape::box({0.5, 0.5, 0.5})});
  c.add_kinematic(g, {.path = pba::PathType::Linear, .velocity = {0, 0, -2e18}});
  c.add_rigid_body(c.create_entity({.name = "crate", .pose = {{0, 3, 0}, pba::Quat(1, 0, 0, 0)}}),
                   box_def({0.5, 0.5, 0.5}));
  m = error_of([&] { c.tick(0, 1.0 / 60); });
  EXPECT_NE(m.find("the kinematic path of entity 0 'pusher' cannot drive its collider in the tick to t = "
                   "0.016666666666666666 s (rigid body"),
            std::string::npos)
      << m;
}

TEST(RigidComponent, BadInputNamesTheEntityAndTheField) {
  World w;
  const EntityId e = w.create_entity({.name = "crate"});
  RigidBodyDef d = box_def({0.5, 0.5, 0.5});
  d.shapes[0].density = -2;
  const std::string m = error_of([&] { w.add_rigid_body(e, d); });
  EXPECT_NE(m.find("rigid body of entity 0 'crate'"), std::string::npos) << m;
  EXPECT_NE(m.find("shapes[0].density"), std::string::npos) << m;
  d = box_def({0.5, 0.5, 0.5});
  d.linear_velocity.x = NAN;
  EXPECT_NE(error_of([&] { w.add_rigid_body(e, d); }).find("'crate'.linear_velocity"), std::string::npos);
  d = box_def({0.5, 0.5, 0.5});
  d.shapes.clear();
  EXPECT_NE(error_of([&] { w.add_rigid_body(e, d); }).find("at least one shape"), std::string::npos);
  // a stale entity
  const EntityId gone = w.create_entity({});
  w.destroy_entity(gone);
  EXPECT_NE(error_of([&] { w.add_rigid_body(gone, box_def({1, 1, 1})); }).find("World::add_rigid_body: entity: stale"),
            std::string::npos);
  // a Kinematic drives only kinematic bodies, in either order of adding
  const EntityId k = w.create_entity({.name = "paddle"});
  w.add_kinematic(k, {.path = pba::PathType::Linear, .velocity = {1, 0, 0}});
  EXPECT_NE(error_of([&] { w.add_rigid_body(k, box_def({1, 1, 1})); }).find("'paddle'.type: the entity has a Kinematic"),
            std::string::npos);
  const EntityId dyn = w.create_entity({.name = "dyn"});
  w.add_rigid_body(dyn, box_def({1, 1, 1}));
  EXPECT_NE(error_of([&] { w.add_kinematic(dyn, {}); }).find("a Kinematic cannot drive"), std::string::npos);
  // the World's rigid settings are checked at creation, by field
  pba::WorldDef bad;
  bad.rigid.contacts.substeps = 0;
  EXPECT_NE(error_of([&] { World x(bad); }).find("WorldDef.rigid.contacts.substeps"), std::string::npos);
}

// A body on an entity with a Kinematic moves as the path says: the kinematic stage sets its
// velocities from the path every tick, so velocities of its own were dropped silently (the
// body of a linear path at 1 m/s given 5 m/s moved at 1). The World refuses them by entity
// and field, as the scene reader does ("a body on a \"kinematic\" path moves as the path
// says"); a kinematic body at rest joins the path.
TEST(RigidComponent, ABodysOwnVelocityOnAKinematicPathIsRefusedByName) {
  World w;
  const EntityId k = w.create_entity({.name = "paddle"});
  w.add_kinematic(k, {.path = pba::PathType::Linear, .velocity = {1, 0, 0}});
  RigidBodyDef d = box_def({1, 1, 1});
  d.type = BodyType::Kinematic;
  d.linear_velocity = {5, 0, 0};
  std::string m = error_of([&] { w.add_rigid_body(k, d); });
  EXPECT_NE(m.find("rigid body of entity 0 'paddle'.linear_velocity: the entity has a Kinematic"), std::string::npos) << m;
  EXPECT_NE(m.find("moves as the path says"), std::string::npos) << m;
  d.linear_velocity = Vec3(0);
  d.angular_velocity = {0, 2, 0};
  m = error_of([&] { w.add_rigid_body(k, d); });
  EXPECT_NE(m.find("'paddle'.angular_velocity: the entity has a Kinematic"), std::string::npos) << m;
  d.angular_velocity = Vec3(0);
  const pba::RigidBodyId body = w.add_rigid_body(k, d);
  w.tick(0, 1.0 / 60);
  EXPECT_EQ(w.rigid().linear_velocity(body), Vec3(1, 0, 0));
}

// The other order of adding: a kinematic body with a velocity of its own given a Kinematic.
// The path set the body's velocities from the first tick, so its own were dropped silently
// (a body at 5 m/s put on a 1 m/s path moved at 1). Refused as add_rigid_body refuses them,
// naming the entity and the body's velocities, the entity left without a Kinematic; the body
// stopped, the path takes it: x = 1 m/s * 1/60 s after a tick.
TEST(RigidComponent, AKinematicOnABodyWithItsOwnVelocityIsRefusedByName) {
  World w;
  const EntityId k = w.create_entity({.name = "paddle"});
  RigidBodyDef d = box_def({1, 1, 1}, BodyType::Kinematic);
  d.linear_velocity = {5, 0, 0};
  const pba::RigidBodyId body = w.add_rigid_body(k, d);
  const pba::KinematicDef path{.path = pba::PathType::Linear, .velocity = {1, 0, 0}};
  std::string m = error_of([&] { w.add_kinematic(k, path); });
  EXPECT_EQ(m.rfind("World::add_kinematic: entity 0 'paddle' has a kinematic rigid body moving at (5, 0, 0) m/s and "
                    "(0, 0, 0) rad/s, and a body on a kinematic path moves as the path says",
                    0),
            0u)
      << m;
  EXPECT_TRUE(w.kinematic_id(k).is_null());
  w.rigid().set_velocity(body, Vec3(0), {0, 0, 2});
  m = error_of([&] { w.add_kinematic(k, path); });
  EXPECT_NE(m.find("moving at (0, 0, 0) m/s and (0, 0, 2) rad/s"), std::string::npos) << m;
  w.rigid().set_velocity(body, Vec3(0), Vec3(0));
  w.add_kinematic(k, path);
  w.tick(0, 1.0 / 60);
  EXPECT_EQ(w.rigid().linear_velocity(body), Vec3(1, 0, 0));
  EXPECT_NEAR(w.rigid().pose(body).position.x, 1.0 / 60, 1e-12);
}

// Free fall under the World's gravity: the soft step's substeps are symplectic Euler steps of
// h = dt / substeps, so after m substeps y = y0 + v0 m h - g h^2 m (m + 1) / 2 exactly (up to
// rounding, 1e-12 m here); a later set_gravity applies from the next tick.
TEST(RigidStage, FreeFallFollowsTheWorldsGravityAndWritesTheEntityPose) {
  World w({.stepper = {.fixed_dt = 1.0 / 60}, .gravity = {0, -4, 0}});
  const EntityId e = w.create_entity({.name = "ball", .pose = {{0, 100, 0}, pba::Quat(1, 0, 0, 0)}});
  RigidBodyDef d;
  d.shapes = {{.shape = ColliderShape::sphere(0.5)}};
  d.linear_velocity = {1, 2, 0};
  w.add_rigid_body(e, d);
  const int substeps = w.rigid().settings().substeps;
  const double h = 1.0 / 60 / substeps;
  for (int i = 0; i < 30; ++i) w.step();
  const double m = 30.0 * substeps;
  EXPECT_NEAR(w.pose(e).position.y, 100 + 2 * m * h - 4 * h * h * m * (m + 1) / 2, 1e-12);
  EXPECT_NEAR(w.pose(e).position.x, m * h, 1e-12);
  EXPECT_NEAR(w.velocity(e).y, 2 - 4 * m * h, 1e-12);
  w.set_gravity({0, 0, 0});
  const double vy = w.velocity(e).y;
  for (int i = 0; i < 10; ++i) w.step();
  EXPECT_NEAR(w.velocity(e).y, vy, 1e-12);
}

// A box dropped on the World's ground plane (a collider without a body) rests on it: the
// soft contact settles where its spring holds the weight, W / (m (2 pi f)^2) = g / (2 pi
// 120)^2 = 1.7e-5 m deep, plus at most the linear slop (5 mm) the solver leaves uncorrected.
TEST(RigidStage, WorldCollidersAreStaticGeometry) {
  World w;
  ground(w);
  const EntityId e = w.create_entity({.name = "box", .pose = {{0, 2, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_rigid_body(e, box_def({0.5, 0.5, 0.5}));
  for (int i = 0; i < 180; ++i) w.step();
  const double slop = w.rigid().settings().linear_slop;
  EXPECT_NEAR(w.pose(e).position.y, 0.5, slop + 1e-4);
  EXPECT_GT(w.pose(e).position.y, 0.5 - slop - 1e-4);
  // the ground's body is a stand-in: not the entity's, and no shape of it joins body_colliders
  EXPECT_EQ(w.rigid().size(), 2u);
  EXPECT_TRUE(w.rigid_body_id(w.find("ground")).is_null());
  EXPECT_EQ(w.body_colliders().size(), 1u);
  // a collider's changed definition remakes its stand-in: the ground rises 1 m, the box with it
  w.collider(w.find("ground")).shape.offset = 1;
  w.rigid().wake(w.rigid_body_id(e));
  for (int i = 0; i < 240; ++i) w.step();
  EXPECT_NEAR(w.pose(e).position.y, 1.5, slop + 1e-4);
  // and a moved collider entity moves its stand-in: a static box under the body
  const EntityId table = w.create_entity({.name = "table", .pose = {{0, -10, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_collider(table, {.shape = ColliderShape::box({2, 0.25, 2})});
  w.set_pose(table, {{0, 2, 0}, pba::Quat(1, 0, 0, 0)});
  w.set_pose(e, {{0, 3, 0}, pba::Quat(1, 0, 0, 0)});
  for (int i = 0; i < 240; ++i) w.step();
  EXPECT_NEAR(w.pose(e).position.y, 2.75, slop + 1e-4);
}

// a World with the ground and a one-metre box on it, stepped until the box sleeps (2 s at most)
std::pair<EntityId, RigidBodyId> box_asleep_on_the_ground(World& w) {
  ground(w);
  const EntityId e = w.create_entity({.name = "box", .pose = {{0, 0.5, 0}, pba::Quat(1, 0, 0, 0)}});
  const RigidBodyId b = w.add_rigid_body(e, box_def({0.5, 0.5, 0.5}));
  for (int i = 0; i < 120 && w.rigid().awake(b); ++i) w.step();
  return {e, b};
}

// set_pose wakes a sleeping body
TEST(RigidStage, SetPoseWakesTheBody) {
  World w;
  const auto [e, b] = box_asleep_on_the_ground(w);
  ASSERT_FALSE(w.rigid().awake(b));
  w.set_pose(e, {{0, 3, 0}, pba::Quat(1, 0, 0, 0)});
  EXPECT_TRUE(w.rigid().awake(b));
  w.step();
  EXPECT_LT(w.pose(e).position.y, 3);
}

// World::set_gravity wakes the bodies asleep under the old gravity: a box asleep on the
// ground, with gravity turned to the ground's plane, slides off at g (frictionless: nothing
// presses it on the ground; within 1% in the first tick, as the rigid stage's test) and is
// g t^2 / 2 along within symplectic Euler's first-order error after a second. Before, it hung
// asleep under the new gravity.
TEST(RigidStage, SetGravityWakesTheSleepers) {
  World w;
  const auto [e, b] = box_asleep_on_the_ground(w);
  ASSERT_FALSE(w.rigid().awake(b));
  const double g = 9.81, dt = w.stepper().settings().fixed_dt;
  w.set_gravity({0, 0, g});
  w.step();
  EXPECT_TRUE(w.rigid().awake(b));
  EXPECT_NEAR(w.rigid().linear_velocity(b).z, g * dt, 0.01 * g * dt);
  const int n = static_cast<int>(std::lround(1 / dt));
  for (int i = 1; i < n; ++i) w.step();
  const double t = n * dt;
  EXPECT_NEAR(w.pose(e).position.z, g * t * t / 2, g * t * dt);
}

// Ray casts see the bodies where they are now, also between ticks: a ray straight down hits
// a body's top face (its pose's y + 0.5) before the first tick, after ticks, after
// World::set_pose moves it (not its old place), and not at all once its entity is destroyed
// (the ground under it then, owned by the ground's entity); a static collider moved by
// set_pose is hit where it went. Before, queries() read the last tick's collision world: it
// found nothing before the first tick, the moved body at its old place, and the destroyed
// entity still (a hit owned by an entity that no longer exists).
TEST(RigidStage, QueriesSeeTheBodiesWhereTheyAreBetweenTicks) {
  World w;
  const EntityId g = ground(w);
  // the height a ray straight down from y = 10 at (x, 0) meets, and whose it is
  auto down = [&](double x) { return w.queries().ray_cast({{x, 10, 0}, {0, -1, 0}, 100.0}); };
  auto top = [&](double x) {
    const pba::QueryRayHit h = down(x);
    return h.hit ? 10 - h.distance : -1.0;
  };
  EXPECT_NEAR(top(0), 0, 1e-12);
  const EntityId e = w.create_entity({.name = "box", .pose = {{0, 3, 0}, pba::Quat(1, 0, 0, 0)}});
  const RigidBodyId b = w.add_rigid_body(e, box_def({0.5, 0.5, 0.5}));
  EXPECT_NEAR(top(0), 3.5, 1e-6);
  for (int i = 0; i < 10; ++i) w.step();
  EXPECT_NEAR(top(0), w.rigid().pose(b).position.y + 0.5, 1e-6);
  w.set_pose(e, {{2, 3, 0}, pba::Quat(1, 0, 0, 0)});
  EXPECT_NEAR(top(2), 3.5, 1e-6);
  EXPECT_NEAR(top(0), 0, 1e-12);
  EXPECT_EQ(down(2).owner, e.index);
  w.step();
  EXPECT_NEAR(top(2), w.rigid().pose(b).position.y + 0.5, 1e-6);
  w.destroy_entity(e);
  EXPECT_NEAR(top(2), 0, 1e-12);
  EXPECT_EQ(down(2).owner, g.index);
  const EntityId shelf = w.create_entity({.name = "shelf", .pose = {{5, 1, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_collider(shelf, {.shape = ColliderShape::box({0.5, 0.5, 0.5})});
  EXPECT_NEAR(top(5), 1.5, 1e-6);
  w.step();
  w.set_pose(shelf, {{7, 1, 0}, pba::Quat(1, 0, 0, 0)});
  EXPECT_NEAR(top(7), 1.5, 1e-6);
  EXPECT_NEAR(top(5), 0, 1e-12);
}

// Adding a body costs the same however many bodies the World holds: the bodies' colliders
// and the collision world are made again when next read, not at each add (each add made every
// body's colliders again, so loading n bodies took O(n^2): a 20,000-body scene file took 24 s
// to load, 0.5 s since). Counted, not timed (a wall-clock ratio of adding 2000 bodies to a
// World of 16,000 against an empty one flaked on a loaded machine): adding 2000 bodies to a
// World of 0 or of 16,000 makes no collider and builds nothing, and the first read after
// makes every body's collider once (a World that made them at each add would count 2000
// builds and, for the 16,000, 2000 x 17,000 colliders). The colliders read are every body's.
TEST(RigidComponent, AddingABodyCostsTheSameHoweverManyThereAre) {
  auto add = [](World& w, int n, double z) {
    RigidBodyDef d = box_def({0.25, 0.25, 0.25});
    for (int i = 0; i < n; ++i) {
      const EntityId e = w.create_entity({.pose = {{(i % 100) * 0.6, 0.25 + (i / 100) * 0.6, z}, pba::Quat(1, 0, 0, 0)}});
      w.add_rigid_body(e, d);
    }
  };
  for (const int before : {0, 16000}) {
    SCOPED_TRACE(before);
    World w({.rigid = {.capacity = 18000}});
    add(w, before, 0);
    EXPECT_EQ(w.body_colliders().size(), static_cast<std::size_t>(before));
    const pba::WorldBuildCounts c0 = w.build_counts();
    add(w, 2000, 10);
    const pba::WorldBuildCounts c1 = w.build_counts();
    EXPECT_EQ(c1.body_collider_builds, c0.body_collider_builds);
    EXPECT_EQ(c1.body_colliders_made, c0.body_colliders_made);
    EXPECT_EQ(c1.collision_builds, c0.collision_builds);
    EXPECT_EQ(w.body_colliders().size(), static_cast<std::size_t>(before + 2000));
    EXPECT_EQ(w.body_colliders().back().end.position.z, 10);
    const pba::WorldBuildCounts c2 = w.build_counts();
    EXPECT_EQ(c2.body_collider_builds, c0.body_collider_builds + 1);
    EXPECT_EQ(c2.body_colliders_made, c0.body_colliders_made + before + 2000);
    EXPECT_EQ(c2.collision_builds, c0.collision_builds);  // built by queries() or the tick only
  }
}

// Particles dropped on a rigid box land on its top face: at the box's top plus their
// radius, not at the ground and not inside. The particle contact keeps the sphere outside
// the surface to float rounding; the box itself sits on the ground within the slop (above).
TEST(RigidStage, ParticlesLandOnTheBodiesOfThisTick) {
  for (const double drop : {0.5, 3.0}) {  // resting on the ground, or falling with the particles
    SCOPED_TRACE(drop);
    World w;
    ground(w);
    const EntityId e = w.create_entity({.name = "box", .pose = {{0, drop, 0}, pba::Quat(1, 0, 0, 0)}});
    w.add_rigid_body(e, box_def({0.5, 0.5, 0.5}));
    std::vector<EntityId> ps;
    for (int i = 0; i < 5; ++i) {
      ps.push_back(w.create_entity({}));
      w.add_particle(ps.back(), {.position = {-0.3 + 0.15 * i, drop + 1.5, 0.1}, .radius = 0.02});
    }
    for (int i = 0; i < 300; ++i) w.step();
    const double top = w.pose(e).position.y + 0.5;
    EXPECT_NEAR(top, 1.0, w.rigid().settings().linear_slop + 1e-4);
    for (EntityId p : ps) EXPECT_NEAR(w.pose(p).position.y, top + 0.02, 1e-3);
    // the box's shape is in the tick's collision world, owned by its entity
    const auto owners = w.collision().owners();
    EXPECT_EQ(owners.back(), e.index);
  }
}

// A cloth dropped on a box that falls to the ground lands on it: 1 s in, the cloth over the
// middle of the box's top face lies flat on it at the top plus the cloth's thickness (the
// soft bodies meet this tick's bodies too; 2 mm: the contact keeps particles outside to
// rounding); later the hanging sides tent it (bending), so it stays on or above the top, and
// no particle is ever inside the box
// (the scene of the "Rigid bodies/Cloth on a falling box" sample, pba/world_scenes.h: a 1 m
// box from 1.5 m, a 2 m cloth of 21 x 21 particles, 1 cm thick, from 2.5 m)
TEST(RigidStage, ClothLandsOnAFallingBox) {
  World w;
  const pba::world_scenes::ClothOnBoxDef def;
  const EntityId e = pba::world_scenes::cloth_on_falling_box(w, def).box;
  const pba::SoftBodyDef& sd = def.cloth;
  for (int i = 1; i <= 240; ++i) {
    w.step();
    const double top = w.pose(e).position.y + 0.5;
    const pba::SoftBody& cloth = pba::soft_system(w).at(0);
    int middle = 0;
    for (std::size_t k = 0; k < cloth.size(); ++k) {
      const Vec3 p = cloth.position(k);
      const bool inside = std::abs(p.x) < 0.49 && std::abs(p.z) < 0.49 && p.y < top - 0.01 && p.y > 0.01;
      EXPECT_FALSE(inside) << "tick " << i << ", particle " << k;
      if (std::abs(p.x) >= 0.25 || std::abs(p.z) >= 0.25) continue;
      ++middle;
      if (i == 60) { EXPECT_NEAR(p.y, top + sd.thickness, 2e-3) << k; }
      if (i == 240) { EXPECT_GE(p.y, top + sd.thickness - 2e-3) << k; }
    }
    if (i == 240) { EXPECT_GE(middle, 16); }
  }
  EXPECT_NEAR(w.pose(e).position.y, 0.5, w.rigid().settings().linear_slop + 1e-4);
}

// An entity with a particle cannot take a rigid body, nor one with a body a particle: both
// would move it (before, both were accepted, and the entity went where the particle went,
// 5.5 m from its body after 1 s, while World::pose was documented as the body's).
TEST(RigidComponent, AParticleAndABodyOnOneEntityAreRefused) {
  World w;
  const EntityId a = w.create_entity({.name = "dot"});
  w.add_particle(a, {.radius = 0.1});
  std::string m = error_of([&] { w.add_rigid_body(a, box_def({0.5, 0.5, 0.5})); });
  EXPECT_NE(m.find("World::add_rigid_body: entity 0 'dot' has a particle"), std::string::npos) << m;
  EXPECT_FALSE(w.valid(w.rigid_body_id(a)));
  const EntityId b = w.create_entity({.name = "crate"});
  w.add_rigid_body(b, box_def({0.5, 0.5, 0.5}));
  m = error_of([&] { w.add_particle(b, {.radius = 0.1}); });
  EXPECT_NE(m.find("World::add_particle: entity 1 'crate' has a rigid body"), std::string::npos) << m;
  EXPECT_EQ(w.particles().size(), 1u);
  for (int i = 0; i < 10; ++i) w.step();  // the world goes on
  EXPECT_NEAR(w.pose(b).position.y, w.rigid().pose(w.rigid_body_id(b)).position.y, 0);
}

// A collider on the entity of a dynamic body follows the body within the tick: a body
// rising at 3 m/s without gravity carries a 1 m collider box, and a particle resting on the
// box's top stays at the top plus its radius at the end of every tick, as on a body's own
// shape (before, the collider sat at the entity's pose of the tick's start, and the particle
// rode v dt = 5 cm inside it); a cloth laid on it likewise stays at its thickness above the
// top (to 0.1 mm: its substeps' contacts leave 11 um at most here, against the 5 cm lag).
// A sensor on a body moving at 2 m/s along x reports a resting particle entity in the tick in
// which the sensor's face reaches its sphere: (2 - 0.05 - 0.5) / 2 = 0.725 s, the tick to
// 44/60 s (before: one tick later).
// (a ball of 10 cm moving at `v` whose entity carries a 1 m World collider box)
EntityId carrier_of_a_box(World& w, const char* name, const Vec3& v, bool sensor) {
  const EntityId e = w.create_entity({.name = name});
  RigidBodyDef d;
  d.shapes = {{.shape = ColliderShape::sphere(0.1)}};
  d.linear_velocity = v;
  w.add_rigid_body(e, d);
  w.add_collider(e, {.shape = ColliderShape::box(Vec3(0.5)), .material = {.restitution = 0}, .sensor = sensor});
  return e;
}

TEST(RigidStage, AColliderOnABodysEntityFollowsTheBodyInTheSameTick) {
  World w({.gravity = {0, 0, 0}});
  const EntityId e = carrier_of_a_box(w, "lift", {0, 3, 0}, false);
  const EntityId p = w.create_entity({.name = "rider"});
  w.add_particle(p, {.position = {0.2, 0.52, 0.2}, .radius = 0.02});
  const EntityId c = w.create_entity({.name = "cloth"});
  const pba::SoftBodyDef sd{.thickness = 0.01};
  pba::soft_system(w).add(w, c, pba::SoftBody::cloth_grid({.origin = {-0.4, 0.51, -0.4}, .edge_u = {0.8, 0, 0},
                                                           .edge_v = {0, 0, 0.8}, .nx = 5, .ny = 5, .mass = 0.05,
                                                           .pins = pba::ClothPins::None}, sd));
  for (int i = 1; i <= 30; ++i) {
    w.step();
    const double top = w.pose(e).position.y + 0.5;
    EXPECT_NEAR(top, 0.5 + 3 * i / 60.0, 1e-9) << i;
    EXPECT_NEAR(w.pose(p).position.y, top + 0.02, 1e-5) << "tick " << i;
    const pba::SoftBody& cloth = pba::soft_system(w).at(0);
    for (std::size_t k = 0; k < cloth.size(); ++k)
      EXPECT_NEAR(cloth.position(k).y, top + sd.thickness, 1e-4) << "tick " << i << ", particle " << k;
  }

  World s({.gravity = {0, 0, 0}});
  const EntityId carrier = carrier_of_a_box(s, "carrier", {2, 0, 0}, true);
  const EntityId visitor = s.create_entity({.name = "visitor"});
  s.add_particle(visitor, {.position = {2, 0, 0}, .radius = 0.05});
  int entered = -1;
  for (int i = 1; i <= 60 && entered < 0; ++i) {
    s.step();
    for (const pba::SensorEvent& ev : s.sensor_enter_events())
      if (ev.sensor == carrier && ev.visitor == visitor) entered = i;
  }
  EXPECT_EQ(entered, 44);
}

// The tick's collision world is built once a tick, also when a collider sits on a moving
// body's entity (before, sync() built it and the rigid stage built it again with that collider
// moved to the body's new pose: 2 builds a tick); a world without bodies builds it once too,
// and queries() after a tick reads the tick's (no build). What the build holds is tested above:
// the rider and the sensor meet the carrier's pose of this tick.
TEST(RigidStage, TheCollisionWorldIsBuiltOnceATick) {
  World w({.gravity = {0, 0, 0}});
  ground(w);
  carrier_of_a_box(w, "lift", {0, 3, 0}, false);
  const EntityId sensor = carrier_of_a_box(w, "carrier", {2, 0, 0}, true);
  w.set_pose(sensor, {{0, 0, 5}, pba::Quat(1, 0, 0, 0)});
  const EntityId p = w.create_entity({.name = "rider"});
  w.add_particle(p, {.position = {0.2, 0.52, 0.2}, .radius = 0.02});
  w.step();
  const std::uint64_t b0 = w.build_counts().collision_builds;
  for (int i = 0; i < 10; ++i) w.step();
  EXPECT_EQ(w.build_counts().collision_builds, b0 + 10);
  w.queries();
  EXPECT_EQ(w.build_counts().collision_builds, b0 + 10);
  // the rider's collider is in it, at the lift's pose of this tick
  EXPECT_NEAR(w.pose(p).position.y, w.collision().colliders()[1].end.position.y + 0.5 + 0.02, 1e-5);

  World particles_only;
  ground(particles_only);
  particles_only.add_particle(particles_only.create_entity({}), {.position = {0, 1, 0}, .radius = 0.02});
  particles_only.step();
  const std::uint64_t q0 = particles_only.build_counts().collision_builds;
  for (int i = 0; i < 10; ++i) particles_only.step();
  EXPECT_EQ(particles_only.build_counts().collision_builds, q0 + 10);
}

// A kinematic paddle on a linear path pushes a resting box on frictionless ground: the box
// ends moving at the paddle's speed (a perfectly inelastic push, e = 0), so its momentum is
// m v_paddle, and it sits against the paddle; the paddle keeps its path to rounding. The
// paddle starts 1 cm away, inside the speculative distance, so the first manifold has the
// whole face (an approach from farther off gets a single speculative corner point first in
// the narrow phase, which tips the box: see the report). The soft contact's push-out of the
// first substep's overlap lends the box a little more speed (measured 0.3% at most over
// gaps of 0 to 2 cm): 1% bounds it.
TEST(RigidStage, KinematicPathsDriveKinematicBodies) {
  for (const bool collider : {false, true}) {  // a kinematic body, or a kinematic collider's stand-in
    SCOPED_TRACE(collider);
    World w;
    ground(w, 0);
    const EntityId paddle = w.create_entity({.name = "paddle", .pose = {{-0.61, 0.5, 0}, pba::Quat(1, 0, 0, 0)}});
    w.add_kinematic(paddle, {.path = pba::PathType::Linear, .velocity = {2, 0, 0}});
    if (collider)
      w.add_collider(paddle, {.shape = ColliderShape::box({0.1, 0.4, 0.5}), .material = {.restitution = 0}});
    else
      w.add_rigid_body(paddle, [] {
        RigidBodyDef d = box_def({0.1, 0.4, 0.5}, BodyType::Kinematic);
        d.shapes[0].material.friction = 0;
        return d;
      }());
    const EntityId box = w.create_entity({.name = "box", .pose = {{0, 0.5, 0}, pba::Quat(1, 0, 0, 0)}});
    RigidBodyDef d = box_def({0.5, 0.5, 0.5});
    d.shapes[0].material.friction = 0;
    const RigidBodyId b = w.add_rigid_body(box, d);
    for (int i = 0; i < 120; ++i) w.step();
    const double t = w.time();
    EXPECT_NEAR(w.pose(paddle).position.x, -0.61 + 2 * t, 1e-12);
    // the box moves with the paddle, 0.6 m ahead (half widths 0.1 + 0.5) within the slop
    EXPECT_NEAR(w.rigid().linear_velocity(b).x, 2, 0.02);
    EXPECT_NEAR(w.rigid().linear_velocity(b).y, 0, 1e-3);
    EXPECT_NEAR(w.pose(box).position.x - w.pose(paddle).position.x, 0.6, w.rigid().settings().linear_slop);
    const double momentum = w.rigid().mass(b) * w.rigid().linear_velocity(b).x;
    EXPECT_NEAR(momentum / (w.rigid().mass(b) * 2), 1, 0.01);
    if (!collider) {
      // the kinematic body is where its path says
      const RigidBodyId k = w.rigid_body_id(paddle);
      EXPECT_NEAR(w.rigid().pose(k).position.x, -0.61 + 2 * t, 1e-9);
    }
  }
}

// a kinematic collider that set_pose teleports: its stand-in jumps there too and goes on at
// the path's speed, instead of sweeping across the world in one tick
TEST(RigidStage, ATeleportedKinematicColliderJumps) {
  World w;
  ground(w);
  const EntityId crate = w.create_entity({.pose = {{5, 0.5, 5}, pba::Quat(1, 0, 0, 0)}});
  w.add_rigid_body(crate, box_def({0.5, 0.5, 0.5}));
  const EntityId p = w.create_entity({.name = "pusher"});
  w.add_collider(p, {.shape = ColliderShape::box({0.2, 0.2, 0.2})});
  w.add_kinematic(p, {.path = pba::PathType::Linear, .velocity = {1, 0, 0}});
  for (int i = 0; i < 10; ++i) w.step();
  w.set_pose(p, {{-10, 2, 0}, pba::Quat(1, 0, 0, 0)});
  w.step();
  // the stand-in: the kinematic body that is no entity's
  RigidBodyId mirror;
  for (std::size_t i = 0; i < w.rigid().size(); ++i)
    if (!w.valid(w.rigid().id_at(i)) && w.rigid().type(w.rigid().id_at(i)) == BodyType::Kinematic)
      mirror = w.rigid().id_at(i);
  ASSERT_FALSE(mirror.is_null());
  EXPECT_NEAR(w.rigid().linear_velocity(mirror).x, 1, 1e-9);
  EXPECT_NEAR(w.rigid().pose(mirror).position.x, -10 + 1.0 / 60, 1e-9);
}

TEST(RigidStage, ANonFiniteBodyStopsTheWorld) {
  World w;
  const EntityId e = w.create_entity({.name = "rocket"});
  RigidBodyDef d = box_def({0.5, 0.5, 0.5});
  d.gravity_scale = 1e308;  // finite, but g times it is not
  w.add_rigid_body(e, d);
  const std::string m = error_of([&] { w.step(); });
  EXPECT_NE(m.find("the rigid body of entity 0 'rocket' stopped the world in the tick to t = 0.0166"),
            std::string::npos) << m;
  EXPECT_NE(m.find("rigid body 0 'rocket' became non-finite"), std::string::npos) << m;
  EXPECT_EQ(w.rigid().failed_body(), w.rigid_body_id(e));
  // the world refuses further ticks, repeating the message
  const std::string again = error_of([&] { w.step(); });
  EXPECT_NE(again.find("the simulation stopped"), std::string::npos) << again;
  EXPECT_NE(again.find("'rocket'"), std::string::npos) << again;
}

// A box pushed past kMaxRigidSpeed beside a resting one: the world names the pushed box's
// entity (before, the contacts turned its resting neighbour to NaN first, and the neighbour
// was named), and the neighbour stays finite.
TEST(RigidStage, ABodyForcedPastTheSpeedLimitIsTheOneNamed) {
  World w;
  ground(w);
  const EntityId calm = w.create_entity({.name = "calm", .pose = {{0, 0.5, 0}}});
  w.add_rigid_body(calm, box_def({0.5, 0.5, 0.5}));
  const EntityId pushed = w.create_entity({.name = "pushed", .pose = {{0, 1.5, 0}}});
  w.add_rigid_body(pushed, box_def({0.5, 0.5, 0.5}));
  for (int i = 0; i < 5; ++i) w.step();
  const RigidBodyId p = w.rigid_body_id(pushed);
  w.rigid().apply_force(p, {0, 0, 1e30 * w.rigid().mass(p)});
  const std::string m = error_of([&] { w.step(); });
  EXPECT_NE(m.find("the rigid body of entity 2 'pushed' stopped the world"), std::string::npos) << m;
  EXPECT_NE(m.find("went faster than kMaxRigidSpeed"), std::string::npos) << m;
  EXPECT_TRUE(pba::is_finite(w.rigid().linear_velocity(w.rigid_body_id(calm))));
}

// A body put beyond what the collision world holds (its bounds are floats, |x| <= 3.4e38 m)
// while its state is still finite: a pose and a shape's placement each within the range could
// add up beyond it (a shape at 6e38 m), and the tick stopped the world naming the entity.
// Since 2026-12-07 RigidBodySystem::set_pose refuses the sum by the body's name, as create
// does, and nothing moves; the world steps on. (No velocity within kMaxRigidSpeed carries a
// body there: 1.7e16 m a tick at most, below the rounding of a position near 3.4e38 m; a step
// that did would stop naming the body, RigidDivergence.ABodyCarriedPastTheFloatRange...)
TEST(RigidStage, ABodyBeyondTheFloatRangeIsRefusedAndTheWorldStepsOn) {
  World w;
  const EntityId e = w.create_entity({.name = "comet"});
  RigidBodyDef d = box_def({0.5, 0.5, 0.5});
  d.linear_velocity = {pba::kMaxRigidSpeed, 0, 0};
  d.shapes[0].local.position = {3e38, 0, 0};
  const RigidBodyId b = w.add_rigid_body(e, d);
  EXPECT_NE(error_of([&] { w.rigid().set_pose(b, {{1.6666666666666666e306, 0, 0}}); }).find("must fit a float"),
            std::string::npos);
  const Vec3 was = w.rigid().pose(b).position;
  EXPECT_EQ(error_of([&] { w.rigid().set_pose(b, {{3e38, 0, 0}}); }),
            "rigid body 0 'comet' set_pose: position (3e+38, 0, 0) + rotation * shapes[0].local.position (3e+38, 0, 0) "
            "= (6e+38, 0, 0) does not fit a float (|component| <= 3.4028234663852886e+38)");
  EXPECT_EQ(w.rigid().pose(b).position, was);
  EXPECT_EQ(error_of([&] { w.step(); }), "");
}

// World::set_pose beyond the float range on an entity with a rigid body is refused before
// anything moves, by the World's name: it set the entity's pose, and then the body refused it
// in its own name. (An entity without one may stand there; its components refuse it.)
TEST(RigidStage, SetPoseBeyondTheFloatRangeIsRefusedAndMovesNothing) {
  World w;
  const EntityId e = w.create_entity({.name = "crate", .pose = {{1, 2, 3}}});
  w.add_rigid_body(e, box_def({0.5, 0.5, 0.5}));
  const std::string m = error_of([&] { w.set_pose(e, {{1e39, 0, 0}}); });
  EXPECT_EQ(m.rfind("World::set_pose.position: must fit a float", 0), 0u) << m;
  EXPECT_EQ(w.pose(e).position, Vec3(1, 2, 3));
  EXPECT_EQ(w.rigid().pose(w.rigid_body_id(e)).position, Vec3(1, 2, 3));
  const EntityId far = w.create_entity({.name = "far", .pose = {{0, -1e39, 0}}});
  EXPECT_EQ(w.pose(far).position.y, -1e39);
}

// World::draw draws each entity body's shapes through the library draw, at the body's pose,
// coloured by type and sleep, and not the colliders' stand-ins (drawn as colliders)
TEST(RigidStage, DrawDrawsTheBodiesShapes) {
  struct Recorder final : pba::DebugDraw {
    std::vector<std::pair<Vec3, pba::Color>> boxes, spheres;
    int planes = 0;
    void point(const Vec3&, float, pba::Color) override {}
    void line(const Vec3&, const Vec3&, pba::Color) override {}
    void sphere(const Vec3& c, double, pba::Color col) override { spheres.emplace_back(c, col); }
    void box(const Vec3& c, const Vec3&, const pba::Quat&, pba::Color col) override { boxes.emplace_back(c, col); }
    void capsule(const Vec3&, const Vec3&, double, pba::Color) override {}
    void plane(const Vec3&, double, double, pba::Color) override { ++planes; }
    void arrow(const Vec3&, const Vec3&, double, pba::Color) override {}
    void text(const Vec3&, std::string_view, pba::Color) override {}
  };
  World w;
  ground(w);
  const EntityId e = w.create_entity({.name = "box", .pose = {{0, 2, 0}, pba::Quat(1, 0, 0, 0)}});
  RigidBodyDef d = box_def({0.5, 0.5, 0.5});
  d.shapes.push_back({.shape = ColliderShape::sphere(0.25), .local = {{0, 1, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_rigid_body(e, d);
  for (int i = 0; i < 10; ++i) w.step();
  Recorder r;
  w.draw(r);
  ASSERT_EQ(r.boxes.size(), 1u);
  ASSERT_EQ(r.spheres.size(), 1u);
  EXPECT_EQ(r.planes, 1);  // the ground collider, once
  EXPECT_EQ(r.boxes[0].first, w.pose(e).position);
  EXPECT_EQ(r.spheres[0].first, pba::apply(w.pose(e), Vec3(0, 1, 0)));
  // dynamic and awake: a shade of orange (76-100% of it, by entity)
  const pba::Color c = r.boxes[0].second, o = pba::colors::orange;
  const float k = c.r / o.r;
  EXPECT_GE(k, 0.76f - 1e-6f);
  EXPECT_LE(k, 1.0f + 1e-6f);
  EXPECT_NEAR(c.g, k * o.g, 1e-6f);
  EXPECT_NEAR(c.b, k * o.b, 1e-6f);
}

// With the contacts flag, World::draw draws the bodies' contact points where they are: a box
// resting on the ground collider shows its four bottom corners at y = 0 (within the soft
// contact's millimetre of overlap), each with one normal arrow along the vertical (the
// manifold's normal, from its first body to its second).
TEST(RigidStage, DrawDrawsTheContactPointsAndNormals) {
  struct Recorder final : pba::DebugDraw {
    std::vector<Vec3> points, arrows;
    void point(const Vec3& p, float, pba::Color) override { points.push_back(p); }
    void line(const Vec3&, const Vec3&, pba::Color) override {}
    void sphere(const Vec3&, double, pba::Color) override {}
    void box(const Vec3&, const Vec3&, const pba::Quat&, pba::Color) override {}
    void capsule(const Vec3&, const Vec3&, double, pba::Color) override {}
    void plane(const Vec3&, double, double, pba::Color) override {}
    void arrow(const Vec3& a, const Vec3& b, double, pba::Color) override { arrows.push_back(b - a); }
    void text(const Vec3&, std::string_view, pba::Color) override {}
  };
  World w;
  ground(w);
  const EntityId e = w.create_entity({.name = "box", .pose = {{0, 0.5, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_rigid_body(e, box_def({0.5, 0.5, 0.5}));
  for (int i = 0; i < 30; ++i) w.step();
  Recorder none;
  w.draw(none);
  EXPECT_TRUE(none.points.empty());  // not unless asked
  Recorder r;
  w.draw(r, {.contacts = true, .normals = true});
  ASSERT_EQ(r.points.size(), 4u);
  ASSERT_EQ(r.arrows.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_NEAR(std::abs(r.points[k].x), 0.5, 1e-3);
    EXPECT_NEAR(std::abs(r.points[k].z), 0.5, 1e-3);
    EXPECT_NEAR(r.points[k].y, 0, 2e-3);
    EXPECT_NEAR(std::abs(glm::normalize(r.arrows[k]).y), 1, 1e-9);
  }
}

// A ball dropped through a sensor box reports one enter and one leave, at the ticks where the
// free fall y(t) = y0 - g t^2 / 2 brings its bottom to the box's top and its top to the box's
// bottom (t = sqrt(2 d / g)); the discrete fall (symplectic Euler substeps) lags the closed
// form by under a millisecond here, so each event falls in the tick that contains its time
// (to one tick). The sensor pushes nothing: the ball keeps falling freely through it.
TEST(Events, ASensorReportsOneEnterAndOneLeaveAtTheClosedFormTimes) {
  World w({.stepper = {.fixed_dt = 1.0 / 60}});
  const EntityId sensor = w.create_entity({.name = "gate", .pose = {{0, 2, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_collider(sensor, {.shape = ColliderShape::box({1, 0.5, 1}), .sensor = true});
  const EntityId ball = w.create_entity({.name = "ball", .pose = {{0, 5, 0}, pba::Quat(1, 0, 0, 0)}});
  RigidBodyDef d;
  d.shapes = {{.shape = ColliderShape::sphere(0.25)}};
  w.add_rigid_body(ball, d);
  const double g = 9.81, dt = 1.0 / 60;
  const double t_enter = std::sqrt(2 * (5 - 0.25 - 2.5) / g), t_leave = std::sqrt(2 * (5 + 0.25 - 1.5) / g);
  int enters = 0, leaves = 0;
  for (int i = 0; i < 90; ++i) {
    w.step();
    for (const pba::SensorEvent& ev : w.sensor_enter_events()) {
      ++enters;
      EXPECT_EQ(ev.sensor, sensor);
      EXPECT_EQ(ev.visitor, ball);
      EXPECT_NEAR(w.time(), t_enter, dt);
      EXPECT_GE(w.time(), t_enter - 1e-3);  // not before it can touch
    }
    for (const pba::SensorEvent& ev : w.sensor_leave_events()) {
      ++leaves;
      EXPECT_EQ(ev.visitor, ball);
      EXPECT_NEAR(w.time(), t_leave, dt);
      EXPECT_GE(w.time(), t_leave - 1e-3);
    }
    EXPECT_TRUE(w.touch_begin_events().empty());
  }
  EXPECT_EQ(enters, 1);
  EXPECT_EQ(leaves, 1);
  EXPECT_NEAR(w.velocity(ball).y, -g * w.time(), 0.02 * g * w.time());  // unhindered
}

// A sensor collider's shape changed between ticks (World::collider hands out its definition)
// is checked at the next tick like any collider's, by field and before anything moves: a box
// sensor's half extent set to NaN went unchecked (the check passed over sensors, which push
// nothing) and the tick stopped in the narrow phase's sensor test naming no collider. Nor
// does a kinematic entity move: the colliders were checked only after run_kinematics had
// moved it along its path, so the refused tick left it a tick ahead of the world's time.
TEST(Events, ASensorsShapeChangedBetweenTicksIsRefusedByField) {
  World w;
  const EntityId sensor = w.create_entity({.name = "gate", .pose = {{0, 2, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_collider(sensor, {.shape = ColliderShape::box({1, 0.5, 1}), .sensor = true});
  const EntityId ball = w.create_entity({.name = "ball", .pose = {{0, 2, 0}, pba::Quat(1, 0, 0, 0)}});
  RigidBodyDef d;
  d.shapes = {{.shape = ColliderShape::sphere(0.25)}};
  w.add_rigid_body(ball, d);
  const EntityId mover = w.create_entity({.name = "mover", .pose = {{0, 5, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_kinematic(mover, {.path = pba::PathType::Linear, .velocity = {1, 0, 0}});
  w.step();
  ASSERT_EQ(w.sensor_enter_events().size(), 1u);  // the premise: the ball is in it
  const double t = w.time();
  const Vec3 at = w.pose(ball).position, mover_at = w.pose(mover).position;
  ASSERT_GT(mover_at.x, 0);  // the premise: the path moves it each tick
  w.collider(sensor).shape.half_extents.y = NAN;
  const std::string msg = pba::test_support::error_of([&] { w.step(); });
  EXPECT_EQ(msg.rfind("collider of entity 0 'gate'", 0), 0u) << msg;
  EXPECT_NE(msg.find("half_extents"), std::string::npos) << msg;
  EXPECT_EQ(w.time(), t);
  EXPECT_EQ(w.pose(ball).position, at);
  EXPECT_EQ(w.pose(mover).position, mover_at);
  w.collider(sensor).shape.half_extents.y = 0.5;
  w.step();  // refused, not stopped
  EXPECT_GT(w.time(), t);
}

// A ball bouncing on the ground (e = 0.8) gives one touch begin and one touch end per bounce:
// the k-th impact at t_1 + sum of the flights 2 e^j v_1 / g (j = 1..k-1) with v_1 = sqrt(2 g h),
// approach speed e^(k-1) v_1; bounces faster than the restitution threshold (1 m/s) leave
// again, so 7 bounces end (4.43 ... 1.16 m/s) and the 8th (0.93 m/s) stays: 8 begins, 7 ends.
// Times to two ticks (below); speeds within 3% (the rebound tests' e^2 h tolerance) plus the
// g dt the last tick before the impact adds.
TEST(Events, ABouncingBallBeginsAndEndsOneTouchPerBounce) {
  World w({.stepper = {.fixed_dt = 1.0 / 120}});
  const EntityId g = w.create_entity({.name = "ground"});
  w.add_collider(g, {.shape = ColliderShape::plane({0, 1, 0}, 0), .material = {.restitution = 0.8, .friction = 0}});
  const double h = 1, r = 0.1, e = 0.8, grav = 9.81, dt = 1.0 / 120;
  const EntityId ball = w.create_entity({.name = "ball", .pose = {{0, h + r, 0}, pba::Quat(1, 0, 0, 0)}});
  RigidBodyDef d;
  d.shapes = {{.shape = ColliderShape::sphere(r), .material = {.restitution = e, .friction = 0}}};
  w.add_rigid_body(ball, d);
  const double v1 = std::sqrt(2 * grav * h);
  std::vector<double> begins, ends, speeds;
  for (int i = 0; i < 5 * 120; ++i) {
    w.step();
    for (const pba::TouchBeginEvent& ev : w.touch_begin_events()) {
      EXPECT_EQ(ev.a, g);
      EXPECT_EQ(ev.b, ball);
      EXPECT_NEAR(ev.normal.y, 1, 1e-9);  // from the ground to the ball
      begins.push_back(w.time());
      speeds.push_back(ev.approach_speed);
    }
    for (const pba::TouchEndEvent& ev : w.touch_end_events()) {
      EXPECT_EQ(ev.b, ball);
      ends.push_back(w.time());
    }
  }
  ASSERT_EQ(begins.size(), 8u);
  ASSERT_EQ(ends.size(), 7u);
  double t = std::sqrt(2 * h / grav), v = v1;
  for (std::size_t k = 0; k < begins.size(); ++k) {
    SCOPED_TRACE(k);
    // reported at the end of the tick that holds the impact (up to a tick late), and the
    // discrete rebounds (within 3% of e^k v_1) shift the later impacts by under a tick more
    EXPECT_NEAR(begins[k], t, 2 * dt);
    EXPECT_NEAR(speeds[k], v, 0.03 * v + grav * dt);
    if (k < ends.size()) {
      EXPECT_GT(ends[k], begins[k]);
      if (k + 1 < begins.size()) { EXPECT_LT(ends[k], begins[k + 1]); }
    }
    v *= e;
    t += 2 * v / grav;
  }
}

// Touching survives sleep: a box that comes to rest begins touching once and, asleep, does
// not end
TEST(Events, RestingContactStaysTouchingWhileAsleep) {
  World w;
  const EntityId g = ground(w);
  const EntityId box = w.create_entity({.name = "box", .pose = {{0, 0.52, 0}, pba::Quat(1, 0, 0, 0)}});
  const RigidBodyId b = w.add_rigid_body(box, box_def({0.5, 0.5, 0.5}));
  int begins = 0, ends = 0;
  for (int i = 0; i < 180; ++i) {
    w.step();
    begins += static_cast<int>(w.touch_begin_events().size());
    ends += static_cast<int>(w.touch_end_events().size());
  }
  EXPECT_FALSE(w.rigid().awake(b));
  EXPECT_EQ(begins, 1);
  EXPECT_EQ(ends, 0);
  // lifting it away ends the touch
  w.set_pose(box, {{0, 3, 0}, pba::Quat(1, 0, 0, 0)});
  w.step();
  ASSERT_EQ(w.touch_end_events().size(), 1u);
  EXPECT_EQ(w.touch_end_events()[0].a, g);
}

// An event names the entities as they were when it was made (stage 4); one destroyed later
// in the same tick (here by a post-stage system, as a game removes a bullet on impact) keeps
// its handle in the event, now stale, as Box2D's event ids may be: valid() says so, every
// World call refuses it with an Error, and the entity that takes its slot has a new
// generation, so the event never names the newcomer, now or in the ticks after.
TEST(Events, ATouchNamingAnEntityDestroyedLaterInTheTickHoldsAStaleHandle) {
  struct Reaper : pba::WorldSystem {
    EntityId ball, newcomer;
    std::string_view name() const override { return "reaper"; }
    void step(World& w, double, double) override {
      for (const pba::TouchBeginEvent& ev : w.touch_begin_events())
        if (ev.b == ball && newcomer.is_null()) {
          w.destroy_entity(ball);
          newcomer = w.create_entity({.name = "newcomer", .pose = {{5, 3, 0}, pba::Quat(1, 0, 0, 0)}});
          w.add_rigid_body(newcomer, box_def({0.5, 0.5, 0.5}));
        }
    }
  };
  World w;
  const EntityId g = ground(w);
  const EntityId ball = w.create_entity({.name = "ball", .pose = {{0, 0.6, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_rigid_body(ball, box_def({0.5, 0.5, 0.5}));
  auto reaper = std::make_unique<Reaper>();
  Reaper& r = *reaper;
  r.ball = ball;
  w.add_system(std::move(reaper));
  int tick = 0;
  while (w.touch_begin_events().empty() && tick < 60) w.step(), ++tick;
  ASSERT_EQ(w.touch_begin_events().size(), 1u);
  const pba::TouchBeginEvent ev = w.touch_begin_events()[0];
  EXPECT_EQ(ev.a, g);
  EXPECT_EQ(ev.b, ball);
  EXPECT_TRUE(w.valid(ev.a));
  EXPECT_FALSE(w.valid(ev.b));
  // the slot is reused (LIFO) at the next generation: the event's handle is not the newcomer's
  ASSERT_FALSE(r.newcomer.is_null());
  EXPECT_EQ(r.newcomer.index, ev.b.index);
  EXPECT_EQ(r.newcomer.generation, ev.b.generation + 1);
  EXPECT_NE(r.newcomer, ev.b);
  EXPECT_NE(error_of([&] { (void)w.pose(ev.b); }).find("World::pose: entity: stale handle"), std::string::npos);
  EXPECT_NE(error_of([&] { w.set_pose(ev.b, {}); }).find("stale handle"), std::string::npos);
  EXPECT_NE(error_of([&] { (void)w.rigid_body_id(ev.b); }).find("stale handle"), std::string::npos);
  EXPECT_NE(error_of([&] { w.destroy_entity(ev.b); }).find("stale handle"), std::string::npos);
  EXPECT_EQ(w.pose(r.newcomer).position, Vec3(5, 3, 0));  // untouched by those calls
  // the destroyed ball's touch ends silently; the newcomer, falling far away, touches nothing
  // until it lands, and never inherits the ball's pair
  for (int i = 0; i < 30; ++i) {
    w.step();
    EXPECT_TRUE(w.touch_end_events().empty());
    for (const pba::TouchBeginEvent& e : w.touch_begin_events()) EXPECT_NE(e.b, ev.b);
  }
}

TEST(RigidStage, HashIncludesTheBodiesAndIsDeterministic) {
  auto run = [](double vx) {
    World w;
    ground(w);
    for (int i = 0; i < 5; ++i) {
      const EntityId e = w.create_entity({.pose = {{0, 0.5 + 1.01 * i, 0}, pba::Quat(1, 0, 0, 0)}});
      RigidBodyDef d = box_def({0.5, 0.5, 0.5});
      d.linear_velocity.x = i == 4 ? vx : 0;
      w.add_rigid_body(e, d);
    }
    for (int i = 0; i < 120; ++i) w.step();
    return w.hash();
  };
  EXPECT_EQ(run(0), run(0));
  EXPECT_NE(run(0), run(0.1));
}

// A Kinematic on a mesh collider's entity (a moving floor of triangles) made its stand-in a
// kinematic mesh body once any entity had a body, which the rigid bodies refuse (a mesh has no
// volume): the first tick threw "collider of entity 0.shapes[0].shape: a mesh has no volume"
// though the user made no body of a mesh. A mesh's stand-in stays static and jumps with its
// entity, as a plane's does; particles still meet the collider where its path puts it: a bead
// rides the lift up 0.5 m/s for 1 s, resting on top (within the particle contact's slop of its
// radius).
TEST(RigidStage, AMovingMeshColliderCarriesParticles) {
  World w({.stepper = {.fixed_dt = 1.0 / 120}});
  const std::vector<Vec3> v = {{-2, 0, -2}, {2, 0, -2}, {2, 0, 2}, {-2, 0, 2}};
  const std::vector<std::array<std::uint32_t, 3>> tri = {{0, 2, 1}, {0, 3, 2}};
  const EntityId floor = w.create_entity({.name = "lift"});
  w.add_collider(floor, {.shape = ColliderShape::triangles(pba::TriangleMesh::build(v, tri)),
                         .material = {.restitution = 0, .friction = 0.6}});
  const double rise = 0.5;  // m/s
  w.add_kinematic(floor, {.path = pba::PathType::Linear, .velocity = {0, rise, 0}});
  const EntityId p = w.create_entity({.name = "bead"});
  const double r = 0.05;
  w.add_particle(p, {.position = {0, r, 0}, .radius = r});
  // a kinematic body beside it: the World makes stand-ins of its colliders
  w.add_rigid_body(w.create_entity({.name = "sign", .pose = {{10, 5, 0}, pba::Quat(1, 0, 0, 0)}}),
                   box_def({0.5, 0.5, 0.5}, BodyType::Kinematic));
  for (int i = 0; i < 120; ++i) ASSERT_EQ(error_of([&] { w.step(); }), "") << "tick " << i;
  EXPECT_NEAR(w.pose(floor).position.y, rise * 1.0, 1e-12);
  EXPECT_NEAR(w.pose(p).position.y, rise * 1.0 + r, 1e-3);
}

// That stand-in jumps along the path with no speed, so it neither carried nor pushed rigid
// bodies: a crate on a mesh floor moving sideways at 1 m/s (friction 0.8) lagged 2.000 m after
// 2 s where a box floor leaves it v^2 / (2 mu g) = 0.063 m behind, and a lift pushed crates up
// out of it with no speed; each jump also woke every sleeping body in the World. A plane did
// the same. A plane or mesh collider on a Kinematic path beside a dynamic rigid body is
// refused, naming the floor and the body and suggesting a box or hull collider, at whichever
// call completes the combination (and at the tick, for a collider changed in place); a box
// floor, a sensor, and kinematic bodies beside the floor are accepted.
TEST(RigidStage, AMovingPlaneOrMeshColliderIsRefusedBesideDynamicBodies) {
  const std::vector<Vec3> v = {{-2, 0, -2}, {2, 0, -2}, {2, 0, 2}, {-2, 0, 2}};
  const std::vector<std::array<std::uint32_t, 3>> tri = {{0, 2, 1}, {0, 3, 2}};
  const ColliderShape mesh = ColliderShape::triangles(pba::TriangleMesh::build(v, tri));
  const ColliderShape plane = ColliderShape::plane({0, 1, 0}, 0);
  const pba::KinematicDef path{.path = pba::PathType::Linear, .velocity = {1, 0, 0}};
  const auto crate = [](World& w) {
    return w.create_entity({.name = "crate", .pose = {{0, 1, 0}, pba::Quat(1, 0, 0, 0)}});
  };
  const auto refused = [](const std::string& m, const std::string& call, const char* type) {
    EXPECT_EQ(m.rfind(call + ": entity 0 'conveyor' has a " + type + " collider on a Kinematic path, which cannot "
                      "carry or push rigid bodies", 0), 0u) << m;
    EXPECT_NE(m.find("beside the dynamic rigid body of entity 1 'crate': give the moving floor a box or hull "
                     "collider"), std::string::npos) << m;
  };
  for (const ColliderShape& shape : {mesh, plane}) {
    const char* type = shape.type == pba::ShapeType::Mesh ? "mesh" : "plane";
    SCOPED_TRACE(type);
    {  // the collider and its path first, then the body
      World w;
      const EntityId f = w.create_entity({.name = "conveyor"});
      w.add_collider(f, {.shape = shape});
      w.add_kinematic(f, path);
      const EntityId c = crate(w);
      refused(error_of([&] { w.add_rigid_body(c, box_def({0.5, 0.5, 0.5})); }), "World::add_rigid_body", type);
      EXPECT_TRUE(w.rigid_body_id(c).is_null());  // nothing added
      w.add_rigid_body(c, box_def({0.5, 0.5, 0.5}, BodyType::Kinematic));  // a kinematic one is fine
      for (int i = 0; i < 10; ++i) w.step();
    }
    {  // the collider, the body, then the path
      World w;
      const EntityId f = w.create_entity({.name = "conveyor"});
      w.add_collider(f, {.shape = shape});
      w.add_rigid_body(crate(w), box_def({0.5, 0.5, 0.5}));
      refused(error_of([&] { w.add_kinematic(f, path); }), "World::add_kinematic", type);
      EXPECT_FALSE(w.valid(w.kinematic_id(f)));
      for (int i = 0; i < 10; ++i) w.step();  // a still floor is fine
    }
    {  // the path, the body, then the collider
      World w;
      const EntityId f = w.create_entity({.name = "conveyor"});
      w.add_kinematic(f, path);
      w.add_rigid_body(crate(w), box_def({0.5, 0.5, 0.5}));
      refused(error_of([&] { w.add_collider(f, {.shape = shape}); }), "World::add_collider", type);
      EXPECT_FALSE(w.valid(w.collider_id(f)));
      // a sensor of the shape on the path is fine (it has no stand-in)
      w.add_collider(f, {.shape = shape, .sensor = true});
      for (int i = 0; i < 10; ++i) w.step();
    }
    {  // a box floor changed in place to the shape: refused at the tick
      World w;
      const EntityId f = w.create_entity({.name = "conveyor"});
      w.add_collider(f, {.shape = ColliderShape::box({2, 0.1, 2})});
      w.add_kinematic(f, path);
      w.add_rigid_body(crate(w), box_def({0.5, 0.5, 0.5}));
      w.step();
      w.collider(f).shape = shape;
      refused(error_of([&] { w.step(); }), "World::tick", type);
    }
  }
}

// A collider the user moves by set_pose wakes the sleeping bodies it reached before or after
// the jump (set_pose's own rule), not every sleeping body in the World: each jump of a sign
// 20 m away woke a box asleep on the ground, so a World with a collider moved every tick
// never slept.
TEST(RigidStage, AColliderMovedBySetPoseWakesOnlyWhatItReaches) {
  World w;
  const EntityId sign = w.create_entity({.name = "sign", .pose = {{20, 1, 0}, pba::Quat(1, 0, 0, 0)}});
  w.add_collider(sign, {.shape = ColliderShape::box({0.5, 0.5, 0.5})});
  const auto [e, b] = box_asleep_on_the_ground(w);
  ASSERT_FALSE(w.rigid().awake(b));  // the premise
  for (int i = 0; i < 60; ++i) {
    w.set_pose(sign, {{20, 1 + 0.01 * i, 0}, pba::Quat(1, 0, 0, 0)});
    w.step();
    ASSERT_FALSE(w.rigid().awake(b)) << "tick " << i;  // was awake from the first jump on
  }
  // the sign set down on the box wakes it
  w.set_pose(sign, {{0, 1.45, 0}, pba::Quat(1, 0, 0, 0)});
  w.step();
  EXPECT_TRUE(w.rigid().awake(b));
}

}  // namespace
