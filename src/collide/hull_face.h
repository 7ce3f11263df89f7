// Private: whether a point of a hull face's plane lies on the face, for the point queries
// (point_query.cpp) and the point contact (point_contact_shapes.cpp).
#pragma once

#include <cstdint>

#include "pba/collide/shape.h"

namespace pba::detail {

/// True when `p`, a point in the plane of face `f` of `h` (local frame), lies inside the
/// face's loop or on its boundary: left of every edge seen from outside (the loop is
/// counter-clockwise about the outward normal).
inline bool on_hull_face(const ConvexHull& h, std::uint32_t f, const Vec3& p) {
  const auto v = h.vertices();
  const auto e = h.edges();
  const ConvexHull::Face& face = h.faces()[f];
  std::uint32_t k = face.edge;
  do {
    const Vec3 a = v[e[k].origin], b = v[e[e[k].next].origin];
    if (glm::dot(glm::cross(b - a, p - a), face.normal) < 0) return false;
    k = e[k].next;
  } while (k != face.edge);
  return true;
}

}  // namespace pba::detail
