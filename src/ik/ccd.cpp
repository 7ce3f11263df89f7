// Cyclic coordinate descent on a Skeleton (workbook Algorithm 1), for Solver.
#include <algorithm>
#include <cmath>

#include "ik/solver_impl.h"

namespace pba::ik {

// -------------------------------------------------------------------------
// CCD, workbook Algorithm 1: visit joints from the effector toward the root, turning
// each so the effector moves toward the target; repeat until within the threshold or
// the iteration cap. One iteration is one sweep over the chain.
//
// A sweep that would raise the cost (the weighted squared position error: several
// effectors pull a joint different ways, or a ball joint's projection into its cone moves
// the effector away) is undone, so CCD never ends worse than it began. CCD's sweeps also
// get stuck: the joints near the effector, visited first, take most of the turn, and on a
// long chain with joint limits (333 limited hinges: 18% of reachable targets) the sweeps
// then bend the chain against its limits for thousands of iterations without getting
// closer (CCD reached 82% of reachable targets on 333 limited hinges within its cap, in up
// to 100 ms). When a sweep is undone or makes no progress, or 16 sweeps have not halved the
// error, damped least squares (monotone, limit-aware) solves from the given pose with the
// remaining iterations of the cap (SolveResult::handed_over), as FABRIK hands over with
// limits.
void Solver::Impl::ccd(SolveResult& r) {
  Skeleton& s = *sk;
  const int cap = max_iterations();
  const auto parents = s.parents();
  const auto types = s.joint_types();
  const double tol = set.tolerance;
  double prev = r.residual, checkpoint = r.residual;
  double prev_cost = cost(0);
  bool handover = false;
  for (int k = 0; k < ne; ++k) eff_pos[k] = s.tips()[s.effector(k).bone];
  for (int it = 0; it < cap && !r.converged && !out_of_time(it, r); ++it) {
    bool done = false;
    // the pose before the sweep, to undo it
    for (int j : active_rev) detail::put(saved_q[j], A::q(s)[j]), saved_angle[j] = A::angle(s)[j];
    saved_root = A::root_position(s);
    for (int j : active_rev) {
      if (types[j] == JointType::Fixed) continue;
      const Vec3 p = s.starts()[j];
      const int u0 = under_off[j], u1 = under_off[j + 1];
      Quat dR(1, 0, 0, 0);
      if (types[j] == JointType::Hinge) {
        // best angle about the world hinge axis, summed over the effectors below
        const Quat F = frame(j);
        const Vec3 a = detail::rotate(F, A::axis(s)[j]);
        double sn = 0, cs = 0;
        for (int u = u0; u < u1; ++u) {
          const int k = under[u];
          const double wk = s.effector(k).weight;
          const Vec3 v1 = eff_pos[k] - p, v2 = s.effector(k).target - p;
          sn += wk * glm::dot(a, glm::cross(v1, v2));
          cs += wk * (glm::dot(v1, v2) - glm::dot(v1, a) * glm::dot(v2, a));
        }
        if (sn == 0 && cs >= 0) continue;
        const double old = A::angle(s)[j];
        A::angle(s)[j] = old + std::atan2(sn, cs);
        A::clamp_joint(s, j);
        double delta = A::angle(s)[j] - old;
        if (delta == 0) continue;
        dR = glm::angleAxis(delta, a);
      } else {
        // shortest arc from (effector - pivot) to (target - pivot); several effectors
        // below average their rotation vectors by weight
        const Quat F = frame(j);
        Quat rot(1, 0, 0, 0);
        if (u1 - u0 == 1) {
          const int k = under[u0];
          rot = detail::from_to(eff_pos[k] - p, s.effector(k).target - p);
        } else {
          Vec3 om(0);
          double ws = 0;
          for (int u = u0; u < u1; ++u) {
            const int k = under[u];
            const double wk = s.effector(k).weight;
            om += wk * detail::quat_log(detail::from_to(eff_pos[k] - p, s.effector(k).target - p));
            ws += wk;
          }
          rot = detail::quat_exp(om / ws);
        }
        const Quat old = A::q(s)[j];
        A::q(s)[j] = glm::conjugate(F) * rot * F * old;
        A::clamp_joint(s, j);
        dR = glm::normalize(F * A::q(s)[j] * glm::conjugate(old) * glm::conjugate(F));
      }
      // carry the effectors below along with the joint's turn
      for (int u = u0; u < u1; ++u) {
        const int k = under[u];
        eff_pos[k] = p + detail::rotate(dR, eff_pos[k] - p);
      }
      // workbook Algorithm 1 tests the threshold after every joint
      if (ne == 1 && glm::length(eff_pos[0] - s.effector(0).target) < tol) {
        done = true;
        break;
      }
      // the joint's own world frame is stale now; parents' frames are still valid
    }
    // a free root translates by the weighted mean error
    if (s.root_free() && !done) {
      Vec3 d(0);
      double ws = 0;
      for (int k = 0; k < ne; ++k) {
        d += s.effector(k).weight * (s.effector(k).target - eff_pos[k]);
        ws += s.effector(k).weight;
      }
      A::root_position(s) += d / ws;
    }
    s.forward_kinematics();
    for (int k = 0; k < ne; ++k) eff_pos[k] = s.tips()[s.effector(k).bone];
    r.iterations = it + 1;
    const double c = cost(0);
    if (c > prev_cost) {
      // the sweep made things worse: undo it and hand over
      for (int j : active_rev) A::q(s)[j] = saved_q[j], A::angle(s)[j] = saved_angle[j];
      A::root_position(s) = saved_root;
      s.forward_kinematics();
      measure(r);
      handover = true;
      break;
    }
    prev_cost = c;
    measure(r);
    if (r.converged) break;
    // no progress at all: every joint is at its best alone, yet the target is not reached
    if (stalled(prev, r.residual)) {
      handover = true;
      break;
    }
    prev = r.residual;
    // stuck: 16 sweeps that have not halved the error
    if (r.iterations % 16 == 0) {
      if (r.residual > 0.5 * checkpoint) {
        handover = true;
        break;
      }
      checkpoint = r.residual;
    }
  }
  if (handover && !r.out_of_time && r.iterations < cap) {
    // from the pose the solve was given: the stuck pose is a poor start (the chain's end
    // curled onto its limits; DLS from there reached 84% of the targets above, from the
    // given pose 100%)
    r.handed_over = true;
    restore_given_pose();
    measure(r);
    jacobian(r, Method::Dls);
  }
}

}  // namespace pba::ik
