#pragma once
// Identification data from the simulator, in process: the excitation plan replayed through the
// runtime (stabilizer on) on sim::Simulator with truth effects the identification is not told
// about, seeded sensor noise on every state, one sysid::Record per executed tick.
#include "overstep/planner/standing.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/runtime/replay.hpp"
#include "overstep/sim/sensor_noise.hpp"
#include "overstep/sim/simulator.hpp"
#include "overstep/stabilizer/params.hpp"
#include "overstep/sysid/dataset.hpp"

namespace overstep::test {

inline sysid::Dataset recordExcitation(robots::WholeBodyModel& model, const core::Plan& plan,
                                       const stabilizer::Params& params,
                                       const sim::TruthEffects& truth, unsigned seed,
                                       double noise = 1.0) {
  runtime::PlanTrack track(plan, model);
  runtime::ReplayOptions ro;
  runtime::Replay replay(track, params, ro);
  sim::SimOptions so;
  so.has_obstacle = false;
  sim::Simulator sim(model, truth, so);
  sim.settle();
  sim::SensorNoise sn(seed, noise);
  replay.start();
  sysid::Dataset data;
  data.period = 1.0 / ro.rate;
  const int steps = static_cast<int>(std::lround(1.0 / (ro.rate * so.dt)));
  core::RobotState before = sim.state();
  sn.apply(before);
  for (int i = 0; i < static_cast<int>(ro.rate * (plan.duration() + 10.0)); ++i) {
    replay.prepare();
    const runtime::TickOutput& o = replay.tick(&before);
    if (o.send_command) sim.setCommand(o.command.q_ref, o.command.qd_ref);
    for (int k = 0; k < steps; ++k) sim.step();
    core::RobotState after = sim.state();
    sn.apply(after);
    if (o.state == runtime::State::Running) data.add(o.sample.t, o.command, before, after);
    before = after;
    if (o.state == runtime::State::Finished || o.state == runtime::State::Hold) break;
  }
  return data;
}

}  // namespace overstep::test
