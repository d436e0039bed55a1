#pragma once
/// \file
/// Does a log record a replay of this plan? `overstep identify` and `overstep report` compare
/// the log's OVERSTEP_PLAN_REF and joint arrays with the plan given to them (issue 20: a plan of
/// another run was accepted and read at the log's plan times and phases, or its phase index read
/// past the plan's phases).

#include <string>

#include "overstep/core/plan.hpp"
#include "overstep/plan_reference_t.hpp"

namespace overstep::monitor {

/// Empty when `ref` can come from a replay of `plan`: the duration it states within one sample
/// period (1 / rate) of the plan's, its plan time inside [0, duration + 1 / rate], its phase an
/// index of the plan's phases with the plan's name for it. Otherwise a one-line reason naming
/// both values.
std::string planReferenceMismatch(const overstep::plan_reference_t& ref, const core::Plan& plan);

/// Throws InputError "LOG: ... (PLAN ...; not the plan of this run?)" when `ref` does not match.
void checkPlanReference(const overstep::plan_reference_t& ref, const core::Plan& plan,
                        const std::string& log, const std::string& plan_path);

/// Throws InputError "LOG: CHANNEL carries N joints, PLAN has M" unless num_joints == joints.
void checkJointCount(int num_joints, int joints, const std::string& channel, const std::string& log,
                     const std::string& plan_path);

}  // namespace overstep::monitor
