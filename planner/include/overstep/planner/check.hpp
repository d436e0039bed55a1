#pragma once
/// \file
/// Independent re-verification of a plan (`overstep check`): everything is recomputed from the
/// robot model and the sampled motion (q, v, a), on a dense grid (1 kHz by default) — none of the
/// planner's internal values are trusted. The plan's foot wrenches are verified against the
/// motion (their sum must equal the contact wrench that inverse dynamics requires, and each
/// elastic ankle must balance its foot's wrench) before their CoP and friction are checked.

#include <string>
#include <vector>

#include "overstep/core/plan.hpp"
#include "overstep/robots/whole_body_model.hpp"

namespace overstep::planner {

struct CheckFamily {
  std::string name;        ///< cop, friction, unilateral, clearance, obstacle, self_collision,
                           ///< joint_limits, velocity, torque, pelvis, stance, dynamics
  double worst = 0.0;      ///< largest violation (unit below); <= 0 means satisfied with margin
  double tolerance = 0.0;  ///< violation accepted
  std::string unit;
  double t_worst = 0.0;  ///< s, where the worst violation happens
  std::string detail;    ///< which foot/joint/pair
  bool ok() const { return worst <= tolerance; }
};

struct CheckReport {
  bool valid = false;
  int grid_points = 0;
  double rate = 0.0;
  std::vector<CheckFamily> families;
  const CheckFamily* family(const std::string& name) const;
  /// With trace: per grid point, its time, the plan phase, and each family's worst value there
  /// (same order as families; -inf where the family has nothing to check at that point).
  std::vector<double> trace_t;
  std::vector<int> trace_phase;
  std::vector<std::vector<double>> trace;
};

/// Throws InputError when the plan was made for another robot (hash mismatch) or is unusable.
CheckReport checkPlan(const core::Plan& plan, const robots::WholeBodyModel& model,
                      double rate_hz = 1000.0, bool trace = false);

/// Where the named families cross their tolerance on a traced report (checkPlan with trace):
/// the worst instant (s) of each maximal run of grid points over the tolerance, in time order.
/// Empty without a trace or without a crossing.
std::vector<double> violationPeaks(const CheckReport& report,
                                   const std::vector<std::string>& families);

}  // namespace overstep::planner
