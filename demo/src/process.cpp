#include "process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace overstep::demo {

namespace {

/// posix_spawn's file actions, destroyed on every path.
struct FileActions {
  posix_spawn_file_actions_t fa;
  FileActions() { posix_spawn_file_actions_init(&fa); }
  ~FileActions() { posix_spawn_file_actions_destroy(&fa); }
  FileActions(const FileActions&) = delete;
  FileActions& operator=(const FileActions&) = delete;
};

}  // namespace

pid_t spawn(const std::vector<std::string>& argv, const std::string& out, const std::string& err) {
  if (argv.empty()) throw std::runtime_error("spawn: empty command");
  FileActions actions;
  const int flags = O_WRONLY | O_CREAT | O_TRUNC;  // not O_CLOEXEC: it becomes the child's fd 1 / 2
  if (!out.empty()) posix_spawn_file_actions_addopen(&actions.fa, 1, out.c_str(), flags, 0644);
  if (!err.empty()) posix_spawn_file_actions_addopen(&actions.fa, 2, err.c_str(), flags, 0644);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, args[0], &actions.fa, nullptr, args.data(), environ);
  if (rc != 0) throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(rc));
  return pid;
}

int waitFor(pid_t pid, double timeout_s) {
  const auto t0 = std::chrono::steady_clock::now();
  int status = 0;
  while (true) {
    const pid_t r = waitpid(pid, &status, timeout_s < 0 ? 0 : WNOHANG);
    if (r == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) return -1;
    if (timeout_s >= 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout_s)
      return kTimedOut;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

int stop(pid_t pid, int sig, double grace_s) {
  kill(pid, sig);
  int code = waitFor(pid, grace_s);
  if (code == kTimedOut) {
    kill(pid, SIGKILL);
    code = waitFor(pid, -1);
  }
  return code;
}

std::string selfExe() {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the overstep executable (/proc/self/exe)");
  return p.string();
}

}  // namespace overstep::demo
