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
    // the vertices as three coordinate arrays (the vectorised support scan's layout), each
    // padded to an even length with the last vertex
    const std::size_t padded = v.size() + (v.size() & 1);
    h->vertex_soa_.resize(3 * padded);
    for (std::size_t i = 0; i < padded; ++i) {
      const Vec3& p = v[std::min(i, v.size() - 1)];
      h->vertex_soa_[i] = p.x, h->vertex_soa_[padded + i] = p.y, h->vertex_soa_[2 * padded + i] = p.z;
    }
    // bounds, volume and centroid
    h->bounds_ = {v[0], v[0]};
    for (const Vec3& p : v) h->bounds_ = {glm::min(h->bounds_.lo, p), glm::max(h->bounds_.hi, p)};
    const Moments m = polyhedron_moments(v, h->edges_, h->faces_);
    h->volume_ = m.volume;
    h->centroid_ = m.centroid;
    // the balls about the centroid inside and around the hull, and the edges' arc secants
    // (the narrow phase's pruning bounds)
    h->inner_radius_ = INFINITY;
    for (const ConvexHull::Face& f : h->faces_) h->inner_radius_ = std::min(h->inner_radius_, f.offset - glm::dot(f.normal, m.centroid));
    h->outer_radius_ = 0;
    for (const Vec3& p : v) h->outer_radius_ = std::max(h->outer_radius_, glm::length(p - m.centroid));
    const std::size_t nf = h->faces_.size(), pf = nf + (nf & 1);
    h->face_soa_.resize(4 * pf);
    for (std::size_t i = 0; i < pf; ++i) {
      const ConvexHull::Face& f = h->faces_[std::min(i, nf - 1)];
      h->face_soa_[i] = f.normal.x, h->face_soa_[pf + i] = f.normal.y, h->face_soa_[2 * pf + i] = f.normal.z;
      h->face_soa_[3 * pf + i] = f.offset;
    }
    const std::size_t ne = n_half / 2, pe = ne + (ne & 1);
    h->edge_soa_.resize(10 * pe);
    for (std::size_t i = 0; i < pe; ++i) {
      const std::size_t k = std::min(i, ne - 1);
      const Vec3 u = h->faces_[h->edges_[2 * k].face].normal, w = h->faces_[h->edges_[2 * k + 1].face].normal;
      const Vec3 p = v[h->edges_[2 * k].origin];
      const double c = 1 + glm::dot(u, w);
      const double col[10] = {u.x, u.y, u.z, w.x, w.y, w.z, p.x, p.y, p.z, c > 0 ? std::sqrt(2 / c) : INFINITY};
      for (std::size_t j = 0; j < 10; ++j) h->edge_soa_[j * pe + i] = col[j];
    }
    // the edge directions: each edge's vector with its first non-zero coordinate made
    // positive (and zeros +0, as == holds -0 equal to +0) is the same for two edges exactly
    // when one's vector equals the other's or its negation; sorted by that key (ties by
    // index), the first of each run is the first such edge in index order
    std::vector<std::pair<Vec3, std::uint32_t>> keys(ne);
    for (std::uint32_t i = 0; i < ne; ++i) {
      Vec3 d = v[h->edges_[h->edges_[2 * i].next].origin] - v[h->edges_[2 * i].origin];
      const double first = d.x != 0 ? d.x : d.y != 0 ? d.y : d.z;
      if (first < 0) d = -d;
      keys[i] = {d + Vec3(0.0), 2 * i};
    }
    auto less = [](const Vec3& a, const Vec3& b) {
      return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
    };
    std::sort(keys.begin(), keys.end(), [&](const auto& a, const auto& b) {
      return less(a.first, b.first) || (a.first == b.first && a.second < b.second);
    });
    for (std::size_t i = 0; i < ne; ++i)
      if (i == 0 || keys[i].first != keys[i - 1].first) h->edge_directions_.push_back(keys[i].second);
    std::sort(h->edge_directions_.begin(), h->edge_directions_.end());
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

namespace {

// a triangle of the hull under construction; edge i runs v[i] -> v[(i + 1) % 3] and
// nb[i] is the triangle across it
struct QhFace {
  std::uint32_t v[3] = {0, 0, 0};
  std::uint32_t nb[3] = {0, 0, 0};
  Vec3 n{0, 0, 1};
  double d = 0;
  bool alive = true;
  std::uint32_t stamp = 0;            // last eye that tested it
  bool visible = false;               // seen from the current eye
  std::vector<std::uint32_t> conflict;  // points above it, each in exactly one list
};

// a horizon edge a -> b: the visible triangle `inner` has it, `outer` (not visible) has b -> a
struct HorizonEdge {
  std::uint32_t a, b, inner, outer;
};

int slot_of(const QhFace& f, std::uint32_t a, std::uint32_t b) {
  for (int i = 0; i < 3; ++i)
    if (f.v[i] == a && f.v[(i + 1) % 3] == b) return i;
  return -1;
}

}  // namespace

// Quickhull in 3D (Barber, Dobkin and Huhdanpaa 1996; Gregorius 2014, "Implementing
// Quickhull"). Triangles are grown from a tetrahedron; a point joins when it is more than
// `tol` above a triangle, and a triangle counts as visible from the eye unless the eye is
// more than `tol` below it, so every new triangle rises at least `tol` from its outer
// neighbour's plane (no slivers, no concave edges). Afterwards coplanar triangles merge
// into polygons and vertices left on only two faces (on an edge) are dropped.
std::shared_ptr<ConvexHull> HullBuilder::quickhull(std::span<const Vec3> points, std::string_view where) {
  const std::string at(where);
  // validate: a count the indices hold, finite points within a float's range (the
  // colliders' range; beyond ~1e150 the plane tests' products overflow, and a spread cloud
  // was called flat or collinear)
  if (points.size() < 4)
    throw Error(at + ": a hull needs at least 4 points that are not coplanar, got " + std::to_string(points.size()) +
                " points");
  require_count(static_cast<long long>(points.size()), 4, 1ll << 26, field_path(where, "size"));
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (fits_float(points[i])) continue;
    require_float(points[i], at + "[" + std::to_string(i) + "]");
  }
  const std::uint32_t n = static_cast<std::uint32_t>(points.size());

  // centre the cloud; the tolerance scales with its extent (relative 1e-9, far above the
  // 1e-16 rounding of the plane tests and far below any intended feature)
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const Vec3 mid = 0.5 * (lo + hi);
  std::vector<Vec3> q(n);
  for (std::uint32_t i = 0; i < n; ++i) q[i] = points[i] - mid;
  const Vec3 ext = hi - lo;
  const double tol = 1e-9 * (ext.x + ext.y + ext.z) + 8 * 2.220446049250313e-16 * glm::length(glm::abs(mid));

  // initial tetrahedron: the farthest pair of axis extremes, the point farthest from their
  // line, the point farthest from their plane
  std::uint32_t ext_i[6];
  for (int a = 0; a < 3; ++a) {
    ext_i[2 * a] = ext_i[2 * a + 1] = 0;
    for (std::uint32_t i = 1; i < n; ++i) {
      if (q[i][a] < q[ext_i[2 * a]][a]) ext_i[2 * a] = i;
      if (q[i][a] > q[ext_i[2 * a + 1]][a]) ext_i[2 * a + 1] = i;
    }
  }
  std::uint32_t i0 = 0, i1 = 0;
  double best = -1;
  for (int a = 0; a < 6; ++a)
    for (int b = a + 1; b < 6; ++b) {
      const double dd = glm::length(q[ext_i[a]] - q[ext_i[b]]);
      if (dd > best) best = dd, i0 = ext_i[a], i1 = ext_i[b];
    }
  const std::string flat = ": a hull needs at least 4 points that are not coplanar (a solid with volume); the " +
                           std::to_string(n) + " points ";
  if (!(best > tol)) throw Error(at + flat + "all coincide");
  // the first point of greatest score(q - q[i0]), and that score in `best`
  auto farthest = [&](auto score) {
    std::uint32_t k = 0;
    best = -1;
    for (std::uint32_t i = 0; i < n; ++i) {
      const double dd = score(q[i] - q[i0]);
      if (dd > best) best = dd, k = i;
    }
    return k;
  };
  const Vec3 axis = (q[i1] - q[i0]) / best;
  const std::uint32_t i2 = farthest([&](const Vec3& r) { return glm::length(glm::cross(r, axis)); });
  if (!(best > tol)) throw Error(at + flat + "are collinear");
  const Vec3 pn = glm::normalize(glm::cross(q[i1] - q[i0], q[i2] - q[i0]));
  const std::uint32_t i3 = farthest([&](const Vec3& r) { return std::abs(glm::dot(r, pn)); });
  if (!(best > tol)) throw Error(at + flat + "are coplanar (a flat cloud)");

  std::vector<QhFace> faces;
  faces.reserve(4 * 64);
  auto make_plane = [&](QhFace& f, const Vec3& fallback) {
    const Vec3 c = glm::cross(q[f.v[1]] - q[f.v[0]], q[f.v[2]] - q[f.v[0]]);
    const double len = glm::length(c);
    f.n = len > 0 ? c / len : fallback;
    f.d = glm::dot(f.n, (q[f.v[0]] + q[f.v[1]] + q[f.v[2]]) / 3.0);
  };
  auto dist = [&](const QhFace& f, std::uint32_t i) { return glm::dot(f.n, q[i]) - f.d; };
  // the tetrahedron's faces, each turned so that the fourth point is below it
  {
    const std::uint32_t t[4][4] = {{i0, i1, i2, i3}, {i0, i1, i3, i2}, {i0, i2, i3, i1}, {i1, i2, i3, i0}};
    for (const auto& r : t) {
      QhFace f;
      f.v[0] = r[0], f.v[1] = r[1], f.v[2] = r[2];
      make_plane(f, Vec3(0, 0, 1));
      if (dist(f, r[3]) > 0) {
        std::swap(f.v[1], f.v[2]);
        make_plane(f, Vec3(0, 0, 1));
      }
      faces.push_back(std::move(f));
    }
    for (std::uint32_t a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i)
        for (std::uint32_t b = 0; b < 4; ++b)
          if (b != a && slot_of(faces[b], faces[a].v[(i + 1) % 3], faces[a].v[i]) >= 0) faces[a].nb[i] = b;
  }
  // every other point goes to the triangle it is farthest above, if more than tol
  auto assign = [&](std::uint32_t i, std::size_t first_face) {
    double bd = tol;
    std::size_t bf = faces.size();
    for (std::size_t f = first_face; f < faces.size(); ++f) {
      if (!faces[f].alive) continue;
      const double dd = dist(faces[f], i);
      if (dd > bd) bd = dd, bf = f;
    }
    if (bf < faces.size()) faces[bf].conflict.push_back(i);
  };
  for (std::uint32_t i = 0; i < n; ++i)
    if (i != i0 && i != i1 && i != i2 && i != i3) assign(i, 0);

  // grow: new triangles are appended, so one pass over the array sees every conflict list
  std::vector<std::uint32_t> stack, visible, horizon_from(n, UINT32_MAX), gathered;
  std::vector<HorizonEdge> horizon;
  std::uint32_t stamp = 0;
  for (std::size_t fi = 0; fi < faces.size(); ++fi) {
    while (faces[fi].alive && !faces[fi].conflict.empty()) {
      // the eye: the point farthest above this triangle
      std::vector<std::uint32_t>& cl = faces[fi].conflict;
      std::size_t ek = 0;
      for (std::size_t k = 1; k < cl.size(); ++k)
        if (dist(faces[fi], cl[k]) > dist(faces[fi], cl[ek])) ek = k;
      const std::uint32_t eye = cl[ek];
      // the visible region: triangles reached from this one that the eye is not clearly below
      ++stamp;
      visible.clear();
      stack.assign(1, static_cast<std::uint32_t>(fi));
      faces[fi].stamp = stamp;
      faces[fi].visible = true;
      while (!stack.empty()) {
        const std::uint32_t f = stack.back();
        stack.pop_back();
        visible.push_back(f);
        for (std::uint32_t g : faces[f].nb) {
          if (faces[g].stamp == stamp) continue;
          faces[g].stamp = stamp;
          faces[g].visible = dist(faces[g], eye) > -tol;
          if (faces[g].visible) stack.push_back(g);
        }
      }
      // the horizon: edges between visible and hidden triangles, linked into one loop
      horizon.clear();
      bool simple = true;
      for (std::uint32_t f : visible)
        for (int i = 0; i < 3; ++i) {
          const std::uint32_t g = faces[f].nb[i];
          if (faces[g].visible && faces[g].stamp == stamp) continue;
          const std::uint32_t a = faces[f].v[i], b = faces[f].v[(i + 1) % 3];
          if (horizon_from[a] != UINT32_MAX) simple = false;
          horizon_from[a] = static_cast<std::uint32_t>(horizon.size());
          horizon.push_back({a, b, f, g});
        }
      std::vector<HorizonEdge> loop;
      loop.reserve(horizon.size());
      if (simple) {
        for (std::uint32_t k = 0; loop.size() < horizon.size();) {
          loop.push_back(horizon[k]);
          k = horizon_from[horizon[k].b];
          if (k == UINT32_MAX || k == 0) break;
        }
        if (loop.size() != horizon.size() || horizon_from[loop.back().b] != 0) simple = false;
      }
      for (const HorizonEdge& h : horizon) horizon_from[h.a] = UINT32_MAX;
      for (std::uint32_t f : visible) faces[f].visible = false;
      if (!simple) {
        // a pinched horizon happens only at the rounding limit: leave this point out
        cl.erase(cl.begin() + static_cast<std::ptrdiff_t>(ek));
        continue;
      }
      // the cone of new triangles from the horizon to the eye
      const std::uint32_t base = static_cast<std::uint32_t>(faces.size());
      const std::uint32_t hn = static_cast<std::uint32_t>(loop.size());
      for (std::uint32_t k = 0; k < hn; ++k) {
        QhFace f;
        f.v[0] = loop[k].a, f.v[1] = loop[k].b, f.v[2] = eye;
        f.nb[0] = loop[k].outer;
        f.nb[1] = base + (k + 1) % hn;
        f.nb[2] = base + (k + hn - 1) % hn;
        make_plane(f, faces[loop[k].inner].n);
        QhFace& outer = faces[loop[k].outer];
        outer.nb[slot_of(outer, loop[k].b, loop[k].a)] = base + k;
        faces.push_back(std::move(f));
      }
      // retire the visible triangles and hand their points to the new ones
      gathered.clear();
      for (std::uint32_t f : visible) {
        faces[f].alive = false;
        for (std::uint32_t i : faces[f].conflict)
          if (i != eye) gathered.push_back(i);
        std::vector<std::uint32_t>().swap(faces[f].conflict);
      }
      for (std::uint32_t i : gathered) assign(i, base);
    }
  }

  // merge coplanar triangles: grow a polygon from each largest unmerged triangle over
  // neighbours whose corners all lie within tol of its plane
  std::vector<std::uint32_t> alive;
  for (std::uint32_t f = 0; f < faces.size(); ++f)
    if (faces[f].alive) alive.push_back(f);
  auto area = [&](std::uint32_t f) {
    return glm::length(glm::cross(q[faces[f].v[1]] - q[faces[f].v[0]], q[faces[f].v[2]] - q[faces[f].v[0]]));
  };
  std::vector<double> areas(faces.size(), 0);
  for (std::uint32_t f : alive) areas[f] = area(f);
  std::vector<std::uint32_t> order = alive;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return areas[a] > areas[b] || (areas[a] == areas[b] && a < b);
  });
  std::vector<std::uint32_t> group(faces.size(), UINT32_MAX);
  std::vector<std::vector<std::uint32_t>> loops;
  std::vector<std::uint32_t> members, edge_from(n, UINT32_MAX);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary;
  for (std::uint32_t seed : order) {
    if (group[seed] != UINT32_MAX) continue;
    const std::uint32_t g = static_cast<std::uint32_t>(loops.size());
    const QhFace& sf = faces[seed];
    members.assign(1, seed);
    group[seed] = g;
    for (std::size_t k = 0; k < members.size(); ++k)
      for (std::uint32_t h : faces[members[k]].nb) {
        if (group[h] != UINT32_MAX || glm::dot(faces[h].n, sf.n) <= 0) continue;
        bool flat = true;
        for (std::uint32_t vi : faces[h].v) flat = flat && std::abs(dist(sf, vi)) <= tol;
        if (flat) group[h] = g, members.push_back(h);
      }
    // the polygon's boundary as one loop; anything else keeps the triangles apart
    boundary.clear();
    bool ok = true;
    for (std::uint32_t m : members)
      for (int i = 0; i < 3; ++i)
        if (group[faces[m].nb[i]] != g) {
          const std::uint32_t a = faces[m].v[i];
          if (edge_from[a] != UINT32_MAX) ok = false;
          edge_from[a] = static_cast<std::uint32_t>(boundary.size());
          boundary.push_back({a, faces[m].v[(i + 1) % 3]});
        }
    std::vector<std::uint32_t> lp;
    if (ok) {
      for (std::uint32_t k = 0; lp.size() < boundary.size();) {
        lp.push_back(boundary[k].first);
        k = edge_from[boundary[k].second];
        if (k == UINT32_MAX || k == 0) break;
      }
      ok = lp.size() == boundary.size() && edge_from[boundary[edge_from[lp.back()]].second] == 0;
    }
    for (const auto& be : boundary) edge_from[be.first] = UINT32_MAX;
    if (ok) {
      loops.push_back(std::move(lp));
    } else {
      for (std::size_t k = 0; k < members.size(); ++k) {
        group[members[k]] = static_cast<std::uint32_t>(loops.size());
        loops.push_back({faces[members[k]].v[0], faces[members[k]].v[1], faces[members[k]].v[2]});
      }
    }
  }

  // drop vertices on only two polygons (they lie on an edge), when both keep 3 corners
  std::vector<std::uint32_t> face_count(n, 0);
  for (const auto& l : loops)
    for (std::uint32_t vi : l) ++face_count[vi];
  std::vector<std::vector<std::uint32_t>> where_in(n);
  for (std::uint32_t li = 0; li < loops.size(); ++li)
    for (std::uint32_t vi : loops[li])
      if (face_count[vi] == 2) where_in[vi].push_back(li);
  for (std::uint32_t vi = 0; vi < n; ++vi) {
    if (face_count[vi] != 2) continue;
    const auto& ls = where_in[vi];
    if (loops[ls[0]].size() <= 3 || loops[ls[1]].size() <= 3) continue;
    for (std::uint32_t li : ls) loops[li].erase(std::find(loops[li].begin(), loops[li].end(), vi));
    face_count[vi] = 0;
  }

  // keep the used vertices in input order
  std::vector<std::uint32_t> remap(n, UINT32_MAX);
  for (const auto& l : loops)
    for (std::uint32_t vi : l) remap[vi] = 0;
  std::vector<Vec3> verts;
  for (std::uint32_t i = 0; i < n; ++i)
    if (remap[i] == 0) remap[i] = static_cast<std::uint32_t>(verts.size()), verts.push_back(points[i]);
  for (auto& l : loops)
    for (std::uint32_t& vi : l) vi = remap[vi];
  return from_faces(std::move(verts), loops, where);
}

std::shared_ptr<const ConvexHull> ConvexHull::build(std::span<const Vec3> points, std::string_view where) {
  return HullBuilder::quickhull(points, where);
}

}  // namespace pba
