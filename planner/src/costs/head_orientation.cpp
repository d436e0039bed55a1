// Seed eq. (26): the head level and facing forward: its yaw, roll and pitch (less
// head_pitch_offset) small (reference 0.05 rad). Zero for a robot without a "head" frame.
#include "cost_term.hpp"

namespace overstep::planner::detail {
namespace {

class HeadOrientation final : public SampleCost {
 public:
  const char* name() const override { return "head"; }
  double value(const ProblemModel& p, const SampleData& d) const override {
    if (p.head_frame < 0) return 0.0;
    const Eigen::Matrix3d Rh = d.model->framePose(p.head_frame).linear();
    const double hy = yawOf(Rh), hp = pitchOf(Rh) - p.cfg.head_pitch_offset, hr = rollOf(Rh);
    return (hy * hy + hp * hp + hr * hr) / 0.0025;
  }
};

}  // namespace

std::unique_ptr<SampleCost> makeHeadOrientation() { return std::make_unique<HeadOrientation>(); }

}  // namespace overstep::planner::detail
