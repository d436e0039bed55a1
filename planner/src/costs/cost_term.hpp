#pragma once
// Internal to the planner library. The objective as a named, weighted sum of terms (the layout of
// Crocoddyl's costs): each sample cost is a squared residual, normalised by a reference scale and
// evaluated per unit time at every sample; the problem integrates it over the motion by the
// trapezoid rule, divides by the duration (a time average: an integral would reward short motions
// through every term) and multiplies by the weight of its name (`weights` in planner.yaml). A
// weight of 0 switches a term off: it is then not evaluated. The two terms that are not sample
// costs, the duration (seed eq. 25) and the torque rate between samples (eq. 27), are the
// problem's own (OverstepProblem::Impl::objective).
#include <memory>
#include <vector>

#include "../constraints/row_term.hpp"

namespace overstep::planner::detail {

class SampleCost {
 public:
  virtual ~SampleCost() = default;
  /// Its key in the weights (one of objectiveTermNames()).
  virtual const char* name() const = 0;
  /// The normalised value per unit time at the sample (dimensionless).
  virtual double value(const ProblemModel& p, const SampleData& d) const = 0;
};

std::unique_ptr<SampleCost> makeElasticAcceleration();
std::unique_ptr<SampleCost> makeElasticVelocity();
std::unique_ptr<SampleCost> makeElasticPosition();
std::unique_ptr<SampleCost> makeVerticalMomentum();
std::unique_ptr<SampleCost> makeVerticalMomentumRate();
std::unique_ptr<SampleCost> makeYawMomentumRate();
std::unique_ptr<SampleCost> makeContactTwist();
std::unique_ptr<SampleCost> makeZmpLipm();
std::unique_ptr<SampleCost> makeHeadOrientation();
std::unique_ptr<SampleCost> makeDsLegTracking();

/// Every sample cost (any order: each writes the slot of its name).
std::vector<std::unique_ptr<SampleCost>> sampleCosts();

}  // namespace overstep::planner::detail
