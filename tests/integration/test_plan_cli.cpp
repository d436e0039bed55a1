// `overstep plan` / `overstep check` as a user runs them: bad input, impossible requests, and a
// small obstacle planned end to end and re-verified independently.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "run_cli.hpp"
#include "test_util.hpp"

namespace overstep {
namespace {

using test::RunResult;

RunResult run(const std::string& args) { return test::runOverstep(args); }

std::string lastLine(const std::string& s) {
  std::string t = s;
  while (!t.empty() && t.back() == '\n') t.pop_back();
  const auto pos = t.rfind('\n');
  return pos == std::string::npos ? t : t.substr(pos + 1);
}

TEST(PlanCli, BadInputIsExitTwoWithOneLine) {
  test::TempDir dir;
  const std::string out = " --out " + dir.file("p.json");
  for (const std::string args :
       {"plan --obstacle-height -0.2", "plan --obstacle-height tall", "plan --obstacle-width 0",
        "plan --obstacle-shape sphere", "plan --margin -1", "plan --robot /nonexistent.yaml",
        "plan --threads -2", "plan --excite 1", "plan --excite 5 --amplitude 3",
        "plan --excite 5 --stand 5", "plan --resample",
        // Issue 20: 0 was taken as "not given" and started a full solve.
        "plan --stand 0", "plan --excite 0", "plan --stand 0 --excite 0", "plan --stand -1"}) {
    const RunResult r = run(args + out);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_NE(lastLine(r.err).find("error"), std::string::npos) << args << ": " << r.err;
    EXPECT_LT(r.seconds, 60.0) << args << ": refused at once, not after a solve";
  }
  test::writeText(dir.path() / "bad.yaml", "cop_box: [1\n");
  const RunResult r = run("plan --config " + dir.file("bad.yaml") + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("malformed YAML"), std::string::npos) << r.err;
}

TEST(PlanCli, ImpossibleObstacleIsExitThreeAtOnce) {
  test::TempDir dir;
  const RunResult r = run("plan --obstacle-height 0.8 --out " + dir.file("p.json"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("beyond the swing foot's reach"), std::string::npos) << r.err;
  EXPECT_LT(r.seconds, 30.0);
  // A bar wider than the longest step (5 m, an obstacle 'width' is its extent along the walk).
  const RunResult w = run("plan --obstacle-width 5 --out " + dir.file("w.json"));
  EXPECT_EQ(w.code, 3) << w.err;
  EXPECT_NE(w.err.find("beyond step_length_max"), std::string::npos) << w.err;
  EXPECT_LT(w.seconds, 30.0);
  // A bar nearer the standing toes than the feet's capsules and the clearance allow.
  const RunResult g = run("plan --obstacle-gap 0.02 --out " + dir.file("g.json"));
  EXPECT_EQ(g.code, 3) << g.err;
  EXPECT_NE(g.err.find("under obstacle_clearance"), std::string::npos) << g.err;
  EXPECT_LT(g.seconds, 30.0);
}

TEST(CheckCli, BadPlanFilesAreExitTwo) {
  test::TempDir dir;
  EXPECT_EQ(run("check " + dir.file("missing.json")).code, 2);
  test::writeText(dir.path() / "garbage.json", "{\"format\": \"something else\"}");
  const RunResult r = run("check " + dir.file("garbage.json"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("format"), std::string::npos) << r.err;
}

// Issue 20: SIGTERM (a scheduler's stop, `timeout`) killed the planner and lost the best attempt
// that Ctrl-C keeps. Both signals, sent once the solve has begun: exit 130, the best attempt in
// <out>.failed.json marked "interrupted", nothing at <out>.
TEST(PlanCli, SigtermKeepsTheBestAttemptLikeSigint) {
  for (const int sig : {SIGTERM, SIGINT}) {
    SCOPED_TRACE(sig == SIGTERM ? "SIGTERM" : "SIGINT");
    test::TempDir dir;
    test::ProcessGuard guard;
    const pid_t pid = guard.add(
        test::spawnOverstep("plan --obstacle-height 0.05 --threads 1 --out " + dir.file("p.json"),
                            dir.file("out"), dir.file("err")));
    // The first line of the iteration table's preamble comes after the handlers are installed.
    const auto t0 = std::chrono::steady_clock::now();
    while (test::slurp(dir.file("out")).find("variables") == std::string::npos) {
      ASSERT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 120.0)
          << test::slurp(dir.file("err"));
      ASSERT_EQ(kill(pid, 0), 0) << "plan ended before the solve: " << test::slurp(dir.file("err"));
      usleep(20000);
    }
    ASSERT_EQ(kill(pid, sig), 0);
    const int code = test::waitOverstep(pid, 120.0);
    const std::string err = test::slurp(dir.file("err"));
    ASSERT_EQ(code, 130) << err;
    EXPECT_NE(
        lastLine(err).find("interrupted; best attempt written to " + dir.file("p.failed.json")),
        std::string::npos)
        << err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("p.json")));
    const auto plan = nlohmann::json::parse(test::slurp(dir.file("p.failed.json")));
    const auto& summary = plan.at("summary");
    EXPECT_EQ(summary.at("status"), "interrupted");
    EXPECT_FALSE(summary.at("x").empty());
  }
}

// Acceptance scenario of the planner issue and the pipeline end to end: a 5 cm bar with the
// default configuration (the seed's 1 cm CoP box), planned from scratch, must be valid and
// accepted by the independent 1 kHz check; the summary reports every key, the checker judges
// every family, and the stored solution re-samples to the same motion.
TEST(PlanCli, SmallObstaclePlansWithTheDefaultBoxAndPassesCheck) {
  test::TempDir dir;
  const std::string plan = dir.file("small.json");
  const RunResult r = run("plan --obstacle-height 0.05 --time-limit 600 --json --out " + plan);
  ASSERT_EQ(r.code, 0) << lastLine(r.err);
  const auto summary = nlohmann::json::parse(r.out);
  for (const char* key :
       {"status", "valid", "duration", "phase_durations", "step_length", "foot_spacing",
        "solve_time", "iterations", "objective_terms", "max_violation", "check", "file"})
    EXPECT_TRUE(summary.contains(key)) << key;
  EXPECT_TRUE(summary["valid"].get<bool>());
  {
    // The contact forces are continuous across every switch: a foot's normal force is zero at
    // its lift-off and at its touchdown, the instants where it leaves and joins the contacts
    // (the plan's first sample with a foot newly in contact, the last before it leaves).
    const auto file = nlohmann::json::parse(test::slurp(plan));
    const auto& s = file.at("samples");
    const auto& t = s.at("t");
    const auto& phases = file.at("phases");
    ASSERT_EQ(s.at("phase").size(), t.size());
    const char* wrench[2] = {"right_wrench", "left_wrench"};
    const char* contact[2] = {"right_contact", "left_contact"};
    auto fz = [&](int f, std::size_t i) { return s.at(wrench[f])[i][2].get<double>(); };
    const double weight = fz(0, 0) + fz(1, 0);  // standing still at the start
    int switches = 0;
    for (std::size_t p = 1; p < phases.size(); ++p)
      for (int f = 0; f < 2; ++f) {
        const bool before = phases[p - 1].at(contact[f]), after = phases[p].at(contact[f]);
        if (before == after) continue;
        // A touchdown: phase p's first sample; a lift-off: phase p - 1's last.
        std::size_t i = 0;
        while (i < t.size() && s.at("phase")[i].get<std::size_t>() < p) ++i;
        if (!after) --i;
        EXPECT_LT(std::abs(fz(f, i)), 0.02 * weight)
            << wrench[f] << (after ? " at its touchdown, t = " : " at its lift-off, t = ")
            << t[i].get<double>();
        ++switches;
      }
    EXPECT_EQ(switches, 4);
  }
  // The time split accounts for the whole solve, every part non-negative; the Jacobians and
  // NLopt's own work are each measured (their shares are benchmark figures, not asserted).
  ASSERT_TRUE(summary.contains("time_split"));
  double parts = 0.0;
  for (const char* part : {"derivatives", "evaluations", "nlopt", "restoration", "other"}) {
    const double v = summary["time_split"][part].get<double>();
    EXPECT_GE(v, -1e-6) << part;
    parts += v;
  }
  EXPECT_NEAR(parts, summary["solve_time"].get<double>(), 1e-6);
  for (const char* part : {"derivatives", "nlopt"}) {
    EXPECT_GT(summary["time_split"][part].get<double>(), 0.0) << part;
    EXPECT_LT(summary["time_split"][part].get<double>(), summary["solve_time"].get<double>())
        << part;
  }
  EXPECT_GT(summary["jacobians"].get<int>(), 0);
  const std::string written = summary["file"].get<std::string>();
  EXPECT_EQ(written, plan);
  // Both feet passed the bar: the right landed and the left landed beyond it.
  EXPECT_GT(summary["step_length"].get<double>(), 0.3);
  EXPECT_GT(summary["duration"].get<double>(), 2.0);
  EXPECT_EQ(summary["phase_durations"].size(), 5u);
  // The seed's eqs. (20)-(27) as 11 named terms, plus the double-support leg's regulariser.
  EXPECT_EQ(summary["objective_terms"].size(), 12u);
  for (const char* term : {"elastic_acc", "zmp_lipm", "time", "head", "torque_rate"})
    EXPECT_TRUE(summary["objective_terms"].contains(term)) << term;
  ASSERT_TRUE(summary.contains("x"));
  const RunResult c = run("check --json " + written);
  ASSERT_EQ(c.code, 0) << c.out;
  const auto report = nlohmann::json::parse(c.out);
  EXPECT_EQ(report["families"].size(), 12u);
  EXPECT_TRUE(report["valid"].get<bool>());
  // The check's trace: every family at every grid point.
  const RunResult t = run("check " + written + " --trace " + dir.file("trace.csv"));
  ASSERT_EQ(t.code, 0) << t.err;
  const std::string trace = test::slurp(dir.file("trace.csv"));
  EXPECT_EQ(std::count(trace.begin(), trace.end(), '\n'), report["grid_points"].get<int>() + 1);
  EXPECT_EQ(trace.rfind("t,cop [m],", 0), 0u) << trace.substr(0, 80);
  // Re-sampling the stored solution without solving reproduces the same motion.
  const RunResult re = run("plan --obstacle-height 0.05 --json --warm-start " + written +
                           " --resample --out " + dir.file("re.json"));
  ASSERT_EQ(re.code, 0) << lastLine(re.err);
  const auto again = nlohmann::json::parse(re.out);
  EXPECT_EQ(again["x"], summary["x"]);
  EXPECT_EQ(again["iterations"].get<int>(), 0);
  EXPECT_DOUBLE_EQ(again["duration"].get<double>(), summary["duration"].get<double>());
  // A warm re-plan for a model overlay (1.5 kg on the chest, the identification loop's case)
  // from the plan is valid for the overlay by the independent check, in a fraction of the
  // solve from scratch (a projection when the check takes the restored point, else the target
  // stage alone).
  const std::string overlay = dir.file("payload.yaml");
  test::writeText(overlay, "base: " + test::hrp2Yaml() +
                               "\npayload:\n  - {link: CHEST_LINK1, mass: 1.5, offset: "
                               "[0.05, 0.0, 0.10]}\n");
  const RunResult warm = run("plan --obstacle-height 0.05 --json --robot " + overlay +
                             " --warm-start " + written + " --out " + dir.file("warm.json"));
  ASSERT_EQ(warm.code, 0) << lastLine(warm.err);
  const auto replan = nlohmann::json::parse(warm.out);
  EXPECT_TRUE(replan["valid"].get<bool>());
  EXPECT_LT(replan["iterations"].get<int>(), summary["iterations"].get<int>() / 2);
  const RunResult wc = run("check --json --robot " + overlay + " " + dir.file("warm.json"));
  EXPECT_EQ(wc.code, 0) << wc.out;
  // A warm start from a plan of another configuration is refused.
  test::writeText(dir.path() / "other.yaml", "spline_intervals: [2, 5, 2, 5, 2]\n");
  const RunResult bad = run("plan --obstacle-height 0.05 --config " + dir.file("other.yaml") +
                            " --warm-start " + written + " --out " + dir.file("x.json"));
  EXPECT_EQ(bad.code, 2) << bad.err;
  // Also one whose vector has the same length but another layout (the bushing spans moved
  // between the single supports).
  test::writeText(dir.path() / "same_length.yaml", "flex_spline_intervals: [3, 11, 3, 13, 3]\n");
  const RunResult moved =
      run("plan --obstacle-height 0.05 --config " + dir.file("same_length.yaml") +
          " --warm-start " + written + " --out " + dir.file("y.json"));
  EXPECT_EQ(moved.code, 2) << moved.err;
  EXPECT_NE(moved.err.find("flex_spline_intervals"), std::string::npos) << moved.err;
}

}  // namespace
}  // namespace overstep
