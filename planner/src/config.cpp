#include "overstep/planner/config.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "overstep/core/error.hpp"
#include "overstep/core/robot_description.hpp"
#include "overstep/core/yaml_reader.hpp"

namespace overstep::planner {
namespace {

/// The shared YAML reader plus per-phase lists.
class ConfigReader : public core::YamlReader {
 public:
  using core::YamlReader::YamlReader;
  template <typename T>
  std::array<T, kPhaseCount> perPhase(const YAML::Node& n, const std::string& key) const {
    if (!n.IsSequence() || n.size() != kPhaseCount)
      fail(key, "expected a list of " + std::to_string(kPhaseCount) + " values (one per phase)");
    std::array<T, kPhaseCount> out{};
    for (int i = 0; i < kPhaseCount; ++i) {
      const double v = positiveValue(n[i], key);
      if constexpr (std::is_same_v<T, int>) {
        if (v != std::floor(v)) fail(key, "expected whole numbers");
        out[static_cast<std::size_t>(i)] = static_cast<int>(v);
      } else {
        out[static_cast<std::size_t>(i)] = v;
      }
    }
    return out;
  }
};

}  // namespace

const std::array<const char*, kObjectiveTerms>& objectiveTermNames() {
  static const std::array<const char*, kObjectiveTerms> names = {
      "elastic_acc",    "elastic_vel",      "elastic_pos", "lin_mom_z", "lin_mom_z_rate",
      "ang_mom_z_rate", "contact_torque_z", "zmp_lipm",    "time",      "head",
      "torque_rate",    "ds_leg_tracking",  "jerk_jump"};
  return names;
}

std::string PlannerConfig::toJson() const {
  nlohmann::json j;
  j["samples_per_phase"] = samples_per_phase;
  j["spline_intervals"] = spline_intervals;
  j["spline_degree"] = spline_degree;
  j["duration_min"] = duration_min;
  j["duration_max"] = duration_max;
  j["duration_guess"] = duration_guess;
  j["start_half_width"] = start_half_width;
  j["step_length_min"] = step_length_min;
  j["step_length_max"] = step_length_max;
  j["foot_y_min"] = foot_y_min;
  j["foot_y_max"] = foot_y_max;
  j["cop_box"] = cop_box;
  j["cop_homotopy"] = cop_homotopy;
  j["friction"] = friction;
  j["torsion"] = torsion;
  j["min_normal_force"] = min_normal_force;
  j["swing_clearance"] = swing_clearance;
  j["obstacle_clearance"] = obstacle_clearance;
  j["swept_clearance"] = swept_clearance;
  j["passive_polish"] = passive_polish;
  j["approach_samples"] = approach_samples;
  j["transfer_anchor"] = transfer_anchor;
  j["velocity_margin"] = velocity_margin;
  j["self_clearance"] = self_clearance;
  j["pelvis_tilt"] = pelvis_tilt;
  j["leg_reach"] = leg_reach;
  j["limit_margin"] = limit_margin;
  j["pelvis_margin"] = pelvis_margin;
  j["ds_balance_band"] = ds_balance_band;
  j["weights"] = weights;
  j["head_pitch_offset"] = head_pitch_offset;
  j["solver"] = {{"algorithm", solver.algorithm},
                 {"max_iterations", solver.max_iterations},
                 {"constraint_tolerance", solver.constraint_tolerance},
                 {"ftol_rel", solver.ftol_rel},
                 {"time_limit", solver.time_limit},
                 {"threads", solver.threads},
                 {"trust_radius", solver.trust_radius},
                 {"round_iterations", solver.round_iterations}};
  return j.dump();
}

PlannerConfig loadPlannerConfig(const std::string& path) {
  YAML::Node root = core::YamlReader::loadFile(path);
  PlannerConfig c;
  if (root.IsNull()) return c;
  if (!root.IsMap()) throw InputError(path + ": expected a YAML map at the top level");
  ConfigReader r(path);
  const std::set<std::string> scalars = {"start_half_width",
                                         "step_length_min",
                                         "step_length_max",
                                         "foot_y_min",
                                         "foot_y_max",
                                         "guess_step_length",
                                         "guess_half_width",
                                         "guess_pelvis_drop",
                                         "guess_swing_clearance",
                                         "cop_box",
                                         "friction",
                                         "torsion",
                                         "min_normal_force",
                                         "swing_clearance",
                                         "obstacle_clearance",
                                         "self_clearance",
                                         "pelvis_tilt",
                                         "leg_reach",
                                         "smooth_min_rho",
                                         "height_homotopy_step",
                                         "head_pitch_offset",
                                         "limit_margin",
                                         "pelvis_margin",
                                         "ds_balance_band",
                                         "swept_clearance",
                                         "passive_polish",
                                         "approach_samples",
                                         "velocity_margin"};
  std::map<std::string, double*> fields = {{"start_half_width", &c.start_half_width},
                                           {"step_length_min", &c.step_length_min},
                                           {"step_length_max", &c.step_length_max},
                                           {"foot_y_min", &c.foot_y_min},
                                           {"foot_y_max", &c.foot_y_max},
                                           {"guess_step_length", &c.guess_step_length},
                                           {"guess_half_width", &c.guess_half_width},
                                           {"guess_pelvis_drop", &c.guess_pelvis_drop},
                                           {"guess_swing_clearance", &c.guess_swing_clearance},
                                           {"cop_box", &c.cop_box},
                                           {"friction", &c.friction},
                                           {"torsion", &c.torsion},
                                           {"min_normal_force", &c.min_normal_force},
                                           {"swing_clearance", &c.swing_clearance},
                                           {"obstacle_clearance", &c.obstacle_clearance},
                                           {"self_clearance", &c.self_clearance},
                                           {"pelvis_tilt", &c.pelvis_tilt},
                                           {"leg_reach", &c.leg_reach},
                                           {"smooth_min_rho", &c.smooth_min_rho},
                                           {"height_homotopy_step", &c.height_homotopy_step},
                                           {"head_pitch_offset", &c.head_pitch_offset},
                                           {"limit_margin", &c.limit_margin},
                                           {"pelvis_margin", &c.pelvis_margin},
                                           {"ds_balance_band", &c.ds_balance_band},
                                           {"swept_clearance", &c.swept_clearance},
                                           {"passive_polish", &c.passive_polish},
                                           {"approach_samples", &c.approach_samples},
                                           {"velocity_margin", &c.velocity_margin}};
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    const YAML::Node& v = kv.second;
    if (scalars.count(key)) {
      *fields.at(key) = key == "head_pitch_offset" ? r.value(v, key)
                        : key == "ds_balance_band" || key == "swept_clearance" ||
                                key == "passive_polish" || key == "approach_samples"
                            ? r.valueAtLeast(v, key, 0.0)
                            : r.positiveValue(v, key);
    } else if (key == "samples_per_phase") {
      c.samples_per_phase = r.perPhase<int>(v, key);
    } else if (key == "spline_intervals") {
      c.spline_intervals = r.perPhase<int>(v, key);
    } else if (key == "transfer_anchor") {
      c.transfer_anchor = v.as<std::string>();
      if (c.transfer_anchor != "right" && c.transfer_anchor != "left")
        r.fail(key, "expected right or left");
    } else if (key == "spline_degree") {
      c.spline_degree = r.as<int>(v, key);
      if (c.spline_degree != 3 && c.spline_degree != 5) r.fail(key, "expected 3 or 5");
    } else if (key == "duration_min") {
      c.duration_min = r.perPhase<double>(v, key);
    } else if (key == "duration_max") {
      c.duration_max = r.perPhase<double>(v, key);
    } else if (key == "duration_guess") {
      c.duration_guess = r.perPhase<double>(v, key);
    } else if (key == "cop_homotopy") {
      if (!v.IsSequence()) r.fail(key, "expected a list of box sizes");
      c.cop_homotopy.clear();
      for (std::size_t i = 0; i < v.size(); ++i)
        c.cop_homotopy.push_back(r.positiveValue(v[i], key));
    } else if (key == "weights") {
      if (!v.IsMap()) r.fail(key, "expected a map of term -> weight");
      for (const auto& w : v) {
        const std::string name = w.first.as<std::string>();
        if (!c.weights.count(name)) r.fail("weights." + name, "unknown objective term");
        const double x = r.value(w.second, "weights." + name);
        if (x < 0.0) r.fail("weights." + name, "expected >= 0");
        c.weights[name] = x;
      }
    } else if (key == "solver") {
      if (!v.IsMap()) r.fail(key, "expected a map");
      for (const auto& s : v) {
        const std::string name = s.first.as<std::string>();
        const std::string k = "solver." + name;
        if (name == "algorithm") {
          c.solver.algorithm = s.second.as<std::string>();
        } else if (name == "max_iterations") {
          c.solver.max_iterations = static_cast<int>(r.positiveValue(s.second, k));
        } else if (name == "constraint_tolerance") {
          c.solver.constraint_tolerance = r.positiveValue(s.second, k);
        } else if (name == "ftol_rel") {
          c.solver.ftol_rel = r.positiveValue(s.second, k);
        } else if (name == "time_limit") {
          c.solver.time_limit = r.positiveValue(s.second, k);
        } else if (name == "threads") {
          c.solver.threads = static_cast<int>(r.positiveValue(s.second, k));
        } else if (name == "trust_radius") {
          c.solver.trust_radius = r.value(s.second, k);
          if (c.solver.trust_radius < 0.0) r.fail(k, "expected >= 0 (0: off)");
        } else if (name == "round_iterations") {
          c.solver.round_iterations = static_cast<int>(r.positiveValue(s.second, k));
        } else {
          r.fail(k, "unknown key");
        }
      }
    } else {
      r.fail(key, "unknown key");
    }
  }
  for (int i = 0; i < kPhaseCount; ++i) {
    const auto u = static_cast<std::size_t>(i);
    if (!(c.duration_min[u] <= c.duration_guess[u] && c.duration_guess[u] <= c.duration_max[u]))
      r.fail("duration_guess", "expected duration_min <= duration_guess <= duration_max");
  }
  if (!(c.step_length_min < c.step_length_max)) r.fail("step_length_min", "expected < max");
  if (!(c.foot_y_min < c.foot_y_max)) r.fail("foot_y_min", "expected < foot_y_max");
  if (c.limit_margin > 1.0) r.fail("limit_margin", "expected a fraction in (0, 1]");
  if (c.pelvis_margin > 1.0) r.fail("pelvis_margin", "expected a fraction in (0, 1]");
  return c;
}

}  // namespace overstep::planner
