// Heap allocations of one NLP evaluation and one derivative (all samples, all rows) on the
// kinematic guess: this program counts every malloc (glibc's, interposed here), so DART's and
// Eigen's allocations count too. Which function makes them: heaptrack (docs/benchmarks.md).
// Run: ./build/tests/bench/bench_allocations
#include <atomic>
#include <cstdio>

#include "overstep/planner/problem.hpp"

namespace {
std::atomic<long> g_mallocs{0};
}  // namespace

extern "C" void* __libc_malloc(std::size_t size);  // NOLINT: glibc's allocator
extern "C" void* malloc(std::size_t size) {        // NOLINT: counts, then allocates
  g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}

int main() {
  using namespace overstep;
  const robots::WholeBodyModel model =
      robots::WholeBodyModel::fromFile(std::string(OVERSTEP_DATA_DIR) + "/robots/hrp2/hrp2.yaml");
  planner::PlannerConfig cfg;
  cfg.solver.threads = 1;
  planner::OverstepProblem problem(model, cfg, core::ObstacleSpec{});
  Eigen::VectorXd x = problem.initialGuess();
  planner::Evaluation e;
  Eigen::VectorXd grad;
  Eigen::MatrixXd jin, jeq;
  problem.evaluate(x, e);  // buffers and DART's caches take their sizes
  problem.derivatives(x, e, grad, jin, jeq);
  x(problem.layout().legs) += 1e-4;  // a new point: nothing served from the caches
  const long before = g_mallocs.load();
  problem.evaluate(x, e);
  const long evaluated = g_mallocs.load();
  problem.derivatives(x, e, grad, jin, jeq);
  const long derived = g_mallocs.load();
  std::printf("mallocs per evaluate(): %ld\nmallocs per derivatives(): %ld\n", evaluated - before,
              derived - evaluated);
  return 0;
}
