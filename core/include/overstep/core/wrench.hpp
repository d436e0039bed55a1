#pragma once
/// \file
/// The typed wrench, and ZMP and CoP helpers (Eigen only).
///
/// A `Wrench` is a force and its moment about a stated reference point, both expressed in one
/// stated set of axes; the point is in the coordinates of the frame those axes belong to. The
/// ordering of 6-vectors exists only at the boundaries: `spatial()` ([moment; force], the order
/// of DART, Featherstone and Jacobian transposes) and `forceMoment()` ([force; moment], the order
/// of the sensors, the LCM messages and the files).

#include <Eigen/Geometry>
#include <cassert>
#include <cstdint>

namespace overstep::core {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// The axes a wrench is expressed in (the foot, where it matters, is known from the context).
enum class Axes : std::uint8_t {
  kWorld,   ///< the world frame: z up, origin on the ground
  kSole,    ///< a foot's sole frame: origin at the sole centre, z along the sole normal
  kSensor,  ///< a foot's force-sensor frame
};

/// "world", "sole" or "sensor".
const char* axesName(Axes axes);

struct Wrench {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();   ///< N
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();  ///< N m, about `point`
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< m, in the frame of `axes`
  Axes axes = Axes::kWorld;

  Wrench() = default;
  Wrench(const Eigen::Vector3d& f, const Eigen::Vector3d& m, const Eigen::Vector3d& p, Axes a)
      : force(f), moment(m), point(p), axes(a) {}
  /// A zero wrench about `p` in axes `a`.
  static Wrench zero(Axes a, const Eigen::Vector3d& p = Eigen::Vector3d::Zero()) {
    return {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), p, a};
  }
  /// From a spatial 6-vector [moment; force] (N m, N) about `p`.
  static Wrench fromSpatial(const Vector6d& m_f, Axes a,
                            const Eigen::Vector3d& p = Eigen::Vector3d::Zero()) {
    return {m_f.tail<3>(), m_f.head<3>(), p, a};
  }
  /// From a sensor-order 6-vector [force; moment] (N, N m) about `p`.
  static Wrench fromForceMoment(const Vector6d& f_m, Axes a,
                                const Eigen::Vector3d& p = Eigen::Vector3d::Zero()) {
    return {f_m.head<3>(), f_m.tail<3>(), p, a};
  }

  /// [moment; force] about `point`.
  Vector6d spatial() const {
    Vector6d v;
    v << moment, force;
    return v;
  }
  /// [force; moment] about `point`.
  Vector6d forceMoment() const {
    Vector6d v;
    v << force, moment;
    return v;
  }

  /// The same wrench with its moment about `q` (same axes): moment + (point - q) x force.
  Wrench about(const Eigen::Vector3d& q) const {
    return {force, moment + (point - q).cross(force), q, axes};
  }
  /// The same wrench expressed in axes `g`, where X_GF is the pose of this wrench's frame F in G:
  /// force and moment rotated, the reference point mapped (the moment stays about the same
  /// physical point).
  Wrench expressedIn(const Eigen::Isometry3d& X_GF, Axes g) const {
    return {X_GF.linear() * force, X_GF.linear() * moment, X_GF * point, g};
  }

  /// This wrench (in G's axes) about the origin of frame F and expressed in F's axes, where X_GF
  /// is F's pose in G: the world wrench a sole carries, in the sole frame about its origin.
  Wrench inFrame(const Eigen::Isometry3d& X_GF, Axes f) const {
    const Wrench w_Fo = about(X_GF.translation());
    return {X_GF.linear().transpose() * w_Fo.force, X_GF.linear().transpose() * w_Fo.moment,
            Eigen::Vector3d::Zero(), f};
  }

  bool allFinite() const { return force.allFinite() && moment.allFinite() && point.allFinite(); }
  bool isZero() const { return force.isZero(0.0) && moment.isZero(0.0); }

  /// Adds `o` (same axes), its moment taken about this wrench's point.
  Wrench& operator+=(const Wrench& o) {
    assert(o.axes == axes && "Wrench::operator+=: wrenches in different axes");
    moment += o.moment + (o.point - point).cross(o.force);
    force += o.force;
    return *this;
  }
  /// Subtracts `o` (same axes), its moment taken about this wrench's point.
  Wrench& operator-=(const Wrench& o) {
    assert(o.axes == axes && "Wrench::operator-=: wrenches in different axes");
    moment -= o.moment + (o.point - point).cross(o.force);
    force -= o.force;
    return *this;
  }
  Wrench& operator*=(double s) {
    force *= s;
    moment *= s;
    return *this;
  }
  Wrench& operator/=(double s) {
    force /= s;
    moment /= s;
    return *this;
  }
};

inline Wrench operator+(Wrench a, const Wrench& b) { return a += b; }
inline Wrench operator-(Wrench a, const Wrench& b) { return a -= b; }
inline Wrench operator*(double s, Wrench w) { return w *= s; }
inline Wrench operator*(Wrench w, double s) { return w *= s; }
inline Wrench operator/(Wrench w, double s) { return w /= s; }

/// A force sensor's calibration: measured = scale * true + bias, in the sensor's axes about its
/// origin.
struct ForceSensorModel {
  Wrench bias = Wrench::zero(Axes::kSensor);  ///< N, N m
  double scale = 1.0;                         ///< dimensionless, > 0
  /// What the sensor reads under the true wrench `w`.
  Wrench measured(const Wrench& w) const { return scale * w + bias; }
  /// The true wrench from a reading `m`.
  Wrench calibrated(const Wrench& m) const { return (m - bias) / scale; }
  bool isIdentity() const { return bias.isZero() && scale == 1.0; }
};

/// ZMP on the horizontal plane z = ground_z from a world-axes wrench (any reference point).
/// Returns NaN when |fz| < min_fz (no contact force, no ZMP).
Eigen::Vector2d zmpFromWrench(const Wrench& w_W, double ground_z = 0.0, double min_fz = 1e-6);

/// Local CoP in the sole plane z = 0 from a sole-axes wrench (any reference point), in the sole
/// frame. Returns NaN when |fz| < min_fz.
Eigen::Vector2d localCop(const Wrench& w_S, double min_fz = 1e-6);

/// Table-cart (3D-LIPM) ZMP: p = c_xy - (c_z - ground_z) / g * cdd_xy.
Eigen::Vector2d tableCartZmp(const Eigen::Vector3d& com, const Eigen::Vector3d& com_acc, double g,
                             double ground_z = 0.0);

}  // namespace overstep::core
