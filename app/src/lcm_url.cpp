#include "overstep/cli/lcm_url.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "overstep/core/error.hpp"
#include "overstep/core/stderr_capture.hpp"

namespace overstep::cli {
namespace {

using core::printable;

/// A decimal number of at most 10 digits in [lo, hi]; -1 otherwise.
long long decimal(const std::string& s, long long lo, long long hi) {
  if (s.empty() || s.size() > 10) return -1;
  long long v = 0;
  for (const char c : s) {
    if (c < '0' || c > '9') return -1;
    v = v * 10 + (c - '0');
  }
  return v >= lo && v <= hi ? v : -1;
}

}  // namespace

void checkLcmUrl(const std::string& url, const std::string& option) {
  std::string u = url, name = option;
  const char* env_url = std::getenv("LCM_DEFAULT_URL");
  if (env_url != nullptr && !u.empty() && u == env_url) name = "LCM_DEFAULT_URL";
  if (u.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    if (env == nullptr || *env == '\0') return;  // liblcm's built-in default
    u = env;
    name = "LCM_DEFAULT_URL";
  }
  const auto bad = [&](const std::string& why) {
    throw InputError(name + " '" + printable(u) + "': " + why);
  };
  for (const char ch : u)
    if (static_cast<unsigned char>(ch) <= 0x20 || static_cast<unsigned char>(ch) >= 0x7f)
      bad("expected printable ASCII without spaces");
  const auto sep = u.find("://");
  if (sep == std::string::npos) bad("expected udpm://GROUP:PORT?ttl=N (or memq://)");
  const std::string provider = u.substr(0, sep), rest = u.substr(sep + 3);
  if (provider == "memq") {
    if (!rest.empty()) bad("memq:// takes no address or options");
    return;
  }
  if (provider != "udpm")
    bad("provider '" + provider +
        "' is not supported (expected udpm://GROUP:PORT?ttl=N, or memq:// within one process)");
  const auto q = rest.find('?');
  const std::string network = rest.substr(0, q);
  if (!network.empty()) {
    const auto colon = network.find(':');
    const std::string group = network.substr(0, colon);
    int octets = 0, first = -1;
    std::size_t at = 0;
    while (at <= group.size()) {
      const auto dot = group.find('.', at);
      const std::string part =
          group.substr(at, dot == std::string::npos ? std::string::npos : dot - at);
      const long long v = part.size() <= 3 ? decimal(part, 0, 255) : -1;
      if (v < 0) {
        octets = -1;
        break;
      }
      if (octets == 0) first = static_cast<int>(v);
      ++octets;
      if (dot == std::string::npos) break;
      at = dot + 1;
    }
    if (octets != 4) bad("group '" + group + "': expected an IPv4 address A.B.C.D");
    if (first < 224 || first > 239)
      bad("group '" + group + "': expected a multicast address (224.0.0.0 to 239.255.255.255)");
    if (colon != std::string::npos && decimal(network.substr(colon + 1), 1, 65535) < 0)
      bad("port '" + network.substr(colon + 1) + "': expected 1 to 65535");
  }
  if (q == std::string::npos) return;
  std::string opts = rest.substr(q + 1);
  std::size_t at = 0;
  while (at < opts.size()) {
    const auto amp = opts.find('&', at);
    const std::string kv = opts.substr(at, amp == std::string::npos ? std::string::npos : amp - at);
    const auto eq = kv.find('=');
    const std::string key = kv.substr(0, eq);
    const std::string value = eq == std::string::npos ? std::string() : kv.substr(eq + 1);
    if (key == "ttl") {
      if (decimal(value, 0, 255) < 0) bad("ttl '" + value + "': expected 0 to 255");
    } else if (key == "recv_buf_size") {
      if (decimal(value, 0, 2147483647) < 0)
        bad("recv_buf_size '" + value + "': expected 0 to 2147483647 bytes");
    } else {
      bad("unknown option '" + key + "' (udpm takes ttl and recv_buf_size)");
    }
    if (amp == std::string::npos) break;
    at = amp + 1;
  }
}

void lcmOpened(bool good, const std::string& url, core::StderrCapture& said) {
  const std::string text = said.text();
  if (!good)
    throw InputError("cannot open LCM at '" + printable(url) + "'" +
                     (text.empty() ? std::string() : ": " + text));
  if (!text.empty()) std::fprintf(stderr, "%s\n", text.c_str());
}

}  // namespace overstep::cli
