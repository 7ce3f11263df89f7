// pba rigid bodies, under each of its four contact solvers, against Bullet on the scenes of
// shared/peers/ (vertical stacks, the 20-level square pyramid, 1000 falling boxes), all in
// this process, one core:
//   taskset -c 1 build/release/bin/bench_rigid [--quick | --budget | --pipeline]
// Prints ms per 60 Hz step (median of the steps), the top box's sag and drift, and the state
// hash for each pba solver. --budget instead runs the stacks and a small pyramid under the four
// solvers at equal budgets of contact passes per step (docs/rigid-bodies.md); --pipeline the
// soft step's phases before the solver (pairs, manifolds) and its islands on the pyramid and the
// falling boxes. Bullet: btDiscreteDynamicsWorld, btDbvtBroadphase, sequential impulses with
// 10 iterations, one step per frame (its default), boxes as btBoxShape, ground a 200 x 2 x 200
// static box, exactly as the peer harnesses set them up. Sleeping is off in both (the
// issue's stacks and the first fall row) except in the "sleep" row.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "pba/rigid_scenes.h"

namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

struct Result {
  double ms = 0, sag = 0, drift = 0;
};

// ---- pba ----
enum class Scene { Stack, Pyramid, Fall };

Result run_pba(Scene scene, int size, int steps, const pba::ContactSettings& settings, std::uint64_t* hash,
               double* asleep_at = nullptr) {
  pba::RigidBodySystem s({.capacity = 4096, .contacts = settings});
  std::vector<pba::RigidBodyId> b;
  switch (scene) {
    case Scene::Stack: b = pba::rigid_scenes::vertical_stack(s, size); break;
    case Scene::Pyramid: b = pba::rigid_scenes::square_pyramid(s, size); break;
    case Scene::Fall: b = pba::rigid_scenes::falling_boxes(s, size); break;
  }
  const pba::Vec3 top0 = s.center_of_mass(b.back());
  std::vector<double> ms;
  for (int i = 0; i < steps; ++i) {
    const auto t0 = Clock::now();
    s.step(1.0 / 60, {0, -9.81, 0});
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    if (asleep_at && *asleep_at < 0 && s.awake_count() == 0) *asleep_at = s.time();
  }
  const pba::Vec3 top = s.center_of_mass(b.back());
  if (hash) *hash = s.hash();
  return {median(ms), top0.y - top.y, std::hypot(top.x - top0.x, top.z - top0.z)};
}

// ---- Bullet ----
Result run_bullet(Scene scene, int size, int steps, bool sleep) {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
  world.setGravity({0, -9.81f, 0});
  btBoxShape ground({200, 1, 200}), cube({0.5f, 0.5f, 0.5f});
  std::vector<btRigidBody*> bodies;
  const float mu = scene == Scene::Pyramid ? 0.6f : 0.5f;
  auto add = [&](btCollisionShape* sh, float m, btVector3 p) {
    btVector3 inertia(0, 0, 0);
    if (m > 0) sh->calculateLocalInertia(m, inertia);
    btTransform t;
    t.setIdentity();
    t.setOrigin(p);
    btRigidBody::btRigidBodyConstructionInfo ci(m, nullptr, sh, inertia);
    ci.m_startWorldTransform = t;
    auto* r = new btRigidBody(ci);
    r->setFriction(mu);
    if (m > 0 && !sleep) r->setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(r);
    bodies.push_back(r);
    return r;
  };
  add(&ground, 0, {0, -1, 0});
  switch (scene) {
    case Scene::Stack:
      for (int i = 0; i < size; ++i) add(&cube, 1, {0, 0.5f + i, 0});
      break;
    case Scene::Pyramid:
      for (int i = 0; i < size; ++i) {
        const int k = size - i;
        for (int a = 0; a < k; ++a)
          for (int c = 0; c < k; ++c) add(&cube, 1, {a - 0.5f * (k - 1), 0.5f + i, c - 0.5f * (k - 1)});
      }
      break;
    case Scene::Fall:
      for (int x = 0; x < size; ++x)
        for (int y = 0; y < size; ++y)
          for (int z = 0; z < size; ++z) add(&cube, 1, {x * 1.5f - 7, 2.0f + y * 1.5f, z * 1.5f - 7});
      break;
  }
  const btVector3 top0 = bodies.back()->getWorldTransform().getOrigin();
  std::vector<double> ms;
  for (int i = 0; i < steps; ++i) {
    const auto t0 = Clock::now();
    world.stepSimulation(1.f / 60.f, 0);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  const btVector3 top = bodies.back()->getWorldTransform().getOrigin();
  for (btRigidBody* r : bodies) {
    world.removeRigidBody(r);
    delete r;
  }
  return {median(ms), top0.y() - top.y(), std::hypot(top.x() - top0.x(), top.z() - top0.z())};
}

// the settings of `solver` at a budget of `passes` contact passes per step: the soft step and
// TGS take passes / 2 substeps of a biased and a relax pass (TGS: one iteration of each), XPBD
// passes / 2 substeps of one position iteration and its velocity pass, sequential impulses
// `passes` iterations
pba::ContactSettings at_budget(pba::RigidSolverType solver, int passes, bool sleep) {
  pba::ContactSettings c{.solver = solver, .sleep = sleep};
  if (passes > 0) {
    c.substeps = std::max(1, passes / 2);
    c.iterations = passes;
  }
  return c;
}

// the four solvers on the equal-budget scenes
int run_budget() {
  struct Case {
    const char* name;
    Scene scene;
    int size, steps;
  };
  const Case cases[] = {{"stack 10", Scene::Stack, 10, 600},
                        {"stack 20", Scene::Stack, 20, 3600},
                        {"stack 40", Scene::Stack, 40, 1200},
                        {"pyramid 10 (385)", Scene::Pyramid, 10, 300}};
  std::printf("%-18s | %-6s | %-28s | %-28s | %-28s | %-28s\n", "scene (steps)", "passes", "soft step ms/sag/drift",
              "SI", "TGS", "XPBD");
  for (const Case& c : cases)
    for (const int passes : {16, 64}) {
      std::printf("%-12s (%4d) | %6d", c.name, c.steps, passes);
      for (const pba::RigidSolverType t : pba::kRigidSolvers) {
        const Result r = run_pba(c.scene, c.size, c.steps, at_budget(t, passes, false), nullptr);
        std::printf(" | %7.3f ms %8.4f %8.4f m", r.ms, r.sag, r.drift);
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  return 0;
}

// ---- the step before the solver (--pipeline): pairs, manifolds, islands and sleep ----

// medians over the steps of one pba run of `scene` under the soft step: the whole step and its
// pre-solver phases (RigidProfile), and the manifolds built and reused in the last step
struct Phases {
  double total = 0, pairs = 0, manifolds = 0, islands = 0;
  std::size_t built = 0, reused = 0, manifold_count = 0;
  double asleep_at = -1;
};

Phases run_pba_phases(Scene scene, int size, int steps, bool sleep) {
  pba::RigidBodySystem s({.capacity = 4096, .contacts = {.sleep = sleep}});
  switch (scene) {
    case Scene::Stack: pba::rigid_scenes::vertical_stack(s, size); break;
    case Scene::Pyramid: pba::rigid_scenes::square_pyramid(s, size); break;
    case Scene::Fall: pba::rigid_scenes::falling_boxes(s, size); break;
  }
  std::vector<double> total, pairs, manifolds, islands;
  Phases out;
  for (int i = 0; i < steps; ++i) {
    const auto t0 = Clock::now();
    s.step(1.0 / 60, {0, -9.81, 0});
    total.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    const pba::RigidProfile& p = s.profile();
    pairs.push_back(1e3 * p.pairs), manifolds.push_back(1e3 * p.manifolds), islands.push_back(1e3 * p.islands);
    if (out.asleep_at < 0 && s.awake_count() == 0) out.asleep_at = s.time();
  }
  out.total = median(total), out.pairs = median(pairs), out.manifolds = median(manifolds), out.islands = median(islands);
  out.built = s.profile().built, out.reused = s.profile().reused, out.manifold_count = s.manifold_count();
  return out;
}

int run_pipeline() {
  struct Case {
    const char* name;
    Scene scene;
    int size, steps;
    bool sleep;
  };
  const Case cases[] = {{"pyramid 20 (2870)", Scene::Pyramid, 20, 120, false},
                        {"fall 1000", Scene::Fall, 10, 600, false},
                        {"fall 1000, sleep", Scene::Fall, 10, 600, true}};
  std::printf("%-18s | %-9s | %-9s | %-9s | %-9s | %-21s | %-9s | %s\n", "scene (steps)", "step ms", "pairs",
              "manifolds", "islands", "built / reused / all", "Bullet ms", "Bullet / pba");
  for (const Case& c : cases) {
    const Phases p = run_pba_phases(c.scene, c.size, c.steps, c.sleep);
    const Result bt = run_bullet(c.scene, c.size, c.steps, c.sleep);
    std::printf("%-12s (%3d) | %9.3f | %9.3f | %9.3f | %9.3f | %6zu %6zu %7zu | %9.3f | %.2fx", c.name, c.steps, p.total,
                p.pairs, p.manifolds, p.islands, p.built, p.reused, p.manifold_count, bt.ms, bt.ms / p.total);
    if (c.sleep) std::printf("  (all asleep at %.2f s)", p.asleep_at);
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  if (argc > 1 && std::strcmp(argv[1], "--budget") == 0) return run_budget();
  if (argc > 1 && std::strcmp(argv[1], "--pipeline") == 0) return run_pipeline();
  struct Case {
    const char* name;
    Scene scene;
    int size, steps;
    bool sleep = false;
  };
  const std::vector<Case> cases = quick ? std::vector<Case>{{"stack 10", Scene::Stack, 10, 120}}
                                        : std::vector<Case>{{"stack 10", Scene::Stack, 10, 600},
                                                            {"stack 20", Scene::Stack, 20, 600},
                                                            {"stack 40", Scene::Stack, 40, 600},
                                                            {"fall 1000", Scene::Fall, 10, 600},
                                                            {"fall 1000, sleep", Scene::Fall, 10, 600, true},
                                                            {"pyramid 20 (2870)", Scene::Pyramid, 20, 60}};
  // pba's four solvers at their defaults, then Bullet
  std::printf("%-18s", "scene");
  for (const pba::RigidSolverType t : pba::kRigidSolvers) std::printf(" | %-28s", std::string(pba::to_string(t)).c_str());
  std::printf(" | %-28s | %s\n", "Bullet ms/sag/drift", "Bullet / pba soft");
  for (const Case& c : cases) {
    std::printf("%-18s", c.name);
    Result soft{};
    std::uint64_t hashes[pba::kRigidSolvers.size()] = {};
    double asleep = -1;
    for (std::size_t k = 0; k < pba::kRigidSolvers.size(); ++k) {
      const Result r = run_pba(c.scene, c.size, c.steps, at_budget(pba::kRigidSolvers[k], 0, c.sleep), &hashes[k],
                               k == 0 ? &asleep : nullptr);
      if (k == 0) soft = r;
      std::printf(" | %7.3f ms %8.4f %8.4f m", r.ms, r.sag, r.drift);
      std::fflush(stdout);
    }
    const Result bt = run_bullet(c.scene, c.size, c.steps, c.sleep);
    std::printf(" | %7.3f ms %8.4f %8.4f m | %.2fx  (hashes", bt.ms, bt.sag, bt.drift, bt.ms / soft.ms);
    for (const std::uint64_t h : hashes) std::printf(" %016llx", static_cast<unsigned long long>(h));
    std::printf(")");
    if (c.sleep && asleep < 0) std::printf("  pba soft: not all asleep after %d steps", c.steps);
    if (c.sleep && asleep >= 0) std::printf("  pba soft: all asleep at %.2f s", asleep);
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}
