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

// closest point to the origin on the simplex; keeps the vertices of the closest feature
// (in their order) with their barycentric weights, returns the point
Vec3 reduce_segment(std::array<SimplexVertex, 4>& s, int& n) {
  const Vec3 a = s[0].w, b = s[1].w;
  const Vec3 ab = b - a;
  const double t = -glm::dot(a, ab);
  const double len2 = glm::dot(ab, ab);
  if (t <= 0 || len2 <= 0) {
    n = 1;
    s[0].weight = 1;
    return a;
  }
  if (t >= len2) {
    s[0] = s[1];
    n = 1;
    s[0].weight = 1;
    return b;
  }
  const double u = t / len2;
  s[0].weight = 1 - u;
  s[1].weight = u;
  return a + u * ab;
}

// Ericson 2005, ClosestPtPointTriangle with p = origin
Vec3 reduce_triangle(std::array<SimplexVertex, 4>& s, int& n) {
  const SimplexVertex A = s[0], B = s[1], C = s[2];
  const Vec3 a = A.w, b = B.w, c = C.w;
  const Vec3 ab = b - a, ac = c - a, ap = -a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    s[0] = A, s[0].weight = 1, n = 1;
    return a;
  }
  const Vec3 bp = -b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) {
    s[0] = B, s[0].weight = 1, n = 1;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    s[0] = A, s[1] = B, s[0].weight = 1 - v, s[1].weight = v, n = 2;
    return a + v * ab;
  }
  const Vec3 cp = -c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) {
    s[0] = C, s[0].weight = 1, n = 1;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    s[0] = A, s[1] = C, s[0].weight = 1 - w, s[1].weight = w, n = 2;
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    s[0] = B, s[1] = C, s[0].weight = 1 - w, s[1].weight = w, n = 2;
    return b + w * (c - b);
  }
  const double denom = 1 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  s[0].weight = 1 - v - w, s[1].weight = v, s[2].weight = w, n = 3;
  return a + ab * v + ac * w;
}

// the tetrahedron: the origin inside (n = 4, returns 0) or the closest of the faces it
// lies outside of (Ericson 2005, ClosestPtPointTetrahedron)
Vec3 reduce_tetrahedron(std::array<SimplexVertex, 4>& s, int& n, bool& inside) {
  const Vec3 a = s[0].w, b = s[1].w, c = s[2].w, d = s[3].w;
  static constexpr int faces[4][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {1, 3, 2, 0}};
  const double vol = glm::dot(b - a, glm::cross(c - a, d - a));
  const double scale = glm::length(b - a) * glm::length(c - a) * glm::length(d - a);
  const bool flat = std::abs(vol) <= 1e-14 * scale;
  inside = false;
  double best = INFINITY;
  std::array<SimplexVertex, 4> best_s{};
  int best_n = 0;
  Vec3 best_p(0.0);
  bool any = false;
  for (const auto& f : faces) {
    // is the origin on the far side of this face from the fourth vertex?
    const Vec3 p0 = s[std::size_t(f[0])].w, p1 = s[std::size_t(f[1])].w, p2 = s[std::size_t(f[2])].w,
               p3 = s[std::size_t(f[3])].w;
    const Vec3 nrm = glm::cross(p1 - p0, p2 - p0);
    const double so = glm::dot(-p0, nrm), sd = glm::dot(p3 - p0, nrm);
    if (!flat && so * sd > 0) continue;
    any = true;
    std::array<SimplexVertex, 4> t{s[std::size_t(f[0])], s[std::size_t(f[1])], s[std::size_t(f[2])], {}};
    int tn = 3;
    const Vec3 q = reduce_triangle(t, tn);
    const double d2 = glm::dot(q, q);
    if (d2 < best) best = d2, best_s = t, best_n = tn, best_p = q;
  }
  if (!any) {
    inside = true;
    // barycentric weights of the origin (for closest points of touching cores)
    const double inv = 1 / vol;
    const double wb = glm::dot(-a, glm::cross(c - a, d - a)) * inv;
    const double wc = glm::dot(b - a, glm::cross(-a, d - a)) * inv;
    const double wd = glm::dot(b - a, glm::cross(c - a, -a)) * inv;
    s[0].weight = 1 - wb - wc - wd, s[1].weight = wb, s[2].weight = wc, s[3].weight = wd;
    n = 4;
    return Vec3(0.0);
  }
  s = best_s;
  n = best_n;
  return best_p;
}

}  // namespace

GjkStepper::GjkStepper(const ConvexProxy& a, const ConvexProxy& b) : a_(a), b_(b) {
  // first vertex: the support along the line between the centres
  Vec3 d = a_.pose.position - b_.pose.position;
  if (glm::dot(d, d) == 0) d = Vec3(1, 0, 0);
  SimplexVertex s{};
  s.a = a_.support(-d, &s.index_a);
  s.b = b_.support(d, &s.index_b);
  s.w = s.a - s.b;
  s.weight = 1;
  simplex_[0] = s;
  count_ = 1;
  v_ = s.w;
  last_ = s;
  gap_ = INFINITY;
}

bool GjkStepper::step() {
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
  SimplexVertex s{};
  s.a = a_.support(-v_, &s.index_a, last_.index_a);
  s.b = b_.support(v_, &s.index_b, last_.index_b);
  s.w = s.a - s.b;
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
  // add it and reduce (the simplex kept first: its count_ vertices are all it is)
  std::array<SimplexVertex, 4> saved;
  const int saved_n = count_;
  for (int i = 0; i < saved_n; ++i) saved[std::size_t(i)] = simplex_[std::size_t(i)];
  simplex_[std::size_t(count_++)] = s;
  Vec3 v(0.0);
  bool inside = false;
  if (count_ == 2) v = reduce_segment(simplex_, count_);
  else if (count_ == 3) v = reduce_triangle(simplex_, count_);
  else v = reduce_tetrahedron(simplex_, count_, inside);
  if (inside) {
    v_ = Vec3(0.0);
    overlap_ = true;
    done_ = true;
    gap_ = 0;
    return false;
  }
  // rounding can stall the descent: keep the better simplex and stop
  if (glm::dot(v, v) >= vv) {
    for (int i = 0; i < saved_n; ++i) simplex_[std::size_t(i)] = saved[std::size_t(i)];
    count_ = saved_n;
    done_ = true;
    return false;
  }
  v_ = v;
  return true;
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
  while (g.step()) {
  }
  DistanceResult r;
  r.iterations = g.iterations();
  Vec3 ca, cb;
  g.closest_points(ca, cb);
  if (g.overlap()) {
    r.cores_overlap = true;
    r.point_a = ca;
    r.point_b = cb;
    return r;
  }
  // the rounded shapes: radii along the core normal
  // v = a - b is the simplex's closest point: its length is the distance estimate
  const Vec3 v = g.closest();
  const double dist = glm::length(v);
  r.core_distance = dist;
  r.normal = dist > 0 ? -v / dist : Vec3(0, 0, 1);
  r.distance = std::max(0.0, dist - a.radius - b.radius);
  r.point_a = ca + a.radius * r.normal;
  r.point_b = cb - b.radius * r.normal;
  return r;
}

}  // namespace pba
