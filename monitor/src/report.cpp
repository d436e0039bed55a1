#include "overstep/monitor/report.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "aligned_run.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/json_depth.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/core/rotation.hpp"
#include "overstep/monitor/fidelity.hpp"
#include "overstep/robots/collision.hpp"
#include "overstep/robots/leg.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/runtime/plan_track.hpp"

namespace overstep::monitor {

namespace fs = std::filesystem;

namespace {

using core::rollPitch;

std::string defaultScript() { return shippedScript("monitor/python/report_plots.py"); }

void setMeasured(robots::WholeBodyModel& model, const Row& r, int base_frame, Eigen::VectorXd& q) {
  q.setZero(model.dofs());
  for (int j = 0; j < r.q_meas.size() && j < model.actuatedCount(); ++j)
    q(model.actuatedCoordinate(j)) = r.q_meas(j);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(model.dofs()), a = v;
  model.anchorBase(base_frame, r.base, q, v, a);
}

/// Height above the ground of the lowest corner of foot f's sole rectangle, at the model's state.
double lowestCorner(const robots::WholeBodyModel& model, const core::FootDescription& foot,
                    int sole_frame) {
  const Eigen::Isometry3d X = model.framePose(sole_frame);
  double z = std::numeric_limits<double>::infinity();
  for (const double x : {foot.sole.x_front, -foot.sole.x_back})
    for (const double y : {foot.yMin(), foot.yMax()})
      z = std::min(z, (X * Eigen::Vector3d(x, y, 0.0)).z());
  return z;
}

nlohmann::json capsules(robots::WholeBodyModel& model, const std::vector<int>& frames) {
  const auto& d = model.description();
  nlohmann::json out = nlohmann::json::array();
  for (std::size_t c = 0; c < d.capsules.size(); ++c) {
    const Eigen::Isometry3d X = model.framePose(frames[c]);
    const Eigen::Vector3d a = X * d.capsules[c].p0, b = X * d.capsules[c].p1;
    out.push_back({{"link", d.capsules[c].link},
                   {"p0", {a.x(), a.y(), a.z()}},
                   {"p1", {b.x(), b.y(), b.z()}},
                   {"r", d.capsules[c].radius}});
  }
  return out;
}

/// The fidelity series, one row per tick (plan and hold): per foot the plan's and the measured
/// normal force and local CoP.
std::string fidelityCsv(const RunSeries& s) {
  std::string csv = "t";
  for (const char* f : {"right", "left"})
    for (const char* c : {"fz_plan", "fz_meas", "cop_x_plan", "cop_y_plan", "cop_x_meas",
                          "cop_y_meas", "contact_plan"})
      csv += std::string(",") + f + "_" + c;
  csv += ",base_speed\n";
  char buf[64];
  for (std::size_t i = 0; i < s.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.4f", s.t[i]);
    csv += buf;
    for (const FootSeries& f : s.foot) {
      for (double v : {f.fz_plan[i], f.fz_meas[i], f.cop_plan[i].x(), f.cop_plan[i].y(),
                       f.cop_meas[i].x(), f.cop_meas[i].y()}) {
        std::snprintf(buf, sizeof buf, ",%.6g", v);
        csv += buf;
      }
      csv += f.plan_contact[i] ? ",1" : ",0";
    }
    std::snprintf(buf, sizeof buf, ",%.6g\n", s.base_speed[i]);
    csv += buf;
  }
  return csv;
}

}  // namespace

RunSeries runSeries(const std::string& plan_path, const std::string& log_path,
                    const std::string& robot_path) {
  const core::Plan plan = core::loadPlan(plan_path);
  robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(robot_path);
  runtime::PlanTrack track(plan, model);  // validates the plan against the robot
  const AlignedRun run = alignRun(plan, track, model.actuatedCount(), log_path, plan_path);
  return toSeries(run, plan, model);
}

int writeReportData(const ReportOptions& o_in, ReportSummary& sum) {
  ReportOptions o = o_in;
  if (o.plan.empty()) o.plan = (fs::path(o.run_dir) / "plan.json").string();
  if (o.log.empty()) o.log = (fs::path(o.run_dir) / "bus.lcmlog").string();
  if (o.out.empty()) o.out = (fs::path(o.run_dir) / "report").string();
  if (!fs::exists(o.plan)) throw InputError(o.plan + ": no plan in the run folder");
  if (!fs::exists(o.log)) throw InputError(o.log + ": no LCM log in the run folder");
  const core::Plan plan = core::loadPlan(o.plan);
  robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(o.robot);
  runtime::PlanTrack track(plan, model);  // validates the plan against the robot
  const auto& d = model.description();
  const int nA = model.actuatedCount();
  const double mg = model.totalMass() * d.gravity;
  // The legs' joints (right, then left; hip to ankle) from the kinematic tree.
  std::array<int, 12> leg{};
  const std::vector<robots::LegChain> chains = robots::legChains(model);
  if (chains.size() != 2) throw InputError("the report needs a robot with two legs");
  for (int i = 0; i < 12; ++i)
    leg[static_cast<std::size_t>(i)] =
        chains[static_cast<std::size_t>(i / 6)].actuated[static_cast<std::size_t>(i % 6)];
  const int base_frame = model.frameIndex(d.base_link);
  const int sole_frame[2] = {model.frameIndex(d.feet[0].sole_frame),
                             model.frameIndex(d.feet[1].sole_frame)};
  std::vector<int> cap_frames;
  for (const auto& c : d.capsules) cap_frames.push_back(model.frameIndex(c.link));

  // ---- align the log: one row per PLAN_REF / STABILIZER pair, with the latest state and command.
  const AlignedRun run = alignRun(plan, track, nA, o.log, o.plan);
  const std::vector<Row>& rows = run.rows;
  sum.log_break_offset = run.break_offset;

  // ---- ticks.csv
  const fs::path data = fs::path(o.out) / "data";
  std::error_code ec;
  fs::create_directories(data, ec);
  if (ec) throw InputError(data.string() + ": cannot create the report folder");
  std::string csv =
      "t,phase,zmp_wb_x,zmp_wb_y,zmp_tc_x,zmp_tc_y,zmp_ref_x,zmp_ref_y,zmp_meas_x,zmp_meas_y,"
      "roll_plan,pitch_plan,roll_meas,pitch_meas,stab_level,stab_mode";
  const char* side[2] = {"right", "left"};
  const char* comp[6] = {"Fx", "Fy", "Fz", "Mx", "My", "Mz"};
  for (const char* s : side) {
    for (const char* c : comp) csv += std::string(",") + s + "_" + c + "_plan";
    for (const char* c : comp) csv += std::string(",") + s + "_" + c + "_meas";
    csv += std::string(",") + s + "_cop_x_plan," + s + "_cop_y_plan," + s + "_cop_x_meas," + s +
           "_cop_y_meas," + s + "_contact";
  }
  // Lowest sole corner above the ground: the plan's, the plan's with its bushings undeflected, and
  // the measured one (encoders and the ground-truth base; bushings unmeasured, taken undeflected).
  for (const char* s : side)
    csv += std::string(",") + s + "_sole_z_plan," + s + "_sole_z_plan_rigid," + s + "_sole_z_meas";
  for (int a : leg) {
    const std::string& j = d.actuated[static_cast<std::size_t>(a)].name;
    csv += "," + j + "_plan," + j + "_cmd," + j + "_meas";
  }
  csv += "\n";
  Eigen::VectorXd qm;
  char buf[64];
  auto num = [&](double v) {
    std::snprintf(buf, sizeof buf, ",%.6g", v);
    csv += buf;
  };
  const double fz_min = 0.05 * mg;  // CoP undefined below 5 % of the weight
  for (const Row& r : rows) {
    const int k = r.index;
    std::snprintf(buf, sizeof buf, "%.4f,%d", r.t, r.phase);
    csv += buf;
    num(plan.zmp_wholebody(0, k));
    num(plan.zmp_wholebody(1, k));
    num(plan.zmp_tablecart(0, k));
    num(plan.zmp_tablecart(1, k));
    num(r.zmp_ref.x());
    num(r.zmp_ref.y());
    num(r.zmp_meas.x());
    num(r.zmp_meas.y());
    model.setPositions(plan.q.col(k));
    const Eigen::Vector2d rp_plan = rollPitch(model.framePose(base_frame).linear());
    Eigen::Vector2d rp_meas;
    if (r.ground_truth) {
      rp_meas = rollPitch(r.base.linear());
    } else {
      rp_meas = rollPitch(r.imu.toRotationMatrix());
    }
    num(rp_plan.x());
    num(rp_plan.y());
    num(rp_meas.x());
    num(rp_meas.y());
    num(r.stab_level);
    csv += "," + std::to_string(r.stab_mode);
    for (int f = 0; f < 2; ++f) {
      const core::Wrench wp = planSoleWrench(plan, f, k);
      for (const core::Wrench* w : {&wp, &r.w_meas[f]}) {
        for (int i = 0; i < 3; ++i) num(w->force(i));
        for (int i = 0; i < 3; ++i) num(w->moment(i));
      }
      const bool contact = f == 0 ? plan.phases[static_cast<std::size_t>(r.phase)].right_contact
                                  : plan.phases[static_cast<std::size_t>(r.phase)].left_contact;
      const Eigen::Vector2d cp = loadedCop(wp, fz_min), cm = loadedCop(r.w_meas[f], fz_min);
      num(cp.x());
      num(cp.y());
      num(cm.x());
      num(cm.y());
      csv += contact ? ",1" : ",0";
    }
    // Sole heights: each of the three postures once, both feet from it (columns per foot).
    double sole_z[2][3];
    auto soles = [&](int col) {
      for (int f = 0; f < 2; ++f)
        sole_z[f][col] = lowestCorner(model, d.feet[static_cast<std::size_t>(f)], sole_frame[f]);
    };
    Eigen::VectorXd q = plan.q.col(k);
    model.setPositions(q);
    soles(0);
    for (int e = 0; e < model.elasticCount(); ++e) q(model.elasticCoordinate(e)) = 0.0;
    model.setPositions(q);
    soles(1);
    if (r.ground_truth) {
      setMeasured(model, r, base_frame, qm);
      soles(2);
    } else {
      for (auto& z : sole_z) z[2] = std::numeric_limits<double>::quiet_NaN();
    }
    for (const auto& z : sole_z)
      for (const double v : z) num(v);
    for (int i = 0; i < 12; ++i) {
      const int a = leg[static_cast<std::size_t>(i)];
      num(plan.q(model.actuatedCoordinate(a), k));
      num(r.q_cmd(a));
      num(r.q_meas(a));
    }
    csv += "\n";
  }
  core::writeFileAtomic((data / "ticks.csv").string(), csv);

  // ---- meta.json
  nlohmann::json meta;
  meta["run_dir"] = o.run_dir;
  meta["plan"] = o.plan;
  meta["log"] = o.log;
  meta["duration"] = plan.duration();
  meta["ground_truth"] = rows.back().ground_truth;
  meta["log_break_offset"] = sum.log_break_offset;
  nlohmann::json phases = nlohmann::json::array();
  for (const auto& p : plan.phases)
    phases.push_back({{"name", p.name},
                      {"start", p.start},
                      {"duration", p.duration},
                      {"right_contact", p.right_contact},
                      {"left_contact", p.left_contact}});
  meta["phases"] = phases;
  nlohmann::json joints = nlohmann::json::array();
  for (int i = 0; i < 12; ++i) {
    const auto& aj = d.actuated[static_cast<std::size_t>(leg[static_cast<std::size_t>(i)])];
    joints.push_back({{"name", aj.name},
                      {"lower", aj.lower},
                      {"upper", aj.upper},
                      {"safe_lower", aj.safeLower()},
                      {"safe_upper", aj.safeUpper()}});
  }
  meta["joints"] = joints;
  nlohmann::json cfg = nlohmann::json::parse(plan.config_json, nullptr, false);
  meta["cop_box"] =
      cfg.is_object() && cfg.contains("cop_box") ? cfg["cop_box"].get<double>() : 0.01;
  meta["pelvis_tilt"] =
      cfg.is_object() && cfg.contains("pelvis_tilt") ? cfg["pelvis_tilt"].get<double>() : 0.005;
  for (int f = 0; f < 2; ++f) {
    const auto* fd = d.foot(side[f]);
    meta["soles"][side[f]] = {{"x_front", fd->sole.x_front},
                              {"x_back", -fd->sole.x_back},
                              {"y_min", fd->yMin()},
                              {"y_max", fd->yMax()}};
  }
  const robots::ObstacleGeometry og =
      robots::ObstacleGeometry::fromSpec(plan.obstacle, plan.toes_x);
  meta["obstacle"] = {
      {"shape", plan.obstacle.shape == core::ObstacleSpec::Shape::Box ? "box" : "cylinder"},
      {"x_min", plan.obstacle.nearX(plan.toes_x)},
      {"x_max", plan.obstacle.farX(plan.toes_x)},
      {"height", plan.obstacle.envelopeHeight()},
      {"centre", {og.centre.x(), og.centre.y(), og.centre.z()}},
      {"radius", og.radius}};
  core::writeFileAtomic((data / "meta.json").string(), meta.dump(1));

  // ---- frames.json: the side-view sequence, plan and measurement at the same plan times.
  nlohmann::json frames = nlohmann::json::array();
  const int nf = o.frames;
  for (int i = 0; i < nf; ++i) {
    const double t = rows.front().t + (rows.back().t - rows.front().t) * i / (nf - 1);
    std::size_t best = 0;
    for (std::size_t k = 0; k < rows.size(); ++k)
      if (std::abs(rows[k].t - t) < std::abs(rows[best].t - t)) best = k;
    const Row& r = rows[best];
    nlohmann::json fr;
    fr["t"] = r.t;
    fr["phase"] = plan.phases[static_cast<std::size_t>(r.phase)].name;
    model.setPositions(plan.q.col(r.index));
    fr["plan"] = capsules(model, cap_frames);
    if (r.ground_truth) {
      setMeasured(model, r, base_frame, qm);
      fr["measured"] = capsules(model, cap_frames);
    } else {
      fr["measured"] = nullptr;
    }
    frames.push_back(fr);
  }
  core::writeFileAtomic((data / "frames.json").string(), frames.dump());

  // ---- fidelity.json / fidelity.csv: the execution's figures (issue 19) and their series.
  const RunSeries series = toSeries(run, plan, model);
  sum.fidelity = fidelityJson(computeFidelity(series));
  core::writeFileAtomic((data / "fidelity.json").string(), sum.fidelity.dump(1));
  core::writeFileAtomic((data / "fidelity.csv").string(), fidelityCsv(series));

  sum.out_dir = o.out;
  sum.ticks = static_cast<int>(rows.size());
  sum.t_begin = rows.front().t;
  sum.t_end = rows.back().t;
  return sum.ticks;
}

std::string shippedScript(const std::string& relative) {
  return (fs::path(OVERSTEP_DATA_DIR) / relative).string();
}

void runPlotScript(const std::string& python, const std::string& script,
                   const std::vector<std::string>& args, const std::string& what) {
  if (!fs::exists(script)) throw InputError(script + ": plotting script not found");
  std::vector<std::string> all = {python, script};
  all.insert(all.end(), args.begin(), args.end());
  std::string cmd;
  std::vector<char*> argv;
  for (auto& a : all) {
    cmd += (cmd.empty() ? "" : " ") + a;
    argv.push_back(const_cast<char*>(a.c_str()));
  }
  argv.push_back(nullptr);
  pid_t pid = -1;
  if (posix_spawnp(&pid, python.c_str(), nullptr, nullptr, argv.data(), environ) != 0)
    throw std::runtime_error(what + ": cannot start " + python);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw std::runtime_error(what + ": the plotting script failed (" + cmd + ", status " +
                             std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                             "); is python3-matplotlib installed?");
  }
}

void checkReportOptions(const ReportOptions& o) {
  if (o.dpi < 20 || o.dpi > 400) throw InputError("--dpi: expected 20..400");
  // The sequence figure has a panel per frame, four to a row (issue 20: 100000 frames drew
  // without end).
  if (o.frames < 2 || o.frames > kMaxFrames)
    throw InputError("--frames: expected 2 to " + std::to_string(kMaxFrames) + ", got " +
                     std::to_string(o.frames));
}

ReportSummary makeReport(const ReportOptions& o_in) {
  ReportOptions o = o_in;
  if (o.out.empty()) o.out = (fs::path(o.run_dir) / "report").string();
  if (o.script.empty()) o.script = defaultScript();
  checkReportOptions(o);
  ReportSummary sum;
  writeReportData(o, sum);
  if (!fs::exists(o.script)) throw InputError(o.script + ": plotting script not found");
  runPlotScript(o.python, o.script, {o.out, std::to_string(o.dpi)}, "report");
  sum.index_html = (fs::path(o.out) / "index.html").string();
  sum.manifest = (fs::path(o.out) / "report.json").string();
  std::string text;
  {
    std::ifstream in(sum.manifest);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  constexpr int kMaxDepth = 32;  // the manifest nests 5 deep (figures[].axes[].series[])
  const nlohmann::json man = core::jsonDepth(text, kMaxDepth) > kMaxDepth
                                 ? nlohmann::json(nlohmann::json::value_t::discarded)
                                 : nlohmann::json::parse(text, nullptr, false);
  if (man.is_discarded() || !man.is_object() || !man.contains("figures") ||
      !man["figures"].is_array())
    throw std::runtime_error("report: " + sum.manifest + " missing or unreadable");
  for (const auto& f : man["figures"])
    sum.figures.push_back((fs::path(o.out) / f["file"].get<std::string>()).string());
  return sum;
}

}  // namespace overstep::monitor
