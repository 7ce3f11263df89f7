// Convex hulls: the half-edge structure, support by hill climbing, 3D quickhull and the
// exact mass properties of a polyhedron.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "pba/collide/shape.h"

namespace pba {

namespace {

// volume, centroid and second moment about the centroid, integral of (x-c)(x-c)^T dV,
// of a closed polyhedron, summed over signed tetrahedra from a reference point inside
// (Tonon 2004: a tetrahedron with a vertex at the origin and edges a, b, c has
// integral x x^T dV = det/120 (a a^T + b b^T + c c^T + s s^T), s = a + b + c, det = a . b x c)
struct Moments {
  double volume = 0;
  Vec3 centroid{0, 0, 0};
  Mat3 covariance{0.0};
};

Moments polyhedron_moments(std::span<const Vec3> v, std::span<const ConvexHull::HalfEdge> e,
                           std::span<const ConvexHull::Face> faces) {
  // reference: the vertex mean, which keeps the terms small
  Vec3 r(0.0);
  for (const Vec3& p : v) r += p;
  r /= static_cast<double>(v.size());
  // fan each face from its first vertex
  double vol = 0;
  Vec3 first(0.0);
  Mat3 cov(0.0);
  for (const ConvexHull::Face& f : faces) {
    const Vec3 a = v[e[f.edge].origin] - r;
    for (std::uint32_t i = e[f.edge].next; e[i].next != f.edge; i = e[i].next) {
      const Vec3 b = v[e[i].origin] - r, c = v[e[e[i].next].origin] - r;
      const double det = glm::dot(a, glm::cross(b, c));
      const Vec3 s = a + b + c;
      vol += det / 6;
      first += (det / 24) * s;
      cov += (det / 120) * (glm::outerProduct(a, a) + glm::outerProduct(b, b) + glm::outerProduct(c, c) +
                            glm::outerProduct(s, s));
    }
  }
  // shift the second moment to the centroid
  Moments m;
  m.volume = vol;
  const Vec3 cr = first / vol;
  m.centroid = r + cr;
  m.covariance = cov - vol * glm::outerProduct(cr, cr);
  return m;
}

}  // namespace

/// Builds hulls: the half-edge structure from face loops, and quickhull.
struct HullBuilder {
  // the hull of `verts` whose faces are the vertex loops `loops` (counter-clockwise from
  // outside, a closed two-manifold); half edges of one edge get indices 2i and 2i + 1
  static std::shared_ptr<ConvexHull> from_faces(std::vector<Vec3> verts,
                                                const std::vector<std::vector<std::uint32_t>>& loops,
                                                std::string_view where) {
    auto h = std::make_shared<ConvexHull>();
    h->vertices_ = std::move(verts);
    const std::vector<Vec3>& v = h->vertices_;
    // pair the directed edges: the first time an edge is met it takes 2i, its twin 2i + 1
    std::map<std::uint64_t, std::uint32_t> pair_of;
    std::size_t n_half = 0;
    for (const auto& l : loops) n_half += l.size();
    h->edges_.assign(n_half, {});
    std::vector<bool> used(n_half, false);
    h->faces_.resize(loops.size());
    for (std::uint32_t f = 0; f < loops.size(); ++f) {
      const auto& l = loops[f];
      std::vector<std::uint32_t> ids(l.size());
      for (std::size_t j = 0; j < l.size(); ++j) {
        const std::uint32_t a = l[j], b = l[(j + 1) % l.size()];
        const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
        auto it = pair_of.find(key);
        std::uint32_t id;
        if (it == pair_of.end()) {
          id = static_cast<std::uint32_t>(2 * pair_of.size());
          pair_of.emplace(key, id);
        } else {
          id = it->second + 1;
        }
        if (id >= n_half || used[id]) throw Error(std::string(where) + ": internal error, the hull is not a closed two-manifold");
        used[id] = true;
        h->edges_[id].origin = a;
        h->edges_[id].face = f;
        h->edges_[id].twin = id ^ 1u;
        ids[j] = id;
      }
      for (std::size_t j = 0; j < l.size(); ++j) h->edges_[ids[j]].next = ids[(j + 1) % l.size()];
      h->faces_[f].edge = ids[0];
    }
    if (2 * pair_of.size() != n_half) throw Error(std::string(where) + ": internal error, the hull has an open edge");
    // one outgoing edge per vertex
    h->vertex_edge_.assign(v.size(), 0);
    for (std::uint32_t i = static_cast<std::uint32_t>(n_half); i-- > 0;) h->vertex_edge_[h->edges_[i].origin] = i;
    // face planes by Newell's method (exact for planar loops), offset the mean over the loop
    for (std::uint32_t f = 0; f < loops.size(); ++f) {
      const auto& l = loops[f];
      Vec3 n(0.0);
      const Vec3 o = v[l[0]];
      for (std::size_t j = 0; j < l.size(); ++j) {
        const Vec3 a = v[l[j]] - o, b = v[l[(j + 1) % l.size()]] - o;
        n += Vec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
      }
      n = glm::normalize(n);
      double d = 0;
      for (std::uint32_t i : l) d += glm::dot(n, v[i]);
      h->faces_[f].normal = n;
      h->faces_[f].offset = d / static_cast<double>(l.size());
    }
    // bounds, volume and centroid
    h->bounds_ = {v[0], v[0]};
    for (const Vec3& p : v) h->bounds_ = {glm::min(h->bounds_.lo, p), glm::max(h->bounds_.hi, p)};
    const Moments m = polyhedron_moments(v, h->edges_, h->faces_);
    h->volume_ = m.volume;
    h->centroid_ = m.centroid;
    return h;
  }

  static std::shared_ptr<ConvexHull> quickhull(std::span<const Vec3> points, std::string_view where);
};

std::shared_ptr<const ConvexHull> ConvexHull::box(const Vec3& half) {
  require_positive(half.x, "ConvexHull::box half_extents.x");
  require_positive(half.y, "ConvexHull::box half_extents.y");
  require_positive(half.z, "ConvexHull::box half_extents.z");
  // vertex i has bit 0, 1, 2 set for +x, +y, +z
  std::vector<Vec3> v(8);
  for (int i = 0; i < 8; ++i) v[i] = Vec3(i & 1 ? half.x : -half.x, i & 2 ? half.y : -half.y, i & 4 ? half.z : -half.z);
  // faces +x, -x, +y, -y, +z, -z, each counter-clockwise seen from outside
  const std::vector<std::vector<std::uint32_t>> loops = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3},
                                                         {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  return HullBuilder::from_faces(std::move(v), loops, "ConvexHull::box");
}

std::uint32_t ConvexHull::support_index(const Vec3& d, std::uint32_t hint) const {
  const std::uint32_t n = static_cast<std::uint32_t>(vertices_.size());
  // small hulls: a plain scan is as fast and independent of the hint
  if (n <= 16) {
    std::uint32_t best = 0;
    double bd = glm::dot(vertices_[0], d);
    for (std::uint32_t i = 1; i < n; ++i) {
      const double s = glm::dot(vertices_[i], d);
      if (s > bd) bd = s, best = i;
    }
    return best;
  }
  // hill climbing over the vertex graph: on a convex polytope a vertex no neighbour of
  // which is farther is the farthest (the simplex method's argument), and each move
  // strictly increases the support value, so the climb ends
  std::uint32_t best = hint < n ? hint : 0;
  double bd = glm::dot(vertices_[best], d);
  for (bool moved = true; moved;) {
    moved = false;
    const std::uint32_t start = vertex_edge_[best];
    std::uint32_t e = start;
    do {
      const std::uint32_t to = edges_[edges_[e].twin].origin;
      const double s = glm::dot(vertices_[to], d);
      if (s > bd) {
        bd = s, best = to, moved = true;
        break;
      }
      e = edges_[edges_[e].twin].next;
    } while (e != start);
  }
  return best;
}

MassProperties ConvexHull::mass_properties(double density) const {
  require_positive(density, "ConvexHull::mass_properties density");
  const Moments m = polyhedron_moments(vertices_, edges_, faces_);
  MassProperties mp;
  mp.volume = m.volume;
  mp.mass = density * m.volume;
  mp.center = m.centroid;
  // inertia from the second moment: I = rho (tr(C) 1 - C)
  const Mat3& c = m.covariance;
  const double tr = c[0][0] + c[1][1] + c[2][2];
  mp.inertia = density * (tr * Mat3(1.0) - c);
  return mp;
}

std::shared_ptr<ConvexHull> HullBuilder::quickhull(std::span<const Vec3>, std::string_view where) {
  throw Error(std::string(where) + ": quickhull is not implemented yet");
}

std::shared_ptr<const ConvexHull> ConvexHull::build(std::span<const Vec3> points, std::string_view where) {
  return HullBuilder::quickhull(points, where);
}

}  // namespace pba
