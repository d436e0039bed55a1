// `overstep report | monitor | export | spy` on a recorded run: a short standing plan replayed on
// the simulator by `overstep demo` inside the private network namespace of netns_run.sh, its bus
// recorded by lcm-logger. Every number the tools print is compared with what the log holds, read
// here by an independent parser of the LCM log format.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "run_cli.hpp"

namespace overstep {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// The LCM log format (lcm-logger): per event a big-endian header [sync 0xEDA1DA01, event number
/// int64, timestamp int64 (us), channel length int32, data length int32], the channel, the data.
struct RawEvent {
  std::int64_t offset = 0, timestamp = 0;
  std::string channel;
};

std::vector<RawEvent> parseLog(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string d((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto be = [&](std::size_t at, int n) {
    std::uint64_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 8) | static_cast<unsigned char>(d[at + i]);
    return v;
  };
  std::vector<RawEvent> out;
  std::size_t off = 0;
  while (off + 28 <= d.size() && be(off, 4) == 0xEDA1DA01u) {
    const auto cl = static_cast<std::size_t>(be(off + 20, 4)),
               dl = static_cast<std::size_t>(be(off + 24, 4));
    if (off + 28 + cl + dl > d.size()) break;
    out.push_back({static_cast<std::int64_t>(off), static_cast<std::int64_t>(be(off + 12, 8)),
                   d.substr(off + 28, cl)});
    off += 28 + cl + dl;
  }
  return out;
}

class MonitorCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!std::getenv("OVERSTEP_NETNS")) return;
    dir_ = new test::TempDir;
    const auto plan = test::runOverstep("plan --stand 1.5 --out " + dir_->file("stand.json"));
    ASSERT_EQ(plan.code, 0) << plan.err;
    // Not cleared (the robot stands), so exit 4; the run is what matters here.
    demo_ = test::runOverstep("demo --plan " + dir_->file("stand.json") +
                              " --obstacle-height 0.05 --no-report --json --timeout 60 --run-dir " +
                              dir_->file("run"));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  void SetUp() override {
    if (!std::getenv("OVERSTEP_NETNS")) GTEST_SKIP() << "run through netns_run.sh";
    ASSERT_TRUE(demo_.code == 0 || demo_.code == 4) << demo_.err;
    ASSERT_TRUE(fs::is_regular_file(run() / "bus.lcmlog"));
  }
  static fs::path run() { return dir_->path() / "run"; }
  static std::string log() { return (run() / "bus.lcmlog").string(); }

  static test::TempDir* dir_;
  static test::RunResult demo_;
};
test::TempDir* MonitorCli::dir_ = nullptr;
test::RunResult MonitorCli::demo_;

TEST_F(MonitorCli, ReportDrawsEveryFigureWithItsSeriesAndTimeRange) {
  const auto r = test::runOverstep("report " + run().string() + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json s = json::parse(r.out);
  const json man = json::parse(test::slurp(s["manifest"].get<std::string>()));
  const double duration = 1.5;
  // file -> (axes, series per axes; -1: Fz plan and measured, then the CoP deviation alone)
  const std::map<std::string, std::pair<int, int>> expected = {
      {"fig1_sequence.png", {8, 2}},  {"fig3_zmp.png", {2, 3}},     {"fig4_torso.png", {2, 2}},
      {"fig5_wrenches.png", {12, 2}}, {"fig6_joints.png", {12, 3}}, {"fig7_cop.png", {2, 2}},
      {"fig_fidelity.png", {4, -1}}};
  ASSERT_EQ(man["figures"].size(), expected.size());
  for (const auto& f : man["figures"]) {
    const std::string file = f["file"];
    ASSERT_TRUE(expected.count(file)) << file;
    const fs::path png = fs::path(s["out_dir"].get<std::string>()) / file;
    ASSERT_TRUE(fs::is_regular_file(png)) << file;
    EXPECT_EQ(test::slurp(png.string()).substr(1, 3), "PNG") << file;
    EXPECT_GT(fs::file_size(png), 10000u) << file;
    ASSERT_EQ(static_cast<int>(f["axes"].size()), expected.at(file).first) << file;
    for (const auto& ax : f["axes"]) {
      const bool cop_deviation = ax["title"].get<std::string>().find("CoP") != std::string::npos;
      const int series = expected.at(file).second >= 0 ? expected.at(file).second
                         : cop_deviation               ? 1
                                                       : 2;
      EXPECT_EQ(static_cast<int>(ax["series"].size()), series) << file << " " << ax["title"];
      if (file == "fig1_sequence.png" || file == "fig7_cop.png") continue;
      if (file == "fig_fidelity.png") {
        // The plan and the hold after it (the demo lingers 3 s).
        ASSERT_TRUE(ax["t_range"].is_array()) << file;
        EXPECT_LE(ax["t_range"][0].get<double>(), 0.006) << file;
        EXPECT_GT(ax["t_range"][1].get<double>(), duration + 1.0) << file;
        continue;
      }
      // Time series cover the executed plan: from its start to its end (one 5 ms tick).
      ASSERT_TRUE(ax["t_range"].is_array()) << file;
      EXPECT_LE(ax["t_range"][0].get<double>(), 0.006) << file;
      EXPECT_NEAR(ax["t_range"][1].get<double>(), duration, 0.006) << file;
    }
  }
  EXPECT_TRUE(fs::is_regular_file(s["index"].get<std::string>()));
  EXPECT_EQ(s["log_break_offset"], -1);
}

TEST_F(MonitorCli, MonitorOnceReportsTheRatesTheLogHas) {
  const auto r = test::runOverstep("monitor " + log() + " --once --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json snap = json::parse(r.out);
  std::map<std::string, std::vector<std::int64_t>> times;
  for (const auto& e : parseLog(log())) times[e.channel].push_back(e.timestamp);
  ASSERT_GE(times["OVERSTEP_STATE"].size(), 300u);
  for (const auto& [ch, ts] : times) {
    ASSERT_TRUE(snap["channels"].contains(ch)) << ch;
    const auto& c = snap["channels"][ch];
    EXPECT_EQ(c["count"].get<std::size_t>(), ts.size()) << ch;
    if (ts.size() < 2) continue;
    const double rate = static_cast<double>(ts.size() - 1) / ((ts.back() - ts.front()) * 1e-6);
    EXPECT_NEAR(c["rate_hz"].get<double>(), rate, 1e-9 * rate) << ch;
  }
  // By the robot's clock the simulator publishes its state at the control rate.
  EXPECT_NEAR(snap["channels"]["OVERSTEP_STATE"]["message_clock_rate_hz"].get<double>(), 200.0,
              1.0);
  EXPECT_EQ(snap["runtime"]["state"], "FINISHED");
  EXPECT_NEAR(snap["plan"]["progress"].get<double>(), 1.0, 1e-9);
  EXPECT_FALSE(snap["sim"]["fell"].get<bool>());
}

TEST_F(MonitorCli, ExportWritesEveryMessageAndStopsAtATruncation) {
  std::map<std::string, std::int64_t> counts;
  const auto events = parseLog(log());
  for (const auto& e : events) ++counts[e.channel];
  const auto r = test::runOverstep("export " + log() + " --csv " + dir_->file("csv") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json s = json::parse(r.out);
  for (const auto& [ch, n] : counts) {
    if (ch.rfind("OVERSTEP_", 0) != 0) continue;  // lcm-logger's own LCM_SELF_TEST etc.
    EXPECT_EQ(s["rows"][ch].get<std::int64_t>(), n) << ch;
    std::ifstream in(s["files"][ch].get<std::string>());
    std::string header;
    std::getline(in, header);
    EXPECT_NE(header.find("utime [us]"), std::string::npos) << ch;
  }
  // Cut the log in the middle of an event: everything before it is exported, the offset named.
  const std::size_t k = events.size() / 2;
  const std::string cut = dir_->file("cut.lcmlog");
  fs::copy_file(log(), cut, fs::copy_options::overwrite_existing);
  fs::resize_file(cut, static_cast<std::uintmax_t>(events[k].offset + 40));
  const auto t = test::runOverstep("export " + cut + " --csv " + dir_->file("csv_cut") + " --json");
  EXPECT_EQ(t.code, 2);
  EXPECT_NE(t.err.find("damaged at byte " + std::to_string(events[k].offset)), std::string::npos)
      << t.err;
  const json ts = json::parse(t.out);
  EXPECT_EQ(ts["events"].get<std::size_t>(), k);
  std::int64_t states = 0;
  for (std::size_t i = 0; i < k; ++i) states += events[i].channel == "OVERSTEP_STATE";
  EXPECT_EQ(ts["rows"]["OVERSTEP_STATE"].get<std::int64_t>(), states);
}

TEST_F(MonitorCli, SpyClassPathHoldsEveryTypeAndTheSpy) {
  const auto r = test::runOverstep("spy --print-classpath");
  ASSERT_EQ(r.code, 0) << r.err;
  std::string cp = r.out;
  while (!cp.empty() && (cp.back() == '\n' || cp.back() == ' ')) cp.pop_back();
  std::stringstream ss(cp);
  std::string jar;
  int jars = 0;
  while (std::getline(ss, jar, ':')) {
    EXPECT_TRUE(fs::is_regular_file(jar)) << jar;
    ++jars;
  }
  // lcm.jar, jchart2d (which brings the jars it needs through its manifest), our types (issue
  // 21: without jchart2d a double-click on a channel threw NoClassDefFoundError;
  // test_monitor_ui clicks it).
  EXPECT_EQ(jars, 3);
  // javap resolves each class through that class path, headlessly: the spy, the chart classes
  // its viewer draws with, our types.
  std::string classes =
      "lcm.spy.Spy info.monitorenter.gui.chart.ITrace2D info.monitorenter.gui.chart.Chart2D";
  for (const char* t :
       {"robot_command_t", "robot_state_t", "plan_reference_t", "stabilizer_status_t",
        "runtime_status_t", "replay_control_t", "sim_status_t"})
    classes += std::string(" overstep.") + t;
  const int code = std::system(("javap -cp '" + cp + "' " + classes + " >/dev/null").c_str());
  EXPECT_EQ(code, 0);
  // A jar missing where Debian puts them: one line naming it and its package, exit 5.
  const fs::path jars_dir = dir_->path() / "java";
  fs::create_directories(jars_dir);
  const auto none = test::runOverstep("spy --print-classpath --java-dir " + jars_dir.string());
  EXPECT_EQ(none.code, 5);
  EXPECT_NE(none.err.find((jars_dir / "lcm.jar").string() + ": missing"), std::string::npos)
      << none.err;
  EXPECT_EQ(std::count(none.err.begin(), none.err.end(), '\n'), 1) << none.err;
  fs::create_symlink("/usr/share/java/lcm.jar", jars_dir / "lcm.jar");
  const auto no_chart = test::runOverstep("spy --java-dir " + jars_dir.string());
  EXPECT_EQ(no_chart.code, 5);
  EXPECT_NE(no_chart.err.find("jchart2d.jar: missing"), std::string::npos) << no_chart.err;
  EXPECT_NE(no_chart.err.find("libjchart2d-java"), std::string::npos) << no_chart.err;
  EXPECT_EQ(std::count(no_chart.err.begin(), no_chart.err.end(), '\n'), 1) << no_chart.err;
  // A folder that cannot be on a class path.
  EXPECT_EQ(test::runOverstep("spy --print-classpath --java-dir /usr/share/java:/tmp").code, 2);
  // Without a display the spy cannot open its window: a clear error, exit 2.
  unsetenv("DISPLAY");
  const auto headless = test::runOverstep("spy");
  EXPECT_EQ(headless.code, 2);
  EXPECT_NE(headless.err.find("DISPLAY"), std::string::npos) << headless.err;
}

TEST_F(MonitorCli, LiveMonitorSeesTheSimulatorAtItsRate) {
  // The simulator in real time publishes its state at 200 Hz; the monitor listens for 1.5 s.
  test::ProcessGuard guard;
  const pid_t sim =
      guard.add(test::spawnOverstep("sim --realtime --no-obstacle --duration 6",
                                    dir_->file("live_sim.out"), dir_->file("live_sim.err")));
  usleep(2000000);  // the simulator settles the robot before it starts publishing
  const auto r = test::runOverstep("monitor --once --json --duration 1.5");
  ASSERT_EQ(r.code, 0) << r.err;
  const json snap = json::parse(r.out);
  ASSERT_TRUE(snap["channels"].contains("OVERSTEP_STATE")) << r.out;
  const auto& st = snap["channels"]["OVERSTEP_STATE"];
  EXPECT_EQ(st["type"], "robot_state_t");
  // Wall-clock pacing on a loaded 2-core machine: a wide band around 200 Hz.
  EXPECT_GT(st["window_rate_hz"].get<double>(), 150.0);
  EXPECT_LT(st["window_rate_hz"].get<double>(), 250.0);
  EXPECT_NEAR(st["message_clock_rate_hz"].get<double>(), 200.0, 1.0);
  EXPECT_LT(st["last_age_s"].get<double>(), 0.2);
  EXPECT_FALSE(snap["sim"].is_null());
  kill(sim, SIGINT);
  test::waitOverstep(sim, 10.0);
}

// Issue 20: `identify` and `report` took the plan of another run (exit 0, this log read against
// it). The recorded run replayed a 1.5 s standing plan; a 3 s one is refused by both, naming both.
TEST_F(MonitorCli, APlanThatDoesNotMatchTheLogIsRefused) {
  const std::string other = dir_->file("stand3.json");
  const auto p = test::runOverstep("plan --stand 3 --out " + other);
  ASSERT_EQ(p.code, 0) << p.err;
  const std::string why = "OVERSTEP_PLAN_REF is of a plan of 1.5 s, the plan lasts 3 s (" + other;
  const auto rep = test::runOverstep("report " + run().string() + " --plan " + other + " --out " +
                                     dir_->file("report_other"));
  EXPECT_EQ(rep.code, 2) << rep.err;
  EXPECT_NE(rep.err.find("error: " + log() + ": " + why), std::string::npos) << rep.err;
  const auto id = test::runOverstep("identify " + log() + " --plan " + other);
  EXPECT_EQ(id.code, 2) << id.err;
  EXPECT_NE(id.err.find("error: " + log() + ": " + why), std::string::npos) << id.err;
  EXPECT_EQ(std::count(id.err.begin(), id.err.end(), '\n'), 1) << id.err;
  // The plan that was replayed passes the same checks.
  const auto same = test::runOverstep("identify " + log() + " --plan " + dir_->file("stand.json"));
  EXPECT_EQ(same.err.find("OVERSTEP_PLAN_REF"), std::string::npos) << same.err;
}

TEST_F(MonitorCli, BadInputIsExitTwoWithOneLine) {
  for (const std::string& args : std::vector<std::string>{
           "monitor /nonexistent.lcmlog --once",
           "export /nonexistent.lcmlog --csv " + dir_->file("x"),
           "report " + dir_->file("nothing_here"), "monitor --interval 0 --once"}) {
    const auto r = test::runOverstep(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << "\n" << r.err;
  }
  // A run folder with a plan but a log without any executed tick.
  fs::create_directories(dir_->path() / "empty_run");
  fs::copy_file(run() / "plan.json", dir_->path() / "empty_run" / "plan.json",
                fs::copy_options::overwrite_existing);
  test::writeText(dir_->path() / "empty_run" / "bus.lcmlog", "");
  const auto r = test::runOverstep("report " + (dir_->path() / "empty_run").string());
  EXPECT_EQ(r.code, 2) << r.err;
}

}  // namespace
}  // namespace overstep
