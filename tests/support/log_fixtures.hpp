#pragma once
// Synthetic LCM logs written with liblcm's own writer: our message types at known rates with
// seeded random contents, plus a foreign message, and the byte offset of every event (for tests
// of export, monitor rates and damaged logs).
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <random>
#include <string>
#include <vector>

#include "msg_fixtures.hpp"

namespace overstep::test {

struct WrittenEvent {
  std::int64_t offset = 0;
  std::int64_t timestamp = 0;  // us
  std::string channel;
  std::vector<std::uint8_t> data;
};

struct SyntheticLog {
  std::vector<WrittenEvent> events;
  std::vector<robot_state_t> states;  // in order, as written on OVERSTEP_STATE
  std::vector<runtime_status_t> statuses;
  double control_rate = 200.0, status_rate = 10.0;
  std::int64_t t0 = 1'700'000'000'000'000;  // us
};

template <class T>
std::vector<std::uint8_t> encodeMsg(const T& m) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

/// `seconds` of control-rate OVERSTEP_STATE and OVERSTEP_COMMAND (receive jitter up to
/// `jitter_us`), OVERSTEP_RUNTIME at 10 Hz, and one foreign message on OTHER_TOOL.
inline SyntheticLog writeSyntheticLog(const std::string& path, double seconds, unsigned seed,
                                      int jitter_us = 300) {
  SyntheticLog log;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> jit(0, jitter_us);
  lcm::LogFile file(path, "w");
  auto write = [&](const std::string& channel, std::int64_t ts, std::vector<std::uint8_t> data) {
    WrittenEvent e;
    e.offset = ftello(file.getFilePtr());
    e.timestamp = ts;
    e.channel = channel;
    e.data = std::move(data);
    lcm::LogEvent le{};
    le.timestamp = ts;
    le.channel = channel;
    le.datalen = static_cast<int32_t>(e.data.size());
    le.data = e.data.data();
    file.writeEvent(&le);
    log.events.push_back(std::move(e));
  };
  const int ticks = static_cast<int>(seconds * log.control_rate);
  const int per_status = static_cast<int>(log.control_rate / log.status_rate);
  for (int k = 0; k < ticks; ++k) {
    const std::int64_t ut = log.t0 + static_cast<std::int64_t>(k * 1e6 / log.control_rate);
    robot_state_t s = makeState(30);
    s.utime = ut;
    s.seq = k;
    for (auto& v : s.q) v = u(rng) * std::pow(10.0, static_cast<int>(6 * u(rng)));
    for (auto& v : s.ft_right) v = u(rng) * 700.0;
    write("OVERSTEP_STATE", ut + jit(rng), encodeMsg(s));
    log.states.push_back(s);
    robot_command_t c = makeCommand(30);
    c.utime = ut;
    c.seq = k;
    for (auto& v : c.q_ref) v = u(rng);
    write("OVERSTEP_COMMAND", ut + 100 + jit(rng), encodeMsg(c));
    if (k % per_status == 0) {
      runtime_status_t r = makeRuntimeStatus();
      r.utime = ut;
      r.seq = k / per_status;
      r.fault_reason = k == 0 ? "quote \" and, comma" : "";
      write("OVERSTEP_RUNTIME", ut + 200 + jit(rng), encodeMsg(r));
      log.statuses.push_back(r);
    }
    if (k == ticks / 2) write("OTHER_TOOL", ut + 300, {1, 2, 3, 4, 5, 6, 7, 8, 9});
  }
  return log;
}

}  // namespace overstep::test
