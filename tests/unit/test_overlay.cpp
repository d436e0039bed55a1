// Model overlays (docs/model-overlay.md): a YAML naming its base robot file and adding identified
// effects; loaded by core, built into the DART model by robots/, written by sysid/.
#include <gtest/gtest.h>

#include <cmath>

#include "overstep/core/error.hpp"
#include "overstep/core/robot_description.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/sysid/overlay.hpp"
#include "test_util.hpp"

namespace overstep {
namespace {

std::string overlayText(const std::string& body) {
  return "base: " + test::hrp2Yaml() + "\n" + body;
}

TEST(Overlay, LoadsEveryEffectOnTopOfTheBase) {
  test::TempDir dir;
  const std::string path = dir.file("o.yaml");
  test::writeText(
      path, overlayText("payload:\n  - {link: CHEST_LINK1, mass: 2.5, offset: [0.05, 0, 0.1]}\n"
                        "friction:\n  - {joints: [RARM_JOINT0, LARM_JOINT0], viscous: 3}\n"
                        "command: {delay: 0.015}\n"
                        "ft_sensor:\n  left: {bias: [0, 0, 10, 0.5, 0, 0], scale: 1.05}\n"
                        "ankle:\n  RLEG_ELASTIC_PITCH: {stiffness: 450}\n"));
  const core::RobotDescription base = core::loadRobotDescription(test::hrp2Yaml());
  const core::RobotDescription d = core::loadRobotDescription(path);
  EXPECT_EQ(d.yaml_path, path);
  EXPECT_EQ(d.base_yaml, test::hrp2Yaml());
  EXPECT_NE(d.hashHex(), base.hashHex());
  ASSERT_EQ(d.effects.payloads.size(), 1u);
  EXPECT_DOUBLE_EQ(d.effects.payloads[0].mass, 2.5);
  EXPECT_DOUBLE_EQ(d.effects.payloads[0].offset.z(), 0.1);
  EXPECT_DOUBLE_EQ(d.effects.viscous(d.actuatedIndex("RARM_JOINT0")), 3.0);
  EXPECT_DOUBLE_EQ(d.effects.viscous(d.actuatedIndex("LARM_JOINT0")), 3.0);
  EXPECT_DOUBLE_EQ(d.effects.viscous(d.actuatedIndex("RARM_JOINT1")), 0.0);
  EXPECT_DOUBLE_EQ(d.effects.command_delay, 0.015);
  EXPECT_DOUBLE_EQ(d.effects.ft[1].bias.force.z(), 10.0);  // the file's [F; M], third entry
  EXPECT_DOUBLE_EQ(d.effects.ft[1].scale, 1.05);
  EXPECT_DOUBLE_EQ(d.effects.ft[0].scale, 1.0);
  EXPECT_DOUBLE_EQ(
      d.elastic[static_cast<std::size_t>(d.elasticIndex("RLEG_ELASTIC_PITCH"))].stiffness, 450.0);
  EXPECT_FALSE(d.effects.empty());
  EXPECT_TRUE(base.effects.empty());
  // The calibration undoes the sensor model: measured = scale * true + bias.
  const core::Wrench truth({1, 2, 300}, {4, 5, 6}, Eigen::Vector3d::Zero(), core::Axes::kSensor);
  const core::Wrench measured = 1.05 * truth + d.effects.ft[1].bias;
  EXPECT_LT((d.effects.calibrated(1, measured) - truth).forceMoment().norm(), 1e-12);
}

TEST(Overlay, BadOverlaysNameTheKey) {
  test::TempDir dir;
  auto expectError = [&](const std::string& body, const std::string& what) {
    const std::string path = dir.file("bad.yaml");
    test::writeText(path, body);
    try {
      core::loadRobotDescription(path);
      ADD_FAILURE() << "accepted: " << body;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expectError(overlayText("paylod: []\n"), "paylod");
  expectError(overlayText("friction:\n  - {joints: NOSUCH, viscous: 1}\n"), "NOSUCH");
  expectError(overlayText("ft_sensor:\n  right: {scale: 3}\n"), "ft_sensor.right.scale");
  expectError(overlayText("payload:\n  - {link: CHEST_LINK1, mass: -1}\n"), "payload[0].mass");
  expectError(overlayText("command: {delay: 2}\n"), "command");
  expectError(overlayText("ankle:\n  RLEG_ELASTIC_PITCH: {stiffness: 0}\n"), "stiffness");
  expectError("base: " + dir.file("missing.yaml") + "\n", "missing.yaml");
  // A payload on a body the robot does not have: named when the model is built.
  const std::string path = dir.file("nolink.yaml");
  test::writeText(path, overlayText("payload:\n  - {link: NOSUCH_LINK, mass: 1}\n"));
  try {
    robots::WholeBodyModel::fromFile(path);
    ADD_FAILURE() << "a payload on a missing link was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("NOSUCH_LINK"), std::string::npos) << e.what();
  }
}

// The payload is part of the rigid-body model: mass, CoM and the gravity torque it adds.
TEST(Overlay, PayloadEntersTheModelsMassAndCom) {
  test::TempDir dir;
  const std::string path = dir.file("o.yaml");
  const Eigen::Vector3d offset(0.05, -0.02, 0.1);
  test::writeText(
      path,
      overlayText("payload:\n  - {link: CHEST_LINK1, mass: 3, offset: [0.05, -0.02, 0.1]}\n"));
  robots::WholeBodyModel base = robots::WholeBodyModel::fromFile(test::hrp2Yaml());
  robots::WholeBodyModel with = robots::WholeBodyModel::fromFile(path);
  EXPECT_NEAR(with.totalMass(), base.totalMass() + 3.0, 1e-9);
  const Eigen::VectorXd q = base.halfSitting();
  base.setPositions(q);
  with.setPositions(q);
  const Eigen::Vector3d p = base.framePose(base.frameIndex("CHEST_LINK1")) * offset;
  const Eigen::Vector3d expected =
      (base.totalMass() * base.com() + 3.0 * p) / (base.totalMass() + 3.0);
  EXPECT_LT((with.com() - expected).norm(), 1e-9);
}

TEST(Overlay, IdentificationBecomesAnOverlayThatLoadsBack) {
  test::TempDir dir;
  const core::RobotDescription base = core::loadRobotDescription(test::hrp2Yaml());
  sysid::Identification r;
  r.verdict = "identified";
  r.effect = "payload";
  r.parameters = {
      {"mass", 2.0}, {"mass*offset_x", 0.1}, {"mass*offset_y", 0.0}, {"mass*offset_z", 0.2}};
  const std::string path = dir.file("payload.yaml");
  core::writeFileAtomic(path, sysid::overlayYaml(r, base, path, "test"));
  const core::RobotDescription d = core::loadRobotDescription(path);
  ASSERT_EQ(d.effects.payloads.size(), 1u);
  EXPECT_NEAR(d.effects.payloads[0].mass, 2.0, 1e-6);
  EXPECT_NEAR(d.effects.payloads[0].offset.x(), 0.05, 1e-6);
  EXPECT_NEAR(d.effects.payloads[0].offset.z(), 0.1, 1e-6);

  // A sensor bias identified on readings already calibrated by an overlay composes with it.
  sysid::Identification b;
  b.verdict = "ambiguous";
  b.effect = "ft_bias_left";
  b.parameters = {{"fz_bias", 4.0}, {"mx_bias", 0.0}, {"my_bias", 0.0}};
  const std::string first = dir.file("bias1.yaml");
  test::writeText(first,
                  overlayText("ft_sensor:\n  left: {bias: [0, 0, 10, 0, 0, 0], scale: 1.1}\n"));
  const core::RobotDescription d1 = core::loadRobotDescription(first);
  const std::string second = dir.file("bias2.yaml");
  core::writeFileAtomic(second, sysid::overlayYaml(b, d1, second, "test"));
  const core::RobotDescription d2 = core::loadRobotDescription(second);
  EXPECT_EQ(d2.base_yaml, first);
  EXPECT_NEAR(d2.effects.ft[1].bias.force.z(), 10.0 + 1.1 * 4.0, 1e-6);
  EXPECT_NEAR(d2.effects.ft[1].scale, 1.1, 1e-12);

  sysid::Identification none;
  none.verdict = "none";
  EXPECT_THROW(sysid::overlayYaml(none, base, path, "test"), InputError);
}

}  // namespace
}  // namespace overstep
