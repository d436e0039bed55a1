// Every leg capsule at least obstacle_clearance from the obstacle, less its swept margin (a leg on
// the ground against the target bar, a swinging leg against the homotopy's current height): one
// row, the smooth minimum (robots::softMin, smooth_min_rho) of the distances (closed form,
// robots::obstacleDistance). Scale: kDistScale (m). One row per sample.
#include "row_term.hpp"

namespace overstep::planner::detail {
namespace {

class ObstacleClearance final : public SampleTerm {
 public:
  Family family() const override { return Family::ObstacleCollision; }
  int rows(const ProblemModel&, const GridPoint&) const override { return 1; }
  void evaluate(const ProblemModel& p, const SampleData& d, double* out) const override {
    auto dist = d.scratch(static_cast<Eigen::Index>(p.leg_caps[0].size() + p.leg_caps[1].size()));
    Eigen::Index i = 0;
    // The homotopy raises the bar under a swinging leg only: a leg on the ground never passes
    // over it, and against the target bar from the first stage on its posture need not change
    // when the bar reaches its height.
    core::ObstacleSpec spec = p.obstacle;
    const robots::ObstacleGeometry& target = p.obstacle_geom;
    spec.height = p.height;
    const robots::ObstacleGeometry stage = robots::ObstacleGeometry::fromSpec(spec, p.toes_x);
    for (int f = 0; f < 2; ++f) {
      const robots::ObstacleGeometry& og = ProblemModel::inContact(d.g->phase, f) ? target : stage;
      for (int c : p.leg_caps[f])
        dist(i++) = robots::obstacleDistance(d.capsules[static_cast<std::size_t>(c)], og) -
                    d.sweep[static_cast<std::size_t>(c)];
    }
    out[0] = (p.cfg.obstacle_clearance - robots::softMin(dist, p.cfg.smooth_min_rho)) / kDistScale;
  }
};

}  // namespace

std::unique_ptr<SampleTerm> makeObstacleClearance() {
  return std::make_unique<ObstacleClearance>();
}

}  // namespace overstep::planner::detail
