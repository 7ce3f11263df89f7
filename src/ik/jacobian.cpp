// The Jacobian family on a Skeleton, for Solver: transpose, pseudo-inverse, damped least
// squares and selectively damped least squares, and the dense m x m routines they use.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "ik/solver_impl.h"

namespace pba::ik {

// ---------------------------------------------------------------------------
// dense helpers on m x m matrices

namespace detail {

bool cholesky_solve(const double* Am, int m, double ridge, double* L, const double* b, double* x) {
  // factor A + ridge I = L L^T (lower triangle of L, row-major)
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j <= i; ++j) {
      double sum = Am[i * m + j] + (i == j ? ridge : 0.0);
      for (int k = 0; k < j; ++k) sum -= L[i * m + k] * L[j * m + k];
      if (i == j) {
        if (!(sum > 0)) return false;
        L[i * m + i] = std::sqrt(sum);
      } else {
        L[i * m + j] = sum / L[j * m + j];
      }
    }
  }
  // forward then backward substitution
  for (int i = 0; i < m; ++i) {
    double sum = b[i];
    for (int k = 0; k < i; ++k) sum -= L[i * m + k] * x[k];
    x[i] = sum / L[i * m + i];
  }
  for (int i = m - 1; i >= 0; --i) {
    double sum = x[i];
    for (int k = i + 1; k < m; ++k) sum -= L[k * m + i] * x[k];
    x[i] = sum / L[i * m + i];
  }
  return true;
}

void jacobi_eigen(const double* Am, int m, double* V, double* w, double* a) {
  // start from A and V = I
  std::memcpy(a, Am, sizeof(double) * m * m);
  for (int i = 0; i < m * m; ++i) V[i] = 0;
  for (int i = 0; i < m; ++i) V[i * m + i] = 1;
  // cyclic sweeps of plane rotations zeroing off-diagonal entries
  for (int sweep = 0; sweep < 50; ++sweep) {
    double off = 0, diag = 0;
    for (int i = 0; i < m; ++i) {
      diag += a[i * m + i] * a[i * m + i];
      for (int j = i + 1; j < m; ++j) off += a[i * m + j] * a[i * m + j];
    }
    if (off <= 1e-30 * diag || off == 0) break;
    for (int p = 0; p < m; ++p) {
      for (int q = p + 1; q < m; ++q) {
        const double apq = a[p * m + q];
        if (apq == 0) continue;
        const double theta = (a[q * m + q] - a[p * m + p]) / (2 * apq);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < m; ++k) {
          const double akp = a[k * m + p], akq = a[k * m + q];
          a[k * m + p] = c * akp - s * akq;
          a[k * m + q] = s * akp + c * akq;
        }
        for (int k = 0; k < m; ++k) {
          const double apk = a[p * m + k], aqk = a[q * m + k];
          a[p * m + k] = c * apk - s * aqk;
          a[q * m + k] = s * apk + c * aqk;
        }
        for (int k = 0; k < m; ++k) {
          const double vkp = V[k * m + p], vkq = V[k * m + q];
          V[k * m + p] = c * vkp - s * vkq;
          V[k * m + q] = s * vkp + c * vkq;
        }
      }
    }
  }
  for (int i = 0; i < m; ++i) w[i] = a[i * m + i];
}

}  // namespace detail

// -------------------------------------------------------------------------
// Jacobian family (Buss 2004, "Introduction to Inverse Kinematics with Jacobian
// Transpose, Pseudoinverse and Damped Least Squares methods"). Columns are
// r_j x (e - p_j) for a hinge (r_j its world axis), the three world axes for a
// ball joint, identity for a free root. J is m x ncols; only J J^T (m x m) is
// ever formed, so the cost per iteration is linear in the DOF count.
double Solver::Impl::largest_reach() const {
  double L = 0;
  for (int k = 0; k < ne; ++k) L = std::max(L, sk->reach(sk->effector(k).bone));
  return L;
}

// fill J and e (error, clamped per effector to `clamp` metres), weighted rows
void Solver::Impl::build_jacobian(double clamp, double ori_scale) {
  Skeleton& s = *sk;
  const auto types = s.joint_types();
  std::fill(J.begin(), J.begin() + static_cast<std::size_t>(m) * ncols, 0.0);
  for (int k = 0; k < ne; ++k) {
    const EffectorDef& ef = s.effector(k);
    const double wk = ef.weight;
    const Vec3 ep = s.tips()[ef.bone];
    // position error, clamped (Buss 2004 sec. 7: clamp the target distance)
    Vec3 err = ef.target - ep;
    const double len = glm::length(err);
    if (len > clamp) err *= clamp / len;
    const int r0 = row_of[k];
    e[r0] = wk * err.x, e[r0 + 1] = wk * err.y, e[r0 + 2] = wk * err.z;
    const int o0 = ori_row_of[k];
    if (o0 >= 0) {
      Vec3 oe = detail::quat_log(*ef.orientation * glm::conjugate(s.world_rotations()[ef.bone]));
      const double ol = glm::length(oe);
      if (ol > 0.5) oe *= 0.5 / ol;
      e[o0] = wk * ori_scale * oe.x, e[o0 + 1] = wk * ori_scale * oe.y, e[o0 + 2] = wk * ori_scale * oe.z;
    }
    // a free root translates every effector one for one
    if (s.root_free()) {
      J[0 * m + r0] = wk;
      J[1 * m + r0 + 1] = wk;
      J[2 * m + r0 + 2] = wk;
    }
    // the joints on this effector's path
    for (int pi = path_off[k]; pi < path_off[k + 1]; ++pi) {
      const int j = path[pi];
      const int c = col_of[j];
      if (c < 0) continue;
      const Vec3 d = ep - s.starts()[j];
      double* col = &J[static_cast<std::size_t>(c) * m];
      if (types[j] == JointType::Hinge) {
        const Vec3 a = detail::rotate(frame(j), A::axis(s)[j]);
        const Vec3 g = glm::cross(a, d);
        col[r0] = wk * g.x, col[r0 + 1] = wk * g.y, col[r0 + 2] = wk * g.z;
        if (o0 >= 0) {
          const double f = wk * ori_scale;
          col[o0] = f * a.x, col[o0 + 1] = f * a.y, col[o0 + 2] = f * a.z;
        }
      } else {
        // x-axis column: (1,0,0) x d = (0, -dz, dy); y: (dz, 0, -dx); z: (-dy, dx, 0)
        double* cx = col;
        double* cy = col + m;
        double* cz = col + 2 * m;
        cx[r0] = 0, cx[r0 + 1] = -wk * d.z, cx[r0 + 2] = wk * d.y;
        cy[r0] = wk * d.z, cy[r0 + 1] = 0, cy[r0 + 2] = -wk * d.x;
        cz[r0] = -wk * d.y, cz[r0 + 1] = wk * d.x, cz[r0 + 2] = 0;
        if (o0 >= 0) {
          const double f = wk * ori_scale;
          cx[o0] = f;
          cy[o0 + 1] = f;
          cz[o0 + 2] = f;
        }
      }
    }
  }
}

// A limited ball joint held at a limit, as drop_saturated_columns does for hinges: a step
// that pushes it further out would be projected back into its limits after the step
// (clamp_ball), off the direction the step was computed for, and the error then creeps
// down by what is left (a chain pressed on its cones toward a target outside them). So
// the limit joins the model: the joint's rotation vector is kept off the limit's outward
// normal, J_j becomes J_j P with P = I - n n^T, a projected gradient step (Rosen 1960).
// With q = (w, x, y, z) the joint rotation and a step q' = exp(w_l) q (apply_dtheta), the
// first-order changes are d(y^2 + z^2) = w_l . (0, wy - xz, xy + wz) for the swing
// (cos swing = 1 - 2 (y^2 + z^2)) and, for the twist t = 2 atan2(x, w) of q = swing twist,
// dt (w^2 + x^2) = w_l . (w^2 + x^2, wz + xy, xz - wy). A limit is held when the swing is
// within 1e-9 rad of its cone, or the twist of an end of its range; it is active when the
// descent direction `desc` (the block of J^T e) points out of it.
int Solver::Impl::held_ball_limits(int j, Vec3& swing_out, Vec3& twist_out) const {
  Skeleton& s = *sk;
  const Quat& q = A::q(s)[j];
  const double sw2 = q.y * q.y + q.z * q.z, tw2 = q.w * q.w + q.x * q.x;
  const double swing_limit = A::swing(s)[j];
  int held = 0;
  Quat F;
  // the swing cone
  if (swing_limit < kPi - 1e-9 && std::acos(std::clamp(1 - 2 * sw2, -1.0, 1.0)) >= swing_limit - kHeldBand) {
    F = frame(j);
    swing_out = detail::rotate(F, Vec3(0, q.w * q.y - q.x * q.z, q.x * q.y + q.w * q.z));
    held |= kHoldSwing;
  }
  // the twist range
  const double lo = A::lo(s)[j], hi = A::hi(s)[j];
  if (hi - lo < 2 * kPi - 1e-9 && tw2 > 1e-24) {
    const double t = detail::wrap_angle(2 * std::atan2(q.x, q.w));
    const double side = t >= hi - kHeldBand ? 1.0 : t <= lo + kHeldBand ? -1.0 : 0.0;
    if (side != 0) {
      if (!(held & kHoldSwing)) F = frame(j);
      twist_out = detail::rotate(F, side * Vec3(tw2, q.w * q.z + q.x * q.y, q.x * q.z - q.w * q.y));
      held |= kHoldTwist;
    }
  }
  return held;
}

int Solver::Impl::ball_active_limits(int j, Vec3 desc) {
  lim1[j] = lim2[j] = Vec3(0);
  Vec3 cs(0), ct(0);
  const int held = held_ball_limits(j, cs, ct);
  if (!held) return 0;
  int count = 0;
  // one held limit, outward normal c: kept when desc points out of it or the step did
  auto consider = [&](Vec3 nw, bool forced) {
    if (count == 1) nw -= glm::dot(nw, lim1[j]) * lim1[j];
    const double l = glm::length(nw);
    if (!(l > 1e-12)) return;
    nw /= l;
    const double push = glm::dot(nw, desc);
    if (push <= 0 && !forced) return;
    desc -= push * nw;
    (count == 0 ? lim1[j] : lim2[j]) = nw;
    ++count;
  };
  if (held & kHoldSwing) consider(cs, hold[j] & kHoldSwing);
  if (held & kHoldTwist) consider(ct, hold[j] & kHoldTwist);
  return count;
}

// After a step is computed: every joint held at a limit that the step (dtheta) pushes
// further out, and that was not already held out of it, is marked in `hold` so that the
// next pass leaves that direction out (the gradient alone can point inward while the
// damped Gauss-Newton step points out: the step then clamped, was rejected, and the
// solve crept). Returns whether any was marked.
bool Solver::Impl::hold_pushed_limits() {
  Skeleton& s = *sk;
  const auto types = s.joint_types();
  bool marked = false;
  for (int j : active_rev) {
    const int c = col_of[j];
    if (c < 0 || !A::limited(s)[j]) continue;
    if (types[j] == JointType::Hinge) {
      const double ang = A::angle(s)[j];
      if ((hold[j] & kHoldHinge) == 0 && ((ang >= A::hi(s)[j] - 1e-12 && dtheta[c] > 0) ||
                                          (ang <= A::lo(s)[j] + 1e-12 && dtheta[c] < 0))) {
        hold[j] |= kHoldHinge;
        marked = true;
      }
      continue;
    }
    Vec3 cs(0), ct(0);
    const int held = held_ball_limits(j, cs, ct);
    const Vec3 w(dtheta[c], dtheta[c + 1], dtheta[c + 2]);
    const double tiny = 1e-12 * glm::length(w);
    if ((held & kHoldSwing) && !(hold[j] & kHoldSwing) && glm::dot(w, cs) > tiny * glm::length(cs))
      hold[j] |= kHoldSwing, marked = true;
    if ((held & kHoldTwist) && !(hold[j] & kHoldTwist) && glm::dot(w, ct) > tiny * glm::length(ct))
      hold[j] |= kHoldTwist, marked = true;
  }
  return marked;
}

// zero the columns of hinges held at a limit that the error pushes further out,
// so the other joints take over (a projected gradient step); project the columns of
// limited ball joints off the limits they are held at (ball_active_limits)
void Solver::Impl::drop_saturated_columns() {
  Skeleton& s = *sk;
  const auto types = s.joint_types();
  for (int j : active_rev) {
    if (!A::limited(s)[j] || col_of[j] < 0) continue;
    double* col = &J[static_cast<std::size_t>(col_of[j]) * m];
    if (types[j] == JointType::Ball) {
      // the block's descent direction J_j^T e, then J_j <- J_j (I - n n^T) per active normal
      Vec3 desc(0);
      for (int r = 0; r < m; ++r) desc += e[r] * Vec3(col[r], col[m + r], col[2 * m + r]);
      const int count = ball_active_limits(j, desc);
      for (int a = 0; a < count; ++a) {
        const Vec3 nv = a == 0 ? lim1[j] : lim2[j];
        for (int r = 0; r < m; ++r) {
          const double img = col[r] * nv.x + col[m + r] * nv.y + col[2 * m + r] * nv.z;
          col[r] -= img * nv.x, col[m + r] -= img * nv.y, col[2 * m + r] -= img * nv.z;
        }
      }
      continue;
    }
    if (types[j] != JointType::Hinge) continue;
    const double ang = A::angle(s)[j];
    const bool at_lo = ang <= A::lo(s)[j] + 1e-12, at_hi = ang >= A::hi(s)[j] - 1e-12;
    if (!at_lo && !at_hi) continue;
    double g = 0;
    for (int r = 0; r < m; ++r) g += col[r] * e[r];
    if ((at_hi && g > 0) || (at_lo && g < 0) || (hold[j] & kHoldHinge)) {
      for (int r = 0; r < m; ++r) col[r] = 0;
    }
  }
}

// One position effector, the rows of J are never formed: a ball joint's 3 x 3 block is
// v -> v x D with D = w (e - p_j) (the columns are the world axes crossed with D), so its
// share of J J^T is |D|^2 I - D D^T and of J^T y is D x y; a hinge's column is
// g = w (a_j x (e - p_j)), its share g g^T and g . y; a free root's block is w I. Fills
// e (the clamped, weighted error), Amat (J J^T) and jd (D or g per joint) in one pass over
// the effector's path, dropping saturated hinges as drop_saturated_columns does.
void Solver::Impl::build_compact(double clamp) {
  Skeleton& s = *sk;
  const auto types = s.joint_types();
  const auto starts = s.starts();
  const EffectorDef& ef = s.effector(0);
  const double wk = ef.weight;
  const Vec3 ep = s.tips()[ef.bone];
  // position error, clamped (Buss 2004 sec. 7: clamp the target distance)
  Vec3 err = ef.target - ep;
  const double len = glm::length(err);
  if (len > clamp) err *= clamp / len;
  const Vec3 ew = wk * err;
  e[0] = ew.x, e[1] = ew.y, e[2] = ew.z;
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
  if (s.root_free()) a00 = a11 = a22 = wk * wk;
  const auto& limited = A::limited(s);
  for (int pi = path_off[0]; pi < path_off[1]; ++pi) {
    const int j = path[pi];
    if (col_of[j] < 0) continue;
    const Vec3 D = wk * (ep - starts[j]);
    if (types[j] == JointType::Ball) {
      const double xx = D.x * D.x, yy = D.y * D.y, zz = D.z * D.z;
      a00 += yy + zz, a11 += xx + zz, a22 += xx + yy;
      a01 -= D.x * D.y, a02 -= D.x * D.z, a12 -= D.y * D.z;
      jd[j] = D;
      // held at a limit the error pushes further out: the block J_j (I - n n^T) takes
      // g g^T off its share of J J^T per active normal n, with g = n x D
      if (limited[j] && ball_active_limits(j, glm::cross(D, ew)) > 0) {
        for (const Vec3& nv : {lim1[j], lim2[j]}) {
          const Vec3 g = glm::cross(nv, D);
          a00 -= g.x * g.x, a01 -= g.x * g.y, a02 -= g.x * g.z;
          a11 -= g.y * g.y, a12 -= g.y * g.z, a22 -= g.z * g.z;
        }
      }
    } else {
      Vec3 g = glm::cross(detail::rotate(frame(j), A::axis(s)[j]), D);
      // a hinge held at a limit that the error pushes further out takes no part
      if (limited[j]) {
        const double ang = A::angle(s)[j], gd = glm::dot(g, ew);
        if ((ang >= A::hi(s)[j] - 1e-12 && gd > 0) || (ang <= A::lo(s)[j] + 1e-12 && gd < 0) ||
            (hold[j] & kHoldHinge)) {
          g = Vec3(0);
        }
      }
      a00 += g.x * g.x, a01 += g.x * g.y, a02 += g.x * g.z;
      a11 += g.y * g.y, a12 += g.y * g.z, a22 += g.z * g.z;
      jd[j] = g;
    }
  }
  Amat[0] = a00, Amat[1] = a01, Amat[2] = a02;
  Amat[3] = a01, Amat[4] = a11, Amat[5] = a12;
  Amat[6] = a02, Amat[7] = a12, Amat[8] = a22;
}

// dtheta = J^T x from the vectors build_compact kept
void Solver::Impl::jt_times_compact(const double* x) {
  Skeleton& s = *sk;
  const auto types = s.joint_types();
  const Vec3 y3(x[0], x[1], x[2]);
  if (s.root_free()) {
    const double wk = s.effector(0).weight;
    dtheta[0] = wk * x[0], dtheta[1] = wk * x[1], dtheta[2] = wk * x[2];
  }
  for (int pi = path_off[0]; pi < path_off[1]; ++pi) {
    const int j = path[pi];
    const int c = col_of[j];
    if (c < 0) continue;
    if (types[j] == JointType::Ball) {
      Vec3 r = glm::cross(jd[j], y3);
      // (I - n n^T) for a joint held at its limits (zero normals when none)
      r -= glm::dot(r, lim1[j]) * lim1[j] + glm::dot(r, lim2[j]) * lim2[j];
      dtheta[c] = r.x, dtheta[c + 1] = r.y, dtheta[c + 2] = r.z;
    } else {
      dtheta[c] = glm::dot(jd[j], y3);
    }
  }
}

// A = J J^T (m x m, symmetric): the only matrix product formed
void Solver::Impl::gram() {
  std::fill(Amat.begin(), Amat.begin() + m * m, 0.0);
  if (m == 3) {
    double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
    for (int c = 0; c < ncols; ++c) {
      const double* col = &J[static_cast<std::size_t>(c) * 3];
      a00 += col[0] * col[0], a01 += col[0] * col[1], a02 += col[0] * col[2];
      a11 += col[1] * col[1], a12 += col[1] * col[2], a22 += col[2] * col[2];
    }
    Amat[0] = a00, Amat[1] = a01, Amat[2] = a02;
    Amat[3] = a01, Amat[4] = a11, Amat[5] = a12;
    Amat[6] = a02, Amat[7] = a12, Amat[8] = a22;
    return;
  }
  for (int c = 0; c < ncols; ++c) {
    const double* col = &J[static_cast<std::size_t>(c) * m];
    for (int i = 0; i < m; ++i) {
      const double ci = col[i];
      if (ci == 0) continue;
      for (int k = i; k < m; ++k) Amat[i * m + k] += ci * col[k];
    }
  }
  for (int i = 0; i < m; ++i)
    for (int k = 0; k < i; ++k) Amat[i * m + k] = Amat[k * m + i];
}

// dtheta = J^T x
void Solver::Impl::jt_times(const double* x) {
  if (compact) {
    jt_times_compact(x);
    return;
  }
  for (int c = 0; c < ncols; ++c) {
    const double* col = &J[static_cast<std::size_t>(c) * m];
    double sum = 0;
    for (int r = 0; r < m; ++r) sum += col[r] * x[r];
    dtheta[c] = sum;
  }
}

// scale dtheta so no entry exceeds `cap` (rad or m)
static void clamp_max_abs(double* x, int count, double cap) {
  double mx = 0;
  for (int i = 0; i < count; ++i) mx = std::max(mx, std::abs(x[i]));
  if (mx > cap) {
    const double f = cap / mx;
    for (int i = 0; i < count; ++i) x[i] *= f;
  }
}

// apply dtheta to the pose, projecting every joint into its limits; with `save`, the
// joint values it changes go to saved_q / saved_angle first (for restore_pose)
void Solver::Impl::apply_dtheta(bool save) {
  Skeleton& s = *sk;
  const auto types = s.joint_types();
  const auto& limited = A::limited(s);
  auto& q = A::q(s);
  auto& angle = A::angle(s);
  saved_root = A::root_position(s);
  if (s.root_free()) A::root_position(s) += Vec3(dtheta[0], dtheta[1], dtheta[2]);
  for (int j : active_rev) {
    const int c = col_of[j];
    if (c < 0) continue;
    if (save) detail::put(saved_q[j], q[j]), saved_angle[j] = angle[j];
    if (types[j] == JointType::Hinge) {
      angle[j] += dtheta[c];
      A::clamp_joint(s, j);
      continue;
    }
    // world rotation vector -> joint frame; q <- exp(w_local) q
    // (1, w/2) normalised turns by 2 atan(|w|/2) = |w| + O(|w|^3) about w, without trigonometry
    const Vec3 om = detail::rotate_inv(frame(j), Vec3(dtheta[c], dtheta[c + 1], dtheta[c + 2]));
    const Quat qn = detail::qmul(Quat(1, 0.5 * om.x, 0.5 * om.y, 0.5 * om.z), q[j]);
    if (limited[j]) {
      detail::put(q[j], qn);
      A::clamp_joint(s, j);
    } else {
      // an unlimited ball joint only needs the normalisation
      detail::put(q[j], qn * (1 / std::sqrt(qn.w * qn.w + qn.x * qn.x + qn.y * qn.y + qn.z * qn.z)));
    }
  }
}

// Buss and Kim (2005), "Selectively damped least squares for inverse kinematics":
// J = U S V^T from the eigen-decomposition of the m x m J J^T (v_i = J^T u_i / s_i);
// each singular direction's step is clamped by gamma_i = gamma_max min(1, N_i / M_i).
void Solver::Impl::sdls_step(double gamma_max) {
  detail::jacobi_eigen(Amat.data(), m, V.data(), w.data(), work.data());
  double wmax = 0;
  for (int i = 0; i < m; ++i) wmax = std::max(wmax, w[i]);
  std::fill(dtheta.begin(), dtheta.begin() + ncols, 0.0);
  // rho_j = sum over effectors of |3-row block of column j|
  for (int c = 0; c < ncols; ++c) {
    const double* col = &J[static_cast<std::size_t>(c) * m];
    double sum = 0;
    for (int r = 0; r < m; r += 3)
      sum += std::sqrt(col[r] * col[r] + col[r + 1] * col[r + 1] + col[r + 2] * col[r + 2]);
    rho[c] = sum;
  }
  for (int i = 0; i < m; ++i) {
    if (!(w[i] > 1e-12 * wmax) || w[i] <= 0) continue;
    const double sigma = std::sqrt(w[i]);
    // u_i (column i of V), alpha_i = u_i . e, N_i = sum of block norms of u_i
    double alpha = 0, N = 0;
    for (int r = 0; r < m; ++r) {
      y[r] = V[r * m + i];
      alpha += y[r] * e[r];
    }
    for (int r = 0; r < m; r += 3) N += std::sqrt(y[r] * y[r] + y[r + 1] * y[r + 1] + y[r + 2] * y[r + 2]);
    // v_i = J^T u_i / sigma_i and M_i = sum_j |v_ij| rho_j / sigma_i
    double M = 0;
    for (int c = 0; c < ncols; ++c) {
      const double* col = &J[static_cast<std::size_t>(c) * m];
      double sum = 0;
      for (int r = 0; r < m; ++r) sum += col[r] * y[r];
      v[c] = sum / sigma;
      M += std::abs(v[c]) * rho[c];
    }
    M /= sigma;
    const double gamma = gamma_max * std::min(1.0, M > 0 ? N / M : 1.0);
    // phi_i = clamp(alpha_i / sigma_i v_i, gamma_i)
    const double f = alpha / sigma;
    double mx = 0;
    for (int c = 0; c < ncols; ++c) mx = std::max(mx, std::abs(f * v[c]));
    const double g = mx > gamma ? gamma / mx : 1.0;
    for (int c = 0; c < ncols; ++c) dtheta[c] += g * f * v[c];
  }
  clamp_max_abs(dtheta.data(), ncols, gamma_max);
}

// the Jacobian methods' loop; `meth` is set.method, or dls when FABRIK hands over its
// last iterations (iterations then count on from r.iterations)
void Solver::Impl::jacobian(SolveResult& r, Method meth) {
  Skeleton& s = *sk;
  layout_rows();
  const int cap = max_iterations();
  const double reach = std::max(largest_reach(), 1e-9);
  // per-effector error clamp and orientation row scale (m per rad)
  const double clamp = (meth == Method::JacobianTranspose ? 1.0 : 0.3) * reach;
  const double ori_scale = reach;
  // DLS's damping in the weighted rows' units: a fraction of the reach times the root sum of
  // squares of the weights (the scale of the weighted J), so that scaling every weight by k
  // (weights are relative), or splitting an effector into copies of weight w / sqrt(n),
  // leaves the steps as they were; with the reach alone a lone effector of weight 1e-3 was
  // damped a thousandfold and ended at the iteration cap
  double weights2 = 0;
  for (int k = 0; k < ne; ++k) weights2 += s.effector(k).weight * s.effector(k).weight;
  const double lambda0 = (set.damping > 0 ? set.damping : 0.02) * reach * std::sqrt(weights2);
  double lambda = lambda0;
  const double step_cap = set.max_step_angle > 0 ? set.max_step_angle
                          : meth == Method::Sdls ? kPi / 4
                                                 : 0.5;
  // Every method accepts a step only when it does not raise the cost (the weighted squared
  // error); a rejected step is undone and retried shorter, so no step can leave the pose
  // worse (an unreachable target used to make the pseudo-inverse coil the chain up):
  // damped least squares with 4 times the damping (Levenberg-Marquardt), SDLS with a quarter
  // of its cap gamma, the transpose and the pseudo-inverse with a quarter of the step along
  // the same direction (backtracking: J^T e is minus the gradient of |e|^2 / 2, and J^+ e a
  // descent direction wherever J has full row rank, so a short enough step lowers the cost
  // unless the pose is stationary). When a millionfold shortening still finds no lower
  // cost, DLS's pose is stationary to rounding and the solve stops there
  // (StopReason::Stalled); the other methods hand over to DLS (below).
  //
  // Slow progress never stops a solve. Joint limits enter the model instead (the hinge
  // columns and ball-joint directions held at a limit that the step would push further out
  // are left out: drop_saturated_columns, build_compact, hold_pushed_limits), so that a
  // chain pressed on its limits slides along them to its stationary pose rather than
  // creeping toward it with steps clamped back (the solve used to stop there when 16
  // iterations gained less than 1%, 2e-2 m from the closest pose on 333 bones). The
  // transpose, the pseudo-inverse and SDLS hand over to DLS when 16 iterations gain less
  // than 1%, and when their accepted step is too short to tell (stall_ratio): the undamped
  // Gauss-Newton step of the pseudo-inverse does not converge locally at a minimum with a
  // large residual, whose curvature J^T J lacks (Nocedal and Wright 2006, sec. 10.3), and
  // the transpose's gradient steps converge slowly; DLS stops at a stationary pose.
  double gamma = step_cap, scale = 1;
  // a warm start continues the shortening of a solve of the same method that ran out of
  // iterations (carry_valid, Impl): the step it was about to try, not the full one again
  if (carry_valid && set.warm_start && carry_method == meth) {
    lambda = carry_lambda * lambda0;
    gamma = carry_gamma * step_cap;
    scale = carry_scale;
  }
  carry_valid = false;
  bool line_search = meth == Method::JacobianTranspose || meth == Method::PseudoInverse;
  double prev_cost = cost(ori_scale);
  compact = m == 3 && meth != Method::Sdls;
  double checkpoint = r.residual;
  int window_end = r.iterations + 16;
  // the remaining iterations go to damped least squares (SolveResult::handed_over)
  auto hand_over_to_dls = [&] {
    meth = Method::Dls;
    line_search = false;
    compact = m == 3;
    lambda = lambda0;
    scale = 1;
    r.handed_over = true;
  };
  for (int it = r.iterations; it < cap && !r.converged && !out_of_time(it, r); ++it) {
    for (int j : active_rev) hold[j] = 0;
    // the step, then again with every limit it pushed a joint held there further out
    // (hold_pushed_limits); a few passes at most, each holding more joints
    for (int pass = 0;; ++pass) {
    if (compact) {
      build_compact(clamp);
    } else {
      build_jacobian(clamp, ori_scale);
      drop_saturated_columns();
      gram();
    }
    switch (meth) {
      case Method::JacobianTranspose: {
        // Buss 2004 eq. 7: alpha = <e, J J^T e> / <J J^T e, J J^T e>
        double num = 0, den = 0;
        for (int i = 0; i < m; ++i) {
          double sum = 0;
          for (int k = 0; k < m; ++k) sum += Amat[i * m + k] * e[k];
          t[i] = sum;
          num += e[i] * sum;
          den += sum * sum;
        }
        const double alpha = den > 0 ? num / den : 0.0;
        jt_times(e.data());
        for (int c = 0; c < ncols; ++c) dtheta[c] *= alpha;
        break;
      }
      case Method::PseudoInverse: {
        // J^+ e = J^T (J J^T)^-1 e; a ridge of 1e-9 of the trace keeps the
        // factorisation defined at exact singularities
        double tr = 0;
        for (int i = 0; i < m; ++i) tr += Amat[i * m + i];
        const double ridge = 1e-9 * tr / m + 1e-300;
        if (!detail::cholesky_solve(Amat.data(), m, ridge, L.data(), e.data(), y.data()))
          std::fill(y.begin(), y.begin() + m, 0.0);
        jt_times(y.data());
        break;
      }
      case Method::Dls: {
        // J^T (J J^T + lambda^2 I)^-1 e (Buss 2004 eq. 11)
        if (!detail::cholesky_solve(Amat.data(), m, lambda * lambda, L.data(), e.data(), y.data()))
          std::fill(y.begin(), y.begin() + m, 0.0);
        jt_times(y.data());
        break;
      }
      case Method::Sdls:
        sdls_step(gamma);
        break;
      default:
        break;
    }
    if (pass == 3 || !hold_pushed_limits()) break;
    }
    clamp_max_abs(dtheta.data(), ncols, meth == Method::Sdls ? gamma : step_cap);
    if (scale < 1)
      for (int c = 0; c < ncols; ++c) dtheta[c] *= scale;
    apply_dtheta(true);
    s.forward_kinematics();
    r.iterations = it + 1;
    // slow progress: the other methods hand over to DLS (see above)
    if (r.iterations >= window_end) {
      measure(r);
      // and when the window's rate, rho = residual / checkpoint, kept for the iterations left,
      // cannot bring the error under the tolerance (residual rho^(left / 16) > tolerance):
      // a first-order method converging linearly at a rate the budget cannot finish (the
      // transpose toward a target 1e-3 m inside a 3-bone chain's reach gained 1.5-3% per 16
      // iterations, above the 1% rule, and ended 0.5 mm short after its 2000)
      const double rho = checkpoint > 0 ? r.residual / checkpoint : 1.0;
      const double left = static_cast<double>(cap - r.iterations) / 16;
      if (meth != Method::Dls && !r.converged &&
          (r.residual > 0.99 * checkpoint || r.residual * std::pow(rho, left) > set.tolerance))
        hand_over_to_dls();
      checkpoint = r.residual;
      window_end = r.iterations + 16;
    }
    const double c = cost(ori_scale);
    if (c > prev_cost) {
      // reject: undo, shorten, and stop once the step has shrunk a millionfold
      restore_pose();
      s.forward_kinematics();
      lambda *= 4;
      gamma *= 0.25;
      if (line_search) scale *= 0.25;
      const bool exhausted = meth == Method::Dls    ? lambda > 1e6 * lambda0
                             : meth == Method::Sdls ? gamma < 1e-6 * step_cap
                                                    : scale < 1e-6;
      if (exhausted) {
        // no shorter step of this method lowers the error: stationary for DLS; for the
        // others it can also be a joint limit (a ball joint's projection into its cone
        // turns a short step off the descent direction), where damped least squares,
        // whose growing damping turns its step toward the gradient, takes over
        if (meth == Method::Dls) break;
        hand_over_to_dls();
      }
      continue;
    }
    // accept: relax the damping, the cap and the step back toward their defaults
    const bool still = stalled(prev_cost, c);
    prev_cost = c;
    lambda = std::max(0.5 * lambda, lambda0);
    gamma = std::min(2 * gamma, step_cap);
    scale = std::min(2 * scale, 1.0);
    // stop on a stationary pose: an accepted step that changes the cost by less than
    // stall_ratio of it (not on slow progress: a chain straightening toward an unreachable
    // target, or sliding along its limits, gains little per iteration for many iterations)
    measure(r);
    if (!r.converged && still) {
      // stationary for DLS; the other methods' tiny accepted step can be a short
      // backtracked one (or SDLS's shrunken cap) on a slope: DLS confirms or goes on
      if (meth == Method::Dls) break;
      hand_over_to_dls();
    }
  }
  measure(r);
  if (!r.converged && r.iterations >= cap && meth == set.method) {
    carry_valid = true;
    carry_method = meth;
    carry_lambda = lambda / lambda0;
    carry_gamma = gamma / step_cap;
    carry_scale = scale;
  }
}

// weighted sum of squared errors (orientation errors scaled to metres)
double Solver::Impl::cost(double ori_scale) const {
  const Skeleton& s = *sk;
  double c = 0;
  for (int k = 0; k < ne; ++k) {
    const EffectorDef& ef = s.effector(k);
    const Vec3 d = s.tips()[ef.bone] - ef.target;
    c += ef.weight * ef.weight * glm::dot(d, d);
    if (ef.orientation && ori_scale > 0) {
      const Vec3 o = detail::quat_log(*ef.orientation * glm::conjugate(s.world_rotations()[ef.bone]));
      c += ef.weight * ef.weight * ori_scale * ori_scale * glm::dot(o, o);
    }
  }
  return c;
}

// undo the last apply_dtheta(true): only the joints it changed
void Solver::Impl::restore_pose() {
  Skeleton& s = *sk;
  for (int j : active_rev)
    if (col_of[j] >= 0) A::q(s)[j] = saved_q[j], A::angle(s)[j] = saved_angle[j];
  A::root_position(s) = saved_root;
}

}  // namespace pba::ik
