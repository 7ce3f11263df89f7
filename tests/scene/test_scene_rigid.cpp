// Rigid bodies in scene files: the shipped rigid scenes hold what they say, stand, and keep
// their pinned hashes; bad rigid-body fields are named by JSON path; `pba run` writes one
// row per body with its quaternion and prints the World's hash.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "commands_run.h"
#include "error_of.h"
#include "pba/scene.h"
#include "pba/soft.h"
#include "pba/world_scenes.h"

namespace {

const std::filesystem::path kDir = PBA_SCENES_DIR;

// the message of parsing `text` as scenes/x.json ("" when it parses)
std::string error_of(const std::string& text) {
  return pba::test_support::error_of([&] { pba::parse_scene(text, "scenes/x.json"); });
}

std::string hex(std::uint64_t h) {
  char s[32];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(h));
  return s;
}

TEST(RigidScenes, StackHoldsWhatTheFileSaysAndStands) {
  pba::Scene s = pba::load_scene(kDir / "rigid_stack.json");
  pba::World& w = s.world;
  EXPECT_EQ(s.name, "rigid stack");
  // 8 boxes, a ball, a capsule and a kinematic paddle (the ground collider's stand-in body
  // joins at the first tick)
  EXPECT_EQ(w.rigid().size(), 11u);
  const pba::EntityId top = w.find("box 7"), paddle = w.find("paddle"), ball = w.find("ball");
  ASSERT_TRUE(w.valid(w.rigid_body_id(top)));
  EXPECT_EQ(w.rigid().type(w.rigid_body_id(paddle)), pba::BodyType::Kinematic);
  EXPECT_FALSE(w.kinematic_id(paddle).is_null());
  EXPECT_EQ(w.rigid().shapes(w.rigid_body_id(ball))[0].rolling_resistance, 0.05);
  EXPECT_EQ(w.rigid().settings().substeps, 8);
  EXPECT_FALSE(w.rigid().settings().auto_substeps);  // substeps given are taken exactly
  EXPECT_TRUE(w.rigid().settings().sleep);
  for (int i = 0; i < 600; ++i) w.step();
  // the stack stands: its top box sags by the soft contacts' n^2 g / (2 pi f)^2 (8 boxes,
  // 120 Hz: 1.1 mm; see ContactSettings::contact_hertz) below the touching height 3.75 m
  // (the file leaves 1 mm gaps), within half that, and stays over its base
  const double hz = w.rigid().settings().contact_hertz;
  const double sag = 64 * 9.81 / std::pow(2 * 3.141592653589793 * hz, 2);
  EXPECT_NEAR(w.pose(top).position.y, 3.75 - sag, 0.5 * sag);
  EXPECT_LT(std::hypot(w.pose(top).position.x, w.pose(top).position.z), 1e-3);
  // the paddle keeps its looping waypoint path: 3 m out along +z at 0.5 m/s, then 2 m back
  EXPECT_NEAR(w.pose(paddle).position.z, 1.5 - (0.5 * 10 - 3), 1e-9);
}

TEST(RigidScenes, PyramidStandsAndTheParticlesRestOnIt) {
  pba::Scene s = pba::load_scene(kDir / "rigid_pyramid.json");
  pba::World& w = s.world;
  EXPECT_EQ(w.rigid().size(), 21u);
  EXPECT_EQ(w.particles().size(), 12u);
  const pba::EntityId top = w.find("box 5.0");
  const double y0 = w.pose(top).position.y;
  for (int i = 0; i < 600; ++i) w.step();
  // the top box stays within the gaps (5 x 2 mm) and the sag above of where it started
  EXPECT_NEAR(w.pose(top).position.y, y0 - 0.01, 0.01);
  // every particle came to rest on a box: above the ground, on a box's top face (within 1 mm)
  std::size_t on_boxes = 0;
  for (std::size_t i = 0; i < w.particles().size(); ++i) {
    const pba::Vec3 p = w.particles().position(i);
    for (const pba::Collider& c : w.body_colliders()) {
      const pba::Vec3 d = glm::conjugate(c.end.rotation) * (p - c.end.position);
      if (std::abs(d.x) <= 0.2 && std::abs(d.z) <= 0.2 && std::abs(d.y - 0.2 - 0.03) < 1e-3) {
        ++on_boxes;
        break;
      }
    }
  }
  EXPECT_GE(on_boxes, 10u) << "most particles fall inside the pyramid's top faces";
}

// The shipped rigid scenes' hashes after 600 ticks (10 s), pinned: a change to the rigid
// stage, the solver or the scene shows here (re-pin with the new value when intended).
TEST(RigidScenes, PinnedHashes) {
  auto run = [](const char* file) {
    pba::Scene s = pba::load_scene(kDir / file);
    for (int i = 0; i < 600; ++i) s.world.step();
    return hex(s.world.hash());
  };
  EXPECT_EQ(run("rigid_stack.json"), "fea9dd6e7848dff5");
  EXPECT_EQ(run("rigid_pyramid.json"), "31ccbfd69b7fbf58");
}

// A scene file that mixes a collider, a rigid body and a cloth builds the same World as the
// C++ builder of the same scene (world_scenes::cloth_on_falling_box, the sample's and
// RigidStage.ClothLandsOnAFallingBox's): the same hash and the same bits in every body and
// cloth particle after 2 s, through the box's landing and the cloth's draping.
TEST(RigidScenes, AFileOfRigidAndSoftBodiesIsTheSameWorldAsItsCppBuilder) {
  pba::World built;
  const pba::world_scenes::ClothOnBox b = pba::world_scenes::cloth_on_falling_box(built);
  pba::Scene file = pba::parse_scene(R"({"version": 1, "name": "cloth on a falling box",
    "colliders": [{"name": "ground", "type": "plane", "restitution": 0, "friction": 0.6}],
    "rigid_bodies": [{"name": "box", "position": [0, 1.5, 0], "shapes": [{"type": "box", "half_extents": [0.5, 0.5, 0.5]}]}],
    "soft_bodies": [{"type": "cloth", "name": "cloth", "origin": [-1, 2.5, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2],
                     "nx": 21, "ny": 21, "mass": 0.2, "pins": "none", "thickness": 0.01}]})",
                                     "cloth_box.json");
  pba::World& w = file.world;
  for (int i = 0; i < 120; ++i) built.step(), w.step();
  EXPECT_EQ(hex(w.hash()), hex(built.hash()));
  const pba::Pose p = w.pose(w.find("box")), q = built.pose(b.box);
  EXPECT_EQ(p.position, q.position);
  EXPECT_EQ(p.rotation, q.rotation);
  const pba::SoftBody &c = pba::soft_system(w).at(0), &d = pba::soft_system(built).at(0);
  ASSERT_EQ(c.size(), d.size());
  for (std::size_t k = 0; k < c.size(); ++k) EXPECT_EQ(c.position(k), d.position(k)) << k;
  EXPECT_NEAR(q.position.y, 0.5, 0.01);  // it landed
}

TEST(RigidScenes, MassScalesTheShapesMassProperties) {
  pba::Scene s = pba::parse_scene(
      R"({"version": 1, "rigid_bodies": [{"name": "b", "mass": 6, "shapes": [{"type": "box", "half_extents": [1, 0.5, 0.25]}]}]})",
      "x.json");
  const pba::RigidBodyId b = s.world.rigid_body_id(s.world.find("b"));
  EXPECT_DOUBLE_EQ(s.world.rigid().mass(b), 6);
  // a solid box: I_xx = m (h_y^2 + h_z^2) / 3
  EXPECT_NEAR(s.world.rigid().world_inertia(b)[0][0], 6 * (0.25 + 0.0625) / 3, 1e-12);
}

TEST(RigidScenes, BadFieldsAreNamedByPath) {
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"type": "dynamic"}]})"),
            "scenes/x.json: /rigid_bodies/0: missing required field \"shapes\"");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"shapes": []}]})"),
            "scenes/x.json: /rigid_bodies/0/shapes: a body needs at least one shape, got none");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"shapes": [{"type": "box", "density": 0}]}]})"),
            "scenes/x.json: /rigid_bodies/0/shapes/0/density: must be > 0, got 0");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"shapes": [{"type": "torus"}]}]})"),
            "scenes/x.json: /rigid_bodies/0/shapes/0/type: unknown value \"torus\" (expected one of \"plane\", "
            "\"sphere\", \"box\", \"capsule\", \"hull\", \"mesh\", \"compound\")");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"shapes": [{"type": "plane"}]}]})"),
            "scenes/x.json: /rigid_bodies/0/shapes/0/type: a plane has no volume, so only a \"static\" body can have "
            "one");
  // a mesh on a moving body was named by the library's field, not by its pointer ("/rigid_bodies/0:
  // rigid body of entity 0.shapes[0].shape: a mesh has no volume ..."), as a plane is
  for (const char* type : {"dynamic", "kinematic"})
    EXPECT_EQ(error_of(std::string(R"({"version": 1, "rigid_bodies": [{"type": ")") + type +
                       R"(", "shapes": [{"type": "box"}, {"type": "mesh", "vertices": [[0, 0, 0], [1, 0, 0], [0, 0, 1]],
                       "triangles": [[0, 1, 2]]}]}]})"),
              "scenes/x.json: /rigid_bodies/0/shapes/1/type: a mesh has no volume, so only a \"static\" body can have "
              "one")
        << type;
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"shapes": [{"type": "box", "half_height": 1}]}]})"),
            "scenes/x.json: /rigid_bodies/0/shapes/0/half_height: only for \"type\": \"capsule\"");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"type": "static", "mass": 2, "shapes": [{"type": "box"}]}]})"),
            "scenes/x.json: /rigid_bodies/0/mass: only for a \"dynamic\" body");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"type": "wobbly", "shapes": [{"type": "box"}]}]})"),
            "scenes/x.json: /rigid_bodies/0/type: unknown value \"wobbly\" (expected one of \"dynamic\", "
            "\"kinematic\", \"static\")");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"shapes": [{"type": "box"}], "kinematic": {"path": "linear"}}]})"),
            "scenes/x.json: /rigid_bodies/0/kinematic: a path drives only a \"kinematic\" body (this one is "
            "\"dynamic\")");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"shapes": [{"type": "box"}], "linear_damping": -1}]})"),
            "scenes/x.json: /rigid_bodies/0/linear_damping: must be >= 0, got -1");
  const std::string u = error_of(R"({"version": 1, "rigid_bodies": [{"shapes": [{"type": "box"}], "velocity": [1, 0, 0]}]})");
  EXPECT_EQ(u.rfind("scenes/x.json: /rigid_bodies/0/velocity: unknown field (allowed here: ", 0), 0u) << u;
  EXPECT_EQ(error_of(R"({"version": 1, "settings": {"rigid": {"solver": "magic"}}})"),
            "scenes/x.json: /settings/rigid/solver: unknown value \"magic\" (expected one of \"soft-step\", "
            "\"sequential-impulse\", \"tgs\", \"xpbd\")");
  EXPECT_EQ(error_of(R"({"version": 1, "settings": {"rigid": {"relax_iterations": -1}}})"),
            "scenes/x.json: /settings/rigid/relax_iterations: must be an integer in [0, 100], got -1");
  EXPECT_EQ(error_of(R"({"version": 1, "settings": {"rigid": {"contact_compliance": -1e-9}}})"),
            "scenes/x.json: /settings/rigid/contact_compliance: must be >= 0, got -1e-09");
  EXPECT_EQ(error_of(R"({"version": 1, "settings": {"rigid": {"auto_substeps_sag": -0.01}}})"),
            "scenes/x.json: /settings/rigid/auto_substeps_sag: must be >= 0, got -0.01");
  EXPECT_EQ(error_of(R"({"version": 1, "settings": {"rigid": {"auto_substeps_sag_fraction": 1.5}}})"),
            "scenes/x.json: /settings/rigid/auto_substeps_sag_fraction: must be in [0, 1], got 1.5");
  EXPECT_EQ(error_of(R"({"version": 1, "settings": {"rigid": {"auto_substeps_least": 0}}})"),
            "scenes/x.json: /settings/rigid/auto_substeps_least: must be an integer in [1, 64], got 0");
  EXPECT_EQ(error_of(R"({"version": 1, "settings": {"rigid": {"substeps": 0}}})"),
            "scenes/x.json: /settings/rigid/substeps: must be an integer in [1, 64], got 0");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"type": "static", "linear_velocity": [1, 0, 0], "shapes": [{"type": "box"}]}]})"),
            "scenes/x.json: /rigid_bodies/0/linear_velocity: a \"static\" body does not move (make it \"kinematic\" to "
            "give it a velocity)");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"type": "static", "angular_velocity": [0, 0, 0], "shapes": [{"type": "box"}]}]})"),
            "");
  // a body driven by a kinematic path takes its velocities from the path at every tick, so a
  // velocity of its own was dropped without a word (a paddle given 5 m/s on a 1 m/s path ran at
  // 1 m/s, its CSV row showing 5 at step 0 only; a motor's spin about z given as 7 rad/s did not
  // turn it): refused like a static body's, at its field; a zero velocity is still taken
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"type": "kinematic", "linear_velocity": [5, 0, 0], "shapes": [{"type": "box"}],
                         "kinematic": {"path": "linear", "velocity": [1, 0, 0]}}]})"),
            "scenes/x.json: /rigid_bodies/0/linear_velocity: a body on a \"kinematic\" path moves as the path says "
            "(give the velocity in /rigid_bodies/0/kinematic)");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"type": "kinematic", "angular_velocity": [0, 0, 7], "shapes": [{"type": "box"}],
                         "kinematic": {"path": "motor", "spin": [0, 2, 0]}}]})"),
            "scenes/x.json: /rigid_bodies/0/angular_velocity: a body on a \"kinematic\" path moves as the path says "
            "(give the velocity in /rigid_bodies/0/kinematic)");
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"type": "kinematic", "linear_velocity": [0, 0, 0], "shapes": [{"type": "box"}],
                         "kinematic": {"path": "linear", "velocity": [1, 0, 0]}}]})"),
            "");
  // without a path a kinematic body keeps the velocity it is given
  {
    pba::Scene k = pba::parse_scene(
        R"({"version": 1, "rigid_bodies": [{"name": "k", "type": "kinematic", "linear_velocity": [5, 0, 0], "shapes": [{"type": "box"}]}]})",
        "x.json");
    for (int i = 0; i < 6; ++i) k.world.step();
    EXPECT_EQ(k.world.rigid().linear_velocity(k.world.rigid_body_id(k.world.find("k"))), pba::Vec3(5, 0, 0));
  }
  // a speed beyond kMaxRigidSpeed (the contact rows' float range) is refused at its field
  const std::string fast = error_of(R"({"version": 1, "rigid_bodies": [{"angular_velocity": [0, 3e20, 0], "shapes": [{"type": "box"}]}]})");
  EXPECT_EQ(fast.rfind("scenes/x.json: /rigid_bodies/0/angular_velocity: (0, 3e+20, 0) has a magnitude of 3e+20 rad/s, "
                       "above the rigid bodies' limit of 1e+18 rad/s", 0), 0u) << fast;
  // a mass whose inverse is no normal float (the contact solver's blocks are floats) is refused
  // before it can turn the first contact into NaN, by its field's path (it was named as the
  // library's "/rigid_bodies/0: rigid body of entity 0 'b'.mass.mass", not by its pointer)
  const std::string big = error_of(R"({"version": 1, "rigid_bodies": [{"name": "b", "mass": 1e39, "shapes": [{"type": "box"}]}]})");
  EXPECT_EQ(big.rfind("scenes/x.json: /rigid_bodies/0/mass: must be in [2.9", 0), 0u) << big;
  EXPECT_NE(big.find("got 1e+39"), std::string::npos) << big;
  // the library's own validation still names the item and the entity
  const std::string m =
      error_of(R"({"version": 1, "rigid_bodies": [{"name": "b", "shapes": [{"type": "box", "density": 1e308, "half_extents": [10, 10, 10]}]}]})");
  EXPECT_EQ(m.rfind("scenes/x.json: /rigid_bodies/0: rigid body of entity 0 'b'", 0), 0u) << m;
  EXPECT_NE(m.find("mass: must be"), std::string::npos) << m;
}

// A collider of triangles on a kinematic path (a moving floor) loads and steps beside a
// kinematic rigid body: the World gave it a kinematic stand-in body, which the rigid bodies
// refuse for a mesh, and the first tick stopped `pba run` with the library's "collider of
// entity 0.shapes[0].shape: a mesh has no volume" (no file, no pointer) for a collider the file
// gives correctly. The particle rides the floor up, 1 m/s for 1 s, resting on it (its radius
// above, within 1 mm). Beside a dynamic body such a floor is refused (it jumps along its path
// with no speed, so it would neither carry nor push the body), named by the body's JSON path.
TEST(RigidScenes, AMovingMeshColliderStepsBesideKinematicBodiesOnly) {
  const std::string floor =
      R"({"version": 1, "settings": {"dt": 0.008333333333333333},
          "colliders": [{"name": "lift", "type": "mesh", "vertices": [[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]],
                         "triangles": [[0, 2, 1], [0, 3, 2]], "kinematic": {"path": "linear", "velocity": [0, 1, 0]}}],
          "particles": [{"name": "bead", "position": [0, 0.05, 0], "radius": 0.05}],
          "rigid_bodies": [{"name": "crate", "position": [10, 5, 0], "shapes": [{"type": "box"}])";
  pba::Scene s = pba::parse_scene(floor + R"(, "type": "kinematic"}]})", "scenes/x.json");
  for (int i = 0; i < 120; ++i) ASSERT_EQ(pba::test_support::error_of([&] { s.world.step(); }), "") << "tick " << i;
  EXPECT_NEAR(s.world.pose(s.world.find("lift")).position.y, 1.0, 1e-12);
  EXPECT_NEAR(s.world.pose(s.world.find("bead")).position.y, 1.0 + 0.05, 1e-3);
  const std::string m = error_of(floor + "}]}");
  EXPECT_EQ(m.rfind("scenes/x.json: /rigid_bodies/0: World::add_rigid_body: entity 1 'lift' has a mesh collider on a "
                    "Kinematic path, which cannot carry or push rigid bodies", 0), 0u) << m;
  EXPECT_NE(m.find("give the moving floor a box or hull collider"), std::string::npos) << m;
}

// The largest settings.rigid.capacity, 2^26 bodies, reserves some 36 GB of address space for
// the World's rigid bodies: where the memory cannot give it (here 2 GiB of address space, in a
// child process) the file's settings are named with the library's message, not an unexplained
// std::bad_alloc. (Not under the sanitizers, whose shadow memory needs the space.)
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
[[noreturn]] void read_capacity_under_two_gib() {
  rlimit two_gib{};
  two_gib.rlim_cur = two_gib.rlim_max = rlim_t(1) << 31;
  setrlimit(RLIMIT_AS, &two_gib);
  const std::string m = error_of(R"({"version": 1, "settings": {"rigid": {"capacity": 67108864}}})");
  std::fprintf(stderr, "%s\n", m.c_str());
  std::exit(m.empty() ? 2 : 0);
}

TEST(RigidScenes, ACapacityTheMemoryCannotHoldIsNamedBySettings) {
  EXPECT_EXIT(read_capacity_under_two_gib(), ::testing::ExitedWithCode(0),
              "scenes/x.json: /settings: RigidSystemDef.capacity: cannot reserve room for 67108864 bodies");
}
#endif

// A quaternion is normalised whatever its scale: [1e200, 1e200, 0, 0] is a quarter turn
// about x and [1e-200, 0, 0, 0] no turn. Their squares overflowed and underflowed: the first
// was refused as "/rigid_bodies/0: EntityDef 'a'.rotation: must be a finite unit quaternion"
// (normalised to zeros, not named by the field's path), the second as "must be a non-zero
// quaternion".
TEST(RigidScenes, AQuaternionOfAnyScaleIsNormalised) {
  pba::Scene s = pba::parse_scene(R"({"version": 1, "rigid_bodies": [
      {"name": "a", "rotation": [1e200, 1e200, 0, 0], "shapes": [{"type": "box"}]},
      {"name": "b", "rotation": [1e-200, 0, 0, 0], "shapes": [{"type": "box"}]},
      {"name": "c", "rotation": [0, 0, 3e-160, -4e-160], "shapes": [{"type": "box"}]}]})",
                                  "scenes/x.json");
  const pba::Quat a = s.world.pose(s.world.find("a")).rotation, b = s.world.pose(s.world.find("b")).rotation,
                  c = s.world.pose(s.world.find("c")).rotation;
  EXPECT_NEAR(a.w, std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(a.x, std::sqrt(0.5), 1e-15);
  EXPECT_EQ(b, pba::Quat(1, 0, 0, 0));
  EXPECT_NEAR(c.y, 0.6, 1e-15);
  EXPECT_NEAR(c.z, -0.8, 1e-15);
  EXPECT_EQ(error_of(R"({"version": 1, "rigid_bodies": [{"rotation": [0, 0, 0, 0], "shapes": [{"type": "box"}]}]})"),
            "scenes/x.json: /rigid_bodies/0/rotation: must be a non-zero quaternion");
}

TEST(RigidScenes, SettingsReachTheWorld) {
  pba::Scene s = pba::parse_scene(
      R"({"version": 1, "settings": {"rigid": {"solver": "sequential-impulse", "iterations": 25, "sleep": false,
          "friction_mix": "minimum", "contact_hertz": 60}}})",
      "x.json");
  const pba::ContactSettings& c = s.world.rigid().settings();
  EXPECT_EQ(c.solver, pba::RigidSolverType::SequentialImpulse);
  EXPECT_EQ(c.iterations, 25);
  EXPECT_FALSE(c.sleep);
  EXPECT_EQ(c.friction_mix, pba::MixRule::Minimum);
  EXPECT_EQ(c.contact_hertz, 60);
}

// the manifold reuse tests' thresholds: read, 0 allowed (every manifold afresh), negative refused
TEST(RigidScenes, ReuseDistanceAndAngleAreRead) {
  auto settings_of = [](const char* json) { return pba::parse_scene(json, "x.json").world.rigid().settings(); };
  const pba::ContactSettings c =
      settings_of(R"({"version": 1, "settings": {"rigid": {"reuse_distance": 0.004, "reuse_angle": 0.01}}})");
  EXPECT_EQ(c.reuse_distance, 0.004);
  EXPECT_EQ(c.reuse_angle, 0.01);
  EXPECT_EQ(settings_of(R"({"version": 1, "settings": {"rigid": {"reuse_distance": 0}}})").reuse_distance, 0);
  EXPECT_EQ(settings_of(R"({"version": 1})").reuse_distance, pba::ContactSettings{}.reuse_distance);
  EXPECT_NE(error_of(R"({"version": 1, "settings": {"rigid": {"reuse_angle": -1}}})")
                .find("/settings/rigid/reuse_angle"),
            std::string::npos);
}

// every solver of the library is named in scene files, with its own settings
TEST(RigidScenes, TgsAndXpbdAreReadWithTheirSettings) {
  pba::Scene t = pba::parse_scene(
      R"({"version": 1, "settings": {"rigid": {"solver": "tgs", "substeps": 12, "substep_iterations": 2,
          "relax_iterations": 3}}})",
      "x.json");
  const pba::ContactSettings& c = t.world.rigid().settings();
  EXPECT_EQ(c.solver, pba::RigidSolverType::Tgs);
  EXPECT_EQ(c.substeps, 12);
  EXPECT_EQ(c.substep_iterations, 2);
  EXPECT_EQ(c.relax_iterations, 3);
  EXPECT_FALSE(c.auto_substeps);
  // without substeps the soft step may take more for a tall column; asked, also with them
  EXPECT_TRUE(pba::parse_scene(R"({"version": 1})", "x.json").world.rigid().settings().auto_substeps);
  const pba::Scene a = pba::parse_scene(
      R"({"version": 1, "settings": {"rigid": {"substeps": 4, "auto_substeps": true}}})", "x.json");
  EXPECT_TRUE(a.world.rigid().settings().auto_substeps);
  EXPECT_EQ(a.world.rigid().settings().substeps, 4);
  // the halving's sag budgets: 2% of each body's size unless given, none in metres unless given
  auto settings_of = [](const char* json) { return pba::parse_scene(json, "x.json").world.rigid().settings(); };
  EXPECT_EQ(settings_of(R"({"version": 1})").auto_substeps_sag_fraction, 0.02);
  EXPECT_EQ(settings_of(R"({"version": 1, "settings": {"rigid": {"auto_substeps_sag_fraction": 0}}})")
                .auto_substeps_sag_fraction,
            0);
  EXPECT_EQ(settings_of(R"({"version": 1})").auto_substeps_sag, 0);
  // the lowering's floor: 3 substeps unless given
  EXPECT_EQ(settings_of(R"({"version": 1})").auto_substeps_least, 3);
  EXPECT_EQ(settings_of(R"({"version": 1, "settings": {"rigid": {"auto_substeps_least": 4}}})").auto_substeps_least, 4);
  EXPECT_EQ(settings_of(R"({"version": 1, "settings": {"rigid": {"auto_substeps_sag": 0.01}}})").auto_substeps_sag, 0.01);
  pba::Scene x = pba::parse_scene(
      R"({"version": 1, "settings": {"rigid": {"solver": "xpbd", "contact_compliance": 1e-7}}})", "x.json");
  EXPECT_EQ(x.world.rigid().settings().solver, pba::RigidSolverType::Xpbd);
  EXPECT_EQ(x.world.rigid().settings().contact_compliance, 1e-7);
}

// a "sensor" collider reaches the World: the ball falls through it (1 m drop to its top
// face takes sqrt(2 / g) = 0.45 s) and is reported entering
TEST(RigidScenes, SensorCollidersReportTheirVisitors) {
  pba::Scene s = pba::parse_scene(
      R"({"version": 1, "colliders": [{"name": "gate", "type": "box", "sensor": true, "half_extents": [1, 0.1, 1]}],
          "rigid_bodies": [{"name": "ball", "position": [0, 1.2, 0], "shapes": [{"type": "sphere", "radius": 0.1}]}]})",
      "x.json");
  EXPECT_TRUE(s.world.collider(s.world.find("gate")).sensor);
  int enters = 0;
  for (int i = 0; i < 60; ++i) {
    s.world.step();
    enters += static_cast<int>(s.world.sensor_enter_events().size());
  }
  EXPECT_EQ(enters, 1);
  EXPECT_LT(s.world.pose(s.world.find("ball")).position.y, -1);  // it pushed nothing
}

// A compound nested in a compound, as a collider and as a dynamic body's shape: the body
// lands on the collider's top box and stays on it (both used to stop the run at the first
// contact: "no narrow phase for the pair sphere-compound")
TEST(RigidScenes, NestedCompoundsCollideAsTheirLeaves) {
  pba::Scene s = pba::parse_scene(
      R"({"version": 1, "colliders": [{"type": "plane"},
          {"name": "table", "type": "compound", "position": [0, 0.5, 0], "children": [
            {"type": "compound", "children": [{"type": "box", "half_extents": [1, 0.1, 1]}]}]}],
          "rigid_bodies": [{"name": "toy", "position": [0, 1.5, 0], "shapes": [{"type": "compound", "children": [
            {"type": "compound", "position": [0, 0.2, 0], "children": [{"type": "sphere", "radius": 0.2}]}]}]}]})",
      "x.json");
  for (int i = 0; i < 120; ++i) s.world.step();
  // the sphere's centre rests 0.2 above the table top (y = 0.6): the body's frame 0.2 below it
  EXPECT_NEAR(s.world.pose(s.world.find("toy")).position.y, 0.6, 0.01);
}

// Sensors of every shape report a ball falling through them: a compound (a box inside a box
// compound) and a mesh (a 2 m square sheet of two triangles) used to stop the run when the
// ball reached them ("no narrow phase for the pair compound-sphere"); a box sensor counts
// for comparison. Each reports one entering and, once the ball is below it, one leaving.
TEST(RigidScenes, CompoundAndMeshSensorsReportTheirVisitors) {
  for (const std::string gate :
       {R"({"name": "gate", "type": "box", "sensor": true, "half_extents": [1, 0.1, 1]})",
        R"({"name": "gate", "type": "compound", "sensor": true, "children": [{"type": "compound", "children": [
             {"type": "box", "half_extents": [1, 0.1, 1]}]}]})",
        R"({"name": "gate", "type": "mesh", "sensor": true, "vertices": [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]],
            "triangles": [[0, 1, 2], [0, 2, 3]]})"}) {
    pba::Scene s = pba::parse_scene(R"({"version": 1, "colliders": [)" + gate + R"(],
          "rigid_bodies": [{"name": "ball", "position": [0, 1.2, 0], "shapes": [{"type": "sphere", "radius": 0.1}]}]})",
                                    "x.json");
    int enters = 0, leaves = 0;
    for (int i = 0; i < 60; ++i) {
      s.world.step();
      for (const pba::SensorEvent& e : s.world.sensor_enter_events()) enters += e.visitor == s.world.find("ball");
      leaves += static_cast<int>(s.world.sensor_leave_events().size());
    }
    EXPECT_EQ(enters, 1) << gate;
    EXPECT_EQ(leaves, 1) << gate;
    EXPECT_LT(s.world.pose(s.world.find("ball")).position.y, -1) << gate;  // it pushed nothing
  }
}

int run(std::vector<std::string> words) {
  words.insert(words.begin(), "run");
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  return pba_run_command(static_cast<int>(argv.size()), argv.data());
}

TEST(RigidScenes, RunWritesTheBodiesPosesAndTheHash) {
  const std::string scene = (kDir / "rigid_stack.json").string();
  const auto csv = std::filesystem::temp_directory_path() / "pba_run_rigid_test.csv";
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({scene, "--steps", "60", "--every", "30", "--csv", csv.string()}), 0);
  const std::string out = testing::internal::GetCapturedStdout();
  pba::Scene s = pba::load_scene(scene);
  for (int i = 0; i < 60; ++i) s.world.step();
  EXPECT_NE(out.find("final hash   " + hex(s.world.hash())), std::string::npos) << out;
  EXPECT_NE(out.find("rigid bodies 11"), std::string::npos) << out;
  EXPECT_NE(out.find("soft-step"), std::string::npos) << out;
  // header with the quaternion columns, then 3 snapshots (steps 0, 30, 60) of 11 bodies
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "step,time,particle,x,y,z,vx,vy,vz,body,qw,qx,qy,qz");
  std::vector<std::string> rows;
  while (std::getline(in, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 3u * 11);
  // the last snapshot's top box: its pose as the World has it
  const pba::Pose p = s.world.pose(s.world.find("box 7"));
  bool found = false;
  for (std::size_t k = 22; k < rows.size(); ++k) {
    if (rows[k].find(",box 7,") == std::string::npos) continue;
    found = true;
    double v[14];
    char name[32];
    ASSERT_EQ(std::sscanf(rows[k].c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%31[^,],%lf,%lf,%lf,%lf", &v[0], &v[1],
                          &v[2], &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], name, &v[10], &v[11], &v[12], &v[13]),
              14);
    EXPECT_EQ(v[0], 60);
    EXPECT_EQ(v[4], p.position.y);  // %.17g round-trips
    EXPECT_EQ(v[10], p.rotation.w);
    EXPECT_NEAR(v[10] * v[10] + v[11] * v[11] + v[12] * v[12] + v[13] * v[13], 1, 1e-12);
  }
  EXPECT_TRUE(found);
}

}  // namespace
