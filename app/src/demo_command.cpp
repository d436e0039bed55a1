// `overstep demo`: the main job. Plans the overstep (or reuses a cached plan for identical inputs),
// starts the simulator and the replay runtime as child processes in lockstep on a private LCM
// port, records the bus with lcm-logger into a run folder, stops everything cleanly and prints a
// verdict. Every child is this same binary (or lcm-logger); the verdict comes from their --json
// summaries.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "overstep/cli/command.hpp"
#include "overstep/cli/lcm_url.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/json_depth.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/core/robot_description.hpp"

namespace overstep {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

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
  unsigned seed = 1;             ///< the simulator's sensor-noise seed
  double timeout = 120.0;        ///< s of wall time for the run (after planning)
  double plan_time_limit = 0.0;  ///< s, passed to overstep plan (0: its configuration's)
};

std::string selfExe() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the overstep executable (/proc/self/exe)");
  return p.string();
}

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string shellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

/// Starts `argv` with stdout/stderr to files (empty: inherit); returns the pid.
pid_t spawn(const std::vector<std::string>& argv, const std::string& out, const std::string& err) {
  std::string cmd = "exec";
  for (const auto& a : argv) cmd += " " + shellQuote(a);
  if (!out.empty()) cmd += " >" + shellQuote(out);
  if (!err.empty()) cmd += " 2>" + shellQuote(err);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

/// Waits up to `timeout_s` (< 0: forever); returns the exit code, -signal, or -1000 on timeout.
int waitFor(pid_t pid, double timeout_s) {
  const auto t0 = std::chrono::steady_clock::now();
  int status = 0;
  while (true) {
    const pid_t r = waitpid(pid, &status, timeout_s < 0 ? 0 : WNOHANG);
    if (r == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
    if (r < 0) return -1;
    if (timeout_s >= 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout_s)
      return -1000;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

int stop(pid_t pid, int sig, double grace_s) {
  kill(pid, sig);
  int code = waitFor(pid, grace_s);
  if (code == -1000) {
    kill(pid, SIGKILL);
    code = waitFor(pid, -1);
  }
  return code;
}

/// A JSON file written by a child command (its summary); discarded when unreadable or nested
/// deeper than any of ours (parsing recurses).
json readJson(const fs::path& p) {
  const std::string text = readAll(p);
  constexpr int kMaxDepth = 32;
  if (core::jsonDepth(text, kMaxDepth) > kMaxDepth) return json(json::value_t::discarded);
  return json::parse(text, nullptr, false);
}

std::string utcStamp() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", std::gmtime(&t));
  return buf;
}

std::string hex(std::uint64_t h) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

/// One demo run into `run`: plan (or reuse), simulate, replay, record, verdict (also written to
/// run/verdict.json).
json demoRun(const DemoOptions& o, const fs::path& run) {
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
  // The key covers the plan format (a cached plan of an older format would be refused) and is a
  // fixed function of its text (FNV-1a, not std::hash: stable across builds and libraries).
  std::string key_text = "format " + std::to_string(core::Plan::kFormatVersion) + "|" +
                         readAll(o.robot) + "|" + (o.config.empty() ? "" : readAll(o.config));
  for (const auto& a : obstacle_args) key_text += "|" + a;
  if (!o.warm_start.empty()) key_text += "|warm|" + readAll(o.warm_start);
  const std::string key = hex(core::fnv1a64(key_text));
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
  const std::string url =
      o.lcm_url.empty() ? "udpm://239.255.76.67:" + std::to_string(7700 + getpid() % 200) + "?ttl=0"
                        : o.lcm_url;
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
  const pid_t sim = spawn(sim_argv, (run / "sim.json").string(), (run / "sim.log").string());
  std::fprintf(stderr, "demo: simulator and runtime running in lockstep on %s; run folder %s\n",
               url.c_str(), run.c_str());
  const auto t0 = std::chrono::steady_clock::now();
  int replay_code = waitFor(replay, o.timeout);
  if (replay_code == -1000) replay_code = stop(replay, SIGINT, 5.0);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const int sim_code = stop(sim, SIGTERM, 10.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  stop(logger, SIGINT, 5.0);

  // ---- 3. verdict
  const json r = readJson(run / "replay.json");
  const json s = readJson(run / "sim.json");
  if (!r.is_object() || !s.is_object())
    throw std::runtime_error("the runtime or the simulator left no summary (see " +
                             (run / "replay.log").string() + " and sim.log)");
  const bool fell = s.value("fell", true);
  const bool contact = s.value("obstacle_contact", true);
  const bool finished = r.value("finished", false);
  const double far_x = s["obstacle_x"][1].get<double>();
  const bool beyond = s.value("right_heel_x", -1e9) > far_x && s.value("left_heel_x", -1e9) > far_x;
  const bool still = s.value("base_speed", 1e9) < 0.02;
  json v;
  v["cleared"] = finished && !fell && !contact && beyond && still;
  v["fell"] = fell;
  v["obstacle_contact"] = contact;
  v["finished"] = finished;
  v["feet_beyond_obstacle"] = beyond;
  v["static_at_end"] = still;
  v["plan_valid"] = plan_valid;
  v["plan_duration"] = plan.duration();
  v["duration"] = r.value("executed_duration", 0.0);
  v["tracking_rms"] = r.value("tracking_rms", 0.0);
  v["cop_max"] = r.value("cop_max", json::object());
  v["torso_deviation_max"] = r.value("torso_deviation_max", 0.0);
  v["stabilizer_effort"] = r.value("stabilizer_effort", 0.0);
  v["stabilizer"] = !o.no_stabilizer;
  v["runtime_state"] = r.value("state", "");
  v["runtime_fault"] = r.value("fault", "");
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

void printVerdict(const json& v) {
  const bool fell = v["fell"].get<bool>(), contact = v["obstacle_contact"].get<bool>();
  const bool finished = v["finished"].get<bool>(), beyond = v["feet_beyond_obstacle"].get<bool>();
  const bool still = v["static_at_end"].get<bool>();
  std::printf("%s: %s\n", v["cleared"].get<bool>() ? "CLEARED" : "NOT CLEARED",
              fell      ? "the robot fell"
              : contact ? "the robot touched the obstacle"
              : !finished
                  ? ("the runtime stopped: " + v["runtime_fault"].get<std::string>()).c_str()
              : !beyond ? "a foot did not get past the obstacle"
              : !still  ? "the robot was still moving at the end"
                        : "both feet past the obstacle, standing still");
  std::printf("executed %.2f s (plan %.2f s%s; the seed: 4.32 s plan, 4.33 s simulated)\n",
              v["duration"].get<double>(), v["plan_duration"].get<double>(),
              v["plan_valid"].get<bool>() ? "" : ", INVALID plan");
  std::printf(
      "tracking RMS %.4f rad, stabilizer effort %.4f rad, largest CoP excursion R %.3f m L "
      "%.3f m, torso deviation %.3f rad\n",
      v["tracking_rms"].get<double>(), v["stabilizer_effort"].get<double>(),
      v["cop_max"].value("right", 0.0), v["cop_max"].value("left", 0.0),
      v["torso_deviation_max"].get<double>());
  std::printf("run folder: %s (plan.json, bus.lcmlog, replay.json, sim.json, verdict.json)\n",
              v["run_dir"].get<std::string>().c_str());
  if (v.contains("report") && v["report"].is_string())
    std::printf("figures: %s\n", v["report"].get<std::string>().c_str());
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
  // can be another motion (5 cm bar, session 6: 6.79 s instead of 6.37 s), which says nothing
  // about the model.
  o2.warm_start = (run / "before" / "plan.json").string();
  const json after = demoRun(o2, run / "after");
  out["after"] = after;
  for (const char* k : {"tracking_rms", "stabilizer_effort"})
    out["change"][k] = {before[k], after[k]};
  return out;
}

int runDemo(const DemoOptions& o) {
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
  const fs::path run = o.run_dir.empty() ? fs::path(o.run_root) / utcStamp() : fs::path(o.run_dir);
  std::error_code ec;
  fs::create_directories(run, ec);
  if (ec) throw InputError("cannot create run folder " + run.string() + ": " + ec.message());
  if (o.identify) {
    const json out = identifyLoop(o, run);
    core::writeFileAtomic((run / "identify_loop.json").string(), out.dump(2) + "\n");
    if (o.json) {
      std::cout << out.dump(2) << "\n";
    } else {
      const json& id = out["identify"];
      std::printf("identified: %s%s%s\n", id.value("verdict", "?").c_str(),
                  id.value("effect", "").empty() ? "" : " -> ", id.value("effect", "").c_str());
      if (out["after"].is_object()) {
        std::printf("%-20s %12s %12s\n", "", "before", "after");
        for (const char* k : {"tracking_rms", "stabilizer_effort"})
          std::printf("%-20s %12.5f %12.5f rad\n", k, out["before"][k].get<double>(),
                      out["after"][k].get<double>());
        std::printf("%-20s %12s %12s\n", "cleared",
                    out["before"]["cleared"].get<bool>() ? "yes" : "no",
                    out["after"]["cleared"].get<bool>() ? "yes" : "no");
      }
      std::printf("run folder: %s (before/, experiment/, identify.json, identified.yaml, after/)\n",
                  run.c_str());
    }
    const json& last = out["after"].is_object() ? out["after"] : out["before"];
    return last["cleared"].get<bool>() ? kExitOk : kExitHeld;
  }
  const json v = demoRun(o, run);
  if (o.json) {
    std::cout << v.dump(2) << "\n";
  } else {
    printVerdict(v);
  }
  return v["cleared"].get<bool>() ? kExitOk : kExitHeld;
}

}  // namespace

void registerDemoCommand(CLI::App& app, cli::Registry& registry) {
  auto o = std::make_shared<DemoOptions>();
  CLI::App* sub = app.add_subcommand(
      "demo", "Plan, simulate and replay the overstep with the stabilizer; print a verdict");
  sub->add_option("--robot", o->robot, "Robot YAML")->default_val(cli::defaultRobotPath());
  sub->add_option("--config", o->config, "Planner configuration (default: embedded)");
  sub->add_option("--obstacle-height", o->height, "Envelope height, m")->default_val(0.20);
  sub->add_option("--obstacle-width", o->width, "Envelope width along x, m")->default_val(0.11);
  sub->add_option("--obstacle-shape", o->shape, "box or cylinder")->default_val("box");
  sub->add_option("--obstacle-gap", o->gap, "From the start toes to the bar, m")->default_val(0.03);
  sub->add_option("--margin", o->margin,
                  "Extra clearance on every side for the planner (not the simulated bar), m")
      ->default_val(0.0);
  sub->add_option("--truth", o->truth, "Simulate with undeclared effects (docs/truth-file.md)");
  sub->add_option("--sim-robot", o->sim_robot,
                  "The simulated robot's model when it differs from --robot (e.g. --robot an "
                  "identified overlay, the simulator the base model plus --truth)");
  sub->add_option("--seed", o->seed,
                  "The simulator's sensor-noise seed (--identify: the experiment and the second "
                  "run use SEED + 1 and SEED + 2)")
      ->default_val(1u);
  sub->add_option("--run-root", o->run_root, "Folder of run folders and the plan cache")
      ->default_val("runs");
  sub->add_option("--run-dir", o->run_dir, "This run's folder (default: RUN_ROOT/<UTC time>)");
  sub->add_option("--cache-dir", o->cache_dir, "Plan cache (default: RUN_ROOT/cache)");
  sub->add_option("--lcm-url", o->lcm_url, "LCM URL (default: a private udpm port, ttl=0)");
  sub->add_option("--timeout", o->timeout, "Wall-time limit of the simulated run, s")
      ->default_val(120.0);
  sub->add_option("--plan-time-limit", o->plan_time_limit,
                  "Wall-time limit of the planner, s (default: its configuration's)");
  sub->add_flag("--replan", o->replan, "Ignore the plan cache");
  sub->add_option("--plan", o->plan,
                  "Replay this plan file instead of planning (its validity: overstep check; with "
                  "--identify: the run before, and the re-plan starts from it)");
  sub->add_flag("--no-report", o->no_report, "Skip the figures (overstep report) at the end");
  sub->add_flag("--allow-invalid-plan", o->allow_invalid,
                "Replay the planner's best attempt when no plan passes the check");
  sub->add_flag("--no-stabilizer", o->no_stabilizer, "Open-loop replay");
  sub->add_flag("--identify", o->identify,
                "Close the loop: run, identify the effect (overstep identify), re-plan with the "
                "identified model, run again; before and after");
  sub->add_flag("--json", o->json, "Print the verdict as JSON");
  sub->footer(
      "Examples:\n"
      "  overstep demo                                  # the 20 cm x 11 cm overstep\n"
      "  overstep demo --obstacle-height 0.05 --json    # a small bar, verdict as JSON\n"
      "  overstep demo --truth truth.yaml               # on a robot with undeclared effects\n"
      "  overstep demo --truth truth.yaml --identify    # ... identify it, re-plan, run again\n"
      "  overstep demo --plan plan.json --truth truth.yaml --identify --seed 2\n"
      "Writes RUN_DIR/{plan.json, bus.lcmlog, replay.json, sim.json, verdict.json}.\n"
      "Exit: 0 cleared, 2 bad input, 3 no valid plan, 4 the robot did not clear the obstacle.");
  registry.add(sub, [o] { return runDemo(*o); });
}

}  // namespace overstep
