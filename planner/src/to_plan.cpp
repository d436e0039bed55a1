// Dense sampling of a solution into the plan file contract (core::Plan).
#include <algorithm>

#include "problem_impl.hpp"

namespace overstep::planner {

core::Plan OverstepProblem::toPlan(const Eigen::VectorXd& x, double rate) {
  Impl& m = *impl_;
  if (!(rate > 0.0)) throw InputError("plan rate: expected > 0 Hz");
  Impl::Workspace& w = m.ws.front();
  m.decode(x, w);
  const PhaseTiming& timing = *w.timing;
  const auto& d = m.model_template.description();
  core::Plan p;
  p.robot_name = d.name;
  p.robot_file = d.yaml_path;
  p.robot_hash = d.hashHex();
  p.obstacle = m.obstacle;
  p.obstacle.height = m.height;
  p.toes_x = m.toes_x;
  p.config_json = m.cfg.toJson();
  p.rate = rate;
  p.coordinates = m.model_template.coordinateNames();
  for (int i = 0; i < kPhaseCount; ++i) {
    const auto& ph = phaseTable()[static_cast<std::size_t>(i)];
    p.phases.push_back(
        {ph.name, timing.start(i), timing.durations()(i), ph.right_contact, ph.left_contact});
  }
  // Samples at k / rate, plus both sides of every phase boundary (1 us apart) so that nothing
  // interpolates across a contact switch.
  const double T = timing.total();
  std::vector<std::pair<double, int>> when;
  for (int k = 0;; ++k) {
    const double t = k / rate;
    if (t > T - 1e-9) break;
    when.emplace_back(t, timing.locate(t).phase);
  }
  for (int b = 1; b < kPhaseCount; ++b) {
    const double tb = timing.start(b);
    when.emplace_back(tb - 1e-6, b - 1);
    when.emplace_back(tb, b);
  }
  when.emplace_back(T, kPhaseCount - 1);
  std::sort(when.begin(), when.end());
  std::vector<std::pair<double, int>> uniq;
  for (const auto& w2 : when)
    if (uniq.empty() || w2.first > uniq.back().first + 1e-9)
      uniq.push_back(w2);
    else if (w2.second != uniq.back().second)
      uniq.back() = w2;  // the boundary sample wins
  const int n = static_cast<int>(uniq.size());
  p.resize(n, m.model_template.dofs(), m.model_template.actuatedCount());
  robots::WholeBodyModel& model = *w.model;
  std::vector<Eigen::VectorXd> q(static_cast<std::size_t>(n)), v(q.size()), a(q.size());
  for (int k = 0; k < n; ++k) {
    m.buildState(w, uniq[static_cast<std::size_t>(k)].second,
                 uniq[static_cast<std::size_t>(k)].first);
    q[static_cast<std::size_t>(k)] = w.st.q;
    v[static_cast<std::size_t>(k)] = w.st.v;
    a[static_cast<std::size_t>(k)] = w.st.a;
  }
  if (m.cfg.passive_polish) m.polishPassive(w, uniq, q, v, a);
  for (int k = 0; k < n; ++k) {
    const double t = uniq[static_cast<std::size_t>(k)].first;
    const int phase = uniq[static_cast<std::size_t>(k)].second;
    m.stateFrom(w, phase, t, q[static_cast<std::size_t>(k)], v[static_cast<std::size_t>(k)],
                a[static_cast<std::size_t>(k)]);
    const State& st = w.st;
    p.t(k) = t;
    p.phase(k) = phase;
    p.q.col(k) = st.q;
    p.v.col(k) = st.v;
    p.a.col(k) = st.a;
    p.tau.col(k) = st.tau_act;
    p.com.col(k) = model.com();
    p.zmp_wholebody.col(k) = core::zmpFromWrench(st.W_O);
    p.zmp_tablecart.col(k) = core::tableCartZmp(model.com(), model.comAcceleration(), d.gravity);
    for (int f = 0; f < 2; ++f) {
      Eigen::Matrix<double, 7, 1> pose;
      pose.head<3>() = st.sole[f].translation();
      const Eigen::Quaterniond qf(st.sole[f].linear());
      pose.tail<4>() << qf.w(), qf.x(), qf.y(), qf.z();
      (f == kRight ? p.right_foot : p.left_foot).col(k) = pose;
      p.setWrench(f == kRight ? 0 : 1, k, st.wrench[f]);
    }
  }
  return p;
}

}  // namespace overstep::planner
