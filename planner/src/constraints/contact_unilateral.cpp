// A stance foot pushes: f_z >= min_normal_force, which an unloading foot ramps to zero over its
// double-support phase and a landing foot ramps up from zero over its own (the switch rows hold
// it at zero at the lift-off and at the touchdown). Scale: the weight (N).
// One row per foot in contact.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class ContactUnilateral final : public SampleTerm {
 public:
  explicit ContactUnilateral(int foot) : foot_(foot) {}
  Family family() const override { return Family::Unilateral; }
  int rows(const ProblemModel&, const GridPoint& g) const override {
    return ProblemModel::inContact(g.phase, foot_) ? 1 : 0;
  }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    Eigen::Vector3d mo, fo;
    soleWrench(*d.st, foot_, mo, fo);
    double fmin = p.cfg.min_normal_force;
    if (foot_ == ProblemModel::liftingFoot(d.g->phase)) fmin *= 1.0 - d.g->s;
    if (foot_ == ProblemModel::landingFoot(d.g->phase)) fmin *= d.g->s;
    out[0] = (fmin - fo.z()) / p.mg;
  }

 private:
  int foot_;
};

}  // namespace

std::unique_ptr<SampleTerm> makeContactUnilateral(int foot) {
  return std::make_unique<ContactUnilateral>(foot);
}

}  // namespace overstep::planner::detail
