// `overstep demo`: options, the verdict printed; the run itself is the demo library
// (overstep/demo/demo.hpp).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "overstep/cli/command.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/demo/demo.hpp"

namespace overstep {
namespace {

namespace fs = std::filesystem;
using demo::DemoOptions;
using nlohmann::json;

std::string utcStamp() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", std::gmtime(&t));
  return buf;
}

/// A figure of fidelityJson: its value, or NaN when null.
double figure(const json& j) {
  return j.is_object() && j["value"].is_number() ? j["value"].get<double>() : std::nan("");
}

/// Two lines: per foot contact losses, peak touchdown load, CoP deviation p95 / max, chatter;
/// then pelvis and settling, and the figures over their targets.
void printFidelity(const json& f) {
  if (!f.is_object()) {
    std::printf("fidelity: not measured (see the message above)\n");
    return;
  }
  for (const char* side : {"right", "left"}) {
    const json& s = f["feet"][side];
    std::printf(
        "fidelity %-5s: %d contact losses, touchdown %+.0f ms, load %.2f x weight, CoP deviation "
        "p95 %.1f mm max %.1f mm, chatter %.2f N m\n",
        side, static_cast<int>(figure(s["contact_losses"])),
        s["touchdown_timing"].is_number() ? 1e3 * s["touchdown_timing"].get<double>()
                                          : std::nan(""),
        figure(s["peak_touchdown_load"]), 1e3 * figure(s["cop_deviation_p95"]),
        1e3 * figure(s["cop_deviation_max"]), figure(s["chatter_rms"]));
  }
  std::string misses;
  for (const auto& m : f["misses"]) misses += (misses.empty() ? "" : ", ") + m.get<std::string>();
  std::printf("fidelity: pelvis within %.1f mrad of the plan, static %.2f s after it; %s\n",
              1e3 * figure(f["pelvis_deviation_max"]), figure(f["settling_time"]),
              misses.empty() ? "every target met" : ("over target: " + misses).c_str());
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
  printFidelity(v["fidelity"]);
  std::printf("run folder: %s (plan.json, bus.lcmlog, replay.json, sim.json, verdict.json)\n",
              v["run_dir"].get<std::string>().c_str());
  if (v.contains("report") && v["report"].is_string())
    std::printf("figures: %s\n", v["report"].get<std::string>().c_str());
}

/// With --plan of a plan that steps over its bar, the simulated bar is the plan's: obstacle
/// options left out are taken from it, and one given that differs is refused (a 5 cm plan
/// replayed in front of the default 20 cm bar walks its shank into it). A plan that does not
/// step (`plan --stand`, `--excite`) stands before whatever bar the options place. `given`
/// lists the obstacle options on the command line.
void obstacleFromPlan(DemoOptions& o, const std::vector<std::string>& given) {
  if (o.plan.empty() || !std::filesystem::is_regular_file(o.plan)) return;
  const core::Plan plan = core::loadPlan(o.plan);
  const bool steps = std::any_of(plan.phases.begin(), plan.phases.end(), [](const auto& ph) {
    return ph.right_contact != ph.left_contact;
  });
  if (!steps) return;
  const core::ObstacleSpec ob = plan.obstacle;
  const std::string shape = ob.shape == core::ObstacleSpec::Shape::Box ? "box" : "cylinder";
  const auto same = [](double a, double b) { return std::abs(a - b) <= 1e-9; };
  const auto metres = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g m", v);
    return std::string(buf);
  };
  const auto agree = [&](const std::string& name, bool equal, const std::string& planned) {
    if (!equal && std::find(given.begin(), given.end(), name) != given.end())
      throw InputError(name + " differs from the plan's obstacle (" + o.plan + ": " + planned +
                       "); leave it out to simulate the plan's bar");
  };
  agree("--obstacle-height", same(o.height, ob.height), metres(ob.height));
  agree("--obstacle-width", same(o.width, ob.width), metres(ob.width));
  agree("--obstacle-gap", same(o.gap, ob.gap), metres(ob.gap));
  agree("--obstacle-shape", o.shape == shape, shape);
  agree("--margin", same(o.margin, ob.margin), metres(ob.margin));
  o.height = ob.height;
  o.width = ob.width;
  o.gap = ob.gap;
  o.shape = shape;
  o.margin = ob.margin;
}

int runDemo(const DemoOptions& o) {
  checkOptions(o);
  const fs::path run = o.run_dir.empty() ? fs::path(o.run_root) / utcStamp() : fs::path(o.run_dir);
  std::error_code ec;
  fs::create_directories(run, ec);
  if (ec) throw InputError("cannot create run folder " + run.string() + ": " + ec.message());
  if (o.identify) {
    const json out = demo::identifyLoop(o, run);
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
  const json v = demo::demoRun(o, run);
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
                  "Replay this plan file instead of planning (its validity: overstep check; a "
                  "plan that steps over its bar is simulated in front of that bar; with "
                  "--identify: the run before, and the re-plan starts from it)");
  sub->add_flag("--no-report", o->no_report, "Skip the figures (overstep report) at the end");
  sub->add_flag("--allow-invalid-plan", o->allow_invalid,
                "Replay the planner's best attempt when no plan passes the check");
  sub->add_flag("--no-stabilizer", o->no_stabilizer, "Open-loop replay");
  sub->add_flag("--sim-contact-log", o->sim_contact_log,
                "The simulator's ground-truth contact of every 1 ms step to RUN_DIR/"
                "sim_contacts.csv (overstep sim --contact-log)");
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
      "Writes RUN_DIR/{plan.json, bus.lcmlog, replay.json, sim.json, verdict.json} (and\n"
      "sim_contacts.csv with --sim-contact-log).\n"
      "Exit: 0 cleared, 2 bad input, 3 no valid plan, 4 the robot did not clear the obstacle.");
  registry.add(sub, [o, sub] {
    std::vector<std::string> given;
    for (const char* name : {"--obstacle-height", "--obstacle-width", "--obstacle-gap",
                             "--obstacle-shape", "--margin"})
      if (sub->count(name) > 0) given.emplace_back(name);
    obstacleFromPlan(*o, given);
    return runDemo(*o);
  });
}

}  // namespace overstep
