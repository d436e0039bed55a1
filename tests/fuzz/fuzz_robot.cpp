// Fuzz target: the robot loader (core::loadRobotDescription with model overlays, the URDF checks,
// robots::WholeBodyModel on DART). An input starting with '<' is the URDF of the two-link test
// robot; any other is a robot YAML (or an overlay of `base.yaml`, the two-link robot) beside
// `two_link.urdf`. Seeds: tests/fuzz/corpus/robot/.
#include <cstdint>

#include "fuzz_util.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/robot_description.hpp"
#include "overstep/robots/whole_body_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace overstep;
  static const bool ready = [] {
    const std::string d = std::string(OVERSTEP_DATA_DIR) + "/tests/data/";
    fuzz::copyFile(d + "two_link.yaml", "base.yaml");
    fuzz::copyFile(d + "two_link.yaml", "fixed.yaml");
    return true;
  }();
  (void)ready;
  const bool urdf = size > 0 && data[0] == '<';
  try {
    if (urdf) {
      fuzz::asFile(data, size, "two_link.urdf");
      (void)robots::WholeBodyModel::fromFile((fuzz::scratch() / "fixed.yaml").string());
    } else {
      fuzz::copyFile(std::string(OVERSTEP_DATA_DIR) + "/tests/data/two_link.urdf", "two_link.urdf");
      const std::string path = fuzz::asFile(data, size, "robot.yaml");
      (void)core::loadRobotDescription(path);
      (void)robots::WholeBodyModel::fromFile(path);
    }
  } catch (const InputError&) {
  }
  return 0;
}
