#include "overstep/planner/version.hpp"

#include "overstep_planner_source_digest.hpp"  // generated: OVERSTEP_PLANNER_SOURCE_DIGEST

namespace overstep::planner {

std::string plannerVersion() { return OVERSTEP_PLANNER_SOURCE_DIGEST; }

}  // namespace overstep::planner
