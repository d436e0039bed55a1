// Seed eq. (24): the whole-body ZMP (from the total contact wrench) near the table-cart ZMP of
// the CoM motion, so that the stabilizer's model agrees with the plan (reference 1 cm).
#include "cost_term.hpp"

namespace overstep::planner::detail {
namespace {

class ZmpLipm final : public SampleCost {
 public:
  const char* name() const override { return "zmp_lipm"; }
  double value(const ProblemModel& p, const SampleData& d) const override {
    const Eigen::Vector3d& cdd = d.com_acc;
    const Eigen::Vector3d com = d.model->com();
    const Eigen::Vector2d zwb = core::zmpFromWrench(d.st->W_O);
    const Eigen::Vector2d ztc =
        core::tableCartZmp(com, cdd, p.model_template.description().gravity);
    return (zwb - ztc).squaredNorm() / 1e-4;
  }
};

}  // namespace

std::unique_ptr<SampleCost> makeZmpLipm() { return std::make_unique<ZmpLipm>(); }

}  // namespace overstep::planner::detail
