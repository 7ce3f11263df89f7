// Private helpers for the IK module: small quaternion routines and joint-limit
// projection, written out so the hot loops avoid trigonometry where they can.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/clones.h"
#include "pba/core.h"

namespace pba::ik::detail {


// Hot IK functions are compiled for AVX2 and the baseline: PBA_CLONES (core/clones.h).

/// d = v, component by component. A plain quaternion assignment after scalar arithmetic
/// makes GCC assemble the value on the stack with 8-byte stores and copy it with 16-byte
/// loads, which cannot be forwarded from those stores and wait for them to retire
/// (~10 cycles each); on the solvers' dependent paths that adds up.
inline void put(Quat& d, const Quat& v) { d.w = v.w, d.x = v.x, d.y = v.y, d.z = v.z; }

/// Hamilton product a * b, written out so it always inlines (glm's may not).
inline Quat qmul(const Quat& a, const Quat& b) {
  return Quat(a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
              a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
              a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
              a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w);
}

/// q * (len, 0, 0): the first column of q's rotation matrix times len.
inline Vec3 rotate_x(const Quat& q, double len) {
  const double yy = q.y * q.y, zz = q.z * q.z;
  return Vec3((1 - 2 * (yy + zz)) * len, 2 * (q.x * q.y + q.w * q.z) * len,
              2 * (q.x * q.z - q.w * q.y) * len);
}

/// Rotates v by unit quaternion q (v' = q v q*).
inline Vec3 rotate(const Quat& q, const Vec3& v) {
  const Vec3 u(q.x, q.y, q.z);
  const Vec3 t = 2.0 * glm::cross(u, v);
  return v + q.w * t + glm::cross(u, t);
}

/// Rotates v by the inverse of unit quaternion q.
inline Vec3 rotate_inv(const Quat& q, const Vec3& v) {
  const Vec3 u(-q.x, -q.y, -q.z);
  const Vec3 t = 2.0 * glm::cross(u, v);
  return v + q.w * t + glm::cross(u, t);
}

/// Shortest-arc rotation taking direction a to direction b (any lengths > 0).
inline Quat from_to(const Vec3& a, const Vec3& b) {
  const double la = glm::length(a), lb = glm::length(b);
  if (la < 1e-300 || lb < 1e-300) return Quat(1, 0, 0, 0);
  const Vec3 ua = a / la, ub = b / lb;
  const double d = glm::dot(ua, ub);
  if (d < -1 + 1e-12) {
    // opposite directions: half turn about any axis perpendicular to a
    Vec3 axis = glm::cross(ua, Vec3(1, 0, 0));
    if (glm::dot(axis, axis) < 1e-12) axis = glm::cross(ua, Vec3(0, 1, 0));
    axis = glm::normalize(axis);
    return Quat(0, axis.x, axis.y, axis.z);
  }
  const Vec3 c = glm::cross(ua, ub);
  return glm::normalize(Quat(1 + d, c.x, c.y, c.z));
}

/// Rotation vector (axis * angle, rad) of a unit quaternion, angle in [0, pi].
inline Vec3 quat_log(Quat q) {
  if (q.w < 0) q = -q;
  const Vec3 v(q.x, q.y, q.z);
  const double s = glm::length(v);
  if (s < 1e-12) return 2.0 * v;
  const double angle = 2 * std::atan2(s, q.w);
  return v * (angle / s);
}

/// Unit quaternion of rotation vector w (rad).
inline Quat quat_exp(const Vec3& w) {
  const double a = glm::length(w);
  if (a < 1e-12) return glm::normalize(Quat(1, 0.5 * w.x, 0.5 * w.y, 0.5 * w.z));
  const double s = std::sin(0.5 * a) / a;
  return Quat(std::cos(0.5 * a), w.x * s, w.y * s, w.z * s);
}

/// Wraps an angle to (-pi, pi].
inline double wrap_angle(double a) {
  if (a > kPi || a <= -kPi) {
    a = std::remainder(a, 2 * kPi);
    if (a <= -kPi) a += 2 * kPi;
  }
  return a;
}

/// Twist angle of q about +X (rad, in (-pi, pi]) and its swing angle from +X (rad, [0, pi]).
inline void swing_twist_angles(const Quat& q, double& swing, double& twist) {
  const double c = 1 - 2 * (q.y * q.y + q.z * q.z);
  swing = std::acos(std::clamp(c, -1.0, 1.0));
  const double n = std::sqrt(q.w * q.w + q.x * q.x);
  twist = n < 1e-12 ? 0.0 : wrap_angle(2 * std::atan2(q.x, q.w));
}

/// Projects a ball-joint rotation into its limits: twist about +X within [lo, hi],
/// swing of +X within a cone of half-angle `swing_limit`. Returns the unit result.
inline Quat clamp_ball(Quat q, double swing_limit, double lo, double hi) {
  q = glm::normalize(q);
  if (q.w < 0) q = -q;
  // split q = swing * twist, twist about +X
  const double n = std::sqrt(q.w * q.w + q.x * q.x);
  Quat twist(1, 0, 0, 0);
  if (n > 1e-12) twist = Quat(q.w / n, q.x / n, 0, 0);
  Quat swing = q * glm::conjugate(twist);
  // clamp the twist angle
  double t = n > 1e-12 ? wrap_angle(2 * std::atan2(twist.x, twist.w)) : 0.0;
  if (t < lo || t > hi) {
    t = std::clamp(t, lo, hi);
    twist = Quat(std::cos(0.5 * t), std::sin(0.5 * t), 0, 0);
  }
  // clamp the swing angle (swing has no x component: its axis is perpendicular to +X)
  if (swing.w < 0) swing = -swing;
  const double sw = std::clamp(swing.w, -1.0, 1.0);
  const double angle = 2 * std::acos(sw);
  if (angle > swing_limit) {
    const double s = std::sqrt(swing.y * swing.y + swing.z * swing.z);
    const double h = 0.5 * swing_limit;
    if (s > 1e-15)
      swing = Quat(std::cos(h), 0, swing.y * std::sin(h) / s, swing.z * std::sin(h) / s);
    else
      swing = Quat(std::cos(h), 0, std::sin(h), 0);
  } else {
    swing.x = 0;
    swing = glm::normalize(swing);
  }
  return swing * twist;
}

}  // namespace pba::ik::detail
