// Face clipping and contact reduction: the incident polygon clipped by the side planes of
// the reference face (Sutherland and Hodgman 1974), each output point labelled by the two
// features that made it, then at most four points kept (Gregorius 2015, "Robust Contact
// Creation for Physics Simulations", GDC): the deepest, the farthest from it, the one
// spanning the largest triangle with them and the one adding the most area outside it.
#include <cmath>

#include "narrow_internal.h"

namespace pba::narrow {

void world_face(const Poly& poly, const Pose& pose, std::uint32_t f, WorldFace& out) {
  // walk the face loop, vertices to world
  const HullFace& F = poly.faces[f];
  const Mat3 R = glm::mat3_cast(pose.rotation);
  out.normal = R * F.normal;
  out.offset = F.offset + glm::dot(out.normal, pose.position);
  out.count = 0;
  std::uint32_t e = F.edge;
  do {
    const HalfEdge& h = poly.edges[e];
    ClipPoint& p = out.pts[std::size_t(out.count)];
    p.p = R * poly.vertices[h.origin] + pose.position;
    p.id = vertex_id(h.origin);
    p.label = e;
    out.half_edges[std::size_t(out.count)] = e;
    ++out.count;
    e = h.next;
  } while (e != F.edge && out.count < kMaxPolygon);
}

std::uint32_t incident_face(const Poly& poly, const Quat& rotation, const Vec3& n) {
  // the least dot product (the first of equals), without branches: keep_max on its negation
  const Vec3 nl = glm::conjugate(rotation) * n;
  if (poly.face_soa) {
    // hulls: two faces at a time from the normals' coordinate columns (the padded face
    // repeats the last, so it never wins), each dot product summed as glm::dot sums it;
    // each lane keeps its first minimum, the lanes' tie goes to the lower index
    using v2d = double __attribute__((vector_size(16)));
    using v2l = long long __attribute__((vector_size(16)));
    const std::uint32_t m = poly.face_stride;
    const double *x = poly.face_soa, *y = x + m, *z = y + m;
    const v2d dx = {nl.x, nl.x}, dy = {nl.y, nl.y}, dz = {nl.z, nl.z};
    v2d best = {INFINITY, INFINITY};
    v2l index = {0, 1}, best_index = index;
    const v2l two = {2, 2};
    for (std::uint32_t i = 0; i < m; i += 2, index += two) {
      const v2d vx = {x[i], x[i + 1]}, vy = {y[i], y[i + 1]}, vz = {z[i], z[i + 1]};
      const v2d d = (vx * dx + vy * dy) + vz * dz;
      const v2l better = d < best;
      best = better ? d : best;
      best_index = better ? index : best_index;
    }
    const bool odd = (best[1] < best[0]) | ((best[1] == best[0]) & (best_index[1] < best_index[0]));
    return std::uint32_t(odd ? best_index[1] : best_index[0]);
  }
  int best = 0;
  double bd = -INFINITY;
  for (std::uint32_t f = 0; f < poly.face_count; ++f) keep_max(-glm::dot(poly.faces[f].normal, nl), int(f), bd, best);
  return std::uint32_t(best);
}

std::uint32_t most_aligned_face(const Poly& poly, const Quat& rotation, const Vec3& n, double* dot) {
  const std::uint32_t f = incident_face(poly, rotation, -n);
  if (dot) *dot = glm::dot(rotation * poly.faces[f].normal, n);
  return f;
}

int clip_faces(const WorldFace& ref, const ClipPoint* incident, int incident_count, bool incident_is_segment,
               const Vec3& dir, double shift, double margin, bool ref_is_a, Candidate* out, bool sides_along_dir) {
  std::array<ClipPoint, kMaxPolygon> buf_a, buf_b;
  ClipPoint* in = buf_a.data();
  ClipPoint* next = buf_b.data();
  int n = std::min(incident_count, kMaxPolygon);
  for (int i = 0; i < n; ++i) in[i] = incident[i];

  // one side plane per reference edge: normal (edge x face normal, or edge x dir) points out
  // of the face
  const Vec3 along = sides_along_dir ? dir : ref.normal;
  for (int k = 0; k < ref.count && n > 0; ++k) {
    const Vec3 p = ref.pts[std::size_t(k)].p;
    const Vec3 q = ref.pts[std::size_t((k + 1) % ref.count)].p;
    const Vec3 s = glm::cross(q - p, along);
    const std::uint32_t plane = kSideLabel | ref.half_edges[std::size_t(k)];
    if (incident_is_segment) {
      // a segment: move the outside end to the plane
      const double d0 = glm::dot(s, in[0].p - p), d1 = glm::dot(s, in[1].p - p);
      if (d0 > 0 && d1 > 0) {
        n = 0;
        break;
      }
      if (d0 > 0) in[0] = {in[0].p + (in[1].p - in[0].p) * (d0 / (d0 - d1)), cross_id(in[0].label, plane), in[0].label};
      else if (d1 > 0) in[1] = {in[0].p + (in[1].p - in[0].p) * (d0 / (d0 - d1)), cross_id(in[0].label, plane), in[0].label};
      continue;
    }
    // Sutherland-Hodgman against this plane (each point's side computed once)
    std::array<double, kMaxPolygon> side;
    const double sp = glm::dot(s, p);
    for (int i = 0; i < n; ++i) side[std::size_t(i)] = glm::dot(s, in[i].p) - sp;
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const int i2 = i + 1 == n ? 0 : i + 1;
      const ClipPoint& c = in[i];
      const ClipPoint& d = in[i2];
      const double dc = side[std::size_t(i)], dd = side[std::size_t(i2)];
      if (dc <= 0 && m < kMaxPolygon) next[m++] = c;
      if ((dc <= 0) != (dd <= 0) && m < kMaxPolygon) {
        // leaving: the new edge runs along the plane; entering: along c's edge
        const Vec3 x = c.p + (d.p - c.p) * (dc / (dc - dd));
        next[m++] = {x, cross_id(c.label, plane), dc <= 0 ? plane : c.label};
      }
    }
    std::swap(in, next);
    n = m;
  }

  // depth of each point along dir, measured to the reference plane
  const double cosine = glm::dot(ref.normal, dir);
  int count = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 qs = in[i].p - shift * dir;
    const double gap = ref.offset - glm::dot(ref.normal, qs);
    // with the sides along dir (an edge contact's face points), a point outside the plane
    // takes its gap to the plane times the cosine, as the box path's (sat_box.cpp): never
    // more than its true distance to the reference body, nor more than the closing along dir
    // that brings it to the plane along the plane's normal
    const double t = sides_along_dir && gap < 0 ? gap * cosine : gap / cosine;
    if (t < -margin) continue;
    const Vec3 on_ref = qs + t * dir;
    Candidate& c = out[count++];
    c.a = ref_is_a ? on_ref : qs;
    c.b = ref_is_a ? qs : on_ref;
    c.depth = t;
    c.id = in[i].id;
  }
  return count;
}

void reduce(const Candidate* c, int count, const Vec3& n, Manifold& m) {
  m.normal = n;
  m.count = 0;
  if (count <= 0) return;
  auto put = [&](int i) {
    m.points[std::size_t(m.count++)] = {c[i].a, c[i].b, c[i].depth, c[i].id};
  };
  if (count <= Manifold::kMaxPoints) {
    for (int i = 0; i < count; ++i) put(i);
    return;
  }
  // the deepest point
  int i1 = 0;
  for (int i = 1; i < count; ++i)
    if (c[i].depth > c[i1].depth) i1 = i;
  // the farthest from it
  const Vec3 p1 = c[i1].b;
  int i2 = -1;
  double best = -1;
  for (int i = 0; i < count; ++i) {
    const double d = glm::dot(c[i].b - p1, c[i].b - p1);
    if (i != i1 && d > best) best = d, i2 = i;
  }
  const Vec3 p2 = c[i2].b;
  // the largest triangle with both (signed area about n)
  auto area = [&](const Vec3& x, const Vec3& y, const Vec3& z) { return glm::dot(glm::cross(y - x, z - x), n); };
  int i3 = -1;
  best = -1;
  for (int i = 0; i < count; ++i) {
    const double a = std::abs(area(p1, p2, c[i].b));
    if (i != i1 && i != i2 && a > best) best = a, i3 = i;
  }
  const Vec3 p3 = c[i3].b;
  const double orient = area(p1, p2, p3) >= 0 ? 1.0 : -1.0;
  // the point adding the most area outside the triangle
  int i4 = -1;
  best = 0;
  for (int i = 0; i < count; ++i) {
    if (i == i1 || i == i2 || i == i3) continue;
    const Vec3 p = c[i].b;
    const double out = std::max({-orient * area(p1, p2, p), -orient * area(p2, p3, p), -orient * area(p3, p1, p)});
    if (out > best) best = out, i4 = i;
  }
  put(i1);
  put(i2);
  put(i3);
  if (i4 >= 0) put(i4);
}

}  // namespace pba::narrow
