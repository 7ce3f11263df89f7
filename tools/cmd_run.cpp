// `pba run SCENE.json --steps N [--csv out.csv] [--every K]`: the headless scene runner.
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cli.h"
#include "commands_run.h"
#include "pba/scene.h"
#include "pba/soft.h"
#include "progress.h"

namespace {

constexpr const char* kRunAbout =
    "Runs a scene file (docs/scene-format.md) headless for N fixed steps of the scene's dt\n"
    "and prints a summary: particles, simulated time, the final state hash, wall time per\n"
    "step and where it went (per-phase profile). Stops with an error naming the particle and\n"
    "the time if the state becomes non-finite. Shows progress on stderr: a live line on a\n"
    "terminal, a line every 5 s otherwise (PBA_PROGRESS_INTERVAL=SECONDS), none with --quiet.";

constexpr const char* kRunFooter =
    "--csv writes one row per particle and step: step,time,particle,x,y,z,vx,vy,vz,body (SI\n"
    "units). body is 'particles' for the particle system, else the soft body's name, and\n"
    "particle the index within its body. A scene with rigid bodies adds the columns\n"
    "qw,qx,qy,qz and one row per rigid body and step: x,y,z the body frame's origin, vx,vy,vz\n"
    "its velocity, qw..qz its orientation (unit quaternion), particle 0 and body the body's\n"
    "entity name (empty for the particles' and soft bodies' rows). --csv - writes the CSV to\n"
    "standard output and the summary (the final hash too, with --quiet) to standard error, so\n"
    "the output stays one CSV.\n"
    "--method NAME replaces the integrator of everything the scene integrates, its particles\n"
    "and mass-spring soft bodies: euler, semi-implicit-euler, verlet, velocity-verlet, rk4,\n"
    "implicit-euler.\n"
    "An option the scene cannot honour is refused (exit code 2): --method on a scene whose\n"
    "soft bodies are solved by XPBD, or with nothing for an integrator to step; --every\n"
    "without --csv.\n"
    "Exit codes: 0 success, 1 bad scene file or failed simulation, 2 bad command line.";

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

// a CSV field: quoted when it holds a comma, a quote or a line break
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

// the world's soft bodies, or nullptr (never adds the system: that would change the hash)
const pba::SoftSystem* soft_bodies(const pba::World& w) {
  return dynamic_cast<const pba::SoftSystem*>(w.find_system(pba::SoftSystem::kName));
}

// the body column of a soft body: its entity's name, else its index
std::string body_name(const pba::World& w, const pba::SoftSystem& soft, std::size_t i) {
  const std::string& n = w.name(soft.owner(i));
  return n.empty() ? "soft body " + std::to_string(i) : n;
}

// the entities' rigid bodies, in the RigidBodySystem's order (the colliders' stand-ins are
// not the entities' bodies)
std::vector<pba::RigidBodyId> entity_bodies(const pba::World& w) {
  std::vector<pba::RigidBodyId> out;
  for (std::size_t i = 0; i < w.rigid().size(); ++i)
    if (w.valid(w.rigid().id_at(i))) out.push_back(w.rigid().id_at(i));
  return out;
}

// the body column of a rigid body: its entity's name, else "rigid body N"
std::string rigid_name(const pba::World& w, pba::RigidBodyId id) {
  const std::string& n = w.name(w.owner(id));
  return n.empty() ? "rigid body " + std::to_string(id.index) : n;
}

// one CSV block at this step: the particle system's particles (body "particles"), then
// every soft body's particles (body: the entity's name), each numbered within its body,
// then (`rigid`) every rigid body's pose and velocity with the quaternion columns
void write_rows(std::FILE* f, long long step, const pba::World& w, bool rigid) {
  const double t = w.time();
  const char* tail = rigid ? ",,,,\n" : "\n";  // particle rows leave the quaternion columns empty
  const pba::ParticleSystem& ps = w.particles();
  const auto x = ps.xs(), y = ps.ys(), z = ps.zs(), vx = ps.vxs(), vy = ps.vys(), vz = ps.vzs();
  for (std::size_t i = 0; i < ps.size(); ++i)
    std::fprintf(f, "%lld,%.17g,%zu,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,particles%s", step, t, i, x[i], y[i], z[i], vx[i],
                 vy[i], vz[i], tail);
  if (rigid)
    for (const pba::RigidBodyId id : entity_bodies(w)) {
      const pba::Pose p = w.rigid().pose(id);
      const pba::Vec3 v = w.rigid().velocity_at(id, p.position);
      std::fprintf(f, "%lld,%.17g,0,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%s,%.17g,%.17g,%.17g,%.17g\n", step, t,
                   p.position.x, p.position.y, p.position.z, v.x, v.y, v.z, csv_field(rigid_name(w, id)).c_str(),
                   p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
    }
  const pba::SoftSystem* soft = soft_bodies(w);
  if (!soft) return;
  for (std::size_t b = 0; b < soft->size(); ++b) {
    const pba::SoftBody& body = soft->at(b);
    const std::string name = csv_field(body_name(w, *soft, b));
    const auto bx = body.xs(), by = body.ys(), bz = body.zs();
    for (std::size_t i = 0; i < body.size(); ++i) {
      const pba::Vec3 v = body.velocity(i);
      std::fprintf(f, "%lld,%.17g,%zu,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%s%s", step, t, i, bx[i], by[i], bz[i],
                   static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z), name.c_str(), tail);
    }
  }
}

struct Options {
  std::string scene;
  std::string builder;
  long long steps = 1000;
  long long every = 1;
  bool every_given = false;
  std::string csv;
  std::optional<pba::Method> method;
  std::string method_text;
  bool quiet = false;
  bool list = false;
};

// the command line; returns the exit code when the command should stop here
std::optional<int> parse(int argc, char** argv, Options& o) {
  CLI::App app{kRunAbout, "pba run"};
  pba::tools::configure_app(app);
  std::string steps, every, csv, method;
  app.add_option("scene", o.scene, "the scene file to run")->type_name("SCENE.json");
  app.add_option("--steps", steps, "steps to run, 1..1000000000 (default: 1000)")->type_name("N");
  app.add_option("--csv", csv, "write the state every K steps, at step 0 and at the last step (columns below); - for standard output")->type_name("FILE");
  app.add_option("--every", every, "CSV interval in steps, 1..1000000000 (default: 1); needs --csv")
      ->type_name("K");
  app.add_option("--method", method, "replace the scene's integrators (see below)")->type_name("NAME");
  app.add_option("--builder", o.builder, "run a built-in scene builder instead of a file (see --list)")
      ->type_name("NAME");
  app.add_flag("--list", o.list, "list the built-in scene builders");
  app.add_flag("--quiet", o.quiet, "print only the final hash (to standard error with --csv -), and no progress");
  app.footer(kRunFooter);
  std::vector<std::string> args(argv + 1, argv + argc);
  const pba::tools::ParseOutcome p = pba::tools::parse_command_line(app, args);
  if (p.exit && p.error.empty()) return p.code;
  if (p.exit) {
    std::string m = p.error;
    if (m.rfind("unexpected argument", 0) == 0) m += " (one scene file per run)";
    throw Usage{m};
  }
  // values, checked with messages that name the flag and the value
  if (app.count("--steps")) o.steps = parse_count(steps, "--steps", 1, 1000000000LL);
  if (app.count("--every")) o.every = parse_count(every, "--every", 1, 1000000000LL), o.every_given = true;
  if (app.count("--csv")) {
    if (csv.empty()) throw Usage{"--csv: must not be empty"};
    o.csv = csv;
  }
  if (app.count("--method")) {
    try {
      o.method = pba::parse_method(method, "--method");
    } catch (const pba::Error& e) {
      throw Usage{e.what()};
    }
    o.method_text = method;
  }
  if (o.list) return std::nullopt;
  if (o.scene.empty() && o.builder.empty()) throw Usage{"missing scene file (or --builder NAME)"};
  if (!o.scene.empty() && !o.builder.empty()) throw Usage{"give a scene file or --builder, not both"};
  if (o.every_given && o.csv.empty())
    throw Usage{"--every " + std::to_string(o.every) + ": sets the CSV interval, so it needs --csv FILE"};
  return std::nullopt;
}

// --method on this world: applied to the particles and every mass-spring soft body, or
// refused (Usage) when some part of the scene is not stepped by an integrator, or nothing is
void apply_method(pba::World& w, pba::Method m, const std::string& text, const std::string& scene) {
  const std::string flag = "--method " + text;
  auto* soft = dynamic_cast<pba::SoftSystem*>(w.find_system(pba::SoftSystem::kName));
  // soft bodies solved by XPBD have no integrator to replace
  if (soft) {
    for (std::size_t b = 0; b < soft->size(); ++b)
      if (soft->at(b).settings().solver == pba::SoftSolver::Xpbd)
        throw Usage{flag + ": scene " + scene + " has the soft body '" + body_name(w, *soft, b) +
                    "' solved by XPBD, which uses no integrator, so --method cannot apply to it; run it "
                    "without --method (a soft body's solver and integrator are its own settings)"};
  }
  const pba::ParticleSystem& ps = w.particles();
  const bool particles = ps.size() > 0 || ps.emitter_count() > 0;
  const bool springs = soft && soft->size() > 0;
  if (!particles && !springs)
    throw Usage{flag + ": scene " + scene + " has no particles, emitters or soft bodies for an integrator to step"};
  w.particles().set_method(m);
  if (soft)
    for (std::size_t b = 0; b < soft->size(); ++b) soft->at(b).settings().method = m;
}

// what integrates the scene, for the summary: the particle system's method (when it has
// particles or emitters) and each soft body's solver
std::string integrators(const pba::World& w) {
  std::string s;
  const pba::ParticleSystem& ps = w.particles();
  if (ps.size() > 0 || ps.emitter_count() > 0) s = "particles " + std::string(pba::name(ps.method()));
  if (const pba::SoftSystem* soft = soft_bodies(w)) {
    for (std::size_t b = 0; b < soft->size(); ++b) {
      const pba::SoftBodyDef& d = soft->at(b).settings();
      if (!s.empty()) s += ", ";
      s += "'" + body_name(w, *soft, b) + "' " +
           (d.solver == pba::SoftSolver::Xpbd ? std::string("xpbd")
                                              : "mass-spring " + std::string(pba::name(d.method)));
    }
  }
  if (!entity_bodies(w).empty()) {
    const pba::ContactSettings& c = w.rigid().settings();
    if (!s.empty()) s += ", ";
    s += "rigid bodies " + std::string(pba::to_string(c.solver)) +
         (c.solver == pba::RigidSolverType::SequentialImpulse ? " x" + std::to_string(c.iterations) + " iterations"
                                                              : " x" + std::to_string(c.substeps) + " substeps");
    // the soft step's own changes to that count (ContactSettings::auto_substeps)
    if (c.solver == pba::RigidSolverType::SoftStep && c.auto_substeps) {
      // and the halving's sag budgets, each when set
      std::string sag;
      char part[64];
      if (c.auto_substeps_sag_fraction > 0) {
        std::snprintf(part, sizeof part, "%g%% of each body's size", 100 * c.auto_substeps_sag_fraction);
        sag = part;
      }
      if (c.auto_substeps_sag > 0) {
        std::snprintf(part, sizeof part, "%g mm", 1e3 * c.auto_substeps_sag);
        sag += (sag.empty() ? "" : " and ") + std::string(part);
      }
      // (below the setting: 8 -> 4 -> 3 at the defaults, none under auto_substeps_least)
      const std::string fewer =
          ", fewer at rest (at least " + std::to_string(c.auto_substeps_least) + ") under a sag of ";
      s += " (more for tall columns" + (sag.empty() ? "" : fewer + sag) + ")";
    }
  }
  return s.empty() ? "none (nothing to integrate)" : s;
}

// soft-body particles in the world
std::size_t soft_particles(const pba::World& w) {
  std::size_t n = 0;
  if (const pba::SoftSystem* soft = soft_bodies(w))
    for (std::size_t b = 0; b < soft->size(); ++b) n += soft->at(b).size();
  return n;
}

}  // namespace

int pba_run_command(int argc, char** argv) {
  Options o;
  try {
    if (const auto code = parse(argc, argv, o)) return *code;
  } catch (const Usage& u) {
    std::fprintf(stderr, "pba run: %s\n(see 'pba run --help')\n", u.message.c_str());
    return 2;
  }
  if (o.list) {
    for (const auto& b : pba::scenes::builders())
      std::printf("%-16s %s\n", std::string(b.name).c_str(), std::string(b.description).c_str());
    return 0;
  }
  const std::string source = o.scene.empty() ? "--builder " + o.builder : o.scene;
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
    if (o.method) {
      try {
        apply_method(w, *o.method, o.method_text, source);
      } catch (const Usage& u) {
        std::fprintf(stderr, "pba run: %s\n", u.message.c_str());
        return 2;
      }
    }
    // the CSV file, with its header and the initial state (the quaternion columns when the
    // scene has rigid bodies)
    const bool rigid = !entity_bodies(w).empty();
    // "-" is standard output (it wrote a file named "-"); the summary then goes to standard
    // error, so what a pipe reads is one CSV
    const bool csv_out = o.csv == "-";
    const std::string csv_name = csv_out ? "standard output" : "'" + o.csv + "'";
    std::FILE* const out = csv_out ? stderr : stdout;
    std::FILE* csv = csv_out ? stdout : nullptr;
    if (!o.csv.empty()) {
      if (!csv_out) csv = std::fopen(o.csv.c_str(), "w");
      if (!csv) {
        std::fprintf(stderr, "pba run: --csv: cannot write '%s'\n", o.csv.c_str());
        return 1;
      }
      std::fputs(rigid ? "step,time,particle,x,y,z,vx,vy,vz,body,qw,qx,qy,qz\n" : "step,time,particle,x,y,z,vx,vy,vz,body\n",
                 csv);
      write_rows(csv, 0, w, rigid);
    }
    // step, accumulating the per-phase profile, with progress on stderr
    pba::WorldProfile sum;
    pba::Stopwatch wall;
    std::size_t contacts = 0, rigid_contacts = 0;
    pba::tools::Progress progress("pba run", "steps", o.steps,
                                  o.quiet ? pba::tools::ProgressMode::Quiet : pba::tools::ProgressMode::Auto);
    try {
      for (long long s = 1; s <= o.steps; ++s) {
        w.step();
        const pba::WorldProfile& p = w.profile();
        sum.kinematic += p.kinematic, sum.sync += p.sync, sum.emit += p.emit, sum.integrate += p.integrate;
        sum.collide += p.collide, sum.recycle += p.recycle, sum.constraints += p.constraints;
        sum.systems += p.systems, sum.total += p.total;
        sum.stages[static_cast<std::size_t>(pba::WorldStage::Rigid)] += p.stages[static_cast<std::size_t>(pba::WorldStage::Rigid)];
        rigid_contacts += w.rigid().manifold_count();
        contacts += w.particles().contacts();
        // every K steps, and the last step whatever K: the CSV ends with the final state
        if (csv && (s % o.every == 0 || s == o.steps)) write_rows(csv, s, w, rigid);
        progress.update(s);
      }
    } catch (const pba::Error& e) {
      progress.finish();
      if (csv && !csv_out) std::fclose(csv);
      if (csv_out) std::fflush(csv);
      std::fprintf(stderr, "pba run: %s: %s\n", source.c_str(), e.what());
      return 1;
    }
    progress.finish();
    const double seconds = wall.seconds();
    // a buffered write that failed on the way (a full disk) is kept in the stream's error
    // flag: fclose returns 0 when its own last flush had nothing left to write (standard
    // output is flushed, not closed: the caller may write to it after)
    const bool csv_failed = csv && std::ferror(csv) != 0;
    if (csv && ((csv_out ? std::fflush(csv) : std::fclose(csv)) != 0 || csv_failed)) {
      std::fprintf(stderr, "pba run: --csv: error writing %s\n", csv_name.c_str());
      return 1;
    }
    // the summary
    const double n = static_cast<double>(o.steps);
    if (o.quiet) {
      std::fprintf(out, "%016llx\n", static_cast<unsigned long long>(w.hash()));
      return 0;
    }
    std::fprintf(out, "scene        %s\n", scene->name.c_str());
    std::fprintf(out, "steps        %lld x %.9g s = %.6g s simulated\n", o.steps, w.stepper().settings().fixed_dt, w.time());
    std::fprintf(out, "integrators  %s%s\n", integrators(w).c_str(), o.method ? " (from --method)" : "");
    std::fprintf(out, "entities     %zu, particles alive %zu, soft-body particles %zu, contacts %.3g per step\n",
                 w.entity_count(), w.particles().size(), soft_particles(w), static_cast<double>(contacts) / n);
    if (rigid) {
      const std::vector<pba::RigidBodyId> bodies = entity_bodies(w);
      std::size_t awake = 0;
      for (const pba::RigidBodyId id : bodies) awake += w.rigid().type(id) == pba::BodyType::Dynamic && w.rigid().awake(id);
      std::fprintf(out, "rigid bodies %zu (%zu dynamic awake at the end), %.3g manifolds per step\n", bodies.size(),
                   awake, static_cast<double>(rigid_contacts) / n);
    }
    std::fprintf(out, "final hash   %016llx\n", static_cast<unsigned long long>(w.hash()));
    std::fprintf(out, "wall time    %.6g s, %.4g ms per step (including CSV output)\n", seconds, seconds / n * 1e3);
    // semi-implicit Euler runs the particles' fused kernel, whose collisions are timed with
    // the integration (a "collide 0" beside contacts said they cost nothing)
    char particle_phases[96];
    if (w.particles().method() == pba::Method::SemiImplicitEuler)
      std::snprintf(particle_phases, sizeof particle_phases, "integrate + collide %.4g (fused)",
                    (sum.integrate + sum.collide) / n * 1e3);
    else
      std::snprintf(particle_phases, sizeof particle_phases, "integrate %.4g, collide %.4g", sum.integrate / n * 1e3,
                    sum.collide / n * 1e3);
    std::fprintf(out,
                 "profile      ms per step: kinematic %.4g, sync %.4g, emit %.4g, %s, recycle %.4g, constraints %.4g, "
                 "rigid %.4g, systems %.4g, total %.4g\n",
                 sum.kinematic / n * 1e3, sum.sync / n * 1e3, sum.emit / n * 1e3, particle_phases, sum.recycle / n * 1e3,
                 sum.constraints / n * 1e3, sum.stages[static_cast<std::size_t>(pba::WorldStage::Rigid)] / n * 1e3,
                 sum.systems / n * 1e3, sum.total / n * 1e3);
    if (!o.csv.empty())
      std::fprintf(out, "csv          %s (every %lld steps)\n", csv_out ? "standard output" : o.csv.c_str(), o.every);
    return 0;
  } catch (const pba::Error& e) {
    std::fprintf(stderr, "pba run: %s\n", e.what());
    return 1;
  }
}
