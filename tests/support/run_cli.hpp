#pragma once
// Runs the `overstep` binary (OVERSTEP_BIN) as a user would and captures exit code, stdout,
// stderr and wall time.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "test_util.hpp"

namespace overstep::test {

struct RunResult {
  int code = -1;
  std::string out, err;
  double seconds = 0.0;
};

inline RunResult runOverstep(const std::string& args) {
  TempDir dir;
  const std::string errfile = dir.file("stderr");
  const std::string cmd = std::string(OVERSTEP_BIN) + " " + args + " 2>" + errfile;
  const auto t0 = std::chrono::steady_clock::now();
  RunResult r;
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = slurp(errfile);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

/// Starts `overstep ARGS` in the background with stdout and stderr to files; returns its pid
/// (the shell execs the binary, so killing the pid kills overstep itself).
inline pid_t spawnOverstep(const std::string& args, const std::string& out_file,
                           const std::string& err_file) {
  const std::string cmd =
      "exec " + std::string(OVERSTEP_BIN) + " " + args + " >" + out_file + " 2>" + err_file;
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

/// Waits for a spawned process; returns its exit code (-signal if killed, -1000 on timeout,
/// after which it is killed).
inline int waitOverstep(pid_t pid, double timeout_s) {
  const auto t0 = std::chrono::steady_clock::now();
  int status = 0;
  while (true) {
    const pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout_s) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return -1000;
    }
    usleep(10000);
  }
}

/// Kills (SIGKILL) and reaps the processes it holds when it goes out of scope, so that a failed
/// assertion never leaves a simulator or runtime talking on the bus of the next test.
class ProcessGuard {
 public:
  pid_t add(pid_t pid) {
    pids_.push_back(pid);
    return pid;
  }
  ~ProcessGuard() {
    for (pid_t p : pids_) {
      if (kill(p, 0) == 0) {
        kill(p, SIGKILL);
        int status = 0;
        waitpid(p, &status, 0);
      }
    }
  }

 private:
  std::vector<pid_t> pids_;
};

}  // namespace overstep::test
