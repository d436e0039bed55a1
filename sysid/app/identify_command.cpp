// `overstep identify`: a replay's log + its plan -> residual -> candidate effect -> parameters.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

#include "overstep/cli/command.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/monitor/lcm_log.hpp"
#include "overstep/monitor/messages.hpp"
#include "overstep/monitor/plan_match.hpp"
#include "overstep/monitor/report.hpp"
#include "overstep/msgs/convert.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/sysid/identify.hpp"
#include "overstep/sysid/overlay.hpp"

namespace overstep {
namespace {

struct IdentifyCliOptions {
  std::string log, plan, robot, residuals, out, plots, python = "/usr/bin/python3";
  bool json = false, no_torque = false, no_ground = false;
  double train = 0.6;
};

/// One tick per command: the state read before it, the plan time it was for (the plan reference
/// published in the same tick carries the same utime), and the first later state that reports
/// having received it (last_command_seq). Paired after reading, so the order in which the logger
/// received the runtime's and the simulator's messages does not matter.
/// Every message is checked against the plan first (its joint count, and each plan reference's
/// duration, time and phase): a log of another plan is refused instead of being read against it.
sysid::Dataset loadDataset(const std::string& path, int joints, const core::Plan& plan,
                           const std::string& plan_path) {
  const double rate = plan.rate, duration = plan.duration();
  monitor::LogReader reader(path);
  monitor::LogEvent ev;
  monitor::AnyMessage msg;
  std::vector<core::RobotState> states;
  struct Cmd {
    core::RobotCommand cmd;
    int before = -1;  // index into states
  };
  std::vector<Cmd> cmds;
  std::map<std::int64_t, double> ref_time;  // utime -> plan time
  std::string why;
  while (reader.next(ev)) {
    if (monitor::decode(ev.data, ev.size, msg) != monitor::DecodeStatus::Ok) continue;
    if (auto* s = std::get_if<overstep::robot_state_t>(&msg)) {
      monitor::checkJointCount(s->num_joints, joints, ev.channel, path, plan_path);
      core::RobotState st;
      if (msgs::fromLcm(*s, joints, st, &why)) states.push_back(st);
    } else if (auto* c = std::get_if<overstep::robot_command_t>(&msg)) {
      monitor::checkJointCount(c->num_joints, joints, ev.channel, path, plan_path);
      core::RobotCommand cmd;
      if (!states.empty() && msgs::fromLcm(*c, joints, cmd, &why))
        cmds.push_back({cmd, static_cast<int>(states.size()) - 1});
    } else if (auto* p = std::get_if<overstep::plan_reference_t>(&msg)) {
      monitor::checkPlanReference(*p, plan, path, plan_path);
      ref_time[p->utime] = p->plan_time;
    }
  }
  if (states.empty() || cmds.empty() || ref_time.empty())
    throw InputError(
        path + ": needs OVERSTEP_STATE, OVERSTEP_COMMAND and OVERSTEP_PLAN_REF (missing: " +
        std::string(states.empty() ? "state " : "") + (cmds.empty() ? "command " : "") +
        (ref_time.empty() ? "plan reference" : "") + ")");
  sysid::Dataset data;
  data.period = 1.0 / rate;
  double last_t = -1.0;
  for (const Cmd& c : cmds) {
    const auto it = ref_time.find(c.cmd.utime);
    if (it == ref_time.end()) continue;
    const double plan_t = it->second;
    if (!(plan_t > last_t && plan_t < duration)) continue;  // moving to the start, or lingering
    for (std::size_t i = static_cast<std::size_t>(c.before) + 1; i < states.size(); ++i) {
      if (states[i].last_command_seq == c.cmd.seq) {
        data.add(plan_t, c.cmd, states[static_cast<std::size_t>(c.before)], states[i]);
        last_t = plan_t;
        break;
      }
      if (states[i].last_command_seq > c.cmd.seq) break;  // never applied alone
    }
  }
  return data;
}

int runIdentify(const IdentifyCliOptions& o) {
  if (!(o.train > 0.1 && o.train < 0.9)) throw InputError("--train: expected 0.1 .. 0.9");
  const core::Plan plan = core::loadPlan(o.plan);
  const robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(o.robot);
  if (plan.robot_hash != model.description().hashHex())
    throw InputError(o.plan + ": planned for another robot (hash " + plan.robot_hash + ")");
  const sysid::Dataset data = loadDataset(o.log, model.actuatedCount(), plan, o.plan);
  if (data.size() < 2)
    throw InputError(o.log + ": no executed tick of this plan in the log (another plan's run?)");
  sysid::IdentifyOptions io;
  io.train_fraction = o.train;
  io.use_torque = !o.no_torque;
  io.use_force = !o.no_ground;
  io.dump_residuals = o.residuals;
  const sysid::Identification r = sysid::identify(data, plan, model, io);
  std::string overlay_written;
  if (!o.out.empty()) {
    if (r.effect.empty()) {
      std::fprintf(stderr, "identify: verdict %s: nothing to add, %s not written\n",
                   r.verdict.c_str(), o.out.c_str());
    } else {
      core::writeFileAtomic(o.out, sysid::overlayYaml(r, model.description(), o.out,
                                                      "log " + o.log + ", plan " + o.plan));
      overlay_written = o.out;
    }
  }
  nlohmann::json j;
  j["verdict"] = r.verdict;
  j["effect"] = r.effect;
  j["confusable"] = r.confusable;
  j["runner_up"] = r.runner_up;
  j["parameters"] = r.parameters;
  j["ci95"] = r.ci95;
  j["error_before"] = r.error_before;
  j["error_after"] = r.error_after;
  j["excess_before"] = r.excess_before;
  j["excess_after"] = r.excess_after;
  j["whiteness"] = r.whiteness;
  j["samples"] = r.samples;
  j["moving_joints"] = r.moving_joints;
  nlohmann::json ch;
  for (const auto& [name, c] : r.channels)
    ch[name] = {{"unit", c.unit},
                {"rms_before", c.rms_before},
                {"rms_after", c.rms_after},
                {"noise", c.noise}};
  j["channels"] = ch;
  j["overlay"] = overlay_written;
  nlohmann::json cands = nlohmann::json::array();
  for (const auto& c : r.candidates)
    cands.push_back({{"name", c.name},
                     {"held_out_reduction", c.reduction},
                     {"f_statistic", c.f_statistic},
                     {"plausible", c.plausible}});
  j["candidates"] = cands;
  if (!o.plots.empty()) {
    // Every residual row and the summary, then the figures (Matplotlib).
    std::error_code ec;
    std::filesystem::create_directories(o.plots, ec);
    if (ec) throw InputError("--plots: cannot create " + o.plots + ": " + ec.message());
    std::string csv = "channel,label,t,held_out,before,after\n";
    char buf[160];
    for (const auto& row : r.residuals) {
      std::snprintf(buf, sizeof buf, ",%.6f,%d,%.9g,%.9g\n", row.t, row.held_out ? 1 : 0,
                    row.before, row.after);
      csv += row.channel + "," + row.label + buf;
    }
    const std::filesystem::path dir(o.plots);
    core::writeFileAtomic((dir / "residuals.csv").string(), csv);
    core::writeFileAtomic((dir / "summary.json").string(), j.dump(2) + "\n");
    monitor::runPlotScript(o.python, monitor::shippedScript("sysid/python/residual_plots.py"),
                           {o.plots}, "identify --plots");
    j["plots"] = {(dir / "fig_residuals.png").string(), (dir / "fig_autocorr.png").string()};
  }
  if (o.json) {
    std::cout << j.dump(2) << "\n";
  } else {
    std::printf("%d ticks, %d moving joints; verdict: %s%s%s\n", r.samples, r.moving_joints,
                r.verdict.c_str(), r.effect.empty() ? "" : " -> ", r.effect.c_str());
    if (!r.confusable.empty()) {
      std::printf("  confusable:");
      for (const auto& c : r.confusable) std::printf(" %s", c.c_str());
      std::printf("\n");
    }
    for (const auto& [name, v] : r.parameters)
      std::printf("  %-28s %12.5g +- %.3g (95 %%)\n", name.c_str(), v, r.ci95.at(name));
    std::printf(
        "held-out error (noise-normalised RMS): before %.3f, after %.3f; above the noise: "
        "before %.3f, after %.3f\n",
        r.error_before, r.error_after, r.excess_before, r.excess_after);
    for (const auto& [name, c] : r.channels)
      std::printf("  %-16s RMS %.4g -> %.4g %s (noise %.3g)\n", name.c_str(), c.rms_before,
                  c.rms_after, c.unit.c_str(), c.noise);
    std::printf("%-26s %10s %10s\n", "candidate", "held-out", "F");
    for (const auto& c : r.candidates)
      std::printf("%-26s %9.1f%% %10.3g%s\n", c.name.c_str(), 100.0 * c.reduction, c.f_statistic,
                  c.plausible ? "" : "  (implausible)");
    if (!overlay_written.empty())
      std::printf("model overlay: %s (use it as --robot)\n", overlay_written.c_str());
    if (!o.plots.empty())
      std::printf("figures: %s/fig_residuals.png, %s/fig_autocorr.png\n", o.plots.c_str(),
                  o.plots.c_str());
  }
  return kExitOk;
}

}  // namespace

void registerIdentifyCommand(CLI::App& app, cli::Registry& registry) {
  auto o = std::make_shared<IdentifyCliOptions>();
  o->robot = cli::defaultRobotPath();
  CLI::App* sub = app.add_subcommand(
      "identify", "Residual of a replay -> the effect the model lacks -> its parameters");
  sub->add_option("log", o->log, "LCM log of the replay (e.g. runs/<run>/bus.lcmlog)")->required();
  sub->add_option("--plan", o->plan, "The plan that was replayed")->required();
  sub->add_option("--robot", o->robot, "Robot YAML (the model to test)")->capture_default_str();
  sub->add_option("--train", o->train, "Fraction of the run used for fitting (rest: held out)")
      ->capture_default_str();
  sub->add_flag("--no-torque", o->no_torque, "Leave the motor-torque channel out");
  sub->add_flag("--no-ground", o->no_ground,
                "Leave the ground channels (ankle sensors' summed force and moment) out");
  sub->add_option("--out", o->out,
                  "Write the identified effect as a model overlay YAML (use it as --robot)");
  sub->add_option("--plots", o->plots,
                  "Folder for the residual before/after and its autocorrelation (PNG, "
                  "Matplotlib) with residuals.csv");
  sub->add_option("--python", o->python, "Python with Matplotlib (for --plots)")
      ->capture_default_str();
  sub->add_option("--residuals", o->residuals,
                  "Write every residual row (channel, joint, t, residual, measured) to this CSV");
  sub->add_flag("--json", o->json,
                "Print {verdict, effect, parameters, ci95, runner_up, error_before, error_after, "
                "channels}");
  sub->footer(
      "Examples:\n"
      "  overstep plan --excite 8 --out excite.json\n"
      "  overstep demo --plan excite.json --truth truth.yaml --run-dir runs/excite\n"
      "  overstep identify runs/excite/bus.lcmlog --plan excite.json --json\n"
      "  overstep identify runs/excite/bus.lcmlog --plan excite.json --out identified.yaml\n"
      "  overstep plan --robot identified.yaml        # re-plan with the identified model\n"
      "Verdicts: identified, ambiguous (confusable candidates named), none, unexplained\n"
      "(docs/identification.md). Exit 2: a log without the needed channels, a plan that does\n"
      "not match the log or the robot, or too short a run.");
  registry.add(sub, [o] { return runIdentify(*o); });
}

}  // namespace overstep
