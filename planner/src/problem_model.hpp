#pragma once
// Internal to the planner library: the problem's model (robot, configuration, obstacle, sample
// grid and row layout) and the state at one instant, which the row terms (constraints/) read.
// Not installed, not included by users.
#include "overstep/planner/problem.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <nlohmann/json.hpp>
#include <thread>

#include "overstep/core/error.hpp"
#include "overstep/core/rotation.hpp"
#include "overstep/core/wrench.hpp"
#include "overstep/planner/spline.hpp"
#include "overstep/robots/collision.hpp"
#include "overstep/robots/leg.hpp"

namespace overstep::planner {
namespace detail {

inline constexpr int kRight = 0;
inline constexpr int kLeft = 1;
inline constexpr double kCopScale = 0.005;       // m, fixed scale of CoP rows
inline constexpr double kDistScale = 0.05;       // m, scale of clearance/distance rows
inline constexpr double kJointScale = 0.1;       // rad
inline constexpr double kFlexTorqueScale = 5.0;  // N m
inline constexpr double kKsSharpness = 40.0;
// The passive polish's least-squares weights (OverstepProblem::Impl::smoothPassive): the
// residual of the bushings' equations it accepts (N m) against the change of the stance CoP (m)
// and the correction (rad) it makes.
inline constexpr double kPolishResidual = 0.1;
inline constexpr double kPolishCop = 1e-3;
inline constexpr double kPolishDeflection = 2e-3;
// Lift-off and touchdown rows: scale of the unloaded foot's normal-force row, a fraction of the
// weight.
inline constexpr double kLiftOffNormal = 0.03;
// Double-support wrench split (distributeWrench).
inline constexpr double kLoadFloor = 0.02;   // softness of the load share at zero force
inline constexpr double kShareFloor = 1e-3;  // a foot's share factor at its contact switch

/// Smooth maximum of values (KS), used to aggregate limit ratios into one row.
inline double smoothMax(const Eigen::Ref<const Eigen::VectorXd>& v, double rho) {
  const double m = v.maxCoeff();
  return m + std::log((rho * (v.array() - m)).exp().sum()) / rho;
}

using core::pitchOf;
using core::rollOf;
inline double yawOf(const Eigen::Matrix3d& R) { return std::atan2(R(1, 0), R(0, 0)); }

inline Eigen::Isometry3d placement(double x, double y) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() << x, y, 0.0;
  return X;
}

/// 6-D pose error of X relative to target, world-aligned [angular; linear].
inline core::Vector6d poseError(const Eigen::Isometry3d& target, const Eigen::Isometry3d& X) {
  core::Vector6d e;
  const Eigen::AngleAxisd aa(target.linear() * X.linear().transpose());
  e.head<3>() = aa.axis() * aa.angle();
  e.tail<3>() = target.translation() - X.translation();
  return e;
}

struct CapsuleRef {
  int frame = -1;
  Eigen::Vector3d p0, p1;
  double radius = 0.0;
  std::string link;
};

/// What one sample contributes.
/// The splines' values at one instant: rows the 12 leg joints (the leg control points' row order)
/// then the 4 bushing coordinates, columns the value, first and second time derivative (rad,
/// rad/s, rad/s^2). What a sample's or a switch's rows depend on besides its phase, its time and
/// the placements.
using SplineState = Eigen::Matrix<double, 16, 3>;

struct SampleOut {
  Eigen::VectorXd ineq;
  Eigen::VectorXd eq;
  std::array<double, kObjectiveTerms> terms{};  // unweighted, normalised, per unit time
  Eigen::VectorXd tau;                          // actuated torques (for the torque-rate term)
  robots::Vector6d ik_leg = robots::Vector6d::Zero();  // double support: State::ik_leg
  double t = 0.0;
};

/// The full state of the robot at one instant, and the contact wrenches.
struct State {
  Eigen::VectorXd q, v, a, tau;  // tau: inverse dynamics without contacts (all coordinates)
  Eigen::VectorXd tau_act;       // actuator torques of the robot in contact (seed eq. 1)
  Eigen::VectorXd tau_contact;   // scratch: all coordinates of tau minus the feet's J^T w
  core::Wrench wrench[2];        // world axes, about each sole origin
  bool contact[2] = {false, false};
  Eigen::Isometry3d sole[2];
  /// 6 x dofs Jacobians of the soles in contact at q ([angular; linear], world axes, about the
  /// sole origin); computed once per state, read by the wrench split, the contact torques and the
  /// elastic rows.
  Eigen::MatrixXd J_sole[2];
  core::Wrench W_O;  // total contact wrench, world axes about the world origin
  double ik_error = 0.0;
  double reach = 0.0;         // hip-ankle distance of the IK leg
  bool beyond_reach = false;  // DS: the IK leg's target beyond its reach (reach continued)
  double ds_balance = 0.0;    // DS: unreachable ankle-moment balance about the feet's line, N m
  /// Each foot's share factor in the double-support split (distributeWrench): 1, ramped for a
  /// foot that lifts off at the phase's end or touched down at its start (shareFactor).
  double share[2] = {1.0, 1.0};
  robots::Vector6d ik_leg = robots::Vector6d::Zero();  // DS: the IK leg's joints (chain order)
  double ik_seed_gap = 0.0;                            // DS: |IK leg - its spline|^2, rad^2
};

/// What the problem knows before any variable is set: the robot and where its legs, feet and
/// capsules are, the configuration, the obstacle and the homotopy stage, the sample grid and the
/// rows each sample and switch contributes. Built once (OverstepProblem's constructor); the
/// evaluation never changes it, except the homotopy stage (setDifficulty).
struct ProblemModel {
  ProblemModel(const robots::WholeBodyModel& m, PlannerConfig c, core::ObstacleSpec o)
      : model_template(m), cfg(std::move(c)), obstacle(o) {}

  robots::WholeBodyModel model_template;
  PlannerConfig cfg;
  core::ObstacleSpec obstacle;
  double height = 0.2;
  double cop_box = 0.01;
  /// The homotopy's last stage (the target problem): the lift-off rows at the check's scale, the
  /// pelvis at pelvis_margin and the switching feet's load shares ramped (shareFactor).
  bool last_stage = true;
  VariableLayout lay;
  int n_ctrl = 0;       // control points per leg joint curve
  int n_ctrl_flex = 0;  // control points per ankle-bushing curve
  double mass = 0.0, mg = 0.0, toes_x = 0.13;
  std::array<int, 12> leg_coord{};  // model coordinates of RLEG_JOINT0-5, LLEG_JOINT0-5
  std::array<int, 12> leg_act{};    // actuated indices
  std::array<int, 4> flex_coord{};  // RLEG roll, pitch, LLEG roll, pitch
  int sole_frame[2]{};
  int hip_frame[2]{};           // hip pitch link origin per leg (reach)
  int ankle_frame[2]{};         // ankle pitch link origin per leg (reach)
  double stretched_reach[2]{};  // hip-ankle frame distance of the stretched leg, m
  int ankle_link_frame[2]{};    // child link of the ankle roll joint (above the bushing)
  std::unique_ptr<robots::LegIk> leg_ik[2];  // closed-form leg solutions (immutable, shared)
  std::array<std::string, 3> leg_links[2];   // thigh, shank and foot bodies per leg
  int head_frame = -1;
  int base_frame = -1;
  core::FootDescription foot[2];
  std::vector<CapsuleRef> caps;
  std::vector<int> leg_caps[2];  // capsules of each leg (indices into caps)
  std::vector<std::pair<int, int>> self_pairs;
  robots::ObstacleGeometry
      obstacle_geom;       // the target bar (the obstacle row of a leg on the ground)
  Eigen::VectorXd q_rest;  // half-sitting (upper body posture held)

  std::vector<GridPoint> grid;  // (phase, s); t filled per evaluation
  int n_regular = 0;            // grid[0, n_regular): the samples; then the check points
  std::vector<GridPoint> check_points;
  std::vector<int> ineq_off, ineq_cnt, eq_off, eq_cnt;
  std::vector<Family> ineq_fam, eq_fam;
  int n_ineq = 0, n_eq = 0;
  static constexpr int kEvents = 4;
  int event_eq_off[kEvents]{};
  int event_eq_cnt[kEvents]{};
  // Per phase, the foot whose placement fixes the floating base (phaseTable()). At a switch the
  // leg changing representation (double-support inverse
  // kinematics <-> spline) is that double-support phase's other leg.
  int anchor_of[kPhaseCount]{};

  /// The foot that lifts at the end of double-support `phase` (-1: none).
  static int liftingFoot(int phase) { return phase == 0 ? kRight : phase == 2 ? kLeft : -1; }
  /// The foot that touched down at the start of double-support `phase` (-1: none).
  static int landingFoot(int phase) { return phase == 2 ? kRight : phase == 4 ? kLeft : -1; }
  static bool inContact(int phase, int foot) {
    const auto& ph = phaseTable()[static_cast<std::size_t>(phase)];
    return foot == kRight ? ph.right_contact : ph.left_contact;
  }
  static bool doubleSupport(int phase) {
    return inContact(phase, kRight) && inContact(phase, kLeft);
  }
  /// Contact switch e (0..3: t1..t4): the double-support phase whose inverse-kinematics leg the
  /// switch rows match, and the phase that starts at the switch.
  static int eventPhase(int e) {
    static const int ds_phase[4] = {0, 2, 2, 4};
    return ds_phase[e];
  }
  static int eventBoundary(int e) { return e + 1; }

  /// The swing sole corners' minimal height: swing_clearance sin(pi s), whose slope at the
  /// contact switches keeps the last samples before a touchdown a few millimetres up (at
  /// sin^2 the sample 8 % of the swing before touchdown asked for 1.3 mm, and a corner dipped
  /// 1.8 mm below the ground between it and the touchdown; measured, docs/planner.md).
  double minHeight(double s) const { return cfg.swing_clearance * std::sin(M_PI * s); }
};

}  // namespace detail
}  // namespace overstep::planner
