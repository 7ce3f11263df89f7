// Brute-force references for the narrow-phase tests: random poses, exact distances between
// boxes and capsule cores by enumerating feature pairs, and box-box penetration by all
// fifteen candidate axes.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "pba/collide/narrow_phase.h"

namespace pba::test_support {

/// A uniformly random rotation (Shoemake 1992) from a seeded engine.
inline Quat random_rotation(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double u1 = u(rng), u2 = u(rng), u3 = u(rng);
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  return glm::normalize(Quat(a * std::sin(2 * kPi * u2), a * std::cos(2 * kPi * u2), b * std::sin(2 * kPi * u3),
                             b * std::cos(2 * kPi * u3)));
}

/// Uniform vector in the cube [-s, s]^3.
inline Vec3 random_vec(std::mt19937_64& rng, double s) {
  std::uniform_real_distribution<double> u(-s, s);
  return Vec3(u(rng), u(rng), u(rng));
}

/// The 8 world corners of a box.
inline std::array<Vec3, 8> box_corners(const Vec3& h, const Pose& p) {
  std::array<Vec3, 8> c{};
  for (int i = 0; i < 8; ++i) c[std::size_t(i)] = apply(p, Vec3((i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z));
  return c;
}

/// The 12 world edges of a box, as corner index pairs.
inline constexpr int kBoxEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                         {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

/// Distance from a world point to a solid box (0 inside): the clamp in the box frame.
inline double point_box_distance(const Vec3& x, const Vec3& h, const Pose& p) {
  const Vec3 l = apply_inverse(p, x);
  return glm::length(l - glm::clamp(l, -h, h));
}

/// Exact distance between two segments, by minimising over a dense parameter grid refined
/// by the closed form (Lumelsky 1985): the unconstrained minimum clamped, and every
/// endpoint against the other segment.
inline double segment_distance(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2) {
  auto point_seg = [](const Vec3& x, const Vec3& a, const Vec3& b) {
    const Vec3 d = b - a;
    const double dd = glm::dot(d, d);
    const double t = dd > 0 ? std::clamp(glm::dot(x - a, d) / dd, 0.0, 1.0) : 0.0;
    return glm::length(x - (a + t * d));
  };
  double best = std::min({point_seg(p1, p2, q2), point_seg(q1, p2, q2), point_seg(p2, p1, q1), point_seg(q2, p1, q1)});
  // interior-interior: the common perpendicular, when its feet lie inside both segments
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = glm::dot(d1, d1), b = glm::dot(d1, d2), c = glm::dot(d1, r), e = glm::dot(d2, d2),
               f = glm::dot(d2, r);
  const double den = a * e - b * b;
  if (den > 1e-14 * a * e) {
    const double s = (b * f - c * e) / den, t = (a * f - b * c) / den;
    if (s > 0 && s < 1 && t > 0 && t < 1) best = std::min(best, glm::length((p1 + s * d1) - (p2 + t * d2)));
  }
  return best;
}

/// Exact distance between two separated boxes: the closest pair of points lies on a vertex
/// of one and the other solid, or on two edges (the feature pairs of convex polytopes).
inline double box_box_distance(const Vec3& ha, const Pose& pa, const Vec3& hb, const Pose& pb) {
  const auto ca = box_corners(ha, pa), cb = box_corners(hb, pb);
  double best = INFINITY;
  for (const Vec3& v : ca) best = std::min(best, point_box_distance(v, hb, pb));
  for (const Vec3& v : cb) best = std::min(best, point_box_distance(v, ha, pa));
  for (const auto& e : kBoxEdges)
    for (const auto& g : kBoxEdges)
      best = std::min(best, segment_distance(ca[std::size_t(e[0])], ca[std::size_t(e[1])], cb[std::size_t(g[0])],
                                             cb[std::size_t(g[1])]));
  return best;
}

/// Exact distance between a segment and a solid box (0 when they meet): the segment's ends
/// against the box and the segment against the box's 12 edges (a non-parallel segment's
/// interior is closest to an edge, never to a face interior); a segment crossing the box
/// (slab clipping, Liang and Barsky 1984) is at distance 0.
inline double segment_box_distance(const Vec3& p, const Vec3& q, const Vec3& h, const Pose& pb) {
  const Vec3 lp = apply_inverse(pb, p), lq = apply_inverse(pb, q), d = lq - lp;
  double t0 = 0, t1 = 1;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-300) {
      if (std::abs(lp[k]) > h[k]) t0 = 2;
      continue;
    }
    double a = (-h[k] - lp[k]) / d[k], b = (h[k] - lp[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a), t1 = std::min(t1, b);
  }
  if (t0 <= t1) return 0;
  const auto cb = box_corners(h, pb);
  double best = std::min(point_box_distance(p, h, pb), point_box_distance(q, h, pb));
  for (const auto& g : kBoxEdges)
    best = std::min(best, segment_distance(p, q, cb[std::size_t(g[0])], cb[std::size_t(g[1])]));
  return best;
}

/// Penetration of two overlapping boxes by the fifteen axes of the separating-axis test
/// (Gottschalk 1996): the three face normals of each box and the nine edge cross products.
/// The minimum overlap over them is the exact depth (the minimum over all directions is
/// attained at a face normal of the Minkowski difference, which is among them). `normal`
/// points from A to B; `second` is the next smallest overlap over distinct axes.
inline double box_box_sat_depth(const Vec3& ha, const Pose& pa, const Vec3& hb, const Pose& pb, Vec3& normal,
                                double& second) {
  const Mat3 ra = glm::mat3_cast(pa.rotation), rb = glm::mat3_cast(pb.rotation);
  std::array<Vec3, 15> axes{};
  int n = 0;
  for (int i = 0; i < 3; ++i) axes[std::size_t(n++)] = ra[i];
  for (int i = 0; i < 3; ++i) axes[std::size_t(n++)] = rb[i];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const Vec3 c = glm::cross(ra[i], rb[j]);
      if (glm::length(c) > 1e-6) axes[std::size_t(n++)] = glm::normalize(c);
    }
  const auto ca = box_corners(ha, pa), cb = box_corners(hb, pb);
  double best = INFINITY;
  second = INFINITY;
  for (int k = 0; k < n; ++k) {
    const Vec3 L = axes[std::size_t(k)];
    double amin = INFINITY, amax = -INFINITY, bmin = INFINITY, bmax = -INFINITY;
    for (const Vec3& v : ca) amin = std::min(amin, glm::dot(v, L)), amax = std::max(amax, glm::dot(v, L));
    for (const Vec3& v : cb) bmin = std::min(bmin, glm::dot(v, L)), bmax = std::max(bmax, glm::dot(v, L));
    // overlap moving B along +L (amax - bmin) or along -L (bmax - amin)
    const double up = amax - bmin, down = bmax - amin;
    const double o = std::min(up, down);
    const Vec3 dir = up <= down ? L : -L;
    if (o < best) {
      second = best;
      best = o;
      normal = dir;
    } else if (o < second) {
      second = o;
    }
  }
  return best;
}

}  // namespace pba::test_support
