// Actuator torques of the robot in contact (State::tau_act: inverse dynamics less the feet's
// J^T w) within their limits: one row, the smooth maximum (KS) of |tau| / limit over every
// actuated joint. Dimensionless. One row per sample.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class TorqueLimit final : public SampleTerm {
 public:
  Family family() const override { return Family::Torque; }
  int rows(const ProblemModel&, const GridPoint&) const override { return 1; }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    const auto& desc = p.model_template.description();
    const int na = p.model_template.actuatedCount();
    auto ratio = d.scratch(2 * na);
    for (int j = 0; j < na; ++j) {
      const double tq = d.st->tau_act(j);
      ratio(2 * j) = tq / desc.actuated[static_cast<std::size_t>(j)].torque;
      ratio(2 * j + 1) = -ratio(2 * j);
    }
    out[0] = smoothMax(ratio, kKsSharpness) - 1.0;
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makeTorqueLimit() { return std::make_unique<TorqueLimit>(); }

}  // namespace overstep::planner::detail
