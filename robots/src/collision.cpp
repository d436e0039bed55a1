#include "overstep/robots/collision.hpp"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

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

/// Squared distance from the segment p0 + s d (s in [0, 1]) to the box [-h, h] (box frame),
/// minimised exactly: it is a convex, piecewise-quadratic function of s whose pieces end where
/// the segment crosses a slab plane x_i = +-h_i; on each piece every coordinate is either inside
/// its slab (no contribution) or beyond one face, so the minimum of each piece is closed form.
double segmentBoxSquaredDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& d,
                                 const Eigen::Vector3d& h, double* s_min) {
  std::array<double, 8> cut{};
  int n = 0;
  cut[static_cast<std::size_t>(n++)] = 0.0;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d(i)) < 1e-15) continue;
    for (double b : {-h(i), h(i)}) {
      const double s = (b - p0(i)) / d(i);
      if (s > 0.0 && s < 1.0) cut[static_cast<std::size_t>(n++)] = s;
    }
  }
  cut[static_cast<std::size_t>(n++)] = 1.0;
  for (int i = 1; i < n; ++i)  // insertion sort of <= 8 (std::sort: GCC 12's -Warray-bounds)
    for (int j = i;
         j > 0 && cut[static_cast<std::size_t>(j - 1)] > cut[static_cast<std::size_t>(j)]; --j)
      std::swap(cut[static_cast<std::size_t>(j - 1)], cut[static_cast<std::size_t>(j)]);
  auto value = [&](double s) {
    const Eigen::Vector3d x = p0 + s * d;
    return (x - x.cwiseMax(-h).cwiseMin(h)).squaredNorm();
  };
  double best = value(0.0), best_s = 0.0;
  for (int k = 0; k + 1 < n; ++k) {
    const double a = cut[static_cast<std::size_t>(k)], b = cut[static_cast<std::size_t>(k + 1)];
    const Eigen::Vector3d mid = p0 + 0.5 * (a + b) * d;
    double qa = 0.0, qb = 0.0;  // the piece: qa s^2 + qb s + const
    bool inside = true;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(mid(i)) <= h(i)) continue;
      const double face = mid(i) > 0.0 ? h(i) : -h(i);
      inside = false;
      qa += d(i) * d(i);
      qb += 2.0 * d(i) * (p0(i) - face);
    }
    if (inside) {  // the piece lies inside the box
      *s_min = 0.5 * (a + b);
      return 0.0;
    }
    const double s = qa > 0.0 ? std::clamp(-qb / (2.0 * qa), a, b) : a;
    const double v = value(s);
    if (v < best) best = v, best_s = s;
  }
  *s_min = best_s;
  return best;
}

/// Penetration depth of a segment that meets the box (box frame) and the direction n that
/// separates them by it (the segment moves along +n): the least overlap over the separating
/// axes of the pair, the box's face normals and their cross products with the segment, which
/// are the face normals of their Minkowski difference (exact for convex polytopes).
double segmentBoxPenetration(const Eigen::Vector3d& p0, const Eigen::Vector3d& d,
                             const Eigen::Vector3d& h, Eigen::Vector3d* n_out) {
  double depth = std::numeric_limits<double>::infinity();
  auto tryAxis = [&](Eigen::Vector3d n) {
    const double len = n.norm();
    if (len < 1e-9) return;
    n /= len;
    const double r = h.cwiseProduct(n).cwiseAbs().sum();
    const double a0 = n.dot(p0), a1 = n.dot(p0 + d);
    const double up = r - std::min(a0, a1);    // move the segment along +n
    const double down = std::max(a0, a1) + r;  // ... along -n
    if (up < depth) depth = up, *n_out = n;
    if (down < depth) depth = down, *n_out = -n;
  };
  for (int i = 0; i < 3; ++i) tryAxis(Eigen::Vector3d::Unit(i));
  for (int i = 0; i < 3; ++i) tryAxis(Eigen::Vector3d::Unit(i).cross(d));
  return depth;
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

double boxDistance(const Capsule& a, const ObstacleGeometry& o, Eigen::Vector3d* pa,
                   Eigen::Vector3d* pb) {
  const Eigen::Vector3d h = 0.5 * o.size, p0 = a.p0 - o.centre, d = a.p1 - a.p0;
  double s = 0.0;
  const double d2 = segmentBoxSquaredDistance(p0, d, h, &s);
  const Eigen::Vector3d q = p0 + s * d;  // the segment's nearest point, box frame
  if (d2 > 0.0) {
    const Eigen::Vector3d b = q.cwiseMax(-h).cwiseMin(h);
    const double dist = std::sqrt(d2);
    const Eigen::Vector3d n = (q - b) / dist;
    if (pa) *pa = o.centre + q - a.radius * n;
    if (pb) *pb = o.centre + b;
    return dist - a.radius;
  }
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  const double depth = segmentBoxPenetration(p0, d, h, &n);
  // Where the segment, moved out by depth along n, touches the box: the box's witness point;
  // the capsule's is that point moved back, less the radius.
  const Eigen::Vector3d out = p0 + depth * n;
  segmentBoxSquaredDistance(out, d, h, &s);
  const Eigen::Vector3d touch = (out + s * d).cwiseMax(-h).cwiseMin(h);
  if (pa) *pa = o.centre + touch - (depth + a.radius) * n;
  if (pb) *pb = o.centre + touch;
  return -depth - a.radius;
}

double obstacleDistanceFcl(const Capsule& a, const ObstacleGeometry& o, Eigen::Vector3d* pa,
                           Eigen::Vector3d* pb) {
  if (o.shape != core::ObstacleSpec::Shape::Box) return obstacleDistance(a, o, pa, pb);
  fcl::Transform3d X = fcl::Transform3d::Identity();
  X.translation() = o.centre;
  return signedDistance(a, fcl::Boxd(o.size), X, pa, pb);
}

double obstacleDistance(const Capsule& a, const ObstacleGeometry& o, Eigen::Vector3d* pa,
                        Eigen::Vector3d* pb) {
  if (o.shape == core::ObstacleSpec::Shape::Box) return boxDistance(a, o, pa, pb);
  // A round bar along world y. Within |y| < length / 2 its surface is that of a capsule of the
  // same radius, whose distance is exact (GJK on FCL's cylinder is off by ~1e-4 m).
  const Eigen::Vector3d half(0.0, 0.5 * o.length, 0.0);
  return capsuleDistance(a, Capsule{o.centre - half, o.centre + half, o.radius}, pa, pb);
}

// Both as expressions: without the optional output they evaluate without allocating.
double smoothMin(const Eigen::Ref<const Eigen::VectorXd>& d, double rho, Eigen::VectorXd* weights) {
  const double m = d.minCoeff();
  const auto e = (-rho * (d.array() - m)).exp();
  const double s = e.sum();
  if (weights) *weights = e / s;
  return m - std::log(s) / rho;
}

double softMin(const Eigen::Ref<const Eigen::VectorXd>& d, double rho, Eigen::VectorXd* gradient) {
  const double m = d.minCoeff();
  const auto e = (-rho * (d.array() - m)).exp();
  const double s = e.sum();
  const auto w = e / s;
  const double b = (w * d.array()).sum();
  if (gradient) *gradient = (w * (1.0 - rho * (d.array() - b))).matrix();
  return b;
}

}  // namespace overstep::robots
