// Box-box separating axes in closed form: the fifteen axes of Gottschalk, Lin and Manocha
// 1996 ("OBBTree"), three face normals of each box and nine edge cross products, measured
// with the rotation between the boxes and its absolute value, in A's frame. The choice
// between them, the feature ids and the face clipping are the polyhedral path's
// (sat.cpp, clip.cpp), with the box's fixed half-edge numbering, so a box pair and the
// same pair as hulls of boxes give the same manifold.
#include <cmath>
#include <utility>

#include "narrow_internal.h"

namespace pba::narrow {

namespace {

// half edge from vertex v along +axis k (v with bit k clear), from the box topology
struct BoxEdgeTable {
  std::uint32_t he[8][3] = {};
};
constexpr BoxEdgeTable make_edge_table() {
  BoxEdgeTable t{};
  for (std::uint32_t e = 0; e < 24; ++e) {
    const std::uint32_t u = kBoxTopology.edges[e].origin;
    const std::uint32_t v = kBoxTopology.edges[kBoxTopology.edges[e].twin].origin;
    const std::uint32_t d = u ^ v;
    const std::uint32_t k = d == 1 ? 0 : (d == 2 ? 1 : 2);
    if ((u & d) == 0) t.he[u][k] = e;
  }
  return t;
}
constexpr BoxEdgeTable kEdgeTable = make_edge_table();


// the four sides of each face in the face's coordinates (u, v) = (x[k + 1], x[k + 2]) of
// face axis k, in a fixed order: u = +h, u = -h, v = +h, v = -h. For each, the half edge on
// it (the side plane's label) and its place in the face's half-edge loop (the order
// Sutherland-Hodgman clipping takes the sides in, clip.cpp)
struct FaceSides {
  std::uint32_t edge[4] = {};
  int order[4] = {};
  std::uint32_t side_label[4] = {};    // the side plane's label (kSideLabel | edge), masked
  std::uint32_t corner_id[2][2] = {};  // [u side][v side]: the id of the rectangle's corner
};
struct FaceSideTable {
  FaceSides face[6] = {};
};
constexpr FaceSideTable make_face_sides() {
  FaceSideTable t{};
  for (std::uint32_t f = 0; f < 6; ++f) {
    std::uint32_t e = kBoxTopology.face_edge[f];
    const std::uint32_t k = f / 2;
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t a = kBoxTopology.edges[e].origin;
      const std::uint32_t b = kBoxTopology.edges[kBoxTopology.edges[e].next].origin;
      // the edge runs along bit a ^ b; the face fixes bit k; the side is the third
      const std::uint32_t bit = 7u & ~((a ^ b) | (1u << k));
      const bool on_u = bit == (1u << ((k + 1) % 3));
      const int c = (on_u ? 0 : 2) + ((a & bit) ? 0 : 1);
      t.face[f].edge[c] = e;
      t.face[f].order[c] = i;
      t.face[f].side_label[c] = (kSideLabel | e) & kLabelMask;
      e = kBoxTopology.edges[e].next;
    }
    // a corner is met where the later side (in loop order) clips the edge the earlier one made
    for (int ku = 0; ku < 2; ++ku)
      for (int kv = 0; kv < 2; ++kv) {
        const FaceSides& s = t.face[f];
        const bool u_first = s.order[ku] < s.order[2 + kv];
        const std::uint32_t first = s.edge[u_first ? ku : 2 + kv], second = s.edge[u_first ? 2 + kv : ku];
        t.face[f].corner_id[ku][kv] = cross_id(kSideLabel | first, kSideLabel | second);
      }
  }
  return t;
}
constexpr FaceSideTable kFaceSides = make_face_sides();

// each face's loop: its corners in order, as c +- a1 +- a2 with a1, a2 the half axes along
// the face's other two axes k + 1, k + 2 (corner index 2 [bit k + 1 set] + [bit k + 2 set]),
// each with its vertex and the half edge leaving it
struct FaceLoopCorner {
  int corner = 0;
  std::uint32_t vertex = 0;
  std::uint32_t edge = 0;
};
struct FaceLoopTable {
  FaceLoopCorner face[6][4] = {};
};
constexpr FaceLoopTable make_face_loops() {
  FaceLoopTable t{};
  for (std::uint32_t f = 0; f < 6; ++f) {
    const std::uint32_t k = f / 2, j1 = (k + 1) % 3, j2 = (k + 2) % 3;
    std::uint32_t e = kBoxTopology.face_edge[f];
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t v = kBoxTopology.edges[e].origin;
      t.face[f][i] = {int(2 * ((v >> j1) & 1) + ((v >> j2) & 1)), v, e};
      e = kBoxTopology.edges[e].next;
    }
  }
  return t;
}
constexpr FaceLoopTable kFaceLoops = make_face_loops();

// a point of the incident polygon in the reference face's coordinates (u, v in the face, w
// along its axis), with its feature id and the label of the polygon edge from it to the next
// point (as ClipPoint)
struct FacePoint {
  double u, v, w;
  std::uint32_t id;
  std::uint32_t label;
};

// The incident face (a parallelogram: centre c, half axes a1, a2, in face coordinates; its
// corners `quad` in loop order, each labelled by the half edge leaving it) clipped by the
// reference face f (the rectangle |u| <= hu, |v| <= hv). The clipped polygon's vertices are
// the incident corners inside the rectangle, the crossings of incident edges with the
// rectangle's sides that lie within the other sides, and the rectangle's corners inside the
// parallelogram: each is found directly, with the feature id Sutherland-Hodgman clipping
// (1974) by the sides in loop order would give it (clip.cpp): an incident corner its vertex,
// a crossing (edge, side), a rectangle corner (earlier side, later side). The polygon's
// order is not kept (the reduction does not need it). Writes the points whose depth below
// the face, h_face - s0 w, is at least -margin into `out` (room for 24, the candidates) and their depths into
// `depth`; returns the count.
int clip_face_rect(const FacePoint* quad, const double* c, const double* a1, const double* a2, std::uint32_t f,
                   double hu, double hv, double h_face, double s0, double margin, FacePoint* out, double* depth) {
  const FaceSides& side = kFaceSides.face[f];
  // the outcodes: bit k set when the corner lies outside side k
  unsigned code[4];
  for (int i = 0; i < 4; ++i) {
    const double u = quad[i].u, v = quad[i].v;
    code[i] = unsigned(u > hu) | unsigned(-u > hu) << 1 | unsigned(v > hv) << 2 | unsigned(-v > hv) << 3;
  }
  // every corner on the outer side of one line: nothing overlaps
  if (code[0] & code[1] & code[2] & code[3]) return 0;
  // every candidate is written in place and kept (the count advanced) by its test, without a
  // branch: the outcomes are as random as the poses
  int n = 0;
  auto emit = [&](double u, double v, double w, std::uint32_t id, bool keep) {
    out[n] = {u, v, w, id, 0};
    n += keep;
  };
  for (int i = 0; i < 4; ++i) emit(quad[i].u, quad[i].v, quad[i].w, quad[i].id, code[i] == 0);
  if ((code[0] | code[1] | code[2] | code[3]) != 0) {
    // edge i from corner i to corner i + 1 crosses side k where their outcodes differ in bit
    // k: an edge that crosses no side is skipped (one branch per edge measured 3% faster
    // than computing its four candidates for nothing); an edge that crosses one computes all
    // four (edge, side) candidates and keeps them by that bit (a loop over the crossings
    // alone mispredicts its count, and a branch per pair of sides measured 2% slower); the
    // sides u = +-hu share the edge's 1 / du, the sides v = +-hv its 1 / dv
    for (int i = 0; i < 4; ++i) {
      const FacePoint& p = quad[i];
      const FacePoint& q = quad[(i + 1) & 3];
      const unsigned cross = code[i] ^ code[(i + 1) & 3];
      if (cross == 0) continue;
      const double du = q.u - p.u, dv = q.v - p.v, dw = q.w - p.w;
      const double iu = 1 / du, iv = 1 / dv;
      const std::uint32_t edge_id = kIdCross | ((p.label & kLabelMask) << 15);
      for (int k = 0; k < 2; ++k) {
        const double x = k == 0 ? hu : -hu;
        const double r = (x - p.u) * iu, v = p.v + dv * r;
        emit(x, v, p.w + dw * r, edge_id | side.side_label[k], ((cross >> k) & 1) & (std::abs(v) <= hv));
      }
      for (int k = 2; k < 4; ++k) {
        const double y = k == 2 ? hv : -hv;
        const double r = (y - p.v) * iv, u = p.u + du * r;
        emit(u, y, p.w + dw * r, edge_id | side.side_label[k], ((cross >> k) & 1) & (std::abs(u) <= hu));
      }
    }
    // the rectangle's corners inside the parallelogram: c + alpha a1 + beta a2, |alpha|,
    // |beta| <= 1 (none when the parallelogram is flat)
    const double det = a1[0] * a2[1] - a1[1] * a2[0];
    const double inv = 1 / det;
    for (int ku = 0; ku < 2; ++ku)
      for (int kv = 0; kv < 2; ++kv) {
        const double u = ku == 0 ? hu : -hu, v = kv == 0 ? hv : -hv;
        const double du = u - c[0], dv = v - c[1];
        const double alpha = (du * a2[1] - dv * a2[0]) * inv, beta = (a1[0] * dv - a1[1] * du) * inv;
        emit(u, v, c[2] + alpha * a1[2] + beta * a2[2], side.corner_id[ku][kv],
             (det != 0) & (std::abs(alpha) <= 1) & (std::abs(beta) <= 1));
      }
  }
  // the points at most `margin` above the face
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    const double d = h_face - s0 * out[i].w;
    out[kept] = out[i];
    depth[kept] = d;
    kept += d >= -margin;
  }
  return kept;
}

// reduces candidate points (face coordinates of the point on B, depth, id) to at most four
// by the rules of reduce() (clip.cpp), in 2D: the same choices, as the areas about the face
// normal are the same numbers; writes the chosen indices to `pick`, returns their count
int reduce_face_points(const FacePoint* b, const double* depth, int count, int* pick) {
  if (count <= Manifold::kMaxPoints) {
    for (int i = 0; i < count; ++i) pick[i] = i;
    return count;
  }
  // without branches: a point already chosen enters each search with a value no candidate
  // loses to (-1 for the squared distance and the area, 0 for the added area)
  int i1 = 0;
  double best = depth[0];
  for (int i = 1; i < count; ++i) keep_max(depth[i], i, best, i1);
  int i2 = -1;
  best = -1;
  for (int i = 0; i < count; ++i) {
    const double du = b[i].u - b[i1].u, dv = b[i].v - b[i1].v, dw = b[i].w - b[i1].w;
    const double free = i != i1;
    keep_max((du * du + dv * dv + dw * dw) * free + (free - 1), i, best, i2);
  }
  auto area = [&](int x, int y, int z) {
    return (b[y].u - b[x].u) * (b[z].v - b[x].v) - (b[y].v - b[x].v) * (b[z].u - b[x].u);
  };
  int i3 = -1;
  best = -1;
  for (int i = 0; i < count; ++i) {
    const double free = (i != i1) & (i != i2);
    keep_max(std::abs(area(i1, i2, i)) * free + (free - 1), i, best, i3);
  }
  const double orient = area(i1, i2, i3) >= 0 ? 1.0 : -1.0;
  int i4 = -1;
  best = 0;
  for (int i = 0; i < count; ++i) {
    const double free = (i != i1) & (i != i2) & (i != i3);
    const double out = std::max({-orient * area(i1, i2, i), -orient * area(i2, i3, i), -orient * area(i3, i1, i)});
    keep_max(out * free, i, best, i4);
  }
  pick[0] = i1, pick[1] = i2, pick[2] = i3;
  if (i4 < 0) return 3;
  pick[3] = i4;
  return 4;
}

// the pair in A's frame, as plain arrays (a glm vector indexed by a run-time index goes
// through a switch; these loops index by axis everywhere)
struct BoxPair {
  double R[3][3];   // R[j][i]: component i, in A's frame, of B's axis j (glm's column j)
  double AR[3][3];  // |R| + 1e-12
  double t[3];      // B's centre in A's frame
  double tb[3];     // t in B's axes: R^T t
  double ha[3], hb[3];
};

constexpr int kNext[3] = {1, 2, 0}, kPrev[3] = {2, 0, 1};

double face_a_sep(const BoxPair& p, int i) {
  const double rb = p.hb[0] * p.AR[0][i] + p.hb[1] * p.AR[1][i] + p.hb[2] * p.AR[2][i];
  return std::abs(p.t[i]) - p.ha[i] - rb;
}
double face_b_sep(const BoxPair& p, int j) {
  const double ra = p.ha[0] * p.AR[j][0] + p.ha[1] * p.AR[j][1] + p.ha[2] * p.AR[j][2];
  return std::abs(p.tb[j]) - p.hb[j] - ra;
}
// axis e_i x b_j, unnormalised: L = (L[i1], L[i2]) = (-R[j][i2], R[j][i1]) with i1, i2 the
// other two axes cyclically; its squared length, and the numerator of the separation: the
// radii are sums of entries of |R| (Gottschalk 1996, table 1)
struct EdgeAxis {
  double num, len2, l1, l2, d;
};
[[gnu::always_inline]] inline EdgeAxis edge_axis(const BoxPair& p, int i, int j) {
  const int i1 = kNext[i], i2 = kPrev[i], j1 = kNext[j], j2 = kPrev[j];
  EdgeAxis a;
  a.l1 = -p.R[j][i2], a.l2 = p.R[j][i1];
  const double ra = p.ha[i1] * p.AR[j][i2] + p.ha[i2] * p.AR[j][i1];
  const double rb = p.hb[j1] * p.AR[j2][i] + p.hb[j2] * p.AR[j1][i];
  a.d = p.t[i1] * a.l1 + p.t[i2] * a.l2;
  a.num = std::abs(a.d) - ra - rb;
  a.len2 = a.l1 * a.l1 + a.l2 * a.l2;
  return a;
}
// near-parallel edges (sin below ~0.3 degrees, as in sat.cpp): their cross product is noise,
// and the face axes cover them
constexpr double kParallel2 = 0.005 * 0.005;
// the separation along e_i x b_j, -inf for near-parallel edges
[[gnu::always_inline]] inline double edge_sep(const BoxPair& p, int i, int j) {
  const EdgeAxis a = edge_axis(p, i, j);
  return a.len2 < kParallel2 ? -INFINITY : a.num / std::sqrt(a.len2);
}
// the numerators and squared lengths of all nine, k = 3 i + j, the indices known at compile time
template <int... K>
[[gnu::always_inline]] inline void edge_terms(const BoxPair& p, double* num, double* len2,
                                              std::integer_sequence<int, K...>) {
  ((num[K] = edge_axis(p, K / 3, K % 3).num, len2[K] = edge_axis(p, K / 3, K % 3).len2), ...);
}

Vec3 corner(const double* h, std::uint32_t v) {
  return Vec3((v & 1) ? h[0] : -h[0], (v & 2) ? h[1] : -h[1], (v & 4) ? h[2] : -h[2]);
}
Vec3 column(const double (&R)[3][3], int j) { return Vec3(R[j][0], R[j][1], R[j][2]); }

}  // namespace

void collide_boxes_sat(const Vec3& ha, const Pose& pa, const Vec3& hb, const Pose& pb, double margin, SatCache* cache,
                       Manifold& m) {
  m.count = 0;
  // the bounding spheres first: each box lies within |h| of its centre, so centres farther
  // apart than |ha| + |hb| + margin (with room for rounding) leave the boxes farther apart
  // than the margin (the broad phase's box pairs are often this far apart)
  {
    const Vec3 d = pb.position - pa.position;
    const double r = std::sqrt(glm::dot(ha, ha)) + std::sqrt(glm::dot(hb, hb)) + margin;
    if (glm::dot(d, d) > r * r * (1 + 1e-12)) return;
  }
  BoxPair p;
  {
    const Quat qa_inv = glm::conjugate(pa.rotation);
    const Mat3 R = glm::mat3_cast(qa_inv * pb.rotation);
    const Vec3 t = qa_inv * (pb.position - pa.position);
    for (int j = 0; j < 3; ++j) {
      p.ha[j] = ha[j], p.hb[j] = hb[j], p.t[j] = t[j];
      for (int i = 0; i < 3; ++i) p.R[j][i] = R[j][i], p.AR[j][i] = std::abs(R[j][i]) + 1e-12;
    }
    for (int j = 0; j < 3; ++j) p.tb[j] = p.R[j][0] * p.t[0] + p.R[j][1] * p.t[1] + p.R[j][2] * p.t[2];
  }

  // the cached axis first
  if (cache) {
    double s = -INFINITY;
    if (cache->kind == SatCache::Kind::FaceA && cache->index_a < 6) s = face_a_sep(p, int(cache->index_a / 2));
    else if (cache->kind == SatCache::Kind::FaceB && cache->index_b < 6) s = face_b_sep(p, int(cache->index_b / 2));
    else if (cache->kind == SatCache::Kind::Edges && cache->index_a < 24 && cache->index_b < 24) {
      auto axis_of = [](std::uint32_t e) {
        const std::uint32_t d = kBoxTopology.edges[e].origin ^ kBoxTopology.edges[kBoxTopology.edges[e].twin].origin;
        return d == 1 ? 0 : (d == 2 ? 1 : 2);
      };
      s = edge_sep(p, axis_of(cache->index_a), axis_of(cache->index_b));
    }
    if (s > margin) return;
  }

  // faces of A, faces of B
  double fa = -INFINITY, fb = -INFINITY;
  int ia = 0, ib = 0;
  for (int i = 0; i < 3; ++i) {
    const double s = face_a_sep(p, i);
    keep_max(s, i, fa, ia);
  }
  const std::uint32_t face_a = std::uint32_t(2 * ia + (p.t[ia] > 0 ? 1 : 0));
  if (fa > margin) {
    if (cache) *cache = {SatCache::Kind::FaceA, face_a, 0};
    return;
  }
  for (int j = 0; j < 3; ++j) {
    const double s = face_b_sep(p, j);
    keep_max(s, j, fb, ib);
  }
  // B's face that looks at A: its outward normal points along -t
  const std::uint32_t face_b = std::uint32_t(2 * ib + (p.tb[ib] < 0 ? 1 : 0));
  if (fb > margin) {
    if (cache) *cache = {SatCache::Kind::FaceB, 0, face_b};
    return;
  }

  // the nine edge axes, unrolled (constant indices keep everything in registers); an edge
  // axis matters only when it separates (beyond the margin) or beats the faces by the
  // hysteresis below (Gregorius 2013), that is when it exceeds `relevant`
  constexpr double kRelEdge = 0.90, kRelFace = 0.98, kAbs = 0.5 * 0.005;
  const double relevant = std::min(margin, kRelEdge * std::max(fa, fb) + kAbs);
  double ee = -INFINITY;
  int ek = 0;
  {
    // numerators and squared lengths unrolled, then the ratios in a loop the compiler
    // vectorises
    std::array<double, 9> num, len2, sep;
    edge_terms(p, num.data(), len2.data(), std::make_integer_sequence<int, 9>{});
    for (std::size_t k = 0; k < 9; ++k) sep[k] = len2[k] < kParallel2 ? -INFINITY : num[k] / std::sqrt(len2[k]);
    for (int k = 0; k < 9; ++k) {
      keep_max(sep[std::size_t(k)], k, ee, ek);
    }
  }
  const int ei = ek / 3, ej = ek % 3;
  if (ee > relevant) {
    // the axis from A to B, and the supporting edges: A's along axis ei farthest along it,
    // B's along ej farthest along its opposite
    const EdgeAxis a = edge_axis(p, ei, ej);
    Vec3 L(0.0);
    L[kNext[ei]] = a.l1;
    L[kPrev[ei]] = a.l2;
    const Vec3 axis = (a.d >= 0 ? L : -L) / std::sqrt(a.len2);
    std::uint32_t va = 0, vb = 0;
    for (int k = 0; k < 3; ++k)
      if (k != ei && axis[k] > 0) va |= 1u << k;
    for (int k = 0; k < 3; ++k)
      if (k != ej && glm::dot(column(p.R, k), axis) < 0) vb |= 1u << k;
    const std::uint32_t edge_a = kEdgeTable.he[va][ei] & ~1u, edge_b = kEdgeTable.he[vb][ej] & ~1u;
    if (cache) *cache = {SatCache::Kind::Edges, edge_a, edge_b};
    if (ee > margin) return;
    // edge contact: the closest points of the two edges
    Vec3 da(0.0);
    da[ei] = 1;
    const Vec3 tv(p.t[0], p.t[1], p.t[2]);
    const Mat3 R(column(p.R, 0), column(p.R, 1), column(p.R, 2));
    const Vec3 a0 = corner(p.ha, va), a1 = a0 + 2 * p.ha[ei] * da;
    const Vec3 b0 = R * corner(p.hb, vb) + tv, b1 = b0 + 2 * p.hb[ej] * column(p.R, ej);
    Vec3 ca, cb;
    closest_segments(a0, a1, b0, b1, ca, cb);
    m.normal = pa.rotation * axis;
    ca = apply(pa, ca);
    cb = apply(pa, cb);
    m.count = 1;
    m.points[0] = {ca, cb, glm::dot(ca - cb, m.normal), edge_pair_id(edge_a, edge_b)};
    return;
  }
  const bool ref_a = !(fb > kRelFace * fa + kAbs);
  if (cache) *cache = ref_a ? SatCache{SatCache::Kind::FaceA, face_a, 0} : SatCache{SatCache::Kind::FaceB, 0, face_b};

  // clip in the reference face's own coordinates, in 2D: the incident box's face most
  // anti-parallel to the reference normal, clipped by the four sides of the reference face
  // (lines u = +-h, v = +-h) in the order of the face's half-edge loop, so the labels and ids
  // are those of the polyhedral path (clip.cpp). Rri[c]: the incident box's axis c in the
  // reference frame, tri its centre
  double Rri[3][3], tri[3];
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) Rri[c][r] = ref_a ? p.R[c][r] : p.R[r][c];
  for (int c = 0; c < 3; ++c) tri[c] = ref_a ? p.t[c] : -p.tb[c];
  const double* hr = ref_a ? p.ha : p.hb;
  const double* hi = ref_a ? p.hb : p.ha;
  const std::uint32_t fr = ref_a ? face_a : face_b;
  const int k0 = int(fr / 2), k1 = kNext[k0], k2 = kPrev[k0];
  const double s0 = double(int(fr & 1) * 2 - 1);
  // the incident face: the incident axis most parallel to the normal, its side facing back
  int k = 0;
  double best = -1;
  for (int c = 0; c < 3; ++c) {
    const double d = std::abs(Rri[c][k0]);
    if (d > best) best = d, k = c;
  }
  const std::uint32_t fi = std::uint32_t(2 * k + (Rri[k][k0] * s0 > 0 ? 0 : 1));
  // its corners in loop order, each labelled by the half edge leaving it, in face coordinates
  // (u, v, w) = (x[k1], x[k2], x[k0]): centre c, half axes a1, a2
  std::array<FacePoint, 4> quad;
  std::array<FacePoint, 24> pts;
  std::array<double, 24> depth;
  int kept = 0;
  {
    const int j1 = kNext[k], j2 = kPrev[k];
    const double hk = hi[k] * double(int(fi & 1) * 2 - 1);
    const int perm[3] = {k1, k2, k0};
    double c[3], a1[3], a2[3];
    for (int r = 0; r < 3; ++r) {
      c[r] = tri[perm[r]] + Rri[k][perm[r]] * hk;
      a1[r] = Rri[j1][perm[r]] * hi[j1];
      a2[r] = Rri[j2][perm[r]] * hi[j2];
    }
    // the four corners c +- a1 +- a2, then in the face's loop order (kFaceLoops)
    double corners[4][3];
    for (int r = 0; r < 3; ++r) {
      const double lo = c[r] - a1[r], hi1 = c[r] + a1[r];
      corners[0][r] = lo - a2[r], corners[1][r] = lo + a2[r], corners[2][r] = hi1 - a2[r], corners[3][r] = hi1 + a2[r];
    }
    for (std::size_t i = 0; i < 4; ++i) {
      const FaceLoopCorner& q = kFaceLoops.face[fi][i];
      const double* x = corners[q.corner];
      quad[i] = {x[0], x[1], x[2], q.vertex, q.edge};
    }
    kept = clip_face_rect(quad.data(), c, a1, a2, fr, hr[k1], hr[k2], hr[k0], s0, margin, pts.data(), depth.data());
  }
  FacePoint* in = pts.data();
  const double w_ref = s0 * hr[k0];
  if (kept == 0) {
    // the incident face lies outside the reference face's sides: the deepest vertex alone
    // (the incident corner farthest along -normal)
    std::uint32_t v = 0;
    for (int c = 0; c < 3; ++c)
      if (-s0 * Rri[c][k0] >= 0) v |= 1u << c;
    double q[3];
    for (int r = 0; r < 3; ++r) {
      q[r] = tri[r];
      for (int c = 0; c < 3; ++c) q[r] += Rri[c][r] * ((v >> c) & 1 ? hi[c] : -hi[c]);
    }
    in[0] = {q[k1], q[k2], q[k0], vertex_id(v), 0};
    depth[0] = hr[k0] - s0 * q[k0];
    kept = 1;
  }
  // B's points: the incident points when A holds the reference face, else their feet on it
  const double incident = ref_a ? 1.0 : 0.0;
  for (int i = 0; i < kept; ++i) in[i].w = in[i].w * incident + w_ref * (1 - incident);
  int pick[4];
  const int count = reduce_face_points(in, depth.data(), kept, pick);

  // back to the world: point_a = point_b + depth normal in every case
  const Pose& pr = ref_a ? pa : pb;
  const Mat3 W = glm::mat3_cast(pr.rotation);
  const Vec3 wu = W[k1], wv = W[k2], ww = W[k0];
  m.normal = ww * (ref_a ? s0 : -s0);
  const std::uint32_t flip_id = ref_a ? 0u : kIdFlip;
  for (int i = 0; i < count; ++i) {
    const FacePoint& q = in[pick[i]];
    const double d = depth[std::size_t(pick[i])];
    ContactPoint& c = m.points[std::size_t(i)];
    c.point_b = wu * q.u + wv * q.v + ww * q.w + pr.position;
    c.point_a = c.point_b + d * m.normal;
    c.depth = d;
    c.id = q.id | flip_id;
  }
  m.count = count;
}

}  // namespace pba::narrow
