// At a contact switch the switching foot carries nothing: at a lift-off (t1, t3) the unloading
// foot's wrench vanishes, and at a touchdown (t2, t4) the landing foot's starts from zero, so
// that the contact forces are continuous across every switch (no load step at a touchdown: a
// sole that meets the ground a fraction of a millimetre early or late, or tilted by a milliradian,
// cannot take a step of its load at once, and the executed foot lands on an edge). Rows for the
// foot's normal force and its two tipping moments (the moments come from its bushing, not from
// the load). Its shear and twist need no rows: the split shares them in proportion to the normal
// loads (distributeWrench), so they vanish with the normal force by construction, and rows for
// them had gradients of ~1e-5 of the others (singular values of the equality Jacobian 4e-6
// against 65): SLSQP's steps to meet them were ~20 scaled units long, half of them rejected
// (measured, docs/history/planner.md).
// Scales: in the homotopy's last stage the check's linear CoP form at zero load (a row at the
// solver's tolerance 1e-2 is 0.17 N of normal force and 0.014 N m of moment); earlier stages
// keep the weight's scale: tight rows from the first stage on left the 15 cm stage at 0.21
// (measured, docs/history/planner.md). Three equality rows per switch of the kind.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class SwitchWrench final : public EventTerm {
 public:
  explicit SwitchWrench(bool lift_off) : lift_off_(lift_off) {}
  Family family() const override { return lift_off_ ? Family::LiftOff : Family::Touchdown; }
  int rows(const ProblemModel&, int event) const override { return foot(event) >= 0 ? 3 : 0; }
  void evaluate(const ProblemModel& p, const EventData& d, double* out) const override {
    Eigen::Vector3d mo, fo;
    soleWrench(*d.st, foot(d.event), mo, fo);
    const double fn = p.last_stage ? kLiftOffNormal * p.mg : p.mg;
    const double ms = (p.last_stage ? 0.5 : 1.0) * p.mg * kCopScale;
    out[0] = fo.z() / fn;
    out[1] = mo.x() / ms;
    out[2] = mo.y() / ms;
  }

 private:
  /// The foot that lifts off (or touches down) at switch e, -1 when it is the other kind.
  int foot(int e) const {
    const int phase = ProblemModel::eventPhase(e);
    const bool starts = ProblemModel::eventBoundary(e) == phase;  // the switch opens the phase
    if (lift_off_) return starts ? -1 : ProblemModel::liftingFoot(phase);
    return starts ? ProblemModel::landingFoot(phase) : -1;
  }
  bool lift_off_;
};

}  // namespace

std::unique_ptr<EventTerm> makeLiftOff() { return std::make_unique<SwitchWrench>(true); }
std::unique_ptr<EventTerm> makeTouchdown() { return std::make_unique<SwitchWrench>(false); }

}  // namespace overstep::planner::detail
