// At each contact switch the leg that changes representation (double-support inverse kinematics
// <-> its spline) is continuous: the spline's angles and rates match the inverse-kinematics leg
// of the double-support phase at the switch. Scales: kJointScale (rad), 1 rad/s. Twelve
// equality rows per switch.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class Switching final : public EventTerm {
 public:
  Family family() const override { return Family::Switching; }
  int rows(const ProblemModel&, int) const override { return 12; }
  void evaluate(const ProblemModel& p, const EventData& d, double* out) const override {
    const SplineState& S = *d.spline;
    const int leg = 1 - p.anchor_of[ProblemModel::eventPhase(d.event)];
    int r = 0;
    for (int j = 0; j < 6; ++j) {
      const int row = 6 * leg + j;
      out[r++] = (S(row, 0) - d.st->q(p.leg_coord[static_cast<std::size_t>(row)])) / kJointScale;
    }
    for (int j = 0; j < 6; ++j) {
      const int row = 6 * leg + j;
      out[r++] = (S(row, 1) - d.st->v(p.leg_coord[static_cast<std::size_t>(row)])) / 1.0;
    }
  }
};

}  // namespace

std::unique_ptr<EventTerm> makeSwitching() { return std::make_unique<Switching>(); }

}  // namespace overstep::planner::detail
