// Real-time factor of the simulator (1 ms steps, the full robot) standing and stepping: a plan is
// replayed through the runtime (in process, lockstep, stabilizer on) and the time spent in
// Simulator::step() is measured. Prints one line per run: simulated time, wall time in the
// simulator, real-time factor, and whether the robot stayed up.
// Usage: bench_sim_stepping [PLAN.json]   (no plan: a 10 s standing plan)
//   e.g. overstep plan --obstacle-height 0.05 --out /tmp/p.json; bench_sim_stepping
//   /tmp/p.failed.json
#include <chrono>
#include <cstdio>
#include <string>

#include "overstep/core/plan.hpp"
#include "overstep/planner/standing.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/runtime/replay.hpp"
#include "overstep/sim/simulator.hpp"
#include "overstep/stabilizer/params.hpp"

int main(int argc, char** argv) {
  using namespace overstep;
  const std::string robot = std::string(OVERSTEP_DATA_DIR) + "/robots/hrp2/hrp2.yaml";
  robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(robot);
  const core::Plan plan = argc > 1 ? core::loadPlan(argv[1]) : planner::standingPlan(model, 10.0);
  runtime::PlanTrack track(plan, model);
  stabilizer::Params params = stabilizer::loadParams(robot);
  params.mass = model.totalMass();
  runtime::ReplayOptions ro;
  runtime::Replay replay(track, params, ro);
  sim::SimOptions so;
  so.has_obstacle = argc > 1;
  so.obstacle = plan.obstacle;
  sim::Simulator sim(model, sim::noTruthEffects(model), so);
  sim.settle();
  replay.start();
  double in_sim = 0.0, lowest = 1e9;
  bool contact = false;
  const int steps = static_cast<int>(1.0 / (ro.rate * so.dt) + 0.5);
  int ticks = 0;
  for (; ticks < 200 * 60; ++ticks) {
    const core::RobotState st = sim.state();
    replay.prepare();
    const runtime::TickOutput& o = replay.tick(&st);
    if (o.send_command) sim.setCommand(o.command.q_ref, o.command.qd_ref);
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 0; k < steps; ++k) sim.step();
    in_sim += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    lowest = std::min(lowest, sim.basePose().translation().z());
    contact = contact || sim.collisions().obstacleContact();
    if (lowest < 0.3 || o.state == runtime::State::Hold) break;
    if (o.state == runtime::State::Finished && sim.time() > track.duration() + 4.0) break;
  }
  std::printf(
      "%s: %.2f s simulated in %.2f s of Simulator::step() -> real-time factor %.2f; "
      "runtime %s, lowest base %.3f m%s\n",
      argc > 1 ? argv[1] : "standing 10 s", sim.time(), in_sim, sim.time() / in_sim,
      runtime::toString(replay.state()), lowest, contact ? ", OBSTACLE CONTACT" : "");
  return 0;
}
