// Convex shapes against triangle meshes: no ghost contacts on the internal edges of a flat
// grid, the same contact as against a plane, a convex (flagged) edge keeping its own normal.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "error_of.h"
#include "pba/collide/narrow_phase.h"

namespace {

using namespace pba;

// an n x n grid of square cells of side `cell` (m) centred on the origin, its height
// amplitude * sin(fi * i) * cos(fj * j) at vertex (i, j), two triangles per cell wound so
// the normals point up
ColliderShape bumpy_grid(int n, double amplitude, double fi, double fj, double cell = 0.5) {
  std::vector<Vec3> v;
  std::vector<std::array<std::uint32_t, 3>> t;
  const double half = 0.5 * cell * n;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      v.push_back({cell * i - half, amplitude * std::sin(fi * i) * std::cos(fj * j), cell * j - half});
  auto id = [&](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      t.push_back({id(i, j), id(i, j + 1), id(i + 1, j)});
      t.push_back({id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)});
    }
  return ColliderShape::triangles(TriangleMesh::build(v, t, "grid"));
}

// a flat n x n grid of 1 m cells at y = 0 over [-n/2, n/2]^2; every edge inside is flat
// (flags clear)
ColliderShape flat_grid(int n) { return bumpy_grid(n, 0, 0, 0, 1); }

// One triangle, as a one-triangle mesh (its edges are boundaries: no normal is snapped)
// and as GJK's proxy of it. Not copyable: the proxy points into v.
struct OneTriangle {
  const std::vector<Vec3> v = {{-0.7, 0.1, -0.5}, {0.9, -0.2, -0.3}, {0.1, 0.3, 0.8}};
  const std::vector<std::array<std::uint32_t, 3>> t = {{0, 1, 2}};
  const ColliderShape mesh = ColliderShape::triangles(TriangleMesh::build(v, t, "one"));
  ConvexProxy proxy;
  OneTriangle() {
    proxy.type = ShapeType::Mesh;
    proxy.triangle = v.data();
  }
  OneTriangle(const OneTriangle&) = delete;
  OneTriangle& operator=(const OneTriangle&) = delete;
};

// a square pyramid of base 1 m and height 0.6 m, its origin at the middle of its base
ColliderShape pyramid_hull() {
  const Vec3 apex[5] = {{0, 0.6, 0}, {0.5, 0, 0}, {-0.5, 0, 0}, {0, 0, 0.5}, {0, 0, -0.5}};
  return ColliderShape::convex(ConvexHull::build(apex, "pyramid"));
}

// The reference contact of a convex shape and the triangle: EPA's depth and normal when the
// cores overlap, else GJK's (depth = the core radius minus the cores' distance); false when
// EPA fails. (The proxy's radius, not the shape's: ColliderShape::radius is only a sphere's
// or a capsule's, and a box keeps its default there.)
bool reference_contact(const ConvexProxy& A, const ConvexProxy& B, double& depth, Vec3& normal) {
  const DistanceResult d = gjk_distance(A, B);
  depth = d.cores_overlap ? 0 : A.radius - d.core_distance;
  normal = d.normal;
  if (!d.cores_overlap) return true;
  const PenetrationResult e = epa_penetration(A, B);
  depth = e.depth, normal = e.normal;
  return e.ok;
}

TEST(Mesh, GridHasUpNormalsAndFlatInternalEdges) {
  const ColliderShape g = flat_grid(4);
  for (std::uint32_t k = 0; k < g.mesh->triangles().size(); ++k) EXPECT_NEAR(g.mesh->normal(k).y, 1.0, 1e-15);
}

// collide_mesh's poses take the quick check first: a rotation 2e-6 off unit length or a
// non-finite position still fails and is named
TEST(Mesh, BadPosesThrowNamingTheValue) {
  const ColliderShape grid = flat_grid(4);
  const ColliderShape box = ColliderShape::box(Vec3(0.5));
  std::array<Manifold, 16> out;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  using test_support::error_of;
  EXPECT_NE(error_of([&] { collide_mesh(box, {Vec3(0, 0.49, 0), Quat(1 + 2e-6, 0, 0, 0)}, grid, {}, out); })
                .find("collide_mesh: pose_a.rotation"),
            std::string::npos);
  EXPECT_NE(error_of([&] { collide_mesh(box, {Vec3(nan, 0.49, 0), Quat(1, 0, 0, 0)}, grid, {}, out); })
                .find("collide_mesh: pose_a.position"),
            std::string::npos);
  EXPECT_NE(error_of([&] { collide_mesh(box, {Vec3(0, 0.49, 0), Quat(1, 0, 0, 0)}, grid, {Vec3(0), Quat(0.5, 0, 0, 0)}, out); })
                .find("collide_mesh: pose_mesh.rotation"),
            std::string::npos);
  EXPECT_GT(collide_mesh(box, {Vec3(0, 0.49, 0), Quat(1 + 1e-7, 0, 0, 0)}, grid, {}, out), 0);
}

TEST(Mesh, BoxSlidingOverInternalEdgesHasNoGhostContacts) {
  // a 1 m box 1 cm deep in the grid, slid across the internal edges x = 0 and the
  // diagonals: every manifold's normal is the face normal, every point 1 cm deep, as on
  // a plane; a ghost contact would show as a tilted normal or a depth of the sliver
  const ColliderShape grid = flat_grid(4);
  const ColliderShape box = ColliderShape::box(Vec3(0.5));
  std::array<Manifold, 16> out;
  for (int k = 0; k <= 40; ++k) {
    const double x = -0.6 + 0.03 * k;  // crosses x = 0, with slivers of 5 mm and less
    const Pose p{Vec3(x + 0.005, 0.49, 0.013), Quat(1, 0, 0, 0)};
    const int n = collide_mesh(box, p, grid, {}, out);
    ASSERT_GT(n, 0);
    int points = 0;
    for (int m = 0; m < n; ++m) {
      EXPECT_NEAR(glm::length(out[std::size_t(m)].normal - Vec3(0, -1, 0)), 0.0, 1e-12) << "x " << x;
      for (int i = 0; i < out[std::size_t(m)].count; ++i) {
        EXPECT_NEAR(out[std::size_t(m)].points[std::size_t(i)].depth, 0.01, 1e-12) << "x " << x;
        ++points;
      }
    }
    EXPECT_GE(points, 4);
  }
}

TEST(Mesh, SphereAndCapsuleOnTheGridMatchThePlane) {
  const ColliderShape grid = flat_grid(4);
  const ColliderShape ground = ColliderShape::plane(Vec3(0, 1, 0), 0);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  std::array<Manifold, 16> out;
  for (int k = 0; k < 100; ++k) {
    const Pose ps{Vec3(u(rng), 0.27, u(rng)), Quat(1, 0, 0, 0)};
    const ColliderShape s = ColliderShape::sphere(0.3);
    const int n = collide_mesh(s, ps, grid, {}, out);
    const Manifold ref = collide(s, ps, ground, {});
    ASSERT_EQ(ref.count, 1);
    ASSERT_GE(n, 1);
    for (int m = 0; m < n; ++m) {
      EXPECT_NEAR(glm::length(out[std::size_t(m)].normal - ref.normal), 0.0, 1e-12);
      EXPECT_NEAR(out[std::size_t(m)].points[0].depth, ref.points[0].depth, 1e-12);
    }
    // a lying capsule: two points per manifold at the plane's depth
    const Pose pc{Vec3(u(rng), 0.18, u(rng)), glm::angleAxis(kPi / 2, Vec3(0, 0, 1))};
    const ColliderShape c = ColliderShape::capsule(0.4, 0.2);
    const int nc = collide_mesh(c, pc, grid, {}, out);
    ASSERT_GE(nc, 1);
    for (int m = 0; m < nc; ++m) {
      EXPECT_NEAR(glm::length(out[std::size_t(m)].normal - Vec3(0, -1, 0)), 0.0, 1e-12);
      for (int i = 0; i < out[std::size_t(m)].count; ++i)
        EXPECT_NEAR(out[std::size_t(m)].points[std::size_t(i)].depth, 0.02, 1e-12);
    }
  }
}

// Spheres and capsules against a triangle take closed forms (the closest points of a point
// or a segment and the triangle); they give what GJK gives on the same cores, the triangle
// as a one-triangle mesh (its edges are boundaries, so nothing is snapped): the normal and
// the depth of every point, and the points of a one-point manifold, over random poses (GJK
// stops within 1e-10 m of the distance). A capsule lying along the face has its segment
// clipped to the triangle along that normal, as before. Cores that pierce the triangle go
// to EPA as before.
TEST(Mesh, SphereAndCapsuleClosedFormsMatchGjk) {
  const OneTriangle one;
  const ColliderShape& tri = one.mesh;
  const ConvexProxy& B = one.proxy;
  const NarrowPhaseSettings ns{.speculative_margin = 0.6};
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.4, 1.4), w(-1, 1);
  std::array<Manifold, 4> out;
  int compared[2] = {0, 0}, one_point = 0;
  for (int k = 0; k < 4000; ++k) {
    const bool capsule = k % 2 == 1;
    const ColliderShape s = capsule ? ColliderShape::capsule(0.5, 0.2) : ColliderShape::sphere(0.3);
    const Pose p{Vec3(u(rng), u(rng), u(rng)), glm::normalize(Quat(w(rng), w(rng), w(rng), w(rng)))};
    const DistanceResult ref = gjk_distance(ConvexProxy::of(s, p), B);
    if (ref.cores_overlap) continue;  // EPA's case, as before
    const double sep = ref.core_distance - s.radius;  // < 0 overlapping (distance is 0 then)
    const int n = collide_mesh(s, p, tri, {}, out, ns);
    if (sep > ns.speculative_margin + 1e-9) {
      EXPECT_EQ(n, 0) << k;
      continue;
    }
    if (sep > ns.speculative_margin - 1e-9) continue;  // at the margin: either
    ASSERT_EQ(n, 1) << k;
    const Manifold& m = out[0];
    EXPECT_LT(glm::length(m.normal - ref.normal), 1e-6) << k;
    // a sphere's one point, and a capsule's unless it lies along the normal's plane (within
    // the 0.05 of its length that makes collide_mesh clip its segment to the triangle): the
    // closest points
    const Vec3 axis = p.rotation * Vec3(0, 1, 0);
    if (!capsule || std::abs(glm::dot(axis, ref.normal)) >= 0.05) {
      ASSERT_EQ(m.count, 1) << k;
      const ContactPoint& cp = m.points[0];
      EXPECT_NEAR(cp.depth, -sep, 1e-9) << k;
      EXPECT_LT(glm::length(cp.point_a - ref.point_a), 1e-6) << k;
      EXPECT_LT(glm::length(cp.point_b - ref.point_b), 1e-6) << k;
      ++one_point;
    }
    ++compared[capsule];
  }
  // most poses are compared (not overlapping, within the margin), most with one point
  EXPECT_GT(compared[0], 800);
  EXPECT_GT(compared[1], 800);
  EXPECT_GT(one_point, 1400);
}

// Boxes and hulls against a triangle take separating axes (the triangle's normal, the
// shape's faces, the crosses of their edges) where they overlap or lie over the face: the
// depth and normal of EPA (GJK when apart) on the same pair, the triangle as a one-triangle
// mesh, over random poses: the normal to 1e-6, a one-point manifold's depth to 1e-9 m
TEST(Mesh, BoxAndHullSeparatingAxesMatchEpa) {
  const OneTriangle one;
  const ColliderShape& tri = one.mesh;
  const ConvexProxy& B = one.proxy;
  const ColliderShape pyramid = pyramid_hull();
  const NarrowPhaseSettings ns{.speculative_margin = 0.3};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0), w(-1, 1);
  std::array<Manifold, 4> out;
  int compared[2] = {0, 0}, one_point = 0;
  for (int k = 0; k < 4000; ++k) {
    const bool hull = k % 2 == 1;
    const ColliderShape s = hull ? pyramid : ColliderShape::box(Vec3(0.2, 0.3, 0.4));
    const Pose p{Vec3(u(rng), u(rng), u(rng)), glm::normalize(Quat(w(rng), w(rng), w(rng), w(rng)))};
    const ConvexProxy A = ConvexProxy::of(s, p);
    double depth = 0;
    Vec3 normal;
    ASSERT_TRUE(reference_contact(A, B, depth, normal)) << k;
    const int n = collide_mesh(s, p, tri, {}, out, ns);
    if (depth < -ns.speculative_margin - 1e-9) {
      EXPECT_EQ(n, 0) << k;
      continue;
    }
    if (depth < -ns.speculative_margin + 1e-9) continue;  // at the margin: either
    ASSERT_EQ(n, 1) << k;
    const Manifold& m = out[0];
    double deepest = -INFINITY;
    for (int i = 0; i < m.count; ++i) deepest = std::max(deepest, m.points[std::size_t(i)].depth);
    // deeper than 0.15 m the side of the triangle is the shape's centre's (the internal
    // edge rule, as before), which may be against EPA's least overlap
    if (depth >= 0.15) continue;
    EXPECT_LT(glm::length(m.normal - normal), 1e-6) << k << " depth " << depth;
    // one point: the deepest; a clipped face (the shape's face against the triangle, as
    // before) holds no point deeper than it
    if (m.count == 1) {
      EXPECT_NEAR(deepest, depth, 1e-9) << k;
      ++one_point;
    } else {
      EXPECT_LE(deepest, depth + 1e-9) << k;
    }
    ++compared[hull];
  }
  EXPECT_GT(compared[0], 800);
  EXPECT_GT(compared[1], 800);
  EXPECT_GT(one_point, 300);
}

// Every manifold point lies on both shapes: point_a on the convex shape's surface, point_b
// on the triangle, point_a - point_b = depth along the normal (to 1e-9 m on shapes of a
// metre), and the deepest point is as deep as EPA's penetration (GJK's distance when apart)
// along the same normal (1e-6 m), over random poses of capsules (most lying within 0.05 of
// the face's plane, over its edges and corners, where the segment is clipped), boxes and a
// hull against one triangle (its edges are boundaries: no normal is snapped)
TEST(Mesh, ManifoldPointsLieOnBothSurfaces) {
  const OneTriangle one;
  const std::vector<Vec3>& v = one.v;
  const ColliderShape& tri = one.mesh;
  const ConvexProxy& B = one.proxy;
  const Vec3 fn = glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
  const Vec3 e1 = glm::normalize(v[1] - v[0]), e2 = glm::cross(fn, e1);
  const ColliderShape pyramid = pyramid_hull();
  const NarrowPhaseSettings ns{.speculative_margin = 0.3};
  // the distance of x to the triangle
  auto off_triangle = [&](const Vec3& x) {
    const Vec3 ab = v[1] - v[0], ac = v[2] - v[0];
    // the nearest point by the pieces: the plane inside, else the three edges
    const double d00 = glm::dot(ab, ab), d01 = glm::dot(ab, ac), d11 = glm::dot(ac, ac);
    const double d20 = glm::dot(x - v[0], ab), d21 = glm::dot(x - v[0], ac), den = d00 * d11 - d01 * d01;
    const double bv = (d11 * d20 - d01 * d21) / den, bw = (d00 * d21 - d01 * d20) / den;
    if (bv >= 0 && bw >= 0 && bv + bw <= 1) return std::abs(glm::dot(x - v[0], fn));
    double best = INFINITY;
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = v[std::size_t(k)], d = v[std::size_t((k + 1) % 3)] - p;
      const double s = std::clamp(glm::dot(x - p, d) / glm::dot(d, d), 0.0, 1.0);
      best = std::min(best, glm::length(x - (p + s * d)));
    }
    return best;
  };
  // the distance of x to the shape's surface (a polytope's: the largest of its planes'
  // signed distances, zero exactly on it)
  auto off_shape = [&](const ColliderShape& s, const Pose& p, const Vec3& x) {
    const Vec3 l = glm::conjugate(p.rotation) * (x - p.position);
    if (s.type == ShapeType::Capsule) {
      const Vec3 c{0, std::clamp(l.y, -s.half_height, s.half_height), 0};
      return std::abs(glm::length(l - c) - s.radius);
    }
    if (s.type == ShapeType::Box) {
      const Vec3 h = s.half_extents;
      return std::abs(std::max({std::abs(l.x) - h.x, std::abs(l.y) - h.y, std::abs(l.z) - h.z}));
    }
    double most = -INFINITY;
    for (const auto& f : s.hull->faces()) most = std::max(most, glm::dot(f.normal, l) - f.offset);
    return std::abs(most);
  };
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0), w(-1, 1);
  std::array<Manifold, 4> out;
  int checked[3] = {0, 0, 0}, deepest_checked = 0, multi[3] = {0, 0, 0};
  for (int k = 0; k < 6000; ++k) {
    const int kind = k % 3;  // capsule, box, hull
    const ColliderShape s = kind == 0 ? ColliderShape::capsule(0.5, 0.2)
                            : kind == 1 ? ColliderShape::box(Vec3(0.2, 0.3, 0.4))
                                        : pyramid;
    Pose p{Vec3(u(rng), u(rng), u(rng)), glm::normalize(Quat(w(rng), w(rng), w(rng), w(rng)))};
    if (kind == 0 && k % 2 == 0) {
      // lying within 0.05 rad of the face's plane, anywhere over the triangle and around it,
      // from 0.1 m into it to 0.1 m beyond the margin
      const double a = 3.2 * w(rng), tilt = 0.05 * w(rng), h = 0.2 + 0.2 * w(rng);
      const Vec3 axis = std::cos(tilt) * (std::cos(a) * e1 + std::sin(a) * e2) + std::sin(tilt) * fn;
      p.position = Vec3(0.1, 0.07, 0) + 1.1 * (u(rng) * e1 + u(rng) * e2) + (w(rng) < 0 ? -h : h) * fn;
      const Vec3 turn = glm::cross(Vec3(0, 1, 0), axis);
      p.rotation = glm::angleAxis(std::acos(std::clamp(axis.y, -1.0, 1.0)), glm::normalize(turn));
    }
    const ConvexProxy A = ConvexProxy::of(s, p);
    double depth = 0;
    Vec3 normal;
    ASSERT_TRUE(reference_contact(A, B, depth, normal)) << k;
    const int n = collide_mesh(s, p, tri, {}, out, ns);
    if (n == 0) continue;
    ASSERT_EQ(n, 1) << k;
    const Manifold& m = out[0];
    double deepest = -INFINITY;
    for (int i = 0; i < m.count; ++i) {
      const ContactPoint& c = m.points[std::size_t(i)];
      EXPECT_LT(off_shape(s, p, c.point_a), 1e-9) << k << " point " << i << " of " << m.count;
      EXPECT_LT(off_triangle(c.point_b), 1e-9) << k << " point " << i << " of " << m.count;
      EXPECT_LT(glm::length(c.point_a - c.point_b - c.depth * m.normal), 1e-9) << k << " point " << i;
      deepest = std::max(deepest, c.depth);
    }
    ++checked[kind];
    if (m.count > 1) ++multi[kind];
    // EPA's side of the triangle is the centre's shallower than 0.15 m (the internal edge
    // rule, as in BoxAndHullSeparatingAxesMatchEpa); at the margin either
    if (depth >= 0.15 || depth < -ns.speculative_margin + 1e-6) continue;
    if (glm::length(m.normal - normal) > 1e-6) continue;
    EXPECT_NEAR(deepest, depth, 1e-6) << k << " count " << m.count << " shape " << kind;
    ++deepest_checked;
  }
  // most poses touch (1505, 1296, 1196 of 2000 each), some with several points (238, 391,
  // 319), most compared with EPA or GJK (3373)
  for (int kind = 0; kind < 3; ++kind) {
    EXPECT_GT(checked[kind], 1000) << kind;
    EXPECT_GT(multi[kind], 60) << kind;
  }
  EXPECT_GT(deepest_checked, 3000);
}

TEST(Mesh, ConvexRidgeKeepsItsEdgeNormal) {
  // two triangles folded into a ridge along x (a roof, convex edge flagged): a sphere
  // right above the ridge line touches the edge, whose normal points straight up, and a
  // sphere off to the side at the edge's end gets the edge-to-centre direction
  const std::vector<Vec3> v = {{-1, 0, -1}, {1, 0, -1}, {-1, 0.5, 0}, {1, 0.5, 0}, {-1, 0, 1}, {1, 0, 1}};
  const std::vector<std::array<std::uint32_t, 3>> t = {{0, 2, 1}, {1, 2, 3}, {2, 4, 3}, {3, 4, 5}};
  const ColliderShape roof = ColliderShape::triangles(TriangleMesh::build(v, t, "roof"));
  std::array<Manifold, 8> out;
  const ColliderShape s = ColliderShape::sphere(0.2);
  const int n = collide_mesh(s, {Vec3(0.1, 0.69, 0), Quat(1, 0, 0, 0)}, roof, {}, out);
  ASSERT_GE(n, 1);
  for (int m = 0; m < n; ++m) {
    EXPECT_NEAR(glm::length(out[std::size_t(m)].normal - Vec3(0, -1, 0)), 0.0, 1e-9);
    EXPECT_NEAR(out[std::size_t(m)].points[0].depth, 0.01, 1e-9);
  }
}

// collide_mesh with a MeshQueryCache gives collide()'s manifolds to the bit without one:
// shapes of each kind wandering over a bumpy grid in small steps (the cache serving) and
// jumps (made anew), a large box over more triangles than the cache holds (the tree serving),
// and one cache taken from one mesh to another
TEST(Mesh, QueryCacheGivesTheSameManifolds) {
  const ColliderShape bumpy = bumpy_grid(24, 0.15, 1.3, 0.9);
  const ColliderShape flat = flat_grid(12);
  const ColliderShape shapes[5] = {ColliderShape::sphere(0.3), ColliderShape::capsule(0.4, 0.2),
                                   ColliderShape::box({0.3, 0.2, 0.4}), pyramid_hull(),
                                   ColliderShape::box({2.5, 0.3, 2.5})};
  const Pose at_mesh{{0.2, -0.1, 0.3}, glm::angleAxis(0.1, glm::normalize(Vec3(1, 2, 3)))};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Manifold> with(64), without(64);
  int touching = 0, many = 0;
  for (const ColliderShape& s : shapes) {
    MeshQueryCache cache;
    Vec3 p(0, 0.15, 0);
    for (int k = 0; k < 400; ++k) {
      // mostly steps of up to 2 cm, now and then a jump
      p += (k % 50 == 49 ? 2.0 : 0.02) * Vec3(u(rng), 0.3 * u(rng), u(rng));
      p = glm::clamp(p, Vec3(-4, -0.2, -4), Vec3(4, 0.5, 4));
      const Pose pose{p, glm::angleAxis(3 * u(rng), glm::normalize(Vec3(u(rng), 1, u(rng))))};
      const ColliderShape& mesh = k < 300 ? bumpy : flat;
      const NarrowPhaseSettings ns{.speculative_margin = 0.05};
      const int a = collide_mesh(s, pose, mesh, at_mesh, with, ns, &cache);
      const int b = collide_mesh(s, pose, mesh, at_mesh, without, ns);
      ASSERT_EQ(a, b) << "step " << k;
      touching += a > 0;
      many += a > MeshQueryCache::kCapacity;
      for (int m = 0; m < a; ++m) {
        EXPECT_EQ(with[m].sub_shape_b, without[m].sub_shape_b);
        EXPECT_EQ(with[m].count, without[m].count);
        EXPECT_TRUE(with[m].normal == without[m].normal) << "step " << k;
        for (int q = 0; q < with[m].count; ++q) {
          EXPECT_TRUE(with[m].points[q].point_a == without[m].points[q].point_a);
          EXPECT_TRUE(with[m].points[q].point_b == without[m].points[q].point_b);
          EXPECT_EQ(with[m].points[q].id, without[m].points[q].id);
        }
      }
    }
  }
  EXPECT_GT(touching, 1000);  // most steps touch
  EXPECT_GT(many, 100);       // the large box touches more triangles than the cache holds
}

// A box's or hull's edge axes against a triangle run four at a time in AVX2 lanes where the
// processor has them: the same operations per axis in the same order, the lanes then judged
// in the scalar loop's order, so every manifold is the plain scalar path's to the bit. Boxes,
// the square pyramid (parallel base edges), a 12-gon prism (its side edges all parallel, its
// caps' edges pairwise), a random 20-point hull, a sphere and a capsule, at random poses from
// 15 cm above a bumpy mesh to 25 cm into it (the edge axes run where every axis overlaps); an
// overlapping contact whose normal is neither the triangle's nor along a face of the shape
// came from an edge axis. The mesh is turned, or only moved (the turns by it left out where
// they give the same bits: shapes at a zero coordinate or unturned about an axis, a mesh at
// a zero coordinate, normals with zero components on the flat grid's part take the turns).
TEST(Mesh, EdgeAxesInLanesGiveTheScalarBits) {
  const ColliderShape bumpy = bumpy_grid(16, 0.3, 1.1, 0.7);
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> prism, cloud;
  for (int k = 0; k < 12; ++k) {
    const double a = 2 * kPi * k / 12;
    prism.push_back({0.4 * std::cos(a), -0.3, 0.4 * std::sin(a)});
    prism.push_back({0.4 * std::cos(a), 0.3, 0.4 * std::sin(a)});
  }
  for (int k = 0; k < 20; ++k) cloud.push_back(Vec3(0.5 * u(rng), 0.3 * u(rng), 0.4 * u(rng)));
  const ColliderShape shapes[7] = {ColliderShape::box({0.3, 0.2, 0.4}), pyramid_hull(),
                                   ColliderShape::convex(ConvexHull::build(prism, "prism")),
                                   ColliderShape::convex(ConvexHull::build(cloud, "cloud")),
                                   ColliderShape::box({1.2, 0.1, 0.05}), ColliderShape::sphere(0.3),
                                   ColliderShape::capsule(0.4, 0.2)};
  // the mesh turned, moved, moved with a zero coordinate
  const Pose mesh_poses[3] = {{{0.1, 0.2, -0.3}, glm::angleAxis(0.2, glm::normalize(Vec3(1, 3, 2)))},
                              {{-150, 2.5, -150}, Quat(1, 0, 0, 0)},
                              {{0, -0.5, 7}, Quat(1, 0, -0.0, 0)}};
  std::vector<Manifold> wide(32), scalar(32);
  int touching = 0;
  for (const ColliderShape& s : shapes) {
    int edge_normals_here = 0;
    for (int k = 0; k < 600; ++k) {
      const Pose& at_mesh = mesh_poses[k % 3];
      Vec3 p(3 * u(rng), 0, 3 * u(rng));
      const double ground = 0.3 * std::sin(1.1 * (p.x + 4) / 0.5) * std::cos(0.7 * (p.z + 4) / 0.5);
      p.y = ground + 0.2 * u(rng) - 0.05;
      Quat q = glm::angleAxis(3 * u(rng), glm::normalize(Vec3(u(rng), u(rng), u(rng))));
      if (k % 7 == 0) p.x = 0;                                   // a zero coordinate in the mesh's frame
      if (k % 11 == 0) q = glm::angleAxis(3 * u(rng), Vec3(0, 1, 0));  // turned about the mesh's up axis only
      const Pose pose{apply(at_mesh, p), at_mesh.rotation * q};
      const NarrowPhaseSettings ns{.speculative_margin = 0.05};
      const int a = collide_mesh(s, pose, bumpy, at_mesh, wide, ns, nullptr, BatchPath::Best);
      const int b = collide_mesh(s, pose, bumpy, at_mesh, scalar, ns, nullptr, BatchPath::Scalar);
      ASSERT_EQ(a, b) << "pose " << k;
      touching += a > 0;
      for (int m = 0; m < a; ++m) {
        ASSERT_EQ(wide[m].sub_shape_b, scalar[m].sub_shape_b);
        ASSERT_EQ(wide[m].count, scalar[m].count);
        // to the bit (memcmp: == takes -0 for +0, and signed zeros are what the shortcuts guard)
        auto same = [](const auto& x, const auto& y) { return std::memcmp(&x, &y, sizeof x) == 0; };
        EXPECT_TRUE(same(wide[m].normal, scalar[m].normal)) << "pose " << k;
        for (int q = 0; q < wide[m].count; ++q) {
          EXPECT_TRUE(same(wide[m].points[q].point_a, scalar[m].points[q].point_a)) << "pose " << k;
          EXPECT_TRUE(same(wide[m].points[q].point_b, scalar[m].points[q].point_b)) << "pose " << k;
          EXPECT_TRUE(same(wide[m].points[q].depth, scalar[m].points[q].depth)) << "pose " << k;
          EXPECT_EQ(wide[m].points[q].id, scalar[m].points[q].id);
        }
        // the normal against the triangle's and the shape's faces' (in the world)
        const Vec3 nm = wide[m].normal;
        bool face = std::abs(glm::dot(nm, at_mesh.rotation * bumpy.mesh->normal(wide[m].sub_shape_b))) > 1 - 1e-9;
        if (s.type == ShapeType::Box) {
          for (int i = 0; i < 3; ++i)
            face = face || std::abs(glm::dot(nm, glm::mat3_cast(pose.rotation)[i])) > 1 - 1e-9;
        } else if (s.type == ShapeType::Hull) {
          for (const auto& f : s.hull->faces())
            face = face || std::abs(glm::dot(nm, pose.rotation * f.normal)) > 1 - 1e-9;
        } else {
          face = true;  // a sphere's or capsule's normal is no edge axis's
        }
        // (overlapping: the separating axes' answer; GJK's normal of a pair apart is the
        // closest points' direction, along which every pair of points is apart)
        double deepest = -INFINITY;
        for (int q = 0; q < wide[m].count; ++q) deepest = std::max(deepest, wide[m].points[q].depth);
        edge_normals_here += !face && deepest > 0;
      }
    }
    if (s.type == ShapeType::Box || s.type == ShapeType::Hull) {
      EXPECT_GT(edge_normals_here, 250);  // every shape's edge axes win often (928-1,327)
    }
  }
  EXPECT_GT(touching, 3500);  // of 4,200 poses (4,157)
}

TEST(Mesh, BadInputAndNoAllocationOfResults) {
  const ColliderShape grid = flat_grid(2);
  std::array<Manifold, 2> out;
  const double nan = std::nan("");
  EXPECT_NE(test_support::error_of([&] { collide_mesh(ColliderShape::sphere(0.5), {Vec3(nan, 0, 0), Quat(1, 0, 0, 0)}, grid, {}, out); })
                .find("pose_a.position"),
            std::string::npos);
  EXPECT_NE(test_support::error_of([&] { collide_mesh(grid, {}, grid, {}, out); }).find("convex"), std::string::npos);
  // at most out.size() manifolds are written
  EXPECT_LE(collide_mesh(ColliderShape::box(Vec3(0.9, 0.5, 0.9)), {Vec3(0, 0.45, 0), Quat(1, 0, 0, 0)}, grid, {}, out),
            2);
}

}  // namespace

namespace {

using namespace pba;

// Three triangles of the sine terrain (rigid_scenes::sine_terrain_mesh) about one vertex, moved
// to the origin: A and C meet on a convex edge, C and B on a concave one, A and B only at the
// vertex. A capsule (radius 0.5, half length 0.75) lies on A 0.1 mm deep, as one did in the
// terrain bench at step 260, 5 cm from B, its core nearest B's concave (internal) edge: B's
// normal is B's face normal there, and B's one-point contact took the capsule's deepest point
// along it, the capsule's far end over A, 0.55 m below B's plane (the surface falls away from
// B across the convex edge). The solver pushed the capsule up out of the ground it lay on at
// the push-out speed. No triangle may find the capsule deeper than it lies in the mesh (0.1
// mm on A), and every point must lie on its triangle. (B's contact now keeps the face normal
// at the pair's own depth, minus the 5 cm distance, at its closest point on B: the plane's
// point lies over no triangle of B's plane.)
TEST(Mesh, AnInternalEdgesContactIsNoDeeperThanTheShapeLiesInTheMesh) {
  const std::vector<Vec3> v = {{0, 0.447, -3}, {-3, -0.848, 0}, {0, 0, 0}, {3, 0.169, -3}, {3, -0.253, 0}};
  const std::vector<std::array<std::uint32_t, 3>> t = {{0, 1, 2}, {0, 2, 3}, {3, 2, 4}};  // A, C, B
  const ColliderShape fan = ColliderShape::triangles(TriangleMesh::build(v, t, "fan"));
  ASSERT_EQ(fan.mesh->edge_flags()[2] & 1, 0);  // B's edge to C is internal
  const ColliderShape capsule = ColliderShape::capsule(0.75, 0.5);
  const Pose p{{-0.8547, 0.3283, -0.3037}, glm::normalize(Quat(-0.55078, 0.46247, -0.27150, -0.63957))};
  std::array<Manifold, 8> out;
  const int n = collide_mesh(capsule, p, fan, {}, out, {.speculative_margin = 0.06});
  ASSERT_GE(n, 1);
  for (int m = 0; m < n; ++m) {
    const Manifold& k = out[std::size_t(m)];
    const auto& ids = fan.mesh->triangles()[k.sub_shape_b];
    for (int i = 0; i < k.count; ++i) {
      const ContactPoint& c = k.points[std::size_t(i)];
      EXPECT_LT(c.depth, 1e-3) << "triangle " << k.sub_shape_b;
      // on the triangle: in its plane, and its barycentric weights in [0, 1]
      const Vec3 a = v[ids[0]], ab = v[ids[1]] - a, ac = v[ids[2]] - a, f = glm::cross(ab, ac), q = c.point_b - a;
      const double ff = glm::dot(f, f), wb = glm::dot(glm::cross(q, ac), f) / ff, wc = glm::dot(glm::cross(ab, q), f) / ff;
      EXPECT_LT(std::abs(glm::dot(q, f)) / std::sqrt(ff), 1e-9) << "triangle " << k.sub_shape_b;
      EXPECT_TRUE(wb >= -1e-9 && wc >= -1e-9 && wb + wc <= 1 + 1e-9) << "triangle " << k.sub_shape_b << ": " << wb << ", " << wc;
    }
  }
}

// A valley of two triangles meeting at a concave (internal) crease along z, sides rising at
// 30 degrees: a ball over the right side, sunk 0.14 m into it, is 6 cm from the left side,
// whose nearest point is on the crease; its deepest point along the left side's normal lies
// over the right side, 6 cm (to rounding) above the left plane there. The left triangle still
// gives its speculative contact (not dropped: a shape coming down into a valley is stopped by
// it), along the left face's normal, at the crease point, as deep as the ball lies from the
// triangle (minus the distance: 0.3 - |(0.2, 0.3)|), not at the plane's depth.
TEST(Mesh, AConcaveCreasesSpeculativeContactKeepsTheDistance) {
  const double t = std::tan(kPi / 6), L = 4;
  const std::vector<Vec3> v = {{0, 0, L}, {0, 0, -L}, {-L, L * t, 0}, {L, L * t, 0}};
  const std::vector<std::array<std::uint32_t, 3>> tri = {{0, 1, 2}, {1, 0, 3}};
  const ColliderShape valley = ColliderShape::triangles(TriangleMesh::build(v, tri, "valley"));
  ASSERT_EQ(valley.mesh->edge_flags()[0] & 1, 0);  // the crease is internal
  const Vec3 centre{0.2, 0.3, 0.1};
  std::array<Manifold, 4> out;
  const int n = collide_mesh(ColliderShape::sphere(0.3), {centre, Quat(1, 0, 0, 0)}, valley, {}, out,
                             {.speculative_margin = 0.1});
  ASSERT_EQ(n, 2);
  const Manifold& left = out[0].sub_shape_b == 0 ? out[0] : out[1];
  ASSERT_EQ(left.sub_shape_b, 0u);
  ASSERT_EQ(left.count, 1);
  EXPECT_NEAR(glm::length(left.normal + valley.mesh->normal(0)), 0.0, 1e-12);
  EXPECT_NEAR(left.points[0].depth, 0.3 - std::hypot(0.2, 0.3), 1e-12);
  EXPECT_NEAR(glm::length(left.points[0].point_b - Vec3(0, 0, 0.1)), 0.0, 1e-12);
}

}  // namespace
