// Private access to a Skeleton's arrays for the solvers in src/ik/, and the small
// dense routines (Cholesky, Jacobi eigen-decomposition) the Jacobian solvers use on
// their m x m matrices (m = rows of the task: 3 per position effector, 3 more per
// orientation target). Never a DOF x DOF matrix.
#pragma once

#include <vector>

#include "pba/ik.h"

namespace pba::ik {

/// Friend of Skeleton: hands the solvers references to its structure-of-arrays state.
struct SolverAccess {
  static std::vector<Quat>& q(Skeleton& s) { return s.q_; }
  static std::vector<double>& angle(Skeleton& s) { return s.angle_; }
  static std::vector<Quat>& world(Skeleton& s) { return s.world_; }
  static std::vector<Vec3>& start(Skeleton& s) { return s.start_; }
  static std::vector<Vec3>& tip(Skeleton& s) { return s.tip_; }
  static const std::vector<Quat>& rest(const Skeleton& s) { return s.rest_; }
  static const std::vector<Vec3>& axis(const Skeleton& s) { return s.axis_; }
  static const std::vector<double>& lo(const Skeleton& s) { return s.lo_; }
  static const std::vector<double>& hi(const Skeleton& s) { return s.hi_; }
  static const std::vector<double>& swing(const Skeleton& s) { return s.swing_; }
  static const std::vector<std::uint8_t>& limited(const Skeleton& s) { return s.limited_; }
  static Vec3& root_position(Skeleton& s) { return s.root_position_; }
  static void clamp_joint(Skeleton& s, int i) { s.clamp_joint(i); }
};

namespace detail {

/// Solves (A) x = b for symmetric positive definite m x m A (row-major), in place
/// in the workspace L (m*m). Adds `ridge` to the diagonal. Returns false if A is
/// not positive definite even with the ridge.
bool cholesky_solve(const double* A, int m, double ridge, double* L, const double* b, double* x);

/// Eigen-decomposition of a symmetric m x m matrix (row-major) by cyclic Jacobi
/// rotations: A = V diag(w) V^T. V (m*m, row-major, columns are eigenvectors) and
/// w (m) are outputs; `work` holds m*m doubles. No allocation.
void jacobi_eigen(const double* A, int m, double* V, double* w, double* work);

/// One reaching pass of FABRIK along a chain (Aristidou and Lasenby 2011, sec. 3; stage 1
/// with the joints taken in reverse, or stage 2): out[0] = from and, for i in [0, count),
///   out[i + 1] = out[i] + len[i] (Q_i - out[i]) / |Q_i - out[i]|,  with Q_i = q[-i]
/// (the goals are read backwards from q; q[1] must exist: it gives the direction of a step
/// whose point coincides with its goal). len[i] > 0 (m); count >= 1. Returns out[count].
/// The squared distance of each step is updated from the previous one,
///   |Q_{i+1} - out[i+1]|^2 = |e|^2 + s^2 |d|^2 - 2 s (e . d),
/// (e = Q_{i+1} - out[i], d = Q_i - out[i], s = len[i] / |d|), so the dependent path per step
/// is a square root, a product and a difference; where that update would cancel (the
/// result under 1/64 of |e|^2 + s^2 |d|^2) it is taken from the vector instead, which bounds
/// its relative error, and so each bone's length error, to about 1e-14.
Vec3 reach_pass(const Vec3& from, const Vec3* q, const double* len, Vec3* out, int count);

/// Arguments of rebuild_rotations: a skeleton's arrays (stored order) and the bones to
/// rebuild, parents first.
struct RebuildArgs {
  const int* bones;                  ///< bone indices, parents before children
  int count;                         ///< number of bones in `bones`
  const int* parents;                ///< parent per bone, -1 for the root
  const double* lengths;             ///< bone lengths (m)
  const double* inv_len;             ///< 1 / length (1/m)
  const std::uint8_t* rest_identity; ///< 1 when the bone's rest rotation is the identity
  const Quat* rest;                  ///< rest rotations
  Vec3 root;                         ///< root joint position (m)
  Quat root_rotation;                ///< root parent frame
  Quat* world;                       ///< in: old world rotations; out: new ones
  Quat* q;                           ///< out: joint rotations
  Vec3* start;                       ///< in: new bone starts (unless `points`); out: from forward kinematics
  Vec3* tip;                         ///< in: new bone tips (unless `points`); out: from forward kinematics
  double* scratch;                   ///< workspace of `count` doubles
  bool chain;                        ///< bones[k] == k and bone k's parent is k - 1 (one chain, stored order)
  const Vec3* points;                ///< null, or the new joint positions along `bones` (count + 1, root
                                     ///< first), read instead of start/tip
};

/// Joint rotations from the bone directions FABRIK left in start/tip (positions-only
/// FABRIK): each bone's world rotation turns by the shortest arc from its old direction to
/// its new one, which keeps twist continuous from frame to frame; the joint rotation is
/// conj(frame) world, and forward kinematics of the bone runs in the same pass.
void rebuild_rotations(const RebuildArgs& args);

/// TwoBoneJob::run (validates, then solves; false when the inputs are invalid).
bool run_two_bone(TwoBoneJob& job);

/// Two-bone analytic solve on a skeleton (the effector's bone is the hinge "mid" bone,
/// its parent the ball "start" bone). Used by Solver for Method::TwoBone.
SolveResult solve_two_bone(Skeleton& s, const SolverSettings& settings);

}  // namespace detail
}  // namespace pba::ik
