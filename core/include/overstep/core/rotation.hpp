#pragma once
/// \file
/// Roll and pitch of a rotation (fixed x-y-z axes: the yaw-pitch-roll decomposition), the tilt
/// the planner bounds, the check verifies, the stabilizer corrects and identification predicts.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace overstep::core {

inline double rollOf(const Eigen::Matrix3d& R) { return std::atan2(R(2, 1), R(2, 2)); }
inline double pitchOf(const Eigen::Matrix3d& R) {
  return std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
}
inline Eigen::Vector2d rollPitch(const Eigen::Matrix3d& R) { return {rollOf(R), pitchOf(R)}; }

}  // namespace overstep::core
