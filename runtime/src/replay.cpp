#include "overstep/runtime/replay.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "overstep/core/error.hpp"

namespace overstep::runtime {

const char* toString(State s) {
  switch (s) {
    case State::Idle:
      return "idle";
    case State::MovingToStart:
      return "moving_to_start";
    case State::Running:
      return "running";
    case State::Paused:
      return "paused";
    case State::Finished:
      return "finished";
    case State::Hold:
      return "hold";
  }
  return "unknown";
}

const char* toString(FaultReason r) {
  switch (r) {
    case FaultReason::None:
      return "";
    case FaultReason::NoState:
      return "no robot state for the watchdog period";
    case FaultReason::NonFiniteState:
      return "non-finite value in the robot state";
    case FaultReason::BadStateSize:
      return "robot state has the wrong joint count";
    case FaultReason::JointLimit:
      return "a measured joint is beyond its limit";
    case FaultReason::Fall:
      return "the robot reports a fall";
    case FaultReason::StabilizerFault:
      return "stabilizer fault";
    case FaultReason::Stopped:
      return "stopped by the operator";
    case FaultReason::StartUnreachable:
      return "the robot does not stand where the plan starts (no safe move to it)";
  }
  return "unknown";
}

Replay::Replay(const PlanTrack& track, const stabilizer::Params& params,
               const ReplayOptions& options)
    : track_(track), opt_(options), stab_(params) {
  if (!(opt_.rate >= 50.0 && opt_.rate <= 1000.0))
    throw InputError("replay rate: expected 50 to 1000 Hz");
  if (!(opt_.move_speed > 0.0 && opt_.move_speed <= 1.0))
    throw InputError("replay move speed: expected a fraction in (0, 1]");
  if (opt_.watchdog_periods < 1) throw InputError("replay watchdog: expected >= 1 period");
  const int n = track.joints();
  out_.command.resize(n);
  out_.sample = track.makeSample();
  last_state_.resize(n);
  move_from_.setZero(n);
  q_hold_.setZero(n);
  q_prev_.setZero(n);
  qd_zero_.setZero(n);
}

void Replay::start() { start_requested_ = true; }

bool Replay::prepare() {
  if (!start_requested_ || !have_state_ || move_ready_ || out_.state != State::Idle) return false;
  move_from_ = last_state_.q;
  double T = opt_.min_move_time;
  const TrackSample first = track_.makeSample();
  for (int j = 0; j < track_.joints(); ++j) {
    const double dist = std::abs(first.q(j) - move_from_(j));
    // A quintic blend peaks at 15/8 of the mean speed.
    T = std::max(T, 1.875 * dist / (opt_.move_speed * track_.velocityLimit()(j)));
  }
  move_T_ = T;
  // Solved at 100 Hz and interpolated per tick: at 1 kHz one IK per tick took ~40 ms here, a
  // stall of 37 periods before the first tick of the move (measured).
  const int samples = static_cast<int>(std::ceil(T * kMoveRate)) + 1;
  if (!track_.planMove(move_from_, samples, move_)) {
    enterHold(FaultReason::StartUnreachable);
    return true;
  }
  move_ready_ = true;
  return true;
}

void Replay::pause() {
  if (out_.state == State::Running) out_.state = State::Paused;
}

void Replay::resume() {
  if (out_.state == State::Paused) out_.state = State::Running;
}

void Replay::stop() { enterHold(FaultReason::Stopped); }

void Replay::reportFault(FaultReason why) { enterHold(why); }

void Replay::enterHold(FaultReason why) {
  if (out_.state == State::Hold) return;  // the first reason stays
  out_.fault = why;
  // Freeze the reference: the plan sample of now while executing it (the stabilizer's
  // corrections then ramp out around it, continuously), else the posture being commanded.
  const bool on_plan = out_.state == State::Running || out_.state == State::Paused ||
                       out_.state == State::Finished || ramping_in_;
  ramping_in_ = false;
  if (on_plan)
    q_hold_ = out_.sample.q;
  else
    q_hold_ = prev_valid_ ? q_prev_ : (have_state_ ? last_state_.q : out_.sample.q);
  stab_.disable();
  out_.state = State::Hold;
}

FaultReason Replay::validate(const core::RobotState& st) const {
  const int n = track_.joints();
  if (st.q.size() != n || st.qd.size() != n) return FaultReason::BadStateSize;
  if (!st.q.allFinite() || !st.qd.allFinite() || !st.ft_right.allFinite() ||
      !st.ft_left.allFinite() || !st.imu_orientation.coeffs().allFinite() ||
      !st.imu_angular_velocity.allFinite())
    return FaultReason::NonFiniteState;
  for (int j = 0; j < n; ++j)
    if (st.q(j) < track_.lower()(j) - opt_.joint_limit_margin ||
        st.q(j) > track_.upper()(j) + opt_.joint_limit_margin)
      return FaultReason::JointLimit;
  return FaultReason::None;
}

const TickOutput& Replay::tick(const core::RobotState* state) {
  const double dt = 1.0 / opt_.rate;
  ++ticks_;
  // How far the plan advances this tick: a period, or with the robot's clock the time since the
  // last state (none without a state; at most the watchdog's span, beyond which it holds).
  double advance = opt_.robot_clock ? 0.0 : dt;
  if (state) {
    const FaultReason f = validate(*state);
    if (f != FaultReason::None) {
      enterHold(f);
    } else {
      if (opt_.robot_clock && have_state_)
        advance = std::clamp(static_cast<double>(state->utime - last_utime_) * 1e-6, 0.0,
                             opt_.watchdog_periods * dt);
      last_state_ = *state;  // same sizes: no allocation
      last_utime_ = state->utime;
      have_state_ = true;
      missed_ = 0;
    }
  } else if (have_state_) {
    if (missed_ < std::numeric_limits<int>::max()) ++missed_;  // an idle wait may be long
    // The watchdog guards the commands. Before the first one (Idle) a robot whose states pause
    // only delays the start: holding there protected nothing, yet a startup stall of the robot's
    // state stream ended the run before it began.
    if (out_.state != State::Idle && missed_ >= opt_.watchdog_periods)
      enterHold(FaultReason::NoState);
  }

  switch (out_.state) {
    case State::Idle:
      if (move_ready_ && missed_ == 0) {  // the first command answers a state of this tick
        move_k_ = 0;
        out_.state = State::MovingToStart;
      }
      break;
    case State::MovingToStart:
      if (advance > 0.0 && !ramping_in_) ++move_k_;
      if (move_k_ >= static_cast<int>(std::ceil(move_T_ * opt_.rate))) {
        // At the plan's first posture the stabilizer ramps in before the plan starts: within
        // its ramp the plan's first lift-off would get part of the feedback only.
        if (opt_.stabilizer && !ramping_in_) {
          stab_.reset();
          stab_.enable();
          ramping_in_ = true;
        }
        if (!opt_.stabilizer || stab_.status().mode == stabilizer::Mode::On) {
          ramping_in_ = false;
          out_.state = State::Running;
          plan_time_ = 0.0;
        }
      }
      break;
    case State::Running:
      plan_time_ += advance;
      if (plan_time_ >= track_.duration()) {
        plan_time_ = track_.duration();
        out_.state = State::Finished;
      }
      break;
    case State::Paused:
    case State::Finished:
    case State::Hold:
      break;
  }

  track_.sample(plan_time_, out_.sample);
  out_.plan_time = plan_time_;
  out_.send_command = have_state_ && out_.state != State::Idle;

  // The stabilizer acts while the plan is being (or has been) executed, and ramps out in Hold.
  const bool stab_active = opt_.stabilizer && out_.state != State::Idle &&
                           (out_.state != State::MovingToStart || ramping_in_) && have_state_;
  if (stab_active) {
    stab_.setReference(out_.sample.ref);
    track_.estimate(out_.sample, last_state_, meas_);
    out_.stab_status = stab_.step(meas_, dt, out_.stab);
    if (!out_.stab_status.ok() && out_.state != State::Hold)
      enterHold(FaultReason::StabilizerFault);
  } else {
    out_.stab = stabilizer::Output{};
    out_.stab_status = stab_.status();
  }
  commandFromReference(stab_active, dt);
  out_.fault = out_.state == State::Hold ? out_.fault : FaultReason::None;
  return out_;
}

void Replay::commandFromReference(bool with_stabilizer, double dt) {
  core::RobotCommand& c = out_.command;
  const TrackSample& s = out_.sample;
  switch (out_.state) {
    case State::Idle:
      c.q_ref = have_state_ ? last_state_.q : s.q;
      c.qd_ref = qd_zero_;
      break;
    case State::MovingToStart: {
      if (ramping_in_) {  // the move is done: the plan's first posture, at rest
        c.q_ref = s.q;
        c.qd_ref = qd_zero_;
        break;
      }
      // Linear interpolation of the 100 Hz move samples at this tick's time.
      const int last = static_cast<int>(move_.cols()) - 1;
      const double u = std::min(static_cast<double>(move_k_) / opt_.rate, move_T_) / move_T_ *
                       static_cast<double>(last);
      const int k = std::min(static_cast<int>(u), std::max(last - 1, 0));
      const int k1 = std::min(k + 1, last);
      const double a = std::clamp(u - k, 0.0, 1.0);
      c.q_ref = (1.0 - a) * move_.col(k) + a * move_.col(k1);
      c.qd_ref = (move_.col(k1) - move_.col(k)) * (static_cast<double>(last) / move_T_);
      break;
    }
    case State::Running:
      c.q_ref = s.q;
      c.qd_ref = s.qd;
      break;
    case State::Paused:
    case State::Finished:
      c.q_ref = s.q;
      c.qd_ref = qd_zero_;
      break;
    case State::Hold:
      c.q_ref = q_hold_;
      c.qd_ref = qd_zero_;
      break;
  }
  if (with_stabilizer) {
    // In Hold the corrections ramp out around the frozen posture, without the plan's motion.
    track_.applyCorrections(s, out_.stab, c.q_ref);
  }
  out_.clamped = false;
  double norm2 = 0.0;
  for (int j = 0; j < track_.joints(); ++j) {
    double q = std::clamp(c.q_ref(j), track_.lower()(j), track_.upper()(j));
    if (prev_valid_) {
      const double step = track_.velocityLimit()(j) * dt;
      q = std::clamp(q, q_prev_(j) - step, q_prev_(j) + step);
    }
    if (q != c.q_ref(j)) out_.clamped = true;
    c.q_ref(j) = q;
    c.qd_ref(j) = std::clamp(c.qd_ref(j), -track_.velocityLimit()(j), track_.velocityLimit()(j));
    const double e = with_stabilizer ? q - (out_.state == State::Hold ? q_hold_(j) : s.q(j)) : 0.0;
    norm2 += e * e;
  }
  out_.correction_norm = std::sqrt(norm2);
  c.has_tau_ff = false;
  c.seq = out_.send_command ? seq_++ : seq_;
  if (out_.send_command) {
    q_prev_ = c.q_ref;
    prev_valid_ = true;
  }
}

}  // namespace overstep::runtime
