// `pba`: the headless multi-tool. Subcommands live in a table; add one by writing a
// function `int cmd_x(Args&)` and a row in kCommands. Larger subcommands live in their
// own tools/cmd_<name>.cpp with a classic (argc, argv) entry point (pba run).
//
// Exit codes: 0 success, 1 a failure while running, 2 bad command line.
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

#include "pba/integrate.h"
#include "pba/lab.h"
#include "commands_run.h"

namespace {

/// A usage error: reported with the command's help hint, exit code 2.
struct UsageError {
  std::string message;
};

/// The remaining command-line words, consumed left to right.
struct Args {
  std::vector<std::string_view> words;
  std::size_t next = 0;
  bool done() const { return next >= words.size(); }
  std::string_view take() { return words[next++]; }
  // the value after a flag, or a usage error naming the flag
  std::string_view value(std::string_view flag) {
    if (done()) throw UsageError{std::string(flag) + ": missing value"};
    return take();
  }
};

long long parse_count(std::string_view text, std::string_view flag, long long lo, long long hi) {
  // whole-string integer parse with range check
  std::string s(text);
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || errno != 0)
    throw UsageError{std::string(flag) + ": expected an integer, got '" + s + "'"};
  if (v < lo || v > hi)
    throw UsageError{std::string(flag) + ": must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                     "], got " + s};
  return v;
}

// ---- pba lab ----------------------------------------------------------------------

constexpr const char* kLabHelp =
    "usage: pba lab [--out DIR] [--problem NAME|all] [--method NAME|all] [--steps N] [--no-plot]\n"
    "\n"
    "The integrator accuracy lab (workbook 3.2.4). For each problem and method it measures\n"
    "the global error against dt and the observed order of convergence, the energy error\n"
    "over a long run, and each method's stability limit on the undamped oscillator. Writes\n"
    "CSV files, then PNG plots with tools/plot_lab.py (python3 + matplotlib), and prints a\n"
    "summary table.\n"
    "\n"
    "  --out DIR        output directory (default: out/lab)\n"
    "  --problem NAME   one problem, repeatable, or 'all' (default: all)\n"
    "  --method NAME    one method, repeatable, or 'all' (default: all)\n"
    "  --steps N        steps of the long energy runs, 1..1000000000 (default: 1000000)\n"
    "  --no-plot        write CSVs only\n";

int run_plot(const std::string& out) {
  // the plotting script: beside this source tree, located via PBA_TOOLS_DIR
  const std::filesystem::path script = std::filesystem::path(PBA_TOOLS_DIR) / "plot_lab.py";
  const std::string hint = "python3 " + script.string() + " " + out;
  if (!std::filesystem::exists(script)) {
    std::printf("CSVs written to %s; plotting script %s not found, so no PNGs.\n", out.c_str(),
                script.string().c_str());
    return 0;
  }
  // the first python3 that has matplotlib (a pyenv or venv python3 on PATH may not)
  std::string python;
  for (const char* candidate : {"python3", "/usr/bin/python3"}) {
    const std::string probe = std::string(candidate) + " -c 'import matplotlib' >/dev/null 2>&1";
    if (std::system(probe.c_str()) == 0) {
      python = candidate;
      break;
    }
  }
  if (python.empty()) {
    std::printf(
        "CSVs written to %s. python3 with matplotlib is not available, so no PNG plots were made.\n"
        "Install it (scripts/install-deps, or apt-get install python3-matplotlib) and run:\n  %s\n",
        out.c_str(), hint.c_str());
    return 0;
  }
  const std::string cmd = python + " '" + script.string() + "' '" + out + "'";
  if (std::system(cmd.c_str()) != 0) {
    std::fprintf(stderr, "pba lab: plotting failed; the CSVs are in %s (retry: %s)\n", out.c_str(),
                 hint.c_str());
    return 1;
  }
  return 0;
}

int cmd_lab(Args& args) {
  pba::lab::LabOptions opt;
  std::string out = "out/lab";
  bool plot = true;
  const auto problems = pba::lab::standard_problems();
  // flags
  while (!args.done()) {
    const std::string_view flag = args.take();
    if (flag == "--help" || flag == "-h") {
      std::fputs(kLabHelp, stdout);
      return 0;
    } else if (flag == "--out") {
      out = std::string(args.value(flag));
      if (out.empty()) throw UsageError{"--out: must not be empty"};
    } else if (flag == "--problem") {
      const std::string_view v = args.value(flag);
      if (v != "all") {
        try {
          opt.problems.push_back(pba::lab::find_problem(problems, v, "--problem").name);
        } catch (const pba::Error& e) {
          throw UsageError{e.what()};
        }
      }
    } else if (flag == "--method") {
      const std::string_view v = args.value(flag);
      if (v != "all") {
        try {
          opt.methods.push_back(pba::parse_method(v, "--method"));
        } catch (const pba::Error& e) {
          throw UsageError{e.what()};
        }
      }
    } else if (flag == "--steps") {
      opt.energy.steps = parse_count(args.value(flag), flag, 1, 1000000000LL);
    } else if (flag == "--no-plot") {
      plot = false;
    } else {
      throw UsageError{"unknown flag '" + std::string(flag) + "' for 'pba lab'"};
    }
  }
  // fail fast on an unusable output directory, before minutes of measuring
  {
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec || !std::filesystem::is_directory(out))
      throw UsageError{"--out: cannot create directory '" + out + "'" + (ec ? ": " + ec.message() : "")};
  }
  // measure, write, plot, summarise
  const auto report = pba::lab::run_lab(problems, opt, [](std::string_view line) {
    std::printf("  %.*s\n", static_cast<int>(line.size()), line.data());
    std::fflush(stdout);
  });
  pba::lab::write_csv(report, out);
  std::printf("\n%s\n", pba::lab::summary_table(report).c_str());
  std::printf("lab ran in %.1f s; CSVs in %s\n", report.seconds, out.c_str());
  std::fflush(stdout);  // before the plotting child writes to the same stream
  return plot ? run_plot(out) : 0;
}

// `pba run`: hands the command word and what follows to tools/cmd_run.cpp
int cmd_run(Args& a) {
  std::vector<std::string> words{"run"};
  while (!a.done()) words.emplace_back(a.take());
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  return pba_run_command(static_cast<int>(words.size()), argv.data());
}

// ---- the command table --------------------------------------------------------------

struct Command {
  const char* name;
  const char* summary;
  int (*run)(Args&);
};

constexpr Command kCommands[] = {
    {"lab", "integrator accuracy lab: convergence, energy and stability of every method", cmd_lab},
    {"run", "run a scene file headless for N steps; per-step state as CSV", cmd_run},
};

void print_help() {
  std::printf("usage: pba <command> [options]     (pba <command> --help for details)\n\ncommands:\n");
  for (const auto& c : kCommands) std::printf("  %-8s %s\n", c.name, c.summary);
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  for (int i = 1; i < argc; ++i) args.words.emplace_back(argv[i]);
  std::string_view cmd_name;
  try {
    // the command word, or help
    if (args.done()) throw UsageError{"missing command"};
    cmd_name = args.take();
    if (cmd_name == "--help" || cmd_name == "-h" || cmd_name == "help") {
      print_help();
      return 0;
    }
    for (const auto& c : kCommands)
      if (cmd_name == c.name) return c.run(args);
    throw UsageError{"unknown command '" + std::string(cmd_name) + "'"};
  } catch (const UsageError& e) {
    const bool known = std::any_of(std::begin(kCommands), std::end(kCommands),
                                   [&](const Command& c) { return cmd_name == c.name; });
    const std::string who = known ? "pba " + std::string(cmd_name) : std::string("pba");
    std::fprintf(stderr, "%s: %s\nrun '%s --help' for usage\n", who.c_str(), e.message.c_str(), who.c_str());
    return 2;
  } catch (const pba::Error& e) {
    std::fprintf(stderr, "pba %.*s: error: %s\n", static_cast<int>(cmd_name.size()), cmd_name.data(), e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pba %.*s: unexpected error: %s\n", static_cast<int>(cmd_name.size()),
                 cmd_name.data(), e.what());
    return 1;
  }
}
