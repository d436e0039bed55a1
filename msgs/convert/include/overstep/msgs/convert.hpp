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

}  // namespace overstep::msgs
