#include <string>

#include "overstep/demo/demo.hpp"

namespace overstep::demo {

using nlohmann::json;

namespace {

/// A number from a child's summary; `fallback` when absent or not a number.
double number(const json& j, const char* key, double fallback) {
  return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : fallback;
}

bool flag(const json& j, const char* key, bool fallback) {
  return j.is_object() && j.contains(key) && j[key].is_boolean() ? j[key].get<bool>() : fallback;
}

std::string text(const json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : "";
}

}  // namespace

json runVerdict(const RunReports& in) {
  const json& r = in.replay;
  const json& s = in.sim;
  const bool fell = flag(s, "fell", true);
  const bool contact = flag(s, "obstacle_contact", true);
  const bool finished = flag(r, "finished", false);
  const bool has_bar = s.is_object() && s.contains("obstacle_x") && s["obstacle_x"].is_array() &&
                       s["obstacle_x"].size() == 2 && s["obstacle_x"][1].is_number();
  const double far_x = has_bar ? s["obstacle_x"][1].get<double>() : 1e9;
  const bool beyond =
      number(s, "right_heel_x", -1e9) > far_x && number(s, "left_heel_x", -1e9) > far_x;
  const bool still = number(s, "base_speed", 1e9) < 0.02;
  json v;
  v["cleared"] = finished && !fell && !contact && beyond && still;
  v["fell"] = fell;
  v["obstacle_contact"] = contact;
  v["finished"] = finished;
  v["feet_beyond_obstacle"] = beyond;
  v["static_at_end"] = still;
  v["plan_valid"] = in.plan_valid;
  v["plan_duration"] = in.plan_duration;
  v["duration"] = number(r, "executed_duration", 0.0);
  v["tracking_rms"] = number(r, "tracking_rms", 0.0);
  v["cop_max"] = r.is_object() && r.contains("cop_max") ? r["cop_max"] : json::object();
  v["torso_deviation_max"] = number(r, "torso_deviation_max", 0.0);
  v["stabilizer_effort"] = number(r, "stabilizer_effort", 0.0);
  v["stabilizer"] = in.stabilizer;
  v["runtime_state"] = text(r, "state");
  v["runtime_fault"] = text(r, "fault");
  v["fidelity"] = in.fidelity;
  return v;
}

}  // namespace overstep::demo
