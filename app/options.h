// Command-line options of pba_samples.
#pragma once

#include <map>

#include <optional>
#include <string>
#include <vector>

#include "pba/draw.h"
#include "pba/integrate.h"
#include "pba/time.h"

namespace pba::app {

/// Parsed command line. Unset optionals keep the sample's or the app's defaults.
struct Options {
  bool help = false;            ///< --help: print usage and exit 0
  bool list = false;            ///< --list: print sample names and exit 0
  std::string sample;           ///< --sample: "Category/Name" or a unique substring
  bool all = false;             ///< --all: run every sample in turn (headless / self-test)
  bool headless = false;        ///< --headless: hidden window, fixed frame time, capture
  bool selftest = false;        ///< --selftest: check every rendered frame, exit 1 on failure
  int frames = -1;              ///< --frames: frames to render headless (default 300)
  std::string out;              ///< --out: directory for PNG frames and the MP4
  int width = 1280, height = 720;  ///< --size WxH
  int screenshot_every = 30;    ///< --screenshot-every K: PNG of every K-th frame (0: none)
  bool video = true;            ///< --no-video disables the MP4
  double fps = 60;              ///< --fps: frames per second of virtual time (headless) and video
  int msaa = 0;                 ///< --msaa: multisample count (1 = off, 0 = auto)
  bool hide_ui = false;         ///< --hide-ui: draw only the 3D view
  std::optional<double> dt;     ///< --dt: physics step (s), 1 / step rate
  std::optional<Strategy> strategy;  ///< --strategy NAME
  std::optional<Method> method;      ///< --integrator NAME
  std::optional<int> substeps;       ///< --substeps N
  bool quiet = false;           ///< --quiet: no progress lines in headless runs
  /// --option KEY=VALUE (repeatable): sample-specific settings, e.g. scenario=orbit.
  std::map<std::string, std::string> sample_options;
  /// --view KEY=on|off (repeatable): the View menu's draw flags at start (pba::DrawFlags).
  DrawFlags view{};
};

/// Result of parsing: options, or an error message naming the flag and value.
struct ParseResult {
  Options options;
  std::string error;  ///< empty on success
  bool done = false;  ///< --help or --version was printed: exit 0
};

/// Parses argv (without argv[0]) with CLI11: "--flag value" and "--flag=value" alike;
/// --help and --version are printed here (then `done`). Refuses combinations that cannot
/// be honoured (--sample with --scene, --screenshot-every 0 with --no-video).
ParseResult ParseOptions(const std::vector<std::string>& args);

/// The --help text.
std::string Usage();

}  // namespace pba::app
