// IK solvers on a Skeleton: analytic 1-DOF and 3-DOF, CCD, the Jacobian family
// (transpose, pseudo-inverse, damped least squares, selectively damped least
// squares) and FABRIK on trees with joint limits. This file holds the names, settings and
// support checks, the driver (workspace, dispatch) and the analytic solvers; the families
// live in ccd.cpp, jacobian.cpp and fabrik.cpp, sharing Solver::Impl (solver_impl.h).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>

#include "ik/solver_impl.h"
#include "pba/ik.h"

namespace pba::ik {

// ---------------------------------------------------------------------------
// names, settings, support checks

std::string_view name(Method m) {
  switch (m) {
    case Method::Analytic1Dof: return "analytic_1dof";
    case Method::Analytic3Dof: return "analytic_3dof";
    case Method::TwoBone: return "two_bone";
    case Method::Ccd: return "ccd";
    case Method::JacobianTranspose: return "jacobian_transpose";
    case Method::PseudoInverse: return "pseudo_inverse";
    case Method::Dls: return "dls";
    case Method::Sdls: return "sdls";
    case Method::Fabrik: return "fabrik";
  }
  return "unknown";
}

std::string method_names() {
  std::string list;
  for (Method m : kAllMethods) {
    if (!list.empty()) list += ", ";
    list += name(m);
  }
  return list;
}

std::string_view name(StopReason r) {
  switch (r) {
    case StopReason::Converged: return "converged";
    case StopReason::Stalled: return "stalled";
    case StopReason::IterationCap: return "iteration_cap";
    case StopReason::OutOfTime: return "out_of_time";
  }
  return "unknown";
}

Method parse_method(std::string_view text, std::string_view where) {
  std::string t(text);
  for (char& c : t) {
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (c == '-') c = '_';
  }
  for (Method m : kAllMethods)
    if (t == name(m)) return m;
  if (t == "1dof") return Method::Analytic1Dof;
  if (t == "3dof") return Method::Analytic3Dof;
  if (t == "twobone" || t == "two_bone_ik") return Method::TwoBone;
  if (t == "jt" || t == "transpose") return Method::JacobianTranspose;
  if (t == "pinv" || t == "pseudoinverse") return Method::PseudoInverse;
  if (t == "svd" || t == "svd_dls") return Method::Sdls;
  throw Error(std::string(where) + ": unknown IK solver '" + std::string(text) +
              "' (expected one of " + method_names() + ")");
}

int default_max_iterations(Method m) {
  switch (m) {
    case Method::Analytic1Dof:
    case Method::Analytic3Dof:
    case Method::TwoBone: return 1;
    case Method::Ccd: return 1000;
    case Method::JacobianTranspose: return 2000;
    case Method::PseudoInverse: return 1000;  // reachable targets take ~5-10; a stuck solve hands over to DLS
    case Method::Dls: return 1000;  // reachable targets take ~5-10; a chain pressed on its limits toward an
                                    // unreachable target, 50-600 (a large-residual minimum: linear convergence)
    case Method::Sdls: return 1000;
    case Method::Fabrik: return 1000;  // free ball chains take tens (76 at 1000 bones); limited chains hand over to DLS
  }
  return 100;
}

void SolverSettings::validate(std::string_view where) const {
  const std::string w(where);
  require_count(max_iterations, 0, 100000000, w + ".max_iterations");
  require_positive(tolerance, w + ".tolerance");
  require_positive(orientation_tolerance, w + ".orientation_tolerance");
  require_non_negative(damping, w + ".damping");
  require_non_negative(max_step_angle, w + ".max_step_angle");
  require_in_range(stall_ratio, 0, 1, w + ".stall_ratio");
  require_non_negative(max_seconds, w + ".max_seconds");
  if (static_cast<int>(method) > static_cast<int>(Method::Fabrik))
    throw Error(w + ".method: unknown value " + std::to_string(static_cast<int>(method)));
}

namespace {

// moving joints on the path from the root to `bone`, and the last one found
int moving_joints_on_path(const Skeleton& s, int bone, int* first_moving, JointType* type) {
  int count = 0;
  for (int j = bone; j >= 0; j = s.parents()[j])
    if (s.joint_types()[j] != JointType::Fixed) {
      ++count;
      if (first_moving) *first_moving = j;
      if (type) *type = s.joint_types()[j];
    }
  return count;
}

}  // namespace

bool supports(Method m, const Skeleton& s, std::string* why) {
  auto fail = [&](std::string msg) {
    if (why) *why = std::string(name(m)) + ": " + msg;
    return false;
  };
  if (m != Method::Analytic1Dof && m != Method::Analytic3Dof && m != Method::TwoBone) return true;
  if (s.effector_count() != 1)
    return fail("needs exactly one effector, got " + std::to_string(s.effector_count()));
  if (s.root_free()) return fail("needs a fixed root");
  const int bone = s.effector(0).bone;
  if (m == Method::TwoBone) {
    const int parent = s.parents()[bone];
    if (s.joint_types()[bone] != JointType::Hinge || parent < 0 ||
        s.joint_types()[parent] != JointType::Ball)
      return fail("needs the effector's bone on a hinge (elbow) whose parent bone is on a ball joint (shoulder)");
    return true;
  }
  JointType type = JointType::Fixed;
  const int count = moving_joints_on_path(s, bone, nullptr, &type);
  const JointType want = m == Method::Analytic1Dof ? JointType::Hinge : JointType::Ball;
  if (count != 1 || type != want)
    return fail(std::string("needs exactly one moving joint, a ") +
                (want == JointType::Hinge ? "hinge" : "ball joint") +
                ", between the root and the effector; found " + std::to_string(count) +
                " moving joints");
  return true;
}

// ---------------------------------------------------------------------------
// the solver

// size the workspace for the skeleton's current effectors (allocates)
void Solver::Impl::prepare() {
  Skeleton& s = *sk;
  if (prepared_version == s.effector_version()) return;
  prepared_version = s.effector_version();
  carry_valid = false;
  n = s.bone_count();
  ne = s.effector_count();
  const auto parents = s.parents();

  // effectors per bone, active bones and per-effector paths
  active.assign(n, 0);
  std::vector<int> count(n + 1, 0);
  for (int k = 0; k < ne; ++k) count[s.effector(k).bone + 1]++;
  eff_off.assign(n + 1, 0);
  for (int i = 0; i < n; ++i) eff_off[i + 1] = eff_off[i] + count[i + 1];
  eff_list.assign(ne, 0);
  std::vector<int> fill(eff_off.begin(), eff_off.end() - 1);
  for (int k = 0; k < ne; ++k) eff_list[fill[s.effector(k).bone]++] = k;
  path_off.assign(ne + 1, 0);
  path.clear();
  std::vector<int> under_count(n, 0);
  for (int k = 0; k < ne; ++k) {
    for (int j = s.effector(k).bone; j >= 0; j = parents[j]) {
      path.push_back(j);
      active[j] = 1;
      under_count[j]++;
    }
    path_off[k + 1] = static_cast<int>(path.size());
  }
  under_off.assign(n + 1, 0);
  for (int i = 0; i < n; ++i) under_off[i + 1] = under_off[i] + under_count[i];
  under.assign(under_off[n], 0);
  std::vector<int> ufill(under_off.begin(), under_off.end() - 1);
  for (int k = 0; k < ne; ++k)
    for (int p = path_off[k]; p < path_off[k + 1]; ++p) under[ufill[path[p]]++] = k;
  active_rev.clear();
  for (int i = n - 1; i >= 0; --i)
    if (active[i]) active_rev.push_back(i);
  active_fwd.assign(active_rev.rbegin(), active_rev.rend());

  // per-bone constants
  rest_identity.assign(n, 0);
  hx.assign(n, Vec3(1, 0, 0));
  hy.assign(n, Vec3(0, 1, 0));
  for (int i = 0; i < n; ++i) {
    const Quat r = A::rest(s)[i];
    rest_identity[i] = r.w == 1 && r.x == 0 && r.y == 0 && r.z == 0;
    if (s.joint_types()[i] == JointType::Hinge) {
      const Vec3 a = A::axis(s)[i];
      Vec3 xp = Vec3(1, 0, 0) - a.x * a;
      const double l = glm::length(xp);
      hx[i] = l > 1e-9 ? xp / l : Vec3(0);  // zero: the hinge only twists the bone
      hy[i] = glm::cross(a, hx[i]);
    }
  }

  // a ball joint with exactly one active child, a hinge: FABRIK solves its twist
  hinge_child.assign(n, -1);
  {
    std::vector<int> active_children(n, 0), last_child(n, -1);
    for (int i = 0; i < n; ++i)
      if (active[i] && parents[i] >= 0) active_children[parents[i]]++, last_child[parents[i]] = i;
    for (int i = 0; i < n; ++i)
      if (active[i] && s.joint_types()[i] == JointType::Ball && active_children[i] == 1 &&
          s.joint_types()[last_child[i]] == JointType::Hinge && glm::length(hx[last_child[i]]) > 0)
        hinge_child[i] = last_child[i];
  }

  // Jacobian layout: 3 rows per effector (+3 with an orientation target),
  // a column per joint DOF on some effector's path (+3 for a free root)
  m = 0;
  row_of.assign(ne, 0);
  ori_row_of.assign(ne, -1);
  for (int k = 0; k < ne; ++k) {
    row_of[k] = m;
    m += 3;
  }
  for (int k = 0; k < ne; ++k)
    if (s.effector(k).orientation) {
      ori_row_of[k] = m;
      m += 3;
    }
  ncols = s.root_free() ? 3 : 0;
  col_of.assign(n, -1);
  for (int i = 0; i < n; ++i) {
    if (!active[i]) continue;
    const JointType jt = s.joint_types()[i];
    if (jt == JointType::Hinge) col_of[i] = ncols, ncols += 1;
    else if (jt == JointType::Ball) col_of[i] = ncols, ncols += 3;
  }
  // orientation targets can be added or removed without a version bump, so size for all
  int mmax = 6 * ne;
  J.assign(static_cast<std::size_t>(mmax) * std::max(ncols, 1), 0.0);
  Amat.assign(mmax * mmax, 0.0);
  L.assign(mmax * mmax, 0.0);
  V.assign(mmax * mmax, 0.0);
  work.assign(mmax * mmax, 0.0);
  w.assign(mmax, 0.0);
  e.assign(mmax, 0.0);
  y.assign(mmax, 0.0);
  t.assign(mmax, 0.0);
  dtheta.assign(std::max(ncols, 1), 0.0);
  v.assign(std::max(ncols, 1), 0.0);
  rho.assign(std::max(ncols, 1), 0.0);
  jd.assign(n, Vec3(0));
  lim1.assign(n, Vec3(0));
  lim2.assign(n, Vec3(0));
  hold.assign(n, 0);
  goal.assign(n, Vec3(0));
  acc.assign(n, Vec3(0));
  accw.assign(n, 0.0);
  eff_pos.assign(std::max(ne, 1), Vec3(0));
  cp.assign(n + 1, Vec3(0));
  fw.assign(n + 1, Vec3(0));
  cl.assign(n, 0.0);
  clr.assign(n, 0.0);
  inv_len.assign(n, 0.0);
  scratch.assign(n, 0.0);
  for (int i = 0; i < n; ++i) inv_len[i] = 1 / s.lengths()[i];
  // the lengths along active_fwd (a chain when there is one effector), forward and reversed
  const int na = static_cast<int>(active_fwd.size());
  active_count = na;
  path_reach = 0;
  for (int k = 0; k < na; ++k) {
    cl[k] = s.lengths()[active_fwd[k]];
    clr[na - 1 - k] = cl[k];
    path_reach += cl[k];
  }
  // one chain in stored order (bone i the child of bone i - 1, every bone active)
  simple_chain = na == n;
  for (int i = 0; i < n; ++i)
    if (parents[i] != i - 1) simple_chain = false;
  // the straight-chain test for paths mixing joints (straighten_mixed): a ball joint after
  // at most one moving joint, a hinge (fixed bones anywhere before it), and every later
  // joint able to hold zero (fixed, a hinge whose range holds 0, a ball whose twist range
  // holds 0), every later rest rotation the identity
  straight_first = -1;
  straight_hinge = -1;
  straight_reach = 0;
  if (ne == 1) {
    int first = -1, hinge = -1;
    bool ok = true;
    for (int k = 0; k < na && ok; ++k) {
      const int i = active_fwd[k];
      const JointType jt = s.joint_types()[i];
      if (first < 0) {
        if (jt == JointType::Fixed) continue;
        if (jt == JointType::Hinge && hinge < 0 && glm::length(hx[i]) > 0) {
          hinge = k;
          continue;
        }
        first = k;
        ok = jt == JointType::Ball;
        continue;
      }
      const bool zero_in = !A::limited(s)[i] || (A::lo(s)[i] <= 0 && A::hi(s)[i] >= 0);
      ok = rest_identity[i] && (jt == JointType::Fixed || zero_in);
    }
    if (ok && first >= 0) {
      straight_first = first;
      straight_hinge = hinge;
      for (int k = first; k < na; ++k) straight_reach += cl[k];
    }
  }
  // FABRIK iterates on positions only when every active joint is an unlimited ball
  all_free_balls = true;
  for (int j : active_rev)
    if (s.joint_types()[j] != JointType::Ball || A::limited(s)[j]) all_free_balls = false;
  saved_q.assign(n, Quat(1, 0, 0, 0));
  saved_angle.assign(n, 0.0);
  given_q.assign(n, Quat(1, 0, 0, 0));
  given_angle.assign(n, 0.0);
  stalled_q.assign(n, Quat(1, 0, 0, 0));
  stalled_angle.assign(n, 0.0);
}

void Solver::Impl::bend_active_joints(double delta) {
  Skeleton& s = *sk;
  const auto types = s.joint_types();
  int k = 0;
  for (int j : active_fwd) {
    if (types[j] == JointType::Fixed) continue;
    const double d = (k++ / 2) % 2 == 0 ? delta : -delta;
    if (types[j] == JointType::Hinge) {
      A::angle(s)[j] += d;
    } else {
      // about the joint frame's Z, across the bone (+X)
      A::q(s)[j] = detail::qmul(A::q(s)[j], Quat(std::cos(0.5 * d), 0, 0, std::sin(0.5 * d)));
    }
    A::clamp_joint(s, j);
  }
}

// A Jacobian column of joint j for effector k is w (a_j x (e - p_j)) per axis a_j (a
// ball's three, a hinge's one), so J^T e = 0 where the error d = e - t of every effector is
// parallel to e - p_j for every moving joint on its path: the chain straight along the
// error. With the target short of the tip (d . (e - p_j) > 0, the target inside the reach
// of the line), folding the chain brings the tip closer: a saddle or a maximum, which the
// bend leaves. With the target beyond the tip the straight chain reaches farthest toward
// it (a true minimum); poses off the line stall only at true minima (a joint limit, a
// target out of a hinge chain's plane, effectors pulling apart), where the bend and its
// second solve were paid and thrown away. The cost of a stationary pose is quadratic in a
// tilt phi off it, changing by about phi^2 of itself, so the stall test (an accepted step
// changing the cost by at most stall_ratio of it) cannot tell a pose within
// sqrt(stall_ratio) rad of the line from one on it: that is the tolerance on the sine of
// the angle between d and e - p_j, and 1e-9 at least (a million times the rounding of a
// position from forward kinematics).
bool Solver::Impl::on_line_saddle() const {
  const Skeleton& s = *sk;
  const auto types = s.joint_types();
  const double tol = std::max(std::sqrt(set.stall_ratio), 1e-9);
  bool any = false;
  for (int k = 0; k < ne; ++k) {
    const EffectorDef& ef = s.effector(k);
    const Vec3 tip = s.tips()[ef.bone];
    const Vec3 d = tip - ef.target;
    const double dl = glm::length(d);
    if (!(dl > 0)) continue;
    for (int i = path_off[k]; i < path_off[k + 1]; ++i) {
      const int j = path[i];
      if (types[j] == JointType::Fixed) continue;
      const Vec3 a = tip - s.starts()[j];
      const double al = glm::length(a);
      if (!(al > 0)) continue;
      if (!(glm::dot(a, d) > 0) || !(glm::length(glm::cross(a, d)) <= tol * al * dl)) return false;
    }
    any = true;
  }
  return any;
}

// -------------------------------------------------------------------------
// analytic: one hinge aims the effector at the target (workbook 2.3, ik_1dof):
// the angle between v1 = e - p and v2 = t - p, projected on the hinge plane,
// is atan2(axis . (v1 x v2), v1 . v2)
void Solver::Impl::analytic_1dof(SolveResult& r) {
  Skeleton& s = *sk;
  const EffectorDef& ef = s.effector(0);
  int j = -1;
  moving_joints_on_path(s, ef.bone, &j, nullptr);
  const Vec3 a = detail::rotate(frame(j), A::axis(s)[j]);
  const Vec3 p = s.starts()[j];
  Vec3 v1 = s.tips()[ef.bone] - p, v2 = ef.target - p;
  v1 -= glm::dot(v1, a) * a;
  v2 -= glm::dot(v2, a) * a;
  if (glm::dot(v1, v1) > 1e-300 && glm::dot(v2, v2) > 1e-300) {
    const double delta = std::atan2(glm::dot(a, glm::cross(v1, v2)), glm::dot(v1, v2));
    A::angle(s)[j] += delta;
    A::clamp_joint(s, j);
  }
  s.forward_kinematics();
  r.iterations = 1;
}

// analytic: one ball joint aims the effector with the shortest-arc rotation from v1 to v2
void Solver::Impl::analytic_3dof(SolveResult& r) {
  Skeleton& s = *sk;
  const EffectorDef& ef = s.effector(0);
  int j = -1;
  moving_joints_on_path(s, ef.bone, &j, nullptr);
  const Quat F = frame(j);
  const Vec3 p = s.starts()[j];
  const Quat d = detail::from_to(s.tips()[ef.bone] - p, ef.target - p);
  A::q(s)[j] = glm::conjugate(F) * d * F * A::q(s)[j];
  A::clamp_joint(s, j);
  s.forward_kinematics();
  r.iterations = 1;
}

SolveResult Solver::Impl::solve() {
  Skeleton& s = *sk;
  prepare();
  // whether the method applies depends only on the effectors and the method: checked once
  if (supported_version != prepared_version || supported_method != set.method) {
    std::string why;
    if (!supports(set.method, s, &why)) throw Error("ik::Solver: " + why);
    supported_version = prepared_version;
    supported_method = set.method;
  }
  has_deadline = set.max_seconds > 0;
  if (has_deadline)
    deadline = std::chrono::steady_clock::now() +
               std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                   std::chrono::duration<double>(std::min(set.max_seconds, 1e9)));
  // a pose changed since the last solve (reset_pose, set_joint_rotation, ...: the dirty
  // flag; every solve leaves it clear) is not the one the last capped solve was shortening
  // its step on: no carry. (A caller that runs forward_kinematics itself after changing the
  // pose clears the flag, and the carry stays: a shorter first step, never a worse pose.)
  if (s.kinematics_dirty()) carry_valid = false;
  if (!set.warm_start) s.reset_pose();
  // every solver leaves kinematics current, so a warm start usually skips this pass
  if (s.kinematics_dirty()) s.forward_kinematics();
  SolveResult r;
  measure(r);
  if (ne == 0 || r.converged) return r;
  // the pose given, to return it when the method ends farther away (see below) or a
  // shortcut misses
  const bool orients = honours_orientation(set.method);
  const double ori_scale = orients ? std::max(largest_reach(), 1e-9) : 0.0;
  const double given_cost = cost(ori_scale);
  for (int j : active_fwd) given_q[j] = A::q(s)[j], given_angle[j] = A::angle(s)[j];
  given_root = A::root_position(s);
  // the straight chain toward an unreachable target is the closest reachable pose, and the
  // chain bent once, from a pose given far from it, meets a target just inside the reach
  // (bend_near_reach): final when it does; a shortcut that misses falls through
  const bool shortcuts = honours_unreachable_shortcut(set.method);
  if (shortcuts && straighten_if_unreachable(r)) {
    r.stop = r.converged ? StopReason::Converged : StopReason::Stalled;
    return r;
  }
  switch (set.method) {
    case Method::Analytic1Dof: analytic_1dof(r); break;
    case Method::Analytic3Dof: analytic_3dof(r); break;
    case Method::TwoBone: {
      const SolveResult t2 = detail::solve_two_bone(s, set);
      r.iterations = t2.iterations;
      break;
    }
    case Method::Ccd: ccd(r); break;
    case Method::JacobianTranspose:
    case Method::PseudoInverse:
    case Method::Dls:
    case Method::Sdls: {
      jacobian(r, set.method);
      // A pose where every column of J is square to the error is stationary for the whole
      // family, be it a minimum or not: the straight chain (the rest pose) toward a target
      // on its line short of the tip, behind the root or at it is a saddle or a maximum of
      // the error, and the methods stopped there untouched (0.5 m from a target half way
      // along a 1 m chain). Once per solve, a pose stalled on such a line (on_line_saddle)
      // is bent by 0.2 rad per joint (bend_active_joints) and solved again; the better of
      // the two poses is kept. Stalls off the line are true minima and end here.
      measure(r);
      if (r.converged || r.out_of_time || r.iterations >= max_iterations() || !on_line_saddle()) break;
      const double stalled_cost = cost(ori_scale);
      for (int j : active_fwd) stalled_q[j] = A::q(s)[j], stalled_angle[j] = A::angle(s)[j];
      stalled_root = A::root_position(s);
      bend_active_joints(0.2);
      s.forward_kinematics();
      jacobian(r, set.method);
      if (!(cost(ori_scale) < stalled_cost)) {
        // back to the stationary pose: the solve stalled there, whatever the second run hit,
        // and the shortening that run may have handed on belongs to the pose thrown away
        for (int j : active_fwd) A::q(s)[j] = stalled_q[j], A::angle(s)[j] = stalled_angle[j];
        A::root_position(s) = stalled_root;
        s.forward_kinematics();
        r.stop = StopReason::Stalled;
        carry_valid = false;
      }
      break;
    }
    case Method::Fabrik: fabrik(r); break;
  }
  measure(r);
  // No solver returns a pose worse than the one it was given. The Jacobian family accepts
  // only steps that do not raise the cost and CCD only sweeps that do not (jacobian.cpp,
  // ccd.cpp), so for them this never fires; FABRIK's reaching passes are not monotone
  // (and the analytic methods' clamp to a limit may land anywhere), so the driver keeps
  // the given pose when the method ended farther away. Costs are weighted squared errors
  // (Impl::cost); the orientation part counts for the methods that honour it. A pose that
  // went non-finite (a NaN cost compares false) is worse than any: the given pose again.
  if (!(cost(ori_scale) <= given_cost)) {
    restore_given_pose();
    measure(r);
  }
  // the rescue: a method that ended short of a target within kNearReachBand of the reach
  // (creeping at the near-straight poses that meet it) is bent once from where it ended,
  // kept when that converges (one more iteration), else the method's pose back
  if (!r.converged && shortcuts && ne == 1) bend_to_rescue(r);
  // why it stopped
  if (r.converged) r.stop = StopReason::Converged;
  else if (r.out_of_time) r.stop = StopReason::OutOfTime;
  else if (r.stop != StopReason::Stalled && r.iterations >= max_iterations() && !is_analytic(set.method))
    r.stop = StopReason::IterationCap;
  else r.stop = StopReason::Stalled;
  return r;
}

Solver::Solver(Skeleton& skeleton, const SolverSettings& settings) {
  settings.validate();
  impl_ = std::make_unique<Impl>(skeleton, settings);
}
Solver::Solver(Skeleton& skeleton, Method m) {
  SolverSettings st;
  st.method = m;
  impl_ = std::make_unique<Impl>(skeleton, st);
}
Solver::~Solver() = default;
Solver::Solver(Solver&&) noexcept = default;
Solver& Solver::operator=(Solver&&) noexcept = default;

void Solver::set_settings(const SolverSettings& settings) {
  settings.validate();
  impl_->set = settings;
  impl_->carry_valid = false;
}
const SolverSettings& Solver::settings() const { return impl_->set; }
void Solver::set_method(Method m) {
  SolverSettings s = impl_->set;
  s.method = m;
  set_settings(s);
}
SolveResult Solver::solve() { return impl_->solve(); }

// ---------------------------------------------------------------------------
// solve, then blend toward the solution (workbook 2.7 exercise 3)

SolveThenBlend::SolveThenBlend(Skeleton& visible, const SolverSettings& settings, Blend blend,
                               double blend_rate, int max_attempts)
    : visible_(&visible), work_(visible), solver_(work_, settings), blend_(blend),
      rate_(blend_rate), max_attempts_(max_attempts) {
  require_positive(blend_rate, "SolveThenBlend blend_rate");
  require_count(max_attempts, 1, 1000000, "SolveThenBlend max_attempts");
  goal_q_.assign(visible.bone_count(), Quat(1, 0, 0, 0));
  goal_angle_.assign(visible.bone_count(), 0.0);
}

SolveResult SolveThenBlend::update(double dt) {
  require_non_negative(dt, "SolveThenBlend::update dt");
  Skeleton& vis = *visible_;
  // copy the targets, solve on the private skeleton (continuing from its last pose)
  for (int k = 0; k < vis.effector_count() && k < work_.effector_count(); ++k) {
    work_.set_target(k, vis.effector(k).target);
    work_.set_orientation_target(k, vis.effector(k).orientation);
    work_.set_pole(k, vis.effector(k).pole);
  }
  SolveResult r;
  for (int attempt = 0; attempt < max_attempts_; ++attempt) {
    r = solver_.solve();
    if (r.converged) break;
  }
  // a converged pose becomes the new goal; otherwise the old goal stays
  if (r.converged) {
    const auto q = work_.joint_rotations();
    std::copy(q.begin(), q.end(), goal_q_.begin());
    const auto a = work_.hinge_angles();
    std::copy(a.begin(), a.end(), goal_angle_.begin());
    goal_root_ = work_.root_position();
    blending_ = true;
  }
  if (!blending_) return r;
  // move a fraction 1 - exp(-rate dt) of the way toward the goal, per joint
  const double f = 1 - std::exp(-rate_ * dt);
  if (f <= 0) return r;
  auto& q = A::q(vis);
  auto& angle = A::angle(vis);
  double remaining = 0;
  for (int i = 0; i < vis.bone_count(); ++i) {
    Quat g = goal_q_[i];
    if (glm::dot(g, q[i]) < 0) g = -g;
    if (vis.joint_types()[i] == JointType::Hinge) {
      const double target = goal_angle_[i];
      angle[i] += f * (target - angle[i]);
      remaining = std::max(remaining, std::abs(target - angle[i]));
    } else {
      q[i] = blend_ == Blend::Slerp ? glm::slerp(q[i], g, f) : glm::normalize(glm::lerp(q[i], g, f));
      remaining = std::max(remaining, 2 * std::acos(std::min(1.0, std::abs(glm::dot(q[i], g)))));
    }
    A::clamp_joint(vis, i);
  }
  A::root_position(vis) += f * (goal_root_ - vis.root_position());
  vis.forward_kinematics();
  if (remaining < 1e-6) blending_ = false;
  return r;
}

}  // namespace pba::ik
