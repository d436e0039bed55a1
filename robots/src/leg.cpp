#include "overstep/robots/leg.hpp"

#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/Joint.hpp>
#include <dart/dynamics/RevoluteJoint.hpp>
#include <dart/dynamics/Skeleton.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "overstep/core/error.hpp"

namespace overstep::robots {
namespace {

Eigen::Matrix3d rotX(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).matrix(); }
Eigen::Matrix3d rotY(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).matrix(); }
Eigen::Matrix3d rotZ(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).matrix(); }

double wrap(double a) { return std::remainder(a, 2.0 * M_PI); }

/// The point nearest (least squares) to lines through o_i along unit d_i, and the largest
/// distance of that point from any of them.
Eigen::Vector3d meetingPoint(const std::vector<Eigen::Vector3d>& o,
                             const std::vector<Eigen::Vector3d>& d, double* spread) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < o.size(); ++i) {
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - d[i] * d[i].transpose();
    A += P;
    b += P * o[i];
  }
  const Eigen::Vector3d p = A.ldlt().solve(b);
  double worst = 0.0;
  for (std::size_t i = 0; i < o.size(); ++i) {
    const Eigen::Vector3d r = p - o[i];
    worst = std::max(worst, (r - d[i] * d[i].dot(r)).norm());
  }
  *spread = worst;
  return p;
}

}  // namespace

std::vector<LegChain> legChains(const WholeBodyModel& model) {
  const auto& d = model.description();
  const auto skel = model.skeleton();
  std::vector<LegChain> out;
  for (const auto& foot : d.feet) {
    LegChain c;
    c.side = foot.side;
    c.foot_link = foot.link;
    std::vector<int> act;
    const dart::dynamics::BodyNode* b = skel->getBodyNode(foot.link);
    std::vector<std::string> links;
    while (b != nullptr && b->getParentBodyNode() != nullptr) {
      links.push_back(b->getName());
      const std::string jn = b->getParentJoint()->getName();
      const int ai = d.actuatedIndex(jn), ei = d.elasticIndex(jn);
      if (ai >= 0) {
        if (act.empty()) c.ankle_link = b->getName();
        act.push_back(ai);
      } else if (ei >= 0 && act.empty()) {
        c.elastic.insert(c.elastic.begin(), ei);
      }
      b = b->getParentBodyNode();
    }
    if (act.size() != 6) {
      throw InputError(d.yaml_path + ": the " + foot.side + " foot (" + foot.link + ") hangs on " +
                       std::to_string(act.size()) +
                       " actuated joints from the base, expected a six-joint leg");
    }
    std::reverse(act.begin(), act.end());
    std::reverse(links.begin(), links.end());
    std::copy(act.begin(), act.end(), c.actuated.begin());
    c.links = links;
    c.ankle_frame = model.frameIndex(c.ankle_link);
    c.sole_frame = model.frameIndex(foot.sole_frame);
    out.push_back(std::move(c));
  }
  return out;
}

LegIk::LegIk(const WholeBodyModel& model_in, const LegChain& chain) {
  WholeBodyModel model(model_in);
  const auto& d = model.description();
  model.setPositions(Eigen::VectorXd::Zero(model.dofs()));  // base at the world origin
  const auto skel = model.skeleton();
  const Eigen::Vector3d expected[6] = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(),
                                       Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitY(),
                                       Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitX()};
  std::vector<Eigen::Vector3d> o(6), a(6);
  for (int i = 0; i < 6; ++i) {
    const std::string& name = d.actuated[static_cast<std::size_t>(chain.actuated[i])].name;
    const auto* rj = dynamic_cast<const dart::dynamics::RevoluteJoint*>(skel->getJoint(name));
    if (rj == nullptr) throw InputError("leg IK: joint " + name + " is not revolute");
    const Eigen::Isometry3d X = model.jointPose(name);
    o[i] = X.translation();
    a[i] = (X.linear() * rj->getAxis()).normalized();
    const double s = a[i].dot(expected[i]);
    if (std::abs(std::abs(s) - 1.0) > 1e-9) {
      throw InputError("leg IK: joint " + name +
                       " is not along the axis the closed form expects (hip z x y, knee y, ankle "
                       "y x at the zero posture)");
    }
    sign_[static_cast<std::size_t>(i)] = s > 0.0 ? 1.0 : -1.0;
  }
  double spread_hip = 0.0, spread_ankle = 0.0;
  p_BH_ = meetingPoint({o[0], o[1], o[2]}, {a[0], a[1], a[2]}, &spread_hip);
  const Eigen::Vector3d A0 = meetingPoint({o[4], o[5]}, {a[4], a[5]}, &spread_ankle);
  if (spread_hip > 1e-9 || spread_ankle > 1e-9) {
    throw InputError("leg IK: the " + chain.side + " leg's " +
                     (spread_hip > 1e-9 ? "hip" : "ankle") +
                     " axes do not meet in one point (closed form impossible)");
  }
  thigh_ = o[3] - p_BH_;
  shank_ = A0 - o[3];
  const Eigen::Isometry3d X_WA = model.framePose(chain.ankle_frame);
  R_BA0_ = X_WA.linear();
  p_AC_ = X_WA.inverse() * A0;
  const double t2 = thigh_.x() * thigh_.x() + thigh_.z() * thigh_.z();
  const double s2 = shank_.x() * shank_.x() + shank_.z() * shank_.z();
  const double rho = std::hypot(thigh_.x() * shank_.x() + thigh_.z() * shank_.z(),
                                thigh_.x() * shank_.z() - thigh_.z() * shank_.x());
  const double dy = thigh_.y() + shank_.y();
  reach_max_ = std::sqrt(t2 + s2 + 2.0 * rho + dy * dy);
  reach_min_ = std::sqrt(std::max(0.0, t2 + s2 - 2.0 * rho) + dy * dy);
  const double knee_hs = d.half_sitting(chain.actuated[3]) * sign_[3];
  const double gamma = std::atan2(thigh_.x() * shank_.z() - thigh_.z() * shank_.x(),
                                  thigh_.x() * shank_.x() + thigh_.z() * shank_.z());
  knee_side_ = wrap(knee_hs - gamma) >= 0.0 ? 1.0 : -1.0;
  for (int i = 0; i < 6; ++i) {
    const auto& j =
        d.actuated[static_cast<std::size_t>(chain.actuated[static_cast<std::size_t>(i)])];
    lower_(i) = j.lower;
    upper_(i) = j.upper;
    reference_(i) = d.half_sitting(chain.actuated[static_cast<std::size_t>(i)]);
  }
}

LegIkResult LegIk::solve(const Eigen::Isometry3d& X_BA, const Vector6d* reference,
                         BeyondReach beyond) const {
  // Two ankle-roll branches: both solved, the one inside the joint limits and nearer the
  // reference posture kept (with a deeply folded knee both can lie inside the limits).
  const Vector6d& ref = reference ? *reference : reference_;
  const Eigen::Matrix3d R = X_BA.linear() * R_BA0_.transpose();  // Rz Rx Ry(phi) Rx(q5)
  const Eigen::Vector3d r = X_BA * p_AC_ - p_BH_;                // hip centre -> ankle centre
  const Eigen::Vector3d r5 = R.transpose() * r;
  const double dy = thigh_.y() + shank_.y();
  const double rho5 = std::hypot(r5.y(), r5.z());
  const double c5 = rho5 > 1e-12 ? dy / rho5 : 0.0;
  const double alpha = std::atan2(r5.z(), r5.y());
  const double a5 = std::acos(std::clamp(c5, -1.0, 1.0));
  LegIkResult best;
  double best_score = std::numeric_limits<double>::infinity();
  for (const double q5 : {wrap(-alpha + a5), wrap(-alpha - a5)}) {
    LegIkResult out = solveGivenRoll(R, r5, q5, beyond);
    out.reachable = out.reachable && std::abs(c5) <= 1.0;
    out.hip_ankle = r.norm();
    double score = 0.0;
    for (int i = 0; i < 6; ++i) {
      const double excess = std::max(0.0, std::max(lower_(i) - out.q(i), out.q(i) - upper_(i)));
      score += 1e6 * excess + (out.q(i) - ref(i)) * (out.q(i) - ref(i));
    }
    if (score < best_score) {
      best_score = score;
      best = out;
    }
  }
  return best;
}

LegIkResult LegIk::solveGivenRoll(const Eigen::Matrix3d& R, const Eigen::Vector3d& r5, double q5,
                                  BeyondReach beyond) const {
  LegIkResult out;
  const Eigen::Vector3d r4 = rotX(q5) * r5;
  // Knee: |t + Ry(q3) s| (x-z plane) = |r4| (x-z plane).
  const double A = thigh_.x() * shank_.x() + thigh_.z() * shank_.z();
  const double B = thigh_.x() * shank_.z() - thigh_.z() * shank_.x();
  const double rho = std::hypot(A, B);
  const double D2 = r4.x() * r4.x() + r4.z() * r4.z();
  const double t2 = thigh_.x() * thigh_.x() + thigh_.z() * thigh_.z();
  const double s2 = shank_.x() * shank_.x() + shank_.z() * shank_.z();
  const double ck = rho > 1e-12 ? 0.5 * (D2 - t2 - s2) / rho : 1.0;
  out.reachable = std::abs(ck) <= 1.0;
  const double bend = ck > 1.0 && beyond == BeyondReach::Continue
                          ? -std::sqrt(2.0 * (ck - 1.0))
                          : std::acos(std::clamp(ck, -1.0, 1.0));
  const double q3 = wrap(std::atan2(B, A) + knee_side_ * bend);
  // Ankle pitch: r4 = Ry(-q4) v, v = Ry(-q3) t + s; psi(p) = atan2(p_x, p_z) grows with Ry.
  const Eigen::Vector3d v = rotY(-q3) * thigh_ + shank_;
  const double q4 = wrap(std::atan2(v.x(), v.z()) - std::atan2(r4.x(), r4.z()));
  // Hip: Rz(q0) Rx(q1) Ry(q2) = R Rx(q5)^T Ry(q3 + q4)^T.
  const Eigen::Matrix3d M = R * rotX(q5).transpose() * rotY(q3 + q4).transpose();
  const double q1 = std::asin(std::clamp(M(2, 1), -1.0, 1.0));
  const double q2 = std::atan2(-M(2, 0), M(2, 2));
  const double q0 = std::atan2(-M(0, 1), M(1, 1));
  const double qp[6] = {q0, q1, q2, q3, q4, q5};
  for (int i = 0; i < 6; ++i) out.q(i) = sign_[static_cast<std::size_t>(i)] * qp[i];
  return out;
}

Eigen::Isometry3d LegIk::forward(const Vector6d& q) const {
  double qp[6];
  for (int i = 0; i < 6; ++i) qp[i] = sign_[static_cast<std::size_t>(i)] * q(i);
  const Eigen::Matrix3d Rzx = rotZ(qp[0]) * rotX(qp[1]);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Rzx * rotY(qp[2] + qp[3] + qp[4]) * rotX(qp[5]) * R_BA0_;
  const Eigen::Vector3d A = p_BH_ + Rzx * (rotY(qp[2]) * thigh_ + rotY(qp[2] + qp[3]) * shank_);
  X.translation() = A - X.linear() * p_AC_;
  return X;
}

Eigen::Matrix<double, 6, 6> LegIk::jacobian(const Vector6d& q) const {
  double qp[6];
  for (int i = 0; i < 6; ++i) qp[i] = sign_[static_cast<std::size_t>(i)] * q(i);
  const Eigen::Matrix3d Rz = rotZ(qp[0]), Rzx = Rz * rotX(qp[1]);
  const Eigen::Vector3d K = p_BH_ + Rzx * rotY(qp[2]) * thigh_;
  const Eigen::Vector3d A = K + Rzx * rotY(qp[2] + qp[3]) * shank_;
  const Eigen::Vector3d p = forward(q).translation();
  const Eigen::Vector3d w[6] = {
      Eigen::Vector3d::UnitZ(),       Rz * Eigen::Vector3d::UnitX(),
      Rzx * Eigen::Vector3d::UnitY(), Rzx * Eigen::Vector3d::UnitY(),
      Rzx * Eigen::Vector3d::UnitY(), Rzx * rotY(qp[2] + qp[3] + qp[4]) * Eigen::Vector3d::UnitX()};
  const Eigen::Vector3d o[6] = {p_BH_, p_BH_, p_BH_, K, A, A};
  Eigen::Matrix<double, 6, 6> J;
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector3d wi = sign_[static_cast<std::size_t>(i)] * w[i];
    J.col(i) << wi, wi.cross(p - o[i]);
  }
  return J;
}

}  // namespace overstep::robots
