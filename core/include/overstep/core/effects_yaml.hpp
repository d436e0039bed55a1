#pragma once
/// \file
/// The effect keys shared by the simulator's truth file (docs/truth-file.md) and model overlays
/// (docs/model-overlay.md): `ankle`, `payload`, `command`, `ft_sensor`. Errors name the file and
/// key.

#include <yaml-cpp/yaml.h>

#include <array>
#include <vector>

#include "overstep/core/robot_description.hpp"
#include "overstep/core/yaml_reader.hpp"

namespace overstep::core {

/// `ankle: {<elastic joint>: {stiffness, damping}}` into per-elastic-joint values (indexed as
/// d.elastic); absent keys leave the values as they are.
void parseAnkles(const YAML::Node& map, const YamlReader& r, const RobotDescription& d,
                 std::vector<double>& stiffness, std::vector<double>& damping);
/// `payload: [{link, mass, offset}]` (links are checked where the model is known).
std::vector<PayloadDescription> parsePayloads(const YAML::Node& list, const YamlReader& r);
/// `command: {delay, lag}` in s (0 .. 1); keys that are absent leave the values as they are.
void parseCommandTiming(const YAML::Node& map, const YamlReader& r, double& delay, double& lag);
/// `ft_sensor: {right|left: {bias: [6], scale}}`; absent keys leave the values as they are.
/// The bias is [F; M] in the sensor frame, N and N m.
void parseForceSensors(const YAML::Node& map, const YamlReader& r,
                       std::array<ForceSensorModel, 2>& sensors);

}  // namespace overstep::core
