// Pelvis roll and pitch within +-pelvis_tilt (seed: 0.005 rad), shrunk by pelvis_margin in the
// homotopy's last stage and by limit_margin before. Scale: the bound itself (rad). Four rows per
// sample.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class PelvisTilt final : public SampleTerm {
 public:
  Family family() const override { return Family::Pelvis; }
  int rows(const ProblemModel&, const GridPoint&) const override { return 4; }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    const Eigen::Matrix3d Rb = d.model->framePose(p.base_frame).linear();
    const double roll = rollOf(Rb), pitch = pitchOf(Rb),
                 eps =
                     p.cfg.pelvis_tilt * (p.last_stage ? p.cfg.pelvis_margin : p.cfg.limit_margin);
    out[0] = (roll - eps) / eps;
    out[1] = (-roll - eps) / eps;
    out[2] = (pitch - eps) / eps;
    out[3] = (-pitch - eps) / eps;
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makePelvisTilt() { return std::make_unique<PelvisTilt>(); }

}  // namespace overstep::planner::detail
