// Pelvis roll and pitch within +-pelvis_tilt (seed: 0.005 rad), shrunk by pelvis_margin in the
// homotopy's last stage and by limit_margin before. Scale: the bound itself (rad). Four rows per
// sample.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class PelvisTilt final : public SampleTerm {
 public:
  Family family() const override { return Family::Pelvis; }
  int rows(const ProblemModel&, const GridPoint&) const override { return 4; }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    const Eigen::Matrix3d Rb = d.model->framePose(p.base_frame).linear();
    const double roll = rollOf(Rb), pitch = pitchOf(Rb),
                 eps =
                     p.cfg.pelvis_tilt * (p.last_stage ? p.cfg.pelvis_margin : p.cfg.limit_margin);
    out[0] = (roll - eps) / eps;
    out[1] = (-roll - eps) / eps;
    out[2] = (pitch - eps) / eps;
    out[3] = (-pitch - eps) / eps;
  }
  // A rotation dtheta (world axes) moves R to (I + [dtheta]x) R, entry (2, j) by
  // dtheta . (R.col(j) x z): roll = atan2(R21, R22) and pitch = asin(-R20) follow.
  bool configurationJacobian(const ProblemModel& p, const SampleData& d,
                             Eigen::Ref<Eigen::MatrixXd> J) const override {
    const Eigen::Matrix3d R = d.model->framePose(p.base_frame).linear();
    const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
    const double n2 = R(2, 1) * R(2, 1) + R(2, 2) * R(2, 2);
    const Eigen::Vector3d g_roll = (R(2, 2) * R.col(1).cross(z) - R(2, 1) * R.col(2).cross(z)) / n2;
    const Eigen::Vector3d g_pitch = -R.col(0).cross(z) / std::sqrt(n2);
    const Eigen::MatrixXd J_w = d.model->frameJacobian(p.base_frame).topRows<3>();
    const double eps =
        p.cfg.pelvis_tilt * (p.last_stage ? p.cfg.pelvis_margin : p.cfg.limit_margin);
    J.row(0) = g_roll.transpose() * J_w / eps;
    J.row(1) = -J.row(0);
    J.row(2) = g_pitch.transpose() * J_w / eps;
    J.row(3) = -J.row(2);
    return true;
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makePelvisTilt() { return std::make_unique<PelvisTilt>(); }

}  // namespace overstep::planner::detail
