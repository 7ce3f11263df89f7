// World queries with a shape: sphere casts by closed forms (the ray against the target grown
// by the radius; a rounded box by its Voronoi regions, Ericson 2005, "Real-Time Collision
// Detection" 5.5.7), convex casts by conservative advancement on the GJK distance (Mirtich
// 1996; Coumans 2006), overlap tests and distance queries by GJK (van den Bergen 2003).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "pba/collide/narrow_phase.h"
#include "pba/collide/query.h"
#include "query_internal.h"

namespace pba {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// a time of impact on one target: distance along the unit direction, the contact point on
// the target and its normal towards the moving shape
struct Cast {
  bool hit = false;
  double t = 0;
  Vec3 point{0, 0, 0};
  Vec3 normal{0, 0, 0};
};

// --- sphere casts: closed forms -------------------------------------------------------------

// entry distance of the ray o + t d (unit d) into the points within r of the segment a-b
// (a capsule; a ball when a == b), for an origin outside it; -1 for a miss; n: the normal
double ray_rounded_segment(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b, double r, Vec3& n) {
  double best = kInf;
  const Vec3 m = b - a, w = o - a;
  const double l2 = glm::dot(m, m);
  // the side: |w_perp + t d_perp| = r with the axial coordinate inside the segment
  if (l2 > 0) {
    const double md = glm::dot(m, d) / l2, mw = glm::dot(m, w) / l2;
    const Vec3 dp = d - md * m, wp = w - mw * m;
    const double qa = glm::dot(dp, dp), qb = glm::dot(wp, dp), qc = glm::dot(wp, wp) - r * r;
    const double disc = qb * qb - qa * qc;
    if (qa > 0 && disc >= 0) {
      const double t = (-qb - std::sqrt(disc)) / qa;
      const double s = mw + t * md;
      if (t >= 0 && s >= 0 && s <= 1) best = t, n = (wp + t * dp) / r;
    }
  }
  // the end balls, by the perpendicular offset (precise for far origins)
  for (const Vec3& c : {a, b}) {
    const Vec3 oc = o - c;
    const double along = glm::dot(oc, d);
    if (along > 0) continue;
    const Vec3 f = oc - along * d;
    const double disc = r * r - glm::dot(f, f);
    if (disc < 0) continue;
    const double t = -along - std::sqrt(disc);
    if (t >= 0 && t < best) best = t, n = (oc + t * d) / r;
  }
  return best == kInf ? -1 : best;
}

// a sphere of radius r from o along d (local frame of the box of half extents h), up to max_t
Cast sphere_box(const Vec3& o, const Vec3& d, const Vec3& h, double r, double max_t) {
  Cast c;
  // the ray against the box grown by r on every side (slabs)
  double t0 = 0, t1 = max_t;
  for (int i = 0; i < 3; ++i) {
    const double e = h[i] + r;
    if (d[i] == 0) {
      if (std::abs(o[i]) > e) return c;
      continue;
    }
    double a = (-e - o[i]) / d[i], b = (e - o[i]) / d[i];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1) return c;
  }
  // the Voronoi region of the entry point: a face (one axis outside the box), an edge (two)
  // or a corner (three), whose rounded part is a slab, a capsule or three capsules
  const Vec3 p = o + t0 * d;
  const Vec3 sgn(p.x < 0 ? -1 : 1, p.y < 0 ? -1 : 1, p.z < 0 ? -1 : 1);
  int out = 0, axis = 0, inside = 0;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(p[i]) > h[i])
      ++out, axis = i;
    else
      inside = i;
  }
  if (out <= 1) {
    c.hit = true;
    c.t = t0;
    c.normal = Vec3(0.0);
    c.normal[axis] = sgn[axis];
  } else {
    const Vec3 corner = sgn * h;
    double best = kInf;
    Vec3 n(0.0);
    for (int k = 0; k < 3; ++k) {
      // the edges through the corner along the axes the entry point is within
      if (out == 2 && k != inside) continue;
      Vec3 other = corner;
      other[k] = -corner[k];
      Vec3 nk;
      const double t = ray_rounded_segment(o, d, corner, other, r, nk);
      if (t >= 0 && t < best) best = t, n = nk;
    }
    if (!(best <= max_t)) return c;
    c.hit = true;
    c.t = best;
    c.normal = n;
  }
  c.point = o + c.t * d - r * c.normal;
  return c;
}

// a sphere's overlap at its start: the closest point on the target, the normal -d
Cast overlap_at_start(const ColliderShape& s, const Pose& p, const Vec3& o, const Vec3& d) {
  return {true, 0, query::point_distance_unchecked(s, p, o).point, -d};
}

// the sphere of radius r whose centre moves along `path` against a sphere, capsule, box or
// plane: the ray against the target grown by r
Cast sphere_closed_form(const ColliderShape& s, const Pose& p, const Ray& path, double r) {
  const Vec3& o = path.origin;
  const Vec3& d = path.direction;
  if (s.type == ShapeType::Box) {
    // start: the centre within r of the box
    const Vec3 ol = apply_inverse(p, o), dl = glm::conjugate(p.rotation) * d;
    const Vec3 q = glm::clamp(ol, -s.half_extents, s.half_extents);
    if (glm::dot(ol - q, ol - q) <= r * r) return overlap_at_start(s, p, o, d);
    Cast c = sphere_box(ol, dl, s.half_extents, r, path.max_distance);
    if (c.hit) c.point = apply(p, c.point), c.normal = p.rotation * c.normal;
    return c;
  }
  // spheres, capsules and planes stay their own kind when grown
  ColliderShape grown;
  grown.type = s.type;
  grown.radius = s.radius + r;
  grown.half_height = s.half_height;
  if (s.type == ShapeType::Plane) {
    const double len = glm::length(s.normal);
    grown.normal = s.normal / len;
    grown.offset = s.offset / len + r;
  }
  // (a ball about its centre: its rotation plays no part)
  const RayHit h = query::ray_cast_unit(grown, s.type == ShapeType::Sphere ? Pose{p.position, Quat(1, 0, 0, 0)} : p, path);
  if (!h.hit) return {};
  if (h.distance == 0 && h.normal == -d) return overlap_at_start(s, p, o, d);
  return {true, h.distance, h.point - r * h.normal, h.normal};
}

// --- convex casts: conservative advancement ----------------------------------------------------

// the moving core `a` (at its start) translated along d against the convex `b`: advance by
// the GJK distance over the approach speed along the closest points' normal, which cannot
// pass the contact (Mirtich 1996), until the gap is below the tolerance
Cast cast_convex(ConvexProxy a, const Vec3& d, double max_t, const ConvexProxy& b) {
  constexpr int kMaxSteps = 64;
  constexpr double kWellConditioned = 1e-7;  // normals from closer cores are GJK rounding
  const Vec3 start = a.pose.position;
  double t = 0;
  Vec3 normal = -d;  // towards the moving shape
  for (int step = 0; step < kMaxSteps; ++step) {
    a.pose.position = start + t * d;
    const DistanceResult g = gjk_distance(a, b);
    if (!g.cores_overlap && g.core_distance >= kWellConditioned) normal = -g.normal;
    if (g.distance <= QueryWorld::kCastTolerance) {
      // touching: at the start the normal is -d (overlap), else the last well-conditioned one
      if (t == 0) return {true, 0, g.point_b, -d};
      return {true, t, g.point_b, normal};
    }
    const double speed = glm::dot(d, g.normal);
    if (!(speed > 0)) return {};  // moving apart or parallel: convex shapes never meet
    t += g.distance / speed;
    if (t > max_t) return {};
  }
  return {};
}

// the signed gap of a proxy's full shape above the plane shape `s` at p (negative: below):
// its lowest point along the world normal n (the support along -n, rounded)
double plane_gap(const ConvexProxy& a, const ColliderShape& s, const Pose& p, Vec3& n, Vec3& low) {
  const double len = glm::length(s.normal);
  n = p.rotation * (s.normal / len);
  low = a.support(-n) - a.radius * n;
  return glm::dot(n, low) - (s.offset / len + glm::dot(n, p.position));
}

// the local bounds of a world box seen from pose p (its 8 corners)
Aabb local_box(const Pose& p, const Aabb& world) {
  Aabb b{Vec3(kInf), Vec3(-kInf)};
  for (int k = 0; k < 8; ++k) {
    const Vec3 c((k & 1) ? world.hi.x : world.lo.x, (k & 2) ? world.hi.y : world.lo.y,
                 (k & 4) ? world.hi.z : world.lo.z);
    const Vec3 l = apply_inverse(p, c);
    b.lo = glm::min(b.lo, l);
    b.hi = glm::max(b.hi, l);
  }
  return b;
}

// calls f(target proxy) for each convex part of a non-plane shape near the world box `near`:
// the shape itself, a compound's children (recursively), a mesh's triangles in the box
template <class F>
void for_each_part(const ColliderShape& s, const Pose& p, const Aabb& near, F&& f) {
  if (s.type == ShapeType::Compound) {
    for (const CompoundChild& c : s.compound->children) for_each_part(c.shape, compose(p, c.pose), near, f);
    return;
  }
  if (s.type == ShapeType::Mesh) {
    const TriangleMesh& m = *s.mesh;
    m.query(local_box(p, near), [&](std::uint32_t t) {
      const Vec3 tri[3] = {m.vertices()[m.triangles()[t][0]], m.vertices()[m.triangles()[t][1]],
                           m.vertices()[m.triangles()[t][2]]};
      ConvexProxy q;
      q.type = ShapeType::Mesh;
      q.triangle = tri;
      q.pose = p;
      f(q);
    });
    return;
  }
  f(ConvexProxy::of(s, p));
}

// the moving convex `a` against any shape: exact for a plane, advancement for the rest
Cast cast_shape(const ConvexProxy& a, const Aabb& swept, const Vec3& d, double max_t, const ColliderShape& s,
                const Pose& p) {
  if (s.type == ShapeType::Plane) {
    Vec3 n, low;
    const double gap = plane_gap(a, s, p, n, low), speed = -glm::dot(n, d);
    if (gap <= 0) return {true, 0, low - gap * n, -d};
    if (!(speed > 0) || gap > speed * max_t) return {};
    const double t = gap / speed;
    return {true, t, low + t * d, n};
  }
  // the earliest part (the first of equal ones, in the shape's own order)
  Cast best;
  for_each_part(s, p, swept, [&](const ConvexProxy& b) {
    const Cast c = cast_convex(a, d, best.hit ? best.t : max_t, b);
    if (c.hit && (!best.hit || c.t < best.t)) best = c;
  });
  return best;
}

// --- overlap and distance ---------------------------------------------------------------------

bool overlaps_shape(const ConvexProxy& a, const Aabb& abox, const ColliderShape& s, const Pose& p) {
  if (s.type == ShapeType::Plane) {
    Vec3 n, low;
    return plane_gap(a, s, p, n, low) <= 0;
  }
  bool any = false;
  for_each_part(s, p, abox, [&](const ConvexProxy& b) {
    if (!any) any = gjk_distance(a, b).distance <= 0;
  });
  return any;
}

// the nearest part of `s` to `a` (distance and closest points; normal from a to s), among
// the parts near `near`
DistanceResult distance_to_shape(const ConvexProxy& a, const Aabb& near, const ColliderShape& s, const Pose& p) {
  if (s.type == ShapeType::Plane) {
    Vec3 n, low;
    const double gap = plane_gap(a, s, p, n, low);
    DistanceResult r;
    r.distance = std::max(0.0, gap);
    r.point_a = low;
    r.point_b = low - gap * n;
    r.normal = -n;
    return r;
  }
  DistanceResult best;
  best.distance = kInf;
  for_each_part(s, p, near, [&](const ConvexProxy& b) {
    const DistanceResult r = gjk_distance(a, b);
    if (r.distance < best.distance) best = r;
  });
  return best;
}

// true when (d, i) comes before the best so far in the (distance, index) order
bool first(bool have, double d, std::uint32_t i, double best_d, std::uint32_t best_i) {
  return !have || d < best_d || (d == best_d && i < best_i);
}

void check_max(double v, std::string_view where) {
  if (!(std::isfinite(v) && v >= 0)) require_non_negative(v, where);
}

}  // namespace

// --- shape casts -----------------------------------------------------------------------

ShapeCastHit QueryWorld::sphere_cast(const Ray& path_in, double radius, const QueryFilter& filter) const {
  const Ray path = query::checked_ray(path_in, "QueryWorld.sphere_cast(path)");
  if (!(std::isfinite(radius) && radius > 0)) require_positive(radius, "QueryWorld.sphere_cast(radius)");
  ShapeCastHit best;
  ConvexProxy ball;
  ball.type = ShapeType::Sphere;
  ball.radius = radius;
  ball.pose.position = path.origin;
  const Aabb start{path.origin - Vec3(radius), path.origin + Vec3(radius)};
  const Aabb swept =
      start.merged({start.lo + path.max_distance * path.direction, start.hi + path.max_distance * path.direction});
  // each candidate up to the best time so far; closed forms where they exist
  auto test = [&](std::uint32_t i, double max_t) {
    if (!accepts(filter, i)) return max_t;
    const ColliderShape& s = shapes_[i];
    const Ray r{path.origin, path.direction, max_t};
    const Cast c = (s.type == ShapeType::Sphere || s.type == ShapeType::Capsule || s.type == ShapeType::Box ||
                    s.type == ShapeType::Plane)
                       ? sphere_closed_form(s, poses_[i], r, radius)
                       : cast_shape(ball, swept, path.direction, max_t, s, poses_[i]);
    if (c.hit && c.t <= max_t && first(best.hit, c.t, i, best.distance, best.collider))
      best = {true, c.t, 0, c.point, c.normal, i, owners_[i]};
    return best.hit ? best.distance : max_t;
  };
  double max_t = path.max_distance;
  for (std::uint32_t i : unbounded_) max_t = test(i, max_t);
  query::sweep(flat_, root_, path.origin, path.direction, max_t, Vec3(-radius), Vec3(radius), test);
  if (best.hit) best.fraction = path.max_distance > 0 ? best.distance / path.max_distance : 0;
  return best;
}

ShapeCastHit QueryWorld::shape_cast(const ColliderShape& shape, const Pose& start, const Vec3& direction,
                                    double max_distance, const QueryFilter& filter) const {
  query::check_convex(shape, start, "QueryWorld.shape_cast(shape)");
  const Vec3 d = query::unit_direction(direction, "QueryWorld.shape_cast(direction)");
  check_max(max_distance, "QueryWorld.shape_cast(max_distance)");
  if (shape.type == ShapeType::Sphere) return sphere_cast({start.position, d, max_distance}, shape.radius, filter);
  // the moving shape's bounds about its origin, and the whole sweep's
  const ConvexProxy a = ConvexProxy::of(shape, start);
  const Aabb b0 = pba::bounds(shape, start);
  const Aabb swept = b0.merged({b0.lo + max_distance * d, b0.hi + max_distance * d});
  ShapeCastHit best;
  auto test = [&](std::uint32_t i, double max_t) {
    if (!accepts(filter, i)) return max_t;
    const Cast c = cast_shape(a, swept, d, max_t, shapes_[i], poses_[i]);
    if (c.hit && c.t <= max_t && first(best.hit, c.t, i, best.distance, best.collider))
      best = {true, c.t, 0, c.point, c.normal, i, owners_[i]};
    return best.hit ? best.distance : max_t;
  };
  double max_t = max_distance;
  for (std::uint32_t i : unbounded_) max_t = test(i, max_t);
  query::sweep(flat_, root_, start.position, d, max_t, b0.lo - start.position, b0.hi - start.position, test);
  if (best.hit) best.fraction = max_distance > 0 ? best.distance / max_distance : 0;
  return best;
}

// --- overlaps --------------------------------------------------------------------------

std::size_t QueryWorld::overlap(const ColliderShape& shape, const Pose& pose, std::span<std::uint32_t> out,
                                const QueryFilter& filter) const {
  query::check_convex(shape, pose, "QueryWorld.overlap(shape)");
  const ConvexProxy a = ConvexProxy::of(shape, pose);
  const Aabb box = pba::bounds(shape, pose);
  std::size_t total = 0;
  auto less = [](std::uint32_t x, std::uint32_t y) { return x < y; };
  auto test = [&](std::uint32_t i) {
    if (bounds_[i].overlaps(box) && accepts(filter, i) && overlaps_shape(a, box, shapes_[i], poses_[i]))
      query::insert_sorted(out, total++, i, less);
    return true;
  };
  for (std::uint32_t i : unbounded_) test(i);
  query::overlapping(flat_, root_, box, test);
  return total;
}

std::size_t QueryWorld::overlap_bounds(const Aabb& box, std::span<std::uint32_t> out, const QueryFilter& filter) const {
  if (!(is_finite(box.lo) && is_finite(box.hi) && glm::all(glm::lessThanEqual(box.lo, box.hi))))
    require_valid_box(box, "QueryWorld.overlap_bounds(box)");
  std::size_t total = 0;
  auto less = [](std::uint32_t x, std::uint32_t y) { return x < y; };
  auto test = [&](std::uint32_t i) {
    if (bounds_[i].overlaps(box) && accepts(filter, i)) query::insert_sorted(out, total++, i, less);
    return true;
  };
  for (std::uint32_t i : unbounded_) test(i);
  query::overlapping(flat_, root_, box, test);
  return total;
}

// --- distances -------------------------------------------------------------------------

QueryDistance QueryWorld::closest_point(const Vec3& point, double max_distance, const QueryFilter& filter) const {
  if (!fits_float(point)) require_float(point, "QueryWorld.closest_point(point)");
  check_max(max_distance, "QueryWorld.closest_point(max_distance)");
  QueryDistance best;
  const Aabb at{point, point};
  // a box beyond the best distance (or beyond 0 once a collider contains the point) holds
  // nothing nearer: outside a shape its signed distance is at least its bounds' distance
  auto bound2 = [&] {
    const double b = std::max(0.0, best.found ? best.distance : max_distance);
    return b * b;
  };
  auto test = [&](std::uint32_t i) {
    if (query::box_distance2(bounds_[i], at) > bound2() || !accepts(filter, i)) return;
    const PointDistance pd = query::point_distance_unchecked(shapes_[i], poses_[i], point);
    if (pd.distance <= max_distance && first(best.found, pd.distance, i, best.distance, best.collider))
      best = {true, pd.distance, pd.point, point, pd.normal, i, owners_[i]};
  };
  for (std::uint32_t i : unbounded_) test(i);
  query::nearest(flat_, root_, at, bound2, test);
  return best;
}

QueryDistance QueryWorld::closest_shape(const ColliderShape& shape, const Pose& pose, double max_distance,
                                        const QueryFilter& filter) const {
  query::check_convex(shape, pose, "QueryWorld.closest_shape(shape)");
  check_max(max_distance, "QueryWorld.closest_shape(max_distance)");
  const ConvexProxy a = ConvexProxy::of(shape, pose);
  const Aabb box = pba::bounds(shape, pose);
  QueryDistance best;
  auto bound = [&] { return best.found ? best.distance : max_distance; };
  auto bound2 = [&] { return bound() * bound(); };
  auto test = [&](std::uint32_t i) {
    if (query::box_distance2(bounds_[i], box) > bound2() || !accepts(filter, i)) return;
    const DistanceResult r = distance_to_shape(a, box.grown(bound()), shapes_[i], poses_[i]);
    if (r.distance <= max_distance && first(best.found, r.distance, i, best.distance, best.collider))
      best = {true, r.distance, r.point_b, r.point_a, -r.normal, i, owners_[i]};
  };
  for (std::uint32_t i : unbounded_) test(i);
  query::nearest(flat_, root_, box, bound2, test);
  return best;
}

}  // namespace pba
