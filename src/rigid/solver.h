// Rigid bodies, private: the compact contact solver of the soft step, sequential impulses and
// TGS. Each step prepare() copies what the velocity passes need out of the contact pairs into
// blocks of kLanes manifolds (structure of arrays of floats: half a cache line per field; the
// separations' anchors in a parallel array), grouped by the colours of the constraint graph
// so that no two manifolds of a block share a dynamic body;
// the passes then run over whole blocks with SIMD (contact_wide.h), and store() writes the
// impulses back to the pairs for next step's warm starting.
//
// Each manifold is solved in its contact frame (t1, t2, n): the bodies' velocities are turned
// into it, the normal points are swept with the small matrix K = J M^-1 J^T of the manifold's
// normal rows (Gauss-Seidel on the manifold's problem, as before, without touching the bodies
// in between), then the friction and twist rows follow, and the change goes back to the bodies
// once. The same arithmetic runs in every lane of every path (scalar, AVX2, AVX-512), so the
// results do not depend on the machine.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/lanes.h"
#include "pba/rigid.h"

namespace pba::detail {

/// Manifolds per block: the widest SIMD path (AVX-512, 16 floats); narrower paths take a block
/// in parts.
inline constexpr int kLanes = 16;
/// Colours a band of the constraint graph may use (contact_solver.cpp, RigidContacts::color):
/// a manifold whose body has this many in its band already goes to the overflow.
inline constexpr int kBandColors = 64;
/// The largest ratio of a body's principal moments of inertia the float passes see (the soft
/// step, sequential impulses, TGS): a larger one is taken at this ratio (its smallest moment
/// raised), which keeps the rounding of the frame's inverse inertia (2^-24 of its largest
/// entry) under 1e-3 of its smallest inverse moment.
inline constexpr double kSolverInertiaRatio = 1e4;
/// The spread of a body's principal inverse moments x, y, z > 0 (1/(kg m^2)) as the float
/// solvers see them: the largest, capped at kSolverInertiaRatio times the least, over the least,
/// less 1 (dimensionless; refresh_inertia's measure). A number or a lane type (vmin and vmax:
/// std::min's and std::max's values, so every path gives the same bits).
template <class V>
PBA_LANES V solver_inertia_spread(V x, V y, V z) {
  using lanes::vmax, lanes::vmin;
  const V least = vmin(vmin(x, y), z), most = vmax(vmax(x, y), z);
  return vmin(most, kSolverInertiaRatio * least) / least - 1.0;
}
/// A body's inverse inertia in the blocks is taken again at its pose now (after a substep's
/// positions: RigidContacts::refresh_inertia) once it has turned by this over (its ratio of
/// principal moments - 1) radians from the orientation the blocks hold it at (rad). An
/// impulse through an inverse inertia turned by a from the body's gives it an angular
/// velocity whose energy is off by about (ratio - 1) a of the impulse's: a thin rod (moments
/// 1e4 : 1 as the passes see them) tumbling 2 rad a 60 Hz step was driven to 1e3-1e5 rad/s
/// within a step with its step's start inverse inertia (docs/rigid-bodies.md).
inline constexpr double kInertiaTurn = 0.01;
/// The lane of a block that holds no manifold.
inline constexpr std::uint32_t kNoPair = std::numeric_limits<std::uint32_t>::max();

/// A block's numbers: single precision (the passes stream the blocks from the caches every
/// pass, so their size sets the passes' speed), and the kernels compute in float, 16 lanes to
/// an AVX-512 register; the bodies' velocities stay in double (the kernels add float changes).
using Real = float;

/// kLanes manifolds in structure-of-arrays form. Empty lanes hold zeros (no mass, no effect)
/// and write nothing back.
struct alignas(64) ContactBlock {
  static constexpr int kPoints = 4;  // normal points a lane holds
  // the frame (world unit vectors, right-handed: t1 x t2 = n; n from body a to b)
  Real t1[3][kLanes], t2[3][kLanes], n[3][kLanes];
  // Masses and impulses are in the lane's impulse unit u (a power of two, `unit`): the
  // impulses and effective masses below are divided by u, the inverse masses, the inverse
  // inertias and K multiplied by it (velocities are unchanged)
  Real ma[kLanes], mb[kLanes];        // inverse masses times u (1/kg; 0 for static, kinematic, asleep)
  Real ia[6][kLanes], ib[6][kLanes];  // inverse inertias in the frame times u: xx, xy, xz, yy, yz, zz (1/(kg m^2))
  // the normal points (unused ones have zero mass and K)
  Real x[4][kLanes], y[4][kLanes];    // the points from the centroid (ca), t1 and t2 coordinates (m)
  Real mass[4][kLanes];               // normal effective masses (kg)
  Real k[10][kLanes];                 // K of the normal rows, upper triangle by rows, times u (1/kg)
  Real impulse[4][kLanes];            // accumulated normal impulses (N s)
  Real sep[4][kLanes];                // separations at the bodies' poses now (m)
  Real slop[kLanes];                  // sequential impulses and TGS: overlap left alone (m), pair_slop()
  // friction at the points' centroid, twist about the normal
  // the points' centroid from a's centre of mass and from b's, in the frame (each kept apart:
  // ca - cb, the centres' distance, may be far larger than either)
  Real ca[3][kLanes], cb[3][kLanes];  // (m)
  Real tangent_mass[2][kLanes];       // (kg)
  Real tangent_k[3][kLanes];          // K of the tangent rows times u: t1 t1, t1 t2, t2 t2 (1/kg)
  Real twist_mass[kLanes];            // (kg m^2)
  Real friction[kLanes];              // mixed coefficient
  Real twist_radius[kLanes];          // mean distance of the points from the centroid (m)
  Real tangent_impulse[2][kLanes];    // accumulated (N s)
  Real twist_impulse[kLanes];         // accumulated (N m s)
  // written by the biased passes
  Real approach[4][kLanes];           // the most negative normal velocity seen (m/s)
  Real max_impulse[4][kLanes];        // the largest single normal impulse (N s)
  // bodies (dense indices) and pairs
  std::uint32_t a[kLanes], b[kLanes];
  std::uint32_t pair[kLanes];           // index into RigidContacts::pairs, kNoPair when empty
  Real unit[kLanes];                    // u (N s; 1 in an empty lane); the kernels do not read it
  std::uint32_t write_a = 0, write_b = 0;  // bit l: lane l writes its body back (dynamic and awake)
  int lanes = 0;                        // lanes in use, from 0
};

/// kLanes manifolds of ONE normal point each (a sphere on anything, a capsule's tip, a box's
/// corner): the point is the manifold's centroid, so it has no lever arm from it (x = y = 0,
/// exactly: the pairs' centroid of one point is the point), no twist (its radius is 0, and a
/// pair carries no twist impulse then) and a K of one entry. The same rows as ContactBlock's
/// otherwise, so the kernels are one template over both (contact_wide.h), and a one-point
/// lane's normal and friction rows give the bits of the same manifold in a ContactBlock
/// (whose other three points hold zeros). A one-point lane's rolling resistance (a ball's) is
/// solved in the block too, right after its friction, with SIMD and in the frame (a
/// ContactBlock's lanes that roll are solved one by one, in double, after their blocks). The
/// block is 58 rows (10 of them the rolling resistance's) to ContactBlock's 83, and its normal
/// sweeps touch one point, not four with their K. prepare() puts a colour's one-point
/// manifolds in blocks of their own after its ContactBlocks (no two manifolds of a colour share
/// a body that moves, so the order within a colour changes nothing); the overflow keeps
/// ContactBlocks.
struct alignas(64) OnePointBlock {
  static constexpr int kPoints = 1;
  // the frame (as ContactBlock's)
  Real t1[3][kLanes], t2[3][kLanes], n[3][kLanes];
  // in the lane's impulse unit u, as ContactBlock's
  Real ma[kLanes], mb[kLanes];        // inverse masses times u (1/kg)
  Real ia[6][kLanes], ib[6][kLanes];  // inverse inertias in the frame times u (1/(kg m^2))
  Real mass[1][kLanes];               // normal effective mass (kg)
  Real k[1][kLanes];                  // K of the normal row, times u (1/kg; the sweeps after the first read it)
  Real impulse[1][kLanes];            // accumulated normal impulse (N s)
  Real sep[1][kLanes];                // separation at the bodies' poses now (m)
  Real slop[kLanes];                  // sequential impulses and TGS: overlap left alone (m), pair_slop()
  Real ca[3][kLanes], cb[3][kLanes];  // the point from a's centre of mass and from b's, in the frame (m)
  Real tangent_mass[2][kLanes];       // (kg)
  Real tangent_k[3][kLanes];          // K of the tangent rows times u: t1 t1, t1 t2, t2 t2 (1/kg)
  Real friction[kLanes];              // mixed coefficient
  Real tangent_impulse[2][kLanes];    // accumulated (N s)
  // rolling resistance: an angular impulse against the bodies' relative turning, up to
  // rolling * the normal impulse (zeros in a lane whose pair does not roll)
  Real rolling[kLanes];               // mixed coefficient times radius (m)
  Real rolling_mass[6][kLanes];       // (Ia^-1 + Ib^-1)^-1 in the frame divided by u: xx, xy, xz, yy, yz, zz (kg m^2)
  Real rolling_impulse[3][kLanes];    // accumulated, in the frame (N m s)
  Real approach[1][kLanes];           // the most negative normal velocity seen (m/s)
  Real max_impulse[1][kLanes];        // the largest single normal impulse (N s)
  std::uint32_t a[kLanes], b[kLanes];
  std::uint32_t pair[kLanes];           // index into RigidContacts::pairs, kNoPair when empty
  Real unit[kLanes];                    // u (N s; 1 in an empty lane)
  std::uint32_t write_a = 0, write_b = 0;  // bit l: lane l writes its body back
  std::uint32_t rolls = 0;                 // bit l: lane l's pair rolls
  int lanes = 0;                        // lanes in use, from 0
};

/// What measuring the separations of a block's manifolds at the poses now needs besides the
/// block: apart from it, so that the passes that do not measure them (the biased ones) do not
/// stream it. The separation at the poses now is base + n.(dp_b - dp_a) + n.(turn_b sb - sb) -
/// n.(turn_a sa - sa), base being the separation at the start of the step and sa, sb the
/// anchors on the shapes' cores: in the frame (x - ex, y - ey, za) and (x + d0 + ex, y + d1 +
/// ey, zb), e being half the step from a's surface point to b's. (Each term is small, so float
/// keeps it to a fraction of a micrometre; the anchors' own projections, near the shapes'
/// size, would cancel.)
/// P: the normal points of a lane (4: a ContactBlock's, 1: a OnePointBlock's).
template <int P>
struct alignas(64) AnchorsOf {
  Real za[P][kLanes], zb[P][kLanes], base[P][kLanes];  // (m)
  Real ex[P][kLanes], ey[P][kLanes];                   // (m)
  // the normal impulses the soft step's last relax pass solved, before its cap (N s, in u;
  // mutable: the passes take the anchors as const, and only the relax pass writes this)
  mutable Real last[P][kLanes];
};
/// A ContactBlock's anchors.
using AnchorBlock = AnchorsOf<4>;
/// A OnePointBlock's anchors.
using OnePointAnchors = AnchorsOf<1>;

/// One contact pass's settings (contact_solver.cpp fills them).
struct PassParams {
  double inv_h = 0;          // 1 / substep (1/s)
  // soft step: the spring's coefficients, [0] between dynamic bodies, [1] against a body that
  // cannot move (twice the stiffness within the same cap)
  double bias_rate[2] = {0, 0}, mass_scale[2] = {1, 1}, impulse_scale[2] = {0, 0};
  double push_out = 0;       // largest push-out speed (m/s)
  double baumgarte_h = 0;    // rigid contacts: baumgarte / h (1/s)
  int sweeps = 1;            // sweeps over a manifold's normal points
  bool bias = true;          // position bias (false: the relax pass)
  bool soft = true;          // soft contacts (false: rigid, Baumgarte)
  bool update_sep = false;   // first measure the separations at the poses now (a relax pass after the positions moved)
  bool warm_next = false;    // then add the impulses to the warm-start accumulators for the next substep
  double carry_speed = 0;    // |g| h (m/s), the velocity gravity gives in a substep: cap_carry, and a landing
                             // while sliding
  bool cap_carry = false;    // with update_sep: cap each point's carried impulse (contact_wide.h, pass())
  bool cap_total = false;    // cap_carry on the manifold's total, not each point's (TGS)
  bool one_colour = false;   // the call's blocks are of one colour: the AVX2 path's lanes that land sliding may
                             // wait to the call's end for their rounds (contact_wide.h, DeferredRounds)
};

/// A body's velocities as the contact passes and the integration see them: one cache line, so
/// the SIMD paths load a lane's body in one or two loads and transpose.
struct alignas(64) SolverBody {
  double v[3];       // centre-of-mass velocity (m/s)
  double w[3];       // world angular velocity (rad/s)
  double pad[2];
};

/// The bodies as the kernels see them, each array one 64-byte row a body (dense index), with a
/// last row that empty lanes point at: velocities (read and written), each body's motion since
/// the start of the step (dp, then the turn as a quaternion w, x, y, z) and the warm-start
/// accumulators (velocity changes for the next substep, laid out as a SolverBody).
struct BodyArrays {
  SolverBody* bodies = nullptr;
  const double* motion = nullptr;  // 8 a body
  SolverBody* warm = nullptr;
};

/// The arrays the free motion of the awake dynamic bodies reads and writes (by dense body).
struct FreeMotionArrays {
  double* v = nullptr;            // velocity of body i at v + stride i (m/s)
  double* w = nullptr;            // angular velocity of body i at w + stride i (rad/s)
  std::size_t stride = 3;
  SolverBody* warm = nullptr;     // optional: velocity changes to add after the forces (and zero)
  Vec3* com = nullptr;            // centres of mass (m)
  const Vec3* com0 = nullptr;     // at the start of the step
  Quat* q = nullptr;              // principal frames
  const Quat* q0 = nullptr;       // at the start of the step
  const Vec3* inertia = nullptr;  // principal moments (kg m^2)
  const Vec3* inv_inertia = nullptr;
  const Vec3* force = nullptr;    // (N)
  const Vec3* torque = nullptr;   // (N m)
  const double* inv_mass = nullptr;
  const double* gravity_scale = nullptr;
  const double* lin_damp = nullptr;
  const double* ang_damp = nullptr;
  bool damped = true;             // false: no body has damping (the divisions by 1 + h c are left out)
  bool torqued = true;            // false: every body's torque is +0 (AVX2 and plain paths: its turns left out)
  double* motion = nullptr;       // optional: dp and turn since the start of the step, 8 a body
};

/// Which code runs the blocks of a colour.
enum class SimdPath : std::uint8_t { Scalar, Avx2, Avx512 };

/// The widest path this CPU runs.
SimdPath best_simd_path();

/// One pass over the coloured blocks [first, last) on `path`: each block's lanes together (no
/// lane shares a dynamic body with another; anchors[i] goes with blocks[i]). With p.update_sep the separations are
/// measured first, with p.warm_next the impulses are added to the warm-start accumulators after.
void solve_colored(SimdPath path, ContactBlock* blocks, AnchorBlock* anchors, std::size_t first, std::size_t last,
                   const PassParams& p, const BodyArrays& bodies);
/// The same for one lane (scalar): the overflow, lane by lane in order.
void solve_lane(ContactBlock& block, const AnchorBlock& anchors, int lane, const PassParams& p,
                const BodyArrays& bodies);
/// Adds the accumulated impulses of the coloured blocks [first, last) to the warm-start accumulators.
void warm_colored(SimdPath path, ContactBlock* blocks, std::size_t first, std::size_t last, const BodyArrays& bodies);
/// The same for one lane (scalar).
void warm_lane(ContactBlock& block, int lane, const BodyArrays& bodies);
/// Measures the separations of the coloured blocks [first, last) at the poses now.
void separation_colored(SimdPath path, ContactBlock* blocks, const AnchorBlock* anchors, std::size_t first,
                        std::size_t last, const BodyArrays& bodies);
/// The same for one lane (scalar).
void separation_lane(ContactBlock& block, const AnchorBlock& anchors, int lane, const BodyArrays& bodies);
/// The approach speed before the solve (m/s) of point `p` of the block's lane `lane` at the
/// velocities va, vb (m/s) and angular velocities wa, wb (rad/s) of its bodies a and b, 3
/// numbers each: the number approaches() makes for it at those (the same bits on every path).
Real approach_at(const ContactBlock& block, int lane, int p, const double* va, const double* wa, const double* vb,
                 const double* wb);
/// The same for a lane of a one-point block (its one point).
Real approach_at(const OnePointBlock& block, int lane, const double* va, const double* wa, const double* vb,
                 const double* wb);
/// The restitution impulses of one lane's points that approached faster than `threshold` and
/// pushed (scalar; the lanes with restitution, in order), swept `sweeps` times over the points:
/// they are coupled through the bodies' turn, and one sweep in order spun a box that landed flat.
void restitution_lane(ContactBlock& block, int lane, double restitution, double threshold, int sweeps,
                      const BodyArrays& bodies);
/// Gravity, forces, torques, damping and the warm start for `count` awake dynamic bodies
/// (integrate_wide.cpp); `round`: every one of them has three equal principal moments. False,
/// with the body in *bad, when a velocity became non-finite.
/// `lanes` (or nullptr: the bodies' arrays): the kind's free motion lanes, gathered for this h
/// and gravity (gather_free_motion_wide).
bool integrate_velocities_wide(SimdPath path, bool round, const std::uint32_t* bodies, std::size_t count,
                               const FreeMotionArrays& f, double h, const Vec3& gravity, const double* lanes,
                               std::uint32_t* bad);
/// How a body's free rotation is integrated, by its principal moments (integrate_wide.cpp).
enum class FreeRotation : std::uint8_t {
  Triaxial,                 ///< all different: the Dullweber-Leimkuhler-McLachlan splitting
  Round,                    ///< all three equal: the exact turn about the constant angular velocity
  AxialX, AxialY, AxialZ,   ///< the other two equal: the exact turns about the momentum and the axis
};
/// The number of kinds of FreeRotation.
inline constexpr std::size_t kFreeRotations = 5;
/// The kind of a body of principal moments m (kg m^2).
inline FreeRotation free_rotation(const Vec3& m) {
  if (m.x == m.y) return m.y == m.z ? FreeRotation::Round : FreeRotation::AxialZ;
  if (m.y == m.z) return FreeRotation::AxialX;
  return m.x == m.z ? FreeRotation::AxialY : FreeRotation::Triaxial;
}
/// Positions and rotations over h of `count` awake dynamic bodies, all of the rotation `kind`,
/// and their motion since the start of the step. `lanes` (or nullptr: the bodies' arrays): the
/// kind's free motion lanes, whose centres and frames it moves (the bodies' arrays keep theirs).
void integrate_positions_wide(SimdPath path, FreeRotation kind, const std::uint32_t* bodies, std::size_t count,
                              const FreeMotionArrays& f, double h, double* lanes);

/// The free motion's lanes (integrate_wide.cpp): for the soft step's and TGS's substeps, the fields the
/// free motion reads and writes, copied once a step from the bodies' arrays into blocks of 8
/// bodies of one kind's list (in its order), each field one 64-byte line of 8 numbers, so that
/// the substeps load and store whole vectors whatever the bodies' indices (the rain's boxes and
/// balls alternate: each kind's list steps by 2). The lines of a block, by field:
enum FreeLine : int {
  kLineCom = 0,       ///< x, y, z: the centre of mass now (m)
  kLineQ = 3,         ///< w, x, y, z: the principal frame now
  kLineCom0 = 7,      ///< x, y, z: the centre at the step's start (m)
  kLineQ0 = 10,       ///< w, x, y, z: the frame at the step's start
  kLineInertia = 14,  ///< the principal moments (kg m^2; not round bodies)
  kLineInv = 17,      ///< their inverses (1/(kg m^2); not round bodies)
  kLineLinear = 20,   ///< h (gravity scale g + inverse mass force): a substep's change of v (m/s)
  kLineAngular = 23,  ///< round bodies: h I^-1 torque, a substep's change of w (rad/s); others: the torque (N m)
  kLineHInv = 26,     ///< h / I per principal axis (s/(kg m^2); not round bodies)
  kLineDamp = 29,     ///< 1 + h c for the linear, then the angular damping c (when some body is damped)
  kLineSpread = 31,   ///< the solvers' largest (capped) over least inverse moment, less 1 (not round bodies)
  kFreeLines = 32,    ///< lines a block
};
/// Bodies in a block of the free motion's lanes.
inline constexpr std::size_t kFreeLaneWidth = 8;
/// Doubles in a block of the free motion's lanes.
inline constexpr std::size_t kFreeBlock = kFreeLines * kFreeLaneWidth;
/// Where position j of a kind's list lives in its lanes (the kind's first block at `lanes`).
inline std::size_t free_lane_at(std::size_t j) { return j / kFreeLaneWidth * kFreeBlock + j % kFreeLaneWidth; }
/// Fills the lanes (the kind's first block at `lanes`, 64-byte aligned) of `count` awake bodies
/// of rotation `kind` from the bodies' arrays, for substeps of h (s) under gravity (m/s^2); the
/// start-of-step lines from f.com and f.q (the caller's bodies have not moved since the start).
void gather_free_motion_wide(SimdPath path, FreeRotation kind, const std::uint32_t* bodies, std::size_t count,
                             const FreeMotionArrays& f, double h, const Vec3& gravity, double* lanes);
/// Puts the lanes' centres and frames back into the bodies' arrays.
void scatter_free_motion_wide(SimdPath path, const std::uint32_t* bodies, std::size_t count,
                              const FreeMotionArrays& f, const double* lanes);
/// Whether each of the `count` doubles from `p` is finite (not infinite, not NaN): x - x summed
/// in lanes (+0 for every finite x, NaN once one is not), on AVX2 unless `path` is Scalar
/// (RigidBodySystem::check_finite's test of the bodies' centres, velocities and frames).
bool all_finite_wide(SimdPath path, const double* p, std::size_t count);
/// Whether each of the `count` doubles from `p` has |x| <= `limit` (false at a NaN): two
/// compares a lane, on AVX2 unless `path` is Scalar (RigidBodySystem::check_finite's test of
/// the bodies' centres against the float range).
bool all_within_wide(SimdPath path, const double* p, std::size_t count, double limit);
/// refresh_inertia's test over a kind's free motion lanes (not round bodies; the kind's first
/// block at `lanes`), several bodies at a time where `path` has a kernel for it (AVX2): the
/// positions j (ascending) of the bodies bodies[j] whose frame in the lanes q is turned from
/// inertia_q[bodies[j]] so far that 8 (1 - |q . q_ref|) spread^2 > kInertiaTurn^2, into `far`
/// (room for count); returns how many. Positions from `tested` on are the caller's to test.
std::size_t turned_far_wide(SimdPath path, const std::uint32_t* bodies, std::size_t count, const double* lanes,
                            const Quat* inertia_q, std::uint32_t* far, std::size_t& tested);
/// The approach speeds before the solve (m/s): the normal relative velocity of each point of
/// the block's lanes at the velocities now, for the points below each lane's `count` (0 past it).
void approaches(SimdPath path, ContactBlock& block, const int* count, const BodyArrays& bodies);

// the same for blocks of one-point manifolds (OnePointBlock), with the same arithmetic

/// One pass over the one-point blocks [first, last) on `path` (as solve_colored).
void solve_colored(SimdPath path, OnePointBlock* blocks, OnePointAnchors* anchors, std::size_t first, std::size_t last,
                   const PassParams& p, const BodyArrays& bodies);
/// Adds the accumulated impulses of the one-point blocks [first, last) to the warm-start accumulators.
void warm_colored(SimdPath path, OnePointBlock* blocks, std::size_t first, std::size_t last, const BodyArrays& bodies);
/// Measures the separations of the one-point blocks [first, last) at the poses now.
void separation_colored(SimdPath path, OnePointBlock* blocks, const OnePointAnchors* anchors, std::size_t first,
                        std::size_t last, const BodyArrays& bodies);
/// The restitution impulse of one lane of a one-point block (as restitution_lane above).
void restitution_lane(OnePointBlock& block, int lane, double restitution, double threshold, const BodyArrays& bodies);
/// Whether a point of lane `lane` of `block` (a ContactBlock or OnePointBlock) approached
/// faster than `threshold` (m/s) and pushed: restitution_lane leaves the other lanes as they
/// are, and changes neither of the two (the approach speeds and the largest impulses).
template <class B>
inline bool lane_bounces(const B& block, int lane, double threshold) {
  bool any = false;
  for (int k = 0; k < B::kPoints; ++k)
    any |= !(double(block.approach[k][lane]) > -threshold || double(block.max_impulse[k][lane]) == 0);
  return any;
}
/// The approach speeds before the solve of the block's lanes (as approaches above).
void approaches(SimdPath path, OnePointBlock& block, const int* count, const BodyArrays& bodies);

}  // namespace pba::detail
