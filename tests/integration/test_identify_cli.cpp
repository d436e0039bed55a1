// `overstep identify` on a recorded run: the excitation plan replayed by `overstep demo` on a
// simulator with an undeclared command delay (inside the private network namespace of
// netns_run.sh); bad input gives exit 2 with one line.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "run_cli.hpp"

namespace overstep {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class IdentifyCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::getenv("OVERSTEP_NETNS")) GTEST_SKIP() << "run through netns_run.sh";
  }
};

TEST_F(IdentifyCli, FindsAnUndeclaredCommandDelayInARecordedRun) {
  test::TempDir dir;
  const auto p = test::runOverstep("plan --excite 6 --out " + dir.file("excite.json"));
  ASSERT_EQ(p.code, 0) << p.err;
  test::writeText(dir.path() / "truth.yaml", "command:\n  delay: 0.02\n");
  const auto d = test::runOverstep("demo --plan " + dir.file("excite.json") +
                                   " --allow-invalid-plan --obstacle-height 0.05 --no-report "
                                   "--timeout 60 --truth " +
                                   dir.file("truth.yaml") + " --run-dir " + dir.file("run"));
  ASSERT_TRUE(d.code == 0 || d.code == 4) << d.err;
  const std::string log = dir.file("run") + "/bus.lcmlog";
  const auto r =
      test::runOverstep("identify " + log + " --plan " + dir.file("excite.json") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  for (const char* key : {"verdict", "effect", "parameters", "ci95", "runner_up", "error_before",
                          "error_after", "channels"})
    EXPECT_TRUE(j.contains(key)) << key;
  // Delay, first-order lag and viscous friction all shift the joints back in proportion to
  // their velocity: the documented confusable set on the joint-position channel.
  const std::string v = j["verdict"];
  ASSERT_TRUE(v == "identified" || v == "ambiguous") << r.out;
  bool named = j["effect"] == "command_delay";
  for (const auto& c : j["confusable"]) named = named || c == "command_delay";
  EXPECT_TRUE(named) << r.out;
  if (j["effect"] == "command_delay") {
    const double delay = j["parameters"]["delay"], ci = j["ci95"]["delay"];
    EXPECT_TRUE(std::abs(delay - 0.02) <= std::max(ci, 0.15 * 0.02)) << delay << " +- " << ci;
  }
  EXPECT_LT(j["error_after"].get<double>(), 0.3 * j["error_before"].get<double>());

  // The identified delay as a model overlay that every command loads as its robot, and the
  // residual figures.
  const std::string overlay = dir.file("identified.yaml");
  const auto o =
      test::runOverstep("identify " + log + " --plan " + dir.file("excite.json") + " --out " +
                        overlay + " --plots " + dir.file("plots") + " --json");
  ASSERT_EQ(o.code, 0) << o.err;
  const json oj = json::parse(o.out);
  EXPECT_EQ(oj["overlay"], overlay);
  const std::string text = test::slurp(overlay);
  EXPECT_NE(text.find("base: "), std::string::npos) << text;
  EXPECT_NE(text.find("command: {delay: "), std::string::npos) << text;
  const auto m = test::runOverstep("model --robot " + overlay + " --json");
  EXPECT_EQ(m.code, 0) << m.err;
  for (const char* f : {"fig_residuals.png", "fig_autocorr.png", "residuals.csv"})
    EXPECT_GT(std::filesystem::file_size(dir.path() / "plots" / f), 1000u) << f;
  // A plan for the base model is refused with the overlay (another robot: re-plan).
  const auto refused = test::runOverstep("identify " + log + " --plan " + dir.file("excite.json") +
                                         " --robot " + overlay);
  EXPECT_EQ(refused.code, 2) << refused.err;
}

TEST_F(IdentifyCli, BadInputIsExitTwoWithOneLine) {
  test::TempDir dir;
  ASSERT_EQ(test::runOverstep("plan --stand 1 --out " + dir.file("stand.json")).code, 0);
  test::writeText(dir.path() / "empty.lcmlog", "");
  for (const std::string& args : std::vector<std::string>{
           "identify /nonexistent.lcmlog --plan " + dir.file("stand.json"),
           "identify " + dir.file("empty.lcmlog") + " --plan " + dir.file("stand.json"),
           "identify " + dir.file("empty.lcmlog") + " --plan /nonexistent.json",
           "identify " + dir.file("empty.lcmlog") + " --plan " + dir.file("stand.json") +
               " --train 2"}) {
    const auto r = test::runOverstep(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << "\n" << r.err;
  }
}

}  // namespace
}  // namespace overstep
