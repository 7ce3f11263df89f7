// Soft bodies in the World and in scene files: the SoftSystem steps bodies with the
// world's colliders, follows entity lifetimes and hashes; the example files hold what
// they say; the builders build what they say; bad soft-body fields name their JSON path.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "error_of.h"
#include "pba/scene.h"
#include "pba/soft.h"

namespace {

std::string error_of(const std::string& text) {
  return pba::test_support::error_of([&] { pba::parse_scene(text, "scenes/x.json"); });
}

pba::Scene load(const char* name) { return pba::load_scene(std::filesystem::path(PBA_SCENES_DIR) / name); }

}  // namespace

// ---------------------------------------------------------------------------------------
// the world's soft system

// A cloth dropped on the world's ground collider stops on it (the system passes the
// world's colliders to the body): after landing no particle is below the ground by more
// than float rounding, and it rests at the body's collision thickness.
TEST(SoftSystem, BodiesCollideWithTheWorldsColliders) {
  pba::World w;
  const pba::EntityId ground = w.create_entity({.name = "ground"});
  w.add_collider(ground, {.shape = {.type = pba::ShapeType::Plane}, .material = {.friction = 0.5}});
  const pba::EntityId e = w.create_entity({.name = "sheet"});
  pba::SoftSystem& soft = pba::soft_system(w);
  EXPECT_EQ(&soft, &pba::soft_system(w));  // found again, not added twice
  soft.add(w, e, pba::SoftBody::cloth_grid({.origin = {-0.5, 0.5, -0.5}, .nx = 6, .ny = 6, .pins = pba::ClothPins::None},
                                           {.substeps = 4, .thickness = 0.01}));
  for (int i = 0; i < 120; ++i) w.step();
  const pba::SoftBody& b = soft.body(e);
  for (std::size_t p = 0; p < b.size(); ++p) EXPECT_NEAR(b.position(p).y, 0.01, 1e-4);
  EXPECT_EQ(soft.owner(0), e);
}

// Destroying the entity removes its body; a stale or foreign handle is refused by name.
TEST(SoftSystem, FollowsEntityLifetimes) {
  pba::World w;
  pba::SoftSystem& soft = pba::soft_system(w);
  const pba::EntityId a = w.create_entity({.name = "a"}), b = w.create_entity({.name = "b"});
  soft.add(w, a, pba::SoftBody::rope({.segments = 4}));
  soft.add(w, b, pba::SoftBody::rope({.segments = 6}));
  EXPECT_EQ(soft.size(), 2u);
  const std::uint64_t h2 = w.hash();
  w.destroy_entity(a);
  EXPECT_EQ(soft.size(), 1u);
  EXPECT_FALSE(soft.has(a));
  EXPECT_EQ(soft.body(b).size(), 7u);
  EXPECT_NE(w.hash(), h2);
  // stale handle, duplicate component, missing body
  try {
    soft.add(w, a, pba::SoftBody::rope({}));
    FAIL();
  } catch (const pba::Error& e) {
    EXPECT_NE(std::string(e.what()).find("not a live entity"), std::string::npos) << e.what();
  }
  try {
    soft.add(w, b, pba::SoftBody::rope({}));
    FAIL();
  } catch (const pba::Error& e) {
    EXPECT_NE(std::string(e.what()).find("'b' already has a soft body"), std::string::npos) << e.what();
  }
  EXPECT_THROW(soft.body(a), pba::Error);
}

// A body that becomes non-finite stops the world with its entity's name in the message.
TEST(SoftSystem, NonFiniteBodyNamesItsEntity) {
  pba::World w;
  const pba::EntityId e = w.create_entity({.name = "doomed rope"});
  pba::soft_system(w).add(w, e, pba::SoftBody::rope({.segments = 3}, {.substeps = 1}));
  pba::soft_system(w).body(e).set_position(2, {3e38, 0, 0});
  try {
    w.step();
    FAIL();
  } catch (const pba::Error& err) {
    const std::string m = err.what();
    EXPECT_NE(m.find("doomed rope"), std::string::npos) << m;
    EXPECT_NE(m.find("became non-finite"), std::string::npos) << m;
  }
}

// ---------------------------------------------------------------------------------------
// example scene files

TEST(SoftScenes, FilesHoldWhatTheySay) {
  pba::Scene flag = load("soft_flag.json");
  const pba::SoftSystem* soft = static_cast<const pba::SoftSystem*>(flag.world.find_system(pba::SoftSystem::kName));
  ASSERT_NE(soft, nullptr);
  ASSERT_EQ(soft->size(), 1u);
  const pba::SoftBody& f = soft->at(0);
  EXPECT_EQ(f.size(), 70u);
  EXPECT_EQ(f.pins().size(), 7u);  // the first column
  EXPECT_EQ(f.settings().aero.lift, 0.6);
  EXPECT_EQ(f.settings().forces.wind.gust, 3.0);  // the world's wind
  EXPECT_EQ(flag.world.name(soft->owner(0)), "flag");

  pba::Scene springs = load("soft_spring.json");
  pba::SoftSystem& ss = pba::soft_system(springs.world);
  ASSERT_EQ(ss.size(), 3u);
  EXPECT_EQ(ss.at(0).settings().solver, pba::SoftSolver::MassSpring);
  EXPECT_EQ(ss.at(1).settings().method, pba::Method::VelocityVerlet);
  EXPECT_EQ(ss.at(2).settings().solver, pba::SoftSolver::Xpbd);
  EXPECT_DOUBLE_EQ(ss.at(2).settings().stretch_compliance, 1.0 / 40);
  EXPECT_EQ(ss.at(0).settings().substeps, 1);

  pba::Scene jelly = load("soft_jelly.json");
  const pba::SoftBody& j = pba::soft_system(jelly.world).at(0);
  EXPECT_EQ(j.tets().size(), 48u);
  EXPECT_NEAR(j.rest_volume(), 0.216, 1e-9);
  // its settings are its material's (jelly_settings at the file's 60 Hz)
  const pba::SoftBodyDef want = pba::jelly_settings({.size = pba::Vec3(0.6), .nx = 2, .ny = 2, .nz = 2, .mass = 1},
                                                    {.young = 5000, .poisson = 0.4, .damping_time = 0.005}, 1.0 / 60);
  EXPECT_EQ(j.settings().stretch_compliance, want.stretch_compliance);
  EXPECT_EQ(j.settings().volume_compliance, want.volume_compliance);
  EXPECT_EQ(j.settings().substeps, want.substeps);
}

// The jelly file's cube (E = 5 kPa, nu = 0.4: K = E / (3 (1 - 2 nu)) = 8333 Pa, G = E /
// (2 (1 + nu)) = 1786 Pa; 1 kg in a 0.6 m cube: rho = 4.63 kg/m^3) lands and rests on a
// face, and its volume follows the material:
// * during the impact no more than v / c_p is lost: a compression wave of strain v / c_p
//   (c_p = sqrt((K + 4 G / 3) / rho) = 48 m/s, the P-wave speed) sweeping the body is the
//   most a flat landing at v = sqrt(2 g 1.2 m) = 4.85 m/s can do: 10 %;
// * at rest it is squeezed by its own weight: a free column's vertical stress averages
//   m g / (2 A), the mean pressure is a third of that and dV/V = -m g / (6 A K) = -5.45e-4;
//   friction holding the base laterally raises the pressure there, the 2-cell lattice has
//   the continuum's moduli only on average (its C44 is 11 % above G): within 25 %;
// * it rests on a face: its centre at half its height plus the 5 mm thickness, less a
//   sag of m g H / (3 A E) = 1.1 mm (an edge would put it at 0.42 m).
// The drape's cloth ends up resting over the ball.
TEST(SoftScenes, JellyKeepsVolumeAndClothDrapes) {
  pba::Scene jelly = load("soft_jelly.json");
  const pba::SoftBody& j = pba::soft_system(jelly.world).at(0);
  const double young = 5000, nu = 0.4, m = 1, side = 0.6, g = 9.81;
  const double bulk = young / (3 * (1 - 2 * nu)), shear = young / (2 * (1 + nu));
  const double rho = m / (side * side * side), area = side * side;
  const double c_p = std::sqrt((bulk + 4 * shear / 3) / rho), v = std::sqrt(2 * g * 1.2);
  double worst = 0;
  for (int i = 0; i < 240; ++i) {
    jelly.world.step();
    worst = std::max(worst, std::abs(j.volume() / j.rest_volume() - 1));
  }
  EXPECT_LE(worst, v / c_p);
  const double squeeze = -m * g / (6 * area * bulk);
  EXPECT_NEAR(j.volume() / j.rest_volume() - 1, squeeze, 0.25 * std::abs(squeeze));
  EXPECT_NEAR(j.center_of_mass().y, side / 2 + 0.005, 0.005);
  pba::Scene drape = load("soft_drape.json");
  const pba::SoftBody& c = pba::soft_system(drape.world).at(0);
  for (int i = 0; i < 240; ++i) drape.world.step();
  // the middle of the cloth rests on the top of the ball (centre 0.6 + radius 0.5 + thickness)
  double top = -1;
  for (std::size_t p = 0; p < c.size(); ++p) top = std::max(top, c.position(p).y);
  EXPECT_NEAR(top, 1.11, 0.02);
}

// A jelly's settings start from jelly_settings(shape, material, the file's dt): exactly
// its compliances, damping and substeps (the shape is read first, and the step is the
// file's, not 1/60); fields given explicitly override them; no material is the default one.
TEST(SoftScenes, JellySettingsComeFromItsMaterial) {
  const std::string body =
      R"("type": "jelly", "size": [0.6, 0.4, 0.5], "cells": [2, 3, 4], "mass": 2,
         "material": {"young": 20000, "poisson": 0.45, "damping_time": 0.004})";
  const pba::JellyDef shape{.size = {0.6, 0.4, 0.5}, .nx = 2, .ny = 3, .nz = 4, .mass = 2};
  const pba::JellyMaterial mat{.young = 20000, .poisson = 0.45, .damping_time = 0.004};
  auto settings = [](const std::string& text) {
    pba::Scene s = pba::parse_scene(text, "scenes/x.json");
    return pba::soft_system(s.world).at(0).settings();
  };
  // at the file's dt
  const pba::SoftBodyDef at100 =
      settings(R"({"version": 1, "settings": {"dt": 0.01}, "soft_bodies": [{)" + body + "}]}");
  const pba::SoftBodyDef want100 = pba::jelly_settings(shape, mat, 0.01);
  EXPECT_EQ(at100.stretch_compliance, want100.stretch_compliance);
  EXPECT_EQ(at100.volume_compliance, want100.volume_compliance);
  EXPECT_EQ(at100.spring_damping, want100.spring_damping);
  EXPECT_EQ(at100.substeps, want100.substeps);
  EXPECT_EQ(at100.forces.gravity, pba::Vec3(0, -9.81, 0));  // the world's
  // without settings the world steps at 1/60 s: more substeps for the same material
  const pba::SoftBodyDef at60 = settings(R"({"version": 1, "soft_bodies": [{)" + body + "}]}");
  EXPECT_EQ(at60.substeps, pba::jelly_settings(shape, mat, 1.0 / 60).substeps);
  EXPECT_GT(at60.substeps, at100.substeps);
  // explicit fields win, the rest stays derived
  const pba::SoftBodyDef over = settings(R"({"version": 1, "soft_bodies": [{)" + body +
                                         R"(, "substeps": 40, "volume_compliance": 0}]})");
  EXPECT_EQ(over.substeps, 40);
  EXPECT_EQ(over.volume_compliance, 0.0);
  EXPECT_EQ(over.stretch_compliance, at60.stretch_compliance);
  // no material: the default one
  const pba::SoftBodyDef plain = settings(R"({"version": 1, "soft_bodies": [{"type": "jelly"}]})");
  const pba::SoftBodyDef want = pba::jelly_settings(pba::JellyDef{});
  EXPECT_EQ(plain.stretch_compliance, want.stretch_compliance);
  EXPECT_EQ(plain.volume_compliance, want.volume_compliance);
  EXPECT_EQ(plain.substeps, want.substeps);
}

// ---------------------------------------------------------------------------------------
// builders

TEST(SoftBuilders, BuildWhatTheySay) {
  pba::World w;
  pba::scenes::cloth_compare(w);
  pba::SoftSystem& soft = pba::soft_system(w);
  ASSERT_EQ(soft.size(), 2u);
  EXPECT_EQ(soft.body(w.find("mass-spring cloth")).settings().solver, pba::SoftSolver::MassSpring);
  EXPECT_EQ(soft.body(w.find("xpbd cloth")).settings().solver, pba::SoftSolver::Xpbd);
  for (int i = 0; i < 120; ++i) w.step();
  // both hang from their pinned rows and are stretched by at most 5%
  EXPECT_LT(soft.body(w.find("xpbd cloth")).strain_stats().mean, 0.01);
  EXPECT_LT(soft.body(w.find("mass-spring cloth")).strain_stats().mean, 0.05);

  // the spring builder with XPBD is the same spring (compliance 1/k)
  pba::World ws;
  const pba::EntityId s = pba::scenes::spring(ws, {.solver = pba::SoftSolver::Xpbd, .stiffness = 25});
  EXPECT_DOUBLE_EQ(pba::soft_system(ws).body(s).settings().stretch_compliance, 0.04);

  // the jelly builder's settings are its material's at the world's step
  pba::World wj({.stepper = {.fixed_dt = 1.0 / 120}});
  const pba::JellyMaterial mat{.young = 8000, .poisson = 0.3, .damping_time = 0.01};
  const pba::EntityId jid = pba::scenes::jelly_drop(wj, {.cells = 2, .size = 0.4, .mass = 0.5, .material = mat});
  const pba::SoftBodyDef& got = pba::soft_system(wj).body(jid).settings();
  const pba::SoftBodyDef want =
      pba::jelly_settings({.size = pba::Vec3(0.4), .nx = 2, .ny = 2, .nz = 2, .mass = 0.5}, mat, 1.0 / 120);
  EXPECT_EQ(got.stretch_compliance, want.stretch_compliance);
  EXPECT_EQ(got.volume_compliance, want.volume_compliance);
  EXPECT_EQ(got.spring_damping, want.spring_damping);
  EXPECT_EQ(got.substeps, want.substeps);
  EXPECT_EQ(got.friction, 0.6);
}

// ---------------------------------------------------------------------------------------
// bad soft-body fields: the message names the file and the JSON path

TEST(SoftBadFiles, FieldsAreNamedByPath) {
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "cloth", "nx": 1}]})"),
            "scenes/x.json: /soft_bodies/0/nx: must be an integer in [2, 4096], got 1");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "rope", "stretch_compliance": -1}]})"),
            "scenes/x.json: /soft_bodies/0/stretch_compliance: must be >= 0, got -1");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "spring", "a": [1, 1, 1], "b": [1, 1, 1]}]})"),
            "scenes/x.json: /soft_bodies/0/b: zero rest length: b coincides with a at (1, 1, 1)");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "spring", "stiffness": -3}]})"),
            "scenes/x.json: /soft_bodies/0/stiffness: must be > 0, got -3");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "blob"}]})"),
            "scenes/x.json: /soft_bodies/0/type: unknown value \"blob\" (expected one of \"spring\", \"rope\", "
            "\"cloth\", \"jelly\")");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "jelly", "cells": [2, 0, 2]}]})"),
            "scenes/x.json: /soft_bodies/0/cells/1: must be an integer in [1, 64], got 0");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "cloth", "substeps": 0}]})"),
            "scenes/x.json: /soft_bodies/0/substeps: must be an integer in [1, 10000], got 0");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "cloth", "pins": "top"}]})"),
            "scenes/x.json: /soft_bodies/0/pins: unknown value \"top\" (expected one of \"none\", \"first-row\", "
            "\"first-row-corners\", \"first-column\")");
  // a jelly's material, by path
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "jelly", "material": {"poisson": 0.6}}]})"),
            "scenes/x.json: /soft_bodies/0/material/poisson: must be in [0.27, 0.49], got 0.6");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "jelly", "material": {"young": 0}}]})"),
            "scenes/x.json: /soft_bodies/0/material/young: must be > 0, got 0");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "jelly", "material": {"damping_time": -1}}]})"),
            "scenes/x.json: /soft_bodies/0/material/damping_time: must be >= 0, got -1");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "jelly", "material": {"shear": 1}}]})"),
            "scenes/x.json: /soft_bodies/0/material/shear: unknown field (allowed here: young, poisson, "
            "damping_time)");
  const std::string mt = error_of(R"({"version": 1, "soft_bodies": [{"type": "jelly", "material": 5}]})");
  EXPECT_EQ(mt.rfind("scenes/x.json: /soft_bodies/0/material: must be an object", 0), 0u) << mt;
  const std::string mc = error_of(R"({"version": 1, "soft_bodies": [{"type": "cloth", "material": {}}]})");
  EXPECT_EQ(mc.rfind("scenes/x.json: /soft_bodies/0/material: unknown field", 0), 0u) << mc;
  // shape fields belong to their type
  const std::string m = error_of(R"({"version": 1, "soft_bodies": [{"type": "rope", "nx": 4}]})");
  EXPECT_EQ(m.rfind("scenes/x.json: /soft_bodies/0/nx: unknown field (allowed here: ", 0), 0u) << m;
  // library validation (a degenerate cloth) still names the item
  const std::string p = error_of(
      R"({"version": 1, "soft_bodies": [{"type": "cloth", "edge_u": [1, 0, 0], "edge_v": [2, 0, 0]}]})");
  EXPECT_EQ(p, "scenes/x.json: /soft_bodies/0/edge_v: must not be parallel to edge_u (1, 0, 0)") << p;
  // the old reserved names are plain unknown fields now, pointing at soft_bodies
  const std::string c = error_of(R"({"version": 1, "cloth": []})");
  EXPECT_NE(c.find("soft_bodies"), std::string::npos) << c;
}

// A builder's refusal names the JSON path of the field it came from, not only the item
// (until 2026-12-07: "/soft_bodies/0: RopeDef.mass split among ..."); a refusal several
// fields decide (a particle beyond a float: "see from and to") stays with the item.
TEST(SoftBadFiles, BuilderErrorsNameTheFieldsPath) {
  struct Case {
    const char* item;  // one soft body
    const char* want;  // the message's start
  };
  for (const Case& c : {
           Case{R"({"type": "rope", "mass": 1e-300})",
                "/soft_bodies/0/mass: split among 21 particles (kg each): must be in ["},
           Case{R"({"type": "cloth", "mass": 1e-300})", "/soft_bodies/0/mass: split among 1024 particles (kg each)"},
           Case{R"({"type": "jelly", "cells": [1, 1, 1], "mass": 1e300})",
                "/soft_bodies/0/mass: split among 8 particles (kg each)"},
           Case{R"({"type": "spring", "velocity_b": [1e39, 0, 0]})", "/soft_bodies/0/velocity_b: must fit a float"},
           Case{R"({"type": "jelly", "velocity": [0, 1e39, 0]})", "/soft_bodies/0/velocity: must fit a float"},
           // a box so small its edges have no finite compliance, or a material so soft: size,
           // cells and material decide together, so the item (until 2026-12-07 always
           // /size, a field the second file does not have)
           Case{R"({"type": "jelly", "size": [1e-200, 1e-200, 1e-200]})",
                "/soft_bodies/0: jelly_settings: JellyDef.size (1e-200, 1e-200, 1e-200) m in 4 x 4 x 4 cells and "
                "JellyMaterial.young 5000 Pa give an edge stiffness k = 4 G a / 3 = 0 N/m"},
           Case{R"({"type": "jelly", "material": {"young": 1e-308}})", "/soft_bodies/0: jelly_settings: JellyDef.size "},
           // a material field the builder refuses alone, under "material" (until 2026-12-07
           // "/soft_bodies/0: JellyMaterial.damping_time: ...")
           Case{R"({"type": "jelly", "material": {"damping_time": 1e307}})",
                "/soft_bodies/0/material/damping_time: 1e+307 s gives the edges the damping c = tau k = inf N s/m"},
           // several fields decide: the item, and the message names them
           Case{R"({"type": "rope", "to": [1e40, 2, 0]})", "/soft_bodies/0: RopeDef: particle 1 at "},
           // a setting the builder refuses (the reader checks >= 0 only): its own path
           // (until 2026-12-07 "/soft_bodies/0: SoftBodyDef.forces.linear_drag: ...")
           Case{R"({"type": "rope", "drag": {"linear": 1e39}})", "/soft_bodies/0/drag/linear: must fit a float"},
           Case{R"({"type": "jelly", "drag": {"quadratic": 1e39}})",
                "/soft_bodies/0/drag/quadratic: must fit a float"}}) {
    const std::string msg = error_of(std::string(R"({"version": 1, "soft_bodies": [)") + c.item + "]}");
    EXPECT_EQ(msg.rfind(std::string("scenes/x.json: ") + c.want, 0), 0u) << msg;
  }
  EXPECT_NE(error_of(R"({"version": 1, "soft_bodies": [{"type": "rope", "to": [1e40, 2, 0]}]})").find("see from and to"),
            std::string::npos);
  // a thickness past what one substep's push keeps finite (9e18 m/s h) loads, and its first
  // step refuses it by name (its bound depends on the substep, known at the step)
  pba::Scene s = pba::parse_scene(R"({"version": 1, "soft_bodies": [{"type": "cloth", "thickness": 1e30}]})",
                                  "scenes/x.json");
  const std::string th = pba::test_support::error_of([&] { s.world.step(); });
  EXPECT_EQ(th.rfind("soft body of entity '': SoftBodyDef.thickness: must be at most kMaxParticleSpeed h = 9e+18 "
                     "m/s * ", 0),
            0u)
      << th;
}

// A field of the other solver was read and ignored without a word: an integrator on an
// XPBD body, a stiffness under XPBD, a compliance or iterations under mass-spring, a
// compliance on a spring (its stiffness sets it). Each is refused by path, saying which
// solver takes what.
TEST(SoftBadFiles, TheOtherSolversFieldsAreRefused) {
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "rope", "integrator": "rk4"}]})"),
            "scenes/x.json: /soft_bodies/0/integrator: an integrator is the mass-spring solver's (\"solver\": "
            "\"mass-spring\"); the XPBD solver projects constraints in \"substeps\" of \"iterations\" sweeps and "
            "takes none");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "cloth", "shear_stiffness": 500}]})"),
            "scenes/x.json: /soft_bodies/0/shear_stiffness: a stiffness (N/m) is the mass-spring solver's "
            "(\"solver\": \"mass-spring\"); the XPBD solver takes \"shear_compliance\", its inverse (m/N)");
  // a jelly is XPBD unless told: its material gives compliances
  EXPECT_NE(error_of(R"({"version": 1, "soft_bodies": [{"type": "jelly", "volume_stiffness": 5}]})")
                .find("/soft_bodies/0/volume_stiffness: a stiffness (N/m) is the mass-spring solver's"),
            std::string::npos);
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "rope", "solver": "mass-spring", "bend_compliance": 0.01}]})"),
            "scenes/x.json: /soft_bodies/0/bend_compliance: a compliance (m/N) is the XPBD solver's (\"solver\": "
            "\"xpbd\"); the mass-spring solver takes \"bend_stiffness\", its inverse (N/m)");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "cloth", "solver": "mass-spring", "iterations": 4}]})"),
            "scenes/x.json: /soft_bodies/0/iterations: constraint iterations are the XPBD solver's; the "
            "mass-spring solver integrates in \"substeps\" with its \"integrator\"");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "spring", "stretch_compliance": 0.01}]})"),
            "scenes/x.json: /soft_bodies/0/stretch_compliance: a spring's compliance is 1 / \"stiffness\" (N/m): "
            "give its stiffness");
  // a spring's stretch is its "stiffness", never "stretch_stiffness" (a field springs
  // refuse: until 2026-12-07 the refusal pointed there)
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "spring", "solver": "mass-spring", "stretch_compliance": 0.01}]})"),
            "scenes/x.json: /soft_bodies/0/stretch_compliance: a compliance (m/N) is the XPBD solver's (\"solver\": "
            "\"xpbd\"); the mass-spring solver takes a spring's \"stiffness\" (N/m)");
  // each solver's own fields still read
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "rope", "solver": "mass-spring", "integrator": "rk4",
                          "stretch_stiffness": 500, "substeps": 20}]})"),
            "");
  EXPECT_EQ(error_of(R"({"version": 1, "soft_bodies": [{"type": "rope", "iterations": 3, "stretch_compliance": 1e-4}]})"),
            "");
  // the shipped files use each field with its solver
  for (const char* f : {"soft_spring.json", "soft_rope.json", "soft_flag.json", "soft_drape.json",
                        "soft_hull_drape.json", "soft_jelly.json"})
    EXPECT_NO_THROW(load(f)) << f;
}
