// The swing sole's four corners above the ground by ProblemModel::minHeight (seed: foot
// clearance; at a mesh-refinement point, above the ground). Scale: kDistScale (m). Four rows per
// single-support sample.
//
// At the lift-off and touchdown samples (s = 0, 1) the switching rows pin the sole flat on the
// ground with zero velocity, so the corners' heights there say nothing (rows for them duplicate
// the switching rows; degenerate constraints stall SLSQP). What keeps a corner out of the ground
// next to them is its vertical acceleration there: a corner at height 0 with zero velocity that
// accelerates downwards comes from (or goes into) the ground. The four rows at s = 0 and s = 1
// ask each corner to leave and to arrive from above (classical acceleration z'' >= 0, scale
// kSwitchAccScale m/s^2): with a corner height cubic in time over the sample interval next to
// the switch and positive at its other end, z'' >= 0 at the switch keeps it positive over the
// whole interval. Without them the 1 kHz check found a corner of the landing foot more than
// 1 mm in the ground in the last tens of milliseconds before a touchdown, and the default bar
// needed a mesh refinement (the target stage solved again, ~25 s).
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

constexpr double kSwitchAccScale = 1.0;  // m/s^2

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
    const double xs[2] = {sole.x_front, -sole.x_back};
    const double ys[2] = {p.foot[sw].yMin(), p.foot[sw].yMax()};
    if (d.g->s == 0.0 || d.g->s == 1.0) {
      // Classical acceleration of a point r_W = R r fixed in the sole: a_o + alpha x r_W +
      // omega x (omega x r_W), world axes.
      const robots::Vector6d acc = d.model->frameAcceleration(p.sole_frame[sw]);
      const robots::Vector6d vel = d.model->frameVelocity(p.sole_frame[sw]);
      const Eigen::Vector3d w = vel.head<3>();
      int r = 0;
      for (double cx : xs)
        for (double cy : ys) {
          const Eigen::Vector3d rw = st.sole[sw].linear() * Eigen::Vector3d(cx, cy, 0.0);
          const Eigen::Vector3d a = acc.tail<3>() + acc.head<3>().cross(rw) + w.cross(w.cross(rw));
          out[r++] = -a.z() / kSwitchAccScale;
        }
      return;
    }
    // A mesh-refinement point asks what the check asks there, the ground (the profile's 2.6 mm
    // at a point 67 ms before the left touchdown, where the check had found a corner 1.5 mm in
    // the ground, stalled a restoration 1.2 mm short).
    const double hmin = d.g->refinement ? 0.0 : p.minHeight(d.g->s);
    int r = 0;
    for (double cx : xs)
      for (double cy : ys) {
        const Eigen::Vector3d c = st.sole[sw] * Eigen::Vector3d(cx, cy, 0.0);
        out[r++] = (hmin - c.z()) / kDistScale;
      }
  }
  // Between the switches a corner's height: z . (v_o + omega x (c - o)) for the sole frame's
  // origin o; at them the rows read accelerations.
  bool configurationJacobian(const ProblemModel& p, const SampleData& d,
                             Eigen::Ref<Eigen::MatrixXd> J) const override {
    if (d.g->s == 0.0 || d.g->s == 1.0) return false;
    const State& st = *d.st;
    const int sw = st.contact[kRight] ? kLeft : kRight;
    const auto& sole = p.foot[sw].sole;
    const double xs[2] = {sole.x_front, -sole.x_back};
    const double ys[2] = {p.foot[sw].yMin(), p.foot[sw].yMax()};
    const Eigen::MatrixXd Js = d.model->frameJacobian(p.sole_frame[sw]);
    int r = 0;
    for (double cx : xs)
      for (double cy : ys) {
        const Eigen::Vector3d rw = st.sole[sw].linear() * Eigen::Vector3d(cx, cy, 0.0);
        // z . (omega x rw) = omega . (rw x z)
        J.row(r++) =
            -(Js.row(5) + rw.cross(Eigen::Vector3d::UnitZ()).transpose() * Js.topRows<3>()) /
            kDistScale;
      }
    return true;
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makeSwingClearance() { return std::make_unique<SwingClearance>(); }

}  // namespace overstep::planner::detail
