// Single support: the four elastic ankle joints obey their equations of motion (seed eq. 1,
// passive rows): inverse dynamics less the stance foot's J^T w is zero. Scale: kFlexTorqueScale
// (N m). Four equality rows per single-support sample.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class ElasticDynamics final : public SampleTerm {
 public:
  Family family() const override { return Family::Dynamics; }
  bool equality() const override { return true; }
  int rows(const ProblemModel&, const GridPoint& g) const override {
    return ProblemModel::doubleSupport(g.phase) ? 0 : 4;
  }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    const State& st = *d.st;
    const int stance = st.contact[kRight] ? kRight : kLeft;
    const Eigen::MatrixXd& J = st.J_sole[stance];
    int e = 0;
    for (int f = 0; f < 2; ++f) {
      for (int k = 0; k < 2; ++k) {
        const int c = p.flex_coord[static_cast<std::size_t>(2 * f + k)];
        double res = st.tau(c);
        if (f == stance) res -= J.col(c).dot(st.wrench[f].spatial());
        out[e++] = res / kFlexTorqueScale;
      }
    }
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makeElasticDynamics() { return std::make_unique<ElasticDynamics>(); }

}  // namespace overstep::planner::detail
