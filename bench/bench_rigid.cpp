// pba rigid bodies, under each of its four contact solvers, against Bullet 3.24 and ODE 0.16
// on the rigid-body issue's scenes (bench/rigid/bench_scenes.cpp: vertical stacks, Jolt's
// 1240-box pyramid, the 2870-box square pyramid, 1000 falling boxes, a rain of 10,000 boxes
// and spheres, 5000 bodies at 250 m/s in a closed box, 1764 bodies on a 20,000-triangle
// terrain), all in this process, one core:
//   taskset -c 1 build/release/bin/bench_rigid [--scene KEY] [--steps N] [--repeat K]
//                                             [--peer all|bullet|ode|none] [--solver all|NAME] [--profile]
//                                             [--trace MS]
//   taskset -c 1 build/release/bin/bench_rigid --quick | --budget
// For each scene a table: per engine the median, mean and slowest ms per 60 Hz step, the top
// box's sag and drift from where it rests (stacks and pyramids), the bodies that left the
// scene (escapes), the bodies awake at the end, each peer's time over the row's (how many
// times faster than the peer the row is) and pba's state hash. With --repeat K the engines run
// in K rounds, each once a round (the peers, then pba's solvers), and each engine's run of
// median ms is shown: a shared host whose speed drifts over the minute a scene takes then
// touches every engine's runs alike (the ratios are of the engines' medians, whose runs may
// come from different rounds). --profile adds under each pba row the medians
// of its step's phases (RigidProfile: collide with pairs and manifolds; solve with prepare, integrate, contacts,
// finish, and islands and sleep within finish), the
// manifolds built and reused in the last step, when every body first slept, and the deepest
// overlap any manifold started a step with (m, and the step: read outside the timing), and under
// Bullet's row its own (its manifolds' points after each step's collision phase). --trace MS prints
// each pba step slower than MS ms with its phases. --budget instead runs the stacks and a
// small pyramid under the four solvers at equal budgets of contact passes per step
// (docs/rigid-bodies.md). The peers copy each scene from the pba system the scene's builder
// filled (bench/rigid/peer_bullet.cpp, peer_ode.cpp), set up as shared/peers/ does.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "pba/rigid_scenes.h"
#include "rigid/bench_scenes.h"

namespace {

using Clock = std::chrono::steady_clock;
using pba::bench::BenchResult;
using pba::bench::BenchScene;

// ---- pba ----

// a pba run: the table's figures, and the medians of each phase of RigidProfile over the steps
struct PbaResult : BenchResult {
  pba::RigidProfile phases{};  // (s)
  std::size_t manifolds = 0;   // after the last step
  double asleep_at = -1;       // when every body first slept (s; -1: never)
  int most_substeps = 0;       // the most substeps a step took (RigidProfile::substeps)
  int tallest = 0;             // the tallest column the soft step measured (RigidProfile::column)
  // the substeps over time: each run of steps that took the same count, as "8 x0-125" (the
  // count, then its first and last step), for --profile
  std::string substeps_runs;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// --trace MS: every pba step slower than MS ms printed with its phases (0: none)
double g_trace_ms = 0;

PbaResult run_pba(const BenchScene& scene, int steps, const pba::ContactSettings& settings) {
  PbaResult r;
  try {
    pba::RigidBodySystem s({.capacity = 16384, .contacts = settings});
    const std::vector<pba::RigidBodyId> b = scene.build(s);
    const pba::Vec3 rest = scene.top_rest ? scene.top_rest() : (b.empty() ? pba::Vec3(0) : s.center_of_mass(b.back()));
    std::vector<double> ms;
    std::vector<char> out(b.size(), 0);
    std::vector<double> phase[10];  // each phase of RigidProfile, by step
    int last_substeps = 0;
    for (int i = 0; i < steps; ++i) {
      const auto t0 = Clock::now();
      s.step(1.0 / 60, {0, -9.81, 0});
      ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      const pba::RigidProfile& p = s.profile();
      const double parts[10] = {p.collide, p.solve,     p.total,     p.pairs,    p.manifolds,
                                p.islands, p.prepare, p.integrate, p.contacts, p.finish};
      for (int k = 0; k < 10; ++k) phase[k].push_back(parts[k]);
      r.most_substeps = std::max(r.most_substeps, p.substeps), r.tallest = std::max(r.tallest, p.column);
      if (i == 0 || p.substeps != last_substeps) {
        if (i > 0) r.substeps_runs += "-" + std::to_string(i - 1) + ", ";
        r.substeps_runs += std::to_string(p.substeps) + " x" + std::to_string(i);
        last_substeps = p.substeps;
      }
      if (i + 1 == steps) r.substeps_runs += "-" + std::to_string(i);
      if (g_trace_ms > 0 && ms.back() > g_trace_ms)
        std::printf("    step %4d %7.2f ms: pairs %.2f manifolds %.2f (%zu built, %zu reused, %zu one-point) | prepare %.2f integrate %.2f "
                    "contacts %.2f finish %.2f (islands %.2f) | %zu awake, %zu proxies moved\n",
                    i, ms.back(), 1e3 * p.pairs, 1e3 * p.manifolds, p.built, p.reused, p.one_point, 1e3 * p.prepare,
                    1e3 * p.integrate, 1e3 * p.contacts, 1e3 * p.finish, 1e3 * p.islands, s.awake_count(), p.moved);
      if (r.asleep_at < 0 && s.awake_count() == 0) r.asleep_at = s.time();
      // (after the clock: not timed) the deepest overlap the step started with
      for (std::size_t k = 0, m = s.manifold_count(); k < m; ++k) {
        const double depth = s.manifold(k).depth;
        if (depth > r.deepest) r.deepest = depth, r.deepest_step = i;
      }
      for (std::size_t j = 0; j < b.size(); ++j)
        if (!out[j] && scene.escaped(s.center_of_mass(b[j]))) out[j] = 1, ++r.escapes;
    }
    r.ran = true;
    pba::bench::summarize_times(ms, r);
    if (!b.empty()) pba::bench::sag_and_drift(s.center_of_mass(b.back()), rest, r);
    r.awake = static_cast<int>(s.awake_count());
    r.hash = s.hash();
    r.phases.collide = median(phase[0]), r.phases.solve = median(phase[1]), r.phases.total = median(phase[2]);
    r.phases.pairs = median(phase[3]), r.phases.manifolds = median(phase[4]), r.phases.islands = median(phase[5]);
    r.phases.prepare = median(phase[6]), r.phases.integrate = median(phase[7]);
    r.phases.contacts = median(phase[8]), r.phases.finish = median(phase[9]);
    r.phases.built = s.profile().built, r.phases.reused = s.profile().reused;
    r.phases.substeps = s.profile().substeps, r.phases.column = s.profile().column;
    r.phases.half_load = s.profile().half_load;
    r.manifolds = s.manifold_count();
  } catch (const pba::Error& e) {
    r.note = e.what();
  }
  return r;
}

// the settings of `solver` at a budget of `passes` contact passes per step: the soft step and
// TGS take passes / 2 substeps of a biased and a relax pass (TGS: one iteration of each), XPBD
// passes / 2 substeps of one position iteration and its velocity pass, sequential impulses
// `passes` iterations; 0: the defaults
pba::ContactSettings at_budget(pba::RigidSolverType solver, int passes, bool sleep) {
  pba::ContactSettings c{.solver = solver, .sleep = sleep};
  if (passes > 0) {
    c.substeps = std::max(1, passes / 2);
    c.auto_substeps = false;  // (the budget is exact)
    c.iterations = passes;
  }
  return c;
}

// the four solvers on the equal-budget scenes
int run_budget() {
  std::vector<BenchScene> cases;
  for (BenchScene& c : pba::bench::bench_scenes())
    if (c.key == "stack10" || c.key == "stack20" || c.key == "stack40") cases.push_back(c);
  cases[1].steps = 3600, cases[2].steps = 1200;
  cases.push_back({.key = "pyramid385", .title = "pyramid 10 (385)", .steps = 300,
                   .build = [](pba::RigidBodySystem& s) { return pba::rigid_scenes::square_pyramid(s, 10); },
                   .has_top = true, .escaped = [](const pba::Vec3&) { return false; }});
  std::printf("%-18s | %-6s | %-28s | %-28s | %-28s | %-28s\n", "scene (steps)", "passes", "soft step ms/sag/drift",
              "SI", "TGS", "XPBD");
  for (const BenchScene& c : cases)
    for (const int passes : {16, 64}) {
      std::printf("%-12s (%4d) | %6d", c.title.c_str(), c.steps, passes);
      for (const pba::RigidSolverType t : pba::kRigidSolvers) {
        const BenchResult r = run_pba(c, c.steps, at_budget(t, passes, false));
        std::printf(" | %7.3f ms %8.4f %8.4f m", r.ms, r.sag, r.drift);
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  return 0;
}

// ---- the tables ----

// the phases of a pba row (median ms per step of the run)
void print_profile(const PbaResult& r) {
  const pba::RigidProfile& p = r.phases;
  std::printf("  %24s phases: collide %.3f (pairs %.3f, manifolds %.3f) | solve %.3f (prepare %.3f, integrate %.3f, "
              "contacts %.3f, finish %.3f, of which islands %.3f) | total %.3f ms"
              "  (%zu manifolds: %zu built, %zu reused; all asleep %s; deepest overlap %.4f m at step %d; "
              "substeps %d at the end, at most %d; tallest column %d; load at half the substeps %.3f)\n",
              "", 1e3 * p.collide, 1e3 * p.pairs, 1e3 * p.manifolds, 1e3 * p.solve, 1e3 * p.prepare, 1e3 * p.integrate,
              1e3 * p.contacts, 1e3 * p.finish, 1e3 * p.islands, 1e3 * p.total,
              r.manifolds, p.built, p.reused, r.asleep_at < 0 ? "never" : (std::to_string(r.asleep_at) + " s").c_str(),
              r.deepest, r.deepest_step, p.substeps, r.most_substeps, r.tallest, p.half_load);
  std::printf("  %24s substeps by step: %s\n", "", r.substeps_runs.c_str());
}

struct Options {
  std::string scene = "all";
  int steps = 0;   // 0: the scene's own
  int repeat = 1;
  bool bullet = true, ode = true;
  bool profile = false;  // a line of per-phase medians under each pba row
  double reuse = -1;     // the pair cache's reuse distance (m); < 0: the default
  double reuse_angle = -1;  // ... and its relative turn (degrees); < 0: the default
  int substeps = 0;      // the solver's substeps, exactly (auto off; sequential impulses: ignored); 0: the default
  double down_sag = -1;  // ContactSettings::auto_substeps_sag (m): fewer substeps where the columns allow; < 0: the default
  double down_fraction = -1;  // ContactSettings::auto_substeps_sag_fraction (of a body's size); < 0: the default
  int least = 0;  // ContactSettings::auto_substeps_least: the fewest substeps the lowering takes; 0: the default
  std::vector<pba::RigidSolverType> solvers{pba::kRigidSolvers.begin(), pba::kRigidSolvers.end()};
};

// of an engine's runs, the one of median ms (a run that failed, if any: its note says why)
template <class Result>
Result median_of(std::vector<Result> runs) {
  for (const Result& r : runs)
    if (!r.ran) return r;
  std::sort(runs.begin(), runs.end(), [](const Result& a, const Result& b) { return a.ms < b.ms; });
  return runs[runs.size() / 2];
}

void print_row(const char* engine, const BenchScene& scene, const BenchResult& r, const BenchResult& bullet,
               const BenchResult& ode, bool is_pba) {
  std::printf("  %-24s", engine);
  if (!r.ran) {
    std::printf(" not run: %s\n", r.note.c_str());
    return;
  }
  std::printf(" %9.3f %9.3f %9.2f", r.ms, r.mean, r.max);
  if (scene.has_top)
    std::printf(" %9.4f %9.4f", r.sag, r.drift);
  else
    std::printf(" %9s %9s", "-", "-");
  std::printf(" %7d %6d", r.escapes, r.awake);
  // how many times the peers' time per step the row's is
  if (bullet.ran && &r != &bullet) std::printf(" %8.2fx", bullet.ms / r.ms); else std::printf(" %9s", "");
  if (ode.ran && &r != &ode) std::printf(" %8.2fx", ode.ms / r.ms); else std::printf(" %9s", "");
  if (is_pba) std::printf("  %016llx", static_cast<unsigned long long>(r.hash));
  // the top box half a metre down has fallen; as far aside with no drop, the top has slid
  if (scene.has_top && std::abs(r.sag) > 0.5) std::printf("  (fell)");
  else if (scene.has_top && r.drift > 0.5) std::printf("  (slid)");
  std::printf("\n");
}

// one scene under the chosen engines, as a table
void run_scene(const BenchScene& scene, const Options& o) {
  const int steps = o.steps > 0 ? o.steps : scene.steps;
  std::printf("== %s: %d steps of 1/60 s, sleeping %s, median of %d run%s ==\n", scene.title.c_str(), steps,
              scene.sleep ? "on" : "off", o.repeat, o.repeat > 1 ? "s" : "");
  std::printf("  %-24s %9s %9s %9s %9s %9s %7s %6s %9s %9s  %s\n", "engine", "ms/step", "mean", "max", "sag m",
              "drift m", "escapes", "awake", "Bullet/", "ODE/", "hash");
  std::fflush(stdout);
  // each solver's settings at the default budget and the options
  std::vector<pba::ContactSettings> settings;
  for (const pba::RigidSolverType t : o.solvers) {
    pba::ContactSettings c = at_budget(t, 0, scene.sleep);
    if (o.reuse >= 0) c.reuse_distance = o.reuse;
    if (o.reuse_angle >= 0) c.reuse_angle = o.reuse_angle * (std::numbers::pi / 180);
    if (o.substeps > 0) c.substeps = o.substeps, c.auto_substeps = false;  // (exactly N)
    if (o.down_sag >= 0) c.auto_substeps_sag = o.down_sag;
    if (o.down_fraction >= 0) c.auto_substeps_sag_fraction = o.down_fraction;
    if (o.least > 0) c.auto_substeps_least = o.least;
    settings.push_back(c);
  }
  // the rounds: each engine once a round, the peers first (copied from the scene's pba system)
  std::vector<BenchResult> bullet_runs, ode_runs;
  std::vector<std::vector<PbaResult>> pba_runs(o.solvers.size());
  {
    pba::RigidBodySystem s({.capacity = 16384});
    const std::vector<pba::RigidBodyId> tracked = scene.build(s);
    for (int k = 0; k < o.repeat; ++k) {
      if (o.bullet) bullet_runs.push_back(pba::bench::run_bullet(scene, s, tracked, steps));
      if (o.ode) ode_runs.push_back(pba::bench::run_ode(scene, s, tracked, steps));
      for (std::size_t i = 0; i < o.solvers.size(); ++i) pba_runs[i].push_back(run_pba(scene, steps, settings[i]));
    }
  }
  BenchResult bullet, ode;
  if (o.bullet) bullet = median_of(bullet_runs);
  if (o.ode) ode = median_of(ode_runs);
  for (std::size_t i = 0; i < o.solvers.size(); ++i) {
    const std::string name = "pba " + std::string(pba::to_string(o.solvers[i]));
    const PbaResult r = median_of(pba_runs[i]);
    // a mesh scene pba cannot collide with yet: say so instead of a figure
    if (scene.has_mesh && (!r.ran || r.escapes > 0)) {
      std::printf("  %-24s pba: mesh contacts not supported yet (%s)\n", name.c_str(),
                  r.ran ? (std::to_string(r.escapes) + " bodies fell through the terrain").c_str() : r.note.c_str());
      continue;
    }
    print_row(name.c_str(), scene, r, bullet, ode, true);
    if (o.profile && r.ran) print_profile(r);
    std::fflush(stdout);
  }
  if (o.bullet) {
    const std::string name = "Bullet 3.24 (" + std::to_string(scene.bullet_iterations) + " it" +
                             (scene.bullet_ccd ? ", CCD)" : ")");
    print_row(name.c_str(), scene, bullet, bullet, ode, false);
    if (o.profile && bullet.ran)
      std::printf("  %24s deepest overlap %.4f m at step %d (its manifolds' points after its collision phase)\n", "",
                  bullet.deepest, bullet.deepest_step);
  }
  if (o.ode) print_row("ODE 0.16 QuickStep 20", scene, ode, bullet, ode, false);
  std::printf("\n");
  std::fflush(stdout);
}

int usage(const char* why) {
  if (why) std::fprintf(stderr, "bench_rigid: %s\n", why);
  std::fprintf(stderr,
               "usage: bench_rigid [--scene KEY|all] [--steps N] [--repeat K] [--peer all|bullet|ode|none]\n"
               "                   [--solver all|soft-step|sequential-impulse|tgs|xpbd] [--reuse M] [--reuse-angle DEG]\n"
               "                   [--substeps N] [--down M] [--down-fraction F] [--least N] [--profile]\n"
               "                   [--trace MS] | --quick | --budget\n"
               "scenes:");
  for (const BenchScene& s : pba::bench::bench_scenes()) std::fprintf(stderr, " %s", s.key.c_str());
  std::fprintf(stderr, "\n");
  return why ? 2 : 0;
}

// a positive integer argument
bool count_arg(const char* text, int* out) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (!end || *end || v < 1 || v > 1000000) return false;
  *out = static_cast<int>(v);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const char* value = i + 1 < argc ? argv[i + 1] : nullptr;
    auto need = [&] {
      if (!value) std::exit(usage((a + ": missing value").c_str()));
      ++i;
      return std::string(value);
    };
    if (a == "--budget") return run_budget();
    if (a == "--help" || a == "-h") return usage(nullptr);
    if (a == "--quick") {
      quick = true;
    } else if (a == "--profile") {
      o.profile = true;
    } else if (a == "--trace") {
      const std::string v = need();
      char* end = nullptr;
      g_trace_ms = std::strtod(v.c_str(), &end);
      if (!end || *end || !(g_trace_ms > 0)) return usage(("--trace '" + v + "': expected a time in ms > 0").c_str());
    } else if (a == "--scene") {
      o.scene = need();
    } else if (a == "--steps") {
      if (!count_arg(need().c_str(), &o.steps)) return usage(("--steps '" + std::string(value) + "': expected a count").c_str());
    } else if (a == "--repeat") {
      if (!count_arg(need().c_str(), &o.repeat)) return usage(("--repeat '" + std::string(value) + "': expected a count").c_str());
    } else if (a == "--reuse") {
      const std::string v = need();
      char* end = nullptr;
      o.reuse = std::strtod(v.c_str(), &end);
      if (!end || *end || !(o.reuse >= 0 && o.reuse < 1))
        return usage(("--reuse '" + v + "': expected a distance in [0, 1) m").c_str());
    } else if (a == "--reuse-angle") {
      const std::string v = need();
      char* end = nullptr;
      o.reuse_angle = std::strtod(v.c_str(), &end);
      if (!end || *end || !(o.reuse_angle >= 0 && o.reuse_angle <= 180))
        return usage(("--reuse-angle '" + v + "': expected an angle in [0, 180] degrees").c_str());
    } else if (a == "--substeps") {
      if (!count_arg(need().c_str(), &o.substeps) || o.substeps > 64)
        return usage(("--substeps '" + std::string(value) + "': expected a count in [1, 64]").c_str());
    } else if (a == "--down") {
      const std::string v = need();
      char* end = nullptr;
      o.down_sag = std::strtod(v.c_str(), &end);
      if (v.empty() || *end || !(o.down_sag >= 0 && o.down_sag < 1))
        return usage(("--down '" + v + "': expected a sag budget in [0, 1) m").c_str());
    } else if (a == "--down-fraction") {
      const std::string v = need();
      char* end = nullptr;
      o.down_fraction = std::strtod(v.c_str(), &end);
      if (v.empty() || *end || !(o.down_fraction >= 0 && o.down_fraction <= 1))
        return usage(("--down-fraction '" + v + "': expected a sag budget in [0, 1] of a body's size").c_str());
    } else if (a == "--least") {
      if (!count_arg(need().c_str(), &o.least) || o.least > 64)
        return usage(("--least '" + std::string(value) + "': expected a count in [1, 64]").c_str());
    } else if (a == "--peer") {
      const std::string p = need();
      if (p != "all" && p != "bullet" && p != "ode" && p != "none")
        return usage(("--peer '" + p + "': expected all, bullet, ode or none").c_str());
      o.bullet = p == "all" || p == "bullet";
      o.ode = p == "all" || p == "ode";
    } else if (a == "--solver") {
      const std::string t = need();
      if (t != "all") {
        try {
          o.solvers = {pba::parse_rigid_solver(t, "--solver")};
        } catch (const pba::Error& e) {
          return usage(e.what());
        }
      }
    } else {
      return usage(("unknown argument '" + a + "'").c_str());
    }
  }
  std::vector<BenchScene> scenes;
  for (const BenchScene& s : pba::bench::bench_scenes())
    if (quick ? s.key == "stack10" : (o.scene == "all" || o.scene == s.key)) scenes.push_back(s);
  if (scenes.empty()) return usage(("--scene '" + o.scene + "': no such scene").c_str());
  if (quick && o.steps == 0) o.steps = 120;
  for (const BenchScene& s : scenes) run_scene(s, o);
  return 0;
}
