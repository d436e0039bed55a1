// NLopt's SLSQP at the planner's size, without the planner: what one iteration's dense
// least-squares subproblem costs against the numbers of variables, equality rows and inequality
// rows. The problem: a smooth convex objective (sum of log cosh) over n bounded variables whose
// unconstrained minimum lies outside dense random linear rows (seeded), so that SLSQP iterates
// with some rows active, as in the planner's stages. Its functions cost microseconds: the time
// is SLSQP's own. Run: ./build/tests/bench/bench_slsqp
#include <benchmark/benchmark.h>
#include <nlopt.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

namespace {

struct Rows {
  Eigen::MatrixXd A_eq, A_in;  ///< one row per constraint
  Eigen::VectorXd b_in;        ///< inequality bounds
  Eigen::VectorXd target;      ///< the objective's unconstrained minimum
  long evaluations = 0;
};

Rows makeRows(int n, int meq, int mineq, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Rows r;
  r.A_eq = Eigen::MatrixXd::NullaryExpr(meq, n, [&] { return g(rng); });
  r.A_in = Eigen::MatrixXd::NullaryExpr(mineq, n, [&] { return g(rng); });
  for (int i = 0; i < meq; ++i) r.A_eq.row(i).normalize();
  for (int i = 0; i < mineq; ++i) r.A_in.row(i).normalize();
  r.b_in = Eigen::VectorXd::Constant(mineq, 5.0);
  for (int i = 0; i < mineq; i += 20) r.b_in(i) = 0.1;
  r.target = Eigen::VectorXd::NullaryExpr(n, [&] { return 3.0 * g(rng); });
  return r;
}

double objective(unsigned n, const double* x, double* grad, void* data) {
  auto& r = *static_cast<Rows*>(data);
  ++r.evaluations;
  double f = 0.0;
  for (unsigned i = 0; i < n; ++i) {
    const double d = x[i] - r.target(i);
    f += std::log(std::cosh(d));
    if (grad) grad[i] = std::tanh(d);
  }
  return f;
}

/// A x - b (rows of A) with A as the Jacobian.
void linearRows(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, double* out, unsigned n,
                const double* x, double* grad) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n);
  Eigen::Map<Eigen::VectorXd>(out, A.rows()) = A * xv - b;
  if (grad) Eigen::Map<Eigen::Matrix<double, -1, -1, Eigen::RowMajor>>(grad, A.rows(), n) = A;
}

/// Equality rows A x = 0 (x = 0 satisfies them).
void equalities(unsigned, double* out, unsigned n, const double* x, double* grad, void* data) {
  const auto& r = *static_cast<Rows*>(data);
  linearRows(r.A_eq, Eigen::VectorXd::Zero(r.A_eq.rows()), out, n, x, grad);
}

/// Inequality rows A x <= b: one in twenty tight (b = 0.1), the others far (b = 5), so that, as
/// in the planner's stages, a small part of them is ever active.
void inequalities(unsigned, double* out, unsigned n, const double* x, double* grad, void* data) {
  const auto& r = *static_cast<Rows*>(data);
  linearRows(r.A_in, r.b_in, out, n, x, grad);
}

/// Arguments: variables, equality rows, inequality rows. Each benchmark iteration runs SLSQP
/// from x = 0 for 20 evaluations (SLSQP asks for the gradient at every one).
void BM_SlsqpEvaluations(benchmark::State& st) {
  const int n = static_cast<int>(st.range(0)), meq = static_cast<int>(st.range(1)),
            mineq = static_cast<int>(st.range(2));
  Rows rows = makeRows(n, meq, mineq, 7u);
  constexpr int kEvaluations = 20;
  long evaluations = 0;
  for (auto _ : st) {
    nlopt::opt opt(nlopt::LD_SLSQP, static_cast<unsigned>(n));
    opt.set_lower_bounds(-10.0);
    opt.set_upper_bounds(10.0);
    opt.set_min_objective(objective, &rows);
    if (meq > 0) opt.add_equality_mconstraint(equalities, &rows, std::vector<double>(meq, 1e-8));
    if (mineq > 0)
      opt.add_inequality_mconstraint(inequalities, &rows, std::vector<double>(mineq, 1e-8));
    opt.set_maxeval(kEvaluations);
    std::vector<double> x(static_cast<std::size_t>(n), 0.0);
    double f = 0.0;
    rows.evaluations = 0;
    try {
      opt.optimize(x, f);
    } catch (const std::exception&) {  // roundoff or a failed subproblem still cost the time
    }
    evaluations += rows.evaluations;
    benchmark::DoNotOptimize(f);
  }
  st.counters["evaluations"] =
      benchmark::Counter(static_cast<double>(evaluations), benchmark::Counter::kAvgIterations);
  st.counters["s_per_evaluation"] = benchmark::Counter(
      static_cast<double>(evaluations), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
// The planner's default problem (379 variables, 158 equality rows, 1858 inequality rows), then
// half the equality rows, half the inequality rows, half the variables.
BENCHMARK(BM_SlsqpEvaluations)
    ->Args({379, 158, 1858})
    ->Args({379, 79, 1858})
    ->Args({379, 158, 929})
    ->Args({190, 158, 1858})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
