#include "overstep/sysid/overlay.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "overstep/core/error.hpp"

namespace overstep::sysid {
namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

double param(const Identification& r, const std::string& name) {
  const auto it = r.parameters.find(name);
  return it == r.parameters.end() ? 0.0 : it->second;
}

}  // namespace

std::string overlayYaml(const Identification& r, const core::RobotDescription& d,
                        const std::string& out_path, const std::string& source) {
  if (r.effect.empty())
    throw InputError("identify: verdict '" + r.verdict + "': no effect to add to the model");
  namespace fs = std::filesystem;
  const fs::path out_dir = fs::absolute(out_path).parent_path();
  const std::string base =
      fs::absolute(d.yaml_path).lexically_normal().lexically_relative(out_dir).string();
  std::ostringstream y;
  y << "# overstep model overlay, written by `overstep identify` (docs/model-overlay.md).\n"
    << "# Use it wherever a robot file goes: overstep plan|sim|replay|demo --robot <this file>.\n"
    << "base: " << base << "\n"
    << "identified: {effect: " << r.effect << ", verdict: " << r.verdict;
  if (!r.confusable.empty()) {
    y << ", confusable: [";
    for (std::size_t i = 0; i < r.confusable.size(); ++i) y << (i ? ", " : "") << r.confusable[i];
    y << "]";
  }
  y << ", held_out_error: [" << num(r.error_before) << ", " << num(r.error_after) << "]}\n";
  y << "# from: " << source << "\n";
  const core::ModelEffects& e = d.effects;
  if (r.effect == "payload") {
    const double m = param(r, "mass");
    const Eigen::Vector3d c(param(r, "mass*offset_x") / m, param(r, "mass*offset_y") / m,
                            param(r, "mass*offset_z") / m);
    y << "payload:\n  - {link: " << r.payload_link << ", mass: " << num(m) << ", offset: ["
      << num(c.x()) << ", " << num(c.y()) << ", " << num(c.z()) << "]}\n";
  } else if (r.effect == "command_delay" || r.effect == "command_lag") {
    const bool delay = r.effect == "command_delay";
    const double v = param(r, delay ? "delay" : "lag");
    // The position channel's servo model has no delay or lag: v is the total.
    y << "command: {delay: " << num(delay ? v : e.command_delay)
      << ", lag: " << num(delay ? e.command_lag : v) << "}\n";
  } else if (r.effect == "joint_viscous_friction" || r.effect == "joint_coulomb_friction") {
    const bool viscous = r.effect == "joint_viscous_friction";
    const std::string prefix = viscous ? "viscous[" : "coulomb[";
    y << "friction:\n";
    for (std::size_t j = 0; j < d.actuated.size(); ++j) {
      const auto& name = d.actuated[j].name;
      const auto idx = static_cast<Eigen::Index>(j);
      // Inverse dynamics has no friction: a fitted value is the total; others are kept.
      double v = viscous ? (e.viscous.size() ? e.viscous(idx) : 0.0)
                         : (e.coulomb.size() ? e.coulomb(idx) : 0.0);
      const auto it = r.parameters.find(prefix + name + "]");
      if (it != r.parameters.end()) v = std::max(it->second, 0.0);
      if (v > 0.0)
        y << "  - {joints: " << name << ", " << (viscous ? "viscous" : "coulomb") << ": " << num(v)
          << "}\n";
    }
  } else if (r.effect.rfind("ft_bias_", 0) == 0 || r.effect.rfind("ft_scale_", 0) == 0) {
    const bool left = r.effect.size() >= 4 && r.effect.substr(r.effect.size() - 4) == "left";
    const std::size_t f = left ? 1 : 0;
    core::ForceSensorModel sensor = e.ft[f];
    if (r.effect.rfind("ft_bias_", 0) == 0) {
      // Identified on calibrated readings: measured = s (true + b_new) + b_old.
      core::Wrench b = core::Wrench::zero(core::Axes::kSensor);
      b.force.z() = param(r, "fz_bias");
      b.moment.x() = param(r, "mx_bias");
      b.moment.y() = param(r, "my_bias");
      sensor.bias += sensor.scale * b;
    } else {
      sensor.scale *= 1.0 + param(r, "scale_minus_1");
    }
    const core::Vector6d bias = sensor.bias.forceMoment();
    y << "ft_sensor:\n  " << (left ? "left" : "right") << ": {bias: [";
    for (int i = 0; i < 6; ++i) y << (i ? ", " : "") << num(bias(i));
    y << "], scale: " << num(sensor.scale) << "}\n";
  } else if (r.effect == "backlash") {
    // One width for the joints whose gain is significant (recorded: no model uses it yet).
    y << "backlash:\n";
    const double width = param(r, "width");
    for (const auto& [name, v] : r.parameters) {
      if (name.rfind("gain[", 0) != 0) continue;
      const auto ci = r.ci95.find(name);
      if (v > (ci == r.ci95.end() ? 0.0 : ci->second))
        y << "  - {joints: " << name.substr(5, name.size() - 6) << ", width: " << num(width)
          << "}\n";
    }
  } else if (r.effect == "ankle_bushing") {
    // Compliance and damping changes of the roll and pitch bushings (both feet).
    y << "ankle:\n";
    for (std::size_t i = 0; i < d.elastic.size(); ++i) {
      const auto& ej = d.elastic[i];
      const bool roll = i % 2 == 0;
      const double c = 1.0 / ej.stiffness + param(r, roll ? "compliance_roll" : "compliance_pitch");
      const double damping = ej.damping + param(r, roll ? "damping_roll" : "damping_pitch");
      if (!(c > 0.0)) throw InputError("identify: the identified ankle compliance is not positive");
      y << "  " << ej.name << ": {stiffness: " << num(1.0 / c)
        << ", damping: " << num(std::max(damping, 0.0)) << "}\n";
    }
  } else {
    throw InputError("identify: effect '" + r.effect + "' has no model overlay form");
  }
  return y.str();
}

}  // namespace overstep::sysid
