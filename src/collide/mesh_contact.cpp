// Convex shapes against static triangle meshes: every triangle the BVH returns for the
// shape's bounds is a thin two-sided hull; the closest points of a sphere's or capsule's core
// (closed forms), else GJK (or EPA when the cores overlap), give its normal and closest
// points, and a normal that comes from an internal edge or vertex whose flags are clear is
// replaced by the face normal before the manifold is built (the
// "internal edge" cure of Jolt's ActiveEdges and Box2D's smooth segments: such an edge
// lies flat or concave between two faces, so its own normal would be a ghost contact).
#include <cmath>
#include <new>
#include <type_traits>

#include "narrow_internal.h"

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>

#include "core/lanes.h"
#define PBA_MESH_LANES_X86 1
#else
#define PBA_MESH_LANES_X86 0
#endif

namespace pba {

using namespace narrow;

namespace {

// the barycentric weights of the point q (in the triangle's plane): u for a, v for b, w for c
void weights(const Vec3 t[3], const Vec3& q, double& u, double& v, double& w) {
  const Vec3 n = glm::cross(t[1] - t[0], t[2] - t[0]);
  const double nn = glm::dot(n, n);
  v = glm::dot(glm::cross(q - t[0], t[2] - t[0]), n) / nn;
  w = glm::dot(glm::cross(t[1] - t[0], q - t[0]), n) / nn;
  u = 1 - v - w;
}

// which of the triangle's features the point q (on it) lies on: the mask of edges it
// touches (ab = 1, bc = 2, ca = 4; 0 = the interior; two bits = a vertex)
std::uint8_t feature_edges(const Vec3 t[3], const Vec3& q) {
  double u, v, w;
  weights(t, q, u, v, w);
  constexpr double kOn = 1e-9;  // relative: the closest point of GJK is exact to rounding
  std::uint8_t m = 0;
  if (w <= kOn) m |= 1;  // opposite c: edge ab
  if (u <= kOn) m |= 2;  // opposite a: edge bc
  if (v <= kOn) m |= 4;  // opposite b: edge ca
  return m;
}

// The closest points ca (on the segment p-q; p = q for a point) and cb (on the triangle) in
// closed form (Ericson 2005, 5.1.5 and 5.1.9): apart, the nearest pair is an end of the
// segment against the triangle or the segment against one of its edges (a segment parallel
// to the face has such a pair among its nearest ones). False when the segment passes
// through the triangle or lies in its plane: the cores overlap, and EPA finds the depth.
bool core_triangle_closest(const Vec3& p, const Vec3& q, const Vec3 tri[3], const Vec3& face_normal, Vec3& ca,
                           Vec3& cb) {
  bool interior = false;
  ca = p;
  cb = closest_on_triangle(p, tri[0], tri[1], tri[2], interior);
  if (p == q) return true;
  const double dp = glm::dot(face_normal, p - tri[0]), dq = glm::dot(face_normal, q - tri[0]);
  if ((dp <= 0 && dq >= 0) || (dp >= 0 && dq <= 0)) {
    if (dp == dq) return false;  // in the plane
    // where the segment crosses the plane: inside the triangle, the cores overlap
    const Vec3 x = p + (dp / (dp - dq)) * (q - p);
    closest_on_triangle(x, tri[0], tri[1], tri[2], interior);
    if (interior) return false;
  }
  double best = glm::dot(ca - cb, ca - cb);
  const Vec3 cq = closest_on_triangle(q, tri[0], tri[1], tri[2], interior);
  if (const double d = glm::dot(q - cq, q - cq); d < best) best = d, ca = q, cb = cq;
  for (int k = 0; k < 3; ++k) {
    Vec3 c1, c2;
    closest_segments(p, q, tri[k], tri[(k + 1) % 3], c1, c2);
    if (const double d = glm::dot(c1 - c2, c1 - c2); d < best) best = d, ca = c1, cb = c2;
  }
  return true;
}

// where a contact normal comes from: the triangle's face, a face of the shape, an edge of
// each (separating axes), or elsewhere (closed forms, GJK, EPA)
enum class Axis { Triangle, Face, Edges, Other };

// out[i] = q * in[i] for i < n, plus *at when given (apply()'s position): glm's quaternion
// rotation (v + 2 (w (u x v) + u x (u x v)), u the quaternion's vector part), lane by lane in
// the same operations and order, four vectors at a time, so the bits are the scalar ones
#if PBA_MESH_LANES_X86
[[gnu::target("avx2")]] [[gnu::noinline]] void turn_avx2(const Quat& q, const Vec3* in, std::uint32_t n,
                                                         const Vec3* at, Vec3* out) {
  using V = detail::lanes::v4d;
  using detail::lanes::splat;
  const V qx = splat<V>(q.x), qy = splat<V>(q.y), qz = splat<V>(q.z), qw = splat<V>(q.w);
  for (std::uint32_t i = 0; i < n; i += 4) {
    // (lanes past n repeat the last vector and are not stored)
    const std::uint32_t i1 = std::min(i + 1, n - 1), i2 = std::min(i + 2, n - 1), i3 = std::min(i + 3, n - 1);
    const V vx = {in[i].x, in[i1].x, in[i2].x, in[i3].x}, vy = {in[i].y, in[i1].y, in[i2].y, in[i3].y},
            vz = {in[i].z, in[i1].z, in[i2].z, in[i3].z};
    V rx, ry, rz;
    detail::lanes::quat_turn(qx, qy, qz, qw, vx, vy, vz, rx, ry, rz);
    if (at) rx = at->x + rx, ry = at->y + ry, rz = at->z + rz;
    for (std::uint32_t l = 0; l < 4 && i + l < n; ++l) out[i + l] = Vec3(rx[l], ry[l], rz[l]);
  }
}
#endif
void turn(bool wide, const Quat& q, const Vec3* in, std::uint32_t n, const Vec3* at, Vec3* out) {
#if PBA_MESH_LANES_X86
  if (wide) return turn_avx2(q, in, n, at, out);
#endif
  (void)wide;
  for (std::uint32_t i = 0; i < n; ++i) out[i] = at ? *at + q * in[i] : q * in[i];
}

// A box or hull (P at pose pa, at most 64 vertices) against a triangle by separating axes:
// the triangle's normal, the shape's face normals and the crosses of their edges. Along
// each axis the shape and the triangle project to intervals; the largest gap between them
// is the separation (negative: the overlap), and for two polytopes the smallest overlap
// over these axes is the penetration depth EPA finds (Gottschalk 1996; Ericson 2005, 5.2.1).
// Returns 0 when some axis separates them by more than `margin`; 1 when they overlap, or
// are apart over the triangle's face (the shape's nearest vertex projects into it), with
// the normal n (shape to triangle), the deepest (or closest) points (point_a on the shape,
// point_b on the triangle, point_a - point_b = depth n) and the triangle's feature the
// contact is on (as feature_edges: 0 the face, an edge's bit, a vertex's two); 2 when they
// are apart otherwise: GJK then finds the distance, which a gap along an axis only bounds.
// `kind` tells where the normal of a 1 comes from. The shape's vertices at pa and a box's
// half axes come from the caller (PolyAt: once for all the triangles).
struct PolyAt {
  std::array<Vec3, 64> v;  // P's vertices at pa (world, m)
  Vec3 half_axes[3];       // a box's: its centre -+ their sum spans it along any axis (m)
  // What the separating axes take from the shape alone, the same for every triangle of the
  // call, made when a sat_triangle first needs them (`made`): the face axes it tests (a box's
  // three, a hull's all) turned to the world, the shape's span along each, and the edge
  // directions (a box's three, a hull's edges once each) turned to the world with the edge
  // each came from and 1e-20 times its squared length (the parallel test's scale). Before,
  // each triangle turned them and, on a hull, projected every vertex on every face axis
  // again: a pyramid on two triangles did it twice. A hull of at most 64 vertices has at most
  // 2 * 64 - 4 faces and 3 * 64 - 6 edges (Euler), so they fit
  static constexpr std::uint32_t kFaces = 124, kEdges = 186;
  bool made = false;
  // the vertices, face axes and edge directions turned, and the edge axes tested, four at a
  // time in AVX2 lanes (turn_avx2, sat_edges_avx2; the caller's choice, on a processor that
  // has them); the edge axes' inputs below are then made too
  bool wide = false;
  std::uint32_t face_axes = 0, edge_dirs = 0;
  Vec3 face_d[kFaces];
  double face_lo[kFaces], face_hi[kFaces];
  Vec3 edge_d[kEdges];
  double edge_scale[kEdges];
  std::uint32_t edge_of[kEdges];
  // For the lanes: edge axis q (edge direction q / 3 crossed with the triangle's edge q % 3,
  // the scalar loop's order) takes the direction's x, y, z and scale at index q; zeros past
  // the last axis up to a multiple of four (never read as an axis)
  static constexpr std::uint32_t kAxes = 3 * kEdges + 2;
  double axis_x[kAxes], axis_y[kAxes], axis_z[kAxes], axis_scale[kAxes];

  // (r: pa.rotation as a matrix; `wide` set before)
  void set(const Poly& P, const Pose& pa, const Mat3& r) {
    turn(wide, pa.rotation, P.vertices, P.vertex_count, &pa.position, v.data());  // apply(pa, vertex)
    if (P.is_box) half_axes[0] = r[0] * P.half.x, half_axes[1] = r[1] * P.half.y, half_axes[2] = r[2] * P.half.z;
    made = false;
  }

  // the shape's span [lo, hi] along the unit axis d (m)
  void span(const Poly& P, const Pose& pa, const Vec3& d, double& lo, double& hi) const {
    if (P.is_box) {
      const double c = glm::dot(d, pa.position);
      const double w = std::abs(glm::dot(d, half_axes[0])) + std::abs(glm::dot(d, half_axes[1])) +
                       std::abs(glm::dot(d, half_axes[2]));
      lo = c - w, hi = c + w;
    } else {
      lo = INFINITY, hi = -INFINITY;
      for (std::uint32_t i = 0; i < P.vertex_count; ++i) {
        const double x = glm::dot(d, v[i]);
        lo = std::min(lo, x), hi = std::max(hi, x);
      }
    }
  }

  void make(const Poly& P, const Pose& pa) {
    made = true;
    face_axes = 0, edge_dirs = 0;
    // the local face normals and edges gathered here, then turned to the world together
    Vec3 local[kEdges];
    for (std::uint32_t f = 0; f < P.face_count; ++f) {
      if (P.is_box && (f & 1) == 0) continue;  // a box's opposite faces share their axis
      local[face_axes++] = P.faces[f].normal;
    }
    turn(wide, pa.rotation, local, face_axes, nullptr, face_d);
    for (std::uint32_t f = 0; f < face_axes; ++f) span(P, pa, face_d[f], face_lo[f], face_hi[f]);
    auto add_edge = [&](std::uint32_t e) {
      const HalfEdge& he = P.edges[e];
      local[edge_dirs] = P.vertices[P.edges[he.next].origin] - P.vertices[he.origin];
      edge_of[edge_dirs] = e;
      ++edge_dirs;
    };
    if (P.is_box) {
      // a box's edges run along its three axes: the first of each
      bool box_direction[3] = {false, false, false};
      for (std::uint32_t e = 0; e < P.edge_count; ++e) {
        const HalfEdge& he = P.edges[e];
        if (he.twin < e) continue;  // each edge once
        const Vec3 local = P.vertices[P.edges[he.next].origin] - P.vertices[he.origin];
        const int i = local.x != 0 ? 0 : local.y != 0 ? 1 : 2;
        if (box_direction[i]) continue;
        box_direction[i] = true;
        add_edge(e);
      }
    } else {
      // A hull's edge equal to a kept one, or its exact opposite (a square pyramid's base
      // has two pairs: 24 edge axes a triangle become 18), gives the same axes or their
      // exact negations: turning, crossing, projecting and the min and max all commute
      // with a sign change (to the bit, but for the signs of zeros), so along -d the gap
      // is the one along d. Its axes then never end the test first nor win (a later axis
      // wins only when deeper by kEdgeBias), and the deepest edge of a direction is
      // searched among all parallel ones (sat_triangle's end): the same result, to the
      // bit. The hull's setup keeps the first edge of each direction
      // (ConvexHull::edge_directions); here a call compared each edge with those kept
      for (const std::uint32_t e : P.hull->edge_directions()) add_edge(e);
    }
    turn(wide, pa.rotation, local, edge_dirs, nullptr, edge_d);
    for (std::uint32_t j = 0; j < edge_dirs; ++j) edge_scale[j] = 1e-20 * glm::dot(edge_d[j], edge_d[j]);
    if (wide) {
      std::uint32_t q = 0;
      for (std::uint32_t j = 0; j < edge_dirs; ++j)
        for (int k = 0; k < 3; ++k, ++q)
          axis_x[q] = edge_d[j].x, axis_y[q] = edge_d[j].y, axis_z[q] = edge_d[j].z, axis_scale[q] = edge_scale[j];
      for (; q % 4 != 0; ++q) axis_x[q] = axis_y[q] = axis_z[q] = axis_scale[q] = 0;
    }
  }
};

// edge pairs win over faces only by more than rounding, so a face resting on a face keeps
// the face's normal
constexpr double kEdgeBias = 1e-9;

// The edge axes' part of sat_triangle (its loop over at.edge_dirs and the triangle's three
// edges) four axes at a time: every lane makes its axis, the shape's span and the gap along
// it with the scalar loop's operations in its order (the same bits), then the lanes are
// judged one by one in the loop's order, as it judges its axes. Returns 0 when an axis
// separates them by more than the margin, 2 when one separates them by no more (the first
// such axis, as the loop meets them), else 1 with the deepest axis kept in best, axis,
// best_above, kind, edge_a and edge_b. An early end wastes the rest of its group (up to
// three axes), which the scalar loop would not make. kBeyondOnly: only whether some axis
// separates them by more than the margin (0), else 1; best and the rest are left alone.
#if PBA_MESH_LANES_X86
template <bool kBeyondOnly>
[[gnu::target("avx2")]] [[gnu::noinline]] int sat_edges_avx2(const Poly& P, const PolyAt& at, const Pose& pa,
                                                             const Vec3 tri[3], const Vec3 te[3], const double tt[3],
                                                             double margin, double& best, Vec3& axis, bool& best_above,
                                                             Axis& kind, std::uint32_t& edge_a, std::uint32_t& edge_b) {
  using V = detail::lanes::v4d;
  using L = detail::lanes::v4l;
  using detail::lanes::load;
  using detail::lanes::splat;
  using detail::lanes::vmax;
  using detail::lanes::vmin;
  // the triangle's edge k = q % 3 of axis q, for the four lanes of the groups starting at
  // q % 12 = 0, 4 and 8 (the pattern's period is 12): edges 0 1 2 0, 1 2 0 1, 2 0 1 2
  const V tx[3] = {V{te[0].x, te[1].x, te[2].x, te[0].x}, V{te[1].x, te[2].x, te[0].x, te[1].x},
                   V{te[2].x, te[0].x, te[1].x, te[2].x}};
  const V ty[3] = {V{te[0].y, te[1].y, te[2].y, te[0].y}, V{te[1].y, te[2].y, te[0].y, te[1].y},
                   V{te[2].y, te[0].y, te[1].y, te[2].y}};
  const V tz[3] = {V{te[0].z, te[1].z, te[2].z, te[0].z}, V{te[1].z, te[2].z, te[0].z, te[1].z},
                   V{te[2].z, te[0].z, te[1].z, te[2].z}};
  const V tq[3] = {V{tt[0], tt[1], tt[2], tt[0]}, V{tt[1], tt[2], tt[0], tt[1]}, V{tt[2], tt[0], tt[1], tt[2]}};
  const V ax = splat<V>(tri[0].x), ay = splat<V>(tri[0].y), az = splat<V>(tri[0].z);
  const V bx = splat<V>(tri[1].x), by = splat<V>(tri[1].y), bz = splat<V>(tri[1].z);
  const V cx = splat<V>(tri[2].x), cy = splat<V>(tri[2].y), cz = splat<V>(tri[2].z);
  const L no_sign = L{} + 0x7fffffffffffffffL;
  auto vabs = [&](const V& x) { return reinterpret_cast<V>(reinterpret_cast<L>(x) & no_sign); };  // std::abs
  const std::uint32_t count = 3 * at.edge_dirs, nv = P.vertex_count;
  const L lane = {0, 1, 2, 3};
  for (std::uint32_t q = 0, r = 0; q < count; q += 4, r = r == 2 ? 0 : r + 1) {
    const V ex = load<V>(at.axis_x + q), ey = load<V>(at.axis_y + q), ez = load<V>(at.axis_z + q);
    const V gx = tx[r], gy = ty[r], gz = tz[r];
    // glm::cross(ea, te[k]), glm::dot(c, c), the parallel test, c / sqrt(cc)
    const V kx = ey * gz - gy * ez, ky = ez * gx - gz * ex, kz = ex * gy - gx * ey;
    const V cc = (kx * kx + ky * ky) + kz * kz;
    const L parallel = cc <= load<V>(at.axis_scale + q) * tq[r];
    const V root = _mm256_sqrt_pd(cc);
    const V dx = kx / root, dy = ky / root, dz = kz / root;
    // the shape's span along d (PolyAt::span)
    V lo, hi;
    if (P.is_box) {
      const V c = (dx * pa.position.x + dy * pa.position.y) + dz * pa.position.z;
      const Vec3* h = at.half_axes;
      const V w = (vabs((dx * h[0].x + dy * h[0].y) + dz * h[0].z) + vabs((dx * h[1].x + dy * h[1].y) + dz * h[1].z)) +
                  vabs((dx * h[2].x + dy * h[2].y) + dz * h[2].z);
      lo = c - w, hi = c + w;
    } else {
      lo = splat<V>(INFINITY), hi = splat<V>(-INFINITY);
      for (std::uint32_t i = 0; i < nv; ++i) {
        const V x = (dx * at.v[i].x + dy * at.v[i].y) + dz * at.v[i].z;
        lo = vmin(lo, x), hi = vmax(hi, x);
      }
    }
    // the gap (sat_triangle's gap_of)
    const V t0 = (dx * ax + dy * ay) + dz * az, t1 = (dx * bx + dy * by) + dz * bz, t2 = (dx * cx + dy * cy) + dz * cz;
    const V tlo = vmin(t0, vmin(t1, t2)), thi = vmax(t0, vmax(t1, t2));
    const V up = lo - thi, down = tlo - hi;
    const L above = up >= down;
    const V g = above ? up : down;
    // the lanes judged one by one only where one is apart or deeper than the best so far
    // (the best only grows within the group, and with it best + kEdgeBias: a lane not
    // deeper than the group's first best + kEdgeBias is not deeper than a later one's)
    const L counted = (lane < L{} + std::int64_t(count - q)) & ~parallel;
    if constexpr (kBeyondOnly) {
      if (_mm256_movemask_pd(reinterpret_cast<__m256d>(counted & (g > margin))) != 0) return 0;
      continue;
    }
    const L judged = counted & ((g > 0) | (g > best + kEdgeBias));
    if (_mm256_movemask_pd(reinterpret_cast<__m256d>(judged)) == 0) continue;
    const std::uint32_t lanes = std::min(4u, count - q);
    for (std::uint32_t l = 0; l < lanes; ++l) {
      if (parallel[l]) continue;
      if (g[l] > margin) return 0;
      if (g[l] > 0) return 2;
      if (g[l] > best + kEdgeBias)
        best = g[l], axis = Vec3(dx[l], dy[l], dz[l]), best_above = above[l] != 0, kind = Axis::Edges,
        edge_a = at.edge_of[(q + l) / 3], edge_b = (q + l) % 3;
    }
  }
  return 1;
}
#endif

int sat_triangle(const Poly& P, PolyAt& at, const Pose& pa, const Vec3 tri[3], const Vec3& face_normal,
                 double normal_lo, double normal_hi, double margin, Vec3& n, Vec3& point_a, Vec3& point_b,
                 std::uint8_t& on, Axis& kind) {
  const std::array<Vec3, 64>& v = at.v;
  const std::uint32_t nv = P.vertex_count;
  // the gap along the unit axis d given the shape's span [lo, hi] along it, and whether the
  // shape lies on its positive side
  auto gap_of = [&](const Vec3& d, double lo, double hi, bool& above) {
    const double t0 = glm::dot(d, tri[0]), t1 = glm::dot(d, tri[1]), t2 = glm::dot(d, tri[2]);
    const double tlo = std::min(t0, std::min(t1, t2)), thi = std::max(t0, std::max(t1, t2));
    above = lo - thi >= tlo - hi;
    return above ? lo - thi : tlo - hi;
  };
  auto gap = [&](const Vec3& d, bool& above) {
    double lo, hi;
    at.span(P, pa, d, lo, hi);
    return gap_of(d, lo, hi, above);
  };
  // whether the shape lies beyond one of the triangle's sides (the planes through an edge at
  // right angles to the face) by more than the margin: a shape apart from the triangle is
  // mostly beside it, past an edge that a neighbour triangle shares
  auto beyond_sides = [&] {
    bool side_above = false;
    for (int k = 0; k < 3; ++k) {
      const Vec3 c = glm::cross(tri[(k + 1) % 3] - tri[k], face_normal);
      const double cc = glm::dot(c, c);
      if (!(cc > 0)) continue;
      if (gap(c / std::sqrt(cc), side_above) > margin) return true;
    }
    return false;
  };
  const Vec3 te[3] = {tri[1] - tri[0], tri[2] - tri[1], tri[0] - tri[2]};
  const double tt[3] = {glm::dot(te[0], te[0]), glm::dot(te[1], te[1]), glm::dot(te[2], te[2])};
  // whether some axis separates them by more than the margin: the triangle's sides, else the
  // shape's face axes and the edge axes, all of them (the test below stops at the first axis
  // that separates them by no more). GJK's distance is never below the gap along any axis, so
  // GJK would find them beyond the margin too: the same answer without its run. (With the
  // triangle's sides alone a fifth of the runs were saved so; with every axis, scalar, about
  // half, for about what they saved. With the face axes' spans made once a call and the edge
  // axes in AVX2 lanes, on the terrain's steps 300-330 the axes cost 0.23 M instructions a
  // step and saved 0.30 M of GJK; its landing's 120 steps, 20 M of 2,445 M in all)
  auto beyond_any = [&] {
    if (beyond_sides()) return true;
    if (!at.made) at.make(P, pa);
    bool side_above = false;
    for (std::uint32_t f = 0; f < at.face_axes; ++f)
      if (gap_of(at.face_d[f], at.face_lo[f], at.face_hi[f], side_above) > margin) return true;
#if PBA_MESH_LANES_X86
    if (at.wide) {
      double unused_best = -INFINITY;
      Vec3 unused_axis;
      bool unused_above = false;
      Axis unused_kind = Axis::Other;
      std::uint32_t unused_a = 0, unused_b = 0;
      return sat_edges_avx2<true>(P, at, pa, tri, te, tt, margin, unused_best, unused_axis, unused_above, unused_kind,
                                  unused_a, unused_b) == 0;
    }
#endif
    for (std::uint32_t j = 0; j < at.edge_dirs; ++j)
      for (std::uint32_t k = 0; k < 3; ++k) {
        const Vec3 c = glm::cross(at.edge_d[j], te[k]);
        const double cc = glm::dot(c, c);
        if (cc <= at.edge_scale[j] * tt[k]) continue;
        if (gap(c / std::sqrt(cc), side_above) > margin) return true;
      }
    return false;
  };
  kind = Axis::Triangle;
  bool above = false;
  // a gap beyond the margin along any axis: no contact (the shape's span along the
  // triangle's normal is the caller's plane test's)
  double best = gap_of(face_normal, normal_lo, normal_hi, above);
  if (best > margin) return 0;
  if (best > 0) {
    // over the face: the shape's nearest vertex projects into the triangle, so that pair of
    // points is as far apart as the gap, a lower bound of the distance: they are the closest
    n = above ? -face_normal : face_normal;
    std::uint32_t nearest = 0;
    for (std::uint32_t i = 1; i < nv; ++i)
      if (glm::dot(n, v[i]) > glm::dot(n, v[nearest])) nearest = i;
    const Vec3 q = v[nearest] + best * n;
    bool interior = false;
    const Vec3 c = closest_on_triangle(q, tri[0], tri[1], tri[2], interior);
    if (interior) {
      point_a = v[nearest], point_b = c, on = 0;
      return 1;
    }
  }
  // apart along an axis by no more than the margin (here and below): GJK's case, unless some
  // axis separates them by more (beyond_any: the triangle's sides, the shape's faces, the edge
  // axes). GJK's distance (never below the true one) is then beyond the margin too, so the
  // answer is the same without the GJK run
  if (best > 0) return beyond_any() ? 0 : 2;
  // (the shape's axes made only now: the tests above need its placed vertices alone)
  if (!at.made) at.make(P, pa);
  Vec3 axis = face_normal;
  bool best_above = above;
  std::uint32_t edge_a = 0, edge_b = 0;
  for (std::uint32_t f = 0; f < at.face_axes; ++f) {
    const Vec3& d = at.face_d[f];
    const double g = gap_of(d, at.face_lo[f], at.face_hi[f], above);
    if (g > margin) return 0;
    if (g > 0) return beyond_any() ? 0 : 2;
    if (g > best) best = g, axis = d, best_above = above, kind = Axis::Face;
  }
#if PBA_MESH_LANES_X86
  if (at.wide) {
    const int r = sat_edges_avx2<false>(P, at, pa, tri, te, tt, margin, best, axis, best_above, kind, edge_a, edge_b);
    if (r == 0) return 0;
    if (r == 2) return beyond_any() ? 0 : 2;
  }
#endif
  for (std::uint32_t j = 0; j < at.edge_dirs && !at.wide; ++j) {
    const Vec3& ea = at.edge_d[j];
    for (std::uint32_t k = 0; k < 3; ++k) {
      const Vec3 c = glm::cross(ea, te[k]);
      const double cc = glm::dot(c, c);
      if (cc <= at.edge_scale[j] * tt[k]) continue;
      const Vec3 d = c / std::sqrt(cc);
      const double g = gap(d, above);
      if (g > margin) return 0;
      if (g > 0) return beyond_any() ? 0 : 2;
      if (g > best + kEdgeBias) best = g, axis = d, best_above = above, kind = Axis::Edges, edge_a = at.edge_of[j], edge_b = k;
    }
  }
  // the normal from the shape to the triangle: against the axis when the shape is above
  n = best_above ? -axis : axis;
  const double depth = -best;
  if (kind == Axis::Triangle) {
    // the shape's deepest vertex into the triangle, onto its plane; the face
    std::uint32_t deepest = 0;
    for (std::uint32_t i = 1; i < nv; ++i)
      if (glm::dot(n, v[i]) > glm::dot(n, v[deepest])) deepest = i;
    point_a = v[deepest];
    point_b = point_a - depth * n;
    on = 0;
  } else if (kind == Axis::Face) {
    // the triangle's deepest vertex (or edge, or all three) into the shape's face
    const double d0 = glm::dot(n, tri[0]), d1 = glm::dot(n, tri[1]), d2 = glm::dot(n, tri[2]);
    const double lo = std::min(d0, std::min(d1, d2));
    const double tie = 1e-9 * (1 + std::abs(lo));
    const bool at[3] = {d0 <= lo + tie, d1 <= lo + tie, d2 <= lo + tie};
    const int i = at[0] ? 0 : at[1] ? 1 : 2;
    point_b = tri[i];
    point_a = point_b + depth * n;
    // a vertex touches its two edges (a: ab and ca, b: ab and bc, c: bc and ca); two
    // vertices, the edge between them; three, the face
    constexpr std::uint8_t kVertexEdges[3] = {1 | 4, 1 | 2, 2 | 4};
    on = 0xff;
    for (int k = 0; k < 3; ++k)
      if (at[k]) on &= kVertexEdges[k];
    if (at[0] && at[1] && at[2]) on = 0;
  } else {
    // the shape's edge of this direction deepest into the triangle, and the triangle's
    // edge: their closest points
    const HalfEdge& he = P.edges[edge_a];
    const Vec3 dir = P.vertices[P.edges[he.next].origin] - P.vertices[he.origin];
    std::uint32_t pick = edge_a;
    double far = -INFINITY;
    for (std::uint32_t e = 0; e < P.edge_count; ++e) {
      const HalfEdge& h = P.edges[e];
      const Vec3 de = P.vertices[P.edges[h.next].origin] - P.vertices[h.origin];
      if (h.twin < e || glm::dot(glm::cross(de, dir), glm::cross(de, dir)) > 1e-18 * glm::dot(de, de) * glm::dot(dir, dir))
        continue;
      const double x = glm::dot(n, v[h.origin] + v[P.edges[h.next].origin]);
      if (x > far) far = x, pick = e;
    }
    const HalfEdge& hp = P.edges[pick];
    closest_segments(v[hp.origin], v[P.edges[hp.next].origin], tri[edge_b], tri[(edge_b + 1) % 3], point_a, point_b);
    on = std::uint8_t(1u << edge_b);
  }
  return 1;
}

// whether the point x lies over the triangle: inside its three side planes (through an edge,
// at right angles to the face)
bool over_triangle(const Vec3 tri[3], const Vec3& x) {
  const Vec3 w = glm::cross(tri[1] - tri[0], tri[2] - tri[0]);  // counter-clockwise about w
  for (int k = 0; k < 3; ++k) {
    const Vec3 p0 = tri[k], p1 = tri[(k + 1) % 3];
    if (glm::dot(glm::cross(p1 - p0, w), x - p0) > 0) return false;
  }
  return true;
}

// whether the point y of triangle t's plane lies on another triangle of the mesh in that
// plane (its normal parallel, y in its plane and over it, each to rounding): the surface goes
// on flat there, so t's plane is the surface at y (a flat grid's neighbour, which then gives
// the same point itself)
bool on_coplanar_triangle(const TriangleMesh& M, std::uint32_t t, const Vec3& y, const Vec3& face_normal) {
  const double eps = 1e-9 * (1 + std::max(std::abs(y.x), std::max(std::abs(y.y), std::abs(y.z))));
  bool found = false;
  M.query(Aabb{y - Vec3(eps), y + Vec3(eps)}, [&](std::uint32_t k) {
    if (found || k == t) return;
    const Vec3 nk = M.normal(k);
    if (std::abs(glm::dot(nk, face_normal)) < 1 - 1e-9) return;
    const auto& idx = M.triangles()[k];
    const Vec3 tk[3] = {M.vertices()[idx[0]], M.vertices()[idx[1]], M.vertices()[idx[2]]};
    if (std::abs(glm::dot(nk, y - tk[0])) > eps) return;
    found = over_triangle(tk, y);
  });
  return found;
}

// one triangle (t of the mesh M) against the convex shape (both in the mesh's frame); true
// when in contact. P: a box's or hull's polyhedron (poly: a is one), at: its vertices at pa
// (P.vertex_count <= 64), both made once by the caller
bool collide_triangle(const ColliderShape& a, const Pose& pa, const ConvexProxy& A, const Poly& P, bool poly,
                      PolyAt& at, const TriangleMesh& M, const Vec3 tri[3], const Vec3& face_normal, double normal_lo,
                      double normal_hi, std::uint8_t flags, double margin, std::uint32_t t, Manifold& m) {
  m.count = 0;
  m.sub_shape_b = t;
  Vec3 n, point_a, point_b;
  // a sphere's or capsule's core (a point or a segment) apart from the triangle: the closest
  // points in closed form give what GJK converges to (its stop at a 1e-10 m gap, and its
  // test for touching cores, a closest point within 1e-12 m of the origin, kept)
  bool closed = false;
  Axis kind = Axis::Other;
  std::uint8_t on = 0xff;  // the triangle's feature, when the separating axes give it
  if (poly && P.vertex_count <= 64) {
    const int r = sat_triangle(P, at, pa, tri, face_normal, normal_lo, normal_hi, margin, n, point_a, point_b, on, kind);
    if (r == 0) return false;
    closed = r == 1;
    if (!closed) kind = Axis::Other;
  } else if (a.type == ShapeType::Sphere || a.type == ShapeType::Capsule) {
    const Segment s = a.type == ShapeType::Capsule ? capsule_core(a, pa) : Segment{pa.position, pa.position};
    Vec3 ca, cb;
    if (core_triangle_closest(s.p, s.q, tri, face_normal, ca, cb)) {
      const Vec3 v = ca - cb;
      const double vv = glm::dot(v, v);
      if (vv > 1e-24) {
        const double dist = std::sqrt(vv);
        if (dist - A.radius > margin) return false;
        n = -v / dist;
        point_a = ca + A.radius * n;
        point_b = cb;
        closed = true;
      }
    }
  }
  if (!closed) {
    ConvexProxy B;
    B.type = ShapeType::Mesh;
    B.triangle = tri;
    if (!contact_normal(A, B, margin, n, point_a, point_b)) return false;
  }
  // an internal (flat or concave) edge or vertex takes the face normal, on the side of
  // the triangle where the shape's centre is (a hull's centroid: its origin may lie on its
  // surface, as a pyramid's at the middle of its base, and a pyramid resting on its base
  // had its side picked by rounding and was pushed through the mesh)
  if (on == 0xff) on = feature_edges(tri, point_b);
  const bool internal = on == 0 || (on & flags) == 0;
  Vec3 use = n;
  if (internal) {
    const Vec3 centre = a.type == ShapeType::Hull ? apply(pa, a.hull->centroid()) : pa.position;
    const double side = glm::dot(centre - tri[0], face_normal) >= 0 ? 1.0 : -1.0;
    use = -side * face_normal;
  }
  // the reference face as separating axes choose it (Gottschalk 1996; Ericson 2005, 5.2.1):
  // the face the normal comes from. The triangle's when it is the triangle's normal (or an
  // internal feature's, snapped to it), the shape's face when it is that face's normal (a
  // triangle's vertex or edge in it: the triangle is then clipped to the face, so its
  // deepest vertex is a point), and none for an edge's or a vertex's normal (one point).
  // A normal that is a face's only to rounding (closed forms, GJK, EPA: within ~4e-5 rad)
  // is made that face's, so the points lie on the face and inside its side planes. Before,
  // the triangle was always the reference, through its first vertex at right angles to the
  // normal: a tilted plane off the triangle when the normal was not its own, whose points
  // lay up to the triangle's size away from both shapes (a capsule over an edge), or missed
  // the deepest (a triangle's vertex in a box's face).
  constexpr double kAligned = 1 - 1e-9;
  enum class Ref { None, Triangle, Shape } ref = Ref::None;
  bool snapped = false;
  std::uint32_t f = 0;
  double dot = 0;
  if (poly) f = most_aligned_face(P, pa.rotation, use, &dot);
  if (internal || kind == Axis::Triangle) {
    ref = Ref::Triangle;
  } else if (kind == Axis::Face) {
    ref = Ref::Shape;
  } else if (kind == Axis::Other) {
    const double along = glm::dot(use, face_normal);
    const Vec3 face_use = along > 0 ? face_normal : -face_normal;
    // the triangle's normal where the shape's point lies over the triangle along it (else
    // it is an edge's or a vertex's normal within 4e-5 rad of the face's, and kept)
    if (std::abs(along) >= kAligned && over_triangle(tri, point_a)) {
      ref = Ref::Triangle;
      use = face_use;
      snapped = true;
    } else if (poly && dot >= kAligned) {
      ref = Ref::Shape;
      use = pa.rotation * P.faces[f].normal;
    }
  }
  // (a snapped normal is the triangle's now: its face again; an internal feature's or the
  // triangle's own normal is the one the face above was found for, so it stands)
  if (ref == Ref::Triangle && poly && snapped) f = most_aligned_face(P, pa.rotation, use, &dot);
  // the triangle's side that faces the shape, its vertices counter-clockwise about it
  WorldFace rf;
  rf.normal = -use;
  rf.offset = glm::dot(rf.normal, tri[0]);
  rf.count = 3;
  const bool flipped = glm::dot(glm::cross(tri[1] - tri[0], tri[2] - tri[0]), rf.normal) < 0;
  for (int k = 0; k < 3; ++k) {
    const int i = flipped ? 2 - k : k;
    rf.pts[std::size_t(k)] = {tri[i], vertex_id(std::uint32_t(i)), std::uint32_t(i)};
    rf.half_edges[std::size_t(k)] = std::uint32_t(flipped ? (i + 2) % 3 : i);
  }
  std::array<Candidate, kMaxPolygon> cand;
  int count = 0;
  const double radius = A.radius;
  bool flip_ids = true;  // the triangle's features are B's: their ids carry the flip bit
  if (ref == Ref::Shape) {
    // the triangle clipped to the shape's face, onto it along the normal
    WorldFace sf;
    world_face(P, pa, f, sf);
    const std::array<ClipPoint, 3> tp{ClipPoint{tri[0], vertex_id(0), 0}, ClipPoint{tri[1], vertex_id(1), 1},
                                      ClipPoint{tri[2], vertex_id(2), 2}};
    count = clip_faces(sf, tp.data(), 3, false, use, 0.0, margin, true, cand.data());
    flip_ids = false;
  } else if (ref == Ref::Triangle && poly) {
    // the shape's face most along the normal clipped to the triangle, at any tilt (as
    // box-box clips its incident face): its vertices beyond the margin drop out, so a face
    // gives its points, an edge its two ends, a vertex itself. Before, only a face within
    // 1e-9 (a snapped normal: 2.5 degrees) was clipped, else the one deepest vertex: a box
    // resting on its edge across a slope (in a valley of 10 degrees) was held at one end of
    // the edge, the deepest vertex switching ends from step to step, and it crept 18 to
    // 72 mm along the valley in 5 s
    WorldFace inf;
    world_face(P, pa, f, inf);
    count = clip_faces(rf, inf.pts.data(), inf.count, false, -use, 0.0, margin, false, cand.data());
    // the deepest vertex is one of the face's on a box; on a hull the face nearest the
    // normal may miss it: then the one-point pair joins them
    double deepest = -INFINITY;
    for (int i = 0; i < count; ++i) deepest = std::max(deepest, cand[std::size_t(i)].depth);
    if (count > 0 && count < kMaxPolygon) {
      const Vec3 x = internal ? A.support(use) : point_a;
      const double t = glm::dot(use, x - tri[0]);
      if (t > deepest + 1e-12 * (1 + std::abs(t))) {
        const Vec3 y = x - t * use;
        if (over_triangle(tri, y)) cand[std::size_t(count++)] = {x, y, t, kLabelMask};
      }
    }
  } else if (ref == Ref::Triangle && a.type == ShapeType::Capsule) {
    const Segment s = capsule_core(a, pa);
    const Vec3 axis = s.q - s.p;
    const double along = glm::dot(axis, use);
    if (std::abs(along) < 0.05 * glm::length(axis)) {
      // the capsule's side line deepest along the normal (the core moved by the radius at
      // right angles to it: on the surface, where the core moved along a normal it is not
      // perpendicular to would lie inside), clipped to the triangle
      const Vec3 side = glm::normalize(use - (along / glm::dot(axis, axis)) * axis);
      const std::array<ClipPoint, 2> seg{ClipPoint{s.p + radius * side, 0, kLabelMask},
                                         ClipPoint{s.q + radius * side, 1, kLabelMask}};
      count = clip_faces(rf, seg.data(), 2, true, -use, 0.0, margin, false, cand.data());
      // the deeper end, unclipped, becomes the cap's deepest point along the normal (the
      // shape's deepest) where that lies over the triangle
      const std::uint32_t deep = along <= 0 ? 0 : 1;
      const Vec3 x = (deep == 0 ? s.p : s.q) + radius * use;
      const double t = glm::dot(use, x - tri[0]);
      const Vec3 y = x - t * use;
      const bool over = over_triangle(tri, y);
      for (int i = 0; i < count; ++i)
        if (cand[std::size_t(i)].id == deep && over) cand[std::size_t(i)] = {x, y, t, deep};
    }
  }
  if (count <= 0) {
    // one point: the shape's deepest point along the normal onto the triangle's plane (for
    // a snapped normal, the shape's point of the pair)
    if (internal) {
      // the face normal, but the depth along it is the plane's, which is the triangle's only
      // where that point lies over the triangle, or over a triangle of the same plane next to
      // it (a flat grid: the neighbour under the shape gives the same point). Elsewhere the
      // plane runs on where the mesh does not: the terrain had a capsule resting on one
      // triangle 5 cm from another, which met it at a vertex across a convex and a concave
      // edge; the capsule's deepest point along that one's face normal lay 1.5 m off it and
      // 0.55 m below its plane, and the solver pushed the capsule out of the ground it lay on.
      // There the pair's own depth (EPA's, or minus GJK's distance) is reported along the
      // face normal, at the pair's point on the triangle: no translation along any direction
      // separates two convex shapes by less than their penetration depth, nor brings them
      // into contact by less than their distance, so it is never deeper than the truth along
      // that normal, and the plane's depth is never shallower (the plane holds the triangle)
      const double depth0 = glm::dot(point_a - point_b, n);
      const Vec3 x = A.support(use) + radius * use;
      const Vec3 y = x - (glm::dot(rf.normal, x) - rf.offset) * rf.normal;
      // (shallower by more than rounding: a separating-axes pair along the face normal is the
      // plane's already, and its point of the triangle is then the projection, maybe off it)
      const double plane_depth = glm::dot(x - y, use);
      if (depth0 < plane_depth - 1e-9 * (1 + std::abs(plane_depth)) && !over_triangle(tri, y) &&
          !on_coplanar_triangle(M, t, y, face_normal)) {
        point_a = point_b + depth0 * use;
      } else {
        point_a = x, point_b = y;
      }
    } else if (snapped) {
      point_b = point_a - (glm::dot(rf.normal, point_a) - rf.offset) * rf.normal;
    }
    cand[0] = {point_a, point_b, glm::dot(point_a - point_b, use), 0};
    if (cand[0].depth < -margin) return false;
    count = 1;
    flip_ids = true;
  }
  if (flip_ids)
    for (int i = 0; i < count; ++i) cand[std::size_t(i)].id |= kIdFlip;
  reduce(cand.data(), count, use, m);
  m.sub_shape_b = t;
  return m.count > 0;
}

}  // namespace

bool narrow::ball_on_face_alone(const TriangleMesh& M, std::uint32_t t, const Vec3& centre, double world,
                                double radius, double reach, const Vec3& toward, const MeshQueryCache& near) {
  const double scale =
      1 + std::max(world, std::max(std::abs(centre.x), std::max(std::abs(centre.y), std::abs(centre.z))));
  const double tol = 1e-9 * scale;
  // the triangles collide_mesh would test are the cache's: its box holds the ball's query box
  // (padded past the rounding of bounds()), and it kept them all
  const double half = radius + reach + tol;
  const Aabb box{centre - Vec3(half), centre + Vec3(half)};
  if (near.mesh != &M || near.count > std::uint32_t(MeshQueryCache::kCapacity) || !near.box.contains(box)) return false;
  const auto& idx = M.triangles()[t];
  const Vec3 tri[3] = {M.vertices()[idx[0]], M.vertices()[idx[1]], M.vertices()[idx[2]]};
  // the manifold's normal is t's face normal, toward the side away from the centre, and the
  // ball within the reach of t's plane, over t's interior well clear of its edges (feature_edges
  // then says 0: an internal feature, whose normal is the face's and whose point is the
  // projection of the ball's deepest point onto the plane)
  const Vec3 nf = M.normal(t);
  const double along = glm::dot(toward, nf), height = glm::dot(centre - tri[0], nf);
  // (an honest face normal, turned by the bodies' rotations, is within a few ulps of it; an edge
  // normal taken near the face's, kept while the carry holds, would tilt every point made again)
  if (!(std::abs(along) >= 1 - 1e-14) || !((along > 0 ? -height : height) > tol)) return false;
  if (!(std::abs(height) - radius <= reach - tol)) return false;
  double u, v, w;
  weights(tri, centre - height * nf, u, v, w);
  constexpr double kClear = 1e-6;  // a thousand times feature_edges' 1e-9
  if (!(u >= kClear && v >= kClear && w >= kClear)) return false;
  // every other triangle that the query box reaches is beyond the reach (collide_triangle's
  // closed form turns it down: its distance less the radius past the margin)
  const std::span<const Vec3> vs = M.vertices();
  for (std::uint32_t k = 0; k < near.count; ++k) {
    const std::uint32_t o = near.triangles[k];
    if (o == t) continue;
    const auto& j = M.triangles()[o];
    const Vec3 &p = vs[j[0]], &q = vs[j[1]], &r = vs[j[2]];
    if (!Aabb{glm::min(p, glm::min(q, r)), glm::max(p, glm::max(q, r))}.overlaps(box)) continue;
    bool interior;
    const Vec3 d = centre - closest_on_triangle(centre, p, q, r, interior);
    if (!(std::sqrt(glm::dot(d, d)) - radius > reach + tol)) return false;
  }
  return true;
}

int collide_mesh(const ColliderShape& a, const Pose& pose_a, const ColliderShape& mesh, const Pose& pose_mesh,
                 std::span<Manifold> out, const NarrowPhaseSettings& settings, MeshQueryCache* cache,
                 BatchPath path) {
  check_pose(pose_a, "collide_mesh: pose_a");
  check_pose(pose_mesh, "collide_mesh: pose_mesh");
  check_shape(a, "collide_mesh: shape_a");
  const double margin = settings.speculative_margin;
  if (!(margin >= 0 && std::isfinite(margin)))
    require_non_negative(margin, "collide_mesh: NarrowPhaseSettings.speculative_margin");
  return collide_mesh_unchecked(a, pose_a, mesh, pose_mesh, out, settings, cache, path);
}

int narrow::collide_mesh_unchecked(const ColliderShape& a, const Pose& pose_a, const ColliderShape& mesh,
                                   const Pose& pose_mesh, std::span<Manifold> out, const NarrowPhaseSettings& settings,
                                   MeshQueryCache* cache, BatchPath path) {
  if (!a.is_convex()) throw Error("collide_mesh: shape_a must be convex, got a " + std::string(to_string(a.type)));
  if (mesh.type != ShapeType::Mesh || !mesh.mesh) throw Error("collide_mesh: mesh must be a triangle mesh with a body");
  const double margin = settings.speculative_margin;

  // A mesh that is only moved (its rotation (1, 0, 0, 0) to the bit but for the signs of the
  // zeros; the terrain's): every product with the rotation's vector part is a zero, and x + 0
  // = x for x != 0, so a turn by it gives each non-zero coordinate back to the bit (a quaternion
  // product the other's non-zero components) and a zero a zero of either sign. Where nothing
  // that sign could reach is a zero, the turns are left out below: the same bits
  // (BatchPath::Scalar, the plain path, makes every turn)
  const Quat& qm = pose_mesh.rotation;
  const bool moved_only = path != BatchPath::Scalar && qm.w == 1 && qm.x == 0 && qm.y == 0 && qm.z == 0;
  // (x + y with x or y a signed zero where the other is 0: the sum's sign would depend on it)
  auto no_shared_zero = [](const Vec3& x, const Vec3& y) {
    return (x.x != 0 || y.x != 0) && (x.y != 0 || y.y != 0) && (x.z != 0 || y.z != 0);
  };
  const Quat& qa = pose_a.rotation;
  // the shape in the mesh's frame (compose(inverse(pose_mesh), pose_a)), and its bounds there
  // grown by the margin
  const Pose local = moved_only && qa.w != 0 && qa.x != 0 && qa.y != 0 && qa.z != 0 &&
                             no_shared_zero(pose_mesh.position, pose_a.position)
                         ? Pose{-pose_mesh.position + pose_a.position, glm::normalize(qa)}
                         : compose(inverse(pose_mesh), pose_a);
  const TriangleMesh& M = *mesh.mesh;
  const ConvexProxy A = ConvexProxy::of(a, local);
  // the shape's reach along a direction d for the triangles' plane test: a box's, capsule's
  // or sphere's core spans d . centre -+ sum |d . axis_k| (axes scaled by the half extents,
  // a capsule's by its half length) with no support calls; a hull's, its two support points
  const Mat3 r = glm::mat3_cast(local.rotation);
  Vec3 axes[3] = {Vec3(0), Vec3(0), Vec3(0)};
  if (a.type == ShapeType::Box)
    axes[0] = r[0] * a.half_extents.x, axes[1] = r[1] * a.half_extents.y, axes[2] = r[2] * a.half_extents.z;
  else if (a.type == ShapeType::Capsule)
    axes[0] = r[1] * a.half_height;
  const bool hull = a.type == ShapeType::Hull;
  // a box's or hull's polyhedron and its vertices in the mesh frame, for every triangle.
  // (Made in place only for them: a Poly is some 600 bytes of initialised members, zeroed for
  // every call before, half or more of the terrain's a sphere's or capsule's, which no path
  // reads it for: they are handed an empty one made once. A std::optional zeroed it always)
  const bool poly = a.type == ShapeType::Box || a.type == ShapeType::Hull;
  static_assert(std::is_trivially_destructible_v<Poly>);
  static const Poly kNoPoly;
  alignas(Poly) unsigned char poly_room[sizeof(Poly)];
  Poly* const made = poly ? new (poly_room) Poly : nullptr;
  if (made) poly_of(a, *made);
  const Poly& P = made ? *made : kNoPoly;
  PolyAt at;
#if PBA_MESH_LANES_X86
  // the shape's turns and edge axes in AVX2 lanes where the processor has them (AVX-512's
  // eight lanes are not offered: a box has 9 edge axes, a square pyramid 18)
  static const bool avx2 = __builtin_cpu_supports("avx2");
  at.wide = avx2 && path != BatchPath::Scalar;
#else
  (void)path;
#endif
  if (poly && P.vertex_count <= 64) at.set(P, local, r);
  const bool hull_placed = hull && P.vertex_count <= 64;
  // the shape's bounds grown by the margin. A hull's from its vertices placed above: bounds()
  // places them as at.set() does (apply(local, v), turn_avx2 the same bits) and keeps each
  // coordinate's extremes in the same order, so the same box, without placing them twice
  // (bounds() was 0.6 M instructions of a terrain landing step, most of it the pyramids')
  const Aabb box = [&] {
    if (!hull_placed) return bounds(a, local).grown(margin);
    Vec3 lo = at.v[0], hi = lo;
    for (std::uint32_t i = 1; i < P.vertex_count; ++i) lo = glm::min(lo, at.v[i]), hi = glm::max(hi, at.v[i]);
    return Aabb{lo, hi}.grown(margin);
  }();
  int written = 0;
  auto visit = [&](std::uint32_t t) {
    if (written >= int(out.size())) return;
    const auto& idx = M.triangles()[t];
    const Vec3 tri[3] = {M.vertices()[idx[0]], M.vertices()[idx[1]], M.vertices()[idx[2]]};
    // a shape wholly beyond the margin on one side of the triangle's plane is beyond it from
    // the triangle (two support points settle what GJK would: a separating axis); the test
    // is kept a rounding's width short of the margin, so nothing GJK would keep is dropped
    const Vec3 nf = M.normal(t);
    const double plane = glm::dot(nf, tri[0]), slack = margin + 1e-12 * (1 + std::abs(plane));
    double lo, hi;
    if (hull && hull_placed) {
      // the hull's vertices, placed once above: their extremes along nf (two support calls
      // turned the direction into the hull's frame and the vertex back, per triangle; the
      // largest dot of the placed vertices is never below the support vertex's, so nothing
      // the support test kept is dropped)
      lo = INFINITY, hi = -INFINITY;
      for (std::uint32_t i = 0; i < P.vertex_count; ++i) {
        const double x = glm::dot(nf, at.v[i]);
        lo = std::min(lo, x), hi = std::max(hi, x);
      }
    } else if (hull) {
      lo = glm::dot(nf, A.support(-nf)), hi = glm::dot(nf, A.support(nf));
    } else {
      const double c = glm::dot(nf, local.position);
      const double w = std::abs(glm::dot(nf, axes[0])) + std::abs(glm::dot(nf, axes[1])) + std::abs(glm::dot(nf, axes[2]));
      lo = c - w, hi = c + w;
    }
    const double above = lo - A.radius - plane;
    const double below = plane - hi - A.radius;
    if (above > slack || below > slack) return;
    Manifold& m = out[std::size_t(written)];
    if (!collide_triangle(a, local, A, P, poly, at, M, tri, nf, lo, hi, M.edge_flags()[t], margin, t, m)) return;
    // back to the world (apply(pose_mesh, x): its position plus the turned x)
    if (!moved_only || m.normal.x == 0 || m.normal.y == 0 || m.normal.z == 0) m.normal = qm * m.normal;
    for (int i = 0; i < m.count; ++i) {
      Vec3& pa = m.points[std::size_t(i)].point_a;
      Vec3& pb = m.points[std::size_t(i)].point_b;
      pa = moved_only && no_shared_zero(pose_mesh.position, pa) ? pose_mesh.position + pa : apply(pose_mesh, pa);
      pb = moved_only && no_shared_zero(pose_mesh.position, pb) ? pose_mesh.position + pb : apply(pose_mesh, pb);
    }
    ++written;
  };
  if (cache) {
    // a box half the shape's smallest half size larger all round than its query box: its
    // triangles (the tree walked once) serve while the query box stays inside it; its
    // triangles that overlap the query box are those the tree gives, in the same order.
    // More than the cache holds: marked (count kCapacity + 1), the tree serves instead.
    // (Half, not a quarter as before: on the terrain a quarter walked the tree in a quarter
    // of the calls, 121k of 475k over 500 steps, each walk waiting on the tree's nodes;
    // half walks it in 64k and tests 2.50 M cached triangles' bounds instead of 2.06 M, and
    // 1.3k calls find more than 16 triangles. A whole half size walked it in 33k but tested
    // 3.50 M: collide_mesh's share of the run's samples 5.0-5.2% at a quarter, 4.5-4.8% at
    // half, 4.8-5.0% at a whole)
    constexpr std::uint32_t kTooMany = MeshQueryCache::kCapacity + 1;
    if (cache->mesh != &M || !cache->box.contains(box)) {
      const Vec3 half = 0.5 * (box.hi - box.lo);
      cache->mesh = &M;
      cache->box = box.grown(0.5 * std::min(half.x, std::min(half.y, half.z)));
      cache->count = 0;
      M.query(cache->box, [&](std::uint32_t t) {
        if (cache->count < std::uint32_t(MeshQueryCache::kCapacity)) cache->triangles[cache->count++] = t;
        else cache->count = kTooMany;
      });
    }
    if (cache->count != kTooMany) {
      // each by its bounds, from the corners the contact reads anyway (min and max are exact:
      // the tree's bounds)
      const std::span<const Vec3> v = M.vertices();
      // (prefetches, no effect on the results: the triangles' corner indices, then as each
      // triangle is tested the next one's corners and edge flags; loads from the mesh's
      // arrays, at the shape's place in them, were a third of this function's samples on the
      // terrain)
      for (std::uint32_t k = 0; k < cache->count; ++k) __builtin_prefetch(&M.triangles()[cache->triangles[k]]);
      for (std::uint32_t k = 0; k < cache->count; ++k) {
        if (k + 1 < cache->count) {
          const std::uint32_t ahead = cache->triangles[k + 1];
          const auto& next = M.triangles()[ahead];
          __builtin_prefetch(&v[next[0]]), __builtin_prefetch(&v[next[1]]), __builtin_prefetch(&v[next[2]]);
          __builtin_prefetch(&M.edge_flags()[ahead]);
        }
        const auto& idx = M.triangles()[cache->triangles[k]];
        const Vec3 &p = v[idx[0]], &q = v[idx[1]], &r = v[idx[2]];
        if (Aabb{glm::min(p, glm::min(q, r)), glm::max(p, glm::max(q, r))}.overlaps(box)) visit(cache->triangles[k]);
      }
      return written;
    }
  }
  M.query(box, visit);
  return written;
}

}  // namespace pba
