#pragma once
/// \file
/// Seeded Gaussian sensor noise for simulated robot states (`overstep sim --seed --noise`, and
/// the identification tests). Standard deviations at scale 1 (realistic small values): encoders
/// 2e-5 rad and 2e-3 rad/s, motor torque 0.5 N m, force 0.5 N, moment 0.03 N m, gyro 1e-3 rad/s,
/// accelerometer 0.02 m/s^2. Not real-time safe (std::normal_distribution); call between ticks.

#include <random>

#include "overstep/core/robot_io.hpp"

namespace overstep::sim {

class SensorNoise {
 public:
  SensorNoise(unsigned seed, double scale) : rng_(seed), scale_(scale) {}
  /// Adds noise to every measured field (not to the ground truth).
  void apply(core::RobotState& st) {
    for (Eigen::Index j = 0; j < st.q.size(); ++j) {
      st.q(j) += n(2e-5);
      st.qd(j) += n(2e-3);
      st.tau(j) += n(0.5);
    }
    for (core::Wrench* w : {&st.ft_right, &st.ft_left}) {
      for (int i = 0; i < 3; ++i) w->force(i) += n(0.5);
      for (int i = 0; i < 3; ++i) w->moment(i) += n(0.03);
    }
    for (int i = 0; i < 3; ++i) {
      st.imu_angular_velocity(i) += n(1e-3);
      st.imu_linear_acceleration(i) += n(0.02);
    }
  }

 private:
  double n(double sigma) {
    if (scale_ <= 0.0) return 0.0;
    std::normal_distribution<double> d(0.0, sigma * scale_);
    return d(rng_);
  }
  std::mt19937_64 rng_;
  double scale_;
};

}  // namespace overstep::sim
