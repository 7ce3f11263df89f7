// Scene builders: functions of the World shared by the samples, the tests and the
// benchmark (DESIGN example 5).
#include <array>
#include <cmath>
#include <string>

#include "pba/scene.h"

namespace pba::scenes {

namespace {

EntityId ground(World& w, double restitution, double friction) {
  const EntityId g = w.create_entity({.name = "ground"});
  w.add_collider(g, {.shape = {.type = ShapeType::Plane, .normal = {0, 1, 0}, .offset = 0},
                     .material = {.restitution = restitution, .friction = friction}});
  return g;
}
}  // namespace

EntityId ballistic(World& w, const BallisticParams& p) {
  // validate the parameters the closed form relies on
  require_non_negative(p.speed, "BallisticParams.speed");
  require_in_range(p.angle_deg, 0, 90, "BallisticParams.angle_deg");
  require_non_negative(p.linear_drag, "BallisticParams.linear_drag");
  // linear drag only: the closed form is for b, not for quadratic drag or wind
  w.particles().forces().linear_drag = p.linear_drag;
  ground(w, p.restitution, 0.3);
  const double a = p.angle_deg * kPi / 180;
  const EntityId e = w.create_entity({.name = "projectile"});
  w.add_particle(e, {.velocity = {p.speed * std::cos(a), p.speed * std::sin(a), 0},
                     .mass = p.mass,
                     .radius = p.radius,
                     .color = colors::orange});
  return e;
}

Vec3 ballistic_position(const BallisticParams& p, const Vec3& g, double t) {
  const double a = p.angle_deg * kPi / 180;
  const Vec3 v0(p.speed * std::cos(a), p.speed * std::sin(a), 0);
  if (p.linear_drag <= 0) return v0 * t + 0.5 * g * t * t;
  const double tau = p.mass / p.linear_drag;
  const double e = 1 - std::exp(-t / tau);
  return v0 * tau * e + g * tau * (t - tau * e);
}

void bouncing_balls(World& w, const BouncingBallsParams& p) {
  require_count(p.count, 1, 10000, "BouncingBallsParams.count");
  ground(w, p.restitution, p.friction);
  const SurfaceMaterial m{.restitution = p.restitution, .friction = p.friction};
  // two boxes under part of the row, one tilted by 20 degrees
  if (p.boxes) {
    const EntityId b1 = w.create_entity({.name = "box", .pose = {.position = {-1.5, 0.25, 0}}});
    w.add_collider(b1, {.shape = {.type = ShapeType::Box, .half_extents = {0.6, 0.25, 0.6}}, .material = m});
    const EntityId b2 = w.create_entity(
        {.name = "ramp", .pose = {.position = {1.5, 0.3, 0}, .rotation = glm::angleAxis(0.35, Vec3(0, 0, 1))}});
    w.add_collider(b2, {.shape = {.type = ShapeType::Box, .half_extents = {0.7, 0.1, 0.6}}, .material = m});
  }
  // a paddle on a circular path
  if (p.moving_paddle) {
    const EntityId pad = w.create_entity({.name = "paddle"});
    w.add_collider(pad, {.shape = {.type = ShapeType::Box, .half_extents = {0.4, 0.05, 0.4}}, .material = m});
    w.add_kinematic(pad, {.path = PathType::Circular, .center = {0, 0.8, 0}, .axis = {0, 0, 1}, .radius = 0.4,
                          .angular_speed = 1.5});
  }
  // the balls in a row, at staggered heights
  for (int i = 0; i < p.count; ++i) {
    const double x = p.count == 1 ? 0.0 : -2.5 + 5.0 * i / (p.count - 1);
    const EntityId b = w.create_entity({.name = "ball " + std::to_string(i),
                                        .pose = {.position = {x, 2.0 + 0.15 * (i % 5), 0.05 * (i % 3)}}});
    w.add_particle(b, {.mass = 0.1, .radius = 0.08, .color = colors::blue});
  }
}

EntityId fountain(World& w, const FountainParams& p) {
  ground(w, p.sparks ? 0.5 : 0.1, p.sparks ? 0.1 : 0.6);
  const EntityId e = w.create_entity({.name = "fountain", .pose = {.position = {0, 0.05, 0}}});
  EmitterDef d;
  d.rate = p.rate;
  d.lifetime = p.lifetime;
  d.lifetime_jitter = 0.2;
  d.speed = p.speed;
  d.speed_jitter = 0.15;
  d.spread = p.spread;
  d.mass = 0.0005;
  d.radius = 0.01;
  d.max_alive = p.max_alive;
  d.seed = 2024;
  if (p.sparks) {
    d.start_color = Color::hex(0xfff2b0);
    d.end_color = Color::rgb(0.9f, 0.2f, 0.05f, 0.0f);
  } else {
    d.start_color = Color::hex(0x9fd4ff);
    d.end_color = Color::rgb(0.1f, 0.3f, 0.9f, 0.2f);
  }
  w.particles().forces().quadratic_drag = std::max(w.particles().forces().quadratic_drag, 1e-5);
  w.add_emitter(e, d);
  return e;
}

void wind_and_drag(World& w, const WindDragParams& p) {
  require_count(p.count, 1, 100000, "WindDragParams.count");
  w.particles().forces().wind = p.wind;
  w.particles().forces().quadratic_drag = p.quadratic_drag;
  w.particles().forces().linear_drag = p.linear_drag;
  w.particles().forces().validate("WindDragParams");
  ground(w, 0.2, 0.4);
  // a column of light balls with a spread of masses (heavier ones drift less)
  for (int i = 0; i < p.count; ++i) {
    const EntityId e = w.create_entity({.name = "leaf " + std::to_string(i)});
    w.add_particle(e, {.position = {-3 + 0.02 * (i % 7), 0.5 + 4.0 * i / p.count, 0.1 * ((i * 7) % 5) - 0.2},
                       .mass = 0.005 * (1 + i % 4),
                       .radius = 0.03,
                       .color = i % 4 == 0 ? colors::green : colors::yellow});
  }
}

void forcer_stream(World& w, const ForcerStreamParams& p) {
  ground(w, 0.2, 0.3);
  w.particles().forces().quadratic_drag = std::max(w.particles().forces().quadratic_drag, 2e-5);
  // the stream: a narrow jet to the right
  const EntityId src = w.create_entity({.name = "stream", .pose = {.position = {-3, 1, 0}}});
  EmitterDef d;
  d.direction = Vec3(1, 0.25, 0);
  d.spread = 0.05;
  d.speed = 5;
  d.rate = p.rate;
  d.lifetime = 4;
  d.mass = 0.001;
  d.radius = 0.01;
  d.start_color = colors::cyan;
  d.end_color = Color::rgb(0.2f, 0.2f, 0.8f, 0.1f);
  d.seed = 7;
  w.add_emitter(src, d);
  // a fan (or air cannon) pushing the jet up
  const EntityId fan = w.create_entity({.name = "fan", .pose = {.position = {-1.5, 1, 0}}});
  Forcer f;
  f.kind = ForcerKind::Fan;
  f.shape = ForcerShape::Box;
  f.half_extents = Vec3(0.4, 0.6, 0.4);
  f.direction = Vec3(0, 1, 0);
  f.strength = p.fan_strength;
  if (p.air_cannon) f.pulse_period = 1, f.pulse_duration = 0.3;
  w.add_forcer(fan, f);
  // a vortex that swirls it
  const EntityId vortex = w.create_entity({.name = "vortex", .pose = {.position = {0.5, 1.5, 0}}});
  w.add_forcer(vortex, {.kind = ForcerKind::Vortex, .shape = ForcerShape::Cylinder, .radius = 0.8, .half_height = 1.0,
                        .strength = p.vortex_strength, .pull = 0.3 * p.vortex_strength});
  // an attractor on a slow circle that gathers what is left
  const EntityId att = w.create_entity({.name = "attractor"});
  w.add_forcer(att, {.kind = ForcerKind::Attractor, .shape = ForcerShape::Sphere, .radius = 1.2,
                     .strength = p.attractor_strength, .softening = 0.2});
  w.add_kinematic(att, {.path = PathType::Circular, .center = {2.5, 1.2, 0}, .axis = {0, 1, 0}, .radius = 0.5,
                        .angular_speed = 0.8});
}

// ---------------------------------------------------------------------------------------
// soft bodies

namespace {
// a soft body's settings with the world's gravity and wind (not its per-particle drag,
// whose kg/s would be far too strong for cloth particles of a few grams)
SoftBodyDef soft_def(const World& w) {
  SoftBodyDef d;
  d.forces.gravity = w.gravity();
  d.forces.wind = w.particles().forces().wind;
  return d;
}

EntityId add_soft(World& w, const char* name, SoftBody body) {
  const EntityId e = w.create_entity({.name = name});
  soft_system(w).add(w, e, std::move(body));
  return e;
}
}  // namespace

EntityId spring(World& w, const SpringParams& p) {
  // the bob hangs below the anchor, stretched; one integrator step per tick
  require_positive(p.rest_length, "SpringParams.rest_length");
  if (!(p.rest_length + p.stretch > 0))
    throw Error("SpringParams.stretch: must be > -rest_length, got " + format_value(p.stretch));
  SoftBodyDef d = soft_def(w);
  d.solver = p.solver;
  d.method = p.method;
  d.substeps = 1;
  const Vec3 anchor(0, 2, 0);
  return add_soft(w, "spring",
                  SoftBody::spring({.a = anchor,
                                    .b = anchor - Vec3(0, p.rest_length + p.stretch, 0),
                                    .mass = p.mass,
                                    .stiffness = p.stiffness,
                                    .damping = p.damping,
                                    .rest_length = p.rest_length},
                                   d));
}

EntityId rope(World& w, const RopeParams& p) {
  require_positive(p.length, "RopeParams.length");
  ground(w, 0.0, 0.5);
  if (p.obstacle) {
    const EntityId ball = w.create_entity({.name = "ball", .pose = {.position = {0.2, 1.0, 0}}});
    w.add_collider(ball, {.shape = {.type = ShapeType::Sphere, .radius = 0.35}, .material = {.friction = 0.3}});
  }
  SoftBodyDef d = soft_def(w);
  d.substeps = p.substeps;
  d.bend_compliance = 1e-3;
  d.thickness = 0.02;
  return add_soft(w, "rope",
                  SoftBody::rope({.from = {-1, 2.2, 0}, .to = {-1 + p.length, 2.2, 0}, .segments = p.segments,
                                  .mass = p.mass},
                                 d));
}

EntityId cloth_flag(World& w, const ClothFlagParams& p) {
  // the wind is the world's, so particles and other bodies feel it too
  w.particles().forces().wind = p.wind;
  ground(w, 0.0, 0.5);
  const EntityId pole = w.create_entity({.name = "pole", .pose = {.position = {0, 1.25, 0}}});
  w.add_collider(pole, {.shape = {.type = ShapeType::Box, .half_extents = {0.03, 1.25, 0.03}}});
  SoftBodyDef d = soft_def(w);
  d.substeps = p.substeps;
  d.aero = {.air_density = 1.2, .drag = p.drag, .lift = p.lift};
  d.bend_compliance = 1e-3;
  d.thickness = 0.005;
  return add_soft(w, "flag",
                  SoftBody::cloth_grid({.origin = {0.05, 2.45, 0}, .edge_u = {p.width, 0, 0},
                                        .edge_v = {0, -p.height, 0}, .nx = p.nx, .ny = p.ny, .mass = p.mass,
                                        .pins = ClothPins::FirstColumn},
                                       d));
}

EntityId cloth_drape(World& w, const ClothDrapeParams& p) {
  require_positive(p.size, "ClothDrapeParams.size");
  ground(w, 0.0, p.friction);
  const EntityId ball = w.create_entity({.name = "ball", .pose = {.position = {0, 0.6, 0}}});
  w.add_collider(ball, {.shape = {.type = ShapeType::Sphere, .radius = 0.5}, .material = {.friction = p.friction}});
  SoftBodyDef d = soft_def(w);
  d.substeps = p.substeps;
  d.bend_compliance = 2e-3;
  d.thickness = 0.01;
  d.damping = 0.2;
  return add_soft(w, "cloth",
                  SoftBody::cloth_grid({.origin = {-p.size / 2, 1.6, -p.size / 2}, .edge_u = {p.size, 0, 0},
                                        .edge_v = {0, 0, p.size}, .nx = p.n, .ny = p.n, .mass = 0.5,
                                        .pins = ClothPins::None},
                                       d));
}

EntityId cloth_tear(World& w, const ClothTearParams& p) {
  require_positive(p.tear_strain, "ClothTearParams.tear_strain");
  SoftBodyDef d = soft_def(w);
  d.substeps = p.substeps;
  d.tear_strain = p.tear_strain;
  d.bend_compliance = 1e-3;
  d.damping = 0.1;
  return add_soft(w, "cloth",
                  SoftBody::cloth_grid({.origin = {-0.8, 2.4, 0}, .edge_u = {1.6, 0, 0}, .edge_v = {0, -1.6, 0},
                                        .nx = p.n, .ny = p.n, .mass = 0.5, .pins = ClothPins::FirstRow},
                                       d));
}

EntityId jelly_drop(World& w, const JellyDropParams& p) {
  // the cube, tilted about (1, 0, 1) so that it lands on an edge
  require_positive(p.size, "JellyDropParams.size");
  const Quat tilt = glm::angleAxis(0.1, glm::normalize(Vec3(1, 0, 1)));
  const JellyDef j{.center = {0, p.height, 0}, .size = Vec3(p.size), .rotation = tilt, .nx = p.cells,
                   .ny = p.cells, .nz = p.cells, .mass = p.mass};
  // its settings from the material at the world's step, then gravity, wind and contact
  ground(w, 0.0, 0.6);
  SoftBodyDef d = jelly_settings(j, p.material, w.stepper().settings().fixed_dt);
  const SoftBodyDef world = soft_def(w);
  d.forces = world.forces;
  d.thickness = 0.005;
  d.friction = 0.6;
  return add_soft(w, "jelly", SoftBody::jelly_box(j, d));
}

void cloth_compare(World& w, const ClothCompareParams& p) {
  // mass-spring on the left, XPBD on the right, the same grid and mass
  SoftBodyDef ms = soft_def(w);
  ms.solver = SoftSolver::MassSpring;
  ms.method = p.method;
  ms.substeps = p.mass_spring_substeps;
  ms.stretch_stiffness = ms.shear_stiffness = p.stiffness;
  ms.bend_stiffness = p.stiffness / 100;
  ms.spring_damping = 0.01;
  add_soft(w, "mass-spring cloth",
           SoftBody::cloth_grid({.origin = {-2.1, 2.2, 0}, .edge_u = {1.6, 0, 0}, .edge_v = {0, 0, 1.6}, .nx = p.n,
                                 .ny = p.n, .mass = 0.5},
                                ms));
  SoftBodyDef x = soft_def(w);
  x.substeps = p.xpbd_substeps;
  add_soft(w, "xpbd cloth",
           SoftBody::cloth_grid({.origin = {0.5, 2.2, 0}, .edge_u = {1.6, 0, 0}, .edge_v = {0, 0, 1.6}, .nx = p.n,
                                 .ny = p.n, .mass = 0.5},
                                x));
}

std::span<const Builder> builders() {
  static constexpr std::array<Builder, 13> kBuilders = {{
      {"ballistic", "one projectile fired at 45 degrees over a ground plane (workbook 4.2 ex. 1)",
       [](World& w) { ballistic(w); }},
      {"ballistic-drag", "the projectile with linear drag, tau = 2 s (workbook 4.2 ex. 2)",
       [](World& w) { ballistic(w, {.linear_drag = 0.1}); }},
      {"bouncing-balls", "balls on a plane, boxes and a moving paddle (workbook 4.2 ex. 3)",
       [](World& w) { bouncing_balls(w); }},
      {"fountain", "a fountain emitter with 100k live particles", [](World& w) { fountain(w); }},
      {"wind-drag", "light particles in gusting wind with quadratic drag", [](World& w) { wind_and_drag(w); }},
      {"forcer-stream", "a particle stream through a fan, a vortex and an attractor",
       [](World& w) { forcer_stream(w); }},
      {"spring", "one spring from a fixed anchor, mass-spring with semi-implicit Euler (workbook 4.3 ex. 2)",
       [](World& w) { spring(w); }},
      {"rope", "an XPBD rope swinging over a sphere onto the ground", [](World& w) { rope(w); }},
      {"cloth-flag", "an XPBD flag on a pole in gusting wind with drag and lift", [](World& w) { cloth_flag(w); }},
      {"cloth-drape", "an XPBD cloth dropped onto a sphere and the ground", [](World& w) { cloth_drape(w); }},
      {"cloth-tear", "a tearable hanging XPBD cloth (pull it with the mouse)", [](World& w) { cloth_tear(w); }},
      {"jelly-drop", "a tetrahedral jelly cube dropped on the ground", [](World& w) { jelly_drop(w); }},
      {"cloth-compare", "the same cloth as a mass-spring network and with XPBD, side by side",
       [](World& w) { cloth_compare(w); }},
  }};
  return kBuilders;
}

}  // namespace pba::scenes
