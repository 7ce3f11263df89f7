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

/// Two-bone analytic solve on a skeleton (the effector's bone is the hinge "mid" bone,
/// its parent the ball "start" bone). Used by Solver for Method::two_bone.
SolveResult solve_two_bone(Skeleton& s, const SolverSettings& settings);

}  // namespace detail
}  // namespace pba::ik
