// `overstep sim`: the simulated robot as a process on LCM. Subscribes to OVERSTEP_COMMAND,
// publishes OVERSTEP_STATE every control period and OVERSTEP_SIM_STATUS.
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>

#include "overstep/cli/command.hpp"
#include "overstep/cli/lcm_url.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/obstacle.hpp"
#include "overstep/msgs/convert.hpp"
#include "overstep/sim/sensor_noise.hpp"
#include "overstep/sim/simulator.hpp"
#include "overstep/sim_status_t.hpp"

namespace overstep {
namespace {

bool stopRequested() { return cli::StopSignals::requested(); }

struct SimCliOptions {
  std::string robot;
  std::string truth;
  bool lockstep = false;
  bool realtime = false;
  double rate = 200.0;
  std::string lcm_url;
  unsigned seed = 1;
  double noise = 1.0;
  double hold_timeout = 0.5;
  double duration = 0.0;
  double fall_height = 0.35;
  bool json = false;
  bool no_obstacle = false;
  core::ObstacleSpec obstacle;
  std::string obstacle_shape = "box";
  std::string contact_log;
};

/// --contact-log: the simulator's ground truth contact after every physics step (1 kHz), as CSV.
/// Written to FILE.part and renamed over FILE when the run ends, so FILE is never half-written.
/// Columns: time, then per foot the ground reaction force (world, N) and its centre of pressure
/// (world x, y on the ground, m; nan without load), then the number of contact points.
class ContactLog {
 public:
  explicit ContactLog(const std::string& path) : path_(path), part_(path + ".part") {
    if (path_.empty()) return;
    f_ = std::fopen(part_.c_str(), "w");
    if (!f_)
      throw InputError("--contact-log: cannot write " + part_ + " (" + std::strerror(errno) + ")");
    std::fputs(
        "t [s],right_Fx [N],right_Fy [N],right_Fz [N],right_cop_x [m],right_cop_y [m],"
        "left_Fx [N],left_Fy [N],left_Fz [N],left_cop_x [m],left_cop_y [m],contact_points\n",
        f_);
  }
  ContactLog(const ContactLog&) = delete;
  ContactLog& operator=(const ContactLog&) = delete;
  ~ContactLog() {
    if (!f_) return;
    std::fclose(f_);
    std::remove(part_.c_str());
  }
  void add(double t, const sim::ContactInfo& c) {
    if (!f_) return;
    std::fprintf(f_, "%.4f", t);
    for (const core::Wrench& w : c.foot_wrench) {  // world axes
      const double fz = w.force.z();
      const Eigen::Vector2d zmp =
          fz > 0.0 ? core::zmpFromWrench(w, 0.0, 0.0) : Eigen::Vector2d::Constant(std::nan(""));
      std::fprintf(f_, ",%.3f,%.3f,%.3f,%.5f,%.5f", w.force.x(), w.force.y(), fz, zmp.x(), zmp.y());
    }
    std::fprintf(f_, ",%d\n", c.contact_points);
  }
  void finish() {
    if (!f_) return;
    const bool ok = std::fclose(f_) == 0;
    f_ = nullptr;
    if (!ok || std::rename(part_.c_str(), path_.c_str()) != 0)
      throw std::runtime_error("--contact-log: could not complete " + path_);
  }

 private:
  std::string path_, part_;
  std::FILE* f_ = nullptr;
};

class SimProcess {
 public:
  SimProcess(const SimCliOptions& o, const robots::WholeBodyModel& model,
             const sim::TruthEffects& truth)
      : o_(o),
        sim_(model, truth, simOptions(o)),
        noise_(o.seed, o.noise),
        lcm_(o.lcm_url),
        joints_(model.actuatedCount()),
        model_desc_(model.description()),
        contact_log_(o.contact_log) {
    cli::lcmOpened(lcm_.good(), o.lcm_url, lcm_said_);
    auto* sub = lcm_.subscribe("OVERSTEP_COMMAND", &SimProcess::onCommandBytes, this);
    sub->setQueueCapacity(1000);  // drain everything; the newest valid command wins
    steps_per_period_ = static_cast<int>(std::lround(1.0 / (o.rate * 0.001)));
    sim_.settle();  // start settled in half-sitting
    const core::RobotState st = sim_.state();
    cmd_.q_ref = st.q;
    cmd_.qd_ref = Eigen::VectorXd::Zero(joints_);
  }

  int run() {
    const double period = 1.0 / o_.rate;
    publish();
    const auto wall0 = std::chrono::steady_clock::now();
    auto deadline = wall0;
    auto rtf_wall = wall0;
    double rtf_sim = 0.0;
    while (!stopRequested()) {
      if (o_.duration > 0.0 && sim_.time() >= o_.duration - 1e-9) break;
      if (o_.lockstep) {
        // One control period per accepted command, as fast as the commands come. While none
        // comes, the state is re-announced every hold timeout (new sequence number, same time),
        // so a runtime that started after the first announcement still gets going.
        fresh_ = false;
        auto announced = std::chrono::steady_clock::now();
        while (!fresh_ && !stopRequested()) {
          if (lcm_.handleTimeout(100) < 0) {
            if (stopRequested()) break;  // interrupted by the signal that stops us
            throw std::runtime_error("LCM receive failed");
          }
          const auto now = std::chrono::steady_clock::now();
          const double idle = std::chrono::duration<double>(now - last_command_wall_).count();
          if (!fresh_ && idle > o_.hold_timeout && !holding_) setHolding(true);
          if (!fresh_ && std::chrono::duration<double>(now - announced).count() > o_.hold_timeout) {
            publish();
            announced = now;
          }
        }
        if (stopRequested()) break;
      } else {
        while (lcm_.handleTimeout(0) > 0) {
        }
        if (sim_.time() - last_command_sim_ > o_.hold_timeout && !holding_) setHolding(true);
      }
      sim_.setCommand(cmd_.q_ref, cmd_.qd_ref);
      for (int i = 0; i < steps_per_period_; ++i) {
        sim_.step();
        contact_log_.add(sim_.time(), sim_.contacts());
      }
      detectFall();
      const auto now = std::chrono::steady_clock::now();
      const double wall = std::chrono::duration<double>(now - rtf_wall).count();
      if (wall >= 1.0) {
        rtf_ = (sim_.time() - rtf_sim) / wall;
        rtf_wall = now;
        rtf_sim = sim_.time();
      }
      publish();
      if (o_.realtime) {
        deadline += std::chrono::nanoseconds(static_cast<long>(period * 1e9));
        std::this_thread::sleep_until(deadline);
      }
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    summary_["sim_time"] = sim_.time();
    summary_["wall_time"] = wall;
    summary_["real_time_factor"] = wall > 0 ? sim_.time() / wall : 0.0;
    summary_["accepted_commands"] = accepted_;
    summary_["rejected_commands"] = rejected_;
    summary_["fell"] = fell_;
    summary_["obstacle_contact"] = obstacle_contact_;
    summary_["states_published"] = state_seq_;
    // Ground truth at the end, for verdicts (never published on the bus).
    const auto& d = model_desc_;
    for (const char* side : {"right", "left"}) {
      const Eigen::Isometry3d X = sim_.framePose(d.foot(side)->sole_frame);
      const core::FootDescription* fd = d.foot(side);
      summary_[std::string(side) + "_sole"] = {X.translation().x(), X.translation().y(),
                                               X.translation().z()};
      // Heel (back edge) x: what must be beyond the bar for the foot to have cleared it.
      summary_[std::string(side) + "_heel_x"] =
          (X * Eigen::Vector3d(-fd->sole.x_back, 0.0, 0.0)).x();
    }
    summary_["base_height"] = sim_.basePose().translation().z();
    summary_["base_speed"] = sim_.baseSpeed();
    summary_["obstacle_x"] = {sim_.obstacleRangeX()[0], sim_.obstacleRangeX()[1]};
    summary_["has_obstacle"] = !o_.no_obstacle;
    contact_log_.finish();
    if (o_.json)
      std::cout << summary_.dump(2) << "\n";
    else
      std::fprintf(stderr,
                   "sim: %.3f s simulated in %.3f s (x%.2f), %lld commands accepted, %lld "
                   "rejected%s\n",
                   sim_.time(), wall, wall > 0 ? sim_.time() / wall : 0.0,
                   static_cast<long long>(accepted_), static_cast<long long>(rejected_),
                   fell_ ? ", FELL" : "");
    return kExitOk;
  }

 private:
  /// Decoded here, not by liblcm's typed subscription: its generated decoder sizes the joint
  /// arrays from the message before checking the bytes (a 50-byte command declaring 2^31 - 1
  /// joints asked for 48 GB). An undecodable command is rejected and counted like a bad one.
  void onCommandBytes(const lcm::ReceiveBuffer* rb, const std::string& channel) {
    std::string why;
    if (!msgs::decodeChecked(rb->data, static_cast<int>(rb->data_size), cmd_msg_, &why)) {
      reject("command of " + std::to_string(rb->data_size) + " bytes: " + why);
      return;
    }
    onCommand(rb, channel, &cmd_msg_);
  }

  void onCommand(const lcm::ReceiveBuffer*, const std::string&,
                 const overstep::robot_command_t* msg) {
    std::string why;
    core::RobotCommand c;
    c.resize(joints_);
    if (!msgs::fromLcm(*msg, joints_, c, &why)) {
      reject("command " + std::to_string(msg->seq) + ": " + why);
      return;
    }
    if (msg->seq == last_seq_ && o_.lockstep) return;  // the same command again (a resend)
    if (msg->seq <= last_seq_) {
      reject("command " + std::to_string(msg->seq) + ": stale sequence number (last accepted " +
             std::to_string(last_seq_) + ")");
      return;
    }
    // Lockstep: a command stamped with a robot time before ours answers a state already stepped
    // past (the runtime stamps its commands with the time of the state it answers).
    const auto now_us = static_cast<std::int64_t>(std::llround(sim_.time() * 1e6));
    if (o_.lockstep && msg->utime < now_us) {
      reject("command " + std::to_string(msg->seq) + ": answers robot time " +
             std::to_string(msg->utime) + " us, already at " + std::to_string(now_us) + " us");
      return;
    }
    last_seq_ = msg->seq;
    cmd_ = c;
    ++accepted_;
    fresh_ = true;
    last_command_sim_ = sim_.time();
    last_command_wall_ = std::chrono::steady_clock::now();
    if (holding_) setHolding(false);
  }

  void reject(const std::string& why) {
    ++rejected_;
    if (rejected_ <= 5) std::fprintf(stderr, "sim: rejected %s\n", why.c_str());
  }

  void setHolding(bool h) {
    holding_ = h;
    if (h)
      std::fprintf(stderr, "sim: no command for %.2f s: holding the last one\n", o_.hold_timeout);
  }

  static sim::SimOptions simOptions(const SimCliOptions& o) {
    sim::SimOptions so;
    so.has_obstacle = !o.no_obstacle;
    so.obstacle = o.obstacle;
    return so;
  }

  void detectFall() {
    const sim::CollisionStatus c = sim_.collisions();
    if (!obstacle_contact_ && c.obstacleContact()) {
      obstacle_contact_ = true;
      std::fprintf(stderr, "sim: OBSTACLE CONTACT at t = %.3f s (%s)\n", sim_.time(),
                   c.obstacle_link.c_str());
    }
    if (fell_) return;
    const Eigen::Isometry3d X = sim_.basePose();
    const double tilt = std::acos(std::clamp(X.linear()(2, 2), -1.0, 1.0));
    if (X.translation().z() < o_.fall_height || tilt > 1.0 || c.nonFootGroundContact()) {
      fell_ = true;
      std::fprintf(stderr,
                   "sim: FALL at t = %.3f s (base height %.3f m, tilt %.2f rad, lowest non-foot "
                   "point %.3f m on %s)\n",
                   sim_.time(), X.translation().z(), tilt, c.ground_clearance,
                   c.ground_link.c_str());
    }
  }

  void publish() {
    core::RobotState st = sim_.state();
    noise_.apply(st);
    st.seq = state_seq_++;
    st.last_command_seq = last_seq_;
    overstep::robot_state_t m;
    msgs::toLcm(st, m);
    lcm_.publish("OVERSTEP_STATE", &m);
    overstep::sim_status_t s{};
    s.utime = st.utime;
    s.seq = st.seq;
    s.sim_time = sim_.time();
    s.real_time_factor = rtf_;
    s.num_contacts = sim_.contacts().contact_points;
    s.right_foot_contact = sim_.contacts().foot_contact[0];
    s.left_foot_contact = sim_.contacts().foot_contact[1];
    s.fell = fell_;
    s.obstacle_contact = obstacle_contact_;
    s.holding = holding_;
    s.rejected_commands = rejected_;
    lcm_.publish("OVERSTEP_SIM_STATUS", &s);
  }

  SimCliOptions o_;
  overstep::robot_command_t cmd_msg_;  // the last command received, decoded (onCommandBytes)
  sim::Simulator sim_;
  sim::SensorNoise noise_;
  core::StderrCapture lcm_said_;  // what liblcm prints while lcm_ opens (into the error line)
  lcm::LCM lcm_;
  int joints_;
  int steps_per_period_ = 5;
  core::RobotCommand cmd_;
  std::int64_t last_seq_ = -1, accepted_ = 0, rejected_ = 0, state_seq_ = 0;
  bool fresh_ = false, holding_ = false, fell_ = false, obstacle_contact_ = false;
  double last_command_sim_ = 0.0, rtf_ = 0.0;
  std::chrono::steady_clock::time_point last_command_wall_ = std::chrono::steady_clock::now();
  nlohmann::json summary_;
  core::RobotDescription model_desc_;
  ContactLog contact_log_;
};

int runSim(const SimCliOptions& o) {
  if (o.lockstep == o.realtime) throw InputError("choose exactly one of --lockstep and --realtime");
  if (!(o.rate >= 50.0 && o.rate <= 1000.0) ||
      std::abs(1000.0 / o.rate - std::round(1000.0 / o.rate)) > 1e-9)
    throw InputError("--rate: expected 50 to 1000 Hz with a whole number of 1 ms steps per period");
  if (!(o.noise >= 0.0 && std::isfinite(o.noise))) throw InputError("--noise: expected >= 0");
  if (!(o.hold_timeout > 0.0)) throw InputError("--hold-timeout: expected > 0 s");
  if (!(o.duration >= 0.0)) throw InputError("--duration: expected >= 0 s");
  cli::checkLcmUrl(o.lcm_url);
  SimCliOptions checked = o;
  checked.obstacle.shape = core::parseObstacleShape(o.obstacle_shape);
  if (!o.no_obstacle) core::validate(checked.obstacle);
  const robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(o.robot);
  const sim::TruthEffects truth =
      o.truth.empty() ? sim::noTruthEffects(model) : sim::loadTruth(o.truth, model);
  SimProcess p(checked, model, truth);
  const cli::StopSignals stop;
  std::fprintf(stderr, "sim: %s at %.0f Hz on %s%s\n", o.lockstep ? "lockstep" : "realtime", o.rate,
               o.lcm_url.c_str(), truth.none() ? "" : " (with truth effects)");
  const int code = p.run();
  return code;
}

}  // namespace

void registerSimCommand(CLI::App& app, cli::Registry& registry) {
  auto o = std::make_shared<SimCliOptions>();
  const char* env_url = std::getenv("LCM_DEFAULT_URL");
  o->lcm_url = env_url ? env_url : "udpm://239.255.76.67:7667?ttl=0";
  CLI::App* sub = app.add_subcommand("sim", "Run the simulated robot on LCM (DART)");
  sub->add_option("--robot", o->robot, "Robot YAML")->default_val(cli::defaultRobotPath());
  sub->add_option("--truth", o->truth,
                  "Truth effects the model does not declare (docs/truth-file.md)");
  sub->add_flag("--lockstep", o->lockstep, "Advance one control period per received command");
  sub->add_flag("--realtime", o->realtime, "Pace by the wall clock");
  sub->add_option("--rate", o->rate, "Control rate: state messages per simulated second, Hz")
      ->default_val(200.0);
  sub->add_option("--lcm-url", o->lcm_url, "LCM URL (default: $LCM_DEFAULT_URL or udpm)");
  sub->add_option("--seed", o->seed, "Sensor noise seed")->default_val(1u);
  sub->add_option("--noise", o->noise, "Sensor noise scale (0: none, 1: realistic)")
      ->default_val(1.0);
  sub->add_option("--hold-timeout", o->hold_timeout, "Seconds without a command before 'holding'")
      ->default_val(0.5);
  sub->add_option("--duration", o->duration, "Stop after this simulated time, s (0: never)")
      ->default_val(0.0);
  sub->add_flag("--json", o->json, "Print a JSON summary on exit");
  sub->add_option("--obstacle-height", o->obstacle.height, "Envelope height, m")->default_val(0.20);
  sub->add_option("--obstacle-width", o->obstacle.width, "Envelope width along x, m")
      ->default_val(0.11);
  sub->add_option("--obstacle-shape", o->obstacle_shape, "box or cylinder")->default_val("box");
  sub->add_option("--obstacle-gap", o->obstacle.gap, "From the start toes to the bar, m")
      ->default_val(0.03);
  sub->add_option("--margin", o->obstacle.margin, "Extra clearance on every side, m")
      ->default_val(0.0);
  sub->add_flag("--no-obstacle", o->no_obstacle, "No bar in the world");
  sub->add_option("--contact-log", o->contact_log,
                  "Write the ground-truth contact of every 1 ms step to this CSV (forces, centres "
                  "of pressure, contact points; not on the bus)");
  sub->footer(
      "Examples:\n"
      "  overstep sim --realtime                      # HRP-2 stand-in at 200 Hz on the default "
      "bus\n"
      "  overstep sim --lockstep --duration 10 --json # deterministic, driven by the runtime\n"
      "  overstep sim --realtime --truth truth.yaml   # with undeclared effects\n"
      "  overstep sim --lockstep --contact-log c.csv  # and the contact truth at 1 kHz\n"
      "Channels: subscribes OVERSTEP_COMMAND; publishes OVERSTEP_STATE, OVERSTEP_SIM_STATUS.\n"
      "Stops on Ctrl-C / SIGTERM (exit 0) or after --duration.");
  registry.add(sub, [o] { return runSim(*o); });
}

}  // namespace overstep
