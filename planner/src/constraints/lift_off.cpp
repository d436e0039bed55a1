// At a lift-off (t1, t3) the unloading foot's wrench vanishes: rows for its normal force and its
// two tipping moments (the moments come from its bushing, not from the load). Its shear and
// twist need no rows: the split shares them in proportion to the normal loads
// (distributeWrench), so they vanish with the normal force by construction, and rows for them
// had gradients of ~1e-5 of the others (singular values of the equality Jacobian 4e-6 against
// 65): SLSQP's steps to meet them were ~20 scaled units long, half of them rejected (measured,
// docs/history/planner.md).
// Scales: in the homotopy's last stage the check's linear CoP form at zero load (a row at the
// solver's tolerance 1e-2 is 0.17 N of normal force and 0.014 N m of moment); earlier stages
// keep the weight's scale: tight rows from the first stage on left the 15 cm stage at 0.21
// (measured, docs/history/planner.md). Three equality rows per lift-off.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class LiftOff final : public EventTerm {
 public:
  Family family() const override { return Family::LiftOff; }
  int rows(const ProblemModel&, int event) const override {
    return event == 0 || event == 2 ? 3 : 0;
  }
  void evaluate(const ProblemModel& p, const EventData& d, double* out) const override {
    const int lifting = ProblemModel::liftingFoot(ProblemModel::eventPhase(d.event));
    Eigen::Vector3d mo, fo;
    soleWrench(*d.st, lifting, mo, fo);
    const double fn = p.last_stage ? kLiftOffNormal * p.mg : p.mg;
    const double ms = (p.last_stage ? 0.5 : 1.0) * p.mg * kCopScale;
    out[0] = fo.z() / fn;
    out[1] = mo.x() / ms;
    out[2] = mo.y() / ms;
  }
};

}  // namespace

std::unique_ptr<EventTerm> makeLiftOff() { return std::make_unique<LiftOff>(); }

}  // namespace overstep::planner::detail
