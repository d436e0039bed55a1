// The capsule pairs a stepping motion can bring together (ProblemModel::self_pairs) at least
// self_clearance apart, less their swept margins: one row, the smooth minimum (KS,
// robots::smoothMin) of the distances. Scale: kDistScale (m). One row per sample.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class SelfClearance final : public SampleTerm {
 public:
  Family family() const override { return Family::SelfCollision; }
  int rows(const ProblemModel&, const GridPoint&) const override { return 1; }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    auto dist = d.scratch(static_cast<Eigen::Index>(p.self_pairs.size()));
    for (std::size_t i = 0; i < p.self_pairs.size(); ++i) {
      const auto a = static_cast<std::size_t>(p.self_pairs[i].first);
      const auto b = static_cast<std::size_t>(p.self_pairs[i].second);
      dist(static_cast<Eigen::Index>(i)) =
          robots::capsuleDistance(d.capsules[a], d.capsules[b]) - d.sweep[a] - d.sweep[b];
    }
    out[0] = (p.cfg.self_clearance - robots::smoothMin(dist, p.cfg.smooth_min_rho)) / kDistScale;
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makeSelfClearance() { return std::make_unique<SelfClearance>(); }

}  // namespace overstep::planner::detail
