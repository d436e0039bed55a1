#include "overstep/monitor/monitor.hpp"

#include <cmath>
#include <cstdio>

namespace overstep::monitor {

double ChannelStats::meanRate() const {
  if (count < 2 || last_recv <= first_recv) return 0.0;
  return static_cast<double>(count - 1) / (static_cast<double>(last_recv - first_recv) * 1e-6);
}

double ChannelStats::messageClockRate() const {
  if (decoded < 2 || last_utime <= first_utime) return 0.0;
  return static_cast<double>(decoded - 1) / (static_cast<double>(last_utime - first_utime) * 1e-6);
}

double ChannelStats::windowRate(std::int64_t now_us, double window) const {
  int n = 0;
  const auto w = static_cast<std::int64_t>(window * 1e6);
  for (std::int64_t t : recent)
    if (t > now_us - w && t <= now_us) ++n;
  return window > 0.0 ? n / window : 0.0;
}

const char* runtimeStateName(int state) {
  static const char* names[] = {"IDLE", "MOVING_TO_START", "RUNNING", "PAUSED", "FINISHED", "HOLD"};
  return state >= 0 && state < 6 ? names[state] : "?";
}

const char* stabilizerModeName(int mode) {
  static const char* names[] = {"OFF", "RAMP_IN", "ON", "RAMP_OUT", "HOLD"};
  return mode >= 0 && mode < 5 ? names[mode] : "?";
}

void Monitor::add(const std::string& channel, std::int64_t recv_time, const void* data, int size) {
  ChannelStats& c = channels_[channel];
  if (c.count == 0) {
    c.channel = channel;
    c.first_recv = recv_time;
  }
  ++c.count;
  c.bytes += size;
  c.last_recv = recv_time;
  c.recent.push_back(recv_time);
  while (!c.recent.empty() &&
         c.recent.front() < recv_time - static_cast<std::int64_t>(2e6 * window_))
    c.recent.pop_front();
  if (decode(data, size, scratch_) != DecodeStatus::Ok) {
    ++c.undecodable;
    return;
  }
  c.type = typeName(scratch_);
  std::int64_t utime = 0, seq = 0;
  stamp(scratch_, utime, seq);
  if (c.decoded == 0) c.first_utime = utime;
  c.last_utime = utime;
  ++c.decoded;
  if (auto* m = std::get_if<overstep::runtime_status_t>(&scratch_)) runtime_ = *m;
  if (auto* m = std::get_if<overstep::plan_reference_t>(&scratch_)) plan_ = *m;
  if (auto* m = std::get_if<overstep::stabilizer_status_t>(&scratch_)) stab_ = *m;
  if (auto* m = std::get_if<overstep::sim_status_t>(&scratch_)) sim_ = *m;
  if (auto* m = std::get_if<overstep::robot_state_t>(&scratch_)) state_ = *m;
  if (auto* m = std::get_if<overstep::robot_command_t>(&scratch_)) command_ = *m;
}

namespace {
std::string saturationNames(int mask) {
  // Bit meaning: stabilizer::Saturation (stabilizer/stabilizer.hpp).
  static const char* bits[] = {"zmp_clamped",    "foot_rotation", "foot_rotation_rate",
                               "foot_height",    "body_attitude", "com_offset",
                               "no_measured_zmp"};
  std::string s;
  for (int i = 0; i < 7; ++i)
    if (mask & (1 << i)) s += (s.empty() ? "" : ",") + std::string(bits[i]);
  return s.empty() ? "none" : s;
}
}  // namespace

nlohmann::json Monitor::snapshot(std::int64_t now, const std::string& source) const {
  nlohmann::json j;
  j["time"] = static_cast<double>(now) * 1e-6;
  j["source"] = source;
  nlohmann::json ch = nlohmann::json::object();
  for (const auto& [name, c] : channels_) {
    ch[name] = {{"type", c.type},
                {"count", c.count},
                {"undecodable", c.undecodable},
                {"bytes", c.bytes},
                {"rate_hz", c.meanRate()},
                {"window_rate_hz", c.windowRate(now, window_)},
                {"message_clock_rate_hz", c.messageClockRate()},
                {"last_age_s", static_cast<double>(now - c.last_recv) * 1e-6}};
  }
  j["channels"] = ch;
  j["runtime"] = nullptr;
  if (runtime_) {
    const auto& r = *runtime_;
    j["runtime"] = {
        {"state", runtimeStateName(r.state)},
        {"fault", r.fault_reason},
        {"tick", r.tick},
        {"plan_time", r.plan_time},
        {"rate_hz", r.rate_hz},
        {"period_us",
         {{"min", r.period_min_us},
          {"mean", r.period_mean_us},
          {"max", r.period_max_us},
          {"p99", r.period_p99_us}}},
        {"processing_us", {{"mean", r.processing_mean_us}, {"max", r.processing_max_us}}},
        {"overruns", r.overruns},
        {"missed_cycles", r.missed_cycles},
        {"late_states", r.late_states},
        {"dropped_states", r.dropped_states}};
  }
  j["plan"] = nullptr;
  if (plan_) {
    const auto& p = *plan_;
    j["plan"] = {{"time", p.plan_time},
                 {"duration", p.plan_duration},
                 {"progress", p.plan_duration > 0 ? p.plan_time / p.plan_duration : 0.0},
                 {"phase", p.phase},
                 {"phase_name", p.phase_name},
                 {"right_contact", p.right_contact != 0},
                 {"left_contact", p.left_contact != 0}};
  }
  j["stabilizer"] = nullptr;
  if (stab_) {
    const auto& s = *stab_;
    const double ex = s.zmp_measured[0] - s.zmp_reference[0];
    const double ey = s.zmp_measured[1] - s.zmp_reference[1];
    j["stabilizer"] = {{"mode", stabilizerModeName(s.mode)},
                       {"ramp", s.ramp},
                       {"fault", s.fault},
                       {"fault_reason", s.fault_reason},
                       {"saturations", s.saturations},
                       {"saturation_names", saturationNames(s.saturations)},
                       {"zmp_error", std::hypot(ex, ey)},
                       {"com_error", {s.com_error[0], s.com_error[1], s.com_error[2]}},
                       {"foot_rotation",
                        {s.right_foot_rotation[0], s.right_foot_rotation[1],
                         s.left_foot_rotation[0], s.left_foot_rotation[1]}},
                       {"body_attitude", {s.body_attitude[0], s.body_attitude[1]}}};
  }
  j["sim"] = nullptr;
  if (sim_) {
    const auto& s = *sim_;
    j["sim"] = {{"time", s.sim_time},
                {"real_time_factor", s.real_time_factor},
                {"contacts", s.num_contacts},
                {"right_foot_contact", s.right_foot_contact != 0},
                {"left_foot_contact", s.left_foot_contact != 0},
                {"fell", s.fell != 0},
                {"obstacle_contact", s.obstacle_contact != 0},
                {"holding", s.holding != 0},
                {"rejected_commands", s.rejected_commands}};
  }
  j["robot"] = nullptr;
  if (state_) {
    const auto& s = *state_;
    j["robot"] = {{"utime", s.utime},
                  {"joints", s.num_joints},
                  {"fz_right", s.ft_right[2]},
                  {"fz_left", s.ft_left[2]},
                  {"last_command_seq", s.last_command_seq}};
    if (s.has_ground_truth)
      j["robot"]["base_position"] = {s.base_position[0], s.base_position[1], s.base_position[2]};
  }
  return j;
}

std::string Monitor::render(std::int64_t now, const std::string& source) const {
  std::string out;
  char buf[256];
  auto line = [&](const char* fmt, auto... args) {
    std::snprintf(buf, sizeof buf, fmt, args...);
    out += buf;
    out += '\n';
  };
  std::int64_t start = now;
  for (const auto& kv : channels_) start = std::min(start, kv.second.first_recv);
  line("overstep monitor  %s  %.1f s since the first message", source.c_str(),
       static_cast<double>(now - start) * 1e-6);
  line("%-24s %-20s %9s %9s %9s %8s", "CHANNEL", "TYPE", "COUNT", "RATE Hz", "MSG Hz", "AGE s");
  for (const auto& [name, c] : channels_) {
    line("%-24s %-20s %9lld %9.1f %9.1f %8.2f", name.c_str(), c.type.empty() ? "?" : c.type.c_str(),
         static_cast<long long>(c.count), c.windowRate(now, window_), c.messageClockRate(),
         static_cast<double>(now - c.last_recv) * 1e-6);
  }
  if (channels_.empty()) line("(no messages yet)");
  out += '\n';
  if (runtime_) {
    const auto& r = *runtime_;
    line("runtime   %-15s tick %lld  %s%s", runtimeStateName(r.state),
         static_cast<long long>(r.tick),
         r.fault_reason.empty() ? "" : "FAULT: ", r.fault_reason.c_str());
    line("  period us: min %.0f mean %.1f max %.0f p99 %.0f   processing us: mean %.1f max %.0f",
         r.period_min_us, r.period_mean_us, r.period_max_us, r.period_p99_us, r.processing_mean_us,
         r.processing_max_us);
    line("  overruns %lld  missed %lld  late states %lld  dropped states %lld",
         static_cast<long long>(r.overruns), static_cast<long long>(r.missed_cycles),
         static_cast<long long>(r.late_states), static_cast<long long>(r.dropped_states));
  } else {
    line("runtime   (no OVERSTEP_RUNTIME yet)");
  }
  if (plan_) {
    const auto& p = *plan_;
    const double f = p.plan_duration > 0 ? std::clamp(p.plan_time / p.plan_duration, 0.0, 1.0) : 0;
    std::string bar(30, '.');
    for (int i = 0; i < static_cast<int>(f * 30.0 + 0.5); ++i)
      bar[static_cast<std::size_t>(i)] = '#';
    line("plan      %6.2f / %.2f s [%s] %-16s feet: %s %s", p.plan_time, p.plan_duration,
         bar.c_str(), p.phase_name.c_str(), p.right_contact ? "R" : "-",
         p.left_contact ? "L" : "-");
  }
  if (stab_) {
    const auto& s = *stab_;
    const double ex = s.zmp_measured[0] - s.zmp_reference[0];
    const double ey = s.zmp_measured[1] - s.zmp_reference[1];
    line("stabilizer %-8s ramp %.2f  zmp error %.1f mm  com error (%.1f, %.1f, %.1f) mm",
         stabilizerModeName(s.mode), s.ramp, 1e3 * std::hypot(ex, ey), 1e3 * s.com_error[0],
         1e3 * s.com_error[1], 1e3 * s.com_error[2]);
    line("  saturated: %s  %s%s", saturationNames(s.saturations).c_str(), s.fault ? "FAULT: " : "",
         s.fault_reason.c_str());
  }
  if (sim_) {
    const auto& s = *sim_;
    line("sim       t %.2f s  rtf %.2f  contacts %d (%s%s)  fell %s  obstacle contact %s%s",
         s.sim_time, s.real_time_factor, s.num_contacts, s.right_foot_contact ? "R" : "-",
         s.left_foot_contact ? "L" : "-", s.fell ? "YES" : "no", s.obstacle_contact ? "YES" : "no",
         s.holding ? "  HOLDING" : "");
  }
  return out;
}

}  // namespace overstep::monitor
