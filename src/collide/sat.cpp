// Separating axes between convex polyhedra (Gregorius 2013, GDC "The Separating Axis Test
// between Convex Polyhedra"): the face normals of A, the face normals of B, and the cross
// products of edge pairs that form a face of the Minkowski difference (the Gauss-map arcs
// of the two edges cross), each measured by the support of the other body. The least
// separated axis decides the contact: a face gives a reference face whose side planes
// clip the other body's most anti-parallel face (Sutherland and Hodgman 1974), an edge
// pair gives the closest points of the two edges.
#include <cmath>

#include "narrow_internal.h"

namespace pba::narrow {

namespace {

struct FaceQuery {
  double separation = -INFINITY;
  std::uint32_t index = 0;
};
struct EdgeQuery {
  double separation = -INFINITY;
  std::uint32_t edge_a = 0, edge_b = 0;  // half edges (even), A's and B's
  Vec3 normal{0, 0, 1};                  // in A's frame, from A to B
};

// relative placement of B in A's frame: x_A = R x_B + t
struct Relative {
  Mat3 R{1.0};
  Mat3 RT{1.0};
  Vec3 t{0, 0, 0};
};

Relative relative(const Pose& pa, const Pose& pb) {
  Relative r;
  const Quat q = glm::conjugate(pa.rotation) * pb.rotation;
  r.R = glm::mat3_cast(q);
  r.RT = glm::transpose(r.R);
  r.t = glm::conjugate(pa.rotation) * (pb.position - pa.position);
  return r;
}

// separation of B from face f of A: plane distance of B's deepest vertex
// (`hint`: where B's hill climb starts; it returns the vertex found)
double face_separation(const Poly& a, std::uint32_t f, const Poly& b, const Relative& r, std::uint32_t* hint = nullptr) {
  const HullFace& F = a.faces[f];
  const Vec3 nb = r.RT * F.normal;
  const std::uint32_t j = b.support_index(-nb, hint ? *hint : 0);
  if (hint) *hint = j;
  return glm::dot(nb, b.vertices[j]) + glm::dot(F.normal, r.t) - F.offset;
}

// Pruning bounds. A ball of radius `inner` about a body's centre c lies inside it, so the
// body reaches at least `inner` behind c along any direction. Face f of A: B's deepest
// point along the face normal lies at least B's inner radius behind B's centre, so the
// face's separation is at most the plane distance of B's centre less that radius.
// Edge of A with arc normals u, v through p, against B (centre c, radius `inner`): a pair
// forming a Minkowski face has its axis n on the arc, and the edge is A's support along n,
// so the pair's separation is at most n . (c - p) - inner; over the arc n . w is at most
// m = max(u . w, v . w) when m <= 0, else m times the arc's secant.
using v2d = double __attribute__((vector_size(16)));
using v2l = long long __attribute__((vector_size(16)));
constexpr std::uint32_t kMaxBounds = 256;  // faces or edges whose bounds are kept on the stack

double face_bound(const Poly& a, std::uint32_t f, const Vec3& cb, double inner_b) {
  const HullFace& F = a.faces[f];
  return glm::dot(F.normal, cb) - F.offset - inner_b;
}
double edge_bound(const Vec3& u, const Vec3& v, const Vec3& p, const Vec3& c, double sec, double inner) {
  const Vec3 w = c - p;
  const double m = std::max(glm::dot(u, w), glm::dot(v, w));
  return (m > 0 ? m * sec : m) - inner;
}
// a box's edges join faces at right angles: the secant of 45 degrees, rounded up
constexpr double kBoxSecant = 1.4142135623730952;
double edge_bound(const Poly& a, std::uint32_t i, const Vec3& c, double inner) {
  const HalfEdge& e = a.edges[2 * i];
  const HalfEdge& t = a.edges[2 * i + 1];
  const double sec = a.is_box ? kBoxSecant : a.edge_soa[9 * a.edge_stride + i];
  return edge_bound(a.faces[e.face].normal, a.faces[t.face].normal, a.vertices[e.origin], c, sec, inner);
}

// every face's bound into ub (a.face_count <= kMaxBounds); returns the face of the largest
// (the first of equals)
std::uint32_t face_bounds(const Poly& a, const Vec3& cb, double inner_b, double* ub) {
  if (!a.face_soa) {
    std::uint32_t best = 0;
    for (std::uint32_t f = 0; f < a.face_count; ++f) {
      ub[f] = face_bound(a, f, cb, inner_b);
      if (ub[f] > ub[best]) best = f;
    }
    return best;
  }
  // two faces at a time from the coordinate columns (the last padded face repeats the last)
  const std::uint32_t m = a.face_stride;
  const double *x = a.face_soa, *y = x + m, *z = y + m, *o = z + m;
  const v2d cx = {cb.x, cb.x}, cy = {cb.y, cb.y}, cz = {cb.z, cb.z}, in = {inner_b, inner_b};
  v2d best = {-INFINITY, -INFINITY};
  v2l index = {0, 1}, best_index = index;
  const v2l two = {2, 2};
  for (std::uint32_t i = 0; i < m; i += 2, index += two) {
    const v2d nx = {x[i], x[i + 1]}, ny = {y[i], y[i + 1]}, nz = {z[i], z[i + 1]}, off = {o[i], o[i + 1]};
    const v2d u = (((nx * cx + ny * cy) + nz * cz) - off) - in;
    ub[i] = u[0], ub[i + 1] = u[1];
    const v2l better = u > best;
    best = better ? u : best;
    best_index = better ? index : best_index;
  }
  const bool odd = (best[1] > best[0]) | ((best[1] == best[0]) & (best_index[1] < best_index[0]));
  return std::uint32_t(odd ? best_index[1] : best_index[0]);
}

// every edge's bound against the other body (centre c in this body's frame, its inner
// radius) into ub (edge_count / 2 <= kMaxBounds)
void edge_bounds(const Poly& a, const Vec3& c, double inner, double* ub) {
  const std::uint32_t n = a.edge_count / 2;
  if (!a.edge_soa) {
    for (std::uint32_t i = 0; i < n; ++i) ub[i] = edge_bound(a, i, c, inner);
    return;
  }
  const std::uint32_t m = a.edge_stride;
  const double* col = a.edge_soa;
  const v2d cx = {c.x, c.x}, cy = {c.y, c.y}, cz = {c.z, c.z}, in = {inner, inner}, zero = {0, 0};
  for (std::uint32_t i = 0; i < m; i += 2) {
    auto at = [&](int k) { return v2d{col[std::uint32_t(k) * m + i], col[std::uint32_t(k) * m + i + 1]}; };
    const v2d wx = cx - at(6), wy = cy - at(7), wz = cz - at(8);
    const v2d mu = (at(0) * wx + at(1) * wy) + at(2) * wz, mv = (at(3) * wx + at(4) * wy) + at(5) * wz;
    const v2d mx = mu > mv ? mu : mv;
    const v2d u = (mx > zero ? mx * at(9) : mx) - in;
    ub[i] = u[0], ub[i + 1] = u[1];
  }
}

// The faces of A against B: the largest separation and its face, the first of equals.
// Exact when the largest exceeds `floor`; otherwise only known to be <= floor. A face whose
// bound (within `eps`, the bounds' rounding) is below the best found, or below floor, cannot
// change the answer and is not measured; the face of the largest bound is measured first,
// so the best found starts near the answer, or `hint_face` (the cached face of the last
// frame) when it is one of A's faces. The answer does not depend on which face comes first.
FaceQuery query_faces(const Poly& a, const Poly& b, const Relative& r, double floor, double eps,
                      std::uint32_t hint_face = ~0u) {
  const Vec3 cb = r.R * b.center + r.t;
  alignas(16) double ub[kMaxBounds];
  const bool stored = a.face_count <= kMaxBounds;
  std::uint32_t seed = 0;
  if (stored) {
    seed = face_bounds(a, cb, b.inner_radius, ub);
  } else {
    for (std::uint32_t f = 1; f < a.face_count; ++f)
      if (face_bound(a, f, cb, b.inner_radius) > face_bound(a, seed, cb, b.inner_radius)) seed = f;
  }
  if (hint_face < a.face_count) seed = hint_face;
  auto bound = [&](std::uint32_t f) { return stored ? ub[f] : face_bound(a, f, cb, b.inner_radius); };
  FaceQuery q;
  std::uint32_t hint = 0;
  double cut = floor;
  // B's vertices found deepest so far (A's frame): any vertex of B bounds a face's
  // separation too (B's deepest point is at most that deep), and they lie where the
  // answer's does, so a face that passes the ball's bound is measured only when it
  // passes theirs
  std::array<Vec3, 4> witness;
  std::uint32_t witnesses = 0;
  auto measure = [&](std::uint32_t f) {
    const double s = face_separation(a, f, b, r, &hint);
    witness[witnesses++ % witness.size()] = r.R * b.vertices[hint] + r.t;
    return s;
  };
  auto witness_bound = [&](std::uint32_t f) {
    const HullFace& F = a.faces[f];
    double u = INFINITY;
    for (std::uint32_t k = 0; k < std::min<std::uint32_t>(witnesses, witness.size()); ++k)
      u = std::min(u, glm::dot(F.normal, witness[k]) - F.offset);
    return u;
  };
  if (!(bound(seed) + eps < cut)) {
    q.separation = measure(seed), q.index = seed;
    cut = std::max(cut, q.separation);
  }
  for (std::uint32_t f = 0; f < a.face_count; ++f) {
    if (f == seed || bound(f) + eps < cut || witness_bound(f) + eps < cut) continue;
    const double s = measure(f);
    if (s > q.separation || (s == q.separation && f < q.index)) q.separation = s, q.index = f;
    cut = std::max(cut, q.separation);
  }
  return q;
}

// the same with A and B exchanged: B's faces against A's vertices
Relative swapped(const Relative& r) {
  Relative s;
  s.R = r.RT;
  s.RT = r.R;
  s.t = -(r.RT * r.t);
  return s;
}

// separation along the cross product of two edges (A's frame), oriented away from A's centre
double edge_separation(const Vec3& pa, const Vec3& ea, const Vec3& pb, const Vec3& eb, const Vec3& ca, Vec3& n) {
  const Vec3 c = glm::cross(ea, eb);
  const double len = glm::length(c);
  // near-parallel edges: their cross product is noise, and the face axes cover them
  constexpr double kParallel = 0.005;  // sin of ~0.3 degrees
  if (len < kParallel * std::sqrt(glm::dot(ea, ea) * glm::dot(eb, eb))) return -INFINITY;
  n = c / len;
  if (glm::dot(n, pa - ca) < 0) n = -n;
  return glm::dot(n, pb - pa);
}

// an edge of A: its Gauss-map arc (its two faces' normals and their cross product) and its
// segment
struct EdgeArc {
  Vec3 u, v, bxa, p, e;
};
EdgeArc arc_of(const Poly& a, std::uint32_t i) {
  const HalfEdge& e1 = a.edges[2 * i];
  const HalfEdge& t1 = a.edges[2 * i + 1];
  EdgeArc g;
  g.u = a.faces[e1.face].normal;
  g.v = a.faces[t1.face].normal;
  g.bxa = glm::cross(g.v, g.u);
  g.p = a.vertices[e1.origin];
  g.e = a.vertices[t1.origin] - g.p;
  return g;
}

// Gregorius 2013: the edges form a face of the Minkowski difference when the Gauss-map arcs
// A B = (u, v) of A's edge and C D = (-u2, -v2) of B's cross: C and D on opposite sides of
// A B's plane (normal B x A), A and B on opposite sides of C D's (D x C), and C, B on the
// same hemisphere. cba = C . (B x A), dba = D . (B x A), adc = A . (D x C), bdc = B . (D x C).
// The three sign tests are combined without branches (each alone goes either way as randomly
// as the poses); T is double or a vector of two
template <class T>
auto arcs_cross(T cba, T dba, T adc, T bdc) {
  const T zero{};
  return (cba * dba < zero) & (adc * bdc < zero) & (cba * bdc > zero);
}

// A's arcs as coordinate columns for the two-lane test, padded with zero arcs (which cross
// nothing) to an even count; with each kept arc's segment and edge index
constexpr std::uint32_t kMaxGathered = 256;
struct ArcColumns {
  alignas(16) double ux[kMaxGathered], uy[kMaxGathered], uz[kMaxGathered];
  alignas(16) double vx[kMaxGathered], vy[kMaxGathered], vz[kMaxGathered];
  alignas(16) double bx[kMaxGathered], by[kMaxGathered], bz[kMaxGathered];
  Vec3 p[kMaxGathered], e[kMaxGathered];
  std::uint32_t edge[kMaxGathered];
};

// The edge pairs: the largest separation, the first of equals in the order (B's edge, A's
// edge). Exact when the largest exceeds `floor`; otherwise only known to be <= floor: edges
// whose bound (edge_bound, within `eps`) is below floor, or B's edges below the best found,
// are left out.
EdgeQuery query_edges(const Poly& a, const Poly& b, const Relative& r, double floor, double eps) {
  EdgeQuery q;
  const std::uint32_t na = a.edge_count / 2, nb = b.edge_count / 2;
  const bool gathered = na <= kMaxGathered;
  const Vec3 cb = r.R * b.center + r.t;       // B's centre in A's frame
  const Vec3 ca = r.RT * (a.center - r.t);    // A's centre in B's frame
  alignas(16) double ub[kMaxBounds];
  const bool b_stored = nb <= kMaxBounds;
  if (b_stored) edge_bounds(b, ca, a.inner_radius, ub);
  ArcColumns c;
  std::uint32_t nk = 0;
  if (gathered) {
    alignas(16) double ua[kMaxBounds];
    edge_bounds(a, cb, b.inner_radius, ua);
    for (std::uint32_t i = 0; i < na; ++i) {
      if (ua[i] + eps < floor) continue;
      const EdgeArc g = arc_of(a, i);
      c.ux[nk] = g.u.x, c.uy[nk] = g.u.y, c.uz[nk] = g.u.z;
      c.vx[nk] = g.v.x, c.vy[nk] = g.v.y, c.vz[nk] = g.v.z;
      c.bx[nk] = g.bxa.x, c.by[nk] = g.bxa.y, c.bz[nk] = g.bxa.z;
      c.p[nk] = g.p, c.e[nk] = g.e, c.edge[nk] = i;
      ++nk;
    }
    if (nk == 0) return q;
    if (nk & 1) {
      c.ux[nk] = c.uy[nk] = c.uz[nk] = c.vx[nk] = c.vy[nk] = c.vz[nk] = c.bx[nk] = c.by[nk] = c.bz[nk] = 0.0;
      c.edge[nk] = na;
      ++nk;
    }
  }
  // B's edges into A's frame once each (outer loop), A's arcs tested two at a time (inner)
  for (std::uint32_t j = 0; j < b.edge_count; j += 2) {
    const HalfEdge& e2 = b.edges[j];
    const HalfEdge& t2 = b.edges[j + 1];
    if ((b_stored ? ub[j / 2] : edge_bound(b, j / 2, ca, a.inner_radius)) + eps < std::max(floor, q.separation))
      continue;
    const Vec3 p2 = r.R * b.vertices[e2.origin] + r.t;
    const Vec3 q2 = r.R * b.vertices[t2.origin] + r.t;
    const Vec3 u2 = r.R * b.faces[e2.face].normal;
    const Vec3 v2 = r.R * b.faces[t2.face].normal;
    const Vec3 e2d = q2 - p2;
    const Vec3 dxc = glm::cross(v2, u2);
    // a crossing pair: its separation along the edges' cross product, the largest kept (the
    // first of equals, in the order j, then i)
    auto consider = [&](std::uint32_t i, const Vec3& p, const Vec3& e) {
      Vec3 n;
      const double s = edge_separation(p, e, p2, e2d, a.center, n);
      if (s > q.separation) q.separation = s, q.edge_a = 2 * i, q.edge_b = j, q.normal = n;
    };
    if (gathered) {
      // each dot product summed as glm::dot sums it, (x + y) + z, so the tests are the
      // scalar ones to the bit; crossings are few, so the branch on them is learnt
      const v2d u2x = {u2.x, u2.x}, u2y = {u2.y, u2.y}, u2z = {u2.z, u2.z};
      const v2d v2x = {v2.x, v2.x}, v2y = {v2.y, v2.y}, v2z = {v2.z, v2.z};
      const v2d dx = {dxc.x, dxc.x}, dy = {dxc.y, dxc.y}, dz = {dxc.z, dxc.z};
      for (std::uint32_t k = 0; k < nk; k += 2) {
        const v2d bx = {c.bx[k], c.bx[k + 1]}, by = {c.by[k], c.by[k + 1]}, bz = {c.bz[k], c.bz[k + 1]};
        const v2d ux = {c.ux[k], c.ux[k + 1]}, uy = {c.uy[k], c.uy[k + 1]}, uz = {c.uz[k], c.uz[k + 1]};
        const v2d vx = {c.vx[k], c.vx[k + 1]}, vy = {c.vy[k], c.vy[k + 1]}, vz = {c.vz[k], c.vz[k + 1]};
        const v2d cba = -((u2x * bx + u2y * by) + u2z * bz), dba = -((v2x * bx + v2y * by) + v2z * bz);
        const v2d adc = (ux * dx + uy * dy) + uz * dz, bdc = (vx * dx + vy * dy) + vz * dz;
        const auto cross = arcs_cross(cba, dba, adc, bdc);
        if (cross[0] | cross[1]) {
          if (cross[0]) consider(c.edge[k], c.p[k], c.e[k]);
          if (cross[1]) consider(c.edge[k + 1], c.p[k + 1], c.e[k + 1]);
        }
      }
    } else {
      for (std::uint32_t i = 0; i < na; ++i) {
        if (edge_bound(a, i, cb, b.inner_radius) + eps < floor) continue;
        const EdgeArc g = arc_of(a, i);
        if (arcs_cross(-glm::dot(u2, g.bxa), -glm::dot(v2, g.bxa), glm::dot(g.u, dxc), glm::dot(g.v, dxc)))
          consider(i, g.p, g.e);
      }
    }
  }
  return q;
}

// the separation of the cached feature (-inf when it no longer applies)
double cached_separation(const Poly& a, const Poly& b, const Relative& r, const SatCache& c) {
  switch (c.kind) {
    case SatCache::Kind::FaceA:
      return c.index_a < a.face_count ? face_separation(a, c.index_a, b, r) : -INFINITY;
    case SatCache::Kind::FaceB:
      return c.index_b < b.face_count ? face_separation(b, c.index_b, a, swapped(r)) : -INFINITY;
    case SatCache::Kind::Edges: {
      if (c.index_a + 1 >= a.edge_count || c.index_b + 1 >= b.edge_count) return -INFINITY;
      const HalfEdge& e1 = a.edges[c.index_a];
      const HalfEdge& e2 = b.edges[c.index_b];
      const Vec3 p1 = a.vertices[e1.origin];
      const Vec3 p2 = r.R * b.vertices[e2.origin] + r.t;
      const Vec3 q2 = r.R * b.vertices[b.edges[c.index_b + 1].origin] + r.t;
      Vec3 n;
      if (edge_separation(p1, a.vertices[a.edges[c.index_a + 1].origin] - p1, p2, q2 - p2, a.center, n) == -INFINITY)
        return -INFINITY;
      // the gap between the bodies' supports along the axis: a proof of separation
      // whether or not the edges still form a Minkowski face
      const Vec3 nb = r.RT * n;
      const double b_min = glm::dot(nb, b.vertices[b.support_index(-nb)]) + glm::dot(n, r.t);
      const double a_max = glm::dot(n, a.vertices[a.support_index(n)]);
      return b_min - a_max;
    }
    default: return -INFINITY;
  }
}

}  // namespace

void collide_polys_sat(const Poly& a, const Pose& pa, const Poly& b, const Pose& pb, double margin, SatCache* cache,
                       Manifold& m) {
  m.count = 0;
  const Relative r = relative(pa, pb);
  // the cached feature first: still separating beyond the margin means no contact
  if (cache && cache->kind != SatCache::Kind::None && cached_separation(a, b, r, *cache) > margin) return;

  // faces of A, faces of B, edge pairs; any separation beyond the margin ends the test.
  // Each query skips what cannot change the outcome (see query_faces, query_edges): B's
  // faces below min(A's best, what would still leave A the reference face), edge pairs
  // below what would still leave a face the contact (or below the margin)
  // prefer faces over edges and A's face over B's unless clearly worse (Gregorius 2013:
  // relative and absolute tolerances keep the choice from flickering between frames)
  constexpr double kRelEdge = 0.90, kRelFace = 0.98, kAbs = 0.5 * 0.005;
  // the bounds' rounding allowance: a tenth of a micrometre per metre of the bodies' size
  // and distance, far above the separations' rounding and the hulls' planarity tolerance
  const double eps = 1e-7 * (a.outer_radius + b.outer_radius + glm::length(r.R * b.center + r.t - a.center));
  // a cached face (a touching pair's reference face of the last frame) is measured first
  const bool cached_a = cache && cache->kind == SatCache::Kind::FaceA;
  const bool cached_b = cache && cache->kind == SatCache::Kind::FaceB;
  const FaceQuery fa = query_faces(a, b, r, -INFINITY, eps, cached_a ? cache->index_a : ~0u);
  if (fa.separation > margin) {
    if (cache) *cache = {SatCache::Kind::FaceA, fa.index, 0};
    return;
  }
  const FaceQuery fb = query_faces(b, a, swapped(r), std::min(fa.separation, kRelFace * fa.separation + kAbs), eps,
                                   cached_b ? cache->index_b : ~0u);
  if (fb.separation > margin) {
    if (cache) *cache = {SatCache::Kind::FaceB, 0, fb.index};
    return;
  }
  const double best_face = std::max(fa.separation, fb.separation);
  // what an edge pair must exceed to be the contact: the best face's separation and a tenth of
  // it, whatever its sign (0.9 times a positive separation let an edge pair whose axis is a
  // face normal tie with the face, and a face-on speculative contact became one point)
  const double edge_over = (best_face > 0 ? (2 - kRelEdge) * best_face : kRelEdge * best_face) + kAbs;
  const EdgeQuery ee = query_edges(a, b, r, std::min(margin, edge_over), eps);
  if (ee.separation > margin) {
    if (cache) *cache = {SatCache::Kind::Edges, ee.edge_a, ee.edge_b};
    return;
  }

  if (ee.separation > edge_over) {
    if (cache) *cache = {SatCache::Kind::Edges, ee.edge_a, ee.edge_b};
    // edge contact: the closest points of the two edges
    const Vec3 p1 = apply(pa, a.vertices[a.edges[ee.edge_a].origin]);
    const Vec3 q1 = apply(pa, a.vertices[a.edges[ee.edge_a + 1].origin]);
    const Vec3 p2 = apply(pb, b.vertices[b.edges[ee.edge_b].origin]);
    const Vec3 q2 = apply(pb, b.vertices[b.edges[ee.edge_b + 1].origin]);
    Vec3 ca, cb;
    closest_segments(p1, q1, p2, q2, ca, cb);
    const Vec3 n = pa.rotation * ee.normal;
    // and B's face most anti-parallel to the axis clipped along the axis by the sides of A's
    // face most parallel to it, its points measured along the axis to A's face plane (the
    // feet on A's face, so no deeper than the axis's penetration; a gap, the point outside
    // the plane, as the gap to the plane times the cosine: clip_faces) and kept within
    // the margin, less any within a thousandth of the bodies' size of the edge point (the
    // contact edges' crossing, found again): up to four in all, the reduction's (Jolt's
    // manifold between two faces; a box meeting another edge first gets points where its
    // faces are about to close, not one it can turn about)
    WorldFace rf, inf;
    world_face(a, pa, most_aligned_face(a, pa.rotation, n, nullptr), rf);
    world_face(b, pb, incident_face(b, pb.rotation, n), inf);
    std::array<Candidate, kMaxPolygon + 1> cand;
    cand[0] = {ca, cb, glm::dot(ca - cb, n), edge_pair_id(ee.edge_a, ee.edge_b)};
    const int clipped = clip_faces(rf, inf.pts.data(), inf.count, false, n, 0.0, margin, true, cand.data() + 1, true);
    const double near = 1e-3 * (a.outer_radius + b.outer_radius);
    int kept = 1;
    for (int i = 1; i <= clipped; ++i) {
      const Vec3 d = cand[std::size_t(i)].b - cb;
      if (glm::dot(d, d) < near * near) continue;
      cand[std::size_t(kept++)] = cand[std::size_t(i)];
    }
    reduce(cand.data(), kept, n, m);
    return;
  }
  const bool ref_a = !(fb.separation > kRelFace * fa.separation + kAbs);
  if (cache) *cache = ref_a ? SatCache{SatCache::Kind::FaceA, fa.index, 0} : SatCache{SatCache::Kind::FaceB, 0, fb.index};

  // reference face, incident face, clip
  const Poly& ref = ref_a ? a : b;
  const Poly& inc = ref_a ? b : a;
  const Pose& pref = ref_a ? pa : pb;
  const Pose& pinc = ref_a ? pb : pa;
  WorldFace rf, inf;
  world_face(ref, pref, ref_a ? fa.index : fb.index, rf);
  world_face(inc, pinc, incident_face(inc, pinc.rotation, rf.normal), inf);
  std::array<Candidate, kMaxPolygon> cand;
  int n = clip_faces(rf, inf.pts.data(), inf.count, false, rf.normal, 0.0, margin, ref_a, cand.data());
  if (n == 0) {
    // the incident face lies outside the reference face's sides (deep overlaps of thin
    // hulls): the deepest incident vertex, which set the face's separation, alone
    const std::uint32_t v = inc.support_index(glm::conjugate(pinc.rotation) * -rf.normal);
    const Vec3 q = apply(pinc, inc.vertices[v]);
    const double depth = rf.offset - glm::dot(rf.normal, q);
    const Vec3 on_ref = q + depth * rf.normal;
    cand[0] = {ref_a ? on_ref : q, ref_a ? q : on_ref, depth, vertex_id(v)};
    n = 1;
  }
  if (!ref_a)
    for (int i = 0; i < n; ++i) cand[std::size_t(i)].id |= kIdFlip;
  reduce(cand.data(), n, ref_a ? rf.normal : -rf.normal, m);
}

}  // namespace pba::narrow
