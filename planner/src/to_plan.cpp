// Dense sampling of a solution into the plan file contract (core::Plan).
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
    p.phases.push_back({ph.name, timing.start(i), timing.durations()(i), ph.right_contact,
                        ph.left_contact});
  }
  const double T = timing.total();
  const int n = static_cast<int>(std::floor(T * rate + 1e-9)) + 1 + 1;
  p.resize(n, m.model_template.dofs(), m.model_template.actuatedCount());
  robots::WholeBodyModel& model = *w.model;
  for (int k = 0; k < n; ++k) {
    const double t = std::min(k / rate, T);
    const GridPoint g = timing.locate(t);
    m.buildState(w, g.phase, t);
    const State& st = w.st;
    p.t(k) = k + 1 == n ? T : t;
    p.phase(k) = g.phase;
    p.q.col(k) = st.q;
    p.v.col(k) = st.v;
    p.a.col(k) = st.a;
    p.tau.col(k) = st.tau.segment(6, model.actuatedCount());
    p.com.col(k) = model.com();
    p.zmp_wholebody.col(k) = core::zmpFromWrench(st.W_O);
    p.zmp_tablecart.col(k) = core::tableCartZmp(model.com(), model.comAcceleration(), d.gravity);
    for (int f = 0; f < 2; ++f) {
      Eigen::Matrix<double, 7, 1> pose;
      pose.head<3>() = st.sole[f].translation();
      const Eigen::Quaterniond qf(st.sole[f].linear());
      pose.tail<4>() << qf.w(), qf.x(), qf.y(), qf.z();
      (f == kRight ? p.right_foot : p.left_foot).col(k) = pose;
      (f == kRight ? p.right_wrench : p.left_wrench).col(k) = st.wrench[f];
    }
  }
  // The last sample lands exactly on T; drop a duplicate if floor() already reached it.
  if (n >= 2 && p.t(n - 1) <= p.t(n - 2) + 1e-12) {
    const int keep = n - 1;
    core::Plan trimmed = p;
    trimmed.resize(keep, m.model_template.dofs(), m.model_template.actuatedCount());
    trimmed.t = p.t.head(keep);
    trimmed.phase = p.phase.head(keep);
    trimmed.q = p.q.leftCols(keep);
    trimmed.v = p.v.leftCols(keep);
    trimmed.a = p.a.leftCols(keep);
    trimmed.tau = p.tau.leftCols(keep);
    trimmed.com = p.com.leftCols(keep);
    trimmed.zmp_wholebody = p.zmp_wholebody.leftCols(keep);
    trimmed.zmp_tablecart = p.zmp_tablecart.leftCols(keep);
    trimmed.right_foot = p.right_foot.leftCols(keep);
    trimmed.left_foot = p.left_foot.leftCols(keep);
    trimmed.right_wrench = p.right_wrench.leftCols(keep);
    trimmed.left_wrench = p.left_wrench.leftCols(keep);
    return trimmed;
  }
  return p;
}

}  // namespace overstep::planner
