// Private to the library: a ball's and a box's world bounds, inline. pba::bounds (shape.cpp)
// makes them with these, and so does the rigid broad phase (RigidContacts::update_proxies,
// rigid/contact_pairs.cpp), which bounds every awake body's shapes each step: through the call
// of pba::bounds (its saved registers and its switch) and a call of rotated_half, a ball cost
// it 48 instructions and a box 142 (the rain's landing steps, 10,000 bodies awake).
#pragma once

#include <cmath>

#include "pba/collide/shape.h"

namespace pba::detail {

/// The world half widths (m) of a box of half extents `h` (m) turned by the unit quaternion
/// `q`: |R| h, R its rotation matrix (the box's bounds are its centre plus and minus these).
[[gnu::always_inline]] inline Vec3 rotated_half(const Quat& q, const Vec3& h) {
  const Mat3 r = glm::mat3_cast(q);
  Vec3 out(0.0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[i] += std::abs(r[j][i]) * h[j];
  return out;
}

/// bounds(s, p) (m), its bits, with a ball's and a box's made inline; the other kinds through
/// the call.
[[gnu::always_inline]] inline Aabb shape_bounds(const ColliderShape& s, const Pose& p) {
  if (s.type == ShapeType::Sphere) return {p.position - Vec3(s.radius), p.position + Vec3(s.radius)};
  if (s.type == ShapeType::Box) {
    const Vec3 h = rotated_half(p.rotation, s.half_extents);
    return {p.position - h, p.position + h};
  }
  return bounds(s, p);
}

}  // namespace pba::detail
