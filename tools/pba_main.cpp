// `pba`: the headless multi-tool. The command word picks a subcommand, which parses the
// words after it with CLI11 (tools/support/cli.h): `pba lab` here, `pba run` in
// tools/cmd_run.cpp (a classic (argc, argv) entry point the tests call in-process).
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

#include "cli.h"
#include "commands_run.h"
#include "pba/integrate.h"
#include "pba/lab.h"
#include "progress.h"

namespace {

/// A usage error: reported with the command's help hint, exit code 2.
struct UsageError {
  std::string message;
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

constexpr const char* kLabAbout =
    "The integrator accuracy lab (workbook 3.2.4). For each problem and method it measures\n"
    "the global error against dt and the observed order of convergence, the energy error\n"
    "over a long run, and each method's stability limit on the undamped oscillator. Writes\n"
    "CSV files, then PNG plots with tools/plot_lab.py (python3 + matplotlib), and prints a\n"
    "summary table. Shows progress on stderr: a live line on a terminal, a line every 5 s\n"
    "otherwise (PBA_PROGRESS_INTERVAL=SECONDS), none with --quiet.";

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

// the lab's measurements, one by one, with progress (pba::lab::run_lab's order)
pba::lab::LabReport measure(const std::vector<pba::lab::Problem>& problems, const pba::lab::LabOptions& o,
                            bool quiet) {
  namespace lab = pba::lab;
  pba::Stopwatch watch;
  lab::LabReport rep;
  std::vector<const lab::Problem*> chosen;
  if (o.problems.empty())
    for (const auto& p : problems) chosen.push_back(&p);
  else
    for (const auto& n : o.problems) chosen.push_back(&lab::find_problem(problems, n, "--problem"));
  const std::vector<pba::Method> methods =
      o.methods.empty() ? std::vector<pba::Method>(pba::kAllMethods.begin(), pba::kAllMethods.end()) : o.methods;
  // the work: a convergence study per problem and method, an energy run where the
  // problem has an energy, a stability scan per method
  long long total = static_cast<long long>(methods.size());
  for (const lab::Problem* p : chosen) total += static_cast<long long>(methods.size()) * (p->energy ? 2 : 1);
  pba::tools::Progress progress("pba lab", "measurements", total,
                                quiet ? pba::tools::ProgressMode::Quiet : pba::tools::ProgressMode::Auto);
  long long done = 0;
  auto say = [&](const std::string& line) {
    if (quiet) return;
    progress.clear();
    std::printf("  %s\n", line.c_str());
    std::fflush(stdout);
  };
  for (const lab::Problem* p : chosen) {
    p->validate();
    say("problem " + p->name + ": " + p->description);
    for (pba::Method m : methods) {
      rep.convergence.push_back(lab::measure_convergence(*p, m, o.convergence));
      progress.update(++done);
      if (p->energy) {
        rep.energy.push_back(lab::measure_energy(*p, m, o.energy));
        progress.update(++done);
      }
    }
  }
  say("stability on the undamped oscillator");
  for (pba::Method m : methods) {
    rep.stability.push_back(lab::measure_stability(m, o.stability));
    progress.update(++done);
  }
  progress.finish();
  rep.seconds = watch.seconds();
  return rep;
}

int cmd_lab(int argc, char** argv) {
  pba::lab::LabOptions opt;
  std::string out = "out/lab";
  bool no_plot = false, quiet = false;
  std::vector<std::string> problem_names, method_names;
  std::string steps;
  const auto problems = pba::lab::standard_problems();
  // the command line
  CLI::App app{kLabAbout, "pba lab"};
  pba::tools::configure_app(app);
  app.add_option("--out", out, "output directory (default: out/lab)")->type_name("DIR");
  app.add_option("--problem", problem_names, "one problem, repeatable, or 'all' (default: all)")
      ->type_name("NAME")
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--method", method_names, "one method, repeatable, or 'all' (default: all)")
      ->type_name("NAME")
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--steps", steps, "steps of the long energy runs, 1..1000000000 (default: 1000000)")
      ->type_name("N");
  app.add_flag("--no-plot", no_plot, "write CSVs only");
  app.add_flag("--quiet", quiet, "no progress and no per-problem lines");
  app.footer("Exit codes: 0 success, 1 a failure while running, 2 bad command line.");
  const pba::tools::ParseOutcome parsed =
      pba::tools::parse_command_line(app, std::vector<std::string>(argv + 1, argv + argc));
  if (parsed.exit && parsed.error.empty()) return parsed.code;
  if (parsed.exit) throw UsageError{parsed.error};
  // values
  if (app.count("--out") && out.empty()) throw UsageError{"--out: must not be empty"};
  for (const std::string& v : problem_names) {
    if (v == "all") continue;
    try {
      opt.problems.push_back(pba::lab::find_problem(problems, v, "--problem").name);
    } catch (const pba::Error& e) {
      throw UsageError{e.what()};
    }
  }
  for (const std::string& v : method_names) {
    if (v == "all") continue;
    try {
      opt.methods.push_back(pba::parse_method(v, "--method"));
    } catch (const pba::Error& e) {
      throw UsageError{e.what()};
    }
  }
  if (app.count("--steps")) opt.energy.steps = parse_count(steps, "--steps", 1, 1000000000LL);
  // fail fast on an unusable output directory, before minutes of measuring
  {
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec || !std::filesystem::is_directory(out))
      throw UsageError{"--out: cannot create directory '" + out + "'" + (ec ? ": " + ec.message() : "")};
  }
  // measure, write, plot, summarise
  const auto report = measure(problems, opt, quiet);
  pba::lab::write_csv(report, out);
  std::printf("\n%s\n", pba::lab::summary_table(report).c_str());
  std::printf("lab ran in %.1f s; CSVs in %s\n", report.seconds, out.c_str());
  std::fflush(stdout);  // before the plotting child writes to the same stream
  return no_plot ? 0 : run_plot(out);
}

// ---- the command table --------------------------------------------------------------

struct Command {
  const char* name;
  const char* summary;
  int (*run)(int argc, char** argv);
};

constexpr Command kCommands[] = {
    {"lab", "integrator accuracy lab: convergence, energy and stability of every method", cmd_lab},
    {"run", "run a scene file headless for N steps; per-step state as CSV", pba_run_command},
};

}  // namespace

int main(int argc, char** argv) {
  std::string who = "pba";
  try {
    // a command word: its own command line
    if (argc >= 2) {
      for (const auto& c : kCommands)
        if (std::string_view(argv[1]) == c.name) {
          who = std::string("pba ") + c.name;
          return c.run(argc - 1, argv + 1);
        }
    }
    // else the top level: help, version, or a usage error
    CLI::App app{"pba: the headless multi-tool of pba (physics-based animation).", "pba"};
    pba::tools::configure_app(app);
    for (const auto& c : kCommands) app.add_subcommand(c.name, c.summary);
    app.footer("Run 'pba <command> --help' for a command's options.\n"
               "Exit codes: 0 success, 1 a failure while running, 2 bad command line.");
    const pba::tools::ParseOutcome parsed =
        pba::tools::parse_command_line(app, std::vector<std::string>(argv + 1, argv + argc));
    if (parsed.exit && parsed.error.empty()) return parsed.code;
    if (parsed.exit) {
      const std::string& e = parsed.error;
      if (e.rfind("unexpected argument ", 0) == 0) throw UsageError{"unknown command " + e.substr(20)};
      throw UsageError{e};
    }
    throw UsageError{"missing command"};
  } catch (const UsageError& e) {
    std::fprintf(stderr, "%s: %s\nrun '%s --help' for usage\n", who.c_str(), e.message.c_str(), who.c_str());
    return 2;
  } catch (const pba::Error& e) {
    std::fprintf(stderr, "%s: error: %s\n", who.c_str(), e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: unexpected error: %s\n", who.c_str(), e.what());
    return 1;
  }
}
