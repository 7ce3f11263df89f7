// Hull pairs: GJK distance against vertex-face and edge-edge enumeration, EPA and SAT depth
// against the minimum overlap over every face normal and edge-pair cross product, and a
// hull of a box colliding like the box.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <vector>

#include "narrow_reference.h"
#include "pba/collide/narrow_phase.h"

namespace {

using namespace pba;
using namespace pba::test_support;

// a random convex hull: 12-30 points on a squashed ellipsoid, jittered inwards
std::shared_ptr<const ConvexHull> random_hull(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.2, 0.8), s(0.7, 1.0);
  std::uniform_int_distribution<int> count(12, 30);
  const Vec3 axes(u(rng), u(rng), u(rng));
  std::vector<Vec3> pts(std::size_t(count(rng)));
  for (Vec3& p : pts) {
    Vec3 d = random_vec(rng, 1.0);
    while (glm::length(d) < 1e-3) d = random_vec(rng, 1.0);
    p = glm::normalize(d) * axes * s(rng);
  }
  return ConvexHull::build(pts, "test hull");
}

// the world vertices and the (even) half edges' end points of a hull at a pose
struct WorldHull {
  std::vector<Vec3> v;
  std::vector<std::pair<Vec3, Vec3>> edges;
  std::vector<std::pair<Vec3, double>> planes;  // world normal and offset per face
  std::vector<std::vector<Vec3>> faces;         // world face loops
};
WorldHull world(const ConvexHull& h, const Pose& p) {
  WorldHull w;
  for (const Vec3& x : h.vertices()) w.v.push_back(apply(p, x));
  const auto e = h.edges();
  for (std::size_t i = 0; i < e.size(); i += 2) w.edges.push_back({w.v[e[i].origin], w.v[e[i + 1].origin]});
  for (const auto& f : h.faces()) {
    const Vec3 n = p.rotation * f.normal;
    w.planes.push_back({n, f.offset + glm::dot(n, p.position)});
    std::vector<Vec3> loop;
    std::uint32_t k = f.edge;
    do {
      loop.push_back(w.v[e[k].origin]);
      k = e[k].next;
    } while (k != f.edge);
    w.faces.push_back(loop);
  }
  return w;
}

// distance from x to a convex face when its projection falls inside the face, else inf
double point_face(const Vec3& x, const Vec3& n, double off, const std::vector<Vec3>& loop) {
  const Vec3 q = x - (glm::dot(n, x) - off) * n;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Vec3 a = loop[i], b = loop[(i + 1) % loop.size()];
    if (glm::dot(glm::cross(b - a, q - a), n) < 0) return INFINITY;
  }
  return std::abs(glm::dot(n, x) - off);
}

// exact distance of separated polytopes: vertex-face and edge-edge pairs (edge-edge
// includes the vertex-vertex and vertex-edge pairs through the segments' end points)
double hull_distance(const WorldHull& a, const WorldHull& b) {
  double best = INFINITY;
  for (const Vec3& x : a.v)
    for (std::size_t f = 0; f < b.faces.size(); ++f)
      best = std::min(best, point_face(x, b.planes[f].first, b.planes[f].second, b.faces[f]));
  for (const Vec3& x : b.v)
    for (std::size_t f = 0; f < a.faces.size(); ++f)
      best = std::min(best, point_face(x, a.planes[f].first, a.planes[f].second, a.faces[f]));
  for (const auto& ea : a.edges)
    for (const auto& eb : b.edges) best = std::min(best, segment_distance(ea.first, ea.second, eb.first, eb.second));
  return best;
}

// overlap of the vertex sets along L when B moves along +L to separate
double overlap(const WorldHull& a, const WorldHull& b, const Vec3& L) {
  double amax = -INFINITY, bmin = INFINITY;
  for (const Vec3& x : a.v) amax = std::max(amax, glm::dot(x, L));
  for (const Vec3& x : b.v) bmin = std::min(bmin, glm::dot(x, L));
  return amax - bmin;
}

// exact penetration depth: the minimum over every face normal (both signs) and every
// edge-pair cross product of the overlap; the minimum over all directions is attained at
// a face normal of A - B, and those are among the candidates
double hull_depth(const WorldHull& a, const WorldHull& b, Vec3& normal) {
  double best = INFINITY;
  auto test = [&](const Vec3& L) {
    for (const Vec3& d : {L, -L}) {
      const double o = overlap(a, b, d);
      if (o < best) best = o, normal = d;
    }
  };
  for (const auto& p : a.planes) test(p.first);
  for (const auto& p : b.planes) test(p.first);
  for (const auto& ea : a.edges)
    for (const auto& eb : b.edges) {
      const Vec3 c = glm::cross(ea.second - ea.first, eb.second - eb.first);
      if (glm::length(c) > 1e-9) test(glm::normalize(c));
    }
  return best;
}

TEST(HullPairs, GjkDistanceEqualsFeatureEnumeration) {
  std::mt19937_64 rng(21);
  int checked = 0;
  for (int trial = 0; trial < 150; ++trial) {
    const auto ha = random_hull(rng), hb = random_hull(rng);
    const Pose pa{random_vec(rng, 0.5), random_rotation(rng)}, pb{random_vec(rng, 2.0), random_rotation(rng)};
    const DistanceResult r = gjk_distance(ConvexProxy::of(ColliderShape::convex(ha), pa),
                                          ConvexProxy::of(ColliderShape::convex(hb), pb));
    if (r.cores_overlap) continue;
    ++checked;
    // GJK's stopping gap is 1e-10 m (see test_gjk.cpp)
    EXPECT_NEAR(r.distance, hull_distance(world(*ha, pa), world(*hb, pb)), 1e-9) << trial;
  }
  EXPECT_GT(checked, 60);
}

TEST(HullPairs, EpaAndSatDepthEqualTheMinimumOverlap) {
  std::mt19937_64 rng(22);
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const auto ha = random_hull(rng), hb = random_hull(rng);
    const Pose pa{random_vec(rng, 0.2), random_rotation(rng)}, pb{random_vec(rng, 0.8), random_rotation(rng)};
    const WorldHull wa = world(*ha, pa), wb = world(*hb, pb);
    Vec3 n(0.0);
    const double depth = hull_depth(wa, wb, n);
    if (depth <= 1e-6) continue;
    ++checked;
    const ColliderShape a = ColliderShape::convex(ha), b = ColliderShape::convex(hb);
    // EPA: within its 1e-10 m stopping gap plus rounding
    const PenetrationResult e = epa_penetration(ConvexProxy::of(a, pa), ConvexProxy::of(b, pb));
    ASSERT_TRUE(e.ok);
    EXPECT_NEAR(e.depth, depth, 1e-9) << trial;
    // SAT: the least separated axis is the depth; a face is kept over a better edge axis
    // (A's over B's) within Gregorius's hysteresis, relative 0.9 (0.98) plus 2.5 mm, so the
    // chosen axis's overlap lies in [depth, ((depth + 2.5 mm) / 0.9 + 2.5 mm) / 0.98]
    const Manifold m = collide(a, pa, b, pb);
    ASSERT_GE(m.count, 1) << trial;
    double deepest = -INFINITY;
    for (int i = 0; i < m.count; ++i) deepest = std::max(deepest, m.points[std::size_t(i)].depth);
    const double axis_overlap = overlap(wa, wb, m.normal);
    EXPECT_GE(axis_overlap, depth - 1e-9) << trial;
    EXPECT_LE(axis_overlap, ((depth + 0.0025) / 0.9 + 0.0025) / 0.98 + 1e-9) << trial;
    EXPECT_LE(deepest, axis_overlap + 1e-9) << trial;
  }
  EXPECT_GT(checked, 100);
}

TEST(HullPairs, HullOfABoxCollidesLikeTheBox) {
  std::mt19937_64 rng(23);
  const Vec3 h(0.5, 0.3, 0.4);
  const Vec3 g(0.3, 0.6, 0.2);
  const ColliderShape as_box = ColliderShape::box(h), as_hull = ColliderShape::convex(ConvexHull::box(h));
  const ColliderShape other_box = ColliderShape::box(g), other_hull = ColliderShape::convex(ConvexHull::box(g));
  int contacts = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Pose pa{random_vec(rng, 0.2), random_rotation(rng)}, pb{random_vec(rng, 1.0), random_rotation(rng)};
    const Manifold mb = collide(as_box, pa, other_box, pb), mh = collide(as_hull, pa, other_hull, pb);
    ASSERT_EQ(mb.count, mh.count) << trial;
    if (mb.count == 0) continue;
    ++contacts;
    EXPECT_NEAR(glm::length(mb.normal - mh.normal), 0.0, 1e-12);
    double db = -INFINITY, dh = -INFINITY;
    for (int i = 0; i < mb.count; ++i) db = std::max(db, mb.points[std::size_t(i)].depth);
    for (int i = 0; i < mh.count; ++i) dh = std::max(dh, mh.points[std::size_t(i)].depth);
    EXPECT_NEAR(db, dh, 1e-12);
  }
  EXPECT_GT(contacts, 50);
}

}  // namespace

namespace {

// the box-box path (closed-form axes, clipping in the reference face's 2D coordinates)
// against the polyhedral path on the hulls of the same boxes: the same normal and, point for
// point (matched by position: the hull numbers its half edges its own way, so the ids
// differ), the same surface points and depths, to rounding (1e-12 m at metre scale, ~1e4
// ulps), on random poses, sizes and margins, overlapping and within the margin. The one
// exception: when the clipped polygon has more than four points and two of them span the
// same triangle area with the deepest and farthest points to rounding (an incident edge
// parallel to that pair), the reduction's choice between them is rounding's; such pairs are
// counted (a handful in 3000) and still have the same normal and deepest depth. The box
// path's ids are distinct within each manifold.
TEST(BoxPath, EqualsThePolyhedralPathPointForPoint) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> size(0.05, 1.0), margin(0.0, 0.05);
  int compared = 0, multi = 0, ties = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Vec3 ha(size(rng), size(rng), size(rng)), hb(size(rng), size(rng), size(rng));
    const Pose pa{random_vec(rng, 0.3), random_rotation(rng)}, pb{random_vec(rng, 1.5), random_rotation(rng)};
    NarrowPhaseSettings set;
    set.speculative_margin = margin(rng);
    const Manifold mb = collide(ColliderShape::box(ha), pa, ColliderShape::box(hb), pb, set);
    const Manifold mh = collide(ColliderShape::convex(ConvexHull::box(ha)), pa, ColliderShape::convex(ConvexHull::box(hb)),
                                pb, set);
    ASSERT_EQ(mb.count, mh.count) << trial;
    if (mb.count == 0) continue;
    ++compared;
    multi += mb.count > 1;
    EXPECT_NEAR(glm::length(mb.normal - mh.normal), 0.0, 1e-12) << trial;
    double db = -INFINITY, dh = -INFINITY;
    for (int i = 0; i < mb.count; ++i) db = std::max(db, mb.points[std::size_t(i)].depth);
    for (int i = 0; i < mh.count; ++i) dh = std::max(dh, mh.points[std::size_t(i)].depth);
    EXPECT_NEAR(db, dh, 1e-12) << trial;
    bool all_matched = true;
    for (int i = 0; i < mb.count; ++i) {
      const ContactPoint& p = mb.points[std::size_t(i)];
      for (int j = 0; j < i; ++j) EXPECT_NE(mb.points[std::size_t(j)].id, p.id) << trial;
      int match = -1;
      for (int j = 0; j < mh.count; ++j)
        if (glm::length(mh.points[std::size_t(j)].point_b - p.point_b) < 1e-9) match = j;
      if (match < 0) {
        all_matched = false;
        continue;
      }
      const ContactPoint& q = mh.points[std::size_t(match)];
      EXPECT_NEAR(glm::length(p.point_a - q.point_a), 0.0, 1e-12) << trial;
      EXPECT_NEAR(glm::length(p.point_b - q.point_b), 0.0, 1e-12) << trial;
      EXPECT_NEAR(p.depth, q.depth, 1e-12) << trial;
    }
    if (!all_matched) {
      EXPECT_EQ(mb.count, 4) << trial;  // only a reduction chooses
      ++ties;
    }
  }
  std::printf("[          ] %d manifolds compared, %d with several points, %d reduction ties\n", compared, multi, ties);
  EXPECT_GT(compared, 500);
  EXPECT_GT(multi, 300);
  EXPECT_LE(ties, 5);
}

// an edge contact's face points within the margin (B's face clipped along the edge axis by
// A's face's sides) are a gap for the solver to close along the normal within a step: a
// closing of that gap along the normal, or along A's face normal, the face's own approach,
// brings no point into A. So each point's gap is at most its true distance to A, and at most
// its gap to A's face plane times the cosine between the normals (closing g along n is
// g / cosine along the face normal; measured along n to the plane, the gap overstated the
// true distance up to sqrt 2 and let a face sink gap (1 / cosine^2 - 1) into A). Box and
// hull paths alike.
TEST(BoxPath, EdgeContactGapsNeverOverstateTheDistanceToA) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> size(0.1, 1.1);
  int speculative = 0;
  double closest = INFINITY;  // the least ratio of the true distance to the gap
  for (int trial = 0; trial < 20000; ++trial) {
    const Vec3 ha(size(rng), size(rng), size(rng)), hb(size(rng), size(rng), size(rng));
    const Pose pa{Vec3(0.0), random_rotation(rng)}, pb{random_vec(rng, 1.5), random_rotation(rng)};
    const NarrowPhaseSettings set{.speculative_margin = 0.1};
    for (const bool hull : {false, true}) {
      NarrowPhaseCache cache;
      const Manifold m = hull ? collide(ColliderShape::convex(ConvexHull::box(ha)), pa,
                                        ColliderShape::convex(ConvexHull::box(hb)), pb, set, &cache)
                              : collide(ColliderShape::box(ha), pa, ColliderShape::box(hb), pb, set, &cache);
      if (cache.sat.kind != SatCache::Kind::Edges || m.count < 2) continue;
      // A's face most parallel to the normal: its plane and the cosine
      const Mat3 ra = glm::mat3_cast(pa.rotation);
      int axis = 0;
      for (int k = 1; k < 3; ++k)
        if (std::abs(glm::dot(ra[k], m.normal)) > std::abs(glm::dot(ra[axis], m.normal))) axis = k;
      const double cosine = std::abs(glm::dot(ra[axis], m.normal));
      const Vec3 face_normal = ra[axis] * (glm::dot(ra[axis], m.normal) > 0 ? 1.0 : -1.0);
      for (int i = 0; i < m.count; ++i) {
        const ContactPoint& p = m.points[std::size_t(i)];
        if (!(p.depth < -1e-9)) continue;
        ++speculative;
        const double gap = -p.depth, dist = point_box_distance(p.point_b, ha, pa);
        const double plane_gap = glm::dot(p.point_b - pa.position, face_normal) - ha[axis];
        EXPECT_LE(gap, dist + 1e-12) << trial << " hull " << hull << " point " << i;
        // the edges' closest points (point_a on A) are at their true distance; the face points
        if (point_box_distance(p.point_a, ha, pa) > 1e-9)
          EXPECT_LE(gap, plane_gap * cosine + 1e-12) << trial << " hull " << hull << " point " << i;
        closest = std::min(closest, dist / gap);
      }
    }
  }
  std::printf("[          ] %d speculative edge-contact points, least distance / gap %.3f\n", speculative, closest);
  EXPECT_GT(speculative, 1000);
}

}  // namespace

namespace {

// the SAT cache carried between frames changes nothing but the work: along a slow path in
// and out of contact, turning, box-hull (both orders: the cache's A and B
// follow the caller's) and hull-hull give the manifold the uncached call gives, bit for bit
TEST(HullPairs, CachedFeatureGivesTheSameManifold) {
  std::mt19937_64 rng(24);
  const auto ha = random_hull(rng), hb = random_hull(rng);
  const ColliderShape box = ColliderShape::box(Vec3(0.4, 0.25, 0.3));
  const ColliderShape a = ColliderShape::convex(ha), b = ColliderShape::convex(hb);
  const std::pair<const ColliderShape*, const ColliderShape*> pairs[] = {{&a, &b}, {&box, &b}, {&b, &box}};
  int touching = 0;
  for (const auto& [sa, sb] : pairs) {
    NarrowPhaseCache cache;
    const Pose pa{Vec3(0), Quat(1, 0, 0, 0)};
    Pose pb{Vec3(1.6, 0, 0), random_rotation(rng)};
    for (int k = 0; k < 400; ++k) {
      // in and out of contact along x, with a wobble
      pb.position = Vec3(1.4 * std::cos(0.03 * k), 0.2 * std::sin(0.07 * k), 0.1) + random_vec(rng, 0.01);
      pb.rotation = glm::normalize(glm::angleAxis(0.05, glm::normalize(random_vec(rng, 1.0) + Vec3(1e-9))) * pb.rotation);
      const Manifold c = collide(*sa, pa, *sb, pb, {}, &cache);
      const Manifold u = collide(*sa, pa, *sb, pb);
      ASSERT_EQ(c.count, u.count) << k;
      touching += c.count > 0;
      EXPECT_EQ(c.normal, u.normal) << k;
      for (int i = 0; i < c.count; ++i) {
        EXPECT_EQ(c.points[std::size_t(i)].id, u.points[std::size_t(i)].id) << k;
        EXPECT_EQ(c.points[std::size_t(i)].point_a, u.points[std::size_t(i)].point_a) << k;
        EXPECT_EQ(c.points[std::size_t(i)].depth, u.points[std::size_t(i)].depth) << k;
      }
    }
  }
  EXPECT_GT(touching, 200);
}

}  // namespace

namespace {

// a prism of `sides` around y: pairs of parallel edges everywhere (degenerate edge pairs)
std::shared_ptr<const ConvexHull> prism(int sides, double r, double h) {
  std::vector<Vec3> pts;
  for (int i = 0; i < sides; ++i) {
    const double t = 2 * kPi * i / sides;
    pts.push_back({r * std::cos(t), -h, r * std::sin(t)});
    pts.push_back({r * std::cos(t), h, r * std::sin(t)});
  }
  return ConvexHull::build(pts, "prism");
}

// a hull of n points on an ellipsoid of the given semi-axes
std::shared_ptr<const ConvexHull> ellipsoid_hull(std::mt19937_64& rng, int n, const Vec3& axes) {
  std::vector<Vec3> pts(std::size_t(n), Vec3(0.0));
  for (Vec3& p : pts) {
    Vec3 d = random_vec(rng, 1.0);
    while (glm::length(d) < 1e-3) d = random_vec(rng, 1.0);
    p = glm::normalize(d) * axes;
  }
  return ConvexHull::build(pts, "ellipsoid hull");
}

}  // namespace

// the pruning data: closed forms for a box and a regular tetrahedron, and the column
// layouts against faces() and edges()
TEST(HullShape, RadiiArcSecantsAndColumns) {
  const auto box = ConvexHull::box(Vec3(0.5, 0.3, 0.2));
  EXPECT_NEAR(box->inner_radius(), 0.2, 1e-15);
  EXPECT_NEAR(box->outer_radius(), std::sqrt(0.25 + 0.09 + 0.04), 1e-15);
  const auto be = box->edge_soa();
  ASSERT_EQ(be.size(), 10 * 12u);
  for (std::size_t i = 0; i < 12; ++i) EXPECT_NEAR(be[9 * 12 + i], std::sqrt(2.0), 1e-15);  // right angles
  // regular tetrahedron of circumradius sqrt(3): inradius a third of it; faces meet at
  // arccos(1/3), so their normals at u . v = -1/3 and the secant sqrt(2 / (2 / 3))
  const std::vector<Vec3> t = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  const auto tet = ConvexHull::build(t, "tetrahedron");
  EXPECT_NEAR(tet->inner_radius(), std::sqrt(3.0) / 3, 1e-14);
  EXPECT_NEAR(tet->outer_radius(), std::sqrt(3.0), 1e-14);
  const auto te = tet->edge_soa();
  ASSERT_EQ(te.size(), 10 * 6u);
  for (std::size_t i = 0; i < 6; ++i) EXPECT_NEAR(te[9 * 6 + i], std::sqrt(3.0), 1e-14);
  // columns of a random hull (odd counts are padded with the last entry)
  std::mt19937_64 rng(31);
  const auto h = random_hull(rng);
  const auto f = h->faces();
  const auto fs = h->face_soa();
  const std::size_t pf = fs.size() / 4;
  ASSERT_EQ(pf, f.size() + (f.size() & 1));
  for (std::size_t i = 0; i < pf; ++i) {
    const auto& F = f[std::min(i, f.size() - 1)];
    EXPECT_EQ(Vec3(fs[i], fs[pf + i], fs[2 * pf + i]), F.normal);
    EXPECT_EQ(fs[3 * pf + i], F.offset);
  }
  const auto e = h->edges();
  const auto es = h->edge_soa();
  const std::size_t ne = e.size() / 2, pe = es.size() / 10;
  ASSERT_EQ(pe, ne + (ne & 1));
  for (std::size_t i = 0; i < ne; ++i) {
    const Vec3 u = f[e[2 * i].face].normal, v = f[e[2 * i + 1].face].normal;
    EXPECT_EQ(Vec3(es[i], es[pe + i], es[2 * pe + i]), u);
    EXPECT_EQ(Vec3(es[3 * pe + i], es[4 * pe + i], es[5 * pe + i]), v);
    EXPECT_EQ(Vec3(es[6 * pe + i], es[7 * pe + i], es[8 * pe + i]), h->vertices()[e[2 * i].origin]);
    EXPECT_NEAR(es[9 * pe + i], 1 / std::cos(0.5 * std::acos(std::clamp(glm::dot(u, v), -1.0, 1.0))), 1e-9);
    // the bound it gives: a unit vector on the arc from u to v, along any w, does not
    // exceed the larger of u . w and v . w times the secant (that alone when <= 0)
    for (int k = 0; k <= 8; ++k) {
      const Vec3 n = glm::normalize(u * double(8 - k) + v * double(k));
      const Vec3 w = random_vec(rng, 1.0);
      const double m = std::max(glm::dot(u, w), glm::dot(v, w));
      EXPECT_LE(glm::dot(n, w), (m > 0 ? m * es[9 * pe + i] : m) + 1e-12);
    }
  }
  // the balls: every vertex within the outer radius, every face plane beyond the inner
  for (const Vec3& p : h->vertices()) EXPECT_LE(glm::length(p - h->centroid()), h->outer_radius() + 1e-15);
  for (const auto& F : f) EXPECT_GE(F.offset - glm::dot(F.normal, h->centroid()), h->inner_radius());
  EXPECT_GT(h->inner_radius(), 0.0);
}

// SAT skips faces and edge pairs by bounds: the axis it picks must be the one a search of
// every face and every edge pair picks under the same rules (the least separated of A's
// faces, B's faces and the edge pairs' cross products; edges only when better than
// 0.9 x the best face + 2.5 mm, B's face only when better than 0.98 x A's + 2.5 mm).
// Hulls from 4 to 90 points (the vertex scan and the hill climb, the edge query's gathered
// columns and its plain loop beyond 256 edges), prisms and boxes with parallel edges,
// thin slabs (small inner radii), equal rotations (parallel edges and faces).
TEST(HullPairs, SatAxisEqualsTheSearchOfEveryFeature) {
  std::mt19937_64 rng(25);
  std::vector<std::shared_ptr<const ConvexHull>> hulls = {
      prism(3, 0.4, 0.3), prism(6, 0.35, 0.25), prism(16, 0.4, 0.2), ConvexHull::box(Vec3(0.5, 0.3, 0.2)),
      ConvexHull::box(Vec3(0.7, 0.03, 0.6)), ellipsoid_hull(rng, 90, Vec3(0.5, 0.4, 0.35)),
      ellipsoid_hull(rng, 40, Vec3(0.6, 0.05, 0.5))};
  for (int k : {4, 8, 16, 32, 32, 64}) hulls.push_back(ellipsoid_hull(rng, k, Vec3(0.3 + 0.01 * k, 0.4, 0.3)));
  std::uniform_int_distribution<std::size_t> pick(0, hulls.size() - 1);
  int faces = 0, edges = 0, several = 0, skipped = 0;
  for (int trial = 0; trial < 700; ++trial) {
    const auto& ha = hulls[pick(rng)];
    const auto& hb = hulls[pick(rng)];
    const Pose pa{random_vec(rng, 0.1), random_rotation(rng)};
    Pose pb{random_vec(rng, 0.6), trial % 4 == 0 ? pa.rotation : random_rotation(rng)};
    const WorldHull wa = world(*ha, pa), wb = world(*hb, pb);
    Vec3 unused(0.0);
    if (hull_depth(wa, wb, unused) <= 1e-6) continue;  // overlapping pairs only
    // the search: separations along every candidate axis, B's support against A's
    const Vec3 ca = apply(pa, ha->centroid());
    auto gap = [&](const Vec3& n) { return -overlap(wa, wb, n); };
    double fa = -INFINITY, fb = -INFINITY, ee = -INFINITY;
    Vec3 na(0.0), nb(0.0), ne(0.0);
    for (const auto& p : wa.planes)
      if (gap(p.first) > fa) fa = gap(p.first), na = p.first;
    for (const auto& p : wb.planes)
      if (gap(-p.first) > fb) fb = gap(-p.first), nb = -p.first;
    double ee_second = -INFINITY;  // the best edge axis of another direction
    for (std::size_t i = 0; i < wa.edges.size(); ++i)
      for (const auto& eb : wb.edges) {
        const Vec3 d1 = wa.edges[i].second - wa.edges[i].first, d2 = eb.second - eb.first;
        const Vec3 c = glm::cross(d1, d2);
        if (glm::length(c) < 0.005 * glm::length(d1) * glm::length(d2)) continue;  // SAT's parallel edges
        Vec3 n = glm::normalize(c);
        if (glm::dot(n, wa.edges[i].first - ca) < 0) n = -n;
        const double g = gap(n);
        if (g > ee) {
          if (glm::length(n - ne) > 1e-6) ee_second = ee;
          ee = g, ne = n;
        } else if (g > ee_second && glm::length(n - ne) > 1e-6) {
          ee_second = g;
        }
      }
    const double best_face = std::max(fa, fb), edge_cut = 0.9 * best_face + 0.0025, face_cut = 0.98 * fa + 0.0025;
    // near a rule's threshold, or two edge axes as good, rounding may go either way
    if (std::abs(ee - edge_cut) < 1e-9 || std::abs(fb - face_cut) < 1e-9 || ee - ee_second < 1e-9) {
      ++skipped;
      continue;
    }
    const Manifold m = collide(ColliderShape::convex(ha), pa, ColliderShape::convex(hb), pb);
    ASSERT_GE(m.count, 1) << trial;
    if (ee > edge_cut) {
      ++edges;
      EXPECT_NEAR(glm::length(m.normal - ne), 0.0, 1e-9) << trial;
      // the edges' closest points at the axis's penetration, and any clipped face point no
      // deeper (its foot along the axis on A's face, the point on B)
      EXPECT_NEAR(m.points[0].depth, -ee, 1e-9) << trial;
      for (int i = 1; i < m.count; ++i) EXPECT_LE(m.points[std::size_t(i)].depth, -ee + 1e-9) << trial;
      several += m.count > 1;
    } else {
      ++faces;
      EXPECT_NEAR(glm::length(m.normal - (fb > face_cut ? nb : na)), 0.0, 1e-9) << trial;
    }
  }
  EXPECT_GT(faces, 200);
  EXPECT_GT(edges, 40);
  EXPECT_GT(several, 10);
  EXPECT_LT(skipped, 20);
}

// A ball or capsule against a hull: collide() leaves out GJK where one of the hull's face
// planes has the core beyond it by more than the radius and the margin (core_hull). Wherever
// a face plane shows that, GJK finds the cores farther apart than the radius and the margin
// too, and there is no manifold; where GJK finds them within it (cores apart), there is one.
TEST(HullPairs, BallAndCapsuleBeyondAFacePlaneAreBeyondForGjkToo) {
  std::mt19937_64 rng(20261206);
  std::uniform_real_distribution<double> size(0.05, 0.5);
  NarrowPhaseSettings settings;
  settings.speculative_margin = 0.1;
  int beyond_plane = 0, within = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const auto h = random_hull(rng);
    const ColliderShape b = ColliderShape::convex(h);
    const ColliderShape a =
        trial % 2 ? ColliderShape::capsule(size(rng), size(rng)) : ColliderShape::sphere(size(rng));
    const Pose pa{random_vec(rng, 1.8), random_rotation(rng)};
    const Pose pb{random_vec(rng, 0.3), random_rotation(rng)};
    const double half = a.type == ShapeType::Capsule ? a.half_height : 0.0;
    const Vec3 u = pa.rotation * Vec3(0, half, 0);
    bool plane_apart = false;
    for (const auto& [n, off] : world(*h, pb).planes)
      plane_apart |= std::min(glm::dot(n, pa.position - u), glm::dot(n, pa.position + u)) - off - a.radius >
                     settings.speculative_margin + 1e-12;
    const DistanceResult g = gjk_distance(ConvexProxy::of(a, pa), ConvexProxy::of(b, pb));
    const bool gjk_beyond = !g.cores_overlap && g.core_distance - a.radius > settings.speculative_margin;
    for (const bool swap : {false, true}) {
      const Manifold m = swap ? collide(b, pb, a, pa, settings) : collide(a, pa, b, pb, settings);
      if (plane_apart) {
        EXPECT_TRUE(gjk_beyond) << trial;
        EXPECT_EQ(m.count, 0) << trial;
      } else if (!g.cores_overlap && !gjk_beyond) {
        EXPECT_GE(m.count, 1) << trial;
      }
    }
    beyond_plane += plane_apart;
    within += !g.cores_overlap && !gjk_beyond;
  }
  EXPECT_GT(beyond_plane, 1000);
  EXPECT_GT(within, 150);
}
