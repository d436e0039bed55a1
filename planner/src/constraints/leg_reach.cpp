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
};

}  // namespace

std::unique_ptr<SampleTerm> makeLegReach() { return std::make_unique<LegReach>(); }

}  // namespace overstep::planner::detail
