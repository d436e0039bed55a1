#include "overstep/sim/truth.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include "overstep/core/effects_yaml.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/yaml_reader.hpp"

namespace overstep::sim {
namespace {

using Reader = core::YamlReader;

/// Actuated joint indices named by a group (the robot file's joint_groups, or all), a joint name,
/// or a list of these.
std::vector<int> jointsOf(const YAML::Node& n, const std::string& key, const Reader& r,
                          const core::RobotDescription& d) {
  std::vector<std::string> names;
  if (n.IsSequence()) {
    for (const auto& e : n) names.push_back(e.as<std::string>());
  } else {
    names.push_back(n.as<std::string>());
  }
  std::set<int> out;
  for (const auto& name : names) {
    if (name == "all") {
      for (std::size_t i = 0; i < d.actuated.size(); ++i) out.insert(static_cast<int>(i));
    } else if (const core::JointGroup* g = d.group(name)) {
      out.insert(g->joints.begin(), g->joints.end());
    } else if (const int i = d.actuatedIndex(name); i >= 0) {
      out.insert(i);
    } else {
      std::string groups;
      for (const auto& gr : d.joint_groups) groups += gr.name + ", ";
      r.fail(key, "unknown joint or group '" + name + "' (groups: " + groups + "all)");
    }
  }
  return {out.begin(), out.end()};
}

}  // namespace

bool TruthEffects::none() const {
  return !elastic_changed && viscous.isZero() && coulomb.isZero() && backlash.isZero() &&
         payloads.empty() && command_delay == 0.0 && command_lag == 0.0 && ft[0].isIdentity() &&
         ft[1].isIdentity() && bends.empty();
}

std::string TruthEffects::describe() const {
  std::ostringstream s;
  for (std::size_t i = 0; elastic_changed && i < elastic_stiffness.size(); ++i)
    s << "elastic[" << i << "]: k " << elastic_stiffness[i] << " N m/rad, d " << elastic_damping[i]
      << " N m s/rad\n";
  if (!viscous.isZero() || !coulomb.isZero())
    s << "joint friction: max viscous " << viscous.maxCoeff() << " N m s/rad, max Coulomb "
      << coulomb.maxCoeff() << " N m\n";
  if (!backlash.isZero()) s << "backlash: max " << backlash.maxCoeff() << " rad\n";
  for (const auto& p : payloads)
    s << "payload: " << p.mass << " kg on " << p.link << " at [" << p.offset.transpose() << "] m\n";
  for (const auto& b : bends)
    s << "bend: " << b.link << " rotated by [" << b.rotation.transpose() << "] rad\n";
  if (command_delay > 0.0 || command_lag > 0.0)
    s << "command: delay " << command_delay << " s, lag " << command_lag << " s\n";
  for (std::size_t f = 0; f < 2; ++f)
    if (!ft[f].isIdentity())
      s << (f == 0 ? "right" : "left") << " F/T: scale " << ft[f].scale << ", bias [F; M] ["
        << ft[f].bias.forceMoment().transpose() << "]\n";
  return s.str();
}

TruthEffects noTruthEffects(const robots::WholeBodyModel& model) {
  const auto& d = model.description();
  TruthEffects t;
  for (const auto& e : d.elastic) {
    t.elastic_stiffness.push_back(e.stiffness);
    t.elastic_damping.push_back(e.damping);
  }
  const auto n = static_cast<Eigen::Index>(d.actuated.size());
  t.viscous.setZero(n);
  t.coulomb.setZero(n);
  t.backlash.setZero(n);
  return t;
}

static TruthEffects loadTruthFile(const std::string& path, const robots::WholeBodyModel& model) {
  YAML::Node root = core::YamlReader::loadFile(path);
  const Reader r(path);
  TruthEffects t = noTruthEffects(model);
  if (root.IsNull()) return t;
  const auto& d = model.description();
  r.onlyKeys(root, "",
             {"ankle", "friction", "payload", "command", "ft_sensor", "backlash", "bend"});
  if (const YAML::Node b = root["bend"]) {
    if (!b.IsSequence()) r.fail("bend", "expected a list of {link, rotation}");
    for (std::size_t k = 0; k < b.size(); ++k) {
      const std::string key = "bend[" + std::to_string(k) + "]";
      r.onlyKeys(b[k], key, {"link", "rotation"});
      if (!b[k]["link"] || !b[k]["rotation"]) r.fail(key, "needs 'link' and 'rotation' (rad)");
      Bend bend;
      bend.link = r.as<std::string>(b[k]["link"], key + ".link");
      if (!model.hasFrame(bend.link)) r.fail(key + ".link", "unknown link '" + bend.link + "'");
      bend.rotation = r.vector<3>(b[k]["rotation"], key + ".rotation");
      if (bend.rotation.norm() > 0.2) r.fail(key + ".rotation", "expected |rotation| <= 0.2 rad");
      t.bends.push_back(bend);
    }
  }

  if (const YAML::Node a = root["ankle"]) {
    core::parseAnkles(a, r, d, t.elastic_stiffness, t.elastic_damping);
    for (std::size_t i = 0; i < d.elastic.size(); ++i)
      t.elastic_changed = t.elastic_changed || t.elastic_stiffness[i] != d.elastic[i].stiffness ||
                          t.elastic_damping[i] != d.elastic[i].damping;
  }
  // A list of {joints: <joint, group or list>, <fields>}; `allowed` includes "joints".
  auto perJoint = [&](const char* section, std::initializer_list<const char*> allowed,
                      auto&& apply) {
    const YAML::Node s = root[section];
    if (!s) return;
    if (!s.IsSequence()) r.fail(section, "expected a list of {joints: ..., ...}");
    for (std::size_t k = 0; k < s.size(); ++k) {
      const std::string key = std::string(section) + "[" + std::to_string(k) + "]";
      r.onlyKeys(s[k], key, allowed);
      if (!s[k]["joints"]) r.fail(key, "missing 'joints' (a joint, a group or a list)");
      apply(s[k], key, jointsOf(s[k]["joints"], key + ".joints", r, d));
    }
  };
  perJoint("friction", {"joints", "viscous", "coulomb"},
           [&](const YAML::Node& n, const std::string& key, const std::vector<int>& js) {
             for (int j : js) {
               if (n["viscous"]) t.viscous(j) = r.valueAtLeast(n["viscous"], key + ".viscous", 0.0);
               if (n["coulomb"]) t.coulomb(j) = r.valueAtLeast(n["coulomb"], key + ".coulomb", 0.0);
             }
           });
  perJoint("backlash", {"joints", "width"},
           [&](const YAML::Node& n, const std::string& key, const std::vector<int>& js) {
             if (!n["width"]) r.fail(key, "missing 'width' (rad)");
             const double w = r.valueAtLeast(n["width"], key + ".width", 0.0);
             if (w > 0.1) r.fail(key + ".width", "expected <= 0.1 rad");
             for (int j : js) t.backlash(j) = w;
           });
  if (const YAML::Node p = root["payload"]) {
    t.payloads = core::parsePayloads(p, r);
    for (std::size_t k = 0; k < t.payloads.size(); ++k)
      if (!model.hasFrame(t.payloads[k].link))
        r.fail("payload[" + std::to_string(k) + "].link",
               "unknown link '" + t.payloads[k].link + "'");
  }
  if (const YAML::Node c = root["command"])
    core::parseCommandTiming(c, r, t.command_delay, t.command_lag);
  if (const YAML::Node f = root["ft_sensor"]) core::parseForceSensors(f, r, t.ft);
  return t;
}

TruthEffects loadTruth(const std::string& path, const robots::WholeBodyModel& model) {
  return core::guardYaml(path, [&] { return loadTruthFile(path, model); });
}

}  // namespace overstep::sim
