// Private: the soft body's state (SoftBody::Impl) and the solver kernels' interface.
//
// Particles are float columns. Distance constraints are stored in solver order: by graph
// colour, and within a colour as runs of evenly spaced particle indices (see Run), so
// each run is a loop without dependencies that the compiler vectorises.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "pba/collide.h"
#include "pba/integrate.h"
#include "pba/soft.h"

#if defined(__GNUC__)
#define PBA_SOFT_INLINE inline __attribute__((always_inline))
#define PBA_SOFT_RESTRICT __restrict__
#else
#define PBA_SOFT_INLINE inline
#define PBA_SOFT_RESTRICT
#endif

namespace pba::detail {

/// How a run of constraints addresses its particles.
enum class RunType : std::uint8_t {
  Contiguous,   ///< constraint k joins a0 + k and a0 + k + offset
  Interleaved,  ///< L = offset in {1, 2}: constraint k joins a0 + (k / L) 2L + k % L and that + L
  Indexed,      ///< constraint k joins ca[c0 + k] and cb[c0 + k] (any mesh)
};

/// A run of constraints of one colour and kind, stored at [c0, c0 + count) in the
/// constraint arrays. Within a colour no two constraints share a particle, so every
/// particle a run touches is touched once: the loop has no dependencies.
struct Run {
  std::uint32_t c0 = 0;      ///< first constraint
  std::uint32_t count = 0;   ///< constraints
  std::uint32_t a0 = 0;      ///< first particle (Contiguous, Interleaved)
  std::uint32_t offset = 0;  ///< b - a (Contiguous, Interleaved)
  RunType type = RunType::Indexed;
  SoftConstraintKind kind = SoftConstraintKind::Stretch;
  std::uint32_t color = 0;  ///< graph colour
  /// The rest length shared by every constraint of the run (m, > 0), or -1 when they
  /// differ or one has torn: then the kernel reads Impl::rest.
  float rest = -1;
};

/// Padding (elements) after the particle columns x, y, z, px, py, pz, w, vx, vy, vz and
/// the constraint columns rest and lambda: the AVX2 kernels load and store whole 8-float
/// windows at the ends of runs (writing back the values they loaded in lanes they do
/// not own), so a window may reach up to 15 elements past the last one.
inline constexpr std::size_t kSoftPad = 16;

/// The tether length of a particle without a tether (pinned, or out of every pin's
/// reach): no distance exceeds it, so the tether pass never moves the particle.
inline constexpr float kNoTether = std::numeric_limits<float>::infinity();

}  // namespace pba::detail

namespace pba {

struct SoftBody::Impl {
  SoftBodyDef def{};
  std::size_t n = 0;  // particles (the padded columns hold n + kSoftPad)

  // ---- particles (float columns) ----
  std::vector<float> x, y, z;        // positions (m)
  std::vector<float> px, py, pz;     // positions at the start of the substep (m)
  std::vector<float> vx, vy, vz;     // velocities (m/s)
  std::vector<float> w;              // inverse masses in use (1/kg; 0 pinned or grabbed)
  std::vector<float> ax, ay, az;     // external accelerations held over a step (m/s^2)
  std::vector<double> mass;          // masses (kg)
  std::vector<std::uint8_t> pinned;  // 1 while pinned (grab included)

  // ---- pins: index, start of step and target ----
  std::vector<std::uint32_t> pins;
  std::vector<Vec3> pin_from, pin_to;
  std::uint32_t grab = kNoParticle;  // grabbed particle
  bool grab_pinned = false;          // grab() pinned it (release() unpins)

  // ---- distance constraints in solver order ----
  std::vector<std::uint32_t> ca, cb;   // particle indices
  std::vector<float> rest;             // rest length in use (m); -1 once broken (masks the kernel)
  std::vector<float> rest0;            // rest length at build (m)
  std::vector<std::uint8_t> kind;      // SoftConstraintKind
  std::vector<std::uint8_t> broken;    // 1 once torn
  std::vector<float> lambda;           // XPBD multipliers (iterations > 1 or damping)
  std::vector<detail::Run> runs;       // in solver order: colour by colour
  std::vector<std::uint32_t> run_of;   // the run holding each constraint (for tearing)
  std::size_t n_colors = 0;
  std::size_t n_broken = 0;

  // ---- long-range attachments (Kim, Chentanez & Mueller 2012) ----
  std::vector<float> rx, ry, rz;           // rest positions (m): the positions at build
  std::vector<std::uint32_t> tether;       // each particle's anchor (nearest pin), or itself: no tether
  std::vector<float> tether_len;           // max distance to the anchor (m); kNoTether without one
  std::vector<float> anchor_x, anchor_y, anchor_z;  // each anchor's position (m), copied when pins move
  long long anchors_step = -1;             // the last step whose tether pass ran (anchors valid after it)
  bool tethers_dirty = true;               // pins changed: recompute before the next XPBD step
  // tether lengths along the body (update_tethers, when the rest shape is not convex):
  // the stretch and shear constraints at each particle (constraint indices, particle i's
  // at [graph_start[i], graph_start[i + 1])) and Dijkstra's scratch, all sized at build
  bool tether_straight = true;             // rest shape convex: straight rest distances are geodesics
  std::vector<std::uint32_t> graph_start, graph_edge;
  std::vector<double> geo_dist;            // path length to the nearest pin (m)
  std::vector<std::uint32_t> heap, heap_pos;  // binary heap of particles, and each one's slot

  // ---- tetrahedra ----
  std::vector<SoftTet> tets;
  std::vector<float> tet_rest;  // rest volumes (m^3), > 0
  std::vector<float> tet_lambda;
  double rest_volume = 0;

  // ---- triangles (all, and those intact) ----
  std::vector<SoftTriangle> tris_all;
  std::vector<std::array<std::uint32_t, 3>> tri_edges;  // constraint per edge, or kNoParticle
  std::vector<SoftTriangle> tris;

  // ---- mass-spring state (double) and integrator ----
  Integrator<Vec3> integ{};
  std::vector<Vec3> msx, msv;
  bool ms_valid = false;  // msx/msv mirror x/v
  bool jacobian_set = false;  // the analytic jacobian is installed in integ
  // the fastest free particle's speed relative to the air at the start of the last
  // mass-spring step (m/s), measured only with quadratic drag: its rate c |u| w
  // (mass_spring_instability)
  double ms_air_speed = 0;

  // ---- solver options ----
  bool simd = true;  // use the explicit AVX2 kernels when the CPU has them (same bits either way)

  // ---- the colliders of the step in progress (flat, from the collision world) ----
  std::span<const detail::FlatShape<double>> colliders;
  CollisionWorld span_world;  // filled by the span overload of SoftBody::step

  // ---- bookkeeping ----
  bool has_aext = false;  // ax/ay/az hold something this step
  double time = 0;
  long long steps = 0;
  std::string failure;
  SoftProfile profile{};

  // solver steps (xpbd.cpp, mass_spring.cpp)
  void step_xpbd(double t, double dt);
  void step_mass_spring(double t, double dt);
  void update_tethers();  // xpbd.cpp: each particle's nearest pin in the rest shape
  void init_tethers();    // xpbd.cpp, at build: straight or path lengths, and the graph
  // shared pieces (soft_body.cpp)
  void external_accelerations(double t);
  [[noreturn]] void aero_overflow(std::uint32_t p, const Vec3& acc, const Vec3& u) const;  // its Error
  void tear();
  void rebuild_triangles();
  void check_finite(double t, double h);  // t: end of the step; h: its substep (s)
  // mass_spring.cpp: the settings past an explicit method's stability bound at substep h
  // (their names and values), or "" (for check_finite's message)
  std::string mass_spring_instability(double h) const;
  // mass_spring.cpp: the settings that put implicit Euler's Newton system at substep h past
  // double precision (their names and values), or "" (for a NewtonFailure's message)
  std::string newton_failure_why(double h) const;
};

namespace detail {

/// The XPBD compliance (m/N) of a constraint kind.
inline double kind_compliance(const SoftBodyDef& d, SoftConstraintKind k) {
  const double v[3] = {d.stretch_compliance, d.shear_compliance, d.bend_compliance};
  return v[static_cast<int>(k)];
}
/// The mass-spring stiffness (N/m) of a constraint kind.
inline double kind_stiffness(const SoftBodyDef& d, SoftConstraintKind k) {
  const double v[3] = {d.stretch_stiffness, d.shear_stiffness, d.bend_stiffness};
  return v[static_cast<int>(k)];
}

/// The spectral radius (dimensionless, per substep) of an explicit mass-spring method's
/// amplification matrix on one damped spring, x'' = -omega^2 x - (z / h) x', with
/// p = (omega h)^2 = k (w_a + w_b) h^2 and z = c (w_a + w_b) h: above 1 the spring's
/// state grows every substep. Each matrix is read off the kernels in include/pba/integrate.h
/// (position Verlet's state is x_n, x_n - x_{n-1} and its cached a_n h^2). Implicit Euler: 0.
double mass_spring_radius(Method m, double p, double z);

/// Internal access to a body's state, for tests (e.g. the scalar and AVX2 kernels must
/// give the same bits).
struct SoftAccess {
  static SoftBody::Impl& impl(SoftBody& b) { return *b.impl_; }
  static const SoftBody::Impl& impl(const SoftBody& b) { return *b.impl_; }
};

/// Projects the particles [0, n) out of every collider at substep fraction f in (0, 1]
/// of the step (centres interpolated), with position-based friction over a substep of
/// h seconds. Returns the number of contacts. Shared by both solvers.
std::size_t collide_particles(SoftBody::Impl& s, double f, double h, double fraction_step);
/// Mass-spring contacts at step fraction f: projects the double positions out and
/// removes approaching normal velocity with Coulomb friction. Returns the contacts.
std::size_t collide_velocities(SoftBody::Impl& s, std::span<Vec3> xs, std::span<Vec3> vs, double f);

/// Projects every particle of `s` onto its tether's sphere after a substep's constraints
/// (Kim, Chentanez & Mueller 2012, sec. 4), copying the anchors first when `copy` (a pin
/// moved); 8 at a time with AVX2 when `avx2` (same bits). In tethers.cpp.
void project_all_tethers(SoftBody::Impl& s, bool avx2, bool copy);

}  // namespace detail
}  // namespace pba
