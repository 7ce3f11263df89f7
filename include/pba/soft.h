// pba soft bodies (workbook 4.3): springs, ropes, cloth and jelly, built from particles
// joined by distance constraints (and, for jelly, tetrahedral volume constraints), and
// solved two ways:
//
//   * XPBD (extended position-based dynamics; Macklin, Mueller & Chentanez 2016) with
//     substeps and one or more iterations per substep (Macklin et al. 2019, "Small Steps
//     in Physics Simulation"): stiff and unconditionally stable. Compliance alpha (m/N)
//     is the inverse of a spring stiffness; alpha = 0 is a rigid constraint.
//   * MassSpring: Hooke springs with damping, integrated by any pba::Method through
//     pba::Integrator (so the samples can show why stiff springs are hard explicitly).
//
// A SoftBody stores its particles as float columns (positions, previous positions,
// velocities, inverse masses; inverse mass 0 means pinned) and its distance constraints
// grouped by graph colour into runs of evenly spaced particle indices, so each colour is
// Gauss-Seidel-correct and each run is a dependency-free loop that vectorises.
// A step never allocates once the body is built.
//
//   pba::SoftBody cloth = pba::SoftBody::cloth_grid(
//       {.origin = {-0.5, 1.5, 0}, .nx = 64, .ny = 64, .mass = 1},
//       {.solver = pba::SoftSolver::Xpbd, .substeps = 20});
//   pba::Collider ball = pba::Collider::sphere({0, 0.5, 0}, 0.3);
//   cloth.step(t, 1.0 / 60, std::span(&ball, 1));   // or a CollisionWorld
//
// Everything here is usable without a World; SoftSystem makes soft bodies components of
// World entities, and scene files describe them in a "soft_bodies" array
// (docs/scene-format.md). The models and samples are explained in docs/soft-bodies.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pba/core.h"
#include "pba/draw.h"
#include "pba/handle.h"
#include "pba/integrate.h"
#include "pba/particles.h"
#include "pba/world.h"

namespace pba {

namespace detail {
struct SoftAccess;  // internal: the tests' access to a body's solver state
}

// ---------------------------------------------------------------------------------------
// settings

/// How a soft body is solved.
enum class SoftSolver : std::uint8_t {
  MassSpring,  ///< "mass-spring": Hooke springs + damping, integrated by SoftBodyDef::method
  Xpbd,        ///< "xpbd": compliant distance and volume constraints, substepped
};

/// The role of a distance constraint (each kind has its own compliance or stiffness).
enum class SoftConstraintKind : std::uint8_t {
  Stretch,  ///< "stretch": structural edges (rope segments, cloth grid edges, jelly edges)
  Shear,    ///< "shear": cloth quad diagonals
  Bend,     ///< "bend": particles two apart (rope, cloth), resisting folding
};

/// Per-triangle aerodynamics for cloth (used when drag or lift is > 0 and the body has
/// triangles): each triangle of area A and unit normal n moving at u = v - wind(t)
/// relative to the air gets the drag F_d = -1/2 rho C_d A |u| (u . n) n and the lift
/// F_l = -1/2 rho C_l A (u . n) (|u|^2 n - (u . n) u) / |u| (zero when u is parallel to
/// n), split equally among its three particles. Evaluated once per step (held over the
/// substeps). Model of Bullet's btSoftBody aero "V_TwoSided"/Keckeisen et al. 2004.
struct SoftAero {
  double air_density = 1.2;  ///< rho (kg/m^3), finite and >= 0
  double drag = 0;           ///< C_d, the normal drag coefficient, finite and >= 0 (0 = off)
  double lift = 0;           ///< C_l, the lift coefficient, finite and >= 0 (0 = off)
};

/// Settings of a soft body. Start from the defaults and change what you need; every
/// field is validated when the body is built and again at each step (fields may be
/// changed between steps through SoftBody::settings()).
struct SoftBodyDef {
  SoftSolver solver = SoftSolver::Xpbd;       ///< which solver
  /// MassSpring only: the integrator (any pba::Method). Implicit Euler is a dense Newton
  /// solve limited to 1536 unknowns (512 particles); larger bodies get an Error.
  Method method = Method::SemiImplicitEuler;
  int substeps = 10;    ///< XPBD: substeps per step, in [1, 10000]; MassSpring: also used (steps of dt/substeps)
  int iterations = 1;   ///< XPBD: constraint iterations per substep, in [1, 1000]

  /// XPBD compliance of stretch constraints (m/N; alpha = 1/k), finite and >= 0; 0 = rigid.
  double stretch_compliance = 0;
  /// XPBD compliance of shear constraints (m/N), finite and >= 0.
  double shear_compliance = 0;
  /// XPBD compliance of bend constraints (m/N), finite and >= 0.
  double bend_compliance = 1e-4;
  /// XPBD compliance of tetrahedron volume constraints C = V - V0 (m^5/N), finite and >= 0;
  /// 0 = incompressible. A tet of rest volume V0 in a material whose volume stiffness
  /// (Lame's lambda) is L has alpha = V0 / L: its energy (V - V0)^2 / (2 alpha) is then
  /// L tr(eps)^2 / 2 per unit volume. 0 locks a fine tet lattice (more tets than degrees
  /// of freedom); jelly_settings derives it from a material.
  double volume_compliance = 0;

  /// MassSpring stiffness of stretch springs (N/m), finite and >= 0.
  double stretch_stiffness = 1000;
  /// MassSpring stiffness of shear springs (N/m), finite and >= 0.
  double shear_stiffness = 1000;
  /// MassSpring stiffness of bend springs (N/m), finite and >= 0.
  double bend_stiffness = 100;
  /// MassSpring stiffness of the volume force -k_v (V - V0) grad V (N/m^5), finite, >= 0.
  double volume_stiffness = 0;
  /// Damping along every spring (N s/m), finite and >= 0: F = -c ((v_b - v_a) . n) n on b.
  /// MassSpring: a force. XPBD: on compliant constraints (alpha > 0) only, an implicit
  /// dashpot at the start of each substep of h that takes the relative velocity along the
  /// constraint u to u / (1 + c h (w_a + w_b)); it only removes energy, and dampers beyond
  /// about m / h all stop the relative motion within a substep (docs/soft-bodies.md).
  double spring_damping = 0;

  /// Gravity, linear and quadratic drag (per particle, relative to the wind) and wind.
  Forces forces{};
  /// Per-triangle aerodynamic drag and lift (cloth).
  SoftAero aero{};
  /// A distance constraint breaks for good when its strain (l - l0)/l0 exceeds this at
  /// the end of a step; finite and >= 0; 0 = never tears.
  double tear_strain = 0;
  /// XPBD long-range attachments (Kim, Chentanez & Mueller 2012, "Long range attachments
  /// - a method to simulate inextensible clothing in computer games", sec. 4): each free
  /// particle i is tethered to its nearest pinned particle a (nearest in the rest shape),
  /// and once per substep, after the constraint iterations, if |x_i - x_a| > L_i it is
  /// moved onto the sphere of radius L_i about x_a (the pin has infinite mass). L_i (m)
  /// is never shorter than the rest distance through the body: when the rest shape is
  /// convex (collinear, as a rope built straight, or planar with a convex outline, as any
  /// cloth_grid) a is the nearest pin in a straight line and L_i their straight rest
  /// distance, exact; otherwise (a folded or curved sheet, a mesh in pieces, any solid:
  /// convexity is not tested in 3D) a is the nearest pin along the stretch and shear
  /// constraints and L_i that path's rest length (Dijkstra; on a flat grid with both
  /// diagonals at most 8.2% longer than the geodesic), and particles no path reaches
  /// get no tether. Unilateral: a particle within its tether is never touched, so a
  /// slack cloth is unaffected. A hanging cloth's tethers are taut (each holds its
  /// particle's weight): at rest its energy is as steady as without them, but in a
  /// swing they make the sheet a bundle of pendulums of different lengths and its
  /// energy rises transiently into bending (measured on a 24^2 sheet: a 1.4e-4 J swing
  /// peaked 6e-4 J above its start at 10 substeps of 1/60 s, 3.6e-6 J at 40, then
  /// decayed). Tethers follow
  /// pin(), unpin() and grab() (recomputed before the next step); set_pin_target() moves
  /// the anchor but keeps L_i. Ignored by MassSpring, and off while tear_strain > 0: a
  /// tether is a shortcut through the cloth, which would keep holding a piece that has
  /// torn away from its pins.
  bool tethers = true;
  /// Collision thickness (m): particles are kept this far outside colliders; finite, >= 0 and,
  /// checked at each step, at most kMaxParticleSpeed h (9e18 m/s times the substep h = dt /
  /// substeps: a push of the thickness in one substep is a speed of thickness / h).
  double thickness = 0.01;
  /// Coulomb friction coefficient against colliders, finite and >= 0; each contact uses
  /// the larger of this and the collider material's friction.
  double friction = 0;
  /// Velocity damping rate (1/s), finite and >= 0 (a drag that does not depend on the
  /// air): XPBD scales velocities by exp(-damping h) each substep of h seconds, MassSpring
  /// adds the force -damping m v; both decay a free velocity as exp(-damping t).
  double damping = 0;

  /// Throws Error "<where>.<field>: ..." naming the first bad field and its value.
  void validate(std::string_view where) const;
};

// ---------------------------------------------------------------------------------------
// meshes and builders

/// Index meaning "no particle" (returned by picking when nothing is near).
inline constexpr std::uint32_t kNoParticle = std::numeric_limits<std::uint32_t>::max();

/// The memory budget of one soft body (bytes): 4 GiB. The cloth builder counts what a
/// grid would take, at most, while it is built and solved (kSoftParticleBytes per
/// particle, kSoftConstraintBytes per constraint, kSoftTriangleBytes per triangle: upper
/// bounds of the peak measured on 512^2 and 1024^2 cloths, 960 B per grid point, and on
/// ropes) and refuses a grid beyond the budget before allocating, naming nx and the
/// memory: a cloth of about 1850 x 1850 particles fits, 4096 x 4096 (21 GiB) does not.
/// Ropes (at most 100000 segments, 48 MB) and jellies (at most 64^3 cells, 0.5 GiB, at
/// kSoftTetBytes per tetrahedron) stay within it by their count limits.
inline constexpr std::size_t kSoftBodyMemoryBudget = std::size_t{4} << 30;
inline constexpr std::size_t kSoftParticleBytes = 160;    ///< per particle (see kSoftBodyMemoryBudget)
inline constexpr std::size_t kSoftConstraintBytes = 160;  ///< per distance constraint
inline constexpr std::size_t kSoftTriangleBytes = 64;     ///< per triangle
inline constexpr std::size_t kSoftTetBytes = 128;         ///< per tetrahedron

/// A distance constraint between particles a and b.
struct SoftConstraint {
  std::uint32_t a = 0;  ///< first particle index
  std::uint32_t b = 0;  ///< second particle index (different from a)
  /// Rest length (m): finite and > 0; negative in a SoftMesh means "the distance at build".
  double rest_length = -1;
  SoftConstraintKind kind = SoftConstraintKind::Stretch;  ///< which compliance/stiffness applies
  bool broken = false;  ///< true once torn (queries only; ignored in a SoftMesh)
};

/// A triangle (particle indices), for drawing, aerodynamics and tearing.
struct SoftTriangle {
  std::uint32_t a = 0, b = 0, c = 0;  ///< particle indices, counter-clockwise seen from the front
};

/// A tetrahedron (particle indices) with a volume constraint.
struct SoftTet {
  std::uint32_t a = 0, b = 0, c = 0, d = 0;  ///< particle indices
};

/// A generic soft body description: particles, constraints, triangles, tetrahedra, pins.
/// SoftBody::from_mesh validates every index and value (Error names the field and index).
struct SoftMesh {
  std::vector<Vec3> positions{};       ///< initial positions (m), finite
  std::vector<Vec3> velocities{};      ///< initial velocities (m/s), finite; empty = all zero
  std::vector<double> masses{};        ///< per particle (kg), finite and > 0; same size as positions
  std::vector<SoftConstraint> constraints{};  ///< distance constraints (a != b, both < positions.size())
  std::vector<SoftTriangle> triangles{};      ///< triangles (indices < positions.size())
  std::vector<SoftTet> tets{};                ///< tetrahedra with non-zero rest volume
  std::vector<std::uint32_t> pinned{};        ///< particles pinned where they start
  /// Optional graph colour per constraint (same size as constraints, or empty): a colour
  /// must never hold two constraints sharing a particle (checked). Empty: greedy colouring.
  std::vector<std::uint32_t> colors{};
};

/// A single Hooke spring between two particles (workbook exercise 2).
struct SpringDef {
  Vec3 a{0, 1, 0};         ///< first end (m), finite
  Vec3 b{0, 0, 0};         ///< second end (m), finite, != a
  Vec3 velocity_b{0, 0, 0};  ///< initial velocity of b (m/s), finite
  double mass = 1;         ///< mass of each free end (kg), finite and > 0
  double stiffness = 100;  ///< k (N/m), finite and > 0; XPBD uses compliance alpha = 1/k
  double damping = 0;      ///< c (N s/m), finite and >= 0
  double rest_length = -1; ///< l0 (m), finite and > 0; negative = |b - a| (which must then be > 0)
  bool fixed_a = true;     ///< a is pinned (a fixed anchor)
};

/// A rope (or chain): `segments` + 1 particles on a straight line, stretch constraints
/// between neighbours and bend constraints between particles two apart.
struct RopeDef {
  Vec3 from{0, 2, 0};   ///< first particle (m), finite
  Vec3 to{1, 2, 0};     ///< last particle (m), finite, != from
  int segments = 20;    ///< segments, in [1, 100000]
  double mass = 1;      ///< total mass (kg), finite and > 0, split evenly among the particles
  bool pin_start = true;  ///< pin the first particle
  bool pin_end = false;   ///< pin the last particle
  bool bending = true;    ///< add bend constraints (i, i+2)
};

/// Which particles of a cloth grid start pinned.
enum class ClothPins : std::uint8_t {
  None,             ///< "none": nothing pinned (a falling sheet)
  FirstRow,         ///< "first-row": the nx particles of row 0 (along edge_u from origin), e.g. a hanging cloth
  FirstRowCorners,  ///< "first-row-corners": particles (0, 0) and (nx-1, 0)
  FirstColumn,      ///< "first-column": the ny particles of column 0 (along edge_v from origin), e.g. a flag on a pole
};

/// A rectangular cloth: nx x ny particles at origin + edge_u i/(nx-1) + edge_v j/(ny-1),
/// particle index j nx + i; structural edges between grid neighbours, shear constraints
/// on both quad diagonals, bend constraints between particles two apart in each
/// direction; two triangles per quad.
struct ClothDef {
  Vec3 origin{-0.5, 1.5, 0};  ///< corner particle (0, 0) (m), finite
  Vec3 edge_u{1, 0, 0};       ///< the row direction and length (m), finite, non-zero
  Vec3 edge_v{0, 0, 1};       ///< the column direction and length (m), finite, non-zero, not parallel to edge_u
  int nx = 32;                ///< particles per row, in [2, 4096], and nx x ny within kSoftBodyMemoryBudget
  int ny = 32;                ///< particles per column, in [2, 4096]
  double mass = 1;            ///< total mass (kg), finite and > 0, split evenly
  ClothPins pins = ClothPins::FirstRow;  ///< which particles start pinned
  bool shear = true;          ///< add shear (diagonal) constraints
  bool bending = true;        ///< add bend constraints
};

/// A jelly box: a lattice of (nx+1)(ny+1)(nz+1) particles, each cell split into 6
/// tetrahedra around one of its diagonals (the Freudenthal/Kuhn split), with a distance
/// constraint on every tet edge and a volume constraint per tet (Macklin et al. 2016;
/// Mueller et al. 2020 "Detailed rigid body simulation with XPBD").
/// The split is mirrored from cell to cell (along each axis the cells alternate between
/// the split and its mirror image, symmetrically about the box's mid-plane), so faces
/// still match and the lattice has the box's mirror symmetries when the cell count along
/// an axis is even (an odd count leaves the middle layer unpaired). The plain Kuhn
/// lattice, every cell split about a diagonal parallel to (1, 1, 1), is anisotropic:
/// squashed along y it shears toward (1, 0, 1), which friction turns into sliding.
struct JellyDef {
  Vec3 center{0, 1, 0};        ///< box centre (m), finite
  Vec3 size{0.5, 0.5, 0.5};    ///< full edge lengths (m), each finite and > 0
  Quat rotation{1, 0, 0, 0};   ///< orientation, unit quaternion
  int nx = 4, ny = 4, nz = 4;  ///< cells per axis, each in [1, 64] (even: mirror-symmetric)
  double mass = 1;             ///< total mass (kg), finite and > 0, split evenly
  Vec3 velocity{0, 0, 0};      ///< initial velocity of every particle (m/s), finite
};

/// An isotropic elastic material for a jelly, turned into XPBD settings by jelly_settings.
struct JellyMaterial {
  double young = 5e3;     ///< Young's modulus E (Pa), finite and > 0 (gelatin: about 1e3 to 1e4)
  /// Poisson ratio nu, in [0.27, 0.49]: the edge springs alone give nu = 5/19 (about
  /// 0.263, a central-force lattice), the volume constraints add the rest of the bulk
  /// modulus; nu -> 0.5 (incompressible) locks the lattice (see jelly_settings).
  double poisson = 0.4;
  /// Stiffness-proportional (Rayleigh) damping time tau (s), finite and >= 0: every edge
  /// gets the damping c = tau k, which damps a mode of angular frequency omega with the
  /// ratio tau omega / 2 (the default: about 0.04 for the default cube's sway, omega
  /// about 30 rad/s, so it bounces and wobbles; its fastest lattice modes are overdamped).
  double damping_time = 2.5e-3;
};

/// XPBD settings that give a jelly box the material `m` (Error names the bad field).
/// Start from SoftBodyDef{} and set, with cell edge a = cbrt(cell volume) and shear
/// modulus G = E / (2 (1 + nu)):
///   * stretch_compliance = 1 / k with k = 4 G a / 3. Every tet edge is a spring of
///     stiffness k; per cell there are 3 axis edges, 3 face and 1 body diagonal, and
///     averaged over the mirrored cells the lattice has cubic symmetry with
///     C11 = 7k/(3a), C12 = C44 = 5k/(6a) (central springs: Cauchy), so G = (C11 -
///     C12)/2 = 3k/(4a) (C44 is 11% stiffer) and the bulk modulus of the springs alone
///     is K_s = (C11 + 2 C12)/3 = 4k/(3a) = 16 G / 9.
///   * volume_compliance = V0 / lambda_v (m^5/N) with V0 = a^3/6 the tet rest volume and
///     lambda_v = K - 16 G/9, K = E / (3 (1 - 2 nu)): the energy (V - V0)^2 / (2 alpha)
///     per tet is the bulk energy lambda_v tr(eps)^2 / 2 per unit volume.
///   * spring_damping = tau k.
///   * substeps: the smallest count >= 10 with omega_max h <= 1 at the step dt (s, > 0),
///     where omega_max^2 = 2 (d - 1) k w bounds the lattice's fastest vibration
///     (Gershgorin; d = 26 edges meet at a particle where mirrored cells' diagonals meet,
///     w = particles / mass). Then alpha / h^2 = 1 / (k h^2) >= 2 (d - 1) w, the sum of
///     the couplings to the constraints sharing a particle: the system each sweep solves
///     is diagonally dominant and one Gauss-Seidel sweep per substep nearly converges it,
///     so the elastic energy the solver stores is the energy it reports. A stiffer or
///     finer jelly gets more substeps rather than an unconverged, hidden compliance
///     (the default cube: 23 at 60 Hz).
/// Why not rigid: alpha = 0 on every edge and tet is a rigid body (604 edges and 384
/// tets on the 369 deformation degrees of freedom of a 4 x 4 x 4 lattice; the volumes
/// are redundant once the edges are rigid, and the edges alone are over-determined). One
/// sweep per substep cannot converge it within an impact, and the residual acts as a
/// spring whose energy potential_energy() cannot see: such a cube dropped flat bounces
/// back at about 0.4 of its impact speed, and dropped tilted it tumbles for metres.
SoftBodyDef jelly_settings(const JellyDef& jelly, const JellyMaterial& m = {}, double dt = 1.0 / 60);

/// Mean and maximum strain |l - l0| / l0 over the intact stretch constraints.
struct StrainStats {
  double mean = 0;  ///< mean strain (dimensionless)
  double max = 0;   ///< largest strain (dimensionless)
};

/// Wall-clock seconds of the last SoftBody::step, by phase.
struct SoftProfile {
  double forces = 0;    ///< wind, aerodynamics and pins, once per step
  double solve = 0;     ///< XPBD: predict, projection and velocities; MassSpring: integration
  double collide = 0;   ///< collisions; for XPBD the first substep's collision time x substeps (an estimate)
  double total = 0;     ///< the whole step
};

/// What SoftBody::draw shows.
struct SoftDrawOptions {
  bool triangles = true;     ///< filled triangles (DebugDraw::triangle), shaded by facing
  bool edges = true;         ///< stretch constraints as lines (all constraints when `all_edges`)
  bool all_edges = false;    ///< also shear and bend constraints
  bool strain_colors = true; ///< colour edges from `color` (no strain) to red at `strain_scale`
  double strain_scale = 0.1; ///< strain drawn fully red, > 0
  bool pins = true;          ///< pinned and grabbed particles as points
  bool particles = false;    ///< every particle as a point
  Color color = colors::cyan;  ///< base colour
};

// ---------------------------------------------------------------------------------------
// the soft body

/// A soft body: particles, distance constraints, tetrahedra and triangles, stepped by
/// XPBD or as a mass-spring network. Movable, not copyable; not thread-safe.
class SoftBody {
 public:
  /// An empty body (no particles) with default settings.
  SoftBody();
  ~SoftBody();
  SoftBody(SoftBody&&) noexcept;
  SoftBody& operator=(SoftBody&&) noexcept;
  SoftBody(const SoftBody&) = delete;
  SoftBody& operator=(const SoftBody&) = delete;

  // ---- builders (each validates its definition and `def`; Error names the field) ----

  /// Builds a body from a generic mesh. `where` prefixes error messages ("SoftMesh").
  static SoftBody from_mesh(const SoftMesh& mesh, const SoftBodyDef& def = {},
                            std::string_view where = "SoftMesh");
  /// One Hooke spring between two particles; `spring.stiffness` and `spring.damping`
  /// replace def's stretch_stiffness and spring_damping, and XPBD uses compliance 1/k.
  static SoftBody spring(const SpringDef& spring, const SoftBodyDef& def = {});
  /// A rope or chain.
  static SoftBody rope(const RopeDef& rope, const SoftBodyDef& def = {});
  /// A rectangular cloth grid (constraints pre-coloured in 12 vectorisable sets).
  static SoftBody cloth_grid(const ClothDef& cloth, const SoftBodyDef& def = {});
  /// A tetrahedral jelly box of the default material: jelly_box(jelly, jelly_settings(jelly)).
  static SoftBody jelly_box(const JellyDef& jelly);
  /// A tetrahedral jelly box with the given settings (all of them: with SoftBodyDef{}
  /// its edges and volumes are rigid, see jelly_settings).
  static SoftBody jelly_box(const JellyDef& jelly, const SoftBodyDef& def);

  // ---- settings ----

  /// The settings; change fields freely between steps (validated at the next step).
  SoftBodyDef& settings();
  /// The settings.
  const SoftBodyDef& settings() const;

  // ---- stepping ----

  /// Advances from time t to t + dt (s; dt finite and > 0), colliding with `colliders`
  /// (their end-of-step poses, centres interpolated over the substeps). Throws Error if
  /// the state becomes non-finite, naming the particle and the time; the body then
  /// refuses to step again and repeats that message. Never allocates.
  void step(double t, double dt, const CollisionWorld& colliders);
  /// The same step with the colliders given as a span (validated, an Error names
  /// colliders[i]; they fill a CollisionWorld the body keeps, so no allocation in steady state).
  void step(double t, double dt, std::span<const Collider> colliders);
  /// The same step with a braced list of colliders (none by default).
  void step(double t, double dt, std::initializer_list<Collider> colliders = {}) {
    step(t, dt, std::span<const Collider>(colliders.begin(), colliders.size()));
  }
  /// Steps taken.
  long long steps() const;
  /// Simulated time (s) at the end of the last step.
  double time() const;
  /// True after a step failed (non-finite state).
  bool failed() const;
  /// Timings of the last step.
  const SoftProfile& profile() const;

  // ---- particles ----

  /// Number of particles.
  std::size_t size() const;
  /// Position of particle i (m); i < size().
  Vec3 position(std::size_t i) const;
  /// Velocity of particle i (m/s); i < size().
  Vec3 velocity(std::size_t i) const;
  /// Mass of particle i (kg; infinity while pinned or grabbed).
  double mass(std::size_t i) const;
  /// Inverse mass of particle i (1/kg; 0 while pinned or grabbed).
  double inverse_mass(std::size_t i) const;
  /// Total mass of the particles (kg), pinned ones included.
  double total_mass() const;
  /// Teleports particle i (validated: index and finite position).
  void set_position(std::size_t i, const Vec3& p);
  /// Sets the velocity of particle i (validated).
  void set_velocity(std::size_t i, const Vec3& v);
  /// Adds dv (m/s) to every free particle's velocity (validated).
  void add_velocity(const Vec3& dv);
  /// The position columns (m), read-only.
  std::span<const float> xs() const;
  std::span<const float> ys() const;  ///< y positions (m)
  std::span<const float> zs() const;  ///< z positions (m)
  /// Copies positions into `out` (size() elements), e.g. for a vertex buffer.
  void copy_positions(std::span<Vec3f> out) const;

  // ---- pins and grabbing ----

  /// Pins particle i where it is (inverse mass 0; it moves only to its pin target).
  void pin(std::size_t i);
  /// Pins particle i at `target` (m); it is moved there over the next step.
  void pin(std::size_t i, const Vec3& target);
  /// Unpins particle i (restores its mass). No effect if it is not pinned.
  void unpin(std::size_t i);
  /// True when particle i is pinned.
  bool is_pinned(std::size_t i) const;
  /// Moves a pinned particle's target (m): over the next step the pin slides linearly
  /// there, ending exactly at the target. Throws Error if i is not pinned.
  void set_pin_target(std::size_t i, const Vec3& target);
  /// The pinned particles' indices (in pinning order).
  std::span<const std::uint32_t> pins() const;
  /// Grabs particle i with the mouse: it becomes a kinematic pin at `target` (m) until
  /// release(). Grabbing a pinned particle moves its pin. Replaces any previous grab.
  void grab(std::size_t i, const Vec3& target);
  /// Moves the grabbed particle's target (m); no effect when nothing is grabbed.
  void move_grab(const Vec3& target);
  /// Releases the grabbed particle (keeping the velocity the drag gave it).
  void release();
  /// The grabbed particle, or kNoParticle.
  std::uint32_t grabbed() const;
  /// The particle nearest to `point`, or kNoParticle for an empty body.
  std::uint32_t nearest_particle(const Vec3& point) const;
  /// The particle nearest to the ray origin + s direction (s >= 0) within `radius`
  /// (m) of it, the one closest to the origin among those; kNoParticle if none.
  std::uint32_t nearest_particle(const Vec3& origin, const Vec3& direction, double radius) const;

  // ---- structure ----

  /// Number of distance constraints (broken ones included).
  std::size_t constraint_count() const;
  /// Distance constraint c (in solver order, fixed at build), with its broken flag.
  SoftConstraint constraint(std::size_t c) const;
  /// Constraints broken so far by tearing.
  std::size_t broken_constraints() const;
  /// The triangles whose edges are all intact (shrinks as the cloth tears).
  std::span<const SoftTriangle> triangles() const;
  /// The tetrahedra.
  std::span<const SoftTet> tets() const;
  /// Number of graph colours of the constraints (the batches solved in sequence).
  std::size_t color_count() const;

  // ---- measurements ----

  /// Kinetic energy 1/2 sum m v^2 of the free particles (J).
  double kinetic_energy() const;
  /// Potential energy (J): gravity -sum m g . x over free particles plus the elastic
  /// energy the solver stores: XPBD sum C^2 / (2 alpha) over constraints with alpha > 0;
  /// MassSpring sum k C^2 / 2 (distance C = l - l0, volume C = V - V0).
  double potential_energy() const;
  /// Mean and maximum strain over intact stretch constraints.
  StrainStats strain_stats() const;
  /// Sum of the signed tetrahedron volumes now (m^3).
  double volume() const;
  /// Sum of the tetrahedron rest volumes (m^3).
  double rest_volume() const;
  /// Centre of mass of the free particles (m), or of all when every particle is pinned.
  Vec3 center_of_mass() const;
  /// 64-bit hash of positions, velocities and broken flags (bit patterns).
  std::uint64_t hash(std::uint64_t seed = 0xcbf29ce484222325ULL) const;
  /// Draws the body.
  void draw(DebugDraw& draw, const SoftDrawOptions& options = {}) const { this->draw(draw, DrawFlags{}, options); }
  /// Draws the body as `options` say, within what `flags` allow: edges only with
  /// flags.constraints, particles and pins only with flags.particles.
  void draw(DebugDraw& draw, const DrawFlags& flags, const SoftDrawOptions& options = {}) const;

  /// Internal state (defined in src/soft).
  struct Impl;

 private:
  friend struct detail::SoftAccess;
  explicit SoftBody(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// ---------------------------------------------------------------------------------------
// world integration

/// Soft bodies as components of World entities: add one with add(), and the system steps
/// every body each world tick (at WorldStage::Soft, after the particles) with the world's
/// colliders, draws and hashes them. Bodies live in world coordinates (the entity pose is
/// not applied). Get the world's system with soft_system(world).
class SoftSystem final : public WorldSystem {
 public:
  /// The name World::find_system knows it by.
  static constexpr std::string_view kName = "soft";

  std::string_view name() const override { return kName; }
  /// Soft bodies run at WorldStage::Soft.
  WorldStage stage() const override { return WorldStage::Soft; }
  /// Makes `body` the soft-body component of entity e (throws Error for a stale handle or
  /// an entity that already has one). Returns the body's index (stable until a removal).
  std::size_t add(const World& world, EntityId e, SoftBody body);
  /// True when entity e has a soft body.
  bool has(EntityId e) const;
  /// The soft body of entity e (throws Error if it has none).
  SoftBody& body(EntityId e);
  /// The soft body of entity e (throws Error if it has none).
  const SoftBody& body(EntityId e) const;
  /// Number of soft bodies.
  std::size_t size() const { return bodies_.size(); }
  /// Body i (i < size()), in the order added (removals move the last one into the gap).
  SoftBody& at(std::size_t i) { return bodies_.at(i); }
  /// Body i.
  const SoftBody& at(std::size_t i) const { return bodies_.at(i); }
  /// The entity owning body i.
  EntityId owner(std::size_t i) const { return owners_.at(i); }
  /// Draw options for every body.
  SoftDrawOptions& draw_options() { return options_; }

  /// Steps every body from t to t + dt against world.collision(), under world.gravity()
  /// (each body's forces.gravity follows it); a body that becomes non-finite throws
  /// Error naming its entity, the particle and the time.
  void step(World& world, double t, double dt) override;
  /// Removes the entity's body.
  void on_destroy(EntityId e) override;
  /// Draws every body.
  void draw(const World& world, DebugDraw& draw, const DrawFlags& flags) const override;
  /// Mixes every body's hash.
  std::uint64_t hash(std::uint64_t seed) const override;

 private:
  std::size_t index_of(EntityId e, std::string_view where) const;
  std::vector<SoftBody> bodies_;
  std::vector<EntityId> owners_;
  SoftDrawOptions options_;
};

/// The world's SoftSystem, added on first use.
SoftSystem& soft_system(World& world);

}  // namespace pba
