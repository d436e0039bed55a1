// The stacking order of the constraint terms: the problem's row layout follows it.
#include "row_term.hpp"

namespace overstep::planner::detail {

std::vector<std::unique_ptr<SampleTerm>> sampleTerms() {
  std::vector<std::unique_ptr<SampleTerm>> t;
  for (int f : {kRight, kLeft}) {
    t.push_back(makeContactCop(f));
    t.push_back(makeContactFriction(f));
    t.push_back(makeContactUnilateral(f));
  }
  t.push_back(makeSwingClearance());
  t.push_back(makeObstacleClearance());
  t.push_back(makeSelfClearance());
  t.push_back(makePelvisTilt());
  t.push_back(makeVelocityLimit());
  t.push_back(makeTorqueLimit());
  t.push_back(makeJointLimits());
  t.push_back(makeLegReach());
  t.push_back(makeSwayBalance());
  t.push_back(makeElasticDynamics());
  return t;
}

std::vector<std::unique_ptr<EventTerm>> eventTerms() {
  std::vector<std::unique_ptr<EventTerm>> t;
  t.push_back(makeSwitching());
  t.push_back(makeLiftOff());
  t.push_back(makeTouchdown());
  return t;
}

}  // namespace overstep::planner::detail
