#pragma once
// A statically consistent standing plan built from the robot model (the robot holds a
// half-sitting-like posture, CoM above the ankles, both feet loaded through their ankle axes), for
// tests of `overstep check` and of the plan file format. Generated here, never hand-written.
#include <cmath>

#include "overstep/core/plan.hpp"
#include "overstep/core/robot_io.hpp"
#include "overstep/planner/standing.hpp"
#include "overstep/robots/whole_body_model.hpp"

namespace overstep::test {

inline core::Plan standingPlan(robots::WholeBodyModel& m, double duration = 0.5,
                               double rate = 200.0) {
  return planner::standingPlan(m, duration, rate);
}

/// The robot state a perfect robot executing plan sample k would report: encoders on the plan,
/// each ankle sensor reading the planned contact wrench plus the weight of the bodies below it
/// (in the sensor frame, [F; M]), the IMU at the planned chest orientation. No noise.
inline core::RobotState perfectState(robots::WholeBodyModel& m, const core::Plan& plan, int k) {
  const auto& d = m.description();
  core::RobotState st;
  st.resize(m.actuatedCount());
  st.q = plan.q.col(k).segment(6, m.actuatedCount());
  st.qd = plan.v.col(k).segment(6, m.actuatedCount());
  st.tau = plan.tau.col(k);
  m.setState(plan.q.col(k), plan.v.col(k), plan.a.col(k));
  for (int f = 0; f < 2; ++f) {
    const auto* foot = d.foot(f == 0 ? "right" : "left");
    const int sensor = m.frameIndex(foot->force_sensor_frame);
    const Eigen::Isometry3d Xs = m.framePose(sensor);
    // The sensor carries the contact wrench and the weight of the bodies below it.
    Eigen::Vector3d c;
    const double mb = m.massBelow(sensor, &c);
    const core::Wrench weight({0, 0, -mb * d.gravity}, Eigen::Vector3d::Zero(), c,
                              core::Axes::kWorld);
    (f == 0 ? st.ft_right : st.ft_left) =
        (plan.wrench(f, k) + weight).inFrame(Xs, core::Axes::kSensor);
  }
  st.imu_orientation = Eigen::Quaterniond(m.framePose(m.frameIndex("imu")).linear());
  return st;
}

}  // namespace overstep::test
