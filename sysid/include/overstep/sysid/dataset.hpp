#pragma once
/// \file
/// What identification works on: one record per control tick of a replay — the command the
/// runtime sent, the state it had read just before (k) and the state that followed the command
/// (k+1), and the plan time. Built from an LCM log (`overstep identify`) or in process (tests).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "overstep/core/robot_io.hpp"

namespace overstep::sysid {

struct Record {
  double t = 0.0;                 ///< s, robot clock of the state that followed the command
  double plan_t = 0.0;            ///< s, plan time the command was for
  Eigen::VectorXd q_ref, qd_ref;  ///< command
  Eigen::VectorXd q0;             ///< encoders when the command was computed (state k)
  Eigen::VectorXd q, qd, tau;     ///< state k+1
  core::Wrench ft[2];             ///< state k+1, each sensor's reading (its axes, about its origin)
  Eigen::Quaterniond imu = Eigen::Quaterniond::Identity();  ///< state k+1, IMU orientation
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();           ///< state k+1, rad/s, IMU frame
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  ///< state k+1, specific force, IMU frame
};

struct Dataset {
  std::vector<Record> records;
  double period = 0.005;  ///< s, control period
  int size() const { return static_cast<int>(records.size()); }
  int joints() const { return records.empty() ? 0 : static_cast<int>(records[0].q.size()); }
  /// Appends one tick; `before` is the state the runtime read, `after` the next one.
  void add(double plan_t, const core::RobotCommand& cmd, const core::RobotState& before,
           const core::RobotState& after);
  /// Records [begin, end).
  Dataset slice(int begin, int end) const;
};

}  // namespace overstep::sysid
