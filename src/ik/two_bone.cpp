// Two-bone limb IK with a pole vector: the law of cosines gives the elbow's interior
// angle, a shortest-arc turn about the shoulder aims the limb at the target, and a
// turn about the shoulder-target axis puts the elbow on the pole's side.
// A stateless job (TwoBoneJob, after ozz-animation's IKTwoBoneJob) and the
// Method::two_bone adapter for skeletons.
#include <algorithm>
#include <cmath>

#include "ik/ik_access.h"
#include "ik/ik_math.h"
#include "pba/ik.h"

namespace pba::ik {

using detail::kPi;

namespace {

// limb length at interior elbow angle phi: c^2 = a^2 + b^2 - 2ab cos(phi)
double limb_length(double a, double b, double cos_phi) {
  return std::sqrt(std::max(0.0, a * a + b * b - 2 * a * b * cos_phi));
}

// the bend that takes the elbow from its current interior angle phi0 to the angle phi1
// that puts the end at `dist` from the start (law of cosines), as the cosine and sine of
// the signed rotation about `axis`. Only square roots: cos(phi1 - phi0) and
// sin(phi1 - phi0) from the angle-difference identities, with sin(phi) >= 0 on [0, pi].
struct Bend {
  double c = 1, s = 0;  // cosine and sine of the rotation about the axis
  double reach = 0;     // start-to-end distance after the bend (m)
  bool reached = false;
};
Bend bend(const Vec3& u, const Vec3& v, const Vec3& axis, double dist, double cos_min, double cos_max) {
  Bend out;
  const double a = glm::length(u), b = glm::length(v);
  // current interior angle (and which way round the axis it opens)
  const double side = glm::dot(axis, glm::cross(u, v)) >= 0 ? 1.0 : -1.0;
  const double c0 = std::clamp(glm::dot(u, v) / (a * b), -1.0, 1.0);
  const double s0 = std::sqrt(std::max(0.0, 1 - c0 * c0));
  // wanted interior angle, clamped to the limb's range
  const double cmin = cos_min == 1 ? std::abs(a - b) : limb_length(a, b, cos_min);
  const double cmax = cos_max == -1 ? a + b : limb_length(a, b, cos_max);
  out.reached = dist >= cmin - 1e-9 * (a + b) && dist <= cmax + 1e-9 * (a + b);
  const double c = std::clamp(dist, cmin, cmax);
  out.reach = c;
  const double c1 = std::clamp((a * a + b * b - c * c) / (2 * a * b), cos_max, cos_min);
  const double s1 = std::sqrt(std::max(0.0, 1 - c1 * c1));
  // rotation by side * (phi1 - phi0)
  out.c = c1 * c0 + s1 * s0;
  out.s = side * (s1 * c0 - c1 * s0);
  return out;
}

// unit quaternion of the rotation about unit `axis` whose cosine and sine are (c, s):
// (1 + c, s axis) is 2 cos(angle / 2) times it, so one normalisation suffices
Quat axis_rotation(const Vec3& axis, double c, double s) {
  if (1 + c < 1e-12) return Quat(0, axis.x, axis.y, axis.z);
  const double k = 1 / std::sqrt((1 + c) * (1 + c) + s * s);
  return Quat((1 + c) * k, axis.x * s * k, axis.y * s * k, axis.z * s * k);
}

// rotation about `start` taking `end` toward `target`, then turning about the
// start-target line so `mid` lies in the half-plane of `pole`
// (`end_len` = |end - start| and `tl` = |target - start| when the caller knows them, else < 0)
Quat aim(const Vec3& start, const Vec3& mid, const Vec3& end, const Vec3& target, const Vec3& pole,
         double end_len = -1, double tl = -1) {
  const Vec3 to_target = target - start;
  const Vec3 e = end - start;
  if (end_len < 0) end_len = glm::length(e);
  if (tl < 0) tl = glm::length(to_target);
  // shortest arc from e to the target direction: normalize(|e||t| + e.t, e x t)
  Quat r1;
  const double w1 = end_len * tl + glm::dot(e, to_target);
  if (w1 > 1e-12 * end_len * tl) {
    const Vec3 x = glm::cross(e, to_target);
    r1 = Quat(w1, x.x, x.y, x.z) * (1 / std::sqrt(w1 * w1 + glm::dot(x, x)));
  } else {
    r1 = detail::from_to(e, to_target);
  }
  if (tl < 1e-12) return r1;
  const Vec3 t = to_target / tl;
  Vec3 m = detail::rotate(r1, mid - start);
  Vec3 p = pole - start;
  m -= glm::dot(m, t) * t;
  p -= glm::dot(p, t) * t;
  if (glm::dot(m, m) < 1e-24 || glm::dot(p, p) < 1e-24) return r1;
  // both lie in the plane normal to t, so the shortest arc between them turns about t
  const Vec3 cr = glm::cross(m, p);
  const double w = std::sqrt(glm::dot(m, m) * glm::dot(p, p)) + glm::dot(m, p);
  const Quat r2 = w > 1e-12 * glm::dot(m, m) ? Quat(w, cr.x, cr.y, cr.z) * (1 / std::sqrt(w * w + glm::dot(cr, cr)))
                                             : Quat(0, t.x, t.y, t.z);
  return detail::qmul(r2, r1);
}

}  // namespace

bool TwoBoneJob::Validate() const {
  for (const Vec3* p : {&start, &mid, &end, &target, &pole, &mid_axis})
    if (!is_finite(*p)) return false;
  // squared lengths: no square roots in validation
  if (std::abs(glm::dot(mid_axis, mid_axis) - 1) > 2e-6) return false;
  const Vec3 u = mid - start, v = end - mid;
  if (!(glm::dot(u, u) > 0) || !(glm::dot(v, v) > 0)) return false;
  if (!(weight >= 0 && weight <= 1)) return false;
  if (!(min_mid_angle >= 0 && min_mid_angle < max_mid_angle && max_mid_angle <= kPi)) return false;
  return true;
}

bool TwoBoneJob::Run() {
  if (!Validate()) return false;
  // bend the mid joint about its axis (law of cosines)
  const double cos_min = min_mid_angle == 0 ? 1.0 : std::cos(min_mid_angle);
  const double cos_max = max_mid_angle == kPi ? -1.0 : std::cos(max_mid_angle);
  const double dist = glm::length(target - start);
  const Bend bd = bend(start - mid, end - mid, mid_axis, dist, cos_min, cos_max);
  reached = bd.reached;
  const Quat cm = axis_rotation(mid_axis, bd.c, bd.s);
  const Vec3 end1 = mid + detail::rotate(cm, end - mid);
  // aim the bent limb, elbow toward the pole (both distances are known: no square roots)
  const Quat cs = aim(start, mid, end1, target, pole, bd.reach, dist);
  // partial weight blends each correction from identity
  const Quat id(1, 0, 0, 0);
  start_correction = weight >= 1 ? cs : glm::slerp(id, cs, weight);
  mid_correction = weight >= 1 ? cm : glm::slerp(id, cm, weight);
  return true;
}

namespace detail {

SolveResult solve_two_bone(Skeleton& s, const SolverSettings&) {
  using A = SolverAccess;
  const EffectorDef& ef = s.effector(0);
  const int e = ef.bone, m = s.parents()[e];
  const auto parents = s.parents();
  auto frame = [&](int i) {
    const int p = parents[i];
    return (p >= 0 ? s.world_rotations()[p] : s.root_rotation()) * A::rest(s)[i];
  };
  // bend the elbow hinge by the law of cosines, within the hinge limits
  const Vec3 start = s.starts()[m], mid = s.starts()[e], end = s.tips()[e];
  const Vec3 axis = detail::rotate(frame(e), A::axis(s)[e]);
  const Bend bd = bend(start - mid, end - mid, axis, glm::length(ef.target - start), 1.0, -1.0);
  A::angle(s)[e] += std::atan2(bd.s, bd.c);
  A::clamp_joint(s, e);
  s.forward_kinematics();
  // turn the shoulder ball joint to aim the limb, elbow toward the pole
  const Vec3 pole = ef.pole ? *ef.pole : s.starts()[e];
  const Quat cs = aim(start, s.starts()[e], s.tips()[e], ef.target, pole);
  const Quat F = frame(m);
  A::q(s)[m] = glm::conjugate(F) * cs * F * A::q(s)[m];
  A::clamp_joint(s, m);
  s.forward_kinematics();
  SolveResult r;
  r.iterations = 1;
  return r;
}

}  // namespace detail
}  // namespace pba::ik
