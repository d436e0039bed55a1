// `overstep check` (planner::checkPlan) and the plan file: accepts a consistent plan, names the
// family a corruption breaks, refuses plans for another robot; files round-trip exactly.
#include <gtest/gtest.h>

#include <algorithm>

#include "overstep/core/error.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/planner/check.hpp"
#include "plan_fixtures.hpp"
#include "test_util.hpp"

namespace overstep::planner {
namespace {

class Check : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    model_ = new robots::WholeBodyModel(robots::WholeBodyModel::fromFile(test::hrp2Yaml()));
    plan_ = new core::Plan(test::standingPlan(*model_));
  }
  static void TearDownTestSuite() {
    delete plan_;
    delete model_;
  }
  static std::vector<std::string> violated(const CheckReport& r) {
    std::vector<std::string> out;
    for (const auto& f : r.families)
      if (!f.ok()) out.push_back(f.name);
    return out;
  }
  static robots::WholeBodyModel* model_;
  static core::Plan* plan_;
};
robots::WholeBodyModel* Check::model_ = nullptr;
core::Plan* Check::plan_ = nullptr;

TEST_F(Check, AcceptsAStaticallyConsistentStandingPlan) {
  const CheckReport r = checkPlan(*plan_, *model_);
  EXPECT_TRUE(r.valid) << ::testing::PrintToString(violated(r));
  EXPECT_EQ(r.grid_points, 501);
  ASSERT_NE(r.family("dynamics"), nullptr);
  EXPECT_LT(r.family("dynamics")->worst, 0.5);  // N / N m
  EXPECT_LT(r.family("cop")->worst, 0.0);       // strictly inside the 1 cm box
}

TEST_F(Check, JointPushedPastItsLimitIsNamed) {
  core::Plan p = *plan_;
  const auto& d = model_->description();
  const int a = d.actuatedIndex("RARM_JOINT3");  // elbow: moves no contact
  p.q.row(model_->actuatedCoordinate(a))
      .setConstant(d.actuated[static_cast<std::size_t>(a)].upper + 0.05);
  const CheckReport r = checkPlan(p, *model_);
  EXPECT_FALSE(r.valid);
  EXPECT_FALSE(r.family("joint_limits")->ok());
  EXPECT_EQ(r.family("joint_limits")->detail, "RARM_JOINT3");
}

TEST_F(Check, FootInsideTheObstacleIsNamed) {
  core::Plan p = *plan_;
  p.toes_x = -0.3;  // the bar now lies under the feet
  p.obstacle.gap = 0.2;
  const CheckReport r = checkPlan(p, *model_);
  EXPECT_FALSE(r.valid);
  EXPECT_FALSE(r.family("obstacle")->ok());
  EXPECT_NE(r.family("obstacle")->detail.find("LEG"), std::string::npos);
}

TEST_F(Check, PassiveCoordinateOffItsDynamicsIsNamed) {
  core::Plan p = *plan_;
  const int e = model_->elasticCoordinate(1);  // right ankle pitch bushing
  p.q.row(e).array() += 0.03;                  // 15 N m of spring torque nobody balances
  const CheckReport r = checkPlan(p, *model_);
  EXPECT_FALSE(r.valid);
  EXPECT_FALSE(r.family("dynamics")->ok());
  EXPECT_GT(r.family("dynamics")->worst, 10.0);
}

TEST_F(Check, WrenchesThatDoNotCarryTheWeightAreNamed) {
  core::Plan p = *plan_;
  p.left_wrench.row(5) *= 0.5;
  const CheckReport r = checkPlan(p, *model_);
  EXPECT_FALSE(r.family("dynamics")->ok());
  EXPECT_EQ(r.family("dynamics")->detail, "base force");
}

TEST(CheckTorques, AKneeOverloadedInContactIsNamedThoughItsHangingTorqueIsSmall) {
  // The same robot with 20 N m knees: standing on both feet, each knee carries about half the
  // weight on the shank's lever (~35 N m); the leg hanging from the pelvis needs ~2 N m. The
  // check must judge the torque of the robot in contact.
  test::TempDir dir;
  std::string yaml = test::slurp(test::hrp2Yaml());
  for (const char* knee : {"RLEG_JOINT3", "LLEG_JOINT3"}) {
    const std::string from = std::string(knee) + ", limits_deg: [-2, 150], safety_margin_deg: 5, " +
                             "velocity: 3.98, torque: 168";
    yaml = test::replaceOnce(yaml, from,
                             std::string(knee) + ", limits_deg: [-2, 150], safety_margin_deg: " +
                                 "5, velocity: 3.98, torque: 20");
  }
  test::writeText(dir.path() / "hrp2.yaml", yaml);
  test::writeText(dir.path() / "hrp2.urdf", test::slurp(test::hrp2Urdf()));
  robots::WholeBodyModel m = robots::WholeBodyModel::fromFile(dir.file("hrp2.yaml"));
  const core::Plan p = test::standingPlan(m);
  const auto& d = m.description();
  m.setState(p.q.col(0), p.v.col(0), p.a.col(0));
  const Eigen::VectorXd hanging = m.inverseDynamics();
  for (const char* knee : {"RLEG_JOINT3", "LLEG_JOINT3"}) {
    const int a = d.actuatedIndex(knee);
    EXPECT_LT(std::abs(hanging(m.actuatedCoordinate(a))), 5.0) << knee;
    EXPECT_GT(std::abs(p.tau(a, 0)), 25.0)
        << knee << ": the plan file's torque is the physical one";
  }
  const CheckReport r = checkPlan(p, m);
  EXPECT_FALSE(r.valid);
  ASSERT_FALSE(r.family("torque")->ok());
  EXPECT_NE(r.family("torque")->detail.find("LEG_JOINT3"), std::string::npos)
      << r.family("torque")->detail;
  EXPECT_GT(r.family("torque")->worst, 0.5);  // > 150 % of the 20 N m limit
}

TEST_F(Check, RefusesAPlanForAnotherRobot) {
  core::Plan p = *plan_;
  p.robot_hash = "0123456789abcdef";
  EXPECT_THROW(checkPlan(p, *model_), InputError);
}

TEST_F(Check, PlanFileRoundTripsExactly) {
  test::TempDir dir;
  core::savePlan(*plan_, dir.file("p.json"));
  const core::Plan back = core::loadPlan(dir.file("p.json"));
  EXPECT_EQ(back.q, plan_->q);
  EXPECT_EQ(back.right_wrench, plan_->right_wrench);
  EXPECT_EQ(back.t, plan_->t);
  EXPECT_EQ(back.robot_hash, plan_->robot_hash);
  EXPECT_EQ(back.coordinates, plan_->coordinates);
  EXPECT_EQ(back.phases.size(), 1u);
  // No temporary file is left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 1);
}

TEST_F(Check, CorruptPlanFilesAreBadInput) {
  test::TempDir dir;
  core::savePlan(*plan_, dir.file("p.json"));
  const std::string text = test::slurp(dir.file("p.json"));
  test::writeText(dir.path() / "trunc.json", text.substr(0, text.size() / 2));
  EXPECT_THROW(core::loadPlan(dir.file("trunc.json")), InputError);
  test::writeText(dir.path() / "ver.json",
                  test::replaceOnce(text, "\"version\":2", "\"version\":9"));
  EXPECT_THROW(core::loadPlan(dir.file("ver.json")), InputError);
  // Version 1 files hold the torques of a robot hanging from its pelvis: refused, saying why.
  test::writeText(dir.path() / "v1.json",
                  test::replaceOnce(text, "\"version\":2", "\"version\":1"));
  try {
    core::loadPlan(dir.file("v1.json"));
    ADD_FAILURE() << "a version 1 plan was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("contact forces"), std::string::npos) << e.what();
  }
  test::writeText(dir.path() / "big.json",
                  test::replaceOnce(text, "\"version\":2", "\"version\":4294967298"));
  EXPECT_THROW(core::loadPlan(dir.file("big.json")), InputError);  // not read modulo 2^32
  test::writeText(dir.path() / "nan.json",
                  test::replaceOnce(text, "\"rate\":200.0", "\"rate\":-1"));
  EXPECT_THROW(core::loadPlan(dir.file("nan.json")), InputError);
  EXPECT_THROW(core::loadPlan(dir.file("missing.json")), InputError);
}

}  // namespace
}  // namespace overstep::planner
