#include "overstep/core/wrench.hpp"

#include <cmath>
#include <limits>

namespace overstep::core {

Vector6d shiftWrench(const Vector6d& w_p, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  Vector6d out = w_p;
  out.head<3>() += (p - q).cross(w_p.tail<3>());
  return out;
}

Vector6d transformWrench(const Eigen::Isometry3d& X_WF, const Vector6d& w_F) {
  const Eigen::Matrix3d& R = X_WF.linear();
  Vector6d out;
  out.tail<3>() = R * w_F.tail<3>();
  out.head<3>() = R * w_F.head<3>() + X_WF.translation().cross(out.tail<3>());
  return out;
}

Eigen::Vector2d zmpFromWrench(const Vector6d& w_O, double ground_z, double min_fz) {
  const double fz = w_O(5);
  if (!(std::abs(fz) >= min_fz)) {
    return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  }
  // torque about P = (px, py, h) vanishes in x and y.
  return {(-w_O(1) + ground_z * w_O(3)) / fz, (w_O(0) + ground_z * w_O(4)) / fz};
}

Eigen::Vector2d localCop(const Vector6d& w_S, double min_fz) {
  return zmpFromWrench(w_S, 0.0, min_fz);
}

Eigen::Vector2d tableCartZmp(const Eigen::Vector3d& com, const Eigen::Vector3d& com_acc, double g,
                             double ground_z) {
  return com.head<2>() - (com.z() - ground_z) / g * com_acc.head<2>();
}

}  // namespace overstep::core
