// GJK and EPA against brute force: distances of random separated convex pairs against
// exact feature-pair enumeration, penetration of random overlapping box pairs against
// the fifteen-axis separating-axis test, and the stepper's invariants.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "narrow_reference.h"
#include "pba/collide/narrow_phase.h"

namespace {

using namespace pba;
using namespace pba::test_support;

ConvexProxy box_proxy(const Vec3& h, const Pose& p) {
  ConvexProxy c;
  c.type = ShapeType::Box;
  c.half_extents = h;
  c.pose = p;
  return c;
}
ConvexProxy capsule_proxy(double hh, double r, const Pose& p) {
  ConvexProxy c;
  c.type = ShapeType::Capsule;
  c.half_height = hh;
  c.radius = r;
  c.pose = p;
  return c;
}
ConvexProxy sphere_proxy(double r, const Pose& p) {
  ConvexProxy c;
  c.type = ShapeType::Sphere;
  c.radius = r;
  c.pose = p;
  return c;
}

// GJK stops when |v| - v.w/|v| <= 1e-10 m, so its distance is within 1e-10 m of the exact
// one plus rounding (~1e-15 m at these sizes); 1e-6 m is the bound, 1e-9 what GJK gives.
constexpr double kGjkTol = 1e-9;

TEST(Gjk, BoxBoxDistanceEqualsFeatureEnumeration) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> size(0.1, 1.0);
  int separated = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Vec3 ha(size(rng), size(rng), size(rng)), hb(size(rng), size(rng), size(rng));
    const Pose pa{random_vec(rng, 1.0), random_rotation(rng)}, pb{random_vec(rng, 3.0), random_rotation(rng)};
    const DistanceResult r = gjk_distance(box_proxy(ha, pa), box_proxy(hb, pb));
    if (r.cores_overlap) continue;
    ++separated;
    const double exact = box_box_distance(ha, pa, hb, pb);
    EXPECT_NEAR(r.distance, exact, kGjkTol) << "trial " << trial;
    // the closest points lie on the boxes and are the distance apart
    EXPECT_NEAR(glm::length(r.point_b - r.point_a), r.distance, kGjkTol);
    EXPECT_NEAR(point_box_distance(r.point_a, ha, pa), 0.0, 1e-9);
    EXPECT_NEAR(point_box_distance(r.point_b, hb, pb), 0.0, 1e-9);
    EXPECT_LT(r.iterations, GjkStepper::kMaxIterations);
  }
  EXPECT_GT(separated, 200);  // the sample mostly exercises separated pairs
}

TEST(Gjk, CapsuleBoxAndSphereBoxDistancesEqualBruteForce) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> size(0.1, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Vec3 hb(size(rng), size(rng), size(rng));
    const double hh = size(rng), r = 0.5 * size(rng);
    const Pose pa{random_vec(rng, 3.0), random_rotation(rng)}, pb{random_vec(rng, 1.0), random_rotation(rng)};
    const Vec3 u = pa.rotation * Vec3(0, hh, 0);
    const double core = segment_box_distance(pa.position - u, pa.position + u, hb, pb);
    if (core == 0) continue;
    ++checked;
    const DistanceResult c = gjk_distance(capsule_proxy(hh, r, pa), box_proxy(hb, pb));
    ASSERT_FALSE(c.cores_overlap);
    EXPECT_NEAR(c.core_distance, core, kGjkTol) << "trial " << trial;
    EXPECT_NEAR(c.distance, std::max(0.0, core - r), kGjkTol);
    const DistanceResult s = gjk_distance(sphere_proxy(r, pa), box_proxy(hb, pb));
    const double ps = point_box_distance(pa.position, hb, pb);
    if (ps > 0) {
      EXPECT_NEAR(s.distance, std::max(0.0, ps - r), kGjkTol);
    }
  }
  EXPECT_GT(checked, 200);
}

TEST(Gjk, StepperDescendsMonotonicallyAndMatchesTheSolver) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 100; ++trial) {
    const Pose pa{random_vec(rng, 1.0), random_rotation(rng)}, pb{random_vec(rng, 4.0), random_rotation(rng)};
    const ConvexProxy a = box_proxy(Vec3(0.5, 0.3, 0.2), pa), b = capsule_proxy(0.4, 0.1, pb);
    GjkStepper g(a, b);
    double last = glm::length(g.closest());
    while (g.step()) {
      // each iteration moves the estimate strictly closer to the origin (van den Bergen 2003)
      const double now = glm::length(g.closest());
      EXPECT_LT(now, last);
      last = now;
      ASSERT_GE(g.simplex().size(), 1u);
      ASSERT_LE(g.simplex().size(), 4u);
      // the simplex points are support points of A - B
      for (const SimplexVertex& v : g.simplex()) EXPECT_EQ(v.w, v.a - v.b);
    }
    const DistanceResult r = gjk_distance(a, b);
    EXPECT_EQ(r.cores_overlap, g.overlap());
    if (!g.overlap()) {
      EXPECT_EQ(glm::length(g.closest()), r.core_distance);
    }
  }
}

// GjkStepper::run() inlines each proxy kind's support (and keeps the world points of the
// vertices it found), as the constructor does for the first vertex, and must give the plain
// step() loop's run (ConvexProxy::support each iteration) to the bit: the same iterations,
// simplex (support points, weights, vertex indices), closest point and bounds. Every pair of
// kinds, at random poses and at axis-aligned ones on a grid (directions with zero coordinates,
// whose signs a turn by the identity may flip), with triangles in the mesh's own frame, only
// moved (a position with and without a zero coordinate) and turned; hulls of 5 and 12 vertices
// (a vertex index past the 8 the run keeps).
TEST(Gjk, RunGivesTheStepLoopsBitsForEveryKind) {
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> size(0.2, 1.0), unit(0.0, 1.0);
  const Vec3 apex[5] = {{0, 1, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 0, 1}, {0, 0, -1}};
  const auto pyramid = ConvexHull::build(apex, "pyramid");
  std::vector<Vec3> ring;
  for (int k = 0; k < 6; ++k) {
    const double t = k * 3.14159265358979 / 3;
    ring.push_back({0.6 * std::cos(t), -0.4, 0.6 * std::sin(t)});
    ring.push_back({0.4 * std::cos(t + 0.5), 0.4, 0.4 * std::sin(t + 0.5)});
  }
  const auto prism = ConvexHull::build(ring, "prism");
  ASSERT_EQ(prism->vertices().size(), 12u);
  const Vec3 tri[3] = {{-0.7, 0.1, -0.4}, {0.8, -0.2, 0.0}, {0.1, 0.3, 0.9}};
  auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  auto same = [&](const Vec3& a, const Vec3& b) {
    return bits(a.x) == bits(b.x) && bits(a.y) == bits(b.y) && bits(a.z) == bits(b.z);
  };
  constexpr int kKinds = 9;  // sphere, capsule, box, pyramid, prism, triangle at 0 / moved / moved to a 0 / turned
  auto proxy = [&](int kind, const Pose& pose) {
    ConvexProxy c;
    c.pose = pose;
    switch (kind) {
      case 0: c = sphere_proxy(size(rng), pose); break;
      case 1: c = capsule_proxy(size(rng), 0.3 * size(rng), pose); break;
      case 2: c = box_proxy(Vec3(size(rng), size(rng), size(rng)), pose); break;
      case 3: c.type = ShapeType::Hull, c.hull = pyramid.get(); break;
      case 4: c.type = ShapeType::Hull, c.hull = prism.get(); break;
      default:
        c.type = ShapeType::Mesh;
        c.triangle = tri;
        if (kind == 5) c.pose = Pose{};
        else if (kind == 6 || kind == 7) c.pose.rotation = Quat(1, 0, 0, 0);
        if (kind == 7) c.pose.position.y = 0;
        break;
    }
    return c;
  };
  int runs = 0, overlaps = 0, zeros = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const int ka = int(trial % kKinds), kb = int((trial / kKinds) % kKinds);
    // a third of the trials on a grid, unturned: supports along directions with zero coordinates
    const bool grid = unit(rng) < 0.33;
    auto pose = [&](double s) {
      if (!grid) return Pose{random_vec(rng, s), random_rotation(rng)};
      return Pose{glm::round(random_vec(rng, s)), Quat(1, 0, 0, 0)};
    };
    const ConvexProxy a = proxy(ka, pose(1.0)), b = proxy(kb, pose(2.5));
    GjkStepper stepped(a, b), ran(a, b);
    {
      // the first vertex (the constructor's, kinds inlined too): support() along the line
      // between the centres
      Vec3 d = a.pose.position - b.pose.position;
      if (glm::dot(d, d) == 0) d = Vec3(1, 0, 0);
      std::uint32_t ia = 0, ib = 0;
      const Vec3 sa = a.support(-d, &ia), sb = b.support(d, &ib);
      const SimplexVertex& first = stepped.simplex()[0];
      ASSERT_TRUE(same(first.a, sa) && same(first.b, sb)) << "trial " << trial << ", kinds " << ka << " " << kb;
      ASSERT_EQ(first.index_a, ia);
      ASSERT_EQ(first.index_b, ib);
    }
    while (stepped.step()) {
    }
    ran.run();
    ++runs;
    overlaps += stepped.overlap();
    // (an overlap's closest point is the origin: only an apart run's counts)
    const Vec3 v = stepped.closest();
    zeros += !stepped.overlap() && (v.x == 0 || v.y == 0 || v.z == 0);
    ASSERT_EQ(ran.iterations(), stepped.iterations()) << "trial " << trial << ", kinds " << ka << " " << kb;
    ASSERT_EQ(ran.overlap(), stepped.overlap()) << "trial " << trial;
    ASSERT_TRUE(ran.done());
    ASSERT_TRUE(same(ran.closest(), stepped.closest())) << "trial " << trial << ", kinds " << ka << " " << kb;
    ASSERT_EQ(bits(ran.gap()), bits(stepped.gap())) << "trial " << trial;
    ASSERT_EQ(ran.simplex().size(), stepped.simplex().size()) << "trial " << trial;
    for (std::size_t i = 0; i < ran.simplex().size(); ++i) {
      const SimplexVertex &p = ran.simplex()[i], &q = stepped.simplex()[i];
      ASSERT_TRUE(same(p.a, q.a) && same(p.b, q.b) && same(p.w, q.w)) << "trial " << trial << ", vertex " << i;
      ASSERT_EQ(bits(p.weight), bits(q.weight)) << "trial " << trial;
      ASSERT_EQ(p.index_a, q.index_a) << "trial " << trial;
      ASSERT_EQ(p.index_b, q.index_b) << "trial " << trial;
    }
    const SimplexVertex &p = ran.last_support(), &q = stepped.last_support();
    ASSERT_TRUE(same(p.a, q.a) && same(p.b, q.b)) << "trial " << trial;
  }
  EXPECT_EQ(runs, 3000);
  EXPECT_GT(overlaps, 100);  // both ends of the run: touching cores ...
  EXPECT_LT(overlaps, 2500);  // ... and apart
  EXPECT_GT(zeros, 100);      // apart along directions with zero coordinates
}

// EPA stops when the support distance along the nearest face's normal exceeds the face
// distance by <= kEpaTolerance (1e-10 m): the face distance is a lower bound of the depth
// (the polytope lies inside A - B) and the support distance an upper bound, so the depth
// is within 1e-10 m; 1e-9 m adds room for rounding. The normal is the normal of the face
// EPA stops on, which for boxes is a face of A - B, i.e. the SAT axis; rounding in its
// cross product is ~1e-14, and 1e-7 covers nearly flat faces.
TEST(Epa, BoxBoxDepthAndNormalEqualSeparatingAxes) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> size(0.2, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const Vec3 ha(size(rng), size(rng), size(rng)), hb(size(rng), size(rng), size(rng));
    const Pose pa{random_vec(rng, 0.2), random_rotation(rng)}, pb{random_vec(rng, 1.2), random_rotation(rng)};
    Vec3 n_sat(0.0);
    double second = 0;
    const double depth = box_box_sat_depth(ha, pa, hb, pb, n_sat, second);
    if (depth <= 1e-6) continue;
    const PenetrationResult e = epa_penetration(box_proxy(ha, pa), box_proxy(hb, pb));
    ASSERT_TRUE(e.ok) << "trial " << trial;
    ++checked;
    EXPECT_NEAR(e.depth, depth, 1e-9) << "trial " << trial;
    // the normal is unique only when the best axis beats the next one
    if (second - depth > 1e-6) {
      EXPECT_NEAR(glm::length(e.normal - n_sat), 0.0, 1e-7) << "trial " << trial;
    }
    // moving B by depth along the normal leaves the boxes touching: the points agree
    EXPECT_NEAR(glm::dot(e.point_a - e.point_b, e.normal), e.depth, 1e-9);
  }
  EXPECT_GT(checked, 200);
}

TEST(Epa, SphereAndCapsuleCoresAddTheirRadii) {
  // a sphere whose centre is 0.1 m inside a box face: depth r + 0.1, normal the face's
  const Pose pb{};
  const Pose pa{Vec3(0, 0.4, 0), Quat(1, 0, 0, 0)};
  const PenetrationResult e = epa_penetration(sphere_proxy(0.25, pa), box_proxy(Vec3(1, 0.5, 1), pb));
  ASSERT_TRUE(e.ok);
  EXPECT_NEAR(e.depth, 0.35, 1e-9);
  EXPECT_NEAR(glm::length(e.normal - Vec3(0, -1, 0)), 0.0, 1e-9);
}

// GJK and EPA do not check their input for finiteness (shapes and poses are checked where
// they are made: ColliderShape, ConvexHull::build, the bodies' and colliders' poses). What
// they must not do with a NaN is hang: a triangle of NaN points (every support point NaN, so
// the simplex grows to a tetrahedron of NaN points), a box at a NaN pose, and cores far past
// the doubles' range (1e300 m, whose differences are infinite) each end within the iteration
// caps, stepped one iteration at a time or run, and EPA after them within its vertex cap
// (128); the answer is documented as meaningless (narrow_phase.h, gjk_distance).
TEST(Gjk, NonFiniteCoresEndWithinTheIterationCaps) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vec3 nan_tri[3] = {{nan, 0, 0}, {0, nan, 0}, {0, 0, nan}};
  const Vec3 far_tri[3] = {{1e300, 0, 0}, {-1e300, 1e300, 0}, {0, -1e300, 1e300}};
  ConvexProxy nan_triangle, far_triangle;
  nan_triangle.type = far_triangle.type = ShapeType::Mesh;
  nan_triangle.triangle = nan_tri, far_triangle.triangle = far_tri;
  const ConvexProxy box = box_proxy(Vec3(0.5), Pose{});
  const ConvexProxy cases[] = {nan_triangle, far_triangle, box_proxy(Vec3(0.5), Pose{Vec3(nan, 0, 0)}),
                               box_proxy(Vec3(1e300), Pose{Vec3(1e300, 0, 0)}),
                               sphere_proxy(0.5, Pose{Vec3(0, nan, 0)})};
  int k = 0;
  for (const ConvexProxy& other : cases) {
    for (const bool swap : {false, true}) {
      const ConvexProxy& a = swap ? other : box;
      const ConvexProxy& b = swap ? box : other;
      const DistanceResult d = gjk_distance(a, b);
      EXPECT_LE(d.iterations, GjkStepper::kMaxIterations) << "case " << k << (swap ? " swapped" : "");
      GjkStepper g(a, b);
      int steps = 0;
      while (steps <= GjkStepper::kMaxIterations && g.step()) ++steps;
      EXPECT_TRUE(g.done()) << "case " << k << (swap ? " swapped" : "");
      EXPECT_LE(g.iterations(), GjkStepper::kMaxIterations) << "case " << k;
      const PenetrationResult e = epa_penetration(a, b);
      EXPECT_LE(e.iterations, 128) << "case " << k << (swap ? " swapped" : "");
    }
    ++k;
  }
}

}  // namespace
