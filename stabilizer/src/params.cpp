#include "overstep/stabilizer/params.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <sstream>

#include "overstep/core/error.hpp"
#include "overstep/core/robot_description.hpp"
#include "overstep/core/yaml_reader.hpp"

namespace overstep::stabilizer {
namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

const std::array<ParamSpec, 33>& paramTable() {
  // Safety ranges: wide enough for any sane tuning, narrow enough to refuse typos (a gain 1000x
  // off, a sign error, a limit that would let the feet rotate by more than 20 degrees).
  static const std::array<ParamSpec, 33> table{{
      {"zmp_delay", &Params::zmp_delay, 0.005, 0.2, "s"},
      {"dcm_kp", &Params::dcm_kp, 0.0, 20.0, "1/s"},
      {"dcm_ki", &Params::dcm_ki, 0.0, 100.0, "1/s^2"},
      {"dcm_integral_time", &Params::dcm_integral_time, 0.1, 100.0, "s"},
      {"zmp_feedforward", &Params::zmp_feedforward, 0.0, 1.0, ""},
      {"cop_margin", &Params::cop_margin, 0.0, 0.05, "m"},
      {"min_ds_force", &Params::min_ds_force, 0.0, 200.0, "N"},
      {"contact_force", &Params::contact_force, 1.0, 300.0, "N"},
      {"damping_roll", &Params::damping_roll, 5.0, 1e4, "N m s/rad"},
      {"damping_pitch", &Params::damping_pitch, 5.0, 1e4, "N m s/rad"},
      {"damping_time_constant", &Params::damping_time_constant, 0.05, 100.0, "s"},
      {"swing_time_constant", &Params::swing_time_constant, 0.01, 10.0, "s"},
      {"max_foot_rotation", &Params::max_foot_rotation, 0.0, 0.35, "rad"},
      {"max_foot_rotation_rate", &Params::max_foot_rotation_rate, 0.0, 2.0, "rad/s"},
      {"force_difference_gain", &Params::force_difference_gain, 0.0, 1e-2, "m/(N s)"},
      {"force_difference_time_constant", &Params::force_difference_time_constant, 0.05, 100.0, "s"},
      {"max_foot_height", &Params::max_foot_height, 0.0, 0.05, "m"},
      {"landing_damping", &Params::landing_damping, 0.0, 1e6, "N s/m"},
      {"landing_time", &Params::landing_time, 0.0, 2.0, "s"},
      {"landing_time_constant", &Params::landing_time_constant, 0.01, 100.0, "s"},
      {"max_landing_rate", &Params::max_landing_rate, 0.0, 1.0, "m/s"},
      {"landing_search_depth", &Params::landing_search_depth, 0.0, 0.02, "m"},
      {"posture_gain", &Params::posture_gain, 0.0, 10.0, "1/s"},
      {"posture_time_constant", &Params::posture_time_constant, 0.05, 100.0, "s"},
      {"max_body_attitude", &Params::max_body_attitude, 0.0, 0.3, "rad"},
      {"com_admittance", &Params::com_admittance, 0.0, 50.0, "1/s^2"},
      {"com_leak_time", &Params::com_leak_time, 0.05, 100.0, "s"},
      {"max_com_offset", &Params::max_com_offset, 0.0, 0.1, "m"},
      {"ramp_time", &Params::ramp_time, 0.01, 10.0, "s"},
      {"max_com_error", &Params::max_com_error, 0.01, 0.5, "m"},
      {"max_torso_tilt", &Params::max_torso_tilt, 0.05, 1.5, "rad"},
      {"max_dt", &Params::max_dt, 1e-4, 0.2, "s"},
      {"gravity", &Params::gravity, 1.0, 20.0, "m/s^2"},
  }};
  return table;
}

std::string validate(const Params& p) {
  for (const auto& s : paramTable()) {
    const double v = p.*(s.field);
    if (!(v >= s.min && v <= s.max))
      return std::string("stabilizer.") + s.key + ": expected " + fmt(s.min) + " to " + fmt(s.max) +
             " " + s.unit + ", got " + fmt(v);
  }
  for (int i = 0; i < 3; ++i) {
    const double l = p.lipm_poles[static_cast<std::size_t>(i)];
    if (!(l >= 0.1 && l <= 100.0))
      return "stabilizer.lipm_poles: expected decay rates in 0.1 to 100 1/s, got " + fmt(l);
  }
  if (!(p.mass > 0.0 && p.mass < 1000.0))
    return "stabilizer mass: expected 0 to 1000 kg (set it from the robot model), got " +
           fmt(p.mass);
  for (const auto& s : p.sole)
    if (!(s.x_min < s.x_max && s.y_min < s.y_max && s.x_min <= 0.0 && s.x_max >= 0.0 &&
          s.y_min <= 0.0 && s.y_max >= 0.0 && s.x_min > -1.0 && s.x_max < 1.0 && s.y_min > -1.0 &&
          s.y_max < 1.0))  // finite: an infinite sole passed (issue 20)
      return "stabilizer sole: expected a rectangle around the sole origin, within 1 m";
  return {};
}

Params loadParams(const std::string& robot_yaml) {
  const core::RobotDescription d = core::loadRobotDescription(robot_yaml);
  Params p;
  p.gravity = d.gravity;
  for (int f = 0; f < 2; ++f) {
    const core::FootDescription* foot = d.foot(f == 0 ? "right" : "left");
    if (!foot)
      throw InputError(robot_yaml + ": feet: the stabilizer needs a right and a left foot");
    auto& s = p.sole[static_cast<std::size_t>(f)];
    s.x_min = -foot->sole.x_back;
    s.x_max = foot->sole.x_front;
    s.y_min = foot->yMin();
    s.y_max = foot->yMax();
  }
  // An overlay (docs/model-overlay.md) holds no stabilizer section: the gains are the robot's.
  const YAML::Node root = core::YamlReader::loadFile(d.robot_yaml);
  const core::YamlReader r(d.robot_yaml);
  if (const YAML::Node st = root["stabilizer"]) {
    if (!st.IsMap()) r.fail("stabilizer", "expected a map");
    for (const auto& kv : st) {
      const std::string key = kv.first.as<std::string>();
      const std::string where = "stabilizer." + key;
      if (key == "feedback") {
        const std::string v = r.as<std::string>(kv.second, where);
        if (v != "lipm" && v != "dcm") r.fail(where, "expected lipm or dcm, got '" + v + "'");
        p.feedback = v == "lipm" ? Feedback::Lipm : Feedback::Dcm;
        continue;
      }
      if (key == "zmp_reference") {
        const std::string v = r.as<std::string>(kv.second, where);
        if (v != "tablecart" && v != "wholebody")
          r.fail(where, "expected tablecart or wholebody, got '" + v + "'");
        p.zmp_reference = v == "tablecart" ? ZmpReference::TableCart : ZmpReference::WholeBody;
        continue;
      }
      if (key == "lipm_poles") {
        const Eigen::Vector3d l = r.vector<3>(kv.second, where);
        p.lipm_poles = {l(0), l(1), l(2)};
        continue;
      }
      const ParamSpec* spec = nullptr;
      for (const auto& s : paramTable())
        if (key == s.key && key != "gravity") spec = &s;
      if (!spec) r.fail(where, "unknown parameter (see stabilizer/README.md)");
      p.*(spec->field) = r.value(kv.second, where);
    }
  }
  Params check = p;
  check.mass = 1.0;  // set by the caller
  const std::string err = validate(check);
  if (!err.empty()) throw InputError(robot_yaml + ": " + err);
  return p;
}

std::array<double, 3> gainsFromPoles(const std::array<double, 3>& l, double omega, double tp) {
  // Closed loop of e = (dc, dcd, dp): dcdd = w^2 (dc - dp), dpd = (k1 dc + k2 dcd + k3 dp - dp) /
  // Tp. Characteristic polynomial s^3 + (1 - k3)/Tp s^2 + w^2 (k2/Tp - 1) s + w^2 (k1 + k3 - 1)/Tp
  // matched to (s + l1)(s + l2)(s + l3) = s^3 + c2 s^2 + c1 s + c0.
  const double c2 = l[0] + l[1] + l[2];
  const double c1 = l[0] * l[1] + l[0] * l[2] + l[1] * l[2];
  const double c0 = l[0] * l[1] * l[2];
  const double w2 = omega * omega;
  return {tp * (c0 / w2 + c2), tp * (1.0 + c1 / w2), 1.0 - tp * c2};
}

}  // namespace overstep::stabilizer
