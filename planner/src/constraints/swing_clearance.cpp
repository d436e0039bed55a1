// The swing sole's four corners above the ground by ProblemModel::minHeight (seed: foot
// clearance; at a mesh-refinement point, above the ground). Scale: kDistScale (m). Four rows per
// single-support sample.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class SwingClearance final : public SampleTerm {
 public:
  Family family() const override { return Family::Clearance; }
  int rows(const ProblemModel&, const GridPoint& g) const override {
    return ProblemModel::doubleSupport(g.phase) ? 0 : 4;
  }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    const State& st = *d.st;
    const int sw = st.contact[kRight] ? kLeft : kRight;
    const auto& sole = p.foot[sw].sole;
    // At touchdown (s = 1) the switching rows pin the sole to the ground: corner rows there
    // would duplicate them (degenerate constraints stall SLSQP), so they are kept inactive. The
    // smooth minimal height keeps the sole up between samples; a mesh-refinement point asks what
    // the check asks there, the ground (the profile's 2.6 mm at a point 67 ms before the left
    // touchdown, where the check had found a corner 1.5 mm in the ground, stalled a
    // restoration 1.2 mm short).
    const double hmin = d.g->s == 1.0 ? -kDistScale : d.g->refinement ? 0.0 : p.minHeight(d.g->s);
    const double xs[2] = {sole.x_front, -sole.x_back};
    const double ys[2] = {p.foot[sw].yMin(), p.foot[sw].yMax()};
    int r = 0;
    for (double cx : xs)
      for (double cy : ys) {
        const Eigen::Vector3d c = st.sole[sw] * Eigen::Vector3d(cx, cy, 0.0);
        out[r++] = (hmin - c.z()) / kDistScale;
      }
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makeSwingClearance() { return std::make_unique<SwingClearance>(); }

}  // namespace overstep::planner::detail
