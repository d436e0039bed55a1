// Stabilizer::step() per tick (issue: goal < 10 us). Release build:
//   cmake --build build --target bench_stabilizer && ./build/tests/bench/bench_stabilizer
#include <benchmark/benchmark.h>

#include "overstep/stabilizer/stabilizer.hpp"
#include "stabilizer_plants.hpp"

namespace st = overstep::stabilizer;

namespace {

void run(benchmark::State& state, bool double_support, const Eigen::Vector2d& zmp_meas,
         double pref_right_share, st::Feedback fb, double com_x = 0.005) {
  st::Params p = overstep::test::plantParams();
  p.feedback = fb;
  const auto feet = overstep::test::feetAt(0.095);
  st::Reference ref = overstep::test::staticReference(
      double_support ? Eigen::Vector2d(0.0, 0.0) : Eigen::Vector2d(0.0, -0.095), feet,
      {{true, double_support}});
  if (double_support) {
    ref.foot[0].wrench.force.z() = pref_right_share * overstep::test::kMass * overstep::test::kG;
    ref.foot[1].wrench.force.z() =
        (1 - pref_right_share) * overstep::test::kMass * overstep::test::kG;
  }
  st::Stabilizer s(p);
  s.setReference(ref);
  s.enable();
  const st::Measurement m = overstep::test::measurementWithZmp(
      Eigen::Vector3d(com_x, 0.0, 0.8), Eigen::Vector3d(0.01, 0, 0), zmp_meas, feet);
  st::Output out;
  for (int i = 0; i < 400; ++i) s.step(m, 0.005, out);  // past the ramp
  if (com_x > 0.05 && !out.distribution.clamped) state.SkipWithError("expected a clamped ZMP");
  for (auto _ : state) {
    s.step(m, 0.005, out);
    benchmark::DoNotOptimize(out);
  }
}

}  // namespace

// Typical double support: the plan's share realises the desired ZMP (one projection).
static void BM_StepDoubleSupport(benchmark::State& s) {
  run(s, true, Eigen::Vector2d(0.01, 0.0), 0.5, st::Feedback::Lipm);
}
// The plan's share cannot realise the ZMP: golden-section search on the share.
static void BM_StepDoubleSupportShareSearch(benchmark::State& s) {
  run(s, true, Eigen::Vector2d(0.03, -0.08), 0.05, st::Feedback::Lipm);
}
// Far outside the support: the desired ZMP is clamped to the realisable boundary (worst case).
static void BM_StepDoubleSupportClamped(benchmark::State& s) {
  run(s, true, Eigen::Vector2d(0.05, 0.0), 0.5, st::Feedback::Lipm, 0.095);
}
static void BM_StepSingleSupport(benchmark::State& s) {
  run(s, false, Eigen::Vector2d(0.01, -0.095), 1.0, st::Feedback::Lipm);
}
static void BM_StepDoubleSupportDcm(benchmark::State& s) {
  run(s, true, Eigen::Vector2d(0.01, 0.0), 0.5, st::Feedback::Dcm);
}
BENCHMARK(BM_StepDoubleSupport);
BENCHMARK(BM_StepDoubleSupportShareSearch);
BENCHMARK(BM_StepDoubleSupportClamped);
BENCHMARK(BM_StepSingleSupport);
BENCHMARK(BM_StepDoubleSupportDcm);
BENCHMARK_MAIN();
