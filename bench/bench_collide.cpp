// Collision benchmark (issue 10): the per-frame broad phase of pba (each method) against
// Bullet's collision world (btDbvtBroadphase) and ODE's spaces (dHashSpace and
// dSweepAndPruneSpace), on the same scene, in the same process; and 5 m ray casts.
//
//   bench_collide [--quick] [--repeat R] [--frames F] [--counts 1000,10000] [--rays N] [--sweeps N]
//                 [--lanes a,b]   only the lanes whose names contain a or b (and pba tree)
//                 [--no-queries]  no rays or world queries
//
// Scene (exactly as /work/shared/peers/bullet_collision.cpp builds it): N bodies, even ones
// 1 m boxes, odd ones spheres of 0.5 m radius, at uniform random positions in the cube
// [0, 1.6 cbrt(N)]^3 with random orientations (std::mt19937 seed 7, float draws); every
// frame every body's position moves by a uniform random step in [-0.02, 0.02] m per axis.
// Each engine replays the same poses (the draws are made once, up front).
//
// Per frame, CPU time of this thread (so other processes on the shared machine do not
// count), averaged over F frames after one warm-up frame; R fresh runs per row, medians
// reported, and ratios taken within each run then their median:
//   pba <method>      world bounds of every body from shape and pose (pba::bounds) +
//                     move_proxy + update_pairs
//   pba tree + collide  the tree, then pba::collide (the contact manifold) for every pair
//   pba tree + collide, cached  the same, each pair's NarrowPhaseCache carried between frames
//   bullet broad      updateAabbs() + computeOverlappingPairs(): Bullet's broad phase only
//   bullet full       performDiscreteCollisionDetection(): the above plus Bullet's narrow
//                     phase (contact manifolds for every overlapping pair)
//   ode hash/sap      dSpaceCollide with a callback that only counts (broad phase only)
//   ode hash+collide  dSpaceCollide whose callback calls dCollide (ODE's narrow phase)
// Rays: 5 m rays from uniform random points in random directions (as Bullet's harness),
// the closest hit; pba casts through the tree and tests each body's box (AABB level) or its
// shape (pba::ray_cast, the same work as Bullet's rayTest, which tests its shapes).
// Queries (pba::QueryWorld, collide/query.h) on the same scene, per query:
//   rays          QueryWorld::ray_cast (closest hit, shapes) against Bullet's rayTest and
//                 ODE's dSpaceCollide2 of a dRay (closest hit) with the hash space
//   sphere casts  QueryWorld::sphere_cast of a 0.25 m sphere from (U, U, -1) to
//                 (U, U, side + 1) (the sweeps of bullet_collision.cpp) against Bullet's
//                 convexSweepTest with a ClosestConvexResultCallback
#include <btBulletCollisionCommon.h>
#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "pba/collide/broad_phase.h"
#include "pba/collide/narrow_phase.h"
#include "pba/collide/query.h"

namespace {

using pba::Vec3;

double cpu_now() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n == 0 ? 0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

// --- the scene: poses drawn once, replayed by every engine ---------------------------------

struct Scene {
  int n = 0;
  double side = 0;
  std::vector<Vec3> start;          // initial positions (m)
  std::vector<pba::Quat> rotation;  // fixed orientations
  std::vector<Vec3> step;           // per frame, per body: the position step (m)
  int frames = 0;
  bool is_box(int i) const { return (i & 1) == 0; }
};

Scene make_scene(int n, int frames) {
  // the same draws, in the same order, as bullet_collision.cpp
  Scene s;
  s.n = n;
  s.frames = frames;
  std::mt19937 rng(7);
  s.side = std::cbrt(double(n)) * 1.6;
  std::uniform_real_distribution<float> U(0, float(s.side)), J(-0.02f, 0.02f);
  for (int i = 0; i < n; ++i) {
    const float x = U(rng), y = U(rng), z = U(rng);
    s.start.emplace_back(x, y, z);
    // btQuaternion(axis, angle) with axis (U, U, U) normalised
    const float ax = U(rng), ay = U(rng), az = U(rng), angle = U(rng);
    const btQuaternion q(btVector3(ax, ay, az), angle);
    s.rotation.emplace_back(double(q.w()), double(q.x()), double(q.y()), double(q.z()));
  }
  s.step.resize(std::size_t(n) * std::size_t(frames + 1));
  for (auto& d : s.step) {
    const float a = J(rng), b = J(rng), c = J(rng);
    d = Vec3(a, b, c);
  }
  return s;
}

// the bodies as pba shapes at their starting poses
struct Bodies {
  std::vector<pba::ColliderShape> shape;
  std::vector<pba::Pose> pose;
  explicit Bodies(const Scene& s) {
    for (int i = 0; i < s.n; ++i) {
      shape.push_back(s.is_box(i) ? pba::ColliderShape::box(Vec3(0.5)) : pba::ColliderShape::sphere(0.5));
      pose.push_back({s.start[i], s.rotation[i]});
    }
  }
};

// --- the engines --------------------------------------------------------------------------

struct FrameResult {
  double ms = 0;       // mean CPU ms per frame
  long pairs = 0;      // pairs in the last frame
};

// What run_pba does per pair: `Broad` counts the pairs (the broad phase alone); `Narrow`
// makes each pair's contact manifold (pba::collide) with no state carried between frames, so
// every box pair runs its full separating-axis test; `NarrowCached` carries each pair's
// NarrowPhaseCache from frame to frame, as a caller that keeps its contacts does (the rigid
// pipeline, and Bullet's full lane, whose persistent manifolds hold its state): the pair list
// is sorted, so last frame's caches are found by walking both lists in step
enum class PbaWork { Broad, Narrow, NarrowCached };

FrameResult run_pba(const Scene& s, pba::BroadPhaseMethod method, PbaWork work = PbaWork::Broad) {
  pba::BroadPhase bp({.method = method});
  bp.reserve(std::size_t(s.n));
  Bodies b(s);
  std::vector<pba::ProxyId> ids(std::size_t(s.n));
  for (int i = 0; i < s.n; ++i) ids[i] = bp.create_proxy(pba::bounds(b.shape[i], b.pose[i]), {}, std::uint64_t(i));
  // each pair's cache, keyed by the pair's proxy indices, in the pair list's order
  struct PairCache {
    std::uint64_t key;
    pba::NarrowPhaseCache cache;
  };
  std::vector<PairCache> caches, next;
  caches.reserve(std::size_t(s.n) * 8);
  next.reserve(std::size_t(s.n) * 8);
  long sink = 0;
  auto frame = [&](int f) {
    // move every body, update its world bounds from shape and pose, find the pairs
    const Vec3* d = &s.step[std::size_t(f) * std::size_t(s.n)];
    for (int i = 0; i < s.n; ++i) {
      b.pose[i].position += d[i];
      bp.move_proxy(ids[i], pba::bounds(b.shape[i], b.pose[i]));
    }
    next.clear();
    std::size_t old = 0;
    for (const pba::ProxyPair& p : bp.update_pairs()) {
      if (work == PbaWork::Broad) {
        sink += p.a.index ^ p.b.index;
        continue;
      }
      const auto ia = std::size_t(bp.user_data(p.a)), ib = std::size_t(bp.user_data(p.b));
      pba::NarrowPhaseCache* cache = nullptr;
      if (work == PbaWork::NarrowCached) {
        const std::uint64_t key = (std::uint64_t(p.a.index) << 32) | p.b.index;
        while (old < caches.size() && caches[old].key < key) ++old;
        next.push_back({key, old < caches.size() && caches[old].key == key ? caches[old].cache : pba::NarrowPhaseCache{}});
        cache = &next.back().cache;
      }
      sink += pba::collide(b.shape[ia], b.pose[ia], b.shape[ib], b.pose[ib], {}, cache).count;
    }
    std::swap(caches, next);
  };
  frame(0);  // warm-up: the first frame queries every proxy
  const double t0 = cpu_now();
  for (int f = 1; f <= s.frames; ++f) frame(f);
  const double ms = (cpu_now() - t0) * 1e3 / s.frames;
  if (sink == 42) std::printf(" ");
  return {ms, long(bp.pairs().size())};
}

struct BulletWorld {
  btDefaultCollisionConfiguration cfg;
  btCollisionDispatcher disp{&cfg};
  btDbvtBroadphase bp;
  btCollisionWorld world{&disp, &bp, &cfg};
  btBoxShape box{btVector3(0.5, 0.5, 0.5)};
  btSphereShape sphere{0.5};
  std::vector<btCollisionObject> objects;
  explicit BulletWorld(const Scene& s) : objects(std::size_t(s.n)) {
    for (int i = 0; i < s.n; ++i) {
      btCollisionObject& o = objects[i];
      o.setCollisionShape(s.is_box(i) ? static_cast<btCollisionShape*>(&box) : &sphere);
      btTransform t;
      t.setIdentity();
      t.setOrigin(btVector3(btScalar(s.start[i].x), btScalar(s.start[i].y), btScalar(s.start[i].z)));
      const pba::Quat& q = s.rotation[i];
      t.setRotation(btQuaternion(btScalar(q.x), btScalar(q.y), btScalar(q.z), btScalar(q.w)));
      o.setWorldTransform(t);
      world.addCollisionObject(&o);
    }
  }
  ~BulletWorld() {
    for (auto& o : objects) world.removeCollisionObject(&o);
  }
  void move(const Scene& s, int f) {
    const Vec3* d = &s.step[std::size_t(f) * std::size_t(s.n)];
    for (int i = 0; i < s.n; ++i) {
      btTransform t = objects[i].getWorldTransform();
      t.setOrigin(t.getOrigin() + btVector3(btScalar(d[i].x), btScalar(d[i].y), btScalar(d[i].z)));
      objects[i].setWorldTransform(t);
    }
  }
};

FrameResult run_bullet(const Scene& s, bool full) {
  BulletWorld b(s);
  auto frame = [&](int f) {
    b.move(s, f);
    if (full) {
      b.world.performDiscreteCollisionDetection();
    } else {
      b.world.updateAabbs();
      b.world.computeOverlappingPairs();
    }
  };
  frame(0);
  const double t0 = cpu_now();
  for (int f = 1; f <= s.frames; ++f) frame(f);
  const double ms = (cpu_now() - t0) * 1e3 / s.frames;
  return {ms, long(b.bp.getOverlappingPairCache()->getNumOverlappingPairs())};
}

struct OdeCount {
  long pairs = 0;
  bool collide = false;
  long contacts = 0;
};

void ode_near(void* data, dGeomID a, dGeomID b) {
  auto* c = static_cast<OdeCount*>(data);
  ++c->pairs;
  if (c->collide) {
    dContactGeom g[4];
    c->contacts += dCollide(a, b, 4, g, sizeof(dContactGeom));
  }
}

FrameResult run_ode(const Scene& s, bool sap, bool collide) {
  dSpaceID space = sap ? dSweepAndPruneSpaceCreate(nullptr, dSAP_AXES_XYZ) : dHashSpaceCreate(nullptr);
  std::vector<dGeomID> geoms(std::size_t(s.n));
  for (int i = 0; i < s.n; ++i) {
    geoms[i] = s.is_box(i) ? dCreateBox(space, 1, 1, 1) : dCreateSphere(space, 0.5);
    dGeomSetPosition(geoms[i], s.start[i].x, s.start[i].y, s.start[i].z);
    const pba::Quat& q = s.rotation[i];
    const dQuaternion dq = {q.w, q.x, q.y, q.z};
    dGeomSetQuaternion(geoms[i], dq);
  }
  std::vector<Vec3> pos = s.start;
  OdeCount count;
  count.collide = collide;
  auto frame = [&](int f) {
    const Vec3* d = &s.step[std::size_t(f) * std::size_t(s.n)];
    for (int i = 0; i < s.n; ++i) {
      pos[i] += d[i];
      dGeomSetPosition(geoms[i], pos[i].x, pos[i].y, pos[i].z);
    }
    count.pairs = 0;
    dSpaceCollide(space, &count, &ode_near);
  };
  frame(0);
  const double t0 = cpu_now();
  for (int f = 1; f <= s.frames; ++f) frame(f);
  const double ms = (cpu_now() - t0) * 1e3 / s.frames;
  dSpaceDestroy(space);  // destroys its geoms (cleanup mode on)
  return {ms, count.pairs};
}

// --- rays ---------------------------------------------------------------------------------

struct RayResult {
  double us = 0;
  int hits = 0;
};

// the rays of bullet_collision.cpp: origin uniform in the cube, direction from J draws
std::vector<pba::Ray> make_rays(const Scene& s, int count) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> U(0, float(s.side)), J(-0.02f, 0.02f);
  std::vector<pba::Ray> rays;
  for (int i = 0; i < count; ++i) {
    const Vec3 a(U(rng), U(rng), U(rng));
    Vec3 d(J(rng), J(rng), J(rng));
    if (glm::dot(d, d) < 1e-8) d = Vec3(0, 0, 1);
    rays.push_back({a, glm::normalize(d), 5.0});
  }
  return rays;
}

// closest hit through the tree; `exact` tests each body's shape (pba::ray_cast), otherwise
// its box (AABB level)
RayResult rays_pba(const Scene& s, const std::vector<pba::Ray>& rays, bool exact) {
  pba::BroadPhase bp;
  Bodies b(s);
  std::vector<pba::Aabb> boxes;
  for (int i = 0; i < s.n; ++i) {
    boxes.push_back(pba::bounds(b.shape[i], b.pose[i]));
    bp.create_proxy(boxes.back());
  }
  bp.update_pairs();
  const pba::DynamicTree& tree = bp.tree();
  int hits = 0;
  const double t0 = cpu_now();
  for (const pba::Ray& ray : rays) {
    const Vec3 inv = 1.0 / ray.direction;
    bool hit = false;
    tree.ray_cast(ray, [&](std::uint32_t u, const pba::Ray& r) {
      // the body hit within the clipped ray clips it further
      if (exact) {
        const pba::RayHit h = pba::ray_cast(b.shape[u], b.pose[u], r);
        if (!h.hit) return r.max_distance;
        hit = true;
        return h.distance;
      }
      const double t = pba::ray_enter_box(r, inv, boxes[u]);
      if (t < 0) return r.max_distance;
      hit = true;
      return t;
    });
    hits += hit;
  }
  return {(cpu_now() - t0) * 1e6 / double(rays.size()), hits};
}

RayResult rays_bullet(const Scene& s, const std::vector<pba::Ray>& rays) {
  BulletWorld b(s);
  b.world.performDiscreteCollisionDetection();
  int hits = 0;
  const double t0 = cpu_now();
  for (const pba::Ray& ray : rays) {
    const btVector3 a(btScalar(ray.origin.x), btScalar(ray.origin.y), btScalar(ray.origin.z));
    const Vec3 e = ray.origin + 5.0 * ray.direction;
    const btVector3 c(btScalar(e.x), btScalar(e.y), btScalar(e.z));
    btCollisionWorld::ClosestRayResultCallback cb(a, c);
    b.world.rayTest(a, c, cb);
    hits += cb.hasHit();
  }
  return {(cpu_now() - t0) * 1e6 / double(rays.size()), hits};
}

// --- world queries ---------------------------------------------------------------------------

// the bodies as colliders; the rotations (float quaternions, |q| - 1 up to about 1e-7)
// normalised in double so that a rotated shape keeps its size to the last bits
pba::QueryWorld query_world(const Scene& s) {
  Bodies b(s);
  std::vector<pba::Collider> cs(std::size_t(s.n));
  for (int i = 0; i < s.n; ++i) {
    cs[i].shape = b.shape[i];
    cs[i].begin = cs[i].end = {b.pose[i].position, glm::normalize(b.pose[i].rotation)};
  }
  pba::QueryWorld q;
  q.build(cs);
  return q;
}

RayResult rays_query(const Scene& s, const std::vector<pba::Ray>& rays) {
  const pba::QueryWorld q = query_world(s);
  int hits = 0;
  const double t0 = cpu_now();
  for (const pba::Ray& ray : rays) hits += q.ray_cast(ray).hit;
  return {(cpu_now() - t0) * 1e6 / double(rays.size()), hits};
}

// ODE: a dRay outside the space, closest hit, against the hash space by dSpaceCollide2
struct OdeRay {
  bool hit = false;
  double depth = 0;
};

void ode_ray_near(void* data, dGeomID a, dGeomID b) {
  auto* r = static_cast<OdeRay*>(data);
  dContactGeom g;
  if (dCollide(a, b, 1, &g, sizeof(dContactGeom)) > 0 && (!r->hit || g.depth < r->depth)) r->hit = true, r->depth = g.depth;
}

RayResult rays_ode(const Scene& s, const std::vector<pba::Ray>& rays) {
  dSpaceID space = dHashSpaceCreate(nullptr);
  for (int i = 0; i < s.n; ++i) {
    const dGeomID g = s.is_box(i) ? dCreateBox(space, 1, 1, 1) : dCreateSphere(space, 0.5);
    dGeomSetPosition(g, s.start[i].x, s.start[i].y, s.start[i].z);
    const pba::Quat& q = s.rotation[i];
    const dQuaternion dq = {q.w, q.x, q.y, q.z};
    dGeomSetQuaternion(g, dq);
  }
  const dGeomID ray = dCreateRay(nullptr, 5.0);
  dGeomRaySetClosestHit(ray, 1);
  int hits = 0;
  const double t0 = cpu_now();
  for (const pba::Ray& r : rays) {
    dGeomRaySet(ray, r.origin.x, r.origin.y, r.origin.z, r.direction.x, r.direction.y, r.direction.z);
    OdeRay out;
    dSpaceCollide2(ray, reinterpret_cast<dGeomID>(space), &out, &ode_ray_near);
    hits += out.hit;
  }
  const double us = (cpu_now() - t0) * 1e6 / double(rays.size());
  dGeomDestroy(ray);
  dSpaceDestroy(space);
  return {us, hits};
}

// the sweeps of bullet_collision.cpp: from (U, U, -1) to (U, U, side + 1)
struct Sweep {
  Vec3 from, to;
};

std::vector<Sweep> make_sweeps(const Scene& s, int count) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> U(0, float(s.side));
  std::vector<Sweep> out;
  for (int i = 0; i < count; ++i) {
    const float ax = U(rng), ay = U(rng), bx = U(rng), by = U(rng);
    out.push_back({Vec3(ax, ay, -1.0), Vec3(bx, by, s.side + 1)});
  }
  return out;
}

constexpr double kProbe = 0.25;  // the swept sphere's radius (m)

RayResult sweeps_query(const Scene& s, const std::vector<Sweep>& sweeps) {
  const pba::QueryWorld q = query_world(s);
  int hits = 0;
  const double t0 = cpu_now();
  for (const Sweep& w : sweeps) {
    const Vec3 d = w.to - w.from;
    hits += q.sphere_cast({w.from, d / glm::length(d), glm::length(d)}, kProbe).hit;
  }
  return {(cpu_now() - t0) * 1e6 / double(sweeps.size()), hits};
}

// one Bullet sweep of `probe` from w.from to w.to, closest hit
btCollisionWorld::ClosestConvexResultCallback bullet_sweep(BulletWorld& b, const btSphereShape& probe, const Sweep& w) {
  btTransform ta, tb;
  ta.setIdentity();
  tb.setIdentity();
  ta.setOrigin(btVector3(btScalar(w.from.x), btScalar(w.from.y), btScalar(w.from.z)));
  tb.setOrigin(btVector3(btScalar(w.to.x), btScalar(w.to.y), btScalar(w.to.z)));
  btCollisionWorld::ClosestConvexResultCallback cb(ta.getOrigin(), tb.getOrigin());
  b.world.convexSweepTest(&probe, ta, tb, cb);
  return cb;
}

RayResult sweeps_bullet(const Scene& s, const std::vector<Sweep>& sweeps) {
  BulletWorld b(s);
  b.world.performDiscreteCollisionDetection();
  btSphereShape probe{btScalar(kProbe)};
  int hits = 0;
  const double t0 = cpu_now();
  for (const Sweep& w : sweeps) {
    const btCollisionWorld::ClosestConvexResultCallback cb = bullet_sweep(b, probe, w);
    hits += cb.hasHit();
  }
  return {(cpu_now() - t0) * 1e6 / double(sweeps.size()), hits};
}

// the same sweeps untimed, pba against Bullet: on the sweeps where both hit the same body,
// the median and largest difference of the distance to the first contact (Bullet works in
// float and lets a cast penetrate by its allowed CCD penetration); the sweeps where they hit
// different bodies, and how many of those pba's hit comes first; and pba's largest gap
// |point distance - r| at its own contacts (0 for an exact time of impact)
void sweep_agreement(const Scene& s, const std::vector<Sweep>& sweeps) {
  const pba::QueryWorld q = query_world(s);
  BulletWorld b(s);
  b.world.performDiscreteCollisionDetection();
  btSphereShape probe{btScalar(kProbe)};
  std::vector<double> same;
  int other = 0, pba_first = 0;
  double gap = 0;
  for (const Sweep& w : sweeps) {
    const Vec3 d = w.to - w.from;
    const double len = glm::length(d);
    const pba::ShapeCastHit h = q.sphere_cast({w.from, d / len, len}, kProbe);
    const btCollisionWorld::ClosestConvexResultCallback cb = bullet_sweep(b, probe, w);
    if (!h.hit || !cb.hasHit()) continue;
    const Vec3 c = w.from + h.distance * (d / len);
    if (h.distance > 0)  // (0: overlapping at the start)
      gap = std::max(gap, std::abs(pba::point_distance(q.shape(h.collider), q.pose(h.collider), c).distance - kProbe));
    const auto body = std::size_t(static_cast<const btCollisionObject*>(cb.m_hitCollisionObject) - b.objects.data());
    const double bd = double(cb.m_closestHitFraction) * len;
    if (body == h.collider) {
      same.push_back(std::abs(h.distance - bd));
    } else {
      ++other;
      pba_first += h.distance < bd;
    }
  }
  std::printf("  against bullet: same body in %zu sweeps, |distance difference| median %.1e m, max %.1e m;\n"
              "  another body in %d (pba's first in %d); pba's largest gap at its contacts %.1e m\n\n",
              same.size(), median(same), same.empty() ? 0.0 : *std::max_element(same.begin(), same.end()), other,
              pba_first, gap);
}

// the query rows: medians of `repeat` runs, ratios within each run
void query_rows(const Scene& s, const std::vector<pba::Ray>& rays, int nsweeps, int repeat) {
  const std::vector<Sweep> sweeps = make_sweeps(s, nsweeps);
  std::vector<double> q, b, o, rb, ro, sq, sb, rs;
  RayResult lq, lb, lo, lsq, lsb;
  for (int r = 0; r < repeat; ++r) {
    lq = rays_query(s, rays), lb = rays_bullet(s, rays), lo = rays_ode(s, rays);
    lsq = sweeps_query(s, sweeps), lsb = sweeps_bullet(s, sweeps);
    q.push_back(lq.us), b.push_back(lb.us), o.push_back(lo.us);
    rb.push_back(lb.us / lq.us), ro.push_back(lo.us / lq.us);
    sq.push_back(lsq.us), sb.push_back(lsb.us), rs.push_back(lsb.us / lsq.us);
  }
  const double nr = double(rays.size()), ns = double(sweeps.size());
  std::printf("  queries, %zu rays of 5 m (closest hit):    us/ray   hit   peer / pba\n", rays.size());
  std::printf("  %-34s %10.3f %4.0f%%\n", "pba QueryWorld::ray_cast", median(q), 100.0 * lq.hits / nr);
  std::printf("  %-34s %10.3f %4.0f%% %10.2f\n", "bullet rayTest", median(b), 100.0 * lb.hits / nr, median(rb));
  std::printf("  %-34s %10.3f %4.0f%% %10.2f\n", "ode dSpaceCollide2(dRay), hash", median(o), 100.0 * lo.hits / nr,
              median(ro));
  std::printf("  sphere casts r = %.2f m, %d, z = -1 to side + 1: us/cast  hit   peer / pba\n", kProbe, nsweeps);
  std::printf("  %-34s %10.3f %4.0f%%\n", "pba QueryWorld::sphere_cast", median(sq), 100.0 * lsq.hits / ns);
  std::printf("  %-34s %10.3f %4.0f%% %10.2f\n", "bullet convexSweepTest", median(sb), 100.0 * lsb.hits / ns,
              median(rs));
  sweep_agreement(s, sweeps);
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 5, frames = 200, nrays = 20000, nsweeps = 2000;
  std::vector<std::string> only;  // --lanes: run the lanes whose names contain one of these
  bool queries = true;
  std::vector<int> counts{1000, 10000};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s: missing value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--quick") {
      repeat = 1;
      frames = 20;
      nrays = 2000;
      nsweeps = 200;
    } else if (a == "--sweeps") {
      nsweeps = std::max(1, std::atoi(value().c_str()));
    } else if (a == "--repeat") {
      repeat = std::max(1, std::atoi(value().c_str()));
    } else if (a == "--frames") {
      frames = std::max(1, std::atoi(value().c_str()));
    } else if (a == "--rays") {
      nrays = std::max(1, std::atoi(value().c_str()));
    } else if (a == "--lanes") {
      const std::string v = value();
      for (std::size_t p = 0; p < v.size();) {
        const std::size_t q = v.find(',', p);
        only.push_back(v.substr(p, q == std::string::npos ? std::string::npos : q - p));
        p = q == std::string::npos ? v.size() : q + 1;
      }
    } else if (a == "--no-queries") {
      queries = false;
    } else if (a == "--counts") {
      counts.clear();
      const std::string v = value();
      for (std::size_t p = 0; p < v.size();) {
        const std::size_t q = v.find(',', p);
        counts.push_back(std::atoi(v.substr(p, q - p).c_str()));
        p = q == std::string::npos ? v.size() : q + 1;
      }
    } else {
      std::fprintf(stderr, "unknown flag '%s'\nusage: bench_collide [--quick] [--repeat R] [--frames F] "
                           "[--counts 1000,10000] [--rays N] [--sweeps N] [--lanes a,b] [--no-queries]\n",
                   a.c_str());
      return 2;
    }
  }
  dInitODE2(0);

  struct Lane {
    const char* name;
    std::function<FrameResult(const Scene&)> run;
  };
  std::vector<Lane> lanes{
      {"pba tree", [](const Scene& s) { return run_pba(s, pba::BroadPhaseMethod::Tree); }},
      {"pba grid", [](const Scene& s) { return run_pba(s, pba::BroadPhaseMethod::Grid); }},
      {"pba sap", [](const Scene& s) { return run_pba(s, pba::BroadPhaseMethod::SweepAndPrune); }},
      {"pba brute-force", [](const Scene& s) { return run_pba(s, pba::BroadPhaseMethod::BruteForce); }},
      {"pba tree + collide (broad+narrow)",
       [](const Scene& s) { return run_pba(s, pba::BroadPhaseMethod::Tree, PbaWork::Narrow); }},
      {"pba tree + collide, cached",
       [](const Scene& s) { return run_pba(s, pba::BroadPhaseMethod::Tree, PbaWork::NarrowCached); }},
      {"bullet broad (dbvt)", [](const Scene& s) { return run_bullet(s, false); }},
      {"bullet full (broad+narrow)", [](const Scene& s) { return run_bullet(s, true); }},
      {"ode hash (broad)", [](const Scene& s) { return run_ode(s, false, false); }},
      {"ode sap (broad)", [](const Scene& s) { return run_ode(s, true, false); }},
      {"ode hash+dCollide (broad+narrow)", [](const Scene& s) { return run_ode(s, false, true); }},
  };

  if (!only.empty()) {
    // the first lane is the reference of the "x pba tree" column: keep it
    std::vector<Lane> kept{lanes.front()};
    for (std::size_t l = 1; l < lanes.size(); ++l)
      for (const std::string& o : only)
        if (std::strstr(lanes[l].name, o.c_str())) {
          kept.push_back(lanes[l]);
          break;
        }
    lanes = kept;
  }

  for (int n : counts) {
    const Scene s = make_scene(n, frames);
    std::printf("N = %d bodies (half 1 m boxes, half 0.5 m spheres), cube side %.1f m, %d frames, %d runs\n", n,
                s.side, frames, repeat);
    // every lane once per run, in the same order; ratios within a run
    std::vector<std::vector<double>> ms(lanes.size());
    std::vector<long> pairs(lanes.size());
    std::vector<std::vector<double>> ratio(lanes.size());  // lane / pba tree, per run
    for (int r = 0; r < repeat; ++r) {
      std::vector<double> run_ms(lanes.size());
      for (std::size_t l = 0; l < lanes.size(); ++l) {
        if (n > 2000 && std::strcmp(lanes[l].name, "pba brute-force") == 0 && r > 0) {
          run_ms[l] = ms[l].back();  // O(n^2): measured once at large n
        } else {
          const FrameResult fr = lanes[l].run(s);
          run_ms[l] = fr.ms;
          pairs[l] = fr.pairs;
        }
        ms[l].push_back(run_ms[l]);
      }
      for (std::size_t l = 0; l < lanes.size(); ++l) ratio[l].push_back(run_ms[l] / run_ms[0]);
    }
    std::printf("  %-34s %10s %10s %14s\n", "engine", "ms/frame", "pairs", "x pba tree");
    for (std::size_t l = 0; l < lanes.size(); ++l)
      std::printf("  %-34s %10.3f %10ld %14.2f\n", lanes[l].name, median(ms[l]), pairs[l], median(ratio[l]));
    // the per-frame goal: each peer's full frame over each pba broad + narrow lane,
    // the median of the per-run ratios
    for (std::size_t l = 0; l < lanes.size(); ++l) {
      if (!std::strstr(lanes[l].name, "+ collide")) continue;
      for (std::size_t k = 0; k < lanes.size(); ++k) {
        if (!std::strstr(lanes[k].name, "full") && !std::strstr(lanes[k].name, "dCollide")) continue;
        std::vector<double> r;
        for (int run = 0; run < repeat; ++run) r.push_back(ms[k][std::size_t(run)] / ms[l][std::size_t(run)]);
        std::printf("  %s / %s: %.2f\n", lanes[k].name, lanes[l].name, median(r));
      }
    }

    if (!queries) continue;
    // rays
    const std::vector<pba::Ray> rays = make_rays(s, nrays);
    std::vector<double> pa, pe, br, ra, re;
    int ha = 0, he = 0, bh = 0;
    for (int r = 0; r < repeat; ++r) {
      const RayResult a = rays_pba(s, rays, false), e = rays_pba(s, rays, true), b = rays_bullet(s, rays);
      pa.push_back(a.us);
      pe.push_back(e.us);
      br.push_back(b.us);
      ra.push_back(b.us / a.us);
      re.push_back(b.us / e.us);
      ha = a.hits, he = e.hits, bh = b.hits;
    }
    std::printf("  rays, 5 m, closest hit, %d rays:            us/ray   hit   bullet / pba\n", nrays);
    std::printf("  %-34s %10.3f %4.0f%% %10.2f\n", "pba tree, boxes (AABB level)", median(pa), 100.0 * ha / nrays,
                median(ra));
    std::printf("  %-34s %10.3f %4.0f%% %10.2f\n", "pba tree + ray_cast(shape)", median(pe), 100.0 * he / nrays,
                median(re));
    std::printf("  %-34s %10.3f %4.0f%%\n\n", "bullet rayTest (shapes)", median(br), 100.0 * bh / nrays);
    query_rows(s, rays, nsweeps, repeat);
  }
  dCloseODE();
  return 0;
}
