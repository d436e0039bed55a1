#pragma once
/// \file
/// Internal to monitor/: a recorded run aligned with its plan, one row per runtime tick (the
/// OVERSTEP_PLAN_REF / OVERSTEP_STABILIZER pair of a tick with the latest OVERSTEP_STATE and
/// OVERSTEP_COMMAND). Shared by the report and the fidelity figures.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "overstep/core/plan.hpp"
#include "overstep/core/wrench.hpp"
#include "overstep/monitor/fidelity.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/runtime/plan_track.hpp"

namespace overstep::monitor {

/// One aligned tick.
struct Row {
  double t = 0.0;  ///< plan time; in the hold after the plan: the time since the plan's start
  int phase = 0;
  int index = 0;  ///< plan sample
  Eigen::Vector2d zmp_meas = Eigen::Vector2d::Zero(), zmp_ref = Eigen::Vector2d::Zero();
  core::Wrench w_meas[2];  ///< measured, sole axes about the sole origin
  Eigen::VectorXd q_meas, q_cmd;
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  Eigen::Vector3d base_velocity = Eigen::Vector3d::Zero();  ///< world, ground truth only
  bool ground_truth = false;
  Eigen::Quaterniond imu = Eigen::Quaterniond::Identity();
  double stab_level = 0.0;  ///< largest correction in units of 1 mrad / 1 mm
  int stab_mode = 0;
};

struct AlignedRun {
  std::vector<Row> rows;        ///< the plan's execution, plan time increasing
  std::vector<Row> hold;        ///< after the plan reached its end (the last sample held)
  long long break_offset = -1;  ///< where a damaged log stopped being read (-1: intact)
};

/// Reads `log` against `plan` (InputError naming both when the log records another plan, or
/// when it has fewer than two executed ticks).
AlignedRun alignRun(const core::Plan& plan, const runtime::PlanTrack& track, int actuated,
                    const std::string& log, const std::string& plan_path);

/// The wrench (sole axes, about the sole origin) that the plan asks of foot f (0 right, 1 left)
/// at sample k.
core::Wrench planSoleWrench(const core::Plan& plan, int f, int k);

/// The fidelity series of an aligned run (plan rows, then hold rows).
RunSeries toSeries(const AlignedRun& run, const core::Plan& plan, robots::WholeBodyModel& model);

}  // namespace overstep::monitor
