// `pba run SCENE.json --steps N [--csv out.csv] [--every K]`: the headless scene runner.
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "commands_run.h"
#include "pba/scene.h"

namespace {

constexpr const char* kRunHelp =
    "usage: pba run SCENE.json [--steps N] [--csv FILE] [--every K] [--method NAME] [--quiet]\n"
    "       pba run --builder NAME [...]\n"
    "\n"
    "Runs a scene file (docs/scene-format.md) headless for N fixed steps of the scene's dt\n"
    "and prints a summary: particles, simulated time, the final state hash, wall time per\n"
    "step and where it went (per-phase profile). Stops with an error naming the particle and\n"
    "the time if the state becomes non-finite.\n"
    "\n"
    "  --steps N        steps to run, 1..1000000000 (default: 1000)\n"
    "  --csv FILE       write the state every K steps (and at step 0): one row per particle,\n"
    "                   columns step,time,particle,x,y,z,vx,vy,vz (SI units)\n"
    "  --every K        CSV interval in steps, 1..1000000000 (default: 1)\n"
    "  --method NAME    override the scene's integrator (" 
    "euler, semi-implicit-euler, verlet, velocity-verlet, rk4, implicit-euler)\n"
    "  --builder NAME   run a built-in scene builder instead of a file (see --list)\n"
    "  --list           list the built-in scene builders\n"
    "  --quiet          print only the final hash\n"
    "\n"
    "Exit codes: 0 success, 1 bad scene file or failed simulation, 2 bad command line.\n";

struct Usage {
  std::string message;
};

long long parse_count(const std::string& text, const char* flag, long long lo, long long hi) {
  // whole-string integer with range check
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0)
    throw Usage{std::string(flag) + ": expected an integer, got '" + text + "'"};
  if (v < lo || v > hi)
    throw Usage{std::string(flag) + ": must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                text};
  return v;
}

// one CSV block: every particle at this step
void write_rows(std::FILE* f, long long step, double t, const pba::ParticleSystem& ps) {
  const auto x = ps.xs(), y = ps.ys(), z = ps.zs(), vx = ps.vxs(), vy = ps.vys(), vz = ps.vzs();
  for (std::size_t i = 0; i < ps.size(); ++i)
    std::fprintf(f, "%lld,%.17g,%zu,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", step, t, i, x[i], y[i], z[i], vx[i], vy[i],
                 vz[i]);
}

struct Options {
  std::string scene;
  std::string builder;
  long long steps = 1000;
  long long every = 1;
  std::string csv;
  std::optional<pba::Method> method;
  bool quiet = false;
  bool list = false;
  bool help = false;
};

Options parse(int argc, char** argv) {
  Options o;
  // words after the subcommand name
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* flag) -> std::string {
      if (i + 1 >= argc) throw Usage{std::string(flag) + ": missing value"};
      return argv[++i];
    };
    if (a == "--help" || a == "-h") {
      o.help = true;
    } else if (a == "--steps") {
      o.steps = parse_count(value("--steps"), "--steps", 1, 1000000000LL);
    } else if (a == "--every") {
      o.every = parse_count(value("--every"), "--every", 1, 1000000000LL);
    } else if (a == "--csv") {
      o.csv = value("--csv");
      if (o.csv.empty()) throw Usage{"--csv: must not be empty"};
    } else if (a == "--method") {
      const std::string m = value("--method");
      try {
        o.method = pba::parse_method(m, "--method");
      } catch (const pba::Error& e) {
        throw Usage{e.what()};
      }
    } else if (a == "--builder") {
      o.builder = value("--builder");
    } else if (a == "--list") {
      o.list = true;
    } else if (a == "--quiet") {
      o.quiet = true;
    } else if (!a.empty() && a[0] == '-') {
      throw Usage{"unknown flag '" + a + "' for 'pba run'"};
    } else if (o.scene.empty()) {
      o.scene = a;
    } else {
      throw Usage{"unexpected argument '" + a + "' (one scene file per run)"};
    }
  }
  if (o.help || o.list) return o;
  if (o.scene.empty() && o.builder.empty()) throw Usage{"missing scene file (or --builder NAME)"};
  if (!o.scene.empty() && !o.builder.empty()) throw Usage{"give a scene file or --builder, not both"};
  return o;
}

}  // namespace

int pba_run_command(int argc, char** argv) {
  Options o;
  try {
    o = parse(argc, argv);
  } catch (const Usage& u) {
    std::fprintf(stderr, "pba run: %s\n(see 'pba run --help')\n", u.message.c_str());
    return 2;
  }
  if (o.help) {
    std::fputs(kRunHelp, stdout);
    return 0;
  }
  if (o.list) {
    for (const auto& b : pba::scenes::builders())
      std::printf("%-16s %s\n", std::string(b.name).c_str(), std::string(b.description).c_str());
    return 0;
  }
  try {
    // the scene: a file, or a builder with its defaults
    std::unique_ptr<pba::Scene> scene;
    if (!o.builder.empty()) {
      const pba::scenes::Builder* found = nullptr;
      for (const auto& b : pba::scenes::builders())
        if (b.name == o.builder) found = &b;
      if (!found) {
        std::fprintf(stderr, "pba run: --builder: unknown builder '%s' (see 'pba run --list')\n", o.builder.c_str());
        return 2;
      }
      scene = std::make_unique<pba::Scene>(pba::Scene{o.builder, std::string(found->description), pba::World()});
      found->build(scene->world);
    } else {
      scene = std::make_unique<pba::Scene>(pba::load_scene(o.scene));
    }
    pba::World& w = scene->world;
    if (o.method) w.particles().set_method(*o.method);
    // the CSV file, with its header and the initial state
    std::FILE* csv = nullptr;
    if (!o.csv.empty()) {
      csv = std::fopen(o.csv.c_str(), "w");
      if (!csv) {
        std::fprintf(stderr, "pba run: --csv: cannot write '%s'\n", o.csv.c_str());
        return 1;
      }
      std::fputs("step,time,particle,x,y,z,vx,vy,vz\n", csv);
      write_rows(csv, 0, w.time(), w.particles());
    }
    // step, accumulating the per-phase profile
    pba::WorldProfile sum;
    pba::Stopwatch wall;
    std::size_t contacts = 0;
    try {
      for (long long s = 1; s <= o.steps; ++s) {
        w.step();
        const pba::WorldProfile& p = w.profile();
        sum.kinematic += p.kinematic, sum.sync += p.sync, sum.emit += p.emit, sum.integrate += p.integrate;
        sum.collide += p.collide, sum.recycle += p.recycle, sum.constraints += p.constraints;
        sum.systems += p.systems, sum.total += p.total;
        contacts += w.particles().contacts();
        if (csv && s % o.every == 0) write_rows(csv, s, w.time(), w.particles());
      }
    } catch (const pba::Error& e) {
      if (csv) std::fclose(csv);
      std::fprintf(stderr, "pba run: %s: %s\n", o.scene.empty() ? o.builder.c_str() : o.scene.c_str(), e.what());
      return 1;
    }
    const double seconds = wall.seconds();
    if (csv && std::fclose(csv) != 0) {
      std::fprintf(stderr, "pba run: --csv: error writing '%s'\n", o.csv.c_str());
      return 1;
    }
    // the summary
    const double n = static_cast<double>(o.steps);
    if (o.quiet) {
      std::printf("%016llx\n", static_cast<unsigned long long>(w.hash()));
      return 0;
    }
    std::printf("scene        %s\n", scene->name.c_str());
    std::printf("steps        %lld x %.9g s = %.6g s simulated (%s)\n", o.steps, w.stepper().settings().fixed_dt,
                w.time(), std::string(pba::name(w.particles().method())).c_str());
    std::printf("entities     %zu, particles alive %zu, contacts %.3g per step\n", w.entity_count(),
                w.particles().size(), static_cast<double>(contacts) / n);
    std::printf("final hash   %016llx\n", static_cast<unsigned long long>(w.hash()));
    std::printf("wall time    %.6g s, %.4g ms per step (including CSV output)\n", seconds, seconds / n * 1e3);
    std::printf("profile      ms per step: kinematic %.4g, sync %.4g, emit %.4g, integrate %.4g, collide %.4g, "
                "recycle %.4g, constraints %.4g, systems %.4g, total %.4g\n",
                sum.kinematic / n * 1e3, sum.sync / n * 1e3, sum.emit / n * 1e3, sum.integrate / n * 1e3,
                sum.collide / n * 1e3, sum.recycle / n * 1e3, sum.constraints / n * 1e3, sum.systems / n * 1e3,
                sum.total / n * 1e3);
    if (!o.csv.empty()) std::printf("csv          %s (every %lld steps)\n", o.csv.c_str(), o.every);
    return 0;
  } catch (const pba::Error& e) {
    std::fprintf(stderr, "pba run: %s\n", e.what());
    return 1;
  }
}
