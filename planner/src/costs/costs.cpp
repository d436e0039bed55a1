// The sample costs of the objective.
#include "cost_term.hpp"

namespace overstep::planner::detail {

std::vector<std::unique_ptr<SampleCost>> sampleCosts() {
  std::vector<std::unique_ptr<SampleCost>> c;
  c.push_back(makeElasticAcceleration());
  c.push_back(makeElasticVelocity());
  c.push_back(makeElasticPosition());
  c.push_back(makeVerticalMomentum());
  c.push_back(makeVerticalMomentumRate());
  c.push_back(makeYawMomentumRate());
  c.push_back(makeContactTwist());
  c.push_back(makeZmpLipm());
  c.push_back(makeHeadOrientation());
  c.push_back(makeDsLegTracking());
  return c;
}

}  // namespace overstep::planner::detail
