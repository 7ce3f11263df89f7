// GJK distance between convex cores (Gilbert, Johnson and Keerthi 1988), in the form of
// van den Bergen 2003 ("Collision Detection in Interactive 3D Environments", ch. 4): the
// simplex of support points of the Minkowski difference A - B is reduced each iteration
// to the smallest sub-simplex holding its point closest to the origin (the Voronoi-region
// tests of Ericson 2005, "Real-Time Collision Detection", 5.1), and the run stops when the
// upper bound |v| and lower bound v.w / |v| of the distance meet.
#include <cmath>

#include "narrow_internal.h"

namespace pba {

ConvexProxy ConvexProxy::of(const ColliderShape& s, const Pose& pose) {
  ConvexProxy p;
  p.type = s.type;
  p.pose = pose;
  switch (s.type) {
    case ShapeType::Sphere: p.radius = s.radius; break;
    case ShapeType::Capsule:
      p.radius = s.radius;
      p.half_height = s.half_height;
      break;
    case ShapeType::Box: p.half_extents = s.half_extents; break;
    case ShapeType::Hull:
      if (!s.hull) throw Error("ConvexProxy: hull shape without a hull body");
      p.hull = s.hull.get();
      break;
    default: throw Error("ConvexProxy: a " + std::string(to_string(s.type)) + " is not convex");
  }
  return p;
}

Vec3 ConvexProxy::support(const Vec3& d, std::uint32_t* vertex, std::uint32_t hint) const {
  // a mesh's triangle in the mesh's own frame (collide_mesh's, half of GJK's support calls
  // there): the rotations below are the identity, so the triangle's vertex itself, plus the
  // pose's +0 that turns a -0 coordinate into +0 as apply() does (the same bits)
  if (type == ShapeType::Mesh && pose.rotation.w == 1 && pose.rotation.x == 0 && pose.rotation.y == 0 &&
      pose.rotation.z == 0 && pose.position == Vec3(0)) {
    const double d0 = glm::dot(triangle[0], d), d1 = glm::dot(triangle[1], d), d2 = glm::dot(triangle[2], d);
    const std::uint32_t index = d1 > d0 ? (d2 > d1 ? 2u : 1u) : (d2 > d0 ? 2u : 0u);
    if (vertex) *vertex = index;
    return triangle[index] + Vec3(0.0);
  }
  // direction into the local frame, local support, back to the world
  const Vec3 dl = glm::conjugate(pose.rotation) * d;
  Vec3 local(0.0);
  std::uint32_t index = 0;
  switch (type) {
    case ShapeType::Capsule:
      index = dl.y >= 0 ? 1u : 0u;
      local = Vec3(0, index ? half_height : -half_height, 0);
      break;
    case ShapeType::Box:
      index = (dl.x >= 0 ? 1u : 0u) | (dl.y >= 0 ? 2u : 0u) | (dl.z >= 0 ? 4u : 0u);
      local = Vec3(dl.x >= 0 ? half_extents.x : -half_extents.x, dl.y >= 0 ? half_extents.y : -half_extents.y,
                   dl.z >= 0 ? half_extents.z : -half_extents.z);
      break;
    case ShapeType::Hull:
      index = narrow::hull_support(*hull, dl, hint);
      local = hull->vertices()[index];
      break;
    case ShapeType::Mesh: {
      const double d0 = glm::dot(triangle[0], dl), d1 = glm::dot(triangle[1], dl), d2 = glm::dot(triangle[2], dl);
      index = d1 > d0 ? (d2 > d1 ? 2u : 1u) : (d2 > d0 ? 2u : 0u);
      local = triangle[index];
      break;
    }
    default: break;  // sphere: the centre
  }
  if (vertex) *vertex = index;
  return apply(pose, local);
}

namespace {

// The point of the simplex (with its new vertex) closest to the origin, worked out on the
// points alone: the simplex's vertices of the closest feature and their barycentric weights.
// step() keeps them only when the point is closer than the last (the simplex is not copied
// to be put back, nor a tetrahedron's faces copied to be tried).
struct Closest {
  Vec3 p;            // the point
  int n;             // vertices kept (0: none, every face's distance NaN)
  int keep[4];       // which, in the order kept
  double weight[4];  // their weights
  bool inside;       // the origin inside the tetrahedron (n = 4, p = 0)
};

// the segment (a, b): vertices 0, 1
Closest closest_on_segment(const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = -glm::dot(a, ab);
  const double len2 = glm::dot(ab, ab);
  if (t <= 0 || len2 <= 0) return {a, 1, {0}, {1}, false};
  if (t >= len2) return {b, 1, {1}, {1}, false};
  const double u = t / len2;
  return {a + u * ab, 2, {0, 1}, {1 - u, u}, false};
}

// the triangle (a, b, c): vertices 0, 1, 2 (Ericson 2005, ClosestPtPointTriangle with p = origin)
Closest closest_on_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = -a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return {a, 1, {0}, {1}, false};
  const Vec3 bp = -b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return {b, 1, {1}, {1}, false};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {a + v * ab, 2, {0, 1}, {1 - v, v}, false};
  }
  const Vec3 cp = -c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return {c, 1, {2}, {1}, false};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {a + w * ac, 2, {0, 2}, {1 - w, w}, false};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b + w * (c - b), 2, {1, 2}, {1 - w, w}, false};
  }
  const double denom = 1 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return {a + ab * v + ac * w, 3, {0, 1, 2}, {1 - v - w, v, w}, false};
}

// the tetrahedron (a, b, c, d): the origin inside (the origin's barycentric weights, for
// closest points of touching cores) or the closest of the faces it lies outside of, its
// vertices in the face's order (Ericson 2005, ClosestPtPointTetrahedron)
Closest closest_on_tetrahedron(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 p[4] = {a, b, c, d};
  static constexpr int faces[4][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {1, 3, 2, 0}};
  const double vol = glm::dot(b - a, glm::cross(c - a, d - a));
  const double scale = glm::length(b - a) * glm::length(c - a) * glm::length(d - a);
  const bool flat = std::abs(vol) <= 1e-14 * scale;
  double best = INFINITY;
  // (what is read when no face is closer than INFINITY, every distance NaN: the kept vertices'
  // places and weights past n are never read, so not zeroed)
  Closest out;
  out.p = Vec3(0.0), out.n = 0, out.inside = false;
  bool any = false;
  for (const auto& f : faces) {
    // is the origin on the far side of this face from the fourth vertex?
    const Vec3 p0 = p[f[0]], p1 = p[f[1]], p2 = p[f[2]], p3 = p[f[3]];
    const Vec3 nrm = glm::cross(p1 - p0, p2 - p0);
    const double so = glm::dot(-p0, nrm), sd = glm::dot(p3 - p0, nrm);
    if (!flat && so * sd > 0) continue;
    any = true;
    const Closest r = closest_on_triangle(p0, p1, p2);
    const double d2 = glm::dot(r.p, r.p);
    if (d2 < best) {
      best = d2, out = r;
      for (int i = 0; i < r.n; ++i) out.keep[i] = f[r.keep[i]];
    }
  }
  if (any) return out;
  const double inv = 1 / vol;
  const double wb = glm::dot(-a, glm::cross(c - a, d - a)) * inv;
  const double wc = glm::dot(b - a, glm::cross(-a, d - a)) * inv;
  const double wd = glm::dot(b - a, glm::cross(c - a, -a)) * inv;
  return {Vec3(0.0), 4, {0, 1, 2, 3}, {1 - wb - wc - wd, wb, wc, wd}, true};
}

// ConvexProxy::support()'s cases one kind at a time, for a GJK run made for the pair's kinds
// (GjkStepper::run): each does its case's operations in the same order, so it gives the same
// point and vertex to the bit, but inlined into the run, computing only what its kind reads
// (a capsule reads one coordinate of the turned direction, a sphere none) and keeping the
// world points of the vertices it found (a run meets the same two or three corners again and
// again: turned back to the world once each).

// the world points of vertices 0-7 found in this run (bit i of `have`: vertex i's is in at[i])
struct FoundVertices {
  FoundVertices() {}  // (at[] is written before it is read: not zeroed)
  std::uint32_t have = 0;
  Vec3 at[8];
  template <class Place>
  const Vec3& get(std::uint32_t i, Place place) {
    if (!(have & (1u << i))) at[i] = place(), have |= 1u << i;
    return at[i];
  }
};

struct SphereSupport {
  const ConvexProxy& p;
  FoundVertices found{};
  Vec3 operator()(const Vec3&, std::uint32_t& index, std::uint32_t) {
    index = 0;
    return found.get(0, [&] { return apply(p.pose, Vec3(0.0)); });
  }
};

struct CapsuleSupport {
  const ConvexProxy& p;
  FoundVertices found{};
  Vec3 operator()(const Vec3& d, std::uint32_t& index, std::uint32_t) {
    const Vec3 dl = glm::conjugate(p.pose.rotation) * d;
    index = dl.y >= 0 ? 1u : 0u;
    return found.get(index, [&] { return apply(p.pose, Vec3(0, index ? p.half_height : -p.half_height, 0)); });
  }
};

struct BoxSupport {
  const ConvexProxy& p;
  FoundVertices found{};
  Vec3 operator()(const Vec3& d, std::uint32_t& index, std::uint32_t) {
    const Vec3 dl = glm::conjugate(p.pose.rotation) * d;
    index = (dl.x >= 0 ? 1u : 0u) | (dl.y >= 0 ? 2u : 0u) | (dl.z >= 0 ? 4u : 0u);
    const Vec3& h = p.half_extents;
    return found.get(index, [&] {
      return apply(p.pose, Vec3(dl.x >= 0 ? h.x : -h.x, dl.y >= 0 ? h.y : -h.y, dl.z >= 0 ? h.z : -h.z));
    });
  }
};

struct HullSupport {
  const ConvexProxy& p;
  FoundVertices found{};
  Vec3 operator()(const Vec3& d, std::uint32_t& index, std::uint32_t hint) {
    const Vec3 dl = glm::conjugate(p.pose.rotation) * d;
    index = narrow::hull_support(*p.hull, dl, hint);
    auto place = [&] { return apply(p.pose, p.hull->vertices()[index]); };
    return index < 8 ? found.get(index, place) : place();
  }
};

// a triangle whose pose only moves it, or not even that: support()'s mesh case where the turns
// by the identity leave the direction and the vertex as they are (a turn by (1, 0, 0, 0) gives
// each non-zero coordinate back to the bit, a zero perhaps with the other sign: the three dot
// products then compare alike, and the vertex plus a position without a zero coordinate is
// the turned vertex plus it); `offset` is +0 for the mesh's own frame, which support() adds
// (always inlined: the GjkStepper constructor called it outlined, 3.9 M instructions of calls and
// saves in the terrain's 120 steps)
struct TriangleSupport {
  const Vec3* triangle;
  Vec3 offset;
  [[gnu::always_inline]] Vec3 operator()(const Vec3& d, std::uint32_t& index, std::uint32_t) const {
    const double d0 = glm::dot(triangle[0], d), d1 = glm::dot(triangle[1], d), d2 = glm::dot(triangle[2], d);
    index = d1 > d0 ? (d2 > d1 ? 2u : 1u) : (d2 > d0 ? 2u : 0u);
    return triangle[index] + offset;
  }
};

// any other proxy: support() itself
struct AnySupport {
  const ConvexProxy& p;
  Vec3 operator()(const Vec3& d, std::uint32_t& index, std::uint32_t hint) const { return p.support(d, &index, hint); }
};

// f(support) with the support object for p's kind
template <class F>
void with_support(const ConvexProxy& p, F&& f) {
  switch (p.type) {
    case ShapeType::Sphere: f(SphereSupport{p}); return;
    case ShapeType::Capsule: f(CapsuleSupport{p}); return;
    case ShapeType::Box: f(BoxSupport{p}); return;
    case ShapeType::Hull: f(HullSupport{p}); return;
    case ShapeType::Mesh: {
      const Quat& q = p.pose.rotation;
      const Vec3& x = p.pose.position;
      if (q.w == 1 && q.x == 0 && q.y == 0 && q.z == 0) {
        if (x == Vec3(0)) return f(TriangleSupport{p.triangle, Vec3(0.0)});
        if (x.x != 0 && x.y != 0 && x.z != 0) return f(TriangleSupport{p.triangle, x});
      }
      return f(AnySupport{p});
    }
    default: f(AnySupport{p}); return;
  }
}

}  // namespace

GjkStepper::GjkStepper(const ConvexProxy& a, const ConvexProxy& b) : a_(a), b_(b) {
  // first vertex: the support along the line between the centres
  Vec3 d = a_.pose.position - b_.pose.position;
  if (glm::dot(d, d) == 0) d = Vec3(1, 0, 0);
  SimplexVertex s;  // (every field written below)
  // (each kind's support inlined, as run() has them; the hint 0 is support()'s default)
  with_support(a_, [&](auto&& sa) { s.a = sa(-d, s.index_a, 0); });
  with_support(b_, [&](auto&& sb) { s.b = sb(d, s.index_b, 0); });
  s.w = s.a - s.b;
  s.weight = 1;
  simplex_[0] = s;
  count_ = 1;
  v_ = s.w;
  last_ = s;
  gap_ = INFINITY;
}

bool GjkStepper::step() {
  AnySupport sa{a_}, sb{b_};
  return step_with(sa, sb);
}

template <class SupportA, class SupportB>
bool GjkStepper::step_with(SupportA& support_a, SupportB& support_b) {
  if (done_) return false;
  // the origin on the simplex: the cores touch or overlap
  const double vv = glm::dot(v_, v_);
  if (vv <= 1e-24) {
    overlap_ = true;
    done_ = true;
    gap_ = 0;
    return false;
  }
  if (iterations_ >= kMaxIterations) {
    done_ = true;
    return false;
  }
  ++iterations_;
  // new support point of A - B along -v
  // (the last support vertices start the hill climbs)
  SimplexVertex s;  // (every field written here: not zeroed first)
  s.a = support_a(-v_, s.index_a, last_.index_a);
  s.b = support_b(v_, s.index_b, last_.index_b);
  s.w = s.a - s.b;
  s.weight = 0;
  last_ = s;
  // van den Bergen's bounds: |v| >= distance >= v.w / |v|
  const double vn = std::sqrt(vv);
  gap_ = vn - glm::dot(v_, s.w) / vn;
  if (gap_ <= kTolerance) {
    done_ = true;
    return false;
  }
  // a support point already in the simplex: no progress is possible
  for (int i = 0; i < count_; ++i) {
    if (simplex_[std::size_t(i)].w == s.w) {
      done_ = true;
      return false;
    }
  }
  // add it and reduce: the closest point of the simplex with s, on the points
  simplex_[std::size_t(count_)] = s;
  const Vec3 *w0 = &simplex_[0].w, *w1 = &simplex_[1].w, *w2 = &simplex_[2].w;
  const Closest r = count_ == 1   ? closest_on_segment(*w0, *w1)
                    : count_ == 2 ? closest_on_triangle(*w0, *w1, *w2)
                                  : closest_on_tetrahedron(*w0, *w1, *w2, simplex_[3].w);
  // rounding can stall the descent: keep the simplex as it was and stop
  if (!r.inside && glm::dot(r.p, r.p) >= vv) {
    done_ = true;
    return false;
  }
  // the kept vertices, with their weights: in place where each comes from its own place or
  // after it (a segment's or triangle's), else copied out first (a tetrahedron's face)
  if (r.n == 0) simplex_ = {};  // (every face's distance NaN: an empty, zeroed simplex)
  if (count_ < 3 || r.inside) {
    for (int i = 0; i < r.n; ++i) {
      if (r.keep[i] != i) simplex_[std::size_t(i)] = simplex_[std::size_t(r.keep[i])];
      simplex_[std::size_t(i)].weight = r.weight[i];
    }
  } else {
    SimplexVertex kept[3];
    for (int i = 0; i < r.n; ++i) kept[i] = simplex_[std::size_t(r.keep[i])];
    for (int i = 0; i < r.n; ++i) {
      simplex_[std::size_t(i)] = kept[i];
      simplex_[std::size_t(i)].weight = r.weight[i];
    }
  }
  count_ = r.n;
  if (r.inside) {
    v_ = Vec3(0.0);
    overlap_ = true;
    done_ = true;
    gap_ = 0;
    return false;
  }
  v_ = r.p;
  return true;
}

void GjkStepper::run() {
  with_support(a_, [&](auto&& sa) { with_support(b_, [&](auto&& sb) { while (step_with(sa, sb)) {} }); });
}

void GjkStepper::closest_points(Vec3& a, Vec3& b) const {
  a = Vec3(0.0);
  b = Vec3(0.0);
  for (int i = 0; i < count_; ++i) {
    a += simplex_[std::size_t(i)].weight * simplex_[std::size_t(i)].a;
    b += simplex_[std::size_t(i)].weight * simplex_[std::size_t(i)].b;
  }
}

DistanceResult gjk_distance(const ConvexProxy& a, const ConvexProxy& b) {
  // run to the end
  GjkStepper g(a, b);
  g.run();
  Vec3 ca, cb;
  g.closest_points(ca, cb);
  // (each field named once, in the returns: a result zeroed first, then filled, was 11
  // quadwords of `rep stos` a call)
  if (g.overlap())
    return DistanceResult{.distance = 0,
                          .core_distance = 0,
                          .point_a = ca,
                          .point_b = cb,
                          .normal = Vec3(0, 0, 1),
                          .cores_overlap = true,
                          .iterations = g.iterations()};
  // the rounded shapes: radii along the core normal
  // v = a - b is the simplex's closest point: its length is the distance estimate
  const Vec3 v = g.closest();
  const double dist = glm::length(v);
  const Vec3 normal = dist > 0 ? -v / dist : Vec3(0, 0, 1);
  return DistanceResult{.distance = std::max(0.0, dist - a.radius - b.radius),
                        .core_distance = dist,
                        .point_a = ca + a.radius * normal,
                        .point_b = cb - b.radius * normal,
                        .normal = normal,
                        .cores_overlap = false,
                        .iterations = g.iterations()};
}

}  // namespace pba
