#include "overstep/monitor/plan_match.hpp"

#include <cmath>
#include <cstdio>

#include "overstep/core/error.hpp"

namespace overstep::monitor {
namespace {

std::string seconds(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g s", v);
  return buf;
}

std::string printableName(const std::string& s) {
  std::string out;
  for (const char c : s) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  return out;
}

}  // namespace

std::string planReferenceMismatch(const overstep::plan_reference_t& ref, const core::Plan& plan) {
  const double duration = plan.duration();
  const double tol = 1.0 / plan.rate + 1e-9;
  if (!(std::abs(ref.plan_duration - duration) <= tol))
    return "OVERSTEP_PLAN_REF is of a plan of " + seconds(ref.plan_duration) + ", the plan lasts " +
           seconds(duration);
  if (!(ref.plan_time >= 0.0 && ref.plan_time <= duration + tol))
    return "OVERSTEP_PLAN_REF at plan time " + seconds(ref.plan_time) + ", outside the plan's " +
           seconds(duration);
  const int phases = static_cast<int>(plan.phases.size());
  if (ref.phase < 0 || ref.phase >= phases)
    return "OVERSTEP_PLAN_REF in phase " + std::to_string(ref.phase) + ", the plan has " +
           std::to_string(phases) + " phases";
  const std::string& name = plan.phases[static_cast<std::size_t>(ref.phase)].name;
  if (ref.phase_name != name)
    return "OVERSTEP_PLAN_REF names phase " + std::to_string(ref.phase) + " '" +
           printableName(ref.phase_name) + "', the plan '" + name + "'";
  return {};
}

void checkPlanReference(const overstep::plan_reference_t& ref, const core::Plan& plan,
                        const std::string& log, const std::string& plan_path) {
  const std::string why = planReferenceMismatch(ref, plan);
  if (!why.empty())
    throw InputError(log + ": " + why + " (" + plan_path +
                     "; not the plan of this run? give the plan that was replayed)");
}

void checkJointCount(int num_joints, int joints, const std::string& channel, const std::string& log,
                     const std::string& plan_path) {
  if (num_joints != joints)
    throw InputError(log + ": " + channel + " carries " + std::to_string(num_joints) + " joints, " +
                     plan_path + " and its robot have " + std::to_string(joints) +
                     " (a run of another robot?)");
}

}  // namespace overstep::monitor
