// Hot paths of the planner (Release build): one NLP evaluation (all samples, all rows) and one
// finite-difference derivative (objective gradient + both Jacobians) on the kinematic guess.
// Run: ./build/tests/bench/bench_planner
#include <benchmark/benchmark.h>

#include "overstep/planner/problem.hpp"

namespace {

using namespace overstep;

struct Fixture {
  robots::WholeBodyModel model =
      robots::WholeBodyModel::fromFile(std::string(OVERSTEP_DATA_DIR) + "/robots/hrp2/hrp2.yaml");
  core::ObstacleSpec obstacle;
  std::unique_ptr<planner::OverstepProblem> problem;
  Eigen::VectorXd x;
  explicit Fixture(int threads) {
    planner::PlannerConfig cfg;
    cfg.solver.threads = threads;
    problem = std::make_unique<planner::OverstepProblem>(model, cfg, obstacle);
    x = problem->initialGuess();
  }
};

void BM_Evaluate(benchmark::State& st) {
  static Fixture f(1);
  planner::Evaluation e;
  for (auto _ : st) f.problem->evaluate(f.x, e);
  st.counters["variables"] = f.problem->layout().total;
  st.counters["rows"] = f.problem->inequalityCount() + f.problem->equalityCount();
}
BENCHMARK(BM_Evaluate)->Unit(benchmark::kMillisecond);

void BM_Derivatives(benchmark::State& st) {
  static Fixture f1(1), f2(2);
  Fixture& f = st.range(0) == 1 ? f1 : f2;
  planner::Evaluation e;
  f.problem->evaluate(f.x, e);
  Eigen::VectorXd g;
  Eigen::MatrixXd ji, je;
  for (auto _ : st) f.problem->derivatives(f.x, e, g, ji, je);
  st.counters["threads"] = static_cast<double>(st.range(0));
}
BENCHMARK(BM_Derivatives)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
