// `pba run`: runs a scene file headless for N steps, optionally writing per-step state as
// CSV, and prints a summary (final state hash, time per step, per-phase profile).
#pragma once

/// Runs the `pba run` subcommand. argv[0] is the subcommand's name ("run") and the
/// options follow (see `pba run --help`). Returns the exit code: 0 on success, 1 when the
/// scene cannot be loaded or the simulation fails (non-finite state), 2 for a bad command
/// line. Messages go to stdout (summary) and stderr (errors).
int pba_run_command(int argc, char** argv);
