#include <fcntl.h>
#include <netinet/in.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "overstep/demo/demo.hpp"

namespace overstep::demo {

namespace {

/// True when no socket on this machine is bound to UDP `port`: a bind without SO_REUSEADDR
/// fails while liblcm's udpm sockets (which set it) hold the port.
bool udpPortFree(int port) {
  const int s = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (s < 0) return false;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool ok = bind(s, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  close(s);
  return ok;
}

/// The lock file of a port, shared by every demo on this machine (a per-user folder would let
/// two users' demos share a bus).
std::string lockPath(int port) {
  return (std::filesystem::temp_directory_path() /
          ("overstep-lcm-" + std::to_string(port) + ".lock"))
      .string();
}

}  // namespace

PrivateBus::PrivateBus(int first, int last) {
  for (int port = first; port <= last; ++port) {
    const int fd = open(lockPath(port).c_str(), O_RDONLY | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    // The lock first (another demo may hold the port without its processes bound yet), then
    // the probe (any other LCM user of the port).
    if (flock(fd, LOCK_EX | LOCK_NB) == 0 && udpPortFree(port)) {
      port_ = port;
      lock_fd_ = fd;
      return;
    }
    close(fd);
  }
  throw std::runtime_error("no free LCM port in " + std::to_string(first) + ".." +
                           std::to_string(last) + " (every one held by another demo or bound)");
}

PrivateBus::~PrivateBus() {
  if (lock_fd_ >= 0) close(lock_fd_);  // releases the lock
}

std::string PrivateBus::url() const {
  return "udpm://239.255.76.67:" + std::to_string(port_) + "?ttl=0";
}

}  // namespace overstep::demo
