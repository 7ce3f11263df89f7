// Long-range attachments (tethers) of the XPBD solver: their projection after each
// substep's constraints, and their anchors and lengths, set when the pins change.
//
// Kim, Chentanez & Mueller 2012, "Long range attachments - a method to simulate
// inextensible clothing in computer games", sec. 4.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define PBA_SOFT_HAVE_AVX2 1
#else
#define PBA_SOFT_HAVE_AVX2 0
#endif

#include "soft_impl.h"

namespace pba {

namespace {

// Long-range attachments (Kim, Chentanez & Mueller 2012, sec. 4, the unilateral
// constraint C_i = |x_i - x_a| - L_i <= 0 with the anchor's inverse mass 0): a particle
// beyond its tether is moved onto the sphere of radius L_i about its anchor a; one
// within it is not touched. Particles without a tether have L = +infinity (kNoTether),
// which no distance exceeds, so the loop has no branch on the tether's presence.
// The anchors' positions come from the columns (ax, ay, az), copied from the pins by
// copy_anchors whenever a pin moves, so the pass streams contiguous memory; a pinned
// particle no tether moves, so the copies stay exact between pin moves.
void project_tethers(std::size_t i0, std::size_t n, float* PBA_SOFT_RESTRICT x, float* PBA_SOFT_RESTRICT y,
                     float* PBA_SOFT_RESTRICT z, const float* PBA_SOFT_RESTRICT anchor_x,
                     const float* PBA_SOFT_RESTRICT anchor_y, const float* PBA_SOFT_RESTRICT anchor_z,
                     const float* PBA_SOFT_RESTRICT len) {
  for (std::size_t i = i0; i < n; ++i) {
    // the offset from the anchor and its length
    const float ax = anchor_x[i], ay = anchor_y[i], az = anchor_z[i];
    const float dx = x[i] - ax, dy = y[i] - ay, dz = z[i] - az;
    const float d2 = dx * dx + dy * dy + dz * dz;
    const float l = len[i];
    // beyond the tether: onto the sphere (selects, not a branch: the loop if-converts;
    // without a tether l is infinite and s too, never selected)
    const bool out = d2 > l * l;
    const float s = l / std::sqrt(d2);
    const float nx = ax + dx * s, ny = ay + dy * s, nz = az + dz * s;
    x[i] = out ? nx : x[i], y[i] = out ? ny : y[i], z[i] = out ? nz : z[i];
  }
}

#if PBA_SOFT_HAVE_AVX2
// project_tethers for particles [0, 8 floor(n / 8)), 8 at a time: the same operations
// in the same order (sqrt and division are correctly rounded in both), so the same bits.
// Returns the particles done.
__attribute__((target("avx2"))) std::size_t project_tethers_avx2(std::size_t n, float* PBA_SOFT_RESTRICT x,
                                                                 float* PBA_SOFT_RESTRICT y, float* PBA_SOFT_RESTRICT z,
                                                                 const float* anchor_x, const float* anchor_y,
                                                                 const float* anchor_z, const float* len) {
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    // the offset from the anchors and its squared length
    const __m256 ax = _mm256_loadu_ps(anchor_x + i), ay = _mm256_loadu_ps(anchor_y + i);
    const __m256 az = _mm256_loadu_ps(anchor_z + i);
    const __m256 xi = _mm256_loadu_ps(x + i), yi = _mm256_loadu_ps(y + i), zi = _mm256_loadu_ps(z + i);
    const __m256 dx = _mm256_sub_ps(xi, ax), dy = _mm256_sub_ps(yi, ay), dz = _mm256_sub_ps(zi, az);
    const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    const __m256 l = _mm256_loadu_ps(len + i);
    // beyond the tether: onto the sphere
    const __m256 out = _mm256_cmp_ps(d2, _mm256_mul_ps(l, l), _CMP_GT_OQ);
    const __m256 sc = _mm256_div_ps(l, _mm256_sqrt_ps(d2));
    _mm256_storeu_ps(x + i, _mm256_blendv_ps(xi, _mm256_add_ps(ax, _mm256_mul_ps(dx, sc)), out));
    _mm256_storeu_ps(y + i, _mm256_blendv_ps(yi, _mm256_add_ps(ay, _mm256_mul_ps(dy, sc)), out));
    _mm256_storeu_ps(z + i, _mm256_blendv_ps(zi, _mm256_add_ps(az, _mm256_mul_ps(dz, sc)), out));
  }
  return i;
}
#endif

// Copies each particle's anchor position (its tether's pin, or itself) into the anchor
// columns: a gather, run only in substeps where a pin has moved.
void copy_anchors(SoftBody::Impl& s) {
  for (std::size_t i = 0; i < s.n; ++i) {
    const std::uint32_t a = s.tether[i];
    s.anchor_x[i] = s.x[a], s.anchor_y[i] = s.y[a], s.anchor_z[i] = s.z[a];
  }
}

}  // namespace

namespace detail {

// every particle onto its tether's sphere (after copying the anchors when a pin moved):
// 8 at a time with AVX2 when `avx2`, the rest one by one, the same bits either way
void project_all_tethers(SoftBody::Impl& s, bool avx2, bool copy) {
  if (copy) copy_anchors(s);
  std::size_t done = 0;
#if PBA_SOFT_HAVE_AVX2
  if (avx2)
    done = project_tethers_avx2(s.n, s.x.data(), s.y.data(), s.z.data(), s.anchor_x.data(), s.anchor_y.data(),
                                s.anchor_z.data(), s.tether_len.data());
#else
  (void)avx2;
#endif
  project_tethers(done, s.n, s.x.data(), s.y.data(), s.z.data(), s.anchor_x.data(), s.anchor_y.data(),
                  s.anchor_z.data(), s.tether_len.data());
}

}  // namespace detail

// ---------------------------------------------------------------------------------------
// tether lengths: a tether may never be shorter than the rest distance to its pin
// measured through the material (the geodesic), or it holds the body short; the straight
// distance is that geodesic only when the straight segment stays within the body

namespace {

// True when the straight segment between any two particles of the rest shape stays in
// the body, so that their straight rest distance is the geodesic between them. Sufficient
// tests: the rest shape is collinear (a rope built straight, taken to be connected along
// its line), or planar with triangles that cover every particle, all face the same way
// and have a boundary that is one loop turning left at every vertex and once round in
// all (a convex polygon: any cloth_grid). Tolerances 1e-4 (of the body's size off the
// line or plane, in radians of a right turn) change a straight distance against the
// geodesic by a relative O(1e-8), inside the tethers' 2^-20 margin.
// Runs once at build (allocates there); O(n + T log T) for T triangles.
bool rest_shape_convex(const SoftBody::Impl& s) {
  const std::size_t n = s.n;
  auto r = [&](std::size_t i) { return Vec3(s.rx[i], s.ry[i], s.rz[i]); };
  if (n < 3) return true;
  // the body's size: the farthest particle from the farthest particle from particle 0
  auto farthest = [&](std::size_t from) {
    std::size_t best = from;
    double d2 = -1;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 e = r(i) - r(from);
      if (glm::dot(e, e) > d2) d2 = glm::dot(e, e), best = i;
    }
    return best;
  };
  const std::size_t p = farthest(0), q = farthest(p);
  const Vec3 o = r(p);
  const double size = glm::length(r(q) - o);
  if (!(size > 0)) return true;
  const double tol = 1e-4 * size;
  // collinear: every particle within tol of the line through p and q
  const Vec3 u = (r(q) - o) / size;
  bool line = true;
  for (std::size_t i = 0; i < n && line; ++i) line = glm::length(glm::cross(r(i) - o, u)) <= tol;
  if (line) return true;
  // planar: every particle within tol of the plane of the triangles' summed normal, and
  // every triangle facing along it (none folded over)
  Vec3 nsum(0.0);
  for (const SoftTriangle& t : s.tris_all) nsum += glm::cross(r(t.b) - r(t.a), r(t.c) - r(t.a));
  if (!(glm::length(nsum) > 0)) return false;
  const Vec3 nrm = nsum / glm::length(nsum);
  for (std::size_t i = 0; i < n; ++i)
    if (std::abs(glm::dot(r(i) - o, nrm)) > tol) return false;
  for (const SoftTriangle& t : s.tris_all)
    if (!(glm::dot(glm::cross(r(t.b) - r(t.a), r(t.c) - r(t.a)), nrm) > 0)) return false;
  // every particle on a triangle (one off them could lie outside the outline)
  std::vector<std::uint8_t> covered(n, 0);
  for (const SoftTriangle& t : s.tris_all) covered[t.a] = covered[t.b] = covered[t.c] = 1;
  if (std::find(covered.begin(), covered.end(), 0) != covered.end()) return false;
  // the boundary: directed triangle edges (interior on their left) whose reverse is in no
  // triangle; each boundary particle must have exactly one outgoing boundary edge
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * s.tris_all.size());
  for (const SoftTriangle& t : s.tris_all)
    for (const auto& [a, b] : {std::pair{t.a, t.b}, std::pair{t.b, t.c}, std::pair{t.c, t.a}})
      edges.push_back(std::uint64_t(a) << 32 | b);
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;  // overlapping triangles
  std::vector<std::uint32_t> next(n, kNoParticle);
  std::size_t boundary = 0;
  std::uint32_t start = kNoParticle;
  for (const std::uint64_t e : edges) {
    const auto a = static_cast<std::uint32_t>(e >> 32), b = static_cast<std::uint32_t>(e);
    if (std::binary_search(edges.begin(), edges.end(), std::uint64_t(b) << 32 | a)) continue;
    if (next[a] != kNoParticle) return false;
    next[a] = b, start = a, ++boundary;
  }
  if (boundary < 3) return false;
  // one loop, turning left (about the normal) at every vertex and 2 pi in all
  double turning = 0;
  std::size_t steps = 0;
  std::uint32_t a = start;
  do {
    const std::uint32_t b = next[a];
    const std::uint32_t c = next[b];
    if (c == kNoParticle || ++steps > boundary) return false;
    const Vec3 e1 = r(b) - r(a), e2 = r(c) - r(b);
    const double sn = glm::dot(glm::cross(e1, e2), nrm), cs = glm::dot(e1, e2);
    if (sn < -1e-4 * glm::length(e1) * glm::length(e2)) return false;
    turning += std::atan2(sn, cs);
    a = b;
  } while (a != start);
  return steps == boundary && std::abs(turning - 2 * kPi) < 1e-3;
}

// Each free particle's nearest pin along the body and the length of that path (m), by
// Dijkstra's algorithm (Dijkstra 1959) from all pins at once over the intact stretch and
// shear constraints weighted by their rest lengths (bend constraints are left out: each
// spans two edges, a shortcut across a fold). Writes geo_dist and tether; a particle no path
// reaches keeps itself. An indexed binary heap in preallocated columns: O(E log n), no
// allocation.
void shortest_paths_from_pins(SoftBody::Impl& s) {
  constexpr std::uint32_t kOff = kNoParticle;  // not in the heap
  double* d = s.geo_dist.data();
  std::uint32_t* heap = s.heap.data();
  std::uint32_t* slot = s.heap_pos.data();
  std::size_t m = 0;
  // sift particle v up from slot k, or down
  auto up = [&](std::size_t k, std::uint32_t v) {
    while (k > 0) {
      const std::size_t parent = (k - 1) / 2;
      if (!(d[v] < d[heap[parent]])) break;
      heap[k] = heap[parent], slot[heap[k]] = static_cast<std::uint32_t>(k), k = parent;
    }
    heap[k] = v, slot[v] = static_cast<std::uint32_t>(k);
  };
  auto down = [&](std::size_t k, std::uint32_t v) {
    for (;;) {
      std::size_t c = 2 * k + 1;
      if (c >= m) break;
      if (c + 1 < m && d[heap[c + 1]] < d[heap[c]]) ++c;
      if (!(d[heap[c]] < d[v])) break;
      heap[k] = heap[c], slot[heap[k]] = static_cast<std::uint32_t>(k), k = c;
    }
    heap[k] = v, slot[v] = static_cast<std::uint32_t>(k);
  };
  // every pin is a source at distance 0, its own anchor
  for (std::size_t i = 0; i < s.n; ++i) {
    d[i] = std::numeric_limits<double>::infinity();
    s.tether[i] = static_cast<std::uint32_t>(i);
    slot[i] = kOff;
  }
  for (const std::uint32_t p : s.pins) d[p] = 0, up(m++, p);
  // settle the nearest particle, relax its edges
  while (m > 0) {
    const std::uint32_t u = heap[0];
    slot[u] = kOff;
    if (--m > 0) down(0, heap[m]);
    for (std::uint32_t k = s.graph_start[u]; k < s.graph_start[u + 1]; ++k) {
      const std::uint32_t c = s.graph_edge[k];
      if (s.broken[c]) continue;
      const std::uint32_t v = s.ca[c] ^ s.cb[c] ^ u;
      const double dv = d[u] + s.rest0[c];
      if (!(dv < d[v])) continue;
      const bool queued = slot[v] != kOff;
      d[v] = dv, s.tether[v] = s.tether[u];
      if (queued) up(slot[v], v);
      else up(m++, v);
    }
  }
}

}  // namespace

// The straight-or-path decision and, for path lengths, the graph and Dijkstra's scratch.
void SoftBody::Impl::init_tethers() {
  tether_straight = rest_shape_convex(*this);
  if (tether_straight) return;
  // constraint indices by particle (CSR), stretch and shear only
  const std::size_t nc = ca.size();
  const auto bend = static_cast<std::uint8_t>(SoftConstraintKind::Bend);
  graph_start.assign(n + 1, 0);
  for (std::size_t c = 0; c < nc; ++c)
    if (kind[c] != bend) ++graph_start[ca[c] + 1], ++graph_start[cb[c] + 1];
  for (std::size_t i = 0; i < n; ++i) graph_start[i + 1] += graph_start[i];
  graph_edge.resize(graph_start[n]);
  std::vector<std::uint32_t> fill(graph_start.begin(), graph_start.end() - 1);
  for (std::uint32_t c = 0; c < nc; ++c)
    if (kind[c] != bend) graph_edge[fill[ca[c]]++] = c, graph_edge[fill[cb[c]]++] = c;
  // Dijkstra's scratch
  geo_dist.assign(n, 0.0), heap.assign(n, 0), heap_pos.assign(n, 0);
}

// Each free particle's anchor and tether length L (Kim et al. 2012, sec. 4), rounded up
// to float with a relative margin of 2^-20 so that a particle exactly at its rest
// distance, whose float distance may round a few ulps long, is not moved. For a convex
// rest shape (init_tethers) the anchor is the pinned particle nearest in a straight line
// (ties to the earliest pin) and L their straight rest distance, exact. Otherwise (a
// folded or curved sheet, a mesh in pieces, any solid) the straight distance may be a
// shortcut through the air that holds the body short, so the anchor is the pin nearest
// along the body's edges and L the length of that path (shortest_paths_from_pins). No
// shape that keeps the edges at their rest lengths puts the particle farther than L from
// its anchor (the triangle inequality along the path), so the tether never holds the
// body short; it is slack by the edge graph's metric error (on a flat grid with both
// diagonals at most sqrt(4 - 2 sqrt 2) - 1 = 8.2%, where a path mixes axis and diagonal
// steps). Run only after pins change; writes preallocated columns. O(particles x pins),
// or O(E log particles) for E edges.
void SoftBody::Impl::update_tethers() {
  tethers_dirty = false;
  if (!tether_straight) {
    shortest_paths_from_pins(*this);
    for (std::size_t i = 0; i < n; ++i) {
      const bool tied = tether[i] != i && !pinned[i];
      if (!tied) tether[i] = static_cast<std::uint32_t>(i);
      tether_len[i] = tied ? static_cast<float>(geo_dist[i] * (1.0 + 0x1p-20)) : detail::kNoTether;
    }
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    // no tether unless a pin is found (pinned particles keep none)
    tether[i] = static_cast<std::uint32_t>(i);
    tether_len[i] = detail::kNoTether;
    if (pinned[i]) continue;
    // the nearest pin in the rest shape
    double best = std::numeric_limits<double>::infinity();
    for (const std::uint32_t p : pins) {
      const double dx = double(rx[i]) - rx[p], dy = double(ry[i]) - ry[p], dz = double(rz[i]) - rz[p];
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (d2 < best) best = d2, tether[i] = p;
    }
    if (tether[i] != i) tether_len[i] = static_cast<float>(std::sqrt(best) * (1.0 + 0x1p-20));
  }
}

}  // namespace pba
