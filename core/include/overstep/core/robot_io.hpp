#pragma once
/// \file
/// Transport-independent robot command and state (the runtime <-> robot contract). msgs/convert
/// maps them to and from the LCM types; nothing else knows both.
/// Vectors are sized for the actuated joints (robot YAML order). Units: rad, rad/s, N, N m, us.

#include <Eigen/Geometry>
#include <cstdint>

#include "overstep/core/wrench.hpp"

namespace overstep::core {

struct RobotCommand {
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  Eigen::VectorXd q_ref;   ///< rad
  Eigen::VectorXd qd_ref;  ///< rad/s
  bool has_tau_ff = false;
  Eigen::VectorXd tau_ff;  ///< N m (meaningful when has_tau_ff)

  void resize(int n) {
    q_ref.setZero(n);
    qd_ref.setZero(n);
    tau_ff.setZero(n);
  }
};

struct RobotState {
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  std::int64_t last_command_seq = -1;
  Eigen::VectorXd q;                              ///< rad
  Eigen::VectorXd qd;                             ///< rad/s
  Eigen::VectorXd tau;                            ///< N m, measured (motor current) torque estimate
  Wrench ft_right = Wrench::zero(Axes::kSensor);  ///< right sensor, about its origin
  Wrench ft_left = Wrench::zero(Axes::kSensor);   ///< left sensor, about its origin
  Eigen::Quaterniond imu_orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d imu_angular_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d imu_linear_acceleration = Eigen::Vector3d::Zero();
  bool has_ground_truth = false;  ///< simulator only
  Eigen::Isometry3d base_pose = Eigen::Isometry3d::Identity();
  Eigen::Vector3d base_linear_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d base_angular_velocity = Eigen::Vector3d::Zero();

  void resize(int n) {
    q.setZero(n);
    qd.setZero(n);
    tau.setZero(n);
  }
};

}  // namespace overstep::core
