#include "overstep/monitor/fidelity.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace overstep::monitor {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

/// Linear-interpolated percentile (p in [0, 1]) of unsorted values; NaN when empty.
double percentile(std::vector<double> v, double p) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const double u = p * static_cast<double>(v.size() - 1);
  const auto k = static_cast<std::size_t>(std::floor(u));
  const std::size_t k1 = std::min(k + 1, v.size() - 1);
  return v[k] + (u - static_cast<double>(k)) * (v[k1] - v[k]);
}

/// The median tick interval (the runtime's period; robust to a missing tick).
double medianDt(const std::vector<double>& t) {
  std::vector<double> d;
  for (std::size_t i = 1; i < t.size(); ++i)
    if (t[i] > t[i - 1]) d.push_back(t[i] - t[i - 1]);
  return d.empty() ? kNaN : percentile(d, 0.5);
}

/// [first, last) tick ranges where `pred(i)` holds.
template <class Pred>
std::vector<std::pair<std::size_t, std::size_t>> segments(std::size_t n, Pred pred) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  std::size_t i = 0;
  while (i < n) {
    if (!pred(i)) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < n && pred(j)) ++j;
    out.emplace_back(i, j);
    i = j;
  }
  return out;
}

/// Contact losses in one planned-contact interval [i0, i1) of a foot, the interval widened back
/// by `before` s to see an early contact: after the first measured contact (Fz above the on
/// level), every stretch below the off level lasting at least `min_duration` while the plan
/// loads the foot above the on level is a loss; a foot that never makes contact is one loss.
/// Where the plan's own force is below the on level (its load ramping to zero before a lift-off,
/// the look-back before a touchdown) the plan is not in contact by the same measure, and a
/// measured foot off the ground there is a lift-off's timing, not a loss.
int lossesIn(const RunSeries& run, const FootSeries& f, std::size_t i0, std::size_t i1,
             const FidelityParams& p) {
  const double on = p.contact_on * run.weight, off = p.contact_off * run.weight;
  std::size_t i = i0;
  while (i > 0 && run.t[i - 1] >= run.t[i0] - p.touchdown_before) --i;
  bool in_contact = false, ever = false;
  double left_at = 0.0;
  int losses = 0;
  for (; i < i1; ++i) {
    const double fz = f.fz_meas[i];
    if (!in_contact && fz > on) {
      in_contact = ever = true;
    } else if (in_contact && fz < off) {
      in_contact = false;
      left_at = run.t[i];
    }
    if (f.fz_plan[i] < on && !in_contact && left_at >= 0.0) left_at = run.t[i];
    // A dip counts once it has lasted min_duration (and it is counted once).
    if (ever && !in_contact && left_at >= 0.0 && run.t[i] - left_at >= p.loss_min_duration) {
      ++losses;
      left_at = -1.0;
    }
  }
  return ever ? losses : 1;
}

int contactLosses(const RunSeries& run, const FootSeries& f, const FidelityParams& p) {
  int losses = 0;
  const auto contact = segments(run.size(), [&](std::size_t i) { return f.plan_contact[i] != 0; });
  for (const auto& [i0, i1] : contact) losses += lossesIn(run, f, i0, i1, p);
  return losses;
}

double peakTouchdownLoad(const RunSeries& run, const FootSeries& f,
                         const std::vector<double>& touchdowns, const FidelityParams& p) {
  if (touchdowns.empty()) return kNaN;
  double peak = 0.0;
  for (double td : touchdowns)
    for (std::size_t i = 0; i < run.size(); ++i)
      if (run.t[i] >= td - p.touchdown_before && run.t[i] <= td + p.touchdown_after)
        peak = std::max(peak, f.fz_meas[i]);
  return peak / run.weight;
}

/// The first measured contact around each planned touchdown against the plan's own (see
/// FootFidelity).
double touchdownTiming(const RunSeries& run, const FootSeries& f,
                       const std::vector<double>& touchdowns, const FidelityParams& p) {
  const double level = p.contact_on * run.weight;
  // The first tick in the touchdown's window whose series is above the contact level.
  auto first = [&](const std::vector<double>& fz, double td, double from) {
    for (std::size_t i = 0; i < run.size(); ++i)
      if (run.t[i] >= from && run.t[i] <= td + p.touchdown_after && fz[i] > level) return run.t[i];
    return kNaN;
  };
  double worst = kNaN;
  for (double td : touchdowns) {
    const double measured = first(f.fz_meas, td, td - p.touchdown_before);
    if (std::isnan(measured)) return kNaN;  // never landed in the window: a contact loss already
    const double planned = first(f.fz_plan, td, td);  // a plan that ramps its load in
    const double timing = measured - (std::isnan(planned) ? td : planned);
    if (std::isnan(worst) || std::abs(timing) > std::abs(worst)) worst = timing;
  }
  return worst;
}

void copDeviation(const RunSeries& run, const FootSeries& f, const FidelityParams& p,
                  FootFidelity& out) {
  const double loaded = p.loaded_fraction * run.weight;
  std::vector<double> dev;
  for (std::size_t i = 0; i < run.size(); ++i) {
    if (!(f.fz_plan[i] > loaded && f.fz_meas[i] > loaded)) continue;
    const double d = (f.cop_meas[i] - f.cop_plan[i]).norm();
    if (std::isfinite(d)) dev.push_back(d);
  }
  out.cop_samples = static_cast<int>(dev.size());
  out.cop_p50 = percentile(dev, 0.5);
  out.cop_p95 = percentile(dev, 0.95);
  out.cop_max = dev.empty() ? kNaN : *std::max_element(dev.begin(), dev.end());
}

/// RMS of the high-passed moment vector over the foot's single supports (as the stance foot),
/// each trimmed at both ends; 0 when the run has none.
double chatter(const RunSeries& run, int side, const FidelityParams& p) {
  const FootSeries& f = run.foot[static_cast<std::size_t>(side)];
  const FootSeries& o = run.foot[static_cast<std::size_t>(1 - side)];
  const double dt = medianDt(run.t);
  if (!std::isfinite(dt)) return 0.0;
  const auto ss = segments(run.size(), [&](std::size_t i) {
    return f.plan_contact[i] != 0 && o.plan_contact[i] == 0 && run.t[i] <= run.plan_end;
  });
  const auto trim = static_cast<std::size_t>(std::ceil(p.chatter_trim / dt));
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& [i0, i1] : ss) {
    if (i1 - i0 <= 2 * trim + 4) continue;
    std::vector<double> x(i1 - i0), y(i1 - i0);
    for (std::size_t k = 0; k < x.size(); ++k) {
      x[k] = f.moment_meas[i0 + k].x();
      y[k] = f.moment_meas[i0 + k].y();
    }
    const std::vector<double> hx = highPass(x, dt, p.chatter_cutoff);
    const std::vector<double> hy = highPass(y, dt, p.chatter_cutoff);
    for (std::size_t k = trim; k + trim < hx.size(); ++k, ++n) sum += hx[k] * hx[k] + hy[k] * hy[k];
  }
  return n ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
}

void settling(const RunSeries& run, const FidelityParams& p, Fidelity& out) {
  out.settled = false;
  out.settling_time = kNaN;
  out.hold_duration = run.size() ? std::max(0.0, run.t.back() - run.plan_end) : 0.0;
  if (run.base_speed.size() != run.size() || !(out.hold_duration > 0.0)) return;
  // The final static stretch after the plan's end (a NaN speed is not static).
  std::size_t settle = run.size();
  while (settle > 0 && run.t[settle - 1] >= run.plan_end &&
         run.base_speed[settle - 1] < p.settle_speed)
    --settle;
  if (settle == run.size()) return;
  out.settled = true;
  out.settling_time = std::max(0.0, run.t[settle] - run.plan_end);
}

/// A figure against its target: {"value", "target", "met"} (a NaN value is null and not met).
nlohmann::json against(double value, double target) {
  nlohmann::json j;
  j["value"] = std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
  j["target"] = target;
  j["met"] = std::isfinite(value) && value <= target;
  return j;
}

}  // namespace

Eigen::Vector2d loadedCop(const core::Wrench& w_sole, double fz_min) {
  if (!(w_sole.force.z() > fz_min)) return {kNaN, kNaN};
  return core::localCop(w_sole);
}

void RunSeries::resize(std::size_t n) {
  t.resize(n);
  for (auto& f : foot) {
    f.fz_plan.resize(n);
    f.fz_meas.resize(n);
    f.cop_plan.resize(n);
    f.cop_meas.resize(n);
    f.moment_meas.resize(n);
    f.plan_contact.resize(n);
  }
  base_speed.resize(n);
  tilt_plan.resize(n);
  tilt_meas.resize(n);
}

std::vector<double> highPass(const std::vector<double>& x, double dt, double cutoff_hz) {
  // RBJ biquad, Q = 1/sqrt(2), bilinear transform with pre-warping.
  const double w0 = 2.0 * kPi * cutoff_hz * dt;
  const double alpha = std::sin(w0) / (2.0 * std::sqrt(0.5)), c = std::cos(w0);
  const double a0 = 1.0 + alpha;
  const double b0 = (1.0 + c) / 2.0 / a0, b1 = -(1.0 + c) / a0, b2 = b0;
  const double a1 = -2.0 * c / a0, a2 = (1.0 - alpha) / a0;
  auto pass = [&](std::vector<double>& v) {
    double x1 = v.empty() ? 0.0 : v.front(), x2 = x1, y1 = 0.0, y2 = 0.0;  // start at rest
    for (double& s : v) {
      const double y = b0 * s + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2;
      x2 = x1;
      x1 = s;
      y2 = y1;
      y1 = y;
      s = y;
    }
  };
  std::vector<double> y = x;
  pass(y);
  std::reverse(y.begin(), y.end());
  pass(y);
  std::reverse(y.begin(), y.end());
  return y;
}

Fidelity computeFidelity(const RunSeries& run, const FidelityParams& p) {
  assert(run.weight > 0.0);
  Fidelity out;
  for (int s = 0; s < 2; ++s) {
    const auto us = static_cast<std::size_t>(s);
    const FootSeries& f = run.foot[us];
    FootFidelity& r = out.foot[us];
    r.touchdowns = static_cast<int>(run.touchdowns[us].size());
    r.contact_losses = contactLosses(run, f, p);
    r.peak_touchdown_load = peakTouchdownLoad(run, f, run.touchdowns[us], p);
    r.touchdown_timing = touchdownTiming(run, f, run.touchdowns[us], p);
    copDeviation(run, f, p, r);
    r.chatter_rms = chatter(run, s, p);
  }
  for (std::size_t i = 0; i < run.size(); ++i)
    out.pelvis_deviation_max = std::max(
        out.pelvis_deviation_max, (run.tilt_meas[i] - run.tilt_plan[i]).cwiseAbs().maxCoeff());
  settling(run, p, out);
  return out;
}

nlohmann::json fidelityJson(const Fidelity& f, const FidelityTargets& t) {
  nlohmann::json j;
  std::vector<std::string> misses;
  auto add = [&](nlohmann::json& into, const std::string& name, double value, double target,
                 const std::string& who) {
    into[name] = against(value, target);
    if (!into[name]["met"].get<bool>()) misses.push_back(who + name);
  };
  const char* side[2] = {"right", "left"};
  for (int s = 0; s < 2; ++s) {
    const FootFidelity& r = f.foot[static_cast<std::size_t>(s)];
    nlohmann::json& foot = j["feet"][side[s]];
    foot["touchdowns"] = r.touchdowns;
    foot["cop_samples"] = r.cop_samples;
    const std::string who = std::string(side[s]) + ".";
    add(foot, "contact_losses", r.contact_losses, t.contact_losses, who);
    // A foot that never touches down has no touchdown load: nothing to meet.
    if (r.touchdowns > 0) {
      add(foot, "peak_touchdown_load", r.peak_touchdown_load, t.peak_touchdown_load, who);
    } else {
      foot["peak_touchdown_load"] = nullptr;
    }
    // Reported, no target of its own (the losses and loads judge what it causes).
    foot["touchdown_timing"] =
        std::isfinite(r.touchdown_timing) ? nlohmann::json(r.touchdown_timing) : nullptr;
    add(foot, "cop_deviation_p95", r.cop_p95, t.cop_p95, who);
    add(foot, "cop_deviation_max", r.cop_max, t.cop_max, who);
    foot["cop_deviation_p50"] = std::isfinite(r.cop_p50) ? nlohmann::json(r.cop_p50) : nullptr;
    add(foot, "chatter_rms", r.chatter_rms, t.chatter_rms, who);
  }
  add(j, "pelvis_deviation_max", f.pelvis_deviation_max, t.pelvis_deviation, "");
  add(j, "settling_time", f.settling_time, t.settling_time, "");
  j["hold_duration"] = f.hold_duration;
  j["meets_targets"] = misses.empty();
  j["misses"] = misses;
  return j;
}

}  // namespace overstep::monitor
