#include "overstep/monitor/messages.hpp"

#include <cstring>
#include <stdexcept>

namespace overstep::monitor {
namespace {

class Sink {
 public:
  Sink(const std::vector<std::string>& joints, std::vector<Cell>& out)
      : joints_(joints), out_(out) {
    out_.clear();
  }
  void integer(const std::string& name, std::int64_t v, const char* unit = "") {
    Cell c;
    c.kind = Cell::Kind::Integer;
    c.name = name;
    c.unit = unit;
    c.integer = v;
    out_.push_back(std::move(c));
  }
  void real(const std::string& name, double v, const char* unit) {
    Cell c;
    c.kind = Cell::Kind::Real;
    c.name = name;
    c.unit = unit;
    c.real = v;
    out_.push_back(std::move(c));
  }
  void text(const std::string& name, const std::string& v) {
    Cell c;
    c.kind = Cell::Kind::Text;
    c.name = name;
    c.text = v;
    out_.push_back(std::move(c));
  }
  template <class T>
  void array(const std::string& name, const T* v, int n, const char* unit,
             const char* const* labels = nullptr) {
    for (int i = 0; i < n; ++i)
      real(name + "[" + (labels ? std::string(labels[i]) : std::to_string(i)) + "]", v[i], unit);
  }
  /// Joint arrays: names from the robot when the count matches.
  void joints(const std::string& name, const std::vector<double>& v, const char* unit) {
    const bool named = joints_.size() == v.size();
    for (std::size_t i = 0; i < v.size(); ++i)
      real(name + "[" + (named ? joints_[i] : std::to_string(i)) + "]", v[i], unit);
  }
  /// Wrench arrays [a b c d e f] with per-element units.
  void wrench(const std::string& name, const double* v, const char* const* labels,
              bool force_first) {
    for (int i = 0; i < 6; ++i)
      real(name + "[" + labels[i] + "]", v[i], (i < 3) == force_first ? "N" : "N m");
  }

 private:
  const std::vector<std::string>& joints_;
  std::vector<Cell>& out_;
};

const char* const kXyz[] = {"x", "y", "z"};
const char* const kWxyz[] = {"w", "x", "y", "z"};
const char* const kXy[] = {"x", "y"};
const char* const kRp[] = {"roll", "pitch"};
const char* const kFm[] = {"Fx", "Fy", "Fz", "Mx", "My", "Mz"};

void fields(const overstep::robot_command_t& m, Sink& s) {
  s.integer("utime", m.utime, "us");
  s.integer("seq", m.seq);
  s.integer("num_joints", m.num_joints);
  s.joints("q_ref", m.q_ref, "rad");
  s.joints("qd_ref", m.qd_ref, "rad/s");
  s.integer("has_tau_ff", m.has_tau_ff ? 1 : 0);
  s.joints("tau_ff", m.tau_ff, "N m");
}
void fields(const overstep::robot_state_t& m, Sink& s) {
  s.integer("utime", m.utime, "us");
  s.integer("seq", m.seq);
  s.integer("last_command_seq", m.last_command_seq);
  s.integer("num_joints", m.num_joints);
  s.joints("q", m.q, "rad");
  s.joints("qd", m.qd, "rad/s");
  s.joints("tau", m.tau, "N m");
  s.wrench("ft_right", m.ft_right, kFm, true);
  s.wrench("ft_left", m.ft_left, kFm, true);
  s.array("imu_quaternion", m.imu_quaternion, 4, "", kWxyz);
  s.array("imu_angular_velocity", m.imu_angular_velocity, 3, "rad/s", kXyz);
  s.array("imu_linear_acceleration", m.imu_linear_acceleration, 3, "m/s^2", kXyz);
  s.integer("has_ground_truth", m.has_ground_truth ? 1 : 0);
  s.array("base_position", m.base_position, 3, "m", kXyz);
  s.array("base_quaternion", m.base_quaternion, 4, "", kWxyz);
  s.array("base_linear_velocity", m.base_linear_velocity, 3, "m/s", kXyz);
  s.array("base_angular_velocity", m.base_angular_velocity, 3, "rad/s", kXyz);
}
void fields(const overstep::plan_reference_t& m, Sink& s) {
  s.integer("utime", m.utime, "us");
  s.integer("seq", m.seq);
  s.real("plan_time", m.plan_time, "s");
  s.real("plan_duration", m.plan_duration, "s");
  s.integer("phase", m.phase);
  s.text("phase_name", m.phase_name);
  s.array("com", m.com, 3, "m", kXyz);
  s.array("com_velocity", m.com_velocity, 3, "m/s", kXyz);
  s.array("zmp_wholebody", m.zmp_wholebody, 2, "m", kXy);
  s.array("zmp_tablecart", m.zmp_tablecart, 2, "m", kXy);
  s.array("right_foot_position", m.right_foot_position, 3, "m", kXyz);
  s.array("right_foot_quaternion", m.right_foot_quaternion, 4, "", kWxyz);
  s.array("left_foot_position", m.left_foot_position, 3, "m", kXyz);
  s.array("left_foot_quaternion", m.left_foot_quaternion, 4, "", kWxyz);
  s.integer("right_contact", m.right_contact ? 1 : 0);
  s.integer("left_contact", m.left_contact ? 1 : 0);
  s.wrench("right_wrench", m.right_wrench, kFm, true);
  s.wrench("left_wrench", m.left_wrench, kFm, true);
}
void fields(const overstep::stabilizer_status_t& m, Sink& s) {
  s.integer("utime", m.utime, "us");
  s.integer("seq", m.seq);
  s.integer("mode", m.mode);
  s.real("ramp", m.ramp, "");
  s.integer("fault", m.fault);
  s.text("fault_reason", m.fault_reason);
  s.integer("saturations", m.saturations);
  s.array("zmp_reference", m.zmp_reference, 2, "m", kXy);
  s.array("zmp_measured", m.zmp_measured, 2, "m", kXy);
  s.array("zmp_command", m.zmp_command, 2, "m", kXy);
  s.array("com_error", m.com_error, 3, "m", kXyz);
  s.array("dcm_error", m.dcm_error, 2, "m", kXy);
  s.array("com_offset", m.com_offset, 3, "m", kXyz);
  s.array("right_foot_rotation", m.right_foot_rotation, 2, "rad", kRp);
  s.array("left_foot_rotation", m.left_foot_rotation, 2, "rad", kRp);
  s.real("foot_height_difference", m.foot_height_difference, "m");
  s.array("body_attitude", m.body_attitude, 2, "rad", kRp);
}
void fields(const overstep::runtime_status_t& m, Sink& s) {
  s.integer("utime", m.utime, "us");
  s.integer("seq", m.seq);
  s.integer("state", m.state);
  s.text("fault_reason", m.fault_reason);
  s.integer("tick", m.tick);
  s.real("plan_time", m.plan_time, "s");
  s.real("rate_hz", m.rate_hz, "Hz");
  s.real("period_min_us", m.period_min_us, "us");
  s.real("period_mean_us", m.period_mean_us, "us");
  s.real("period_max_us", m.period_max_us, "us");
  s.real("period_p99_us", m.period_p99_us, "us");
  s.real("processing_mean_us", m.processing_mean_us, "us");
  s.real("processing_max_us", m.processing_max_us, "us");
  s.integer("overruns", m.overruns);
  s.integer("missed_cycles", m.missed_cycles);
  s.integer("late_states", m.late_states);
  s.integer("dropped_states", m.dropped_states);
}
void fields(const overstep::replay_control_t& m, Sink& s) {
  s.integer("utime", m.utime, "us");
  s.integer("seq", m.seq);
  s.integer("command", m.command);
}
void fields(const overstep::sim_status_t& m, Sink& s) {
  s.integer("utime", m.utime, "us");
  s.integer("seq", m.seq);
  s.real("sim_time", m.sim_time, "s");
  s.real("real_time_factor", m.real_time_factor, "");
  s.integer("num_contacts", m.num_contacts);
  s.integer("right_foot_contact", m.right_foot_contact ? 1 : 0);
  s.integer("left_foot_contact", m.left_foot_contact ? 1 : 0);
  s.integer("fell", m.fell ? 1 : 0);
  s.integer("obstacle_contact", m.obstacle_contact ? 1 : 0);
  s.integer("holding", m.holding ? 1 : 0);
  s.integer("rejected_commands", m.rejected_commands);
}

/// Byte offset of `num_joints` in the types with joint arrays (after the 8-byte fingerprint and
/// the int64 fields before it; test_monitor checks both), -1 in the others.
template <class T>
constexpr int kJointCountAt = -1;
template <>
constexpr int kJointCountAt<overstep::robot_command_t> = 8 + 2 * 8;  // utime, seq
template <>
constexpr int kJointCountAt<overstep::robot_state_t> = 8 + 3 * 8;  // utime, seq, last_command_seq

/// Byte offset of the length of the one string field in the types that have one (after the
/// fingerprint and the fixed-size fields before it; test_monitor checks each), -1 in the others.
template <class T>
constexpr int kStringAt = -1;
template <>
constexpr int kStringAt<overstep::plan_reference_t> = 8 + 4 * 8 + 4;  // ... plan_duration, phase
template <>
constexpr int kStringAt<overstep::runtime_status_t> = 8 + 2 * 8 + 1;  // utime, seq, state
template <>
constexpr int kStringAt<overstep::stabilizer_status_t> = 8 + 2 * 8 + 1 + 8 + 4;  // ... ramp, fault

std::int32_t int32At(const unsigned char* b, int at) {
  return static_cast<std::int32_t>((std::uint32_t{b[at]} << 24) | (std::uint32_t{b[at + 1]} << 16) |
                                   (std::uint32_t{b[at + 2]} << 8) | std::uint32_t{b[at + 3]});
}

/// False when the string's declared length (bytes with its terminating NUL) is below 1 or beyond
/// the message: lcm-gen 1.3's decoder copies length - 1 bytes after checking only the upper bound
/// (found by tests/fuzz/fuzz_msgs: length 0 threw std::length_error, -2^31 read 2 GB past the
/// buffer: SIGSEGV in export, monitor and report).
template <class T>
bool stringLengthFits(const unsigned char* b, int size) {
  constexpr int at = kStringAt<T>;
  if constexpr (at < 0) {
    return true;
  } else {
    if (size < at + 4) return false;
    const std::int32_t n = int32At(b, at);
    return n >= 1 && n <= size - at - 4;
  }
}

/// False when the declared joint count is negative or its arrays cannot fit in `size` bytes: the
/// generated decoder resizes the arrays before it reads them (a negative count threw
/// std::length_error, 2^26 joints in a 1 kB event allocated 512 MB).
template <class T>
bool jointCountFits(const unsigned char* b, int size) {
  constexpr int at = kJointCountAt<T>;
  if constexpr (at < 0) {
    return true;
  } else {
    if (size < at + 4) return false;
    const auto n =
        static_cast<std::int32_t>((std::uint32_t{b[at]} << 24) | (std::uint32_t{b[at + 1]} << 16) |
                                  (std::uint32_t{b[at + 2]} << 8) | std::uint32_t{b[at + 3]});
    return n >= 0 && std::int64_t{n} * 8 <= size - at - 4;
  }
}

template <class T>
DecodeStatus tryDecode(const void* data, int size, std::int64_t hash, AnyMessage& out,
                       bool& matched) {
  if (matched || hash != T::getHash()) return DecodeStatus::UnknownType;
  matched = true;
  if (!jointCountFits<T>(static_cast<const unsigned char*>(data), size) ||
      !stringLengthFits<T>(static_cast<const unsigned char*>(data), size))
    return DecodeStatus::Malformed;
  T msg;
  try {  // belt and braces: what the generated code throws is a malformed message too
    if (msg.decode(data, 0, size) != size) return DecodeStatus::Malformed;
  } catch (const std::exception&) {
    return DecodeStatus::Malformed;
  }
  out = std::move(msg);
  return DecodeStatus::Ok;
}

}  // namespace

std::string typeName(const AnyMessage& m) {
  if (m.index() == 0) return "";
  return knownTypeNames()[m.index() - 1];
}

const std::vector<std::string>& knownTypeNames() {
  static const std::vector<std::string> names = {
      "robot_command_t",  "robot_state_t",    "plan_reference_t", "stabilizer_status_t",
      "runtime_status_t", "replay_control_t", "sim_status_t"};
  return names;
}

DecodeStatus decode(const void* data, int size, AnyMessage& out) {
  out = std::monostate{};
  if (data == nullptr || size < 8) return DecodeStatus::UnknownType;
  // The fingerprint is a big-endian int64 at the start of the message.
  const auto* b = static_cast<const unsigned char*>(data);
  std::uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | b[i];
  const auto hash = static_cast<std::int64_t>(h);
  bool matched = false;
  DecodeStatus st = DecodeStatus::UnknownType;
  auto take = [&](DecodeStatus s) {
    if (matched && st == DecodeStatus::UnknownType) st = s;
  };
  take(tryDecode<overstep::robot_command_t>(data, size, hash, out, matched));
  take(tryDecode<overstep::robot_state_t>(data, size, hash, out, matched));
  take(tryDecode<overstep::plan_reference_t>(data, size, hash, out, matched));
  take(tryDecode<overstep::stabilizer_status_t>(data, size, hash, out, matched));
  take(tryDecode<overstep::runtime_status_t>(data, size, hash, out, matched));
  take(tryDecode<overstep::replay_control_t>(data, size, hash, out, matched));
  take(tryDecode<overstep::sim_status_t>(data, size, hash, out, matched));
  return st;
}

void flatten(const AnyMessage& m, const std::vector<std::string>& joint_names,
             std::vector<Cell>& out) {
  Sink s(joint_names, out);
  std::visit(
      [&](const auto& msg) {
        if constexpr (!std::is_same_v<std::decay_t<decltype(msg)>, std::monostate>) fields(msg, s);
      },
      m);
}

bool stamp(const AnyMessage& m, std::int64_t& utime, std::int64_t& seq) {
  return std::visit(
      [&](const auto& msg) {
        if constexpr (std::is_same_v<std::decay_t<decltype(msg)>, std::monostate>) {
          return false;
        } else {
          utime = msg.utime;
          seq = msg.seq;
          return true;
        }
      },
      m);
}

}  // namespace overstep::monitor
