// Command-line parsing shared by `pba` and `pba_samples`: CLI11 (Debian libcli11-dev) with
// one look for help, `--version`, `--flag value` and `--flag=value`, and messages that name
// the flag and the value. Values are checked by the tools themselves after parsing, so a
// bad value is reported as "<flag>: <what is wrong>, got '<value>'".
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace pba::tools {

/// The project version from CMake (e.g. "0.1.0").
const char* version();

/// Sets up `app` the same way in every tool: "usage:" help in CLI11's layout, `--version`
/// printing "<name> <version>", the last of a repeated option wins, and unknown words kept
/// (checked by parse_command_line, which names them).
void configure_app(CLI::App& app);

/// What parse_command_line found.
struct ParseOutcome {
  bool exit = false;   ///< true: stop with `code` (help or version printed, or an error)
  int code = 0;        ///< exit code when `exit`: 0 after --help/--version, 2 on error
  std::string error;   ///< the error message (empty after help or version)
};

/// Parses `args` (without the program name) into `app`. Help and version are printed to
/// stdout. Errors are returned, never printed: a missing value ("--frames: missing
/// value"), an unknown flag ("unknown flag '--bogus'") or a stray word ("unexpected
/// argument 'x'").
ParseOutcome parse_command_line(CLI::App& app, const std::vector<std::string>& args);

}  // namespace pba::tools
