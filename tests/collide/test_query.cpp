// Tests for the world queries (collide/query.h): ray casts (closest, any, all, batched) equal
// a brute-force loop over every collider on 10^5 random rays with and without filters;
// overlaps and distances equal brute force on random scenes; the tree refits; bad input
// throws an Error naming the value; the World's queries see the colliders as the World stands now.
//
// The brute force calls the same per-shape functions (ray_cast, point_distance, GJK) on
// every collider, so closest hits and distances must agree exactly (same bits): any
// difference is a collider the tree or the filter dropped or one the tie rule ordered
// differently. The per-shape functions have their own analytic tests (test_ray.cpp,
// test_point.cpp, test_gjk.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "pba/collide/query.h"
#include "pba/world.h"
#include "query_scene.h"

namespace {

using namespace pba;
using namespace pba::test_support;

#if defined(__SANITIZE_ADDRESS__)
constexpr int kRays = 10000;  // the sanitizers run ~10x slower
constexpr int kScale = 10;     // and a tenth of the other cases
#else
constexpr int kRays = 100000;
constexpr int kScale = 1;
#endif

// the query's filter for query k: none, layers, an owner to skip, a predicate, all of them
struct Filters {
  static constexpr auto pred = [](std::uint32_t i, std::uint32_t) { return i % 3 != 0; };
  QueryFilter pick(int k, std::mt19937_64& rng) const {
    QueryFilter f;
    switch (k % 5) {
      case 0: break;
      case 1: f.layer = 1ull << (rng() % 3), f.mask = (rng() % 2) ? 5 : 3; break;
      case 2: f.ignore_owner = static_cast<std::uint32_t>(rng() % 20); break;
      case 3: f.accept = QueryPredicate::of(pred); break;
      default:
        f.layer = 2;
        f.mask = 6;
        f.ignore_owner = static_cast<std::uint32_t>(rng() % 20);
        f.accept = QueryPredicate::of(pred);
    }
    return f;
  }
};

Ray random_ray(std::mt19937_64& rng, double side) {
  std::uniform_real_distribution<double> pos(-1, side + 1), len(0, 12);
  return {Vec3(pos(rng), pos(rng), pos(rng)), random_unit(rng), len(rng)};
}

TEST(Query, RaysEqualBruteForce) {
  QueryScene s = make_query_scene(400, 20, 1);
  std::mt19937_64 rng(2);
  const Filters filters;
  std::vector<QueryRayHit> all(16), brute;
  std::vector<Ray> batch;
  std::vector<QueryRayHit> batch_hits;
  std::vector<QueryFilter> batch_filter;
  long hits = 0, filtered_out = 0, truncated = 0;
  for (int k = 0; k < kRays; ++k) {
    const Ray ray = random_ray(rng, s.side);
    const QueryFilter f = filters.pick(k, rng);
    // brute force: every accepted collider's own hit, in (distance, index) order
    brute.clear();
    for (std::size_t i = 0; i < s.colliders.size(); ++i) {
      const RayHit h = ray_cast(s.colliders[i].shape, s.colliders[i].end, ray);
      if (!h.hit) continue;
      if (!brute_accepts(s, f, i)) {
        ++filtered_out;
        continue;
      }
      brute.push_back({true, h.distance, h.point, h.normal, h.feature, std::uint32_t(i), s.owners[i]});
    }
    std::stable_sort(brute.begin(), brute.end(),
                     [](const QueryRayHit& a, const QueryRayHit& b) { return a.distance < b.distance; });
    // closest
    const QueryRayHit c = s.world.ray_cast(ray, f);
    ASSERT_EQ(c.hit, !brute.empty()) << "ray " << k;
    if (c.hit) {
      hits++;
      ASSERT_EQ(c.collider, brute[0].collider) << "ray " << k;
      ASSERT_EQ(c.distance, brute[0].distance);
      ASSERT_EQ(c.normal, brute[0].normal);
      ASSERT_EQ(c.owner, s.owners[c.collider]);
    }
    // any: a hit exactly when there is one, and a real one
    const QueryRayHit a = s.world.ray_cast_any(ray, f);
    ASSERT_EQ(a.hit, c.hit);
    if (a.hit) {
      ASSERT_TRUE(brute_accepts(s, f, a.collider));
      ASSERT_EQ(a.distance, ray_cast(s.colliders[a.collider].shape, s.colliders[a.collider].end, ray).distance);
    }
    // all: the same list, truncated to the output's size
    const std::span<QueryRayHit> slots(all.data(), k % 2 ? 16 : 2);
    const std::size_t n = s.world.ray_cast_all(ray, slots, f);
    ASSERT_EQ(n, brute.size());
    truncated += n > slots.size();
    for (std::size_t j = 0; j < std::min(n, slots.size()); ++j) {
      ASSERT_EQ(all[j].collider, brute[j].collider) << "ray " << k << " hit " << j;
      ASSERT_EQ(all[j].distance, brute[j].distance);
    }
    // batched: one filter per batch
    if (k % 5 == 0) {
      batch.push_back(ray);
      batch_hits.push_back(c);
    }
  }
  std::vector<QueryRayHit> out(batch.size());
  const std::size_t count = s.world.ray_cast(batch, out);
  std::size_t expect = 0;
  for (std::size_t j = 0; j < batch.size(); ++j) {
    ASSERT_EQ(out[j].hit, batch_hits[j].hit);
    expect += out[j].hit;
    if (out[j].hit) {
      ASSERT_EQ(out[j].collider, batch_hits[j].collider);
      ASSERT_EQ(out[j].distance, batch_hits[j].distance);
    }
  }
  EXPECT_EQ(count, expect);
  // the test exercised what it claims: hits, filtered colliders, long lists
  EXPECT_GT(hits, kRays / 4);
  EXPECT_GT(filtered_out, kRays / 20);
  EXPECT_GT(truncated, 0);
}

TEST(Query, TiesGoToTheLowerIndex) {
  // two identical boxes: the hit is collider 0 whatever the tree order, and all() lists both
  std::vector<Collider> cs(3, Collider::box(Vec3(0, 0, 5), Vec3(1)));
  cs[0] = Collider::sphere(Vec3(40, 0, 0), 1);
  QueryWorld q;
  q.build(cs);
  const Ray ray{Vec3(0, 0, 0), Vec3(0, 0, 1), 10};
  const QueryRayHit h = q.ray_cast(ray);
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.collider, 1u);
  EXPECT_DOUBLE_EQ(h.distance, 4.0);  // the face z = 4
  QueryRayHit all[2];
  EXPECT_EQ(q.ray_cast_all(ray, all), 2u);
  EXPECT_EQ(all[0].collider, 1u);
  EXPECT_EQ(all[1].collider, 2u);
  // one slot: the first in the order
  EXPECT_EQ(q.ray_cast_all(ray, std::span<QueryRayHit>(all, 1)), 2u);
  EXPECT_EQ(all[0].collider, 1u);
}

TEST(Query, EmptyAndPlaneOnlyWorlds) {
  // no colliders: nothing is hit, found or overlapped
  QueryWorld q;
  const Ray down{Vec3(0, 5, 0), Vec3(0, -1, 0), 10};
  std::uint32_t ids[2];
  EXPECT_FALSE(q.ray_cast(down).hit);
  EXPECT_FALSE(q.sphere_cast(down, 0.5).hit);
  EXPECT_EQ(q.overlap(ColliderShape::sphere(1), {}, ids), 0u);
  EXPECT_FALSE(q.closest_point(Vec3(0.0), 100).found);
  // a ground plane alone (outside the tree): ray 5 m, sphere of 0.5 m 4.5 m, a box resting
  // on it overlaps, a point 2 m above is 2 m away
  q.build(std::vector<Collider>{Collider::plane(Vec3(0, 1, 0), 0)});
  EXPECT_DOUBLE_EQ(q.ray_cast(down).distance, 5.0);
  EXPECT_DOUBLE_EQ(q.sphere_cast(down, 0.5).distance, 4.5);
  EXPECT_EQ(q.overlap(ColliderShape::box(Vec3(0.5)), {Vec3(0, 0.5, 0), Quat(1, 0, 0, 0)}, ids), 1u);
  EXPECT_EQ(q.overlap(ColliderShape::box(Vec3(0.5)), {Vec3(0, 0.51, 0), Quat(1, 0, 0, 0)}, ids), 0u);
  EXPECT_DOUBLE_EQ(q.closest_point(Vec3(0, 2, 0), 100).distance, 2.0);
  const QueryDistance d = q.closest_shape(ColliderShape::sphere(0.5), {Vec3(0, 2, 0), Quat(1, 0, 0, 0)}, 100);
  EXPECT_DOUBLE_EQ(d.distance, 1.5);
  EXPECT_NEAR(glm::length(d.point - Vec3(0, 0, 0)), 0, 1e-15);
  EXPECT_NEAR(glm::length(d.normal - Vec3(0, 1, 0)), 0, 1e-15);
}

TEST(Query, UnnormalisedDirectionsAreNormalised) {
  QueryWorld q;
  q.build(std::vector<Collider>{Collider::sphere(Vec3(0, 0, 10), 1)});
  const QueryRayHit h = q.ray_cast({Vec3(0.0), Vec3(0, 0, 1e-3), 20});
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 9.0, 1e-12);  // along the unit direction
}

TEST(Query, OverlapsEqualBruteForce) {
  QueryScene s = make_query_scene(300, 15, 3);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> pos(-1, s.side + 1), size(0.2, 2.0);
  const Filters filters;
  std::vector<std::uint32_t> out(64), brute;
  long found = 0, spheres_checked = 0;
  for (int k = 0; k < 3000 / kScale; ++k) {
    // a query shape of each convex kind
    ColliderShape qs;
    switch (k % 4) {
      case 0: qs = ColliderShape::sphere(size(rng)); break;
      case 1: qs = ColliderShape::box(Vec3(size(rng), size(rng), size(rng))); break;
      case 2: qs = ColliderShape::capsule(size(rng), 0.5 * size(rng)); break;
      default: qs = ColliderShape::convex(random_hull(rng, 2.0));
    }
    const Pose qp{Vec3(pos(rng), pos(rng), pos(rng)), random_rotation(rng)};
    const QueryFilter f = filters.pick(k / 4, rng);
    const ConvexProxy a = ConvexProxy::of(qs, qp);
    // brute force: every accepted collider at distance 0 (planes: the lowest point on or below)
    brute.clear();
    for (std::size_t i = 0; i < s.colliders.size(); ++i) {
      if (!brute_accepts(s, f, i)) continue;
      const Collider& c = s.colliders[i];
      const bool hit = c.shape.type == ShapeType::Plane ? plane_gap(a, c.shape, c.end) <= 0
                                                         : brute_distance(a, c.shape, c.end) <= 0;
      if (hit) brute.push_back(std::uint32_t(i));
      // a sphere-sphere pair away from touching also agrees with the closed form
      if (qs.type == ShapeType::Sphere && c.shape.type == ShapeType::Sphere) {
        const double gap = glm::length(qp.position - c.end.position) - qs.radius - c.shape.radius;
        if (std::abs(gap) > 1e-9) {
          EXPECT_EQ(hit, gap < 0);
          ++spheres_checked;
        }
      }
    }
    const std::size_t n = s.world.overlap(qs, qp, out, f);
    ASSERT_EQ(n, brute.size()) << "query " << k;
    for (std::size_t j = 0; j < std::min(n, out.size()); ++j) ASSERT_EQ(out[j], brute[j]);
    found += long(n);
    // bounds overlap: brute force over the boxes
    const Aabb box = bounds(qs, qp);
    std::size_t nb = 0;
    for (std::size_t i = 0; i < s.colliders.size(); ++i) nb += brute_accepts(s, f, i) && s.world.bounds(i).overlaps(box);
    ASSERT_EQ(s.world.overlap_bounds(box, out, f), nb);
  }
  EXPECT_GT(found, 1000 / kScale);
  EXPECT_GT(spheres_checked, 100 / kScale);
}

TEST(Query, DistancesEqualBruteForce) {
  QueryScene s = make_query_scene(300, 15, 5);
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> pos(-1, s.side + 1), size(0.2, 1.0), maxd(0, 4);
  const Filters filters;
  long found = 0, inside = 0;
  for (int k = 0; k < 3000 / kScale; ++k) {
    const QueryFilter f = filters.pick(k, rng);
    const double max_distance = maxd(rng);
    // a point: the signed distance of every accepted collider within max_distance
    const Vec3 p(pos(rng), pos(rng), pos(rng));
    bool have = false;
    double best = 0;
    std::uint32_t best_i = 0;
    for (std::size_t i = 0; i < s.colliders.size(); ++i) {
      if (!brute_accepts(s, f, i)) continue;
      const double d = point_distance(s.colliders[i].shape, s.colliders[i].end, p).distance;
      if (d <= max_distance && (!have || d < best)) have = true, best = d, best_i = std::uint32_t(i);
    }
    const QueryDistance qd = s.world.closest_point(p, max_distance, f);
    ASSERT_EQ(qd.found, have) << "point " << k;
    if (have) {
      ASSERT_EQ(qd.collider, best_i);
      ASSERT_EQ(qd.distance, best);
      ++found;
      inside += best < 0;
    }
    // a shape: the GJK distance of every accepted collider (meshes by every triangle)
    const ColliderShape qs = k % 2 ? ColliderShape::box(Vec3(size(rng), size(rng), size(rng)))
                                   : ColliderShape::capsule(size(rng), 0.5 * size(rng));
    const Pose qp{p, random_rotation(rng)};
    const ConvexProxy a = ConvexProxy::of(qs, qp);
    have = false;
    for (std::size_t i = 0; i < s.colliders.size(); ++i) {
      if (!brute_accepts(s, f, i)) continue;
      const double d = brute_distance(a, s.colliders[i].shape, s.colliders[i].end);
      if (d <= max_distance && (!have || d < best)) have = true, best = d, best_i = std::uint32_t(i);
    }
    const QueryDistance qs_d = s.world.closest_shape(qs, qp, max_distance, f);
    ASSERT_EQ(qs_d.found, have) << "shape " << k;
    if (have) {
      ASSERT_EQ(qs_d.collider, best_i) << "shape " << k;
      ASSERT_EQ(qs_d.distance, best);
      // the closest points are that far apart (GJK's tolerance, 1e-10 m, times a few)
      if (best > 0) {
        EXPECT_NEAR(glm::length(qs_d.point - qs_d.query_point), best, 1e-9);
      }
    }
  }
  EXPECT_GT(found, 1000 / kScale);
  EXPECT_GT(inside, 10 / kScale);
}

TEST(Query, RefitFollowsMovedColliders) {
  // build, move every collider by more than the fat margin, build again (a refit): the
  // queries see the new poses exactly as a fresh world does
  QueryScene s = make_query_scene(200, 12, 7);
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> step(-1, 1);
  for (int round = 0; round < 5; ++round) {
    for (std::size_t i = 3; i < s.colliders.size(); ++i) s.colliders[i].end.position += Vec3(step(rng), step(rng), step(rng));
    s.world.build(s.colliders, s.owners, s.filters);
    QueryWorld fresh;
    fresh.build(s.colliders, s.owners, s.filters);
    s.world.tree().validate();
    for (int k = 0; k < 2000; ++k) {
      const Ray ray = random_ray(rng, s.side);
      const QueryRayHit a = s.world.ray_cast(ray), b = fresh.ray_cast(ray);
      ASSERT_EQ(a.hit, b.hit);
      if (a.hit) {
        ASSERT_EQ(a.collider, b.collider);
        ASSERT_EQ(a.distance, b.distance);
      }
    }
  }
}

// the Error's message contains `what`
template <class F>
void expect_error(F&& f, const std::string& what) {
  try {
    f();
    ADD_FAILURE() << "no Error for " << what;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST(Query, BadInputNamesTheValue) {
  QueryWorld q;
  q.build(std::vector<Collider>{Collider::sphere(Vec3(0, 0, 5), 1)});
  const double nan = std::nan(""), inf = INFINITY;
  expect_error([&] { q.ray_cast({Vec3(nan, 0, 0), Vec3(0, 0, 1), 1}); }, "ray_cast(ray).origin");
  expect_error([&] { q.ray_cast({Vec3(0.0), Vec3(0, inf, 1), 1}); }, "ray_cast(ray).direction: must be finite");
  expect_error([&] { q.ray_cast_any({Vec3(0.0), Vec3(0.0), 1}); }, "ray_cast_any(ray).direction: must be non-zero");
  expect_error([&] { q.ray_cast_all({Vec3(0.0), Vec3(0, 0, 1), -1}, {}); }, "ray_cast_all(ray).max_distance");
  expect_error([&] { q.ray_cast({Vec3(0.0), Vec3(0, 0, 1), nan}); }, "max_distance");
  std::vector<Ray> rays(3, Ray{Vec3(0.0), Vec3(0, 0, 1), 1});
  rays[2].direction = Vec3(0.0);
  std::vector<QueryRayHit> hits(3);
  expect_error([&] { q.ray_cast(rays, hits); }, "ray_cast(rays)[2].direction");
  expect_error([&] { q.ray_cast(rays, std::span<QueryRayHit>(hits.data(), 2)); }, "2 hits for 3 rays");
  expect_error([&] { q.sphere_cast({Vec3(0.0), Vec3(0, 0, 1), 1}, 0); }, "sphere_cast(radius): must be finite and > 0");
  expect_error([&] { q.sphere_cast({Vec3(0.0), Vec3(0, 0, 1), 1}, nan); }, "sphere_cast(radius)");
  expect_error([&] { q.sphere_cast({Vec3(0.0), Vec3(0.0), 1}, 1); }, "sphere_cast(path).direction");
  const ColliderShape box = ColliderShape::box(Vec3(1));
  expect_error([&] { q.shape_cast(box, {}, Vec3(0.0), 1); }, "shape_cast(direction): must be non-zero");
  expect_error([&] { q.shape_cast(box, {}, Vec3(1, 0, 0), -2); }, "shape_cast(max_distance)");
  expect_error([&] { q.shape_cast(box, {Vec3(0.0), Quat(2, 0, 0, 0)}, Vec3(1, 0, 0), 1); }, "shape_cast(shape).pose.rotation");
  expect_error([&] { q.shape_cast(ColliderShape::plane(Vec3(0, 1, 0), 0), {}, Vec3(1, 0, 0), 1); },
               "shape_cast(shape).type: must be a sphere, capsule, box or hull, got a plane");
  ColliderShape bad = box;
  bad.half_extents.y = -1;
  std::uint32_t out[4];
  expect_error([&] { q.overlap(bad, {}, out); }, "overlap(shape).half_extents.y");
  expect_error([&] { q.overlap_bounds({Vec3(1), Vec3(0)}, out); }, "overlap_bounds(box)");
  expect_error([&] { q.closest_point(Vec3(0, nan, 0), 1); }, "closest_point(point)");
  expect_error([&] { q.closest_point(Vec3(0.0), -1); }, "closest_point(max_distance)");
  expect_error([&] { q.closest_shape(box, {Vec3(inf), Quat(1, 0, 0, 0)}, 1); }, "closest_shape(shape).pose.position");
  // building: a bad collider by index and field, mismatched spans
  std::vector<Collider> cs(3, Collider::sphere(Vec3(0.0), 1));
  cs[1].shape.radius = -1;
  expect_error([&] { q.build(cs, {}, {}, "level.colliders"); }, "level.colliders[1].radius");
  cs[1] = Collider::sphere(Vec3(0.0), 1);
  cs[2].end.position.x = nan;
  expect_error([&] { q.build(cs); }, "colliders[2].end.position");
  std::vector<std::uint32_t> owners(2);
  expect_error([&] { q.build(std::span<const Collider>(cs.data(), 2), owners, std::vector<CollisionFilter>(1)); },
               "filters has 1 entries for 2 colliders");
  expect_error([&] { q.set_filter(7, {}); }, "collider 7 out of range");
}

// Positions and sizes up to a float's range (3.4e38, the colliders' range everywhere):
// the nearest collider is the brute force's, by formulas scaled to stay in range (the
// queries compare squared distances, so until 2026-12-06 a point beyond ~1.3e154 m found
// nothing or the wrong collider: now refused by name, as are shapes and poses beyond it).
TEST(Query, TheFloatRangeIsHeldAndRefusedBeyondByName) {
  const double edge = 3.4e38, size = 1e37;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Collider> cs;
  for (int i = 0; i < 40; ++i) {
    const Vec3 c = 0.9 * edge * Vec3(u(rng), u(rng), u(rng));
    cs.push_back(i % 2 ? Collider::sphere(c, size) : Collider::box(c, Vec3(size, 0.5 * size, 2 * size)));
  }
  QueryWorld q;
  q.build(cs);
  const ColliderShape probe = ColliderShape::sphere(1e30);
  for (int k = 0; k < 400; ++k) {
    const Vec3 p = edge * Vec3(u(rng), u(rng), u(rng));
    // the signed distance in units of `size` (no square leaves the range)
    double best = INFINITY;
    std::uint32_t best_i = 0;
    for (std::uint32_t i = 0; i < cs.size(); ++i) {
      const Vec3 x = (p - cs[i].end.position) / size;
      const Vec3 h = i % 2 ? Vec3(0.0) : Vec3(1, 0.5, 2);
      const double d = glm::length(x - glm::clamp(x, -h, h)) - (i % 2 ? 1 : 0);
      if (d < best) best = d, best_i = i;
    }
    const QueryDistance d = q.closest_point(p, 1e300);
    ASSERT_TRUE(d.found) << "point " << k;
    EXPECT_EQ(d.collider, best_i) << "point " << k;
    EXPECT_NEAR(d.distance / size, best, 1e-9 * std::max(1.0, best)) << "point " << k;
    const QueryDistance s = q.closest_shape(probe, {p, Quat(1, 0, 0, 0)}, 1e300);
    ASSERT_TRUE(s.found) << "shape " << k;
    EXPECT_EQ(s.collider, best_i) << "shape " << k;
  }
  // beyond: refused, naming the value
  const double far = 1e200;
  const ColliderShape box = ColliderShape::box(Vec3(1));
  std::uint32_t out[4];
  expect_error([&] { q.closest_point(Vec3(far, 0, 0), 1e300); }, "closest_point(point): must fit a float");
  expect_error([&] { q.closest_shape(box, {Vec3(0, far, 0), Quat(1, 0, 0, 0)}, 1); },
               "closest_shape(shape).pose.position: must fit a float");
  expect_error([&] { q.overlap(ColliderShape::sphere(far), {}, out); }, "overlap(shape).radius: must fit a float");
  expect_error([&] { q.shape_cast(box, {Vec3(0, 0, -far), Quat(1, 0, 0, 0)}, Vec3(0, 0, 1), 1); },
               "shape_cast(shape).pose.position: must fit a float");
  expect_error([&] { q.overlap(ColliderShape::box(Vec3(1, far, 1)), {}, out); },
               "overlap(shape).half_extents: must fit a float");
  std::vector<Collider> beyond{Collider::sphere(Vec3(0.0), 1), Collider::sphere(Vec3(1e39, 0, 0), 1)};
  expect_error([&] { q.build(beyond, {}, {}, "level"); }, "level[1].end.position: must fit a float");
  beyond[1] = Collider::sphere(Vec3(0.0), 1e39);
  expect_error([&] { q.build(beyond, {}, {}, "level"); }, "level[1].radius: must fit a float");
  // the range's rim: just past the float's largest, where a float rounds to it, require_float
  // takes a value, and so do the queries (a collider there is built and found)
  const double rim = static_cast<double>(std::numeric_limits<float>::max()) * (1 + 0x1p-30);
  std::vector<Collider> at_rim{Collider::sphere(Vec3(0.0), 1), Collider::sphere(Vec3(rim, 0, 0), 1)};
  q.build(at_rim);
  const QueryDistance r = q.closest_point(Vec3(rim, 0, 0), 1e300);
  ASSERT_TRUE(r.found);
  EXPECT_EQ(r.collider, 1u);
}

TEST(Query, WorldQueriesFollowTheWorldBetweenTicks) {
  // a ground plane and a box entity moved between ticks: the World's queries follow it, at
  // once (until 2026-12-03 they kept the last tick's colliders until the next tick, so a
  // destroyed entity was still hit; test_rigid_world.cpp has the bodies' case)
  World w;
  const EntityId ground = w.create_entity({.name = "ground"});
  w.add_collider(ground, {.shape = ColliderShape::plane(Vec3(0, 1, 0), 0)});
  const EntityId crate = w.create_entity({.name = "crate", .pose = {Vec3(0, 1, 0), Quat(1, 0, 0, 0)}});
  w.add_collider(crate, {.shape = ColliderShape::box(Vec3(0.5))});
  w.step();
  QueryRayHit h = w.queries().ray_cast({Vec3(0, 10, 0), Vec3(0, -1, 0), 20});
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.owner, crate.index);
  EXPECT_NEAR(h.distance, 8.5, 1e-12);  // the crate's top face at y = 1.5
  // the crate moves away: the queries see it where it went, before the next tick too
  w.set_pose(crate, {Vec3(5, 1, 0), Quat(1, 0, 0, 0)});
  EXPECT_EQ(w.queries().ray_cast({Vec3(0, 10, 0), Vec3(0, -1, 0), 20}).owner, ground.index);
  EXPECT_EQ(w.queries().ray_cast({Vec3(5, 10, 0), Vec3(0, -1, 0), 20}).owner, crate.index);
  w.step();
  h = w.queries().ray_cast({Vec3(0, 10, 0), Vec3(0, -1, 0), 20});
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.owner, ground.index);
  EXPECT_NEAR(h.distance, 10.0, 1e-12);
  // the crate's owner can be ignored (a character's own shape)
  const ShapeCastHit s = w.queries().sphere_cast({Vec3(0, 1, 0), Vec3(1, 0, 0), 10}, 0.25, {.ignore_owner = ground.index});
  ASSERT_TRUE(s.hit);
  EXPECT_EQ(s.owner, crate.index);
  EXPECT_NEAR(s.distance, 4.25, 1e-12);  // the sphere meets the face x = 4.5
}

}  // namespace
