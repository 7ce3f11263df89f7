// The closest points of a segment and a box in closed form (capsule-box pairs, manifold.cpp).
//
// In the box's frame the squared distance from p(t) = p + t (q - p) to the box is
// f(t) = sum_k e_k(t)^2, e_k the coordinate's excess over its slab [-h_k, h_k] (0 inside).
// Each term is convex and once differentiable, so f is convex with a continuous,
// non-decreasing half slope g(t) = sum_k e_k(t) d_k, and it is one quadratic between the
// (at most six) values of t where a coordinate crosses a slab face. The minimum is at 0 when
// g(0) >= 0, at 1 when g(1) <= 0, else inside the one piece between the last breakpoint
// where g < 0 and the first where g >= 0 (g is monotone, so no breakpoint lies between
// them): there the coordinates outside their slabs are fixed and g's root is a division.
#include <algorithm>
#include <cmath>

#include "narrow_internal.h"
#include "pba/core.h"

namespace pba {

SegmentBoxClosest narrow::segment_box_closest_unchecked(const Vec3& p, const Vec3& q, const Vec3& h) {
  const Vec3 d = q - p;
  // half the slope of f at t
  auto slope = [&](double t) {
    double s = 0;
    for (int k = 0; k < 3; ++k) {
      const double x = p[k] + t * d[k];
      s += (x - std::clamp(x, -h[k], h[k])) * d[k];
    }
    return s;
  };
  double t = 0;
  if (slope(0) < 0) {
    // (g(1) = 0 exactly: a flat stretch ending at q, whose start the bracket below finds, as
    // the header's rule asks of points that are not unique)
    if (slope(1) < 0) {
      t = 1;
    } else {
      // narrow [lo, hi] to the piece holding g's root: a breakpoint inside the bracket
      // replaces the end whose sign of g it shares
      double lo = 0, hi = 1;
      for (int k = 0; k < 3; ++k) {
        if (d[k] == 0) continue;
        for (const double face : {-h[k], h[k]}) {
          const double b = (face - p[k]) / d[k];
          if (!(b > lo && b < hi)) continue;
          if (slope(b) < 0) lo = b;
          else hi = b;
        }
      }
      // on that piece the coordinates outside their slabs (at its middle) make g linear:
      // g(t) = sum (p_k - s_k h_k) d_k + t sum d_k^2, s_k the side they are out on
      const double mid = 0.5 * (lo + hi);
      double num = 0, den = 0;
      for (int k = 0; k < 3; ++k) {
        const double x = p[k] + mid * d[k];
        const double face = x > h[k] ? h[k] : (x < -h[k] ? -h[k] : x);
        if (face == x) continue;
        num += (p[k] - face) * d[k];
        den += d[k] * d[k];
      }
      // (den > 0 whenever g changes sign on the piece; rounding may leave it 0 on a piece
      // shorter than the breakpoints' rounding: then its low end)
      t = den > 0 ? std::clamp(-num / den, lo, hi) : lo;
    }
  }
  SegmentBoxClosest r;
  r.t = t;
  r.on_segment = t == 1 ? q : p + t * d;
  r.on_box = glm::clamp(r.on_segment, -h, h);
  const Vec3 e = r.on_segment - r.on_box;
  r.distance2 = glm::dot(e, e);
  return r;
}

SegmentBoxClosest segment_box_closest(const Vec3& p, const Vec3& q, const Vec3& h) {
  // one test for the usual input; the named checks only when it fails
  const bool ok = std::isfinite(p.x + p.y + p.z + q.x + q.y + q.z) && h.x > 0 && h.y > 0 && h.z > 0 &&
                  std::isfinite(h.x + h.y + h.z);
  if (!ok) {
    require_finite(p, "segment_box_closest: p");
    require_finite(q, "segment_box_closest: q");
    for (int k = 0; k < 3; ++k) {
      require_finite(h[k], "segment_box_closest: half_extents");
      require_positive(h[k], "segment_box_closest: half_extents");
    }
  }
  return narrow::segment_box_closest_unchecked(p, q, h);
}

}  // namespace pba
