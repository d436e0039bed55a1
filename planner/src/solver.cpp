#include "overstep/planner/solver.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <nlopt.hpp>
#include <optional>

#include "overstep/core/error.hpp"

namespace overstep::planner {
namespace {

/// SLSQP iterations without a point 1 % nearer to feasibility that end an infeasible stage.
constexpr int kInfeasibleStall = 80;
/// SLSQP iterations after a stage's first feasible point that end it (its best point kept). A
/// budget, not a stall rule: SLSQP still lowers the objective then, slowly (the 5 cm bar's
/// target stage: 3.44 at its first feasible point, 2.61 after the 40; ending a stage only after
/// 40 iterations without a 1e-4 better objective took that plan from 371 Jacobians, 121 s to
/// 765, 267 s for an objective of 1.92; docs/history/planner.md).
constexpr int kFeasibleBudget = 40;
/// The same budget in the homotopy's intermediate stages, whose solutions only start the next
/// stage. Their objective matters for where the target stage starts (ending them at their first
/// feasible point left the default bar with no valid plan; docs/history/planner.md), but a few
/// iterations of it do: with 40, the default bar and five of the six perturbed bars took
/// 141-166 s, with 15 83-119 s (measured before the switch-corner rows); with 8 instead of 15
/// the default took 64 s instead of 74-77 s and the six perturbed bars 67-86 s instead of
/// 79-88 s, all valid, at objectives a few per cent higher (default 2.55 instead of 2.30).
constexpr int kIntermediateBudget = 8;
/// kInfeasibleStall in the intermediate stages, scaled as their feasible budget is (8 of 40), once
/// SLSQP has found a point less violated than the stage's start: an intermediate stage's
/// solution only starts the next stage, and its polish, not more SLSQP iterations, takes that
/// best point to the tolerance; the iterations that lower the objective near it are not kept
/// (one path of the bar 5 mm nearer: stage 4 at 0.014-0.04 for 80 iterations after its best
/// point; with 16 the same plan 10 s sooner). While the best point is still the start, where the
/// stage's projection stalled, the polish would stall there again, and SLSQP keeps the target
/// stage's 80 (16 there sent another path of that bar to a bisection stage: 81.5 s against
/// 70.4 s). The eight bars of docs/benchmarks.md are solved the same to the bit.
constexpr int kIntermediateStall = 16;

using Clock = std::chrono::steady_clock;

class NloptSolver final : public NlpSolver {
 public:
  NloptSolver(SolverSettings s, std::function<void(const IterationInfo&)> cb,
              const std::atomic<bool>* stop)
      : settings_(std::move(s)), on_iteration_(std::move(cb)), stop_(stop) {
    algorithm_ = nlopt::LD_SLSQP;
    bool found = false;
    // NLopt names algorithms NLOPT_LD_SLSQP etc.; nlopt_algorithm_from_string takes "LD_SLSQP".
    const nlopt_algorithm alg = nlopt_algorithm_from_string(settings_.algorithm.c_str());
    if (static_cast<int>(alg) >= 0) {
      algorithm_ = static_cast<nlopt::algorithm>(alg);
      found = true;
    }
    if (!found) {
      throw InputError("solver.algorithm: unknown NLopt algorithm '" + settings_.algorithm +
                       "' (e.g. LD_SLSQP, AUGLAG)");
    }
  }

  SolveResult solve(OverstepProblem& problem, const Eigen::VectorXd& x0, int stage,
                    double deadline_s, int max_iterations) override {
    const int n = problem.layout().total;
    nlopt::opt opt(algorithm_, static_cast<unsigned>(n));
    if (algorithm_ == nlopt::AUGLAG || algorithm_ == nlopt::AUGLAG_EQ) {
      nlopt::opt local(nlopt::LD_LBFGS, static_cast<unsigned>(n));
      local.set_ftol_rel(settings_.ftol_rel);
      opt.set_local_optimizer(local);
    }
    Eigen::VectorXd lo, hi;
    problem.bounds(lo, hi);
    const Eigen::VectorXd D = problem.variableScale();
    const Eigen::VectorXd lot = lo.cwiseQuotient(D), hit = hi.cwiseQuotient(D);
    opt.set_lower_bounds(std::vector<double>(lot.data(), lot.data() + n));
    opt.set_upper_bounds(std::vector<double>(hit.data(), hit.data() + n));
    State s(problem, *this, stage);
    s.D = D;
    s.max_iterations = max_iterations > 0 ? max_iterations : settings_.max_iterations;
    s.feasible_budget = problem.lastStage() ? kFeasibleBudget : kIntermediateBudget;
    s.infeasible_stall = problem.lastStage() ? kInfeasibleStall : kIntermediateStall;
    {
      // The objective enters at O(1): SLSQP's line search and QP are sensitive to its scale.
      Evaluation e0;
      problem.evaluate(x0, e0);
      s.fscale = 1.0 / std::max(1.0, std::abs(e0.objective));
    }
    opt.set_min_objective(&NloptSolver::objective, &s);
    try {
      opt.add_inequality_mconstraint(
          &NloptSolver::inequalities, &s,
          std::vector<double>(static_cast<std::size_t>(problem.inequalityCount()),
                              settings_.constraint_tolerance));
      opt.add_equality_mconstraint(
          &NloptSolver::equalities, &s,
          std::vector<double>(static_cast<std::size_t>(problem.equalityCount()),
                              settings_.constraint_tolerance));
    } catch (const std::invalid_argument&) {
      throw InputError("solver.algorithm: " + settings_.algorithm +
                       " does not take nonlinear equality and inequality constraints");
    }
    opt.set_ftol_rel(settings_.ftol_rel);
    opt.set_xtol_rel(1e-8);
    opt.set_maxeval(s.max_iterations * 4);
    opt.set_maxtime(std::max(1.0, deadline_s));
    std::vector<double> x(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i)
      x[static_cast<std::size_t>(i)] = std::clamp(x0(i), lo(i), hi(i)) / D(i);
    double f = 0.0;
    SolveResult r;
    try {
      const nlopt::result res = opt.optimize(x, f);
      r.status = resultName(res);
    } catch (const nlopt::forced_stop&) {
      r.status = s.stalled                          ? "stalled"
                 : s.iterations >= s.max_iterations ? "max_iterations"
                                                    : "interrupted";
      r.interrupted = r.status == "interrupted";
    } catch (const nlopt::roundoff_limited&) {
      r.status = "roundoff_limited";
    } catch (const std::runtime_error& e) {
      r.status = std::string("failure: ") + e.what();
    }
    // The best point seen (least violation, then objective) rather than NLopt's last one.
    r.x = s.best_x.size()
              ? s.best_x
              : Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(x.data(), n).cwiseProduct(D));
    problem.evaluate(r.x, r.evaluation);
    r.objective = r.evaluation.objective;
    r.max_violation = maxViolation(r.evaluation);
    r.iterations = s.iterations;
    return r;
  }

  static double maxViolation(const Evaluation& e) {
    double v = 0.0;
    if (e.ineq.size()) v = std::max(v, e.ineq.maxCoeff());
    if (e.eq.size()) v = std::max(v, e.eq.cwiseAbs().maxCoeff());
    return v;
  }
  /// The most violated row of e (at x), described; empty when none is beyond the tolerance.
  static std::string worstRow(const OverstepProblem& problem, const Eigen::VectorXd& x,
                              const Evaluation& e) {
    Eigen::Index in = 0, eq = 0;
    const double vi = e.ineq.size() ? e.ineq.maxCoeff(&in) : 0.0;
    const double ve = e.eq.size() ? e.eq.cwiseAbs().maxCoeff(&eq) : 0.0;
    if (std::max(vi, ve) <= kFeasibilityTolerance) return {};
    return vi >= ve ? problem.describeRow(x, false, static_cast<int>(in))
                    : problem.describeRow(x, true, static_cast<int>(eq));
  }

 private:
  struct State {
    State(OverstepProblem& p, NloptSolver& solver, int st)
        : problem(p), self(solver), stage(st), start(solver.created_) {}
    OverstepProblem& problem;
    NloptSolver& self;
    int stage;
    Clock::time_point start;
    Eigen::VectorXd x;  // cache key
    Evaluation eval;
    bool have_derivs = false;
    Eigen::VectorXd grad;
    Eigen::MatrixXd jin, jeq;
    int iterations = 0;
    double fscale = 1.0;
    Eigen::VectorXd D;  // variable scale: x = D .* x_solver
    int max_iterations = 0;
    int feasible_budget = kFeasibleBudget;
    int feasible_count = 0;  // iterations since the best point became feasible
    double infeasible_reference = std::numeric_limits<double>::infinity();
    int infeasible_count = 0;
    int infeasible_stall = kInfeasibleStall;
    int best_points = 0;  // times the best point changed, the start's evaluation included
    bool stalled = false;
    Eigen::VectorXd last_iterate;
    Eigen::VectorXd best_x;
    double best_violation = std::numeric_limits<double>::infinity();
    double best_objective = std::numeric_limits<double>::infinity();
  };

  static void refresh(State& s, unsigned n, const double* xp, bool need_grad) {
    const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(xp, n).cwiseProduct(s.D);
    if (s.x.size() != static_cast<Eigen::Index>(n) || s.x != x) {
      s.x = x;
      s.problem.evaluate(s.x, s.eval);
      s.have_derivs = false;
      const double v = maxViolation(s.eval);
      // Keep the best point: feasible beats infeasible, then lower objective.
      const bool feasible = v <= kFeasibilityTolerance;
      const bool best_feasible = s.best_violation <= kFeasibilityTolerance;
      if ((feasible && (!best_feasible || s.eval.objective < s.best_objective)) ||
          (!feasible && !best_feasible && v < s.best_violation)) {
        s.best_x = s.x;
        s.best_violation = v;
        s.best_objective = s.eval.objective;
        ++s.best_points;
      }
    }
    if (need_grad && !s.have_derivs) {
      s.problem.derivatives(s.x, s.eval, s.grad, s.jin, s.jeq);
      s.have_derivs = true;
      ++s.iterations;
      IterationInfo info;
      info.stage = s.stage;
      info.iteration = s.iterations;
      info.objective = s.eval.objective;
      info.max_violation = maxViolation(s.eval);
      info.step = s.last_iterate.size() ? (s.x - s.last_iterate).cwiseQuotient(s.D).norm() : 0.0;
      info.elapsed = std::chrono::duration<double>(Clock::now() - s.start).count();
      info.worst = worstRow(s.problem, s.x, s.eval);
      s.last_iterate = s.x;
      if (s.self.on_iteration_) s.self.on_iteration_(info);
      // SLSQP can cycle between two iterates for hundreds of iterations (measured): a stage ends
      // its budget of iterations (kFeasibleBudget, kIntermediateBudget) after its first feasible
      // point.
      if (s.best_violation <= kFeasibilityTolerance) {
        if (++s.feasible_count >= s.feasible_budget) s.stalled = true;
      } else if (s.best_violation < s.infeasible_reference * 0.99) {
        s.infeasible_reference = s.best_violation;
        s.infeasible_count = 0;
      } else if (++s.infeasible_count >=
                 (s.best_points > 1 ? s.infeasible_stall : kInfeasibleStall)) {
        // No point seen for that many iterations (kIntermediateStall or kInfeasibleStall, see
        // there) comes 1 % nearer to feasibility: the
        // restoration steps after the stage do better from the best one (20 cm run, last stage:
        // SLSQP wandered at 0.9 for 280 iterations, 260 s, from a start at 0.023; measured).
        s.stalled = true;
      }
      if ((s.self.stop_ && s.self.stop_->load()) || s.iterations >= s.max_iterations || s.stalled)
        throw nlopt::forced_stop();
    }
  }

  static double objective(unsigned n, const double* x, double* grad, void* data) {
    State& s = *static_cast<State*>(data);
    refresh(s, n, x, grad != nullptr);
    if (grad) Eigen::Map<Eigen::VectorXd>(grad, n) = s.grad.cwiseProduct(s.D) * s.fscale;
    return s.eval.objective * s.fscale;
  }
  static void inequalities(unsigned m, double* result, unsigned n, const double* x, double* grad,
                           void* data) {
    State& s = *static_cast<State*>(data);
    refresh(s, n, x, grad != nullptr);
    Eigen::Map<Eigen::VectorXd>(result, m) = s.eval.ineq;
    // NLopt wants grad[i * n + j] = d c_i / d x_j (row-major).
    if (grad)
      Eigen::Map<Eigen::Matrix<double, -1, -1, Eigen::RowMajor>>(grad, m, n) =
          s.jin * s.D.asDiagonal();
  }
  static void equalities(unsigned m, double* result, unsigned n, const double* x, double* grad,
                         void* data) {
    State& s = *static_cast<State*>(data);
    refresh(s, n, x, grad != nullptr);
    Eigen::Map<Eigen::VectorXd>(result, m) = s.eval.eq;
    if (grad)
      Eigen::Map<Eigen::Matrix<double, -1, -1, Eigen::RowMajor>>(grad, m, n) =
          s.jeq * s.D.asDiagonal();
  }

  static std::string resultName(nlopt::result r) {
    switch (r) {
      case nlopt::SUCCESS:
        return "success";
      case nlopt::STOPVAL_REACHED:
        return "stopval_reached";
      case nlopt::FTOL_REACHED:
        return "ftol_reached";
      case nlopt::XTOL_REACHED:
        return "xtol_reached";
      case nlopt::MAXEVAL_REACHED:
        return "max_evaluations";
      case nlopt::MAXTIME_REACHED:
        return "time_limit";
      default:
        return "failure";
    }
  }

  SolverSettings settings_;
  Clock::time_point created_ = Clock::now();  // elapsed times count from the solver's creation
  std::function<void(const IterationInfo&)> on_iteration_;
  const std::atomic<bool>* stop_;
  nlopt::algorithm algorithm_;
};

/// Restoration steps after a stage that SLSQP left infeasible.
constexpr int kPolishIterations = 400;
/// A restoration far from feasibility (largest scaled violation above kStallAbove) but within
/// SLSQP's reach (below kStallBelow) whose last kStallSteps steps took less than kStallDecrease
/// of it off ends: SLSQP does better from there. From violations of a few units SLSQP's first,
/// identity-Hessian steps wander (measured: the 19.5 cm bar's guess restoration stalled at 2.96,
/// and stage 1 then took 157 iterations, 1 s each, without coming nearer), so a restoration
/// there keeps going.
constexpr int kStallSteps = 10;
constexpr double kStallDecrease = 1e-2;
constexpr double kStallAbove = 10.0 * kFeasibilityTolerance;
constexpr double kStallBelow = 1.0;
/// Damping increases (x5 each) a restoration step may try before the restoration ends: lambda up
/// to 1e-3 * 5^13 ~ 1e6 x diag(J^T J). With 8 (lambda up to ~400) the 1.5 kg chest payload's
/// warm start from the default plan ended on its first step at 0.36 and SLSQP took 21 s; the
/// first steps needed lambda 650-3000, after which it was projected in 3 s.
constexpr int kStepTries = 14;
/// Continuation step control: a stage that ends infeasible is solved again after a stage halfway
/// between it and the last stage that ended feasible, from that stage's solution; at most this
/// many such stages per solve.
constexpr int kMaxBisections = 3;
constexpr int kPolishRefusals = 3;  // the check's refusals that end the target stage's polish
constexpr int kGuessSteps = 60;     // the kinematic guess's restoration
/// A guess restoration that ends above this violation (scaled) is run again from the guess with
/// its first damping this many times larger; the first run also ends once it crawls there
/// (RestorationGoal::Probe). Over 41 bars within 1 cm of the default the first run ended at
/// 0.06-1.11 but twice at 2.9 (docs/history/planner.md).
constexpr double kGuessRestartAbove = kStallBelow;
constexpr double kGuessRestartDamping = 10.0;

}  // namespace

RestorationResult restoreFeasibility(OverstepProblem& problem, const Eigen::VectorXd& x0,
                                     int max_iterations, const std::atomic<bool>* stop,
                                     const std::function<void(const IterationInfo&)>& on_iter,
                                     double time_limit_s, const AcceptFn& accept,
                                     double accept_below, int refusals_to_stop,
                                     RestorationGoal goal, double damping) {
  // Projected Levenberg-Marquardt on the violation residuals r = [max(0, g); h] (rows near
  // activity keep their Jacobians so the step does not break them). NLopt offers no
  // least-squares method; SLSQP started far from feasibility stalls (measured: docs/planner.md).
  const auto start = Clock::now();
  Eigen::VectorXd lo, hi;
  problem.bounds(lo, hi);
  RestorationResult out;
  Eigen::VectorXd x = x0.cwiseMax(lo).cwiseMin(hi);
  Evaluation e;
  problem.evaluate(x, e);
  auto residual = [&](const Evaluation& ev, Eigen::VectorXd* r, std::vector<int>* rows) {
    std::vector<int> idx;
    for (int i = 0; i < ev.ineq.size(); ++i)
      if (ev.ineq(i) > -0.05) idx.push_back(i);
    if (rows) *rows = idx;
    Eigen::VectorXd res(static_cast<Eigen::Index>(idx.size()) + ev.eq.size());
    for (std::size_t k = 0; k < idx.size(); ++k)
      res(static_cast<Eigen::Index>(k)) = std::max(0.0, ev.ineq(idx[k]));
    res.tail(ev.eq.size()) = ev.eq;
    if (r) *r = res;
    return 0.5 * (ev.ineq.cwiseMax(0.0).squaredNorm() + ev.eq.squaredNorm());
  };
  double cost = residual(e, nullptr, nullptr);
  double lambda = damping;
  Eigen::VectorXd grad;
  Eigen::MatrixXd jin, jeq;
  int next_ask = 0, gap = 5;  // when `accept` is asked next (a step count), and then how often
  // The largest violations after the last kStallSteps steps: far from feasibility (above
  // kStallAbove) the restoration ends once that many steps took less than kStallDecrease of it
  // off (the kinematic guess's on the default bar: 33 of its 60 steps between 0.938 and 0.905,
  // a standing leg in the target bar, which the first stage's SLSQP resolves). Near the tolerance
  // it crawls at well under 1 % per ten steps and still ends feasible (measured), so a polish
  // goes on. A projection (the start of a stage solve) has no use for those steps: it ends at
  // the tolerance and stalls anywhere above it (the default's projections spent their last 20-25
  // of 40 steps crawling, e.g. 0.026 -> 0.024; ending there took the plan from 64 s to 59 s).
  std::array<double, kStallSteps> history;
  history.fill(std::numeric_limits<double>::infinity());
  const bool project = goal != RestorationGoal::Polish;
  const double done_below = project ? kFeasibilityTolerance : 0.1 * kFeasibilityTolerance;
  const double stall_above = project ? kFeasibilityTolerance : kStallAbove;
  const double stall_below =
      goal == RestorationGoal::Probe ? std::numeric_limits<double>::infinity() : kStallBelow;
  for (int it = 0; it < max_iterations; ++it) {
    const double viol = NloptSolver::maxViolation(e);
    if (viol <= done_below) break;
    if (accept && viol <= accept_below && it >= next_ask) {
      if (accept(x)) {
        out.accepted = true;
        break;
      }
      problem.evaluate(x, e);  // the problem's state at x again (the same values)
      if (++out.refusals == refusals_to_stop) break;
      next_ask = it + gap;
      gap *= 2;
    }
    if (stop && stop->load()) {
      out.interrupted = true;
      break;
    }
    if (!(std::chrono::duration<double>(Clock::now() - start).count() < time_limit_s)) {
      out.timed_out = true;
      break;
    }
    problem.derivatives(x, e, grad, jin, jeq);
    Eigen::VectorXd r;
    std::vector<int> rows;
    residual(e, &r, &rows);
    Eigen::MatrixXd J(r.size(), x.size());
    for (std::size_t k = 0; k < rows.size(); ++k)
      J.row(static_cast<Eigen::Index>(k)) = jin.row(rows[k]);
    J.bottomRows(jeq.rows()) = jeq;
    Eigen::MatrixXd JtJ = J.transpose() * J;
    Eigen::VectorXd Jtr = J.transpose() * r;
    // Variables on a bound whose descent direction leaves the box are held (projected LM).
    for (int i = 0; i < x.size(); ++i) {
      const bool at_lo = x(i) <= lo(i) + 1e-12 && Jtr(i) > 0.0;
      const bool at_hi = x(i) >= hi(i) - 1e-12 && Jtr(i) < 0.0;
      if (at_lo || at_hi) {
        JtJ.row(i).setZero();
        JtJ.col(i).setZero();
        JtJ(i, i) = 1.0;
        Jtr(i) = 0.0;
      }
    }
    bool accepted = false;
    for (int tries = 0; tries < kStepTries && !accepted; ++tries) {
      Eigen::MatrixXd A = JtJ;
      A.diagonal() += lambda * (JtJ.diagonal().array() + 1e-6).matrix();
      const Eigen::VectorXd dx = -A.ldlt().solve(Jtr);
      if (!dx.allFinite()) {  // a singular system (measured once at 20 cm: a NaN duration)
        lambda *= 5.0;
        continue;
      }
      const Eigen::VectorXd xn = (x + dx).cwiseMax(lo).cwiseMin(hi);
      Evaluation en;
      problem.evaluate(xn, en);
      const double cn = residual(en, nullptr, nullptr);
      if (std::isfinite(cn) && cn < cost) {
        x = xn;
        e = en;
        cost = cn;
        lambda = std::max(1e-9, lambda / 3.0);
        accepted = true;
      } else {
        lambda *= 5.0;
      }
    }
    ++out.iterations;
    if (on_iter) {
      IterationInfo info;
      info.stage = 0;
      info.iteration = out.iterations;
      info.objective = e.objective;
      info.max_violation = NloptSolver::maxViolation(e);
      info.step = lambda;
      info.elapsed = std::chrono::duration<double>(Clock::now() - start).count();
      info.worst = NloptSolver::worstRow(problem, x, e);
      on_iter(info);
    }
    if (!accepted) break;
    const double now = NloptSolver::maxViolation(e);
    double& oldest = history[static_cast<std::size_t>(it % kStallSteps)];
    if (now > stall_above && now < stall_below && now > (1.0 - kStallDecrease) * oldest) break;
    oldest = now;
  }
  out.x = x;
  out.max_violation = NloptSolver::maxViolation(e);
  return out;
}

std::unique_ptr<NlpSolver> makeNloptSolver(const SolverSettings& settings,
                                           std::function<void(const IterationInfo&)> on_iteration,
                                           const std::atomic<bool>* stop) {
  return std::make_unique<NloptSolver>(settings, std::move(on_iteration), stop);
}

PlanOutcome planOverstep(OverstepProblem& problem, NlpSolver& solver, double time_limit_s,
                         const std::function<void(const std::string&)>& on_stage,
                         const std::function<void(const IterationInfo&)>& on_restore,
                         const std::atomic<bool>* stop, const Eigen::VectorXd* warm_start,
                         const AcceptFn& accept) {
  const auto start = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  const WorkAccount work0 = problem.work();
  PlanOutcome out;
  // Runs `part` and adds its wall time, less the problem's own work inside it, to `own`.
  auto accounted = [&](double& own, const auto& part) {
    const WorkAccount w0 = problem.work();
    const auto t0 = Clock::now();
    auto result = part();
    const WorkAccount& w1 = problem.work();
    own += std::chrono::duration<double>(Clock::now() - t0).count() -
           (w1.evaluate_s - w0.evaluate_s) - (w1.derivatives_s - w0.derivatives_s);
    return result;
  };
  auto restore = [&](const Eigen::VectorXd& from, int iterations, const AcceptFn& take = {},
                     int refusals_to_stop = 0, RestorationGoal goal = RestorationGoal::Polish,
                     double damping = kRestorationDamping) {
    return accounted(out.split.restoration, [&] {
      return restoreFeasibility(problem, from, iterations, stop, on_restore,
                                time_limit_s - elapsed(), take, kFeasibilityTolerance,
                                refusals_to_stop, goal, damping);
    });
  };
  // The result is x itself (no stage solve ended the plan).
  auto endAt = [&](const Eigen::VectorXd& x, const char* status) {
    out.final.x = x;
    problem.evaluate(x, out.final.evaluation);
    out.final.objective = out.final.evaluation.objective;
    out.final.max_violation = NloptSolver::maxViolation(out.final.evaluation);
    out.final.status = status;
  };
  const PlannerConfig& cfg = problem.config();
  const double target_h = problem.obstacle().height;
  std::vector<double> boxes = cfg.cop_homotopy;
  boxes.push_back(cfg.cop_box);
  // Stages: heights up to the target with the largest box, then the smaller boxes.
  std::vector<std::pair<double, double>> stages;
  const double step = cfg.height_homotopy_step;
  for (double h = std::min(target_h, step); h < target_h - 1e-9; h += step)
    stages.emplace_back(h, boxes.front());
  stages.emplace_back(target_h, boxes.front());
  for (std::size_t i = 1; i < boxes.size(); ++i) stages.emplace_back(target_h, boxes[i]);

  Eigen::VectorXd x;
  if (warm_start != nullptr) {
    if (warm_start->size() != problem.layout().total)
      throw InputError("warm start: " + std::to_string(warm_start->size()) +
                       " values, the problem has " + std::to_string(problem.layout().total) +
                       " variables (another configuration?)");
    Eigen::VectorXd lo, hi;
    problem.bounds(lo, hi);
    x = warm_start->cwiseMax(lo).cwiseMin(hi);
    stages.erase(stages.begin(), stages.end() - 1);
    problem.setDifficulty(stages.front().first, stages.front().second, true);
    if (on_stage) on_stage("warm start: restoring feasibility, then only the target stage");
    const RestorationResult rest = restore(x, 60, accept);
    x = rest.x;
    out.iterations += rest.iterations;
    if (rest.accepted) {
      // The neighbouring problem's solution projected onto this one's feasible set is the
      // re-plan: SLSQP from such a point (fresh identity Hessian) left the feasible set for its
      // whole 40-iteration budget and found no better feasible point (measured on the default
      // with a 1.5 kg chest payload: 34 of the re-plan's 46 s; docs/planner.md).
      if (on_stage) on_stage("warm start: the restored point passes the check; no stage solve");
      stages.clear();
      endAt(x, "projected");
    }
  } else {
    problem.setDifficulty(stages.front().first, stages.front().second, stages.size() == 1);
    const Eigen::VectorXd guess = problem.initialGuess();
    if (on_stage) on_stage("restoring feasibility of the kinematic guess (Levenberg-Marquardt)");
    RestorationResult rest = restore(guess, kGuessSteps, {}, 0, RestorationGoal::Probe);
    out.iterations += rest.iterations;
    if (rest.max_violation > kGuessRestartAbove && !rest.interrupted && !rest.timed_out) {
      // Stuck far from the feasible set: the first, nearly Gauss-Newton steps from the guess's
      // large CoP violations can drag the swinging foot through the bar, where the violations'
      // sum of squares has a local minimum (the foot low across the bar, ~2.9; 20 cm x 11 cm bar
      // 1 mm lower or 4 mm farther). Shorter first steps from the guess avoid it there.
      if (on_stage) on_stage("stuck far from feasibility: restoring the guess again, damped");
      const RestorationResult again = restore(guess, kGuessSteps, {}, 0, RestorationGoal::Project,
                                              kGuessRestartDamping * kRestorationDamping);
      out.iterations += again.iterations;
      if (again.max_violation < rest.max_violation) rest = again;
    }
    x = rest.x;
  }
  // The last stage that ended feasible (its parameters and solution): where a failed stage's
  // bisection starts.
  std::optional<std::pair<double, double>> good_stage;
  Eigen::VectorXd good_x;
  int bisections = 0;
  for (std::size_t i = 0; i < stages.size(); ++i) {
    problem.setDifficulty(stages[i].first, stages[i].second, i + 1 == stages.size());
    if (on_stage) {
      char buf[128];
      std::snprintf(buf, sizeof buf, "stage %zu/%zu: obstacle %.3f m, CoP box %.3f m", i + 1,
                    stages.size(), stages[i].first, stages[i].second);
      on_stage(buf);
    }
    const double left = time_limit_s - elapsed();
    if (left <= 0.0) {
      out.final.status = "time_limit";
      break;
    }
    if (i > 0 && warm_start == nullptr) {
      // A harder stage starts infeasible (e.g. violations ~2 when the CoP box halves); SLSQP's
      // identity-Hessian steps from there wander (measured). Project back first.
      const RestorationResult proj = restore(x, 40, {}, 0, RestorationGoal::Project);
      out.iterations += proj.iterations;
      x = proj.x;
    }
    const double remaining = time_limit_s - elapsed();
    if (remaining <= 0.0) {
      out.final.status = "time_limit";
      break;
    }
    SolveResult r = accounted(out.split.nlopt, [&] {
      return solver.solve(problem, x, static_cast<int>(i + 1), remaining,
                          cfg.solver.max_iterations);
    });
    out.iterations += r.iterations;
    x = r.x;
    out.final = r;
    if (out.final.interrupted) break;
    if (out.final.max_violation > kFeasibilityTolerance) {
      // SLSQP ends near, not always inside, the feasible set: polish with restoration steps
      // (they end at a tenth of the tolerance or when no step reduces the violations; on the
      // 20 cm run 30 steps ended at 0.013 and 150 at 0.0137, still descending; measured,
      // docs/planner.md). The target stage's polish may stop at the first feasible point the
      // caller's finer measure takes (on the default: the last 396 of its 400 steps went from
      // 0.0096 to 0.0073 without `accept`), and stops once it has refused kPolishRefusals
      // feasible points: more steps inside the rows rarely move what the check finds between
      // samples (the 20.5 cm bar: six refusals over its last 183 steps, 24 s), a grid point
      // there does (the caller's mesh refinement). An intermediate stage's polish ends at the
      // tolerance, like a projection: the next stage starts with a projection onto its own rows
      // (gap 0.025 once crawled 400 steps from 0.0017 towards a tenth of it, 24 s).
      const bool target = i + 1 == stages.size();
      const RestorationResult polish =
          restore(x, kPolishIterations, target ? accept : AcceptFn{}, target ? kPolishRefusals : 0,
                  target ? RestorationGoal::Polish : RestorationGoal::Project);
      out.iterations += polish.iterations;
      x = polish.x;
      problem.evaluate(x, out.final.evaluation);
      out.final.x = x;
      out.final.objective = out.final.evaluation.objective;
      out.final.max_violation = polish.max_violation;
      if (polish.timed_out) out.final.status = "time_limit";
    }
    if (out.final.max_violation <= kFeasibilityTolerance) {
      good_stage = stages[i];
      good_x = x;
    } else if (good_stage && bisections < kMaxBisections && !out.final.interrupted &&
               elapsed() < time_limit_s) {
      // Continuation step control: halve the step from the last feasible stage and come back.
      const std::pair<double, double> mid{0.5 * (good_stage->first + stages[i].first),
                                          0.5 * (good_stage->second + stages[i].second)};
      if (std::abs(mid.first - stages[i].first) >= 2.5e-3 ||
          std::abs(mid.second - stages[i].second) >= 2.5e-3) {
        ++bisections;
        if (on_stage) {
          char buf[160];
          std::snprintf(buf, sizeof buf,
                        "stage %zu ended infeasible (%.4f): a stage at obstacle %.3f m, CoP box "
                        "%.4f m first, from the last feasible stage's solution",
                        i + 1, out.final.max_violation, mid.first, mid.second);
          on_stage(buf);
        }
        stages.insert(stages.begin() + static_cast<std::ptrdiff_t>(i), mid);
        x = good_x;
        --i;  // the loop's ++i runs the inserted stage next
      }
    }
  }
  if (out.final.x.size() == 0) endAt(x, "time_limit");  // no stage ran before the time limit
  out.solve_time = elapsed();
  const WorkAccount& work1 = problem.work();
  out.split.evaluations = work1.evaluate_s - work0.evaluate_s;
  out.split.derivatives = work1.derivatives_s - work0.derivatives_s;
  out.split.other = out.solve_time - out.split.evaluations - out.split.derivatives -
                    out.split.nlopt - out.split.restoration;
  const bool at_target = problem.lastStage();  // false when the solve ended before it
  out.valid = at_target && out.final.max_violation <= kFeasibilityTolerance;
  for (int f = 0; f < static_cast<int>(Family::kCount); ++f) {
    if (out.final.evaluation.worst[static_cast<std::size_t>(f)] > kFeasibilityTolerance)
      out.violated.push_back(familyName(static_cast<Family>(f)));
  }
  return out;
}

}  // namespace overstep::planner
