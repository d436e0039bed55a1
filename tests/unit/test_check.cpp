// `overstep check` (planner::checkPlan) and the plan file: accepts a consistent plan, names the
// family a corruption breaks, refuses plans for another robot and plan files or grid rates it
// cannot check in full (issue 20); files round-trip exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>

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

// The planner's mesh refinement reads where a family crosses its tolerance: one instant per
// maximal run, its worst, from a traced report; nothing from an untraced one or for a family that
// holds.
TEST_F(Check, ViolationPeaksAreTheWorstInstantOfEachCrossing) {
  core::Plan p = *plan_;
  const auto& d = model_->description();
  const int a = d.actuatedIndex("RARM_JOINT3");
  const int row = model_->actuatedCoordinate(a);
  const double upper = d.actuated[static_cast<std::size_t>(a)].safeUpper();
  const int n = p.samples();
  const int peak[2] = {n / 4, (3 * n) / 4};
  for (int k = 0; k < n; ++k)
    for (int c : peak)
      if (std::abs(k - c) < 4) p.q(row, k) = upper + 0.05 - 0.01 * std::abs(k - c);
  const CheckReport traced = checkPlan(p, *model_, 1000.0, true);
  ASSERT_FALSE(traced.family("joint_limits")->ok());
  const std::vector<double> t = violationPeaks(traced, {"joint_limits"});
  ASSERT_EQ(t.size(), 2u);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(t[static_cast<std::size_t>(i)], p.t(peak[i]), 1.5e-3);
  EXPECT_TRUE(violationPeaks(traced, {"cop", "pelvis"}).empty());                // those hold
  EXPECT_TRUE(violationPeaks(checkPlan(p, *model_), {"joint_limits"}).empty());  // no trace
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
  for (int k = 0; k < p.samples(); ++k) {
    core::Wrench w = p.wrench(1, k);
    w.force.z() *= 0.5;
    p.setWrench(1, k, w);
  }
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

// A knee 3 rad past its limit, checked at a rate whose grid overflowed an int (5e9 Hz on this
// 0.5 s plan, 3e9 Hz on the 5.29 s default: a negative grid size, "VALID" after checking nothing)
// or that never ended (1e9 Hz): refused, as is any rate outside (0, 10 kHz].
TEST_F(Check, RatesOutsideTheGridCapAreRefusedNotPassed) {
  core::Plan p = *plan_;
  const auto& d = model_->description();
  const int knee = d.actuatedIndex("RLEG_JOINT3");
  p.q.row(model_->actuatedCoordinate(knee))
      .setConstant(d.actuated[static_cast<std::size_t>(knee)].upper + 3.0);
  for (double rate : {5e9, 3e9, 1e9, 2e4, 0.0, -1000.0, std::numeric_limits<double>::quiet_NaN(),
                      std::numeric_limits<double>::infinity()}) {
    try {
      const CheckReport r = checkPlan(p, *model_, rate);
      ADD_FAILURE() << "rate " << rate << ": checked " << r.grid_points << " points, valid "
                    << r.valid;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("check rate: expected a rate in (0, 10000] Hz"),
                std::string::npos)
          << e.what();
    }
  }
  const CheckReport r = checkPlan(p, *model_, 10000.0);  // the cap itself is checked in full
  EXPECT_EQ(r.grid_points, 5001);
  EXPECT_FALSE(r.family("joint_limits")->ok());
}

// The fixture plan written to a file with one edit of its text, then read: a one-line InputError
// naming the file and containing `expect`.
void expectPlanRefused(const core::Plan& plan, const std::function<std::string(std::string)>& edit,
                       const std::string& expect) {
  test::TempDir dir;
  core::savePlan(plan, dir.file("p.json"));
  test::writeText(dir.path() / "bad.json", edit(test::slurp(dir.file("p.json"))));
  try {
    core::loadPlan(dir.file("bad.json"));
    ADD_FAILURE() << "read a plan that should be refused with '" << expect << "'";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(dir.file("bad.json") + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(expect), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    EXPECT_LT(msg.size(), 300u) << msg;
  }
}

// The same with an edit of the parsed JSON.
void expectJsonRefused(const core::Plan& plan, const std::function<void(nlohmann::json&)>& edit,
                       const std::string& expect) {
  expectPlanRefused(
      plan,
      [&](const std::string& text) {
        nlohmann::json j = nlohmann::json::parse(text);
        edit(j);
        return j.dump();
      },
      expect);
}

TEST_F(Check, PlanFilesWithAnOddTimeAxisAreRefused) {
  using J = nlohmann::json;
  const auto times = [](J& j) -> J& { return j["samples"]["t"]; };
  // The last sample at 1e308 (the grid size overflowed), 1e6 s (the check never ended).
  expectJsonRefused(
      *plan_, [&](J& j) { times(j).back() = 1e308; },
      "samples.t[100]: expected samples at most 1 / rate = 0.005 s apart");
  expectJsonRefused(
      *plan_, [&](J& j) { times(j).back() = 1e6; }, "at most 1 / rate");
  // Every time and the rate scaled: evenly spaced, but 1000 s long.
  expectJsonRefused(
      *plan_,
      [&](J& j) {
        for (J& t : times(j)) t = t.get<double>() * 2000.0;
        j["rate"] = j["rate"].get<double>() / 2000.0;
      },
      "samples.t: expected a duration of at most 600 s, got 1000");
  expectJsonRefused(
      *plan_,
      [&](J& j) {
        for (J& t : times(j)) t = t.get<double>() + 1.0;
      },
      "samples.t[0]: expected 0, got 1");
  expectJsonRefused(
      *plan_,
      [&](J& j) {
        for (J& t : times(j)) t = t.get<double>() - 1.0;
      },
      "samples.t[0]: expected 0, got -1");
  expectJsonRefused(
      *plan_, [&](J& j) { times(j)[4] = times(j)[3]; },
      "samples.t[4]: expected increasing times, got 0.015 after 0.015");
  expectPlanRefused(
      *plan_, [](std::string s) { return test::replaceOnce(s, "\"t\":[0.0,", "\"t\":[1e999,"); },
      "not a valid JSON plan file (number overflow parsing '1e999')");
  expectJsonRefused(
      *plan_, [&](J& j) { j["rate"] = 1e9; },
      "rate: expected a rate in (0, 10000] Hz, got 1000000000");
}

TEST_F(Check, PlanFilesWithBadPhasesOrValuesAreRefused) {
  using J = nlohmann::json;
  for (const J& index : {J(0.7), J(true), J(4294967296u), J(-1), J("0")})
    expectJsonRefused(
        *plan_, [&](J& j) { j["samples"]["phase"][7] = index; },
        "samples.phase[7]: expected an integer in [0, 1), got " + index.dump());
  expectJsonRefused(
      *plan_, [](J& j) { j["phases"][0]["duration"] = -0.5; },
      "phases[0].duration: expected [0, 600] s, got -0.5");
  expectJsonRefused(
      *plan_, [](J& j) { j["phases"][0]["right_contact"] = "yes"; },
      "phases[0].right_contact: expected true or false, got \"yes\"");
  expectJsonRefused(
      *plan_, [](J& j) { j["samples"]["left_foot"][2] = {0, 0.1, 0, 0, 0, 0, 0}; },
      "samples.left_foot[2]: expected a unit quaternion, got norm 0");
  expectJsonRefused(
      *plan_, [](J& j) { j["obstacle"]["height"] = 0.0; },
      "obstacle height: expected a positive length");
  expectJsonRefused(
      *plan_, [](J& j) { j["obstacle"]["height"] = -0.2; },
      "obstacle height: expected a positive length");
  expectJsonRefused(
      *plan_, [](J& j) { j["obstacle"]["width"] = 1e20; },
      "obstacle width: expected a positive length in m (at most 100), got 1e+20");
  expectJsonRefused(
      *plan_, [](J& j) { j["obstacle"]["toes_x"] = 1e308; },
      "obstacle.toes_x: expected within +-100 m, got 1e+308");
  expectJsonRefused(
      *plan_, [](J& j) { j["samples"]["q"][5][0] = 1e308; },
      "samples.q[5]: expected numbers within +-1000, got 1e+308");
  expectJsonRefused(
      *plan_, [](J& j) { j["coordinates"][3] = 3; }, "coordinates: expected names, got 3");
}

// 60,000 nested brackets overflowed the stack in the JSON library: refused before parsing, also
// inside a string-free corner nobody reads, while brackets inside strings do not count.
TEST_F(Check, DeeplyNestedPlanFilesAreRefusedBeforeParsing) {
  const std::string deep = std::string(60000, '[') + std::string(60000, ']');
  expectPlanRefused(
      *plan_,
      [&](std::string s) {
        return test::replaceOnce(s, "\"config\":{", "\"config\":{\"x\":" + deep + ",");
      },
      "JSON nested deeper than 16 levels");
  expectPlanRefused(
      *plan_,
      [](std::string s) {
        return test::replaceOnce(s, "{",
                                 "{\"x\":" + std::string(17, '[') + std::string(17, ']') + ",");
      },
      "JSON nested deeper than 16 levels");
  test::TempDir dir;
  core::Plan p = *plan_;
  p.robot_name = std::string(100, '[') + "\"{";
  core::savePlan(p, dir.file("p.json"));
  EXPECT_EQ(core::loadPlan(dir.file("p.json")).robot_name, p.robot_name);
}

}  // namespace
}  // namespace overstep::planner
