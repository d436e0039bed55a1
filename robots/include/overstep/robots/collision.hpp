#pragma once
/// \file
/// Collision geometry (planner, check and simulator): link capsules (rounded cylinders, seed
/// III-C-2) and the obstacle, with signed distances (negative = penetration depth) in closed form
/// and, for the box, also from FCL; and a smooth minimum (Kreisselmeier-Steinhauser) to
/// aggregate many distances into one differentiable row.

#include <Eigen/Geometry>

#include "overstep/core/obstacle.hpp"

namespace overstep::robots {

/// A capsule in the world frame: segment p0-p1 swept by a sphere of `radius`.
struct Capsule {
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d p1 = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

/// The obstacle's solid in the world frame. A box bar spans [x_near, x_far] x [-length/2,
/// length/2] x [0, height]; a cylinder bar has its axis along y at x = centre, z = height - r.
struct ObstacleGeometry {
  core::ObstacleSpec::Shape shape = core::ObstacleSpec::Shape::Box;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< box extents (x, y, z)
  double radius = 0.0;                             ///< cylinder radius
  double length = 0.0;                             ///< cylinder length along y

  /// The envelope (with margin) placed `spec.gap` ahead of the start toes at x = toes_x.
  static ObstacleGeometry fromSpec(const core::ObstacleSpec& spec, double toes_x);
};

/// Signed distance between two capsules; nearest points (world) if requested.
double capsuleDistance(const Capsule& a, const Capsule& b, Eigen::Vector3d* pa = nullptr,
                       Eigen::Vector3d* pb = nullptr);
/// Signed distance between a capsule and the obstacle, closed form (the planner's rows):
/// boxDistance for a box bar, capsuleDistance for a round one. Nearest points (world) if
/// requested; when they overlap, the points the least translation separating them joins.
double obstacleDistance(const Capsule& a, const ObstacleGeometry& obstacle,
                        Eigen::Vector3d* pa = nullptr, Eigen::Vector3d* pb = nullptr);
/// Signed distance between a capsule and a box obstacle (axis-aligned, world frame): the exact
/// minimum over the segment of its distance to the box less the radius; when the segment meets
/// the box, minus the least translation that separates them (by the separating axes) less the
/// radius.
double boxDistance(const Capsule& a, const ObstacleGeometry& box, Eigen::Vector3d* pa = nullptr,
                   Eigen::Vector3d* pb = nullptr);
/// The same signed distance from FCL (GJK and EPA of libccd, within ~1e-6 m): a second,
/// independent implementation, for `overstep check` and the simulator's collision report.
double obstacleDistanceFcl(const Capsule& a, const ObstacleGeometry& obstacle,
                           Eigen::Vector3d* pa = nullptr, Eigen::Vector3d* pb = nullptr);
/// Smooth minimum -1/rho log(sum exp(-rho d_i)) (KS; <= min d_i, within log(n)/rho of it);
/// writes d(smoothMin)/d(d_i) (softmax weights, summing to 1) if requested.
double smoothMin(const Eigen::Ref<const Eigen::VectorXd>& d, double rho,
                 Eigen::VectorXd* weights = nullptr);
/// Smooth minimum of distances as their softmin-weighted mean, sum_i w_i d_i with
/// w = softmax(-rho d) (the Boltzmann operator). Exact where the nearest distances tie (a foot's
/// parallel capsules facing a bar) and where one is nearest by far; otherwise above min d_i by at
/// most (n - 1) / (e rho) (about 1 mm for ten capsules at rho = 1000 1/m). The log-sum-exp
/// minimum (KS) lies below min d_i by up to log(n) / rho instead: 1.8 mm for six tied foot
/// capsules, which made a start stance 10.5 mm from the bar violate a 10 mm clearance.
/// Writes the gradient d(softMin)/d(d_i) = w_i (1 - rho (d_i - softMin)) if requested.
double softMin(const Eigen::Ref<const Eigen::VectorXd>& d, double rho,
               Eigen::VectorXd* gradient = nullptr);

}  // namespace overstep::robots
