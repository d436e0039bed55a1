// The `overstep` front end as a user runs it: exit codes, one-line errors, JSON output.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "run_cli.hpp"
#include "test_util.hpp"

namespace overstep {
namespace {

using test::RunResult;

RunResult run(const std::string& args) { return test::runOverstep(args); }

void expectOneLineError(const RunResult& r, int code, const std::string& fragment) {
  EXPECT_EQ(r.code, code) << r.err;
  EXPECT_NE(r.err.find(fragment), std::string::npos) << r.err;
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "not one line: " << r.err;
}

TEST(Cli, HelpListsModelWithExamples) {
  const RunResult r = run("--help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("model"), std::string::npos);
  EXPECT_NE(r.out.find("Examples"), std::string::npos);
  const RunResult m = run("model --help");
  EXPECT_EQ(m.code, 0);
  EXPECT_NE(m.out.find("--json"), std::string::npos);
}

TEST(Cli, ModelJsonReportsTheHrp2ClassModel) {
  const RunResult r = run("model --json --robot " + test::hrp2Yaml());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["dofs"], 40);
  EXPECT_EQ(j["actuated"], 30);
  EXPECT_EQ(j["elastic"], 4);
  EXPECT_GE(j["mass"].get<double>(), 56.0);
  EXPECT_LE(j["mass"].get<double>(), 59.0);
  EXPECT_GE(j["com"][2].get<double>(), 0.78);
  EXPECT_LE(j["com"][2].get<double>(), 0.84);
  // Sole centres on the ground, left foot on +y, 0.19 m + sole asymmetry apart.
  EXPECT_NEAR(j["feet"]["left"][2].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(j["feet"]["right"][2].get<double>(), 0.0, 1e-9);
  EXPECT_GT(j["feet"]["left"][1].get<double>(), 0.09);
  EXPECT_LT(j["feet"]["right"][1].get<double>(), -0.09);
  EXPECT_EQ(j["joints"].size(), 30u);
}

TEST(Cli, MissingRobotFileIsBadInput) {
  expectOneLineError(run("model --robot /nonexistent/robot.yaml"), 2, "no such file");
}

TEST(Cli, MalformedRobotYamlIsBadInput) {
  test::TempDir dir;
  test::writeText(dir.path() / "bad.yaml", "name: [unclosed\n");
  expectOneLineError(run("model --robot " + dir.file("bad.yaml")), 2, "malformed YAML");
}

TEST(Cli, NegativeStiffnessIsBadInput) {
  test::TempDir dir;
  test::writeText(dir.path() / "hrp2.urdf", test::slurp(test::hrp2Urdf()));
  test::writeText(dir.path() / "hrp2.yaml", test::replaceOnce(test::slurp(test::hrp2Yaml()),
                                                              "stiffness: 502", "stiffness: -502"));
  expectOneLineError(run("model --robot " + dir.file("hrp2.yaml")), 2, "expected >= 0");
}

TEST(Cli, UnknownSubcommandOrFlagIsBadInput) {
  expectOneLineError(run("fly"), 2, "error");
  expectOneLineError(run("model --frobnicate"), 2, "frobnicate");
}

}  // namespace
}  // namespace overstep
