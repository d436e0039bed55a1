#include "overstep/core/wrench.hpp"

#include <cmath>
#include <limits>

namespace overstep::core {

const char* axesName(Axes axes) {
  switch (axes) {
    case Axes::kWorld:
      return "world";
    case Axes::kSole:
      return "sole";
    case Axes::kSensor:
      return "sensor";
  }
  return "unknown";
}

namespace {

/// The point (x, y, h) about which the wrench's x and y moments vanish, from its moment about the
/// frame's origin.
Eigen::Vector2d pressureCentre(const Wrench& w, double h, double min_fz) {
  const Wrench w_O = w.point.isZero(0.0) ? w : w.about(Eigen::Vector3d::Zero());
  const double fz = w_O.force.z();
  if (!(std::abs(fz) >= min_fz)) {
    return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  }
  return {(-w_O.moment.y() + h * w_O.force.x()) / fz, (w_O.moment.x() + h * w_O.force.y()) / fz};
}

}  // namespace

Eigen::Vector2d zmpFromWrench(const Wrench& w_W, double ground_z, double min_fz) {
  assert(w_W.axes == Axes::kWorld && "zmpFromWrench: a world-axes wrench");
  return pressureCentre(w_W, ground_z, min_fz);
}

Eigen::Vector2d localCop(const Wrench& w_S, double min_fz) {
  assert(w_S.axes == Axes::kSole && "localCop: a sole-axes wrench");
  return pressureCentre(w_S, 0.0, min_fz);
}

Eigen::Vector2d tableCartZmp(const Eigen::Vector3d& com, const Eigen::Vector3d& com_acc, double g,
                             double ground_z) {
  return com.head<2>() - (com.z() - ground_z) / g * com_acc.head<2>();
}

}  // namespace overstep::core
