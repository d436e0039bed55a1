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
                  test::replaceOnce(text, "\"version\":1", "\"version\":9"));
  EXPECT_THROW(core::loadPlan(dir.file("ver.json")), InputError);
  test::writeText(dir.path() / "nan.json",
                  test::replaceOnce(text, "\"rate\":200.0", "\"rate\":-1"));
  EXPECT_THROW(core::loadPlan(dir.file("nan.json")), InputError);
  EXPECT_THROW(core::loadPlan(dir.file("missing.json")), InputError);
}

}  // namespace
}  // namespace overstep::planner
