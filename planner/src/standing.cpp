#include "overstep/planner/standing.hpp"

#include <cmath>

#include "overstep/core/error.hpp"

namespace overstep::planner {

core::Plan standingPlan(robots::WholeBodyModel& m, double duration, double rate) {
  if (!(duration > 0.0 && duration <= 3600.0))
    throw InputError("standing plan: duration " + std::to_string(duration) +
                     " s outside (0, 3600]");
  if (!(rate >= 50.0 && rate <= 1000.0))
    throw InputError("standing plan: rate " + std::to_string(rate) + " Hz outside [50, 1000]");
  const auto& d = m.description();
  const int rs = m.frameIndex(d.foot("right")->sole_frame);
  const int ls = m.frameIndex(d.foot("left")->sole_frame);
  const int n = m.dofs();
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  // Lean the legs (ankle pitch +delta, hip pitch -delta) until the CoM is above the ankles, with
  // the pelvis upright; the left sole is the anchor at the origin of its placement.
  const int hip[2] = {m.actuatedCoordinate(d.actuatedIndex("RLEG_JOINT2")),
                      m.actuatedCoordinate(d.actuatedIndex("LLEG_JOINT2"))};
  const int ank[2] = {m.actuatedCoordinate(d.actuatedIndex("RLEG_JOINT4")),
                      m.actuatedCoordinate(d.actuatedIndex("LLEG_JOINT4"))};
  Eigen::Isometry3d X_left = Eigen::Isometry3d::Identity();
  X_left.translation() << 0.0, 0.095, 0.0;
  auto build = [&](double delta) {
    Eigen::VectorXd q = m.halfSitting(), v = zero, a = zero;
    for (int f = 0; f < 2; ++f) {
      q(hip[f]) -= delta;
      q(ank[f]) += delta;
    }
    m.anchorBase(ls, X_left, q, v, a);
    return q;
  };
  double delta = 0.0;
  for (int it = 0; it < 20; ++it) {
    m.setPositions(build(delta));
    const double err = m.com().x() - m.framePose(ls).translation().x();
    m.setPositions(build(delta + 1e-6));
    const double err2 = m.com().x() - m.framePose(ls).translation().x();
    delta -= err / ((err2 - err) / 1e-6);
  }
  const Eigen::VectorXd q = build(delta);
  m.setState(q, zero, zero);
  const Eigen::VectorXd tau = m.inverseDynamics();
  const Eigen::Vector3d c = m.com();
  const Eigen::Isometry3d Xr = m.framePose(rs), Xl = m.framePose(ls);
  const double mg = m.totalMass() * d.gravity;
  const double yl = Xl.translation().y(), yr = Xr.translation().y();
  const double fl = mg * (c.y() - yr) / (yl - yr);
  core::Plan p;
  p.robot_name = d.name;
  p.robot_file = d.yaml_path;
  p.robot_hash = d.hashHex();
  p.obstacle.gap = 0.10;  // well ahead of the toes
  p.toes_x = Xl.translation().x() + d.foot("left")->sole.x_front;
  p.config_json = R"({"cop_box": 0.01, "friction": 0.7, "torsion": 0.02, "pelvis_tilt": 0.005})";
  p.summary_json = R"({"status": "standing"})";
  p.phases.push_back({"ds_start", 0.0, duration, true, true});
  p.rate = rate;
  p.coordinates = m.coordinateNames();
  const int N = static_cast<int>(std::round(duration * rate)) + 1;
  p.resize(N, n, m.actuatedCount());
  for (int k = 0; k < N; ++k) {
    p.t(k) = k / rate;
    p.q.col(k) = q;
    p.tau.col(k) = tau.segment(6, m.actuatedCount());
    p.com.col(k) = c;
    p.zmp_wholebody.col(k) = c.head<2>();
    p.zmp_tablecart.col(k) = c.head<2>();
    for (int f = 0; f < 2; ++f) {
      const Eigen::Isometry3d& X = f == 0 ? Xr : Xl;
      Eigen::Matrix<double, 7, 1> pose;
      const Eigen::Quaterniond qf(X.linear());
      pose << X.translation(), qf.w(), qf.x(), qf.y(), qf.z();
      (f == 0 ? p.right_foot : p.left_foot).col(k) = pose;
      core::Vector6d w = core::Vector6d::Zero();
      w(5) = f == 0 ? mg - fl : fl;
      (f == 0 ? p.right_wrench : p.left_wrench).col(k) = w;
    }
  }
  return p;
}

}  // namespace overstep::planner
