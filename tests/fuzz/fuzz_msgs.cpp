// Fuzz target: every LCM message decoder as it is used (monitor::decode for every type, which
// checks joint counts and string lengths first; msgs::decodeChecked for states and commands, as
// the runtime and the simulator receive them; the replay control's generated decoder) and
// msgs_convert's fromLcm. Seeds:
// tests/fuzz/corpus/msgs/ (one encoded message of each type).
#include <cstdint>
#include <string>

#include "overstep/core/robot_io.hpp"
#include "overstep/monitor/messages.hpp"
#include "overstep/msgs/convert.hpp"
#include "overstep/replay_control_t.hpp"
#include "overstep/robot_command_t.hpp"
#include "overstep/robot_state_t.hpp"

namespace {

/// A generated decoder on its own, as an lcm-cpp typed subscription calls it: it must not read
/// out of bounds (ASan).
template <class T>
void raw(const std::uint8_t* data, std::size_t size) {
  T m;
  (void)m.decode(data, 0, static_cast<int>(size));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace overstep;
  if (size > (1u << 20)) return 0;
  // What the processes decode from the bus: the runtime's OVERSTEP_REPLAY_CONTROL through
  // liblcm's typed subscription (no arrays, no strings: the generated decoder as it is), the
  // runtime's states and the simulator's commands through msgs::decodeChecked (lcm-gen resizes
  // their joint arrays before checking the bytes), then fromLcm as they use it.
  raw<overstep::replay_control_t>(data, size);
  std::string why;
  overstep::robot_command_t command;
  core::RobotCommand cmd;
  if (msgs::decodeChecked(data, static_cast<int>(size), command, &why))
    (void)msgs::fromLcm(command, 30, cmd, &why);
  overstep::robot_state_t state;
  core::RobotState st;
  if (msgs::decodeChecked(data, static_cast<int>(size), state, &why))
    (void)msgs::fromLcm(state, 30, st, &why);
  // The status types' strings are read past the buffer by the generated code for lengths <= 0;
  // they are decoded through monitor::decode only, which checks lengths first.
  monitor::AnyMessage msg;
  if (monitor::decode(data, static_cast<int>(size), msg) != monitor::DecodeStatus::Ok) return 0;
  if (auto* s = std::get_if<overstep::robot_state_t>(&msg)) {
    (void)msgs::fromLcm(*s, s->num_joints, st, &why);
  } else if (auto* c = std::get_if<overstep::robot_command_t>(&msg)) {
    (void)msgs::fromLcm(*c, c->num_joints, cmd, &why);
  }
  std::vector<monitor::Cell> cells;
  monitor::flatten(msg, {}, cells);
  return 0;
}
