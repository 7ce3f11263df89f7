// Box-box separating axes in closed form: the fifteen axes of Gottschalk, Lin and Manocha
// 1996 ("OBBTree"), three face normals of each box and nine edge cross products, measured
// with the rotation between the boxes and its absolute value, in A's frame. The choice
// between them, the feature ids and the face clipping are the polyhedral path's
// (sat.cpp, clip.cpp), with the box's fixed half-edge numbering, so a box pair and the
// same pair as hulls of boxes give the same manifold.
#include <cmath>
#include <cstring>
#include <limits>
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

// the feature ids of clip_face_rect's 24 candidates, in its order, for reference face fr and
// incident face fi: the incident corners' vertices, the (edge, side) crossings, the
// rectangle's corners
struct CandidateIdTable {
  std::uint32_t id[6][6][24] = {};
};
constexpr CandidateIdTable make_candidate_ids() {
  CandidateIdTable t{};
  for (std::uint32_t fr = 0; fr < 6; ++fr)
    for (std::uint32_t fi = 0; fi < 6; ++fi) {
      std::uint32_t* id = t.id[fr][fi];
      const FaceSides& side = kFaceSides.face[fr];
      for (int i = 0; i < 4; ++i) {
        id[i] = kFaceLoops.face[fi][i].vertex;
        const std::uint32_t edge_id = kIdCross | ((kFaceLoops.face[fi][i].edge & kLabelMask) << 15);
        for (int k = 0; k < 4; ++k) id[4 + 4 * i + k] = edge_id | side.side_label[k];
      }
      for (int ku = 0; ku < 2; ++ku)
        for (int kv = 0; kv < 2; ++kv) id[20 + 2 * ku + kv] = side.corner_id[ku][kv];
    }
  return t;
}
constexpr CandidateIdTable kCandidateIds = make_candidate_ids();

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

// The edge-edge axis ek = 3 ei + ej (separation ee, above the faces' by the hysteresis): the
// cache takes the supporting edges; beyond the margin nothing, else the closest points of
// the two edges and, as Jolt's manifold between two faces does for any axis, the points of
// B's face most anti-parallel to the axis clipped by the sides of A's face most parallel to
// it, each measured along the axis to A's face plane and kept within the margin (up to four
// in all, the reduction's; the two edges lie on those faces, so the closest points are the
// deepest). A box meeting another edge first gets points where its faces are about to close,
// not one it can turn about. Shared by the single pair and the lanes (the same bits); the
// same points as sat.cpp's edge contact on the boxes' hulls.
[[gnu::always_inline]] inline void edge_contact(const BoxPair& p, int ek, double ee, double margin, const Pose& pa,
                                                SatCache* cache, Manifold& m) {
  const int ei = ek / 3, ej = ek % 3;
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
  const Vec3 cb_local = cb;
  m.normal = pa.rotation * axis;
  ca = apply(pa, ca);
  cb = apply(pa, cb);
  const ContactPoint edge_point{ca, cb, glm::dot(ca - cb, m.normal), edge_pair_id(edge_a, edge_b)};
  // the reference face: A's most parallel to the axis (the first of equals in face order);
  // the incident face: B's most anti-parallel to it
  int fr_i = 0, fi_i = 0;
  double best_r = -INFINITY, best_i = -INFINITY;
  for (int f = 0; f < 6; ++f) {
    const double sign = (f & 1) ? 1.0 : -1.0;
    keep_max(sign * axis[f / 2], f, best_r, fr_i);
    keep_max(-(sign * glm::dot(column(p.R, f / 2), axis)), f, best_i, fi_i);
  }
  const std::uint32_t fr = std::uint32_t(fr_i), fi = std::uint32_t(fi_i);
  const int k0 = int(fr / 2), k1 = kNext[k0], k2 = kPrev[k0], k = int(fi / 2), j1 = kNext[k], j2 = kPrev[k];
  const double s0 = double(int(fr & 1) * 2 - 1), cosine = s0 * axis[k0];
  // B's face in A's face coordinates (u, v, w) = (x[k1], x[k2], x[k0]), as the face contact's,
  // then sheared along the axis, (u, v) + (w_ref - w) (gu, gv), onto A's face plane: the sides
  // then clip along the axis, so every kept point's foot lies on A's face and its depth along
  // the axis is at most the axes' penetration (the foot in A, the point in B)
  std::array<FacePoint, 4> quad;
  std::array<FacePoint, 25> pts;
  std::array<double, 25> depth;
  const double hk = p.hb[k] * double(int(fi & 1) * 2 - 1);
  const int perm[3] = {k1, k2, k0};
  const double w_ref = s0 * p.ha[k0], gu = axis[k1] / axis[k0], gv = axis[k2] / axis[k0];
  double c[3], e1[3], e2[3], corners[4][3];
  for (int r = 0; r < 3; ++r) {
    c[r] = p.t[perm[r]] + p.R[k][perm[r]] * hk;
    e1[r] = p.R[j1][perm[r]] * p.hb[j1];
    e2[r] = p.R[j2][perm[r]] * p.hb[j2];
  }
  for (int r = 0; r < 3; ++r) {
    const double lo = c[r] - e1[r], hi1 = c[r] + e1[r];
    corners[0][r] = lo - e2[r], corners[1][r] = lo + e2[r], corners[2][r] = hi1 - e2[r], corners[3][r] = hi1 + e2[r];
  }
  auto shear = [&](double* x, double w0) { x[0] += (w0 - x[2]) * gu, x[1] += (w0 - x[2]) * gv; };
  shear(c, w_ref), shear(e1, 0.0), shear(e2, 0.0);
  for (auto& x : corners) shear(x, w_ref);
  for (std::size_t i = 0; i < 4; ++i) {
    const FaceLoopCorner& q = kFaceLoops.face[fi][i];
    const double* x = corners[q.corner];
    quad[i] = {x[0], x[1], x[2], q.vertex, q.edge};
  }
  // the edge point first (B's point in face coordinates), then the clipped points within the
  // margin along the axis, less any within a thousandth of the boxes' size of the edge point
  // (the crossing of the two contact edges, found again by the clipping)
  pts[0] = {cb_local[k1], cb_local[k2], cb_local[k0], edge_point.id, 0};
  depth[0] = edge_point.depth;
  const int clipped = clip_face_rect(quad.data(), c, e1, e2, fr, p.ha[k1], p.ha[k2], p.ha[k0], s0, INFINITY,
                                     pts.data() + 1, depth.data() + 1);
  const double near = 1e-3 * (std::sqrt(p.ha[0] * p.ha[0] + p.ha[1] * p.ha[1] + p.ha[2] * p.ha[2]) +
                              std::sqrt(p.hb[0] * p.hb[0] + p.hb[1] * p.hb[1] + p.hb[2] * p.hb[2]));
  int kept = 1;
  for (int i = 1; i <= clipped; ++i) {
    // back from the foot on A's face to the point on B's
    pts[std::size_t(i)].u -= (w_ref - pts[std::size_t(i)].w) * gu;
    pts[std::size_t(i)].v -= (w_ref - pts[std::size_t(i)].w) * gv;
    // the depth along the axis; a gap (the point still outside A's face plane) is the gap to
    // the plane times the cosine instead: a closing along the axis by that much, made along
    // the plane's normal, brings the point to the plane and no further (gap / cosine, the gap
    // along the axis, let a face closing along its own normal sink gap (1 / cosine^2 - 1)
    // within the step), and the true distance to A is no less than the gap to the plane
    const double d = depth[std::size_t(i)] >= 0 ? depth[std::size_t(i)] / cosine : depth[std::size_t(i)] * cosine;
    const double du = pts[std::size_t(i)].u - pts[0].u, dv = pts[std::size_t(i)].v - pts[0].v,
                 dw = pts[std::size_t(i)].w - pts[0].w;
    if (!(d >= -margin) || du * du + dv * dv + dw * dw < near * near) continue;
    pts[std::size_t(kept)] = pts[std::size_t(i)];
    depth[std::size_t(kept)] = d;
    ++kept;
  }
  int pick[4];
  const int count = reduce_face_points(pts.data(), depth.data(), kept, pick);
  for (int i = 0; i < count; ++i) {
    const int j = pick[i];
    if (j == 0) {
      m.points[std::size_t(i)] = edge_point;
      continue;
    }
    const FacePoint& q = pts[std::size_t(j)];
    Vec3 x(0.0);
    x[k1] = q.u, x[k2] = q.v, x[k0] = q.w;
    ContactPoint& out = m.points[std::size_t(i)];
    out.point_b = apply(pa, x);
    out.depth = depth[std::size_t(j)];
    out.point_a = out.point_b + out.depth * m.normal;
    out.id = q.id;
  }
  m.count = count;
}

// The face contact after the clipping: `in` (the clipped points in the reference face's
// coordinates, their depths; `kept` >= 1) moved onto B's surface (unless kOnB), reduced to at most four
// and written to the world through the reference face's frame, frame(wu, wv, ww, origin):
// its axes (u, v and the face's axis) and the reference box's centre (m). Shared by the
// single pair and the lanes.
template <bool kOnB = false, class Frame>
[[gnu::always_inline]] inline void finish_face(FacePoint* in, const double* depth, int kept, bool ref_a, double s0,
                                               double w_ref, Frame&& frame, Manifold& m) {
  // B's points: the incident points when A holds the reference face, else their feet on it
  // (kOnB: the caller has moved them)
  const double incident = ref_a ? 1.0 : 0.0;
  if constexpr (!kOnB)
    for (int i = 0; i < kept; ++i) in[i].w = in[i].w * incident + w_ref * (1 - incident);
  int pick[4];
  const int count = reduce_face_points(in, depth, kept, pick);
  // back to the world: point_a = point_b + depth normal in every case
  Vec3 wu, wv, ww, origin;
  frame(wu, wv, ww, origin);
  m.normal = ww * (ref_a ? s0 : -s0);
  const std::uint32_t flip_id = ref_a ? 0u : kIdFlip;
  for (int i = 0; i < count; ++i) {
    const FacePoint& q = in[pick[i]];
    const double d = depth[std::size_t(pick[i])];
    ContactPoint& c = m.points[std::size_t(i)];
    c.point_b = wu * q.u + wv * q.v + ww * q.w + origin;
    c.point_a = c.point_b + d * m.normal;
    c.depth = d;
    c.id = q.id | flip_id;
  }
  m.count = count;
}

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
  // (the tolerance is a tenth of the face's separation whatever its sign: for boxes apart,
  // 0.9 times it would let an edge pair tie with a face, as e_x x e_z does with the y faces
  // of two aligned boxes, and make a face-on speculative contact one point)
  const double face = std::max(fa, fb);
  const double relevant = std::min(margin, (face > 0 ? (2 - kRelEdge) * face : kRelEdge * face) + kAbs);
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
  if (ee > relevant) {
    edge_contact(p, ek, ee, margin, pa, cache, m);
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
  finish_face(in, depth.data(), kept, ref_a, s0, w_ref,
              [&](Vec3& wu, Vec3& wv, Vec3& ww, Vec3& origin) {
                const Pose& pr = ref_a ? pa : pb;
                const Mat3 W = glm::mat3_cast(pr.rotation);
                wu = W[k1], wv = W[k2], ww = W[k0], origin = pr.position;
              },
              m);
}

}  // namespace pba::narrow

// --- many pairs in SIMD lanes ---------------------------------------------------------------
// collide_boxes_sat for up to 8 pairs at once: the relative pose, the fifteen axes and their
// choice, the reference and incident faces and the incident face's corners in the reference
// face's coordinates run in SIMD lanes (one pair per lane, AVX2 or AVX-512 doubles as GCC
// vector extensions, core/lanes.h), with selections where the single pair branches or
// indexes by a run-time axis; the clipping, the reduction and the edge contact then run pair
// by pair through the single pair's own functions. Each lane does the single pair's
// operations in its order (the build has -ffp-contract=off; division and square root are
// correctly rounded; the selections are the same comparisons), so every path gives the same
// bits (BoxBatch.* in tests/collide/test_narrow_batch.cpp).

namespace pba::narrow {

namespace {

// what the lanes leave for the pair-by-pair tail, lane l of W at [l]
template <int W>
struct BoxLanes {
  double R[3][3][W], AR[3][3][W], t[3][W], tb[3][W], ha[3][W], hb[3][W];  // the BoxPair
  double face_sep_a[3][W], face_sep_b[3][W], edge_sep[9][W];                // every axis's separation
  double valid[W];  // 1: the pair passes collide()'s quick input checks (else collide() decides)
  double far[W], margin[W], fa[W], fb[W], ee[W], ek[W], face_a[W], face_b[W], edge[W], ref_a[W];
  // the face contact: reference face fr (its half sizes hu, hv, h_face, its side s0), incident
  // face fi (centre c, half axes a1, a2, corners), the deepest incident vertex (the clipping's
  // fallback: its face coordinates, vertex, depth) and the reference face's world frame
  double fr[W], fi[W], s0[W];
  // the clipping's 24 candidates (clip_face_rect's, in its order): face coordinates and
  // depth, and in bits[l] bit k set when lane l keeps candidate k
  double cu[24][W], cv[24][W], cw[24][W], cd[24][W];
  long bits[W];
  double deep[3][W], deep_vertex[W], deep_depth[W];
  double wu[3][W], wv[3][W], ww[3][W], origin[3][W], w_ref[W];
};

}  // namespace

}  // namespace pba::narrow

#if defined(__GNUC__) && defined(__x86_64__)
#include "core/lanes.h"

namespace pba::narrow {

namespace {

using detail::lanes::kWidth;
using detail::lanes::splat;
using detail::lanes::store;
using detail::lanes::vmax;
using detail::lanes::vmin;
using detail::lanes::vsqrt;

template <class V>
using LaneMask = decltype(V{} < V{});

// std::abs: the sign bit cleared
template <class V>
PBA_LANES V vabs(V x) {
  using L = LaneMask<V>;
  return reinterpret_cast<V>(reinterpret_cast<L>(x) & (L{} + 0x7fffffffffffffffL));
}
// y[r] = x[(s + r) % 3], s in {0, 1, 2} per lane: the cyclic relabelling that indexing by a
// run-time axis is in the single pair (its face coordinates (k1, k2, k0), its incident axes
// (k, j1, j2))
template <class V>
PBA_LANES void rotate3(V s, const V* x, V* y) {
  const LaneMask<V> one = s == 1, two = s == 2;
  y[0] = two ? x[2] : (one ? x[1] : x[0]);
  y[1] = two ? x[0] : (one ? x[2] : x[1]);
  y[2] = two ? x[1] : (one ? x[0] : x[2]);
}
// glm::mat3_cast, R[column][row]
template <class V>
PBA_LANES void mat3_of(V w, V x, V y, V z, V (&R)[3][3]) {
  const V qxx = x * x, qyy = y * y, qzz = z * z, qxz = x * z, qxy = x * y, qyz = y * z, qwx = w * x, qwy = w * y,
          qwz = w * z;
  const V one = splat<V>(1), two = splat<V>(2);
  R[0][0] = one - two * (qyy + qzz);
  R[0][1] = two * (qxy + qwz);
  R[0][2] = two * (qxz - qwy);
  R[1][0] = two * (qxy - qwz);
  R[1][1] = one - two * (qxx + qzz);
  R[1][2] = two * (qyz + qwx);
  R[2][0] = two * (qxz + qwy);
  R[2][1] = two * (qyz - qwx);
  R[2][2] = one - two * (qxx + qyy);
}

// clip_face_rect in lanes: the incident face's corners (in the order c -+ a1 -+ a2) taken in
// the incident face fi's loop order, their outcodes against the reference rectangle |u| <=
// hu, |v| <= hv, then all 24 candidates (4 corners, 4 edges x 4 sides, 4 rectangle corners)
// computed as clip_face_rect computes them, each kept by the mask of the test that keeps it
// there (an edge's candidates when it crosses that side, the rectangle's corners when some
// corner is outside; none when every corner is outside one side) and by the depth filter;
// the candidates' w is stored on B's surface (incident 1: as is, 0: w_ref)
template <class V>
PBA_LANES void clip_lanes(const V (&corner)[4][3], const V* c, const V* a1, const V* a2, V fi, V hu, V hv, V h_face,
                          V s0, V margin, V incident, V w_ref, BoxLanes<kWidth<V>>& o) {
  using M = LaneMask<V>;
  using L = LaneMask<V>;
  // the corners in the loop order of face fi
  V qu[4], qv[4], qw[4];
  {
    M face[6];
    for (int f = 0; f < 6; ++f) face[f] = fi == f;
    for (int i = 0; i < 4; ++i) {
      V idx = splat<V>(0);
      for (int f = 0; f < 6; ++f) idx = face[f] ? splat<V>(kFaceLoops.face[f][i].corner) : idx;
      const M one = idx == 1, two = idx == 2, three = idx == 3;
      V x[3];
      for (int r = 0; r < 3; ++r) x[r] = three ? corner[3][r] : (two ? corner[2][r] : (one ? corner[1][r] : corner[0][r]));
      qu[i] = x[0], qv[i] = x[1], qw[i] = x[2];
    }
  }
  M out_u[4], out_nu[4], out_v[4], out_nv[4], inside[4];
  for (int i = 0; i < 4; ++i) {
    out_u[i] = qu[i] > hu, out_nu[i] = -qu[i] > hu, out_v[i] = qv[i] > hv, out_nv[i] = -qv[i] > hv;
    inside[i] = ~(out_u[i] | out_nu[i] | out_v[i] | out_nv[i]);
  }
  const M none = (out_u[0] & out_u[1] & out_u[2] & out_u[3]) | (out_nu[0] & out_nu[1] & out_nu[2] & out_nu[3]) |
                 (out_v[0] & out_v[1] & out_v[2] & out_v[3]) | (out_nv[0] & out_nv[1] & out_nv[2] & out_nv[3]);
  const M some = ~(inside[0] & inside[1] & inside[2] & inside[3]) & ~none;
  L bits = L{};
  const V floor = -margin;
  auto emit = [&](int k, V u, V v, V w, M keep) {
    const V d = h_face - s0 * w;
    // w stored on B's surface (finish_face's move, made here)
    store(o.cu[k], u), store(o.cv[k], v), store(o.cw[k], w * incident + w_ref * (1 - incident)), store(o.cd[k], d);
    bits |= (keep & (d >= floor)) & (L{} + (1L << k));
  };
  for (int i = 0; i < 4; ++i) emit(i, qu[i], qv[i], qw[i], inside[i] & ~none);
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) & 3;
    const V du = qu[j] - qu[i], dv = qv[j] - qv[i], dw = qw[j] - qw[i];
    const V iu = 1 / du, iv = 1 / dv;
    const M cross[4] = {out_u[i] ^ out_u[j], out_nu[i] ^ out_nu[j], out_v[i] ^ out_v[j], out_nv[i] ^ out_nv[j]};
    for (int k = 0; k < 2; ++k) {
      const V x = k == 0 ? hu : -hu;
      const V r = (x - qu[i]) * iu, v = qv[i] + dv * r;
      emit(4 + 4 * i + k, x, v, qw[i] + dw * r, cross[k] & (vabs(v) <= hv) & some);
    }
    for (int k = 2; k < 4; ++k) {
      const V y = k == 2 ? hv : -hv;
      const V r = (y - qv[i]) * iv, u = qu[i] + du * r;
      emit(4 + 4 * i + k, u, y, qw[i] + dw * r, cross[k] & (vabs(u) <= hu) & some);
    }
  }
  // the rectangle's corners inside the parallelogram c + alpha a1 + beta a2, |alpha|, |beta| <= 1
  const V det = a1[0] * a2[1] - a1[1] * a2[0];
  const V inv = 1 / det;
  for (int ku = 0; ku < 2; ++ku)
    for (int kv = 0; kv < 2; ++kv) {
      const V u = ku == 0 ? hu : -hu, v = kv == 0 ? hv : -hv;
      const V du = u - c[0], dv = v - c[1];
      const V alpha = (du * a2[1] - dv * a2[0]) * inv, beta = (a1[0] * dv - a1[1] * du) * inv;
      emit(20 + 2 * ku + kv, u, v, c[2] + alpha * a1[2] + beta * a2[2],
           some & (det != 0) & (vabs(alpha) <= 1) & (vabs(beta) <= 1));
    }
  detail::lanes::store(reinterpret_cast<double*>(o.bits), reinterpret_cast<V>(bits));
}

// The pairs of a batch, one a lane: the boxes' half extents, centres and orientations (w, x,
// y, z) and the margin (m).
template <class V>
struct PairLanes {
  V ha[3], hb[3], xa[3], xb[3], qa[4], qb[4], margin;
};

// up to W pairs into P, one a lane (lanes past n repeat the last pair)
template <class V>
PBA_LANES void gather_pairs(const PairQuery* const* q, int n, PairLanes<V>& P) {
  constexpr int W = kWidth<V>;
  const PairQuery* p[W];
  for (int l = 0; l < W; ++l) p[l] = q[l < n ? l : n - 1];
  // one lane per pair, each vector built from its lanes' values (no stores to reload)
  auto gather = [&]<std::size_t... L>(V& to, auto&& field, std::index_sequence<L...>) { to = V{field(*p[L])...}; };
  const auto lanes = std::make_index_sequence<std::size_t(W)>{};
  for (int k = 0; k < 3; ++k) {
    gather(P.ha[k], [k](const PairQuery& x) { return x.a->half_extents[k]; }, lanes);
    gather(P.hb[k], [k](const PairQuery& x) { return x.b->half_extents[k]; }, lanes);
    gather(P.xa[k], [k](const PairQuery& x) { return x.pose_a.position[k]; }, lanes);
    gather(P.xb[k], [k](const PairQuery& x) { return x.pose_b.position[k]; }, lanes);
  }
  gather(P.qa[0], [](const PairQuery& x) { return x.pose_a.rotation.w; }, lanes);
  gather(P.qa[1], [](const PairQuery& x) { return x.pose_a.rotation.x; }, lanes);
  gather(P.qa[2], [](const PairQuery& x) { return x.pose_a.rotation.y; }, lanes);
  gather(P.qa[3], [](const PairQuery& x) { return x.pose_a.rotation.z; }, lanes);
  gather(P.qb[0], [](const PairQuery& x) { return x.pose_b.rotation.w; }, lanes);
  gather(P.qb[1], [](const PairQuery& x) { return x.pose_b.rotation.x; }, lanes);
  gather(P.qb[2], [](const PairQuery& x) { return x.pose_b.rotation.y; }, lanes);
  gather(P.qb[3], [](const PairQuery& x) { return x.pose_b.rotation.z; }, lanes);
  gather(P.margin, [](const PairQuery& x) { return x.margin; }, lanes);
}

// collide()'s quick input checks (manifold.cpp) into o.valid: unit quaternions to within
// 0.9e-6, positions and half extents > 0 within the float range (|x| <= 3.4e38), a finite
// margin >= 0; a pair that fails them takes collide(), whose full checks throw or pass it.
// And the bounding spheres apart into o.far (d: xb - xa)
template <class V>
PBA_LANES void checks_and_spheres(const PairLanes<V>& P, const V (&d)[3], BoxLanes<kWidth<V>>& o) {
  using M = LaneMask<V>;
  const V zero = splat<V>(0), one = splat<V>(1);
  {
    constexpr double kHuge = std::numeric_limits<double>::max();
    constexpr double kFloat = std::numeric_limits<float>::max();  // the colliders' range
    constexpr double kLo = (1 - 0.9e-6) * (1 - 0.9e-6), kHi = (1 + 0.9e-6) * (1 + 0.9e-6);
    const V qa2 = P.qa[0] * P.qa[0] + P.qa[1] * P.qa[1] + P.qa[2] * P.qa[2] + P.qa[3] * P.qa[3];
    const V qb2 = P.qb[0] * P.qb[0] + P.qb[1] * P.qb[1] + P.qb[2] * P.qb[2] + P.qb[3] * P.qb[3];
    M ok = (qa2 >= kLo) & (qa2 <= kHi) & (qb2 >= kLo) & (qb2 <= kHi) & (P.margin >= 0) & (P.margin <= kHuge);
    for (int k = 0; k < 3; ++k)
      ok &= (vabs(P.xa[k]) <= kFloat) & (vabs(P.xb[k]) <= kFloat) & (P.ha[k] > 0) & (P.ha[k] <= kFloat) &
            (P.hb[k] > 0) & (P.hb[k] <= kFloat);
    store(o.valid, ok ? one : zero);
  }
  const V r = vsqrt(P.ha[0] * P.ha[0] + P.ha[1] * P.ha[1] + P.ha[2] * P.ha[2]) +
              vsqrt(P.hb[0] * P.hb[0] + P.hb[1] * P.hb[1] + P.hb[2] * P.hb[2]) + P.margin;
  const M far = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) > r * r * (1 + 1e-12);
  store(o.far, far ? one : zero);
}

// b in a's frame: R = mat3_cast(conj(qa) qb) (R[column][row]) and t = conj(qa) (xb - xa), as
// glm computes them (relative_pose, d: xb - xa), and tb = R^T t (box_lanes)
template <class V>
struct Relative {
  V R[3][3], t[3], tb[3];
};

template <class V>
PBA_LANES void relative_pose(const PairLanes<V>& P, const V (&d)[3], Relative<V>& rel) {
  const V pw = P.qa[0], px = -P.qa[1], py = -P.qa[2], pz = -P.qa[3];
  const V* qb = P.qb;
  const V w = pw * qb[0] - px * qb[1] - py * qb[2] - pz * qb[3];
  const V x = pw * qb[1] + px * qb[0] + py * qb[3] - pz * qb[2];
  const V y = pw * qb[2] + py * qb[0] + pz * qb[1] - px * qb[3];
  const V z = pw * qb[3] + pz * qb[0] + px * qb[2] - py * qb[1];
  mat3_of(w, x, y, z, rel.R);
  detail::lanes::quat_turn(px, py, pz, pw, d[0], d[1], d[2], rel.t[0], rel.t[1], rel.t[2]);
}

// The separating axes (the single pair's face_a_sep, face_b_sep and edge_sep): every axis's
// separation into o, the deepest face of each box (fa, fb; its face index face_a, face_b) and
// the deepest edge axis (ee, ek), whether an edge contact is made (o.edge) and whether a's
// face is the reference (returned); AR: |R| + 1e-12
template <class V>
PBA_LANES LaneMask<V> separating_axes(const PairLanes<V>& P, const Relative<V>& rel, const V (&AR)[3][3], V& face_a,
                                      V& face_b, BoxLanes<kWidth<V>>& o) {
  using M = LaneMask<V>;
  const V zero = splat<V>(0), one = splat<V>(1), two = splat<V>(2), inf = splat<V>(INFINITY);
  const V(&R)[3][3] = rel.R;
  const V* t = rel.t;
  const V* ha = P.ha;
  const V* hb = P.hb;
  // faces of A, faces of B (keep_max: the first maximum)
  V fa = -inf, fb = -inf, ia = zero, ib = zero;
  for (int i = 0; i < 3; ++i) {
    const V rb = hb[0] * AR[0][i] + hb[1] * AR[1][i] + hb[2] * AR[2][i];
    const V s = vabs(t[i]) - ha[i] - rb;
    store(o.face_sep_a[i], s);
    const M more = s > fa;
    ia = more ? splat<V>(i) : ia;
    fa = more ? s : fa;
  }
  for (int j = 0; j < 3; ++j) {
    const V ra = ha[0] * AR[j][0] + ha[1] * AR[j][1] + ha[2] * AR[j][2];
    const V s = vabs(rel.tb[j]) - hb[j] - ra;
    store(o.face_sep_b[j], s);
    const M more = s > fb;
    ib = more ? splat<V>(j) : ib;
    fb = more ? s : fb;
  }
  V t_ia[3], tb_ib[3];
  rotate3(ia, t, t_ia);
  rotate3(ib, rel.tb, tb_ib);
  face_a = two * ia + (t_ia[0] > 0 ? one : zero);
  face_b = two * ib + (tb_ib[0] < 0 ? one : zero);
  store(o.fa, fa), store(o.fb, fb), store(o.face_a, face_a), store(o.face_b, face_b);

  // the nine edge axes (edge_axis, edge_sep)
  V ee = -inf, ek = zero;
#pragma GCC unroll 9
  for (int k = 0; k < 9; ++k) {
    const int i = k / 3, j = k % 3, i1 = kNext[i], i2 = kPrev[i], j1 = kNext[j], j2 = kPrev[j];
    const V l1 = -R[j][i2], l2 = R[j][i1];
    const V ra = ha[i1] * AR[j][i2] + ha[i2] * AR[j][i1];
    const V rb = hb[j1] * AR[j2][i] + hb[j2] * AR[j1][i];
    const V dd = t[i1] * l1 + t[i2] * l2;
    const V num = vabs(dd) - ra - rb;
    const V len2 = l1 * l1 + l2 * l2;
    const V s = len2 < kParallel2 ? -inf : num / vsqrt(len2);
    store(o.edge_sep[k], s);
    const M more = s > ee;
    ek = more ? splat<V>(k) : ek;
    ee = more ? s : ee;
  }
  store(o.ee, ee), store(o.ek, ek);
  constexpr double kRelEdge = 0.90, kRelFace = 0.98, kAbs = 0.5 * 0.005;
  const V face = vmax(fa, fb);
  const V relevant = vmin(P.margin, (face > 0 ? (2 - kRelEdge) * face : kRelEdge * face) + kAbs);
  store(o.edge, ee > relevant ? one : zero);
  const M ref_a = !(fb > kRelFace * fa + kAbs);
  store(o.ref_a, ref_a ? one : zero);
  return ref_a;
}

// The face contact: the reference face fr (axis k0, side s0) and, in its coordinates (u, v,
// w) = (x[k1], x[k2], x[k0]), the incident face's centre, half axes and corners, clipped
// (clip_lanes); the deepest incident vertex; the reference box's world frame
template <class V>
PBA_LANES void face_contact(const PairLanes<V>& P, const Relative<V>& rel, LaneMask<V> ref_a, V face_a, V face_b,
                            BoxLanes<kWidth<V>>& o) {
  using M = LaneMask<V>;
  const V zero = splat<V>(0), one = splat<V>(1), two = splat<V>(2);
  V Rri[3][3], tri[3], hr[3], hi[3];
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) Rri[c][r] = ref_a ? rel.R[c][r] : rel.R[r][c];
    tri[c] = ref_a ? rel.t[c] : -rel.tb[c];
    hr[c] = ref_a ? P.ha[c] : P.hb[c];
    hi[c] = ref_a ? P.hb[c] : P.ha[c];
  }
  const V fr = ref_a ? face_a : face_b;
  const V k0 = fr >= 4 ? two : (fr >= 2 ? one : zero);
  const V s0 = (fr - two * k0) * two - one;
  const V perm = k0 == 2 ? zero : k0 + one;  // (k1, k2, k0) = x[(perm + r) % 3]
  // the incident axis most parallel to the normal (the first maximum of |Rri[c][k0]|)
  V g[3];
  for (int c = 0; c < 3; ++c) {
    V row[3];
    rotate3(k0, Rri[c], row);
    g[c] = row[0];
  }
  V kk = zero, best = vabs(g[0]);
  for (int c = 1; c < 3; ++c) {
    const M more = vabs(g[c]) > best;
    kk = more ? splat<V>(c) : kk;
    best = more ? vabs(g[c]) : best;
  }
  V gk[3];
  rotate3(kk, g, gk);
  const V back = gk[0] * s0 > 0 ? zero : one;  // the incident face's side bit
  const V fi = two * kk + back;
  // its rows (k, j1, j2), then their components in the face's order
  V rows[3][3], hik[3];
  for (int r = 0; r < 3; ++r) {
    const V col[3] = {Rri[0][r], Rri[1][r], Rri[2][r]};
    V x[3];
    rotate3(kk, col, x);
    for (int c = 0; c < 3; ++c) rows[c][r] = x[c];
  }
  rotate3(kk, hi, hik);
  const V hk = hik[0] * (back * two - one);
  V rk[3], rj1[3], rj2[3], tf[3], hf[3];
  rotate3(perm, rows[0], rk);
  rotate3(perm, rows[1], rj1);
  rotate3(perm, rows[2], rj2);
  rotate3(perm, tri, tf);
  rotate3(perm, hr, hf);
  V c[3], a1[3], a2[3], corner[4][3];
  for (int r = 0; r < 3; ++r) {
    c[r] = tf[r] + rk[r] * hk, a1[r] = rj1[r] * hik[1], a2[r] = rj2[r] * hik[2];
    const V lo = c[r] - a1[r], hi1 = c[r] + a1[r];
    corner[0][r] = lo - a2[r], corner[1][r] = lo + a2[r], corner[2][r] = hi1 - a2[r], corner[3][r] = hi1 + a2[r];
  }
  const V w_ref = s0 * hf[2], incident = ref_a ? one : zero;
  store(o.fr, fr), store(o.fi, fi), store(o.s0, s0), store(o.w_ref, w_ref);
  clip_lanes<V>(corner, c, a1, a2, fi, hf[0], hf[1], hf[2], s0, P.margin, incident, w_ref, o);
  // the deepest incident vertex (the incident corner farthest along -normal)
  {
    V qv[3] = {tri[0], tri[1], tri[2]}, bits = zero;
    for (int c = 0; c < 3; ++c) {
      const M set = (-s0 * g[c]) >= 0;
      bits = bits + (set ? splat<V>(1 << c) : zero);
      for (int r = 0; r < 3; ++r) qv[r] = qv[r] + Rri[c][r] * (set ? hi[c] : -hi[c]);
    }
    V qf[3];
    rotate3(perm, qv, qf);
    store(o.deep[0], qf[0]), store(o.deep[1], qf[1]), store(o.deep[2], qf[2] * incident + w_ref * (1 - incident));
    store(o.deep_vertex, bits);
    store(o.deep_depth, hf[2] - s0 * qf[2]);
  }
  // the reference box's frame in the world: its axes (k1, k2, k0) and centre
  {
    V W3[3][3];
    mat3_of(ref_a ? P.qa[0] : P.qb[0], ref_a ? P.qa[1] : P.qb[1], ref_a ? P.qa[2] : P.qb[2],
            ref_a ? P.qa[3] : P.qb[3], W3);
    for (int r = 0; r < 3; ++r) {
      const V col[3] = {W3[0][r], W3[1][r], W3[2][r]};
      V x[3];
      rotate3(perm, col, x);
      store(o.wu[r], x[0]), store(o.wv[r], x[1]), store(o.ww[r], x[2]);
      store(o.origin[r], ref_a ? P.xa[r] : P.xb[r]);
    }
  }
}

// The lanes' part of up to W pairs (lanes past n repeat the last pair): the input checks, the
// relative pose, the separating axes and the face contact.
template <class V>
PBA_LANES void box_lanes(const PairQuery* const* q, int n, BoxLanes<kWidth<V>>& o) {
  PairLanes<V> P;
  gather_pairs<V>(q, n, P);
  V d[3];
  for (int k = 0; k < 3; ++k) d[k] = P.xb[k] - P.xa[k];
  checks_and_spheres(P, d, o);
  Relative<V> rel;
  relative_pose(P, d, rel);
  V AR[3][3];
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) AR[j][i] = vabs(rel.R[j][i]) + 1e-12;
  for (int j = 0; j < 3; ++j) rel.tb[j] = rel.R[j][0] * rel.t[0] + rel.R[j][1] * rel.t[1] + rel.R[j][2] * rel.t[2];
  for (int j = 0; j < 3; ++j) {
    store(o.t[j], rel.t[j]), store(o.tb[j], rel.tb[j]), store(o.ha[j], P.ha[j]), store(o.hb[j], P.hb[j]);
    for (int i = 0; i < 3; ++i) store(o.R[j][i], rel.R[j][i]), store(o.AR[j][i], AR[j][i]);
  }
  store(o.margin, P.margin);
  V face_a, face_b;
  const LaneMask<V> ref_a = separating_axes(P, rel, AR, face_a, face_b, o);
  face_contact(P, rel, ref_a, face_a, face_b, o);
}

}  // namespace

}  // namespace pba::narrow
#define PBA_BOX_LANES_X86 1
#else
#define PBA_BOX_LANES_X86 0
#endif

namespace pba::narrow {

namespace {

// The pair-by-pair tail of lane l: collide_boxes_sat's decisions in its order, then the edge
// contact or the face clipping, reduction and output through the single pair's functions.
template <int W>
[[gnu::always_inline]] inline void box_tail(const BoxLanes<W>& o, int l, const PairQuery& q, Manifold& m) {
  if (o.valid[l] == 0) {
    m = collide(*q.a, q.pose_a, *q.b, q.pose_b, {.speculative_margin = q.margin}, q.cache);
    return;
  }
  // a fresh Manifold, as collide() returns it (stores the width of the lanes, not a string op)
  std::memset(static_cast<void*>(&m), 0, sizeof m);
  m.normal.z = 1;
  if (o.far[l] != 0) return;
  SatCache* cache = q.cache ? &q.cache->sat : nullptr;
  const double margin = o.margin[l];
  if (cache) {
    double s = -INFINITY;
    auto axis_of = [](std::uint32_t e) {
      const std::uint32_t d = kBoxTopology.edges[e].origin ^ kBoxTopology.edges[kBoxTopology.edges[e].twin].origin;
      return d == 1 ? 0 : (d == 2 ? 1 : 2);
    };
    if (cache->kind == SatCache::Kind::FaceA && cache->index_a < 6) s = o.face_sep_a[cache->index_a / 2][l];
    else if (cache->kind == SatCache::Kind::FaceB && cache->index_b < 6) s = o.face_sep_b[cache->index_b / 2][l];
    else if (cache->kind == SatCache::Kind::Edges && cache->index_a < 24 && cache->index_b < 24)
      s = o.edge_sep[3 * axis_of(cache->index_a) + axis_of(cache->index_b)][l];
    if (s > margin) return;
  }
  const std::uint32_t face_a = std::uint32_t(o.face_a[l]), face_b = std::uint32_t(o.face_b[l]);
  if (o.fa[l] > margin) {
    if (cache) *cache = {SatCache::Kind::FaceA, face_a, 0};
    return;
  }
  if (o.fb[l] > margin) {
    if (cache) *cache = {SatCache::Kind::FaceB, 0, face_b};
    return;
  }
  if (o.edge[l] != 0) {
    BoxPair p;
    for (int j = 0; j < 3; ++j) {
      p.t[j] = o.t[j][l], p.tb[j] = o.tb[j][l], p.ha[j] = o.ha[j][l], p.hb[j] = o.hb[j][l];
      for (int i = 0; i < 3; ++i) p.R[j][i] = o.R[j][i][l], p.AR[j][i] = o.AR[j][i][l];
    }
    edge_contact(p, int(o.ek[l]), o.ee[l], margin, q.pose_a, cache, m);
    return;
  }
  const bool ref_a = o.ref_a[l] != 0;
  if (cache) *cache = ref_a ? SatCache{SatCache::Kind::FaceA, face_a, 0} : SatCache{SatCache::Kind::FaceB, 0, face_b};
  const std::uint32_t fr = std::uint32_t(o.fr[l]), fi = std::uint32_t(o.fi[l]);
  const double s0 = o.s0[l];
  // the kept candidates, in order, with their feature ids
  std::array<FacePoint, 24> pts;
  std::array<double, 24> depth;
  const std::uint32_t* ids = kCandidateIds.id[fr][fi];
  int kept = 0;
  for (unsigned long b = static_cast<unsigned long>(o.bits[l]); b != 0; b &= b - 1) {
    const int k = __builtin_ctzl(b);
    pts[std::size_t(kept)] = {o.cu[k][l], o.cv[k][l], o.cw[k][l], ids[k], 0};
    depth[std::size_t(kept)] = o.cd[k][l];
    ++kept;
  }
  if (kept == 0) {
    pts[0] = {o.deep[0][l], o.deep[1][l], o.deep[2][l], vertex_id(std::uint32_t(o.deep_vertex[l])), 0};
    depth[0] = o.deep_depth[l];
    kept = 1;
  }
  finish_face<true>(pts.data(), depth.data(), kept, ref_a, s0, o.w_ref[l],
              [&](Vec3& wu, Vec3& wv, Vec3& ww, Vec3& origin) {
                wu = Vec3(o.wu[0][l], o.wu[1][l], o.wu[2][l]), wv = Vec3(o.wv[0][l], o.wv[1][l], o.wv[2][l]);
                ww = Vec3(o.ww[0][l], o.ww[1][l], o.ww[2][l]), origin = Vec3(o.origin[0][l], o.origin[1][l], o.origin[2][l]);
              },
              m);
}

#if PBA_BOX_LANES_X86
template <class V>
[[gnu::always_inline]] inline void box_group(const PairQuery* const* q, Manifold* const* out, int n) {
  constexpr int W = kWidth<V>;
  BoxLanes<W> o;
  for (int first = 0; first < n; first += W) {
    const int count = std::min(W, n - first);
    box_lanes<V>(q + first, count, o);
    for (int l = 0; l < count; ++l) box_tail(o, l, *q[first + l], *out[first + l]);
  }
}

#if PBA_AVX512
__attribute__((target("avx512f"))) void box_group_avx512(const PairQuery* const* q, Manifold* const* out, int n) {
  box_group<detail::lanes::v8d>(q, out, n);
}
#endif
__attribute__((target("avx2"))) void box_group_avx2(const PairQuery* const* q, Manifold* const* out, int n) {
  box_group<detail::lanes::v4d>(q, out, n);
}
#endif

}  // namespace

void collide_boxes_sat_batch(const PairQuery* const* q, Manifold* const* out, int n, BatchPath path) {
#if PBA_BOX_LANES_X86
  // Best is AVX2 where the processor has it, even beside AVX-512: GCC 12 turns the lane masks
  // of eight-double vectors into scalar code (a compare and a set per lane), so the eight-lane
  // path measured slower (0.25 against 0.12 us per pair, docs/benchmarks.md); it is kept, and
  // tested to give the same bits, for a compiler that keeps those masks in registers
  static const bool avx2 = __builtin_cpu_supports("avx2"), avx512 = PBA_AVX512 && __builtin_cpu_supports("avx512f");
  if (path == BatchPath::Best) path = avx2 ? BatchPath::Avx2 : BatchPath::Scalar;
  if (path == BatchPath::Avx512 && !avx512) path = avx2 ? BatchPath::Avx2 : BatchPath::Scalar;
  if (path == BatchPath::Avx2 && !avx2) path = BatchPath::Scalar;
#if PBA_AVX512
  if (path == BatchPath::Avx512) return box_group_avx512(q, out, n);
#endif
  if (path == BatchPath::Avx2) return box_group_avx2(q, out, n);
#endif
  (void)path;
  for (int i = 0; i < n; ++i) {
    const PairQuery& p = *q[i];
    Manifold& m = *out[i];
    m = Manifold{};
    collide_boxes_sat(p.a->half_extents, p.pose_a, p.b->half_extents, p.pose_b, p.margin,
                      p.cache ? &p.cache->sat : nullptr, m);
  }
}

}  // namespace pba::narrow
