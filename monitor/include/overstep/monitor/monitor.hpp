#pragma once
/// \file
/// What `overstep monitor` shows: per channel, message counts and rates (receive clock and the
/// messages' own clock) and the age of the last one; the latest runtime, plan, stabilizer and
/// simulator status. Fed message by message from a live bus or a log; no LCM in here.

#include <cstdint>
#include <deque>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "overstep/monitor/messages.hpp"

namespace overstep::monitor {

struct ChannelStats {
  std::string channel;
  std::string type;  ///< "" while no message decoded
  std::int64_t count = 0;
  std::int64_t undecodable = 0;  ///< foreign or malformed messages
  std::int64_t bytes = 0;
  std::int64_t first_recv = 0, last_recv = 0;  ///< us, receive clock
  std::int64_t first_utime = 0, last_utime = 0;
  std::int64_t decoded = 0;
  std::deque<std::int64_t> recent;  ///< receive times (us) inside the rate window

  /// Mean rate over everything received, receive clock (Hz); 0 below two messages.
  double meanRate() const;
  /// Rate by the messages' own timestamps (utime): the publisher's clock (robot time in a
  /// lock-step simulation); 0 below two decoded messages.
  double messageClockRate() const;
  /// Rate over the last `window` seconds before `now_us` (receive clock).
  double windowRate(std::int64_t now_us, double window) const;
};

class Monitor {
 public:
  explicit Monitor(double window_s = 1.0) : window_(window_s) {}
  /// One message received at `recv_us` (us, the receive clock: wall time live, the logger's
  /// timestamps on a log).
  void add(const std::string& channel, std::int64_t recv_us, const void* data, int size);

  const std::map<std::string, ChannelStats>& channels() const { return channels_; }
  /// Snapshot as JSON: {time, source, channels: {NAME: {...}}, runtime, plan, stabilizer, sim,
  /// robot}. Sections without data are null.
  nlohmann::json snapshot(std::int64_t now_us, const std::string& source) const;
  /// The terminal view (plain text, fits 100 columns).
  std::string render(std::int64_t now_us, const std::string& source) const;

 private:
  double window_;
  std::map<std::string, ChannelStats> channels_;
  std::optional<overstep::runtime_status_t> runtime_;
  std::optional<overstep::plan_reference_t> plan_;
  std::optional<overstep::stabilizer_status_t> stab_;
  std::optional<overstep::sim_status_t> sim_;
  std::optional<overstep::robot_state_t> state_;
  std::optional<overstep::robot_command_t> command_;
  AnyMessage scratch_;
};

/// Names of runtime states and stabilizer modes as the messages number them.
const char* runtimeStateName(int state);
const char* stabilizerModeName(int mode);

}  // namespace overstep::monitor
