// The problem's first derivatives (OverstepProblem::derivatives).
//
// A sample's or a switch's rows depend on the variables through three things only: the phase
// durations (its time, every spline's knots), the foot placements its contacts read, and the
// splines' values at its time (SplineState: the 12 leg joints and the 4 bushing coordinates with
// their first and second time derivatives). The durations and placements are differentiated
// column by column, each re-evaluating the samples and switches it moves. The control points,
// nine in ten columns, go through the samples and switches: each one's outputs are
// differentiated with respect to its 48 spline values once (forward differences of that one
// point), and a control point's column is the chain rule through the B-spline basis, which is
// exact.
#include <chrono>
#include <thread>

#include "problem_impl.hpp"

namespace overstep::planner {

namespace {

/// Forward-difference step (times max(1, |value|)) of a variable and of a spline value, velocity
/// or acceleration. The rows' curvature sets it: with 1e-6 entries of the swinging leg's
/// self-clearance, a sharp smooth minimum, came out several times their value
/// (Problem.DerivativesMatchFineCentralDifferences).
constexpr double kStep = 1e-7;

/// The control points (full, Impl::expand) that free point fi of a curve with F free and n_ctrl
/// full points stands for: the first and the last free point each tie three.
std::pair<int, int> tiedControlPoints(int fi, int F, int n_ctrl) {
  if (fi == 0) return {0, 2};
  if (fi == F - 1) return {n_ctrl - 3, n_ctrl - 1};
  return {fi + 2, fi + 2};
}

/// A curve's value, velocity and acceleration per unit of the control points c_lo..c_hi at the
/// basis b's instant (zero outside their support).
Eigen::Vector3d basisCoefficients(const PhaseSpline::Basis& b, int c_lo, int c_hi) {
  Eigen::Vector3d coef = Eigen::Vector3d::Zero();
  const int last = b.first + static_cast<int>(b.value.size()) - 1;
  for (int ci = std::max(c_lo, b.first); ci <= std::min(c_hi, last); ++ci)
    coef += Eigen::Vector3d(b.value(ci - b.first), b.d1(ci - b.first), b.d2(ci - b.first));
  return coef;
}

/// S0 with its entry i (column-major: 16 x order + row) moved by its forward-difference step into
/// S; returns the step.
double perturbed(const SplineState& S0, int i, SplineState& S) {
  const int row = i % 16, order = i / 16;
  S = S0;
  const double h = kStep * std::max(1.0, std::abs(S0(row, order)));
  S(row, order) += h;
  return h;
}

/// Column `row` of the spline values' sensitivities, chained with a control point's coefficients
/// (an expression over D, evaluated where it is assigned).
auto chain(const Eigen::MatrixXd& D, int row, const Eigen::Vector3d& coef) {
  return D.col(row) * coef(0) + D.col(16 + row) * coef(1) + D.col(32 + row) * coef(2);
}

}  // namespace

void OverstepProblem::Impl::sampleSensitivity(Workspace& w, int k, Sensitivity& d) const {
  const SampleOut& base = base_samples[static_cast<std::size_t>(k)];
  const GridPoint& g = grid[static_cast<std::size_t>(k)];
  d.legs = w.spline->evaluate(base.t);
  d.flex = w.flex_spline->evaluate(base.t);
  d.ik_leg = doubleSupport(g.phase) ? 1 - anchor_of[g.phase] : -1;
  constexpr int n = Sensitivity::kInputs;
  d.ineq.setZero(base.ineq.size(), n);
  d.eq.setZero(base.eq.size(), n);
  d.terms.setZero(kObjectiveTerms, n);
  d.tau.setZero(base.tau.size(), n);
  const SplineState S0 = splineState(w, base.t);
  const Eigen::Map<const Eigen::VectorXd> terms0(base.terms.data(), kObjectiveTerms);
  SampleOut out;
  // The rows in closed form first (at the sample's own state), then the others by forward
  // differences.
  sampleRows(w, k, out, &S0);
  std::vector<bool> exact(sample_terms.size(), false);
  closedFormRows(w, k, d, exact);
  SplineState S;
  for (int i = 0; i < n; ++i) {
    const int row = i % 16;
    if (row < 12 && row / 6 == d.ik_leg) continue;  // set by the inverse kinematics
    const double h = perturbed(S0, i, S);
    sampleRows(w, k, out, &S);
    copyDifferences(k, out, base, h, i, exact, d);
    d.terms.col(i) =
        (Eigen::Map<const Eigen::VectorXd>(out.terms.data(), kObjectiveTerms) - terms0) / h;
    d.tau.col(i) = (out.tau - base.tau) / h;
  }
}

void OverstepProblem::Impl::closedFormRows(Workspace& w, int k, Sensitivity& d,
                                           std::vector<bool>& exact) const {
  const GridPoint& g = grid[static_cast<std::size_t>(k)];
  Eigen::MatrixXd T, J;
  if (!configurationSensitivity(w, g.phase, T)) return;
  forEachTermBlock(g, [&](std::size_t ti, const SampleTerm& term, int r0, int rows) {
    J.setConstant(rows, T.rows(), std::numeric_limits<double>::quiet_NaN());
    if (!term.configurationJacobian(*this, w.sample, J)) return;
    // The values; velocities and accelerations move nothing.
    (term.equality() ? d.eq : d.ineq).block(r0, 0, rows, 16) = J * T;
    exact[ti] = true;
  });
}

void OverstepProblem::Impl::copyDifferences(int k, const SampleOut& out, const SampleOut& base,
                                            double h, int i, const std::vector<bool>& exact,
                                            Sensitivity& d) const {
  const GridPoint& g = grid[static_cast<std::size_t>(k)];
  forEachTermBlock(g, [&](std::size_t ti, const SampleTerm& term, int r0, int rows) {
    if (exact[ti]) return;
    const bool eq = term.equality();
    (eq ? d.eq : d.ineq).col(i).segment(r0, rows) = ((eq ? out.eq : out.ineq).segment(r0, rows) -
                                                     (eq ? base.eq : base.ineq).segment(r0, rows)) /
                                                    h;
  });
}

void OverstepProblem::Impl::eventSensitivity(Workspace& w, int e, Sensitivity& d) const {
  const Eigen::VectorXd& base = base_events[static_cast<std::size_t>(e)];
  const double t = w.timing->start(eventBoundary(e));
  d.legs = w.spline->evaluate(t);
  d.flex = w.flex_spline->evaluate(t);
  d.ik_leg = -1;
  constexpr int n = Sensitivity::kInputs;
  d.eq.setZero(base.size(), n);
  const SplineState S0 = splineState(w, t);
  Eigen::VectorXd out;
  SplineState S;
  for (int i = 0; i < n; ++i) {
    const double h = perturbed(S0, i, S);
    eventRows(w, e, out, &S);
    d.eq.col(i) = (out - base) / h;
  }
}

void OverstepProblem::Impl::placementOrDurationColumn(Workspace& w, const Eigen::VectorXd& x,
                                                      const Evaluation& at, int j, ColumnScratch& c,
                                                      Eigen::VectorXd& grad, Eigen::MatrixXd& jin,
                                                      Eigen::MatrixXd& jeq) {
  Eigen::VectorXd xp = x;
  const double hj = kStep * std::max(1.0, std::abs(x(j)));
  xp(j) += hj;
  if (j < lay.feet) {  // a duration moves every sample
    evaluateAll(xp, w, c.local, c.local_events);
    Evaluation ev;
    assemble(w, c.local, c.local_events, ev);
    grad(j) = (ev.objective - at.objective) / hj;
    jin.col(j) = (ev.ineq - at.ineq) / hj;
    jeq.col(j) = (ev.eq - at.eq) / hj;
    decode(x, w);
    return;
  }
  // A placement: the states that read it (readsPlacement); every other value is the same at x
  // and at x + h.
  decode(xp, w);
  const int v = (j - lay.feet) / 2;
  for (std::size_t k = 0; k < grid.size(); ++k) {
    c.ptr[k] = &base_samples[k];
    if (!readsPlacement(grid[k].phase, v)) continue;
    sampleRows(w, static_cast<int>(k), c.changed[k]);
    c.ptr[k] = &c.changed[k];
    jin.col(j).segment(ineq_off[k], ineq_cnt[k]) = (c.changed[k].ineq - base_samples[k].ineq) / hj;
    jeq.col(j).segment(eq_off[k], eq_cnt[k]) = (c.changed[k].eq - base_samples[k].eq) / hj;
  }
  grad(j) = (objective(w, c.ptr, nullptr) - at.objective) / hj;
  for (int e = 0; e < kEvents; ++e) {
    if (!readsPlacement(eventPhase(e), v)) continue;
    eventRows(w, e, c.event);
    jeq.col(j).segment(event_eq_off[e], event_eq_cnt[e]) =
        (c.event - base_events[static_cast<std::size_t>(e)]) / hj;
  }
  decode(x, w);
}

void OverstepProblem::Impl::controlPointColumn(const Workspace& w, const Eigen::VectorXd& x,
                                               const Evaluation& at, int j,
                                               const std::vector<Sensitivity>& sens,
                                               ColumnScratch& c, Eigen::VectorXd& grad,
                                               Eigen::MatrixXd& jin, Eigen::MatrixXd& jeq) const {
  const bool is_leg = j < lay.flex;
  const int F = is_leg ? lay.free_cp : lay.flex_free_cp;
  const int offset = j - (is_leg ? lay.legs : lay.flex);
  const int row = is_leg ? offset / F : 12 + offset / F;  // SplineState row
  const auto [c_lo, c_hi] = tiedControlPoints(offset % F, F, is_leg ? n_ctrl : n_ctrl_flex);
  const double hj = kStep * std::max(1.0, std::abs(x(j)));
  for (std::size_t k = 0; k < grid.size(); ++k) {
    const SampleOut& base = base_samples[k];
    const Sensitivity& d = sens[k];
    c.ptr[k] = &base;
    const Eigen::Vector3d coef = basisCoefficients(is_leg ? d.legs : d.flex, c_lo, c_hi);
    if (coef.isZero(0.0)) continue;
    if (is_leg && row / 6 == d.ik_leg) {
      dsLegSplineChanged(w, static_cast<int>(k), base, row % 6, hj * coef(0), c.changed[k]);
      c.ptr[k] = &c.changed[k];
      continue;
    }
    jin.col(j).segment(ineq_off[k], ineq_cnt[k]) = chain(d.ineq, row, coef);
    jeq.col(j).segment(eq_off[k], eq_cnt[k]) = chain(d.eq, row, coef);
    // The objective through the linearised outputs (a forward difference of its quadratic terms).
    SampleOut& ch = c.changed[k];
    ch.t = base.t;
    ch.tau = base.tau + hj * chain(d.tau, row, coef);
    const auto dterms = chain(d.terms, row, coef);
    for (int i = 0; i < kObjectiveTerms; ++i)
      ch.terms[static_cast<std::size_t>(i)] =
          base.terms[static_cast<std::size_t>(i)] + hj * dterms(i);
    c.ptr[k] = &ch;
  }
  grad(j) = (objective(w, c.ptr, nullptr) - at.objective) / hj;
  for (int e = 0; e < kEvents; ++e) {
    const Sensitivity& d = sens[grid.size() + static_cast<std::size_t>(e)];
    const Eigen::Vector3d coef = basisCoefficients(is_leg ? d.legs : d.flex, c_lo, c_hi);
    if (coef.isZero(0.0)) continue;
    jeq.col(j).segment(event_eq_off[e], event_eq_cnt[e]) = chain(d.eq, row, coef);
  }
}

void OverstepProblem::derivatives(const Eigen::VectorXd& x, const Evaluation& at,
                                  Eigen::VectorXd& grad, Eigen::MatrixXd& jin,
                                  Eigen::MatrixXd& jeq) {
  Impl& m = *impl_;
  if (m.base_x.size() != x.size() || m.base_x != x) {
    Evaluation tmp;
    evaluate(x, tmp);
  }
  const auto start = std::chrono::steady_clock::now();
  const int n = m.lay.total;
  grad.setZero(n);
  jin.setZero(m.n_ineq, n);
  jeq.setZero(m.n_eq, n);
  // Two passes over the workspaces: the samples' and switches' sensitivities, then the columns.
  // Each item's numbers do not depend on the thread that computes it.
  const int samples = static_cast<int>(m.grid.size());
  std::vector<Impl::Sensitivity> sens(m.grid.size() + Impl::kEvents);
  auto parallel = [&](int count, auto&& item) {
    std::atomic<int> next{0};
    auto worker = [&](std::size_t wi) {
      for (int i = next++; i < count; i = next++) item(m.ws[wi], i);
    };
    std::vector<std::thread> threads;
    for (std::size_t i = 1; i < m.ws.size(); ++i) threads.emplace_back(worker, i);
    worker(0);
    for (auto& t : threads) t.join();
  };
  for (auto& w : m.ws) m.decode(x, w);
  parallel(samples + Impl::kEvents, [&](Impl::Workspace& w, int i) {
    if (i < samples)
      m.sampleSensitivity(w, i, sens[static_cast<std::size_t>(i)]);
    else
      m.eventSensitivity(w, i - samples, sens[static_cast<std::size_t>(i)]);
  });
  std::vector<Impl::ColumnScratch> scratch(m.ws.size());
  for (auto& c : scratch) {
    c.changed.resize(m.grid.size());
    c.ptr.resize(m.grid.size());
  }
  parallel(n, [&](Impl::Workspace& w, int j) {
    Impl::ColumnScratch& c = scratch[static_cast<std::size_t>(&w - m.ws.data())];
    if (j < m.lay.legs)
      m.placementOrDurationColumn(w, x, at, j, c, grad, jin, jeq);
    else
      m.controlPointColumn(w, x, at, j, sens, c, grad, jin, jeq);
  });
  ++m.work.jacobians;
  m.work.derivatives_s +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace overstep::planner
