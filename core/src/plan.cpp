#include "overstep/core/plan.hpp"

#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "overstep/core/error.hpp"
#include "overstep/core/json_depth.hpp"
#include "overstep/core/robot_description.hpp"

namespace overstep::core {
namespace {

using nlohmann::json;

json rows(const Eigen::MatrixXd& m) {  // one array per sample (column)
  json out = json::array();
  for (Eigen::Index c = 0; c < m.cols(); ++c) {
    json col = json::array();
    for (Eigen::Index r = 0; r < m.rows(); ++r) col.push_back(m(r, c));
    out.push_back(std::move(col));
  }
  return out;
}

/// Wrench columns [torque; force] -> file order [force, torque].
Eigen::MatrixXd forceFirst(const Eigen::MatrixXd& w) {
  Eigen::MatrixXd out(6, w.cols());
  out.topRows(3) = w.bottomRows(3);
  out.bottomRows(3) = w.topRows(3);
  return out;
}

std::string num(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

/// A JSON value for an error message: one line, at most 40 characters.
std::string shown(const json& v) {
  const std::string d = v.dump();
  return d.size() <= 40 ? d : d.substr(0, 37) + "...";
}

class PlanReader {
 public:
  PlanReader(std::string path, const json& root) : path_(std::move(path)), root_(root) {}

  [[noreturn]] void fail(const std::string& key, const std::string& msg) const {
    throw InputError(path_ + ": " + key + ": " + msg);
  }
  const json& need(const json& parent, const std::string& key, const std::string& where) const {
    if (!parent.is_object() || !parent.contains(key)) fail(where + key, "missing");
    return parent.at(key);
  }
  double number(const json& parent, const std::string& key, const std::string& where) const {
    const json& v = need(parent, key, where);
    if (!v.is_number()) fail(where + key, "expected a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(where + key, "expected a finite number");
    return d;
  }
  bool boolean(const json& parent, const std::string& key, const std::string& where) const {
    const json& v = need(parent, key, where);
    if (!v.is_boolean()) fail(where + key, "expected true or false, got " + shown(v));
    return v.get<bool>();
  }
  /// An integer in [0, end) (not 0.7, true or 2^32).
  int index(const json& v, const std::string& key, int end) const {
    // nlohmann-json reads a non-negative integer as unsigned, a negative one as signed.
    const bool ok = v.is_number_unsigned() && v.get<std::uint64_t>() < static_cast<unsigned>(end);
    if (!ok) fail(key, "expected an integer in [0, " + std::to_string(end) + "), got " + shown(v));
    return static_cast<int>(v.get<std::int64_t>());
  }
  std::string text(const json& parent, const std::string& key, const std::string& where) const {
    const json& v = need(parent, key, where);
    if (!v.is_string()) fail(where + key, "expected a string");
    return v.get<std::string>();
  }
  /// rows_expected x n finite numbers, each within +-bound (physical bounds far beyond any motion
  /// of the robot, which keep the model and collision libraries' arithmetic finite).
  Eigen::MatrixXd matrix(const json& samples, const std::string& key, int rows_expected, int n,
                         double bound) const {
    const json& arr = need(samples, key, "samples.");
    if (!arr.is_array() || static_cast<int>(arr.size()) != n)
      fail("samples." + key, "expected " + std::to_string(n) + " samples");
    Eigen::MatrixXd m(rows_expected, n);
    for (int c = 0; c < n; ++c) {
      const json& col = arr[static_cast<std::size_t>(c)];
      if (!col.is_array() || static_cast<int>(col.size()) != rows_expected)
        fail("samples." + key + "[" + std::to_string(c) + "]",
             "expected " + std::to_string(rows_expected) + " numbers");
      for (int r = 0; r < rows_expected; ++r) {
        const json& x = col[static_cast<std::size_t>(r)];
        const std::string at = "samples." + key + "[" + std::to_string(c) + "]";
        if (!x.is_number() || !std::isfinite(x.get<double>()))
          fail(at, "expected finite numbers, got " + shown(x));
        if (!(std::abs(x.get<double>()) <= bound))
          fail(at, "expected numbers within +-" + num(bound) + ", got " + shown(x));
        m(r, c) = x.get<double>();
      }
    }
    return m;
  }

 private:
  std::string path_;
  const json& root_;
};

}  // namespace

int jsonDepth(const std::string& text, int cap) {
  int depth = 0, deepest = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size() && deepest <= cap; ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

int Plan::sampleAt(double time, int which_phase) const {
  const int n = samples();
  if (n == 0) return -1;
  if (!(time > t(0))) return 0;  // also NaN
  const double* begin = t.data();
  // First sample at or after `time`, and the one before it: the nearer of the two.
  const int hi = static_cast<int>(std::lower_bound(begin, begin + n, time) - begin);
  if (hi >= n) return n - 1;
  int k = hi > 0 && time - t(hi - 1) < t(hi) - time ? hi - 1 : hi;
  // Samples sharing k's time (a phase switch: the planner writes them 1 us apart): the one of
  // the phase asked for, else the last.
  constexpr double kSameTime = 1e-5;
  int first = k, last = k;
  while (first > 0 && t(k) - t(first - 1) <= kSameTime) --first;
  while (last + 1 < n && t(last + 1) - t(k) <= kSameTime) ++last;
  k = last;
  if (which_phase >= 0)
    for (int i = first; i <= last; ++i)
      if (phase(i) == which_phase) k = i;
  return k;
}

Wrench Plan::wrench(int foot, int k) const {
  const Eigen::MatrixXd& w = foot == 0 ? right_wrench : left_wrench;
  const Eigen::MatrixXd& pose = foot == 0 ? right_foot : left_foot;
  return Wrench::fromSpatial(w.col(k), Axes::kWorld, pose.col(k).head<3>());
}

void Plan::setWrench(int foot, int k, const Wrench& w) {
  assert(w.axes == Axes::kWorld && "Plan::setWrench: a world-axes wrench");
  const Eigen::MatrixXd& pose = foot == 0 ? right_foot : left_foot;
  (foot == 0 ? right_wrench : left_wrench).col(k) = w.about(pose.col(k).head<3>()).spatial();
}

void Plan::resize(int n, int dofs, int actuated) {
  t.setZero(n);
  phase.setZero(n);
  q.setZero(dofs, n);
  v.setZero(dofs, n);
  a.setZero(dofs, n);
  tau.setZero(actuated, n);
  com.setZero(3, n);
  zmp_wholebody.setZero(2, n);
  zmp_tablecart.setZero(2, n);
  right_foot.setZero(7, n);
  left_foot.setZero(7, n);
  right_wrench.setZero(6, n);
  left_wrench.setZero(6, n);
}

void validatePlan(const Plan& p, const std::string& where) {
  const auto fail = [&](const std::string& key, const std::string& msg) {
    throw InputError(where + ": " + key + ": " + msg);
  };
  if (!(p.rate > 0.0 && p.rate <= Plan::kMaxRate))
    fail("rate", "expected a rate in (0, " + num(Plan::kMaxRate) + "] Hz, got " + num(p.rate));
  const int n = p.samples();
  if (n < 2) fail("samples.t", "expected at least 2 samples, got " + std::to_string(n));
  for (const Eigen::MatrixXd* m :
       {&p.q, &p.v, &p.a, &p.tau, &p.com, &p.zmp_wholebody, &p.zmp_tablecart, &p.right_foot,
        &p.left_foot, &p.right_wrench, &p.left_wrench})
    if (m->cols() != n)
      fail("samples", "expected " + std::to_string(n) + " samples in every array");
  if (p.phase.size() != n) fail("samples.phase", "expected " + std::to_string(n) + " indices");
  if (p.t(0) != 0.0) fail("samples.t[0]", "expected 0, got " + num(p.t(0)));
  const double max_step = 1.0 / p.rate + 1e-6;  // boundary samples lie between the grid's
  const auto time = [&](int k) { return "samples.t[" + std::to_string(k) + "]"; };
  for (int k = 0; k < n; ++k) {
    if (!std::isfinite(p.t(k))) fail(time(k), "expected a finite time, got " + num(p.t(k)));
    if (k > 0 && !(p.t(k) > p.t(k - 1)))
      fail(time(k), "expected increasing times, got " + num(p.t(k)) + " after " + num(p.t(k - 1)));
    if (k > 0 && !(p.t(k) - p.t(k - 1) <= max_step))
      fail(time(k), "expected samples at most 1 / rate = " + num(1.0 / p.rate) + " s apart, got " +
                        num(p.t(k)) + " after " + num(p.t(k - 1)));
  }
  if (!(p.duration() <= Plan::kMaxDuration))
    fail("samples.t", "expected a duration of at most " + num(Plan::kMaxDuration) + " s, got " +
                          num(p.duration()));
  if (p.phases.empty()) fail("phases", "expected a non-empty list");
  for (std::size_t i = 0; i < p.phases.size(); ++i) {
    const std::string key = "phases[" + std::to_string(i) + "].";
    const auto within = [&](double v, const char* name) {
      if (!(v >= 0.0 && v <= Plan::kMaxDuration))
        fail(key + name, "expected [0, " + num(Plan::kMaxDuration) + "] s, got " + num(v));
    };
    within(p.phases[i].start, "start");
    within(p.phases[i].duration, "duration");
  }
  const int phases = static_cast<int>(p.phases.size());
  for (int k = 0; k < n; ++k)
    if (p.phase(k) < 0 || p.phase(k) >= phases)
      fail("samples.phase[" + std::to_string(k) + "]",
           "expected an index into phases, got " + std::to_string(p.phase(k)));
  for (const auto& [name, foot] :
       {std::pair{"right_foot", &p.right_foot}, std::pair{"left_foot", &p.left_foot}}) {
    if (foot->rows() != 7)
      fail(std::string("samples.") + name, "expected 7 rows (x y z qw qx qy qz)");
    for (int k = 0; k < n; ++k)
      if (!(std::abs(foot->col(k).tail<4>().norm() - 1.0) <= 1e-3))
        fail(std::string("samples.") + name + "[" + std::to_string(k) + "]",
             "expected a unit quaternion, got norm " + num(foot->col(k).tail<4>().norm()));
  }
  try {
    validate(p.obstacle);
  } catch (const InputError& e) {
    throw InputError(where + ": " + e.what());
  }
  if (!(std::abs(p.toes_x) <= 100.0))
    fail("obstacle.toes_x", "expected within +-100 m, got " + num(p.toes_x));
}

void writeFileAtomic(const std::string& path, const std::string& text) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(path + ": directory does not exist");
  if (fs::is_directory(target, ec)) throw InputError(path + ": is a folder (give a file name)");
  const fs::path tmp =
      dir / ("." + target.filename().string() + ".tmp." + std::to_string(::getpid()));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path + ": cannot write (temporary file " + tmp.string() + ")");
    out << text;
    out.flush();
    if (!out) {
      fs::remove(tmp, ec);
      throw InputError(path + ": write failed");
    }
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError(path + ": cannot replace it (" + ec.message() + ")");
  }
}

void savePlan(const Plan& p, const std::string& path) {
  json j;
  j["format"] = "overstep-plan";
  j["version"] = Plan::kFormatVersion;
  j["robot"] = {{"name", p.robot_name}, {"file", p.robot_file}, {"hash", p.robot_hash}};
  j["obstacle"] = {{"shape", obstacleShapeName(p.obstacle.shape)},
                   {"height", p.obstacle.height},
                   {"width", p.obstacle.width},
                   {"length", p.obstacle.length},
                   {"gap", p.obstacle.gap},
                   {"margin", p.obstacle.margin},
                   {"toes_x", p.toes_x}};
  j["config"] = json::parse(p.config_json);
  j["summary"] = json::parse(p.summary_json);
  json phases = json::array();
  for (const auto& ph : p.phases) {
    phases.push_back({{"name", ph.name},
                      {"start", ph.start},
                      {"duration", ph.duration},
                      {"right_contact", ph.right_contact},
                      {"left_contact", ph.left_contact}});
  }
  j["phases"] = phases;
  j["rate"] = p.rate;
  j["coordinates"] = p.coordinates;
  json s;
  s["t"] = std::vector<double>(p.t.data(), p.t.data() + p.t.size());
  s["phase"] = std::vector<int>(p.phase.data(), p.phase.data() + p.phase.size());
  s["q"] = rows(p.q);
  s["v"] = rows(p.v);
  s["a"] = rows(p.a);
  s["tau"] = rows(p.tau);
  s["com"] = rows(p.com);
  s["zmp_wholebody"] = rows(p.zmp_wholebody);
  s["zmp_tablecart"] = rows(p.zmp_tablecart);
  s["right_foot"] = rows(p.right_foot);
  s["left_foot"] = rows(p.left_foot);
  s["right_wrench"] = rows(forceFirst(p.right_wrench));
  s["left_wrench"] = rows(forceFirst(p.left_wrench));
  j["samples"] = s;
  writeFileAtomic(path, j.dump() + "\n");
}

Plan loadPlan(const std::string& path) {
  const std::string text = readFile(path);
  constexpr int kMaxDepth = 16;  // a plan nests 4 deep (samples.q[k][i]), its config a few more
  if (jsonDepth(text, kMaxDepth) > kMaxDepth)
    throw InputError(path + ": JSON nested deeper than " + std::to_string(kMaxDepth) +
                     " levels: not a plan file");
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InputError(path + ": not a valid JSON plan file (parse error at byte " +
                     std::to_string(e.byte) + ")");
  } catch (const json::exception& e) {  // e.g. out_of_range: a number beyond double (1e999)
    const std::string what = e.what();  // "[json.exception.out_of_range.406] number overflow ..."
    throw InputError(path + ": not a valid JSON plan file (" + what.substr(what.find(']') + 2) +
                     ")");
  }
  PlanReader r(path, j);
  if (!j.is_object() || !j.contains("format") || j["format"] != "overstep-plan")
    r.fail("format", "expected \"overstep-plan\"");
  if (!j.contains("version") || !j["version"].is_number_integer())
    r.fail("version", "expected the integer " + std::to_string(Plan::kFormatVersion));
  if (j["version"] == 1)
    r.fail("version",
           "1 is no longer read: its torques leave out the contact forces (re-plan it with this "
           "overstep)");
  if (j["version"] != Plan::kFormatVersion)
    r.fail("version",
           "expected " + std::to_string(Plan::kFormatVersion) + ", got " + j["version"].dump());
  Plan p;
  const json& robot = r.need(j, "robot", "");
  p.robot_name = r.text(robot, "name", "robot.");
  p.robot_file = r.text(robot, "file", "robot.");
  p.robot_hash = r.text(robot, "hash", "robot.");
  const json& ob = r.need(j, "obstacle", "");
  try {
    p.obstacle.shape = parseObstacleShape(r.text(ob, "shape", "obstacle."));
  } catch (const InputError& e) {
    r.fail("obstacle.shape", e.what());
  }
  p.obstacle.height = r.number(ob, "height", "obstacle.");
  p.obstacle.width = r.number(ob, "width", "obstacle.");
  p.obstacle.length = r.number(ob, "length", "obstacle.");
  p.obstacle.gap = r.number(ob, "gap", "obstacle.");
  p.obstacle.margin = r.number(ob, "margin", "obstacle.");
  p.toes_x = r.number(ob, "toes_x", "obstacle.");
  p.config_json = j.contains("config") ? j["config"].dump() : "{}";
  p.summary_json = j.contains("summary") ? j["summary"].dump() : "{}";
  const json& phases = r.need(j, "phases", "");
  if (!phases.is_array() || phases.empty()) r.fail("phases", "expected a non-empty list");
  for (std::size_t i = 0; i < phases.size(); ++i) {
    const std::string w = "phases[" + std::to_string(i) + "].";
    PlanPhase ph;
    ph.name = r.text(phases[i], "name", w);
    ph.start = r.number(phases[i], "start", w);
    ph.duration = r.number(phases[i], "duration", w);
    ph.right_contact = r.boolean(phases[i], "right_contact", w);
    ph.left_contact = r.boolean(phases[i], "left_contact", w);
    p.phases.push_back(ph);
  }
  p.rate = r.number(j, "rate", "");
  const json& coords = r.need(j, "coordinates", "");
  if (!coords.is_array()) r.fail("coordinates", "expected a list of names");
  for (const auto& c : coords) {
    if (!c.is_string()) r.fail("coordinates", "expected names, got " + shown(c));
    p.coordinates.push_back(c.get<std::string>());
  }
  const json& s = r.need(j, "samples", "");
  const json& t = r.need(s, "t", "samples.");
  if (!t.is_array() || t.size() < 2) r.fail("samples.t", "expected at least 2 samples");
  const int n = static_cast<int>(t.size());
  const int dofs = static_cast<int>(p.coordinates.size());
  p.resize(n, dofs, 0);
  for (int k = 0; k < n; ++k) {
    const json& x = t[static_cast<std::size_t>(k)];
    if (!x.is_number() || !std::isfinite(x.get<double>()))
      r.fail("samples.t[" + std::to_string(k) + "]", "expected a finite number, got " + shown(x));
    p.t(k) = x.get<double>();
  }
  const json& ph = r.need(s, "phase", "samples.");
  if (!ph.is_array() || static_cast<int>(ph.size()) != n)
    r.fail("samples.phase", "expected " + std::to_string(n) + " phase indices");
  for (int k = 0; k < n; ++k)
    p.phase(k) =
        r.index(ph[static_cast<std::size_t>(k)], "samples.phase[" + std::to_string(k) + "]",
                static_cast<int>(p.phases.size()));
  p.q = r.matrix(s, "q", dofs, n, 1e3);  // m, rad
  p.v = r.matrix(s, "v", dofs, n, 1e4);
  p.a = r.matrix(s, "a", dofs, n, 1e6);
  const json& tau0 = r.need(s, "tau", "samples.");
  const int na =
      tau0.is_array() && !tau0.empty() && tau0[0].is_array() ? static_cast<int>(tau0[0].size()) : 0;
  p.tau = r.matrix(s, "tau", na, n, 1e6);  // N m
  p.com = r.matrix(s, "com", 3, n, 1e3);   // m
  p.zmp_wholebody = r.matrix(s, "zmp_wholebody", 2, n, 1e3);
  p.zmp_tablecart = r.matrix(s, "zmp_tablecart", 2, n, 1e3);
  p.right_foot = r.matrix(s, "right_foot", 7, n, 1e3);
  p.left_foot = r.matrix(s, "left_foot", 7, n, 1e3);
  p.right_wrench = forceFirst(r.matrix(s, "right_wrench", 6, n, 1e7));  // its own inverse
  p.left_wrench = forceFirst(r.matrix(s, "left_wrench", 6, n, 1e7));
  validatePlan(p, path);
  return p;
}

}  // namespace overstep::core
