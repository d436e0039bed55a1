#pragma once
/// \file
/// The only code that knows both the LCM types and the core types. Conversions into core types
/// validate (joint count, finite values) and never throw: they return false and name the problem.
/// They reuse the destination's storage (no allocation once sized).

#include <string>

#include "overstep/core/robot_io.hpp"
#include "overstep/robot_command_t.hpp"
#include "overstep/robot_state_t.hpp"

namespace overstep::msgs {

void toLcm(const core::RobotCommand& in, overstep::robot_command_t& out);
/// Rejects a wrong joint count (expected_joints) or any non-finite value.
bool fromLcm(const overstep::robot_command_t& in, int expected_joints, core::RobotCommand& out,
             std::string* why = nullptr);

void toLcm(const core::RobotState& in, overstep::robot_state_t& out);
bool fromLcm(const overstep::robot_state_t& in, int expected_joints, core::RobotState& out,
             std::string* why = nullptr);

/// Decodes a command or a state of `size` bytes as it arrives on a channel, checking the
/// fingerprint and the declared joint count against the bytes before lcm-gen's decoder sizes the
/// joint arrays (it resizes them first: 2^31 - 1 joints in 50 bytes asked for 16 GB per array, a
/// negative count threw; issue 20). False, naming the problem, on anything that does not decode
/// to exactly `size` bytes. Allocates only what the bytes can hold.
bool decodeChecked(const void* data, int size, overstep::robot_command_t& out,
                   std::string* why = nullptr);
bool decodeChecked(const void* data, int size, overstep::robot_state_t& out,
                   std::string* why = nullptr);

}  // namespace overstep::msgs
