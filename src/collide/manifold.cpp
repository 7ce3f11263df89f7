// collide(): the pair dispatch, the closed forms (spheres, capsules, sphere-box, capsule-box
// apart, convex vs plane) and the GJK/EPA path with feature clipping along the found normal
// (the way Jolt's ManifoldBetweenTwoFaces builds a manifold from one penetration axis).
#include <cmath>

#include "core/lanes.h"
#include "narrow_internal.h"

namespace pba {

using namespace narrow;

namespace {
// the colliders' range, a float's (|x| <= 3.4e38 m, docs/collision.md): positions and sizes
// within it keep every product the pairs form finite (a fourth power of 3.4e38 is 1.3e154;
// at 1e300 m a box pair's went NaN); the quick checks' bound, a value a little beyond it that
// still rounds to a finite float goes through the full checks, which take it
constexpr double kHuge = 3.4028234663852886e38;  // the largest float
}  // namespace

narrow::Segment narrow::capsule_core(const ColliderShape& s, const Pose& p) {
  const Vec3 u = p.rotation * Vec3(0, s.half_height, 0);
  return {p.position - u, p.position + u};
}

namespace {

// a unit vector perpendicular to u (deterministic)
Vec3 perpendicular(const Vec3& u) {
  const Vec3 ref = std::abs(u.x) < 0.57 ? Vec3(1, 0, 0) : (std::abs(u.y) < 0.57 ? Vec3(0, 1, 0) : Vec3(0, 0, 1));
  return glm::normalize(glm::cross(u, ref));
}

Vec3 closest_on_segment(const Segment& s, const Vec3& x) {
  const Vec3 d = s.q - s.p;
  const double dd = glm::dot(d, d);
  const double t = dd > 0 ? std::clamp(glm::dot(x - s.p, d) / dd, 0.0, 1.0) : 0.0;
  return s.p + t * d;
}

// one point between two core points with radii; `fallback` is the normal when they coincide
void point_pair(const Vec3& ca, double ra, const Vec3& cb, double rb, const Vec3& fallback, double margin,
                std::uint32_t id, Manifold& m) {
  const Vec3 d = cb - ca;
  const double dist = glm::length(d);
  m.count = 0;
  if (dist - ra - rb > margin) return;
  m.normal = dist > 0 ? d / dist : fallback;
  m.points[0] = {ca + ra * m.normal, cb - rb * m.normal, ra + rb - dist, id};
  m.count = 1;
}

void sphere_sphere(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb, double margin,
                   Manifold& m) {
  point_pair(pa.position, a.radius, pb.position, b.radius, Vec3(0, 1, 0), margin, 0, m);
}

void sphere_capsule(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb, double margin,
                    Manifold& m) {
  // the sphere centre against the capsule's core segment
  const Segment s = capsule_core(b, pb);
  const Vec3 c = closest_on_segment(s, pa.position);
  point_pair(pa.position, a.radius, c, b.radius, -perpendicular(pb.rotation * Vec3(0, 1, 0)), margin, 0, m);
}

void capsule_capsule(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb, double margin,
                     Manifold& m) {
  const Segment sa = capsule_core(a, pa), sb = capsule_core(b, pb);
  const Vec3 ua = pa.rotation * Vec3(0, 1, 0), ub = pb.rotation * Vec3(0, 1, 0);
  Vec3 c1, c2;
  closest_segments(sa.p, sa.q, sb.p, sb.q, c1, c2);
  const Vec3 cross = glm::cross(ua, ub);
  Vec3 fallback = glm::dot(cross, cross) > 1e-24 ? glm::normalize(cross) : perpendicular(ua);
  if (glm::dot(fallback, pb.position - pa.position) < 0) fallback = -fallback;
  point_pair(c1, a.radius, c2, b.radius, fallback, margin, 0, m);
  if (m.count == 0) return;
  // parallel axes (within ~0.06 degrees): two points at the ends of the overlap of the
  // segments, so a capsule lying on another does not roll on one point
  constexpr double kParallelSin = 1e-3;
  if (glm::length(cross) > kParallelSin) return;
  const double s0 = glm::dot(sb.p - pa.position, ua), s1 = glm::dot(sb.q - pa.position, ua);
  const double lo = std::max(-a.half_height, std::min(s0, s1)), hi = std::min(a.half_height, std::max(s0, s1));
  if (hi - lo <= 1e-9 * std::max(1.0, a.half_height)) return;
  const Vec3 n = m.normal;
  m.count = 0;
  for (const double s : {lo, hi}) {
    const Vec3 qa = pa.position + s * ua;
    const Vec3 qb = closest_on_segment(sb, qa);
    const Vec3 point_a = qa + a.radius * n, point_b = qb - b.radius * n;
    const double depth = glm::dot(point_a - point_b, n);
    if (depth < -margin) continue;
    const std::uint32_t id = std::uint32_t(m.count + 1);
    m.points[std::size_t(m.count++)] = {point_a, point_b, depth, id};
  }
}

void sphere_box(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb, double margin,
                Manifold& m) {
  // the sphere centre in the box frame, clamped to the box
  m.count = 0;
  const Vec3 h = b.half_extents;
  const Vec3 c = apply_inverse(pb, pa.position);
  const Vec3 q = glm::clamp(c, -h, h);
  const double r = a.radius;
  if (q != c) {
    // outside: the clamped point is the closest
    const Vec3 d = q - c;
    const double dist = glm::length(d);
    if (dist - r > margin) return;
    const Vec3 nl = d / dist;
    m.normal = pb.rotation * nl;
    m.points[0] = {pa.position + r * m.normal, apply(pb, q), r - dist, 0};
    m.count = 1;
    return;
  }
  // inside: out through the nearest face
  int axis = 0;
  double best = h.x - std::abs(c.x);
  for (int k = 1; k < 3; ++k) {
    const double g = h[k] - std::abs(c[k]);
    if (g < best) best = g, axis = k;
  }
  const double sign = c[axis] >= 0 ? 1.0 : -1.0;
  Vec3 nl(0.0), face = c;
  nl[axis] = -sign;
  face[axis] = sign * h[axis];
  m.normal = pb.rotation * nl;
  m.points[0] = {pa.position + r * m.normal, apply(pb, face), r + best, 0};
  m.count = 1;
}

// A box's eight corners against a plane (np, off: its world normal and offset), into `cand`
// from n on in corner order: convex_plane's arithmetic for each corner (the corner turned by
// the quaternion as glm turns a vector, moved to the box, its depth below the plane), two
// corners at a time in the lanes of SSE2 vectors, each lane the same operations in the same
// order as the scalar code does for its corner, so the same bits (the rain's ground made some
// 2,700 box manifolds a step at about 900 instructions each, over half of them the turns).
// `rn`: the core radius times np (a box's core is the box: r = 0).
void box_plane_corners(const Vec3& h, const Pose& pa, const Vec3& np, double off, const Vec3& rn, double margin,
                       Candidate* cand, int& n) {
  using v2d = double __attribute__((vector_size(16)));
  auto all = [](double x) { return v2d{x, x}; };
  const Quat& q = pa.rotation;
  const v2d qx = all(q.x), qy = all(q.y), qz = all(q.z), qw = all(q.w);
  const v2d vx = {-h.x, h.x};
  double pax[8], pay[8], paz[8], pbx[8], pby[8], pbz[8], depth[8];
  for (int k = 0; k < 4; ++k) {
    // corners 2k and 2k + 1: x of both signs, y and z by k's bits (i & 2, i & 4 of corner i)
    const v2d vy = all((k & 1) ? h.y : -h.y), vz = all((k & 2) ? h.z : -h.z);
    // the corner turned as glm turns a vector
    v2d tx, ty, tz;
    detail::lanes::quat_turn(qx, qy, qz, qw, vx, vy, vz, tx, ty, tz);
    // apply(): the position plus the turned corner; then the core's point on the surface
    const v2d ax = (all(pa.position.x) + tx) - all(rn.x), ay = (all(pa.position.y) + ty) - all(rn.y),
              az = (all(pa.position.z) + tz) - all(rn.z);
    // off - dot(np, a), the dot summed as glm sums it: (x + y) + z
    const v2d d = all(off) - ((all(np.x) * ax + all(np.y) * ay) + all(np.z) * az);
    const v2d bx = ax + d * all(np.x), by = ay + d * all(np.y), bz = az + d * all(np.z);
    for (int l = 0; l < 2; ++l) {
      const int i = 2 * k + l;
      pax[i] = ax[l], pay[i] = ay[l], paz[i] = az[l], pbx[i] = bx[l], pby[i] = by[l], pbz[i] = bz[l], depth[i] = d[l];
    }
  }
  for (int i = 0; i < 8; ++i) {
    if (depth[i] < -margin || n >= kMaxPolygon) continue;
    cand[std::size_t(n++)] = {Vec3(pax[i], pay[i], paz[i]), Vec3(pbx[i], pby[i], pbz[i]), depth[i], std::uint32_t(i)};
  }
}

// any convex shape (A) against a plane (B): the core's vertices below plane + margin
void convex_plane(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb, double margin,
                  Manifold& m) {
  const Vec3 np = pb.rotation * b.normal;
  const double off = b.offset + glm::dot(np, pb.position);
  if (a.type == ShapeType::Sphere) {
    // one point: what reduce() makes of the one candidate, without the list
    const Vec3 pa_s = pa.position - a.radius * np;
    const double depth = off - glm::dot(np, pa_s);
    m.normal = -np;
    m.count = 0;
    if (depth < -margin) return;
    m.points[0] = {pa_s, pa_s + depth * np, depth, 0};
    m.count = 1;
    return;
  }
  std::array<Candidate, kMaxPolygon> cand;
  int n = 0;
  double r = 0;
  auto add = [&](const Vec3& core, std::uint32_t id) {
    const Vec3 pa_s = core - r * np;
    const double depth = off - glm::dot(np, pa_s);
    if (depth < -margin || n >= kMaxPolygon) return;
    cand[std::size_t(n++)] = {pa_s, pa_s + depth * np, depth, id};
  };
  switch (a.type) {
    case ShapeType::Capsule: {
      r = a.radius;
      const Segment s = capsule_core(a, pa);
      add(s.p, 0);
      add(s.q, 1);
      break;
    }
    case ShapeType::Box:
      box_plane_corners(a.half_extents, pa, np, off, r * np, margin, cand.data(), n);
      break;
    default: {
      const auto v = a.hull->vertices();
      for (std::uint32_t i = 0; i < v.size(); ++i) add(apply(pa, v[i]), i);
      break;
    }
  }
  reduce(cand.data(), n, -np, m);
}

}  // namespace

void narrow::poly_of(const ColliderShape& s, Poly& p) {
  if (s.type == ShapeType::Box) make_box_poly(s.half_extents, p);
  else make_hull_poly(*s.hull, p);
}

namespace {

// GJK on the cores; EPA when they overlap; then a manifold along the normal
void convex_gjk(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb, double margin,
                Manifold& m) {
  m.count = 0;
  Vec3 n, point_a, point_b;
  if (!contact_normal(ConvexProxy::of(a, pa), ConvexProxy::of(b, pb), margin, n, point_a, point_b)) return;
  manifold_from_normal(a, pa, b, pb, n, point_a, point_b, margin, m);
}

// a ball or capsule (A) against a hull (B): a face of the hull whose plane the core (its
// centre, or both ends of its segment) lies beyond by more than the radius and the margin
// separates them by more than the margin, and GJK's distance, never below a separating
// plane's gap, would find that too: no manifold, without the run. Else GJK (EPA where the
// cores overlap) as convex_gjk. (On the terrain the capsule-pyramid and ball-pyramid pairs
// were most of the body pairs GJK ran for: over its 500 steps 52k of their 134k calls end
// here, and 19k of the 82k GJK runs left find them beyond the margin)
void core_hull(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb, double margin,
               Manifold& m) {
  m.count = 0;
  const Segment s = a.type == ShapeType::Capsule ? capsule_core(a, pa) : Segment{pa.position, pa.position};
  const Vec3 p = apply_inverse(pb, s.p), q = apply_inverse(pb, s.q);  // in the hull's frame
  const double reach = a.radius + margin;
  for (const ConvexHull::Face& f : b.hull->faces())
    if (std::min(glm::dot(f.normal, p), glm::dot(f.normal, q)) - f.offset > reach) return;
  convex_gjk(a, pa, b, pb, margin, m);
}

// a capsule (A) against a box (B): the closest points of the core segment and the box in
// the box's frame in closed form (segment_box_closest: a few dozen operations where GJK took
// three or four iterations), then contact_normal's normal and points and the manifold along
// it; GJK and EPA where the segment meets the box or comes within rounding of it (there the
// normal would be the direction of a difference of nearly equal points)
void capsule_box(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb, double margin,
                 Manifold& m) {
  m.count = 0;
  const Segment s = capsule_core(a, pa);
  const SegmentBoxClosest c =
      segment_box_closest_unchecked(apply_inverse(pb, s.p), apply_inverse(pb, s.q), b.half_extents);
  const Vec3& h = b.half_extents;
  const double touch = 1e-9 * std::max({1.0, h.x, h.y, h.z, a.half_height});
  if (!(c.distance2 > touch * touch)) {
    convex_gjk(a, pa, b, pb, margin, m);
    return;
  }
  const double dist = std::sqrt(c.distance2);
  if (dist - a.radius > margin) return;
  // the normal from the capsule to the box; the points on the two surfaces
  const Vec3 n = pb.rotation * ((c.on_box - c.on_segment) / dist);
  const Vec3 point_a = apply(pb, c.on_segment) + a.radius * n;
  manifold_from_normal(a, pa, b, pb, n, point_a, apply(pb, c.on_box), margin, m);
}

}  // namespace

bool narrow::contact_normal(const ConvexProxy& A, const ConvexProxy& B, double margin, Vec3& n, Vec3& point_a,
                            Vec3& point_b) {
  GjkStepper g(A, B);
  g.run();
  if (!g.overlap()) {
    // apart: the closest points, the radii along their direction
    Vec3 ca, cb;
    g.closest_points(ca, cb);
    const Vec3 v = g.closest();
    const double dist = glm::length(v);
    if (dist - A.radius - B.radius > margin) return false;
    n = -v / dist;
    point_a = ca + A.radius * n;
    point_b = cb - B.radius * n;
    return true;
  }
  // the cores overlap: EPA
  const PenetrationResult p = epa_from_gjk(g);
  if (!p.ok) return false;
  n = p.normal;
  point_a = p.point_a;
  point_b = p.point_b;
  return true;
}

namespace {

// quick checks of collide()'s input: true means check_pose and check_shape would pass (for a
// pose, |q| within 1e-6 of 1 tested on |q|^2 a little inside those bounds; a false answer
// sends the input through the full checks, which decide). Combined with & so a pair costs
// one well-predicted branch, whatever its types
// (a squared length whose length is within 1e-6 of 1, a little inside: a plane's normal too)
inline bool unit_length2(double l2) {
  constexpr double kLo = (1 - 0.9e-6) * (1 - 0.9e-6), kHi = (1 + 0.9e-6) * (1 + 0.9e-6);
  return (l2 >= kLo) & (l2 <= kHi);
}
inline bool pose_looks_valid(const Pose& p) {
  const Quat& q = p.rotation;
  const double q2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  const Vec3& x = p.position;
  return unit_length2(q2) & (std::abs(x.x) <= kHuge) & (std::abs(x.y) <= kHuge) & (std::abs(x.z) <= kHuge);
}
inline bool positive_finite(double x) { return (x > 0) & (x <= kHuge); }
template <ShapeType T>
bool looks_valid(const ColliderShape& s) {
  if constexpr (T == ShapeType::Sphere) return positive_finite(s.radius);
  else if constexpr (T == ShapeType::Capsule)
    return positive_finite(s.radius) & (s.half_height >= 0) & (s.half_height <= kHuge);
  else if constexpr (T == ShapeType::Box)
    return positive_finite(s.half_extents.x) & positive_finite(s.half_extents.y) & positive_finite(s.half_extents.z);
  else if constexpr (T == ShapeType::Hull) return s.hull && !s.hull->vertices().empty();
  else if constexpr (T == ShapeType::Plane) return unit_length2(glm::dot(s.normal, s.normal)) & (std::abs(s.offset) <= kHuge);
  else return false;
}

}  // namespace

void narrow::check_pose(const Pose& p, const char* where) {
  if (pose_looks_valid(p)) return;  // (collide_mesh's every call: the lengths' square roots only when in doubt)
  const double qn = glm::length(p.rotation);
  if (!is_finite(p.position)) require_finite(p.position, std::string(where) + ".position");
  if (!(std::abs(qn - 1) <= 1e-6)) require_unit_quat(p.rotation, std::string(where) + ".rotation");
  if (!fits_float(p.position)) require_float(p.position, std::string(where) + ".position");
}

void narrow::check_shape(const ColliderShape& s, const char* where) {
  // the message strings are built only on failure (collide() must not allocate)
  auto w = [where] { return std::string(where); };
  switch (s.type) {
    case ShapeType::Sphere:
      if (!(s.radius > 0 && std::isfinite(s.radius))) require_positive(s.radius, w() + ".radius");
      if (!fits_float(s.radius)) require_float(s.radius, w() + ".radius");
      break;
    case ShapeType::Capsule:
      if (!(s.radius > 0 && std::isfinite(s.radius))) require_positive(s.radius, w() + ".radius");
      if (!(s.half_height >= 0 && std::isfinite(s.half_height))) require_non_negative(s.half_height, w() + ".half_height");
      if (!fits_float(s.radius)) require_float(s.radius, w() + ".radius");
      if (!fits_float(s.half_height)) require_float(s.half_height, w() + ".half_height");
      break;
    case ShapeType::Box:
      for (int k = 0; k < 3; ++k) {
        if (!(s.half_extents[k] > 0 && std::isfinite(s.half_extents[k])))
          require_positive(s.half_extents[k], w() + ".half_extents[" + std::to_string(k) + "]");
        if (!fits_float(s.half_extents[k])) require_float(s.half_extents[k], w() + ".half_extents[" + std::to_string(k) + "]");
      }
      break;
    case ShapeType::Hull:
      if (!s.hull || s.hull->vertices().empty()) throw Error(w() + ".hull: missing hull body");
      break;
    case ShapeType::Plane:
      if (!is_finite(s.normal) || !std::isfinite(s.offset) || std::abs(glm::length(s.normal) - 1) > 1e-6)
        throw Error(w() + ".normal/offset: plane must have a finite unit normal and offset, got normal " +
                    format_vec3(s.normal) + ", offset " + format_value(s.offset));
      if (!fits_float(s.offset)) require_float(s.offset, w() + ".offset");
      break;
    default: break;
  }
}

namespace {

// --- the pair table -----------------------------------------------------------------------
// One function per ordered pair of shape types, found by indexing a table with the two
// types: a pair costs one indirect call, not a chain of type tests the branch predictor
// cannot learn when pairs of every kind come mixed (a broad phase's pair list). Each entry of
// the checked table checks its two shapes (kUncheckedTable's, for collide_unchecked_into, do
// not), runs the pair's algorithm in canonical order (sphere < capsule < box < hull
// < plane) and flips the manifold back when it swapped them.

using PairFn = void (*)(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb,
                        const NarrowPhaseSettings& settings, NarrowPhaseCache* cache, Manifold& m);
// an algorithm on a canonically ordered pair; `swapped`: A and B are the caller's B and A
using AlgoFn = void (*)(const ColliderShape& A, const Pose& PA, const ColliderShape& B, const Pose& PB,
                        const NarrowPhaseSettings& settings, NarrowPhaseCache* cache, bool swapped, Manifold& m);

template <void (*F)(const ColliderShape&, const Pose&, const ColliderShape&, const Pose&, double, Manifold&)>
void closed(const ColliderShape& A, const Pose& PA, const ColliderShape& B, const Pose& PB,
            const NarrowPhaseSettings& settings, NarrowPhaseCache*, bool, Manifold& m) {
  F(A, PA, B, PB, settings.speculative_margin, m);
}

// box and hull pairs: separating axes (the closed-form box path for two boxes) or GJK/EPA
void polys(const ColliderShape& A, const Pose& PA, const ColliderShape& B, const Pose& PB,
           const NarrowPhaseSettings& settings, NarrowPhaseCache* cache, bool swapped, Manifold& m) {
  const double margin = settings.speculative_margin;
  if (settings.method != ConvexMethod::Sat) {
    convex_gjk(A, PA, B, PB, margin, m);
  } else if (A.type == ShapeType::Box && B.type == ShapeType::Box) {
    collide_boxes_sat(A.half_extents, PA, B.half_extents, PB, margin, cache ? &cache->sat : nullptr, m);
  } else {
    Poly pa, pb;
    poly_of(A, pa);
    poly_of(B, pb);
    // the cache's A and B are the caller's: swap its roles with the pair
    SatCache* c = cache ? &cache->sat : nullptr;
    SatCache local{};
    auto exchange = [](SatCache& k) {
      if (k.kind == SatCache::Kind::FaceA) k.kind = SatCache::Kind::FaceB;
      else if (k.kind == SatCache::Kind::FaceB) k.kind = SatCache::Kind::FaceA;
      std::swap(k.index_a, k.index_b);
    };
    if (c && swapped) {
      local = *c;
      exchange(local);
      c = &local;
    }
    collide_polys_sat(pa, PA, pb, PB, margin, c, m);
    if (cache && swapped) {
      exchange(local);
      cache->sat = local;
    }
  }
}

// (`Checked`: the shapes' quick checks, as collide_into's table has them; collide_unchecked_into's
// table goes without)
template <ShapeType TA, ShapeType TB, AlgoFn F, bool Swap, bool Checked>
void pair_entry(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb,
                const NarrowPhaseSettings& settings, NarrowPhaseCache* cache, Manifold& m) {
  if constexpr (Checked) {
    if (!(looks_valid<TA>(a) & looks_valid<TB>(b))) {
      check_shape(a, "collide: shape_a");
      check_shape(b, "collide: shape_b");
    }
  }
  if constexpr (Swap) {
    F(b, pb, a, pa, settings, cache, true, m);
    flip(m);
  } else {
    F(a, pa, b, pb, settings, cache, false, m);
  }
}

constexpr int kTypes = 7;  // ShapeType's values
struct PairTable {
  PairFn fn[kTypes][kTypes] = {};
};

template <ShapeType TA, ShapeType TB, AlgoFn F, bool Checked>
constexpr void put(PairTable& t) {
  t.fn[int(TA)][int(TB)] = &pair_entry<TA, TB, F, false, Checked>;
  if constexpr (TA != TB) t.fn[int(TB)][int(TA)] = &pair_entry<TB, TA, F, true, Checked>;
}

template <bool Checked>
constexpr PairTable make_pair_table() {
  using T = ShapeType;
  PairTable t{};
  put<T::Sphere, T::Sphere, closed<sphere_sphere>, Checked>(t);
  put<T::Sphere, T::Capsule, closed<sphere_capsule>, Checked>(t);
  put<T::Sphere, T::Box, closed<sphere_box>, Checked>(t);
  put<T::Sphere, T::Hull, closed<core_hull>, Checked>(t);
  put<T::Sphere, T::Plane, closed<convex_plane>, Checked>(t);
  put<T::Capsule, T::Capsule, closed<capsule_capsule>, Checked>(t);
  put<T::Capsule, T::Box, closed<capsule_box>, Checked>(t);
  put<T::Capsule, T::Hull, closed<core_hull>, Checked>(t);
  put<T::Capsule, T::Plane, closed<convex_plane>, Checked>(t);
  put<T::Box, T::Box, polys, Checked>(t);
  put<T::Box, T::Hull, polys, Checked>(t);
  put<T::Box, T::Plane, closed<convex_plane>, Checked>(t);
  put<T::Hull, T::Hull, polys, Checked>(t);
  put<T::Hull, T::Plane, closed<convex_plane>, Checked>(t);
  return t;
}
constexpr PairTable kPairTable = make_pair_table<true>();
constexpr PairTable kUncheckedTable = make_pair_table<false>();

}  // namespace

void narrow::manifold_from_normal(const ColliderShape& sa, const Pose& pa, const ColliderShape& sb, const Pose& pb,
                                  const Vec3& n, const Vec3& point_a, const Vec3& point_b, double margin,
                                  Manifold& m) {
  m.normal = n;
  m.count = 0;
  // a face is a contact face when the normal is its normal (GJK and EPA return a face
  // normal of A - B to rounding; an edge-pair normal a little off a face would make the
  // face's clipped points deeper than the contact); a capsule axis within ~3 degrees of
  // perpendicular is a contact segment
  constexpr double kFaceCos = 1 - 1e-9, kSegmentSin = 0.05;
  const bool poly_a = sa.type == ShapeType::Box || sa.type == ShapeType::Hull;
  const bool poly_b = sb.type == ShapeType::Box || sb.type == ShapeType::Hull;
  Poly A, B;
  double da = -1, db = -1;
  std::uint32_t fa = 0, fb = 0;
  if (poly_a) poly_of(sa, A), fa = most_aligned_face(A, pa.rotation, n, &da);
  if (poly_b) poly_of(sb, B), fb = most_aligned_face(B, pb.rotation, -n, &db);
  const bool seg_a = sa.type == ShapeType::Capsule && std::abs(glm::dot(pa.rotation * Vec3(0, 1, 0), n)) < kSegmentSin;
  const bool seg_b = sb.type == ShapeType::Capsule && std::abs(glm::dot(pb.rotation * Vec3(0, 1, 0), n)) < kSegmentSin;

  std::array<Candidate, kMaxPolygon> cand;
  int count = -1;
  bool ref_a = false;
  WorldFace rf, inf;
  if (poly_a && poly_b && std::max(da, db) >= kFaceCos) {
    // two faces: the better aligned is the reference (A's on a tie)
    ref_a = da >= db;
    const Poly& inc = ref_a ? B : A;
    const Pose& pinc = ref_a ? pb : pa;
    world_face(ref_a ? A : B, ref_a ? pa : pb, ref_a ? fa : fb, rf);
    world_face(inc, pinc, incident_face(inc, pinc.rotation, rf.normal), inf);
    count = clip_faces(rf, inf.pts.data(), inf.count, false, ref_a ? n : -n, 0.0, margin, ref_a, cand.data());
  } else if ((poly_a && seg_b && da >= kFaceCos) || (poly_b && seg_a && db >= kFaceCos)) {
    // a face and a capsule's segment: clip the segment by the face's side planes
    ref_a = poly_a;
    const ColliderShape& cap = ref_a ? sb : sa;
    const Segment s = capsule_core(cap, ref_a ? pb : pa);
    world_face(ref_a ? A : B, ref_a ? pa : pb, ref_a ? fa : fb, rf);
    std::array<ClipPoint, 2> seg{ClipPoint{s.p, 0, kLabelMask}, ClipPoint{s.q, 1, kLabelMask}};
    count = clip_faces(rf, seg.data(), 2, true, ref_a ? n : -n, cap.radius, margin, ref_a, cand.data());
  }
  if (count <= 0) {
    // one point: the pair the normal came from
    m.points[0] = {point_a, point_b, glm::dot(point_a - point_b, n), 0};
    m.count = m.points[0].depth >= -margin ? 1 : 0;
    return;
  }
  if (!ref_a)
    for (int i = 0; i < count; ++i) cand[std::size_t(i)].id |= kIdFlip;
  reduce(cand.data(), count, n, m);
}

Manifold collide(const ColliderShape& a, const Pose& pose_a, const ColliderShape& b, const Pose& pose_b,
                 const NarrowPhaseSettings& settings, NarrowPhaseCache* cache) {
  Manifold m;
  collide_into(a, pose_a, b, pose_b, settings, cache, m);
  return m;
}

void narrow::collide_into(const ColliderShape& a, const Pose& pose_a, const ColliderShape& b, const Pose& pose_b,
                          const NarrowPhaseSettings& settings, NarrowPhaseCache* cache, Manifold& m) {
  // bad input is reported before any geometry runs: quick tests first (this is every pair's
  // fixed cost), the full checks in order (poses, shapes, margin, then the pair) when one fails
  const double margin = settings.speculative_margin;
  const unsigned ta = unsigned(a.type), tb = unsigned(b.type);
  const PairFn fn = (ta < unsigned(kTypes)) & (tb < unsigned(kTypes)) ? kPairTable.fn[ta][tb] : nullptr;
  if (!(pose_looks_valid(pose_a) & pose_looks_valid(pose_b) & (margin >= 0) & (margin <= kHuge)) || !fn) {
    check_pose(pose_a, "collide: pose_a");
    check_pose(pose_b, "collide: pose_b");
    check_shape(a, "collide: shape_a");
    check_shape(b, "collide: shape_b");
    if (!(margin >= 0 && std::isfinite(margin)))
      require_non_negative(margin, "collide: NarrowPhaseSettings.speculative_margin");
    if (!fn)
      throw Error("collide: no narrow phase for the pair " + std::string(to_string(a.type)) + "-" +
                  std::string(to_string(b.type)) + " (meshes and compounds are traversed by their callers)");
  }
  m.sub_shape_b = 0;
  fn(a, pose_a, b, pose_b, settings, cache, m);
}

void narrow::collide_unchecked_into(const ColliderShape& a, const Pose& pose_a, const ColliderShape& b,
                                    const Pose& pose_b, const NarrowPhaseSettings& settings, NarrowPhaseCache* cache,
                                    Manifold& m) {
  // (a pair of types with no narrow phase, a mesh or a compound, goes to collide_into, which throws)
  const PairFn fn = kUncheckedTable.fn[unsigned(a.type)][unsigned(b.type)];
  if (!fn) return collide_into(a, pose_a, b, pose_b, settings, cache, m);
  m.sub_shape_b = 0;
  fn(a, pose_a, b, pose_b, settings, cache, m);
}


void collide_batch(std::span<const PairQuery> pairs, std::span<Manifold> out, ConvexMethod method, BatchPath path) {
  if (out.size() < pairs.size())
    throw Error("collide_batch: out holds " + std::to_string(out.size()) + " manifolds for " +
                std::to_string(pairs.size()) + " pairs");
  // box-box pairs wait in groups of kGroup for the lanes; every other pair runs collide()
  constexpr int kGroup = 32;
  const PairQuery* group[kGroup];
  Manifold* group_out[kGroup];
  int waiting = 0;
  const bool sat = method == ConvexMethod::Sat;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const PairQuery& p = pairs[i];
    if (!p.a || !p.b) throw Error("collide_batch: pairs[" + std::to_string(i) + "] has a null shape");
    // a pair that is not two boxes takes collide(); the lanes make collide()'s quick checks
    // of a box pair's input (one that fails them takes collide() too, which throws for bad input)
    if (!(sat & (p.a->type == ShapeType::Box) & (p.b->type == ShapeType::Box))) {
      const NarrowPhaseSettings settings{.speculative_margin = p.margin, .method = method};
      out[i] = collide(*p.a, p.pose_a, *p.b, p.pose_b, settings, p.cache);
      continue;
    }
    group[waiting] = &p;
    group_out[waiting] = &out[i];
    if (++waiting == kGroup) {
      collide_boxes_sat_batch(group, group_out, waiting, path);
      waiting = 0;
    }
  }
  if (waiting > 0) collide_boxes_sat_batch(group, group_out, waiting, path);
}

}  // namespace pba
