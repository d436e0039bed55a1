// `overstep demo` end to end inside the private network namespace of netns_run.sh: plan a small
// bar, run the simulator and the runtime in lockstep, record the bus, write the verdict.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "run_cli.hpp"

namespace overstep {
namespace {

using nlohmann::json;

class DemoLcm : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::getenv("OVERSTEP_NETNS")) GTEST_SKIP() << "run through netns_run.sh";
  }
  // One plan cache for the suite: the small bar is planned once (about 30 s on 2 cores).
  static void SetUpTestSuite() { shared_ = std::make_unique<test::TempDir>(); }
  static void TearDownTestSuite() { shared_.reset(); }
  /// demo arguments for the 5 cm bar with the default options (1 cm CoP box), plans cached in
  /// the suite's folder.
  static std::string smallBar() {
    return "demo --obstacle-height 0.05 --plan-time-limit 300 --cache-dir " +
           shared_->file("cache");
  }
  static std::unique_ptr<test::TempDir> shared_;
};
std::unique_ptr<test::TempDir> DemoLcm::shared_;

// The pipeline on a 5 cm bar (a check-valid plan; the best attempt would be replayed otherwise,
// --allow-invalid-plan): the run must complete, record the bus, write a verdict consistent with
// the simulator's ground truth and meet the execution targets.
TEST_F(DemoLcm, SmallObstacleRunWritesAConsistentVerdict) {
  test::TempDir dir;
  const auto r = test::runOverstep(smallBar() + " --allow-invalid-plan --json --run-root " +
                                   dir.file("runs") + " --run-dir " + dir.file("run"));
  ASSERT_TRUE(r.code == 0 || r.code == 4) << r.err;
  const json v = json::parse(r.out, nullptr, false);
  ASSERT_TRUE(v.is_object()) << r.out;
  for (const char* key : {"cleared", "fell", "obstacle_contact", "duration", "tracking_rms",
                          "cop_max", "stabilizer_effort", "run_dir", "plan_valid"})
    EXPECT_TRUE(v.contains(key)) << key;
  EXPECT_EQ(v["cleared"].get<bool>(), r.code == 0);
  namespace fs = std::filesystem;
  const fs::path run = v["run_dir"].get<std::string>();
  for (const char* f : {"plan.json", "replay.json", "sim.json", "verdict.json", "bus.lcmlog"})
    EXPECT_TRUE(fs::is_regular_file(run / f)) << f;
  EXPECT_GT(fs::file_size(run / "bus.lcmlog"), 100000u) << "the bus was recorded";
  // The report is drawn at the end of the run.
  ASSERT_TRUE(v.contains("report") && v["report"].is_string()) << v.dump();
  EXPECT_TRUE(fs::is_regular_file(v["report"].get<std::string>()));
  EXPECT_TRUE(fs::is_regular_file(run / "report" / "fig5_wrenches.png"));
  // The verdict is the simulator's ground truth, not the runtime's opinion.
  const json s = json::parse(test::slurp((run / "sim.json").string()));
  EXPECT_EQ(v["fell"], s["fell"]);
  EXPECT_EQ(v["obstacle_contact"], s["obstacle_contact"]);
  if (v["cleared"].get<bool>()) {
    EXPECT_GT(s["right_heel_x"].get<double>(), s["obstacle_x"][1].get<double>());
    EXPECT_GT(s["left_heel_x"].get<double>(), s["obstacle_x"][1].get<double>());
  }
  // Execution fidelity (issue 19), from the recorded sensor readings, against the issue's
  // targets: no contact loss, touchdown load <= 1.3 x weight, CoP deviation p95 <= 15 mm and max
  // <= 30 mm, chatter <= 0.3 N m, pelvis within 10 mrad, static within 1 s. Measured on this
  // plan (seeds 1-3, right / left): loads 0.87 / 0.26-0.27, CoP p95 4.0-4.1 / 5.4-5.6 mm, max
  // 6.5-16.8 / 12.3-14.0 mm, pelvis 2.0-2.2 mrad, static at once (docs/benchmarks.md).
  ASSERT_TRUE(v.contains("fidelity")) << v.dump();
  const json& fid = v["fidelity"];
  for (const char* side : {"right", "left"}) {
    const json& f = fid["feet"][side];
    EXPECT_EQ(f["contact_losses"]["value"].get<double>(), 0.0) << side;
    EXPECT_LE(f["peak_touchdown_load"]["value"].get<double>(), 1.3) << side;
    EXPECT_LE(f["chatter_rms"]["value"].get<double>(), 0.3) << side;
    EXPECT_LE(f["cop_deviation_p95"]["value"].get<double>(), 0.015) << side;
    EXPECT_LE(f["cop_deviation_max"]["value"].get<double>(), 0.030) << side;
  }
  EXPECT_TRUE(fid["meets_targets"].get<bool>()) << fid.dump();
  EXPECT_LE(fid["pelvis_deviation_max"]["value"].get<double>(), 0.010);
  EXPECT_LE(fid["settling_time"]["value"].get<double>(), 1.0);
  // The plan steps over a 5 cm bar: replayed with another bar's options it is refused before
  // anything starts (without them, the simulated bar is the plan's).
  const std::string replay = "demo --no-report --run-root " + dir.file("runs2") + " --plan " +
                             (run / "plan.json").string();
  for (const std::string opt : {"--obstacle-height", "--obstacle-gap"}) {
    const auto bad = test::runOverstep(replay + " " + opt + " 0.25");
    EXPECT_EQ(bad.code, 2) << opt << "\n" << bad.err;
    EXPECT_NE(bad.err.find(opt + " differs from the plan's obstacle"), std::string::npos)
        << bad.err;
  }
  EXPECT_FALSE(fs::exists(dir.path() / "runs2")) << "refused before a run folder";
  // A second run with the same inputs reuses the cached plan: no planning.
  const auto again = test::runOverstep(smallBar() + " --allow-invalid-plan --json --timeout 60 " +
                                       "--run-root " + dir.file("runs"));
  EXPECT_NE(again.err.find("reusing"), std::string::npos) << again.err;
}

// The identification loop on the simulated robot with an undeclared 1.5 kg chest payload: the
// run before (the plan for the base model), the excitation, `overstep identify`, the re-plan for
// the identified overlay and the run after. The overlay must name the payload with its mass, the
// re-plan must be a valid plan for the overlay (and not for the base model), and the run after
// must track the plan better with less stabilizer correction (measured on this bar: tracking
// 0.92 -> 0.28 mrad, effort 0.0050 -> 0.0015; docs/identification.md). About 2.5 min on 2 cores.
TEST_F(DemoLcm, IdentifyLoopReducesTrackingErrorAndEffortWithAPayload) {
  test::TempDir dir;
  test::writeText(dir.path() / "payload.yaml",
                  "payload:\n  - {link: CHEST_LINK1, mass: 1.5, offset: [0.05, 0.0, 0.10]}\n");
  const auto r = test::runOverstep(smallBar() + " --truth " + dir.file("payload.yaml") +
                                   " --identify --no-report --json --run-root " + dir.file("runs") +
                                   " --run-dir " + dir.file("loop"));
  ASSERT_EQ(r.code, 0) << r.err;
  const json out = json::parse(r.out, nullptr, false);
  ASSERT_TRUE(out.is_object()) << r.out;
  const json& id = out["identify"];
  ASSERT_TRUE(id.is_object()) << out.dump(2);
  EXPECT_TRUE(id["verdict"] == "identified" || id["verdict"] == "ambiguous") << id.dump(2);
  EXPECT_EQ(id["effect"], "payload") << id.dump(2);
  const double mass = id["parameters"]["mass"].get<double>();
  EXPECT_TRUE(std::abs(mass - 1.5) <= std::max(id["ci95"]["mass"].get<double>(), 0.15 * 1.5))
      << mass;
  // The re-plan is a plan for the identified model.
  const std::string overlay = dir.file("loop/identified.yaml");
  const std::string after_plan = dir.file("loop/after/plan.json");
  ASSERT_TRUE(std::filesystem::is_regular_file(overlay));
  EXPECT_EQ(test::runOverstep("check " + after_plan + " --robot " + overlay).code, 0);
  EXPECT_EQ(test::runOverstep("check " + after_plan).code, 2) << "a plan for the base model?";
  const json &before = out["before"], &after = out["after"];
  ASSERT_TRUE(after.is_object()) << out.dump(2);
  // The run before executes a plan for the wrong model: it must step over the bar without a
  // fall or a touch, but it need not come to rest (a plan for the wrong model has left the base
  // moving at 4 cm/s 3 s after its end; docs/identification.md). The run after must clear
  // outright.
  for (const char* k : {"finished", "feet_beyond_obstacle"})
    EXPECT_TRUE(before[k].get<bool>()) << k;
  for (const char* k : {"fell", "obstacle_contact"}) EXPECT_FALSE(before[k].get<bool>()) << k;
  EXPECT_TRUE(after["cleared"].get<bool>());
  EXPECT_TRUE(after["plan_valid"].get<bool>());
  for (const char* k : {"tracking_rms", "stabilizer_effort"}) {
    EXPECT_LT(after[k].get<double>(), 0.95 * before[k].get<double>())
        << k << ": before " << before[k] << ", after " << after[k];
    EXPECT_EQ(out["change"][k][0], before[k]);
    EXPECT_EQ(out["change"][k][1], after[k]);
  }
  EXPECT_TRUE(std::filesystem::is_regular_file(dir.file("loop/identify_loop.json")));
}

TEST_F(DemoLcm, BadInputIsExitTwo) {
  for (const char* args : {"demo --obstacle-height -1", "demo --robot /nonexistent.yaml",
                           "demo --truth /nonexistent.yaml", "demo --timeout 0",
                           "demo --identify --plan /nonexistent.json",
                           "demo --sim-robot /nonexistent.yaml", "demo --seed x"}) {
    const auto r = test::runOverstep(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
  }
  // A robot file whose stabilizer section the runtime would refuse (a gain out of its range):
  // exit 2 naming the key, before anything is planned or started.
  namespace fs = std::filesystem;
  test::TempDir dir;
  const std::string text = test::slurp(test::hrp2Yaml());
  const std::string key = "  damping_roll:";
  const std::size_t at = text.find(key);
  ASSERT_NE(at, std::string::npos);
  const std::size_t eol = text.find('\n', at);
  const fs::path robot = dir.file("hrp2.yaml");
  test::writeText(robot, text.substr(0, at) + key + " 0.0" + text.substr(eol));
  fs::copy_file(fs::path(test::hrp2Yaml()).parent_path() / "hrp2.urdf", dir.file("hrp2.urdf"));
  const auto r = test::runOverstep(
      "demo --obstacle-height 0.05 --plan-time-limit 1 --allow-invalid-plan --no-report --robot " +
      robot.string() + " --cache-dir " + dir.file("cache") + " --run-root " + dir.file("runs"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("damping_roll"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace overstep
