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

/// Needs two legs (robots::legChains; their hip and ankle pitch joints lean the body) and a
/// left and right foot.
/// Throws InputError for a duration outside (0, 3600] s or a rate outside [50, 1000] Hz.
core::Plan standingPlan(robots::WholeBodyModel& model, double duration, double rate = 200.0);

/// An identification experiment on two feet: the standing posture of standingPlan() with the
/// chest, head and arm joints swinging (sums of sines at 0.3-1.1 Hz, amplitudes 0.1-0.4 rad times
/// `amplitude`, faded in and out over 1 s so that it starts and ends static). The legs hold still,
/// so the feet never move; the motion moves the CoM by centimetres and loads the ankles, the
/// force sensors and the moving joints' servos (`overstep plan --excite`, `overstep identify`).
/// Foot wrenches: the total contact wrench of the motion split between the feet by the ZMP.
/// Throws InputError for a duration outside [3, 3600] s, a rate outside [50, 1000] Hz or an
/// amplitude outside (0, 2].
core::Plan excitationPlan(robots::WholeBodyModel& model, double duration, double amplitude = 1.0,
                          double rate = 200.0);

}  // namespace overstep::planner
