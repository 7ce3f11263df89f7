// Command-line parsing with errors that name the flag and the bad value.
#include "options.h"

#include <charconv>
#include <cmath>
#include <cstdlib>

#include "cli.h"

namespace pba::app {

namespace {

// parse a whole string as a number of type T; false on trailing junk or overflow
template <class T>
bool parse_number(const std::string& s, T* out) {
  if (s.empty()) return false;
  if constexpr (std::is_floating_point_v<T>) {
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (end != s.c_str() + s.size()) return false;
    *out = static_cast<T>(v);
    return true;
  } else {
    const char* b = s.data();
    const char* e = s.data() + s.size();
    if (*b == '+') ++b;
    auto r = std::from_chars(b, e, *out);
    return r.ec == std::errc() && r.ptr == e;
  }
}

std::string bad(const std::string& flag, const std::string& value, const std::string& rule) {
  return flag + " " + (value.empty() ? "''" : "'" + value + "'") + ": " + rule;
}

}  // namespace

namespace {

constexpr const char* kAbout =
    "Interactive samples for pba (physics-based animation). With no display, renders the\n"
    "default sample headless under xvfb-run and writes PNG frames and an MP4 to ./captures/.\n"
    "Headless runs show progress on stderr (a live line on a terminal, a line every 5 s\n"
    "otherwise); --quiet turns it off.";

constexpr const char* kFooter =
    "--option KEY=VALUE sets a sample's own setting (repeatable); a key the sample does not\n"
    "read is an error that lists its keys. E.g. Dynamics/Integrators:\n"
    "scenario=ballistic|spring|orbit, drag=0|1, nan_at=SECONDS (poisons one object: shows\n"
    "the divergence handling); Dynamics/Time stepping: delay=MS, cost=MS, fps=HZ.\n"
    "--scene FILE is --sample \"scene file\" --option file=FILE, so it does not go with\n"
    "--sample. --screenshot-every 0 with --no-video would write nothing: refused (use\n"
    "--selftest to check frames without writing them). A headless run whose sample cannot\n"
    "show its subject (a scene file that does not load) exits with code 1.\n"
    "\n"
    "keys: P pause, O single step, R restart, [ / ] or PageUp / PageDown previous / next\n"
    "      sample, F1 toggle panels, Esc quit.\n"
    "mouse: left-drag orbit, right- or middle-drag (or shift + left) pan, wheel zoom.";

// the words of the options that take a value, checked after parsing
struct Raw {
  std::string sample, scene, out, frames, screenshot_every, msaa, substeps, size, fps, dt, strategy, method;
  std::vector<std::string> options, view;
};

// every option of pba_samples, in the order of the help
void describe(CLI::App& app, Options& o, Raw& r) {
  tools::configure_app(app);
  app.footer(kFooter);
  app.add_flag("--list", o.list, "list the samples (\"Category/Name\") and exit");
  app.add_option("--sample", r.sample,
                 "start with this sample: \"Category/Name\", or a unique part of it (any case)")
      ->type_name("NAME");
  app.add_option("--scene", r.scene, "open a scene file (docs/scene-format.md) in \"Particles/Scene file\"")
      ->type_name("FILE.json");
  app.add_flag("--headless", o.headless, "render in a hidden window with a fixed frame time and capture");
  app.add_option("--frames", r.frames, "frames to render headless (default 300)")->type_name("N");
  app.add_option("--out", r.out, "where PNGs and the MP4 go (default ./captures/<sample>)")->type_name("DIR");
  app.add_option("--size", r.size, "image / window size in pixels (default 1280x720)")->type_name("WxH");
  app.add_option("--screenshot-every", r.screenshot_every,
                 "write every K-th frame as PNG, plus the last (default 30; 0 = none)")
      ->type_name("K");
  app.add_flag("--no-video")->description("do not write the MP4");
  app.add_option("--fps", r.fps, "frames per second of virtual time when headless (default 60)")->type_name("F");
  app.add_option("--dt", r.dt, "physics step, 1 / step rate (default 1/60)")->type_name("SECONDS");
  app.add_option("--strategy", r.strategy, "time stepping: per-frame, max-step, fixed, threaded")->type_name("NAME");
  app.add_option("--integrator,--method", r.method,
                 "euler, semi-implicit-euler, verlet, velocity-verlet, rk4, implicit-euler")
      ->type_name("NAME");
  app.add_option("--substeps", r.substeps, "integration substeps per physics step (default 1)")->type_name("N");
  app.add_option("--msaa", r.msaa, "multisample anti-aliasing samples, 1 = off (default 4; 1 live on llvmpipe)")
      ->type_name("N");
  app.add_flag("--hide-ui", o.hide_ui, "draw only the 3D view (no panels)");
  app.add_option("--option", r.options, "a sample's own setting (repeatable, see below)")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--view", r.view,
                 "a View menu draw flag at start (repeatable): shapes, aabbs, tree, contacts, normals, "
                 "particles, forcers, constraints, each =on or =off")
      ->type_name("FLAG=on|off")
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_flag("--selftest", o.selftest,
               "headless check that every frame shows the scene; exit code 1 on failure");
  app.add_flag("--all", o.all, "with --headless/--selftest: every sample in turn");
  app.add_flag("--quiet", o.quiet, "no progress lines in headless runs");
}

}  // namespace

std::string Usage() {
  Options o;
  Raw r;
  CLI::App app{kAbout, "pba_samples"};
  describe(app, o, r);
  return app.help();
}

ParseResult ParseOptions(const std::vector<std::string>& args) {
  ParseResult result;
  Options& o = result.options;
  Raw r;
  CLI::App app{kAbout, "pba_samples"};
  describe(app, o, r);
  const tools::ParseOutcome parsed = tools::parse_command_line(app, args);
  if (parsed.exit) {
    if (parsed.error.empty()) o.help = true, result.done = true;  // help or version printed
    result.error = parsed.error;
    if (result.error.rfind("unknown flag", 0) == 0) result.error += " (see --help)";
    if (result.error.rfind("unexpected argument", 0) == 0) result.error += " (flags start with --, see --help)";
    return result;
  }
  auto given = [&](const char* flag) { return app.count(flag) > 0; };
  auto fail = [&](const std::string& message) {
    result.error = message;
    return result;
  };
  // each value, with a message naming the flag and the value
  if (given("--no-video")) o.video = false;
  if (given("--sample")) {
    if (r.sample.empty()) return fail(bad("--sample", r.sample, "expected a sample name (see --list)"));
    o.sample = r.sample;
  }
  if (given("--out")) {
    if (r.out.empty()) return fail(bad("--out", r.out, "expected a directory"));
    o.out = r.out;
  }
  if (given("--frames") && (!parse_number(r.frames, &o.frames) || o.frames < 1 || o.frames > 1000000))
    return fail(bad("--frames", r.frames, "expected an integer in [1, 1000000]"));
  if (given("--screenshot-every") && (!parse_number(r.screenshot_every, &o.screenshot_every) ||
                                      o.screenshot_every < 0 || o.screenshot_every > 1000000))
    return fail(bad("--screenshot-every", r.screenshot_every, "expected an integer in [0, 1000000]"));
  if (given("--msaa") && (!parse_number(r.msaa, &o.msaa) || o.msaa < 1 || o.msaa > 16))
    return fail(bad("--msaa", r.msaa, "expected an integer in [1, 16]"));
  if (given("--substeps")) {
    int n = 0;
    if (!parse_number(r.substeps, &n) || n < 1 || n > 1000)
      return fail(bad("--substeps", r.substeps, "expected an integer in [1, 1000]"));
    o.substeps = n;
  }
  if (given("--size")) {
    const auto x = r.size.find('x');
    int w = 0, h = 0;
    if (x == std::string::npos || !parse_number(r.size.substr(0, x), &w) || !parse_number(r.size.substr(x + 1), &h) ||
        w < 64 || h < 64 || w > 7680 || h > 4320)
      return fail(bad("--size", r.size, "expected WIDTHxHEIGHT, each from 64 up to 7680x4320, e.g. 1280x720"));
    o.width = w, o.height = h;
  }
  if (given("--fps")) {
    double v = 0;
    if (!parse_number(r.fps, &v) || !std::isfinite(v) || v < 1 || v > 1000)
      return fail(bad("--fps", r.fps, "expected a number of frames per second in [1, 1000]"));
    o.fps = v;
  }
  if (given("--dt")) {
    double v = 0;
    if (!parse_number(r.dt, &v)) return fail(bad("--dt", r.dt, "expected a number of seconds, e.g. 0.01"));
    if (!std::isfinite(v) || v < 1e-6 || v > 10) return fail(bad("--dt", r.dt, "must be finite and in [1e-06, 10] seconds"));
    o.dt = v;
  }
  for (const std::string& kv : r.options) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) return fail(bad("--option", kv, "expected KEY=VALUE, e.g. scenario=orbit"));
    o.sample_options[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  for (const std::string& kv : r.view) {
    const auto eq = kv.find('=');
    const std::string key = kv.substr(0, eq), value = eq == std::string::npos ? "" : kv.substr(eq + 1);
    bool* flag = key == "shapes"        ? &o.view.shapes
                 : key == "aabbs"       ? &o.view.aabbs
                 : key == "tree"        ? &o.view.tree
                 : key == "contacts"    ? &o.view.contacts
                 : key == "normals"     ? &o.view.normals
                 : key == "particles"   ? &o.view.particles
                 : key == "forcers"     ? &o.view.forcers
                 : key == "constraints" ? &o.view.constraints
                                        : nullptr;
    if (!flag)
      return fail(bad("--view", kv, "expected FLAG=on or FLAG=off, FLAG one of shapes, aabbs, tree, contacts, normals, "
                                    "particles, forcers, constraints"));
    if (value == "on" || value == "1" || value == "true") *flag = true;
    else if (value == "off" || value == "0" || value == "false") *flag = false;
    else return fail(bad("--view", kv, "expected " + key + "=on or " + key + "=off"));
  }
  try {
    if (given("--strategy")) o.strategy = parse_strategy(r.strategy, "--strategy");
    if (given("--integrator")) o.method = parse_method(r.method, "--integrator");
  } catch (const Error& e) {
    return fail(e.what());
  }
  // combinations that cannot be honoured
  if (given("--scene")) {
    if (r.scene.empty()) return fail(bad("--scene", r.scene, "expected a scene file (.json)"));
    if (given("--sample"))
      return fail("--sample '" + r.sample + "' and --scene '" + r.scene +
                  "': give one of them (--scene opens its file in the \"Particles/Scene file\" sample)");
    if (o.sample_options.count("file"))
      return fail("--scene '" + r.scene + "' and --option file=" + o.sample_options["file"] +
                  ": both name the scene file; give one of them");
    o.sample = "Particles/Scene file";
    o.sample_options["file"] = r.scene;
  }
  if (given("--screenshot-every") && o.screenshot_every == 0 && !o.video && !o.selftest)
    return fail("--screenshot-every 0 with --no-video: the run would write no image and no video; drop one of "
                "them (or use --selftest to check the frames without writing them)");
  return result;
}

}  // namespace pba::app
