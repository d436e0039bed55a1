// `overstep demo` as a library (demo/demo.hpp): plan or reuse, then the simulator, the runtime
// and lcm-logger as child processes (this binary, started without a shell) in lockstep on a
// private bus, the run recorded, judged from the children's summaries and the log.
#include "overstep/demo/demo.hpp"

#include <signal.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "overstep/cli/lcm_url.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/json_depth.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/core/robot_description.hpp"
#include "overstep/monitor/fidelity.hpp"
#include "overstep/planner/version.hpp"
#include "overstep/stabilizer/params.hpp"
#include "process.hpp"

namespace overstep::demo {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string hex(std::uint64_t h) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

/// The fidelity figures of a recorded run; null (with the reason on stderr) when its log cannot
/// give them (e.g. a standing plan's run without executed ticks).
json fidelityOfRun(const fs::path& run, const std::string& robot) {
  try {
    const monitor::RunSeries series =
        monitor::runSeries((run / "plan.json").string(), (run / "bus.lcmlog").string(), robot);
    return monitor::fidelityJson(monitor::computeFidelity(series));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "demo: no fidelity figures: %s\n", e.what());
    return nullptr;
  }
}

/// A JSON file written by a child command (its summary); discarded when unreadable or nested
/// deeper than any of ours (parsing recurses).
json readJson(const fs::path& p) {
  const std::string text = readAll(p);
  constexpr int kMaxDepth = 32;
  if (core::jsonDepth(text, kMaxDepth) > kMaxDepth) return json(json::value_t::discarded);
  return json::parse(text, nullptr, false);
}

/// The last non-empty line of a child's log (its one-line error, when it failed on its input).
std::string lastLine(const fs::path& p) {
  const std::string text = readAll(p);
  std::size_t end = text.find_last_not_of("\r\n");
  if (end == std::string::npos) return "";
  const std::size_t newline = text.rfind('\n', end);
  const std::size_t begin = newline == std::string::npos ? 0 : newline + 1;
  return text.substr(begin, end + 1 - begin);
}

}  // namespace

json demoRun(const DemoOptions& o, const fs::path& run) {
  // The runtime reads the robot file's stabilizer section: a gain out of its range is refused
  // here, before anything is planned or started.
  (void)stabilizer::loadParams(o.robot);
  const std::string exe = selfExe();
  const fs::path cache =
      o.cache_dir.empty() ? fs::path(o.run_root) / "cache" : fs::path(o.cache_dir);
  std::error_code ec;
  fs::create_directories(run, ec);
  if (ec) throw InputError("cannot create run folder " + run.string() + ": " + ec.message());
  fs::create_directories(cache, ec);
  if (ec) throw InputError("cannot create cache folder " + cache.string() + ": " + ec.message());

  // ---- 1. plan (cached on every input that shapes it)
  std::vector<std::string> obstacle_args = {"--obstacle-height", std::to_string(o.height),
                                            "--obstacle-width",  std::to_string(o.width),
                                            "--obstacle-shape",  o.shape,
                                            "--obstacle-gap",    std::to_string(o.gap),
                                            "--margin",          std::to_string(o.margin)};
  const std::string key =
      planCacheKey(planner::plannerVersion(), core::Plan::kFormatVersion, readAll(o.robot),
                   o.config.empty() ? "" : readAll(o.config), obstacle_args,
                   o.warm_start.empty() ? "" : readAll(o.warm_start));
  const fs::path plan_file = cache / ("plan-" + key + ".json");
  const fs::path failed_file = cache / ("plan-" + key + ".failed.json");
  bool plan_valid = false;
  fs::path plan_used;
  if (!o.plan.empty()) {
    // A given plan: its validity is what the independent check says.
    if (!fs::is_regular_file(o.plan)) throw InputError("plan file not found: " + o.plan);
    const int code =
        waitFor(spawn({exe, "check", o.plan, "--robot", o.robot, "--json"},
                      (run / "plan_check.json").string(), (run / "plan_check.log").string()),
                -1);
    if (code == kExitBadInput)
      throw InputError(o.plan + ": not a plan for this robot (see " +
                       (run / "plan_check.log").string() + ")");
    plan_valid = code == kExitOk;
    if (!plan_valid && !o.allow_invalid)
      throw InfeasibleError(o.plan +
                            ": overstep check rejects it (replay it anyway with "
                            "--allow-invalid-plan)");
    plan_used = o.plan;
  } else if (!o.replan && fs::is_regular_file(plan_file)) {
    std::fprintf(stderr, "demo: reusing the plan cached for these inputs: %s\n", plan_file.c_str());
    plan_valid = true;
    plan_used = plan_file;
  } else if (!o.replan && o.allow_invalid && fs::is_regular_file(failed_file)) {
    std::fprintf(stderr, "demo: reusing the invalid plan cached for these inputs: %s\n",
                 failed_file.c_str());
    plan_used = failed_file;
  } else {
    std::vector<std::string> argv = {
        exe, "plan", "--robot", o.robot, "--out", plan_file.string(), "--json"};
    if (!o.config.empty()) argv.insert(argv.end(), {"--config", o.config});
    if (o.plan_time_limit > 0.0)
      argv.insert(argv.end(), {"--time-limit", std::to_string(o.plan_time_limit)});
    argv.insert(argv.end(), obstacle_args.begin(), obstacle_args.end());
    if (!o.warm_start.empty()) argv.insert(argv.end(), {"--warm-start", o.warm_start});
    std::fprintf(stderr, "demo: planning (the plan is cached in %s)\n", cache.c_str());
    const int code = waitFor(spawn(argv, (run / "plan_summary.json").string(), ""), -1);
    if (code == kExitOk) {
      plan_valid = true;
      plan_used = plan_file;
    } else if (code == kExitInfeasible && o.allow_invalid && fs::is_regular_file(failed_file)) {
      std::fprintf(stderr,
                   "demo: no valid plan; replaying the best attempt (--allow-invalid-plan)\n");
      plan_used = failed_file;
    } else if (code == kExitInfeasible) {
      throw InfeasibleError("no valid plan for this obstacle (best attempt " +
                            failed_file.string() + "; replay it anyway with --allow-invalid-plan)");
    } else if (code == kExitBadInput) {
      throw InputError("the planner refused the inputs (see its message above)");
    } else {
      throw std::runtime_error("the planner failed with exit code " + std::to_string(code));
    }
  }
  fs::copy_file(plan_used, run / "plan.json", fs::copy_options::overwrite_existing, ec);
  const core::Plan plan = core::loadPlan((run / "plan.json").string());

  // ---- 2. simulator, runtime and logger on a private LCM port
  // A bus no other demo on this machine uses (held until this run ends).
  std::optional<PrivateBus> bus;
  if (o.lcm_url.empty()) bus.emplace();
  const std::string url = bus ? bus->url() : o.lcm_url;
  setenv("LCM_DEFAULT_URL", url.c_str(), 1);
  const pid_t logger =
      spawn({"lcm-logger", "-q", "-f", "--lcm-url=" + url, (run / "bus.lcmlog").string()}, "",
            (run / "logger.err").string());
  std::vector<std::string> replay_argv = {exe,        "replay",  (run / "plan.json").string(),
                                          "--robot",  o.robot,   "--clock",
                                          "lockstep", "--start", "--json",
                                          "--linger", "3.0",     "--lcm-url",
                                          url};
  if (o.no_stabilizer) replay_argv.push_back("--no-stabilizer");
  const pid_t replay =
      spawn(replay_argv, (run / "replay.json").string(), (run / "replay.log").string());
  std::vector<std::string> sim_argv = {
      exe,      "sim",       "--lockstep", "--robot", o.sim_robot.empty() ? o.robot : o.sim_robot,
      "--json", "--lcm-url", url,          "--seed",  std::to_string(o.seed)};
  // The simulated bar is the envelope itself: --margin is extra clearance for the planner only
  // (the last two obstacle arguments).
  sim_argv.insert(sim_argv.end(), obstacle_args.begin(), obstacle_args.end() - 2);
  if (!o.truth.empty()) sim_argv.insert(sim_argv.end(), {"--truth", o.truth});
  if (o.sim_contact_log)
    sim_argv.insert(sim_argv.end(), {"--contact-log", (run / "sim_contacts.csv").string()});
  const pid_t sim = spawn(sim_argv, (run / "sim.json").string(), (run / "sim.log").string());
  std::fprintf(stderr, "demo: simulator and runtime running in lockstep on %s; run folder %s\n",
               url.c_str(), run.c_str());
  const auto t0 = std::chrono::steady_clock::now();
  int replay_code = waitFor(replay, o.timeout);
  if (replay_code == kTimedOut) replay_code = stop(replay, SIGINT, 5.0);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const int sim_code = stop(sim, SIGTERM, 10.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  stop(logger, SIGINT, 5.0);

  // A child that refused its input (e.g. a stabilizer gain out of its range in --robot) names it.
  if (replay_code == kExitBadInput)
    throw InputError("the runtime refused the inputs: " + lastLine(run / "replay.log"));
  if (sim_code == kExitBadInput)
    throw InputError("the simulator refused the inputs: " + lastLine(run / "sim.log"));

  // ---- 3. verdict and execution fidelity (from the recorded log, as `overstep report`)
  RunReports reports;
  reports.replay = readJson(run / "replay.json");
  reports.sim = readJson(run / "sim.json");
  if (!reports.replay.is_object() || !reports.sim.is_object())
    throw std::runtime_error("the runtime or the simulator left no summary (see " +
                             (run / "replay.log").string() + " and sim.log)");
  reports.plan_valid = plan_valid;
  reports.plan_duration = plan.duration();
  reports.stabilizer = !o.no_stabilizer;
  reports.fidelity = fidelityOfRun(run, o.robot);
  json v = runVerdict(reports);
  v["obstacle"] = {{"height", o.height},
                   {"width", o.width},
                   {"shape", o.shape},
                   {"gap", o.gap},
                   {"margin", o.margin}};
  v["truth"] = o.truth;
  v["run_dir"] = run.string();
  v["wall_time"] = wall;
  v["exit_codes"] = {{"replay", replay_code}, {"sim", sim_code}};
  if (!o.no_report) {
    // The figures (overstep report), whose page opens with this verdict (read from the run
    // folder: written first, then again with the report's path); a failure there is reported but
    // does not change the verdict.
    core::writeFileAtomic((run / "verdict.json").string(), v.dump(2) + "\n");
    const int code =
        waitFor(spawn({exe, "report", run.string(), "--robot", o.robot, "--json"},
                      (run / "report_summary.json").string(), (run / "report.log").string()),
                -1);
    if (code == kExitOk) {
      v["report"] = (run / "report" / "index.html").string();
    } else {
      v["report"] = nullptr;
      std::fprintf(stderr, "demo: the report failed (exit %d, see %s)\n", code,
                   (run / "report.log").c_str());
    }
  }
  core::writeFileAtomic((run / "verdict.json").string(), v.dump(2) + "\n");
  return v;
}

/// `--identify`: run with the model as it is; an identification experiment on the same simulated
/// robot (overstep plan --excite: standing, chest, head and arms swinging); identify the effect
/// from its log (a model overlay in the run folder); re-plan with the identified model and run
/// again; before and after.
json identifyLoop(const DemoOptions& o, const fs::path& run) {
  const std::string exe = selfExe();
  std::fprintf(stderr, "demo --identify: 1/4 run with the model as it is\n");
  const json before = demoRun(o, run / "before");
  std::fprintf(stderr, "demo --identify: 2/4 identification experiment (8 s, standing)\n");
  const fs::path ex = run / "experiment";
  std::error_code ec;
  fs::create_directories(ex, ec);
  if (waitFor(spawn({exe, "plan", "--excite", "8", "--robot", o.robot, "--out",
                     (ex / "excite.json").string()},
                    (ex / "plan.log").string(), (ex / "plan.err").string()),
              -1) != kExitOk)
    throw std::runtime_error("the excitation plan failed (see " + (ex / "plan.err").string() + ")");
  DemoOptions oe = o;
  oe.seed = o.seed + 1;  // another run: its own sensor noise
  oe.plan = (ex / "excite.json").string();
  oe.allow_invalid = true;  // a quasi-static split of the wrenches: overstep check rejects it
  oe.no_report = true;
  const json experiment = demoRun(oe, ex);
  const fs::path overlay = run / "identified.yaml";
  std::fprintf(stderr, "demo --identify: 3/4 identify from %s\n", (ex / "bus.lcmlog").c_str());
  const int code = waitFor(
      spawn({exe, "identify", (ex / "bus.lcmlog").string(), "--plan", (ex / "plan.json").string(),
             "--robot", o.robot, "--out", overlay.string(), "--json"},
            (run / "identify.json").string(), (run / "identify.log").string()),
      -1);
  const json id = readJson(run / "identify.json");
  if (code != kExitOk || !id.is_object())
    throw std::runtime_error("identify failed (exit " + std::to_string(code) + ", see " +
                             (run / "identify.log").string() + ")");
  json out;
  out["before"] = before;
  out["experiment"] = experiment;
  out["identify"] = id;
  out["run_dir"] = run.string();
  if (!fs::is_regular_file(overlay)) {
    std::fprintf(stderr, "demo --identify: verdict %s, nothing to add to the model\n",
                 id.value("verdict", "?").c_str());
    out["after"] = nullptr;
    return out;
  }
  std::fprintf(stderr, "demo --identify: 4/4 re-plan and run with %s (%s)\n", overlay.c_str(),
               id.value("effect", "?").c_str());
  DemoOptions o2 = o;
  o2.seed = o.seed + 2;
  o2.robot = overlay.string();
  o2.plan.clear();  // --plan: the run before; the re-plan starts from it
  o2.sim_robot =
      o.sim_robot.empty() ? o.robot : o.sim_robot;  // the simulated robot stays what it is
  // The same motion re-solved for the identified model: a plan from scratch for another model
  // can be another motion (measured on the 5 cm bar: 6.79 s instead of 6.37 s), which says
  // nothing about the model.
  o2.warm_start = (run / "before" / "plan.json").string();
  const json after = demoRun(o2, run / "after");
  out["after"] = after;
  for (const char* k : {"tracking_rms", "stabilizer_effort"})
    out["change"][k] = {before[k], after[k]};
  return out;
}

std::string planCacheKey(const std::string& planner_version, int plan_format,
                         const std::string& robot_text, const std::string& config_text,
                         const std::vector<std::string>& obstacle_args,
                         const std::string& warm_start_text) {
  // Each part with its length, so that no two different inputs give one text.
  std::string text;
  auto part = [&](const std::string& s) { text += std::to_string(s.size()) + ":" + s + "|"; };
  part("planner " + planner_version);
  part("format " + std::to_string(plan_format));
  part(robot_text);
  part(config_text);
  for (const auto& a : obstacle_args) part(a);
  part(warm_start_text);
  return hex(core::fnv1a64(text));
}

void checkOptions(const DemoOptions& o) {
  if (!(o.timeout > 0.0)) throw InputError("--timeout: expected > 0 s");
  if (!(o.plan_time_limit >= 0.0)) throw InputError("--plan-time-limit: expected >= 0 s");
  if (!o.lcm_url.empty()) {
    cli::checkLcmUrl(o.lcm_url);
    if (o.lcm_url.rfind("udpm://", 0) != 0)
      throw InputError("--lcm-url '" + o.lcm_url +
                       "': the demo's processes share the bus: expected udpm://GROUP:PORT?ttl=N");
  }
  if (!fs::is_regular_file(o.robot)) throw InputError("robot file not found: " + o.robot);
  if (!o.config.empty() && !fs::is_regular_file(o.config))
    throw InputError("planner config not found: " + o.config);
  if (!o.sim_robot.empty() && !fs::is_regular_file(o.sim_robot))
    throw InputError("simulated robot file not found: " + o.sim_robot);
  if (!o.truth.empty() && !fs::is_regular_file(o.truth))
    throw InputError("truth file not found: " + o.truth);
  if (!o.plan.empty() && !fs::is_regular_file(o.plan))
    throw InputError("plan file not found: " + o.plan);
}

}  // namespace overstep::demo
