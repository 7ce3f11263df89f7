// Forcer volumes: validation, drawing, and the double-precision reference of the forcer
// force (the kernels use a float copy). Colliders live in the collide module.
#include <cmath>
#include <string>

#include "kernels.h"
#include "pba/particles.h"

namespace pba {

void Forcer::validate(std::string_view where) const {
  if (!is_finite(pose.position)) require_finite(pose.position, field_path(where, "position"));
  // (field_path builds a string: only when a check fails, so a step that validates its
  // forcers does not allocate)
  if (!detail::is_unit_quat(pose.rotation))
    require_unit_quat(pose.rotation, field_path(where, "rotation"));
  if (shape == ForcerShape::Box) {
    if (!(std::isfinite(half_extents.x) && (half_extents.x) > 0))
      require_positive(half_extents.x, field_path(where, "half_extents.x"));
    if (!(std::isfinite(half_extents.y) && (half_extents.y) > 0))
      require_positive(half_extents.y, field_path(where, "half_extents.y"));
    if (!(std::isfinite(half_extents.z) && (half_extents.z) > 0))
      require_positive(half_extents.z, field_path(where, "half_extents.z"));
  } else {
    if (!(std::isfinite(radius) && (radius) > 0)) require_positive(radius, field_path(where, "radius"));
    if (shape == ForcerShape::Cylinder)
      if (!(std::isfinite(half_height) && (half_height) > 0))
        require_positive(half_height, field_path(where, "half_height"));
  }
  if (!is_finite(direction)) require_finite(direction, field_path(where, "direction"));
  if (kind == ForcerKind::Fan && glm::length(direction) == 0)
    throw Error(field_path(where, "direction") + ": must be non-zero, got (0, 0, 0)");
  if (!std::isfinite(strength)) require_finite(strength, field_path(where, "strength"));
  if (!std::isfinite(pull)) require_finite(pull, field_path(where, "pull"));
  if (!(std::isfinite(softening) && (softening) > 0)) require_positive(softening, field_path(where, "softening"));
  if (!(std::isfinite(pulse_period) && (pulse_period) >= 0))
    require_non_negative(pulse_period, field_path(where, "pulse_period"));
  if (!((pulse_duration) >= (0) && (pulse_duration) <= (pulse_period > 0 ? pulse_period : 1e300)))
    require_in_range(pulse_duration, 0, pulse_period > 0 ? pulse_period : 1e300, field_path(where, "pulse_duration"));
  // the forcer kernels work in floats: finite doubles a float cannot hold are refused too
  if (!fits_float(pose.position)) require_float(pose.position, field_path(where, "position"));
  if (!fits_float(half_extents)) require_float(half_extents, field_path(where, "half_extents"));
  if (!fits_float(radius)) require_float(radius, field_path(where, "radius"));
  if (!fits_float(half_height)) require_float(half_height, field_path(where, "half_height"));
  if (!fits_float(direction)) require_float(direction, field_path(where, "direction"));
  if (!fits_float(strength)) require_float(strength, field_path(where, "strength"));
  if (!fits_float(pull)) require_float(pull, field_path(where, "pull"));
  if (!fits_float(softening)) require_float(softening, field_path(where, "softening"));
}

bool Forcer::active(double t) const {
  if (pulse_period <= 0) return true;
  // on for the first pulse_duration of every period
  const double phase = t - std::floor(t / pulse_period) * pulse_period;
  return phase < pulse_duration;
}

Vec3 Forcer::force_at(const Vec3& p, double t) const {
  if (!active(t)) return Vec3(0);
  // the offset in the local frame and the inside test
  const Quat q = glm::normalize(pose.rotation);
  const Vec3 d = p - pose.position;
  const Vec3 l = glm::conjugate(q) * d;
  bool inside = false;
  switch (shape) {
    case ForcerShape::Box:
      inside = std::abs(l.x) <= half_extents.x && std::abs(l.y) <= half_extents.y && std::abs(l.z) <= half_extents.z;
      break;
    case ForcerShape::Cylinder:
      inside = l.x * l.x + l.z * l.z <= radius * radius && std::abs(l.y) <= half_height;
      break;
    case ForcerShape::Sphere: inside = glm::dot(l, l) <= radius * radius; break;
  }
  if (!inside) return Vec3(0);
  // the force by kind
  switch (kind) {
    case ForcerKind::Fan: return q * glm::normalize(direction) * strength;
    case ForcerKind::Vortex: {
      const Vec3 axis = q * Vec3(0, 1, 0);
      const Vec3 radial = d - glm::dot(d, axis) * axis;
      const double r = glm::length(radial);
      if (r <= 1e-6) return Vec3(0);
      return (strength * glm::cross(axis, radial) - pull * radial) / r;
    }
    case ForcerKind::Attractor: {
      const double dist = glm::length(d);
      return -strength * d / std::max(dist, softening);
    }
  }
  return Vec3(0);
}

void Forcer::draw(DebugDraw& draw, Color c, const DrawFlags& flags) const {
  if (!flags.forcers) return;
  const Quat q = glm::normalize(pose.rotation);
  const Vec3 o = pose.position;
  // the volume's outline
  if (shape == ForcerShape::Box) {
    const Vec3 h = half_extents;
    for (int a = 0; a < 3; ++a)
      for (int s1 = -1; s1 <= 1; s1 += 2)
        for (int s2 = -1; s2 <= 1; s2 += 2) {
          Vec3 p0(0), p1(0);
          const int b = (a + 1) % 3, cc = (a + 2) % 3;
          p0[a] = -h[a], p1[a] = h[a];
          p0[b] = p1[b] = s1 * h[b];
          p0[cc] = p1[cc] = s2 * h[cc];
          draw.line(o + q * p0, o + q * p1, c);
        }
  } else {
    const double hh = shape == ForcerShape::Cylinder ? half_height : 0;
    const int segments = 24;
    for (int i = 0; i < segments; ++i) {
      const double a0 = 2 * kPi * i / segments, a1 = 2 * kPi * (i + 1) / segments;
      for (double y : {-hh, hh}) {
        const Vec3 p0(radius * std::cos(a0), y, radius * std::sin(a0));
        const Vec3 p1(radius * std::cos(a1), y, radius * std::sin(a1));
        draw.line(o + q * p0, o + q * p1, c);
      }
    }
  }
  // what it does
  if (kind == ForcerKind::Fan) draw.arrow(o, o + q * glm::normalize(direction) * 0.5, 0.1, c);
  if (kind == ForcerKind::Vortex) draw.arrow(o, o + q * Vec3(0, 0.5, 0), 0.1, c);
  if (kind == ForcerKind::Attractor) draw.sphere(o, 0.05, c);
}

}  // namespace pba
