// `overstep replay`: the fixed-rate replay service. Streams a plan through the stabilizer to the
// robot (simulator or hardware bridge) over LCM.
#include <sched.h>
#include <sys/mman.h>
#include <time.h>
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "overstep/cli/command.hpp"
#include "overstep/cli/lcm_url.hpp"
#include "overstep/core/error.hpp"
#include "overstep/msgs/convert.hpp"
#include "overstep/plan_reference_t.hpp"
#include "overstep/replay_control_t.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/runtime/loop_stats.hpp"
#include "overstep/runtime/replay.hpp"
#include "overstep/runtime_status_t.hpp"
#include "overstep/sim_status_t.hpp"
#include "overstep/stabilizer/params.hpp"
#include "overstep/stabilizer_status_t.hpp"

namespace overstep {
namespace {

bool stopRequested() { return cli::StopSignals::requested(); }

enum class Clock { Timer, Lcm, Lockstep };

struct ReplayCliOptions {
  std::string plan;
  std::string robot;
  double rate = 200.0;
  std::string clock = "timer";
  std::string lcm_url;
  bool no_stabilizer = false;
  bool start = false;
  double linger = 1.0;
  bool stay = false;
  double state_timeout = 0.5;
  int watchdog = 3;
  bool json = false;
  bool quiet = false;
};

double nowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Running measures of how the execution went (for --json and the demo's verdict).
struct RunMeasures {
  double track_sq = 0.0;  ///< sum over running ticks of the mean squared joint tracking error
  long track_n = 0;
  double effort_sq = 0.0;
  long effort_n = 0;
  double cop_max[2] = {0.0, 0.0};  ///< m, largest |local CoP| (inf-norm) of a loaded foot
  double torso_dev_max = 0.0;      ///< rad, largest torso roll/pitch deviation from the plan
  double zmp_err_max = 0.0;        ///< m
  double run_start = -1.0, run_end = -1.0;  ///< robot time (s) of running start / finished

  void add(const runtime::TickOutput& o, const core::RobotState& st, const runtime::PlanTrack& tr,
           double robot_time) {
    const bool executing = o.state == runtime::State::Running ||
                           o.state == runtime::State::Finished || o.state == runtime::State::Paused;
    if (o.state == runtime::State::Running && run_start < 0.0) run_start = robot_time;
    if (o.state == runtime::State::Finished && run_end < 0.0) run_end = robot_time;
    if (!executing) return;
    track_sq += (st.q - o.sample.q).squaredNorm() / static_cast<double>(st.q.size());
    ++track_n;
    effort_sq += o.correction_norm * o.correction_norm;
    ++effort_n;
    for (int f = 0; f < 2; ++f) {
      const core::Wrench w = tr.soleWrench(o.sample.index, f, f == 0 ? st.ft_right : st.ft_left);
      if (w.force.z() < 50.0) continue;
      cop_max[f] = std::max(cop_max[f], core::localCop(w).cwiseAbs().maxCoeff());
    }
    const Eigen::AngleAxisd d(st.imu_orientation * o.sample.ref.torso.conjugate());
    const Eigen::Vector3d v = d.axis() * d.angle();
    torso_dev_max = std::max(torso_dev_max, std::hypot(v.x(), v.y()));
    zmp_err_max = std::max(zmp_err_max, o.stab.zmp_error.norm());
  }
};

class ReplayProcess {
 public:
  ReplayProcess(const ReplayCliOptions& o, Clock clock, const runtime::PlanTrack& track,
                const stabilizer::Params& params, const runtime::ReplayOptions& ro)
      : o_(o), clock_(clock), track_(track), replay_(track, params, ro), lcm_(o.lcm_url) {
    cli::lcmOpened(lcm_.good(), o.lcm_url, lcm_said_);
    state_.resize(track.joints());
    auto* s = lcm_.subscribe("OVERSTEP_STATE", &ReplayProcess::onStateBytes, this);
    s->setQueueCapacity(1000);
    lcm_.subscribe("OVERSTEP_SIM_STATUS", &ReplayProcess::onSimStatus, this);
    lcm_.subscribe("OVERSTEP_REPLAY_CONTROL", &ReplayProcess::onControl, this);
    period_ = 1.0 / o.rate;
    if (o.start) replay_.start();
  }

  int run() {
    if (clock_ == Clock::Timer) tryRealtime();
    const double t0 = nowSeconds();
    double deadline = t0;
    double last_tick = t0, last_status = t0, last_progress = t0;
    double done_since = -1.0, done_wall = 0.0;
    while (true) {
      const core::RobotState* st = nullptr;
      if (clock_ == Clock::Timer) {
        deadline += period_;
        sleepUntil(deadline);
        const double now = nowSeconds();
        if (now > deadline + period_) {  // woke up late: skip the lost deadlines
          const auto lost = static_cast<long>((now - deadline) / period_);
          missed_ += lost;
          deadline += static_cast<double>(lost) * period_;
        }
        drain(0);
        st = takeFresh();
      } else {
        // One tick per state message; a tick without one after the timeout (watchdog).
        // lcm: a state is due every period; wait half a period more before ticking without one
        // (waiting exactly one period raced the next state and made 0.1 ms periods: measured).
        const double timeout = clock_ == Clock::Lcm ? 1.5 * period_ : o_.state_timeout;
        const double until = nowSeconds() + timeout;
        while (!fresh_ && !stopRequested()) {
          const double left = until - nowSeconds();
          if (left <= 0.0) break;
          drain(std::max(1, static_cast<int>(std::ceil(left * 1000.0))));
        }
        st = takeFresh();
        // Lockstep: one tick per robot time. The simulator re-announces its state (same time,
        // new sequence number) while it waits for a command; ticking on that again advanced the
        // plan one period ahead of the robot for the rest of the run (measured: a 0.6 mrad
        // joint-position lead in 2 of 5 identical runs, docs/runtime.md). Answer it with the
        // same command instead (lost on the way: the simulator takes it; already taken: it
        // rejects the repeated sequence number).
        if (clock_ == Clock::Lockstep && st && st->utime == commanded_utime_) {
          lcm_.publish("OVERSTEP_COMMAND", &cmd_msg_);
          continue;
        }
      }
      if (stopRequested()) {
        replay_.stop();
        interrupted_ = true;
      }
      replay_.prepare();  // between ticks: plans the move to the start once it is requested
      const double tick_start = nowSeconds();
      const runtime::TickOutput& out = replay_.tick(st);
      if (out.state == runtime::State::Hold && hold_missed_ < 0)
        hold_missed_ = replay_.missedPeriods();
      publish(out, tick_start, st);
      if (replay_.state() != runtime::State::Idle && st)
        measures_.add(out, state_, track_, static_cast<double>(state_.utime) * 1e-6);
      const double tick_end = nowSeconds();
      stats_.record((tick_start - last_tick) * 1e6, (tick_end - tick_start) * 1e6, period_ * 1e6);
      last_tick = tick_start;
      if (tick_end - last_status >= 0.1) {
        publishStatus(out, tick_end);
        last_status = tick_end;
      }
      if (!o_.quiet && tick_end - last_progress >= 0.5) {
        progress(out);
        last_progress = tick_end;
      }
      const bool done = out.state == runtime::State::Finished || out.state == runtime::State::Hold;
      // Linger in robot periods while the robot answers, in wall time when it does not.
      if (done && done_since < 0.0) {
        done_since = static_cast<double>(replay_.ticks()) * period_;
        done_wall = tick_end;
      }
      if (interrupted_) break;
      if (done && !o_.stay &&
          (static_cast<double>(replay_.ticks()) * period_ - done_since >= o_.linger ||
           tick_end - done_wall >= o_.linger + 1.0))
        break;
    }
    if (!o_.quiet) {
      progress(replay_.output());
      std::fprintf(stderr, "\n");
    }
    const runtime::TickOutput& out = replay_.output();
    const LoopSummary ls = summaryNow();
    nlohmann::json j;
    j["state"] = runtime::toString(out.state);
    j["fault"] = runtime::toString(out.fault);
    j["finished"] = out.state == runtime::State::Finished;
    j["ticks"] = replay_.ticks();
    j["plan_duration"] = track_.duration();
    j["executed_duration"] = measures_.run_end >= 0.0 && measures_.run_start >= 0.0
                                 ? measures_.run_end - measures_.run_start
                                 : 0.0;
    j["plan_time"] = out.plan_time;
    j["rate"] = o_.rate;
    j["clock"] = o_.clock;
    j["stabilizer"] = !o_.no_stabilizer;
    j["tracking_rms"] = measures_.track_n
                            ? std::sqrt(measures_.track_sq / static_cast<double>(measures_.track_n))
                            : 0.0;
    j["stabilizer_effort"] =
        measures_.effort_n
            ? std::sqrt(measures_.effort_sq / static_cast<double>(measures_.effort_n))
            : 0.0;
    j["cop_max"] = {{"right", measures_.cop_max[0]}, {"left", measures_.cop_max[1]}};
    j["torso_deviation_max"] = measures_.torso_dev_max;
    j["zmp_error_max"] = measures_.zmp_err_max;
    // Over every tick of the run (p99 from a 10 us histogram); the worst 0.1 s window beside it.
    const runtime::LoopStats::Summary whole = stats_.run();
    j["period_us"] = {{"min", whole.period_min},
                      {"mean", whole.period_mean},
                      {"max", whole.period_max},
                      {"p99", whole.period_p99},
                      {"p99_worst_window", ls.all.period_p99}};
    j["processing_us"] = {{"mean", ls.all.processing_mean}, {"max", ls.all.processing_max}};
    j["overruns"] = stats_.overruns();
    j["missed_cycles"] = missed_;
    j["late_states"] = late_;
    j["dropped_states"] = dropped_;
    j["bad_states"] = bad_states_;
    j["round_trip_us"] = {{"mean", rtt_n_ ? rtt_sum_ / static_cast<double>(rtt_n_) : 0.0},
                          {"max", rtt_max_},
                          {"count", rtt_n_}};
    j["hold_missed_periods"] = hold_missed_;
    j["realtime"] = realtime_note_;
    if (o_.json) std::cout << j.dump(2) << "\n";
    if (interrupted_) return kExitInterrupted;
    return out.state == runtime::State::Finished ? kExitOk : kExitHeld;
  }

 private:
  struct LoopSummary {
    runtime::LoopStats::Summary all;
  };

  LoopSummary summaryNow() {
    LoopSummary s;
    s.all = all_stats_;
    return s;
  }

  void tryRealtime() {
    sched_param sp{};
    sp.sched_priority = 80;
    const bool fifo = sched_setscheduler(0, SCHED_FIFO, &sp) == 0;
    const bool locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
    realtime_note_ = std::string(fifo ? "SCHED_FIFO 80" : "SCHED_FIFO not permitted") + ", " +
                     (locked ? "memory locked" : "mlockall not permitted");
    if (!o_.quiet) std::fprintf(stderr, "replay: %s\n", realtime_note_.c_str());
  }

  void sleepUntil(double t) {
    timespec ts{};
    // steady_clock is CLOCK_MONOTONIC on Linux (libstdc++).
    ts.tv_sec = static_cast<time_t>(std::floor(t));
    ts.tv_nsec = static_cast<long>((t - std::floor(t)) * 1e9);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
      if (stopRequested()) return;
    }
  }

  void drain(int timeout_ms) {
    if (lcm_.handleTimeout(timeout_ms) < 0) return;
    while (lcm_.handleTimeout(0) > 0) {
    }
  }

  const core::RobotState* takeFresh() {
    if (!fresh_) return nullptr;
    fresh_ = false;
    return &state_;
  }

  /// Decoded here, not by liblcm's typed subscription: its generated decoder sizes the joint
  /// arrays from the message before checking the bytes (2^31 - 1 joints in a short message asked
  /// for 48 GB). An undecodable state is counted with the bad ones and ignored: without a valid
  /// state the watchdog holds.
  void onStateBytes(const lcm::ReceiveBuffer* rb, const std::string& channel) {
    std::string why;
    if (!msgs::decodeChecked(rb->data, static_cast<int>(rb->data_size), state_msg_, &why)) {
      ++bad_states_;
      if (bad_states_ <= 3)
        std::fprintf(stderr, "replay: undecodable robot state (%u bytes): %s\n", rb->data_size,
                     why.c_str());
      return;
    }
    onState(rb, channel, &state_msg_);
  }

  void onState(const lcm::ReceiveBuffer*, const std::string&, const overstep::robot_state_t* m) {
    std::string why;
    if (!msgs::fromLcm(*m, track_.joints(), state_, &why)) {
      // Counted and ignored like an undecodable one (another publisher's message, a damaged
      // packet): without a valid state for three periods the watchdog holds.
      ++bad_states_;
      if (bad_states_ <= 3) std::fprintf(stderr, "replay: bad robot state: %s\n", why.c_str());
      return;
    }
    if (last_state_seq_ >= 0) {
      if (m->seq <= last_state_seq_) return;  // duplicate or reordered: never act on stale data
      dropped_ += m->seq - last_state_seq_ - 1;
    }
    last_state_seq_ = m->seq;
    fresh_ = true;
    // Round trip: this state reflects command last_command_seq; how long ago was it sent? A state
    // more than one period behind our newest command is late (the robot acts on stale data).
    if (m->last_command_seq >= 0 && m->last_command_seq < cmd_seq_next_ &&
        cmd_seq_next_ - m->last_command_seq <= kSendRing) {
      const double sent = sent_wall_[static_cast<std::size_t>(m->last_command_seq % kSendRing)];
      const double rtt = (nowSeconds() - sent) * 1e6;
      rtt_sum_ += rtt;
      rtt_max_ = std::max(rtt_max_, rtt);
      ++rtt_n_;
      if (cmd_seq_next_ - 1 - m->last_command_seq > 1) ++late_;
    }
  }

  void onSimStatus(const lcm::ReceiveBuffer*, const std::string&, const overstep::sim_status_t* m) {
    if (m->fell) replay_.reportFault(runtime::FaultReason::Fall);
  }

  void onControl(const lcm::ReceiveBuffer*, const std::string&,
                 const overstep::replay_control_t* m) {
    switch (m->command) {
      case overstep::replay_control_t::START:
        replay_.start();
        break;
      case overstep::replay_control_t::PAUSE:
        replay_.pause();
        break;
      case overstep::replay_control_t::RESUME:
        replay_.resume();
        break;
      case overstep::replay_control_t::STOP:
        replay_.stop();
        break;
      default:
        std::fprintf(stderr, "replay: unknown control command %d\n", m->command);
    }
  }

  void publish(const runtime::TickOutput& out, double now, const core::RobotState* st) {
    // The tick's messages share one stamp: the wall clock, or in lockstep the robot time the
    // tick answers (the newest state's), so that the simulator can refuse an answer to a state
    // it has already stepped past.
    const auto utime = clock_ == Clock::Lockstep ? (st ? st->utime : state_.utime)
                                                 : static_cast<std::int64_t>(now * 1e6);
    if (out.send_command) {
      msgs::toLcm(out.command, cmd_msg_);
      cmd_msg_.utime = utime;
      if (clock_ == Clock::Lockstep) commanded_utime_ = utime;
      lcm_.publish("OVERSTEP_COMMAND", &cmd_msg_);
      sent_wall_[static_cast<std::size_t>(out.command.seq % kSendRing)] = nowSeconds();
      cmd_seq_next_ = out.command.seq + 1;
    }
    if (out.state == runtime::State::Idle) return;
    const runtime::TrackSample& s = out.sample;
    overstep::plan_reference_t r{};
    r.utime = utime;
    r.seq = ref_seq_++;
    r.plan_time = s.t;
    r.plan_duration = track_.duration();
    r.phase = s.phase;
    r.phase_name = track_.phaseName(s.phase);
    for (int i = 0; i < 3; ++i) {
      r.com[i] = s.ref.com(i);
      r.com_velocity[i] = s.ref.com_vel(i);
    }
    for (int i = 0; i < 2; ++i) {
      r.zmp_wholebody[i] = s.zmp_wholebody(i);
      r.zmp_tablecart[i] = s.ref.zmp(i);
    }
    for (int f = 0; f < 2; ++f) {
      const auto& fr = s.ref.foot[static_cast<std::size_t>(f)];
      double* pos = f == 0 ? r.right_foot_position : r.left_foot_position;
      double* quat = f == 0 ? r.right_foot_quaternion : r.left_foot_quaternion;
      double* w = f == 0 ? r.right_wrench : r.left_wrench;
      const Eigen::Quaterniond qq(fr.pose.linear());
      for (int i = 0; i < 3; ++i) pos[i] = fr.pose.translation()(i);
      quat[0] = qq.w();
      quat[1] = qq.x();
      quat[2] = qq.y();
      quat[3] = qq.z();
      // World axes about the sole origin, [F; M] (the message's convention).
      const core::Vector6d fm = fr.wrench.expressedIn(fr.pose, core::Axes::kWorld).forceMoment();
      for (int i = 0; i < 6; ++i) w[i] = fm(i);
      (f == 0 ? r.right_contact : r.left_contact) = fr.contact;
    }
    lcm_.publish("OVERSTEP_PLAN_REF", &r);
    overstep::stabilizer_status_t m{};
    m.utime = utime;
    m.seq = r.seq;
    m.mode = static_cast<int8_t>(out.stab_status.mode);
    m.ramp = out.stab.ramp;
    m.fault = static_cast<int32_t>(out.stab_status.fault);
    m.fault_reason = out.stab_status.ok() ? "" : stabilizer::toString(out.stab_status.fault);
    m.saturations = static_cast<int32_t>(out.stab_status.saturation);
    for (int i = 0; i < 2; ++i) {
      m.zmp_reference[i] = out.stab.zmp_reference(i);
      m.zmp_measured[i] = out.stab.zmp_measured(i);
      m.zmp_command[i] = out.stab.zmp_desired(i);
      m.com_error[i] = out.stab.com_error(i);
      m.dcm_error[i] = out.stab.dcm_error(i);
      m.right_foot_rotation[i] = out.stab.foot_rotation[0](i);
      m.left_foot_rotation[i] = out.stab.foot_rotation[1](i);
      m.body_attitude[i] = out.stab.body_attitude(i);
    }
    m.com_error[2] = 0.0;
    for (int i = 0; i < 3; ++i) m.com_offset[i] = out.stab.com_offset(i);
    m.foot_height_difference = out.stab.foot_height[1] - out.stab.foot_height[0];
    lcm_.publish("OVERSTEP_STABILIZER", &m);
  }

  void publishStatus(const runtime::TickOutput& out, double now) {
    const int window = std::max(1, static_cast<int>(std::lround(0.1 * o_.rate)));
    const runtime::LoopStats::Summary s = stats_.summary(window, false);
    window_stats_ = s;
    accumulate(s);
    overstep::runtime_status_t m{};
    m.utime = static_cast<std::int64_t>(now * 1e6);
    m.seq = status_seq_++;
    m.state = static_cast<int8_t>(out.state);
    m.fault_reason = out.state == runtime::State::Hold ? runtime::toString(out.fault) : "";
    m.tick = replay_.ticks();
    m.plan_time = out.plan_time;
    m.rate_hz = o_.rate;
    m.period_min_us = s.period_min;
    m.period_mean_us = s.period_mean;
    m.period_max_us = s.period_max;
    m.period_p99_us = s.period_p99;
    m.processing_mean_us = s.processing_mean;
    m.processing_max_us = s.processing_max;
    m.overruns = stats_.overruns();
    m.missed_cycles = missed_;
    m.late_states = late_;
    m.dropped_states = dropped_;
    lcm_.publish("OVERSTEP_RUNTIME", &m);
  }

  /// Whole-run statistics from the 10 Hz windows (min/max exact, mean and p99 as the worst window
  /// p99 and the mean of the window means).
  void accumulate(const runtime::LoopStats::Summary& s) {
    if (s.count == 0) return;
    // Skip the first window: it contains start-up.
    if (++windows_ == 1) return;
    auto& a = all_stats_;
    if (a.count == 0) {
      a = s;
      return;
    }
    a.period_min = std::min(a.period_min, s.period_min);
    a.period_max = std::max(a.period_max, s.period_max);
    a.period_mean = (a.period_mean * a.count + s.period_mean * s.count) / (a.count + s.count);
    a.processing_mean =
        (a.processing_mean * a.count + s.processing_mean * s.count) / (a.count + s.count);
    a.processing_max = std::max(a.processing_max, s.processing_max);
    a.period_p99 = std::max(a.period_p99, s.period_p99);
    a.count += s.count;
  }

  void progress(const runtime::TickOutput& out) {
    std::fprintf(stderr,
                 "\rreplay: %-15s t = %6.2f / %.2f s  %-16s  stab %-8s  overruns %lld  dropped "
                 "%lld  late %lld%s%s   ",
                 runtime::toString(out.state), out.plan_time, track_.duration(),
                 track_.phaseName(out.sample.phase).c_str(),
                 stabilizer::toString(out.stab_status.mode),
                 static_cast<long long>(stats_.overruns()), static_cast<long long>(dropped_),
                 static_cast<long long>(late_), out.state == runtime::State::Hold ? "  HOLD: " : "",
                 out.state == runtime::State::Hold ? runtime::toString(out.fault) : "");
  }

  ReplayCliOptions o_;
  Clock clock_;
  const runtime::PlanTrack& track_;
  runtime::Replay replay_;
  overstep::robot_state_t state_msg_;  // the last state received, decoded (onStateBytes)
  core::StderrCapture lcm_said_;       // what liblcm prints while lcm_ opens (into the error line)
  lcm::LCM lcm_;
  double period_ = 0.005;
  core::RobotState state_;
  bool fresh_ = false, interrupted_ = false;
  std::int64_t last_state_seq_ = -1, dropped_ = 0, late_ = 0, missed_ = 0, bad_states_ = 0;
  std::int64_t ref_seq_ = 0, status_seq_ = 0;
  static constexpr std::int64_t kSendRing = 1024;
  std::array<double, kSendRing> sent_wall_{};  ///< wall time each recent command was sent
  std::int64_t cmd_seq_next_ = 0;
  std::int64_t commanded_utime_ = -1;  // lockstep: robot time the last command answered
  double rtt_sum_ = 0.0, rtt_max_ = 0.0;
  std::int64_t rtt_n_ = 0;
  int hold_missed_ = -1;  ///< periods without a state when the hold began
  int windows_ = 0;
  overstep::robot_command_t cmd_msg_{};
  runtime::LoopStats stats_;
  runtime::LoopStats::Summary window_stats_{}, all_stats_{};
  RunMeasures measures_;
  std::string realtime_note_ = "not requested";
};

Clock parseClock(const std::string& s) {
  if (s == "timer") return Clock::Timer;
  if (s == "lcm") return Clock::Lcm;
  if (s == "lockstep") return Clock::Lockstep;
  throw InputError("--clock: unknown clock '" + s + "' (expected timer, lcm or lockstep)");
}

int runReplay(const ReplayCliOptions& o) {
  const Clock clock = parseClock(o.clock);
  if (!(o.rate >= 50.0 && o.rate <= 1000.0)) throw InputError("--rate: expected 50 to 1000 Hz");
  if (!(o.linger >= 0.0)) throw InputError("--linger: expected >= 0 s");
  if (!(o.state_timeout > 0.0)) throw InputError("--state-timeout: expected > 0 s");
  if (o.watchdog < 1) throw InputError("--watchdog: expected >= 1 period");
  cli::checkLcmUrl(o.lcm_url);
  // Everything is validated before anything is sent: the plan, the model, the parameters.
  const core::Plan plan = core::loadPlan(o.plan);
  robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(o.robot);
  const runtime::PlanTrack track(plan, model);
  stabilizer::Params params = stabilizer::loadParams(o.robot);
  params.mass = model.totalMass();
  runtime::ReplayOptions ro;
  ro.rate = o.rate;
  ro.stabilizer = !o.no_stabilizer;
  ro.watchdog_periods = o.watchdog;
  // The lcm clock ticks on the robot's states, and on the watchdog's timeout without one: the
  // plan follows the states' time stamps. (Lockstep answers every state once, a period each.)
  ro.robot_clock = clock == Clock::Lcm;
  ReplayProcess p(o, clock, track, params, ro);
  const cli::StopSignals stop;
  if (!o.quiet)
    std::fprintf(stderr, "replay: %s (%.2f s, %d samples) at %.0f Hz, clock %s, stabilizer %s%s\n",
                 o.plan.c_str(), track.duration(), track.samples(), o.rate, o.clock.c_str(),
                 o.no_stabilizer ? "off" : "on",
                 o.start ? "" : "; waiting for START on OVERSTEP_REPLAY_CONTROL");
  const int code = p.run();
  return code;
}

}  // namespace

void registerReplayCommand(CLI::App& app, cli::Registry& registry) {
  auto o = std::make_shared<ReplayCliOptions>();
  const char* env_url = std::getenv("LCM_DEFAULT_URL");
  o->lcm_url = env_url ? env_url : "udpm://239.255.76.67:7667?ttl=0";
  CLI::App* sub = app.add_subcommand("replay", "Stream a plan through the stabilizer to the robot");
  sub->add_option("plan", o->plan, "Plan file (overstep plan --out)")->required();
  sub->add_option("--robot", o->robot, "Robot YAML")->default_val(cli::defaultRobotPath());
  sub->add_option("--rate", o->rate, "Loop rate, Hz (50-1000)")->default_val(200.0);
  sub->add_option("--clock", o->clock,
                  "timer (absolute deadlines), lcm (one tick per robot state) or lockstep "
                  "(with overstep sim --lockstep)")
      ->default_val("timer");
  sub->add_option("--lcm-url", o->lcm_url, "LCM URL (default: $LCM_DEFAULT_URL or udpm)");
  sub->add_flag("--no-stabilizer", o->no_stabilizer, "Open-loop replay of the plan");
  sub->add_flag("--start", o->start, "Start at once (else wait for START on the control channel)");
  sub->add_option("--linger", o->linger, "Seconds to keep holding after finishing, then exit")
      ->default_val(1.0);
  sub->add_flag("--stay", o->stay, "Keep running after finishing until Ctrl-C");
  sub->add_option("--state-timeout", o->state_timeout,
                  "lockstep: seconds without a state that count as one missed period")
      ->default_val(0.5);
  sub->add_option("--watchdog", o->watchdog, "Missed periods before holding")->default_val(3);
  sub->add_flag("--json", o->json, "Print a JSON summary on exit");
  sub->add_flag("--quiet", o->quiet, "No progress line");
  sub->footer(
      "Examples:\n"
      "  overstep sim --lockstep &  overstep replay plan.json --clock lockstep --start\n"
      "  overstep replay plan.json --clock timer --rate 1000     # 1 kHz, wall-clock deadlines\n"
      "  overstep replay plan.json --clock lcm --json            # paced by the robot's states\n"
      "Channels: subscribes OVERSTEP_STATE, OVERSTEP_SIM_STATUS, OVERSTEP_REPLAY_CONTROL;\n"
      "publishes OVERSTEP_COMMAND, OVERSTEP_PLAN_REF, OVERSTEP_STABILIZER (every tick),\n"
      "OVERSTEP_RUNTIME (10 Hz). Exit: 0 finished, 2 bad input, 4 ended holding after a fault,\n"
      "130 interrupted.");
  registry.add(sub, [o] { return runReplay(*o); });
}

}  // namespace overstep
