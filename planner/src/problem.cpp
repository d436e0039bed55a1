#include <chrono>

#include "problem_impl.hpp"

namespace overstep::planner {

const char* familyName(Family f) {
  static const char* names[] = {"cop",       "friction",       "unilateral", "clearance",
                                "obstacle",  "self_collision", "pelvis",     "joint_limits",
                                "velocity",  "torque",         "reach",      "dynamics",
                                "switching", "lift_off",       "touchdown"};
  return names[static_cast<int>(f)];
}

// ==================================================================== public interface
OverstepProblem::OverstepProblem(const robots::WholeBodyModel& model, PlannerConfig config,
                                 core::ObstacleSpec obstacle, std::vector<GridPoint> check_points)
    : impl_(std::make_unique<Impl>(model, std::move(config), obstacle)) {
  core::validate(obstacle);
  impl_->setUp(std::move(check_points));
}
const std::vector<GridPoint>& OverstepProblem::checkPoints() const { return impl_->check_points; }
OverstepProblem::~OverstepProblem() = default;

const VariableLayout& OverstepProblem::layout() const { return impl_->lay; }
const PlannerConfig& OverstepProblem::config() const { return impl_->cfg; }
const core::ObstacleSpec& OverstepProblem::obstacle() const { return impl_->obstacle; }
int OverstepProblem::inequalityCount() const { return impl_->n_ineq; }
int OverstepProblem::equalityCount() const { return impl_->n_eq; }
const std::vector<Family>& OverstepProblem::inequalityFamilies() const { return impl_->ineq_fam; }
const std::vector<Family>& OverstepProblem::equalityFamilies() const { return impl_->eq_fam; }
double OverstepProblem::toesX() const { return impl_->toes_x; }
double OverstepProblem::startClearance() const {
  const Impl& m = *impl_;
  robots::WholeBodyModel tmp(m.model_template);
  tmp.setPositions(m.q_rest);
  double d = std::numeric_limits<double>::infinity();
  for (int f = 0; f < 2; ++f) {
    // The start placements (bounds(): fixed): the right sole at (0, -w), the left at (0, w).
    const double y = (f == kLeft ? 1.0 : -1.0) * m.cfg.start_half_width;
    // The model's world at half-sitting carried so that the sole lands on its start placement.
    const Eigen::Isometry3d X_shift = placement(0.0, y) * tmp.framePose(m.sole_frame[f]).inverse();
    for (int c : m.leg_caps[f]) {
      const CapsuleRef& ref = m.caps[static_cast<std::size_t>(c)];
      if (ref.link != m.leg_links[f][2]) continue;  // the foot's capsules only
      const Eigen::Isometry3d X = X_shift * tmp.framePose(ref.frame);
      d = std::min(d,
                   robots::obstacleDistance({X * ref.p0, X * ref.p1, ref.radius}, m.obstacle_geom));
    }
  }
  return d;
}
int OverstepProblem::evaluationCount() const { return impl_->evaluations.load(); }
const WorkAccount& OverstepProblem::work() const { return impl_->work; }
void OverstepProblem::setDifficulty(double h, double box, bool last_stage) {
  impl_->height = h;
  impl_->cop_box = box;
  impl_->last_stage = last_stage;
}
bool OverstepProblem::lastStage() const { return impl_->last_stage; }
double OverstepProblem::currentHeight() const { return impl_->height; }
double OverstepProblem::currentCopBox() const { return impl_->cop_box; }

void OverstepProblem::bounds(Eigen::VectorXd& lo, Eigen::VectorXd& hi) const {
  const Impl& m = *impl_;
  const auto& c = m.cfg;
  const auto& lay = m.lay;
  lo.resize(lay.total);
  hi.resize(lay.total);
  for (int i = 0; i < kPhaseCount; ++i) {
    lo(i) = c.duration_min[static_cast<std::size_t>(i)];
    hi(i) = c.duration_max[static_cast<std::size_t>(i)];
  }
  // right start, right landing, left landing. The start is where the robot stands (half-sitting,
  // soles start_half_width either side of the middle): fixed, or the runtime could not get from
  // the robot's stance to the plan's first posture without a step.
  lo.segment<2>(lay.feet) << 0.0, -c.start_half_width;
  hi.segment<2>(lay.feet) = lo.segment<2>(lay.feet);
  lo.segment<2>(lay.feet + 2) << c.step_length_min, -c.foot_y_max;
  hi.segment<2>(lay.feet + 2) << c.step_length_max, -c.foot_y_min;
  lo.segment<2>(lay.feet + 4) << c.step_length_min, c.foot_y_min;
  hi.segment<2>(lay.feet + 4) << c.step_length_max, c.foot_y_max;
  const auto& d = m.model_template.description();
  for (int j = 0; j < 12; ++j) {
    const auto& a = d.actuated[static_cast<std::size_t>(m.leg_act[static_cast<std::size_t>(j)])];
    lo.segment(lay.legs + j * lay.free_cp, lay.free_cp).setConstant(a.safeLower());
    hi.segment(lay.legs + j * lay.free_cp, lay.free_cp).setConstant(a.safeUpper());
  }
  lo.segment(lay.flex, 4 * lay.flex_free_cp).setConstant(-0.15);
  hi.segment(lay.flex, 4 * lay.flex_free_cp).setConstant(0.15);
}

Eigen::VectorXd OverstepProblem::variableScale() const {
  const auto& lay = impl_->lay;
  Eigen::VectorXd d(lay.total);
  d.head(kPhaseCount).setConstant(0.3);                         // s
  d.segment(lay.feet, 6).setConstant(0.05);                     // m
  d.segment(lay.legs, lay.flex - lay.legs).setConstant(0.2);    // rad
  d.segment(lay.flex, lay.total - lay.flex).setConstant(0.01);  // rad: stiff springs
  return d;
}

void OverstepProblem::evaluate(const Eigen::VectorXd& x, Evaluation& out) {
  Impl& m = *impl_;
  if (x.size() != m.lay.total) throw InputError("planner: wrong number of variables");
  const auto start = std::chrono::steady_clock::now();
  auto& w = m.ws.front();
  m.evaluateAll(x, w, m.base_samples, m.base_events);
  m.base_x = x;
  m.assemble(w, m.base_samples, m.base_events, out);
  ++m.work.evaluations;
  m.work.evaluate_s +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string OverstepProblem::describeRow(const Eigen::VectorXd& x, bool equality, int row) const {
  const Impl& m = *impl_;
  const PhaseTiming timing(x.head(kPhaseCount));
  const auto& fam = equality ? m.eq_fam : m.ineq_fam;
  if (row < 0 || row >= static_cast<int>(fam.size())) return "?";
  std::string where;
  char buf[160];
  const auto& off = equality ? m.eq_off : m.ineq_off;
  const auto& cnt = equality ? m.eq_cnt : m.ineq_cnt;
  for (std::size_t k = 0; k < m.grid.size(); ++k) {
    if (row >= off[k] && row < off[k] + cnt[k]) {
      const GridPoint& g = m.grid[k];
      std::snprintf(buf, sizeof buf, "%s at t = %.3f s (%s, row %d of sample %zu)",
                    familyName(fam[static_cast<std::size_t>(row)]), timing.timeOf(g.phase, g.s),
                    phaseTable()[static_cast<std::size_t>(g.phase)].name, row - off[k], k);
      return buf;
    }
  }
  for (int e = 0; e < Impl::kEvents; ++e) {
    if (row >= m.event_eq_off[e] && row < m.event_eq_off[e] + m.event_eq_cnt[e]) {
      std::snprintf(buf, sizeof buf, "%s at t = %.3f s (switch %d, row %d)",
                    familyName(fam[static_cast<std::size_t>(row)]), timing.start(e + 1), e + 1,
                    row - m.event_eq_off[e]);
      return buf;
    }
  }
  return familyName(fam[static_cast<std::size_t>(row)]);
}

Eigen::VectorXd OverstepProblem::durations(const Eigen::VectorXd& x) const {
  return x.head(kPhaseCount);
}
double OverstepProblem::stepLength(const Eigen::VectorXd& x) const {
  const auto& lay = impl_->lay;
  return x(lay.feet + 2) - x(lay.feet);
}
double OverstepProblem::footSpacing(const Eigen::VectorXd& x) const {
  const auto& lay = impl_->lay;
  return x(lay.feet + 5) - x(lay.feet + 3);
}

}  // namespace overstep::planner
