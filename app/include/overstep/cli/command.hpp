#pragma once
/// \file
/// Shared plumbing of the git-style `overstep` front end: each module's app/ code registers its
/// subcommand with a Registry; main() parses and runs the selected one. Errors become one line on
/// stderr ("overstep <cmd>: error: ...") and an exit code from overstep::ExitCode.

#include <CLI/CLI.hpp>
#include <atomic>
#include <functional>
#include <string>
#include <vector>

namespace overstep::cli {

using Runner = std::function<int()>;

class Registry {
 public:
  /// Registers a parsed subcommand and the function that runs it.
  void add(CLI::App* sub, Runner run);
  /// Runs the subcommand the user selected, mapping exceptions to exit codes.
  int runSelected() const;

 private:
  std::vector<std::pair<CLI::App*, Runner>> commands_;
};

/// Calls fn; InputError -> exit 2, InfeasibleError -> 3, anything else -> 1, each with one line.
int guarded(const std::string& command, const Runner& fn);

/// The default robot YAML: robots/hrp2/hrp2.yaml under the working directory when present, else
/// the copy in the source tree this binary was built from.
std::string defaultRobotPath();

/// Prints a one-line error for command to stderr.
void printError(const std::string& command, const std::string& message);

/// While alive, SIGINT (and SIGTERM if asked) set a flag instead of killing the process, so that
/// long work (a solve, a simulation, a replay) can stop cleanly and keep what it has; the
/// previous handlers come back on destruction. One at a time.
class StopSignals {
 public:
  explicit StopSignals(bool also_sigterm = true);
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  /// The flag (async-signal-safe to set; pass it to code that polls it).
  static std::atomic<bool>& flag();
  static bool requested() { return flag().load(); }

 private:
  bool sigterm_;
  void (*prev_int_)(int) = nullptr;
  void (*prev_term_)(int) = nullptr;
};

}  // namespace overstep::cli
