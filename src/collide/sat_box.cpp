// Box-box separating axes in closed form: the fifteen axes of Gottschalk, Lin and Manocha
// 1996 ("OBBTree"), three face normals of each box and nine edge cross products, measured
// with the rotation between the boxes and its absolute value, in A's frame. The choice
// between them, the feature ids and the face clipping are the polyhedral path's
// (sat.cpp, clip.cpp), with the box's fixed half-edge numbering, so a box pair and the
// same pair as hulls of boxes give the same manifold.
#include <cmath>

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

Vec3 corner(const Vec3& h, std::uint32_t v) {
  return Vec3((v & 1) ? h.x : -h.x, (v & 2) ? h.y : -h.y, (v & 4) ? h.z : -h.z);
}

// face f of a box with its labels, in a frame where the box sits at (R, t)
void box_face(const Vec3& h, std::uint32_t f, const Mat3& R, const Vec3& t, WorldFace& out) {
  const int axis = int(f / 2);
  Vec3 n(0.0);
  n[axis] = (f & 1) ? 1.0 : -1.0;
  out.normal = R * n;
  out.offset = h[axis] + glm::dot(out.normal, t);
  out.count = 4;
  std::uint32_t e = kBoxTopology.face_edge[f];
  for (int k = 0; k < 4; ++k) {
    const HalfEdge& he = kBoxTopology.edges[e];
    out.pts[std::size_t(k)] = {R * corner(h, he.origin) + t, vertex_id(he.origin), e};
    out.half_edges[std::size_t(k)] = e;
    e = he.next;
  }
}

struct BoxPair {
  Mat3 R{1.0};    // B's axes in A's frame (columns)
  Mat3 AR{1.0};   // |R| + epsilon
  Vec3 t{0.0};    // B's centre in A's frame
  Vec3 tb{0.0};   // t in B's axes: R^T t
};

double face_a_sep(const BoxPair& p, const Vec3& ha, const Vec3& hb, int i) {
  const double rb = hb.x * p.AR[0][i] + hb.y * p.AR[1][i] + hb.z * p.AR[2][i];
  return std::abs(p.t[i]) - ha[i] - rb;
}
double face_b_sep(const BoxPair& p, const Vec3& ha, const Vec3& hb, int j) {
  const double ra = glm::dot(ha, p.AR[j]);
  return std::abs(p.tb[j]) - hb[j] - ra;
}
// axis e_i x b_j; -inf for near-parallel edges (the face axes cover them). With i1, i2 the
// other two axes cyclically, L = (L[i1], L[i2]) = (-R[j][i2], R[j][i1]) and the radii are
// sums of entries of |R| (Gottschalk 1996, table 1)
double edge_sep(const BoxPair& p, const Vec3& ha, const Vec3& hb, int i, int j, Vec3* axis) {
  static constexpr int next[3] = {1, 2, 0}, prev[3] = {2, 0, 1};
  const int i1 = next[i], i2 = prev[i], j1 = next[j], j2 = prev[j];
  const double l1 = -p.R[j][i2], l2 = p.R[j][i1];
  const double len2 = l1 * l1 + l2 * l2;
  if (len2 < 0.005 * 0.005) return -INFINITY;  // sin of ~0.3 degrees, as in sat.cpp
  const double len = std::sqrt(len2);
  const double ra = ha[i1] * p.AR[j][i2] + ha[i2] * p.AR[j][i1];
  const double rb = hb[j1] * p.AR[j2][i] + hb[j2] * p.AR[j1][i];
  const double d = p.t[i1] * l1 + p.t[i2] * l2;
  if (axis) {
    Vec3 L(0.0);
    L[i1] = l1;
    L[i2] = l2;
    *axis = (d >= 0 ? L : -L) / len;
  }
  return (std::abs(d) - ra - rb) / len;
}

}  // namespace

void collide_boxes_sat(const Vec3& ha, const Pose& pa, const Vec3& hb, const Pose& pb, double margin, SatCache* cache,
                       Manifold& m) {
  m.count = 0;
  BoxPair p;
  const Quat qa_inv = glm::conjugate(pa.rotation);
  p.R = glm::mat3_cast(qa_inv * pb.rotation);
  p.t = qa_inv * (pb.position - pa.position);
  for (int j = 0; j < 3; ++j) {
    p.AR[j] = glm::abs(p.R[j]) + Vec3(1e-12);
    p.tb[j] = glm::dot(p.R[j], p.t);
  }

  // the cached axis first
  if (cache) {
    double s = -INFINITY;
    if (cache->kind == SatCache::Kind::FaceA && cache->index_a < 6) s = face_a_sep(p, ha, hb, int(cache->index_a / 2));
    else if (cache->kind == SatCache::Kind::FaceB && cache->index_b < 6) s = face_b_sep(p, ha, hb, int(cache->index_b / 2));
    else if (cache->kind == SatCache::Kind::Edges && cache->index_a < 24 && cache->index_b < 24) {
      auto axis_of = [](std::uint32_t e) {
        const std::uint32_t d = kBoxTopology.edges[e].origin ^ kBoxTopology.edges[kBoxTopology.edges[e].twin].origin;
        return d == 1 ? 0 : (d == 2 ? 1 : 2);
      };
      s = edge_sep(p, ha, hb, axis_of(cache->index_a), axis_of(cache->index_b), nullptr);
    }
    if (s > margin) return;
  }

  // faces of A, faces of B, edge pairs
  double fa = -INFINITY, fb = -INFINITY, ee = -INFINITY;
  int ia = 0, ib = 0, ei = 0, ej = 0;
  for (int i = 0; i < 3; ++i) {
    const double s = face_a_sep(p, ha, hb, i);
    if (s > fa) fa = s, ia = i;
  }
  const std::uint32_t face_a = std::uint32_t(2 * ia + (p.t[ia] > 0 ? 1 : 0));
  if (fa > margin) {
    if (cache) *cache = {SatCache::Kind::FaceA, face_a, 0};
    return;
  }
  for (int j = 0; j < 3; ++j) {
    const double s = face_b_sep(p, ha, hb, j);
    if (s > fb) fb = s, ib = j;
  }
  // B's face that looks at A: its outward normal points along -t
  const std::uint32_t face_b = std::uint32_t(2 * ib + (p.tb[ib] < 0 ? 1 : 0));
  if (fb > margin) {
    if (cache) *cache = {SatCache::Kind::FaceB, 0, face_b};
    return;
  }
  Vec3 edge_axis(0, 0, 1);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double s = edge_sep(p, ha, hb, i, j, nullptr);
      if (s > ee) ee = s, ei = i, ej = j;
    }
  if (ee > -INFINITY) edge_sep(p, ha, hb, ei, ej, &edge_axis);
  // the supporting edges: A's along axis ei farthest along L, B's along ej farthest along -L
  std::uint32_t va = 0, vb = 0;
  if (ee > -INFINITY) {
    for (int k = 0; k < 3; ++k)
      if (k != ei && edge_axis[k] > 0) va |= 1u << k;
    const Vec3 Lb = glm::transpose(p.R) * -edge_axis;
    for (int k = 0; k < 3; ++k)
      if (k != ej && Lb[k] > 0) vb |= 1u << k;
  }
  const std::uint32_t edge_a = kEdgeTable.he[va][ei] & ~1u, edge_b = kEdgeTable.he[vb][ej] & ~1u;
  if (ee > margin) {
    if (cache) *cache = {SatCache::Kind::Edges, edge_a, edge_b};
    return;
  }

  // the same hysteresis as the polyhedral path (Gregorius 2013)
  constexpr double kRelEdge = 0.90, kRelFace = 0.98, kAbs = 0.5 * 0.005;
  if (ee > kRelEdge * std::max(fa, fb) + kAbs) {
    if (cache) *cache = {SatCache::Kind::Edges, edge_a, edge_b};
    const Vec3 da(ei == 0, ei == 1, ei == 2);
    const Vec3 a0 = corner(ha, va), a1 = a0 + 2 * ha[ei] * da;
    const Vec3 b0 = p.R * corner(hb, vb) + p.t, b1 = b0 + 2 * hb[ej] * p.R[ej];
    Vec3 ca, cb;
    closest_segments(a0, a1, b0, b1, ca, cb);
    m.normal = pa.rotation * edge_axis;
    ca = apply(pa, ca);
    cb = apply(pa, cb);
    m.count = 1;
    m.points[0] = {ca, cb, glm::dot(ca - cb, m.normal), edge_pair_id(edge_a, edge_b)};
    return;
  }
  const bool ref_a = !(fb > kRelFace * fa + kAbs);
  if (cache) *cache = ref_a ? SatCache{SatCache::Kind::FaceA, face_a, 0} : SatCache{SatCache::Kind::FaceB, 0, face_b};

  // clip in the reference box's frame: the incident box's face most anti-parallel to the
  // reference normal, clipped by the reference face's four sides
  const Mat3 Rri = ref_a ? p.R : glm::transpose(p.R);
  const Vec3 tri = ref_a ? p.t : -p.tb;
  const Vec3& hr = ref_a ? ha : hb;
  const Vec3& hi = ref_a ? hb : ha;
  const std::uint32_t fr = ref_a ? face_a : face_b;
  WorldFace rf, inf;
  box_face(hr, fr, Mat3(1.0), Vec3(0.0), rf);
  int k = 0;
  double best = -1;
  for (int c = 0; c < 3; ++c) {
    const double d = std::abs(glm::dot(Rri[c], rf.normal));
    if (d > best) best = d, k = c;
  }
  const std::uint32_t fi = std::uint32_t(2 * k + (glm::dot(Rri[k], rf.normal) > 0 ? 0 : 1));
  box_face(hi, fi, Rri, tri, inf);
  std::array<Candidate, kMaxPolygon> cand;
  int n = clip_faces(rf, inf.pts.data(), inf.count, false, rf.normal, 0.0, margin, ref_a, cand.data());
  if (n == 0) {
    // the incident face lies outside the reference face's sides: the deepest vertex alone
    std::uint32_t v = 0;
    double dv = INFINITY;
    for (std::uint32_t c = 0; c < 8; ++c) {
      const double d = glm::dot(rf.normal, Rri * corner(hi, c) + tri);
      if (d < dv) dv = d, v = c;
    }
    const Vec3 q = Rri * corner(hi, v) + tri;
    const double depth = rf.offset - dv;
    const Vec3 on_ref = q + depth * rf.normal;
    cand[0] = {ref_a ? on_ref : q, ref_a ? q : on_ref, depth, vertex_id(v)};
    n = 1;
  }
  if (!ref_a)
    for (int i = 0; i < n; ++i) cand[std::size_t(i)].id |= kIdFlip;
  const Vec3 normal_ref = ref_a ? rf.normal : -rf.normal;
  reduce(cand.data(), n, normal_ref, m);
  // back to the world
  const Pose& pr = ref_a ? pa : pb;
  const Mat3 W = glm::mat3_cast(pr.rotation);
  m.normal = W * m.normal;
  for (int i = 0; i < m.count; ++i) {
    ContactPoint& c = m.points[std::size_t(i)];
    c.point_a = W * c.point_a + pr.position;
    c.point_b = W * c.point_b + pr.position;
  }
}

}  // namespace pba::narrow
