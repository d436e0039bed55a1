#pragma once
/// \file
/// Planner configuration (planner/planner.yaml): discretisation, bounds, contact model,
/// clearances, objective weights and solver settings. Units SI.

#include <array>
#include <map>
#include <string>
#include <vector>

#include "overstep/planner/phases.hpp"

namespace overstep::planner {

struct SolverSettings {
  std::string algorithm = "LD_SLSQP";
  int max_iterations = 300;
  double constraint_tolerance = 1e-6;
  double ftol_rel = 1e-7;
  double time_limit = 900.0;  ///< s
  int threads = 2;
};

struct PlannerConfig {
  std::array<int, kPhaseCount> samples_per_phase{9, 12, 9, 12, 9};
  std::array<int, kPhaseCount> spline_intervals{3, 6, 3, 6, 3};  ///< cubic B-spline spans (legs)
  /// Cubic B-spline spans of the ankle-bushing coordinates. In single support their equations of
  /// motion are collocated at every sample: one span per sample interval there gives the curve a
  /// degree of freedom per collocation row, so the bushings can meet their dynamics without
  /// bending the legs (keep the single-support entries equal to samples_per_phase's).
  std::array<int, kPhaseCount> flex_spline_intervals{3, 12, 3, 12, 3};
  std::array<double, kPhaseCount> duration_min{0.4, 0.7, 0.15, 0.7, 0.4};
  std::array<double, kPhaseCount> duration_max{1.2, 2.0, 1.0, 2.0, 1.2};
  std::array<double, kPhaseCount> duration_guess{0.8, 1.5, 0.6, 1.5, 0.8};

  double start_half_width = 0.095;
  double step_length_min = 0.30, step_length_max = 0.65;
  double foot_y_min = 0.06, foot_y_max = 0.13;
  double guess_step_length = 0.41, guess_half_width = 0.085;
  double guess_reach_margin = 0.03, guess_swing_clearance = 0.06;

  double cop_box = 0.01;
  std::vector<double> cop_homotopy{0.04};
  double friction = 0.7, torsion = 0.02, min_normal_force = 20.0;

  double swing_clearance = 0.02, obstacle_clearance = 0.01, self_clearance = 0.005;
  double pelvis_tilt = 0.005, leg_reach = 0.595, smooth_min_rho = 1000.0;
  /// Fraction of the CoP box, friction and torsion coefficients and pelvis range enforced at the
  /// samples: the motion between samples keeps the rest as margin (`overstep check` verifies on a
  /// 1 kHz grid).
  double limit_margin = 0.8;
  /// Fraction of the pelvis range enforced at the samples in the homotopy's last stage (earlier
  /// stages: limit_margin): the pelvis rotates fastest in the last swing interval before a
  /// touchdown (1.2 mrad beyond the range between samples at 0.8 on the 20 cm run; measured,
  /// docs/planner.md).
  double pelvis_margin = 0.5;
  /// N m: the double-support sway balance (the ankles' moment about the line joining the feet,
  /// which only the bushings can supply) within +-ds_balance_band at each sample.
  double ds_balance_band = 0.3;
  /// Swept clearance: each leg capsule's obstacle and self-collision distance at a sample is
  /// reduced by this factor times its fastest endpoint's speed times half the sample interval (the
  /// farthest it can travel before the nearer sample), so that the clearance holds between
  /// samples too. 0: off; 1: the full half-interval travel.
  double swept_clearance = 1.0;
  /// The plan file's passive (elastic) coordinates in single support corrected between the
  /// collocation samples so that they obey their equations of motion under the planned joint
  /// trajectories: a least-squares boundary-value problem per phase, zero with its rate at each
  /// contact switch (OverstepProblem::toPlan, docs/planner.md); false: the splines as solved.
  bool passive_polish = true;
  /// Fraction of each joint's velocity limit enforced at the samples (the motion between them
  /// overshoots; measured 9 % at 1.0).
  double velocity_margin = 0.9;
  double height_homotopy_step = 0.05;

  std::map<std::string, double> weights{{"elastic_acc", 0.01},
                                        {"elastic_vel", 0.1},
                                        {"elastic_pos", 1.0},
                                        {"lin_mom_z", 0.1},
                                        {"lin_mom_z_rate", 0.1},
                                        {"ang_mom_z_rate", 0.1},
                                        {"contact_torque_z", 0.1},
                                        {"zmp_lipm", 1.0},
                                        {"time", 0.3},
                                        {"head", 0.1},
                                        {"torque_rate", 0.01},
                                        {"ds_leg_tracking", 0.01}};
  double head_pitch_offset = 0.0;

  SolverSettings solver;

  /// The configuration as a JSON object (for plan files and --json output).
  std::string toJson() const;
};

/// One scalar key of planner.yaml: the table drives loading (range checks), --json / plan-file
/// output and the documentation (planner/planner.yaml lists every key; a test holds them equal).
struct ConfigEntry {
  const char* key;
  const char* unit;
  double lo, hi;  ///< accepted range, inclusive (open_low: lo itself excluded)
  bool open_low;
  double PlannerConfig::*field;
  const char* help;
};
/// The scalar keys, in planner.yaml order. Lists, maps and the solver section are read beside it.
const std::vector<ConfigEntry>& configTable();

/// Loads planner.yaml; keys absent from the file keep their defaults. InputError on a malformed
/// file, an unknown key or an invalid value (one line naming file and key).
PlannerConfig loadPlannerConfig(const std::string& path);

/// Number of objective terms: the seed's eqs. (20)-(27) split into 11 named terms, plus
/// "ds_leg_tracking", a small regulariser that keeps the double-support leg's (unused) spline near
/// its inverse-kinematics solution, so that the spline is a good start for the switching rows.
inline constexpr int kObjectiveTerms = 12;
/// Names of the objective terms, in report order.
const std::array<const char*, kObjectiveTerms>& objectiveTermNames();

}  // namespace overstep::planner
