#pragma once
/// \file
/// The planner's version: a digest of the sources that shape a plan (planner/ and robots/:
/// formulation, defaults, model, leg IK), computed at build time (cmake/source_digest.cmake).
/// Two builds of the same sources give the same version; any change to them another. Plan
/// caches key on it (overstep demo); `overstep plan --json` reports it.

#include <string>

namespace overstep::planner {

/// 16 hex digits.
std::string plannerVersion();

}  // namespace overstep::planner
