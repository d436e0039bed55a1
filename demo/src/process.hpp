#pragma once
/// \file
/// Internal to demo/: child processes started directly (posix_spawn, no shell), their output
/// redirected to files.

#include <sys/types.h>

#include <string>
#include <vector>

namespace overstep::demo {

/// Starts argv[0] (found on PATH when it has no slash) with stdout / stderr to the files `out` /
/// `err` (empty: inherited); returns the pid. std::runtime_error when it cannot start.
pid_t spawn(const std::vector<std::string>& argv, const std::string& out, const std::string& err);

/// Waits up to `timeout_s` (< 0: forever); returns the exit code, -signal, or kTimedOut.
int waitFor(pid_t pid, double timeout_s);
constexpr int kTimedOut = -1000;

/// Sends `sig`, waits `grace_s`, then SIGKILL; returns as waitFor.
int stop(pid_t pid, int sig, double grace_s);

/// This binary (/proc/self/exe).
std::string selfExe();

}  // namespace overstep::demo
