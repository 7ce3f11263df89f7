// The IK solver driver's private state (Solver::Impl): the skeleton binding, the settings,
// the effector structure and every solver family's workspace, sized in prepare(). The
// families' loops are defined in their own files: ccd.cpp, jacobian.cpp (transpose,
// pseudo-inverse, DLS, SDLS) and fabrik.cpp; solver.cpp holds the driver and the
// analytic solvers.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>

#include "ik/ik_access.h"
#include "ik/ik_math.h"
#include "pba/ik.h"

namespace pba::ik {

using A = SolverAccess;

struct Solver::Impl {
  Skeleton* sk = nullptr;
  SolverSettings set;
  std::uint64_t prepared_version = ~std::uint64_t(0);
  bool has_deadline = false;             // SolverSettings::max_seconds > 0 for this solve
  std::chrono::steady_clock::time_point deadline;  // ... and when it ends
  int active_count = 0;                  // active bones (sets how often the clock is read)
  std::uint64_t supported_version = ~std::uint64_t(0);  // effectors for which supports() held
  Method supported_method = Method::Fabrik;              // ... with this method

  // effector structure (rebuilt when effectors change)
  int n = 0, ne = 0;
  std::vector<std::uint8_t> active;      // bone is an effector's bone or one of its ancestors
  std::vector<int> active_rev;           // active bones, children before parents
  std::vector<int> active_fwd;           // active bones, parents before children
  bool all_free_balls = false;           // every active joint is an unlimited ball (FABRIK on positions)
  bool simple_chain = false;             // bone i is bone i - 1's child, every bone active
  double path_reach = 0;                 // summed length of the active bones (m): one effector's reach
  int straight_first = -1;               // one effector: index in active_fwd of the path's first moving
                                         // joint when it is a ball and every later joint can be straight
  int straight_hinge = -1;               // ... and the index in active_fwd of the one hinge before it, or -1
  double straight_reach = 0;             // summed length from that joint to the effector (m)
  std::vector<int> eff_off, eff_list;    // effectors on each bone
  std::vector<int> under_off, under;     // effectors in each bone's subtree
  std::vector<int> path_off, path;       // each effector's bones up to the root
  std::vector<std::uint8_t> rest_identity;
  std::vector<Vec3> hx, hy;              // hinge: local in-plane basis (x = bone axis projected)
  std::vector<int> hinge_child;          // ball bone's single active child when that is a hinge, else -1

  // Jacobian workspace: m rows, ncols columns, column-major J
  int m = 0, ncols = 0;
  std::vector<int> col_of;               // first column of each bone's joint, -1 if none
  std::vector<int> row_of, ori_row_of;   // rows of each effector (-1: no orientation rows)
  std::vector<double> J, Amat, L, V, w, work, e, y, t, dtheta, v, rho;
  // one position effector (3 rows): J is never stored, only each joint's vector (see build_compact)
  bool compact = false;
  std::vector<Vec3> jd;
  // a limited ball joint held at its swing or twist limit that the error pushes further out:
  // the outward normals (world rotation vectors, orthonormal; zero when unused) that its
  // columns are projected off this iteration (ball_active_limits)
  std::vector<Vec3> lim1, lim2;
  // limits held out of this iteration's step whatever the gradient says (hold_pushed_limits)
  static constexpr std::uint8_t kHoldSwing = 1, kHoldTwist = 2, kHoldHinge = 4;
  // a ball joint's swing or twist within this of its limit (rad) is held there: a step
  // along a held limit's tangent leaves the joint inside it by the step's second order, and
  // a joint left just inside would be pushed out and clamped by the next step (rejected,
  // and the solve creeps); held, it stays at most this far inside, which moves the tip by
  // at most this times its reach
  static constexpr double kHeldBand = 1e-6;
  std::vector<std::uint8_t> hold;

  // FABRIK and CCD workspace
  std::vector<Vec3> goal, acc, eff_pos, cp, fw;  // fw: FABRIK stage 1 points, target first
  std::vector<double> cl, clr, inv_len;           // chain lengths forward, reversed; 1 / length
  std::vector<double> scratch;                    // n doubles for detail::rebuild_rotations
  std::vector<Quat> saved_q;
  std::vector<double> saved_angle;
  Vec3 saved_root{0};
  std::vector<double> accw;
  // the pose a solve was given (active joints and the root), kept in case the method ends worse
  std::vector<Quat> given_q;
  std::vector<double> given_angle;
  Vec3 given_root{0};
  // A Jacobian solve that ended at its iteration cap hands its shortening (DLS's damping over
  // lambda0, SDLS's cap over its default, the line search's scale) to the next warm-started
  // solve of the same method (jacobian): with a budget of one or two iterations a frame, each
  // solve used to start from the full step again, have it rejected, and end where it began.
  bool carry_valid = false;
  Method carry_method = Method::Dls;
  double carry_lambda = 1, carry_gamma = 1, carry_scale = 1;
  // a Jacobian method's stalled pose, kept while it tries once more from a bent one (solve)
  std::vector<Quat> stalled_q;
  std::vector<double> stalled_angle;
  Vec3 stalled_root{0};

  explicit Impl(Skeleton& s, const SolverSettings& st) : sk(&s), set(st) { prepare(); }

  int max_iterations() const {
    return set.max_iterations > 0 ? set.max_iterations : default_max_iterations(set.method);
  }

  // size the workspace for the skeleton's current effectors (allocates)
  void prepare();

  // orientation rows may appear later (set_orientation_target): recompute row layout, no allocation
  void layout_rows() {
    m = 3 * ne;
    for (int k = 0; k < ne; ++k) {
      if (sk->effector(k).orientation) {
        ori_row_of[k] = m;
        m += 3;
      } else {
        ori_row_of[k] = -1;
      }
    }
  }

  Quat frame(int i) const {
    const Skeleton& s = *sk;
    const int p = s.parents()[i];
    const Quat base = p >= 0 ? s.world_rotations()[p] : s.root_rotation();
    return rest_identity[i] ? base : detail::qmul(base, A::rest(s)[i]);
  }

  // back to the pose the solve was given (active joints and the root), with forward kinematics
  void restore_given_pose() {
    for (int j : active_fwd) A::q(*sk)[j] = given_q[j], A::angle(*sk)[j] = given_angle[j];
    A::root_position(*sk) = given_root;
    sk->forward_kinematics();
  }

  // bends every active joint by `delta` rad, the signs in pairs (+ + - - ...) so that hinges
  // alternating between two axes, and ball joints, zig-zag in each plane: the tips come
  // closer to the root by the second order of delta and drift sideways by one bone's
  // length times delta at most. Clamped to the limits; forward kinematics left stale.
  void bend_active_joints(double delta);

  // whether a stalled pose is the saddle the bend is for (solve): every effector with a
  // position error has it along the line through its tip and every moving joint on its
  // path, pointing from the target toward the tip and the joints (the target short of the
  // tip, behind the root or at it). Forward kinematics current.
  bool on_line_saddle() const;

  // whether a method honours orientation targets (FABRIK and the Jacobian family)
  static bool honours_orientation(Method m) {
    return m == Method::Fabrik || m == Method::Dls || m == Method::Sdls || m == Method::PseudoInverse ||
           m == Method::JacobianTranspose;
  }
  // the iterative methods, which take the straight chain toward an unreachable target first
  static bool honours_unreachable_shortcut(Method m) { return m == Method::Ccd || honours_orientation(m); }
  static bool is_analytic(Method m) {
    return m == Method::Analytic1Dof || m == Method::Analytic3Dof || m == Method::TwoBone;
  }

  // residuals after forward kinematics
  void measure(SolveResult& r) const {
    const Skeleton& s = *sk;
    r.residual = 0;
    r.orientation_residual = 0;
    for (int k = 0; k < ne; ++k) {
      const EffectorDef& ef = s.effector(k);
      r.residual = std::max(r.residual, glm::length(s.tips()[ef.bone] - ef.target));
      if (ef.orientation) {
        const Quat d = *ef.orientation * glm::conjugate(s.world_rotations()[ef.bone]);
        r.orientation_residual = std::max(r.orientation_residual, glm::length(detail::quat_log(d)));
      }
    }
    // CCD and the analytic solvers handle positions only: orientation targets are reported, not required
    const bool orients = honours_orientation(set.method);
    r.converged = r.residual <= set.tolerance &&
                  (!orients || r.orientation_residual <= set.orientation_tolerance);
  }

  bool stalled(double prev, double now) const {
    return std::abs(prev - now) <= set.stall_ratio * std::max(now, 1e-300);
  }

  // the time budget: whether SolverSettings::max_seconds is spent, read from the clock on
  // every iteration from 64 active bones on and every 8th below (a read costs ~60 ns)
  bool out_of_time(int iteration, SolveResult& r) const {
    if (!has_deadline || (active_count < 64 && iteration % 8 != 0)) return false;
    if (std::chrono::steady_clock::now() < deadline) return false;
    r.out_of_time = true;
    return true;
  }


  // -------------------------------------------------------------------------
  // analytic: one hinge aims the effector at the target (workbook 2.3) (solver.cpp)
  void analytic_1dof(SolveResult& r);

  // analytic: one ball joint aims the effector by the shortest arc
  void analytic_3dof(SolveResult& r);

  // -------------------------------------------------------------------------
  // CCD, workbook Algorithm 1 (ccd.cpp)
  void ccd(SolveResult& r);

  // -------------------------------------------------------------------------
  // Jacobian family (Buss 2004; Buss and Kim 2005) (jacobian.cpp)

  // the largest root-to-effector reach (m)
  double largest_reach() const;

  // fill J and e (error, clamped per effector to `clamp` metres), weighted rows
  void build_jacobian(double clamp, double ori_scale);

  // zero the columns of hinges held at a limit that the error pushes further out, and
  // project limited ball joints' columns off the limits they are held at
  void drop_saturated_columns();

  // limited ball joint j: the outward normals of the swing and twist limits it is held at
  // that `desc` (its block of J^T e, a world rotation vector) pushes against, into lim1[j]
  // and lim2[j] (orthonormal, zero when unused); returns how many
  int ball_active_limits(int j, Vec3 desc);

  // limited ball joint j: which limits it is held at (kHoldSwing, kHoldTwist), with their
  // outward normals as world rotation vectors (not normalised)
  int held_ball_limits(int j, Vec3& swing_out, Vec3& twist_out) const;

  // mark in `hold` the held limits that the computed step pushes further out; true if any
  bool hold_pushed_limits();

  // one position effector: e, J J^T and each joint's vector, J never formed
  void build_compact(double clamp);

  // dtheta = J^T x from the vectors build_compact kept
  void jt_times_compact(const double* x);

  // A = J J^T (m x m, symmetric): the only matrix product formed
  void gram();

  // dtheta = J^T x
  void jt_times(const double* x);

  // apply dtheta to the pose, projecting every joint into its limits (`save`: for restore_pose)
  void apply_dtheta(bool save);

  // one SDLS step (Buss and Kim 2005)
  void sdls_step(double gamma_max);

  // the Jacobian methods' loop; `meth` is set.method, or dls on a hand-over
  void jacobian(SolveResult& r, Method meth);

  // weighted sum of squared errors (orientation errors scaled to metres)
  double cost(double ori_scale) const;

  // undo the last apply_dtheta(true): only the joints it changed
  void restore_pose();

  // -------------------------------------------------------------------------
  // FABRIK (Aristidou and Lasenby 2011) (fabrik.cpp)
  void fabrik(SolveResult& r);

  // joint rotations from the bone directions positions-only FABRIK left in start/tip
  void rebuild_rotations(const Vec3* points);

  // the twist of ball joint i that turns its hinge child's plane onto the child's goal
  Quat twist_for_hinge_child(int i, const Quat& F, const Quat& sw, const Vec3& st, const Quat& tw_old);

  // FABRIK on one chain of unlimited ball joints, on contiguous joint positions
  // (true: it handed over, damped least squares takes the remaining iterations)
  bool fabrik_chain(SolveResult& r);

  // an unreachable target on a path of unlimited ball joints: straighten toward it
  bool straighten_if_unreachable(SolveResult& r);
  // the same on a path mixing joints, aimed by its first moving joint, a ball joint
  bool straighten_mixed(SolveResult& r);
  // a target within kNearReachBand of the reach of such a path (bend_near_reach)
  static constexpr double kNearReachBand = 0.05;
  // the path bent once at a joint to meet a target near its reach (near_reach_bend): the
  // first part's direction, the bend's position (m) and the second part's direction
  struct NearReachBend {
    Vec3 u1{0}, mid{0}, u2{0};
  };
  bool near_reach_bend(int first, int split, const Vec3& d, double dist, NearReachBend& out) const;
  // index in active_fwd of the ball (or, with `any`, moving) joint nearest the path's middle
  int middle_joint(int first, bool any) const;
  // free ball joints: the path bent once to meet a target d (|d| = dist, m) from its root
  bool bend_near_reach(const Vec3& d, double dist);
  // mixed joints after a first ball joint: the same by joint rotations, when the cones allow
  bool bend_mixed_near_reach();
  // either bend, forward kinematics current and r measured; false when not bent
  bool bend_if_near_reach(SolveResult& r);
  // the bend up front, kept only when it converged (else the given pose back, false)
  bool bend_or_give_back(SolveResult& r);
  // the bend after a method ended short, kept only when it converged (else the pose back)
  void bend_to_rescue(SolveResult& r);

  // residual from the tips only (positions-only FABRIK keeps world rotations stale)
  void measure_tips(SolveResult& r) const {
    const Skeleton& s = *sk;
    r.residual = 0;
    for (int k = 0; k < ne; ++k) {
      const EffectorDef& ef = s.effector(k);
      r.residual = std::max(r.residual, glm::length(s.tips()[ef.bone] - ef.target));
    }
    r.converged = r.residual <= set.tolerance;
  }

  SolveResult solve();
};

}  // namespace pba::ik
