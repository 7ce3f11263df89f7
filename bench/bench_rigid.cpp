// pba rigid bodies, under each of its four contact solvers, against Bullet on the scenes of
// shared/peers/ (vertical stacks, the 20-level square pyramid, 1000 falling boxes), all in
// this process, one core:
//   taskset -c 1 build/release/bin/bench_rigid [--quick | --budget] [--scene S] [--solver S] [--steps N] [--profile] [--no-peer]
// Prints ms per 60 Hz step (median of the steps), the top box's sag and drift, and the state
// hash for each pba solver. --budget instead runs the stacks and a small pyramid under the four
// solvers at equal budgets of contact passes per step (docs/rigid-bodies.md). Bullet: btDiscreteDynamicsWorld, btDbvtBroadphase, sequential impulses with
// 10 iterations, one step per frame (its default), boxes as btBoxShape, ground a 200 x 2 x 200
// static box, exactly as the peer harnesses set them up. Sleeping is off in both (the
// issue's stacks and the first fall row) except in the "sleep" row.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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
  pba::RigidProfile profile{};  // medians of each phase over the steps (s)
  std::size_t manifolds = 0;    // after the last step
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
  // each phase of RigidProfile, by step
  std::vector<double> phase[7];
  for (int i = 0; i < steps; ++i) {
    const auto t0 = Clock::now();
    s.step(1.0 / 60, {0, -9.81, 0});
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    const pba::RigidProfile& p = s.profile();
    const double parts[7] = {p.collide, p.solve, p.total, p.prepare, p.integrate, p.contacts, p.finish};
    for (int k = 0; k < 7; ++k) phase[k].push_back(parts[k]);
    if (asleep_at && *asleep_at < 0 && s.awake_count() == 0) *asleep_at = s.time();
  }
  const pba::Vec3 top = s.center_of_mass(b.back());
  if (hash) *hash = s.hash();
  Result r{median(ms), top0.y - top.y, std::hypot(top.x - top0.x, top.z - top0.z)};
  r.profile = {median(phase[0]), median(phase[1]), median(phase[2]), median(phase[3]),
               median(phase[4]), median(phase[5]), median(phase[6])};
  r.manifolds = s.manifold_count();
  return r;
}

// one line of per-phase medians (ms per step)
void print_profile(const char* solver, const Result& r) {
  const pba::RigidProfile& p = r.profile;
  std::printf("    %-18s phases (median ms): collide %.3f | prepare %.3f | integrate %.3f | contacts %.3f | "
              "finish %.3f | total %.3f  (%zu manifolds)\n",
              solver, 1e3 * p.collide, 1e3 * p.prepare, 1e3 * p.integrate, 1e3 * p.contacts, 1e3 * p.finish,
              1e3 * p.total, r.manifolds);
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

// the options: --quick, --budget, --scene NAME (one scene), --solver NAME (one pba solver, with
// Bullet), --steps N (instead of the scene's), --profile (a line of per-phase medians per solver),
// --no-peer (pba only, for profiling)
struct Options {
  bool quick = false, budget = false, profile = false, peer = true;
  std::string scene, solver;
  int steps = 0;
};

int usage(const char* why) {
  std::fprintf(stderr,
               "bench_rigid: %s\nusage: bench_rigid [--quick | --budget] [--scene stack10|stack20|stack40|fall|"
               "fall-sleep|pyramid|pyramid10] [--solver soft-step|sequential-impulse|tgs|xpbd] [--steps N] [--profile] [--no-peer]\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (a == "--quick") o.quick = true;
    else if (a == "--budget") o.budget = true;
    else if (a == "--profile") o.profile = true;
    else if (a == "--no-peer") o.peer = false;
    else if (a == "--scene") o.scene = value();
    else if (a == "--solver") o.solver = value();
    else if (a == "--steps") o.steps = std::atoi(value().c_str());
    else return usage(("unknown option " + a).c_str());
  }
  if (o.budget) return run_budget();
  std::vector<pba::RigidSolverType> solvers(pba::kRigidSolvers.begin(), pba::kRigidSolvers.end());
  if (!o.solver.empty()) {
    try {
      solvers = {pba::parse_rigid_solver(o.solver, "--solver")};
    } catch (const pba::Error& e) {
      return usage(e.what());
    }
  }
  struct Case {
    const char* name;
    const char* key;
    Scene scene;
    int size, steps;
    bool sleep = false;
  };
  std::vector<Case> cases = o.quick ? std::vector<Case>{{"stack 10", "stack10", Scene::Stack, 10, 120}}
                                    : std::vector<Case>{{"stack 10", "stack10", Scene::Stack, 10, 600},
                                                        {"stack 20", "stack20", Scene::Stack, 20, 600},
                                                        {"stack 40", "stack40", Scene::Stack, 40, 600},
                                                        {"fall 1000", "fall", Scene::Fall, 10, 600},
                                                        {"fall 1000, sleep", "fall-sleep", Scene::Fall, 10, 600, true},
                                                        {"pyramid 20 (2870)", "pyramid", Scene::Pyramid, 20, 60}};
  // a scene by itself, not in the full run
  if (o.scene == "pyramid10") cases.push_back({"pyramid 10 (385)", "pyramid10", Scene::Pyramid, 10, 300});
  if (!o.scene.empty()) {
    std::erase_if(cases, [&](const Case& c) { return o.scene != c.key; });
    if (cases.empty()) return usage(("unknown scene " + o.scene).c_str());
  }
  if (o.steps > 0)
    for (Case& c : cases) c.steps = o.steps;
  // pba's solvers at their defaults, then Bullet
  std::printf("%-18s", "scene");
  for (const pba::RigidSolverType t : solvers) std::printf(" | %-28s", std::string(pba::to_string(t)).c_str());
  std::printf(" | %-28s | %s\n", "Bullet ms/sag/drift", "Bullet / pba first");
  for (const Case& c : cases) {
    std::printf("%-18s", c.name);
    Result first{};
    std::vector<Result> results;
    std::vector<std::uint64_t> hashes(solvers.size());
    double asleep = -1;
    for (std::size_t k = 0; k < solvers.size(); ++k) {
      const Result r = run_pba(c.scene, c.size, c.steps, at_budget(solvers[k], 0, c.sleep), &hashes[k],
                               k == 0 ? &asleep : nullptr);
      if (k == 0) first = r;
      results.push_back(r);
      std::printf(" | %7.3f ms %8.4f %8.4f m", r.ms, r.sag, r.drift);
      std::fflush(stdout);
    }
    const Result bt = o.peer ? run_bullet(c.scene, c.size, c.steps, c.sleep) : Result{};
    std::printf(" | %7.3f ms %8.4f %8.4f m | %.2fx  (hashes", bt.ms, bt.sag, bt.drift, bt.ms / first.ms);
    for (const std::uint64_t h : hashes) std::printf(" %016llx", static_cast<unsigned long long>(h));
    std::printf(")");
    if (c.sleep && asleep < 0) std::printf("  pba %s: not all asleep after %d steps",
                                           std::string(pba::to_string(solvers[0])).c_str(), c.steps);
    if (c.sleep && asleep >= 0) std::printf("  pba %s: all asleep at %.2f s",
                                            std::string(pba::to_string(solvers[0])).c_str(), asleep);
    std::printf("\n");
    if (o.profile)
      for (std::size_t k = 0; k < solvers.size(); ++k) print_profile(std::string(pba::to_string(solvers[k])).c_str(), results[k]);
    std::fflush(stdout);
  }
  return 0;
}
