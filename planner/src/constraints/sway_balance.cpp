// Double support: the elastic ankles' balance about the line through both bushings, which no
// split of the contact wrench reaches (State::ds_balance), within +-ds_balance_band. Scale:
// kFlexTorqueScale (N m). Two rows per double-support sample.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class SwayBalance final : public SampleTerm {
 public:
  Family family() const override { return Family::Dynamics; }
  int rows(const ProblemModel&, const GridPoint& g) const override {
    return ProblemModel::doubleSupport(g.phase) ? 2 : 0;
  }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    out[0] = (d.st->ds_balance - p.cfg.ds_balance_band) / kFlexTorqueScale;
    out[1] = (-d.st->ds_balance - p.cfg.ds_balance_band) / kFlexTorqueScale;
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makeSwayBalance() { return std::make_unique<SwayBalance>(); }

}  // namespace overstep::planner::detail
