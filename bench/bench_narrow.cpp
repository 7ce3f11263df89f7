// Narrow-phase benchmark (issue 10): box-box and hull-hull contact manifolds per pair, pba
// against Bullet in the same process on the same random overlapping poses.
//
//   bench_narrow [--pairs N] [--repeat R] [--rounds K] [--scene box|hull|both]
//
// Defaults: 2000 pairs, each pass over them repeated 20 times, 9 rounds; in each round the
// engines of a scene run one after the other; the median of the rounds' per-pair CPU times
// is reported, and each ratio is the median of the per-round ratios. Run it on one core: taskset -c 1.
//
// Scenes. Box-box: 1 m cubes and boxes of half extents in [0.25, 0.75] m, A at a random
// rotation near the origin, B at a random rotation and offset in [-0.8, 0.8]^3 m; only
// pairs that overlap are kept. Hull-hull: hulls of 32 random points on an ellipsoid of
// semi-axes in [0.3, 0.6] m (pba's quickhull; Bullet gets the same hull vertices and
// builds its polyhedral features from them), the same placement rule.
//
// Engines:
//   pba SAT      collide() with ConvexMethod::Sat (the default), margin 0.02 m
//   pba SAT, cached  the same with each pair's NarrowPhaseCache carried from pass to pass
//                (poses unchanged: the cached feature is the last pass's, as for a resting
//                pair)
//   pba SAT, batched  collide_batch() over chunks of 64 pairs (queries built inside the
//                timing), box-box pairs several at a time in SIMD lanes: the path the rigid
//                pipeline takes; the box-box verdict uses this lane
//   pba GJK/EPA  collide() with ConvexMethod::GjkEpa, margin 0.02 m
//   Bullet box   btBoxBoxDetector::getClosestPoints (what btBoxBoxCollisionAlgorithm runs)
//   Bullet hull  btGjkPairDetector (btVoronoiSimplexSolver, btGjkEpaPenetrationDepthSolver)
//                for the normal, then btPolyhedralContactClipping::clipHullAgainstHull with
//                threshold 0.02 m: the path btConvexConvexAlgorithm takes for two
//                polyhedral shapes (m_enableSatConvex off, its default). Collision
//                margins are 0 so both engines see the same solids.
// Bullet is Debian's single-precision build (btScalar = float); pba runs in double.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <random>
#include <string>
#include <vector>

#include <BulletCollision/CollisionDispatch/btBoxBoxDetector.h>
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btConvexPolyhedron.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPolyhedralContactClipping.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>

#include "pba/collide/narrow_phase.h"

namespace {

using pba::Pose;
using pba::Quat;
using pba::Vec3;

constexpr double kMargin = 0.02;  // m: pba's speculative margin and Bullet's clipping threshold

double cpu_now() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

Quat random_rotation(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double u1 = u(rng), u2 = u(rng), u3 = u(rng);
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  return glm::normalize(Quat(a * std::sin(2 * pba::kPi * u2), a * std::cos(2 * pba::kPi * u2),
                             b * std::sin(2 * pba::kPi * u3), b * std::cos(2 * pba::kPi * u3)));
}
Vec3 random_vec(std::mt19937_64& rng, double s) {
  std::uniform_real_distribution<double> u(-s, s);
  return Vec3(u(rng), u(rng), u(rng));
}

btTransform to_bt(const Pose& p) {
  return btTransform(btQuaternion(btScalar(p.rotation.x), btScalar(p.rotation.y), btScalar(p.rotation.z),
                                  btScalar(p.rotation.w)),
                     btVector3(btScalar(p.position.x), btScalar(p.position.y), btScalar(p.position.z)));
}

// a Bullet result that only counts points and keeps the deepest (no allocation)
struct CountResult : btDiscreteCollisionDetectorInterface::Result {
  int points = 0;
  btScalar deepest = 0;
  void setShapeIdentifiersA(int, int) override {}
  void setShapeIdentifiersB(int, int) override {}
  void addContactPoint(const btVector3&, const btVector3&, btScalar depth) override {
    ++points;
    deepest = std::min(deepest, depth);
  }
};
// the GJK result btConvexConvexAlgorithm keeps: the normal and distance of the closest pair
struct NormalResult : btDiscreteCollisionDetectorInterface::Result {
  bool found = false;
  btVector3 normal{0, 0, 1};
  btScalar distance = 0;
  void setShapeIdentifiersA(int, int) override {}
  void setShapeIdentifiersB(int, int) override {}
  void addContactPoint(const btVector3& n, const btVector3&, btScalar depth) override {
    found = true;
    normal = n;
    distance = depth;
  }
};

struct Pair {
  int a = 0, b = 0;  // shape indices
  Pose pa{}, pb{};
};

struct Scene {
  std::vector<pba::ColliderShape> shapes;
  std::vector<btConvexShape*> bt_shapes;
  std::vector<Pair> pairs;
};

// pairs whose solids overlap (pba's SAT with zero margin reports a point)
void make_pairs(Scene& s, int n, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> pick(0, int(s.shapes.size()) - 1);
  pba::NarrowPhaseSettings zero;
  zero.speculative_margin = 0;
  while (int(s.pairs.size()) < n) {
    Pair p{pick(rng), pick(rng), {random_vec(rng, 0.1), random_rotation(rng)}, {random_vec(rng, 0.8), random_rotation(rng)}};
    if (pba::collide(s.shapes[std::size_t(p.a)], p.pa, s.shapes[std::size_t(p.b)], p.pb, zero).count > 0)
      s.pairs.push_back(p);
  }
}

Scene box_scene(int n, std::mt19937_64& rng) {
  Scene s;
  std::uniform_real_distribution<double> h(0.25, 0.75);
  for (int i = 0; i < 16; ++i) {
    const Vec3 e = i == 0 ? Vec3(0.5) : Vec3(h(rng), h(rng), h(rng));
    s.shapes.push_back(pba::ColliderShape::box(e));
    auto* b = new btBoxShape(btVector3(btScalar(e.x), btScalar(e.y), btScalar(e.z)));
    s.bt_shapes.push_back(b);
  }
  make_pairs(s, n, rng);
  return s;
}

Scene hull_scene(int n, std::mt19937_64& rng, double* mean_vertices, double* mean_faces) {
  Scene s;
  std::uniform_real_distribution<double> ax(0.3, 0.6);
  double nv = 0, nf = 0;
  for (int i = 0; i < 16; ++i) {
    const Vec3 axes(ax(rng), ax(rng), ax(rng));
    std::vector<Vec3> pts(32);
    for (Vec3& p : pts) {
      Vec3 d = random_vec(rng, 1.0);
      while (glm::length(d) < 1e-3) d = random_vec(rng, 1.0);
      p = glm::normalize(d) * axes;
    }
    auto hull = pba::ConvexHull::build(pts, "bench hull");
    nv += double(hull->vertices().size());
    nf += double(hull->faces().size());
    auto* bh = new btConvexHullShape();
    for (const Vec3& v : hull->vertices()) bh->addPoint(btVector3(btScalar(v.x), btScalar(v.y), btScalar(v.z)), false);
    bh->recalcLocalAabb();
    bh->setMargin(0);
    bh->initializePolyhedralFeatures();
    s.bt_shapes.push_back(bh);
    s.shapes.push_back(pba::ColliderShape::convex(hull));
  }
  *mean_vertices = nv / 16;
  *mean_faces = nf / 16;
  make_pairs(s, n, rng);
  return s;
}

struct Timing {
  double median_us = 0;
  double points = 0;  // mean contact points per pair
};

// one engine's rounds: CPU time per pair of each round, in order
struct Lane {
  std::vector<double> us;
  double points = 0;
  void add(const Timing& t) {
    us.push_back(t.median_us);
    points = t.points;
  }
  double median() const {
    std::vector<double> v = us;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  }
  // the median over rounds of this lane's time over `pba`'s in the same round
  double ratio_to(const Lane& pba) const {
    std::vector<double> r;
    for (std::size_t i = 0; i < us.size(); ++i) r.push_back(us[i] / pba.us[i]);
    std::sort(r.begin(), r.end());
    return r[r.size() / 2];
  }
};

template <class F>
Timing time_it(const Scene& s, int repeat, int rounds, F&& one) {
  std::vector<double> per_pair;
  long long points = 0;
  for (int r = 0; r < rounds; ++r) {
    points = 0;
    const double t0 = cpu_now();
    for (int k = 0; k < repeat; ++k)
      for (const Pair& p : s.pairs) points += one(p);
    const double t1 = cpu_now();
    per_pair.push_back((t1 - t0) / double(repeat) / double(s.pairs.size()) * 1e6);
  }
  std::sort(per_pair.begin(), per_pair.end());
  return {per_pair[per_pair.size() / 2], double(points) / double(repeat) / double(s.pairs.size())};
}

Timing run_pba(const Scene& s, pba::ConvexMethod method, int repeat, int rounds) {
  pba::NarrowPhaseSettings set;
  set.speculative_margin = kMargin;
  set.method = method;
  return time_it(s, repeat, rounds, [&](const Pair& p) {
    return pba::collide(s.shapes[std::size_t(p.a)], p.pa, s.shapes[std::size_t(p.b)], p.pb, set).count;
  });
}

// the same with each pair's NarrowPhaseCache carried from pass to pass (the pose does not
// change: the cached feature is last pass's, as for a resting pair frame after frame)
Timing run_pba_cached(const Scene& s, std::vector<pba::NarrowPhaseCache>& caches, int repeat, int rounds) {
  pba::NarrowPhaseSettings set;
  set.speculative_margin = kMargin;
  const Pair* first = s.pairs.data();
  return time_it(s, repeat, rounds, [&](const Pair& p) {
    return pba::collide(s.shapes[std::size_t(p.a)], p.pa, s.shapes[std::size_t(p.b)], p.pb, set,
                        &caches[std::size_t(&p - first)])
        .count;
  });
}

// collide_batch() over the pairs in chunks of 64, the queries built inside the timing (as a
// caller builds them from its pair list): box-box pairs run in SIMD lanes (`path`)
Timing run_pba_batched(const Scene& s, pba::BatchPath path, int repeat, int rounds) {
  constexpr std::size_t kChunk = 64;
  std::vector<double> per_pair;
  long long points = 0;
  pba::PairQuery q[kChunk];
  pba::Manifold out[kChunk];
  for (int r = 0; r < rounds; ++r) {
    points = 0;
    const double t0 = cpu_now();
    for (int k = 0; k < repeat; ++k)
      for (std::size_t first = 0; first < s.pairs.size(); first += kChunk) {
        const std::size_t n = std::min(kChunk, s.pairs.size() - first);
        for (std::size_t i = 0; i < n; ++i) {
          const Pair& p = s.pairs[first + i];
          q[i] = {&s.shapes[std::size_t(p.a)], p.pa, &s.shapes[std::size_t(p.b)], p.pb, kMargin, nullptr};
        }
        pba::collide_batch({q, n}, {out, n}, pba::ConvexMethod::Sat, path);
        for (std::size_t i = 0; i < n; ++i) points += out[i].count;
      }
    const double t1 = cpu_now();
    per_pair.push_back((t1 - t0) / double(repeat) / double(s.pairs.size()) * 1e6);
  }
  std::sort(per_pair.begin(), per_pair.end());
  return {per_pair[per_pair.size() / 2], double(points) / double(repeat) / double(s.pairs.size())};
}

Timing run_bullet_box(const Scene& s, int repeat, int rounds) {
  return time_it(s, repeat, rounds, [&](const Pair& p) {
    btBoxBoxDetector det(static_cast<btBoxShape*>(s.bt_shapes[std::size_t(p.a)]),
                         static_cast<btBoxShape*>(s.bt_shapes[std::size_t(p.b)]));
    btDiscreteCollisionDetectorInterface::ClosestPointInput in;
    in.m_transformA = to_bt(p.pa);
    in.m_transformB = to_bt(p.pb);
    CountResult out;
    det.getClosestPoints(in, out, nullptr);
    return out.points;
  });
}

Timing run_bullet_hull(const Scene& s, int repeat, int rounds) {
  btVoronoiSimplexSolver simplex;
  btGjkEpaPenetrationDepthSolver epa;
  btVertexArray verts1, verts2;
  verts1.reserve(64);
  verts2.reserve(64);
  return time_it(s, repeat, rounds, [&](const Pair& p) {
    auto* a = static_cast<btConvexHullShape*>(s.bt_shapes[std::size_t(p.a)]);
    auto* b = static_cast<btConvexHullShape*>(s.bt_shapes[std::size_t(p.b)]);
    btGjkPairDetector gjk(a, b, &simplex, &epa);
    btDiscreteCollisionDetectorInterface::ClosestPointInput in;
    in.m_transformA = to_bt(p.pa);
    in.m_transformB = to_bt(p.pb);
    in.m_maximumDistanceSquared = btScalar(kMargin * kMargin);
    NormalResult normal;
    gjk.getClosestPoints(in, normal, nullptr);
    CountResult out;
    if (normal.found && normal.distance < btScalar(kMargin)) {
      verts1.resize(0);
      btPolyhedralContactClipping::clipHullAgainstHull(normal.normal, *a->getConvexPolyhedron(), *b->getConvexPolyhedron(),
                                                       in.m_transformA, in.m_transformB,
                                                       normal.distance - btScalar(kMargin), btScalar(kMargin), verts1,
                                                       verts2, out);
    }
    return out.points;
  });
}

}  // namespace

int main(int argc, char** argv) {
  int pairs = 2000, repeat = 20, rounds = 9;
  std::string only = "both";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&] {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_narrow: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return std::atoi(argv[++i]);
    };
    if (a == "--pairs") pairs = next();
    else if (a == "--repeat") repeat = next();
    else if (a == "--rounds") rounds = next();
    else if (a == "--scene" && i + 1 < argc) only = argv[++i];
    else {
      std::fprintf(stderr, "usage: bench_narrow [--pairs N] [--repeat R] [--rounds K] [--scene box|hull|both]\n");
      return 2;
    }
  }
  if (pairs < 1 || repeat < 1 || rounds < 1) {
    std::fprintf(stderr, "bench_narrow: counts must be >= 1\n");
    return 2;
  }
  std::mt19937_64 rng(2026);
  const Scene boxes = box_scene(pairs, rng);
  double nv = 0, nf = 0;
  const Scene hulls = hull_scene(pairs, rng, &nv, &nf);

  std::printf("narrow phase, %d overlapping pairs, %d passes x %d rounds (median), CPU time per pair\n", pairs, repeat,
              rounds);
  std::printf("hulls: %.1f vertices, %.1f faces on average\n\n", nv, nf);
  std::printf("%-10s %-22s %12s %14s\n", "pair", "engine", "us/pair", "points/pair");
  // the engines of a scene take turns, one round each, so a slow spell of the shared machine
  // falls on all of them; the ratios are taken within each round, then their median
  Lane bs, bc, bt, bg, bb, hs, hc, hg, hb;
  std::vector<pba::NarrowPhaseCache> box_caches(boxes.pairs.size()), hull_caches(hulls.pairs.size());
  for (int r = 0; r < rounds; ++r) {
    if (only != "hull") {
      bs.add(run_pba(boxes, pba::ConvexMethod::Sat, repeat, 1));
      bc.add(run_pba_cached(boxes, box_caches, repeat, 1));
      bt.add(run_pba_batched(boxes, pba::BatchPath::Best, repeat, 1));
      bg.add(run_pba(boxes, pba::ConvexMethod::GjkEpa, repeat, 1));
      bb.add(run_bullet_box(boxes, repeat, 1));
    }
    if (only != "box") {
      hs.add(run_pba(hulls, pba::ConvexMethod::Sat, repeat, 1));
      hc.add(run_pba_cached(hulls, hull_caches, repeat, 1));
      hg.add(run_pba(hulls, pba::ConvexMethod::GjkEpa, repeat, 1));
      hb.add(run_bullet_hull(hulls, repeat, 1));
    }
  }
  if (only != "hull") {
    std::printf("%-10s %-22s %12.3f %14.2f\n", "box-box", "pba SAT", bs.median(), bs.points);
    std::printf("%-10s %-22s %12.3f %14.2f\n", "box-box", "pba SAT, cached", bc.median(), bc.points);
    std::printf("%-10s %-22s %12.3f %14.2f\n", "box-box", "pba SAT, batched", bt.median(), bt.points);
    std::printf("%-10s %-22s %12.3f %14.2f\n", "box-box", "pba GJK/EPA", bg.median(), bg.points);
    std::printf("%-10s %-22s %12.3f %14.2f\n", "box-box", "Bullet btBoxBoxDetector", bb.median(), bb.points);
  }
  if (only != "box") {
    std::printf("%-10s %-22s %12.3f %14.2f\n", "hull-hull", "pba SAT", hs.median(), hs.points);
    std::printf("%-10s %-22s %12.3f %14.2f\n", "hull-hull", "pba SAT, cached", hc.median(), hc.points);
    std::printf("%-10s %-22s %12.3f %14.2f\n", "hull-hull", "pba GJK/EPA", hg.median(), hg.points);
    std::printf("%-10s %-22s %12.3f %14.2f\n", "hull-hull", "Bullet GJK+clipping", hb.median(), hb.points);
  }
  std::printf("\nratios (Bullet / pba, median of the per-round ratios; goal >= 2):\n");
  auto verdict = [](double sat, double gjk) { return std::max(sat, gjk) >= 2 ? "met" : "NOT met"; };
  if (only != "hull") {
    // the verdict on the batched lane: the path the rigid pipeline's narrow phase takes
    const double s = bb.ratio_to(bs), t = bb.ratio_to(bt), g = bb.ratio_to(bg);
    std::printf("  box-box   SAT batched %.2fx (one pair at a time %.2fx, cached %.2fx), GJK/EPA %.2fx  %s\n", t, s,
                bb.ratio_to(bc), g, verdict(t, g));
  }
  if (only != "box") {
    const double s = hb.ratio_to(hs), g = hb.ratio_to(hg);
    std::printf("  hull-hull SAT %.2fx (cached %.2fx), GJK/EPA %.2fx  %s\n", s, hb.ratio_to(hc), g, verdict(s, g));
  }
  for (auto* p : boxes.bt_shapes) delete p;
  for (auto* p : hulls.bt_shapes) delete p;
  return 0;
}
