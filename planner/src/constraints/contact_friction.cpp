// Coulomb friction of a stance foot, as a pyramid inscribed in the cone (mu / sqrt 2 per axis),
// and the twist about the sole normal (|M_z| <= torsion f_z), both shrunk by limit_margin.
// Scales: the weight (N) for the pyramid, the weight at the torsion length (N m) for the twist.
// Six rows per foot in contact.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class ContactFriction final : public SampleTerm {
 public:
  explicit ContactFriction(int foot) : foot_(foot) {}
  Family family() const override { return Family::Friction; }
  int rows(const ProblemModel&, const GridPoint& g) const override {
    return ProblemModel::inContact(g.phase, foot_) ? 6 : 0;
  }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    Eigen::Vector3d mo, fo;
    soleWrench(*d.st, foot_, mo, fo);
    const double mu = p.cfg.friction / std::sqrt(2.0) * p.cfg.limit_margin;
    const double tors = p.cfg.torsion * p.cfg.limit_margin;
    out[0] = (fo.x() - mu * fo.z()) / p.mg;
    out[1] = (-fo.x() - mu * fo.z()) / p.mg;
    out[2] = (fo.y() - mu * fo.z()) / p.mg;
    out[3] = (-fo.y() - mu * fo.z()) / p.mg;
    out[4] = (mo.z() - tors * fo.z()) / (p.mg * p.cfg.torsion);
    out[5] = (-mo.z() - tors * fo.z()) / (p.mg * p.cfg.torsion);
  }

 private:
  int foot_;
};

}  // namespace

std::unique_ptr<SampleTerm> makeContactFriction(int foot) {
  return std::make_unique<ContactFriction>(foot);
}

}  // namespace overstep::planner::detail
