#include "overstep/planner/config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
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
      "elastic_acc",    "elastic_vel",    "elastic_pos",      "lin_mom_z",
      "lin_mom_z_rate", "ang_mom_z_rate", "contact_torque_z", "zmp_lipm",
      "time",           "head",           "torque_rate",      "ds_leg_tracking"};
  return names;
}

const std::vector<ConfigEntry>& configTable() {
  using C = PlannerConfig;
  // key, unit, accepted range (inclusive; a lower bound of 0 with `open_low` excludes it), field.
  static const std::vector<ConfigEntry> table = {
      {"start_half_width", "m", 1e-3, 0.5, false, &C::start_half_width,
       "|y| of the start soles (where the robot stands)"},
      {"step_length_min", "m", 0.0, 2.0, true, &C::step_length_min, "shortest step along x"},
      {"step_length_max", "m", 0.0, 2.0, true, &C::step_length_max, "longest step along x"},
      {"foot_y_min", "m", 0.0, 0.5, true, &C::foot_y_min, "smallest |y| of a landed sole"},
      {"foot_y_max", "m", 0.0, 0.5, true, &C::foot_y_max, "largest |y| of a landed sole"},
      {"guess_step_length", "m", 0.0, 2.0, true, &C::guess_step_length, "initial guess: step"},
      {"guess_half_width", "m", 0.0, 0.5, true, &C::guess_half_width, "initial guess: landing |y|"},
      {"guess_reach_margin", "m", 0.0, 0.3, false, &C::guess_reach_margin,
       "initial guess: legs short of leg_reach by this"},
      {"guess_swing_clearance", "m", 0.0, 0.5, false, &C::guess_swing_clearance,
       "initial guess: sole above the obstacle top"},
      {"cop_box", "m", 0.0, 0.2, true, &C::cop_box, "side of each stance foot's CoP square"},
      {"friction", "", 0.0, 2.0, true, &C::friction, "Coulomb coefficient (pyramid)"},
      {"torsion", "m", 0.0, 0.2, true, &C::torsion, "|Mz| <= torsion * Fz"},
      {"min_normal_force", "N", 0.0, 1000.0, false, &C::min_normal_force,
       "least normal force of a foot in contact"},
      {"swing_clearance", "m", 0.0, 0.3, false, &C::swing_clearance,
       "peak of the swing sole's smooth minimal height"},
      {"obstacle_clearance", "m", 0.0, 0.3, false, &C::obstacle_clearance,
       "smallest capsule-obstacle distance"},
      {"self_clearance", "m", 0.0, 0.3, false, &C::self_clearance,
       "smallest distance of checked capsule pairs"},
      {"pelvis_tilt", "rad", 0.0, 0.5, true, &C::pelvis_tilt, "|roll|, |pitch| of the pelvis"},
      {"leg_reach", "m", 0.0, 2.0, true, &C::leg_reach,
       "hip-ankle distance bound of the double-support leg"},
      {"smooth_min_rho", "1/m", 10.0, 1e5, false, &C::smooth_min_rho,
       "sharpness of the smooth minimum over distances"},
      {"limit_margin", "", 0.0, 1.0, true, &C::limit_margin,
       "fraction of CoP box, friction, torsion, pelvis range enforced at the samples"},
      {"pelvis_margin", "", 0.0, 1.0, true, &C::pelvis_margin,
       "fraction of the pelvis range enforced in the last stage"},
      {"ds_balance_band", "N m", 0.0, 100.0, true, &C::ds_balance_band,
       "double-support sway balance band"},
      {"swept_clearance", "", 0.0, 2.0, false, &C::swept_clearance,
       "capsule distances minus this x speed x half the sample interval"},
      {"velocity_margin", "", 0.0, 1.0, true, &C::velocity_margin,
       "fraction of the joint velocity limits enforced at the samples"},
      {"height_homotopy_step", "m", 0.0, 1.0, true, &C::height_homotopy_step,
       "obstacle height steps toward the target"},
      {"head_pitch_offset", "rad", -1.0, 1.0, false, &C::head_pitch_offset,
       "head pitch the head objective aims at"},
  };
  return table;
}

std::string PlannerConfig::toJson() const {
  nlohmann::json j;
  j["samples_per_phase"] = samples_per_phase;
  j["spline_intervals"] = spline_intervals;
  j["flex_spline_intervals"] = flex_spline_intervals;
  j["duration_min"] = duration_min;
  j["duration_max"] = duration_max;
  j["duration_guess"] = duration_guess;
  for (const auto& e : configTable()) j[e.key] = this->*e.field;
  j["cop_homotopy"] = cop_homotopy;
  j["passive_polish"] = passive_polish;
  j["weights"] = weights;
  j["solver"] = {{"algorithm", solver.algorithm},
                 {"max_iterations", solver.max_iterations},
                 {"constraint_tolerance", solver.constraint_tolerance},
                 {"ftol_rel", solver.ftol_rel},
                 {"time_limit", solver.time_limit},
                 {"threads", solver.threads}};
  return j.dump();
}

static PlannerConfig loadPlannerConfigFile(const std::string& path) {
  YAML::Node root = core::YamlReader::loadFile(path);
  PlannerConfig c;
  if (root.IsNull()) return c;
  if (!root.IsMap()) throw InputError(path + ": expected a YAML map at the top level");
  ConfigReader r(path);
  auto inRange = [&](const YAML::Node& v, const std::string& key, double lo, double hi,
                     bool open_low) {
    const double x = r.value(v, key);
    if (x < lo || x > hi || (open_low && x == lo)) {
      char b[96];
      std::snprintf(b, sizeof b, "expected %s %g and <= %g, got %g", open_low ? ">" : ">=", lo, hi,
                    x);
      r.fail(key, b);
    }
    return x;
  };
  std::set<std::string> seen;
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    const YAML::Node& v = kv.second;
    if (!seen.insert(key).second) r.fail(key, "given twice");
    const auto entry = std::find_if(configTable().begin(), configTable().end(),
                                    [&](const ConfigEntry& e) { return key == e.key; });
    if (entry != configTable().end()) {
      c.*(entry->field) = inRange(v, key, entry->lo, entry->hi, entry->open_low);
    } else if (key == "samples_per_phase" || key == "spline_intervals" ||
               key == "flex_spline_intervals") {
      auto& out = key == "samples_per_phase"  ? c.samples_per_phase
                  : key == "spline_intervals" ? c.spline_intervals
                                              : c.flex_spline_intervals;
      out = r.perPhase<int>(v, key);
      for (int n : out)
        if (n > 200) r.fail(key, "expected at most 200 per phase, got " + std::to_string(n));
    } else if (key == "passive_polish") {
      c.passive_polish = r.as<bool>(v, key);
    } else if (key == "duration_min") {
      c.duration_min = r.perPhase<double>(v, key);
    } else if (key == "duration_max") {
      c.duration_max = r.perPhase<double>(v, key);
    } else if (key == "duration_guess") {
      c.duration_guess = r.perPhase<double>(v, key);
    } else if (key == "cop_homotopy") {
      if (!v.IsSequence() || v.size() > 10) r.fail(key, "expected a list of up to 10 box sizes");
      c.cop_homotopy.clear();
      for (std::size_t i = 0; i < v.size(); ++i)
        c.cop_homotopy.push_back(inRange(v[i], key, 0.0, 0.2, true));
    } else if (key == "weights") {
      if (!v.IsMap()) r.fail(key, "expected a map of term -> weight");
      for (const auto& w : v) {
        const std::string name = w.first.as<std::string>();
        if (!c.weights.count(name)) r.fail("weights." + name, "unknown objective term");
        c.weights[name] = inRange(w.second, "weights." + name, 0.0, 1e6, false);
      }
    } else if (key == "solver") {
      if (!v.IsMap()) r.fail(key, "expected a map");
      for (const auto& s : v) {
        const std::string name = s.first.as<std::string>();
        const std::string k = "solver." + name;
        if (name == "algorithm") {
          c.solver.algorithm = r.as<std::string>(s.second, k);
        } else if (name == "max_iterations") {
          c.solver.max_iterations = static_cast<int>(inRange(s.second, k, 1.0, 1e5, false));
        } else if (name == "constraint_tolerance") {
          c.solver.constraint_tolerance = inRange(s.second, k, 0.0, 1.0, true);
        } else if (name == "ftol_rel") {
          c.solver.ftol_rel = inRange(s.second, k, 0.0, 1.0, true);
        } else if (name == "time_limit") {
          c.solver.time_limit = inRange(s.second, k, 0.0, 86400.0, true);
        } else if (name == "threads") {
          c.solver.threads = static_cast<int>(inRange(s.second, k, 1.0, 64.0, false));
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
    if (c.duration_max[u] > 60.0) r.fail("duration_max", "expected at most 60 s per phase");
  }
  if (!(c.step_length_min < c.step_length_max)) r.fail("step_length_min", "expected < max");
  if (!(c.foot_y_min < c.foot_y_max)) r.fail("foot_y_min", "expected < foot_y_max");
  return c;
}

PlannerConfig loadPlannerConfig(const std::string& path) {
  return core::guardYaml(path, [&] { return loadPlannerConfigFile(path); });
}

}  // namespace overstep::planner
