#include "overstep/core/plan.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "overstep/core/error.hpp"
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
  std::string text(const json& parent, const std::string& key, const std::string& where) const {
    const json& v = need(parent, key, where);
    if (!v.is_string()) fail(where + key, "expected a string");
    return v.get<std::string>();
  }
  Eigen::MatrixXd matrix(const json& samples, const std::string& key, int rows_expected,
                         int n) const {
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
        if (!x.is_number() || !std::isfinite(x.get<double>()))
          fail("samples." + key + "[" + std::to_string(c) + "]", "expected finite numbers");
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

void writeFileAtomic(const std::string& path, const std::string& text) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(path + ": directory does not exist");
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
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InputError(path + ": not a valid JSON plan file (parse error at byte " +
                     std::to_string(e.byte) + ")");
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
    ph.right_contact = r.need(phases[i], "right_contact", w).get<bool>();
    ph.left_contact = r.need(phases[i], "left_contact", w).get<bool>();
    p.phases.push_back(ph);
  }
  p.rate = r.number(j, "rate", "");
  if (!(p.rate > 0.0)) r.fail("rate", "expected > 0");
  const json& coords = r.need(j, "coordinates", "");
  if (!coords.is_array()) r.fail("coordinates", "expected a list of names");
  for (const auto& c : coords) p.coordinates.push_back(c.get<std::string>());
  const json& s = r.need(j, "samples", "");
  const json& t = r.need(s, "t", "samples.");
  if (!t.is_array() || t.size() < 2) r.fail("samples.t", "expected at least 2 samples");
  const int n = static_cast<int>(t.size());
  const int dofs = static_cast<int>(p.coordinates.size());
  p.resize(n, dofs, 0);
  for (int k = 0; k < n; ++k) {
    const json& x = t[static_cast<std::size_t>(k)];
    if (!x.is_number() || !std::isfinite(x.get<double>())) r.fail("samples.t", "expected numbers");
    p.t(k) = x.get<double>();
    if (k > 0 && !(p.t(k) > p.t(k - 1))) r.fail("samples.t", "expected increasing times");
  }
  const json& ph = r.need(s, "phase", "samples.");
  if (!ph.is_array() || static_cast<int>(ph.size()) != n)
    r.fail("samples.phase", "expected " + std::to_string(n) + " phase indices");
  for (int k = 0; k < n; ++k) {
    const int v = ph[static_cast<std::size_t>(k)].get<int>();
    if (v < 0 || v >= static_cast<int>(p.phases.size())) r.fail("samples.phase", "out of range");
    p.phase(k) = v;
  }
  p.q = r.matrix(s, "q", dofs, n);
  p.v = r.matrix(s, "v", dofs, n);
  p.a = r.matrix(s, "a", dofs, n);
  const json& tau0 = r.need(s, "tau", "samples.");
  const int na =
      tau0.is_array() && !tau0.empty() && tau0[0].is_array() ? static_cast<int>(tau0[0].size()) : 0;
  p.tau = r.matrix(s, "tau", na, n);
  p.com = r.matrix(s, "com", 3, n);
  p.zmp_wholebody = r.matrix(s, "zmp_wholebody", 2, n);
  p.zmp_tablecart = r.matrix(s, "zmp_tablecart", 2, n);
  p.right_foot = r.matrix(s, "right_foot", 7, n);
  p.left_foot = r.matrix(s, "left_foot", 7, n);
  p.right_wrench = forceFirst(r.matrix(s, "right_wrench", 6, n));  // its own inverse
  p.left_wrench = forceFirst(r.matrix(s, "left_wrench", 6, n));
  return p;
}

}  // namespace overstep::core
