#pragma once
/// \file
/// Wrench, ZMP and CoP helpers (Eigen only). A wrench is a 6-vector [torque; force] (N m, N) whose
/// torque is taken about a stated point and expressed in a stated frame.

#include <Eigen/Geometry>

namespace overstep::core {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Moves a wrench's reference point: torque about q = torque about p + (p - q) x force.
Vector6d shiftWrench(const Vector6d& w_p, const Eigen::Vector3d& p, const Eigen::Vector3d& q);

/// Re-expresses a wrench given in frame F (about F's origin) in frame W about W's origin.
Vector6d transformWrench(const Eigen::Isometry3d& X_WF, const Vector6d& w_F);

/// ZMP on the horizontal plane z = ground_z from a wrench about the world origin in the world
/// frame. Returns NaN when |fz| < min_fz (no contact force, no ZMP).
Eigen::Vector2d zmpFromWrench(const Vector6d& w_O, double ground_z = 0.0, double min_fz = 1e-6);

/// Local CoP from a wrench about the sole-frame origin, in the sole frame (sole plane z = 0).
/// Returns NaN when |fz| < min_fz.
Eigen::Vector2d localCop(const Vector6d& w_S, double min_fz = 1e-6);

/// Table-cart (3D-LIPM) ZMP: p = c_xy - (c_z - ground_z) / g * cdd_xy.
Eigen::Vector2d tableCartZmp(const Eigen::Vector3d& com, const Eigen::Vector3d& com_acc, double g,
                             double ground_z = 0.0);

}  // namespace overstep::core
