// Cloth benchmark (issue 5): a hanging cloth swinging down from one pinned edge, pba's
// XPBD cloth against Bullet soft bodies on the same mesh, pins, masses and constraint
// set, in the same process and run.
//
//   bench_cloth [--quick] [--repeat R] [--grids 32,64,128,256] [--configs 1x10,10x3,30x1]
//               [--frames WARM MEASURED] [--equal-strain N,...] [--budget CPU_SECONDS]
//               [--engine both|pba|bullet] [--bullet-order creation|reversed|random]
//
// Defaults: every grid and configuration above, 120 warm-up + 120 measured frames, 3
// fresh runs per row, equal-strain searches at 128^2. --quick: 32^2 and 64^2, 20 + 20
// frames, 1 run, searches at 64^2 (seconds). Run it on one core: taskset -c 1.
//
// Scene: a 1 m square of N x N particles, 1 kg in total (every particle 1/N^2 kg; the
// N particles of the pinned edge are then made immovable), starting horizontal in the
// xz plane at y = 0 and at rest, the edge z = 0 pinned, gravity (0, -10, 0) m/s^2,
// 60 Hz frames. Particle (i, j) starts at (i h, 0, j h), h = 1 / (N - 1), and has index
// j N + i in both engines. Each frame advances 1/60 s as `substeps` steps of
// 1/(60 substeps) s with `iterations` solver sweeps each.
//
// Per (engine, grid, substeps x iterations) it prints: CPU time per frame (median and
// p90 over the measured frames, after the warm-up frames), strain |l - l0| / l0 over
// the structural edges (mean and max at the end, max over the run, mean averaged over
// the measured frames), total energy (kinetic + gravitational, E0 = 0 at the start) at
// the end and its maximum over the run, heap allocations per frame, and divergence:
//   - a position or velocity that is not finite, or
//   - a particle more than 1.5 m from the pinned particle of its column (the column is
//     1 m long: 50% stretch), or
//   - energy above E0 + 0.5 J (energy created: 10% of the 5 J released when the cloth
//     falls from horizontal to hanging straight down).
// A diverged run stops at that frame. Then: the ratios of the two engines' times, the
// comparison at equal strain both ways (Bullet searched for pba's 30x1 strain, pba for
// Bullet's; see equal_strain()), and the goals, met or not.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include "alloc_count.h"
#include "pba/core.h"

// pba's side needs the soft-body library; -DPBA_CLOTH_BENCH_BULLET_ONLY builds Bullet's alone
#if __has_include("pba/soft.h") && !defined(PBA_CLOTH_BENCH_BULLET_ONLY)
#include "pba/soft.h"
#define PBA_CLOTH_BENCH_HAS_PBA 1
#else
#define PBA_CLOTH_BENCH_HAS_PBA 0
#endif

namespace {

using pba::Vec3;
using pba::test_support::g_allocations;

constexpr double kGravity = 10.0;       // m/s^2, along -y
constexpr double kFrameDt = 1.0 / 60.0;  // s
constexpr double kSide = 1.0;            // m
constexpr double kTotalMass = 1.0;       // kg, before the pinned edge is made immovable
constexpr double kMaxColumnReach = 1.5;  // m, divergence threshold (column length 1 m)
constexpr double kEnergyGrowth = 0.5;    // J, divergence threshold above E0

// --- timing -------------------------------------------------------------------------

// per-frame times are this thread's CPU time, so pre-emption by other processes on the
// shared machine does not count
double cpu_now() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size() - 1) + 0.5));
  return v[i];
}

// --- the shared scene ---------------------------------------------------------------

struct Config {
  int substeps = 1;    // steps per 1/60 s frame
  int iterations = 1;  // solver sweeps per step
  std::string label() const { return std::to_string(substeps) + "x" + std::to_string(iterations); }
};

// grid geometry shared by both engines: index j n + i, pinned edge j = 0
struct Grid {
  int n = 0;       // particles per side
  double h = 0;    // m, rest spacing
  double m = 0;    // kg, mass of a free particle
  std::vector<std::pair<int, int>> structural;  // (i, i+1) and (j, j+1) neighbours
  explicit Grid(int n_) : n(n_), h(kSide / (n_ - 1)), m(kTotalMass / (double(n_) * n_)) {
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (i + 1 < n) structural.emplace_back(idx(i, j), idx(i + 1, j));
        if (j + 1 < n) structural.emplace_back(idx(i, j), idx(i, j + 1));
      }
  }
  int idx(int i, int j) const { return j * n + i; }
  int count() const { return n * n; }
  bool pinned(int k) const { return k < n; }
  Vec3 start(int k) const { return {(k % n) * h, 0.0, (k / n) * h}; }
};

struct Strain {
  double mean = 0, max = 0;
};

// an engine under test: advances whole frames and copies its state out in grid order
class Engine {
 public:
  virtual ~Engine() = default;
  virtual const char* name() const = 0;
  // advance 1/60 s
  virtual void frame() = 0;
  // positions (m) and velocities (m/s) of every particle, index j n + i
  virtual void read(std::vector<Vec3>& x, std::vector<Vec3>& v) const = 0;
  // mass (kg) of particle k, 0 for a pinned particle
  virtual double mass(int k) const = 0;
  // internal steps taken so far (to check the substep count)
  virtual long long steps() const = 0;
  // a disagreement between the engine's own measurements and the bench's, or empty
  virtual std::string check(const Strain&) const { return {}; }
  // false when the engine allocates through something other than operator new
  virtual bool counts_allocations() const { return true; }
};

// --- Bullet soft body ---------------------------------------------------------------

// Bullet's link solver (btSoftBody::PSolve_Links) is position-based dynamics with a
// stiffness kLST in [0, 1] per material and no compliance; per step it integrates
// v += g dt, x += v dt, runs `piterations` Gauss-Seidel sweeps over the links in their
// order of creation, and sets v = (x - x_prev) / dt (Mueller et al. 2007, PBD).
struct BulletStiffness {
  double stretch = 1, shear = 1, bend = 1;  // kLST of each link class
};

// the order Bullet's Gauss-Seidel sweep visits the links in (an experiment: the
// benchmark's figures use Creation)
enum class BulletOrder {
  Creation,  // CreatePatch's structural links row by row from the pinned edge, then shear, then bend
  Reversed,  // the same, backwards: from the free edge towards the pinned one
  Random,    // btSoftBody::randomizeConstraints (Bullet's own "reduce solver bias" shuffle)
};

class BulletCloth final : public Engine {
 public:
  BulletCloth(const Grid& g, const Config& c, const BulletStiffness& k, BulletOrder order) : c_(c) {
    // world: no rigid bodies, so the soft body collides with nothing
    world_ = std::make_unique<btSoftRigidDynamicsWorld>(&dispatcher_, &broadphase_, &solver_, &collision_);
    world_->setGravity(btVector3(0, btScalar(-kGravity), 0));
    btSoftBodyWorldInfo& info = world_->getWorldInfo();
    info.m_broadphase = &broadphase_;
    info.m_dispatcher = &dispatcher_;
    info.m_gravity = btVector3(0, btScalar(-kGravity), 0);
    info.m_sparsesdf.Initialize();
    world_->setInternalTickCallback(&BulletCloth::on_tick, this);

    // mesh: nodes j n + i at (i h, 0, j h), the structural links of the grid and two
    // triangles per cell; gendiags = false, the shear links are added below
    const btScalar s = btScalar(kSide);
    body_ = btSoftBodyHelpers::CreatePatch(info, btVector3(0, 0, 0), btVector3(s, 0, 0), btVector3(0, 0, s),
                                           btVector3(s, 0, s), g.n, g.n, 0, false);
    body_->m_materials[0]->m_kLST = btScalar(k.stretch);
    btSoftBody::Material* shear = body_->appendMaterial();
    shear->m_kLST = btScalar(k.shear);
    btSoftBody::Material* bend = body_->appendMaterial();
    bend->m_kLST = btScalar(k.bend);

    // shear: both diagonals of every cell; bending: every second neighbour along i and j
    // (the same sets as pba's cloth, see append_matching_links)
    append_matching_links(g, shear, bend);
    if (order == BulletOrder::Reversed)
      for (int a = 0, b = body_->m_links.size() - 1; a < b; ++a, --b) body_->m_links.swap(a, b);
    if (order == BulletOrder::Random) body_->randomizeConstraints();  // a fixed-seed shuffle

    // masses: 1 kg over all N^2 nodes (setTotalMass), then the pinned edge immovable
    body_->setTotalMass(btScalar(kTotalMass));
    for (int i = 0; i < g.n; ++i) body_->setMass(g.idx(i, 0), 0);

    // solver: iterations per step, no damping, no drag or lift, no collisions
    body_->m_cfg.piterations = c.iterations;
    body_->m_cfg.kDP = 0;
    body_->m_cfg.kDG = 0;
    body_->m_cfg.kLF = 0;
    body_->m_cfg.collisions = 0;
    world_->addSoftBody(body_);
  }
  ~BulletCloth() override {
    world_->removeSoftBody(body_);
    delete body_;
  }
  BulletCloth(const BulletCloth&) = delete;
  BulletCloth& operator=(const BulletCloth&) = delete;

  const char* name() const override { return "Bullet"; }
  void frame() override {
    // `substeps` fixed steps of 1/(60 substeps) s; steps() counts them to make sure
    // Bullet's float time accumulator took exactly that many
    world_->stepSimulation(btScalar(kFrameDt), c_.substeps, btScalar(kFrameDt / c_.substeps));
  }
  void read(std::vector<Vec3>& x, std::vector<Vec3>& v) const override {
    const int n = body_->m_nodes.size();
    x.resize(std::size_t(n));
    v.resize(std::size_t(n));
    for (int k = 0; k < n; ++k) {
      const btSoftBody::Node& node = body_->m_nodes[k];
      x[std::size_t(k)] = Vec3(node.m_x.x(), node.m_x.y(), node.m_x.z());
      v[std::size_t(k)] = Vec3(node.m_v.x(), node.m_v.y(), node.m_v.z());
    }
  }
  double mass(int k) const override { return double(body_->getMass(k)); }
  long long steps() const override { return ticks_; }
  // Bullet allocates through btAlignedAlloc (malloc), which the counter does not see
  bool counts_allocations() const override { return false; }

 private:
  static void on_tick(btDynamicsWorld* w, btScalar) { static_cast<BulletCloth*>(w->getWorldUserInfo())->ticks_++; }

  void append_matching_links(const Grid& g, btSoftBody::Material* shear, btSoftBody::Material* bend) {
    const int n = g.n;
    for (int j = 0; j + 1 < n; ++j)
      for (int i = 0; i + 1 < n; ++i) {
        body_->appendLink(g.idx(i, j), g.idx(i + 1, j + 1), shear);
        body_->appendLink(g.idx(i + 1, j), g.idx(i, j + 1), shear);
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (i + 2 < n) body_->appendLink(g.idx(i, j), g.idx(i + 2, j), bend);
        if (j + 2 < n) body_->appendLink(g.idx(i, j), g.idx(i, j + 2), bend);
      }
  }

  Config c_;
  btSoftBodyRigidBodyCollisionConfiguration collision_;
  btCollisionDispatcher dispatcher_{&collision_};
  btDbvtBroadphase broadphase_;
  btSequentialImpulseConstraintSolver solver_;
  std::unique_ptr<btSoftRigidDynamicsWorld> world_;
  btSoftBody* body_ = nullptr;
  long long ticks_ = 0;
};

// --- measurement --------------------------------------------------------------------

struct Result {
  std::string engine, grid, config;
  std::vector<double> frame_ms;     // measured frames
  double allocs_per_frame = -1;     // heap allocations (operator new) per measured frame, -1: not counted
  double mean_strain_end = 0, max_strain_end = 0, max_strain_run = 0, mean_strain_avg = 0;
  double energy_end = 0, energy_max = 0;  // J, E0 = 0
  bool diverged = false;
  std::string why;                  // divergence reason
  std::uint64_t hash = 0;           // final positions and velocities
  long long steps = 0, steps_expected = 0;
  double ms_med = 0, ms_p90 = 0;    // ms per frame: median and 90th percentile
};

Strain strain(const Grid& g, const std::vector<Vec3>& x) {
  Strain s;
  for (const auto& [a, b] : g.structural) {
    const double e = std::abs(glm::length(x[std::size_t(b)] - x[std::size_t(a)]) - g.h) / g.h;
    s.mean += e;
    s.max = std::max(s.max, e);
  }
  s.mean /= double(g.structural.size());
  return s;
}

double energy(const Engine& e, const std::vector<Vec3>& x, const std::vector<Vec3>& v) {
  double sum = 0;
  for (std::size_t k = 0; k < x.size(); ++k)
    sum += e.mass(int(k)) * (0.5 * glm::dot(v[k], v[k]) + kGravity * x[k].y);
  return sum;
}

// the first divergence criterion met, or empty
std::string divergence(const Grid& g, const std::vector<Vec3>& x, const std::vector<Vec3>& v, double E) {
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (!pba::is_finite(x[k]) || !pba::is_finite(v[k])) return "non-finite particle " + std::to_string(k);
    const std::size_t top = k % std::size_t(g.n);
    if (glm::length(x[k] - x[top]) > kMaxColumnReach) return "particle " + std::to_string(k) + " beyond 1.5 m";
  }
  if (!(E <= kEnergyGrowth)) return "energy " + pba::format_value(E) + " J > 0.5 J";
  return {};
}

Result run(Engine& e, const Grid& g, const Config& c, int warm, int measured) {
  Result r;
  r.engine = e.name();
  r.grid = std::to_string(g.n) + "^2";
  r.config = c.label();
  std::vector<Vec3> x, v;
  x.reserve(std::size_t(g.count()));
  v.reserve(std::size_t(g.count()));
  long long allocs = 0;
  double strain_sum = 0;
  std::vector<double> all_ms;  // every frame, warm-up included
  // the same start: positions (to float precision), masses, pins
  e.read(x, v);
  for (int k = 0; k < g.count() && r.why.empty(); ++k) {
    const double m = g.pinned(k) ? 0.0 : g.m;
    if (glm::length(x[std::size_t(k)] - g.start(k)) > 1e-6 || std::abs(e.mass(k) - m) > 1e-6 * g.m)
      r.why = "SETUP DIFFERS at particle " + std::to_string(k);
  }
  for (int f = 0; f < warm + measured; ++f) {
    // the timed frame, with its heap allocations
    const long long a0 = g_allocations.load(std::memory_order_relaxed);
    const double t0 = cpu_now();
    try {
      e.frame();
    } catch (const pba::Error& err) {
      r.diverged = true;
      r.why = "frame " + std::to_string(f) + ": " + err.what();
      break;
    }
    const double t1 = cpu_now();
    const long long a1 = g_allocations.load(std::memory_order_relaxed);
    all_ms.push_back(1e3 * (t1 - t0));
    if (f >= warm) {
      r.frame_ms.push_back(1e3 * (t1 - t0));
      allocs += a1 - a0;
    }
    // state, strain, energy, divergence (not timed)
    e.read(x, v);
    const Strain s = strain(g, x);
    const double E = energy(e, x, v);
    r.mean_strain_end = s.mean;
    r.max_strain_end = s.max;
    r.max_strain_run = std::max(r.max_strain_run, s.max);
    r.energy_end = E;
    r.energy_max = f == 0 ? E : std::max(r.energy_max, E);
    if (f >= warm) strain_sum += s.mean;
    if (const std::string why = divergence(g, x, v, E); !why.empty()) {
      r.diverged = true;
      r.why = "frame " + std::to_string(f) + ": " + why;
      break;
    }
  }
  if (!r.diverged && r.why.empty()) r.why = e.check(strain(g, x));
  r.mean_strain_avg = r.frame_ms.empty() ? r.mean_strain_end : strain_sum / double(r.frame_ms.size());
  if (e.counts_allocations()) r.allocs_per_frame = r.frame_ms.empty() ? 0 : double(allocs) / double(r.frame_ms.size());
  r.hash = pba::hash_span(std::span<const Vec3>(x), pba::hash_span(std::span<const Vec3>(v)));
  r.steps = e.steps();
  r.steps_expected = (long long)(warm + measured) * c.substeps;
  // a run that diverged during the warm-up is timed over the frames it ran
  const std::vector<double>& timed = r.frame_ms.empty() ? all_ms : r.frame_ms;
  r.ms_med = quantile(timed, 0.5);
  r.ms_p90 = quantile(timed, 0.9);
  if (r.frame_ms.empty()) r.why += " (timed over its " + std::to_string(all_ms.size()) + " frames)";
  return r;
}

// --- pba cloth ----------------------------------------------------------------------

// compliances of pba's cloth (m/N): stretch and shear rigid, bending pba's default
constexpr double kStretchCompliance = 0.0;
constexpr double kShearCompliance = 0.0;
constexpr double kBendCompliance = 1e-4;

#if PBA_CLOTH_BENCH_HAS_PBA
// pba::SoftBody::cloth_grid with XPBD: particle j n + i at (i h, 0, j h), row j = 0
// pinned, 1 kg split evenly over all N^2 particles (the pinned ones keep their share),
// stretch constraints on grid edges, shear on both diagonals of every cell, bend between
// particles two apart along i and j; the constraints are solved colour by colour.
class PbaCloth final : public Engine {
 public:
  PbaCloth(const Grid& g, const Config& c) : substeps_(c.substeps) {
    // the grid
    pba::ClothDef cloth;
    cloth.origin = {0, 0, 0};
    cloth.edge_u = {kSide, 0, 0};
    cloth.edge_v = {0, 0, kSide};
    cloth.nx = g.n;
    cloth.ny = g.n;
    cloth.mass = kTotalMass;
    cloth.pins = pba::ClothPins::FirstRow;
    cloth.shear = true;
    cloth.bending = true;
    // the solver: no damping, drag or aerodynamics
    pba::SoftBodyDef def;
    def.solver = pba::SoftSolver::Xpbd;
    def.substeps = c.substeps;
    def.iterations = c.iterations;
    def.stretch_compliance = kStretchCompliance;
    def.shear_compliance = kShearCompliance;
    def.bend_compliance = kBendCompliance;
    def.spring_damping = 0;
    def.damping = 0;
    def.forces = pba::Forces{};
    def.forces.gravity = {0, -kGravity, 0};
    def.aero = pba::SoftAero{};
    body_ = pba::SoftBody::cloth_grid(cloth, def);
  }
  const char* name() const override { return "pba"; }
  void frame() override {
    body_.step(double(frames_) * kFrameDt, kFrameDt);
    ++frames_;
  }
  void read(std::vector<Vec3>& x, std::vector<Vec3>& v) const override {
    x.resize(body_.size());
    v.resize(body_.size());
    for (std::size_t k = 0; k < body_.size(); ++k) {
      x[k] = body_.position(k);
      v[k] = body_.velocity(k);
    }
  }
  double mass(int k) const override {
    return body_.inverse_mass(std::size_t(k)) > 0 ? body_.mass(std::size_t(k)) : 0.0;
  }
  long long steps() const override { return body_.steps() * substeps_; }
  std::string check(const Strain& s) const override {
    // the library's own strain over its stretch constraints must agree with ours
    // (float positions: agreement to 1e-3 relative plus 1e-5 absolute)
    const pba::StrainStats own = body_.strain_stats();
    if (std::abs(own.mean - s.mean) > 1e-5 + 1e-3 * s.mean || std::abs(own.max - s.max) > 1e-5 + 1e-3 * s.max)
      return "strain_stats() " + pba::format_value(own.mean) + " / " + pba::format_value(own.max) + " disagrees";
    return {};
  }

 private:
  pba::SoftBody body_;
  int substeps_ = 1;
  long long frames_ = 0;
};
#endif

// Bullet's stiffness matching an XPBD compliance alpha on one constraint between two
// free particles of mass m at step dt: one XPBD projection from rest moves the pair by
// the fraction w / (w + alpha / dt^2) of the violation, w = 2 / m (Macklin, Mueller and
// Chentanez 2016, eq. 18), and one PBD projection by the fraction kLST.
double bullet_stiffness(double alpha, const Grid& g, const Config& c) {
  const double dt = kFrameDt / c.substeps;
  const double w = 2.0 / g.m;
  return w / (w + alpha / (dt * dt));
}

BulletOrder g_bullet_order = BulletOrder::Creation;  // --bullet-order

std::unique_ptr<Engine> make_bullet(const Grid& g, const Config& c) {
  BulletStiffness k;
  k.stretch = bullet_stiffness(kStretchCompliance, g, c);
  k.shear = bullet_stiffness(kShearCompliance, g, c);
  k.bend = bullet_stiffness(kBendCompliance, g, c);
  return std::make_unique<BulletCloth>(g, c, k, g_bullet_order);
}

std::unique_ptr<Engine> make_pba([[maybe_unused]] const Grid& g, [[maybe_unused]] const Config& c) {
#if PBA_CLOTH_BENCH_HAS_PBA
  return std::make_unique<PbaCloth>(g, c);
#else
  return nullptr;
#endif
}

// --- runs and tables ----------------------------------------------------------------

struct Options {
  int repeat = 3;
  std::vector<int> grids{32, 64, 128, 256};
  std::vector<Config> configs{{1, 10}, {10, 3}, {30, 1}};
  int warm = 120, measured = 120;
  std::vector<int> equal_strain_grids{128};
  int goal_grid = 128;  // the grid the goals name
  double equal_strain_budget = 1200;  // s of CPU time for the equal-strain search
  bool run_pba = true, run_bullet = true;
};

// `repeat` fresh runs of one engine; times are the medians over the runs of each run's
// median and p90, the physics is the first run's (every run must give the same bits)
Result repeated(std::unique_ptr<Engine> (*make)(const Grid&, const Config&), const Grid& g, const Config& c,
                const Options& o) {
  Result first;
  std::vector<double> med, p90;
  bool same_bits = true;
  for (int r = 0; r < o.repeat; ++r) {
    std::unique_ptr<Engine> e = make(g, c);
    Result res = run(*e, g, c, o.warm, o.measured);
    med.push_back(res.ms_med);
    p90.push_back(res.ms_p90);
    if (r == 0) first = std::move(res);
    else same_bits = same_bits && res.hash == first.hash;
  }
  first.ms_med = quantile(med, 0.5);
  first.ms_p90 = quantile(p90, 0.5);
  if (!same_bits) first.why += (first.why.empty() ? "" : "; ") + std::string("RUNS DIFFER IN BITS");
  return first;
}

void print_header() {
  std::printf("| engine | grid | substeps x iters | ms/frame med | ms/frame p90 | mean strain end | max strain end "
              "| max strain run | mean strain avg | E end (J) | E max (J) | diverged | allocs/frame |\n");
  std::printf("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|\n");
}

void print_row(const Result& r) {
  std::string note = r.diverged ? "**yes** (" + r.why + ")" : (r.why.empty() ? "no" : "no; " + r.why);
  if (r.steps != r.steps_expected && !r.diverged)
    note += "; " + std::to_string(r.steps) + " steps, expected " + std::to_string(r.steps_expected);
  const std::string allocs = r.allocs_per_frame < 0 ? "—" : pba::format_value(r.allocs_per_frame);
  std::printf("| %s | %s | %s | %.3f | %.3f | %.2e | %.2e | %.2e | %.2e | %.4f | %.2e | %s | %s |\n",
              r.engine.c_str(), r.grid.c_str(), r.config.c_str(), r.ms_med, r.ms_p90, r.mean_strain_end,
              r.max_strain_end, r.max_strain_run, r.mean_strain_avg, r.energy_end, r.energy_max, note.c_str(),
              allocs.c_str());
  std::fflush(stdout);
}

// "At equal strain": Bullet's link solver has no compliance, so its strain at a given
// cost is whatever its steps and sweeps leave; so is pba's with rigid constraints. The
// measure is the mean strain averaged over the measured frames, and the knob the number
// of substeps at one iteration (the cheapest way to cut a position solver's strain,
// Macklin et al. 2019, "Small Steps"). From an engine's 30 x 1 run the substeps are
// halved while it stays at or below the target strain, or doubled until it gets there
// (each doubling also tries the same work as 30 substeps x more iterations); then a
// bisection narrows the substep count to within 1/16. A run that diverges counts as
// missing the target. The fastest run at or below the target is the one compared. If
// the CPU-time budget (--budget) runs out first, the ratio against the most expensive
// run is a bound.
struct EqualStrain {
  std::vector<Result> tried;
  int chosen = -1;  // index into tried, -1 when no run reached the target strain
};

using Maker = std::unique_ptr<Engine> (*)(const Grid&, const Config&);

EqualStrain equal_strain(Maker make, const Grid& g, const Result& start, double target, const Options& o) {
  EqualStrain es;
  const double frames = double(o.repeat) * (o.warm + o.measured);
  double spent = 0;  // s of CPU time, from the measured frame times
  const auto meets = [&](const Result& r) { return !r.diverged && r.mean_strain_avg <= target; };
  const auto record = [&](Result r) -> const Result* {
    es.tried.push_back(std::move(r));
    const Result& t = es.tried.back();
    print_row(t);
    spent += 1e-3 * t.ms_med * frames;
    if (meets(t) && (es.chosen < 0 || t.ms_med < es.tried[std::size_t(es.chosen)].ms_med))
      es.chosen = int(es.tried.size()) - 1;
    return &t;
  };
  // one configuration, unless its estimated cost would overrun the budget
  const auto attempt = [&](const Config& c, double estimate_ms) -> const Result* {
    if (spent + 1e-3 * estimate_ms * frames > o.equal_strain_budget) return nullptr;
    return record(repeated(make, g, c, o));
  };

  // bracket: lo substeps miss the target (0: none tried), hi substeps meet it
  int lo = 0, hi = 0;
  double hi_ms = 0;
  const Result* r = record(start);
  double last_ms = r->ms_med;
  if (meets(*r)) {
    hi = 30, hi_ms = r->ms_med;
  } else {
    for (lo = 30; hi == 0; lo *= 2) {
      const int s = 2 * lo;
      if (!(r = attempt({s, 1}, 2 * last_ms))) return es;
      last_ms = r->ms_med;
      if (meets(*r)) hi = s, hi_ms = r->ms_med;
      if (!attempt({30, s / 30}, 2 * last_ms)) return es;
      if (hi) break;
    }
  }
  // bisection on the substep count
  while (hi - lo > std::max(1, hi / 16)) {
    const int mid = lo + (hi - lo) / 2;
    if (!(r = attempt({mid, 1}, hi_ms * mid / hi))) break;
    if (meets(*r)) hi = mid, hi_ms = r->ms_med;
    else lo = mid;
  }
  return es;
}

// Bullet's time over pba's at equal strain, searching `searched` (its 30x1 run is
// `start`) for the strain of `fixed`; prints the search and returns the ratio
double equal_strain_ratio(Maker make, const Grid& g, const Result& start, const Result& fixed, bool bullet_searched,
                          const Options& o) {
  std::printf("\n### %s at %s's strain, %s (%s %s: mean strain avg %.2e, %.3f ms)\n\n", start.engine.c_str(),
              fixed.engine.c_str(), fixed.grid.c_str(), fixed.engine.c_str(), fixed.config.c_str(),
              fixed.mean_strain_avg, fixed.ms_med);
  print_header();
  const EqualStrain es = equal_strain(make, g, start, fixed.mean_strain_avg, o);
  const Result* found = es.chosen >= 0 ? &es.tried[std::size_t(es.chosen)] : nullptr;
  if (!found)  // the bound: the most (Bullet) or least (pba) expensive run tried
    for (const Result& r : es.tried)
      if (!found || (bullet_searched ? r.ms_med > found->ms_med : r.ms_med < found->ms_med)) found = &r;
  const double ratio = bullet_searched ? found->ms_med / fixed.ms_med : fixed.ms_med / found->ms_med;
  if (es.chosen >= 0)
    std::printf("\n%s's fastest run at or below %s's strain: %s, mean strain avg %.2e, %.3f ms: pba %.1fx "
                "faster than Bullet at equal strain.\n",
                start.engine.c_str(), fixed.engine.c_str(), found->config.c_str(), found->mean_strain_avg,
                found->ms_med, ratio);
  else
    std::printf("\n%s did not reach %s's strain within the budget (%s, %.3f ms): pba %s %.1fx faster.\n",
                start.engine.c_str(), fixed.engine.c_str(), found->config.c_str(), found->ms_med,
                bullet_searched ? "more than" : "less than", ratio);
  return ratio;
}

std::vector<int> parse_list(const char* s) {
  std::vector<int> v;
  for (const char* p = s; *p;) {
    char* end = nullptr;
    const long x = std::strtol(p, &end, 10);
    if (end == p) break;
    v.push_back(int(x));
    p = *end == ',' ? end + 1 : end;
  }
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  // options
  Options o;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) {
      o.repeat = 1, o.grids = {32, 64}, o.warm = 20, o.measured = 20;
      o.equal_strain_grids = {64}, o.goal_grid = 64;
      o.equal_strain_budget = 2;
    } else if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc) {
      o.repeat = std::max(1, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--grids") && i + 1 < argc) {
      o.grids = parse_list(argv[++i]);
    } else if (!std::strcmp(argv[i], "--configs") && i + 1 < argc) {
      // "30x1,10x3": substeps x iterations
      o.configs.clear();
      for (const char* p = argv[++i]; *p;) {
        char* end = nullptr;
        const long sub = std::strtol(p, &end, 10);
        if (*end != 'x') break;
        const long it = std::strtol(end + 1, &end, 10);
        o.configs.push_back({int(std::clamp(sub, 1L, 10000L)), int(std::clamp(it, 1L, 1000L))});
        p = *end == ',' ? end + 1 : end;
      }
    } else if (!std::strcmp(argv[i], "--frames") && i + 2 < argc) {
      o.warm = std::max(0, std::atoi(argv[++i]));
      o.measured = std::max(1, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--equal-strain") && i + 1 < argc) {
      o.equal_strain_grids = parse_list(argv[++i]);
    } else if (!std::strcmp(argv[i], "--budget") && i + 1 < argc) {
      o.equal_strain_budget = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--bullet-order") && i + 1 < argc) {
      const std::string b = argv[++i];
      g_bullet_order = b == "reversed" ? BulletOrder::Reversed : b == "random" ? BulletOrder::Random : BulletOrder::Creation;
    } else if (!std::strcmp(argv[i], "--engine") && i + 1 < argc) {
      const std::string e = argv[++i];
      o.run_pba = e != "bullet";
      o.run_bullet = e != "pba";
    } else {
      // --help, or anything unknown
      const bool help = !std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h");
      std::fprintf(help ? stdout : stderr,
                   "usage: %s [--quick] [--repeat R] [--grids 32,64,128,256] [--configs 1x10,10x3,30x1] "
                   "[--frames WARM MEASURED] "
                   "[--equal-strain N,... (0: off)] [--budget CPU_SECONDS] [--engine both|pba|bullet] "
                   "[--bullet-order creation|reversed|random]\n",
                   argv[0]);
      return help ? 0 : 2;
    }
  }
  if (o.configs.empty()) {
    std::fprintf(stderr, "--configs: expected substeps x iterations, e.g. 30x1,10x3\n");
    return 2;
  }
  for (int n : o.grids)
    if (n < 2) {
      std::fprintf(stderr, "--grids: every grid needs at least 2 particles per side, got %d\n", n);
      return 2;
    }
  if (!PBA_CLOTH_BENCH_HAS_PBA) {
    std::printf("pba/soft.h is not available in this build: Bullet only.\n");
    o.run_pba = false;
  }

  std::printf("# Cloth: hanging cloth swinging down from one pinned edge\n\n");
  std::printf("1 m square, 1 kg, g = %.0f m/s^2, 60 Hz frames, %d warm-up + %d measured frames, %d run(s) per "
              "row (medians). Bullet %d, btScalar = %zu bytes. CPU time of this thread per frame.\n\n",
              kGravity, o.warm, o.measured, o.repeat, btGetVersion(), sizeof(btScalar));

  // the constraint sets and Bullet's stiffness for pba's bend compliance
  const std::vector<Config>& configs = o.configs;
  std::printf("Both engines: stretch on the grid edges, shear on both diagonals of every cell, bend between "
              "particles two apart along each axis; pba compliances stretch %g, shear %g, bend %g m/N; Bullet "
              "kLST stretch 1, shear 1, bend matched per step (bullet_stiffness):",
              kStretchCompliance, kShearCompliance, kBendCompliance);
  for (int n : o.grids)
    for (const Config& c : configs)
      std::printf(" %d^2 %s %.4f%s", n, c.label().c_str(), bullet_stiffness(kBendCompliance, Grid(n), c),
                  n == o.grids.back() && &c == &configs.back() ? ".\n\n" : ",");

  // the main table
  std::vector<Result> pba_rows, bullet_rows;
  print_header();
  for (int n : o.grids) {
    const Grid g(n);
    for (const Config& c : configs) {
      if (o.run_pba) print_row(pba_rows.emplace_back(repeated(&make_pba, g, c, o)));
      if (o.run_bullet) print_row(bullet_rows.emplace_back(repeated(&make_bullet, g, c, o)));
    }
  }

  // ratios measured in the same run
  if (o.run_pba && o.run_bullet) {
    std::printf("\n### pba against Bullet, same settings\n\n");
    std::printf("| grid | substeps x iters | pba ms | Bullet ms | Bullet / pba time | pba mean strain avg | "
                "Bullet mean strain avg |\n|---|---|---:|---:|---:|---:|---:|\n");
    for (std::size_t k = 0; k < pba_rows.size(); ++k) {
      const Result& p = pba_rows[k];
      const Result& b = bullet_rows[k];
      std::printf("| %s | %s | %.3f | %.3f | %.1fx | %.2e | %.2e |\n", p.grid.c_str(), p.config.c_str(), p.ms_med,
                  b.ms_med, b.ms_med / p.ms_med, p.mean_strain_avg, b.mean_strain_avg);
    }
  }

  // equal strain, both ways: Bullet searched for pba's strain, pba for Bullet's
  const auto find = [](const std::vector<Result>& rows, int n, const char* config) -> const Result* {
    for (const Result& r : rows)
      if (r.grid == std::to_string(n) + "^2" && r.config == config) return &r;
    return nullptr;
  };
  double equal_ratio = 0;
  for (int n : o.equal_strain_grids) {
    const Result* p = find(pba_rows, n, "30x1");
    const Result* b = find(bullet_rows, n, "30x1");
    if (!p || !b) continue;
    const double ratio = equal_strain_ratio(&make_bullet, Grid(n), *b, *p, true, o);
    if (n == o.goal_grid) equal_ratio = ratio;
    if (!b->diverged) equal_strain_ratio(&make_pba, Grid(n), *p, *b, false, o);
  }

  // goals
  if (const Result* goal = find(pba_rows, o.goal_grid, "30x1")) {
    bool any_diverged = false;
    for (const Result& r : pba_rows) any_diverged = any_diverged || r.diverged;
    double allocs = 0;
    for (const Result& r : pba_rows) allocs = std::max(allocs, r.allocs_per_frame);
    std::printf("\n### Goals (%d^2, 30 substeps x 1 iteration)\n\n| goal | measured | met? |\n|---|---|---|\n",
                o.goal_grid);
    std::printf("| <= 4 ms per frame | %.3f ms | %s |\n", goal->ms_med, goal->ms_med <= 4 ? "yes" : "no");
    std::printf("| mean strain <= 1%% | %.3f%% end, %.3f%% averaged | %s |\n", 100 * goal->mean_strain_end,
                100 * goal->mean_strain_avg,
                goal->mean_strain_end <= 0.01 && goal->mean_strain_avg <= 0.01 ? "yes" : "no");
    if (equal_ratio > 0)
      std::printf("| >= 10x faster than Bullet at equal strain | %.1fx | %s |\n", equal_ratio,
                  equal_ratio >= 10 ? "yes" : "no");
    std::printf("| no divergence, any configuration | %s | %s |\n", any_diverged ? "diverged" : "none",
                any_diverged ? "no" : "yes");
    std::printf("| zero allocations per step | %s per frame (max over rows) | %s |\n",
                pba::format_value(allocs).c_str(), allocs == 0 ? "yes" : "no");
  }
  return 0;
}
