// pba inverse kinematics: skeletons (trees of bones and joints), end-effectors,
// forward kinematics, and run-time selectable solvers: analytic (1-DOF, 3-DOF,
// two-bone with a pole), CCD, the Jacobian family (transpose, pseudo-inverse,
// damped least squares, SVD-based selectively damped least squares) and FABRIK.
//
// Conventions. Every bone has its own frame; the bone extends `length` metres
// along its local +X axis from its joint (the "start") to its "tip". A child's
// joint sits at its parent's tip. The world rotation of bone i is
//   R_i = R_parent * rest_i * q_i
// where rest_i is the fixed rotation of the bone's frame relative to its parent
// (at zero joint angles) and q_i is the joint rotation: angleAxis(angle_i, axis_i)
// for a hinge, a free unit quaternion for a ball joint, identity for a fixed joint.
// The root's parent frame is (root_position, root_rotation).
//
// See docs/ik.md for the maths, references and when to use which solver.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pba/core.h"
#include "pba/draw.h"

namespace pba::ik {

/// Kind of joint at the start of a bone.
enum class JointType : std::uint8_t {
  Fixed,  ///< no degree of freedom: the bone is welded to its parent at `rest`
  Hinge,  ///< 1 DOF: rotation by an angle (rad) about `axis`, within [min_angle, max_angle]
  Ball,   ///< 3 DOF: swing inside a cone about the bone axis (+X) and twist about it
};

/// Definition of one bone and the joint at its start. Defaults make a free ball joint.
struct BoneDef {
  std::string name;                 ///< optional, used in error messages and drawing
  int parent = -1;                  ///< index of the parent in SkeletonDef::bones, -1 for the root
  double length = 1.0;              ///< bone length (m), > 0 and <= 3.4e38 (a float's range)
  Quat rest{1, 0, 0, 0};            ///< rotation of the joint frame relative to the parent bone's frame (unit)
  JointType joint = JointType::Ball;  ///< joint kind
  Vec3 axis{0, 0, 1};               ///< hinge axis in the joint frame (unit); should not be parallel to +X
  double min_angle = -kPi;  ///< hinge lower limit (rad), in [-pi, pi]
  double max_angle = kPi;   ///< hinge upper limit (rad), in [min_angle, pi]; a 2 pi range is unlimited
  double swing_limit = kPi; ///< ball: max angle (rad) between the bone axis and the rest +X, in [0, pi]
  double min_twist = -kPi;  ///< ball: lower twist limit about the bone axis (rad), in [-pi, pi]
  double max_twist = kPi;   ///< ball: upper twist limit (rad), in [min_twist, pi]
  double radius = 0;                ///< drawing radius of the capsule (m); 0 picks 8% of the length
};

/// Definition of a skeleton: a tree of bones. Built into a Skeleton, which validates it.
struct SkeletonDef {
  std::vector<BoneDef> bones;       ///< any order; exactly one root; no cycles
  Vec3 root_position{0, 0, 0};      ///< world position of the root joint (m), |component| <= 3.4e38
  Quat root_rotation{1, 0, 0, 0};   ///< world rotation of the root's parent frame (unit)
  bool root_free = false;           ///< true: the solvers may also translate the root (3 more DOF)
};

/// Smallest effector weight (EffectorDef::weight). Weights are relative, and the solvers
/// compare weighted squared errors: a weight below this underflowed them (a solve
/// stalled where it started), one above kMaxEffectorWeight overflowed them (the pose came
/// back non-finite from jacobian_transpose, unmoved from the others).
inline constexpr double kMinEffectorWeight = 1e-6;
/// Largest effector weight (see kMinEffectorWeight).
inline constexpr double kMaxEffectorWeight = 1e6;

/// An end-effector: the tip of a bone pulled toward a target.
struct EffectorDef {
  int bone = 0;                     ///< bone index (Skeleton order, see Skeleton::index_of)
  Vec3 target{0, 0, 0};             ///< target position of the bone tip (m), finite, |component| <= 3.4e38
  std::optional<Quat> orientation;  ///< optional target world rotation of the bone (unit)
  double weight = 1.0;              ///< relative importance, in [kMinEffectorWeight, kMaxEffectorWeight]
  std::optional<Vec3> pole;         ///< optional pole position (m) for the two-bone solver, as target
};

/// Options for Skeleton::draw.
struct SkeletonDrawOptions {
  bool bones = true;                ///< capsules for bones
  double bone_radius = 0;           ///< capsule radius (m), >= 0; 0: each bone's BoneDef::radius, or 8% of its length
  double min_radius = 0;            ///< smallest capsule radius (m), >= 0, so that the many short bones of a long
                                    ///< chain stay visible
  bool joints = true;               ///< spheres at joints, coloured by type
  bool limits = false;              ///< hinge arcs and ball cones
  bool targets = true;              ///< effector targets and their error lines
  bool frames = false;              ///< small RGB axis triads per bone
  Color bone_color = colors::grey;  ///< capsule colour
};

/// A built skeleton: its model (lengths, joints, limits), its pose (joint rotations),
/// its world transforms (after forward_kinematics) and its end-effectors.
/// Bones are stored in topological order (parents before children), so forward
/// kinematics is one forward pass. If SkeletonDef::bones was not in that order, the
/// bones are reordered and index_of() maps a definition index to the stored index.
class Skeleton {
 public:
  /// Validates `def` and builds the skeleton at its rest pose (all joint angles 0).
  /// Throws pba::Error naming the bone index and the bad value (length, limits,
  /// axis, rest rotation, parent index out of range, cycles, several roots).
  explicit Skeleton(const SkeletonDef& def);

  /// A chain of `n` bones of `length` metres along +X from the origin, all with
  /// `joint` joints (hinges about local Z by default). A convenience for samples and tests.
  static Skeleton chain(int n, double length, JointType joint = JointType::Ball,
                        const BoneDef& joint_template = {});

  /// Number of bones (>= 1).
  int bone_count() const { return static_cast<int>(parent_.size()); }
  /// Number of joint degrees of freedom (hinge 1, ball 3), plus 3 for a free root.
  int dof_count() const { return dof_count_; }
  /// Stored index of the bone with SkeletonDef index `def_index`.
  int index_of(int def_index) const;
  /// Stored index of the bone named `name`, or -1.
  int find(std::string_view name) const;

  // --- model (read only) ---
  /// Parent index of each bone (-1 for the root), in stored order.
  std::span<const int> parents() const { return parent_; }
  /// Bone lengths (m).
  std::span<const double> lengths() const { return length_; }
  /// Joint type per bone.
  std::span<const JointType> joint_types() const { return type_; }
  /// Definition of bone i (stored order), as given (parent index remapped to stored order).
  /// Throws pba::Error naming i and the bone count unless 0 <= i < bone_count().
  const BoneDef& bone_def(int i) const {
    if (i < 0 || i >= bone_count()) index_out_of_range(i, bone_count(), "bone", "Skeleton::bone_def");
    return defs_[i];
  }
  /// Sum of all bone lengths (m).
  double total_length() const { return total_length_; }
  /// Sum of the lengths from the root to the tip of `bone` (m): the reach of that tip.
  double reach(int bone) const;
  /// True when the root may translate.
  bool root_free() const { return root_free_; }

  // --- pose ---
  /// Local joint rotations q_i (unit quaternions), stored order.
  std::span<const Quat> joint_rotations() const { return q_; }
  /// Hinge angles (rad); 0 for non-hinge bones.
  std::span<const double> hinge_angles() const { return angle_; }
  /// Sets bone i's joint rotation. A hinge takes the rotation's angle about its axis.
  /// The result is clamped to the joint limits. Throws on a non-finite or zero quaternion.
  void set_joint_rotation(int i, const Quat& q);
  /// Sets a hinge angle (rad), clamped to its limits. Throws if bone i is not a hinge.
  void set_hinge_angle(int i, double angle);
  /// Resets all joints to zero angles (the rest pose) and the root to its definition.
  void reset_pose();
  /// Root joint position (m) (changes only for a free root).
  const Vec3& root_position() const { return root_position_; }
  /// Moves the root joint (m). Throws on values that are not finite or beyond 3.4e38.
  void set_root_position(const Vec3& p);
  /// Root parent frame rotation.
  const Quat& root_rotation() const { return root_rotation_; }
  /// True when every joint is within its limits to `tol` rad. Writes the first bad bone to `bad`.
  bool within_limits(double tol = 1e-9, int* bad = nullptr) const;

  // --- forward kinematics ---
  /// Recomputes world rotations, joint positions and tips from the pose: one pass, O(bones).
  void forward_kinematics();
  /// True when the pose changed (set_joint_rotation, set_hinge_angle, reset_pose,
  /// set_root_position) since the last forward_kinematics().
  bool kinematics_dirty() const { return fk_dirty_; }
  /// World position of bone i's joint (its start) (m), valid after forward_kinematics.
  std::span<const Vec3> starts() const { return start_; }
  /// World position of bone i's tip (m), valid after forward_kinematics.
  std::span<const Vec3> tips() const { return tip_; }
  /// World rotation of bone i (its +X is the bone direction).
  std::span<const Quat> world_rotations() const { return world_; }

  // --- end-effectors ---
  /// Adds an end-effector (allocates; do this at set-up, not per frame). Returns its index.
  /// Throws on a bad bone index, a target or pole not finite or beyond 3.4e38, or a weight
  /// outside [kMinEffectorWeight, kMaxEffectorWeight].
  int add_effector(const EffectorDef& e);
  /// Adds a position-only effector on `bone` pulled toward `target` (m) with `weight` (in
  /// [kMinEffectorWeight, kMaxEffectorWeight]).
  int add_effector(int bone, const Vec3& target, double weight = 1.0);
  /// Removes every end-effector.
  void clear_effectors();
  /// Number of end-effectors.
  int effector_count() const { return static_cast<int>(effectors_.size()); }
  /// Definition of effector k (its current target included). Throws pba::Error naming k and
  /// the effector count unless 0 <= k < effector_count().
  const EffectorDef& effector(int k) const {
    if (k < 0 || k >= effector_count()) index_out_of_range(k, effector_count(), "effector", "Skeleton::effector");
    return effectors_[k];
  }
  /// Moves effector k's position target (m). Throws pba::Error on values that are not finite
  /// or beyond 3.4e38. Never allocates.
  void set_target(int k, const Vec3& target);
  /// Sets or clears effector k's orientation target. Throws on a non-finite or zero quaternion.
  void set_orientation_target(int k, std::optional<Quat> q);
  /// Sets effector k's pole position (m) for the two-bone solver (finite, |component| <= 3.4e38).
  void set_pole(int k, std::optional<Vec3> pole);
  /// Position error |tip - target| of effector k (m), valid after forward_kinematics. Throws
  /// pba::Error naming k and the effector count unless 0 <= k < effector_count().
  double effector_error(int k) const;
  /// Largest position error over all effectors (m); 0 without effectors.
  double max_effector_error() const;
  /// Incremented whenever effectors are added or removed (solvers re-size then).
  std::uint64_t effector_version() const { return effector_version_; }

  /// Hash of the pose and world positions, for determinism checks.
  std::uint64_t state_hash() const;

  /// Draws bones as capsules, joints as spheres, limits and targets.
  void draw(DebugDraw& dd, const SkeletonDrawOptions& options = {}) const;

 private:
  friend struct SolverAccess;  // the solvers in src/ik work on these arrays in place
  // the Error of an index out of range: the call, the index and how many there are
  [[noreturn]] static void index_out_of_range(int i, int count, const char* what, const char* call);
  void clamp_joint(int i);

  std::vector<BoneDef> defs_;
  std::vector<int> def_to_stored_;
  // model, structure of arrays
  std::vector<int> parent_;
  std::vector<double> length_;
  std::vector<JointType> type_;
  std::vector<Quat> rest_;
  std::vector<std::uint8_t> rest_identity_;  // 1 when rest_ is exactly the identity
  std::vector<Vec3> axis_;
  std::vector<double> lo_, hi_;          // hinge angle or ball twist limits (rad)
  std::vector<double> swing_;            // ball swing limit (rad)
  std::vector<std::uint8_t> limited_;    // 1 when the joint has effective limits
  std::vector<int> dof_offset_;          // first DOF index of each joint
  std::vector<double> reach_;            // root-to-tip length per bone (m)
  double total_length_ = 0;
  int dof_count_ = 0;
  bool root_free_ = false;
  Vec3 root_position0_{0}, root_position_{0};
  Quat root_rotation_{1, 0, 0, 0};
  // pose
  std::vector<Quat> q_;
  std::vector<double> angle_;
  // world transforms
  std::vector<Quat> world_;
  std::vector<Vec3> start_, tip_;
  bool fk_dirty_ = true;                 // pose changed since the last forward_kinematics
  // effectors
  std::vector<EffectorDef> effectors_;
  std::uint64_t effector_version_ = 0;
};

/// Solver methods, all usable on the same skeleton through ik::Solver. Enumerators are
/// PascalCase like pba::Method's (the integrators); the names users type (scene files,
/// --option solver=...) are name()'s: "analytic_1dof", ..., "fabrik".
enum class Method : std::uint8_t {
  Analytic1Dof,       ///< "analytic_1dof": one hinge aims its bone at the target with a dot and a cross product
                      ///< (workbook 2.3)
  Analytic3Dof,       ///< "analytic_3dof": one ball joint aims its bone at the target (shortest-arc rotation)
  TwoBone,            ///< "two_bone": law of cosines on a ball + hinge limb, with a pole vector (TwoBoneJob)
  Ccd,                ///< "ccd": cyclic coordinate descent, workbook Algorithm 1
  JacobianTranspose,  ///< "jacobian_transpose": dtheta = alpha J^T e, alpha from Buss (2004) eq. 7
  PseudoInverse,      ///< "pseudo_inverse": dtheta = J^T (J J^T)^-1 e (workbook 2.5)
  Dls,                ///< "dls": damped least squares, J^T (J J^T + lambda^2 I)^-1 e
  Sdls,               ///< "sdls": SVD-based selectively damped least squares (Buss and Kim 2005)
  Fabrik,             ///< "fabrik": forward and backward reaching IK (Aristidou and Lasenby 2011)
};

/// Every method, in declaration order (for UI lists and benchmarks).
inline constexpr Method kAllMethods[] = {Method::Analytic1Dof,  Method::Analytic3Dof,      Method::TwoBone,
                                         Method::Ccd,           Method::JacobianTranspose, Method::PseudoInverse,
                                         Method::Dls,           Method::Sdls,              Method::Fabrik};

/// The method's name as users type it ("ccd", "dls", "fabrik", ...; see Method). The helpers
/// are named as the integrators' (pba::Method): name(), method_names(), parse_method().
std::string_view name(Method m);
/// All method names joined by ", " (for help texts and error messages).
std::string method_names();
/// Parses a method name as printed by name(), case-insensitive, '-' for '_' (also "jt",
/// "pinv", "two-bone", "svd"). Throws pba::Error "<where>: unknown IK solver 'x' (expected
/// one of ...)".
Method parse_method(std::string_view text, std::string_view where = "ik solver");

/// Solver settings. All lengths in metres, angles in radians.
struct SolverSettings {
  Method method = Method::Fabrik;   ///< the algorithm
  int max_iterations = 0;           ///< iteration cap, >= 0; 0 picks the method's default
  double tolerance = 1e-4;          ///< converged when every effector is within this distance (m), > 0
  double orientation_tolerance = 1e-3;  ///< converged when orientation errors are below this (rad), > 0
  double damping = 0.0;             ///< DLS lambda as a fraction of the effectors' reach times the root sum of
                                    ///< squares of their weights (m), >= 0; 0 picks 0.02
  double max_step_angle = 0.0;      ///< Jacobian methods' cap on any joint change per iteration (rad), >= 0;
                                    ///< 0 picks 0.5 (pi/4 for sdls, Buss and Kim's gamma_max)
  bool warm_start = true;           ///< start from the current pose; false starts from the rest pose
  double stall_ratio = 1e-9;        ///< in [0, 1]: stop (StopReason::Stalled) when an accepted step changes the error
                                    ///< by less than this fraction of it, a stationary pose (the closest reachable
                                    ///< pose of an unreachable target); slow progress never stops a solve
                                    ///< (docs/ik.md, "Stopping"): the transpose, the pseudo-inverse, SDLS and
                                    ///< FABRIK hand over to DLS
  double max_seconds = 0.0;         ///< time budget per solve (s), >= 0; 0: none. The iterative methods stop
                                    ///< once it is spent (checked every iteration from 64 bones on, every 8
                                    ///< below; one check costs about 60 ns). With a budget, results depend
                                    ///< on the machine's speed: leave 0 where runs must repeat bit for bit
  /// Validates every field; throws pba::Error naming the field and value.
  void validate(std::string_view where = "SolverSettings") const;
};

/// Why a solve stopped (SolveResult::stop).
enum class StopReason : std::uint8_t {
  Converged,     ///< every effector within SolverSettings::tolerance (and orientation tolerance, where honoured)
  Stalled,       ///< no step lowers the error any more: the pose is stationary (the closest reachable
                 ///< pose of an unreachable target, or a local minimum pressed on joint limits), or the
                 ///< analytic method's one step did not reach the target
  IterationCap,  ///< the iteration budget (SolverSettings::max_iterations, or the method's default) is spent
  OutOfTime,     ///< the time budget SolverSettings::max_seconds is spent
};

/// Short name of a stop reason ("converged", "stalled", "iteration_cap", "out_of_time").
std::string_view name(StopReason r);

/// What a solve did. A solve never returns a pose worse than the one it was given: its
/// weighted squared position error (plus the orientation error, scaled by the effectors'
/// reach, for the methods that honour orientation targets) is at most the starting one.
struct SolveResult {
  int iterations = 0;        ///< iterations performed (analytic solvers: 1); rejected steps count
  double residual = 0;       ///< largest effector position error after the solve (m)
  double orientation_residual = 0;  ///< largest orientation error (rad), 0 without orientation targets
  bool converged = false;    ///< residual <= tolerance, and orientation residual <= its tolerance for
                             ///< the methods that honour orientation targets (FABRIK and the Jacobian family)
  bool out_of_time = false;  ///< the solve stopped because SolverSettings::max_seconds was spent
  StopReason stop = StopReason::Converged;  ///< why the solve stopped
  bool handed_over = false;  ///< the method stopped making progress (or stalled where that does not mean a
                             ///< stationary pose) and damped least squares took the remaining iterations
                             ///< (every iterative method but DLS can; see docs/ik.md)
};

/// Default iteration cap of a method (used when SolverSettings::max_iterations is 0).
int default_max_iterations(Method m);

/// Whether `m` can solve `skeleton` with its current effectors; on false, `why`
/// explains (e.g. "analytic_1dof needs exactly one moving joint, a hinge").
bool supports(Method m, const Skeleton& skeleton, std::string* why = nullptr);

/// An IK solver bound to one skeleton. Its workspace is sized when built (and again,
/// once, if effectors are added or removed); solve() then allocates nothing.
class Solver {
 public:
  /// Builds a solver for `skeleton` (which must outlive it). Validates `settings`.
  Solver(Skeleton& skeleton, const SolverSettings& settings = {});
  /// Builds a solver with default settings for method `m`.
  Solver(Skeleton& skeleton, Method m);
  /// Releases the workspace.
  ~Solver();
  /// Moves the solver (the skeleton binding and workspace go with it).
  Solver(Solver&&) noexcept;
  /// Move-assigns the solver.
  Solver& operator=(Solver&&) noexcept;

  /// Replaces the settings (validated; throws pba::Error).
  void set_settings(const SolverSettings& settings);
  /// Current settings.
  const SolverSettings& settings() const;
  /// Switches the method, keeping the other settings.
  void set_method(Method m);

  /// Moves the skeleton's pose toward the effectors' targets and leaves it with
  /// forward kinematics up to date. Never violates joint limits. Throws pba::Error
  /// if the method does not support the skeleton (see supports()).
  SolveResult solve();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Blend mode between two poses.
enum class Blend : std::uint8_t {
  Lerp,   ///< normalised linear interpolation of joint quaternions (nlerp)
  Slerp,  ///< spherical linear interpolation (constant angular speed)
};

/// The workbook's "move the arm only once a solution is found" option: a solver runs on
/// a private copy of the pose; when it converges (within `max_attempts` solves, each up to
/// the iteration cap, continuing from where the previous stopped), that pose becomes the
/// goal and the visible skeleton blends toward it over time. Allocates only when built.
class SolveThenBlend {
 public:
  /// `visible` is the skeleton that is drawn; the solver works on an internal copy.
  SolveThenBlend(Skeleton& visible, const SolverSettings& settings, Blend blend = Blend::Slerp,
                 double blend_rate = 8.0, int max_attempts = 4);
  /// Not copyable or movable: its solver is bound to its own internal skeleton (hold it by
  /// std::unique_ptr to move it around).
  SolveThenBlend(const SolveThenBlend&) = delete;
  /// Not assignable (see the copy constructor).
  SolveThenBlend& operator=(const SolveThenBlend&) = delete;
  /// Copies targets from the visible skeleton, solves (up to max_attempts), and on
  /// success sets a new goal. Then advances the visible pose toward the goal by
  /// 1 - exp(-blend_rate dt) of the remaining rotation. `dt` (s) finite, >= 0.
  /// Returns the last solve's result; `converged` false means the goal was kept.
  SolveResult update(double dt);
  /// True while a goal pose is set and not yet reached (to 1e-6 rad).
  bool blending() const { return blending_; }
  /// The internal skeleton (holding the goal pose).
  const Skeleton& goal() const { return work_; }

 private:
  Skeleton* visible_;
  Skeleton work_;
  Solver solver_;
  Blend blend_;
  double rate_;
  int max_attempts_;
  bool blending_ = false;
  std::vector<Quat> goal_q_;
  std::vector<double> goal_angle_;
  Vec3 goal_root_{0};
};

/// Two-bone limb IK as a stateless job (after ozz-animation's IKTwoBoneJob): fill the
/// inputs, call validate(), then run(). Computes the rotation corrections that bring the
/// end of a start-mid-end limb to `target`, bending the mid joint about `mid_axis` and
/// turning the limb's plane toward `pole`. Uses the law of cosines; no iteration, no
/// allocation, no trigonometric call (square roots only). All inputs are world space;
/// `mid_axis` must be perpendicular to the limb's plane (start-mid and mid-end), as an
/// elbow or knee hinge is.
struct TwoBoneJob {
  // inputs
  Vec3 start{0};            ///< shoulder / hip joint position (m)
  Vec3 mid{0};              ///< elbow / knee joint position (m)
  Vec3 end{0};              ///< wrist / ankle position (m)
  Vec3 target{0};           ///< where `end` should go (m)
  Vec3 pole{0, 1, 0};       ///< the mid joint bends toward this point's side (m)
  Vec3 mid_axis{0, 0, 1};   ///< world hinge axis of the mid joint (unit)
  double weight = 1.0;      ///< blend from no correction (0) to full (1), in [0, 1]
  double min_mid_angle = 0;    ///< smallest interior elbow angle allowed (rad), in [0, pi)
  double max_mid_angle = kPi; ///< largest interior elbow angle (rad), in (min, pi]
  // outputs (written by run)
  Quat start_correction{1, 0, 0, 0};  ///< world rotation to pre-multiply onto the start bone
  Quat mid_correction{1, 0, 0, 0};    ///< world rotation about mid_axis to pre-multiply onto the mid bone (applied
                                      ///< before start_correction)
  bool reached = false;               ///< true when the target is within reach (to 1e-9 of the limb)

  /// True when all inputs are finite (and below about 1e150 m, so that their squares are),
  /// mid_axis is unit length, bones have non-zero lengths and weight and angles are in range.
  bool validate() const;
  /// Computes the corrections; returns false (outputs untouched) when validate() fails.
  bool run();
};

}  // namespace pba::ik
