// The double-support inverse-kinematics leg short of stretched: hip-ankle distance <= leg_reach
// (keeps the knee bent and the leg Jacobian regular). Scale: kDistScale (m). One row per
// double-support sample.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class LegReach final : public SampleTerm {
 public:
  Family family() const override { return Family::Reach; }
  int rows(const ProblemModel&, const GridPoint& g) const override {
    return ProblemModel::doubleSupport(g.phase) ? 1 : 0;
  }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    out[0] = (d.st->reach - p.cfg.leg_reach) / kDistScale;
  }
  // Within reach: the distance of the hip and ankle frames, n . (v_ankle - v_hip).
  bool configurationJacobian(const ProblemModel& p, const SampleData& d,
                             Eigen::Ref<Eigen::MatrixXd> J) const override {
    if (d.st->beyond_reach) return false;
    const int leg = 1 - p.anchor_of[d.g->phase];
    const robots::WholeBodyModel& m = *d.model;
    const Eigen::Vector3d r =
        m.framePose(p.ankle_frame[leg]).translation() - m.framePose(p.hip_frame[leg]).translation();
    const Eigen::Vector3d n = r / r.norm();
    J.row(0) = n.transpose() *
               (m.frameJacobian(p.ankle_frame[leg]).bottomRows<3>() -
                m.frameJacobian(p.hip_frame[leg]).bottomRows<3>()) /
               kDistScale;
    return true;
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makeLegReach() { return std::make_unique<LegReach>(); }

}  // namespace overstep::planner::detail
