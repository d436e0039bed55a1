// The joints of the leg solved by inverse kinematics in double support inside their safe range
// (the spline legs are kept there by bounds on their control points). Scale: kJointScale (rad).
// Twelve rows per double-support sample (upper and lower, hip to ankle).
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class JointLimits final : public SampleTerm {
 public:
  Family family() const override { return Family::JointLimits; }
  int rows(const ProblemModel&, const GridPoint& g) const override {
    return ProblemModel::doubleSupport(g.phase) ? 12 : 0;
  }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    const auto& desc = p.model_template.description();
    const int leg = 1 - p.anchor_of[d.g->phase];
    for (int j = 0; j < 6; ++j) {
      const int a = p.leg_act[static_cast<std::size_t>(6 * leg + j)];
      const auto& aj = desc.actuated[static_cast<std::size_t>(a)];
      const double qj = d.st->q(p.model_template.actuatedCoordinate(a));
      out[2 * j] = (qj - aj.safeUpper()) / kJointScale;
      out[2 * j + 1] = (aj.safeLower() - qj) / kJointScale;
    }
  }
  bool configurationJacobian(const ProblemModel& p, const SampleData& d,
                             Eigen::Ref<Eigen::MatrixXd> J) const override {
    const int leg = 1 - p.anchor_of[d.g->phase];
    J.setZero();
    for (int j = 0; j < 6; ++j) {
      const int c = p.leg_coord[static_cast<std::size_t>(6 * leg + j)];
      J(2 * j, c) = 1.0 / kJointScale;
      J(2 * j + 1, c) = -1.0 / kJointScale;
    }
    return true;
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makeJointLimits() { return std::make_unique<JointLimits>(); }

}  // namespace overstep::planner::detail
