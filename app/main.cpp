// pba_samples: command line, the no-display re-exec under xvfb-run, then the app.
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <unistd.h>

#include "app.h"
#include "capture.h"
#include "options.h"
#include "sample.h"

namespace {

bool has_display() {
  const char* d = std::getenv("DISPLAY");
  return d && *d;
}

// re-run this program under a virtual X server; returns only on failure
int reexec_under_xvfb(const std::vector<std::string>& args, const pba::app::Options& o) {
  if (std::getenv("PBA_SAMPLES_UNDER_XVFB")) {
    std::fprintf(stderr, "pba_samples: still no display under xvfb-run (DISPLAY is empty)\n");
    return 1;
  }
  if (!pba::app::on_path("xvfb-run")) {
    std::fprintf(stderr,
                 "pba_samples: no display (DISPLAY is not set) and xvfb-run is not installed.\n"
                 "Run scripts/install-deps (it installs xvfb), or run pba_samples on a desktop.\n");
    return 1;
  }
  char self[4096];
  const ssize_t n = ::readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0) {
    std::fprintf(stderr, "pba_samples: cannot find my own executable to re-run it under xvfb-run\n");
    return 1;
  }
  self[n] = '\0';
  // the virtual screen is at least as large as the capture
  const std::string screen = "-screen 0 " + std::to_string(std::max(o.width, 1280)) + "x" +
                             std::to_string(std::max(o.height, 720)) + "x24";
  std::vector<std::string> argv_s = {"xvfb-run", "-a", "-s", screen, self};
  if (!o.headless && !o.selftest) argv_s.push_back("--headless");
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::printf("pba_samples: no display; rendering headless under xvfb-run\n");
  std::fflush(stdout);
  ::setenv("PBA_SAMPLES_UNDER_XVFB", "1", 1);
  ::execvp("xvfb-run", argv.data());
  std::perror("pba_samples: could not run xvfb-run");
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  // a dying ffmpeg must not kill the app through SIGPIPE; the write error is handled
  std::signal(SIGPIPE, SIG_IGN);
  std::vector<std::string> args(argv + 1, argv + argc);
  pba::app::ParseResult parsed = pba::app::ParseOptions(args);
  if (!parsed.error.empty()) {
    std::fprintf(stderr, "pba_samples: %s\n", parsed.error.c_str());
    return 2;
  }
  if (parsed.done) return 0;  // --help or --version, printed by the parser
  pba::app::Options& o = parsed.options;
  if (o.list) {
    for (const auto& e : pba::app::Samples()) std::printf("%s\n", e.full_name().c_str());
    return 0;
  }
  // the sample name is checked before any window opens
  if (!o.sample.empty()) {
    std::string error;
    if (pba::app::FindSample(o.sample, &error) < 0) {
      std::fprintf(stderr, "pba_samples: %s\n", error.c_str());
      return 2;
    }
  }
  // capture flags imply headless; --all needs it
  if (o.frames > 0 || !o.out.empty()) o.headless = true;
  if (o.all && !o.headless && !o.selftest) {
    std::fprintf(stderr, "pba_samples: --all: needs --headless or --selftest\n");
    return 2;
  }
  if (!has_display()) return reexec_under_xvfb(args, o);
  pba::app::App app(o);
  return app.run();
}
