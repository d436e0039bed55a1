// Seed eq. (21): the vertical linear momentum (reference: the mass at 0.1 m/s) and its rate
// (the CoM's vertical acceleration, reference 1 m/s^2) small.
#include "cost_term.hpp"

namespace overstep::planner::detail {
namespace {

class VerticalMomentum final : public SampleCost {
 public:
  const char* name() const override { return "lin_mom_z"; }
  double value(const ProblemModel& p, const SampleData& d) const override {
    const core::Vector6d hc = d.model->centroidalMomentum();  // [linear; angular]
    return (hc(2) / (p.mass * 0.1)) * (hc(2) / (p.mass * 0.1));
  }
};

class VerticalMomentumRate final : public SampleCost {
 public:
  const char* name() const override { return "lin_mom_z_rate"; }
  double value(const ProblemModel&, const SampleData& d) const override {
    const Eigen::Vector3d& cdd = d.com_acc;
    return cdd.z() * cdd.z();
  }
};

}  // namespace

std::unique_ptr<SampleCost> makeVerticalMomentum() { return std::make_unique<VerticalMomentum>(); }
std::unique_ptr<SampleCost> makeVerticalMomentumRate() {
  return std::make_unique<VerticalMomentumRate>();
}

}  // namespace overstep::planner::detail
