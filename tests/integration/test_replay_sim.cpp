// The replay runtime and the simulator in one process, lockstep, no LCM: the runtime's commands
// go straight to sim::Simulator and its states straight back. Deterministic end-to-end checks of
// the closed loop (plan -> stabilizer -> joint references -> simulated HRP-2 -> sensors).
#include <gtest/gtest.h>

#include <cmath>

#include "overstep/robots/whole_body_model.hpp"
#include "overstep/runtime/replay.hpp"
#include "overstep/sim/simulator.hpp"
#include "overstep/stabilizer/params.hpp"
#include "plan_fixtures.hpp"
#include "test_util.hpp"

namespace overstep {
namespace {

struct LoopResult {
  runtime::State state = runtime::State::Idle;
  double min_base_height = 1e9;
  double cop_max[2] = {0.0, 0.0};    ///< m, largest |local CoP| (x or y) while executing
  double cop_final[2] = {0.0, 0.0};  ///< m, at the end
  double load_min = 1e9;             ///< N, smallest normal force of either foot while executing
};

/// Runs a plan through Replay and the simulator, `extra` seconds past its end.
LoopResult runLoop(const core::Plan& plan, const stabilizer::Params& params, bool stabilizer,
                   double extra, robots::WholeBodyModel& model) {
  runtime::PlanTrack track(plan, model);
  runtime::ReplayOptions ro;
  ro.stabilizer = stabilizer;
  runtime::Replay replay(track, params, ro);
  sim::SimOptions so;
  so.has_obstacle = false;
  sim::Simulator sim(model, sim::noTruthEffects(model), so);
  sim.settle();
  replay.start();
  LoopResult r;
  const int steps = static_cast<int>(std::lround(1.0 / (ro.rate * so.dt)));
  for (int i = 0; i < 200 * 30 && r.state != runtime::State::Hold; ++i) {
    const core::RobotState st = sim.state();
    replay.prepare();
    const runtime::TickOutput& o = replay.tick(&st);
    r.state = o.state;
    const bool executing =
        o.state == runtime::State::Running || o.state == runtime::State::Finished;
    for (int f = 0; f < 2; ++f) {
      const core::Wrench w = track.soleWrench(o.sample.index, f, f == 0 ? st.ft_right : st.ft_left);
      const double cop = core::localCop(w, 0.0).cwiseAbs().maxCoeff();
      if (executing) {
        r.cop_max[f] = std::max(r.cop_max[f], cop);
        r.load_min = std::min(r.load_min, w.force.z());
      }
      r.cop_final[f] = cop;
    }
    if (o.send_command) sim.setCommand(o.command.q_ref, o.command.qd_ref);
    for (int k = 0; k < steps; ++k) sim.step();
    r.min_base_height = std::min(r.min_base_height, sim.basePose().translation().z());
    if (o.state == runtime::State::Finished && sim.time() > 2.0 + track.duration() + extra) break;
  }
  return r;
}

class ReplaySim : public ::testing::Test {
 protected:
  void SetUp() override {
    model_ = std::make_unique<robots::WholeBodyModel>(
        robots::WholeBodyModel::fromFile(test::hrp2Yaml()));
    params_ = stabilizer::loadParams(test::hrp2Yaml());
    params_.mass = model_->totalMass();
  }
  std::unique_ptr<robots::WholeBodyModel> model_;
  stabilizer::Params params_;
};

TEST_F(ReplaySim, StabilizedStandingPlanSettlesOnBothFeet) {
  const core::Plan plan = test::standingPlan(*model_, 2.0);
  const LoopResult r = runLoop(plan, params_, true, 1.0, *model_);
  EXPECT_EQ(r.state, runtime::State::Finished);
  EXPECT_GT(r.min_base_height, 0.5);
  // Both feet stay loaded (no rocking from one foot to the other) and flat.
  EXPECT_GT(r.load_min, 200.0);
  EXPECT_LT(r.cop_max[0], 0.03);
  EXPECT_LT(r.cop_max[1], 0.03);
  // The CoM feedback brings both CoPs back under the ankles (the plan's CoPs are at the origin).
  EXPECT_LT(r.cop_final[0], 0.005);
  EXPECT_LT(r.cop_final[1], 0.005);
}

TEST_F(ReplaySim, OpenLoopStandingPlanAlsoStands) {
  const core::Plan plan = test::standingPlan(*model_, 1.0);
  const LoopResult r = runLoop(plan, params_, false, 0.5, *model_);
  EXPECT_EQ(r.state, runtime::State::Finished);
  EXPECT_GT(r.load_min, 200.0);
}

}  // namespace
}  // namespace overstep
