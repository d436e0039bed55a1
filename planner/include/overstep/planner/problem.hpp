#pragma once
/// \file
/// The overstep optimal control problem transcribed to a nonlinear program (see docs/planner.md).
///
/// Decision variables x (all O(1) after scaling is left to NLopt's bounds):
///   [0, 5)     phase durations T_i, s
///   [5, 11)    foot placements: right start (x, y), right landing (x, y), left landing (x, y), m
///   then       leg joints: 12 cubic B-splines (RLEG_JOINT0-5, LLEG_JOINT0-5), free control points
///   then       elastic ankle coordinates: 4 cubic B-splines on their own knot spans
///              (flex_spline_intervals), free control points
/// The first three and the last three control points of every curve are tied (rest at start and
/// end), so each curve has (spans + 3) - 4 free control points (VariableLayout::free_cp for the
/// legs, flex_free_cp for the bushings). The upper body holds half-sitting.
///
/// At every sample the floating base follows from the phase's anchor foot lying flat at its
/// placement (robots::WholeBodyModel::anchorBase); in double support the other leg is solved by
/// inverse kinematics onto its placement, and its spline is matched to that solution at the
/// switching instants. Contact wrenches come from the base rows of inverse dynamics: in single
/// support the stance wrench is unique; in double support the two wrenches are the minimum-norm
/// split that also balances both elastic ankles. The elastic ankles are passive spring-dampers:
/// their inverse-dynamics residual is constrained to zero in single support and holds by
/// construction in double support.
///
/// Constraint rows are scaled to O(1); inequalities are g(x) <= 0, equalities h(x) = 0.

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "overstep/core/obstacle.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/planner/config.hpp"
#include "overstep/planner/phases.hpp"
#include "overstep/robots/whole_body_model.hpp"

namespace overstep::planner {

enum class Family {
  CoP = 0,
  Friction,
  Unilateral,
  Clearance,
  ObstacleCollision,
  SelfCollision,
  Pelvis,
  JointLimits,
  Velocity,
  Torque,
  Reach,
  Dynamics,
  Switching,
  LiftOff,
  Touchdown,
  kCount
};
const char* familyName(Family f);

struct VariableLayout {
  int durations = 0;
  int feet = 5;
  int legs = 11;
  int flex = 0;
  int free_cp = 0;       ///< free control points per leg joint curve
  int flex_free_cp = 0;  ///< free control points per ankle-bushing curve
  int total = 0;
  static constexpr int kLegJoints = 12;
  static constexpr int kFlex = 4;
};

struct Evaluation {
  double objective = 0.0;
  std::array<double, kObjectiveTerms> terms{};  ///< weighted terms (objectiveTermNames order)
  Eigen::VectorXd ineq;                         ///< scaled, <= 0 when satisfied
  Eigen::VectorXd eq;                           ///< scaled, = 0 when satisfied
  /// Largest violation per family (scaled units), index by Family.
  std::array<double, static_cast<int>(Family::kCount)> worst{};
};

/// Work done by the problem since its creation (wall time, s): what a solve spends where.
struct WorkAccount {
  int evaluations = 0;         ///< calls of evaluate() (trajectory evaluations by the solvers)
  int jacobians = 0;           ///< calls of derivatives()
  double evaluate_s = 0.0;     ///< in evaluate()
  double derivatives_s = 0.0;  ///< in derivatives() (every column, all threads' wall time)
};

class OverstepProblem {
 public:
  /// check_points: grid points (phase, s) added to the regular grid that carry the path
  /// constraints (every row but the elastic dynamics' collocation) and no objective weight (mesh
  /// refinement, where `overstep check` found a bound crossed between samples). A point within 1e-3
  /// (in s) of another is dropped; checkPoints() lists the kept.
  OverstepProblem(const robots::WholeBodyModel& model, PlannerConfig config,
                  core::ObstacleSpec obstacle, std::vector<GridPoint> check_points = {});
  ~OverstepProblem();
  OverstepProblem(const OverstepProblem&) = delete;
  OverstepProblem& operator=(const OverstepProblem&) = delete;

  const VariableLayout& layout() const;
  const PlannerConfig& config() const;
  const core::ObstacleSpec& obstacle() const;
  int inequalityCount() const;
  int equalityCount() const;
  const std::vector<Family>& inequalityFamilies() const;
  const std::vector<Family>& equalityFamilies() const;
  /// The check points kept (constructor), sorted by phase and s.
  const std::vector<GridPoint>& checkPoints() const;
  /// x of the start toes (front edge of the start soles); the obstacle gap is measured from it.
  double toesX() const;
  /// Distance (m) from the target bar to the nearest collision capsule of the feet (the
  /// capsules rigid with the soles) where they stand at the start, which no plan moves: below
  /// obstacle_clearance the request has no plan (e.g. a bar nearer the toes than the capsules'
  /// overhang in front of the soles and the clearance allow).
  double startClearance() const;

  void bounds(Eigen::VectorXd& lower, Eigen::VectorXd& upper) const;
  /// Typical magnitude of a useful change of each variable (s, m, rad): solvers work on x / scale
  /// so that every column of the Jacobian has a comparable size.
  Eigen::VectorXd variableScale() const;
  /// Homotopy parameters: the obstacle height in use and the CoP box side.
  /// `last_stage`: the target problem (the lift-off rows at the check's scale, the pelvis at
  /// pelvis_margin, the lifting foot's load share ramped); a new problem starts there.
  void setDifficulty(double obstacle_height, double cop_box, bool last_stage);
  bool lastStage() const;
  double currentHeight() const;
  double currentCopBox() const;

  /// Kinematic initial guess: quasi-static whole-body IK on a dense grid (pelvis as high as the
  /// legs reach, CoM over the stance ankle, swing sole lifted vertically, carried over the
  /// obstacle top and set down), then a least-squares fit of the splines.
  Eigen::VectorXd initialGuess();

  void evaluate(const Eigen::VectorXd& x, Evaluation& out);
  /// Objective gradient and row Jacobians: durations and placements by forward differences of
  /// what each moves; a control point by the chain rule through its B-spline basis, from each
  /// sample's forward-difference sensitivities to its spline values (derivatives.cpp); samples
  /// and columns split over threads.
  void derivatives(const Eigen::VectorXd& x, const Evaluation& at, Eigen::VectorXd& grad,
                   Eigen::MatrixXd& jac_ineq, Eigen::MatrixXd& jac_eq);
  /// Trajectory evaluations of every kind, the finite-difference ones included.
  int evaluationCount() const;
  const WorkAccount& work() const;

  /// "family at t = 1.234 s (phase name)" for a constraint row, using the durations of x.
  std::string describeRow(const Eigen::VectorXd& x, bool equality, int row) const;

  /// Dense samples of the motion at `rate` Hz (plus the planner's summary fields left empty).
  core::Plan toPlan(const Eigen::VectorXd& x, double rate);

  /// Phase durations, step length (m, right foot, start to landing) and foot spacing (m, lateral
  /// distance of the landed feet) of x.
  Eigen::VectorXd durations(const Eigen::VectorXd& x) const;
  double stepLength(const Eigen::VectorXd& x) const;
  double footSpacing(const Eigen::VectorXd& x) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace overstep::planner
