#pragma once
// Internal to the planner library: the problem's private state, shared by problem.cpp, guess.cpp
// and to_plan.cpp. Not installed, not included by users.
#include <Eigen/Sparse>

#include "constraints/row_term.hpp"
#include "costs/cost_term.hpp"
#include "problem_model.hpp"

namespace overstep::planner {

using namespace detail;  // NOLINT: internal header

struct OverstepProblem::Impl : ProblemModel {
  struct Workspace {
    std::unique_ptr<robots::WholeBodyModel> model;
    std::unique_ptr<PhaseSpline> spline, flex_spline;  // legs, ankle bushings
    Eigen::MatrixXd legs_c, flex_c;                    // full control points (12 x C, 4 x C_flex)
    Eigen::Vector2d feet[3];                           // right start, right landing, left landing
    std::unique_ptr<PhaseTiming> timing;
    State st;
    SampleData sample;  // what the sample terms read (capsules reused between samples)
  };
  std::vector<Workspace> ws;
  std::vector<std::unique_ptr<SampleTerm>> sample_terms;  // stacking order: constraints/terms.cpp
  std::vector<std::unique_ptr<EventTerm>> event_terms;
  /// The sample costs switched on (weight != 0), with their slot in objectiveTermNames().
  std::vector<std::pair<int, std::unique_ptr<SampleCost>>> sample_costs;
  /// The one sample cost that reads the double-support leg's spline (State::ik_seed_gap), when
  /// switched on, and its slot: OverstepProblem::derivatives differentiates that spline's control
  /// points at a double-support sample through it alone.
  const SampleCost* ds_tracking = nullptr;
  int ds_tracking_slot = -1;
  std::atomic<int> evaluations{0};
  WorkAccount work;

  // Baseline cache (for finite differences).
  std::vector<SampleOut> base_samples;
  std::vector<Eigen::VectorXd> base_events;
  Eigen::VectorXd base_x;

  Impl(const robots::WholeBodyModel& m, PlannerConfig c, core::ObstacleSpec o)
      : ProblemModel(m, std::move(c), o) {}

  // -------------------------------------------------------------- set-up
  void setUp(std::vector<GridPoint> extra) {
    const auto& d = model_template.description();
    if (model_template.baseDofs() != 6 || d.feet.size() != 2) {
      throw InputError("planner: needs a floating-base robot with two feet");
    }
    // The legs from the kinematic tree (right, left): joints hip to ankle, then the bushing's
    // roll and pitch below the ankle.
    const std::vector<robots::LegChain> legs = robots::legChains(model_template);
    if (legs.size() != 2 || legs[kRight].side != "right" || legs[kLeft].side != "left")
      throw InputError("planner: needs a right and a left leg, in that order");
    for (int f = 0; f < 2; ++f) {
      const robots::LegChain& c = legs[static_cast<std::size_t>(f)];
      if (c.elastic.size() != 2)
        throw InputError("planner: the " + c.side + " ankle needs a roll and a pitch bushing");
      for (int j = 0; j < 6; ++j) {
        const int a = c.actuated[static_cast<std::size_t>(j)];
        leg_act[static_cast<std::size_t>(6 * f + j)] = a;
        leg_coord[static_cast<std::size_t>(6 * f + j)] = model_template.actuatedCoordinate(a);
      }
      for (int e = 0; e < 2; ++e)
        flex_coord[static_cast<std::size_t>(2 * f + e)] =
            model_template.elasticCoordinate(c.elastic[static_cast<std::size_t>(e)]);
      // Reach: hip pitch link to ankle pitch link (children of the third and fifth joints).
      hip_frame[f] = model_template.frameIndex(c.links[2]);
      ankle_frame[f] = model_template.frameIndex(c.links[4]);
      leg_links[f] = {c.links[2], c.links[3], c.foot_link};  // thigh, shank, foot
      ankle_link_frame[f] = c.ankle_frame;
      leg_ik[f] = std::make_unique<robots::LegIk>(model_template, c);
    }
    foot[kRight] = *d.foot("right");
    foot[kLeft] = *d.foot("left");
    for (int f = 0; f < 2; ++f) sole_frame[f] = model_template.frameIndex(foot[f].sole_frame);
    head_frame = model_template.hasFrame("head") ? model_template.frameIndex("head") : -1;
    base_frame = model_template.frameIndex(d.base_link);
    mass = model_template.totalMass();
    mg = mass * d.gravity;
    toes_x = foot[kLeft].sole.x_front;  // left start sole frame at x = 0
    for (const auto& c : d.capsules) {
      caps.push_back({model_template.frameIndex(c.link), c.p0, c.p1, c.radius, c.link});
    }
    for (int f = 0; f < 2; ++f)
      for (const std::string& l : leg_links[f])  // every capsule of the thigh, shank and foot
        for (std::size_t i = 0; i < caps.size(); ++i)
          if (caps[i].link == l) leg_caps[f].push_back(static_cast<int>(i));
    // Self-collision pairs: the legs with each other, then the pairs the robot file lists
    // (`self_collision:`, e.g. the hanging arms with the thighs).
    for (int a : leg_caps[kRight])
      for (int b : leg_caps[kLeft]) self_pairs.emplace_back(a, b);
    for (const auto& [la, lb] : d.self_collision)
      for (std::size_t a = 0; a < caps.size(); ++a)
        for (std::size_t b = 0; b < caps.size(); ++b)
          if (caps[a].link == la && caps[b].link == lb)
            self_pairs.emplace_back(static_cast<int>(a), static_cast<int>(b));
    {
      robots::WholeBodyModel tmp(model_template);
      q_rest = tmp.halfSitting();
      // Each leg stretched (its ankle asked 1 m below its zero posture): the reach row's value
      // where the double-support leg's target lies beyond reach (solveOtherLeg).
      Eigen::VectorXd q = q_rest;
      for (int f = 0; f < 2; ++f) {
        Eigen::Isometry3d X_BA = leg_ik[f]->forward(robots::Vector6d::Zero());
        X_BA.translation().z() -= 1.0;
        const robots::LegIkResult ik = leg_ik[f]->solve(X_BA);
        for (int j = 0; j < 6; ++j) q(leg_coord[static_cast<std::size_t>(6 * f + j)]) = ik.q(j);
      }
      tmp.setPositions(q);
      for (int f = 0; f < 2; ++f)
        stretched_reach[f] = (tmp.framePose(ankle_frame[f]).translation() -
                              tmp.framePose(hip_frame[f]).translation())
                                 .norm();
    }
    height = obstacle.height;
    cop_box = cfg.cop_box;
    obstacle_geom = robots::ObstacleGeometry::fromSpec(obstacle, toes_x);

    n_ctrl = PhaseSpline(cfg.spline_intervals).controlPointCount();
    n_ctrl_flex = PhaseSpline(cfg.flex_spline_intervals).controlPointCount();
    lay.free_cp = n_ctrl - 4;
    lay.flex_free_cp = n_ctrl_flex - 4;
    if (lay.free_cp < 2) throw InputError("planner: spline_intervals too small");
    if (lay.flex_free_cp < 2) throw InputError("planner: flex_spline_intervals too small");
    lay.durations = 0;
    lay.feet = kPhaseCount;
    lay.legs = lay.feet + 6;
    lay.flex = lay.legs + VariableLayout::kLegJoints * lay.free_cp;
    lay.total = lay.flex + VariableLayout::kFlex * lay.flex_free_cp;

    // Grid and row layout.
    // Single-support phases are sampled on their closed interval (s = 0 .. 1): the stance ankle
    // obeys its dynamics right up to touchdown (without the s = 1 sample its residual reached
    // 10 N m in the last 85 ms; measured with overstep check). A double-support phase that ends
    // with a lift-off stops one sample short of it, and one that starts with a touchdown starts
    // one sample after it: every contact row of the switching foot degenerates there (F = 0),
    // and the switch rows hold its wrench at zero instead (switch_wrench.cpp).
    for (int i = 0; i < kPhaseCount; ++i) {
      const int nph = cfg.samples_per_phase[static_cast<std::size_t>(i)];
      for (int k = firstSample(i); k <= lastSample(i); ++k)
        grid.push_back({i, static_cast<double>(k) / nph, 0.0});
    }
    n_regular = static_cast<int>(grid.size());
    addCheckPoints(std::move(extra));
    // The row layout, from the terms (constraints/terms.cpp gives the stacking order).
    sample_terms = sampleTerms();
    event_terms = eventTerms();
    const auto& names = objectiveTermNames();
    for (auto& cost : sampleCosts()) {
      const auto it = std::find_if(names.begin(), names.end(),
                                   [&](const char* n) { return std::string(n) == cost->name(); });
      if (it == names.end())
        throw std::logic_error(std::string("cost without weight: ") + cost->name());
      if (cfg.weights.at(*it) != 0.0)
        sample_costs.emplace_back(static_cast<int>(it - names.begin()), std::move(cost));
    }
    for (const auto& [slot, cost] : sample_costs) {
      if (std::string(cost->name()) != "ds_leg_tracking") continue;
      ds_tracking = cost.get();
      ds_tracking_slot = slot;
    }
    for (const auto& g : grid) {
      ineq_off.push_back(n_ineq);
      eq_off.push_back(n_eq);
      for (const auto& term : sample_terms) {
        auto& fam = term->equality() ? eq_fam : ineq_fam;
        fam.insert(fam.end(), static_cast<std::size_t>(termRows(*term, g)), term->family());
      }
      ineq_cnt.push_back(static_cast<int>(ineq_fam.size()) - n_ineq);
      eq_cnt.push_back(static_cast<int>(eq_fam.size()) - n_eq);
      n_ineq = static_cast<int>(ineq_fam.size());
      n_eq = static_cast<int>(eq_fam.size());
    }
    for (int i = 0; i < kPhaseCount; ++i)
      anchor_of[i] =
          phaseTable()[static_cast<std::size_t>(i)].base_foot == Foot::Right ? kRight : kLeft;
    // The landed right foot carries the transfer (phaseTable()): at its touchdown the left leg
    // goes from spline to inverse kinematics, and back at its lift-off.
    for (int e = 0; e < kEvents; ++e) {
      event_eq_off[e] = n_eq;
      for (const auto& term : event_terms)
        eq_fam.insert(eq_fam.end(), static_cast<std::size_t>(term->rows(*this, e)), term->family());
      event_eq_cnt[e] = static_cast<int>(eq_fam.size()) - n_eq;
      n_eq = static_cast<int>(eq_fam.size());
    }

    const int threads = std::max(1, cfg.solver.threads);
    ws.resize(static_cast<std::size_t>(threads));
    for (auto& w : ws) {
      w.model = std::make_unique<robots::WholeBodyModel>(model_template);
      w.spline = std::make_unique<PhaseSpline>(cfg.spline_intervals);
      w.flex_spline = std::make_unique<PhaseSpline>(cfg.flex_spline_intervals);
    }
  }

  /// The initial guess's pelvis height (guess.cpp).
  double pelvisHeight(robots::WholeBodyModel& model, const Eigen::VectorXd& q,
                      const Eigen::Vector2d& pelvis, const Eigen::Vector2d feet2[2],
                      const double lift[2]) const;

  // -------------------------------------------------------------- decoding x
  /// The full control points of a curve from its F free ones at x(offset..): the first and the
  /// last free point each stand for three tied ones (rest at the start and the end).
  static void expand(const Eigen::VectorXd& x, int offset, int F,
                     Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> c) {
    c.head(3).setConstant(x(offset));
    for (int i = 1; i < F - 1; ++i) c(i + 2) = x(offset + i);
    c.tail(3).setConstant(x(offset + F - 1));
  }

  void decode(const Eigen::VectorXd& x, Workspace& w) const {
    w.timing = std::make_unique<PhaseTiming>(x.head(kPhaseCount));
    w.spline->setTiming(*w.timing);
    w.flex_spline->setTiming(*w.timing);
    w.legs_c.resize(12, n_ctrl);
    w.flex_c.resize(4, n_ctrl_flex);
    for (int j = 0; j < 12; ++j)
      expand(x, lay.legs + j * lay.free_cp, lay.free_cp, w.legs_c.row(j));
    for (int j = 0; j < 4; ++j)
      expand(x, lay.flex + j * lay.flex_free_cp, lay.flex_free_cp, w.flex_c.row(j));
    for (int f = 0; f < 3; ++f) w.feet[f] = x.segment<2>(lay.feet + 2 * f);
  }

  /// Which placement variable (Workspace::feet: 0 right start, 1 right landing, 2 left landing)
  /// says where a foot stands in a phase in which it is in contact; -1: the left start, the
  /// world's reference.
  static int placementVariable(int phase, int foot_index) {
    if (foot_index == kLeft) return phase <= 2 ? -1 : 2;
    return phase == 0 ? 0 : 1;
  }
  /// Whether the state at a grid point of `phase` depends on placement variable `v` (buildState
  /// reads the anchor's placement, and in double support the other foot's).
  bool readsPlacement(int phase, int v) const {
    const int anchor = anchor_of[phase];
    return placementVariable(phase, anchor) == v ||
           (doubleSupport(phase) && placementVariable(phase, 1 - anchor) == v);
  }
  /// Where a foot stands in a phase in which it is in contact.
  Eigen::Isometry3d footPlacement(int phase, int foot_index, const Workspace& w) const {
    const int v = placementVariable(phase, foot_index);
    return v < 0 ? placement(0.0, cfg.start_half_width) : placement(w.feet[v].x(), w.feet[v].y());
  }
  /// |q_ik - seed|^2 of the double-support leg (State::ik_seed_gap): its inverse-kinematics
  /// solution against its spline's values.
  static double seedGap(const robots::Vector6d& q_ik, const robots::Vector6d& seed) {
    double gap2 = 0.0;
    for (int j = 0; j < 6; ++j) {
      const double gap = q_ik(j) - seed(j);
      gap2 += gap * gap;
    }
    return gap2;
  }
  Eigen::Isometry3d anchorPlacement(int phase, const Workspace& w) const {
    return footPlacement(phase, anchor_of[phase], w);
  }
  Eigen::Isometry3d otherPlacement(int phase, const Workspace& w) const {
    return footPlacement(phase, 1 - anchor_of[phase], w);
  }

  /// The splines' values at time t (SplineState: legs_c's rows, then flex_c's).
  SplineState splineState(const Workspace& w, double t) const {
    SplineState S;
    const PhaseSpline::Basis b = w.spline->evaluate(t);
    const PhaseSpline::Basis bf = w.flex_spline->evaluate(t);
    const auto legs = w.legs_c.middleCols(b.first, static_cast<int>(b.value.size()));
    const auto flex = w.flex_c.middleCols(bf.first, static_cast<int>(bf.value.size()));
    S.block<12, 1>(0, 0).noalias() = legs * b.value;
    S.block<12, 1>(0, 1).noalias() = legs * b.d1;
    S.block<12, 1>(0, 2).noalias() = legs * b.d2;
    S.block<4, 1>(12, 0).noalias() = flex * bf.value;
    S.block<4, 1>(12, 1).noalias() = flex * bf.d1;
    S.block<4, 1>(12, 2).noalias() = flex * bf.d2;
    return S;
  }

  /// Builds the robot state at time t in the contact configuration of `phase`.
  void buildState(Workspace& w, int phase, double t) const {
    buildState(w, phase, t, splineState(w, t));
  }
  /// The same from the splines' values S at t (splineState).
  void buildState(Workspace& w, int phase, double t, const SplineState& S) const {
    robots::WholeBodyModel& m = *w.model;
    State& st = w.st;
    const int n = m.dofs();
    st.q = q_rest;
    st.v.setZero(n);
    st.a.setZero(n);
    for (int j = 0; j < 12; ++j) {
      st.q(leg_coord[static_cast<std::size_t>(j)]) = S(j, 0);
      st.v(leg_coord[static_cast<std::size_t>(j)]) = S(j, 1);
      st.a(leg_coord[static_cast<std::size_t>(j)]) = S(j, 2);
    }
    for (int j = 0; j < 4; ++j) {
      st.q(flex_coord[static_cast<std::size_t>(j)]) = S(12 + j, 0);
      st.v(flex_coord[static_cast<std::size_t>(j)]) = S(12 + j, 1);
      st.a(flex_coord[static_cast<std::size_t>(j)]) = S(12 + j, 2);
    }
    const auto& ph = phaseTable()[static_cast<std::size_t>(phase)];
    const int anchor = anchor_of[phase];
    const int other = 1 - anchor;
    m.anchorBase(sole_frame[anchor], anchorPlacement(phase, w), st.q, st.v, st.a);
    st.contact[kRight] = ph.right_contact;
    st.contact[kLeft] = ph.left_contact;
    st.ik_error = 0.0;
    st.reach = 0.0;
    st.beyond_reach = false;
    st.ik_seed_gap = 0.0;
    if (ph.right_contact && ph.left_contact) {
      robots::Vector6d seed;
      for (int j = 0; j < 6; ++j)
        seed(j) = st.q(leg_coord[static_cast<std::size_t>(6 * other + j)]);
      solveOtherLeg(w, other, otherPlacement(phase, w));
      for (int j = 0; j < 6; ++j)
        st.ik_leg(j) = st.q(leg_coord[static_cast<std::size_t>(6 * other + j)]);
      st.ik_seed_gap = seedGap(st.ik_leg, seed);
    }
    m.frameJacobian(sole_frame[anchor], st.J_sole[anchor]);  // the other's: solveOtherLeg
    m.inverseDynamics(st.tau);
    st.W_O = m.contactWrenchFromBase(st.tau);
    for (int f = 0; f < 2; ++f) st.sole[f] = m.framePose(sole_frame[f]);
    for (int f = 0; f < 2; ++f) st.share[f] = shareFactor(w, phase, t, f);
    distributeWrench(w);
    contactTorques(w);
  }

  /// Actuator torques of the robot in contact (seed eq. 1): the actuated rows of inverse dynamics
  /// minus the feet's J^T w (the torque rows, seed eq. 27 and the plan file use these; the same
  /// sum as WholeBodyModel::torquesInContact, which `overstep check` uses, without recomputing
  /// the Jacobians; a foot out of contact carries no wrench).
  void contactTorques(Workspace& w) const {
    State& st = w.st;
    Eigen::VectorXd& tau = st.tau_contact;
    tau = st.tau;
    for (int f = 0; f < 2; ++f)
      if (st.contact[f]) tau.noalias() -= st.J_sole[f].transpose() * st.wrench[f].spatial();
    st.tau_act = tau.segment(6, model_template.actuatedCount());
  }

  /// How the configuration built by buildState (at w's state) moves with the splines' 16 values
  /// (SplineState rows: leg joints, then bushings): dv = T du, T dofs x 16, in the model's
  /// velocity coordinates. Each value moves its own coordinate; the base follows so that the
  /// anchor sole stays at its placement (J_a dv = 0), and in double support the inverse-
  /// kinematics leg follows so that the other sole stays at its own (J_o dv = 0; the implicit-
  /// function theorem through the leg Jacobian: that leg's own spline values move nothing).
  /// False where the inverse kinematics is not exact (a target beyond reach, a singular leg):
  /// the derivatives there are finite differences.
  bool configurationSensitivity(const Workspace& w, int phase, Eigen::MatrixXd& T) const {
    const State& st = w.st;
    const int anchor = anchor_of[phase], other = 1 - anchor;
    const bool ds = doubleSupport(phase);
    if (ds && (st.beyond_reach || st.ik_error > 1e-9)) return false;
    const Eigen::MatrixXd& Ja = st.J_sole[anchor];
    const Eigen::PartialPivLU<Eigen::Matrix<double, 6, 6>> base(Ja.leftCols<6>());
    Eigen::Matrix<double, 6, 6> Jl = Eigen::Matrix<double, 6, 6>::Identity();
    if (ds)
      for (int j = 0; j < 6; ++j)
        Jl.col(j) = st.J_sole[other].col(leg_coord[static_cast<std::size_t>(6 * other + j)]);
    const Eigen::PartialPivLU<Eigen::Matrix<double, 6, 6>> leg(Jl);
    if (ds && leg.rcond() < 1e-10) return false;
    T.setZero(w.model->dofs(), 16);
    for (int i = 0; i < 16; ++i) {
      if (ds && i < 12 && i / 6 == other) continue;  // set by the inverse kinematics
      const int c = i < 12 ? leg_coord[static_cast<std::size_t>(i)]
                           : flex_coord[static_cast<std::size_t>(i - 12)];
      T(c, i) = 1.0;
      T.col(i).head<6>() = -base.solve(Ja.col(c));
      if (!ds) continue;
      const core::Vector6d dl = -leg.solve(st.J_sole[other] * T.col(i));
      for (int j = 0; j < 6; ++j) T(leg_coord[static_cast<std::size_t>(6 * other + j)], i) = dl(j);
    }
    return true;
  }

  /// st.J_sole of the feet in contact at the model's current positions.
  void soleJacobians(Workspace& w) const {
    for (int f = 0; f < 2; ++f)
      if (w.st.contact[f]) w.model->frameJacobian(sole_frame[f], w.st.J_sole[f]);
  }

  /// Closed-form inverse kinematics of leg `leg` (robots::LegIk) putting its sole frame at X_WS,
  /// with the base and the ankle bushing as they are in q; `reference` (chain order) picks the
  /// ankle-roll branch. Exact wherever the target is within reach; the angles are not clamped
  /// (the joint-limit rows see them).
  robots::LegIkResult legToSole(robots::WholeBodyModel& m, int leg, const Eigen::Isometry3d& X_WS,
                                const Eigen::VectorXd& q, const robots::Vector6d& reference,
                                robots::BeyondReach beyond = robots::BeyondReach::Continue) const {
    m.setPositions(q);
    const Eigen::Isometry3d X_WB = m.framePose(base_frame);
    // Ankle link to sole: the bushing's deflection and the foot's geometry (no leg joint in it).
    const Eigen::Isometry3d X_AS =
        m.framePose(ankle_link_frame[leg]).inverse() * m.framePose(sole_frame[leg]);
    return leg_ik[leg]->solve(X_WB.inverse() * X_WS * X_AS.inverse(), &reference, beyond);
  }

  void solveOtherLeg(Workspace& w, int leg, const Eigen::Isometry3d& target) const {
    robots::WholeBodyModel& m = *w.model;
    State& st = w.st;
    const int f = sole_frame[leg];
    int cols[6];
    for (int j = 0; j < 6; ++j) cols[j] = leg_coord[static_cast<std::size_t>(6 * leg + j)];
    Eigen::Matrix<double, 6, 6> J;
    // The leg's spline values choose the ankle-roll branch (they coincide for stepping postures).
    robots::Vector6d seed;
    for (int j = 0; j < 6; ++j) seed(j) = st.q(cols[j]);
    const robots::LegIkResult ik = legToSole(m, leg, target, st.q, seed);
    for (int j = 0; j < 6; ++j) st.q(cols[j]) = ik.q(j);
    m.setPositions(st.q);
    st.ik_error = poseError(target, m.framePose(f)).norm();
    m.frameJacobian(f, st.J_sole[leg]);
    const Eigen::MatrixXd& Jf = st.J_sole[leg];
    for (int j = 0; j < 6; ++j) J.col(j) = Jf.col(cols[j]);
    // The leg is singular only when stretched beyond reach (a point the reach row rejects, met
    // during line searches): damped least squares there keeps the state finite.
    const Eigen::PartialPivLU<Eigen::Matrix<double, 6, 6>> lu(J);
    const bool regular = lu.rcond() > 1e-10;
    auto solve6 = [&](const core::Vector6d& b) -> core::Vector6d {
      if (regular) return lu.solve(b);
      return J.transpose() *
             (J * J.transpose() + 1e-8 * Eigen::Matrix<double, 6, 6>::Identity()).ldlt().solve(b);
    };
    for (int j = 0; j < 6; ++j) st.v(cols[j]) = 0.0;
    const Eigen::Matrix<double, 6, 1> dv = -solve6(Jf * st.v);
    for (int j = 0; j < 6; ++j) st.v(cols[j]) = dv(j);
    for (int j = 0; j < 6; ++j) st.a(cols[j]) = 0.0;
    m.setVelocities(st.v);
    m.setAccelerations(st.a);
    const Eigen::Matrix<double, 6, 1> da = -solve6(m.frameAcceleration(f));
    for (int j = 0; j < 6; ++j) st.a(cols[j]) = da(j);
    m.setAccelerations(st.a);
    // Beyond reach the knee is continued past straight (robots::BeyondReach::Continue) and the
    // achieved distance shrinks again: the stretched leg's distance plus the target's excess
    // keeps the row growing with it (without it, the reach row and the knee's joint-limit row
    // held constant there: a restoration stalled at the knee's 0.524 with no gradient).
    const double excess = ik.hip_ankle - leg_ik[leg]->maxReach();
    st.beyond_reach = excess > 0.0;
    st.reach = excess > 0.0 ? stretched_reach[leg] + excess
                            : (m.framePose(ankle_frame[leg]).translation() -
                               m.framePose(hip_frame[leg]).translation())
                                  .norm();
  }

  /// The state (q, v, a) as given, with everything buildState() derives from it: torques, the
  /// total and per-foot contact wrenches, the sole poses, the double-support sway balance.
  void stateFrom(Workspace& w, int phase, double t, const Eigen::VectorXd& q,
                 const Eigen::VectorXd& v, const Eigen::VectorXd& a) const {
    robots::WholeBodyModel& m = *w.model;
    State& st = w.st;
    const auto& ph = phaseTable()[static_cast<std::size_t>(phase)];
    st.q = q;
    st.v = v;
    st.a = a;
    st.contact[kRight] = ph.right_contact;
    st.contact[kLeft] = ph.left_contact;
    m.setState(q, v, a);
    soleJacobians(w);
    m.inverseDynamics(st.tau);
    st.W_O = m.contactWrenchFromBase(st.tau);
    for (int f = 0; f < 2; ++f) st.sole[f] = m.framePose(sole_frame[f]);
    for (int f = 0; f < 2; ++f) st.share[f] = shareFactor(w, phase, t, f);
    distributeWrench(w);
    contactTorques(w);
  }

  /// In single support, at the current state: the four elastic joints' equations of motion
  /// (residuals, N m) and the stance sole's CoP (m, sole frame), what the passive polish
  /// corrects and what it must leave in place.
  Eigen::VectorXd residualAndCop(Workspace& w, int phase) const {
    const State& st = w.st;
    const int stance = inContact(phase, kRight) ? kRight : kLeft;
    const Eigen::MatrixXd& J = st.J_sole[stance];
    Eigen::VectorXd r(6);
    for (int f = 0; f < 2; ++f)
      for (int e = 0; e < 2; ++e) {
        const int c = flex_coord[static_cast<std::size_t>(2 * f + e)];
        r(2 * f + e) = st.tau(c) - (f == stance ? J.col(c).dot(st.wrench[f].spatial()) : 0.0);
      }
    Eigen::Vector3d mo, fo;
    soleWrench(st, stance, mo, fo);
    r(4) = -mo.y() / fo.z();
    r(5) = mo.x() / fo.z();
    return r;
  }

  /// In single support, the directions (columns, tangent space) in which the passive coordinates
  /// can move with every actuated joint held and the stance sole fixed: each elastic joint with
  /// the base following the stance foot.
  Eigen::MatrixXd passiveDirections(Workspace& w, int phase, const Eigen::VectorXd& q) const {
    robots::WholeBodyModel& m = *w.model;
    const int anchor = anchor_of[phase];
    m.setPositions(q);
    const Eigen::Isometry3d X = m.framePose(sole_frame[anchor]);
    const double eps = 1e-6;
    Eigen::MatrixXd U(m.dofs(), 4);
    Eigen::VectorXd v0 = Eigen::VectorXd::Zero(m.dofs()), a0 = v0;
    for (int c = 0; c < 4; ++c) {
      Eigen::VectorXd qp = q;
      qp(flex_coord[static_cast<std::size_t>(c)]) += eps;
      v0.setZero();
      a0.setZero();
      m.anchorBase(sole_frame[anchor], X, qp, v0, a0);
      U.col(c) = m.difference(qp, q) / eps;
    }
    m.setPositions(q);
    return U;
  }

  /// Makes the passive coordinates obey their equations of motion between the collocation
  /// samples. The planner enforces the elastic joints' dynamics only at its samples; between them
  /// the dense motion leaves a residual F(t) (N m). In each single-support phase this finds the
  /// correction delta along the passive directions U (the linearised residual F + A delta'' +
  /// B delta' + C delta, A, B, C by finite differences at every dense sample) that removes it in
  /// the least-squares sense (smoothPassive) and adds U delta to q (U delta', U delta'' to v, a):
  /// the motion the robot's passive joints make under the planned actuated trajectories.
  /// Corrections are of the order of 1e-4 rad; the actuated joints are untouched. The correction
  /// is zero, with its rate, at every contact switch, and double support keeps the solver's
  /// motion: at a lift-off the unloading foot's whole wrench must vanish, and a correction's
  /// spring torque (k delta) would reappear as a moment on a foot that carries no load
  /// (measured: 0.27 N m under 2 N, a CoP 11 cm off, 4 ms before the first lift-off); in double
  /// support a correction moved the lightly loaded landing foot's moments (1.3 mm of CoP beyond
  /// the box 40 ms after the 20 cm run's second touchdown).
  void polishPassive(Workspace& w, const std::vector<std::pair<double, int>>& when,
                     std::vector<Eigen::VectorXd>& q, std::vector<Eigen::VectorXd>& v,
                     std::vector<Eigen::VectorXd>& a) const {
    robots::WholeBodyModel& m = *w.model;
    const std::size_t n = when.size();
    std::vector<Eigen::MatrixXd> U(n), A(n), B(n), C(n);
    std::vector<Eigen::VectorXd> F(n);
    const double h = 1e-5;
    for (std::size_t k = 0; k < n; ++k) {
      const int phase = when[k].second;
      if (doubleSupport(phase)) continue;
      U[k] = passiveDirections(w, phase, q[k]);
      const int c = static_cast<int>(U[k].cols());
      stateFrom(w, phase, when[k].first, q[k], v[k], a[k]);
      F[k] = residualAndCop(w, phase);
      A[k].resize(c + 2, c);
      B[k].resize(c + 2, c);
      C[k].resize(c + 2, c);
      for (int j = 0; j < c; ++j) {
        stateFrom(w, phase, when[k].first, q[k], v[k], a[k] + h * U[k].col(j));
        A[k].col(j) = (residualAndCop(w, phase) - F[k]) / h;
        stateFrom(w, phase, when[k].first, q[k], v[k] + h * U[k].col(j), a[k]);
        B[k].col(j) = (residualAndCop(w, phase) - F[k]) / h;
        stateFrom(w, phase, when[k].first, m.integrate(q[k], U[k].col(j), h), v[k], a[k]);
        C[k].col(j) = (residualAndCop(w, phase) - F[k]) / h;
      }
    }
    std::vector<Eigen::VectorXd> D(n), DV(n), DA(n);
    for (std::size_t k0 = 0; k0 < n;) {
      std::size_t k1 = k0;
      while (k1 + 1 < n && when[k1 + 1].second == when[k0].second) ++k1;
      if (!doubleSupport(when[k0].second)) smoothPassive(when, U, A, B, C, F, k0, k1, D, DV, DA);
      k0 = k1 + 1;
    }
    for (std::size_t k = 0; k < n; ++k) {
      if (D[k].size() == 0) continue;  // double support, or a phase too short to correct
      // U keeps the stance sole fixed to first order; re-anchoring the base keeps it exactly.
      const int anchor = anchor_of[when[k].second];
      m.setPositions(q[k]);
      const Eigen::Isometry3d X = m.framePose(sole_frame[anchor]);
      q[k] = m.integrate(q[k], U[k] * D[k], 1.0);
      v[k] += U[k] * DV[k];
      a[k] += U[k] * DA[k];
      m.anchorBase(sole_frame[anchor], X, q[k], v[k], a[k]);
    }
  }

  /// The passive correction of one single-support phase, samples [k0, k1]: the delta (along U)
  /// minimising sum_k |R_k(delta)|^2 / kPolishResidual^2 + |P_k(delta)|^2 / kPolishCop^2 +
  /// |delta_k|^2 / kPolishDeflection^2, where [R; P]_k = F_k + A_k delta''_k + B_k delta'_k +
  /// C_k delta_k stacks the linearised residuals (R, N m; their value F) and the stance CoP's
  /// change (P, m; residualAndCop), the derivatives by three-point differences on the samples,
  /// delta held at zero on the phase's first two and last two samples (the solver's own motion,
  /// its value and rate, at both contact switches). A boundary-value problem over the phase:
  /// integrating the equations forward from the lift-off instead (Newmark) accumulated the
  /// residual's mean between the collocation samples through the slow mode of the body swaying
  /// on its stance bushing, 3.9 mrad of stance roll by mid-swing on the bar 5 mm farther, and the
  /// pelvis left its range; without the CoP term the correction's rotation of the body on that
  /// bushing moved the CoP 2.1 mm beyond the check's tolerance on the bar 5 mm nearer (measured,
  /// docs/history/planner.md).
  void smoothPassive(const std::vector<std::pair<double, int>>& when,
                     const std::vector<Eigen::MatrixXd>& U, const std::vector<Eigen::MatrixXd>& A,
                     const std::vector<Eigen::MatrixXd>& B, const std::vector<Eigen::MatrixXd>& C,
                     const std::vector<Eigen::VectorXd>& F, std::size_t k0, std::size_t k1,
                     std::vector<Eigen::VectorXd>& D, std::vector<Eigen::VectorXd>& DV,
                     std::vector<Eigen::VectorXd>& DA) const {
    if (k1 < k0 + 4) return;
    const int c = static_cast<int>(U[k0].cols());
    for (std::size_t k = k0; k <= k1; ++k) {
      D[k] = Eigen::VectorXd::Zero(c);
      DV[k] = D[k];
      DA[k] = D[k];
    }
    const std::size_t first = k0 + 2, last = k1 - 2;  // free samples
    const int unknowns = c * static_cast<int>(last - first + 1);
    auto col = [&](std::size_t k) { return c * static_cast<int>(k - first); };
    auto free = [&](std::size_t k) { return k >= first && k <= last; };
    // Three-point weights of delta' and delta'' at k on its neighbours (k-1, k, k+1).
    auto stencil = [&](std::size_t k, double d1[3], double d2[3]) {
      const double h1 = when[k].first - when[k - 1].first, h2 = when[k + 1].first - when[k].first;
      d1[0] = -h2 / (h1 * (h1 + h2));
      d1[1] = (h2 - h1) / (h1 * h2);
      d1[2] = h1 / (h2 * (h1 + h2));
      d2[0] = 2.0 / (h1 * (h1 + h2));
      d2[1] = -2.0 / (h1 * h2);
      d2[2] = 2.0 / (h2 * (h1 + h2));
    };
    // Rows per free sample: the c residuals (their value F, weight 1 / kPolishResidual), the
    // stance CoP's change (1 / kPolishCop) and the correction itself (1 / kPolishDeflection).
    const int per = 2 * c + 2;
    Eigen::VectorXd weight(c + 2);
    weight << Eigen::VectorXd::Constant(c, 1.0 / kPolishResidual), 1.0 / kPolishCop,
        1.0 / kPolishCop;
    std::vector<Eigen::Triplet<double>> trip;
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(per * (unknowns / c));
    int row = 0;
    for (std::size_t k = first; k <= last; ++k, row += per) {
      double d1[3], d2[3];
      stencil(k, d1, d2);
      for (int j = 0; j < 3; ++j) {
        const std::size_t kk = k - 1 + static_cast<std::size_t>(j);
        if (!free(kk)) continue;
        const Eigen::MatrixXd M =
            weight.asDiagonal() * (d2[j] * A[k] + d1[j] * B[k] + (kk == k ? 1.0 : 0.0) * C[k]);
        for (int r = 0; r < c + 2; ++r)
          for (int q = 0; q < c; ++q)
            if (M(r, q) != 0.0) trip.emplace_back(row + r, col(kk) + q, M(r, q));
      }
      rhs.segment(row, c) = -F[k].head(c) / kPolishResidual;
      for (int i = 0; i < c; ++i)
        trip.emplace_back(row + c + 2 + i, col(k) + i, 1.0 / kPolishDeflection);
    }
    Eigen::SparseMatrix<double> J(row, unknowns);
    J.setFromTriplets(trip.begin(), trip.end());
    const Eigen::SparseMatrix<double> JtJ = J.transpose() * J;
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(JtJ);
    const Eigen::VectorXd x = ldlt.solve(J.transpose() * rhs);
    if (ldlt.info() != Eigen::Success || !x.allFinite()) return;  // no correction
    auto at = [&](std::size_t k) -> Eigen::VectorXd {
      return free(k) ? Eigen::VectorXd(x.segment(col(k), c)) : Eigen::VectorXd::Zero(c);
    };
    for (std::size_t k = first; k <= last; ++k) {
      double d1[3], d2[3];
      stencil(k, d1, d2);
      D[k] = at(k);
      DV[k] = d1[0] * at(k - 1) + d1[1] * at(k) + d1[2] * at(k + 1);
      DA[k] = d2[0] * at(k - 1) + d2[1] * at(k) + d2[2] * at(k + 1);
    }
  }

  /// Foot f's share factor in double-support `phase` (s its fraction, fixed at each sample, so
  /// the split stays smooth in the variables): (1 - s) + a floor for a foot that lifts off at the
  /// phase's end, s + the floor for one that touched down at its start, 1 otherwise. The load of
  /// a foot ramps out before its lift-off and in after its touchdown, where the switch rows hold
  /// its wrench at zero. Only in the homotopy's last stage, like the tight switch rows: from the
  /// first stage on, the lift-off's ramp took the 5 cm stage 286 SLSQP iterations instead of 56
  /// and the 20 cm run reached its 20 cm stage after 394 s instead of 127 s (measured).
  double shareFactor(const Workspace& w, int phase, double t, int f) const {
    const bool lifts = liftingFoot(phase) == f, lands = landingFoot(phase) == f;
    if (!(lifts || lands) || !last_stage) return 1.0;
    const double s =
        std::clamp((t - w.timing->start(phase)) / w.timing->durations()(phase), 0.0, 1.0);
    return (lifts ? 1.0 - s : s) + kShareFloor;
  }

  /// One weighted pass of distributeWrench: the wrenches z = [m_R f_R m_L f_L] minimising
  /// sum_f |w_f|^2 / rho_f (moments weighted as forces at a 0.1 m lever) subject to the sum and
  /// the three reachable elastic-ankle balances; sets the state's sway-balance residual (the
  /// fourth, which no split reaches).
  Eigen::Matrix<double, 12, 1> distributePass(const Eigen::Matrix<double, 10, 12>& A,
                                              const Eigen::Matrix<double, 10, 1>& b,
                                              const Eigen::Vector2d& rho, State& st) const {
    Eigen::Matrix<double, 12, 1> qh_inv;
    for (int f = 0; f < 2; ++f) {
      const double r = std::sqrt(rho(f));
      qh_inv.segment<3>(6 * f).setConstant(0.1 * r);
      qh_inv.segment<3>(6 * f + 3).setConstant(r);
    }
    const Eigen::Matrix<double, 6, 12> B = A.topRows<6>() * qh_inv.asDiagonal();
    const Eigen::Matrix<double, 12, 1> up =
        B.transpose() * (B * B.transpose()).ldlt().solve(b.head<6>());
    const Eigen::FullPivHouseholderQR<Eigen::Matrix<double, 12, 6>> qr(B.transpose());
    const Eigen::Matrix<double, 12, 12> Qfull = qr.matrixQ();
    const Eigen::Matrix<double, 12, 6> N = Qfull.rightCols<6>();  // null space of B
    const Eigen::Matrix<double, 4, 12> Afs = A.bottomRows<4>() * qh_inv.asDiagonal();
    const Eigen::Matrix<double, 4, 6> C = Afs * N;
    const Eigen::Vector4d dvec = b.tail<4>() - Afs * up;
    const Eigen::JacobiSVD<Eigen::Matrix<double, 4, 6>> svd(
        C, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Vector4d sig = svd.singularValues();
    // Three directions are always reachable (sigma ~ 0.06-0.11 here); the fourth is not: the sum
    // of both ankles' moments about the line joining the feet can only come from the springs
    // (sigma ~ 0, up to small foot tilts). Solve the three exactly, report the fourth.
    Eigen::Matrix<double, 6, 1> y = Eigen::Matrix<double, 6, 1>::Zero();
    for (int i = 0; i < 3; ++i)
      y += svd.matrixV().col(i) * (svd.matrixU().col(i).dot(dvec) / sig(i));
    // Sign-stable scalar: orient the unreachable direction along (c, s, c, s), the moment axis
    // of the line between the feet, so that finite differences never see a flipped sign.
    const Eigen::Vector3d dp = st.sole[kLeft].translation() - st.sole[kRight].translation();
    const double phi = std::atan2(dp.y(), dp.x());
    const Eigen::Vector4d ref(std::cos(phi), std::sin(phi), std::cos(phi), std::sin(phi));
    Eigen::Vector4d u4 = svd.matrixU().col(3);
    if (u4.dot(ref) < 0.0) u4 = -u4;
    st.ds_balance = -u4.dot(dvec);
    return qh_inv.asDiagonal() * (up + N * y);
  }

  /// Contact wrenches at the sole origins from the total contact wrench (and, in double support,
  /// the two elastic-ankle balances).
  void distributeWrench(Workspace& w) const {
    State& st = w.st;
    for (int f = 0; f < 2; ++f)
      st.wrench[f] = core::Wrench::zero(core::Axes::kWorld, st.sole[f].translation());
    if (st.contact[kRight] != st.contact[kLeft]) {
      const int f = st.contact[kRight] ? kRight : kLeft;
      st.wrench[f] = st.W_O.about(st.sole[f].translation());
      return;
    }
    // Unknowns z = [m_R f_R m_L f_L]; rows: sum (6) and the four elastic joints.
    Eigen::Matrix<double, 10, 12> A = Eigen::Matrix<double, 10, 12>::Zero();
    Eigen::Matrix<double, 10, 1> b;
    for (int f = 0; f < 2; ++f) {
      const Eigen::Vector3d p = st.sole[f].translation();
      A.block<3, 3>(0, 6 * f).setIdentity();
      Eigen::Matrix3d px;
      px << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
      A.block<3, 3>(0, 6 * f + 3) = px;
      A.block<3, 3>(3, 6 * f + 3).setIdentity();
      const Eigen::MatrixXd& J = st.J_sole[f];
      for (int e = 0; e < 2; ++e) {
        const int c = flex_coord[static_cast<std::size_t>(2 * f + e)];
        A.block<1, 6>(6 + 2 * f + e, 6 * f) = J.col(c).transpose();
        b(6 + 2 * f + e) = st.tau(c);
      }
    }
    b.head<6>() = st.W_O.spatial();
    // The sum is exact (Newton-Euler). The remaining six internal degrees of freedom balance the
    // four elastic ankles through a weighted pseudo-inverse: exact whenever the feet can balance
    // them, and a residual (a row of the problem, met by the ankle-flex variables) in the
    // directions they cannot, e.g. pitch with the feet side by side. What the ankles leave free
    // (the feet's squeeze, shear and twist) is shared in proportion to the normal loads: each
    // foot's wrench weighted by 1 / rho_f, rho_f a smooth positive part of its normal force, so
    // both feet see about the same friction ratio and an unloading foot's shear and twist vanish
    // with its load. (An even split left the lifting foot 14 N of shear at zero normal force at
    // the 20 cm run's second lift-off; measured, docs/planner.md.) Three passes: the first with
    // equal weights, each next one with the loads of the one before.
    Eigen::Vector2d rho(1.0, 1.0);
    Eigen::Matrix<double, 12, 1> z;
    for (int pass = 0; pass < 3; ++pass) {
      z = distributePass(A, b, rho, st);
      for (int f = 0; f < 2; ++f) {
        const double fz = st.sole[f].linear().col(2).dot(z.segment<3>(6 * f + 3)) / mg;
        rho(f) = 0.5 * (fz + std::sqrt(fz * fz + kLoadFloor * kLoadFloor)) * st.share[f];
      }
    }
    for (int f = 0; f < 2; ++f)
      st.wrench[f] = core::Wrench::fromSpatial(z.segment<6>(6 * f), core::Axes::kWorld,
                                               st.sole[f].translation());
  }

  // -------------------------------------------------------------- rows of one sample

  /// The capsules in the world at the current state, and how far each can travel before the
  /// nearer sample (swept clearance; 0 when off).
  void worldCapsules(Workspace& w, int phase, SampleData& sd) const {
    const robots::WholeBodyModel& m = *w.model;
    sd.capsules.resize(caps.size());
    sd.sweep.assign(caps.size(), 0.0);
    const double half_h =
        0.5 * w.timing->durations()(phase) / cfg.samples_per_phase[static_cast<std::size_t>(phase)];
    for (std::size_t i = 0; i < caps.size(); ++i) {
      const Eigen::Isometry3d X = m.framePose(caps[i].frame);
      robots::Capsule& c = sd.capsules[i];
      c = {X * caps[i].p0, X * caps[i].p1, caps[i].radius};
      if (cfg.swept_clearance > 0.0) {
        const core::Vector6d V = m.frameVelocity(caps[i].frame);
        const Eigen::Vector3d w0 = V.head<3>(), v0 = V.tail<3>();
        const double s0 = (v0 + w0.cross(c.p0 - X.translation())).norm();
        const double s1 = (v0 + w0.cross(c.p1 - X.translation())).norm();
        sd.sweep[i] = cfg.swept_clearance * half_h * std::max(s0, s1);
      }
    }
  }

  /// Rows, costs and torques of sample k at the decode in w, or with the splines' values S there.
  void sampleRows(Workspace& w, int k, SampleOut& out, const SplineState* S = nullptr) const {
    const GridPoint& g = grid[static_cast<std::size_t>(k)];
    const double t = w.timing->timeOf(g.phase, g.s);
    buildState(w, g.phase, t, S ? *S : splineState(w, t));
    robots::WholeBodyModel& m = *w.model;
    const State& st = w.st;
    out.t = t;
    out.ineq.resize(ineq_cnt[static_cast<std::size_t>(k)]);
    out.eq.resize(eq_cnt[static_cast<std::size_t>(k)]);
    SampleData& sd = w.sample;
    sd.g = &g;
    sd.t = t;
    sd.model = &m;
    sd.st = &st;
    worldCapsules(w, g.phase, sd);
    sd.com_acc = m.comAcceleration();
    forEachTermBlock(g, [&](std::size_t, const SampleTerm& term, int r0, int) {
      term.evaluate(*this, sd, (term.equality() ? out.eq : out.ineq).data() + r0);
    });
    // Sample costs (per unit time, normalised), each in the slot of its name.
    out.terms.fill(0.0);
    for (const auto& [slot, cost] : sample_costs)
      out.terms[static_cast<std::size_t>(slot)] = cost->value(*this, sd);
    out.tau = st.tau_act;
    out.ik_leg = st.ik_leg;
  }

  /// Sample k of `base` (double support) as it is after joint j of the leg the inverse
  /// kinematics sets moves by dq in its spline alone (the decode in w otherwise): that spline only
  /// picks the leg's inverse-kinematics branch (unchanged by a small change) and enters
  /// ds_leg_tracking, so the rows and every other term keep their values.
  void dsLegSplineChanged(const Workspace& w, int k, const SampleOut& base, int j, double dq,
                          SampleOut& out) const {
    out = base;
    if (!ds_tracking) return;
    const GridPoint& g = grid[static_cast<std::size_t>(k)];
    robots::Vector6d seed = splineState(w, base.t).block<6, 1>(6 * (1 - anchor_of[g.phase]), 0);
    seed(j) += dq;
    State st;
    st.ik_seed_gap = seedGap(base.ik_leg, seed);
    SampleData sd;
    sd.g = &g;
    sd.t = base.t;
    sd.st = &st;
    out.terms[static_cast<std::size_t>(ds_tracking_slot)] = ds_tracking->value(*this, sd);
  }

  /// Switching rows at event e (instants t1..t4): the spline of the leg that changes
  /// representation matches the double-support IK in position and velocity; lift-off forces. At
  /// the decode in w, or with the splines' values S at the switch.
  void eventRows(Workspace& w, int e, Eigen::VectorXd& out, const SplineState* S = nullptr) const {
    const double t = w.timing->start(eventBoundary(e));
    const SplineState S0 = S ? *S : splineState(w, t);
    buildState(w, eventPhase(e), t, S0);
    EventData ed;
    ed.event = e;
    ed.st = &w.st;
    ed.spline = &S0;
    out.resize(event_eq_cnt[e]);
    int r = 0;
    for (const auto& term : event_terms) {
      const int n = term->rows(*this, e);
      if (n == 0) continue;
      term->evaluate(*this, ed, out.data() + r);
      r += n;
    }
  }

  /// Rows of a sample term at grid point g. A mesh-refinement point carries the path
  /// constraints, not the collocation of the elastic dynamics: the samples are its grid, and the
  /// plan integrates the bushings between them (passive_polish), which the check verifies.
  int termRows(const SampleTerm& term, const GridPoint& g) const {
    return g.refinement && term.family() == Family::Dynamics ? 0 : term.rows(*this, g);
  }
  /// Calls f(ti, term, r0, rows) for each sample term with rows at g, in stacking order: ti its
  /// index in sample_terms, r0 its first row among the sample's equality rows or inequality rows
  /// (term.equality()).
  template <class F>
  void forEachTermBlock(const GridPoint& g, F&& f) const {
    int ri = 0, re = 0;
    for (std::size_t ti = 0; ti < sample_terms.size(); ++ti) {
      const SampleTerm& term = *sample_terms[ti];
      const int rows = termRows(term, g);
      if (rows == 0) continue;
      int& r0 = term.equality() ? re : ri;
      f(ti, term, r0, rows);
      r0 += rows;
    }
  }

  /// Mesh refinement: each point joins the grid after the regular points (rows only, no
  /// objective weight; termRows). A double support keeps its points off a lift-off at its end and
  /// a touchdown at its start (its contact rows degenerate there; the switch rows hold there).
  void addCheckPoints(std::vector<GridPoint> extra) {
    std::sort(extra.begin(), extra.end(), [](const GridPoint& a, const GridPoint& b) {
      return a.phase != b.phase ? a.phase < b.phase : a.s < b.s;
    });
    for (GridPoint g : extra) {
      if (g.phase < 0 || g.phase >= kPhaseCount || !(g.s >= 0.0 && g.s <= 1.0))
        throw InputError("planner: check point outside the phases (phase " +
                         std::to_string(g.phase) + ", s " + std::to_string(g.s) + ")");
      if (liftingFoot(g.phase) >= 0) g.s = std::min(g.s, 1.0 - 1e-3);
      if (landingFoot(g.phase) >= 0) g.s = std::max(g.s, 1e-3);
      g.t = 0.0;
      g.refinement = true;
      const bool near = std::any_of(grid.begin(), grid.end(), [&](const GridPoint& o) {
        return o.phase == g.phase && std::abs(o.s - g.s) < 1e-3;
      });
      if (near) continue;
      grid.push_back(g);
      check_points.push_back(g);
    }
  }

  // -------------------------------------------------------------- derivatives (derivatives.cpp)
  /// A sample's or a switch's outputs (rows; a sample's costs and torques too) differentiated with
  /// respect to its splines' values (SplineState, column-major index: 16 x order + row) by
  /// forward differences of that one point, and the splines' bases at its time: a control
  /// point's column is then the chain rule through the basis. A double-support sample does not
  /// read the spline of the leg its inverse kinematics sets (zero columns; it enters
  /// ds_leg_tracking alone, dsLegSplineChanged); a switch reads every one.
  struct Sensitivity {
    static constexpr int kInputs = 48;
    Eigen::MatrixXd ineq, eq, terms, tau;  // rows x kInputs
    PhaseSpline::Basis legs, flex;
    int ik_leg = -1;  // double-support sample: the leg set by inverse kinematics
  };
  /// Per-thread scratch of the column loops.
  struct ColumnScratch {
    std::vector<SampleOut> changed, local;
    std::vector<const SampleOut*> ptr;
    std::vector<Eigen::VectorXd> local_events;
    Eigen::VectorXd event;
  };
  void sampleSensitivity(Workspace& w, int k, Sensitivity& d) const;
  /// The rows of sample k that its terms give in closed form (SampleTerm::configurationJacobian
  /// through configurationSensitivity), into d's value columns; w at the sample's state. Marks
  /// those terms in `exact` (sample_terms order).
  void closedFormRows(Workspace& w, int k, Sensitivity& d, std::vector<bool>& exact) const;
  /// Column i of d from the forward difference out - base (step h) for the rows not in closed
  /// form.
  void copyDifferences(int k, const SampleOut& out, const SampleOut& base, double h, int i,
                       const std::vector<bool>& exact, Sensitivity& d) const;
  void eventSensitivity(Workspace& w, int e, Sensitivity& d) const;
  /// Column j of a phase duration or a foot placement, by a forward difference of the samples
  /// and switches it moves; leaves w decoded at x.
  void placementOrDurationColumn(Workspace& w, const Eigen::VectorXd& x, const Evaluation& at,
                                 int j, ColumnScratch& c, Eigen::VectorXd& grad,
                                 Eigen::MatrixXd& jin, Eigen::MatrixXd& jeq);
  /// Column j of a spline control point: the chain rule through the basis at the samples and
  /// switches in its support (sens: the samples', then the switches'); w decoded at x.
  void controlPointColumn(const Workspace& w, const Eigen::VectorXd& x, const Evaluation& at, int j,
                          const std::vector<Sensitivity>& sens, ColumnScratch& c,
                          Eigen::VectorXd& grad, Eigen::MatrixXd& jin, Eigen::MatrixXd& jeq) const;

  // -------------------------------------------------------------- assembly
  /// The first and the last sample index (of samples_per_phase) of a phase on the grid: a double
  /// support skips the instant of a lift-off at its end and of a touchdown at its start.
  int firstSample(int phase) const { return landingFoot(phase) >= 0 ? 1 : 0; }
  int lastSample(int phase) const {
    const int n = cfg.samples_per_phase[static_cast<std::size_t>(phase)];
    return liftingFoot(phase) >= 0 ? n - 1 : n;
  }

  /// Quadrature weight of regular grid point k within its phase: the trapezoid rule over the
  /// phase's samples, and a skipped switch instant's interval to the sample next to it.
  double sampleWeight(const Workspace& w, int k) const {
    const GridPoint& g = grid[static_cast<std::size_t>(k)];
    const int n = cfg.samples_per_phase[static_cast<std::size_t>(g.phase)];
    const double h = w.timing->durations()(g.phase) / n;
    const int i = static_cast<int>(std::lround(g.s * n));
    const int lo = firstSample(g.phase), hi = lastSample(g.phase);
    double wk = (i == lo || i == hi) ? 0.5 * h : h;
    if (i == lo && lo > 0) wk += h;
    if (i == hi && hi < n) wk += h;
    return wk;
  }

  double objective(const Workspace& w, const std::vector<const SampleOut*>& s,
                   std::array<double, kObjectiveTerms>* terms) const {
    std::array<double, kObjectiveTerms> acc{};
    const auto& names = objectiveTermNames();
    // Check points (after the regular ones) carry rows only.
    for (std::size_t k = 0; k < static_cast<std::size_t>(n_regular); ++k) {
      const double wk = sampleWeight(w, static_cast<int>(k));
      for (int i = 0; i < kObjectiveTerms; ++i)
        acc[static_cast<std::size_t>(i)] += wk * s[k]->terms[static_cast<std::size_t>(i)];
      if (k > 0) {
        const double dt = s[k]->t - s[k - 1]->t;
        if (dt > 1e-9) {
          const double rate = ((s[k]->tau - s[k - 1]->tau) / dt).squaredNorm();
          acc[10] += dt * rate / (1e4 * static_cast<double>(s[k]->tau.size()));
        }
      }
    }
    // Time averages: an integral would reward short motions through every term; the time term
    // (seed eq. 25) alone carries the duration.
    const double total = w.timing->total();
    for (int i = 0; i < kObjectiveTerms; ++i) acc[static_cast<std::size_t>(i)] /= total;
    acc[8] = total;
    double f = 0.0;
    for (int i = 0; i < kObjectiveTerms; ++i) {
      acc[static_cast<std::size_t>(i)] *= cfg.weights.at(names[static_cast<std::size_t>(i)]);
      f += acc[static_cast<std::size_t>(i)];
    }
    if (terms) *terms = acc;
    return f;
  }

  void evaluateAll(const Eigen::VectorXd& x, Workspace& w, std::vector<SampleOut>& samples,
                   std::vector<Eigen::VectorXd>& events) {
    decode(x, w);
    samples.resize(grid.size());
    for (std::size_t k = 0; k < grid.size(); ++k) sampleRows(w, static_cast<int>(k), samples[k]);
    events.resize(kEvents);
    for (int e = 0; e < kEvents; ++e) eventRows(w, e, events[static_cast<std::size_t>(e)]);
    ++evaluations;
  }

  void assemble(const Workspace& w, const std::vector<SampleOut>& samples,
                const std::vector<Eigen::VectorXd>& events, Evaluation& out) const {
    out.ineq.resize(n_ineq);
    out.eq.resize(n_eq);
    std::vector<const SampleOut*> ptr;
    for (std::size_t k = 0; k < samples.size(); ++k) {
      out.ineq.segment(ineq_off[k], ineq_cnt[k]) = samples[k].ineq;
      out.eq.segment(eq_off[k], eq_cnt[k]) = samples[k].eq;
      ptr.push_back(&samples[k]);
    }
    for (int e = 0; e < kEvents; ++e)
      out.eq.segment(event_eq_off[e], event_eq_cnt[e]) = events[static_cast<std::size_t>(e)];
    out.objective = objective(w, ptr, &out.terms);
    out.worst.fill(0.0);
    for (int i = 0; i < n_ineq; ++i) {
      auto& wv = out.worst[static_cast<std::size_t>(ineq_fam[static_cast<std::size_t>(i)])];
      wv = std::max(wv, out.ineq(i));
    }
    for (int i = 0; i < n_eq; ++i) {
      auto& wv = out.worst[static_cast<std::size_t>(eq_fam[static_cast<std::size_t>(i)])];
      wv = std::max(wv, std::abs(out.eq(i)));
    }
  }
};

}  // namespace overstep::planner
