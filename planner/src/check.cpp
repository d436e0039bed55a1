#include "overstep/planner/check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "overstep/core/error.hpp"
#include "overstep/core/rotation.hpp"
#include "overstep/core/wrench.hpp"
#include "overstep/robots/collision.hpp"
#include "overstep/robots/leg.hpp"

namespace overstep::planner {
namespace {

std::string fmt(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

double jsonNumber(const nlohmann::json& j, const char* key, double fallback) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : fallback;
}

struct Tracker {
  CheckFamily f;
  double point = -std::numeric_limits<double>::infinity();  // worst at the current grid point
  Tracker(std::string name, double tol, std::string unit) {
    f.name = std::move(name);
    f.tolerance = tol;
    f.unit = std::move(unit);
    f.worst = -std::numeric_limits<double>::infinity();
  }
  void add(double v, double t, const std::string& detail) {
    point = std::max(point, v);
    if (v > f.worst) {
      f.worst = v;
      f.t_worst = t;
      f.detail = detail;
    }
  }
};

}  // namespace

const CheckFamily* CheckReport::family(const std::string& name) const {
  for (const auto& f : families)
    if (f.name == name) return &f;
  return nullptr;
}

CheckReport checkPlan(const core::Plan& plan, const robots::WholeBodyModel& model_in,
                      double rate_hz, bool trace) {
  robots::WholeBodyModel model(model_in);
  const auto& d = model.description();
  if (plan.robot_hash != d.hashHex()) {
    throw InputError("plan was made for robot '" + plan.robot_name + "' (hash " + plan.robot_hash +
                     "), not for " + d.yaml_path + " (hash " + d.hashHex() + ")");
  }
  if (plan.q.rows() != model.dofs() || plan.tau.rows() != model.actuatedCount()) {
    throw InputError("plan has " + std::to_string(plan.q.rows()) + " coordinates, robot has " +
                     std::to_string(model.dofs()));
  }
  if (!(rate_hz > 0.0 && rate_hz <= core::Plan::kMaxRate))
    throw InputError("check rate: expected a rate in (0, " + fmt(core::Plan::kMaxRate) +
                     "] Hz, got " + fmt(rate_hz));
  core::validatePlan(plan, "plan '" + plan.robot_name + "'");
  nlohmann::json cfg = nlohmann::json::parse(plan.config_json, nullptr, false);
  if (cfg.is_discarded()) cfg = nlohmann::json::object();
  const double cop_half = 0.5 * jsonNumber(cfg, "cop_box", 0.01);
  const double mu = jsonNumber(cfg, "friction", 0.7) / std::sqrt(2.0);
  const double torsion = jsonNumber(cfg, "torsion", 0.02);
  const double tilt = jsonNumber(cfg, "pelvis_tilt", 0.005);
  const double mg = model.totalMass() * d.gravity;

  Tracker cop("cop", 1e-3, "m"), fric("friction", 0.02, "ratio"), uni("unilateral", 1.0, "N"),
      clear("clearance", 1e-3, "m"), obst("obstacle", 1e-3, "m"), self("self_collision", 1e-3, "m"),
      lim("joint_limits", 0.5 * M_PI / 180.0, "rad"), vel("velocity", 0.02, "ratio"),
      trq("torque", 0.02, "ratio"), pel("pelvis", 1e-3, "rad"), stance("stance", 1e-3, "m"),
      dyn("dynamics", 1.0, "N or N m");

  const int rf = model.frameIndex(d.foot("right")->sole_frame);
  const int lf = model.frameIndex(d.foot("left")->sole_frame);
  const int sole[2] = {rf, lf};
  const core::FootDescription* foot[2] = {d.foot("right"), d.foot("left")};
  const int base = model.frameIndex(d.base_link);
  std::vector<int> cap_frame;
  for (const auto& c : d.capsules) cap_frame.push_back(model.frameIndex(c.link));

  // Every capsule of the legs' thighs, shanks and feet (the children of the hip pitch and knee
  // joints, and the foot, from the kinematic tree); self-collision: right leg vs left leg.
  std::vector<int> leg_caps, side_caps[2];
  const std::vector<robots::LegChain> legs = robots::legChains(model);
  for (int f = 0; f < 2 && f < static_cast<int>(legs.size()); ++f) {
    const robots::LegChain& c = legs[static_cast<std::size_t>(f)];
    for (const std::string& l : {c.links[2], c.links[3], c.foot_link})
      for (std::size_t i = 0; i < d.capsules.size(); ++i)
        if (d.capsules[i].link == l) {
          leg_caps.push_back(static_cast<int>(i));
          side_caps[f].push_back(static_cast<int>(i));
        }
  }
  std::vector<std::pair<int, int>> pairs;
  for (int a : side_caps[0])
    for (int b : side_caps[1]) pairs.emplace_back(a, b);
  const robots::ObstacleGeometry og =
      robots::ObstacleGeometry::fromSpec(plan.obstacle, plan.toes_x);

  // Stance reference poses: where each foot is when its contact begins.
  Eigen::Isometry3d anchor[2];
  bool anchored[2] = {false, false};

  // The grid in 64 bits and capped: an int overflowed to a negative size and checked nothing.
  const double T = plan.duration();
  const double points = std::floor(T * rate_hz) + 1.0;
  constexpr double kMaxPoints = core::Plan::kMaxDuration * core::Plan::kMaxRate + 1.0;
  if (!(points >= 1.0 && points <= kMaxPoints))
    throw InputError("check grid: " + fmt(points) + " points (duration x rate), expected at most " +
                     fmt(kMaxPoints));
  const auto n = static_cast<std::int64_t>(points);
  CheckReport report;
  report.rate = rate_hz;
  report.grid_points = static_cast<int>(n);
  Tracker* all[] = {&cop, &fric, &uni, &clear, &obst, &self, &lim, &vel, &trq, &pel, &stance, &dyn};
  int k = 0;
  for (std::int64_t i = 0; i < n; ++i) {
    for (Tracker* tr : all) tr->point = -std::numeric_limits<double>::infinity();
    const double t = std::min(static_cast<double>(i) / rate_hz, T);
    while (k + 1 < plan.samples() && plan.t(k + 1) <= t + 1e-12) ++k;
    const double tau_dt = t - plan.t(k);
    // Expansion from the sample at or before t with the acceleration varying linearly to the
    // next sample of the same phase: exact at the samples and consistent with the linear wrench
    // interpolation below (a constant acceleration left ~10-20 N of spurious base-force residual
    // 2-4 ms after each sample; measured).
    Eigen::VectorXd jerk = Eigen::VectorXd::Zero(model.dofs());
    if (k + 1 < plan.samples() && plan.phase(k + 1) == plan.phase(k))
      jerk = (plan.a.col(k + 1) - plan.a.col(k)) / (plan.t(k + 1) - plan.t(k));
    const double h2 = tau_dt * tau_dt;
    const Eigen::VectorXd q = model.integrate(
        plan.q.col(k),
        plan.v.col(k) * tau_dt + 0.5 * plan.a.col(k) * h2 + jerk * (h2 * tau_dt / 6.0), 1.0);
    const Eigen::VectorXd v = plan.v.col(k) + plan.a.col(k) * tau_dt + 0.5 * jerk * h2;
    const Eigen::VectorXd a = plan.a.col(k) + jerk * tau_dt;
    const int ph = plan.phase(k);
    const bool contact[2] = {plan.phases[static_cast<std::size_t>(ph)].right_contact,
                             plan.phases[static_cast<std::size_t>(ph)].left_contact};
    model.setState(q, v, a);
    const Eigen::VectorXd tau = model.inverseDynamics();
    const core::Wrench W = model.contactWrenchFromBase(tau);
    const Eigen::Isometry3d X[2] = {model.framePose(sole[0]), model.framePose(sole[1])};
    core::Wrench w[2];
    const double s = plan.samples() > k + 1 ? tau_dt / (plan.t(k + 1) - plan.t(k)) : 0.0;
    for (int f = 0; f < 2; ++f) {
      // No interpolation across a phase change: the wrench may jump at a contact switch.
      const bool same = k + 1 < plan.samples() && plan.phase(k + 1) == plan.phase(k);
      const core::Wrench w_k = plan.wrench(f, k);
      w[f] = (same ? (1 - s) * w_k + s * plan.wrench(f, k + 1) : w_k).about(X[f].translation());
      if (!contact[f]) w[f] = core::Wrench::zero(core::Axes::kWorld, X[f].translation());
    }
    // Dynamic consistency: base rows and the elastic joints.
    const core::Wrench res = W - w[0] - w[1];  // about the world origin
    dyn.add(res.moment.cwiseAbs().maxCoeff(), t, "base moment");
    dyn.add(res.force.cwiseAbs().maxCoeff(), t, "base force");
    // The robot in contact: actuator torques and the bushings' residual are what inverse
    // dynamics leaves after the feet's wrenches (J^T w), not the torques of a robot hanging
    // from its pelvis.
    const Eigen::VectorXd tau_c = model.torquesInContact(tau, {{sole[0], w[0]}, {sole[1], w[1]}});
    for (int e = 0; e < model.elasticCount(); ++e)
      dyn.add(std::abs(tau_c(model.elasticCoordinate(e))), t,
              d.elastic[static_cast<std::size_t>(e)].name);
    for (int f = 0; f < 2; ++f) {
      const std::string side = f == 0 ? "right" : "left";
      if (contact[f]) {
        const core::Wrench w_S = w[f].inFrame(X[f], core::Axes::kSole);
        const Eigen::Vector3d &mo = w_S.moment, &fo = w_S.force;
        uni.add(-fo.z(), t, side);
        // CoP and friction ratios are meaningless as the load vanishes (lift-off): below 5 % of
        // the weight they are checked in their linear form against that 5 %.
        const double fref = std::max(fo.z(), 0.05 * mg);
        cop.add((std::max(std::abs(mo.y()), std::abs(mo.x())) - cop_half * fo.z()) / fref, t, side);
        fric.add((std::max(std::abs(fo.x()), std::abs(fo.y())) - mu * fo.z()) / (mu * fref), t,
                 side);
        fric.add((std::abs(mo.z()) - torsion * fo.z()) / (torsion * fref), t, side + " torsion");
        if (!anchored[f]) {
          anchor[f] = X[f];
          anchored[f] = true;
        }
        stance.add((X[f].translation() - anchor[f].translation()).norm(), t, side + " position");
        stance.add(0.1 * Eigen::AngleAxisd(anchor[f].linear().transpose() * X[f].linear()).angle(),
                   t, side + " orientation (0.1 m lever)");
      } else {
        anchored[f] = false;
        for (double cx : {foot[f]->sole.x_front, -foot[f]->sole.x_back})
          for (double cy : {foot[f]->yMin(), foot[f]->yMax()})
            clear.add(-(X[f] * Eigen::Vector3d(cx, cy, 0.0)).z(), t, side + " sole corner");
      }
    }
    std::vector<robots::Capsule> wc(d.capsules.size());
    for (std::size_t c = 0; c < d.capsules.size(); ++c) {
      const Eigen::Isometry3d Xc = model.framePose(cap_frame[c]);
      wc[c] = {Xc * d.capsules[c].p0, Xc * d.capsules[c].p1, d.capsules[c].radius};
    }
    for (int c : leg_caps)
      obst.add(-robots::obstacleDistanceFcl(wc[static_cast<std::size_t>(c)], og), t,
               d.capsules[static_cast<std::size_t>(c)].link);
    for (const auto& [a2, b2] : pairs)
      self.add(-robots::capsuleDistance(wc[static_cast<std::size_t>(a2)],
                                        wc[static_cast<std::size_t>(b2)]),
               t,
               d.capsules[static_cast<std::size_t>(a2)].link + "/" +
                   d.capsules[static_cast<std::size_t>(b2)].link);
    for (int j = 0; j < model.actuatedCount(); ++j) {
      const auto& aj = d.actuated[static_cast<std::size_t>(j)];
      const int c = model.actuatedCoordinate(j);
      lim.add(std::max(q(c) - aj.safeUpper(), aj.safeLower() - q(c)), t, aj.name);
      vel.add(std::abs(v(c)) / aj.velocity - 1.0, t, aj.name);
      trq.add(std::abs(tau_c(c)) / aj.torque - 1.0, t, aj.name);
    }
    const Eigen::Matrix3d R = model.framePose(base).linear();
    pel.add(std::abs(core::rollOf(R)) - tilt, t, "roll");
    pel.add(std::abs(core::pitchOf(R)) - tilt, t, "pitch");
    if (trace) {
      report.trace_t.push_back(t);
      report.trace_phase.push_back(ph);
      std::vector<double> row;
      for (const Tracker* tr : all) row.push_back(tr->point);
      report.trace.push_back(std::move(row));
    }
  }
  for (Tracker* tr : all) {
    if (!std::isfinite(tr->f.worst)) tr->f.worst = 0.0;
    report.families.push_back(tr->f);
  }
  report.valid = std::all_of(report.families.begin(), report.families.end(),
                             [](const CheckFamily& f) { return f.ok(); });
  return report;
}

std::vector<double> violationPeaks(const CheckReport& report,
                                   const std::vector<std::string>& families) {
  std::vector<double> peaks;
  for (std::size_t f = 0; f < report.families.size(); ++f) {
    const CheckFamily& fam = report.families[f];
    if (std::find(families.begin(), families.end(), fam.name) == families.end()) continue;
    double worst = 0.0, t_worst = 0.0;
    bool in_run = false;
    for (std::size_t i = 0; i <= report.trace.size(); ++i) {
      const bool over = i < report.trace.size() && f < report.trace[i].size() &&
                        report.trace[i][f] > fam.tolerance;
      if (over && (!in_run || report.trace[i][f] > worst)) {
        worst = report.trace[i][f];
        t_worst = report.trace_t[i];
      }
      if (in_run && !over) peaks.push_back(t_worst);
      in_run = over;
    }
  }
  std::sort(peaks.begin(), peaks.end());
  return peaks;
}

}  // namespace overstep::planner
