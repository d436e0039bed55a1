// Seed eq. (23): each stance foot's moment about its sole normal small (reference 5 N m).
#include "cost_term.hpp"

namespace overstep::planner::detail {
namespace {

class ContactTwist final : public SampleCost {
 public:
  const char* name() const override { return "contact_torque_z"; }
  double value(const ProblemModel&, const SampleData& d) const override {
    const State& st = *d.st;
    double sum = 0.0;
    for (int f = 0; f < 2; ++f) {
      if (!st.contact[f]) continue;
      const double mz = (st.sole[f].linear().transpose() * st.wrench[f].moment).z();
      sum += (mz / 5.0) * (mz / 5.0);
    }
    return sum;
  }
};

}  // namespace

std::unique_ptr<SampleCost> makeContactTwist() { return std::make_unique<ContactTwist>(); }

}  // namespace overstep::planner::detail
