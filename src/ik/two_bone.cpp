// Two-bone limb IK with a pole vector: the law of cosines gives the elbow's interior
// angle, a shortest-arc turn about the shoulder aims the limb at the target, and a
// turn about the shoulder-target axis puts the elbow on the pole's side.
// A stateless job (TwoBoneJob, after ozz-animation's IKTwoBoneJob) and the
// Method::TwoBone adapter for skeletons.
//
// TwoBoneJob::run is written for latency: no trigonometric call (but the cosines of elbow
// limits, when there are any), every normalisation as sqrt(x) (1 / x) (the
// division beside the root rather than after it), sines from cross products rather than
// sqrt(1 - cos^2), and the intermediate shortest-arc quaternions left unnormalised (a
// quaternion of norm k rotates a vector and scales it by k^2, which changes no direction),
// so the job normalises once, at the end.
#include <algorithm>
#include <cmath>

#include "ik/ik_access.h"
#include "ik/ik_math.h"
#include "pba/ik.h"

namespace pba::ik {


namespace {

// 1 / sqrt(x) for x > 0, with the division running beside the square root
inline double rsqrt(double x) { return std::sqrt(x) * (1 / x); }

// The bend that takes the elbow from its current interior angle phi0 (between
// u = start - mid and v = end - mid) to the angle phi1 that puts the end at distance
// sqrt(dist2) from the start (law of cosines, c^2 = a^2 + b^2 - 2ab cos phi1), as the cosine
// and sine of the signed rotation about `axis` (unit, normal to the plane of u and v):
// cos(phi1 - phi0) and sin(phi1 - phi0) from the angle-difference identities, with
// cos phi0 = u.v / ab and sin phi0 = |u x v| / ab (both roots run side by side).
struct Bend {
  double c = 1, s = 0;  // cosine and sine of the rotation about the axis
  double reach2 = 0;    // squared start-to-end distance after the bend (m^2)
  bool reached = false;
};
// With `Perpendicular` the axis is known to be normal to the plane (TwoBoneJob's contract),
// so |u x v| = |axis . (u x v)| needs no square root.
template <bool Perpendicular>
Bend bend(const Vec3& u, const Vec3& v, const Vec3& axis, double dist2, double cos_min, double cos_max) {
  Bend out;
  // lengths, and the current angle's cosine and sine (which way round the axis it opens)
  const double a2 = glm::dot(u, u), b2 = glm::dot(v, v), uv = glm::dot(u, v);
  const Vec3 w = glm::cross(u, v);
  const double aw = glm::dot(axis, w);
  const double side = aw >= 0 ? 1.0 : -1.0;
  const double ab = std::sqrt(a2 * b2), sw = Perpendicular ? std::abs(aw) : std::sqrt(glm::dot(w, w));
  const double inv_ab = 1 / ab;
  const double c0 = std::clamp(uv * inv_ab, -1.0, 1.0), s0 = std::min(1.0, sw * inv_ab);
  // the distances the elbow range allows, a^2 + b^2 - 2ab cos(phi) for phi in it; reached
  // within about 1e-9 of the limb's length, 2e-9 (a + b)^2 in squared distance
  const double sum = a2 + b2;
  const double lo2 = sum - 2 * ab * cos_min, hi2 = sum - 2 * ab * cos_max;
  const double slack = 2e-9 * (sum + 2 * ab);
  out.reached = dist2 >= lo2 - slack && dist2 <= hi2 + slack;
  const double c2 = std::clamp(dist2, std::max(lo2, 0.0), hi2);
  out.reach2 = c2;
  // wanted interior angle, clamped to the range
  const double c1 = std::clamp((sum - c2) * (0.5 * inv_ab), cos_max, cos_min);
  const double s1 = std::sqrt(std::max(0.0, 1 - c1 * c1));
  // rotation by side * (phi1 - phi0)
  out.c = c1 * c0 + s1 * s0;
  out.s = side * (s1 * c0 - c1 * s0);
  return out;
}

// v rotated about unit `axis` by the angle whose cosine and sine are (c, s) (Rodrigues),
// for v normal to the axis (its component along the axis, which would stay, is zero)
inline Vec3 rotate_cs_normal(const Vec3& v, const Vec3& axis, double c, double s) {
  return v * c + glm::cross(axis, v) * s;
}

// unit quaternion of the rotation about unit `axis` whose cosine and sine are (c, s):
// (1 + c, s axis) is 2 cos(angle / 2) times it, so one normalisation suffices
Quat axis_rotation(const Vec3& axis, double c, double s) {
  if (1 + c < 1e-12) return Quat(0, axis.x, axis.y, axis.z);
  const double k = rsqrt((1 + c) * (1 + c) + s * s);
  return Quat((1 + c) * k, axis.x * s * k, axis.y * s * k, axis.z * s * k);
}

// |q|^2 q* v q (not normalised): v rotated by q / |q| and scaled by |q|^2
inline Vec3 rotate_scaled(const Quat& q, const Vec3& v) {
  const Vec3 r(q.x, q.y, q.z);
  return v * (q.w * q.w - glm::dot(r, r)) + r * (2 * glm::dot(r, v)) + glm::cross(r, v) * (2 * q.w);
}

// The unit rotation about the shoulder that takes e (= end - start) onto t (= target -
// start), then turns about t so that m (= mid - start) lies in the half-plane of
// p (= pole - start). `et` = |e| |t|; `t2` = |t|^2; `p2` = |p|^2.
Quat aim(const Vec3& m, const Vec3& e, const Vec3& t, const Vec3& p, double et, double t2, double p2) {
  // shortest arc from e to t: (|e||t| + e.t, e x t), unnormalised
  Quat r1;
  const double w1 = et + glm::dot(e, t);
  if (w1 > 1e-12 * et) {
    const Vec3 x = glm::cross(e, t);
    r1 = Quat(w1, x.x, x.y, x.z);
  } else {
    r1 = detail::from_to(e, t);  // opposite directions (or a zero vector)
  }
  auto unit = [](const Quat& q) { return q * rsqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z); };
  if (!(t2 > 1e-24)) return unit(r1);
  // the components of the turned m and of p normal to t, both scaled by positive factors
  const Vec3 m1 = rotate_scaled(r1, m);
  const Vec3 mn = m1 * t2 - t * glm::dot(m1, t);
  const Vec3 pn = p * t2 - t * glm::dot(p, t);
  const double mm = glm::dot(mn, mn), pp = glm::dot(pn, pn);
  // no half-plane when either lies on the line (to 1e-12 of its length)
  const double tt2 = t2 * t2;
  if (!(mm > 1e-24 * glm::dot(m1, m1) * tt2) || !(pp > 1e-24 * p2 * tt2)) return unit(r1);
  // both lie in the plane normal to t, so the shortest arc between them turns about t
  const double mp = std::sqrt(mm * pp);
  const double w2 = mp + glm::dot(mn, pn);
  Quat r2;
  if (w2 > 1e-12 * mp) {
    const Vec3 x = glm::cross(mn, pn);
    r2 = Quat(w2, x.x, x.y, x.z);
  } else {
    r2 = Quat(0, t.x, t.y, t.z);  // a half turn about t
  }
  return unit(detail::qmul(r2, r1));
}

// The squared lengths every check and the solve need, computed once: the upper and lower
// bones (u = start - mid, v = end - mid), the shoulder-target and shoulder-pole vectors, and
// the hinge axis. Their sum is finite exactly when every input is (and small enough, below
// about 1e150 m, for the squares to be finite), which checks all 18 inputs in one test.
struct Limb {
  Vec3 u, v, t, p;
  double a2, b2, t2, p2, n2;
  explicit Limb(const TwoBoneJob& j)
      : u(j.start - j.mid), v(j.end - j.mid), t(j.target - j.start), p(j.pole - j.start),
        a2(glm::dot(u, u)), b2(glm::dot(v, v)), t2(glm::dot(t, t)), p2(glm::dot(p, p)),
        n2(glm::dot(j.mid_axis, j.mid_axis)) {}
  bool valid(const TwoBoneJob& j) const {
    if (!std::isfinite(a2 + b2 + t2 + p2 + n2)) return false;
    if (std::abs(n2 - 1) > 2e-6) return false;
    if (!(a2 > 0) || !(b2 > 0)) return false;
    if (!(j.weight >= 0 && j.weight <= 1)) return false;
    return j.min_mid_angle >= 0 && j.min_mid_angle < j.max_mid_angle && j.max_mid_angle <= kPi;
  }
};

}  // namespace

bool TwoBoneJob::validate() const { return Limb(*this).valid(*this); }

bool TwoBoneJob::run() { return detail::run_two_bone(*this); }

namespace detail {

// TwoBoneJob::run, compiled for AVX2 and for the baseline (GCC function multi-versioning:
// the three-operand encoding spares the register copies of the two-operand one); both give
// the same bits (-ffp-contract=off: no fused multiply-adds)
PBA_CLONES bool run_two_bone(TwoBoneJob& job) {
  const Limb l(job);
  if (!l.valid(job)) return false;
  const double min_mid_angle = job.min_mid_angle, max_mid_angle = job.max_mid_angle;
  const Vec3& mid_axis = job.mid_axis;
  const double weight = job.weight;
  // bend the mid joint about its axis (law of cosines); the elbow range as cosines
  const double cos_min = min_mid_angle == 0 ? 1.0 : std::cos(min_mid_angle);
  const double cos_max = max_mid_angle == kPi ? -1.0 : std::cos(max_mid_angle);
  const Bend bd = bend<true>(l.u, l.v, mid_axis, l.t2, cos_min, cos_max);
  job.reached = bd.reached;
  // the bent limb's end, relative to the start (rotated about the axis without a quaternion),
  // and |e| |t| from the law of cosines' squared reach
  const Vec3 e = rotate_cs_normal(l.v, mid_axis, bd.c, bd.s) - l.u;
  const double et = std::sqrt(bd.reach2 * l.t2);
  // aim the bent limb, elbow toward the pole
  const Quat cs = aim(-l.u, e, l.t, l.p, et, l.t2, l.p2);
  const Quat cm = axis_rotation(mid_axis, bd.c, bd.s);
  // partial weight blends each correction from identity
  const Quat id(1, 0, 0, 0);
  detail::put(job.start_correction, weight >= 1 ? cs : glm::slerp(id, cs, weight));
  detail::put(job.mid_correction, weight >= 1 ? cm : glm::slerp(id, cm, weight));
  return true;
}

SolveResult solve_two_bone(Skeleton& s, const SolverSettings&) {
  using A = SolverAccess;
  const EffectorDef& ef = s.effector(0);
  const int e = ef.bone, m = s.parents()[e];
  const auto parents = s.parents();
  auto frame = [&](int i) {
    const int p = parents[i];
    const Quat base = p >= 0 ? s.world_rotations()[p] : s.root_rotation();
    return detail::qmul(base, A::rest(s)[i]);
  };
  // bend the elbow hinge by the law of cosines, within the hinge limits
  const Vec3 start = s.starts()[m], mid = s.starts()[e], end = s.tips()[e];
  const Quat Fe = frame(e);
  const Vec3 axis = detail::rotate(Fe, A::axis(s)[e]);
  const Vec3 t = ef.target - start;
  const double t2 = glm::dot(t, t);
  const Bend bd = bend<false>(start - mid, end - mid, axis, t2, 1.0, -1.0);
  // the new angle (wrapped to (-pi, pi]); within the limits, the joint rotation is the old
  // one turned by the bend, (1 + c, s axis) normalised, which needs no sine or cosine and
  // leaves the angle's arc tangent off the path to the result; else clamp_joint projects it
  double& angle = A::angle(s)[e];
  const double a = detail::wrap_angle(angle + std::atan2(bd.s, bd.c));
  Vec3 end1;
  if (!A::limited(s)[e] || (a >= A::lo(s)[e] && a <= A::hi(s)[e])) {
    const Quat qe = detail::qmul(axis_rotation(A::axis(s)[e], bd.c, bd.s), A::q(s)[e]);
    detail::put(A::q(s)[e], qe * rsqrt(qe.w * qe.w + qe.x * qe.x + qe.y * qe.y + qe.z * qe.z));
    angle = a;
    // the end turned about the world axis (Rodrigues), without waiting for the rotation
    const Vec3 v = end - mid;
    end1 = mid + v * bd.c + glm::cross(axis, v) * bd.s + axis * (glm::dot(axis, v) * (1 - bd.c));
  } else {
    angle = a;
    A::clamp_joint(s, e);
    end1 = mid + detail::rotate_x(detail::qmul(Fe, A::q(s)[e]), s.lengths()[e]);
  }
  // turn the shoulder ball joint to aim the limb, elbow toward the pole
  const Vec3 p = (ef.pole ? *ef.pole : mid) - start;
  const Vec3 el = end1 - start;
  const Quat cs = aim(mid - start, el, t, p, std::sqrt(glm::dot(el, el) * t2), t2, glm::dot(p, p));
  const Quat F = frame(m);
  const Quat qm = detail::qmul(detail::qmul(glm::conjugate(F), cs), detail::qmul(F, A::q(s)[m]));
  if (A::limited(s)[m]) {
    detail::put(A::q(s)[m], qm);
    A::clamp_joint(s, m);
  } else {
    detail::put(A::q(s)[m], qm * rsqrt(qm.w * qm.w + qm.x * qm.x + qm.y * qm.y + qm.z * qm.z));
  }
  s.forward_kinematics();
  SolveResult r;
  r.iterations = 1;
  return r;
}

}  // namespace detail
}  // namespace pba::ik
