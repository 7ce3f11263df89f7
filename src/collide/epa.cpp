// Penetration depth by the expanding polytope algorithm (van den Bergen 2001, "Proximity
// Queries and Penetration Depth Computation on 3D Game Objects"): starting from GJK's
// final tetrahedron, which holds the origin, the face of the polytope nearest the origin
// is replaced by the support point of A - B along its normal until the support point
// lies on that face. For polytope cores the Minkowski difference has finitely many faces,
// so the loop ends on one of them and the depth is exact up to kEpaTolerance.
#include <cmath>

#include "narrow_internal.h"

namespace pba {

namespace {

constexpr int kMaxVertices = 128;
constexpr int kMaxFaces = 256;
constexpr int kMaxHorizon = 128;

struct EpaFace {
  int v[3] = {0, 0, 0};
  Vec3 normal{0, 0, 1};
  double dist = 0;
  bool alive = false;
};

struct Polytope {
  std::array<SimplexVertex, kMaxVertices> verts{};
  int nv = 0;
  std::array<EpaFace, kMaxFaces> faces{};
  int nf = 0;

  // a face i, j, k (counter-clockwise seen from outside); degenerate faces get an
  // infinite distance so they are never expanded
  bool add_face(int i, int j, int k) {
    if (nf >= kMaxFaces) return false;
    EpaFace& f = faces[std::size_t(nf++)];
    f.v[0] = i, f.v[1] = j, f.v[2] = k;
    const Vec3 a = verts[std::size_t(i)].w, b = verts[std::size_t(j)].w, c = verts[std::size_t(k)].w;
    const Vec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    f.alive = true;
    if (len <= 1e-30) {
      f.normal = Vec3(0, 0, 1);
      f.dist = INFINITY;
    } else {
      f.normal = n / len;
      f.dist = glm::dot(f.normal, a);
    }
    return true;
  }
};

SimplexVertex support_point(const ConvexProxy& a, const ConvexProxy& b, const Vec3& d) {
  SimplexVertex s;
  s.a = a.support(d);
  s.b = b.support(-d);
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

// grows a GJK simplex of 1-3 points (origin on it) to a tetrahedron by supports along
// directions off its affine hull
bool complete_tetrahedron(const ConvexProxy& a, const ConvexProxy& b, std::array<SimplexVertex, 4>& s, int& n) {
  static const Vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  while (n < 4) {
    bool grown = false;
    if (n == 1) {
      for (const Vec3& d : axes) {
        const SimplexVertex w = support_point(a, b, d);
        if (off_hull(s, n, w.w) > 1e-9) {
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
        if (off_hull(s, n, w.w) > 1e-9) {
          s[std::size_t(n++)] = w;
          grown = true;
        }
      }
    } else {
      const Vec3 nrm = glm::normalize(glm::cross(s[1].w - s[0].w, s[2].w - s[0].w));
      for (const Vec3& d : {nrm, -nrm}) {
        const SimplexVertex w = support_point(a, b, d);
        if (off_hull(s, n, w.w) > 1e-9) {
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
  while (g.step()) {
  }
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
  if (!complete_tetrahedron(a, b, s, n)) {
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

  EpaFace nearest{};
  for (int it = 0;; ++it) {
    // nearest live face
    int best = -1;
    double bd = INFINITY;
    for (int f = 0; f < P.nf; ++f) {
      const EpaFace& F = P.faces[std::size_t(f)];
      if (F.alive && F.dist < bd) bd = F.dist, best = f;
    }
    if (best < 0) return r;
    r.iterations = it;
    const EpaFace face = P.faces[std::size_t(best)];
    nearest = face;
    // support along its normal: on the face means the face is part of the boundary
    const SimplexVertex w = support_point(a, b, face.normal);
    const double gain = glm::dot(face.normal, w.w) - face.dist;
    if (gain <= kEpaTolerance || P.nv >= kMaxVertices || it >= 200) break;
    // remove the faces w sees, keep their boundary (the horizon) as directed edges
    std::array<std::array<int, 2>, kMaxHorizon> horizon{};
    int nh = 0;
    bool overflow = false;
    for (int f = 0; f < P.nf; ++f) {
      EpaFace& F = P.faces[std::size_t(f)];
      if (!F.alive) continue;
      if (glm::dot(F.normal, w.w - P.verts[std::size_t(F.v[0])].w) <= 0 && f != best) continue;
      F.alive = false;
      for (int e = 0; e < 3; ++e) {
        const int i = F.v[e], j = F.v[(e + 1) % 3];
        // an edge seen from both sides is interior to the removed region
        int found = -1;
        for (int h = 0; h < nh; ++h)
          if (horizon[std::size_t(h)][0] == j && horizon[std::size_t(h)][1] == i) found = h;
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
    // compact the face array when it fills
    if (P.nf + nh > kMaxFaces) {
      int k = 0;
      for (int f = 0; f < P.nf; ++f)
        if (P.faces[std::size_t(f)].alive) P.faces[std::size_t(k++)] = P.faces[std::size_t(f)];
      P.nf = k;
      if (P.nf + nh > kMaxFaces) break;  // out of room: report the nearest face found
    }
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
