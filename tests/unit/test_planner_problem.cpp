// The overstep NLP: derivatives against central finite differences, row layout, the kinematic
// guess, consistency of the sampled motion, configuration loading.
#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "overstep/core/error.hpp"
#include "overstep/planner/check.hpp"
#include "overstep/planner/problem.hpp"
#include "overstep/planner/solver.hpp"
#include "overstep/robots/leg.hpp"
#include "test_util.hpp"

namespace overstep::planner {
namespace {

class Problem : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    model_ = new robots::WholeBodyModel(robots::WholeBodyModel::fromFile(test::hrp2Yaml()));
    core::ObstacleSpec ob;
    ob.height = 0.05;
    problem_ = new OverstepProblem(*model_, PlannerConfig{}, ob);
    raw_ = new OverstepProblem(*model_, rawConfig(), ob);
    x_ = new Eigen::VectorXd(problem_->initialGuess());
  }
  /// The configuration without the polish and the swept clearance (for the restorations below).
  static PlannerConfig rawConfig() {
    PlannerConfig off;
    off.passive_polish = false;
    off.swept_clearance = 0.0;
    return off;
  }
  static void TearDownTestSuite() {
    delete x_;
    delete raw_;
    delete problem_;
    delete model_;
  }
  /// The guess made nearly feasible at the samples (restoration on the problem without the
  /// polish and the swept clearance), computed once: the guess itself is not everywhere
  /// reachable (the transfer's trailing ankle beyond its limit), which the joint-limit rows report.
  static const Eigen::VectorXd& restored() {
    static const Eigen::VectorXd x = [] {
      const RestorationResult rest = restoreFeasibility(*raw_, *x_, 40, nullptr, nullptr);
      EXPECT_LT(rest.max_violation, 0.5);
      return rest.x;
    }();
    return x;
  }
  static robots::WholeBodyModel* model_;
  static OverstepProblem* problem_;
  static OverstepProblem* raw_;
  static Eigen::VectorXd* x_;
};
robots::WholeBodyModel* Problem::model_ = nullptr;
OverstepProblem* Problem::problem_ = nullptr;
OverstepProblem* Problem::raw_ = nullptr;
Eigen::VectorXd* Problem::x_ = nullptr;

// The restoration honours its time limit (the polish after a stage used to run up to 400 steps,
// ~70 s, past the planner's limit): none left -> no step, the start returned (inside the bounds),
// and with time left it takes steps and lowers the violation.
TEST_F(Problem, RestorationStopsAtItsTimeLimit) {
  OverstepProblem& raw = *raw_;
  const double v0 = restoreFeasibility(raw, *x_, 0, nullptr, nullptr).max_violation;
  ASSERT_GT(v0, 0.1 * kFeasibilityTolerance) << "the guess must need restoring for this test";
  for (const double limit : {0.0, -1.0}) {
    const RestorationResult none = restoreFeasibility(raw, *x_, 40, nullptr, nullptr, limit);
    EXPECT_EQ(none.iterations, 0) << limit;
    EXPECT_TRUE(none.timed_out) << limit;
    EXPECT_EQ(none.max_violation, v0) << limit;
    Eigen::VectorXd lo, hi;
    raw.bounds(lo, hi);
    EXPECT_TRUE(none.x.isApprox(x_->cwiseMax(lo).cwiseMin(hi)));
  }
  const RestorationResult some = restoreFeasibility(raw, *x_, 3, nullptr, nullptr, 600.0);
  EXPECT_FALSE(some.timed_out);
  EXPECT_GE(some.iterations, 1);
  EXPECT_LT(some.max_violation, v0);
}

// The restoration's first damping (Levenberg-Marquardt, relative to diag(J^T J)): a hundred times
// more damped, the first step from the guess is shorter (measured: 8.5 against 16.8 in scaled
// variables) (the planner restarts a guess restoration
// that stalls far from feasibility with a larger one) and still lowers the violation. Both steps
// are taken at their first trial (the damping after an accepted step is a third of it), so
// that they solve the same linear model.
TEST_F(Problem, RestorationDampingShortensTheFirstStep) {
  OverstepProblem& raw = *raw_;
  const double v0 = restoreFeasibility(raw, *x_, 0, nullptr, nullptr).max_violation;
  const Eigen::VectorXd scale = raw.variableScale();
  Eigen::VectorXd lo, hi;
  raw.bounds(lo, hi);
  const Eigen::VectorXd x0 = x_->cwiseMax(lo).cwiseMin(hi);
  const auto inf = std::numeric_limits<double>::infinity();
  double length[2] = {0.0, 0.0};
  const double damping[2] = {0.1, 10.0};
  for (int i = 0; i < 2; ++i) {
    double after = 0.0;
    const auto record = [&](const IterationInfo& info) { after = info.step; };
    const RestorationResult one =
        restoreFeasibility(raw, *x_, 1, nullptr, record, inf, {}, kFeasibilityTolerance, 0,
                           RestorationGoal::Project, damping[i]);
    ASSERT_EQ(one.iterations, 1);
    ASSERT_DOUBLE_EQ(after, damping[i] / 3.0) << "not taken at the first trial";
    EXPECT_LT(one.max_violation, v0) << damping[i];
    length[i] = (one.x - x0).cwiseQuotient(scale).norm();
  }
  EXPECT_GT(length[1], 0.0);
  EXPECT_LT(length[1], length[0]);
}

// Beyond reach the double-support leg's reach rows keep growing with its target (the leg
// continued past straight, the row the stretched leg's distance plus the target's excess; before,
// both stopped at the stretched leg and a restoration held there without a gradient): the right
// landing 30 cm further forward stretches the left leg in the transfer; 1 cm further still,
// every reach row more than 5 cm beyond leg_reach grows, by up to that centimetre.
TEST_F(Problem, ReachRowsGrowBeyondReach) {
  OverstepProblem& p = *raw_;
  const std::vector<Family>& fam = p.inequalityFamilies();
  Eigen::VectorXd x = restored();
  const int landing_x = p.layout().feet + 2;  // the right foot's landing placement, x
  Evaluation near, far;
  x(landing_x) += 0.30;
  p.evaluate(x, near);
  x(landing_x) += 0.01;
  p.evaluate(x, far);
  int beyond = 0;
  for (int i = 0; i < near.ineq.size(); ++i) {
    if (fam[static_cast<std::size_t>(i)] != Family::Reach || !(near.ineq(i) > 1.0)) continue;
    ++beyond;
    EXPECT_TRUE(std::isfinite(far.ineq(i))) << p.describeRow(x, false, i);
    EXPECT_GT(far.ineq(i) - near.ineq(i), 0.05) << p.describeRow(x, false, i);  // 2.5 mm
    EXPECT_LT(far.ineq(i) - near.ineq(i), 0.2 + 1e-9) << p.describeRow(x, false, i);
  }
  // Fails too where the rows stop at the stretched leg (~0.12), as they did before.
  EXPECT_GT(beyond, 0) << "no reach row 5 cm beyond leg_reach";
}

// The restoration's `accept` (the plan command passes the 1 kHz check): asked only at iterates
// within its violation level (here 0.5, which the guess's restoration reaches in a few steps; the
// planner uses the feasibility tolerance), then after 5, 10, ... more steps; an iterate it
// refuses changes nothing (the same steps, bit for bit, as without it); the first one it takes
// ends the restoration there.
TEST_F(Problem, RestorationStopsWhereAcceptTakesAPoint) {
  OverstepProblem& p = *raw_;
  constexpr int kSteps = 25;
  constexpr double kLevel = 0.5;
  const auto inf = std::numeric_limits<double>::infinity();
  const RestorationResult plain = restoreFeasibility(p, *x_, kSteps, nullptr, nullptr);
  std::vector<Eigen::VectorXd> asked;
  std::vector<int> asked_at;  // restoration steps taken before each question
  int steps = 0;
  const auto count = [&](const IterationInfo& i) { steps = i.iteration; };
  const AcceptFn refuse = [&](const Eigen::VectorXd& x) {
    Evaluation e;
    p.evaluate(x, e);
    EXPECT_LE(std::max(e.ineq.maxCoeff(), e.eq.cwiseAbs().maxCoeff()), kLevel);
    asked.push_back(x);
    asked_at.push_back(steps);
    return false;
  };
  const RestorationResult refused =
      restoreFeasibility(p, *x_, kSteps, nullptr, count, inf, refuse, kLevel);
  ASSERT_GE(asked.size(), 2u) << "the restoration ended at " << plain.max_violation;
  for (std::size_t i = 1; i < asked_at.size(); ++i)
    EXPECT_EQ(asked_at[i] - asked_at[i - 1], 5 << (i - 1)) << i;
  EXPECT_FALSE(refused.accepted);
  EXPECT_EQ(refused.iterations, plain.iterations);
  EXPECT_EQ(refused.x, plain.x);
  int calls = 0;
  const AcceptFn take = [&](const Eigen::VectorXd&) { return ++calls > 0; };
  const RestorationResult taken =
      restoreFeasibility(p, *x_, kSteps, nullptr, nullptr, inf, take, kLevel);
  EXPECT_TRUE(taken.accepted);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(taken.x, asked.front());
  EXPECT_EQ(taken.iterations, asked_at.front());
  EXPECT_LE(taken.max_violation, kLevel);
  // With refusals_to_stop it ends at the iterate of that refusal, not accepted.
  asked.clear();
  asked_at.clear();
  steps = 0;
  const RestorationResult stopped =
      restoreFeasibility(p, *x_, kSteps, nullptr, count, inf, refuse, kLevel, 2);
  EXPECT_FALSE(stopped.accepted);
  EXPECT_EQ(stopped.refusals, 2);
  ASSERT_EQ(asked.size(), 2u);
  EXPECT_EQ(stopped.x, asked.back());
  EXPECT_EQ(stopped.iterations, asked_at.back());
  EXPECT_LT(stopped.iterations, plain.iterations);
}

// A probe (the planner's first restoration of its guess, which a damped second start may follow)
// takes the projection's steps, bit for bit, and also ends once ten steps took less than 1 % off
// a violation above 1, where the projection goes on: from the guess for a 40 cm bar, which no
// swing clears.
TEST_F(Problem, ProbeEndsOnAStallFarFromFeasibility) {
  core::ObstacleSpec ob;
  ob.height = 0.4;
  OverstepProblem p(*model_, rawConfig(), ob);
  const Eigen::VectorXd x0 = p.initialGuess();
  constexpr int kSteps = 30;
  const auto inf = std::numeric_limits<double>::infinity();
  std::vector<double> viol;  // after each projection step
  const auto record = [&](const IterationInfo& i) { viol.push_back(i.max_violation); };
  const RestorationResult project = restoreFeasibility(
      p, x0, kSteps, nullptr, record, inf, {}, kFeasibilityTolerance, 0, RestorationGoal::Project);
  const RestorationResult probe = restoreFeasibility(
      p, x0, kSteps, nullptr, nullptr, inf, {}, kFeasibilityTolerance, 0, RestorationGoal::Probe);
  ASSERT_EQ(static_cast<int>(viol.size()), project.iterations);
  // The projection's first step that took less than 1 % off the violation ten steps before it,
  // above 1 (below 1 the projection itself stops there).
  int expected = project.iterations;
  for (int k = 11; k <= project.iterations; ++k) {
    const double v = viol[static_cast<std::size_t>(k - 1)];
    if (v > 0.99 * viol[static_cast<std::size_t>(k - 11)]) {
      expected = k;
      break;
    }
  }
  ASSERT_LT(expected, project.iterations) << "the projection did not crawl: no stall to probe";
  ASSERT_GT(viol[static_cast<std::size_t>(expected - 1)], 1.0);
  EXPECT_EQ(probe.iterations, expected);
  EXPECT_EQ(probe.max_violation, viol[static_cast<std::size_t>(expected - 1)]);
}

// A projection (the start of a stage solve) takes the polish's steps, bit for bit, and ends at
// the first iterate within the feasibility tolerance, or once ten steps took less than 1 % off
// a violation above it; the polish goes on toward a tenth of the tolerance.
TEST_F(Problem, ProjectionEndsAtTheToleranceOnThePolishPath) {
  OverstepProblem& p = *raw_;
  const Eigen::VectorXd x0 = restored();  // at the suite's difficulty
  // The homotopy's first CoP box (4 cm), within which the restored point is feasible after a few
  // steps; the suite's difficulty is set back at the end.
  const double h = p.currentHeight(), box = p.currentCopBox();
  const bool last = p.lastStage();
  p.setDifficulty(h, 0.04, false);
  constexpr int kSteps = 30;
  const auto inf = std::numeric_limits<double>::infinity();
  std::vector<double> viol;  // after each polish step
  const auto record = [&](const IterationInfo& i) { viol.push_back(i.max_violation); };
  const RestorationResult polish = restoreFeasibility(p, x0, kSteps, nullptr, record);
  const RestorationResult project = restoreFeasibility(
      p, x0, kSteps, nullptr, nullptr, inf, {}, kFeasibilityTolerance, 0, RestorationGoal::Project);
  ASSERT_EQ(static_cast<int>(viol.size()), polish.iterations);
  // Where the projection must end: the polish's first feasible iterate or its first stall.
  int expected = polish.iterations;
  Evaluation e0;
  p.evaluate(x0, e0);
  const double v0 = std::max(e0.ineq.maxCoeff(), e0.eq.cwiseAbs().maxCoeff());
  for (int k = 0; k <= polish.iterations; ++k) {
    const double v = k == 0 ? v0 : viol[static_cast<std::size_t>(k - 1)];
    // The stall rule compares a step's result with the one ten steps before (from the 11th on).
    const double ten_before = k >= 11 ? viol[static_cast<std::size_t>(k - 11)] : inf;
    if (v <= kFeasibilityTolerance || (v < 1.0 && v > 0.99 * ten_before)) {
      expected = k;
      break;
    }
  }
  EXPECT_EQ(project.iterations, expected);
  EXPECT_LE(project.iterations, polish.iterations);
  if (expected < polish.iterations) {
    // The same point as the polish's iterate there (a second polish, stopped by its step cap).
    const RestorationResult cut = restoreFeasibility(p, x0, expected, nullptr, nullptr);
    EXPECT_EQ(project.x, cut.x);
  }
  std::printf("projection: %d of the polish's %d steps, violation %.4g (polish %.4g)\n",
              project.iterations, polish.iterations, project.max_violation, polish.max_violation);
  p.setDifficulty(h, box, last);
}

// The height homotopy raises the bar under a swinging leg only: the obstacle row of a sample
// whose legs are both on the ground reads the target bar at every stage; a single-support row
// reads the stage's bar (lower bar, more clearance).
TEST_F(Problem, TheHomotopyRaisesTheBarUnderTheSwingingLegOnly) {
  core::ObstacleSpec ob;
  ob.height = 0.20;
  OverstepProblem p(*model_, PlannerConfig{}, ob);
  const Eigen::VectorXd x = p.initialGuess();
  Evaluation low, target;
  p.setDifficulty(0.05, 0.04, false);
  p.evaluate(x, low);
  p.setDifficulty(0.20, 0.04, false);
  p.evaluate(x, target);
  int ds = 0, ss_lower = 0;
  for (int r = 0; r < p.inequalityCount(); ++r) {
    if (p.inequalityFamilies()[static_cast<std::size_t>(r)] != Family::ObstacleCollision) continue;
    const std::string where = p.describeRow(x, false, r);
    if (where.find("(ds_") != std::string::npos) {
      EXPECT_EQ(low.ineq(r), target.ineq(r)) << where;
      ++ds;
    } else if (low.ineq(r) < target.ineq(r)) {
      ++ss_lower;  // the swinging leg sees the 5 cm bar: farther from it
    }
  }
  EXPECT_GT(ds, 20);
  EXPECT_GT(ss_lower, 5);
}

// The feet's capsules where they stand at the start: the bar's distance to them grows with the gap
// one for one, and equals the gap less the capsules' overhang in front of the toes, taken from
// the robot description (the foot capsules' front ends, carried into the sole frame by the
// model at half-sitting).
TEST_F(Problem, StartClearanceIsTheGapLessTheFeetCapsulesOverhang) {
  auto clearance = [&](double gap) {
    core::ObstacleSpec ob;
    ob.gap = gap;
    return OverstepProblem(*model_, PlannerConfig{}, ob).startClearance();
  };
  EXPECT_NEAR(clearance(0.05) - clearance(0.03), 0.02, 1e-12);
  const auto& d = model_->description();
  robots::WholeBodyModel m(*model_);
  m.setPositions(m.halfSitting());
  double overhang = -std::numeric_limits<double>::infinity();
  for (const robots::LegChain& leg : robots::legChains(*model_)) {
    const auto* foot = d.foot(leg.side);
    const Eigen::Isometry3d X_SW = m.framePose(m.frameIndex(foot->sole_frame)).inverse();
    for (const auto& c : d.capsules) {
      if (c.link != leg.foot_link) continue;
      const Eigen::Isometry3d X_SC = X_SW * m.framePose(m.frameIndex(c.link));
      const double front = std::max((X_SC * c.p0).x(), (X_SC * c.p1).x()) + c.radius;
      overhang = std::max(overhang, front - foot->sole.x_front);
    }
  }
  ASSERT_TRUE(std::isfinite(overhang));
  EXPECT_NEAR(clearance(0.03), 0.03 - overhang, 1e-9);
}

TEST_F(Problem, LayoutAndRowFamiliesAreConsistent) {
  const auto& lay = problem_->layout();
  EXPECT_EQ(lay.total, 5 + 6 + 12 * lay.free_cp + 4 * lay.flex_free_cp);
  EXPECT_EQ(lay.flex, 5 + 6 + 12 * lay.free_cp);
  EXPECT_EQ(static_cast<int>(problem_->inequalityFamilies().size()), problem_->inequalityCount());
  EXPECT_EQ(static_cast<int>(problem_->equalityFamilies().size()), problem_->equalityCount());
  EXPECT_LT(problem_->equalityCount(), lay.total);  // SLSQP needs m_eq <= n
  Evaluation e;
  problem_->evaluate(*x_, e);
  EXPECT_EQ(e.ineq.size(), problem_->inequalityCount());
  EXPECT_EQ(e.eq.size(), problem_->equalityCount());
  EXPECT_TRUE(e.ineq.allFinite());
  EXPECT_TRUE(e.eq.allFinite());
  EXPECT_TRUE(std::isfinite(e.objective));
}

// The row layout follows from the terms: count each family's rows against the phase table and
// the sample grid (single-support phases sampled on their closed interval, double-support ones
// without the instant of a switch: one sample short of a lift-off at their end and one sample
// after a touchdown at their start).
TEST_F(Problem, RowLayoutFollowsThePhasesAndSamples) {
  const PlannerConfig cfg;
  int contacts = 0, ss = 0, ds = 0;
  auto two = [](int i) {
    const auto& ph = phaseTable()[static_cast<std::size_t>(i)];
    return ph.right_contact && ph.left_contact;
  };
  for (int i = 0; i < kPhaseCount; ++i) {
    const bool touchdown = two(i) && i > 0 && !two(i - 1);
    const bool lift_off = two(i) && i + 1 < kPhaseCount && !two(i + 1);
    const int n = cfg.samples_per_phase[static_cast<std::size_t>(i)] + 1 - (touchdown ? 1 : 0) -
                  (lift_off ? 1 : 0);
    contacts += n * (two(i) ? 2 : 1);
    (two(i) ? ds : ss) += n;
  }
  auto count = [](const std::vector<Family>& fams, Family f) {
    return static_cast<int>(std::count(fams.begin(), fams.end(), f));
  };
  const auto& in = problem_->inequalityFamilies();
  const auto& eq = problem_->equalityFamilies();
  EXPECT_EQ(count(in, Family::CoP), 4 * contacts);
  EXPECT_EQ(count(in, Family::Friction), 6 * contacts);
  EXPECT_EQ(count(in, Family::Unilateral), contacts);
  EXPECT_EQ(count(in, Family::Clearance), 4 * ss);
  EXPECT_EQ(count(in, Family::ObstacleCollision), ss + ds);
  EXPECT_EQ(count(in, Family::SelfCollision), ss + ds);
  EXPECT_EQ(count(in, Family::Pelvis), 4 * (ss + ds));
  EXPECT_EQ(count(in, Family::JointLimits), 12 * ds);
  EXPECT_EQ(count(in, Family::Reach), ds);
  EXPECT_EQ(count(in, Family::Dynamics), 2 * ds);
  EXPECT_EQ(count(eq, Family::Dynamics), 4 * ss);
  EXPECT_EQ(count(eq, Family::Switching), 4 * 12);
  EXPECT_EQ(count(eq, Family::LiftOff), 2 * 3);
  EXPECT_EQ(count(eq, Family::Touchdown), 2 * 3);
  // Each row's family is the one describeRow names.
  for (int r = 0; r < problem_->inequalityCount(); r += 97)
    EXPECT_EQ(
        problem_->describeRow(*x_, false, r).rfind(familyName(in[static_cast<std::size_t>(r)]), 0),
        0u)
        << r;
}

TEST_F(Problem, InitialGuessIsInsideTheBounds) {
  Eigen::VectorXd lo, hi;
  problem_->bounds(lo, hi);
  EXPECT_TRUE(((x_->array() >= lo.array()) && (x_->array() <= hi.array())).all());
  EXPECT_GT(problem_->stepLength(*x_), 0.3);
  EXPECT_GT(problem_->footSpacing(*x_), 0.1);
}

// Every column of the Jacobian and the gradient against central differences of whole
// evaluations, on a restored point (the next test covers the guess too), with check points in
// the grid. The Jacobian's columns are forward differences: on rows with curvature on small scales
// (smooth minima over 1 mm of distance) their error is about a percent, hence the tolerance; an
// entry whose row is not differentiable at the point (a kink at x, where one-sided differences
// disagree, or within the steps, where central differences at a tenth and ten times the step
// disagree: e.g. the distance of two parallel capsules, the feet side by side, in their yaw)
// is left out.
TEST_F(Problem, DerivativesMatchCentralDifferencesInEveryColumn) {
  std::vector<GridPoint> extra = {{0, 0.45, 0.0}, {2, 0.3, 0.0}, {3, 0.6, 0.0}};
  core::ObstacleSpec ob;
  ob.height = 0.05;
  OverstepProblem refined(*model_, PlannerConfig{}, ob, extra);
  constexpr double kTolerance = 2e-2;
  const Eigen::VectorXd& x = restored();
  Evaluation e0;
  refined.evaluate(x, e0);
  Eigen::VectorXd g = Eigen::VectorXd::Constant(x.size(), std::nan(""));
  Eigen::MatrixXd ji = Eigen::MatrixXd::Constant(refined.inequalityCount(), x.size(), std::nan(""));
  Eigen::MatrixXd je = Eigen::MatrixXd::Constant(refined.equalityCount(), x.size(), std::nan(""));
  refined.derivatives(x, e0, g, ji, je);
  ASSERT_TRUE(g.allFinite() && ji.allFinite() && je.allFinite());
  Eigen::VectorXd v0(1 + e0.ineq.size() + e0.eq.size());
  v0 << e0.objective, e0.ineq, e0.eq;
  auto at = [&](int j, double h) {
    Eigen::VectorXd xh = x;
    xh(j) += h;
    Evaluation e;
    refined.evaluate(xh, e);
    Eigen::VectorXd v(v0.size());
    v << e.objective, e.ineq, e.eq;
    return v;
  };
  const int ni = refined.inequalityCount();
  for (int j = 0; j < x.size(); ++j) {
    const double h = 1e-7 * std::max(1.0, std::abs(x(j)));
    Eigen::VectorXd J(1 + ji.rows() + je.rows());
    J << g(j), ji.col(j), je.col(j);
    const Eigen::VectorXd vp = at(j, h), vm = at(j, -h);
    const Eigen::VectorXd fd = (vp - vm) / (2 * h);
    Eigen::VectorXd err = (J - fd).cwiseAbs();
    const double tol = kTolerance * (1.0 + fd.cwiseAbs().maxCoeff());
    if (err.maxCoeff() > tol) {
      // Not differentiable: one-sided differences disagree (a kink at x), or central ones at
      // a tenth of the step or ten times it (a kink within the steps the Jacobian takes).
      const Eigen::VectorXd fd_small = (at(j, 0.1 * h) - at(j, -0.1 * h)) / (0.2 * h);
      const Eigen::VectorXd fd_large = (at(j, 10 * h) - at(j, -10 * h)) / (20 * h);
      const Eigen::VectorXd fwd = (vp - v0) / h, bwd = (v0 - vm) / h;
      for (Eigen::Index r = 0; r < err.size(); ++r) {
        const double s = kTolerance * (1.0 + std::abs(fd(r)));
        if (std::abs(fd(r) - fd_small(r)) > s || std::abs(fd(r) - fd_large(r)) > s ||
            std::abs(fwd(r) - bwd(r)) > s)
          err(r) = 0.0;
      }
    }
    Eigen::Index r = 0;
    const double worst = err.maxCoeff(&r);
    const int row = static_cast<int>(r) - 1;
    ASSERT_LE(worst, tol) << "column " << j << ": "
                          << (row < 0    ? std::string("objective")
                              : row < ni ? refined.describeRow(x, false, row)
                                         : refined.describeRow(x, true, row - ni))
                          << ", derivative " << J(r) << ", central difference " << fd(r);
  }
}

// Every column against central differences of whole evaluations with a fine step (1e-7), to kFine
// of the column's largest entry (measured 1.6e-5 on the guess and the restored point, 9.7e-5 on
// the random one: the obstacle row's smooth minimum), on the guess, a restored point and a seeded
// random point near it, with
// check points in the grid, every row family with non-zero entries compared (printed per family):
// the durations' and placements' forward differences of what each moves, the control points' chain
// rule through the basis. Forward differences of whole evaluations with a step of 1e-6, which the
// derivatives were before, miss by up to 112 % there (printed): the swinging leg's self-clearance
// at the swing's check point, a sharp smooth minimum, whose curvature such a step does not resolve.
TEST_F(Problem, DerivativesMatchFineCentralDifferences) {
  std::vector<GridPoint> extra = {{0, 0.45, 0.0}, {2, 0.3, 0.0}, {3, 0.6, 0.0}};
  core::ObstacleSpec ob;
  ob.height = 0.05;
  OverstepProblem refined(*model_, PlannerConfig{}, ob, extra);
  constexpr double kFine = 2e-4;
  double worst = 0.0, worst_coarse = 0.0;
  // Per row family (and the objective, the last slot): the worst entry and how many entries were
  // compared where the central difference is not zero (every family must have some: a family
  // whose derivatives are all zero at both points would pass vacuously).
  constexpr int kSlots = static_cast<int>(Family::kCount) + 1;
  std::array<double, kSlots> fam_worst{};
  std::array<int, kSlots> fam_tested{};
  std::vector<int> slot_of(1, kSlots - 1);
  for (Family f : refined.inequalityFamilies()) slot_of.push_back(static_cast<int>(f));
  for (Family f : refined.equalityFamilies()) slot_of.push_back(static_cast<int>(f));
  // The guess, a restored point, and the restored point moved by a seeded random step of 1 % of
  // each variable's scale (inside the bounds).
  Eigen::VectorXd random_point = restored();
  {
    std::mt19937 rng(7);
    std::normal_distribution<double> n01(0.0, 1.0);
    Eigen::VectorXd lo, hi;
    refined.bounds(lo, hi);
    const Eigen::VectorXd D = refined.variableScale();
    for (Eigen::Index j = 0; j < random_point.size(); ++j)
      random_point(j) = std::clamp(random_point(j) + 0.01 * D(j) * n01(rng), lo(j), hi(j));
  }
  for (const Eigen::VectorXd& x : {*x_, restored(), random_point}) {
    Evaluation e0;
    refined.evaluate(x, e0);
    Eigen::VectorXd g = Eigen::VectorXd::Constant(x.size(), std::nan(""));
    Eigen::MatrixXd ji, je;
    refined.derivatives(x, e0, g, ji, je);
    auto values = [&](int j, double h) {
      Eigen::VectorXd xh = x;
      xh(j) += h;
      Evaluation e;
      refined.evaluate(xh, e);
      Eigen::VectorXd v(1 + e.ineq.size() + e.eq.size());
      v << e.objective, e.ineq, e.eq;
      return v;
    };
    const Eigen::VectorXd v0 = values(0, 0.0);
    for (int j = 0; j < x.size(); ++j) {
      const double h = 1e-7 * std::max(1.0, std::abs(x(j)));
      const Eigen::VectorXd cd = (values(j, h) - values(j, -h)) / (2 * h);
      Eigen::VectorXd J(cd.size());
      J << g(j), ji.col(j), je.col(j);
      const double scale = 1.0 + cd.cwiseAbs().maxCoeff();
      const double rel = (J - cd).cwiseAbs().maxCoeff() / scale;
      worst = std::max(worst, rel);
      for (Eigen::Index r = 0; r < cd.size(); ++r) {
        const int slot = slot_of[static_cast<std::size_t>(r)];
        fam_worst[slot] = std::max(fam_worst[slot], std::abs(J(r) - cd(r)) / scale);
        if (std::abs(cd(r)) > 1e-6) ++fam_tested[slot];
      }
      ASSERT_LE(rel, kFine) << "column " << j;
      const double hc = 1e-6 * std::max(1.0, std::abs(x(j)));
      const Eigen::VectorXd coarse = (values(j, hc) - v0) / hc;
      worst_coarse = std::max(worst_coarse, (coarse - cd).cwiseAbs().maxCoeff() / scale);
    }
  }
  std::printf(
      "worst column against central differences: %.2e (forward differences of whole "
      "evaluations, step 1e-6: %.2e)\n",
      worst, worst_coarse);
  for (int slot = 0; slot < kSlots; ++slot) {
    const bool present = std::count(slot_of.begin(), slot_of.end(), slot) > 0;
    if (!present) continue;
    const char* name = slot == kSlots - 1 ? "objective" : familyName(static_cast<Family>(slot));
    std::printf("  %-15s worst %.2e over %d non-zero entries\n", name, fam_worst[slot],
                fam_tested[slot]);
    EXPECT_GT(fam_tested[slot], 0) << name << ": no non-zero derivative was compared";
  }
}

// Each objective term alone (its weight 1, every other 0: switched off): its gradient against
// central differences of the objective (step 1e-7) on a restored point, NaN-prefilled, over the
// durations, the placements and every fifth control point, to 1e-4 of the largest entry; the
// term must move with some of them (a term with a zero gradient would pass vacuously).
TEST_F(Problem, EachObjectiveTermsGradientMatchesCentralDifferences) {
  const Eigen::VectorXd& x = restored();
  const int lead = problem_->layout().legs;  // durations and placements come first
  for (const auto& [name, weight] : PlannerConfig{}.weights) {
    (void)weight;
    PlannerConfig cfg;
    for (auto& [other, w] : cfg.weights) w = other == name ? 1.0 : 0.0;
    core::ObstacleSpec ob;
    ob.height = 0.05;
    OverstepProblem one(*model_, cfg, ob);
    ASSERT_EQ(one.layout().total, x.size());
    Evaluation e0;
    one.evaluate(x, e0);
    Eigen::VectorXd g = Eigen::VectorXd::Constant(x.size(), std::nan(""));
    Eigen::MatrixXd ji, je;
    one.derivatives(x, e0, g, ji, je);
    ASSERT_TRUE(g.allFinite()) << name;
    auto objective = [&](int j, double h) {
      Eigen::VectorXd xh = x;
      xh(j) += h;
      Evaluation e;
      one.evaluate(xh, e);
      return e.objective;
    };
    double largest = 0.0, worst = 0.0;
    int worst_j = -1;
    for (int j = 0; j < x.size(); ++j) {
      if (j >= lead && (j - lead) % 5 != 0) continue;
      const double h = 1e-7 * std::max(1.0, std::abs(x(j)));
      const double cd = (objective(j, h) - objective(j, -h)) / (2 * h);
      largest = std::max(largest, std::abs(cd));
      if (std::abs(g(j) - cd) > worst) {
        worst = std::abs(g(j) - cd);
        worst_j = j;
      }
    }
    std::printf("  %-17s worst %.2e of the largest entry %.2e\n", name.c_str(), worst, largest);
    EXPECT_GT(largest, 1e-6) << name << ": the term does not move";
    EXPECT_LE(worst, 1e-4 * (1.0 + largest)) << name << ", column " << worst_j;
  }
}

// Mesh refinement: check points carry the path constraints of their instant (not the elastic
// dynamics) and no objective weight; a point on or next to a sample is dropped; the rows'
// derivatives at them are right.
TEST_F(Problem, CheckPointsAddRowsButLeaveTheObjective) {
  core::ObstacleSpec ob;
  ob.height = 0.05;
  const double first = 1.0 / PlannerConfig{}.samples_per_phase[2];  // the transfer's first sample
  const std::vector<GridPoint> pts = {
      {1, 0.37, 0.0},    // right swing
      {1, 0.3704, 0.0},  // within 1e-3 of the first: dropped
      {2, first, 0.0},   // a sample of the transfer: dropped
      {2, 0.97, 0.0}};   // late in the transfer, after its last sample
  OverstepProblem refined(*model_, PlannerConfig{}, ob, pts);
  ASSERT_EQ(refined.checkPoints().size(), 2u);
  EXPECT_EQ(refined.checkPoints()[0].phase, 1);
  EXPECT_EQ(refined.checkPoints()[1].phase, 2);
  // The transfer's switch instants are off its grid: points there move just inside it.
  const OverstepProblem ends(*model_, PlannerConfig{}, ob, {{2, 0.0, 0.0}, {2, 1.0, 0.0}});
  ASSERT_EQ(ends.checkPoints().size(), 2u);
  EXPECT_GT(ends.checkPoints()[0].s, 0.0);
  EXPECT_LT(ends.checkPoints()[1].s, 1.0);
  EXPECT_GT(refined.inequalityCount(), problem_->inequalityCount());
  EXPECT_EQ(refined.equalityCount(), problem_->equalityCount());  // no elastic collocation
  const auto& fam = refined.inequalityFamilies();
  EXPECT_EQ(std::count(fam.begin() + problem_->inequalityCount(), fam.end(), Family::Dynamics), 0);
  EXPECT_EQ(std::count(fam.begin() + problem_->inequalityCount(), fam.end(), Family::Clearance), 4);
  Evaluation base, more;
  problem_->evaluate(*x_, base);
  refined.evaluate(*x_, more);
  EXPECT_EQ(more.objective, base.objective);
  EXPECT_EQ(more.ineq.head(base.ineq.size()), base.ineq);  // the samples' rows come first
  // The added rows' derivatives against central differences (a duration moves every point; a
  // leg and a bushing control point whose support holds the swing's check point move it).
  Eigen::VectorXd g;
  Eigen::MatrixXd ji, je;
  OverstepProblem& r = refined;
  r.derivatives(*x_, more, g, ji, je);
  const auto& lay = r.layout();
  const int extra = r.inequalityCount() - problem_->inequalityCount();
  for (int j : {1, 2, lay.legs + 2 * lay.free_cp + 6, lay.flex + lay.flex_free_cp + 6}) {
    const double h = 1e-5;
    Eigen::VectorXd xp = *x_, xm = *x_;
    xp(j) += h;
    xm(j) -= h;
    Evaluation ep, em;
    r.evaluate(xp, ep);
    r.evaluate(xm, em);
    const Eigen::VectorXd di = (ep.ineq - em.ineq).tail(extra) / (2 * h);
    EXPECT_GT(di.cwiseAbs().maxCoeff(), 0.0) << "column " << j << " moves no check-point row";
    EXPECT_LT((ji.col(j).tail(extra) - di).cwiseAbs().maxCoeff(),
              1e-3 * (1.0 + di.cwiseAbs().maxCoeff()))
        << "column " << j;
  }
  EXPECT_THROW(OverstepProblem(*model_, PlannerConfig{}, ob, {{5, 0.5, 0.0}}), InputError);
  EXPECT_THROW(OverstepProblem(*model_, PlannerConfig{}, ob, {{1, 1.5, 0.0}}), InputError);
}

// The derivatives are split over solver.threads workspaces: one thread and two give the same
// numbers to the bit (so `--threads 1` and `--threads 2` give the same plan). The evaluation is
// at a perturbed point so that every workspace's cached state differs from the baseline.
TEST_F(Problem, DerivativesAreTheSameWithOneOrTwoThreads) {
  PlannerConfig one, two;
  one.solver.threads = 1;
  two.solver.threads = 2;
  core::ObstacleSpec ob;
  ob.height = 0.05;
  OverstepProblem p1(*model_, one, ob), p2(*model_, two, ob);
  Eigen::VectorXd x = *x_;
  x.tail(x.size() - p1.layout().legs).array() += 1e-3;
  Eigen::VectorXd g1, g2;
  Eigen::MatrixXd i1, e1, i2, e2;
  for (int round = 0; round < 2; ++round) {  // the second round reuses dirty workspaces
    Evaluation a1, a2;
    p1.evaluate(x, a1);
    p2.evaluate(x, a2);
    ASSERT_EQ(a1.objective, a2.objective);
    p1.derivatives(x, a1, g1, i1, e1);
    p2.derivatives(x, a2, g2, i2, e2);
    EXPECT_EQ((g1 - g2).cwiseAbs().maxCoeff(), 0.0) << round;
    EXPECT_EQ((i1 - i2).cwiseAbs().maxCoeff(), 0.0) << round;
    EXPECT_EQ((e1 - e2).cwiseAbs().maxCoeff(), 0.0) << round;
    x(0) += 0.01;
  }
}

// SLSQP solves the linearised equalities exactly: a row whose gradient is tiny beside the others
// (e.g. a force that vanishes by construction of the wrench split) makes its steps huge. At the
// restored guess the scaled equality Jacobian must have full rank with a bounded condition
// number (the lift-off shear and twist rows had singular values of 4e-6 against 65, and SLSQP's
// steps were ~20 scaled units long, half of them rejected).
TEST_F(Problem, EqualityJacobianIsWellConditioned) {
  const Eigen::VectorXd& x = restored();
  Evaluation e;
  raw_->evaluate(x, e);
  Eigen::VectorXd g;
  Eigen::MatrixXd ji, je;
  raw_->derivatives(x, e, g, ji, je);
  const Eigen::MatrixXd A = je * raw_->variableScale().asDiagonal();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU);
  const Eigen::VectorXd sv = svd.singularValues();
  ASSERT_EQ(sv.size(), raw_->equalityCount());
  const Eigen::VectorXd u = svd.matrixU().col(sv.size() - 1);
  Eigen::Index worst = 0;
  u.cwiseAbs().maxCoeff(&worst);
  EXPECT_GT(sv(sv.size() - 1), 1e-6 * sv(0))
      << "smallest singular value " << sv(sv.size() - 1) << " of " << sv(0) << ", mostly "
      << raw_->describeRow(x, true, static_cast<int>(worst));
}

// At each lift-off and touchdown the swing sole's four corner rows read the corners' vertical
// acceleration (z'' >= 0: the sole leaves and arrives from above): the same number as the second
// derivative of the sampled plan's corner heights there (a cubic through the swing phase's four
// samples nearest the switch, the switch's own sample included; 1 kHz).
TEST_F(Problem, SwitchCornerRowsAreTheCornersVerticalAcceleration) {
  const Eigen::VectorXd& x = restored();
  Evaluation e;
  raw_->evaluate(x, e);
  const core::Plan plan = raw_->toPlan(x, 1000.0);
  const auto& d = model_->description();
  const std::vector<Family>& fam = raw_->inequalityFamilies();
  double largest = 0.0;
  for (const int phase : {1, 3}) {
    const int foot = phase == 1 ? 0 : 1;  // the swinging foot: right, then left
    const core::FootDescription& fd = *d.foot(foot == 0 ? "right" : "left");
    const Eigen::MatrixXd& pose = foot == 0 ? plan.right_foot : plan.left_foot;
    const std::string name = phase == 1 ? "ss_right_swing" : "ss_left_swing";
    std::vector<int> rows;  // the phase's clearance rows, in sample order
    for (int i = 0; i < raw_->inequalityCount(); ++i)
      if (fam[static_cast<std::size_t>(i)] == Family::Clearance &&
          raw_->describeRow(x, false, i).find(name) != std::string::npos)
        rows.push_back(i);
    ASSERT_GE(rows.size(), 8u);
    std::vector<int> in_phase;
    for (int k = 0; k < plan.samples(); ++k)
      if (plan.phase(k) == phase) in_phase.push_back(k);
    ASSERT_GE(in_phase.size(), 8u);
    for (const bool touchdown : {false, true}) {
      const int first_row = touchdown ? rows[rows.size() - 4] : rows[0];
      const double t_sw = touchdown ? plan.t(in_phase.back()) : plan.t(in_phase.front());
      Eigen::Matrix4d V;
      Eigen::Matrix<double, 4, 4> Z;  // corner heights (columns) at the four samples (rows)
      for (int i = 0; i < 4; ++i) {
        const int k = touchdown ? in_phase[in_phase.size() - 1 - static_cast<std::size_t>(i)]
                                : in_phase[static_cast<std::size_t>(i)];
        const double tau = plan.t(k) - t_sw;
        V.row(i) << 1.0, tau, tau * tau, tau * tau * tau;
        const Eigen::Quaterniond qf(pose(3, k), pose(4, k), pose(5, k), pose(6, k));
        int c = 0;
        for (const double cx : {fd.sole.x_front, -fd.sole.x_back})
          for (const double cy : {fd.yMin(), fd.yMax()})
            Z(i, c++) = (pose.col(k).head<3>() + qf * Eigen::Vector3d(cx, cy, 0.0)).z();
      }
      const Eigen::Matrix4d coeff = V.fullPivLu().solve(Z);
      for (int c = 0; c < 4; ++c) {
        const double acc = 2.0 * coeff(2, c);  // m/s^2
        const double row = e.ineq(first_row + c);
        EXPECT_NEAR(-row, acc, 0.02 + 0.01 * std::abs(acc))
            << name << (touchdown ? " touchdown" : " lift-off") << " corner " << c;
        largest = std::max(largest, std::abs(acc));
      }
    }
  }
  EXPECT_GT(largest, 0.05);  // the guess's feet do accelerate at the switches
}

TEST_F(Problem, SampledMotionKeepsStanceFeetAndCarriesTheWeight) {
  const Eigen::VectorXd& x = restored();
  const core::Plan p = problem_->toPlan(x, 100.0);
  EXPECT_NEAR(p.duration(), problem_->durations(x).sum(), 1e-9);
  EXPECT_EQ(p.phases.size(), 5u);
  // The left foot never moves before its swing; the right never after its landing.
  for (int k = 0; k < p.samples(); ++k) {
    if (p.phase(k) <= 2) {
      EXPECT_LT((p.left_foot.col(k).head<3>() - p.left_foot.col(0).head<3>()).norm(), 1e-9);
    }
    if (p.phase(k) >= 2) {
      EXPECT_LT((p.right_foot.col(k).head<2>() - Eigen::Vector2d(x(7), x(8))).norm(), 1e-6);
    }
  }
  // The foot wrenches sum to the contact wrench the motion needs (base rows), on a 1 kHz grid.
  const CheckReport r = checkPlan(p, *model_);
  EXPECT_FALSE(r.family("stance")->worst > 1e-3)
      << r.family("stance")->worst << " at " << r.family("stance")->t_worst << " "
      << r.family("stance")->detail;
}

/// Largest elastic-joint residual (N m) over the plan's own samples: inverse dynamics of the
/// sampled motion against the sampled foot wrenches.
/// Largest elastic-joint residual (N m) over the plan's samples, or over its single-support
/// samples only.
double elasticResidual(const core::Plan& p, bool single_support_only = false) {
  robots::WholeBodyModel m(robots::WholeBodyModel::fromFile(test::hrp2Yaml()));
  const auto& d = m.description();
  const int sole[2] = {m.frameIndex(d.foot("right")->sole_frame),
                       m.frameIndex(d.foot("left")->sole_frame)};
  double worst = 0.0;
  for (int k = 0; k < p.samples(); ++k) {
    const auto& ph = p.phases[static_cast<std::size_t>(p.phase(k))];
    if (single_support_only && ph.right_contact && ph.left_contact) continue;
    m.setState(p.q.col(k), p.v.col(k), p.a.col(k));
    const Eigen::VectorXd tau = m.torquesInContact(
        m.inverseDynamics(), {{sole[0], p.wrench(0, k)}, {sole[1], p.wrench(1, k)}});
    for (int e = 0; e < m.elasticCount(); ++e)
      worst = std::max(worst, std::abs(tau(m.elasticCoordinate(e))));
  }
  return worst;
}

// The passive polish changes the elastic coordinates in single support only, by small amounts,
// and keeps the solver's own motion in double support and at every lift-off.
TEST_F(Problem, PassivePolishChangesOnlySingleSupportAndKeepsTheLiftOffs) {
  core::ObstacleSpec ob;
  ob.height = 0.05;
  OverstepProblem raw(*model_, rawConfig(), ob);
  // The guess is far from dynamics (~100 N m): a nearly feasible point at the samples, where the
  // linearised correction applies, with the bushing curves' control points zig-zagging by
  // +-0.5 mrad inside each single support (what unconverged solutions showed: bushing curves
  // with a span per sample interval are free between the samples). Only control points whose
  // support lies two spans inside the phase: the correction is held at zero on its first and
  // last two samples.
  Eigen::VectorXd x = restored();
  const auto& lay = problem_->layout();
  const auto& spans = PlannerConfig{}.flex_spline_intervals;
  int first_span = 0;
  for (int ph = 0; ph < kPhaseCount; ++ph) {
    const int n = spans[static_cast<std::size_t>(ph)];
    // Control point i (clamped cubic) moves spans i-3..i; free point f is control point f + 2.
    for (int i = first_span + 5; ph % 2 == 1 && i <= first_span + n - 3; ++i)
      for (int e = 0; e < VariableLayout::kFlex; ++e)
        x(lay.flex + e * lay.flex_free_cp + i - 2) += i % 2 ? 5e-4 : -5e-4;
    first_span += n;
  }
  const core::Plan p0 = raw.toPlan(x, 200.0);
  const core::Plan p1 = problem_->toPlan(x, 200.0);
  // The polish makes the bushings obey their dynamics between the samples (measured: 6.7 N m
  // unpolished, 1.06 N m polished; the point is not converged at the samples themselves, so the
  // check's 1 N m, which every written plan meets, is not the bound here).
  ASSERT_GT(elasticResidual(p0, true), 2.0);
  EXPECT_LT(elasticResidual(p1, true), 0.2 * elasticResidual(p0, true));
  ASSERT_EQ(p0.samples(), p1.samples());
  double joint_change = 0.0, elastic_change = 0.0;
  for (int k = 0; k < p0.samples(); ++k) {
    // Actuated joints of the anchor legs are kept; only the double-support leg follows its foot.
    for (int j = 0; j < model_->actuatedCount(); ++j) {
      const int c = model_->actuatedCoordinate(j);
      joint_change = std::max(joint_change, std::abs(p1.q(c, k) - p0.q(c, k)));
    }
    for (int e = 0; e < model_->elasticCount(); ++e) {
      const int c = model_->elasticCoordinate(e);
      elastic_change = std::max(elastic_change, std::abs(p1.q(c, k) - p0.q(c, k)));
    }
  }
  // A boundary-value problem over each phase does not drift: the correction stays at the size
  // of the residual over the bushing stiffness (2.2 mrad measured), where a forward integration
  // let the slow sway mode carry it to 3.9 mrad on a converged plan.
  EXPECT_GT(elastic_change, 0.0);
  EXPECT_LT(elastic_change, 0.01);
  EXPECT_LT(joint_change, 0.05);
  // In double support the plan is the solver's own motion (the polish is single support only).
  for (int k = 0; k < p1.samples(); ++k) {
    if (p1.phase(k) % 2 != 0) continue;  // phases 0, 2, 4 are double support
    EXPECT_LT((p1.q.col(k) - p0.q.col(k)).cwiseAbs().maxCoeff(), 1e-9) << "t = " << p1.t(k);
  }
  // The correction is zero at each lift-off: there the plan is the
  // solver's own, whose unloading foot carries nothing (lift-off rows).
  for (int k = 0; k + 1 < p1.samples(); ++k) {
    const int ph = p1.phase(k), next = p1.phase(k + 1);
    if (!((ph == 0 && next == 1) || (ph == 2 && next == 3))) continue;
    const int f = ph == 0 ? 0 : 1;
    EXPECT_LT((p1.wrench(f, k) - p0.wrench(f, k)).forceMoment().norm(), 1e-6)
        << "lift-off at t = " << p1.t(k);
    for (int e = 0; e < model_->elasticCount(); ++e) {
      const int c = model_->elasticCoordinate(e);
      EXPECT_NEAR(p1.q(c, k), p0.q(c, k), 1e-9) << "t = " << p1.t(k);
    }
  }
  // And before each touchdown: the last single-support sample is the solver's own motion, value
  // and rate (the correction held at zero on the phase's last two samples), while the swinging
  // foot's bushing is corrected earlier in its swing.
  for (int k = 0; k + 1 < p1.samples(); ++k) {
    const int ph = p1.phase(k), next = p1.phase(k + 1);
    if (!((ph == 1 && next == 2) || (ph == 3 && next == 4))) continue;
    const int swing_leg = ph == 1 ? 0 : 1;  // elastic joints: right roll, pitch, left roll, pitch
    double early = 0.0;
    for (int i = 0; i < k; ++i) {
      if (p1.phase(i) != ph || p1.t(i) > p1.t(k) - 0.15) continue;
      for (int e = 2 * swing_leg; e < 2 * swing_leg + 2; ++e) {
        const int c = model_->elasticCoordinate(e);
        early = std::max(early, std::abs(p1.q(c, i) - p0.q(c, i)));
      }
    }
    EXPECT_GT(early, 1e-6) << "touchdown at t = " << p1.t(k);
    for (int e = 0; e < model_->elasticCount(); ++e) {
      const int c = model_->elasticCoordinate(e);
      EXPECT_NEAR(p1.q(c, k), p0.q(c, k), 1e-9) << "touchdown at t = " << p1.t(k);
      EXPECT_NEAR(p1.v(c, k), p0.v(c, k), 1e-7) << "touchdown at t = " << p1.t(k);
    }
  }
}

TEST(PlannerConfig, LoadsTheShippedFileAndRejectsBadOnes) {
  const PlannerConfig c = loadPlannerConfig(test::dataDir() + "/planner/planner.yaml");
  const PlannerConfig d;
  EXPECT_EQ(c.samples_per_phase, d.samples_per_phase);
  EXPECT_EQ(c.spline_intervals, d.spline_intervals);
  EXPECT_EQ(c.duration_max, d.duration_max);
  EXPECT_DOUBLE_EQ(c.cop_box, d.cop_box);
  EXPECT_EQ(c.weights, d.weights);
  EXPECT_EQ(c.solver.algorithm, "LD_SLSQP");
  test::TempDir dir;
  test::writeText(dir.path() / "a.yaml", "cop_box: -0.01\n");
  EXPECT_THROW(loadPlannerConfig(dir.file("a.yaml")), InputError);
  test::writeText(dir.path() / "b.yaml", "copbox: 0.01\n");
  EXPECT_THROW(loadPlannerConfig(dir.file("b.yaml")), InputError);
  test::writeText(dir.path() / "c.yaml", "weights: {speed: 1}\n");
  EXPECT_THROW(loadPlannerConfig(dir.file("c.yaml")), InputError);
  test::writeText(dir.path() / "d.yaml", "samples_per_phase: [1, 2]\n");
  EXPECT_THROW(loadPlannerConfig(dir.file("d.yaml")), InputError);
  test::writeText(dir.path() / "e.yaml", "friction: [oops\n");
  EXPECT_THROW(loadPlannerConfig(dir.file("e.yaml")), InputError);
  // Sizes and counts are capped before anything is allocated; ranges are physical.
  for (const char* bad :
       {"samples_per_phase: [1000000000, 12, 9, 12, 9]\n", "solver: {threads: 100000}\n",
        "cop_box: 1e308\n", "friction: .nan\n", "limit_margin: 1.5\n",
        "cop_box: 0.01\ncop_box: 0.02\n", "passive_polish: 3\n", "spline_degree: 5\n",
        "solver: {trust_radius: 1}\n"}) {
    test::writeText(dir.path() / "f.yaml", bad);
    EXPECT_THROW(loadPlannerConfig(dir.file("f.yaml")), InputError) << bad;
  }
}

TEST(PlannerConfig, ShippedFileDocumentsEveryKeyWithItsDefault) {
  // planner/planner.yaml is the configuration's documentation: every key of the table appears
  // in it with the embedded default, and it names no key the table does not know.
  const YAML::Node file = YAML::LoadFile(test::dataDir() + "/planner/planner.yaml");
  const PlannerConfig d;
  for (const auto& e : configTable()) {
    ASSERT_TRUE(file[e.key]) << e.key << " is not documented in planner.yaml";
    EXPECT_DOUBLE_EQ(file[e.key].as<double>(), d.*(e.field)) << e.key;
    EXPECT_GE(d.*(e.field), e.lo) << e.key;
    EXPECT_LE(d.*(e.field), e.hi) << e.key;
  }
  const std::set<std::string> others = {"samples_per_phase",
                                        "spline_intervals",
                                        "flex_spline_intervals",
                                        "duration_min",
                                        "duration_max",
                                        "duration_guess",
                                        "cop_homotopy",
                                        "passive_polish",
                                        "weights",
                                        "solver"};
  // The per-phase lists with their defaults too.
  const std::pair<const char*, std::array<int, kPhaseCount>> lists[] = {
      {"samples_per_phase", d.samples_per_phase},
      {"spline_intervals", d.spline_intervals},
      {"flex_spline_intervals", d.flex_spline_intervals}};
  for (const auto& [key, value] : lists) {
    ASSERT_TRUE(file[key]) << key << " is not documented in planner.yaml";
    EXPECT_EQ((file[key].as<std::vector<int>>()), std::vector<int>(value.begin(), value.end()))
        << key;
  }
  for (const auto& kv : file) {
    const std::string k = kv.first.as<std::string>();
    const bool in_table = std::any_of(configTable().begin(), configTable().end(),
                                      [&](const ConfigEntry& e) { return k == e.key; });
    EXPECT_TRUE(in_table || others.count(k)) << k;
  }
  // The plan file's configuration carries every key too.
  const auto j = nlohmann::json::parse(d.toJson());
  for (const auto& e : configTable()) EXPECT_TRUE(j.contains(e.key)) << e.key;
}

}  // namespace
}  // namespace overstep::planner
