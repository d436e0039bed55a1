// Fuzz target: the plan reader (core::loadPlan, core::validatePlan) and `overstep check`
// (planner::checkPlan) on the HRP-2-class model. Seeds: tests/fuzz/corpus/plan/.
#include <cstdint>

#include "fuzz_util.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/planner/check.hpp"
#include "overstep/robots/whole_body_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace overstep;
  static const robots::WholeBodyModel model =
      robots::WholeBodyModel::fromFile(std::string(OVERSTEP_DATA_DIR) + "/robots/hrp2/hrp2.yaml");
  try {
    const core::Plan plan = core::loadPlan(fuzz::asFile(data, size, "plan.json"));
    // The check's cost grows with the plan's duration (a 1 kHz grid): bounded here, as the
    // command bounds it by its input's size.
    if (plan.duration() <= 1.0) planner::checkPlan(plan, model);
  } catch (const InputError&) {
  } catch (const InfeasibleError&) {
  }
  return 0;
}
