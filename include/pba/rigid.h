// pba rigid bodies (workbook chapter 6), part 1: the bodies and their free motion.
//
// A RigidBodySystem stores bodies as contiguous arrays (structure of arrays) and advances
// them under gravity, applied forces and torques, damping, impulses and contacts. The free rotation
// of a body is integrated by the symmetric splitting of Dullweber, Leimkuhler and McLachlan
// (1997): each substep is five exact rotations about the body's principal axes, so a
// torque-free body keeps its world angular momentum to rounding and its kinetic energy to
// O(h^2) without drift, and the gyroscopic precession (the intermediate-axis flip of a
// tumbling T-handle) comes out right at game time steps. Bodies with equal principal moments
// take their exact free rotation instead: a round one (a cube, a ball) turns about its constant
// angular velocity, an axisymmetric one (a capsule) about its momentum and its axis.
//
// Each body carries one or more shapes of the collide module. A step finds the pairs of
// shapes whose bounds overlap, builds their manifolds with the narrow phase (speculative
// points included), matches the points to last step's by feature id so the solver starts
// from last step's impulses, and solves the contacts with the selected solver (the
// soft-step default of Box2D v3: substeps, soft contacts, a relax pass and a restitution
// pass; see docs/rigid-bodies.md).
//
//   pba::RigidBodySystem bodies;
//   bodies.create({.type = pba::BodyType::Static, .shapes = {{.shape = pba::ColliderShape::plane({0, 1, 0}, 0)}}});
//   auto box = bodies.create({.pose = {{0, 5, 0}}, .shapes = {{.shape = pba::ColliderShape::box({0.5, 0.5, 0.5})}}});
//   bodies.apply_impulse(box, {0, 0, 1}, {0.5, 5, 0});   // N s at a world point
//   bodies.step(1.0 / 60, {0, -9.81, 0});
//
// Units: metres, seconds, kilograms; forces in N, torques in N m, impulses in N s.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pba/collide/shape.h"
#include "pba/core.h"
#include "pba/draw.h"
#include "pba/handle.h"

namespace pba {

/// How a body moves.
enum class BodyType : std::uint8_t {
  Static,     ///< never moves; infinite mass
  Kinematic,  ///< moves at its set velocity, ignoring forces; infinite mass (pushes dynamic bodies)
  Dynamic,    ///< moves under forces, gravity and impulses
};

/// Lower-case name of a body type ("static", "kinematic", "dynamic").
std::string_view to_string(BodyType t);

/// Mass, centre of mass and inertia of a body, in the body's frame.
struct RigidMass {
  double mass = 1;          ///< kg, finite and > 0 for a dynamic body
  Vec3 center{0, 0, 0};     ///< centre of mass in the body frame (m), within the float range
  Mat3 inertia{1.0};        ///< inertia tensor about the centre of mass, body axes (kg m^2):
                            ///< symmetric positive definite, satisfying the triangle inequality

  /// The mass properties of a uniform solid shape at `density` (kg/m^3), placed at `local`
  /// in the body frame (collide module's mass_properties, moved and rotated).
  static RigidMass of_shape(const ColliderShape& s, double density, const Pose& local = {},
                            std::string_view where = "shape");
  /// A solid box of `mass` kg and half extents `half` (m) about the body origin. Throws Error
  /// naming the argument unless the mass and each half extent are finite and > 0.
  static RigidMass box(double mass, const Vec3& half);
  /// A solid sphere of `mass` kg and radius `r` (m) about the body origin. Throws Error naming
  /// the argument unless both are finite and > 0.
  static RigidMass sphere(double mass, double r);
  /// The sum of two bodies rigidly joined (parallel-axis theorem).
  RigidMass operator+(const RigidMass& o) const;
  /// Throws Error naming `where` and the bad field: mass not finite and > 0, a centre not
  /// finite or outside the float range (|component| <= 3.4e38 m), or an inertia that is not
  /// symmetric positive definite and physical (each principal moment at most the sum of the
  /// other two).
  void validate(std::string_view where) const;
};

/// A shape attached to a body, with its material.
struct RigidShapeDef {
  ColliderShape shape{};  ///< any shape; planes and meshes only on static bodies
  Pose local{};           ///< placement in the body frame (position within the float range, m)
  double density = 1000;  ///< kg/m^3, finite and > 0: the body's mass comes from its shapes' densities
  /// Friction and restitution (mixed between the two shapes of a contact, see ContactSettings).
  SurfaceMaterial material{.restitution = 0, .friction = 0.6};
  /// Rolling resistance, dimensionless, finite and >= 0: a rolling contact loses angular
  /// impulse up to this times the normal impulse times the shape's radius.
  double rolling_resistance = 0;
};

/// The fastest a rigid body may move, 1e18 m/s, and turn, 1e18 rad/s. The contact rows carry
/// speeds and impulses in float (at most 3.4e38) and square the relative speed of a contact's
/// bodies (so at most 1.8e19 m/s): a box sliding on the ground at 2e19 m/s, or spun at 3e19
/// rad/s against another, turned non-finite (within the 1e20 this was before). A point's speed
/// is |v| + |w| r at r from the centre of mass, so two bodies reaching up to 8 m from their
/// centres may meet with both speeds at the limit and stay finite (their impact may throw one
/// past the limit, which stops the step naming it). A velocity beyond it is refused where it is
/// given (create, set_velocity, impulses); a body a force or a contact takes beyond it stops the
/// step, named.
inline constexpr double kMaxRigidSpeed = 1e18;

/// Throws an Error naming `where` unless |v| <= kMaxRigidSpeed (a NaN fails too); `unit` is
/// the value's unit for the message ("m/s" or "rad/s").
void require_rigid_speed(const Vec3& v, std::string_view where, std::string_view unit);

/// How far a given centre of mass (RigidBodyDef::mass) may lie outside its body's shapes, in
/// their sizes (the diagonal of the shapes' bounds in the body frame): 10. A hollow body's
/// centre lies within its shapes' hull, and a ballast left out of the shapes near them; one
/// 1e20 m from a 0.5 m ball (a unit slip, a wrong field) is refused at create() by name.
inline constexpr double kMaxCenterOfMassOffset = 10;

/// Definition of a rigid body. Start from the defaults and change what you need.
struct RigidBodyDef {
  std::string name{};               ///< optional; used in error messages
  BodyType type = BodyType::Dynamic;  ///< static, kinematic or dynamic
  /// Body frame in the world: a unit rotation, and a position within the float range
  /// (|component| <= 3.4e38 m: the shapes' bounds and the contact rows hold it as floats).
  Pose pose{};
  /// velocity of the centre of mass (m/s), |v| <= kMaxRigidSpeed; validated but not used on a
  /// static body, which never moves (as set_velocity; scene files refuse a non-zero one)
  Vec3 linear_velocity{0, 0, 0};
  Vec3 angular_velocity{0, 0, 0};   ///< world angular velocity (rad/s), |w| <= kMaxRigidSpeed; as linear_velocity
  std::vector<RigidShapeDef> shapes{};  ///< at least one
  /// Dynamic bodies: mass properties; unset means from the shapes' densities. The mass (kg)
  /// and the principal moments (kg m^2) must each be in [2.94e-39, 8.5e37], and the centre
  /// (body frame, m) within kMaxCenterOfMassOffset sizes of the shapes (create()). Static
  /// and kinematic bodies have infinite mass: they neither read nor validate it (scene files
  /// refuse a "mass" on them).
  std::optional<RigidMass> mass{};
  double linear_damping = 0;        ///< 1/s, finite and >= 0: dv/dt = -c v
  double angular_damping = 0;       ///< 1/s, finite and >= 0: dw/dt = -c w
  double gravity_scale = 1;         ///< multiplies the system's gravity, finite
  /// fast body: continuous collision against static geometry and, swept after the other bodies,
  /// against the moving non-bullet bodies at their poses at the step's end (not other bullets)
  bool bullet = false;

  /// Throws Error naming `where` and the bad field.
  void validate(std::string_view where) const;
};

/// Tag for rigid-body handles.
struct RigidBodyTag {};
/// Generation-checked rigid-body handle.
using RigidBodyId = Handle<RigidBodyTag>;

/// The contact solvers, switchable between steps. Names for the command line and the UI are
/// "soft-step", "sequential-impulse", "tgs" and "xpbd" (to_string / parse_rigid_solver).
enum class RigidSolverType : std::uint8_t {
  SoftStep,           ///< Box2D v3 / Box3D: substeps, soft contacts, relax and restitution passes
  SequentialImpulse,  ///< one step, iterations with warm starting, Baumgarte position correction
  /// temporal Gauss-Seidel (Macklin et al. 2019; PhysX TGS): substeps of few iterations of
  /// rigid contacts biased by the separation at the bodies' current poses, relax, restitution
  Tgs,
  /// extended position-based dynamics for rigid bodies (Mueller et al. 2020): substeps of
  /// positional contact and static friction constraints, then a velocity pass
  Xpbd,
};

/// Every rigid solver, in the order the UI lists them.
inline constexpr std::array<RigidSolverType, 4> kRigidSolvers = {
    RigidSolverType::SoftStep, RigidSolverType::SequentialImpulse, RigidSolverType::Tgs, RigidSolverType::Xpbd};

/// Lower-case name of a solver ("soft-step", "sequential-impulse", "tgs", "xpbd").
std::string_view to_string(RigidSolverType t);

/// Parses a solver's name (exact, lowercase, as to_string gives it). Throws Error naming the
/// text, `where` it came from (e.g. "--solver") and the valid names.
RigidSolverType parse_rigid_solver(std::string_view text, std::string_view where);

/// How two materials' coefficients combine at a contact.
enum class MixRule : std::uint8_t {
  GeometricMean,  ///< sqrt(a b) (Box2D's friction rule)
  Minimum,        ///< min(a, b)
  Maximum,        ///< max(a, b) (Box2D's restitution rule)
  Average,        ///< (a + b) / 2
  Product,        ///< a b
};

/// Contact and solver settings; change them between steps.
struct ContactSettings {
  RigidSolverType solver = RigidSolverType::SoftStep;  ///< which solver
  int substeps = 8;  ///< soft step, TGS and XPBD: substeps per step, in [1, 64]
  /// Soft step: take more substeps while a column of boxes stands too tall for the contacts'
  /// springs at `substeps` (its buckling load: docs/rigid-bodies.md, "Why 8 substeps and
  /// 120 Hz"): the substeps and `contact_hertz` are doubled together, up to four times (and
  /// 64 substeps), for the whole system, and halved again once the columns have fitted the
  /// fewer substeps for a second. Worlds without a tall column keep `substeps` exactly (and
  /// their bits). RigidProfile::substeps tells the substeps a step took. Off (or
  /// set_substeps()), the soft step takes exactly `substeps` and `contact_hertz`.
  bool auto_substeps = true;
  /// Soft step with `auto_substeps`: where the bodies allow it, also HALVE the substeps and
  /// `contact_hertz` (8 -> 4 and 120 -> 60 Hz at the defaults; then lower, a rung at a time
  /// down to `auto_substeps_least`, on the same conditions: 3 and 45 Hz), a budget on the static sag
  /// that the halving may give, as a fraction of each body's size (twice its smallest half
  /// size), finite and in [0, 1]; 0: no such budget. Halved once, for a second, the columns
  /// have carried at most half the buckling bound that raises the substeps, every awake
  /// body's sag predicted from the contacts' carried loads (each contact gives load /
  /// (m_eff w^2) at the halved rate, summed up the levels of a column) and each touching
  /// contact's own deflection have stayed within half the budget of the body's size, the
  /// contact pairs have stayed the same and every awake body has moved slower than
  /// `sleep_linear` and `sleep_angular` (at rest: not while a pile lands or a column rocks);
  /// back at once when the load or the sag passes its whole bound. Only for an even
  /// `substeps`. The default 0.02 halves a column of one-metre cubes only where it sags at
  /// most 1 cm at 4 substeps (up to 11 cubes: the 20-stack bound) and keeps balls of
  /// 1-5 mm at 8 (their ground springs sink them 0.17 mm at 4). docs/rigid-bodies.md,
  /// "Fewer substeps where the bodies allow it".
  double auto_substeps_sag_fraction = 0.02;
  /// Soft step with `auto_substeps`: a budget (m) on the static sag of the halving above, in
  /// metres whatever the bodies' sizes, finite and >= 0; 0 (the default): none. With both
  /// budgets the halving needs both; with neither (`auto_substeps_sag_fraction` 0 too) the
  /// soft step never lowers the substeps.
  double auto_substeps_sag = 0;
  /// Soft step with a sag budget above: the fewest substeps the lowering takes, in [1, 64].
  /// Below the halving the substeps come down a rung at a time, each three quarters of the
  /// last, rounded down (8 -> 4 -> 3 -> 2 -> 1, `contact_hertz` with them: 45 Hz at 3), each
  /// rung on the halving's conditions judged at its own rate and after kCalmTime (a second) at
  /// the rung above; none under this. The default 3 is the fewest at which the pyramids of the
  /// benchmarks sag no more than Bullet's (at 2 the Jolt pyramid of 2 m cubes sags 8.5 mm against
  /// Bullet's 8.0, at 3 4.8 mm: docs/rigid-bodies.md, "A ladder below the halving"). Half of
  /// `substeps` keeps the halving alone, as before 2026-12-05 (4 at the default 8; 3 for 6);
  /// a `substeps` whose half is under it is not lowered at all (4 or 2 at the default 3: halved
  /// to 2 and 1 before).
  int auto_substeps_least = 3;
  int iterations = 10;  ///< sequential impulses: velocity iterations per step, in [1, 1000]
  /// TGS: biased contact iterations per substep; XPBD: position iterations per substep; in
  /// [1, 100]. TGS and XPBD take many substeps of few iterations (Macklin et al. 2019).
  int substep_iterations = 1;
  /// TGS: relax iterations per substep (contacts solved without position bias after the
  /// positions move, so no push-out velocity survives), in [0, 100]
  int relax_iterations = 1;
  /// Sweeps over a manifold's points per pass, in [1, 16]: more converge its points toward
  /// their joint solution (4 keeps a 20-box stack from rocking; see docs/rigid-bodies.md).
  /// The relax passes (soft step, TGS) take three quarters of them, rounded up (3 of 4).
  int manifold_iterations = 4;
  /// Soft step: contact stiffness (Hz), finite and > 0, used up to a quarter of the substep
  /// rate. Contacts are implicit springs of this natural frequency, damped by `damping_ratio`,
  /// so a contact under a load W between bodies of effective mass m settles
  /// W / (m (2 pi hertz)^2) deep, and a stack of n boxes sags by about n^2 g / (2 pi hertz)^2:
  /// 7 mm for 20 one-metre boxes at the default 120 Hz and 8 substeps of a 60 Hz step.
  /// `auto_substeps` raises it with the substeps for a tall column (240 Hz at 16).
  double contact_hertz = 120;
  double damping_ratio = 10;     ///< soft step: contact damping ratio, finite and >= 0
  double push_out_speed = 3;     ///< largest speed (m/s) at which overlap is pushed apart, finite and > 0
  /// Sequential impulses: fraction of overlap removed per step; TGS: per substep, measured
  /// from the bodies' poses at that substep; in [0, 1]
  double baumgarte = 0.2;
  /// XPBD: compliance of a contact (m/N, the inverse stiffness), finite and >= 0; 0 is rigid
  double contact_compliance = 0;
  double linear_slop = 0.005;    ///< overlap (m) left uncorrected so contacts persist, finite and >= 0
  double speculative_distance = 0.02;  ///< manifolds include points closer than this (m), finite and >= 0
  /// A pair's manifold is carried over to the next step, its points fixed to the bodies, while
  /// the pair's points have moved less than this (m) against each other since the narrow phase
  /// made it (Jolt's body pair cache): the moving body's centre shift in the other's frame plus
  /// the chord its reach turns through, 2 r sin(angle / 2), so a carried point's separation is
  /// within this of a fresh one's. Finite and >= 0; 0 makes every manifold afresh each step.
  /// On by default (1 mm): resting piles then make almost no manifolds (docs/rigid-bodies.md).
  /// A ball's or a box's manifold with a plane that this test turns down is still carried while
  /// the narrow phase would make the same points, its plane points made again (exact on a flat
  /// plane; with reuse_distance > 0 only); so is a ball's one point on a mesh triangle's face
  /// while no other triangle comes within the reach.
  double reuse_distance = 0.001;
  /// ... and their relative rotation less than this (rad), finite and >= 0. The distance test
  /// already counts the chord a turn moves the body's reach through; a body's reach is at
  /// least sqrt(3) times its thinnest half size and a pair's reuse distance at most 0.02 of
  /// it, so whatever reuse_distance is, no pair keeps its manifold by this test (the plane's
  /// carry above aside) past 2 asin(0.01 / sqrt(3)) = 0.66 degrees of turn, and this test
  /// binds only when set below that (Jolt's body pair cache allows 2 degrees, with no chord;
  /// docs/rigid-bodies.md).
  double reuse_angle = 0.0175;
  /// Approach speeds (m/s) below this bounce with no restitution, so resting bodies stay put
  /// (finite and >= 0; XPBD also at speeds below 2 |g| h, Mueller et al. 2020).
  double restitution_threshold = 1;
  /// how friction coefficients combine (a value outside the enum is refused by name)
  MixRule friction_mix = MixRule::GeometricMean;
  /// how restitutions combine (a value outside the enum is refused by name)
  MixRule restitution_mix = MixRule::Maximum;
  bool warm_starting = true;     ///< start from last step's impulses (matched by feature id)
  /// Let resting islands (bodies linked by touching contacts) fall asleep: an island whose
  /// every body has moved slower than the tolerances for `time_to_sleep` stops being
  /// simulated until a contact with an awake body, a force, an impulse or a pose or velocity
  /// change wakes it. Turned off, the next step wakes every sleeping body. "Moved slower"
  /// is measured over the window (a column rocking 1 cm either way rests), and where the
  /// positions are too coarse to show a step's motion at `sleep_linear` (beyond
  /// sleep_linear * (dt / substeps) * 2^52, 4.7e11 m at the defaults) also by the speed. A
  /// body pushed by a force or torque in a step does not rest in it, nor does one speeding
  /// up steadily since its window began (a box sliding or tipping slowly from rest).
  bool sleep = true;
  double sleep_linear = 0.05;    ///< m/s, finite and >= 0 (Box2D's linear sleep tolerance)
  double sleep_angular = 0.0349; ///< rad/s (2 degrees/s), finite and >= 0
  /// s, finite and >= 0: how long an island must rest to fall asleep; a body's window is at
  /// least the step, and 16 sleep_linear / |gravity * gravity_scale| (82 ms at the defaults,
  /// at most 1 s), so a ball dropped or thrown stays awake with 0 (docs/rigid-bodies.md)
  double time_to_sleep = 0.5;

  /// Throws Error naming `where` and the bad field.
  void validate(std::string_view where) const;
  bool operator==(const ContactSettings&) const = default;
};

/// The instructions that run the contact solver's blocks (src/rigid/solver.h). Every path
/// does the same arithmetic in every lane, so all give the same bits; they differ in speed.
enum class RigidSimd : std::uint8_t {
  Best,    ///< the widest this CPU runs (AVX-512, else AVX2, else scalar) of those the build has
  Scalar,  ///< one manifold at a time
  Avx2,    ///< 4 manifolds at a time (x86-64 with AVX2)
  Avx512,  ///< 8 manifolds at a time (x86-64 with AVX-512F)
};

/// Lower-case name of a SIMD path ("best", "scalar", "avx2", "avx512").
std::string_view to_string(RigidSimd s);

/// Settings of a RigidBodySystem.
struct RigidSystemDef {
  std::size_t capacity = 256;  ///< bodies reserved up front; creating more allocates once per doubling
  ContactSettings contacts{};  ///< solver and contact settings
};

/// One contact point after the last step, for drawing and tests.
struct RigidContactPoint {
  RigidBodyId a{}, b{};        ///< the two bodies (the normal points from a to b)
  Vec3 position{0, 0, 0};      ///< world point (m)
  Vec3 normal{0, 0, 1};        ///< unit normal from a to b
  double depth = 0;            ///< overlap at the start of the step (m); < 0 speculative
  double normal_impulse = 0;   ///< normal impulse of the last substep (N s)
  double tangent_impulse = 0;  ///< the manifold's friction impulse (N s per substep) shared among its points
  std::uint32_t id = 0;        ///< feature id
};

/// One contact manifold of the last step in brief (RigidBodySystem::manifold), for events.
struct RigidManifoldInfo {
  RigidBodyId a{}, b{};           ///< the two bodies (the normal points from a to b)
  Vec3 normal{0, 0, 1};           ///< unit normal from a to b
  Vec3 point{0, 0, 0};            ///< its deepest point at the start of the step (world, m)
  double depth = 0;               ///< that point's overlap at the start of the step (m); < 0 speculative
  double approach_speed = 0;      ///< fastest normal closing speed of its points before the solve (m/s, >= 0)
  double max_normal_impulse = 0;  ///< largest single normal impulse of the step (N s); > 0: the solver pushed
  int points = 0;                 ///< contact points, 1 to 4
  /// The constraint-graph colour the solver put it in (the passes run the colours in order;
  /// no two manifolds of a colour share a dynamic body, so a colour is solved several at a
  /// time); -1 when it was solved one at a time (rolling resistance, or no colour free) or by XPBD.
  int color = -1;
};

/// Where the last step's time went (s).
struct RigidProfile {
  double collide = 0;    ///< pairs and manifolds
  double solve = 0;      ///< contact solver and integration (everything after collide)
  double total = 0;      ///< the whole step
  // the parts of `collide`
  double pairs = 0;      ///< shape bounds, the pair list and waking sleepers (s)
  double manifolds = 0;  ///< manifolds built or reused and warm-start data (s)
  // the parts of `solve`
  double prepare = 0;    ///< the solver's constraint arrays (colours, blocks), the soft step's columns (s)
  double integrate = 0;  ///< velocities and positions, all substeps (s)
  double contacts = 0;   ///< the contact passes: solve, relax (with the warm start), restitution (s)
  double finish = 0;     ///< continuous collision, storing the impulses, islands and sleep (s)
  double islands = 0;    ///< of `finish`: islands and sleeping (s)
  std::size_t built = 0;    ///< manifolds (pairs of shapes, or shape and triangle) the narrow phase made
  std::size_t reused = 0;   ///< manifolds carried over from an earlier step (the pair barely moved)
  std::size_t moved = 0;    ///< shape proxies that left their fat bounds and were re-inserted
  /// pairs of shapes in the broad phase's list when the manifolds were made (their fat boxes
  /// overlap; a manifold is made or carried for those whose tight boxes do; count)
  std::size_t shape_pairs = 0;
  /// bodies the continuous pass put back to their time of impact (continuous.cpp; count)
  std::size_t put_back = 0;
  /// manifolds the velocity solver took in blocks of one-point manifolds (a sphere's, a
  /// capsule's tip; the soft step and sequential impulses; 0 under TGS and XPBD)
  std::size_t one_point = 0;
  /// manifolds whose solver lanes kept last step's bodies, write masks, inverse masses,
  /// impulse unit and slop (the colours and the blocks' layout stood: a pile at rest; the
  /// soft step, sequential impulses and TGS; 0 when the layout was made anew)
  std::size_t lanes_kept = 0;
  /// substeps the step took (the soft step: `substeps`, or more for a tall column under
  /// ContactSettings::auto_substeps; TGS and XPBD: `substeps`; sequential impulses: 1)
  int substeps = 0;
  /// the soft step's tallest column of the last measure: dynamic bodies resting face on face
  /// along gravity, counted from one that rests on a body that does not move (0 for the other solvers)
  int column = 0;
  /// the soft step's load at half the substeps of the last measure, in the column model's
  /// n^3 g / (w^2 s) (a free column of n cubes of side s at the halved rate w): the braced
  /// model's for piles whose levels make a tree, the column model's otherwise and while the
  /// pairs change at 8 substeps (when the halving cannot use it, it is not made); the halving
  /// needs at most 0.25 (docs/rigid-bodies.md, "Braced piles"; 0 without a halving budget or other
  /// solvers)
  double half_load = 0;
};

namespace detail {
struct RigidContacts;
struct SolverBody;
struct FreeMotionArrays;
}  // namespace detail

/// How RigidBodySystem::draw colours the bodies.
struct RigidDrawOptions {
  /// Dynamic bodies cycle through these by dense index (one colour when it holds one).
  std::span<const Color> palette{};
  Color dynamic = colors::blue;     ///< dynamic bodies when the palette is empty
  Color fixed = colors::grey;       ///< static bodies
  Color kinematic = colors::orange; ///< kinematic bodies
  /// Sleeping bodies are drawn this far (0..1) from their colour toward grey, so the sleep
  /// state shows (0: no difference).
  float sleep_fade = 0.6f;
  RigidBodyId highlight{};          ///< a body drawn in `highlight_color` (none when null)
  Color highlight_color = colors::yellow;  ///< see highlight
  double plane_half_size = 10;      ///< drawn extent of planes (m)
  /// Draw planes facing +Y too (false leaves a ground at y = 0 to the app's own grid).
  bool horizontal_planes = true;
};

/// Rigid bodies in structure-of-arrays layout. Not thread-safe. Steps never allocate.
class RigidBodySystem {
 public:
  /// Validates `def` (throws Error naming the bad field).
  explicit RigidBodySystem(const RigidSystemDef& def = {});

  // ---- bodies ----

  /// Creates a body (validates `def`; the Error names `where`, the body's name and the field).
  /// A dynamic body's mass (kg) and principal moments (kg m^2), given or from the shapes,
  /// must each be in [2.94e-39, 8.5e37] (the contact solver stores them and their inverses as
  /// floats). Compounds, nested ones too, become their leaf shapes.
  RigidBodyId create(const RigidBodyDef& def, std::string_view where = "RigidBodyDef");
  /// Removes a body (throws Error for a stale handle).
  void destroy(RigidBodyId id);
  /// True when `id` names a live body.
  bool valid(RigidBodyId id) const { return ids_.valid(id); }
  /// Throws Error naming `where` unless valid(id): a null, stale or never issued handle, as
  /// HandlePool::require says it.
  void require(RigidBodyId id, std::string_view where) const { ids_.require(id, where); }
  /// Live bodies.
  std::size_t size() const { return type_.size(); }
  /// The handle of the i-th live body, i in [0, size()) (the order changes when bodies are
  /// destroyed). Throws Error naming `i` and the range outside it.
  RigidBodyId id_at(std::size_t i) const {
    if (i >= owner_.size()) id_out_of_range(i);
    return {owner_[i], ids_.generation(owner_[i])};
  }

  /// The body frame's pose.
  Pose pose(RigidBodyId id) const;
  /// The world position of the centre of mass (m).
  Vec3 center_of_mass(RigidBodyId id) const;
  /// The velocity of the centre of mass (m/s).
  Vec3 linear_velocity(RigidBodyId id) const;
  /// The world angular velocity (rad/s).
  Vec3 angular_velocity(RigidBodyId id) const;
  /// The velocity of the body's material point now at world point `p` (m/s).
  Vec3 velocity_at(RigidBodyId id, const Vec3& p) const;
  /// The world angular momentum about the centre of mass (kg m^2/s).
  Vec3 angular_momentum(RigidBodyId id) const;
  /// Kinetic energy, translational plus rotational (J).
  double kinetic_energy(RigidBodyId id) const;
  /// Mass (kg; infinity for static and kinematic bodies).
  double mass(RigidBodyId id) const;
  /// The world inertia tensor about the centre of mass (kg m^2; zero for non-dynamic bodies).
  Mat3 world_inertia(RigidBodyId id) const;
  /// The body's type.
  BodyType type(RigidBodyId id) const;
  /// False while the body sleeps (static bodies are never awake; kinematic ones always).
  bool awake(RigidBodyId id) const;
  /// Wakes the body and the island it slept in.
  void wake(RigidBodyId id);
  /// Dynamic bodies awake now.
  std::size_t awake_count() const;
  /// The body's name.
  const std::string& name(RigidBodyId id) const;

  /// Moves a body (validated as RigidBodyDef::pose: a unit rotation, a position within the
  /// float range) and wakes it; a static or kinematic body moved also wakes the sleeping
  /// bodies its shapes' bounds reach before or after the move (what rested on it, what it
  /// jumped into), and a dynamic one those its shapes touch (closer than
  /// ContactSettings::speculative_distance) before the move at once (what rested on it, in
  /// its island or not) and after it at the next step (what it jumped into, as Box2D's
  /// contact begin wakes them; a sleeper only near it sleeps on). The cost is the broad
  /// phase's query of the body's bounds, not a scan of the bodies. A kinematic body moved
  /// this way has no velocity: what rests on it is not carried by friction (give it a
  /// velocity for that).
  void set_pose(RigidBodyId id, const Pose& pose);
  /// Sets the centre of mass velocity and the angular velocity (validated) and wakes the
  /// body; a static body never moves, so on one it only validates (make it kinematic to move it).
  void set_velocity(RigidBodyId id, const Vec3& linear, const Vec3& angular);
  /// Adds a force (N) at world point `p` (m) for the next step (a torque (p - com) x F too).
  /// Forces, torques and impulses act on dynamic bodies only: on a static or kinematic body
  /// (infinite mass) they are validated and change nothing.
  void apply_force(RigidBodyId id, const Vec3& force, const Vec3& p);
  /// Adds a force (N) at the centre of mass for the next step.
  void apply_force(RigidBodyId id, const Vec3& force);
  /// Adds a torque (N m) for the next step.
  void apply_torque(RigidBodyId id, const Vec3& torque);
  /// Applies an impulse (N s) at world point `p` now: dv = J / m, dw = I^-1 (p - com) x J.
  void apply_impulse(RigidBodyId id, const Vec3& impulse, const Vec3& p);
  /// Applies an angular impulse (N m s) now.
  void apply_angular_impulse(RigidBodyId id, const Vec3& impulse);

  // ---- stepping ----

  /// Contact and solver settings (validated at each step).
  ContactSettings& settings() { return settings_; }
  /// Contact and solver settings.
  const ContactSettings& settings() const { return settings_; }
  /// Sets the substeps per step, in [1, 64], exactly: it turns ContactSettings::auto_substeps off.
  void set_substeps(int n);
  /// Picks the contact solver's SIMD path (for tests and benchmarks; results do not depend on
  /// it). Throws Error naming the path when this CPU cannot run it, or this build left it out
  /// (CMake's PBA_AVX512=OFF leaves out the AVX-512 kernels).
  void set_simd(RigidSimd path);
  /// The SIMD path in use (never Best).
  RigidSimd simd() const;
  /// Whether a step whose contact colours and block layout are last step's keeps the solver
  /// lanes' bodies, inverse masses and slop instead of gathering them again (on by default;
  /// for tests and benchmarks: results do not depend on it, RigidProfile::lanes_kept counts them).
  void set_lane_reuse(bool on);
  /// Advances every body from t to t + dt (s; finite and > 0) under `gravity` (m/s^2). A
  /// gravity other than the last step's wakes the sleeping bodies (gravity_scale != 0).
  /// Throws Error if a body's state becomes non-finite, naming the body and the step's end
  /// time; the system then refuses to step again. A step stopped so leaves the bodies partway:
  /// each where its last whole substep took it (the step's start under sequential impulses,
  /// which had not moved them), the failed body with the velocity that stopped it, and the
  /// others' velocities not those of their positions (the soft step and TGS leave them at the
  /// step's start, XPBD a substep ahead of the positions).
  void step(double dt, const Vec3& gravity);
  /// Simulated time (s).
  double time() const { return time_; }
  /// 64-bit hash of every body's pose and velocities (bit patterns).
  std::uint64_t hash() const;
  /// Draws what `flags` select: each body's shapes (sleeping bodies faded), their world
  /// bounds, and the contact points (red overlapping, green speculative) and normals.
  void draw(DebugDraw& draw, const DrawFlags& flags = {}, const RigidDrawOptions& options = {}) const;
  /// Draws one body's shapes at its pose now in `color`, as `flags` select (shapes, aabbs);
  /// a plane is a patch `options.plane_half_size` wide (none facing +Y unless
  /// `options.horizontal_planes`). Throws Error for a stale handle.
  void draw_body(DebugDraw& draw, RigidBodyId id, Color color, const DrawFlags& flags = {},
                 const RigidDrawOptions& options = {}) const;
  /// Draws the last step's contact points (red overlapping, green speculative) and their
  /// normals, as `flags` select (contacts, normals).
  void draw_contacts(DebugDraw& draw, const DrawFlags& flags = {}) const;
  /// The contact points of the last step (copies; allocates, for drawing and tests).
  std::vector<RigidContactPoint> contacts() const;
  /// Contact manifolds (touching or speculative shape pairs) in the last step.
  std::size_t manifold_count() const;
  /// Manifold k of the last step in brief, k in [0, manifold_count()) (no allocation; the
  /// order is the solver's, deterministic). Pairs whose bodies all sleep are not stepped,
  /// so they have no manifold.
  RigidManifoldInfo manifold(std::size_t k) const;
  /// Timings of the last step.
  const RigidProfile& profile() const { return profile_; }
  /// The body that stopped the system (its state non-finite, or faster than kMaxRigidSpeed;
  /// step() throws naming it), or a null handle while it runs.
  RigidBodyId failed_body() const { return failed_; }
  /// The world bounds of every shape of body `id` at its pose now.
  std::vector<Aabb> shape_bounds(RigidBodyId id) const;
  /// The shapes of body `id` (in the body frame).
  std::span<const RigidShapeDef> shapes(RigidBodyId id) const;

  ~RigidBodySystem();
  RigidBodySystem(RigidBodySystem&&) noexcept;
  RigidBodySystem& operator=(RigidBodySystem&&) noexcept;

 private:
  friend struct detail::RigidContacts;
  std::size_t index(RigidBodyId id, std::string_view where) const;
  [[noreturn]] void id_out_of_range(std::size_t i) const;  // id_at's Error
  // the body frame of dense body i, from its principal frame and centre of mass (defined in
  // src/rigid/body_frame.h with detail::body_frame, which leaves out the identities' products
  // where they give the same bits; inline for update_proxies, which makes one an awake body a step)
  inline Pose body_pose(std::size_t i) const;
  std::string describe(std::size_t i) const;
  // dense body i's shapes in colour c (draw, draw_body)
  void draw_shapes(DebugDraw& draw, std::size_t i, Color c, const DrawFlags& flags,
                   const RigidDrawOptions& options) const;
  // the free motion's arrays (velocities in `rows` when given, else in v_ and w_)
  detail::FreeMotionArrays free_motion(detail::SolverBody* rows, detail::SolverBody* warm, double* motion);
  // rows (optional): the contact solver's velocity rows, used instead of v_ and w_; warm
  // (optional, by body): velocity changes added after the forces and zeroed
  void integrate_velocities(double h, const Vec3& gravity, detail::SolverBody* rows = nullptr,
                            detail::SolverBody* warm = nullptr);
  // motion (optional, 8 doubles by body): each moving body's dp and turn since the start of the step
  void integrate_positions(double h, detail::SolverBody* rows = nullptr, double* motion = nullptr);
  void check_finite();
  [[noreturn]] void fail(std::size_t i);
  void update_sleep(double dt);
  void wake_island(std::size_t i);
  // wakes sleeping body i's island and lists its bodies as jumped (list_jumped): next step
  // wakes the sleepers they touch, one island a step up a chain of sleeping islands
  void wake_island_listed(std::size_t i);
  // lists handle slot `slot` for the next step's wake_touched, once
  void list_jumped(std::uint32_t slot);
  // the margin (m) within which two shapes touch for waking: the speculative distance or the
  // linear slop, whichever is larger, plus 1 um (a body rests at a gap of 0 or 1e-11 m when
  // both are 0, and a point comes out only closer than the margin)
  double touch_margin() const;
  // whether shape shape_i of dense body i and shape shape_k of body k (both solid) are closer
  // than touch_margin() at their poses now (the narrow phase: a manifold with points)
  bool shapes_touch(std::size_t i, std::size_t shape_i, std::size_t k, std::size_t shape_k) const;
  // wake the sleeping bodies (found by the broad phase's tree) whose shapes' bounds overlap
  // `reach` (world, m), or that body i's shapes touch at its pose now (shapes_touch), and
  // list them as jumped (wake_island_listed)
  void wake_reached(const Aabb& reach);
  void wake_touching(std::size_t i);

  ContactSettings settings_{};
  ContactSettings validated_{};  // the settings last validated (validation builds messages)
  RigidProfile profile_{};
  std::unique_ptr<detail::RigidContacts> contacts_;
  double time_ = 0;
  double last_dt_ = 0;
  Vec3 gravity_{0, 0, 0};  // the last step's gravity (m/s^2): a change wakes the sleepers
  std::string failure_;
  RigidBodyId failed_{};  // the body failure_ names
  HandlePool<RigidBodyTag> ids_;
  std::vector<std::uint32_t> slot_;   // handle slot -> dense index
  std::vector<std::uint32_t> owner_;  // dense index -> handle slot
  // hot state, dense by body
  std::vector<BodyType> type_;
  std::vector<Vec3> com_;             // world centre of mass (m)
  std::vector<Quat> q_;               // principal frame in the world
  std::vector<Vec3> v_, w_;           // centre-of-mass velocity, world angular velocity
  std::vector<Vec3> force_, torque_;  // accumulated for the next step
  std::vector<double> inv_mass_;
  std::vector<Vec3> inv_inertia_;     // principal inverse moments (1 / (kg m^2)); 0 for non-dynamic
  std::vector<Vec3> inertia_;         // principal moments (kg m^2)
  std::vector<double> lin_damp_, ang_damp_, gravity_scale_;
  // cold: the body frame relative to the principal frame, names
  std::vector<Vec3> com_local_;       // centre of mass in the body frame
  std::vector<Quat> principal_;       // principal frame in the body frame
  std::vector<std::string> name_;
  std::vector<std::uint8_t> bullet_;
  std::vector<double> extent_;      // bounding radius of the shapes about the centre of mass (m)
  std::vector<double> min_extent_;  // smallest half size of a shape (m): faster than half of it per step is fast
  std::vector<std::vector<RigidShapeDef>> shapes_;  // by dense index
  // sleeping: flags, time spent slow, and for a sleeping body the next member of its island
  // (a ring of dense indices; an awake body points to itself)
  std::vector<std::uint8_t> asleep_;
  std::vector<double> sleep_time_;
  // where the body's current rest window began: its centre of mass and principal frame then,
  // and its velocities then (m/s, rad/s: a body speeding up since does not rest)
  std::vector<Vec3> rest_com_;
  std::vector<Quat> rest_q_;
  std::vector<Vec3> rest_v_, rest_w_;
  std::vector<std::uint32_t> island_;
  std::vector<std::uint32_t> parent_;  // union-find scratch
  std::vector<double> island_slow_;    // scratch: the island's least slow time past its window, s
  // start of the step, for the contact solver's separation updates
  std::vector<Vec3> com0_;
  std::vector<Quat> q0_;
  // ContactSettings::auto_substeps: the factor on the substeps and contact_hertz now, as a
  // power of two (0, 1 or 2), or -k at the k-th rung below `substeps` that a sag budget allows
  // (-1 halved, -2 three eighths at the defaults: columns.cpp), and how long (s) the columns
  // have fitted the next count down
  int auto_shift_ = 0;
  double auto_calm_ = 0;
  // the soft step's substeps this step (auto_substeps) and its factor on contact_hertz
  int step_substeps(double dt, const Vec3& gravity);
};

}  // namespace pba
