#include "overstep/robots/collision.hpp"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <cmath>

namespace overstep::robots {
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
  req.enable_signed_distance = true;  // libccd's EPA gives the penetration depth
  req.enable_nearest_points = pa != nullptr || pb != nullptr;
  req.gjk_solver_type = fcl::GST_LIBCCD;
  fcl::DistanceResultd res;
  fcl::distance(&ga, Xa, &shape, X_shape, req, res);
  if (pa) *pa = res.nearest_points[0];
  if (pb) *pb = res.nearest_points[1];
  return res.min_distance;
}

/// Closest points between segments p0-p1 and q0-q1 (Ericson, Real-Time Collision Detection,
/// 5.1.9). Capsule pairs need this rather than FCL: FCL 0.7's signed distance for overlapping
/// capsules with its closed-form solver trips an assertion (distance-inl.h:177, no contact
/// returned), and its GJK path is only accurate to ~1e-5 m.
double segmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                       const Eigen::Vector3d& q0, const Eigen::Vector3d& q1, Eigen::Vector3d* cp,
                       Eigen::Vector3d* cq) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  constexpr double kEps = 1e-14;
  double s = 0.0, t = 0.0;
  if (a <= kEps && e <= kEps) {
    s = t = 0.0;
  } else if (a <= kEps) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kEps) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > kEps ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  *cp = p0 + d1 * s;
  *cq = q0 + d2 * t;
  return (*cp - *cq).norm();
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
  Eigen::Vector3d ca, cb;
  const double d = segmentDistance(a.p0, a.p1, b.p0, b.p1, &ca, &cb);
  if (pa || pb) {
    const Eigen::Vector3d n = d > 1e-12 ? Eigen::Vector3d((cb - ca) / d) : Eigen::Vector3d::UnitZ();
    if (pa) *pa = ca + a.radius * n;
    if (pb) *pb = cb - b.radius * n;
  }
  return d - a.radius - b.radius;
}

double obstacleDistance(const Capsule& a, const ObstacleGeometry& o, Eigen::Vector3d* pa,
                        Eigen::Vector3d* pb) {
  fcl::Transform3d X = fcl::Transform3d::Identity();
  X.translation() = o.centre;
  if (o.shape == core::ObstacleSpec::Shape::Box) {
    return signedDistance(a, fcl::Boxd(o.size), X, pa, pb);
  }
  // A round bar along world y. Within |y| < length / 2 its surface is that of a capsule of the
  // same radius, whose distance is exact (GJK on FCL's cylinder is off by ~1e-4 m).
  const Eigen::Vector3d half(0.0, 0.5 * o.length, 0.0);
  return capsuleDistance(a, Capsule{o.centre - half, o.centre + half, o.radius}, pa, pb);
}

double smoothMin(const Eigen::VectorXd& d, double rho, Eigen::VectorXd* weights) {
  const double m = d.minCoeff();
  const Eigen::ArrayXd e = (-rho * (d.array() - m)).exp();
  const double s = e.sum();
  if (weights) *weights = e / s;
  return m - std::log(s) / rho;
}

}  // namespace overstep::robots
