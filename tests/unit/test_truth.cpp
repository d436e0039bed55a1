// Truth-effects file: parsing into per-joint/per-link effects and refusal of bad input.
#include <gtest/gtest.h>

#include "overstep/core/error.hpp"
#include "overstep/sim/truth.hpp"
#include "test_util.hpp"

namespace {

const overstep::robots::WholeBodyModel& model() {
  static const auto m = overstep::robots::WholeBodyModel::fromFile(overstep::test::hrp2Yaml());
  return m;
}

overstep::sim::TruthEffects load(const std::string& text) {
  overstep::test::TempDir dir;
  overstep::test::writeText(dir.path() / "truth.yaml", text);
  return overstep::sim::loadTruth(dir.file("truth.yaml"), model());
}

std::string error(const std::string& text) {
  try {
    load(text);
  } catch (const overstep::InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(Truth, EmptyFileMeansNoEffect) {
  const auto t = load("");
  EXPECT_TRUE(t.none());
  EXPECT_EQ(t.viscous.size(), 30);
  EXPECT_EQ(t.elastic_stiffness.size(), 4u);
  EXPECT_DOUBLE_EQ(t.elastic_stiffness[1], model().description().elastic[1].stiffness);
}

TEST(Truth, EveryEffectIsParsedWithItsUnits) {
  const auto t = load(R"(
ankle:
  RLEG_ELASTIC_PITCH: {stiffness: 400, damping: 12}
friction:
  - {joints: legs, viscous: 2.0, coulomb: 1.5}
  - {joints: [CHEST_JOINT0], viscous: 0.5}
backlash:
  - {joints: RLEG_JOINT3, width: 0.004}
payload:
  - {link: CHEST_LINK1, mass: 2.5, offset: [0.05, 0.0, 0.1]}
command: {delay: 0.01, lag: 0.02}
ft_sensor:
  left: {bias: [1, 2, 3, 0.1, 0.2, 0.3], scale: 1.05}
bend:
  - {link: RARM_LINK3, rotation: [0.0, 0.05, 0.0]}
)");
  EXPECT_FALSE(t.none());
  ASSERT_EQ(t.bends.size(), 1u);
  EXPECT_EQ(t.bends[0].link, "RARM_LINK3");
  EXPECT_DOUBLE_EQ(t.bends[0].rotation.y(), 0.05);
  const auto& d = model().description();
  EXPECT_DOUBLE_EQ(
      t.elastic_stiffness[static_cast<std::size_t>(d.elasticIndex("RLEG_ELASTIC_PITCH"))], 400.0);
  EXPECT_DOUBLE_EQ(
      t.elastic_damping[static_cast<std::size_t>(d.elasticIndex("RLEG_ELASTIC_PITCH"))], 12.0);
  EXPECT_DOUBLE_EQ(
      t.elastic_stiffness[static_cast<std::size_t>(d.elasticIndex("LLEG_ELASTIC_PITCH"))],
      d.elastic[static_cast<std::size_t>(d.elasticIndex("LLEG_ELASTIC_PITCH"))].stiffness);
  int legs = 0;
  for (std::size_t j = 0; j < d.actuated.size(); ++j) {
    const bool leg = d.actuated[j].name.find("LEG_JOINT") != std::string::npos;
    legs += leg;
    EXPECT_DOUBLE_EQ(t.viscous(static_cast<Eigen::Index>(j)),
                     leg ? 2.0 : (d.actuated[j].name == "CHEST_JOINT0" ? 0.5 : 0.0));
    EXPECT_DOUBLE_EQ(t.coulomb(static_cast<Eigen::Index>(j)), leg ? 1.5 : 0.0);
  }
  EXPECT_EQ(legs, 12);
  EXPECT_DOUBLE_EQ(t.backlash(d.actuatedIndex("RLEG_JOINT3")), 0.004);
  EXPECT_DOUBLE_EQ(t.backlash.sum(), 0.004);
  ASSERT_EQ(t.payloads.size(), 1u);
  EXPECT_EQ(t.payloads[0].link, "CHEST_LINK1");
  EXPECT_DOUBLE_EQ(t.payloads[0].mass, 2.5);
  EXPECT_DOUBLE_EQ(t.payloads[0].offset.z(), 0.1);
  EXPECT_DOUBLE_EQ(t.command_delay, 0.01);
  EXPECT_DOUBLE_EQ(t.command_lag, 0.02);
  EXPECT_DOUBLE_EQ(t.ft[1].scale, 1.05);
  EXPECT_DOUBLE_EQ(t.ft[1].bias.moment.z(), 0.3);  // the file's [F; M], last entry
  EXPECT_TRUE(t.ft[0].bias.isZero());
  EXPECT_NE(t.describe().find("payload: 2.5 kg on CHEST_LINK1"), std::string::npos);
}

TEST(Truth, BadInputIsRefusedWithTheKeyNamed) {
  EXPECT_NE(error("ankle:\n  RLEG_ELASTIC_PITCH: {stiffness: -5}\n")
                .find("ankle.RLEG_ELASTIC_PITCH.stiffness"),
            std::string::npos);
  EXPECT_NE(error("ankle:\n  RLEG_ELASTIC_YAW: {stiffness: 5}\n").find("unknown elastic joint"),
            std::string::npos);
  EXPECT_NE(
      error("payload:\n  - {link: NO_SUCH_LINK, mass: 1}\n").find("unknown link 'NO_SUCH_LINK'"),
      std::string::npos);
  EXPECT_NE(error("payload:\n  - {link: BODY, mass: -1}\n").find("payload[0].mass"),
            std::string::npos);
  EXPECT_NE(
      error("friction:\n  - {joints: tail, viscous: 1}\n").find("unknown joint or group 'tail'"),
      std::string::npos);
  EXPECT_NE(error("friction:\n  - {joints: legs, viscous: abc}\n").find("expected a number"),
            std::string::npos);
  EXPECT_NE(error("friction:\n  - {joints: legs, viscous: -1}\n").find(">= 0"), std::string::npos);
  EXPECT_NE(error("command: {delay: -0.1}\n").find("command.delay"), std::string::npos);
  EXPECT_NE(error("ft_sensor:\n  right: {scale: 0}\n").find("ft_sensor.right.scale"),
            std::string::npos);
  EXPECT_NE(error("ft_sensor:\n  right: {bias: [1, 2]}\n").find("bias"), std::string::npos);
  EXPECT_NE(error("gravity: 3\n").find("gravity: unknown key"), std::string::npos);
  EXPECT_NE(error("bend:\n  - {link: NOPE, rotation: [0, 0, 0.1]}\n").find("bend[0].link"),
            std::string::npos);
  EXPECT_NE(
      error("bend:\n  - {link: RARM_LINK3, rotation: [0, 0, 0.5]}\n").find("bend[0].rotation"),
      std::string::npos);
  EXPECT_NE(error("ankle: [1, 2\n").find("malformed YAML"), std::string::npos);
  EXPECT_THROW(overstep::sim::loadTruth("/nonexistent/truth.yaml", model()), overstep::InputError);
}
