// Hot paths of the whole-body model (Release build): what one planner sample evaluation costs.
// Run: ./build/tests/bench/bench_model
#include <benchmark/benchmark.h>

#include <random>

#include "overstep/robots/leg.hpp"
#include "overstep/robots/whole_body_model.hpp"

namespace {

using overstep::robots::WholeBodyModel;

WholeBodyModel& model() {
  static WholeBodyModel m =
      WholeBodyModel::fromFile(std::string(OVERSTEP_DATA_DIR) + "/robots/hrp2/hrp2.yaml");
  return m;
}

void setRandomState(WholeBodyModel& m) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  Eigen::VectorXd q = m.halfSitting(), v(m.dofs()), a(m.dofs());
  for (int i = 0; i < m.dofs(); ++i) {
    q(i) += u(rng);
    v(i) = u(rng);
    a(i) = u(rng);
  }
  m.setState(q, v, a);
}

void BM_SetStateAndInverseDynamics(benchmark::State& st) {
  WholeBodyModel& m = model();
  setRandomState(m);
  const Eigen::VectorXd q = m.positions(), v = m.velocities(), a = m.accelerations();
  const Eigen::VectorXd q1 = q.array() + 1e-3;
  bool flip = false;
  for (auto _ : st) {
    m.setState(flip ? q1 : q, v, a);  // two configurations: nothing cached across iterations
    flip = !flip;
    benchmark::DoNotOptimize(m.inverseDynamics());
  }
}
BENCHMARK(BM_SetStateAndInverseDynamics);

void BM_MassMatrix(benchmark::State& st) {
  WholeBodyModel& m = model();
  setRandomState(m);
  // Alternate two configurations so that DART cannot serve a cached matrix.
  const Eigen::VectorXd q0 = m.positions();
  const Eigen::VectorXd q1 = q0.array() + 1e-3;
  bool flip = false;
  for (auto _ : st) {
    m.setPositions(flip ? q1 : q0);
    flip = !flip;
    benchmark::DoNotOptimize(m.massMatrix());
  }
}
BENCHMARK(BM_MassMatrix);

void BM_ComAndJacobian(benchmark::State& st) {
  WholeBodyModel& m = model();
  setRandomState(m);
  const Eigen::VectorXd q = m.positions();
  const Eigen::VectorXd q1 = q.array() + 1e-3;
  bool flip = false;
  for (auto _ : st) {
    m.setPositions(flip ? q1 : q);
    flip = !flip;
    benchmark::DoNotOptimize(m.com());
    benchmark::DoNotOptimize(m.comJacobian());
  }
}
BENCHMARK(BM_ComAndJacobian);

void BM_TwoFootJacobians(benchmark::State& st) {
  WholeBodyModel& m = model();
  setRandomState(m);
  const Eigen::VectorXd q = m.positions();
  const int r = m.frameIndex("right_sole"), l = m.frameIndex("left_sole");
  const Eigen::VectorXd q1 = q.array() + 1e-3;
  bool flip = false;
  for (auto _ : st) {
    m.setPositions(flip ? q1 : q);
    flip = !flip;
    benchmark::DoNotOptimize(m.frameJacobian(r));
    benchmark::DoNotOptimize(m.frameJacobian(l));
  }
}
BENCHMARK(BM_TwoFootJacobians);

void BM_CentroidalMomentum(benchmark::State& st) {
  WholeBodyModel& m = model();
  setRandomState(m);
  for (auto _ : st) benchmark::DoNotOptimize(m.centroidalMomentum());
}
BENCHMARK(BM_CentroidalMomentum);

// One closed-form leg solve (the double-support leg of every planner sample, the runtime's move
// to a plan's start), two targets alternating.
void BM_LegIkClosedForm(benchmark::State& st) {
  WholeBodyModel& m = model();
  const auto legs = overstep::robots::legChains(m);
  const overstep::robots::LegIk ik(m, legs[0]);
  overstep::robots::Vector6d q0, q1;
  q0 << 0.05, -0.1, -0.5, 0.9, -0.4, 0.1;
  q1 << -0.1, 0.05, -0.3, 1.1, -0.6, -0.05;
  const Eigen::Isometry3d X[2] = {ik.forward(q0), ik.forward(q1)};
  int k = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(ik.solve(X[k]));
    k ^= 1;
  }
}
BENCHMARK(BM_LegIkClosedForm);

}  // namespace

BENCHMARK_MAIN();
