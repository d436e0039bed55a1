// core: robot description loading/validation, the wrench/ZMP helpers and plan sample lookup.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <random>
#include <vector>

#include "overstep/core/error.hpp"
#include "overstep/core/json_depth.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/core/robot_description.hpp"
#include "overstep/core/stderr_capture.hpp"
#include "overstep/core/wrench.hpp"
#include "overstep/core/yaml_reader.hpp"
#include "test_util.hpp"

namespace overstep {
namespace {

using test::TempDir;

TEST(RobotDescription, LoadsHrp2Tables) {
  const core::RobotDescription d = core::loadRobotDescription(test::hrp2Yaml());
  ASSERT_EQ(d.actuated.size(), 30u);
  ASSERT_EQ(d.elastic.size(), 4u);
  EXPECT_EQ(d.actuated.front().name, "RLEG_JOINT0");
  EXPECT_EQ(d.actuated[12].name, "CHEST_JOINT0");
  EXPECT_EQ(d.actuated.back().name, "LARM_JOINT6");
  ASSERT_EQ(d.feet.size(), 2u);
  EXPECT_EQ(d.feet[0].side, "right");
  // Sole rectangle 0.230 x 0.131 m.
  EXPECT_NEAR(d.feet[0].sole.x_front + d.feet[0].sole.x_back, 0.230, 1e-12);
  EXPECT_NEAR(d.feet[0].yMax() - d.feet[0].yMin(), 0.131, 1e-12);
  EXPECT_LT(d.feet[0].centre().y(), 0.0);  // right foot: outer side is -y
  EXPECT_GT(d.feet[1].centre().y(), 0.0);
  for (const auto& a : d.actuated) {
    EXPECT_LT(a.lower, a.safeLower()) << a.name;
    EXPECT_GT(a.upper, a.safeUpper()) << a.name;
  }
  for (Eigen::Index i = 0; i < d.half_sitting.size(); ++i) {
    const auto& a = d.actuated[static_cast<std::size_t>(i)];
    EXPECT_GE(d.half_sitting(i), a.safeLower()) << a.name;
    EXPECT_LE(d.half_sitting(i), a.safeUpper()) << a.name;
  }
  EXPECT_NE(d.content_hash, 0u);
  EXPECT_EQ(d.hashHex().size(), 16u);
}

// Writes a copy of the HRP-2 YAML (and URDF) with one edit and expects an InputError whose single
// line contains `expect`.
void expectYamlError(const std::string& from, const std::string& to, const std::string& expect) {
  TempDir dir;
  test::writeText(dir.path() / "hrp2.urdf", test::slurp(test::hrp2Urdf()));
  test::writeText(dir.path() / "hrp2.yaml",
                  test::replaceOnce(test::slurp(test::hrp2Yaml()), from, to));
  try {
    core::loadRobotDescription(dir.file("hrp2.yaml"));
    FAIL() << "expected InputError containing '" << expect << "'";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(expect), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message must be one line: " << msg;
  }
}

// The robot hash covers what shapes a plan: the stabilizer's gains can be tuned on a plan (the
// plan stays the robot's), the model cannot.
TEST(RobotDescription, HashIgnoresWhatDoesNotShapeAPlan) {
  EXPECT_EQ(
      core::withoutSection("a: 1\nstabilizer:\n  k: 2\n\n  # c\n  j: 3\nb: 4\n", "stabilizer"),
      "a: 1\nb: 4\n");
  EXPECT_EQ(core::withoutSection("stabilizer: {k: 2}\nstabilizers: 1", "stabilizer"),
            "stabilizers: 1");
  EXPECT_EQ(core::withoutSection("a: 1\n  stabilizer: 2\n", "stabilizer"),
            "a: 1\n  stabilizer: 2\n");
  auto hashWith = [](const std::string& from, const std::string& to) {
    TempDir dir;
    test::writeText(dir.path() / "hrp2.urdf", test::slurp(test::hrp2Urdf()));
    test::writeText(dir.path() / "hrp2.yaml",
                    test::replaceOnce(test::slurp(test::hrp2Yaml()), from, to));
    return core::loadRobotDescription(dir.file("hrp2.yaml")).content_hash;
  };
  const std::uint64_t base = core::loadRobotDescription(test::hrp2Yaml()).content_hash;
  EXPECT_EQ(hashWith("posture_gain: 0.5", "posture_gain: 0.0"), base);
  EXPECT_EQ(hashWith("damping_roll: 240.0", "damping_roll: 90.0"), base);
  EXPECT_NE(hashWith("stiffness: 707", "stiffness: 708"), base);
  // The identification's inputs do not shape a plan either; the self-collision pairs do.
  EXPECT_EQ(hashWith("frequency: 0.31", "frequency: 0.32"), base);
  EXPECT_EQ(hashWith("  head: [HEAD_JOINT0, HEAD_JOINT1]", "  head: [HEAD_JOINT0]"), base);
  EXPECT_NE(hashWith("  - [LARM_LINK6, LLEG_LINK2]\n", ""), base);
  // Nor the bushings' vertical give, which the planner's model leaves out.
  EXPECT_EQ(hashWith("{stiffness: 239018, damping: 1000}", "{stiffness: 150000, damping: 500}"),
            base);
}

// Robot specifics the code once named as literals come from the robot file: the self-collision
// pairs, the joint groups and the excitation.
TEST(RobotDescription, ReadsSelfCollisionPairsGroupsAndExcitation) {
  const core::RobotDescription d = core::loadRobotDescription(test::hrp2Yaml());
  ASSERT_EQ(d.self_collision.size(), 4u);
  EXPECT_EQ(d.self_collision[0],
            std::make_pair(std::string("RARM_LINK3"), std::string("RLEG_LINK2")));
  const core::JointGroup* legs = d.group("legs");
  ASSERT_NE(legs, nullptr);
  ASSERT_EQ(legs->joints.size(), 12u);
  for (int j : legs->joints)
    EXPECT_NE(d.actuated[static_cast<std::size_t>(j)].name.find("LEG_"), std::string::npos);
  EXPECT_EQ(d.group("tail"), nullptr);
  ASSERT_FALSE(d.excitation.empty());
  for (const auto& e : d.excitation) {
    EXPECT_GE(d.actuatedIndex(e.joint), 0) << e.joint;
    EXPECT_GT(e.amplitude, 0.0);
    EXPECT_GT(e.frequency, 0.0);
  }
}

TEST(RobotDescription, RejectsBadSelfCollisionGroupsAndExcitation) {
  expectYamlError("  - [RARM_LINK3, RLEG_LINK2]", "  - [RARM_LINK4, RLEG_LINK2]",
                  "self_collision[0]: link 'RARM_LINK4' has no capsule");
  expectYamlError("  - [RARM_LINK3, RLEG_LINK2]", "  - [RARM_LINK3]",
                  "self_collision[0]: expected [link, link]");
  expectYamlError("  chest: [CHEST_JOINT0, CHEST_JOINT1]", "  chest: [CHEST_JOINT0, CHEST_JOINT9]",
                  "joint_groups.chest: unknown actuated joint 'CHEST_JOINT9'");
  expectYamlError("  chest: [CHEST_JOINT0, CHEST_JOINT1]", "  all: [CHEST_JOINT0]",
                  "joint_groups.all: 'all' is reserved");
  expectYamlError("  chest: [CHEST_JOINT0, CHEST_JOINT1]", "  chest: [CHEST_JOINT0, CHEST_JOINT0]",
                  "listed twice");
  expectYamlError("{joint: CHEST_JOINT0, amplitude: 0.15", "{joint: CHEST_JOINT0, amplitude: 3",
                  "excitation[0].amplitude: expected <= 1 rad");
  expectYamlError("{joint: CHEST_JOINT0, amplitude", "{joint: TAIL_JOINT0, amplitude",
                  "excitation[0].joint: unknown actuated joint 'TAIL_JOINT0'");
  expectYamlError("frequency: 0.31", "frequency: -0.31", "excitation[0].frequency");
}

// Issue 20, found by fuzz_robot (10^6-run long run, seed 27): a list entry that is a scalar where
// a map belongs made yaml-cpp throw BadSubscript past the typed reads (the process aborted).
TEST(RobotDescription, ScalarListEntriesAreBadInputNotACrash) {
  expectYamlError("elastic_joints:\n", "elastic_joints:\n  - 2.0}\n",
                  "elastic_joints[0]: expected a map");
  expectYamlError("frames:\n", "frames:\n  - tip\n", "frames[0]: expected a map");
  expectYamlError("capsules:\n", "capsules:\n  - [1, 2]\n", "capsules[0]: expected a map");
  expectYamlError("excitation:\n", "excitation:\n  - 0.3\n", "excitation[0]: expected a map");
}

TEST(RobotDescription, RejectsNegativeStiffness) {
  expectYamlError("stiffness: 707", "stiffness: -707",
                  "elastic_joints[0].stiffness: expected >= 0");
}

TEST(RobotDescription, RejectsBadBushingVerticalGive) {
  const std::string row = "bushing_vertical: {stiffness: 239018, damping: 1000}";
  expectYamlError(row, "bushing_vertical: 3", "bushing_vertical: expected {stiffness, damping}");
  expectYamlError(row, "bushing_vertical: {stiffness: 50, damping: 1000}",
                  "bushing_vertical.stiffness: expected 0 (rigid) or 1e3 to 1e6 N/m, got 50");
  expectYamlError(row, "bushing_vertical: {stiffness: 5e6, damping: 1000}",
                  "bushing_vertical.stiffness: expected 0 (rigid) or 1e3 to 1e6 N/m");
  expectYamlError(row, "bushing_vertical: {stiffness: 239018, damping: -1}",
                  "bushing_vertical.damping: expected >= 0");
  expectYamlError(row, "bushing_vertical: {stiffness: 239018, damping: 2e4}",
                  "bushing_vertical.damping: expected 0 to 1e4 N s/m");
  expectYamlError(row, "bushing_vertical: {stiffness: 239018}", "damping");
}

TEST(RobotDescription, RejectsNegativeDamping) {
  expectYamlError("damping: 10", "damping: -1", "damping: expected >= 0");
}

TEST(RobotDescription, RejectsMalformedYaml) {
  expectYamlError("name: hrp2_class", "name: [hrp2_class", "malformed YAML");
}

TEST(RobotDescription, RejectsNonNumeric) {
  expectYamlError("velocity: 3.54", "velocity: fast", "expected a number, got 'fast'");
}

TEST(RobotDescription, RejectsInvertedLimits) {
  expectYamlError("limits_deg: [-45, 30]", "limits_deg: [30, -45]", "expected lower < upper");
}

TEST(RobotDescription, RejectsMissingKey) {
  expectYamlError("base_link: BODY", "base_lnk: BODY", "base_link: missing key");
}

TEST(RobotDescription, RejectsHalfSittingOutsideLimits) {
  expectYamlError("half_sitting_deg: [0, 0, -26, 50", "half_sitting_deg: [0, 0, -26, 170",
                  "outside its limits");
}

// Issue 20: a robot without feet loaded (then plan / check dereferenced the missing foot); infinite
// limits, a negative acceleration limit and an absurd gravity passed; a key given twice was read
// once (the first) and the second silently ignored.
TEST(RobotDescription, RejectsAFloatingBaseWithoutFeet) {
  expectYamlError("\nfeet:", "\nfee:", "hrp2.yaml: feet: missing key (a floating-base robot");
}

TEST(RobotDescription, RejectsNonFiniteLimits) {
  expectYamlError("limits_deg: [-45, 30]", "limits_deg: [-.inf, 30]",
                  "actuated_joints[0].limits_deg: expected a finite number, got -inf");
  expectYamlError("limits_deg: [-45, 30]", "limits_deg: [-45, .inf]",
                  "actuated_joints[0].limits_deg: expected a finite number, got inf");
  expectYamlError("limits_deg: [-45, 30]", "limits_deg: [.nan, 30]",
                  "actuated_joints[0].limits_deg: expected a finite number, got nan");
}

TEST(RobotDescription, RejectsANonPositiveAccelerationLimit) {
  expectYamlError("acceleration_limit: 30.0", "acceleration_limit: -5",
                  "acceleration_limit: expected > 0 rad/s^2, got -5");
  expectYamlError("acceleration_limit: 30.0", "acceleration_limit: 0",
                  "acceleration_limit: expected > 0 rad/s^2, got 0");
}

TEST(RobotDescription, RejectsAbsurdGravity) {
  expectYamlError("gravity: 9.81", "gravity: 1e308",
                  "gravity: expected a magnitude of at most 1e+09, got 1e+308");
  expectYamlError("gravity: 9.81", "gravity: 1e5",
                  "gravity: expected 0 < gravity <= 100 m/s^2, got 100000");
  expectYamlError("gravity: 9.81", "gravity: .nan", "gravity: expected a finite number, got nan");
}

TEST(RobotDescription, RejectsDuplicateKeys) {
  expectYamlError("base_link: BODY", "base_link: BODY\nbase_link: CHEST",
                  "hrp2.yaml: base_link: duplicate key (again at line 7)");
  expectYamlError("stiffness: 707, damping: 10.0", "stiffness: 707, damping: 10.0, stiffness: 1",
                  "elastic_joints[0].stiffness: duplicate key");
}

TEST(RobotDescription, RejectsYamlAliasesThatExpandBeyondTheFile) {
  // "Billion laughs": 9 levels of 10 aliases each, 10^9 nodes from a few hundred bytes.
  std::string yaml = "a0: &a0 [x]\n";
  for (int i = 1; i < 10; ++i) {
    yaml += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
    for (int k = 0; k < 10; ++k) yaml += std::string(k ? ", " : "") + "*a" + std::to_string(i - 1);
    yaml += "]\n";
  }
  TempDir dir;
  test::writeText(dir.path() / "laughs.yaml", yaml);
  try {
    core::loadRobotDescription(dir.file("laughs.yaml"));
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("laughs.yaml: YAML aliases expand"), std::string::npos)
        << e.what();
  }
}

TEST(RobotDescription, TheFixedBaseTwoLinkRobotNeedsNoFeet) {
  EXPECT_TRUE(core::loadRobotDescription(test::twoLinkYaml()).feet.empty());
}

TEST(RobotDescription, RejectsMissingFile) {
  try {
    core::loadRobotDescription("/nonexistent/robot.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/robot.yaml: no such file"),
              std::string::npos);
  }
}

TEST(Wrench, ZmpOfPureForceIsItsLineOfAction) {
  // A vertical force of 500 N through (0.1, -0.2, 0), seen about that point and about others.
  const Eigen::Vector3d p(0.1, -0.2, 0.0);
  const core::Wrench w_p({0, 0, 500}, Eigen::Vector3d::Zero(), p, core::Axes::kWorld);
  for (const Eigen::Vector3d& q :
       std::vector<Eigen::Vector3d>{Eigen::Vector3d::Zero(), Eigen::Vector3d(0.3, 0.4, 0.9)}) {
    const Eigen::Vector2d z = core::zmpFromWrench(w_p.about(q));
    EXPECT_NEAR(z.x(), 0.1, 1e-12);
    EXPECT_NEAR(z.y(), -0.2, 1e-12);
  }
}

TEST(Wrench, ZmpOnRaisedGroundAccountsForShear) {
  // Force with shear through (0.05, 0.02, 0.1): the ZMP on z = 0.1 is that point.
  const Eigen::Vector3d p(0.05, 0.02, 0.1);
  const core::Wrench w_p({30, -20, 400}, Eigen::Vector3d::Zero(), p, core::Axes::kWorld);
  const Eigen::Vector2d z = core::zmpFromWrench(w_p.about(Eigen::Vector3d::Zero()), 0.1);
  EXPECT_NEAR(z.x(), 0.05, 1e-12);
  EXPECT_NEAR(z.y(), 0.02, 1e-12);
}

TEST(Wrench, NoNormalForceGivesNaN) {
  EXPECT_TRUE(core::zmpFromWrench(core::Wrench::zero(core::Axes::kWorld)).hasNaN());
  EXPECT_TRUE(core::localCop(core::Wrench::zero(core::Axes::kSole)).hasNaN());
}

TEST(Wrench, OrderingsAreStatedAtTheBoundaries) {
  core::Vector6d fm;
  fm << 1, 2, 3, 4, 5, 6;  // [F; M], the sensors' and the files' order
  const core::Wrench w = core::Wrench::fromForceMoment(fm, core::Axes::kSensor);
  EXPECT_EQ(w.force, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(w.moment, Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(w.forceMoment(), fm);
  core::Vector6d mf;
  mf << 4, 5, 6, 1, 2, 3;  // [M; F], DART's spatial order
  EXPECT_EQ(w.spatial(), mf);
  const core::Wrench back = core::Wrench::fromSpatial(mf, core::Axes::kSensor);
  EXPECT_EQ(back.force, w.force);
  EXPECT_EQ(back.moment, w.moment);
  EXPECT_STREQ(core::axesName(w.axes), "sensor");
}

TEST(Wrench, ExpressedInRotatesAndMapsThePointAndInFrameUndoesIt) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::Isometry3d X_WF = Eigen::Isometry3d::Identity();
    X_WF.linear() =
        Eigen::AngleAxisd(3 * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized())
            .toRotationMatrix();
    X_WF.translation() << u(rng), u(rng), u(rng);
    const core::Wrench w_F({10 * u(rng), 10 * u(rng), 100 * u(rng)}, {u(rng), u(rng), u(rng)},
                           Eigen::Vector3d::Zero(), core::Axes::kSole);
    const core::Wrench w_W = w_F.expressedIn(X_WF, core::Axes::kWorld);
    EXPECT_EQ(w_W.axes, core::Axes::kWorld);
    EXPECT_LT((w_W.force - X_WF.linear() * w_F.force).norm(), 1e-12);
    EXPECT_LT((w_W.point - X_WF.translation()).norm(), 1e-12);
    // About the world origin: R m + p x (R f).
    const core::Wrench w_O = w_W.about(Eigen::Vector3d::Zero());
    const Eigen::Vector3d expect =
        X_WF.linear() * w_F.moment + X_WF.translation().cross(X_WF.linear() * w_F.force);
    EXPECT_LT((w_O.moment - expect).norm(), 1e-12);
    // Back to the frame from any reference point.
    const core::Wrench back = w_O.inFrame(X_WF, core::Axes::kSole);
    EXPECT_EQ(back.axes, core::Axes::kSole);
    EXPECT_TRUE(back.point.isZero(0.0));
    EXPECT_LT((back.force - w_F.force).norm(), 1e-12);
    EXPECT_LT((back.moment - w_F.moment).norm(), 1e-11);
  }
}

TEST(Wrench, SumsTakeEveryMomentAboutOnePoint) {
  // Two vertical 100 N forces at x = +-0.1 balance about the origin; about x = 0.1 they do not.
  const core::Wrench a({0, 0, 100}, Eigen::Vector3d::Zero(), {0.1, 0, 0}, core::Axes::kWorld);
  const core::Wrench b({0, 0, 100}, Eigen::Vector3d::Zero(), {-0.1, 0, 0}, core::Axes::kWorld);
  const core::Wrench sum = core::Wrench::zero(core::Axes::kWorld) + a + b;
  EXPECT_LT(sum.moment.norm(), 1e-12);
  EXPECT_DOUBLE_EQ(sum.force.z(), 200.0);
  const core::Wrench sum_a = a + b;  // about a's point
  EXPECT_NEAR(sum_a.moment.y(), 100.0 * 0.2, 1e-12);
  // Whatever point it is taken about, the sum is the same wrench.
  EXPECT_LT((sum_a.about(Eigen::Vector3d::Zero()).moment - sum.moment).norm(), 1e-12);
  EXPECT_LT(((a - a).force).norm() + (a - a).moment.norm(), 1e-15);
}

TEST(Wrench, ForceSensorCalibrationInvertsTheMeasurement) {
  core::ForceSensorModel s;
  EXPECT_TRUE(s.isIdentity());
  s.scale = 1.05;
  s.bias.force << 1.0, -2.0, 10.0;
  s.bias.moment << 0.1, -0.2, 0.3;
  EXPECT_FALSE(s.isIdentity());
  const core::Wrench truth({5, 6, 400}, {1, -2, 0.5}, Eigen::Vector3d::Zero(), core::Axes::kSensor);
  const core::Wrench m = s.measured(truth);
  EXPECT_NEAR(m.force.z(), 1.05 * 400 + 10.0, 1e-12);
  const core::Wrench back = s.calibrated(m);
  EXPECT_LT((back.force - truth.force).norm() + (back.moment - truth.moment).norm(), 1e-12);
}

TEST(Wrench, TableCartZmpOfStaticComIsItsProjection) {
  const Eigen::Vector2d z = core::tableCartZmp({0.03, -0.01, 0.8}, Eigen::Vector3d::Zero(), 9.81);
  EXPECT_DOUBLE_EQ(z.x(), 0.03);
  EXPECT_DOUBLE_EQ(z.y(), -0.01);
  // Accelerating forward moves the ZMP backward by z/g * a.
  const Eigen::Vector2d z2 = core::tableCartZmp({0.0, 0.0, 0.8}, {1.0, 0.0, 0.0}, 9.81);
  EXPECT_NEAR(z2.x(), -0.8 / 9.81, 1e-12);
}

}  // namespace
}  // namespace overstep

namespace overstep::core {
namespace {

// A plan at 200 Hz whose phase switches repeat the switch time (1 us apart, as the planner
// writes them): three switches, so round(t * rate) would be three samples late at the end.
Plan switchingPlan() {
  Plan p;
  std::vector<double> t;
  std::vector<int> ph;
  double now = 0.0;
  for (int phase = 0; phase < 4; ++phase) {
    if (phase > 0) now += 1e-6;  // the switch sample of the new phase
    for (int i = 0; i < 40; ++i) {
      t.push_back(now);
      ph.push_back(phase);
      if (i + 1 < 40) now += 0.005;
    }
  }
  p.resize(static_cast<int>(t.size()), 1, 0);
  for (std::size_t k = 0; k < t.size(); ++k) {
    p.t(static_cast<Eigen::Index>(k)) = t[k];
    p.phase(static_cast<Eigen::Index>(k)) = ph[k];
  }
  return p;
}

TEST(Plan, SampleAtFindsEverySampleAcrossPhaseSwitches) {
  const Plan p = switchingPlan();
  for (int k = 0; k < p.samples(); ++k)
    EXPECT_EQ(p.sampleAt(p.t(k), p.phase(k)), k) << "t " << p.t(k) << " phase " << p.phase(k);
  // Between samples: the nearer one, never more than half a period away (the rate-based index
  // was 3 samples = 15 ms off after the third switch).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, p.duration());
  for (int i = 0; i < 2000; ++i) {
    const double t = u(rng);
    const int k = p.sampleAt(t);
    ASSERT_GE(k, 0);
    EXPECT_LE(std::abs(p.t(k) - t), 0.5 * 0.005 + 1e-6) << t;
  }
  EXPECT_EQ(p.sampleAt(-1.0), 0);
  EXPECT_EQ(p.sampleAt(std::nan("")), 0);
  EXPECT_EQ(p.sampleAt(p.duration() + 1.0), p.samples() - 1);
  // At a switch without a phase: the later sample (the new phase).
  EXPECT_EQ(p.phase(p.sampleAt(p.t(40))), 1);
  EXPECT_EQ(Plan{}.sampleAt(0.0), -1);
}

// The plan stores each foot's wrench about that foot's sole origin: one set about another point
// reads back as the same physical wrench, about the sole origin.
TEST(Plan, WrenchesAreReadAboutTheSoleOriginWhateverPointTheyWereSetAbout) {
  Plan p = switchingPlan();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < p.samples(); ++k)
    for (Eigen::MatrixXd* pose : {&p.right_foot, &p.left_foot})
      pose->col(k) << 0.3 * u(rng), 0.2 * u(rng), 0.01 * u(rng), 1.0, 0.0, 0.0, 0.0;
  for (int k = 0; k < p.samples(); k += 7)
    for (int f = 0; f < 2; ++f) {
      const Eigen::Vector3d o = (f == 0 ? p.right_foot : p.left_foot).col(k).head<3>();
      const Wrench w({20 * u(rng), 20 * u(rng), 300 + 100 * u(rng)}, {u(rng), u(rng), u(rng)},
                     o + Eigen::Vector3d(0.05 * u(rng), 0.03 * u(rng), 0.0), Axes::kWorld);
      p.setWrench(f, k, w);
      const Wrench back = p.wrench(f, k);
      EXPECT_EQ(back.axes, Axes::kWorld);
      EXPECT_EQ(back.point, o);
      EXPECT_EQ(back.force, w.force);
      const Eigen::Vector3d q(0.1, -0.2, 0.7);  // any point: the same moment about it
      EXPECT_LT((back.about(q).moment - w.about(q).moment).norm(), 1e-12) << k << " " << f;
    }
}

// The bracket scan every JSON reader asks before parsing (nlohmann-json recurses).
TEST(Json, DepthCountsBracketsOutsideStringsAndStopsPastTheCap) {
  EXPECT_EQ(core::jsonDepth("1", 8), 0);
  EXPECT_EQ(core::jsonDepth("{\"a\": [1, {\"b\": []}]}", 8), 4);
  EXPECT_EQ(core::jsonDepth("[\"[[[[\", \"\\\"[[[\"]", 8),
            1);  // brackets in strings, an escaped quote
  const std::string deep = std::string(60000, '[') + std::string(60000, ']');
  EXPECT_EQ(core::jsonDepth(deep, 16), 17);  // stopped just past the cap
  EXPECT_EQ(core::jsonDepth(deep, 100000), 60000);
}

// Every number of our YAML files: finite and at most 1e9 in magnitude (1e308 reached DART).
TEST(Yaml, NumbersBeyondTheMagnitudeCapAreRefusedWithTheirKey) {
  const core::YamlReader r("f.yaml");
  EXPECT_EQ(r.value(YAML::Load("1e9"), "k"), 1e9);
  EXPECT_EQ(r.value(YAML::Load("-2.5"), "k"), -2.5);
  for (const char* v : {"1e308", "-1e10", ".inf", ".nan"}) {
    try {
      r.value(YAML::Load(v), "a.b");
      ADD_FAILURE() << v << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("f.yaml: a.b: expected a ", 0), 0u) << e.what();
    }
  }
}

// Found by tests/fuzz/fuzz_robot: a list, map or null as a key threw yaml-cpp's
// TypedBadConversion out of the readers ("internal error").
TEST(Yaml, KeysThatAreNotPlainScalarsAreRefused) {
  for (const char* text : {"{[a]: 1}", "a:\n  {b: 1}: 2\n", "~: 1", "- {? [x, y]: 1}"}) {
    try {
      core::YamlReader::parse(text, "f.yaml");
      ADD_FAILURE() << text << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("expected a plain key"), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(core::YamlReader::parse("a: {b: 1, \"c d\": [1, 2]}\n", "f.yaml"));
}

// Issue 20: a folder given as a file was "no such file", and writing onto one said "(Success)".
TEST(Files, AFolderIsNamedAsSuchWhenReadOrWritten) {
  TempDir dir;
  auto message = [](auto fn) {
    try {
      fn();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message([&] { core::readFile(dir.path().string()); }),
            dir.path().string() + ": is a folder, not a file");
  EXPECT_EQ(message([&] { core::readFile(dir.file("missing")); }),
            dir.file("missing") + ": no such file");
  std::filesystem::create_directory(dir.path() / "out.json");
  EXPECT_EQ(message([&] { core::writeFileAtomic(dir.file("out.json"), "{}"); }),
            dir.file("out.json") + ": is a folder (give a file name)");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            1)
      << "a temporary file was left";
}

// What a library prints on stderr while captured comes back as one line, and stderr is
// restored afterwards.
TEST(StderrCapture, ReturnsWhatWasPrintedAsOneLine) {
  std::string text;
  {
    core::StderrCapture c;
    std::fprintf(stderr, "Error: first line\n  second\t\n\n");
    std::cerr << "third" << std::endl;
    EXPECT_EQ(::write(2, "fourth\n", 7), 7);
    text = c.text();
    EXPECT_EQ(c.text(), text);  // idempotent
  }
  EXPECT_EQ(text, "Error: first line; second; third; fourth");
  core::StderrCapture nothing;
  EXPECT_EQ(nothing.text(), "");
}

}  // namespace
}  // namespace overstep::core
