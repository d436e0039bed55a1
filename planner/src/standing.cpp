#include "overstep/planner/standing.hpp"

#include <cmath>

#include "overstep/core/error.hpp"
#include "overstep/core/wrench.hpp"
#include "overstep/robots/leg.hpp"

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
  const std::vector<robots::LegChain> legs = robots::legChains(m);  // hip pitch: 3rd, ankle: 5th
  if (legs.size() != 2) throw InputError("standing plan: needs a robot with two legs");
  const int hip[2] = {m.actuatedCoordinate(legs[0].actuated[2]),
                      m.actuatedCoordinate(legs[1].actuated[2])};
  const int ank[2] = {m.actuatedCoordinate(legs[0].actuated[4]),
                      m.actuatedCoordinate(legs[1].actuated[4])};
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
  const core::Wrench w_r(Eigen::Vector3d(0.0, 0.0, mg - fl), Eigen::Vector3d::Zero(),
                         Xr.translation(), core::Axes::kWorld);
  const core::Wrench w_l(Eigen::Vector3d(0.0, 0.0, fl), Eigen::Vector3d::Zero(), Xl.translation(),
                         core::Axes::kWorld);
  const Eigen::VectorXd tau_c = m.torquesInContact(tau, {{rs, w_r}, {ls, w_l}});
  for (int k = 0; k < N; ++k) {
    p.t(k) = k / rate;
    p.q.col(k) = q;
    p.tau.col(k) = tau_c.segment(6, m.actuatedCount());
    p.com.col(k) = c;
    p.zmp_wholebody.col(k) = c.head<2>();
    p.zmp_tablecart.col(k) = c.head<2>();
    for (int f = 0; f < 2; ++f) {
      const Eigen::Isometry3d& X = f == 0 ? Xr : Xl;
      Eigen::Matrix<double, 7, 1> pose;
      const Eigen::Quaterniond qf(X.linear());
      pose << X.translation(), qf.w(), qf.x(), qf.y(), qf.z();
      (f == 0 ? p.right_foot : p.left_foot).col(k) = pose;
      p.setWrench(f, k, f == 0 ? w_r : w_l);
    }
  }
  return p;
}

core::Plan excitationPlan(robots::WholeBodyModel& m, double duration, double amplitude,
                          double rate) {
  if (!(duration >= 3.0 && duration <= 3600.0))
    throw InputError("excitation plan: duration " + std::to_string(duration) +
                     " s outside [3, 3600]");
  if (!(amplitude > 0.0 && amplitude <= 2.0))
    throw InputError("excitation plan: amplitude " + std::to_string(amplitude) + " outside (0, 2]");
  core::Plan p = standingPlan(m, duration, rate);
  const auto& d = m.description();
  if (d.excitation.empty())
    throw InputError("excitation plan: the robot file (" + d.yaml_path +
                     ") names no joints under `excitation:`");
  const double fade = 1.0;  // s
  const double mg = m.totalMass() * d.gravity;
  const int rs = m.frameIndex(d.foot("right")->sole_frame);
  const int ls = m.frameIndex(d.foot("left")->sole_frame);
  const Eigen::Isometry3d X_left = m.framePose(ls);
  const int n = m.dofs();
  for (int k = 0; k < p.samples(); ++k) {
    const double t = p.t(k);
    // Envelope e(t): sin^2 ramps at both ends (C1), with its derivatives.
    double e = 1.0, de = 0.0, dde = 0.0;
    const double tr = std::min(t, duration - t);
    const double sgn = t < duration - t ? 1.0 : -1.0;
    if (tr < fade) {
      const double w = M_PI / (2.0 * fade);
      e = std::sin(w * tr) * std::sin(w * tr);
      de = sgn * w * std::sin(2.0 * w * tr);
      dde = 2.0 * w * w * std::cos(2.0 * w * tr);
    }
    Eigen::VectorXd q = p.q.col(k), v = Eigen::VectorXd::Zero(n), a = v;
    for (const core::ExcitationJoint& s : d.excitation) {
      const int c = m.actuatedCoordinate(d.actuatedIndex(s.joint));
      const double w = 2.0 * M_PI * s.frequency, A = amplitude * s.amplitude;
      const double f = A * std::sin(w * t + s.phase) - A * std::sin(s.phase);
      const double df = A * w * std::cos(w * t + s.phase);
      const double ddf = -A * w * w * std::sin(w * t + s.phase);
      q(c) += e * f;
      v(c) = de * f + e * df;
      a(c) = dde * f + 2.0 * de * df + e * ddf;
    }
    const auto& aj = d.actuated;
    for (int j = 0; j < m.actuatedCount(); ++j) {
      const int c = m.actuatedCoordinate(j);
      q(c) = std::clamp(q(c), aj[static_cast<std::size_t>(j)].safeLower(),
                        aj[static_cast<std::size_t>(j)].safeUpper());
    }
    m.anchorBase(ls, X_left, q, v, a);
    const Eigen::VectorXd tau = m.inverseDynamics();
    const core::Wrench W = m.contactWrenchFromBase(tau);
    p.q.col(k) = q;
    p.v.col(k) = v;
    p.a.col(k) = a;
    p.com.col(k) = m.com();
    const Eigen::Vector2d zmp = core::zmpFromWrench(W);
    p.zmp_wholebody.col(k) = zmp;
    p.zmp_tablecart.col(k) = core::tableCartZmp(m.com(), m.comAcceleration(), d.gravity);
    // Split the normal force by the ZMP's lateral position; each foot's CoP at the ZMP's x.
    const double yr = p.right_foot(1, k), yl = p.left_foot(1, k);
    const double fz = W.force.z() > 0.0 ? W.force.z() : mg;
    const double share_l = std::clamp((zmp.y() - yr) / (yl - yr), 0.0, 1.0);
    for (int f = 0; f < 2; ++f) {
      const double fzf = fz * (f == 0 ? 1.0 - share_l : share_l);
      const Eigen::Vector3d o = (f == 0 ? p.right_foot : p.left_foot).col(k).head<3>();
      // About the sole origin: the CoP at the ZMP's x.
      p.setWrench(
          f, k,
          core::Wrench(Eigen::Vector3d(0.0, 0.0, fzf),
                       Eigen::Vector3d(0.0, -(zmp.x() - o.x()) * fzf, 0.0), o, core::Axes::kWorld));
    }
    p.tau.col(k) = m.torquesInContact(tau, {{rs, p.wrench(0, k)}, {ls, p.wrench(1, k)}})
                       .segment(6, m.actuatedCount());
  }
  p.summary_json = R"({"status": "excitation"})";
  return p;
}

}  // namespace overstep::planner
