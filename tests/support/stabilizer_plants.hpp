#pragma once
// Closed-form plants for the stabilizer tests and benchmark: a LIPM whose ZMP lags its command
// (Kajita 2010's model of a position-controlled humanoid) and a flexible-ankle inverted pendulum
// (a point mass on a rigid leg over a spring-damper bushing at the sole, HRP-2's elastic ankle).
#include <Eigen/Geometry>
#include <array>

#include "overstep/stabilizer/stabilizer.hpp"

namespace overstep::test {

constexpr double kMass = 58.0;
constexpr double kG = 9.81;
constexpr double kComHeight = 0.8;

inline stabilizer::Params plantParams() {
  stabilizer::Params p;
  p.mass = kMass;
  p.gravity = kG;
  for (auto& s : p.sole) s = {-0.10, 0.13, -0.065, 0.065};
  p.ramp_time = 0.01;
  return p;
}

/// Feet side by side at y = -+half_width (right, left), flat, at the origin's height.
inline std::array<Eigen::Isometry3d, 2> feetAt(double half_width, double yaw_r = 0.0,
                                               double yaw_l = 0.0, double x_r = 0.0,
                                               double x_l = 0.0) {
  std::array<Eigen::Isometry3d, 2> X{
      {Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity()}};
  X[0].linear() = Eigen::AngleAxisd(yaw_r, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X[1].linear() = Eigen::AngleAxisd(yaw_l, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X[0].translation() << x_r, -half_width, 0.0;
  X[1].translation() << x_l, half_width, 0.0;
  return X;
}

/// A static reference: CoM over `zmp`, both feet (or only `support`) in contact, equal shares.
inline stabilizer::Reference staticReference(const Eigen::Vector2d& zmp,
                                             const std::array<Eigen::Isometry3d, 2>& feet,
                                             std::array<bool, 2> contact = {{true, true}}) {
  stabilizer::Reference r;
  r.com << zmp, kComHeight;
  r.zmp = zmp;
  const int n = static_cast<int>(contact[0]) + static_cast<int>(contact[1]);
  for (std::size_t f = 0; f < 2; ++f) {
    r.foot[f].contact = contact[f];
    r.foot[f].pose = feet[f];
    r.foot[f].wrench = overstep::core::Wrench::zero(overstep::core::Axes::kSole);
    if (contact[f]) r.foot[f].wrench.force.z() = kMass * kG / n;
  }
  return r;
}

/// Measurement whose feet carry the whole weight with the combined ZMP at p: all the load on
/// foot `f` (CoP = p, which may lie outside the sole: a plant abstraction).
inline stabilizer::Measurement measurementWithZmp(const Eigen::Vector3d& com,
                                                  const Eigen::Vector3d& com_vel,
                                                  const Eigen::Vector2d& p,
                                                  const std::array<Eigen::Isometry3d, 2>& feet,
                                                  int f = 0) {
  stabilizer::Measurement m;
  m.com = com;
  m.com_vel = com_vel;
  m.foot_pose = feet;
  const auto fi = static_cast<std::size_t>(f);
  const Eigen::Vector2d local = (feet[fi].inverse() * Eigen::Vector3d(p.x(), p.y(), 0.0)).head<2>();
  const double fz = kMass * kG;
  m.foot_wrench[fi] = overstep::core::Wrench({0.0, 0.0, fz}, {local.y() * fz, -local.x() * fz, 0.0},
                                             Eigen::Vector3d::Zero(), overstep::core::Axes::kSole);
  m.foot_wrench[1 - fi] = overstep::core::Wrench::zero(overstep::core::Axes::kSole);
  return m;
}

/// One axis of the LIPM with a first-order ZMP lag: cdd = w^2 (c - p), pd = (u - p) / Tp.
/// Integrated with RK4 over one control period with u held (zero-order hold).
struct LagLipm {
  double c = 0, cd = 0, p = 0;
  double w2 = kG / kComHeight, tp = 0.05;
  void step(double u, double dt, int sub = 10) {
    const double h = dt / sub;
    for (int i = 0; i < sub; ++i) {
      auto f = [&](const Eigen::Vector3d& s) {
        return Eigen::Vector3d(s(1), w2 * (s(0) - s(2)), tp > 0 ? (u - s(2)) / tp : 0.0);
      };
      Eigen::Vector3d s(c, cd, p);
      const Eigen::Vector3d k1 = f(s), k2 = f(s + 0.5 * h * k1), k3 = f(s + 0.5 * h * k2),
                            k4 = f(s + h * k3);
      s += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
      c = s(0), cd = s(1), p = tp > 0 ? s(2) : u;
    }
  }
};

/// Sagittal inverted pendulum on an elastic bushing at the sole: leg angle phi (CoM x = l phi),
/// bushing deflection psi = phi + theta (theta: commanded foot pitch), bushing moment
/// tau = -k psi - d psid = the ground moment about the sole origin (massless foot).
struct FlexAnklePendulum {
  double phi = 0, phid = 0;
  double k = 502.0, d = 30.0, l = kComHeight, m = kMass;
  double tau(double theta, double thetad) const { return -k * (phi + theta) - d * (phid + thetad); }
  void step(double theta, double thetad, double dt, int sub = 20) {
    const double h = dt / sub;
    for (int i = 0; i < sub; ++i) {  // semi-implicit Euler, fine at h = 50 us
      const double acc = (m * kG * l * phi + tau(theta, thetad)) / (m * l * l);
      phid += h * acc;
      phi += h * phid;
    }
  }
  stabilizer::Measurement measure(double theta, double thetad,
                                  const std::array<Eigen::Isometry3d, 2>& feet) const {
    stabilizer::Measurement meas;
    meas.com << l * phi, feet[0].translation().y(), l;
    meas.com_vel << l * phid, 0.0, 0.0;
    meas.foot_pose = feet;
    const double fz = m * kG;
    meas.foot_wrench[0] =
        overstep::core::Wrench({0.0, 0.0, fz}, {0.0, tau(theta, thetad), 0.0},
                               Eigen::Vector3d::Zero(), overstep::core::Axes::kSole);
    meas.foot_wrench[1] = overstep::core::Wrench::zero(overstep::core::Axes::kSole);
    return meas;
  }
};

}  // namespace overstep::test
