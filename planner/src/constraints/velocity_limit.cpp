// Leg joint speeds within velocity_margin of their limits: one row, the smooth maximum (KS,
// kKsSharpness) of |qdot| / limit over the twelve leg joints. Dimensionless. One row per sample.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class VelocityLimit final : public SampleTerm {
 public:
  Family family() const override { return Family::Velocity; }
  int rows(const ProblemModel&, const GridPoint&) const override { return 1; }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    const auto& desc = p.model_template.description();
    auto ratio = d.scratch(24);
    for (int j = 0; j < 12; ++j) {
      const auto& aj =
          desc.actuated[static_cast<std::size_t>(p.leg_act[static_cast<std::size_t>(j)])];
      const double qd = d.st->v(p.leg_coord[static_cast<std::size_t>(j)]);
      ratio(2 * j) = qd / aj.velocity;
      ratio(2 * j + 1) = -qd / aj.velocity;
    }
    out[0] = smoothMax(ratio, kKsSharpness) - p.cfg.velocity_margin;
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makeVelocityLimit() { return std::make_unique<VelocityLimit>(); }

}  // namespace overstep::planner::detail
