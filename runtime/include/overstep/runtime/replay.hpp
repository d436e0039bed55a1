#pragma once
/// \file
/// The replay service's per-tick logic, free of any transport or clock: lifecycle
/// (idle -> moving to the first sample -> running -> finished, pause / resume / stop), watchdog and
/// faults, the stabilizer, and the joint command with its limits. The `overstep replay` process
/// (runtime/app) feeds it robot states from LCM on one of its clocks and publishes what it returns.
///
/// tick() never allocates and never throws: faults are statuses, and every fault freezes the
/// reference, ramps the stabilizer out and holds the posture (State::Hold, with a reason).

#include <Eigen/Core>
#include <cstdint>
#include <memory>

#include "overstep/core/robot_io.hpp"
#include "overstep/runtime/plan_track.hpp"
#include "overstep/stabilizer/stabilizer.hpp"

namespace overstep::runtime {

enum class State : std::uint8_t {
  Idle = 0,
  MovingToStart = 1,
  Running = 2,
  Paused = 3,
  Finished = 4,
  Hold = 5,
};
const char* toString(State s);

enum class FaultReason : std::uint8_t {
  None = 0,
  NoState,           ///< no robot state for watchdog_periods periods
  NonFiniteState,    ///< NaN / infinity in the robot state
  BadStateSize,      ///< wrong joint count
  JointLimit,        ///< a measured joint beyond its mechanical limit
  Fall,              ///< the robot (or simulator) reports a fall
  StabilizerFault,   ///< the stabilizer latched a fault (CoM error, torso tilt, ...)
  Stopped,           ///< operator stop
  StartUnreachable,  ///< the robot does not stand where the plan starts (no safe move to it)
};
const char* toString(FaultReason r);

struct ReplayOptions {
  double rate = 200.0;         ///< Hz
  bool stabilizer = true;      ///< false: open-loop replay of the plan
  double move_speed = 0.1;     ///< fraction of each joint's velocity limit for the move to start
  double min_move_time = 2.0;  ///< s, quasi-static: the CoM moves to the plan's start
  int watchdog_periods = 3;    ///< periods without a state before Hold
  double joint_limit_margin = 0.02;   ///< rad beyond the mechanical limit that counts as a fault
  double stabilizer_ramp_lead = 0.0;  ///< s of the plan's start held while the stabilizer ramps in
  /// The plan advances with the robot's clock (the states' time stamps: the lcm and lockstep
  /// clocks) instead of one period per tick: a tick without a state (the watchdog's) holds the
  /// plan's time, and a state that comes late or after a lost one catches it up.
  bool robot_clock = false;
};

/// What one tick produced (preallocated; the loop publishes it).
struct TickOutput {
  State state = State::Idle;
  FaultReason fault = FaultReason::None;
  double plan_time = 0.0;
  bool send_command = false;  ///< false while idle without a state (nothing known yet)
  core::RobotCommand command;
  TrackSample sample;
  stabilizer::Output stab;
  stabilizer::Status stab_status;
  double correction_norm = 0.0;  ///< |q_cmd - q_plan| over the joints, rad (stabilizer effort)
  bool clamped = false;          ///< a joint command was clamped to a limit this tick
};

class Replay {
 public:
  /// The track must outlive the replay. Throws InputError for bad options or parameters.
  Replay(const PlanTrack& track, const stabilizer::Params& params, const ReplayOptions& options);

  /// Requests the start: once a state is known, prepare() plans the move to the plan's first
  /// posture and the next tick begins it (Idle -> MovingToStart). With the stabilizer the move
  /// ends with its ramp-in (ramp_time) at that posture, and the plan starts with it fully on.
  void start();
  /// Work that must not run in the tick (it allocates and uses the model): planning the move to
  /// the start once it is requested and a state is known. Call it between ticks; returns true
  /// when it did something. A move that cannot be made holds with StartUnreachable.
  bool prepare();
  void pause();   ///< Running -> Paused (the reference stops; the stabilizer keeps balancing)
  void resume();  ///< Paused -> Running
  void stop();    ///< anything -> Hold (reason Stopped)
  /// An external fault (a fall flag from the simulator status): Hold with that reason. (A
  /// malformed state is not one: the caller ignores it, and the watchdog holds if no valid
  /// state follows.)
  void reportFault(FaultReason why);

  /// One control period. `state` is the newest robot state if one arrived since the last tick,
  /// else nullptr. Never allocates, never throws.
  const TickOutput& tick(const core::RobotState* state);

  State state() const { return out_.state; }
  FaultReason fault() const { return out_.fault; }
  std::int64_t ticks() const { return ticks_; }
  /// Consecutive periods without a robot state (the watchdog's count).
  int missedPeriods() const { return missed_; }
  const TickOutput& output() const { return out_; }
  const PlanTrack& track() const { return track_; }

 private:
  void enterHold(FaultReason why);
  FaultReason validate(const core::RobotState& st) const;
  void commandFromReference(bool with_stabilizer, double dt);

  const PlanTrack& track_;
  ReplayOptions opt_;
  stabilizer::Stabilizer stab_;
  TickOutput out_;
  core::RobotState last_state_;
  std::int64_t last_utime_ = 0;  ///< time stamp of the last accepted state (robot_clock)
  bool have_state_ = false;
  bool start_requested_ = false;
  int missed_ = 0;
  std::int64_t ticks_ = 0, seq_ = 0;
  double plan_time_ = 0.0;
  double move_T_ = 1.0;
  static constexpr double kMoveRate = 100.0;  ///< Hz of the planned move's samples
  Eigen::MatrixXd move_;                      ///< joints x samples, planned by prepare()
  bool move_ready_ = false;
  int move_k_ = 0;
  bool ramping_in_ = false;  ///< the move is done; the stabilizer ramps in at the first posture
  Eigen::VectorXd move_from_, q_hold_, q_prev_, qd_zero_;
  bool prev_valid_ = false;
  stabilizer::Measurement meas_;
};

}  // namespace overstep::runtime
