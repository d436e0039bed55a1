// Seed eq. (22): the rate of the angular momentum about the vertical through the CoM small: the
// total contact wrench's vertical moment about the CoM (reference 10 N m).
#include "cost_term.hpp"

namespace overstep::planner::detail {
namespace {

class YawMomentumRate final : public SampleCost {
 public:
  const char* name() const override { return "ang_mom_z_rate"; }
  double value(const ProblemModel&, const SampleData& d) const override {
    const Eigen::Vector3d com = d.model->com();
    const core::Wrench Wc = d.st->W_O.about(com);
    return (Wc.moment.z() / 10.0) * (Wc.moment.z() / 10.0);
  }
};

}  // namespace

std::unique_ptr<SampleCost> makeYawMomentumRate() { return std::make_unique<YawMomentumRate>(); }

}  // namespace overstep::planner::detail
