#pragma once
/// \file
/// Our LCM types, recognised by their fingerprint (the first 8 bytes of every encoded message, so
/// a message is identified whatever channel it came on), decoded, and flattened into named columns
/// with units (for CSV export, the monitor and the report).

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "overstep/plan_reference_t.hpp"
#include "overstep/replay_control_t.hpp"
#include "overstep/robot_command_t.hpp"
#include "overstep/robot_state_t.hpp"
#include "overstep/runtime_status_t.hpp"
#include "overstep/sim_status_t.hpp"
#include "overstep/stabilizer_status_t.hpp"

namespace overstep::monitor {

using AnyMessage =
    std::variant<std::monostate, overstep::robot_command_t, overstep::robot_state_t,
                 overstep::plan_reference_t, overstep::stabilizer_status_t,
                 overstep::runtime_status_t, overstep::replay_control_t, overstep::sim_status_t>;

/// Type name of a decoded message ("" for monostate).
std::string typeName(const AnyMessage& m);
/// Names of every type we know, in AnyMessage order (without monostate).
const std::vector<std::string>& knownTypeNames();

enum class DecodeStatus { Ok, UnknownType, Malformed };

/// Decodes `size` bytes. UnknownType: the fingerprint is none of ours (another program's type,
/// or a log written with another schema); Malformed: ours, but the bytes do not decode (a joint
/// count that is negative or more than the bytes can hold is refused before anything is allocated).
DecodeStatus decode(const void* data, int size, AnyMessage& out);

/// One flattened field.
struct Cell {
  enum class Kind { Integer, Real, Text } kind = Kind::Real;
  std::string name;
  std::string unit;  ///< "" for dimensionless / counters
  std::int64_t integer = 0;
  double real = 0.0;
  std::string text;
};

/// Every field of the message as columns (arrays element by element). Joint arrays are named
/// `q[RLEG_JOINT0]` when `joint_names` has one name per element, else `q[0]`.
void flatten(const AnyMessage& m, const std::vector<std::string>& joint_names,
             std::vector<Cell>& out);

/// The message's own timestamp (utime, us) and sequence number; false for monostate.
bool stamp(const AnyMessage& m, std::int64_t& utime, std::int64_t& seq);

}  // namespace overstep::monitor
