// bench_rigid's scenes: each a builder from include/pba/rigid_scenes.h with the settings the
// peers ran it with (steps, sleeping, Bullet's iterations and CCD, the peers' unit masses),
// which body's sag and drift are reported, and when a body has left the scene. The peers
// (peer_bullet.cpp, peer_ode.cpp) copy each scene from the pba system the builder filled,
// so every engine starts from the same bodies.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "pba/rigid.h"

namespace pba::bench {

/// One benchmark scene.
struct BenchScene {
  std::string key{};  ///< command-line name (--scene KEY)
  std::string title{};  ///< the table's name
  int steps = 600;    ///< 60 Hz steps per run
  bool sleep = false; ///< sleeping on (pba, Bullet and ODE alike)
  /// Fills a system with the scene and returns its dynamic bodies (the top one last when
  /// `has_top`).
  std::function<std::vector<RigidBodyId>(RigidBodySystem&)> build{};
  bool has_top = false;  ///< the last body's sag and drift mean something (stacks, pyramids)
  /// Where the last body rests when the scene stands (m); unset: its start.
  std::function<Vec3()> top_rest{};
  /// True when a body centred at `c` (m) has left the scene (through a wall or the ground).
  std::function<bool(const Vec3& c)> escaped{};
  /// Peers: every dynamic body of mass 1 kg (the peer harnesses' cube scenes; ODE's CFM is
  /// not scale-free), else the pba body's mass.
  bool unit_mass = false;
  int bullet_iterations = 10;  ///< btContactSolverInfo::m_numIterations
  bool bullet_ccd = false;     ///< Bullet's continuous collision on every dynamic body
  bool has_mesh = false;       ///< the scene's static geometry is a triangle mesh
};

/// What one engine measured on one scene.
struct BenchResult {
  bool ran = false;       ///< false: not run (the reason in `note`)
  double ms = 0;          ///< median wall time per step (ms)
  double mean = 0;        ///< mean wall time per step (ms)
  double max = 0;         ///< slowest step (ms)
  double sag = 0;         ///< the top body's drop from where it rests (m)
  double drift = 0;       ///< the top body's horizontal distance from where it rests (m)
  int escapes = 0;        ///< bodies that left the scene at some step
  int awake = -1;         ///< dynamic bodies awake at the end (-1: not known)
  std::uint64_t hash = 0; ///< pba: the system's state hash after the run
  /// The deepest overlap of any contact point at the start of any step (m; the narrow
  /// phase's, before that step's solve; 0 when none overlapped), and that step (-1: none or
  /// not known: ODE)
  double deepest = 0;
  int deepest_step = -1;
  std::string note;       ///< why it did not run, or what went wrong
};

/// The scenes of the rigid-body issue's benchmark, in the default run's order.
std::vector<BenchScene> bench_scenes();

/// The median, mean and largest of the step times `ms` into `r`.
inline void summarize_times(std::vector<double> ms, BenchResult& r) {
  if (ms.empty()) return;
  r.mean = 0;
  for (const double m : ms) r.mean += m / static_cast<double>(ms.size());
  std::sort(ms.begin(), ms.end());
  r.ms = ms[ms.size() / 2];
  r.max = ms.back();
}

/// Sag and drift of `top` against `rest` (m).
inline void sag_and_drift(const Vec3& top, const Vec3& rest, BenchResult& r) {
  r.sag = rest.y - top.y;
  r.drift = std::hypot(top.x - rest.x, top.z - rest.z);
}

// ---- the peers (each copies the scene from `s`, built and not yet stepped) ----

/// Bullet 3.24 (float, btDiscreteDynamicsWorld, sequential impulses, one step per frame).
BenchResult run_bullet(const BenchScene& scene, const RigidBodySystem& s, const std::vector<RigidBodyId>& tracked,
                       int steps);
/// ODE 0.16 (double, dHashSpace, dWorldQuickStep with 20 iterations, ERP 0.2, CFM 1e-5).
BenchResult run_ode(const BenchScene& scene, const RigidBodySystem& s, const std::vector<RigidBodyId>& tracked,
                    int steps);

}  // namespace pba::bench
