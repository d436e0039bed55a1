#pragma once
/// \file
/// Execution fidelity of a run (issue 19): per foot, what the force sensors measured against what
/// the plan asked for — contact losses, touchdown loads, local CoP deviation, moment chatter —
/// plus the pelvis tilt against the plan's and the settling time after the plan. Computed from
/// the recorded sensor readings only (the log's OVERSTEP_STATE against its OVERSTEP_PLAN_REF
/// ticks), so a run from hardware gives the same figures as one from the simulator; the base
/// speed needs a ground truth or an estimate (NaN otherwise: the settling time is then not
/// measured). docs/report.md defines each figure.

#include <Eigen/Core>
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "overstep/core/wrench.hpp"

namespace overstep::monitor {

/// One foot's series, one entry per aligned tick. Sole frame of that foot (x forward, z up),
/// wrenches about the sole origin; N and N m.
struct FootSeries {
  std::vector<double> fz_plan, fz_meas;             ///< normal force, N
  std::vector<Eigen::Vector2d> cop_plan, cop_meas;  ///< local CoP, m (NaN where unloaded)
  std::vector<Eigen::Vector2d> moment_meas;         ///< measured [Mx, My], N m
  std::vector<char> plan_contact;                   ///< the plan's contact flag (0 / 1)
};

/// A run as aligned ticks: the plan's execution, then the hold after it (t > plan_end, the plan's
/// last sample held).
struct RunSeries {
  std::vector<double> t;           ///< s, plan time; past plan_end: the time since the plan's start
  double plan_end = 0.0;           ///< s
  double weight = 0.0;             ///< the robot's weight, N
  std::array<FootSeries, 2> foot;  ///< right, left
  std::array<std::vector<double>, 2> touchdowns;      ///< planned touchdown times per foot, s
  std::vector<double> base_speed;                     ///< m/s, NaN where not measured
  std::vector<Eigen::Vector2d> tilt_plan, tilt_meas;  ///< pelvis [roll, pitch], rad

  /// Ticks held (every series has this length: resize() sets them all).
  std::size_t size() const { return t.size(); }
  void resize(std::size_t n);
};

/// Definitions of the figures (each value's meaning in docs/report.md).
struct FidelityParams {
  double loaded_fraction = 0.10;  ///< CoP compared where plan and measurement carry > this x weight
  double contact_on = 0.05;       ///< measured contact begins above this x weight ...
  double contact_off = 0.02;      ///< ... and ends below this x weight (hysteresis)
  double loss_min_duration = 0.01;  ///< s: a shorter dip is not a contact loss
  double touchdown_before = 0.2;    ///< s before a planned touchdown: an early contact counts
  double touchdown_after = 0.5;     ///< s after it: the window of the touchdown's peak load
  double chatter_cutoff = 20.0;     ///< Hz: moment content above it is chatter
  double chatter_trim = 0.05;       ///< s dropped at each end of a single support (filter edges)
  double settle_speed = 0.01;       ///< m/s: static below it
};

struct FootFidelity {
  int touchdowns = 0;      ///< planned touchdowns in the run
  int contact_losses = 0;  ///< planned-contact intervals left (or never reached) by the foot
  double peak_touchdown_load = 0.0;  ///< largest Fz around a touchdown / weight (NaN: none)
  /// s, measured first contact (Fz above contact_on) minus the plan's (its first load above the
  /// same level after the touchdown, which a plan that ramps the landing foot's load in reaches
  /// after the touchdown instant), the largest in magnitude over the foot's touchdowns (signed:
  /// < 0 early; NaN: none, or never landed)
  double touchdown_timing = 0.0;
  double cop_p50 = 0.0, cop_p95 = 0.0, cop_max = 0.0;  ///< m, |CoP_meas - CoP_plan|
  int cop_samples = 0;                                 ///< ticks where both load the foot
  double chatter_rms = 0.0;  ///< N m, RMS of |(Mx, My)| above the cutoff in single support
};

struct Fidelity {
  std::array<FootFidelity, 2> foot;   ///< right, left
  double pelvis_deviation_max = 0.0;  ///< rad, largest roll or pitch difference from the plan
  bool settled = false;               ///< the base slower than settle_speed until the end
  double settling_time = 0.0;         ///< s after plan_end (NaN: not settled or not measured)
  double hold_duration = 0.0;         ///< s of log after the plan's end
};

/// The figures of a run. Pure function of the series.
Fidelity computeFidelity(const RunSeries& run, const FidelityParams& params = {});

/// What a faithful execution achieves (issue 19; docs/runtime.md): at most these.
struct FidelityTargets {
  double contact_losses = 0.0;
  double peak_touchdown_load = 1.3;         ///< x weight
  double cop_p95 = 0.015, cop_max = 0.030;  ///< m
  double chatter_rms = 0.3;                 ///< N m
  double pelvis_deviation = 0.010;          ///< rad
  double settling_time = 1.0;               ///< s
};

/// Every figure as {"value", "target", "met"} (per foot under "feet"), "meets_targets" and
/// "misses" (the names of the figures over their targets, e.g. "left.cop_deviation_p95").
nlohmann::json fidelityJson(const Fidelity& f, const FidelityTargets& targets = {});

/// The run's series from its log and plan (the report's alignment, monitor/src/report.cpp):
/// InputError as makeReport for a log without executed plan ticks or of another plan.
RunSeries runSeries(const std::string& plan_path, const std::string& log_path,
                    const std::string& robot_path);

/// The local CoP of a sole-axes wrench (core::localCop), m; NaN where Fz <= fz_min (N).
Eigen::Vector2d loadedCop(const core::Wrench& w_sole, double fz_min);

/// Zero-phase high-pass (2nd-order Butterworth, forward and backward) of a uniformly sampled
/// signal: the chatter filter, exposed for its test.
std::vector<double> highPass(const std::vector<double>& x, double dt, double cutoff_hz);

}  // namespace overstep::monitor
