#pragma once
// Filled instances of every LCM type (distinct, non-default values) for round-trip tests.
#include "overstep/plan_reference_t.hpp"
#include "overstep/replay_control_t.hpp"
#include "overstep/robot_command_t.hpp"
#include "overstep/robot_state_t.hpp"
#include "overstep/runtime_status_t.hpp"
#include "overstep/sim_status_t.hpp"
#include "overstep/stabilizer_status_t.hpp"

namespace overstep::test {

template <std::size_t N>
inline void fill(double (&a)[N], double base) {
  for (std::size_t i = 0; i < N; ++i) a[i] = base + 0.1 * static_cast<double>(i);
}

inline robot_command_t makeCommand(int n) {
  robot_command_t m;
  m.utime = 1000;
  m.seq = 1;
  m.num_joints = n;
  for (int i = 0; i < n; ++i) {
    m.q_ref.push_back(0.01 * i);
    m.qd_ref.push_back(-0.01 * i);
    m.tau_ff.push_back(0.1 * i);
  }
  m.has_tau_ff = true;
  return m;
}

inline robot_state_t makeState(int n) {
  robot_state_t m;
  m.utime = 2000;
  m.seq = 2;
  m.last_command_seq = 1;
  m.num_joints = n;
  for (int i = 0; i < n; ++i) {
    m.q.push_back(0.02 * i);
    m.qd.push_back(0.03 * i);
    m.tau.push_back(-0.5 * i);
  }
  fill(m.ft_right, 10.0);
  fill(m.ft_left, 20.0);
  m.imu_quaternion[0] = 1.0;
  m.imu_quaternion[1] = m.imu_quaternion[2] = m.imu_quaternion[3] = 0.0;
  fill(m.imu_angular_velocity, 0.5);
  fill(m.imu_linear_acceleration, 9.0);
  m.has_ground_truth = true;
  fill(m.base_position, 0.6);
  m.base_quaternion[0] = 1.0;
  m.base_quaternion[1] = m.base_quaternion[2] = m.base_quaternion[3] = 0.0;
  fill(m.base_linear_velocity, 0.01);
  fill(m.base_angular_velocity, 0.02);
  return m;
}

inline plan_reference_t makePlanReference() {
  plan_reference_t m;
  m.utime = 3000;
  m.seq = 3;
  m.plan_time = 1.25;
  m.plan_duration = 4.3;
  m.phase = 1;
  m.phase_name = "ss_right_swing";
  fill(m.com, 0.8);
  fill(m.com_velocity, 0.1);
  fill(m.zmp_wholebody, 0.01);
  fill(m.zmp_tablecart, 0.02);
  fill(m.right_foot_position, 0.3);
  fill(m.right_foot_quaternion, 0.5);
  fill(m.left_foot_position, 0.4);
  fill(m.left_foot_quaternion, 0.5);
  m.right_contact = false;
  m.left_contact = true;
  fill(m.right_wrench, 0.0);
  fill(m.left_wrench, 100.0);
  return m;
}

inline stabilizer_status_t makeStabilizerStatus() {
  stabilizer_status_t m;
  m.utime = 4000;
  m.seq = 4;
  m.mode = stabilizer_status_t::MODE_ON;
  m.ramp = 1.0;
  m.fault = 0;
  m.fault_reason = "";
  m.saturations = 5;
  fill(m.zmp_reference, 0.01);
  fill(m.zmp_measured, 0.02);
  fill(m.zmp_command, 0.03);
  fill(m.com_error, 0.001);
  fill(m.dcm_error, 0.002);
  fill(m.com_offset, 0.003);
  fill(m.right_foot_rotation, 0.004);
  fill(m.left_foot_rotation, 0.005);
  m.foot_height_difference = 0.006;
  fill(m.body_attitude, 0.007);
  return m;
}

inline runtime_status_t makeRuntimeStatus() {
  runtime_status_t m;
  m.utime = 5000;
  m.seq = 5;
  m.state = runtime_status_t::STATE_RUNNING;
  m.fault_reason = "";
  m.tick = 1234;
  m.plan_time = 2.5;
  m.rate_hz = 200;
  m.period_min_us = 4900;
  m.period_mean_us = 5000;
  m.period_max_us = 5600;
  m.period_p99_us = 5400;
  m.processing_mean_us = 120;
  m.processing_max_us = 300;
  m.overruns = 1;
  m.missed_cycles = 2;
  m.late_states = 3;
  m.dropped_states = 4;
  return m;
}

inline replay_control_t makeReplayControl() {
  replay_control_t m;
  m.utime = 6000;
  m.seq = 6;
  m.command = replay_control_t::PAUSE;
  return m;
}

inline sim_status_t makeSimStatus() {
  sim_status_t m;
  m.utime = 7000;
  m.seq = 7;
  m.sim_time = 7.0;
  m.real_time_factor = 2.1;
  m.num_contacts = 8;
  m.right_foot_contact = true;
  m.left_foot_contact = true;
  m.fell = false;
  m.obstacle_contact = false;
  m.holding = false;
  m.rejected_commands = 0;
  return m;
}

}  // namespace overstep::test
