// Proves that Replay::tick() never touches the heap, in every state it can be in (its own
// executable: alloc_counter.hpp replaces the global operator new).
#include <gtest/gtest.h>

#include <cmath>

#include "alloc_counter.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/runtime/replay.hpp"
#include "overstep/stabilizer/params.hpp"
#include "plan_fixtures.hpp"
#include "test_util.hpp"

namespace overstep {
namespace {

TEST(RuntimeRealTime, TickNeverAllocates) {
  robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(test::hrp2Yaml());
  const core::Plan plan = test::standingPlan(model, 1.0);
  const runtime::PlanTrack track(plan, model);
  stabilizer::Params params = stabilizer::loadParams(test::hrp2Yaml());
  params.mass = model.totalMass();
  runtime::ReplayOptions o;
  o.min_move_time = 0.1;
  runtime::Replay r(track, params, o);
  core::RobotState st;
  st.resize(track.joints());
  st.q = plan.q.col(0).segment(6, track.joints());
  st.ft_right.force.z() = st.ft_left.force.z() =
      0.5 * model.totalMass() * 9.81;  // sensor z up, loaded
  core::RobotState bad = st;
  bad.q(2) = std::nan("");
  int states_seen[6] = {0, 0, 0, 0, 0, 0};
  r.tick(nullptr);  // idle, nothing known
  r.tick(&st);      // idle with a state
  r.start();
  r.prepare();  // plans the move to the start: allocates, outside the tick by design
  const long before = test::allocations();
  for (int i = 0; i < 600; ++i) {
    if (i == 300) r.pause();  // running: after the 0.1 s move and the stabilizer's 1 s ramp-in
    if (i == 330) r.resume();
    const core::RobotState* in = &st;
    if (i == 500) in = &bad;                  // fault -> hold
    if (i > 550 && i % 3 == 0) in = nullptr;  // missing states while holding
    const auto& out = r.tick(in);
    ++states_seen[static_cast<int>(out.state)];
  }
  EXPECT_EQ(test::allocations() - before, 0) << "heap allocations inside Replay::tick()";
  EXPECT_GT(states_seen[static_cast<int>(runtime::State::MovingToStart)], 0);
  EXPECT_GT(states_seen[static_cast<int>(runtime::State::Running)], 0);
  EXPECT_GT(states_seen[static_cast<int>(runtime::State::Paused)], 0);
  EXPECT_GT(states_seen[static_cast<int>(runtime::State::Hold)], 0);
  EXPECT_EQ(r.fault(), runtime::FaultReason::NonFiniteState);
}

}  // namespace
}  // namespace overstep
