// Centre of pressure of a stance foot inside the CoP box (seed: 1 cm x 1 cm), shrunk by
// limit_margin: |cop_x|, |cop_y| <= h in the sole frame, written linear in the wrench
// (m_y, m_x against h f_z). Scale: the weight at kCopScale (N m). Four rows per foot in contact.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class ContactCop final : public SampleTerm {
 public:
  explicit ContactCop(int foot) : foot_(foot) {}
  Family family() const override { return Family::CoP; }
  int rows(const ProblemModel&, const GridPoint& g) const override {
    return ProblemModel::inContact(g.phase, foot_) ? 4 : 0;
  }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    Eigen::Vector3d mo, fo;
    soleWrench(*d.st, foot_, mo, fo);
    const double h = 0.5 * p.cop_box * p.cfg.limit_margin;
    const double s_cop = 1.0 / (p.mg * kCopScale);
    out[0] = (-mo.y() - h * fo.z()) * s_cop;  // cop_x <= h
    out[1] = (mo.y() - h * fo.z()) * s_cop;   // cop_x >= -h
    out[2] = (mo.x() - h * fo.z()) * s_cop;   // cop_y <= h
    out[3] = (-mo.x() - h * fo.z()) * s_cop;  // cop_y >= -h
  }

 private:
  int foot_;
};

}  // namespace

std::unique_ptr<SampleTerm> makeContactCop(int foot) { return std::make_unique<ContactCop>(foot); }

}  // namespace overstep::planner::detail
