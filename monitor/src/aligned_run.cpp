#include "aligned_run.hpp"

#include <cmath>
#include <limits>
#include <optional>

#include "overstep/core/error.hpp"
#include "overstep/core/rotation.hpp"
#include "overstep/monitor/lcm_log.hpp"
#include "overstep/monitor/messages.hpp"
#include "overstep/monitor/plan_match.hpp"

namespace overstep::monitor {

namespace {

Row makeRow(const overstep::plan_reference_t& ref, const overstep::stabilizer_status_t& st,
            const overstep::robot_state_t& state, const overstep::robot_command_t& command,
            const core::Plan& plan, const runtime::PlanTrack& track, int nA) {
  Row r;
  r.t = ref.plan_time;
  r.phase = ref.phase;
  r.index = plan.sampleAt(r.t, ref.phase);
  r.zmp_meas << st.zmp_measured[0], st.zmp_measured[1];
  r.zmp_ref << st.zmp_reference[0], st.zmp_reference[1];
  r.q_meas = Eigen::Map<const Eigen::VectorXd>(state.q.data(), nA);
  r.q_cmd = Eigen::Map<const Eigen::VectorXd>(command.q_ref.data(), nA);
  for (int f = 0; f < 2; ++f) {
    const core::Wrench ft = core::Wrench::fromForceMoment(
        Eigen::Map<const core::Vector6d>(f == 0 ? state.ft_right : state.ft_left),
        core::Axes::kSensor);
    r.w_meas[f] = track.soleWrench(r.index, f, ft);
  }
  r.ground_truth = state.has_ground_truth;
  if (r.ground_truth) {
    r.base.translation() << state.base_position[0], state.base_position[1], state.base_position[2];
    r.base.linear() = Eigen::Quaterniond(state.base_quaternion[0], state.base_quaternion[1],
                                         state.base_quaternion[2], state.base_quaternion[3])
                          .normalized()
                          .toRotationMatrix();
    r.base_velocity << state.base_linear_velocity[0], state.base_linear_velocity[1],
        state.base_linear_velocity[2];
  }
  r.imu = Eigen::Quaterniond(state.imu_quaternion[0], state.imu_quaternion[1],
                             state.imu_quaternion[2], state.imu_quaternion[3])
              .normalized();
  double level = 0.0;
  for (int i = 0; i < 2; ++i)
    level =
        std::max({level, std::abs(st.right_foot_rotation[i]) / 1e-3,
                  std::abs(st.left_foot_rotation[i]) / 1e-3, std::abs(st.body_attitude[i]) / 1e-3});
  for (int i = 0; i < 3; ++i) level = std::max(level, std::abs(st.com_offset[i]) / 1e-3);
  r.stab_level = level;
  r.stab_mode = st.mode;
  return r;
}

}  // namespace

core::Wrench planSoleWrench(const core::Plan& plan, int f, int k) {
  const Eigen::MatrixXd& pf = f == 0 ? plan.right_foot : plan.left_foot;
  Eigen::Isometry3d X_WF = Eigen::Isometry3d::Identity();
  X_WF.linear() =
      Eigen::Quaterniond(pf(3, k), pf(4, k), pf(5, k), pf(6, k)).normalized().toRotationMatrix();
  X_WF.translation() = pf.col(k).head<3>();
  return plan.wrench(f, k).inFrame(X_WF, core::Axes::kSole);
}

AlignedRun alignRun(const core::Plan& plan, const runtime::PlanTrack& track, int nA,
                    const std::string& log, const std::string& plan_path) {
  LogReader reader(log);
  LogEvent ev;
  AnyMessage msg;
  std::optional<overstep::robot_state_t> state;
  std::optional<overstep::robot_command_t> command;
  std::optional<overstep::plan_reference_t> ref;
  AlignedRun out;
  std::int64_t end_utime = 0;  // the robot's clock when the plan reached its end
  while (reader.next(ev)) {
    if (decode(ev.data, ev.size, msg) != DecodeStatus::Ok) continue;
    // Every message is checked against the plan (issue 20: another run's plan was drawn against
    // this log, its phase index read past the plan's phases).
    if (auto* s = std::get_if<overstep::robot_state_t>(&msg)) {
      checkJointCount(s->num_joints, nA, ev.channel, log, plan_path);
      state = *s;
    }
    if (auto* c = std::get_if<overstep::robot_command_t>(&msg)) {
      checkJointCount(c->num_joints, nA, ev.channel, log, plan_path);
      command = *c;
    }
    if (auto* p = std::get_if<overstep::plan_reference_t>(&msg)) {
      checkPlanReference(*p, plan, log, plan_path);
      ref = *p;
    }
    auto* st = std::get_if<overstep::stabilizer_status_t>(&msg);
    if (!st || !ref || ref->seq != st->seq || !state || !command) continue;
    const double t = ref->plan_time;
    std::vector<Row>& rows = out.rows;
    const bool ended = !rows.empty() && rows.back().t >= track.duration();
    if (ended) {
      Row r = makeRow(*ref, *st, *state, *command, plan, track, nA);
      r.t = track.duration() + static_cast<double>(state->utime - end_utime) * 1e-6;
      if (r.t > (out.hold.empty() ? track.duration() : out.hold.back().t))
        out.hold.push_back(std::move(r));
      continue;
    }
    if (!rows.empty() && t <= rows.back().t) {
      if (t == 0.0 && rows.size() == 1)
        rows.pop_back();  // keep the last tick at the start
      else
        continue;  // paused
    }
    rows.push_back(makeRow(*ref, *st, *state, *command, plan, track, nA));
    if (t >= track.duration()) end_utime = state->utime;
  }
  out.break_offset = reader.breakOffset();
  if (out.rows.size() < 2) {
    throw InputError(log + ": no executed plan ticks in the log (OVERSTEP_PLAN_REF, " +
                     "OVERSTEP_STABILIZER, OVERSTEP_STATE and OVERSTEP_COMMAND are needed)");
  }
  return out;
}

RunSeries toSeries(const AlignedRun& run, const core::Plan& plan, robots::WholeBodyModel& model) {
  RunSeries s;
  const std::size_t n = run.rows.size() + run.hold.size();
  s.resize(n);
  s.plan_end = plan.duration();
  s.weight = model.totalMass() * model.description().gravity;
  const double fz_min = 0.05 * s.weight;  // CoP undefined below 5 % of the weight
  const int base_frame = model.frameIndex(model.description().base_link);
  for (std::size_t i = 0; i < n; ++i) {
    const Row& r = i < run.rows.size() ? run.rows[i] : run.hold[i - run.rows.size()];
    const int k = r.index;
    s.t[i] = r.t;
    for (int f = 0; f < 2; ++f) {
      FootSeries& fs = s.foot[static_cast<std::size_t>(f)];
      const core::Wrench wp = planSoleWrench(plan, f, k);
      fs.fz_plan[i] = wp.force.z();
      fs.fz_meas[i] = r.w_meas[f].force.z();
      fs.cop_plan[i] = loadedCop(wp, fz_min);
      fs.cop_meas[i] = loadedCop(r.w_meas[f], fz_min);
      fs.moment_meas[i] = r.w_meas[f].moment.head<2>();
      const auto& ph = plan.phases[static_cast<std::size_t>(r.phase)];
      fs.plan_contact[i] = f == 0 ? ph.right_contact : ph.left_contact;
    }
    s.base_speed[i] =
        r.ground_truth ? r.base_velocity.norm() : std::numeric_limits<double>::quiet_NaN();
    model.setPositions(plan.q.col(k));
    s.tilt_plan[i] = core::rollPitch(model.framePose(base_frame).linear());
    s.tilt_meas[i] = core::rollPitch(r.ground_truth ? r.base.linear() : r.imu.toRotationMatrix());
  }
  for (std::size_t p = 1; p < plan.phases.size(); ++p) {
    const auto &prev = plan.phases[p - 1], &ph = plan.phases[p];
    if (ph.right_contact && !prev.right_contact) s.touchdowns[0].push_back(ph.start);
    if (ph.left_contact && !prev.left_contact) s.touchdowns[1].push_back(ph.start);
  }
  return s;
}

}  // namespace overstep::monitor
