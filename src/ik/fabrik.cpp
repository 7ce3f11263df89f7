// FABRIK on a Skeleton, for Solver: the reaching passes, positions-only chains and the
// rotations rebuilt from them (Aristidou and Lasenby 2011).
#include <algorithm>
#include <cmath>

#include "ik/solver_impl.h"

namespace pba::ik {

namespace detail {

PBA_CLONES Vec3 reach_pass(const Vec3& from, const Vec3* q, const double* len, Vec3* out, int count) {
  constexpr double kTiny = 1e-300;  // below this squared distance the direction is undefined
  // a direction for a step whose point coincides with its goal: the one between the goals
  // (the bone keeps the pose it had), else +X
  auto fallback = [&](int i, double& dx, double& dy, double& dz) {
    dx = q[-i].x - q[1 - i].x, dy = q[-i].y - q[1 - i].y, dz = q[-i].z - q[1 - i].z;
    double l2 = dx * dx + dy * dy + dz * dz;
    if (!(l2 > kTiny)) dx = 1, dy = 0, dz = 0, l2 = 1;
    return l2;
  };
  double px = from.x, py = from.y, pz = from.z;
  out[0] = from;
  // the first step's difference and squared distance, from the vector
  double dx = q[0].x - px, dy = q[0].y - py, dz = q[0].z - pz;
  double l2e = dx * dx + dy * dy + dz * dz;
  if (!(l2e > kTiny)) l2e = fallback(0, dx, dy, dz);
  double l2 = l2e;
  for (int i = 0;; ++i) {
    // the step: scale len / |d| as sqrt(l2) (len / l2), the division beside the root
    const double li = len[i];
    const double inv = li / l2;
    const double root = std::sqrt(l2);
    const double sc = root * inv;
    const double sx = sc * dx, sy = sc * dy, sz = sc * dz;
    const double nx = px + sx, ny = py + sy, nz = pz + sz;
    out[i + 1] = Vec3(nx, ny, nz);
    if (i + 1 == count) return out[i + 1];
    // the next difference d' = e - sc d with e = Q_{i+1} - p, and its squared length
    // |e|^2 + sc^2 |d|^2 - 2 sc (e . d), where sc^2 |d|^2 = len (len / l2) |d|^2 and
    // 2 sc (e . d) = sqrt(l2) (2 (len / l2) (e . d)): one product after the root
    const Vec3& qn = q[-(i + 1)];
    const double ex = qn.x - px, ey = qn.y - py, ez = qn.z - pz;
    const double ee = ex * ex + ey * ey + ez * ez;
    const double ed2 = 2 * (ex * dx + ey * dy + ez * dz);
    const double c = ee + inv * (li * l2e);
    dx = ex - sx, dy = ey - sy, dz = ez - sz;
    px = nx, py = ny, pz = nz;
    l2e = dx * dx + dy * dy + dz * dz;
    l2 = c - root * (inv * ed2);
    // cancellation (the new distance small next to the terms): take it from the vector
    if (!(l2 > c * (1.0 / 64))) {
      l2 = l2e;
      if (!(l2 > kTiny)) l2 = l2e = fallback(i + 1, dx, dy, dz);
    }
  }
}

PBA_CLONES void rebuild_rotations(const RebuildArgs& a) {
  // Three passes, so that the bones' independent work overlaps: in one loop, a bone's turn,
  // product and normalisation formed a dependent path of ~90 cycles in ~190 instructions,
  // about what the out-of-order window holds, so bones hardly overlapped (108 cycles per
  // bone on a chain of 10; 54 in three passes, with the square roots and divisions
  // vectorised in the second and the quaternions stored component by component).
  // 1. each bone's world rotation turned by the shortest arc from its old direction (the x
  //    column of the old rotation, unit) to its new one (unit: the bone is its length long
  //    by construction). The turn (1 + c, a x b) is 2 cos(angle / 2) times a unit
  //    quaternion: the product with the old rotation is normalised once, in pass 2.
  for (int k = 0; k < a.count; ++k) {
    const int i = a.bones[k];
    const Quat w0 = a.world[i];
    const double yy = w0.y * w0.y, zz = w0.z * w0.z;
    const double ax = 1 - 2 * (yy + zz), ay = 2 * (w0.x * w0.y + w0.w * w0.z), az = 2 * (w0.x * w0.z - w0.w * w0.y);
    const double il = a.inv_len[i];
    const Vec3& t0 = a.points ? a.points[k + 1] : a.tip[i];
    const Vec3& s0 = a.points ? a.points[k] : a.start[i];
    const double bx = (t0.x - s0.x) * il, by = (t0.y - s0.y) * il, bz = (t0.z - s0.z) * il;
    const double c = ax * bx + ay * by + az * bz;
    Quat w;
    if (c > -1 + 1e-12) {
      const double tw = 1 + c, tx = ay * bz - az * by, ty = az * bx - ax * bz, tz = ax * by - ay * bx;
      w = Quat(tw * w0.w - tx * w0.x - ty * w0.y - tz * w0.z, tw * w0.x + tx * w0.w + ty * w0.z - tz * w0.y,
               tw * w0.y - tx * w0.z + ty * w0.w + tz * w0.x, tw * w0.z + tx * w0.y - ty * w0.x + tz * w0.w);
    } else {
      w = qmul(from_to(Vec3(ax, ay, az), Vec3(bx, by, bz)), w0);
    }
    put(a.world[i], w);
    a.scratch[k] = w.w * w.w + w.x * w.x + w.y * w.y + w.z * w.z;
  }
  // 2. the normalising factors 1 / sqrt(n2) = sqrt(n2) (1 / n2), on a contiguous array
  for (int k = 0; k < a.count; ++k) a.scratch[k] = std::sqrt(a.scratch[k]) * (1 / a.scratch[k]);
  // 3. normalise; the joint rotation is conj(frame) world; forward kinematics of the bone.
  //    Quaternions are stored component by component (detail::put).
  if (a.chain) {
    // bone k is bone k - 1's child: the parent's new rotation and tip stay in registers
    Quat base = a.root_rotation;
    Vec3 st = a.root;
    for (int i = 0; i < a.count; ++i) {
      const double nk = a.scratch[i];
      const Quat& wu = a.world[i];
      const Quat w(wu.w * nk, wu.x * nk, wu.y * nk, wu.z * nk);
      put(a.world[i], w);
      const Quat F = a.rest_identity[i] ? base : qmul(base, a.rest[i]);
      // both factors are unit to rounding, so the product is too (no drift: world is
      // renormalised every solve)
      put(a.q[i], qmul(Quat(F.w, -F.x, -F.y, -F.z), w));
      a.start[i] = st;
      st = st + rotate_x(w, a.lengths[i]);
      a.tip[i] = st;
      base = w;
    }
    return;
  }
  for (int k = 0; k < a.count; ++k) {
    const int i = a.bones[k];
    const double nk = a.scratch[k];
    const Quat& wu = a.world[i];
    const Quat w(wu.w * nk, wu.x * nk, wu.y * nk, wu.z * nk);
    put(a.world[i], w);
    const int p = a.parents[i];
    const Quat base = p >= 0 ? a.world[p] : a.root_rotation;
    const Quat F = a.rest_identity[i] ? base : qmul(base, a.rest[i]);
    put(a.q[i], qmul(Quat(F.w, -F.x, -F.y, -F.z), w));
    const Vec3 st = p >= 0 ? a.tip[p] : a.root;
    a.start[i] = st;
    a.tip[i] = st + rotate_x(w, a.lengths[i]);
  }
}

}  // namespace detail

// -------------------------------------------------------------------------
// FABRIK (Aristidou and Lasenby 2011, "FABRIK: a fast, iterative solver for the
// inverse kinematics problem", Graphical Models 73(5)). Stage 1 (forward reaching)
// runs from the effectors to the root: each bone's tip goes to its target (or to the
// centroid of the sub-base positions proposed by its children, Aristidou sec. 5) and
// its start is pulled along the bone. Stage 2 (backward reaching) runs from the root:
// each joint turns its bone toward the stage-1 tip goal, in joint coordinates, so the
// joint type and limits are enforced exactly; this pass is also forward kinematics.
void Solver::Impl::fabrik(SolveResult& r) {
  Skeleton& s = *sk;
  const int cap = max_iterations();
  const auto parents = s.parents();
  const auto types = s.joint_types();
  const auto lengths = s.lengths();
  const auto& limited = A::limited(s);
  const auto& lo = A::lo(s);
  const auto& hi = A::hi(s);
  const auto& swing = A::swing(s);
  const auto& axis = A::axis(s);
  auto& q = A::q(s);
  auto& ang = A::angle(s);
  auto& world = A::world(s);
  auto& start = A::start(s);
  auto& tip = A::tip(s);
  Vec3& root = A::root_position(s);
  const Quat root_rot = s.root_rotation();
  // unlimited ball joints without orientation targets constrain nothing but the bone
  // lengths: iterate on positions only and recover the rotations once at the end
  bool positions_only = all_free_balls;
  for (int k = 0; k < ne; ++k)
    if (s.effector(k).orientation) positions_only = false;
  double prev = r.residual, checkpoint = r.residual;
  bool handover = false;
  // one effector on free ball joints: the dedicated chain loop does all the iterations
  const bool chain_fast = positions_only && ne == 1;
  if (chain_fast) handover = fabrik_chain(r);
  for (int it = 0; it < cap && !r.converged && !chain_fast && !out_of_time(it, r); ++it) {
    // stage 1: forward reaching, effectors to root
    Vec3 root_goal = root;
    for (int j : active_rev) {
      Vec3 g = acc[j];
      double ws = accw[j];
      const Quat* orient = nullptr;
      for (int u = eff_off[j]; u < eff_off[j + 1]; ++u) {
        const EffectorDef& ef = s.effector(eff_list[u]);
        g += ef.weight * ef.target;
        ws += ef.weight;
        if (ef.orientation && !orient) orient = &*ef.orientation;
      }
      g /= ws;
      acc[j] = Vec3(0);
      accw[j] = 0;
      goal[j] = g;
      // the bone's start, pulled toward the goal along the bone (or set by an orientation target)
      Vec3 sp;
      if (orient) {
        sp = g - detail::rotate_x(*orient, lengths[j]);
      } else if (types[j] == JointType::Fixed) {
        // a welded bone keeps its current direction: translate it, do not turn it
        sp = g - (tip[j] - start[j]);
      } else {
        Vec3 d = start[j] - g;
        if (types[j] == JointType::Hinge || (types[j] == JointType::Ball && limited[j])) {
          // constrain the bone direction in the joint's current frame: a hinge keeps the
          // bone in its plane (and its angle range), a limited ball inside its cone.
          // Aristidou and Lasenby 2011 sec. 4 apply constraints in both stages too.
          const int p = parents[j];
          const Quat F = (p >= 0 ? world[p] : root_rot) * A::rest(s)[j];
          const Vec3 dl = detail::rotate_inv(F, -d);
          const double l2 = glm::dot(dl, dl);
          Vec3 c = dl;
          if (types[j] == JointType::Hinge) {
            const double x = glm::dot(hx[j], dl), yv = glm::dot(hy[j], dl);
            if (x * x + yv * yv > 1e-12 * l2) {
              if (limited[j]) {
                const double a = std::clamp(std::atan2(yv, x), lo[j], hi[j]);
                c = std::cos(a) * hx[j] + std::sin(a) * hy[j];
              } else {
                c = x * hx[j] + yv * hy[j];
              }
            }
          } else if (l2 > 1e-300) {
            const Vec3 u = dl / std::sqrt(l2);
            const double cl = std::cos(swing[j]);
            if (u.x < cl) {
              const double rl = std::sqrt(u.y * u.y + u.z * u.z);
              const double sl = std::sin(swing[j]);
              c = rl > 1e-15 ? Vec3(cl, sl * u.y / rl, sl * u.z / rl) : Vec3(cl, sl, 0);
            }
          }
          d = -detail::rotate(F, c);
        }
        const double l2 = glm::dot(d, d);
        sp = l2 > 1e-300 ? g + d * (lengths[j] / std::sqrt(l2)) : g - detail::rotate_x(world[j], lengths[j]);
      }
      const int p = parents[j];
      if (p >= 0) {
        acc[p] += sp;
        accw[p] += 1;
      } else {
        root_goal = sp;
      }
    }
    if (s.root_free()) root = root_goal;

    if (positions_only) {
      // stage 2 on positions: each tip at bone length from its start, toward its goal
      for (int i : active_fwd) {
        const int p = parents[i];
        const Vec3 st = p >= 0 ? tip[p] : root;
        const Vec3 d = goal[i] - st;
        const double l2 = glm::dot(d, d);
        const Vec3 old_dir = tip[i] - start[i];
        start[i] = st;
        tip[i] = l2 > 1e-300 ? st + d * (lengths[i] / std::sqrt(l2)) : st + old_dir;
      }
      r.iterations = it + 1;
      measure_tips(r);
      // as below: a fixed point of the passes (effectors pulling apart, or one target near
      // the reach) goes on to damped least squares, which stops at once at a stationary pose
      if (!r.converged && stalled(prev, r.residual)) {
        handover = true;
        break;
      }
      prev = r.residual;
      continue;
    }

    // stage 2: backward reaching, root to effectors, in joint coordinates
    for (int i = 0; i < n; ++i) {
      const int p = parents[i];
      const Vec3 st = p >= 0 ? tip[p] : root;
      const Quat base = p >= 0 ? world[p] : root_rot;
      const Quat F = rest_identity[i] ? base : detail::qmul(base, A::rest(s)[i]);
      if (active[i]) {
        const JointType jt = types[i];
        if (jt == JointType::Hinge) {
          // angle of the goal direction in the hinge plane
          const Vec3 dl = detail::rotate_inv(F, goal[i] - st);
          const double x = glm::dot(hx[i], dl), yv = glm::dot(hy[i], dl);
          if (x * x + yv * yv > 1e-300) {
            double a = std::atan2(yv, x);
            if (limited[i]) a = std::clamp(a, lo[i], hi[i]);
            ang[i] = a;
            const double sh = std::sin(0.5 * a);
            q[i] = Quat(std::cos(0.5 * a), axis[i].x * sh, axis[i].y * sh, axis[i].z * sh);
          }
        } else if (jt == JointType::Ball) {
          const Quat* orient = nullptr;
          for (int u = eff_off[i]; u < eff_off[i + 1]; ++u)
            if (s.effector(eff_list[u]).orientation) {
              orient = &*s.effector(eff_list[u]).orientation;
              break;
            }
          if (orient) {
            // an orientation target sets the whole joint rotation
            q[i] = glm::conjugate(F) * *orient;
            if (limited[i]) q[i] = detail::clamp_ball(q[i], swing[i], lo[i], hi[i]);
          } else {
            Vec3 d = detail::rotate_inv(F, goal[i] - st);
            const double l2 = glm::dot(d, d);
            if (l2 > 1e-300) {
              d /= std::sqrt(l2);
              // keep the swing inside the cone
              if (limited[i] && swing[i] < kPi) {
                const double cl = std::cos(swing[i]);
                if (d.x < cl) {
                  const double rl = std::sqrt(d.y * d.y + d.z * d.z);
                  const double sl = std::sin(swing[i]);
                  d = rl > 1e-15 ? Vec3(cl, sl * d.y / rl, sl * d.z / rl) : Vec3(cl, sl, 0);
                }
              }
              // shortest arc from +X to d, then the joint's previous twist
              Quat sw;
              if (d.x > -1 + 1e-12) {
                sw = Quat(1 + d.x, 0, -d.z, d.y);
                sw = sw * (1 / std::sqrt(sw.w * sw.w + sw.y * sw.y + sw.z * sw.z));
              } else {
                sw = Quat(0, 0, 1, 0);
              }
              const Quat& o = q[i];
              const double tn = std::sqrt(o.w * o.w + o.x * o.x);
              Quat tw = tn > 1e-12 ? Quat(o.w / tn, o.x / tn, 0, 0) : Quat(1, 0, 0, 0);
              if (hinge_child[i] >= 0) tw = twist_for_hinge_child(i, F, sw, st, tw);
              q[i] = detail::qmul(sw, tw);
            }
          }
        }
      }
      const Quat wi = detail::qmul(F, q[i]);
      detail::put(world[i], wi);
      start[i] = st;
      tip[i] = st + detail::rotate_x(wi, lengths[i]);
    }
    r.iterations = it + 1;
    measure(r);
    // a fixed point of the two passes with joint constraints is not a stationary pose of
    // the error (a chain pressed on its limits toward an unreachable target stopped up to
    // 2.6e-2 m from it): damped least squares goes on from there, and stops at once if
    // the pose is stationary
    if (!r.converged && stalled(prev, r.residual)) {
      handover = true;
      break;
    }
    prev = r.residual;
    // with joint constraints the passes can fight the limits and creep (or circle an
    // unreachable target) instead of converging: when 8 iterations have not halved the
    // error, damped least squares (monotone, limit-aware) takes the remaining iterations
    if (r.converged || (it + 1) % 8 != 0) continue;
    if (r.residual > 0.5 * checkpoint) {
      handover = true;
      break;
    }
    checkpoint = r.residual;
  }
  // (a simple chain's new positions are still in cp: fabrik_chain did not scatter them)
  if (positions_only) rebuild_rotations(chain_fast && simple_chain ? cp.data() : nullptr);
  if (handover && !r.out_of_time) {
    r.handed_over = true;
    jacobian(r, Method::Dls);
  }
}

// joint rotations from the bone directions positions-only FABRIK left in start/tip
// (detail::rebuild_rotations), then the transforms of bones off every effector's path
void Solver::Impl::rebuild_rotations(const Vec3* points) {
  Skeleton& s = *sk;
  detail::RebuildArgs args{active_fwd.data(),      static_cast<int>(active_fwd.size()),
                           s.parents().data(),     s.lengths().data(),
                           inv_len.data(),         rest_identity.data(),
                           A::rest(s).data(),      A::root_position(s),
                           s.root_rotation(),      A::world(s).data(),
                           A::q(s).data(),         A::start(s).data(),
                           A::tip(s).data(),       scratch.data(),
                           simple_chain,           points};
  detail::rebuild_rotations(args);
  // bones off every effector's path still need their transforms
  if (static_cast<int>(active_fwd.size()) != s.bone_count()) s.forward_kinematics();
}

// The twist of ball joint i that turns its hinge child's plane onto the child's goal
// (a ball joint's twist is otherwise never solved by positions alone, and a knee or
// elbow could then never leave its plane). With a' the child's hinge axis in bone i's
// frame and v the vector from bone i's tip to the child's goal, in that frame before
// twist, twisting by tau about +X makes (R_x(tau) a') . v = A cos tau + B sin tau + C
// vanish; of the two roots, keep the one whose child hinge angle fits the child's limits
// (then the one nearer the current twist), clamped to bone i's twist range.
Quat Solver::Impl::twist_for_hinge_child(int i, const Quat& F, const Quat& sw, const Vec3& st, const Quat& tw_old) {
  Skeleton& s = *sk;
  const int c = hinge_child[i];
  const Quat Fs = detail::qmul(F, sw);
  const Vec3 tip_i = st + detail::rotate_x(Fs, s.lengths()[i]);
  const Vec3 v = detail::rotate_inv(Fs, goal[c] - tip_i);
  const Vec3 a = detail::rotate(A::rest(s)[c], A::axis(s)[c]);
  const double Ac = a.y * v.y + a.z * v.z, Bc = a.y * v.z - a.z * v.y, Cc = a.x * v.x;
  const double R = std::sqrt(Ac * Ac + Bc * Bc);
  if (R < 1e-12 * (glm::length(v) + 1e-300)) return tw_old;
  const double phi = std::atan2(Bc, Ac), delta = std::acos(std::clamp(-Cc / R, -1.0, 1.0));
  const double old = 2 * std::atan2(tw_old.x, tw_old.w);
  const bool limited = A::limited(s)[i] != 0;
  double best = old, best_score = 1e300;
  for (double cand : {phi + delta, phi - delta}) {
    double t = detail::wrap_angle(cand);
    if (limited) t = std::clamp(t, A::lo(s)[i], A::hi(s)[i]);
    // the child's hinge angle toward its goal with this twist
    const Quat tq(std::cos(0.5 * t), std::sin(0.5 * t), 0, 0);
    const Vec3 dl = detail::rotate_inv(detail::qmul(tq, A::rest(s)[c]), v);
    const double th = std::atan2(glm::dot(hy[c], dl), glm::dot(hx[c], dl));
    const double out = A::limited(s)[c] ? std::max({0.0, A::lo(s)[c] - th, th - A::hi(s)[c]}) : 0.0;
    const double score = out + 1e-3 * std::abs(detail::wrap_angle(t - old));
    if (score < best_score) best_score = score, best = t;
  }
  return Quat(std::cos(0.5 * best), std::sin(0.5 * best), 0, 0);
}

// FABRIK on one chain of unlimited ball joints (the root-to-effector path), on
// contiguous joint positions: stage 1 is a reaching pass from the target over the
// joints in reverse, stage 2 one from the root over stage 1's points in reverse, both
// by reach_pass (whose dependent path per joint is a square root, a multiplication
// and a subtraction). Rotations are rebuilt once, after the last iteration.
bool Solver::Impl::fabrik_chain(SolveResult& r) {
  Skeleton& s = *sk;
  const int L = static_cast<int>(active_fwd.size());
  const int cap = max_iterations();
  auto& start = A::start(s);
  auto& tip = A::tip(s);
  // gather the path: cp[0] the root joint, cp[k + 1] the tip of path bone k (cl and clr,
  // its lengths forward and reversed, are set in prepare())
  cp[0] = start[active_fwd[0]];
  for (int k = 0; k < L; ++k) cp[k + 1] = tip[active_fwd[k]];
  const Vec3 target = s.effector(0).target;
  const bool free_root = s.root_free();
  const double tol = set.tolerance;
  double prev = r.residual, checkpoint = r.residual;
  bool handover = false;
  for (int it = 0; it < cap && !r.converged && !out_of_time(it, r); ++it) {
    // stage 1: from the target back to the root; fw[j] is the new tip of bone L-1-j
    const Vec3 root_goal = detail::reach_pass(target, &cp[L - 1], clr.data(), fw.data(), L);
    if (free_root) cp[0] = root_goal;
    // stage 2: from the root out to the effector, toward stage 1's tips
    const Vec3 end = detail::reach_pass(cp[0], &fw[L - 1], cl.data(), cp.data(), L);
    r.iterations = it + 1;
    r.residual = glm::length(end - target);
    r.converged = r.residual <= tol;
    // a fixed point of the passes short of a reachable target (the straight chain toward an
    // unreachable one is taken before, straighten_if_unreachable) is not known to be a
    // stationary pose of the error: damped least squares goes on, and stops at once if it is
    // (this break used to end the solve there, as the other loop's once did)
    if (!r.converged && stalled(prev, r.residual)) {
      handover = true;
      break;
    }
    prev = r.residual;
    // as on the other loop, damped least squares takes the remaining iterations when the
    // passes creep (toward a target near the reach: 1000 iterations ended 0.16-2.9 mm short of
    // targets 1e-3 m inside 1 m chains of 3-100 bones), here when 64 iterations have not halved
    // the error: a cold solve on a long free chain halves it in fewer, though not always in 8
    // (all 200 random targets of a 1000-bone chain would hand over at 8; its 76 iterations
    // there are benchmarked, docs/ik.md)
    if (r.converged || (it + 1) % 64 != 0) continue;
    if (r.residual > 0.5 * checkpoint) {
      handover = true;
      break;
    }
    checkpoint = r.residual;
  }
  // scatter back to the skeleton's arrays (a simple chain's rebuild reads cp itself)
  if (free_root) A::root_position(s) = cp[0];
  if (simple_chain) return handover;
  for (int k = 0; k < L; ++k) {
    start[active_fwd[k]] = cp[k];
    tip[active_fwd[k]] = cp[k + 1];
  }
  return handover;
}

// An unreachable target for one effector on a path of unlimited ball joints from a fixed
// root: the closest reachable point is the tip of the straight path pointing at the target
// (Aristidou and Lasenby 2011, Algorithm 1, tests this first), which the iterative methods
// only approach slowly (DLS, SDLS and CCD need more than their caps at 1000 bones). Every
// bone on the path turns, by its shortest arc, onto the root-target direction; returns
// true when it did (the result is then final: no iteration improves on it). The given pose
// (given_q, solve()) is saved before: a shortcut whose result misses gives it back and
// returns false, and the iterations go on from it.
bool Solver::Impl::straighten_if_unreachable(SolveResult& r) {
  Skeleton& s = *sk;
  if (ne != 1 || s.root_free() || s.effector(0).orientation) return false;
  // a target within kNearReachBand of the reach is bent for up front only from a pose given
  // farther from it than the band is wide (a cold start, where a jump is expected anyway); a
  // pose given nearer (a warm start tracking a moving target) iterates first, from where it
  // is, and is bent only when the iterations end short (solve(), bend_to_rescue): the bend
  // turns the joints by up to tenths of a radian whatever the target's move
  const bool cold = r.residual > kNearReachBand * path_reach;
  if (!all_free_balls) return straighten_mixed(r) || (cold && bend_or_give_back(r));
  const int L = static_cast<int>(active_fwd.size());
  auto& start = A::start(s);
  auto& tip = A::tip(s);
  const Vec3 root = start[active_fwd[0]];
  const Vec3 d = s.effector(0).target - root;
  const double d2 = glm::dot(d, d);
  // also a target within half the tolerance inside the reach: the straight path's tip is
  // then within half the tolerance of it (converged, with room for the rounding of forward
  // kinematics), where the iterations, at the singular straight pose, crept (FABRIK 0.5 mm
  // short of a target 1e-6 m inside a 10-bone chain's reach after its 1000 iterations; CCD,
  // DLS, SDLS and the pseudo-inverse 0.2 mm on 100 bones); a target farther inside, within
  // kNearReachBand of the reach, is met by the chain bent once (bend_near_reach)
  const double near = std::max(path_reach - 0.5 * set.tolerance, 0.0);
  const double dist = std::sqrt(d2);
  if (!(dist > near)) return cold && bend_or_give_back(r);
  // the straight path, then the rotations and forward kinematics from it
  const Vec3 u = d / dist;
  Vec3 p = root;
  for (int k = 0; k < L; ++k) {
    const int i = active_fwd[k];
    start[i] = p;
    p += u * cl[k];
    tip[i] = p;
  }
  rebuild_rotations(nullptr);
  r.iterations = 1;
  measure(r);
  return true;
}

// A target within kNearReachBand of the reach, one effector, a fixed root: the path bent
// once (bend_near_reach on free ball joints, bend_mixed_near_reach on mixed ones), forward
// kinematics current and r measured; false, the pose possibly changed, when it was not
// bent (the callers give a pose back)
bool Solver::Impl::bend_if_near_reach(SolveResult& r) {
  Skeleton& s = *sk;
  if (ne != 1 || s.root_free() || s.effector(0).orientation) return false;
  if (!all_free_balls) {
    if (!bend_mixed_near_reach()) return false;
  } else {
    const Vec3 d = s.effector(0).target - s.starts()[active_fwd[0]];
    const double dist = glm::length(d);
    if (!(dist <= path_reach) || !bend_near_reach(d, dist)) return false;
    rebuild_rotations(nullptr);
  }
  measure(r);
  return true;
}

// the bend up front (straighten_if_unreachable): kept, as final, only when it meets the
// target within the tolerance; else the given pose back and false (the iterations go on:
// the reviewer's chains whose first ball joint's twist range excludes 0, or cones that
// clamp, are such misses)
bool Solver::Impl::bend_or_give_back(SolveResult& r) {
  if (bend_if_near_reach(r) && r.converged) {
    r.iterations = 1;
    return true;
  }
  restore_given_pose();
  measure(r);
  return false;
}

// A target just inside the reach of a path (farther from its first moving joint than
// (1 - kNearReachBand) of the length from there): every pose that meets it is nearly
// straight, a near-singular pose where the iterative methods creep. Measured from the bent
// pose on 1 m chains, free ball joints: the transpose 0.5-4 mm short of targets 1e-3 to
// 1e-2 m inside 3- and 10-bone chains after its 2000 iterations; CCD, DLS, SDLS and the
// pseudo-inverse 0.1-0.3 mm short of targets 1e-4 m inside 100 bones and 1-6 mm short of
// 1e-4 to 1e-3 m inside 1000 bones after their 1000; chains mixing hinges and ball joints,
// the same from 1e-6 m inside. A pose that meets it exactly: the path split at a joint
// near its middle into two straight parts of lengths a and b, bent there (law of cosines:
// the first part makes the angle alpha with the line from the first joint p0 to the target,
// cos alpha = (a^2 + d^2 - b^2) / (2 a d)), in the plane of the current bend at that joint
// (any plane when it is on the line). `split` is the index in active_fwd of the joint to
// bend at, `first` that of the path's first moving joint; false when |a - b| >= d.
bool Solver::Impl::near_reach_bend(int first, int split, const Vec3& d, double dist, NearReachBend& out) const {
  const Skeleton& s = *sk;
  double a = 0, reach = 0;
  for (int k = first; k < static_cast<int>(active_fwd.size()); ++k) (k < split ? a : reach) += cl[k];
  const double b = reach;
  if (!(std::abs(a - b) < dist) || !(a > 0) || !(b > 0)) return false;
  const Vec3 p0 = s.starts()[active_fwd[first]];
  const Vec3 u = d / dist;
  // the bend's side: the split joint's offset across the line, else any normal
  Vec3 w = s.starts()[active_fwd[split]] - p0;
  w -= glm::dot(w, u) * u;
  double wl = glm::length(w);
  if (!(wl > 1e-9 * (a + b))) {
    w = glm::cross(u, std::abs(u.x) < 0.6 ? Vec3(1, 0, 0) : Vec3(0, 1, 0));
    wl = glm::length(w);
  }
  w /= wl;
  const double c = std::clamp((a * a + dist * dist - b * b) / (2 * a * dist), -1.0, 1.0);
  out.u1 = c * u + std::sqrt(std::max(1 - c * c, 0.0)) * w;
  out.mid = p0 + a * out.u1;
  out.u2 = glm::normalize(s.effector(0).target - out.mid);
  return true;
}

// the index in active_fwd, after `first`, of the joint of kind Ball (any moving kind when
// `any`) whose start is nearest the middle of the path from `first` on; -1 if none
int Solver::Impl::middle_joint(int first, bool any) const {
  const auto types = sk->joint_types();
  const int L = static_cast<int>(active_fwd.size());
  double reach = 0;
  for (int k = first; k < L; ++k) reach += cl[k];
  int best = -1;
  double a = 0, best_gap = 1e300;
  for (int k = first; k < L; ++k) {
    const JointType jt = types[active_fwd[k]];
    if (k > first && (jt == JointType::Ball || (any && jt != JointType::Fixed)) &&
        std::abs(a - 0.5 * reach) < best_gap)
      best = k, best_gap = std::abs(a - 0.5 * reach);
    a += cl[k];
  }
  return best;
}

// free ball joints: the path's positions bent once (near_reach_bend), rotations rebuilt
// by the caller from start and tip; true when it did
bool Solver::Impl::bend_near_reach(const Vec3& d, double dist) {
  if (!(dist > (1 - kNearReachBand) * path_reach)) return false;
  const int k0 = middle_joint(0, true);
  NearReachBend g;
  if (k0 < 0 || !near_reach_bend(0, k0, d, dist, g)) return false;
  auto& start = A::start(*sk);
  auto& tip = A::tip(*sk);
  Vec3 p = start[active_fwd[0]];
  for (int k = 0; k < static_cast<int>(active_fwd.size()); ++k) {
    const int i = active_fwd[k];
    if (k == k0) p = g.mid;
    start[i] = p;
    p += (k < k0 ? g.u1 : g.u2) * cl[k];
    tip[i] = p;
  }
  return true;
}

// the rescue (solve(), after the method): a method that ended short of a target within
// kNearReachBand of the reach, where the iterations creep, takes the bend from the pose it
// ended in; kept with one more iteration counted when it converges, else that pose back
void Solver::Impl::bend_to_rescue(SolveResult& r) {
  Skeleton& s = *sk;
  for (int j : active_fwd) stalled_q[j] = A::q(s)[j], stalled_angle[j] = A::angle(s)[j];
  stalled_root = A::root_position(s);
  const int iterations = r.iterations;
  if (bend_if_near_reach(r) && r.converged) {
    r.iterations = iterations + 1;
    carry_valid = false;  // a Jacobian method's step shortening belongs to the pose it left
    return;
  }
  for (int j : active_fwd) A::q(s)[j] = stalled_q[j], A::angle(s)[j] = stalled_angle[j];
  A::root_position(s) = stalled_root;
  s.forward_kinematics();
  measure(r);
}

// a path mixing joints whose first moving joint is a ball joint and every later joint can
// hold zero (straight_first, no hinge before it): that ball joint aims the first part, the
// ball joint nearest the middle bends toward the target, every other joint at zero, when
// both directions are inside their cones; true when it did (forward kinematics current;
// the caller measures the result: a clamp may have moved the tip, see below). False may
// leave the pose changed.
bool Solver::Impl::bend_mixed_near_reach() {
  Skeleton& s = *sk;
  if (straight_first < 0 || straight_hinge >= 0) return false;
  const int f = active_fwd[straight_first];
  const Vec3 d = s.effector(0).target - s.starts()[f];
  const double dist = glm::length(d);
  if (!(dist > (1 - kNearReachBand) * straight_reach) || !(dist <= straight_reach)) return false;
  const int k0 = middle_joint(straight_first, false);
  NearReachBend g;
  if (k0 < 0 || !near_reach_bend(straight_first, k0, d, dist, g)) return false;
  const int m0 = active_fwd[k0];
  const auto& limited = A::limited(s);
  // the first ball joint's swing toward u1, every later joint at zero
  const Vec3 l1 = detail::rotate_inv(frame(f), g.u1);
  if (limited[f] && l1.x < std::cos(A::swing(s)[f])) return false;
  auto& q = A::q(s);
  auto& angle = A::angle(s);
  for (int k = straight_first; k < static_cast<int>(active_fwd.size()); ++k) {
    const int i = active_fwd[k];
    q[i] = k == straight_first ? detail::from_to(Vec3(1, 0, 0), l1) : Quat(1, 0, 0, 0);
    angle[i] = 0;
    A::clamp_joint(s, i);
  }
  // the clamp moves a twist range that excludes 0 to its nearer end: the swing (the first
  // part's direction) stays, the frame turns about it, so the middle joint's direction is
  // taken in its frame after the clamp (taken before, the second part turned about u1 with
  // the twist and the tip missed by up to 0.54 m, review of 2026-12-07)
  s.forward_kinematics();
  const Vec3 l2 = detail::rotate_inv(frame(m0), g.u2);
  if (limited[m0] && l2.x < std::cos(A::swing(s)[m0])) return false;
  q[m0] = detail::from_to(Vec3(1, 0, 0), l2);
  A::clamp_joint(s, m0);
  s.forward_kinematics();
  return true;
}

// The same on a path that mixes joints: when the path's first moving joint is a ball joint
// and every joint after it can hold the straight pose (zero angle, identity rest: see
// prepare(), straight_first), the tip of the moving part lies within straight_reach of that
// joint, so a target farther away is closest, at |d| - straight_reach, for the straight
// path pointing at it, which the ball joint can aim if the direction is inside its cone.
// One hinge may come before the ball joint (a chain whose root joint is a hinge): it moves
// the ball joint's position p on a circle about its axis, and every pose's tip is at least
// |t - p| - straight_reach from the target, so the closest pose turns the hinge to bring p
// nearest the target (the angle of analytic_1dof, or the nearer end of its range) and then
// straightens the rest toward the target. Iterative methods approach these poses only
// sublinearly (a singular pose with a large residual: Gauss-Newton's J^T J misses the
// curvature that straightens the chain): DLS ended 3e-3 m away after its 1000 iterations on
// 333 bones whose root is a hinge.
bool Solver::Impl::straighten_mixed(SolveResult& r) {
  Skeleton& s = *sk;
  if (straight_first < 0) return false;
  const int f = active_fwd[straight_first];
  const Vec3 target = s.effector(0).target;
  auto& q = A::q(s);
  auto& angle = A::angle(s);
  const auto& limited = A::limited(s);
  // the hinge before the ball joint: the angle that brings the ball joint nearest the target
  const int h = straight_hinge >= 0 ? active_fwd[straight_hinge] : -1;
  const double given_angle = h >= 0 ? angle[h] : 0.0;
  if (h >= 0) {
    const Vec3 a = detail::rotate(frame(h), A::axis(s)[h]);
    const Vec3 c = s.starts()[h];
    Vec3 v = s.starts()[f] - c, w = target - c;
    v -= glm::dot(v, a) * a;
    w -= glm::dot(w, a) * a;
    if (glm::dot(v, v) > 1e-300 && glm::dot(w, w) > 1e-300) {
      // |t - p|^2 = const - 2 |v| |w| cos(theta - best) over the hinge angle theta
      const double best = angle[h] + std::atan2(glm::dot(a, glm::cross(v, w)), glm::dot(v, w));
      double want = detail::wrap_angle(best);
      if (limited[h] && (want < A::lo(s)[h] || want > A::hi(s)[h])) {
        // outside the range: the end nearer the best angle around the circle
        const double dlo = std::abs(detail::wrap_angle(A::lo(s)[h] - best));
        const double dhi = std::abs(detail::wrap_angle(A::hi(s)[h] - best));
        want = dlo <= dhi ? A::lo(s)[h] : A::hi(s)[h];
      }
      angle[h] = want;
      A::clamp_joint(s, h);
      s.forward_kinematics();
    }
  }
  // give the hinge back when the straight path is not the answer
  auto refuse = [&] {
    if (h >= 0 && angle[h] != given_angle) {
      angle[h] = given_angle;
      A::clamp_joint(s, h);
      s.forward_kinematics();
    }
    return false;
  };
  const Vec3 d = target - s.starts()[f];
  const double d2 = glm::dot(d, d);
  if (!(d2 > straight_reach * straight_reach)) return refuse();
  // the direction in the ball joint's frame, inside its cone
  const Vec3 u = detail::rotate_inv(frame(f), d) / std::sqrt(d2);
  if (limited[f] && u.x < std::cos(A::swing(s)[f])) return refuse();
  // aim the ball joint (a swing, no twist), every later joint at zero
  q[f] = detail::from_to(Vec3(1, 0, 0), u);
  A::clamp_joint(s, f);
  for (int k = straight_first + 1; k < static_cast<int>(active_fwd.size()); ++k) {
    const int i = active_fwd[k];
    q[i] = Quat(1, 0, 0, 0);
    angle[i] = 0;
  }
  s.forward_kinematics();
  measure(r);
  // final only when the tip lies where the straight path's does, |d| - straight_reach from
  // the target (a clamp that moved it: the given pose back, the iterations go on)
  if (!(r.residual <= std::sqrt(glm::dot(target - s.starts()[f], target - s.starts()[f])) - straight_reach +
                          set.tolerance)) {
    restore_given_pose();
    measure(r);
    return false;
  }
  r.iterations = 1;
  return true;
}

}  // namespace pba::ik
