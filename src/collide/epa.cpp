// Penetration depth by the expanding polytope algorithm (van den Bergen 2001, "Proximity
// Queries and Penetration Depth Computation on 3D Game Objects"): starting from GJK's
// final tetrahedron, which holds the origin, the face of the polytope nearest the origin
// is replaced by the support point of A - B along its normal until the support point
// lies on that face. For polytope cores the Minkowski difference has finitely many faces,
// so the loop ends on one of them and the depth is exact up to kEpaTolerance (or 1e-15 of
// the shapes' world coordinates, where that is more: their rounding).
#include <algorithm>
#include <cmath>

#include "narrow_internal.h"

namespace pba {

namespace {

constexpr int kMaxVertices = 128;
constexpr int kMaxFaces = 256;
constexpr int kMaxHorizon = 128;

struct EpaFace {
  int v[3];
  Vec3 normal;
  double dist;
};

struct Polytope {
  // scratch storage, filled as the polytope grows (left uninitialised: no memset per call).
  // Faces are stored as they are made; the live ones are listed by index with their
  // distances, in the order they were made (removed ones are squeezed out of the list)
  std::array<SimplexVertex, kMaxVertices> verts;
  int nv = 0;
  std::array<EpaFace, kMaxFaces> faces;
  int nf = 0;  // faces stored
  std::array<int, kMaxFaces> live;
  std::array<double, kMaxFaces> live_dist;
  int nl = 0;  // faces live

  // a face i, j, k (counter-clockwise seen from outside); degenerate faces get an
  // infinite distance so they are never expanded
  bool add_face(int i, int j, int k) {
    if (nf >= kMaxFaces) return false;
    live[std::size_t(nl)] = nf;
    EpaFace& f = faces[std::size_t(nf++)];
    f.v[0] = i, f.v[1] = j, f.v[2] = k;
    const Vec3 a = verts[std::size_t(i)].w, b = verts[std::size_t(j)].w, c = verts[std::size_t(k)].w;
    const Vec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    if (len <= 1e-30) {
      f.normal = Vec3(0, 0, 1);
      f.dist = INFINITY;
    } else {
      f.normal = n / len;
      f.dist = glm::dot(f.normal, a);
    }
    live_dist[std::size_t(nl++)] = f.dist;
    return true;
  }

  // moves the live faces to the front of the storage, in order (when it fills)
  void compact() {
    for (int q = 0; q < nl; ++q) {
      faces[std::size_t(q)] = faces[std::size_t(live[std::size_t(q)])];
      live[std::size_t(q)] = q;
    }
    nf = nl;
  }
};

SimplexVertex support_point(const ConvexProxy& a, const ConvexProxy& b, const Vec3& d, const SimplexVertex* near = nullptr) {
  SimplexVertex s{};
  s.a = a.support(d, &s.index_a, near ? near->index_a : 0);
  s.b = b.support(-d, &s.index_b, near ? near->index_b : 0);
  s.w = s.a - s.b;
  return s;
}

// distance of w from the affine hull of the first n simplex points
double off_hull(const std::array<SimplexVertex, 4>& s, int n, const Vec3& w) {
  if (n == 1) return glm::length(w - s[0].w);
  if (n == 2) {
    const Vec3 e = s[1].w - s[0].w;
    return glm::length(glm::cross(e, w - s[0].w)) / std::max(glm::length(e), 1e-300);
  }
  const Vec3 nrm = glm::cross(s[1].w - s[0].w, s[2].w - s[0].w);
  return std::abs(glm::dot(nrm, w - s[0].w)) / std::max(glm::length(nrm), 1e-300);
}

// The rounding scale of the points of A - B (m): the largest coordinate of the world support
// points they are differences of (a world position rounds to about 1e-16 of itself, and so do
// the differences, however small). EPA's tolerances grow with it beyond 100 km, below which
// they are the fixed ones: at 1e12 m a deep capsule-box pair's gain never fell below 1e-10 m,
// the polytope filled with rounding-level slivers and the pair came out as no contact.
double rounding_scale(const std::array<SimplexVertex, 4>& s, int n) {
  double big = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 &a = s[std::size_t(i)].a, &b = s[std::size_t(i)].b;
    big = std::max({big, std::abs(a.x), std::abs(a.y), std::abs(a.z), std::abs(b.x), std::abs(b.y), std::abs(b.z)});
  }
  return big;
}

// grows a GJK simplex of 1-3 points (origin on it) to a tetrahedron by supports along
// directions off its affine hull (by more than `off`, m)
bool complete_tetrahedron(const ConvexProxy& a, const ConvexProxy& b, std::array<SimplexVertex, 4>& s, int& n,
                          double off) {
  static const Vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  while (n < 4) {
    bool grown = false;
    if (n == 1) {
      for (const Vec3& d : axes) {
        const SimplexVertex w = support_point(a, b, d);
        if (off_hull(s, n, w.w) > off) {
          s[std::size_t(n++)] = w;
          grown = true;
          break;
        }
      }
    } else if (n == 2) {
      // directions perpendicular to the segment, turning around it
      const Vec3 e = glm::normalize(s[1].w - s[0].w);
      const Vec3 ref = std::abs(e.x) < 0.57 ? Vec3(1, 0, 0) : (std::abs(e.y) < 0.57 ? Vec3(0, 1, 0) : Vec3(0, 0, 1));
      const Vec3 u = glm::normalize(glm::cross(e, ref)), v = glm::cross(e, u);
      for (int k = 0; k < 6 && !grown; ++k) {
        const double ang = kPi * k / 3;
        const SimplexVertex w = support_point(a, b, std::cos(ang) * u + std::sin(ang) * v);
        if (off_hull(s, n, w.w) > off) {
          s[std::size_t(n++)] = w;
          grown = true;
        }
      }
    } else {
      const Vec3 nrm = glm::normalize(glm::cross(s[1].w - s[0].w, s[2].w - s[0].w));
      for (const Vec3& d : {nrm, -nrm}) {
        const SimplexVertex w = support_point(a, b, d);
        if (off_hull(s, n, w.w) > off) {
          s[std::size_t(n++)] = w;
          grown = true;
          break;
        }
      }
    }
    if (!grown) return false;  // the difference is flat: no volume to expand
  }
  return true;
}

}  // namespace

PenetrationResult epa_penetration(const ConvexProxy& a, const ConvexProxy& b) {
  // GJK first: separated cores have no penetration
  GjkStepper g(a, b);
  g.run();
  return narrow::epa_from_gjk(g);
}

PenetrationResult narrow::epa_from_gjk(const GjkStepper& g) {
  PenetrationResult r;
  if (!g.overlap()) return r;
  const ConvexProxy& a = g.proxy_a();
  const ConvexProxy& b = g.proxy_b();
  std::array<SimplexVertex, 4> s{};
  int n = int(g.simplex().size());
  for (int i = 0; i < n; ++i) s[std::size_t(i)] = g.simplex()[std::size_t(i)];
  // the tolerances: 1e-9 m off the hull, kEpaTolerance of gain, or 1e-14 and 1e-15 of the
  // rounding scale where that is more (the same as ever up to 100 km). Some 45 and 4.5 ulps
  // of the scale: enough for the rounding, and no looser (1e-12 and 1e-13 ended a 1 cm pair
  // at 1e10 m with its depth 0.15 of its size off and its normal flipped)
  const double scale = rounding_scale(s, n);
  const double off = std::max(1e-9, 1e-14 * scale), tolerance = std::max(kEpaTolerance, 1e-15 * scale);
  if (!complete_tetrahedron(a, b, s, n, off)) {
    // touching cores with a flat difference: zero depth along any direction
    Vec3 ca, cb;
    g.closest_points(ca, cb);
    r.ok = true;
    r.depth = a.radius + b.radius;
    r.normal = Vec3(0, 0, 1);
    r.point_a = ca + a.radius * r.normal;
    r.point_b = cb - b.radius * r.normal;
    return r;
  }

  // the initial tetrahedron, faces oriented outwards
  Polytope P;
  for (int i = 0; i < 4; ++i) P.verts[std::size_t(i)] = s[std::size_t(i)];
  P.nv = 4;
  if (glm::dot(s[1].w - s[0].w, glm::cross(s[2].w - s[0].w, s[3].w - s[0].w)) < 0) {
    std::swap(P.verts[1], P.verts[2]);
  }
  P.add_face(0, 2, 1);
  P.add_face(0, 1, 3);
  P.add_face(0, 3, 2);
  P.add_face(1, 2, 3);

  // the loops over the faces run without data-dependent branches where they can (which
  // face is nearest, which faces the new point sees: as random as the shapes' poses); the
  // faces stay in the order they were made, so ties go as they always did
  EpaFace nearest{{0, 1, 2}, Vec3(0, 0, 1), 0};
  std::array<int, kMaxFaces> gone;  // the faces the new point sees, in order
  for (int it = 0;; ++it) {
    // nearest face (the first of equals)
    if (P.nl == 0) return r;
    int bq = 0;
    double bd = P.live_dist[0];
    for (int q = 1; q < P.nl; ++q) {
      const double d = P.live_dist[std::size_t(q)];
      bq = d < bd ? q : bq;
      bd = std::min(bd, d);
    }
    if (!(bd < INFINITY)) return r;
    r.iterations = it;
    const EpaFace face = P.faces[std::size_t(P.live[std::size_t(bq)])];
    nearest = face;
    // support along its normal: on the face means the face is part of the boundary
    const SimplexVertex w = support_point(a, b, face.normal, &P.verts[std::size_t(face.v[0])]);
    const double gain = glm::dot(face.normal, w.w) - face.dist;
    if (gain <= tolerance || P.nv >= kMaxVertices || it >= 200) break;
    // the faces w sees (and the nearest) leave; the others close up, in order
    int ns = 0, kept = 0;
    for (int q = 0; q < P.nl; ++q) {
      const int f = P.live[std::size_t(q)];
      const EpaFace& F = P.faces[std::size_t(f)];
      const bool sees = (glm::dot(F.normal, w.w - P.verts[std::size_t(F.v[0])].w) > 0) | (q == bq);
      gone[std::size_t(ns)] = f;
      ns += sees;
      P.live_dist[std::size_t(kept)] = P.live_dist[std::size_t(q)];
      P.live[std::size_t(kept)] = f;
      kept += !sees;
    }
    P.nl = kept;
    // their boundary (the horizon) as directed edges: an edge seen from both sides is
    // interior to the removed region
    std::array<std::array<int, 2>, kMaxHorizon> horizon;
    int nh = 0;
    bool overflow = false;
    for (int q = 0; q < ns; ++q) {
      const EpaFace& F = P.faces[std::size_t(gone[std::size_t(q)])];
      for (int e = 0; e < 3; ++e) {
        const int i = F.v[e], j = F.v[(e + 1) % 3];
        int found = -1;
        for (int h = 0; h < nh; ++h)
          found = (horizon[std::size_t(h)][0] == j) & (horizon[std::size_t(h)][1] == i) ? h : found;
        if (found >= 0) {
          horizon[std::size_t(found)] = horizon[std::size_t(nh - 1)];
          --nh;
        } else if (nh < kMaxHorizon) {
          horizon[std::size_t(nh++)] = {i, j};
        } else {
          overflow = true;
        }
      }
    }
    if (overflow) break;
    if (P.nf + nh > kMaxFaces) P.compact();
    if (P.nf + nh > kMaxFaces) break;  // out of room: report the nearest face found
    const int wi = P.nv++;
    P.verts[std::size_t(wi)] = w;
    for (int h = 0; h < nh; ++h) P.add_face(horizon[std::size_t(h)][0], horizon[std::size_t(h)][1], wi);
  }

  // the origin's projection on the nearest face gives the contact points
  const EpaFace& F = nearest;
  const Vec3 p = F.dist * F.normal;
  const SimplexVertex& A = P.verts[std::size_t(F.v[0])];
  const SimplexVertex& B = P.verts[std::size_t(F.v[1])];
  const SimplexVertex& C = P.verts[std::size_t(F.v[2])];
  const Vec3 fn = glm::cross(B.w - A.w, C.w - A.w);
  const double nn = glm::dot(fn, fn);
  double u = 1.0 / 3, v = 1.0 / 3, wgt = 1.0 / 3;
  if (nn > 0) {
    v = glm::dot(glm::cross(p - A.w, C.w - A.w), fn) / nn;
    wgt = glm::dot(glm::cross(B.w - A.w, p - A.w), fn) / nn;
    u = 1 - v - wgt;
  }
  const Vec3 ca = u * A.a + v * B.a + wgt * C.a;
  const Vec3 cb = u * A.b + v * B.b + wgt * C.b;
  r.ok = true;
  r.normal = F.normal;
  r.depth = F.dist + a.radius + b.radius;
  r.point_a = ca + a.radius * r.normal;
  r.point_b = cb - b.radius * r.normal;
  return r;
}

}  // namespace pba
