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
