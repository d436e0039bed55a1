// `overstep plan` and `overstep check`.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "overstep/cli/command.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/planner/check.hpp"
#include "overstep/planner/solver.hpp"
#include "overstep/planner/standing.hpp"
#include "overstep/planner/version.hpp"
#include "overstep/robots/whole_body_model.hpp"

namespace overstep {
namespace {

/// Check-driven mesh refinement. The rows hold at the samples, the CoP box, friction and pelvis
/// range at a margin (limit_margin, pelvis_margin) so that the motion between samples keeps
/// inside; `overstep check` verifies on a 1 kHz grid. When the planner's solution passes its
/// rows but the check finds a family over its bound between samples, a grid point carrying the
/// path constraints (no objective weight; OverstepProblem's check_points) is added at the worst
/// instant of each crossing and the last stage is solved again from that solution; where no new
/// point can be added (the crossing is at a grid point already), the CoP / friction or pelvis
/// margin is tightened by a fifth instead. At most twice; a foot off its placement (`stance`) ends
/// it. Measured: the identification loop's re-plan for a 1.5 kg payload (5 cm bar, 2 cm box) passed
/// its rows with a CoP 1.3 mm over the box at the right touchdown. Returns the work of the
/// re-solves' problems (evaluations and Jacobians); `checked` holds the dense plan of the final
/// solution and its check when the last check was of that solution (the caller then need not sample
/// and check it again).
struct CheckedPlan {
  core::Plan plan;
  planner::CheckReport report;
};
/// The target stage's polish stops at the first feasible point whose dense plan `overstep check`
/// accepts (planOverstep's `accept`): the check, not a tenth of the rows' tolerance, is what
/// makes a plan valid.
planner::AcceptFn checkAccepts(planner::OverstepProblem& problem,
                               const robots::WholeBodyModel& model, double rate, std::FILE* log) {
  return [&problem, &model, rate, log](const Eigen::VectorXd& x) {
    const planner::CheckReport report = planner::checkPlan(problem.toPlan(x, rate), model);
    std::string over;
    for (const auto& f : report.families)
      if (!f.ok()) over += (over.empty() ? "" : ", ") + f.name;
    std::fprintf(log, "-- the 1 kHz check of the polished point: %s%s\n",
                 report.valid ? "valid" : "over in ", over.c_str());
    std::fflush(log);
    return report.valid;
  };
}

planner::WorkAccount refineByCheck(planner::OverstepProblem& problem, planner::NlpSolver& solver,
                                   const planner::PlannerConfig& cfg, const core::ObstacleSpec& ob,
                                   const robots::WholeBodyModel& model, double rate, std::FILE* log,
                                   const std::function<void(const planner::IterationInfo&)>& row,
                                   planner::PlanOutcome& out, std::optional<CheckedPlan>& checked) {
  planner::WorkAccount extra;
  planner::PlannerConfig tight = cfg;
  std::vector<planner::GridPoint> points;
  std::unique_ptr<planner::OverstepProblem> refined;
  auto account = [&] {
    if (!refined) return;
    extra.evaluations += refined->evaluationCount();
    extra.jacobians += refined->work().jacobians;
  };
  for (int retry = 0; retry < 2 && out.valid && !cli::StopSignals::requested(); ++retry) {
    // Sampled by the caller's problem (the margins do not enter the dense plan; its recorded
    // configuration stays the caller's).
    checked = CheckedPlan{problem.toPlan(out.final.x, rate), {}};
    checked->report = planner::checkPlan(checked->plan, model, 1000.0, true);
    const planner::CheckReport& report = checked->report;
    if (report.valid) break;
    bool contact = false, pelvis = false, other = false;
    std::vector<std::string> over;
    for (const auto& f : report.families) {
      if (f.ok()) continue;
      over.push_back(f.name);
      if (f.name == "cop" || f.name == "friction")
        contact = true;
      else if (f.name == "pelvis")
        pelvis = true;
      else if (f.name == "stance")
        other = true;  // the feet's placement: no row at a point holds it
    }
    if (other) break;
    const planner::PhaseTiming timing(out.final.x.head(planner::kPhaseCount));
    const std::size_t before = points.size();
    for (double t : planner::violationPeaks(report, over)) points.push_back(timing.locate(t));
    account();
    refined = std::make_unique<planner::OverstepProblem>(model, tight, ob, points);
    points = refined->checkPoints();
    if (points.size() == before) {  // every crossing at a point already: tighten a margin
      if (!contact && !pelvis) break;
      if (contact) tight.limit_margin *= 0.8;
      if (pelvis) tight.pelvis_margin *= 0.8;
      refined = std::make_unique<planner::OverstepProblem>(model, tight, ob, points);
    }
    std::string names;
    for (const auto& n : over) names += (names.empty() ? "" : ", ") + n;
    std::fprintf(log,
                 "-- the 1 kHz check found %s over between samples: the last stage again with "
                 "%zu check points, limit_margin %.3f, pelvis_margin %.3f\n",
                 names.c_str(), points.size(), tight.limit_margin, tight.pelvis_margin);
    std::fflush(log);
    const Eigen::VectorXd from = out.final.x;
    planner::PlanOutcome again = planner::planOverstep(
        *refined, solver, std::max(1.0, cfg.solver.time_limit - out.solve_time),
        [log](const std::string& st) {
          std::fprintf(log, "-- %s\n", st.c_str());
          std::fflush(log);
        },
        row, &cli::StopSignals::flag(), &from, checkAccepts(problem, model, rate, log));
    if (!again.valid) break;  // the first solution stays (and `checked` is its check)
    checked.reset();
    again.iterations += out.iterations;
    again.solve_time += out.solve_time;
    again.split.derivatives += out.split.derivatives;
    again.split.evaluations += out.split.evaluations;
    again.split.nlopt += out.split.nlopt;
    again.split.restoration += out.split.restoration;
    again.split.other += out.split.other;
    out = again;
  }
  account();
  return extra;
}

/// A warm start's solution vector is laid out by its configuration's spline spans: the same
/// spans or an InputError naming the key (two layouts can have the same length). Plans written
/// before the bushing curves had their own spans used the legs' (`spline_intervals`).
void checkWarmLayout(const std::string& path, const core::Plan& plan,
                     const planner::PlannerConfig& cfg) {
  const nlohmann::json pc = nlohmann::json::parse(plan.config_json, nullptr, false);
  if (!pc.is_object()) throw InputError(path + ": no planner configuration to read its layout");
  auto spans = [&](const char* key, const char* fallback) {
    const nlohmann::json& v = pc.contains(key)        ? pc[key]
                              : pc.contains(fallback) ? pc[fallback]
                                                      : pc;
    const bool ok = v.is_array() && v.size() == planner::kPhaseCount &&
                    std::all_of(v.begin(), v.end(),
                                [](const nlohmann::json& n) { return n.is_number_integer(); });
    if (!ok) throw InputError(path + ": its configuration has no " + key + " (5 integers)");
    return v.get<std::vector<int>>();
  };
  auto text = [](const std::vector<int>& v) {
    std::string t;
    for (int n : v) t += (t.empty() ? "" : ", ") + std::to_string(n);
    return "[" + t + "]";
  };
  const std::pair<const char*, const std::array<int, planner::kPhaseCount>*> keys[] = {
      {"spline_intervals", &cfg.spline_intervals},
      {"flex_spline_intervals", &cfg.flex_spline_intervals}};
  for (const auto& [key, mine] : keys) {
    const std::vector<int> theirs = spans(key, "spline_intervals");
    const std::vector<int> ours(mine->begin(), mine->end());
    if (theirs != ours)
      throw InputError(path + ": its " + key + " " + text(theirs) + " differ from this " +
                       "configuration's " + text(ours) + " (give --config the plan's spans)");
  }
}

/// Beyond this the swing sole cannot be lifted over the bar at all (hip below 0.65 m, leg 0.6 m
/// plus foot): answer at once instead of searching.
constexpr double kReachableHeight = 0.45;

struct PlanOptions {
  std::string robot, config, out = "plan.json", shape = "box", warm_start;
  double height = 0.20, width = 0.11, gap = 0.03, margin = 0.0, time_limit = 0.0, rate = 200.0;
  int threads = 0;
  bool json = false, resample = false;
  double stand = 0.0;   ///< --stand: write a static standing plan of this duration instead
  double excite = 0.0;  ///< --excite: write an identification excitation plan of this duration
  /// Given on the command line (issue 20: `--stand 0` was taken as absent and started a solve).
  bool stand_given = false, excite_given = false;
  double amplitude = 1.0;  ///< of the excitation
};

int runStand(const PlanOptions& o) {
  robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(o.robot);
  const bool excite = o.excite_given;
  const core::Plan plan = excite ? planner::excitationPlan(model, o.excite, o.amplitude, o.rate)
                                 : planner::standingPlan(model, o.stand, o.rate);
  core::savePlan(plan, o.out);
  if (o.json) {
    nlohmann::json j;
    j["status"] = excite ? "excitation" : "standing";
    j["valid"] = true;
    j["duration"] = plan.duration();
    j["file"] = o.out;
    std::cout << j.dump(2) << "\n";
  } else {
    std::cerr << (excite ? "excitation plan: " : "standing plan: ") << plan.duration() << " s, "
              << plan.samples() << " samples -> " << o.out << "\n";
  }
  return kExitOk;
}

std::string failedPath(const std::string& out) {
  std::filesystem::path p(out);
  std::string stem = p.stem().string();
  return (p.parent_path() / (stem + ".failed.json")).string();
}

int runPlan(const PlanOptions& o) {
  if (o.stand_given && o.excite_given) throw InputError("choose one of --stand and --excite");
  if (o.stand_given || o.excite_given) return runStand(o);
  core::ObstacleSpec ob;
  ob.shape = core::parseObstacleShape(o.shape);
  ob.height = o.height;
  ob.width = o.width;
  ob.gap = o.gap;
  ob.margin = o.margin;
  core::validate(ob);
  planner::PlannerConfig cfg =
      o.config.empty() ? planner::PlannerConfig{} : planner::loadPlannerConfig(o.config);
  if (o.threads < 0) throw InputError("--threads: expected >= 1, got " + std::to_string(o.threads));
  if (o.threads > 0) cfg.solver.threads = o.threads;
  if (o.time_limit < 0.0) throw InputError("--time-limit: expected >= 0 s");
  if (o.time_limit > 0.0) cfg.solver.time_limit = o.time_limit;
  if (!(o.rate > 0.0) || o.rate > 2000.0) throw InputError("--rate: expected 0 < rate <= 2000 Hz");
  const robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(o.robot);
  {
    std::error_code ec;
    const auto dir = std::filesystem::path(o.out).parent_path();
    if (!dir.empty() && !std::filesystem::is_directory(dir, ec))
      throw InputError("--out: directory " + dir.string() + " does not exist");
  }
  FILE* log = o.json ? stderr : stdout;
  if (ob.envelopeHeight() > kReachableHeight) {
    throw InfeasibleError("obstacle height " + std::to_string(ob.envelopeHeight()) +
                          " m is beyond the swing foot's reach (about " +
                          std::to_string(kReachableHeight) + " m for this robot): no plan exists");
  }
  {
    // The landing heel must clear the bar's far face: a bar wider than the longest step allows
    // has no plan (answered at once; the solver would search until its time limit).
    const auto& sole = model.description().foot("right")->sole;
    const double toes_x = model.description().foot("left")->sole.x_front;
    const double needed = ob.farX(toes_x) + cfg.obstacle_clearance + sole.x_back;
    if (needed > cfg.step_length_max) {
      throw InfeasibleError("a step over this bar needs at least " + std::to_string(needed) +
                            " m, beyond step_length_max " + std::to_string(cfg.step_length_max) +
                            " m: no plan exists");
    }
  }
  // From here on Ctrl-C or SIGTERM (a job scheduler's stop, `timeout`, `kill`) stops the solve
  // and keeps the best attempt; installed before the first line of output, so that a signal
  // sent after it never kills the process outright.
  const cli::StopSignals stop;
  planner::OverstepProblem problem(model, cfg, ob);
  if (const double d = problem.startClearance(); d < cfg.obstacle_clearance - 1e-9) {
    // The feet stand at their start until they lift off: their capsules' distance to the bar
    // there is the same in every plan (answered at once; the solver would search until its
    // time limit).
    throw InfeasibleError("the feet's collision capsules at the start are " + std::to_string(d) +
                          " m from the bar, under obstacle_clearance " +
                          std::to_string(cfg.obstacle_clearance) +
                          " m (the bar nearer the toes than their overhang and the clearance "
                          "allow): no plan exists");
  }
  Eigen::VectorXd warm;
  if (!o.warm_start.empty()) {
    const core::Plan wp = core::loadPlan(o.warm_start);
    const nlohmann::json ws = nlohmann::json::parse(wp.summary_json, nullptr, false);
    if (!ws.is_object() || !ws.contains("x") || !ws["x"].is_array())
      throw InputError(o.warm_start + ": no solution vector (summary.x) to start from");
    checkWarmLayout(o.warm_start, wp, cfg);
    const auto xs = ws["x"].get<std::vector<double>>();
    warm = Eigen::Map<const Eigen::VectorXd>(xs.data(), static_cast<Eigen::Index>(xs.size()));
    if (warm.size() != problem.layout().total)
      throw InputError(o.warm_start + ": " + std::to_string(warm.size()) +
                       " variables, this configuration has " +
                       std::to_string(problem.layout().total));
  }
  std::fprintf(log, "overstep plan: %d variables, %d inequalities, %d equalities, %s, %d threads\n",
               problem.layout().total, problem.inequalityCount(), problem.equalityCount(),
               cfg.solver.algorithm.c_str(), cfg.solver.threads);
  std::fprintf(log, "%5s %5s %14s %12s %10s %9s  %s\n", "stage", "iter", "objective", "max viol",
               "step", "elapsed", "most violated row");
  auto row = [log](const planner::IterationInfo& i) {
    std::fprintf(log, "%5d %5d %14.6g %12.3g %10.3g %8.1fs  %s\n", i.stage, i.iteration,
                 i.objective, i.max_violation, i.step, i.elapsed, i.worst.c_str());
    std::fflush(log);
  };
  auto solver = planner::makeNloptSolver(cfg.solver, row, &cli::StopSignals::flag());
  planner::PlanOutcome out;
  planner::WorkAccount refined_work;  // re-solves after the 1 kHz check (refineByCheck)
  std::optional<CheckedPlan> last_check;
  if (o.resample) {
    // No solve: the stored solution, evaluated and sampled with this configuration.
    if (warm.size() == 0) throw InputError("--resample needs --warm-start PLAN");
    out.final.x = warm;
    problem.evaluate(warm, out.final.evaluation);
    out.final.objective = out.final.evaluation.objective;
    out.final.status = "resampled";
    for (int f = 0; f < static_cast<int>(planner::Family::kCount); ++f) {
      const double wv = out.final.evaluation.worst[static_cast<std::size_t>(f)];
      out.final.max_violation = std::max(out.final.max_violation, wv);
      if (wv > planner::kFeasibilityTolerance)
        out.violated.push_back(planner::familyName(static_cast<planner::Family>(f)));
    }
    out.valid = out.final.max_violation <= planner::kFeasibilityTolerance;
  } else {
    out = planner::planOverstep(
        problem, *solver, cfg.solver.time_limit,
        [log](const std::string& s) {
          std::fprintf(log, "-- %s\n", s.c_str());
          std::fflush(log);
        },
        row, &cli::StopSignals::flag(), warm.size() ? &warm : nullptr,
        checkAccepts(problem, model, o.rate, log));
    refined_work =
        refineByCheck(problem, *solver, cfg, ob, model, o.rate, log, row, out, last_check);
  }

  const Eigen::VectorXd& x = out.final.x;
  nlohmann::json summary;
  summary["status"] =
      cli::StopSignals::requested() ? "interrupted" : (out.valid ? "solved" : "infeasible");
  summary["solver_status"] = out.final.status;
  summary["valid"] = out.valid;
  summary["planner_version"] = planner::plannerVersion();
  summary["duration"] = problem.durations(x).sum();
  summary["phase_durations"] = std::vector<double>(x.data(), x.data() + planner::kPhaseCount);
  summary["step_length"] = problem.stepLength(x);
  summary["foot_spacing"] = problem.footSpacing(x);
  summary["solve_time"] = out.solve_time;
  summary["iterations"] = out.iterations;
  summary["evaluations"] = problem.evaluationCount() + refined_work.evaluations;
  summary["jacobians"] = problem.work().jacobians + refined_work.jacobians;
  summary["time_split"] = {{"derivatives", out.split.derivatives},
                           {"evaluations", out.split.evaluations},
                           {"nlopt", out.split.nlopt},
                           {"restoration", out.split.restoration},
                           {"other", out.split.other}};
  summary["objective"] = out.final.objective;
  summary["x"] = std::vector<double>(x.data(), x.data() + x.size());  // for --warm-start
  nlohmann::json terms;
  for (std::size_t i = 0; i < planner::objectiveTermNames().size(); ++i)
    terms[planner::objectiveTermNames()[i]] = out.final.evaluation.terms[i];
  summary["objective_terms"] = terms;
  nlohmann::json viol;
  for (int f = 0; f < static_cast<int>(planner::Family::kCount); ++f)
    viol[planner::familyName(static_cast<planner::Family>(f))] =
        std::max(0.0, out.final.evaluation.worst[static_cast<std::size_t>(f)]);
  summary["max_violation"] = viol;
  summary["obstacle"] = {{"shape", o.shape},
                         {"height", ob.height},
                         {"width", ob.width},
                         {"gap", ob.gap},
                         {"margin", ob.margin}};

  // The planner's word is not enough: the written plan must also pass the independent check.
  core::Plan plan = last_check ? std::move(last_check->plan) : problem.toPlan(x, o.rate);
  const planner::CheckReport report =
      last_check ? std::move(last_check->report) : planner::checkPlan(plan, model);
  std::vector<std::string> violated = out.violated;
  for (const auto& f : report.families)
    if (!f.ok()) violated.push_back("check:" + f.name);
  const bool valid = out.valid && report.valid;
  summary["valid"] = valid;
  summary["status"] =
      cli::StopSignals::requested() ? "interrupted" : (valid ? "solved" : "infeasible");
  nlohmann::json checked;
  for (const auto& f : report.families) checked[f.name] = f.worst;
  summary["check"] = {{"valid", report.valid}, {"worst", checked}};
  const std::string path = valid ? o.out : failedPath(o.out);
  summary["file"] = path;
  plan.summary_json = summary.dump();
  core::savePlan(plan, path);

  std::fprintf(
      log,
      "%s: duration %.3f s, step length %.3f m, foot spacing %.3f m, %d iterations, %.1f s -> %s\n",
      valid ? "valid plan"
            : (out.valid ? "planner-feasible, rejected by the 1 kHz check" : "no valid plan"),
      summary["duration"].get<double>(), summary["step_length"].get<double>(),
      summary["foot_spacing"].get<double>(), out.iterations, out.solve_time, path.c_str());
  std::fprintf(log,
               "time: derivatives %.1f s, evaluations %.1f s, NLopt %.1f s, restoration %.1f s, "
               "other %.1f s (%d Jacobians, %d evaluations)\n",
               out.split.derivatives, out.split.evaluations, out.split.nlopt, out.split.restoration,
               out.split.other, summary["jacobians"].get<int>(), summary["evaluations"].get<int>());
  if (o.json) std::cout << summary.dump(2) << "\n";
  if (cli::StopSignals::requested()) {
    cli::printError("plan", "interrupted; best attempt written to " + path);
    return kExitInterrupted;
  }
  if (!valid) {
    std::string fams;
    for (const auto& f : violated) fams += (fams.empty() ? "" : ", ") + f;
    throw InfeasibleError("no valid plan found (still violated: " +
                          (fams.empty() ? std::string("homotopy not completed") : fams) +
                          "); best attempt written to " + path);
  }
  return kExitOk;
}

struct CheckOptions {
  std::string plan, robot, trace;
  double rate = 1000.0;
  bool json = false;
};

int runCheck(const CheckOptions& o) {
  const core::Plan plan = core::loadPlan(o.plan);
  const robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(o.robot);
  const planner::CheckReport r = planner::checkPlan(plan, model, o.rate, !o.trace.empty());
  if (!o.trace.empty()) {
    std::string csv = "t";
    for (const auto& f : r.families) csv += "," + f.name + " [" + f.unit + "]";
    csv += ",phase\n";
    char buf[64];
    for (std::size_t i = 0; i < r.trace_t.size(); ++i) {
      std::snprintf(buf, sizeof buf, "%.4f", r.trace_t[i]);
      csv += buf;
      for (double v : r.trace[i]) {
        std::snprintf(buf, sizeof buf, ",%.6g", std::isfinite(v) ? v : 0.0);
        csv += buf;
      }
      csv += "," + std::to_string(r.trace_phase[i]) + "\n";
    }
    core::writeFileAtomic(o.trace, csv);
  }
  if (o.json) {
    nlohmann::json j;
    j["valid"] = r.valid;
    j["grid_points"] = r.grid_points;
    j["rate"] = r.rate;
    j["duration"] = plan.duration();
    nlohmann::json fam;
    for (const auto& f : r.families) {
      fam[f.name] = {{"worst", f.worst}, {"tolerance", f.tolerance}, {"unit", f.unit},
                     {"t", f.t_worst},   {"where", f.detail},        {"ok", f.ok()}};
    }
    j["families"] = fam;
    std::cout << j.dump(2) << "\n";
  } else {
    std::printf("plan %s: %.3f s, %d samples; checked on %d points at %.0f Hz\n", o.plan.c_str(),
                plan.duration(), plan.samples(), r.grid_points, r.rate);
    std::printf("%-15s %12s %10s %-9s %8s  %s\n", "family", "worst", "tolerance", "unit", "t (s)",
                "where");
    for (const auto& f : r.families) {
      std::printf("%-15s %12.4g %10.3g %-9s %8.3f  %s%s\n", f.name.c_str(), f.worst, f.tolerance,
                  f.unit.c_str(), f.t_worst, f.detail.c_str(), f.ok() ? "" : "  <-- VIOLATED");
    }
    std::printf("%s\n", r.valid ? "VALID" : "INVALID");
  }
  return r.valid ? kExitOk : kExitInfeasible;
}

}  // namespace

void registerPlanCommands(CLI::App& app, cli::Registry& registry) {
  auto po = std::make_shared<PlanOptions>();
  po->robot = cli::defaultRobotPath();
  CLI::App* plan = app.add_subcommand("plan", "Plan the two-step motion over the obstacle (NLopt)");
  plan->add_option("--robot", po->robot, "Robot YAML")->capture_default_str();
  plan->add_option("--config", po->config,
                   "Planner YAML (default: embedded defaults, see planner/planner.yaml)");
  plan->add_option("--obstacle-height", po->height, "Envelope height incl. safety margin, m")
      ->capture_default_str();
  plan->add_option("--obstacle-width", po->width, "Envelope width along x, m")
      ->capture_default_str();
  plan->add_option("--obstacle-shape", po->shape, "box or cylinder")->capture_default_str();
  plan->add_option("--obstacle-gap", po->gap, "Distance from the start toes to the bar, m")
      ->capture_default_str();
  plan->add_option("--margin", po->margin, "Extra clearance on every side, m")
      ->capture_default_str();
  plan->add_option("--out", po->out, "Plan file (written atomically)")->capture_default_str();
  plan->add_option("--threads", po->threads, "Threads for gradients (default from config: 2)");
  plan->add_option("--time-limit", po->time_limit,
                   "Seconds for the whole solve (default from config)");
  plan->add_option("--rate", po->rate, "Sample rate of the plan file, Hz")->capture_default_str();
  CLI::Option* excite =
      plan->add_option("--excite", po->excite,
                       "Write an identification experiment of this many seconds instead: standing, "
                       "chest, head and arms swinging (overstep identify)");
  plan->add_option("--amplitude", po->amplitude, "Scale of the --excite swings (0, 2]")
      ->capture_default_str();
  CLI::Option* stand = plan->add_option(
      "--stand", po->stand,
      "Write a static standing plan of this many seconds instead (runtime bring-up)");
  plan->add_option("--warm-start", po->warm_start,
                   "Start from the solution stored in a plan file (same configuration): only the "
                   "target stage runs");
  plan->add_flag("--resample", po->resample,
                 "With --warm-start: no solve, write the stored solution sampled with this "
                 "configuration (e.g. another --rate)");
  plan->add_flag("--json", po->json,
                 "Print the summary as one JSON object on stdout (progress on stderr)");
  plan->footer(
      "Examples:\n"
      "  overstep plan                                   # 20 cm x 11 cm bar -> plan.json\n"
      "  overstep plan --obstacle-height 0.05 --out small.json\n"
      "  overstep plan --obstacle-shape cylinder --json > summary.json\n"
      "  overstep plan --obstacle-height 0.05 --warm-start small.failed.json --out small.json\n"
      "Exit: 0 valid plan written; 2 bad input; 3 no valid plan (best attempt in\n"
      "<out>.failed.json); 130 interrupted (Ctrl-C or SIGTERM keeps the best attempt).");
  registry.add(plan, [po, stand, excite] {
    po->stand_given = stand->count() > 0;
    po->excite_given = excite->count() > 0;
    return runPlan(*po);
  });

  auto co = std::make_shared<CheckOptions>();
  co->robot = cli::defaultRobotPath();
  CLI::App* check = app.add_subcommand("check", "Re-verify a plan independently on a dense grid");
  check->add_option("plan", co->plan, "Plan file")->required();
  check->add_option("--robot", co->robot, "Robot YAML")->capture_default_str();
  check->add_option("--rate", co->rate, "Grid rate, Hz")->capture_default_str();
  check->add_flag("--json", co->json, "Print {valid, families} as JSON");
  check->add_option("--trace", co->trace,
                    "Write each family's worst value at every grid point to this CSV "
                    "(0 where a family has nothing to check)");
  check->footer(
      "Examples:\n"
      "  overstep check plan.json\n"
      "  overstep check plan.json --json | jq .valid\n"
      "  overstep check plan.json --trace families.csv   # where violations build up\n"
      "Exit: 0 valid; 3 invalid (the table names the families); 2 bad input.");
  registry.add(check, [co] { return runCheck(*co); });
}

}  // namespace overstep
