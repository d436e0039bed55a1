#include "overstep/planner/collision.hpp"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/narrowphase/distance.h>

#include <cmath>

namespace overstep::planner {
namespace {

/// FCL's capsule is centred with its axis along local z: pose from the segment.
fcl::Transform3d capsulePose(const Capsule& c, double* length) {
  const Eigen::Vector3d axis = c.p1 - c.p0;
  *length = axis.norm();
  fcl::Transform3d X = fcl::Transform3d::Identity();
  X.translation() = 0.5 * (c.p0 + c.p1);
  if (*length > 1e-12) {
    X.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis / *length)
                     .toRotationMatrix();
  }
  return X;
}

template <typename Shape>
double signedDistance(const Capsule& a, const Shape& shape, const fcl::Transform3d& X_shape,
                      Eigen::Vector3d* pa, Eigen::Vector3d* pb) {
  double len = 0.0;
  const fcl::Transform3d Xa = capsulePose(a, &len);
  const fcl::Capsuled ga(a.radius, len);
  fcl::DistanceRequestd req;
  req.enable_signed_distance = true;
  req.enable_nearest_points = pa != nullptr || pb != nullptr;
  req.gjk_solver_type = fcl::GST_INDEP;  // closed form for capsule pairs
  fcl::DistanceResultd res;
  fcl::distance(&ga, Xa, &shape, X_shape, req, res);
  if (pa) *pa = res.nearest_points[0];
  if (pb) *pb = res.nearest_points[1];
  return res.min_distance;
}

}  // namespace

ObstacleGeometry ObstacleGeometry::fromSpec(const core::ObstacleSpec& spec, double toes_x) {
  ObstacleGeometry g;
  g.shape = spec.shape;
  const double x0 = spec.nearX(toes_x), x1 = spec.farX(toes_x), h = spec.envelopeHeight();
  if (spec.shape == core::ObstacleSpec::Shape::Box) {
    g.size = Eigen::Vector3d(x1 - x0, spec.length, h);
    g.centre = Eigen::Vector3d(0.5 * (x0 + x1), 0.0, 0.5 * h);
  } else {
    g.radius = 0.5 * (x1 - x0);
    g.length = spec.length;
    g.centre = Eigen::Vector3d(0.5 * (x0 + x1), 0.0, h - g.radius);
  }
  return g;
}

double capsuleDistance(const Capsule& a, const Capsule& b, Eigen::Vector3d* pa,
                       Eigen::Vector3d* pb) {
  double len = 0.0;
  const fcl::Transform3d Xb = capsulePose(b, &len);
  return signedDistance(a, fcl::Capsuled(b.radius, len), Xb, pa, pb);
}

double obstacleDistance(const Capsule& a, const ObstacleGeometry& o, Eigen::Vector3d* pa,
                        Eigen::Vector3d* pb) {
  fcl::Transform3d X = fcl::Transform3d::Identity();
  X.translation() = o.centre;
  if (o.shape == core::ObstacleSpec::Shape::Box) {
    return signedDistance(a, fcl::Boxd(o.size), X, pa, pb);
  }
  // A round bar along world y. Within |y| < length / 2 its surface is that of a capsule of the
  // same radius, which FCL treats in closed form (GJK on a cylinder is off by ~1e-4 m).
  X.linear() = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return signedDistance(a, fcl::Capsuled(o.radius, o.length), X, pa, pb);
}

double smoothMin(const Eigen::VectorXd& d, double rho, Eigen::VectorXd* weights) {
  const double m = d.minCoeff();
  const Eigen::ArrayXd e = (-rho * (d.array() - m)).exp();
  const double s = e.sum();
  if (weights) *weights = e / s;
  return m - std::log(s) / rho;
}

}  // namespace overstep::planner
