// Tests for ConvexHull::build (quickhull): structure (twins, Euler, planar convex faces),
// containment of the input, coplanar merging on boxes and lattices, degenerate clouds,
// hill-climbing support against brute force, and exact mass properties.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "error_of.h"
#include "pba/collide/shape.h"
#include "shape_checks.h"
#include "shape_gen.h"

namespace {

using namespace pba;
using namespace pba::test_support;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// the builder's tolerance is 1e-9 of the cloud's extent (x + y + z sizes); merging coplanar
// triangles moves a plane by at most that again, so a point lies within 2 tol of the hull
double hull_tol(std::span<const Vec3> pts) {
  Vec3 lo = pts[0], hi = pts[0];
  for (const Vec3& p : pts) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const Vec3 e = hi - lo;
  return 2e-9 * (e.x + e.y + e.z);
}

void expect_contains(const ConvexHull& h, std::span<const Vec3> pts, double tol) {
  for (std::size_t i = 0; i < pts.size(); ++i) {
    double worst = -1e300;
    for (const auto& f : h.faces()) worst = std::max(worst, glm::dot(f.normal, pts[i]) - f.offset);
    EXPECT_LE(worst, tol) << "point " << i << " outside the hull";
  }
}


// box closed form: I = m/12 diag(b^2 + c^2, a^2 + c^2, a^2 + b^2) for edge lengths a, b, c
Mat3 box_inertia(const Vec3& h, double density) {
  const Vec3 l = 2.0 * h;
  const double m = density * l.x * l.y * l.z;
  Mat3 i(0.0);
  i[0][0] = m / 12 * (l.y * l.y + l.z * l.z);
  i[1][1] = m / 12 * (l.x * l.x + l.z * l.z);
  i[2][2] = m / 12 * (l.x * l.x + l.y * l.y);
  return i;
}


// box corners (each three times), random points on its faces and edges and inside, shuffled
std::vector<Vec3> messy_box_cloud(const Vec3& h, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> pts;
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 8; ++i) pts.push_back(Vec3(i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z));
  for (int k = 0; k < 300; ++k) {
    Vec3 p(u(rng) * h.x, u(rng) * h.y, u(rng) * h.z);
    const int axis = k % 3, kind = (k / 3) % 3;
    if (kind >= 1) p[axis] = (k & 8 ? 1 : -1) * h[axis];                      // on a face
    if (kind == 2) p[(axis + 1) % 3] = (k & 16 ? 1 : -1) * h[(axis + 1) % 3];  // on an edge
    pts.push_back(p);
  }
  std::shuffle(pts.begin(), pts.end(), rng);
  return pts;
}

// ---------------------------------------------------------------------------

TEST(CollideHull, BoxCloudWithDuplicatesAndCoplanarPointsGivesTheBox) {
  std::mt19937_64 rng(3);
  const Vec3 h(0.5, 1.25, 2);
  const std::vector<Vec3> pts = messy_box_cloud(h, rng);
  const auto hull = ConvexHull::build(pts);
  EXPECT_EQ(hull->vertices().size(), 8u);
  EXPECT_EQ(hull->faces().size(), 6u);
  EXPECT_EQ(hull->edges().size(), 24u);
  expect_valid_hull(*hull, 1e-14);
  expect_contains(*hull, pts, 1e-14);
  // the box's mass properties, exactly (rounding only: 1e-12 relative)
  const MassProperties mp = hull->mass_properties(800);
  const double vol = 8 * h.x * h.y * h.z;
  EXPECT_NEAR(mp.volume, vol, 1e-12 * vol);
  EXPECT_NEAR(mp.mass, 800 * vol, 1e-12 * 800 * vol);
  EXPECT_NEAR(glm::length(mp.center), 0, 1e-12 * glm::length(h));
  expect_mat_near(mp.inertia, box_inertia(h, 800), 1e-12);
  EXPECT_NEAR(hull->volume(), vol, 1e-12 * vol);
}

TEST(CollideHull, RotatedBoxCornersMergeAndKeepTheRotatedInertia) {
  // corners of a box rotated and moved: coplanar only to rounding, still 6 quads; the
  // inertia is R I0 R^T about the moved centre
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 h(0.3 + 0.1 * trial, 0.7, 1.1);
    const Pose p{Vec3(3 - trial, 2, -7), random_rotation(rng)};
    std::vector<Vec3> pts;
    for (int i = 0; i < 8; ++i) pts.push_back(apply(p, Vec3(i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z)));
    const auto hull = ConvexHull::build(pts);
    ASSERT_EQ(hull->faces().size(), 6u) << "trial " << trial;
    EXPECT_EQ(hull->vertices().size(), 8u);
    expect_valid_hull(*hull, 1e-12);
    const MassProperties mp = hull->mass_properties(2);
    EXPECT_NEAR(glm::length(mp.center - p.position), 0, 1e-12 * glm::length(p.position));
    const Mat3 r = glm::mat3_cast(p.rotation);
    expect_mat_near(mp.inertia, r * box_inertia(h, 2) * glm::transpose(r), 1e-12);
  }
}

TEST(CollideHull, RandomCloudsGiveValidHullsThatContainThem) {
  std::mt19937_64 rng(17);
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int kind = 0; kind < 4; ++kind) {
    for (int trial = 0; trial < 5; ++trial) {
      std::vector<Vec3> pts;
      const int count = 50 + 400 * trial;
      for (int i = 0; i < count; ++i) {
        if (kind == 0) pts.push_back(2.0 * glm::normalize(Vec3(g(rng), g(rng), g(rng))));  // on a sphere
        if (kind == 1) pts.push_back(Vec3(u(rng), u(rng), 3 * u(rng)));                   // in a box
        if (kind == 2) pts.push_back(Vec3(g(rng), g(rng), g(rng)) + Vec3(100, 0, 0));     // gaussian, off centre
        if (kind == 3) {
          // integer lattice points: most of the hull's points are coplanar or collinear
          std::uniform_int_distribution<int> k(-3, 3);
          pts.push_back(Vec3(k(rng), k(rng), k(rng)) * 0.25);
        }
      }
      const auto hull = ConvexHull::build(pts);
      const double tol = hull_tol(pts);
      expect_valid_hull(*hull, tol);
      expect_contains(*hull, pts, tol);
      // the hull's vertices are input points
      for (const Vec3& v : hull->vertices()) EXPECT_NE(std::find(pts.begin(), pts.end(), v), pts.end());
      const auto corner = [&](const Vec3& c) { return std::find(pts.begin(), pts.end(), c) != pts.end(); };
      bool corners = true;
      for (int i = 0; i < 8; ++i) corners = corners && corner(0.75 * Vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1));
      if (kind == 3 && corners) {
        // a lattice sample holding the cube's 8 corners has the cube for hull: 6 faces
        EXPECT_EQ(hull->vertices().size(), 8u);
        EXPECT_EQ(hull->faces().size(), 6u);
      }
    }
  }
}

// ConvexHull::edge_directions: the first edge of each direction, as comparing every edge
// with those kept before it (exact equality of the vectors or of one and the other's
// negation) finds them, in index order; a square pyramid's diamond base has two pairs of
// opposite edges (8 edges, 6 directions), a cube three directions, a prism's sides one.
TEST(CollideHull, EdgeDirectionsAreTheFirstEdgeOfEachDirection) {
  std::vector<std::vector<Vec3>> clouds;
  clouds.push_back({{0, 0.6, 0}, {0.5, 0, 0}, {-0.5, 0, 0}, {0, 0, 0.5}, {0, 0, -0.5}});
  clouds.push_back({});
  for (int i = 0; i < 8; ++i) clouds.back().push_back(Vec3(i & 1 ? 0.5 : -0.5, i & 2 ? 0.25 : -0.25, i & 4 ? 1 : -1));
  clouds.push_back({});
  for (int k = 0; k < 12; ++k) {
    const double a = 2 * kPi * k / 12;
    clouds.back().push_back({std::cos(a), -1, std::sin(a)});
    clouds.back().push_back({std::cos(a), 1, std::sin(a)});
  }
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int> lattice(-2, 2);
  clouds.push_back({});
  for (int i = 0; i < 40; ++i) clouds.back().push_back(Vec3(u(rng), u(rng), u(rng)));
  clouds.push_back({});
  for (int i = 0; i < 200; ++i) clouds.back().push_back(0.5 * Vec3(lattice(rng), lattice(rng), lattice(rng)));
  std::vector<std::size_t> counts, edges;
  for (const auto& c : clouds) {
    const auto hull = ConvexHull::build(c);
    const auto e = hull->edges();
    const auto vs = hull->vertices();
    std::vector<std::uint32_t> expect;
    std::vector<Vec3> kept;
    for (std::uint32_t i = 0; i < e.size(); i += 2) {
      const Vec3 d = vs[e[e[i].next].origin] - vs[e[i].origin];
      bool seen = false;
      for (const Vec3& k : kept) seen = seen || k == d || k == -d;
      if (!seen) kept.push_back(d), expect.push_back(i);
    }
    const auto got = hull->edge_directions();
    EXPECT_EQ(std::vector<std::uint32_t>(got.begin(), got.end()), expect);
    counts.push_back(got.size()), edges.push_back(e.size() / 2);
  }
  EXPECT_EQ(counts[0], 6u);
  EXPECT_EQ(counts[1], 3u);
  EXPECT_LE(counts[2], 1 + 12u);  // the sides' one; the caps' edges in 12 equal pairs
  EXPECT_LT(counts[4], edges[4]);  // a lattice's hull has parallel edges
}

TEST(CollideHull, FullLatticeGivesTheCube) {
  std::vector<Vec3> pts;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 6; ++k) pts.push_back(Vec3(i, j, k) * 0.2 - Vec3(0.5));
  const auto hull = ConvexHull::build(pts);
  EXPECT_EQ(hull->vertices().size(), 8u);
  EXPECT_EQ(hull->faces().size(), 6u);
  expect_valid_hull(*hull, 1e-14);
  EXPECT_NEAR(hull->volume(), 1.0, 1e-14);
}

TEST(CollideHull, PrismCapsAndSidesMergeIntoPolygons) {
  // a 48-gon prism sampled on its caps' rims, on its side lines and inside the caps: two
  // 48-gon caps and 48 quads; the side points are collinear with the rims and dropped
  std::vector<Vec3> pts;
  const int m = 48;
  for (int k = 0; k < m; ++k) {
    const double a = 2 * kPi * k / m;
    for (int j = 0; j <= 4; ++j) pts.push_back(Vec3(std::cos(a), std::sin(a), -1 + 0.5 * j));
    pts.push_back(Vec3(0.5 * std::cos(a), 0.5 * std::sin(a), 1));
  }
  const auto hull = ConvexHull::build(pts);
  EXPECT_EQ(hull->vertices().size(), 2u * m);
  EXPECT_EQ(hull->faces().size(), m + 2u);
  expect_valid_hull(*hull, hull_tol(pts));
  expect_contains(*hull, pts, hull_tol(pts));
  // its volume is the polygon's area times the height: (m/2) sin(2 pi/m) * 2
  EXPECT_NEAR(hull->volume(), m * std::sin(2 * kPi / m), 1e-12);
}

TEST(CollideHull, LatitudeLongitudeSphereWithRepeatedPoles) {
  // rings of a UV sphere are coplanar and the poles repeat once per meridian: the hull has
  // one vertex per distinct point, quads between rings and triangle fans at the poles
  std::vector<Vec3> pts;
  const int rings = 12, sectors = 24;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      const double t = kPi * i / rings, a = 2 * kPi * j / sectors;
      pts.push_back(Vec3(std::sin(t) * std::cos(a), std::cos(t), std::sin(t) * std::sin(a)));
    }
  const auto hull = ConvexHull::build(pts);
  EXPECT_EQ(hull->vertices().size(), static_cast<std::size_t>((rings - 1) * sectors + 2));
  EXPECT_EQ(hull->faces().size(), static_cast<std::size_t>((rings - 2) * sectors + 2 * sectors));
  expect_valid_hull(*hull, hull_tol(pts));
  expect_contains(*hull, pts, hull_tol(pts));
}

TEST(CollideHull, LargeCloudIsValid) {
  // 3 10^4 points in a ball and on a sphere (quickhull is O(n log n) expected)
  std::mt19937_64 rng(37);
  std::normal_distribution<double> g(0, 1);
  std::vector<Vec3> pts;
  for (int i = 0; i < 30000; ++i) {
    const Vec3 d = glm::normalize(Vec3(g(rng), g(rng), g(rng)));
    pts.push_back(i % 10 == 0 ? d : d * std::cbrt(std::uniform_real_distribution<double>(0, 1)(rng)));
  }
  Stopwatch sw;
  const auto hull = ConvexHull::build(pts);
  std::printf("quickhull of %zu points: %zu vertices, %zu faces in %.3f s\n", pts.size(), hull->vertices().size(),
              hull->faces().size(), sw.seconds());
  // containment, checked on every 50th point (all of them take 2e9 plane tests)
  std::vector<Vec3> some;
  for (std::size_t i = 0; i < pts.size(); i += 50) some.push_back(pts[i]);
  expect_contains(*hull, some, hull_tol(pts));
  EXPECT_EQ(static_cast<long>(hull->vertices().size()) - static_cast<long>(hull->edges().size() / 2) +
                static_cast<long>(hull->faces().size()),
            2);
  // inscribed in the unit ball: a deficit, small. The level-4 icosphere (2562 evenly spread
  // vertices) misses 0.009; 3000 random points are spread less evenly, so allow 0.03
  const double deficit = 4.0 / 3.0 * kPi - hull->volume();
  EXPECT_GT(deficit, 0);
  EXPECT_LT(deficit, 0.03);
}

TEST(CollideHull, IcosphereHullConvergesToTheSphereAtSecondOrder) {
  // an inscribed polyhedron with edge h misses a sagitta ~ h^2 / (8 r) of the sphere over its
  // whole surface, so the volume and inertia errors fall by 4 per subdivision (h halves)
  const double vs = 4.0 / 3.0 * kPi, is = 2.0 / 5.0 * vs;  // density 1, r = 1: I = 2/5 m r^2
  double prev_v = 0, prev_i = 0, prev_dv = 0, prev_di = 0;
  for (int level = 1; level <= 5; ++level) {
    const auto s = test_support::icosphere(level);
    const auto hull = ConvexHull::build(s.vertices);
    EXPECT_EQ(hull->faces().size(), s.triangles.size());
    EXPECT_EQ(hull->vertices().size(), s.vertices.size());
    if (level <= 3) expect_valid_hull(*hull, 1e-12);
    const MassProperties mp = hull->mass_properties(1);
    const double ev = vs - mp.volume, ei = is - mp.inertia[0][0];
    EXPECT_GT(ev, 0);
    EXPECT_GT(ei, 0);
    // the ratio's own error is O(h^2) too (3.90, 3.97, 3.99 for the inertia at levels 3-5):
    // it shrinks at every level and is under 0.05 from level 4 on
    if (level >= 2) {
      const double dv = std::abs(prev_v / ev - 4), di = std::abs(prev_i / ei - 4);
      if (level >= 3) { EXPECT_LT(dv, prev_dv) << "level " << level; }
      if (level >= 3) { EXPECT_LT(di, prev_di) << "level " << level; }
      if (level >= 4) { EXPECT_LT(dv, 0.05) << "level " << level; }
      if (level >= 4) { EXPECT_LT(di, 0.05) << "level " << level; }
      prev_dv = dv, prev_di = di;
    }
    // the icosahedral symmetry keeps the tensor isotropic
    EXPECT_NEAR(mp.inertia[1][1], mp.inertia[0][0], 1e-12);
    EXPECT_NEAR(mp.inertia[0][1], 0, 1e-12);
    prev_v = ev, prev_i = ei;
  }
}

TEST(CollideHull, NearCoplanarJitterStillMerges) {
  // face points moved off their plane by 1e-12 m (under the 1e-9 relative tolerance)
  std::mt19937_64 rng(23);
  std::vector<Vec3> pts = messy_box_cloud({1, 1, 1}, rng);
  std::uniform_real_distribution<double> j(-1e-12, 1e-12);
  for (Vec3& p : pts) p += Vec3(j(rng), j(rng), j(rng));
  const auto hull = ConvexHull::build(pts);
  EXPECT_EQ(hull->faces().size(), 6u);
  EXPECT_EQ(hull->vertices().size(), 8u);
  expect_valid_hull(*hull, 1e-11);
  expect_contains(*hull, pts, 1e-11);
}

TEST(CollideHull, SupportClimbEqualsBruteForce) {
  std::mt19937_64 rng(29);
  std::normal_distribution<double> g(0, 1);
  std::vector<Vec3> pts;
  for (int i = 0; i < 2000; ++i) pts.push_back(Vec3(g(rng), 2 * g(rng), 0.5 * g(rng)));
  const auto hull = ConvexHull::build(pts);
  ASSERT_GT(hull->vertices().size(), 16u);  // the climb, not the small-hull scan
  const auto v = hull->vertices();
  std::uniform_int_distribution<std::uint32_t> hint(0, static_cast<std::uint32_t>(v.size() - 1));
  for (int k = 0; k < 2000; ++k) {
    const Vec3 d(g(rng), g(rng), g(rng));
    double brute = -1e300;
    for (const Vec3& p : v) brute = std::max(brute, glm::dot(p, d));
    EXPECT_EQ(glm::dot(v[hull->support_index(d, hint(rng))], d), brute);
  }
}

TEST(CollideHull, SameCloudSameBits) {
  std::mt19937_64 rng(31);
  std::vector<Vec3> pts = messy_box_cloud({1, 2, 3}, rng);
  std::normal_distribution<double> g(0, 1);
  for (int i = 0; i < 500; ++i) pts.push_back(Vec3(g(rng), g(rng), g(rng)));
  const auto a = ConvexHull::build(pts), b = ConvexHull::build(pts);
  ASSERT_EQ(a->edges().size(), b->edges().size());
  EXPECT_EQ(hash_span(a->vertices()), hash_span(b->vertices()));
  for (std::size_t i = 0; i < a->edges().size(); ++i) {
    EXPECT_EQ(a->edges()[i].origin, b->edges()[i].origin);
    EXPECT_EQ(a->edges()[i].next, b->edges()[i].next);
  }
}

TEST(CollideHull, DegenerateCloudsThrowNamingTheInput) {
  const std::vector<Vec3> three = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_EQ(error_of([&] { ConvexHull::build(three, "rock"); }),
            "rock: a hull needs at least 4 points that are not coplanar, got 3 points");
  std::vector<Vec3> flat, line, same;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) flat.push_back(Vec3(i, 0.5 * i + 0.25 * j, j));  // the plane y = x/2 + z/4
  for (int i = 0; i < 20; ++i) line.push_back(Vec3(i, 2 * i, -i));
  for (int i = 0; i < 20; ++i) same.push_back(Vec3(1, 2, 3));
  EXPECT_EQ(error_of([&] { ConvexHull::build(flat, "rock"); }),
            "rock: a hull needs at least 4 points that are not coplanar (a solid with volume); the 100 points are "
            "coplanar (a flat cloud)");
  EXPECT_EQ(error_of([&] { ConvexHull::build(line, "rock"); }),
            "rock: a hull needs at least 4 points that are not coplanar (a solid with volume); the 20 points are "
            "collinear");
  EXPECT_EQ(error_of([&] { ConvexHull::build(same, "rock"); }),
            "rock: a hull needs at least 4 points that are not coplanar (a solid with volume); the 20 points all "
            "coincide");
  // thinner than the tolerance counts as flat
  std::vector<Vec3> thin = flat;
  thin.push_back(Vec3(3, 1.5 + 0.25 * 3 + 1e-10, 3));
  EXPECT_NE(error_of([&] { ConvexHull::build(thin, "rock"); }).find("coplanar (a flat cloud)"), std::string::npos);
  std::vector<Vec3> bad = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {kNaN, 0, 0}};
  EXPECT_EQ(error_of([&] { ConvexHull::build(bad, "rock"); }), "rock[5]: must be finite, got (nan, 0, 0)");
  bad[5] = Vec3(0, std::numeric_limits<double>::infinity(), 0);
  EXPECT_EQ(error_of([&] { ConvexHull::build(bad, "rock"); }), "rock[5]: must be finite, got (0, inf, 0)");
  // beyond a float's range (the colliders'): until 2026-12-06 a cloud spread over 1e150 m
  // was called coplanar or collinear (the plane tests' products overflowed)
  bad[5] = Vec3(0, 0, 1e150);
  EXPECT_EQ(error_of([&] { ConvexHull::build(bad, "rock"); }),
            "rock[5]: must fit a float (|component| <= 3.4028234663852886e+38), got (0, 0, 1e+150)");
  // at the range's edge the hull is built and holds its points
  std::vector<Vec3> edge;
  for (int i = 0; i < 8; ++i)
    edge.push_back(3.4e38 * Vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1));
  const auto big = ConvexHull::build(edge, "rock");
  EXPECT_EQ(big->faces().size(), 6u);
  EXPECT_EQ(big->vertices().size(), 8u);
}

}  // namespace
