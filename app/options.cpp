// Command-line parsing with errors that name the flag and the bad value.
#include "options.h"

#include <charconv>
#include <cmath>
#include <cstdlib>

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

std::string Usage() {
  return R"(usage: pba_samples [options]

Interactive samples for pba (physics-based animation). With no display, renders the
default sample headless under xvfb-run and writes PNG frames and an MP4 to ./captures/.

options:
  --help                 show this help and exit
  --list                 list the samples ("Category/Name") and exit
  --sample NAME          start with this sample: "Category/Name", its name, or a unique
                         part of it (case-insensitive), e.g. --sample stepping
  --scene FILE.json      open a scene file (docs/scene-format.md) in the "Particles/Scene
                         file" sample; the same as --sample "scene file" --option file=FILE
  --headless             render in a hidden window with a fixed frame time and capture
  --frames N             frames to render headless (default 300)
  --out DIR              where PNGs and the MP4 go (default ./captures/<sample>)
  --size WxH             image / window size in pixels (default 1280x720)
  --screenshot-every K   write every K-th frame as PNG, plus the last (default 30; 0 = none)
  --no-video             do not write the MP4
  --fps F                frames per second of virtual time when headless (default 60)
  --dt SECONDS           physics step, 1 / step rate (default 1/60)
  --strategy NAME        time stepping: per-frame, max-step, fixed, threaded
  --integrator NAME      euler, semi-implicit-euler, verlet, velocity-verlet, rk4,
                         implicit-euler
  --substeps N           integration substeps per physics step (default 1)
  --msaa N               multisample anti-aliasing samples, 1 = off (default 4; 1 for
                         interactive use on a software rasteriser such as llvmpipe)
  --hide-ui              draw only the 3D view (no panels)
  --option KEY=VALUE     a sample's own setting (repeatable); Dynamics/Integrators:
                         scenario=ballistic|spring|orbit, drag=0|1, nan_at=SECONDS
                         (poisons one object: shows the divergence handling);
                         Dynamics/Time stepping: delay=MS, cost=MS, fps=HZ
  --selftest             headless check: each frame must show the scene (not blank,
                         background visible, the sample's colours present, changing);
                         exit code 1 on failure
  --all                  with --headless/--selftest: every sample in turn

keys: P pause, O single step, R restart, [ / ] or PageUp / PageDown previous / next
      sample, F1 toggle panels, Esc quit.
mouse: left-drag orbit, right- or middle-drag (or shift + left) pan, wheel zoom.
)";
}

ParseResult ParseOptions(const std::vector<std::string>& args) {
  ParseResult r;
  Options& o = r.options;
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string flag = args[i];
    std::string value;
    bool has_value = false;
    // --flag=value form
    if (flag.rfind("--", 0) == 0) {
      const auto eq = flag.find('=');
      if (eq != std::string::npos) {
        value = flag.substr(eq + 1);
        flag = flag.substr(0, eq);
        has_value = true;
      }
    }
    // flags without a value
    auto no_value = [&](bool* target) {
      if (has_value) {
        r.error = flag + ": takes no value, got '" + value + "'";
        return false;
      }
      *target = true;
      return true;
    };
    // flags with a value: from "=value" or the next argument
    auto take = [&]() {
      if (has_value) return true;
      if (i + 1 >= args.size()) {
        r.error = flag + ": missing value (see --help)";
        return false;
      }
      value = args[++i];
      return true;
    };
    if (flag == "--help" || flag == "-h") {
      if (!no_value(&o.help)) return r;
    } else if (flag == "--list") {
      if (!no_value(&o.list)) return r;
    } else if (flag == "--headless") {
      if (!no_value(&o.headless)) return r;
    } else if (flag == "--selftest") {
      if (!no_value(&o.selftest)) return r;
    } else if (flag == "--all") {
      if (!no_value(&o.all)) return r;
    } else if (flag == "--hide-ui") {
      if (!no_value(&o.hide_ui)) return r;
    } else if (flag == "--no-video") {
      bool b = false;
      if (!no_value(&b)) return r;
      o.video = false;
    } else if (flag == "--sample") {
      if (!take()) return r;
      if (value.empty()) return r.error = bad(flag, value, "expected a sample name (see --list)"), r;
      o.sample = value;
    } else if (flag == "--scene") {
      // shorthand for the scene-file sample with its file option
      if (!take()) return r;
      if (value.empty()) return r.error = bad(flag, value, "expected a scene file (.json)"), r;
      o.sample = "Particles/Scene file";
      o.sample_options["file"] = value;
    } else if (flag == "--out") {
      if (!take()) return r;
      if (value.empty()) return r.error = bad(flag, value, "expected a directory"), r;
      o.out = value;
    } else if (flag == "--frames") {
      if (!take()) return r;
      if (!parse_number(value, &o.frames) || o.frames < 1 || o.frames > 1000000)
        return r.error = bad(flag, value, "expected an integer in [1, 1000000]"), r;
    } else if (flag == "--screenshot-every") {
      if (!take()) return r;
      if (!parse_number(value, &o.screenshot_every) || o.screenshot_every < 0 || o.screenshot_every > 1000000)
        return r.error = bad(flag, value, "expected an integer in [0, 1000000]"), r;
    } else if (flag == "--msaa") {
      if (!take()) return r;
      if (!parse_number(value, &o.msaa) || o.msaa < 1 || o.msaa > 16)
        return r.error = bad(flag, value, "expected an integer in [1, 16]"), r;
    } else if (flag == "--substeps") {
      if (!take()) return r;
      int n = 0;
      if (!parse_number(value, &n) || n < 1 || n > 1000)
        return r.error = bad(flag, value, "expected an integer in [1, 1000]"), r;
      o.substeps = n;
    } else if (flag == "--size") {
      if (!take()) return r;
      const auto x = value.find('x');
      int w = 0, h = 0;
      if (x == std::string::npos || !parse_number(value.substr(0, x), &w) ||
          !parse_number(value.substr(x + 1), &h) || w < 64 || h < 64 || w > 7680 || h > 4320)
        return r.error = bad(flag, value, "expected WIDTHxHEIGHT, each from 64 up to 7680x4320, e.g. 1280x720"), r;
      o.width = w, o.height = h;
    } else if (flag == "--fps") {
      if (!take()) return r;
      double v = 0;
      if (!parse_number(value, &v) || !std::isfinite(v) || v < 1 || v > 1000)
        return r.error = bad(flag, value, "expected a number of frames per second in [1, 1000]"), r;
      o.fps = v;
    } else if (flag == "--dt") {
      if (!take()) return r;
      double v = 0;
      if (!parse_number(value, &v))
        return r.error = bad(flag, value, "expected a number of seconds, e.g. 0.01"), r;
      if (!std::isfinite(v) || v < 1e-6 || v > 10)
        return r.error = bad(flag, value, "must be finite and in [1e-06, 10] seconds"), r;
      o.dt = v;
    } else if (flag == "--option") {
      if (!take()) return r;
      const auto eq = value.find('=');
      if (eq == std::string::npos || eq == 0)
        return r.error = bad(flag, value, "expected KEY=VALUE, e.g. scenario=orbit"), r;
      o.sample_options[value.substr(0, eq)] = value.substr(eq + 1);
    } else if (flag == "--strategy") {
      if (!take()) return r;
      try {
        o.strategy = parse_strategy(value, "--strategy");
      } catch (const Error& e) {
        return r.error = e.what(), r;
      }
    } else if (flag == "--integrator" || flag == "--method") {
      if (!take()) return r;
      try {
        o.method = parse_method(value, flag);
      } catch (const Error& e) {
        return r.error = e.what(), r;
      }
    } else if (flag.rfind("-", 0) == 0) {
      r.error = "unknown flag '" + flag + "' (see --help)";
      return r;
    } else {
      r.error = "unexpected argument '" + flag + "' (flags start with --, see --help)";
      return r;
    }
  }
  return r;
}

}  // namespace pba::app
