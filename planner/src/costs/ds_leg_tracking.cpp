// A regulariser, not in the seed: in double support the spline of the leg solved by inverse
// kinematics stays near the solution (State::ik_seed_gap, reference 0.05 rad), so that spline,
// which the switching rows match, has no free directions.
#include "cost_term.hpp"

namespace overstep::planner::detail {
namespace {

class DsLegTracking final : public SampleCost {
 public:
  const char* name() const override { return "ds_leg_tracking"; }
  double value(const ProblemModel&, const SampleData& d) const override {
    return d.st->ik_seed_gap / 0.0025;
  }
};

}  // namespace

std::unique_ptr<SampleCost> makeDsLegTracking() { return std::make_unique<DsLegTracking>(); }

}  // namespace overstep::planner::detail
