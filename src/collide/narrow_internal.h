// Narrow phase internals shared by sat.cpp, manifold.cpp and the GJK/EPA files: a
// half-edge view of boxes and hulls, face clipping with feature ids, and the reduction
// of a clipped polygon to four points. Not installed.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "pba/collide/narrow_phase.h"

namespace pba::narrow {

/// segment_box_closest without its input checks (the capsule-box pair's: its poses and box
/// were checked by collide()); NaN coordinates give a NaN distance2.
SegmentBoxClosest segment_box_closest_unchecked(const Vec3& p, const Vec3& q, const Vec3& h);

using HalfEdge = ConvexHull::HalfEdge;
using HullFace = ConvexHull::Face;

/// best = max(best, x) and index = i when x > best, without a branch (which of a few
/// candidates wins is as random as the poses of the shapes): the first maximum, as a chain
/// of ifs keeps it.
inline void keep_max(double x, int i, double& best, int& index) {
  index = x > best ? i : index;
  best = std::max(best, x);
}

/// The hull vertex farthest along d (the first of equals): up to 64 vertices, a scan of
/// the coordinate arrays (ConvexHull::vertex_soa) two vertices at a time without branches
/// (contiguous dot products beat the hill climb's dependent loads there; each lane keeps its
/// first maximum, and the lanes' tie goes to the lower index); the hull's hill climb from
/// `hint` beyond. The dot products are summed as glm::dot sums them, (x + y) + z, so the
/// choice is the plain scan's to the bit.
inline std::uint32_t hull_support(const ConvexHull& h, const Vec3& d, std::uint32_t hint) {
  const std::size_t n = h.vertices().size();
  if (n > 64) return h.support_index(d, hint);
  using v2d = double __attribute__((vector_size(16)));
  using v2l = long long __attribute__((vector_size(16)));
  const std::span<const double> soa = h.vertex_soa();
  const std::size_t m = soa.size() / 3;
  const double* x = soa.data();
  const double* y = x + m;
  const double* z = y + m;
  const v2d dx = {d.x, d.x}, dy = {d.y, d.y}, dz = {d.z, d.z};
  auto dots = [&](std::size_t i) {
    const v2d vx = {x[i], x[i + 1]}, vy = {y[i], y[i + 1]}, vz = {z[i], z[i + 1]};
    return (vx * dx + vy * dy) + vz * dz;
  };
  v2d best = dots(0);
  v2l index = {0, 1}, best_index = index;
  const v2l two = {2, 2};
  for (std::size_t i = 2; i < m; i += 2) {
    index += two;
    const v2d s = dots(i);
    const v2l better = s > best;
    best = better ? s : best;
    best_index = better ? index : best_index;
  }
  const long long i0 = best_index[0], i1 = best_index[1];
  const bool odd = (best[1] > best[0]) | ((best[1] == best[0]) & (i1 < i0));
  return std::uint32_t(odd ? i1 : i0);
}

// --- the box as a half-edge polyhedron ---------------------------------------------
// vertex i is (+-hx, +-hy, +-hz) with bit 0, 1, 2 of i set for +x, +y, +z; faces are
// -x, +x, -y, +y, -z, +z (face 2k + 1 is the + side of axis k); twins at 2i, 2i + 1.

struct BoxTopology {
  std::array<HalfEdge, 24> edges{};
  std::array<std::uint32_t, 6> face_edge{};
};

constexpr BoxTopology make_box_topology() {
  // face loops, counter-clockwise seen from outside
  constexpr std::uint32_t loops[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                         {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  BoxTopology t{};
  std::uint32_t pair_of[8][8] = {};
  bool seen[8][8] = {};
  std::uint32_t pairs = 0;
  std::uint32_t he_of[6][4] = {};
  // allocate twin pairs in the order edges are met
  for (std::uint32_t f = 0; f < 6; ++f) {
    for (std::uint32_t k = 0; k < 4; ++k) {
      const std::uint32_t u = loops[f][k], v = loops[f][(k + 1) % 4];
      std::uint32_t h = 0;
      if (!seen[u][v]) {
        seen[u][v] = seen[v][u] = true;
        pair_of[u][v] = pair_of[v][u] = pairs;
        h = 2 * pairs;
        t.edges[h].origin = u;
        t.edges[h + 1].origin = v;
        t.edges[h].twin = h + 1;
        t.edges[h + 1].twin = h;
        ++pairs;
      } else {
        h = 2 * pair_of[u][v] + 1;
      }
      t.edges[h].face = f;
      he_of[f][k] = h;
    }
  }
  // next pointers around each face
  for (std::uint32_t f = 0; f < 6; ++f) {
    for (std::uint32_t k = 0; k < 4; ++k) t.edges[he_of[f][k]].next = he_of[f][(k + 1) % 4];
    t.face_edge[f] = he_of[f][0];
  }
  return t;
}

inline constexpr BoxTopology kBoxTopology = make_box_topology();

/// A convex polyhedron in its local frame: vertices, half edges, faces, and a centre.
/// Boxes fill `box.parts` (no heap; make_box_poly); hulls point at their ConvexHull.
struct Poly {
  const Vec3* vertices = nullptr;
  std::uint32_t vertex_count = 0;
  const HalfEdge* edges = nullptr;
  std::uint32_t edge_count = 0;
  const HullFace* faces = nullptr;
  std::uint32_t face_count = 0;
  Vec3 center{0, 0, 0};
  double inner_radius = 0;              // a ball about `center` inside the solid (m)
  double outer_radius = 0;              // a ball about `center` holding it (m)
  const double* face_soa = nullptr;     // hulls: ConvexHull::face_soa() (boxes: none)
  std::uint32_t face_stride = 0;        // its arrays' length
  const double* edge_soa = nullptr;     // hulls: ConvexHull::edge_soa() (boxes: none)
  std::uint32_t edge_stride = 0;        // its arrays' length
  bool is_box = false;
  Vec3 half{0, 0, 0};
  // A box's own vertices and faces (`vertices` and `faces` point at them), written by
  // make_box_poly and read through those pointers only: left unwritten until then (the
  // union's empty constructor), as members with initialisers they were 54 quadwords zeroed
  // for every Poly, a hull's too (collide_mesh's, manifold's)
  struct BoxParts {
    std::array<Vec3, 8> vertices;
    std::array<HullFace, 6> faces;
  };
  union BoxRoom {
    BoxRoom() {}
    BoxParts parts;
  } box;

  Poly() = default;
  Poly(const Poly&) = delete;
  Poly& operator=(const Poly&) = delete;

  /// The local vertex farthest along d (box: closed form; hull: its hill climb).
  std::uint32_t support_index(const Vec3& d, std::uint32_t hint = 0) const {
    if (is_box) return (d.x >= 0 ? 1u : 0u) | (d.y >= 0 ? 2u : 0u) | (d.z >= 0 ? 4u : 0u);
    return hull_support(*hull, d, hint);
  }
  const ConvexHull* hull = nullptr;
};

/// Fills `p` with the box of half extents h.
inline void make_box_poly(const Vec3& h, Poly& p) {
  p.is_box = true;
  p.half = h;
  for (std::uint32_t i = 0; i < 8; ++i)
    p.box.parts.vertices[i] = Vec3((i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z);
  for (std::uint32_t f = 0; f < 6; ++f) {
    const int axis = int(f / 2);
    const double s = (f & 1) ? 1.0 : -1.0;
    Vec3 n(0.0);
    n[axis] = s;
    p.box.parts.faces[f] = HullFace{n, h[axis], kBoxTopology.face_edge[f]};
  }
  p.vertices = p.box.parts.vertices.data();
  p.vertex_count = 8;
  p.edges = kBoxTopology.edges.data();
  p.edge_count = 24;
  p.faces = p.box.parts.faces.data();
  p.face_count = 6;
  p.center = Vec3(0.0);
  p.inner_radius = std::min({h.x, h.y, h.z});
  p.outer_radius = glm::length(h);
  p.face_soa = p.edge_soa = nullptr;
}

/// Points `p` at hull `h`.
inline void make_hull_poly(const ConvexHull& h, Poly& p) {
  p.is_box = false;
  p.hull = &h;
  p.vertices = h.vertices().data();
  p.vertex_count = std::uint32_t(h.vertices().size());
  p.edges = h.edges().data();
  p.edge_count = std::uint32_t(h.edges().size());
  p.faces = h.faces().data();
  p.face_count = std::uint32_t(h.faces().size());
  p.center = h.centroid();
  p.inner_radius = h.inner_radius();
  p.outer_radius = h.outer_radius();
  p.face_soa = h.face_soa().data();
  p.face_stride = std::uint32_t(h.face_soa().size() / 4);
  p.edge_soa = h.edge_soa().data();
  p.edge_stride = std::uint32_t(h.edge_soa().size() / 10);
}

// --- feature ids ----------------------------------------------------------------------
// A clipped point lies where two "lines" of the clipping meet: an edge of the incident
// face (label = its half edge) or a side plane of the reference face (label = 0x4000 |
// the reference half edge). An unclipped incident vertex is its vertex index. Bit 31
// says the reference face was B's, bit 30 marks an intersection, bits 29..15 and 14..0
// hold the two labels.

inline constexpr std::uint32_t kSideLabel = 0x4000;
inline constexpr std::uint32_t kLabelMask = 0x7fff;
inline constexpr std::uint32_t kIdFlip = 0x80000000u;
inline constexpr std::uint32_t kIdCross = 0x40000000u;
/// Edge-edge contacts: both half edges, marked by bits 30 and 31 both set... kept apart
/// from face ids by bit 29 of the first label (labels stay below 0x4000 | 0x3fff).
constexpr std::uint32_t vertex_id(std::uint32_t v) { return v & kLabelMask; }
constexpr std::uint32_t cross_id(std::uint32_t l1, std::uint32_t l2) {
  return kIdCross | ((l1 & kLabelMask) << 15) | (l2 & kLabelMask);
}
inline std::uint32_t edge_pair_id(std::uint32_t ea, std::uint32_t eb) {
  return kIdFlip | kIdCross | ((ea & 0x3fff) << 15) | (eb & 0x3fff) | (std::uint32_t(1) << 14);
}

// closest points of segments p1-q1 and p2-q2 (Ericson 2005, 5.1.9)
inline void closest_segments(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, Vec3& c1, Vec3& c2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = glm::dot(d1, d1), e = glm::dot(d2, d2), f = glm::dot(d2, r);
  double s = 0, t = 0;
  if (a <= 1e-300 && e <= 1e-300) {
  } else if (a <= 1e-300) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = glm::dot(d1, r);
    if (e <= 1e-300) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = glm::dot(d1, d2), den = a * e - b * b;
      s = den > 0 ? std::clamp((b * f - c * e) / den, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) t = 0, s = std::clamp(-c / a, 0.0, 1.0);
      else if (t > 1) t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
    }
  }
  c1 = p1 + d1 * s;
  c2 = p2 + d2 * t;
}

// Ericson 2005, "Real-Time Collision Detection" 5.1.5: the closest point of triangle abc
// to p by its Voronoi regions; `interior` tells whether it is inside the face
inline Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, bool& interior) {
  interior = false;
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double den = 1 / (va + vb + vc);
  interior = true;
  return a + ab * (vb * den) + ac * (vc * den);
}

// --- polygons -------------------------------------------------------------------------

inline constexpr int kMaxPolygon = 64;  // points of a clipped polygon we keep

// the polygon types are left uninitialised on construction (no member initialisers): they
// are scratch buffers of a few kilobytes filled per call, and zeroing them dominated the
// cost of a box-box manifold
struct ClipPoint {
  Vec3 p;
  std::uint32_t id;     // feature id of the point
  std::uint32_t label;  // label of the polygon edge from this point to the next
};

/// A face of a polyhedron in world coordinates with its labels.
struct WorldFace {
  std::array<ClipPoint, kMaxPolygon> pts;
  int count = 0;
  Vec3 normal{0, 0, 1};  // outward, world
  double offset = 0;     // normal . x = offset on the face
  std::array<std::uint32_t, kMaxPolygon> half_edges;  // half edge starting at pts[i]
};

/// Face `f` of `poly` at `pose` in world coordinates (at most kMaxPolygon vertices).
void world_face(const Poly& poly, const Pose& pose, std::uint32_t f, WorldFace& out);

/// The face of `poly` whose world normal is most anti-parallel to `n` (most negative dot).
std::uint32_t incident_face(const Poly& poly, const Quat& rotation, const Vec3& n);
/// The face of `poly` whose world normal is most parallel to `n`, and that dot.
std::uint32_t most_aligned_face(const Poly& poly, const Quat& rotation, const Vec3& n, double* dot);

/// A contact candidate before reduction.
struct Candidate {
  Vec3 a, b;
  double depth;
  std::uint32_t id;
};

/// Clips `incident` (points with labels, on the incident surface) against the side planes
/// of `ref`, then writes into `out` every point whose depth along `dir` (unit, pointing
/// from the reference body into the incident one) is >= -margin; `ref_is_a` decides which
/// of Candidate::a / b is the reference surface. `shift` moves each incident point by
/// -shift dir first (the incident core's radius). The side planes contain the reference
/// face's edges and its normal, or `dir` when `sides_along_dir` (every kept point's foot
/// along dir then lies on the reference face, and a point outside the face's plane at a gap g
/// (m) to it reads the gap g cosine instead of g / cosine, cosine between dir and the face
/// normal: never above its true distance). Returns the candidate count.
int clip_faces(const WorldFace& ref, const ClipPoint* incident, int incident_count, bool incident_is_segment,
               const Vec3& dir, double shift, double margin, bool ref_is_a, Candidate* out,
               bool sides_along_dir = false);

/// Reduces candidates to at most 4 (deepest, farthest from it, largest triangle, largest
/// quadrilateral; Gregorius 2015 "Robust contact creation for physics simulations") and
/// writes them into m with normal n.
void reduce(const Candidate* c, int count, const Vec3& n, Manifold& m);

/// collide() into `m`: writes its count, sub_shape_b (0), and when count > 0 its normal and
/// points [0, count); the rest of `m` is left as it was (collide() starts from Manifold{}:
/// zeroing its 288 bytes was a third of collide()'s own instructions, and a caller that
/// reads only the first `count` points, as the rigid contacts' do, need not pay it). Checks
/// and throws as collide() does.
void collide_into(const ColliderShape& a, const Pose& pose_a, const ColliderShape& b, const Pose& pose_b,
                  const NarrowPhaseSettings& settings, NarrowPhaseCache* cache, Manifold& m);

/// collide_into() for input its caller has made sure of: shapes that pass check_shape (the
/// rigid bodies' are checked when the body is made, a plane's normal unit there too), poses
/// whose position is finite and rotation a unit quaternion (a rigid body's: finite by
/// set_pose's checks and check_finite after every step, unit as body_pose and shape_frame
/// normalise it) and a finite margin (m) >= 0;
/// the same manifold, without collide_into's quick checks and the pair entries' (in the rain's
/// landing, 198 -> 50 instructions a closed-form pair around its own algorithm). Shape types
/// must be ShapeType values; a pair with no narrow phase (a mesh, a compound) throws as
/// collide() does.
void collide_unchecked_into(const ColliderShape& a, const Pose& pose_a, const ColliderShape& b, const Pose& pose_b,
                            const NarrowPhaseSettings& settings, NarrowPhaseCache* cache, Manifold& m);

/// collide_mesh() for input its caller has made sure of, as for collide_unchecked_into: a
/// shape that passes check_shape, poses whose position is finite and rotation a unit
/// quaternion, and a finite margin (m) >= 0; the same manifolds, to the bit, without its
/// check_pose and check_shape calls (about 140 instructions a call: the terrain's landing
/// makes 1,700 calls a step). A shape that is not convex, or a mesh without its body, still throws.
int collide_mesh_unchecked(const ColliderShape& a, const Pose& pose_a, const ColliderShape& mesh, const Pose& pose_mesh,
                           std::span<Manifold> out, const NarrowPhaseSettings& settings, MeshQueryCache* cache,
                           BatchPath path);

/// Whether collide_mesh_unchecked would make one manifold, and that a point of triangle `t`'s
/// face, for a ball of `radius` (m) centred at `centre` (the mesh's frame) out to `reach` (m):
/// its normal `toward` (unit, from the ball into the mesh, the mesh's frame) is t's face
/// normal, the ball is within the reach of t's plane on the side away from it and over t's
/// interior clear of its edges, and every other triangle of `near` (the pair's cache, which
/// must hold the ball's query box and all its triangles) that the query box reaches is beyond
/// the reach; margins of 1e-9 relative to the larger of the centre's coordinates and `world`
/// (m: the largest world coordinate of the two poses, whose rounding the narrow phase's centre
/// carries) keep the answer off the narrow phase's rounding. False where it cannot tell.
/// (make_manifolds' carry of a ball's manifold on a mesh.)
bool ball_on_face_alone(const TriangleMesh& M, std::uint32_t t, const Vec3& centre, double world, double radius,
                        double reach,
                        const Vec3& toward, const MeshQueryCache& near);

/// The manifold with A and B exchanged (normal flipped, points swapped).
inline void flip(Manifold& m) {
  m.normal = -m.normal;
  for (int i = 0; i < m.count; ++i) std::swap(m.points[std::size_t(i)].point_a, m.points[std::size_t(i)].point_b);
}

/// A capsule's core segment in the world: bottom (-y) and top (+y) ends.
struct Segment {
  Vec3 p, q;
};
Segment capsule_core(const ColliderShape& s, const Pose& p);
/// The box or hull view of a box or hull shape.
void poly_of(const ColliderShape& s, Poly& p);
/// Throws Error naming `where` for a non-finite pose or a rotation that is not unit.
void check_pose(const Pose& p, const char* where);
/// Throws Error naming `where` and the field for bad shape parameters.
void check_shape(const ColliderShape& s, const char* where);

/// EPA seeded by a finished GJK run whose cores overlap (ok = false otherwise).
PenetrationResult epa_from_gjk(const GjkStepper& g);

/// GJK on the cores, EPA when they overlap: the normal (A to B) and the surface points.
/// False when the shapes are farther apart than `margin` (or EPA finds no depth).
bool contact_normal(const ConvexProxy& A, const ConvexProxy& B, double margin, Vec3& n, Vec3& point_a,
                    Vec3& point_b);

/// Box/hull pair by separating axes and face clipping (sat.cpp).
void collide_polys_sat(const Poly& a, const Pose& pa, const Poly& b, const Pose& pb, double margin, SatCache* cache,
                       Manifold& m);
/// Box-box by the fifteen axes in closed form, the same choices and ids as collide_polys_sat
/// on two box polyhedra (sat_box.cpp).
void collide_boxes_sat(const Vec3& ha, const Pose& pa, const Vec3& hb, const Pose& pb, double margin, SatCache* cache,
                       Manifold& m);
/// Box-box pairs q[0..n) (both shapes boxes, already checked) into *out[0..n): the same
/// bits, and the same cache updates, as collide_boxes_sat pair by pair, computed up to 8
/// pairs at a time in SIMD lanes on `path` (sat_box.cpp).
void collide_boxes_sat_batch(const PairQuery* const* q, Manifold* const* out, int n, BatchPath path);
/// A manifold from a contact normal n (A to B) and one fallback point pair: the support
/// features of both bodies along n clipped against each other when one of them is a face
/// within a few degrees of n, else the single point (manifold.cpp).
void manifold_from_normal(const ColliderShape& sa, const Pose& pa, const ColliderShape& sb, const Pose& pb,
                          const Vec3& n, const Vec3& point_a, const Vec3& point_b, double margin, Manifold& m);

}  // namespace pba::narrow
