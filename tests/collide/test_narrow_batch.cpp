// collide_batch(): box-box pairs several at a time in SIMD lanes give collide()'s manifolds and
// caches to the bit on every path, mixed pair types and bad input behave as collide(), and the
// batched manifolds have the penetration depth of the fifteen-axis reference.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "narrow_reference.h"
#include "pba/collide/narrow_phase.h"
#include "pba/core.h"

using namespace pba;
using pba::test_support::box_box_sat_depth;
using pba::test_support::random_rotation;
using pba::test_support::random_vec;

namespace {

// A box pair of one of the kinds the lanes must reproduce: random sizes and poses (overlapping,
// touching or apart, some beyond the bounding spheres), a box resting near-aligned on another,
// exactly aligned faces, and aligned with the world axes.
struct BoxCase {
  ColliderShape a, b;
  Pose pa, pb;
  double margin = 0;
};

BoxCase random_case(std::mt19937_64& rng, int i) {
  std::uniform_real_distribution<double> ext(0.05, 1.0), u(-1, 1);
  BoxCase c;
  const Vec3 ha(ext(rng), ext(rng), ext(rng)), hb(ext(rng), ext(rng), ext(rng));
  c.a = ColliderShape::box(ha);
  c.b = ColliderShape::box(hb);
  c.pa = {random_vec(rng, 0.2), random_rotation(rng)};
  c.margin = (i / 5) % 2 ? 0.02 : 0.0;
  switch (i % 5) {
    case 0: c.pb = {c.pa.position + random_vec(rng, 1.5), random_rotation(rng)}; break;
    case 1: {
      // resting, tilted by up to a milliradian
      const Quat tilt = glm::angleAxis(1e-3 * u(rng), glm::normalize(Vec3(u(rng), u(rng), u(rng) + 2)));
      c.pb = {c.pa.position + c.pa.rotation * Vec3(0.3 * u(rng), ha.y + hb.y + 0.01 * u(rng), 0.3 * u(rng)),
              c.pa.rotation * tilt};
      break;
    }
    case 2:
      // exactly aligned faces, overlapping by 5 mm
      c.pb = {c.pa.position + c.pa.rotation * Vec3(0.5 * u(rng), ha.y + hb.y - 0.005, 0.5 * u(rng)), c.pa.rotation};
      break;
    case 3:
      // aligned with the world axes (ties between equal separations)
      c.pa.rotation = Quat(1, 0, 0, 0);
      c.pb = {c.pa.position + Vec3(0.25 * std::round(4 * u(rng)), ha.y + hb.y - 0.01, 0), Quat(1, 0, 0, 0)};
      break;
    default: c.pb = {c.pa.position + random_vec(rng, 0.6), random_rotation(rng)}; break;
  }
  return c;
}

// every byte that matters: the count, the normal, all four points (unused ones included) and
// the sub-shape
void expect_same(const Manifold& x, const Manifold& y, const std::string& what) {
  ASSERT_EQ(x.count, y.count) << what;
  EXPECT_EQ(std::memcmp(&x.normal, &y.normal, sizeof x.normal), 0) << what;
  for (std::size_t i = 0; i < 4; ++i) {
    const ContactPoint &p = x.points[i], &q = y.points[i];
    EXPECT_EQ(std::memcmp(&p.point_a, &q.point_a, sizeof p.point_a), 0) << what << " point " << i;
    EXPECT_EQ(std::memcmp(&p.point_b, &q.point_b, sizeof p.point_b), 0) << what << " point " << i;
    EXPECT_EQ(std::memcmp(&p.depth, &q.depth, sizeof p.depth), 0) << what << " point " << i;
    EXPECT_EQ(p.id, q.id) << what << " point " << i;
  }
  EXPECT_EQ(x.sub_shape_b, y.sub_shape_b) << what;
}
void expect_same(const NarrowPhaseCache& x, const NarrowPhaseCache& y, const std::string& what) {
  EXPECT_EQ(x.sat.kind, y.sat.kind) << what;
  EXPECT_EQ(x.sat.index_a, y.sat.index_a) << what;
  EXPECT_EQ(x.sat.index_b, y.sat.index_b) << what;
}

const char* name(BatchPath p) {
  switch (p) {
    case BatchPath::Best: return "best";
    case BatchPath::Scalar: return "scalar";
    case BatchPath::Avx2: return "avx2";
    case BatchPath::Avx512: return "avx512";
  }
  return "?";
}

}  // namespace

TEST(BoxBatch, EveryPathGivesCollidesBitsAndCaches) {
  // 20 000 pairs, each twice: without a cache, and with one carried from the same pair a few
  // millimetres and a hundredth of a radian away (the cached axis may end the test early);
  // the batch runs in groups that leave partly filled lanes (20 000 is no multiple of 8 x 32)
  std::mt19937_64 rng(77);
  const int n = 20000;
  std::vector<BoxCase> cases;
  for (int i = 0; i < n; ++i) cases.push_back(random_case(rng, i));
  std::vector<NarrowPhaseCache> warm(std::size_t(n) * 2);
  for (int i = 0; i < n; ++i) {
    BoxCase& c = cases[std::size_t(i)];
    Pose moved = c.pb;
    moved.position += random_vec(rng, 0.01);
    moved.rotation = glm::normalize(moved.rotation * glm::angleAxis(0.01, glm::normalize(random_vec(rng, 1) + Vec3(0, 0, 2))));
    collide(c.a, c.pa, c.b, moved, {.speculative_margin = c.margin}, &warm[std::size_t(2 * i + 1)]);
  }
  // collide(), pair by pair
  std::vector<Manifold> expected(std::size_t(2 * n));
  std::vector<NarrowPhaseCache> expected_cache = warm;
  for (int i = 0; i < 2 * n; ++i) {
    const BoxCase& c = cases[std::size_t(i / 2)];
    expected[std::size_t(i)] = collide(c.a, c.pa, c.b, c.pb, {.speculative_margin = c.margin},
                                       i % 2 ? &expected_cache[std::size_t(i)] : nullptr);
  }
  int counts[5] = {}, edge_one = 0, edge_more = 0;
  for (const Manifold& m : expected) ++counts[m.count];
  for (int i = 1; i < 2 * n; i += 2)
    if (expected_cache[std::size_t(i)].sat.kind == SatCache::Kind::Edges && expected[std::size_t(i)].count > 0)
      ++(expected[std::size_t(i)].count == 1 ? edge_one : edge_more);
  // the kinds the lanes must get right all occur: no contact, edge contacts of one point
  // and of several (the clipped faces along the edge axis), clipped faces
  EXPECT_GT(counts[0], 2000);
  EXPECT_GT(edge_one, 100);
  EXPECT_GT(edge_more, 300);
  EXPECT_GT(counts[4], 5000);
  for (const BatchPath path : {BatchPath::Scalar, BatchPath::Avx2, BatchPath::Avx512, BatchPath::Best}) {
    std::vector<NarrowPhaseCache> cache = warm;
    std::vector<PairQuery> q;
    for (int i = 0; i < 2 * n; ++i) {
      const BoxCase& c = cases[std::size_t(i / 2)];
      q.push_back({&c.a, c.pa, &c.b, c.pb, c.margin, i % 2 ? &cache[std::size_t(i)] : nullptr});
    }
    std::vector<Manifold> out(q.size());
    collide_batch(q, out, ConvexMethod::Sat, path);
    for (int i = 0; i < 2 * n; ++i) {
      const std::string what = std::string(name(path)) + " pair " + std::to_string(i);
      expect_same(out[std::size_t(i)], expected[std::size_t(i)], what);
      expect_same(cache[std::size_t(i)], expected_cache[std::size_t(i)], what);
      if (testing::Test::HasFailure()) return;
    }
  }
}

TEST(BoxBatch, BatchedDepthIsTheFifteenAxisPenetration) {
  // overlapping random pairs: the deepest batched point is the exact penetration depth (the
  // minimum overlap over the fifteen axes) where the contact's normal is that axis (as
  // BoxBox.SatAndGjkEpaAgreeOnRandomOverlaps asks of collide(); SAT may prefer a face within
  // its hysteresis of the best axis)
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> size(0.2, 1.0);
  std::vector<ColliderShape> a, b;
  std::vector<Pose> pa, pb;
  for (int k = 0; k < 400; ++k) {
    a.push_back(ColliderShape::box(Vec3(size(rng), size(rng), size(rng))));
    b.push_back(ColliderShape::box(Vec3(size(rng), size(rng), size(rng))));
    pa.push_back({random_vec(rng, 0.2), random_rotation(rng)});
    pb.push_back({random_vec(rng, 1.2), random_rotation(rng)});
  }
  std::vector<PairQuery> q;
  for (std::size_t k = 0; k < a.size(); ++k) q.push_back({&a[k], pa[k], &b[k], pb[k], 0.0, nullptr});
  std::vector<Manifold> out(q.size());
  collide_batch(q, out);
  int checked = 0;
  for (std::size_t k = 0; k < q.size(); ++k) {
    Vec3 n(0.0);
    double second = 0;
    const double depth = box_box_sat_depth(a[k].half_extents, pa[k], b[k].half_extents, pb[k], n, second);
    if (depth <= 1e-6 || second - depth < 1e-3) continue;
    const Manifold& m = out[k];
    ASSERT_GE(m.count, 1) << k;
    double deepest = -INFINITY;
    for (int i = 0; i < m.count; ++i) deepest = std::max(deepest, m.points[std::size_t(i)].depth);
    if (glm::length(m.normal - n) < 1e-9) {
      EXPECT_NEAR(deepest, depth, 1e-9) << k;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(BoxBatch, MixedPairsAndTheGjkMethodEqualCollide) {
  // boxes among spheres, capsules and hulls, both methods: each pair is collide()'s
  std::mt19937_64 rng(8);
  const std::vector<Vec3> pts = {{-0.4, -0.3, -0.2}, {0.4, -0.3, -0.2}, {0, 0.5, -0.2}, {0, 0, 0.5}};
  const ColliderShape shapes[] = {ColliderShape::sphere(0.4), ColliderShape::capsule(0.5, 0.2),
                                  ColliderShape::box(Vec3(0.5, 0.3, 0.2)), ColliderShape::box(Vec3(0.3, 0.3, 0.6)),
                                  ColliderShape::convex(ConvexHull::build(pts, "test hull"))};
  std::vector<PairQuery> q;
  for (int k = 0; k < 2000; ++k)
    q.push_back({&shapes[k % 5], {random_vec(rng, 0.3), random_rotation(rng)}, &shapes[(k / 5) % 5],
                 {random_vec(rng, 1.0), random_rotation(rng)}, 0.02, nullptr});
  for (const ConvexMethod method : {ConvexMethod::Sat, ConvexMethod::GjkEpa}) {
    std::vector<Manifold> out(q.size());
    collide_batch(q, out, method);
    for (std::size_t k = 0; k < q.size(); ++k) {
      const Manifold m = collide(*q[k].a, q[k].pose_a, *q[k].b, q[k].pose_b, {.speculative_margin = 0.02, .method = method});
      expect_same(out[k], m, "pair " + std::to_string(k));
    }
  }
}

TEST(BoxBatch, BadInputThrowsNamingTheValue) {
  const ColliderShape a = ColliderShape::box(Vec3(0.5));
  ColliderShape bad = a;
  bad.half_extents.y = -1;
  std::vector<PairQuery> q(20, PairQuery{&a, Pose{}, &a, Pose{Vec3(0.9, 0, 0), Quat(1, 0, 0, 0)}, 0.02, nullptr});
  std::vector<Manifold> out(q.size());
  q[13].b = &bad;
  try {
    collide_batch(q, out);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("half_extents[1]"), std::string::npos) << e.what();
  }
  q[13].b = &a;
  q[7].pose_a.position.x = NAN;
  EXPECT_THROW(collide_batch(q, out), Error);
  q[7].pose_a.position.x = 0;
  q[3].margin = -1;
  EXPECT_THROW(collide_batch(q, out), Error);
  q[3].margin = 0.02;
  q[5].a = nullptr;
  EXPECT_THROW(collide_batch(q, out), Error);
  q[5].a = &a;
  std::vector<Manifold> short_out(5);
  EXPECT_THROW(collide_batch(q, short_out), Error);
  collide_batch(q, out);
  EXPECT_EQ(out[19].count, 4);
}
