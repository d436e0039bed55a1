#pragma once
/// \file
/// `overstep demo` as a library: plan (or reuse a cached plan), run the simulator, the replay
/// runtime and lcm-logger as child processes of this binary in lockstep on a private LCM bus,
/// record the bus into a run folder, and judge the run (verdict and execution fidelity).
/// The CLI (demo/app/demo_command.cpp) only parses options and prints.

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace overstep::demo {

struct DemoOptions {
  std::string robot, config, truth, run_root = "runs", run_dir, cache_dir, lcm_url, plan;
  /// The simulated robot's model when it differs from the controller's (--identify: the base
  /// model plus the truth, while the planner and the runtime use the identified overlay).
  std::string sim_robot;
  /// A plan whose solution starts the planner (--identify's re-plan starts from the plan it ran
  /// before, so that the second run is the same motion re-solved for the identified model).
  std::string warm_start;
  double height = 0.20, width = 0.11, gap = 0.03, margin = 0.0;
  std::string shape = "box";
  bool replan = false, allow_invalid = false, no_stabilizer = false, json = false;
  bool no_report = false, identify = false;
  bool sim_contact_log = false;  ///< the simulator writes RUN_DIR/sim_contacts.csv
  unsigned seed = 1;             ///< the simulator's sensor-noise seed
  double timeout = 120.0;        ///< s of wall time for the run (after planning)
  double plan_time_limit = 0.0;  ///< s, passed to overstep plan (0: its configuration's)
};

/// InputError (one line) for options out of range or files that do not exist.
void checkOptions(const DemoOptions& options);

/// One run into `run`: plan (or reuse), simulate, replay, record, verdict (also written to
/// run/verdict.json). InputError / InfeasibleError as `overstep plan` and `overstep check`.
nlohmann::json demoRun(const DemoOptions& options, const std::filesystem::path& run);

/// `--identify`: run; an identification experiment; identify; re-plan with the identified model;
/// run again. The before / experiment / identify / after summaries.
nlohmann::json identifyLoop(const DemoOptions& options, const std::filesystem::path& run);

/// The plan cache's key for these inputs: a fixed function (FNV-1a, stable across builds and
/// standard libraries) of the plan format, the planner's version (a digest of the sources that
/// shape a plan, planner::plannerVersion()), the robot and configuration texts, the obstacle
/// arguments and the warm start's text.
std::string planCacheKey(const std::string& planner_version, int plan_format,
                         const std::string& robot_text, const std::string& config_text,
                         const std::vector<std::string>& obstacle_args,
                         const std::string& warm_start_text);

/// What the run's processes reported, and the plan, to judge the run by.
struct RunReports {
  nlohmann::json replay;    ///< `overstep replay --json`
  nlohmann::json sim;       ///< `overstep sim --json`
  nlohmann::json fidelity;  ///< monitor::fidelityJson of the log (null: not computed)
  bool plan_valid = false;
  double plan_duration = 0.0;
  bool stabilizer = true;
};

/// The verdict: cleared when the runtime finished, the robot did not fall or touch the obstacle,
/// both heels are past it and the base is still (< 2 cm/s) at the end; missing fields count
/// against clearing. Pure function of the reports.
nlohmann::json runVerdict(const RunReports& reports);

/// A private LCM bus for one demo: a udpm port no other demo on this machine holds (a lock file
/// per port, held while this object lives) and no socket on this machine is bound to (probed).
class PrivateBus {
 public:
  /// Tries ports first..last; std::runtime_error when every one is taken.
  explicit PrivateBus(int first = 7700, int last = 7999);
  ~PrivateBus();
  PrivateBus(const PrivateBus&) = delete;
  PrivateBus& operator=(const PrivateBus&) = delete;
  int port() const { return port_; }
  std::string url() const;  ///< udpm://239.255.76.67:PORT?ttl=0

 private:
  int port_ = -1, lock_fd_ = -1;
};

}  // namespace overstep::demo
