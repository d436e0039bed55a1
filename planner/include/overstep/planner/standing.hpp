#pragma once
/// \file
/// A static standing plan: the robot holds a half-sitting-like posture with its CoM above the
/// ankles (hip and ankle pitch leaned together, the pelvis upright), both feet loaded through
/// their ankle axes, for `duration` seconds. Dynamically consistent by construction (statics), so
/// `overstep check` accepts it. For bringing up the runtime and the stabilizer on a robot
/// (`overstep plan --stand`), for tests and benchmarks.

#include "overstep/core/plan.hpp"
#include "overstep/robots/whole_body_model.hpp"

namespace overstep::planner {

/// Needs RLEG/LLEG_JOINT2 (hip pitch) and JOINT4 (ankle pitch) and a left and right foot.
/// Throws InputError for a duration outside (0, 3600] s or a rate outside [50, 1000] Hz.
core::Plan standingPlan(robots::WholeBodyModel& model, double duration, double rate = 200.0);

}  // namespace overstep::planner
