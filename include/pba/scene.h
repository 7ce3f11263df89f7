// pba scenes: the JSON scene-file format and the scene builders.
//
// A scene file (docs/scene-format.md) describes a World: settings (time step, integrator,
// gravity, drag, wind) and arrays of particles, emitters, forcers and colliders, any of
// which may carry a kinematic path. Later modules add their own arrays (springs, cloth,
// rigid bodies, skeletons). A bad file gets an Error naming the file, the JSON path of the
// bad field and what is wrong, e.g.
//   "scenes/x.json: /emitters/2/rate: must be finite and >= 0, got -5"
// and syntax errors give the line and column.
//
// Scene builders are functions of the World (DESIGN example 5): the samples app, the
// tests and the benchmark all build the same scenes by calling them.
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <string_view>

#include "pba/soft.h"
#include "pba/world.h"

namespace pba {

/// The scene-file format version this build reads and writes.
inline constexpr int kSceneFormatVersion = 1;

/// A loaded scene: its world and descriptive text.
struct Scene {
  std::string name{};         ///< "name" field, or the file stem
  std::string description{};  ///< "description" field, may be empty
  World world;              ///< the world, at time 0, ready to step
};

/// Reads and builds a scene file. Throws Error naming the file and the JSON path of the
/// first bad field (or the line and column of a syntax error).
Scene load_scene(const std::filesystem::path& file);
/// Builds a scene from JSON text; `source` names it in error messages (e.g. the path).
Scene parse_scene(std::string_view json_text, std::string_view source);

namespace scenes {

/// Workbook 4.2 exercise 1 (and 2 with drag): one projectile fired from the origin over
/// a ground plane at y = 0.
struct BallisticParams {
  double speed = 15;         ///< launch speed (m/s), >= 0
  double angle_deg = 45;     ///< launch elevation (degrees), in [0, 90]
  double linear_drag = 0;    ///< b (kg/s), >= 0; tau = mass / b
  double mass = 0.2;         ///< projectile mass (kg), > 0
  double radius = 0.05;      ///< projectile radius (m), > 0
  double restitution = 0.3;  ///< ground restitution, in [0, 1]
};
/// Builds the ballistic experiment; returns the projectile entity ("projectile").
EntityId ballistic(World& world, const BallisticParams& p = {});

/// The closed-form projectile position (m) at time t (s) for a launch from the origin:
/// with b = 0 the parabola, otherwise x(t) = v0 tau (1 - e^{-t/tau}) + g tau (t - tau (1 -
/// e^{-t/tau})) with tau = m / b. `g` is the gravity vector (m/s^2).
Vec3 ballistic_position(const BallisticParams& p, const Vec3& g, double t);

/// Workbook 4.2 exercise 3: balls dropped in a row onto a ground plane and two boxes.
struct BouncingBallsParams {
  int count = 8;             ///< balls, in [1, 10000]
  double restitution = 0.8;  ///< of the ground and the boxes, in [0, 1]
  double friction = 0.2;     ///< Coulomb coefficient, >= 0
  bool boxes = true;         ///< add two boxes (one tilted) under part of the row
  bool moving_paddle = true; ///< add a box paddle on a circular kinematic path
};
/// Builds the bouncing balls.
void bouncing_balls(World& world, const BouncingBallsParams& p = {});

/// A fountain (or sparks) emitter over a ground plane: at rate x lifetime live particles.
struct FountainParams {
  double rate = 20000;       ///< particles per second, >= 0 (100k live at 20k/s x 5 s)
  double lifetime = 5;       ///< seconds, > 0
  double speed = 8;          ///< launch speed (m/s)
  double spread = 0.25;      ///< cone half-angle (rad)
  bool sparks = false;       ///< sparks: hot colours, bouncy ground, short lives
  std::size_t max_alive = 0; ///< cap on live particles (0 = none)
};
/// Builds the fountain; returns the emitter entity ("fountain").
EntityId fountain(World& world, const FountainParams& p = {});

/// Wind and drag: a column of light particles released into steady and gusting wind with
/// quadratic drag, over a ground plane.
struct WindDragParams {
  int count = 64;                ///< particles, in [1, 100000]
  Wind wind{{4, 0, 0}, 2, 0.7, 11};  ///< the wind (m/s)
  double quadratic_drag = 0.002; ///< c (kg/m)
  double linear_drag = 0.0;      ///< b (kg/s)
};
/// Builds wind and drag (sets the world's drag and wind).
void wind_and_drag(World& world, const WindDragParams& p = {});

/// A particle stream through Forcer volumes: a fan, a vortex, and an attractor.
struct ForcerStreamParams {
  double rate = 2000;        ///< particles per second
  double fan_strength = 0.004;     ///< N
  double vortex_strength = 0.003;  ///< N
  double attractor_strength = 0.002;  ///< N
  bool air_cannon = false;   ///< pulse the fan (0.3 s on every 1 s)
};
/// Builds the forcer stream.
void forcer_stream(World& world, const ForcerStreamParams& p = {});

// ---- soft bodies (workbook 4.3): each is a SoftBody component of one entity in the
//      world's SoftSystem (soft_system(world)); gravity and wind come from the world ----

/// Workbook 4.3 exercise 2: one spring hanging from a fixed anchor at (0, 2, 0), released
/// `stretch` beyond its rest length, to compare integrators (one integrator step per tick).
struct SpringParams {
  SoftSolver solver = SoftSolver::MassSpring;  ///< mass-spring (any integrator) or XPBD (alpha = 1/k)
  Method method = Method::SemiImplicitEuler;   ///< the integrator (mass-spring)
  double stiffness = 40;   ///< k (N/m), > 0
  double mass = 0.5;       ///< the bob's mass (kg), > 0
  double damping = 0;      ///< c (N s/m), >= 0
  double rest_length = 1;  ///< l0 (m), > 0
  double stretch = 0.4;    ///< initial extension beyond the rest length (m), > -rest_length
};
/// Builds the spring; returns its entity ("spring").
EntityId spring(World& world, const SpringParams& p = {});

/// A rope (XPBD) pinned at one end, released horizontally to swing over a sphere and
/// fall onto the ground.
struct RopeParams {
  int segments = 30;     ///< segments, in [1, 10000]
  double length = 2;     ///< m, > 0
  double mass = 0.5;     ///< kg, > 0
  int substeps = 20;     ///< XPBD substeps per tick, in [1, 10000]
  bool obstacle = true;  ///< add the sphere under it
};
/// Builds the rope; returns its entity ("rope").
EntityId rope(World& world, const RopeParams& p = {});

/// A flag (XPBD cloth) on a pole in gusting wind, with per-triangle drag and lift.
struct ClothFlagParams {
  int nx = 40;                          ///< particles along the flag, in [2, 4096]
  int ny = 26;                          ///< particles up the pole, in [2, 4096]
  double width = 2.0, height = 1.3;     ///< m, > 0
  double mass = 0.3;                    ///< kg, > 0
  int substeps = 12;                    ///< in [1, 10000]
  Wind wind{{7, 0, 1.5}, 3, 0.7, 5};    ///< the wind
  double drag = 1.0, lift = 0.6;        ///< aerodynamic coefficients, >= 0
};
/// Builds the flag (and sets the world's wind); returns its entity ("flag").
EntityId cloth_flag(World& world, const ClothFlagParams& p = {});

/// A square cloth (XPBD) dropped flat onto a sphere above a ground plane with friction.
struct ClothDrapeParams {
  int n = 40;             ///< particles per side, in [2, 4096]
  double size = 1.6;      ///< side (m), > 0
  int substeps = 15;      ///< in [1, 10000]
  double friction = 0.4;  ///< Coulomb coefficient of the sphere and ground, >= 0
};
/// Builds the drape; returns the cloth's entity ("cloth").
EntityId cloth_drape(World& world, const ClothDrapeParams& p = {});

/// A tearable hanging cloth (XPBD) pinned along its top edge, for pulling with the mouse
/// (SoftBody::grab) until it tears.
struct ClothTearParams {
  int n = 40;                ///< particles per side, in [2, 4096]
  double tear_strain = 0.4;  ///< strain at which a constraint breaks, > 0
  int substeps = 15;         ///< in [1, 10000]
};
/// Builds the cloth; returns its entity ("cloth").
EntityId cloth_tear(World& world, const ClothTearParams& p = {});

/// A jelly cube (XPBD tetrahedra with volume constraints) dropped onto the ground,
/// tilted 0.1 rad so that it lands on an edge, bounces and wobbles. Its settings are
/// jelly_settings(cube, material, the world's fixed step) with friction 0.6.
struct JellyDropParams {
  int cells = 4;                ///< cells per axis, in [1, 64] (even: mirror-symmetric lattice)
  double size = 0.6;            ///< edge (m), finite and > 0
  double height = 1.5;          ///< initial centre height (m), finite
  double mass = 1;              ///< kg, finite and > 0
  /// Young's modulus (Pa, > 0), Poisson ratio (in [0.27, 0.49]) and damping time (s, >= 0)
  /// from which jelly_settings derives the edge and volume compliances, the edge damping
  /// and the substeps. The default but for a damping time of 5 ms: the default 2.5 ms
  /// (damping ratio about 0.04 for the sway) lets this drop roll 0.9 m, 5 ms stops it
  /// within 0.25 m of where it landed (measured at 60 Hz).
  JellyMaterial material{.damping_time = 5e-3};
};
/// Builds the jelly; returns its entity ("jelly").
EntityId jelly_drop(World& world, const JellyDropParams& p = {});

/// The same hanging cloth twice, side by side: a mass-spring network under `method`
/// (stiff springs need many substeps) on the left, XPBD on the right.
struct ClothCompareParams {
  int n = 16;                                 ///< particles per side, in [2, 4096]
  Method method = Method::SemiImplicitEuler;  ///< the mass-spring integrator
  double stiffness = 2000;                    ///< mass-spring k (N/m), > 0
  int mass_spring_substeps = 40;              ///< in [1, 10000]
  int xpbd_substeps = 10;                     ///< in [1, 10000]
};
/// Builds both cloths ("mass-spring cloth" and "xpbd cloth").
void cloth_compare(World& world, const ClothCompareParams& p = {});

/// A named builder with its default parameters, for menus, tests and `pba run --builder`.
struct Builder {
  std::string_view name;         ///< e.g. "bouncing-balls"
  std::string_view description;  ///< one line
  void (*build)(World&);         ///< builds with default parameters
};
/// Every builder above, in a fixed order.
std::span<const Builder> builders();

}  // namespace scenes
}  // namespace pba
