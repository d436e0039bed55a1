#include "overstep/core/robot_description.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

#include "overstep/core/effects_yaml.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/yaml_reader.hpp"

namespace overstep::core {
namespace {

constexpr double kDeg = M_PI / 180.0;

using Reader = YamlReader;

}  // namespace

std::uint64_t fnv1a64(const std::string& bytes, std::uint64_t seed) {
  std::uint64_t h = seed;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

std::string readFile(const std::string& path) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(st)) throw InputError(path + ": is a folder, not a file");
  if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
    throw InputError(path + ": not a regular file");  // a FIFO or a device would block or stream
  if (!std::filesystem::is_regular_file(st)) throw InputError(path + ": no such file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot be read");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

int RobotDescription::actuatedIndex(const std::string& joint) const {
  for (std::size_t i = 0; i < actuated.size(); ++i)
    if (actuated[i].name == joint) return static_cast<int>(i);
  return -1;
}

int RobotDescription::elasticIndex(const std::string& joint) const {
  for (std::size_t i = 0; i < elastic.size(); ++i)
    if (elastic[i].name == joint) return static_cast<int>(i);
  return -1;
}

const FootDescription* RobotDescription::foot(const std::string& side) const {
  for (const auto& f : feet)
    if (f.side == side) return &f;
  return nullptr;
}

const JointGroup* RobotDescription::group(const std::string& group_name) const {
  for (const auto& g : joint_groups)
    if (g.name == group_name) return &g;
  return nullptr;
}

std::string RobotDescription::hashHex() const {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(content_hash));
  return buf;
}

namespace {

RobotDescription loadRobotDescriptionAt(const std::string& yaml_path, int depth);

/// A list of joint names (or one name) -> actuated indices.
std::vector<int> jointList(const YAML::Node& n, const std::string& key, const Reader& r,
                           const RobotDescription& d) {
  std::vector<std::string> names;
  if (n.IsScalar()) {
    names.push_back(n.as<std::string>());
  } else if (n.IsSequence()) {
    for (const auto& x : n) names.push_back(r.as<std::string>(x, key));
  } else {
    r.fail(key, "expected a joint name or a list of them");
  }
  std::vector<int> out;
  for (const auto& nm : names) {
    const int j = d.actuatedIndex(nm);
    if (j < 0) r.fail(key, "unknown joint '" + nm + "'");
    out.push_back(j);
  }
  return out;
}

RobotDescription loadOverlay(const std::string& yaml_path, const std::string& text,
                             const YAML::Node& root, int depth) {
  const Reader r(yaml_path);
  r.onlyKeys(root, "",
             {"base", "identified", "ankle", "friction", "payload", "command", "ft_sensor"});
  std::filesystem::path bp(r.as<std::string>(root["base"], "base"));
  if (bp.is_relative()) bp = std::filesystem::path(yaml_path).parent_path() / bp;
  if (depth > 4) r.fail("base", "overlays nested more than 4 deep");
  RobotDescription d = loadRobotDescriptionAt(bp.lexically_normal().string(), depth + 1);
  d.base_yaml = d.yaml_path;
  d.yaml_path = yaml_path;
  ModelEffects& e = d.effects;
  if (const YAML::Node a = root["ankle"]) {
    std::vector<double> k, c;
    for (const auto& ej : d.elastic) {
      k.push_back(ej.stiffness);
      c.push_back(ej.damping);
    }
    parseAnkles(a, r, d, k, c);
    for (std::size_t i = 0; i < d.elastic.size(); ++i) {
      d.elastic[i].stiffness = k[i];
      d.elastic[i].damping = c[i];
    }
  }
  if (const YAML::Node f = root["friction"]) {
    if (!f.IsSequence()) r.fail("friction", "expected a list of {joints, viscous, coulomb}");
    const auto n = static_cast<Eigen::Index>(d.actuated.size());
    e.viscous.setZero(n);
    e.coulomb.setZero(n);
    for (std::size_t k = 0; k < f.size(); ++k) {
      const std::string key = "friction[" + std::to_string(k) + "]";
      r.onlyKeys(f[k], key, {"joints", "viscous", "coulomb"});
      if (!f[k]["joints"]) r.fail(key, "missing 'joints'");
      for (int j : jointList(f[k]["joints"], key + ".joints", r, d)) {
        if (f[k]["viscous"]) e.viscous(j) = r.valueAtLeast(f[k]["viscous"], key + ".viscous", 0.0);
        if (f[k]["coulomb"]) e.coulomb(j) = r.valueAtLeast(f[k]["coulomb"], key + ".coulomb", 0.0);
      }
    }
  }
  if (const YAML::Node b = root["backlash"]) {
    if (!b.IsSequence()) r.fail("backlash", "expected a list of {joints, width}");
    e.backlash.setZero(static_cast<Eigen::Index>(d.actuated.size()));
    for (std::size_t k = 0; k < b.size(); ++k) {
      const std::string key = "backlash[" + std::to_string(k) + "]";
      r.onlyKeys(b[k], key, {"joints", "width"});
      if (!b[k]["joints"] || !b[k]["width"]) r.fail(key, "needs 'joints' and 'width' (rad)");
      const double w = r.valueAtLeast(b[k]["width"], key + ".width", 0.0);
      if (w > 0.1) r.fail(key + ".width", "expected <= 0.1 rad");
      for (int j : jointList(b[k]["joints"], key + ".joints", r, d)) e.backlash(j) = w;
    }
  }
  if (const YAML::Node p = root["payload"]) {
    const auto more = parsePayloads(p, r);
    e.payloads.insert(e.payloads.end(), more.begin(), more.end());
  }
  if (const YAML::Node c = root["command"])
    parseCommandTiming(c, r, e.command_delay, e.command_lag);
  if (const YAML::Node f = root["ft_sensor"]) {
    parseForceSensors(f, r, e.ft);
    for (int i = 0; i < 2; ++i)
      if (std::abs(e.ft[static_cast<std::size_t>(i)].scale - 1.0) > 0.5)
        r.fail(std::string("ft_sensor.") + (i == 0 ? "right" : "left") + ".scale",
               "expected 0.5 .. 1.5");
  }
  d.content_hash = fnv1a64(text, d.content_hash);
  return d;
}

}  // namespace

RobotDescription loadRobotDescription(const std::string& yaml_path) {
  return guardYaml(yaml_path, [&] { return loadRobotDescriptionAt(yaml_path, 0); });
}

namespace {

/// `self_collision:` a list of [link, link] pairs, each link carrying a capsule.
void parseSelfCollision(const YAML::Node& root, const Reader& r, RobotDescription& d) {
  const YAML::Node sc = root["self_collision"];
  if (!sc) return;
  if (!sc.IsSequence()) r.fail("self_collision", "expected a list of [link, link] pairs");
  for (std::size_t i = 0; i < sc.size(); ++i) {
    const std::string w = "self_collision[" + std::to_string(i) + "]";
    if (!sc[i].IsSequence() || sc[i].size() != 2) r.fail(w, "expected [link, link]");
    const auto a = r.as<std::string>(sc[i][0], w), b = r.as<std::string>(sc[i][1], w);
    for (const std::string& l : {a, b}) {
      const bool has = std::any_of(d.capsules.begin(), d.capsules.end(),
                                   [&](const CapsuleDescription& c) { return c.link == l; });
      if (!has) r.fail(w, "link '" + l + "' has no capsule");
    }
    if (a == b) r.fail(w, "a link paired with itself ('" + a + "')");
    d.self_collision.emplace_back(a, b);
  }
}

/// `joint_groups:` a map from a group's name to its actuated joints.
void parseJointGroups(const YAML::Node& root, const Reader& r, RobotDescription& d) {
  const YAML::Node jg = root["joint_groups"];
  if (!jg) return;
  if (!jg.IsMap()) r.fail("joint_groups", "expected a map: group name -> list of joints");
  for (const auto& kv : jg) {
    JointGroup g;
    g.name = r.as<std::string>(kv.first, "joint_groups");
    const std::string w = "joint_groups." + g.name;
    if (g.name == "all") r.fail(w, "'all' is reserved (every actuated joint)");
    if (!kv.second.IsSequence() || kv.second.size() == 0) r.fail(w, "expected a list of joints");
    for (const auto& j : kv.second) {
      const auto name = r.as<std::string>(j, w);
      const int a = d.actuatedIndex(name);
      if (a < 0) r.fail(w, "unknown actuated joint '" + name + "'");
      if (std::find(g.joints.begin(), g.joints.end(), a) != g.joints.end())
        r.fail(w, "joint '" + name + "' listed twice");
      g.joints.push_back(a);
    }
    d.joint_groups.push_back(std::move(g));
  }
}

/// `excitation:` the joints the identification excitation swings.
void parseExcitation(const YAML::Node& root, const Reader& r, RobotDescription& d) {
  const YAML::Node ex = root["excitation"];
  if (!ex) return;
  if (!ex.IsSequence()) r.fail("excitation", "expected a list");
  for (std::size_t i = 0; i < ex.size(); ++i) {
    const std::string w = "excitation[" + std::to_string(i) + "]";
    ExcitationJoint e;
    e.joint = r.as<std::string>(r.need(ex[i], "joint", w), w + ".joint");
    if (d.actuatedIndex(e.joint) < 0)
      r.fail(w + ".joint", "unknown actuated joint '" + e.joint + "'");
    e.amplitude = r.positive(ex[i], "amplitude", w);
    e.frequency = r.positive(ex[i], "frequency", w);
    e.phase = r.number(ex[i], "phase", w);
    if (e.amplitude > 1.0)
      r.fail(w + ".amplitude", "expected <= 1 rad, got " + Reader::fmt(e.amplitude));
    if (e.frequency > 10.0)
      r.fail(w + ".frequency", "expected <= 10 Hz, got " + Reader::fmt(e.frequency));
    d.excitation.push_back(e);
  }
}

RobotDescription loadRobotDescriptionAt(const std::string& yaml_path, int depth) {
  const std::string text = readFile(yaml_path);  // parsed and hashed
  YAML::Node root = YamlReader::parse(text, yaml_path);
  Reader r(yaml_path);
  if (!root.IsMap()) throw InputError(yaml_path + ": expected a YAML map at the top level");
  if (root["base"]) return loadOverlay(yaml_path, text, root, depth);

  RobotDescription d;
  d.yaml_path = yaml_path;
  d.robot_yaml = yaml_path;
  d.name = r.as<std::string>(r.need(root, "name", ""), "name");
  const std::string urdf = r.as<std::string>(r.need(root, "urdf", ""), "urdf");
  std::filesystem::path up(urdf);
  if (up.is_relative()) up = std::filesystem::path(yaml_path).parent_path() / up;
  d.urdf_path = up.lexically_normal().string();
  d.base_link = r.as<std::string>(r.need(root, "base_link", ""), "base_link");
  d.floating_base =
      root["floating_base"] ? r.as<bool>(root["floating_base"], "floating_base") : true;
  d.gravity = r.numberOr(root, "gravity", "", 9.81);
  if (!(d.gravity > 0.0 && d.gravity <= 100.0))
    r.fail("gravity", "expected 0 < gravity <= 100 m/s^2, got " + Reader::fmt(d.gravity));
  d.acceleration_limit = r.numberOr(root, "acceleration_limit", "", 30.0);
  if (!(d.acceleration_limit > 0.0))
    r.fail("acceleration_limit", "expected > 0 rad/s^2, got " + Reader::fmt(d.acceleration_limit));

  const YAML::Node joints = r.need(root, "actuated_joints", "");
  if (!joints.IsSequence()) r.fail("actuated_joints", "expected a list");
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const std::string w = "actuated_joints[" + std::to_string(i) + "]";
    const YAML::Node j = joints[i];
    ActuatedJoint a;
    a.name = r.as<std::string>(r.need(j, "name", w), w + ".name");
    const YAML::Node lim = r.need(j, "limits_deg", w);
    if (!lim.IsSequence() || lim.size() != 2) r.fail(w + ".limits_deg", "expected [lower, upper]");
    a.lower = r.value(lim[0], w + ".limits_deg") * kDeg;  // finite: no .inf, no .nan
    a.upper = r.value(lim[1], w + ".limits_deg") * kDeg;
    if (!(a.lower < a.upper))
      r.fail(w + ".limits_deg", "expected lower < upper, got [" + Reader::fmt(a.lower / kDeg) +
                                    ", " + Reader::fmt(a.upper / kDeg) + "]");
    a.safety_margin = r.nonNegative(j, "safety_margin_deg", w) * kDeg;
    if (!(a.safeLower() < a.safeUpper()))
      r.fail(w + ".safety_margin_deg", "margin leaves no range inside the limits");
    a.velocity = r.positive(j, "velocity", w);
    a.torque = r.positive(j, "torque", w);
    a.gear_ratio = r.positive(j, "gear_ratio", w);
    a.rotor_inertia = r.nonNegative(j, "rotor_inertia", w);
    if (d.actuatedIndex(a.name) >= 0) r.fail(w + ".name", "duplicate joint '" + a.name + "'");
    d.actuated.push_back(a);
  }

  if (const YAML::Node el = root["elastic_joints"]) {
    if (!el.IsSequence()) r.fail("elastic_joints", "expected a list");
    for (std::size_t i = 0; i < el.size(); ++i) {
      const std::string w = "elastic_joints[" + std::to_string(i) + "]";
      ElasticJoint e;
      e.name = r.as<std::string>(r.need(el[i], "name", w), w + ".name");
      e.stiffness = r.nonNegative(el[i], "stiffness", w);
      e.damping = r.nonNegative(el[i], "damping", w);
      if (d.elasticIndex(e.name) >= 0 || d.actuatedIndex(e.name) >= 0)
        r.fail(w + ".name", "duplicate joint '" + e.name + "'");
      d.elastic.push_back(e);
    }
  }

  if (const YAML::Node bv = root["bushing_vertical"]) {
    if (!bv.IsMap()) r.fail("bushing_vertical", "expected {stiffness, damping}");
    d.bushing_vertical_stiffness = r.nonNegative(bv, "stiffness", "bushing_vertical");
    d.bushing_vertical_damping = r.nonNegative(bv, "damping", "bushing_vertical");
    // Below 1e3 N/m a 60 kg robot would sink by more than half a metre; above 1e6 the
    // simulator's explicit spring on a 1 kg foot is no longer stable at 1 ms (k dt^2 / m <= 1).
    if (d.bushing_vertical_stiffness != 0.0 &&
        !(d.bushing_vertical_stiffness >= 1e3 && d.bushing_vertical_stiffness <= 1e6))
      r.fail("bushing_vertical.stiffness", "expected 0 (rigid) or 1e3 to 1e6 N/m, got " +
                                               Reader::fmt(d.bushing_vertical_stiffness));
    if (!(d.bushing_vertical_damping <= 1e4))
      r.fail("bushing_vertical.damping",
             "expected 0 to 1e4 N s/m, got " + Reader::fmt(d.bushing_vertical_damping));
  }

  if (const YAML::Node fr = root["frames"]) {
    if (!fr.IsSequence()) r.fail("frames", "expected a list");
    for (std::size_t i = 0; i < fr.size(); ++i) {
      const std::string w = "frames[" + std::to_string(i) + "]";
      FrameDescription f;
      f.name = r.as<std::string>(r.need(fr[i], "name", w), w + ".name");
      f.link = r.as<std::string>(r.need(fr[i], "link", w), w + ".link");
      const Eigen::Vector3d xyz = r.vec3(fr[i], "xyz", w);
      const Eigen::Vector3d rpy = fr[i]["rpy"] ? r.vec3(fr[i], "rpy", w) : Eigen::Vector3d::Zero();
      f.X_LF.linear() = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                         Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                            .toRotationMatrix();
      f.X_LF.translation() = xyz;
      for (const auto& o : d.frames)
        if (o.name == f.name) r.fail(w + ".name", "duplicate frame '" + f.name + "'");
      d.frames.push_back(f);
    }
  }
  auto hasFrame = [&d](const std::string& n) {
    for (const auto& f : d.frames)
      if (f.name == n) return true;
    return false;
  };

  const YAML::Node feet = root["feet"];
  if (!feet && d.floating_base)
    r.fail("feet", "missing key (a floating-base robot stands on a right and a left foot)");
  if (feet) {
    for (const char* side : {"right", "left"}) {
      const std::string w = std::string("feet.") + side;
      const YAML::Node f = r.need(feet, side, "feet");
      FootDescription fd;
      fd.side = side;
      fd.link = r.as<std::string>(r.need(f, "link", w), w + ".link");
      fd.sole_frame = r.as<std::string>(r.need(f, "sole_frame", w), w + ".sole_frame");
      fd.force_sensor_frame =
          r.as<std::string>(r.need(f, "force_sensor_frame", w), w + ".force_sensor_frame");
      for (const auto& fn : {fd.sole_frame, fd.force_sensor_frame})
        if (!hasFrame(fn)) r.fail(w, "names frame '" + fn + "', which 'frames' does not define");
      const YAML::Node s = r.need(f, "sole", w);
      fd.sole.x_front = r.positive(s, "x_front", w + ".sole");
      fd.sole.x_back = r.positive(s, "x_back", w + ".sole");
      fd.sole.y_outer = r.positive(s, "y_outer", w + ".sole");
      fd.sole.y_inner = r.positive(s, "y_inner", w + ".sole");
      d.feet.push_back(fd);
    }
  }

  if (const YAML::Node caps = root["capsules"]) {
    if (!caps.IsSequence()) r.fail("capsules", "expected a list");
    for (std::size_t i = 0; i < caps.size(); ++i) {
      const std::string w = "capsules[" + std::to_string(i) + "]";
      CapsuleDescription c;
      c.link = r.as<std::string>(r.need(caps[i], "link", w), w + ".link");
      c.p0 = r.vec3(caps[i], "p0", w);
      c.p1 = r.vec3(caps[i], "p1", w);
      c.radius = r.positive(caps[i], "radius", w);
      d.capsules.push_back(c);
    }
  }

  parseSelfCollision(root, r, d);
  parseJointGroups(root, r, d);
  parseExcitation(root, r, d);

  d.half_sitting = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(d.actuated.size()));
  if (const YAML::Node hs = root["half_sitting_deg"]) {
    if (!hs.IsSequence() || hs.size() != d.actuated.size())
      r.fail("half_sitting_deg", "expected " + std::to_string(d.actuated.size()) +
                                     " angles (one per actuated joint), got " +
                                     std::to_string(hs.IsSequence() ? hs.size() : 0));
    for (std::size_t i = 0; i < hs.size(); ++i) {
      const double v = r.as<double>(hs[i], "half_sitting_deg") * kDeg;
      const auto& a = d.actuated[i];
      if (!(v >= a.lower && v <= a.upper))
        r.fail("half_sitting_deg[" + std::to_string(i) + "]",
               "angle of " + a.name + " outside its limits, got " + Reader::fmt(v / kDeg) + " deg");
      d.half_sitting(static_cast<Eigen::Index>(i)) = v;
    }
  }

  d.content_hash =
      fnv1a64(readFile(d.urdf_path),
              fnv1a64(withoutSection(
                  withoutSection(withoutSection(withoutSection(text, "stabilizer"), "joint_groups"),
                                 "excitation"),
                  "bushing_vertical")));
  return d;
}

}  // namespace

std::string withoutSection(const std::string& yaml, const std::string& key) {
  std::string out;
  bool skipping = false;
  std::size_t pos = 0;
  while (pos < yaml.size()) {
    std::size_t end = yaml.find('\n', pos);
    end = end == std::string::npos ? yaml.size() : end + 1;
    const std::string_view line(yaml.data() + pos, end - pos);
    // A top-level key starts a section; indented, blank and comment lines continue one.
    const bool top = !line.empty() && line[0] != ' ' && line[0] != '\t' && line[0] != '#' &&
                     line[0] != '\n' && line[0] != '\r';
    if (top) skipping = line.substr(0, key.size() + 1) == key + ":";
    if (!skipping) out.append(line);
    pos = end;
  }
  return out;
}

std::vector<PayloadDescription> parsePayloads(const YAML::Node& p, const YamlReader& r) {
  if (!p.IsSequence()) r.fail("payload", "expected a list of {link, mass, offset}");
  std::vector<PayloadDescription> out;
  for (std::size_t k = 0; k < p.size(); ++k) {
    const std::string key = "payload[" + std::to_string(k) + "]";
    r.onlyKeys(p[k], key, {"link", "mass", "offset"});
    if (!p[k]["link"] || !p[k]["mass"]) r.fail(key, "needs 'link' and 'mass'");
    PayloadDescription pl;
    pl.link = r.as<std::string>(p[k]["link"], key + ".link");
    pl.mass = r.positiveValue(p[k]["mass"], key + ".mass");
    if (const YAML::Node o = p[k]["offset"]) {
      pl.offset = r.vector<3>(o, key + ".offset");
      if (pl.offset.cwiseAbs().maxCoeff() > 1.0) r.fail(key + ".offset", "expected |x| <= 1 m");
    }
    out.push_back(pl);
  }
  return out;
}

void parseAnkles(const YAML::Node& a, const YamlReader& r, const RobotDescription& d,
                 std::vector<double>& stiffness, std::vector<double>& damping) {
  if (!a.IsMap()) r.fail("ankle", "expected a map from elastic joint name to {stiffness, damping}");
  for (const auto& kv : a) {
    const std::string name = kv.first.as<std::string>();
    const int i = d.elasticIndex(name);
    const std::string key = "ankle." + name;
    if (i < 0) r.fail(key, "unknown elastic joint");
    r.onlyKeys(kv.second, key, {"stiffness", "damping"});
    if (kv.second["stiffness"])
      stiffness[static_cast<std::size_t>(i)] =
          r.positiveValue(kv.second["stiffness"], key + ".stiffness");
    if (kv.second["damping"])
      damping[static_cast<std::size_t>(i)] =
          r.valueAtLeast(kv.second["damping"], key + ".damping", 0.0);
  }
}

void parseCommandTiming(const YAML::Node& c, const YamlReader& r, double& delay, double& lag) {
  r.onlyKeys(c, "command", {"delay", "lag"});
  if (c["delay"]) delay = r.valueAtLeast(c["delay"], "command.delay", 0.0);
  if (c["lag"]) lag = r.valueAtLeast(c["lag"], "command.lag", 0.0);
  if (delay > 1.0 || lag > 1.0) r.fail("command", "expected <= 1 s");
}

void parseForceSensors(const YAML::Node& f, const YamlReader& r,
                       std::array<ForceSensorModel, 2>& sensors) {
  r.onlyKeys(f, "ft_sensor", {"right", "left"});
  for (int i = 0; i < 2; ++i) {
    const char* side = i == 0 ? "right" : "left";
    const YAML::Node s = f[side];
    if (!s) continue;
    const std::string key = std::string("ft_sensor.") + side;
    r.onlyKeys(s, key, {"bias", "scale"});
    ForceSensorModel& sensor = sensors[static_cast<std::size_t>(i)];
    if (s["bias"])
      sensor.bias = Wrench::fromForceMoment(r.vector<6>(s["bias"], key + ".bias"), Axes::kSensor);
    if (s["scale"]) sensor.scale = r.positiveValue(s["scale"], key + ".scale");
  }
}

}  // namespace overstep::core
