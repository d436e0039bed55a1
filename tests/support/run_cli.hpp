#pragma once
// Runs the `overstep` binary (OVERSTEP_BIN) as a user would and captures exit code, stdout,
// stderr and wall time.
#include <sys/wait.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <string>

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

}  // namespace overstep::test
