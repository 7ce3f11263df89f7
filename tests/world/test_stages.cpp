// The World's named stages: the documented order, systems at their declared stage, the
// world's gravity read by every system each tick, generation-checked component handles,
// poses written by the system that simulates the entity, and a profile per stage.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "pba/soft.h"
#include "pba/world.h"

#include "error_of.h"

namespace {

using pba::EntityId;
using pba::Vec3;
using pba::World;
using pba::WorldStage;
using pba::test_support::error_of;

// records the stage it ran at, and whether the particles had stepped in this tick by then
class Probe final : public pba::WorldSystem {
 public:
  Probe(WorldStage s, std::vector<std::string>* log) : stage_(s), log_(log) {}
  std::string_view name() const override { return pba::to_string(stage_); }
  WorldStage stage() const override { return stage_; }
  void step(World& w, double, double) override {
    const bool stepped = w.particles().steps() > w.ticks();
    log_->push_back(std::string(pba::to_string(stage_)) + (stepped ? "+" : "-"));
  }

 private:
  WorldStage stage_;
  std::vector<std::string>* log_;
};

}  // namespace

// Systems run at their stage, in the documented order, whatever order they were added
// in; the particles move between the rigid and the particles stages.
TEST(Stages, RunInTheDocumentedOrder) {
  World w;
  const EntityId ball = w.create_entity({.pose = {.position = {0, 2, 0}}});
  w.add_particle(ball, {});
  std::vector<std::string> log;
  for (WorldStage s : {WorldStage::Post, WorldStage::Constraints, WorldStage::Soft, WorldStage::Particles,
                       WorldStage::Rigid, WorldStage::Collide, WorldStage::Kinematic})
    w.add_system(std::make_unique<Probe>(s, &log));
  w.step();
  const std::vector<std::string> expected = {"kinematic-", "collide-", "rigid-", "particles+",
                                             "soft+",      "constraints+", "post+"};
  EXPECT_EQ(log, expected);
  // the profile has every stage, and they add up to no more than the tick
  double sum = 0;
  for (double s : w.profile().stages) {
    EXPECT_GE(s, 0.0);
    sum += s;
  }
  EXPECT_LE(sum, w.profile().total * (1 + 1e-9) + 1e-9);
}

// Gravity is the world's: a particle and a soft body in the world both fall under it and
// both follow a change of it, whatever the body was built with.
TEST(Stages, GravityIsTheWorlds) {
  World w({.stepper = {.fixed_dt = 0.01}, .gravity = {0, -2, 0}});
  EXPECT_EQ(w.gravity(), Vec3(0, -2, 0));
  EXPECT_EQ(w.particles().forces().gravity, Vec3(0, -2, 0));
  const EntityId ball = w.create_entity({.pose = {.position = {0, 10, 0}}});
  w.add_particle(ball, {});
  pba::SoftBodyDef d;
  d.forces.gravity = {0, -50, 0};  // overridden by the world's
  const EntityId rope = w.create_entity({.name = "rope"});
  pba::soft_system(w).add(w, rope, pba::SoftBody::rope({.from = {0, 10, 0}, .to = {1, 10, 0}, .pin_start = false}, d));
  w.step();
  // one semi-implicit Euler step from rest: v = g dt, for the particle and every rope node
  // (no constraint is stretched by a uniform fall)
  EXPECT_NEAR(w.velocity(ball).y, -2 * 0.01, 1e-6);
  const pba::SoftBody& body = pba::soft_system(w).body(rope);
  EXPECT_NEAR(body.velocity(3).y, -2 * 0.01, 1e-5);
  EXPECT_EQ(body.settings().forces.gravity, Vec3(0, -2, 0));
  w.set_gravity({0, 0, 0});
  const double vy = w.velocity(ball).y;
  w.step();
  EXPECT_EQ(w.velocity(ball).y, vy);  // no drag, no gravity: unchanged
  EXPECT_NE(error_of([&] { w.set_gravity({0, NAN, 0}); }).find("set_gravity"), std::string::npos);
  EXPECT_NE(error_of([&] { World bad({.gravity = {0, INFINITY, 0}}); }).find("WorldDef.gravity"), std::string::npos);
}

// Every component has a generation-checked handle that names its entity and goes stale
// when the entity is destroyed (a new component in the same slot gets a new generation).
TEST(Stages, ComponentHandlesAreGenerationChecked) {
  World w;
  const EntityId a = w.create_entity({.name = "a"});
  const EntityId b = w.create_entity({.name = "b", .pose = {.position = {1, 0, 0}}});
  w.add_particle(a, {});
  w.add_particle(b, {});
  const pba::ColliderId c = w.add_collider(a, {.shape = {.type = pba::ShapeType::Sphere, .radius = 0.1}});
  const pba::ForcerId f = w.add_forcer(a, {});
  const pba::KinematicId k = w.add_kinematic(a, {});
  const pba::ConstraintId s = w.add_constraint(b, {.other = a});
  EXPECT_TRUE(w.valid(c) && w.valid(f) && w.valid(k) && w.valid(s));
  EXPECT_EQ(w.owner(c), a);
  EXPECT_EQ(w.owner(s), b);
  EXPECT_EQ(w.collider_id(a), c);
  EXPECT_EQ(w.constraint_id(b), s);
  EXPECT_TRUE(w.collider_id(b).is_null());
  // destroying a removes its components and the constraint that points at it
  w.destroy_entity(a);
  EXPECT_FALSE(w.valid(c) || w.valid(f) || w.valid(k) || w.valid(s));
  EXPECT_NE(error_of([&] { w.owner(c); }).find("stale handle"), std::string::npos);
  const EntityId e = w.create_entity({});
  const pba::ColliderId c2 = w.add_collider(e, {.shape = {.type = pba::ShapeType::Sphere, .radius = 0.1}});
  EXPECT_EQ(c2.index, c.index);
  EXPECT_NE(c2.generation, c.generation);
  EXPECT_FALSE(w.valid(c));
  EXPECT_EQ(w.owner(c2), e);
}

// The particle system writes the pose of the particle entities it simulates; a kinematic
// path writes the pose of the entities it drives.
TEST(Stages, TheSimulatingSystemWritesThePose) {
  World w({.stepper = {.fixed_dt = 0.01}});
  const EntityId ball = w.create_entity({.pose = {.position = {0, 1, 0}}});
  w.add_particle(ball, {});
  const EntityId lift = w.create_entity({});
  w.add_kinematic(lift, {.path = pba::PathType::Linear, .velocity = {0, 1, 0}});
  for (int i = 0; i < 10; ++i) w.step();
  // the ball: 10 semi-implicit Euler steps from rest, y = 1 - g dt^2 (1 + 2 + ... + 10)
  EXPECT_NEAR(w.pose(ball).position.y, 1 - 9.81 * 1e-4 * 55, 1e-6);
  EXPECT_NEAR(w.pose(lift).position.y, 0.1, 1e-12);
}
