// Helpers shared by the particle samples (app/samples/particles_*.cpp): stepping a
// pba::World with the app's integrator choice, and drawing particles, colliders, Forcer
// volumes and wind in the samples' style.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "pba/particles.h"
#include "pba/world.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"
#include "settings.h"

namespace pba::app {

/// Surface colours shared by the particle samples.
namespace particle_colors {
inline constexpr Color solid = Color::hex(0x6b7280);     ///< static boxes and spheres
inline constexpr Color moving = Color::hex(0x8e4ec6);    ///< kinematic colliders
inline constexpr Color fan = Color::hex(0x46a758);       ///< fan / air cannon volumes
inline constexpr Color vortex = Color::hex(0xffc53d);    ///< vortex volumes
inline constexpr Color attractor = Color::hex(0xd6409f); ///< attractor volumes
inline constexpr Color wind = Color::hex(0xa5d8ff);      ///< wind arrows
inline constexpr Color body = Color::hex(0xf76b15);      ///< dynamic rigid bodies, awake
inline constexpr Color asleep = Color::hex(0x8c3d0b);    ///< dynamic rigid bodies, asleep
}  // namespace particle_colors

/// One tick of `world` from its own time by `dt`, with the integrator chosen in the app.
void TickWorld(World& world, const Settings& settings, double dt);

/// Draws the particles: lit spheres (at least `min_radius` metres, so small ones stay
/// visible) when there are at most `sphere_limit`, else screen-space points of `point_px`;
/// nothing when the View menu's `flags.particles` is off.
void DrawParticles(Renderer& r, const ParticleSystem& ps, const DrawFlags& flags, float point_px,
                   double min_radius = 0, std::size_t sphere_limit = 2000);

/// Draws the world's rigid bodies (the entities' bodies, not the colliders' stand-ins) as
/// solids at their poses now: dynamic orange (darker asleep), kinematic as moving colliders,
/// static as solid ones.
void DrawRigidBodies(Renderer& r, const World& world, const DrawFlags& flags);

/// Draws the colliders as solids; `moving` tells which ones are kinematic (by index; when
/// empty, a collider that moved or has a velocity is taken as moving). A horizontal plane at y = 0 is left to the app's ground grid.
void DrawColliders(Renderer& r, std::span<const Collider> colliders, std::span<const bool> moving = {},
                   const DrawFlags& flags = {});

/// Appends the world's live particles and soft-body nodes, thinned evenly to about
/// `max_points`, to `out` (Sample::SimulatedPoints of the samples built on a World).
void WorldPoints(const World& world, std::vector<Vec3>& out, std::size_t max_points);

/// The colour of a Forcer kind.
Color ForcerColor(ForcerKind kind);

/// Draws a Forcer volume at time t: a translucent shell, its outline and arrows that
/// sample the force field inside it (dimmed while an air cannon is off); nothing when the
/// View menu's `flags.forcers` is off.
void DrawForcer(Renderer& r, const Forcer& f, double t, const DrawFlags& flags);

/// Draws a field of wind arrows (the air velocity `wind`, m/s) over a box of the ground
/// from `lo` to `hi`, `n` x `m` arrows at each of the given heights.
void DrawWindField(Renderer& r, const Vec3& wind, const Vec3& lo, const Vec3& hi, int n, int m);

/// The number given by --option key=value, or `fallback` when the key is not given; throws
/// Error naming the option when it is not a number in [lo, hi] (an empty value, `spin=`, too).
double OptionNumber(const SampleContext& ctx, const std::string& key, double fallback, double lo, double hi);

/// The whole number given by --option key=value (a count, a size), or `fallback`; throws
/// Error naming the option when it is not an integer in [lo, hi] (`count=2.5` is refused, not
/// cut to 2).
int OptionInteger(const SampleContext& ctx, const std::string& key, int fallback, int lo, int hi);

/// The switch given by --option key=0 or key=1, or `fallback` when the key is not given;
/// throws Error naming the option for any other value (`compare=0.5` is refused, not read as
/// on; an empty `sleep=` is refused, not read as the default).
bool OptionFlag(const SampleContext& ctx, const std::string& key, bool fallback);

/// A plot series from its arrays, colour and width.
PlotSeries Series(const float* x, const float* y, int count, Color color, float width);

/// Formats a count with thousands separators ("104 233").
std::string Thousands(long long n);

/// Shows the world's last tick profile (ms per phase) as ImGui text.
void ProfileReadout(const World& world);

}  // namespace pba::app
