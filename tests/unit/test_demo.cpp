// The demo library (demo/demo.hpp): the verdict from the children's reports, the plan-cache key,
// the private bus and child processes started without a shell.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "overstep/demo/demo.hpp"
#include "process.hpp"

namespace overstep::demo {
namespace {

using nlohmann::json;

RunReports clearedRun() {
  RunReports r;
  r.replay = {{"finished", true},
              {"executed_duration", 5.0},
              {"tracking_rms", 0.001},
              {"state", "finished"},
              {"fault", "none"}};
  r.sim = {{"fell", false},        {"obstacle_contact", false}, {"obstacle_x", {0.16, 0.27}},
           {"right_heel_x", 0.35}, {"left_heel_x", 0.36},       {"base_speed", 0.001}};
  r.plan_valid = true;
  r.plan_duration = 5.0;
  r.fidelity = {{"meets_targets", false}};
  return r;
}

TEST(DemoVerdict, ARunThatEndsStillWithBothHeelsPastTheBarIsCleared) {
  const json v = runVerdict(clearedRun());
  EXPECT_TRUE(v["cleared"].get<bool>()) << v.dump(1);
  EXPECT_EQ(v["fidelity"], clearedRun().fidelity);
  EXPECT_EQ(v["runtime_state"], "finished");
}

TEST(DemoVerdict, EachFailureAndEachMissingReportKeepsTheRunFromClearing) {
  auto notCleared = [](RunReports r, const char* why) {
    const json v = runVerdict(r);
    EXPECT_FALSE(v["cleared"].get<bool>()) << why << ": " << v.dump(1);
  };
  RunReports r = clearedRun();
  r.sim["fell"] = true;
  notCleared(r, "fell");
  r = clearedRun();
  r.sim["obstacle_contact"] = true;
  notCleared(r, "touched the bar");
  r = clearedRun();
  r.sim["left_heel_x"] = 0.2;
  notCleared(r, "a heel over the bar");
  r = clearedRun();
  r.sim["base_speed"] = 0.05;
  notCleared(r, "moving at the end");
  r = clearedRun();
  r.replay["finished"] = false;
  notCleared(r, "runtime held");
  for (const char* key : {"fell", "obstacle_contact", "obstacle_x", "right_heel_x", "base_speed"}) {
    r = clearedRun();
    r.sim.erase(key);
    notCleared(r, key);
  }
  r = clearedRun();
  r.sim["obstacle_x"] = "far";  // a wrong type: not cleared, no exception
  notCleared(r, "obstacle_x a string");
  r = clearedRun();
  r.replay = json::array();
  r.sim = nullptr;
  notCleared(r, "no reports");
}

TEST(DemoCacheKey, EveryInputChangesTheKeyAndTheSameInputsGiveTheSameKey) {
  const std::vector<std::string> bar = {"--obstacle-height", "0.2"};
  const std::string k = planCacheKey("abc", 3, "robot", "config", bar, "");
  EXPECT_EQ(k, planCacheKey("abc", 3, "robot", "config", bar, ""));
  EXPECT_EQ(k.size(), 16u);
  std::set<std::string> keys = {
      k, planCacheKey("abd", 3, "robot", "config", bar, ""),
      planCacheKey("abc", 4, "robot", "config", bar, ""),
      planCacheKey("abc", 3, "robot2", "config", bar, ""),
      planCacheKey("abc", 3, "robot", "config2", bar, ""),
      planCacheKey("abc", 3, "robot", "config", {"--obstacle-height", "0.21"}, ""),
      planCacheKey("abc", 3, "robot", "config", bar, "warm"),
      // the same bytes split differently between the parts
      planCacheKey("abc", 3, "robotc", "onfig", bar, "")};
  EXPECT_EQ(keys.size(), 8u);
}

/// A socket bound as liblcm's udpm binds (SO_REUSEADDR) to `port`.
int bindLikeLcm(int port) {
  const int s = socket(AF_INET, SOCK_DGRAM, 0);
  const int one = 1;
  setsockopt(s, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  EXPECT_EQ(bind(s, reinterpret_cast<const sockaddr*>(&a), sizeof a), 0);
  return s;
}

TEST(DemoPrivateBus, TwoDemosNeverShareAPortAndABoundPortIsSkipped) {
  // A range of its own (the suite's demo tests use the default one).
  const int first = 47700, last = 47703;
  const int held = bindLikeLcm(first);  // another LCM program on the first port
  {
    PrivateBus a(first, last), b(first, last);
    EXPECT_NE(a.port(), first);
    EXPECT_NE(b.port(), first);
    EXPECT_NE(a.port(), b.port());
    EXPECT_NE(a.url().find(":" + std::to_string(a.port()) + "?ttl=0"), std::string::npos);
    PrivateBus c(first, last);
    EXPECT_THROW(PrivateBus(first, last), std::runtime_error);  // all four taken
  }
  close(held);
  PrivateBus again(first, last);  // released by the others' destructors
  EXPECT_EQ(again.port(), first);
}

TEST(DemoProcess, ArgumentsReachTheChildVerbatimWithoutAShell) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("overstep-test-demo-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string arg = "a; touch '" + (dir / "x").string() + "' $(id) `id` \"q\" *";
  const std::string out = (dir / "out.txt").string();
  EXPECT_EQ(waitFor(spawn({"/bin/echo", arg}, out, ""), 10.0), 0);
  std::ifstream in(out);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), arg + "\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "x"));
  EXPECT_EQ(waitFor(spawn({"/bin/sh", "-c", "exit 7"}, "", ""), 10.0), 7);
  EXPECT_THROW(spawn({"/nonexistent/overstep-no-such-program"}, "", ""), std::runtime_error);
  const pid_t sleeper = spawn({"/bin/sleep", "30"}, "", "");
  EXPECT_EQ(waitFor(sleeper, 0.1), kTimedOut);
  EXPECT_EQ(stop(sleeper, SIGTERM, 5.0), -SIGTERM);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace overstep::demo
