#pragma once
/// \file
/// Validating reads from a YAML document with one-line errors "FILE: KEY: what was expected, got
/// what" (InputError). Shared by every loader of a YAML file (robot description, planner
/// configuration, stabilizer parameters, truth effects) so that they word their errors alike.

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <set>
#include <string>
#include <type_traits>

#include "overstep/core/error.hpp"
#include "overstep/core/robot_description.hpp"

namespace overstep::core {

class YamlReader {
 public:
  explicit YamlReader(std::string file) : file_(std::move(file)) {}

  const std::string& file() const { return file_; }

  /// Reads and parses a whole YAML file; a missing file or malformed YAML is an InputError
  /// naming the file (and the line).
  static YAML::Node loadFile(const std::string& path) { return parse(readFile(path), path); }
  /// Parses YAML text read from `path` (named in the error). A key given twice in a map is
  /// refused (yaml-cpp keeps both and every reader would take the first), and so is a key that is
  /// not a plain scalar.
  static YAML::Node parse(const std::string& text, const std::string& path) {
    YAML::Node root;
    try {
      root = YAML::Load(text);
    } catch (const YAML::Exception& e) {
      throw InputError(path + ": malformed YAML at line " + std::to_string(e.mark.line + 1) + ": " +
                       e.msg);
    }
    std::size_t budget = text.size() + 1;  // nodes: more only through aliases (billion laughs)
    refuseDuplicateKeys(root, path, "", budget);
    return root;
  }

  [[noreturn]] void fail(const std::string& key, const std::string& msg) const {
    throw InputError(file_ + ": " + key + ": " + msg);
  }

  /// Child `name` of `node`; fails with "missing key" when absent. `where` prefixes the key.
  YAML::Node need(const YAML::Node& node, const std::string& name, const std::string& where) const {
    // yaml-cpp throws BadSubscript for a key looked up in a scalar (found by fuzz_robot).
    if (!node.IsMap()) fail(where.empty() ? name : where, "expected a map");
    YAML::Node child = node[name];
    if (!child) fail(join(where, name), "missing key");
    return child;
  }

  /// Fails on any key of `map` not in `allowed` (and when `map` is not a map).
  void onlyKeys(const YAML::Node& map, const std::string& where,
                std::initializer_list<const char*> allowed) const {
    if (!map.IsMap()) fail(where.empty() ? std::string("(top level)") : where, "expected a map");
    for (const auto& kv : map) {
      const std::string k = kv.first.as<std::string>();
      bool ok = false;
      for (const char* a : allowed) ok = ok || k == a;
      if (!ok) fail(join(where, k), "unknown key");
    }
  }

  template <typename T>
  T as(const YAML::Node& node, const std::string& key) const {
    try {
      return node.as<T>();
    } catch (const YAML::Exception&) {
      fail(key, "expected a " + typeName<T>() + ", got '" + scalarText(node) + "'");
    }
  }

  /// The largest magnitude of any number in our YAML files: far beyond every quantity of a robot,
  /// a planner or a simulation in SI units (the largest in the shipped files is 1e4), far below
  /// where sums and products overflow (issue 20: 1e308 reached DART's and FCL's assertions).
  static constexpr double kMaxMagnitude = 1e9;

  /// A finite number of magnitude at most kMaxMagnitude held by `node` itself.
  double value(const YAML::Node& node, const std::string& key) const {
    const double v = as<double>(node, key);
    if (!std::isfinite(v)) fail(key, "expected a finite number, got " + fmt(v));
    if (std::abs(v) > kMaxMagnitude)
      fail(key, "expected a magnitude of at most " + fmt(kMaxMagnitude) + ", got " + fmt(v));
    return v;
  }
  double valueAtLeast(const YAML::Node& node, const std::string& key, double min) const {
    const double v = value(node, key);
    if (v < min) fail(key, "expected >= " + fmt(min) + ", got " + fmt(v));
    return v;
  }
  double positiveValue(const YAML::Node& node, const std::string& key) const {
    const double v = value(node, key);
    if (!(v > 0.0)) fail(key, "expected > 0, got " + fmt(v));
    return v;
  }

  /// The same, for child `name` of `parent` (required).
  double number(const YAML::Node& parent, const std::string& name, const std::string& where) const {
    return value(need(parent, name, where), join(where, name));
  }
  double numberOr(const YAML::Node& parent, const std::string& name, const std::string& where,
                  double fallback) const {
    return parent.IsMap() && parent[name] ? number(parent, name, where) : fallback;
  }
  double nonNegative(const YAML::Node& parent, const std::string& name,
                     const std::string& where) const {
    return valueAtLeast(need(parent, name, where), join(where, name), 0.0);
  }
  double positive(const YAML::Node& parent, const std::string& name,
                  const std::string& where) const {
    return positiveValue(need(parent, name, where), join(where, name));
  }

  /// A list of N finite numbers.
  template <int N>
  Eigen::Matrix<double, N, 1> vector(const YAML::Node& n, const std::string& key) const {
    if (!n.IsSequence() || n.size() != static_cast<std::size_t>(N))
      fail(key, "expected a list of " + std::to_string(N) + " numbers");
    Eigen::Matrix<double, N, 1> v;
    for (int i = 0; i < N; ++i) v(i) = value(n[static_cast<std::size_t>(i)], key);
    return v;
  }
  Eigen::Vector3d vec3(const YAML::Node& parent, const std::string& name,
                       const std::string& where) const {
    return vector<3>(need(parent, name, where), join(where, name));
  }

  static std::string fmt(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
  }
  static std::string join(const std::string& where, const std::string& name) {
    return where.empty() ? name : where + "." + name;
  }
  static void refuseDuplicateKeys(const YAML::Node& n, const std::string& path,
                                  const std::string& where, std::size_t& budget) {
    if (budget-- == 0)
      throw InputError(path + ": YAML aliases expand to more nodes than it has bytes");
    if (n.IsSequence())
      for (std::size_t i = 0; i < n.size(); ++i)
        refuseDuplicateKeys(n[i], path, where + "[" + std::to_string(i) + "]", budget);
    if (!n.IsMap()) return;
    std::set<std::string> seen;
    for (const auto& kv : n) {
      const std::string key = join(where, scalarText(kv.first));
      // Every reader takes keys as strings: a list, map or null as a key threw yaml-cpp's
      // TypedBadConversion, an "internal error" (found by tests/fuzz/fuzz_robot).
      if (!kv.first.IsScalar()) throw InputError(path + ": " + key + ": expected a plain key");
      if (!seen.insert(kv.first.Scalar()).second)
        throw InputError(path + ": " + key + ": duplicate key (again at line " +
                         std::to_string(kv.first.Mark().line + 1) + ")");
      refuseDuplicateKeys(kv.second, path, key, budget);
    }
  }
  static std::string scalarText(const YAML::Node& n) {
    if (n.IsScalar()) return n.Scalar();
    if (n.IsSequence()) return "<list>";
    if (n.IsMap()) return "<map>";
    return "<null>";
  }

 private:
  template <typename T>
  static std::string typeName() {
    if constexpr (std::is_same_v<T, double> || std::is_same_v<T, int>) return "number";
    if constexpr (std::is_same_v<T, bool>) return "boolean";
    return "string";
  }
  std::string file_;
};

/// Runs `load` (a YAML file's reader), turning a yaml-cpp exception that escaped the typed
/// reads (e.g. a key looked up in a scalar or a list entry: BadSubscript) into a one-line
/// InputError naming the file and the line.
template <typename F>
auto guardYaml(const std::string& path, F&& load) -> decltype(load()) {
  try {
    return load();
  } catch (const YAML::Exception& e) {
    throw InputError(path + ": line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

}  // namespace overstep::core
