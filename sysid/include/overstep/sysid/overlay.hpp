#pragma once
/// \file
/// The identified effect as a model overlay (docs/model-overlay.md): a YAML that names the robot
/// file it modifies (`base:`) and adds the effect in the simulator truth file's keys, so that
/// every command taking `--robot` (planner, simulator, runtime and its stabilizer) uses it.

#include <string>

#include "overstep/core/robot_description.hpp"
#include "overstep/sysid/identify.hpp"

namespace overstep::sysid {

/// The overlay text for `result` on top of `model` (a robot YAML or itself an overlay, whose
/// effects the new one composes with: sensor calibrations chain, a payload adds, friction and
/// command timing are totals and replace). `out_path` is where it will be written (`base:` is
/// relative to it); `source` one line on what it came from. InputError when the verdict has no
/// effect to add.
std::string overlayYaml(const Identification& result, const core::RobotDescription& model,
                        const std::string& out_path, const std::string& source);

}  // namespace overstep::sysid
