#pragma once
/// \file
/// Solving the overstep NLP: a solver interface (NLopt behind it; another solver can be added
/// without touching the problem), and the homotopy driver that plans a motion: obstacle height
/// raised in steps with a large CoP box, then the box shrunk to its target (planner.md).

#include <atomic>
#include <functional>
#include <limits>
#include <memory>
#include <string>

#include "overstep/planner/problem.hpp"

namespace overstep::planner {

struct IterationInfo {
  int stage = 0;      ///< homotopy stage index
  int iteration = 0;  ///< iterate count within the stage
  double objective = 0.0;
  double max_violation = 0.0;  ///< largest scaled constraint violation
  double step = 0.0;           ///< |x_k - x_{k-1}|
  double elapsed = 0.0;        ///< s since the solve began
  /// The most violated row (OverstepProblem::describeRow); empty when every row holds.
  std::string worst;
};

struct SolveResult {
  Eigen::VectorXd x;
  std::string status;  ///< solver's word for how it stopped
  int iterations = 0;
  double objective = 0.0;
  double max_violation = 0.0;
  bool interrupted = false;
  Evaluation evaluation;  ///< at x
};

class NlpSolver {
 public:
  virtual ~NlpSolver() = default;
  /// Solves from x0 within the variable bounds, for at most max_iterations (derivative
  /// evaluations) and deadline_s seconds.
  virtual SolveResult solve(OverstepProblem& problem, const Eigen::VectorXd& x0, int stage,
                            double deadline_s, int max_iterations) = 0;
};

/// NLopt with vector constraints and an x-keyed cache (one trajectory evaluation serves the
/// objective and all constraint blocks). `algorithm` is an NLopt name such as "LD_SLSQP";
/// throws InputError for an unknown name or one that cannot take the problem's constraints.
std::unique_ptr<NlpSolver> makeNloptSolver(const SolverSettings& settings,
                                           std::function<void(const IterationInfo&)> on_iteration,
                                           const std::atomic<bool>* stop);

/// Where a solve's wall time went (s); the parts add up to PlanOutcome::solve_time.
struct TimeSplit {
  double derivatives = 0.0;  ///< the problem's Jacobians (finite differences)
  double evaluations = 0.0;  ///< the problem's trajectory evaluations (values only)
  double nlopt = 0.0;        ///< inside the NLopt solver, between its calls to the problem
  double restoration = 0.0;  ///< restoration's own linear algebra, between its calls
  double other = 0.0;        ///< initial guess, set-up
};

struct PlanOutcome {
  bool valid = false;                 ///< every constraint family within the feasibility tolerance
  SolveResult final;                  ///< the last stage's result (best attempt)
  int iterations = 0;                 ///< over all stages
  double solve_time = 0.0;            ///< s
  TimeSplit split;                    ///< of solve_time
  std::vector<std::string> violated;  ///< families still violated when not valid
};

/// Scaled violation accepted as feasible by the planner's own check after NLopt returns: e.g.
/// 50 um of CoP beyond its box, 0.05 N m of ankle imbalance, 0.5 mm of clearance, 1e-3 rad at a
/// switch. `overstep check` re-verifies the plan with physical tolerances on a 1 kHz grid.
inline constexpr double kFeasibilityTolerance = 1e-2;
/// The restoration's first Levenberg-Marquardt damping (restoreFeasibility).
inline constexpr double kRestorationDamping = 1e-3;

struct RestorationResult {
  Eigen::VectorXd x;
  int iterations = 0;
  double max_violation = 0.0;
  bool interrupted = false;
  bool timed_out = false;  ///< stopped by its time limit
  bool accepted = false;   ///< stopped because `accept` took a feasible iterate
  int refusals = 0;        ///< feasible iterates `accept` refused
};

/// Judges a feasible solution vector by a finer measure than the rows at the samples (e.g. the
/// plan's 1 kHz check); true: good enough to stop at.
using AcceptFn = std::function<bool(const Eigen::VectorXd&)>;

/// What a restoration is for. Polish: a feasible point to end the plan at; it aims at a tenth of
/// kFeasibilityTolerance and gives up only far from it. Project: the start of a stage solve, which
/// SLSQP takes from any point near the feasible set, or the end of an intermediate stage; it ends
/// at the tolerance, or once it crawls.
/// Probe: a Project that also ends once it crawls far from the feasible set (above 1, scaled),
/// for a caller with another start to try (the planner's guess).
enum class RestorationGoal { Polish, Project, Probe };

/// Drives x toward feasibility (least squares on the violations, bounds respected). Stops after
/// `max_iterations` steps, on `stop`, once `time_limit_s` of wall time has passed (checked
/// before each step; <= 0: no step at all), or when, with its largest violation above ten times
/// the tolerance (Project: above the tolerance) and below 1 (Probe: anywhere above the
/// tolerance), ten steps took less than 1 % off it. Without
/// `accept` it aims at a tenth of kFeasibilityTolerance (Project: the tolerance); with it, it also
/// stops at the first iterate within `accept_below` (scaled violation; by default the
/// feasibility tolerance) that `accept` takes (asked at the first such iterate, then after 5, 10,
/// 20, ... more steps); asking changes no step.
/// With `refusals_to_stop` > 0 it also stops, feasible and not accepted, once `accept` has refused
/// that many iterates (the caller then refines where the finer measure fails).
/// `damping`: the Levenberg-Marquardt damping of the first step, relative to diag(J^T J); each
/// accepted step divides it by 3, each rejected trial multiplies it by 5.
RestorationResult restoreFeasibility(
    OverstepProblem& problem, const Eigen::VectorXd& x0, int max_iterations,
    const std::atomic<bool>* stop, const std::function<void(const IterationInfo&)>& on_iter,
    double time_limit_s = std::numeric_limits<double>::infinity(), const AcceptFn& accept = {},
    double accept_below = kFeasibilityTolerance, int refusals_to_stop = 0,
    RestorationGoal goal = RestorationGoal::Polish, double damping = kRestorationDamping);

/// Runs the homotopy from the kinematic guess (after a feasibility restoration) to the target
/// obstacle and CoP box; with `warm_start` (a solution vector of this problem's layout, e.g. a
/// plan file's summary.x) x is first restored onto this problem's feasible set; when `accept`
/// takes a restored point that point is the result (status "projected"), else the target stage
/// runs from there. `accept` (optional) also ends the restoration that polishes the target
/// stage at the first feasible point it takes, instead of at a tenth of the tolerance
/// (restoreFeasibility).
PlanOutcome planOverstep(OverstepProblem& problem, NlpSolver& solver, double time_limit_s,
                         const std::function<void(const std::string&)>& on_stage,
                         const std::function<void(const IterationInfo&)>& on_restore,
                         const std::atomic<bool>* stop, const Eigen::VectorXd* warm_start = nullptr,
                         const AcceptFn& accept = {});

}  // namespace overstep::planner
