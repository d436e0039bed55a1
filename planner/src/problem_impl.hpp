#pragma once
// Internal to the planner library: the problem's private state, shared by problem.cpp, guess.cpp
// and to_plan.cpp. Not installed, not included by users.
#include "overstep/planner/problem.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <nlohmann/json.hpp>
#include <thread>

#include "overstep/core/error.hpp"
#include "overstep/core/rotation.hpp"
#include "overstep/core/wrench.hpp"
#include "overstep/planner/spline.hpp"
#include "overstep/robots/collision.hpp"
#include "overstep/robots/leg.hpp"

namespace overstep::planner {
namespace detail {

inline constexpr int kRight = 0;
inline constexpr int kLeft = 1;
inline constexpr double kCopScale = 0.005;       // m, fixed scale of CoP rows
inline constexpr double kDistScale = 0.05;       // m, scale of clearance/distance rows
inline constexpr double kJointScale = 0.1;       // rad
inline constexpr double kFlexTorqueScale = 5.0;  // N m
inline constexpr double kKsSharpness = 40.0;
// Lift-off rows: scale of the lifting foot's normal-force row, a fraction of the weight.
inline constexpr double kLiftOffNormal = 0.03;
// Double-support wrench split (distributeWrench).
inline constexpr double kLoadFloor = 0.02;        // softness of the load share at zero force
inline constexpr double kLiftWeightFloor = 1e-3;  // lifting foot's share factor at lift-off

/// Smooth maximum of values (KS), used to aggregate limit ratios into one row.
inline double smoothMax(const Eigen::VectorXd& v, double rho) {
  const double m = v.maxCoeff();
  return m + std::log((rho * (v.array() - m)).exp().sum()) / rho;
}

using core::pitchOf;
using core::rollOf;
inline double yawOf(const Eigen::Matrix3d& R) { return std::atan2(R(1, 0), R(0, 0)); }

inline Eigen::Isometry3d placement(double x, double y) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() << x, y, 0.0;
  return X;
}

/// 6-D pose error of X relative to target, world-aligned [angular; linear].
inline core::Vector6d poseError(const Eigen::Isometry3d& target, const Eigen::Isometry3d& X) {
  core::Vector6d e;
  const Eigen::AngleAxisd aa(target.linear() * X.linear().transpose());
  e.head<3>() = aa.axis() * aa.angle();
  e.tail<3>() = target.translation() - X.translation();
  return e;
}

struct CapsuleRef {
  int frame = -1;
  Eigen::Vector3d p0, p1;
  double radius = 0.0;
  std::string link;
};

/// What one sample contributes.
struct SampleOut {
  Eigen::VectorXd ineq;
  Eigen::VectorXd eq;
  std::array<double, kObjectiveTerms> terms{};  // unweighted, normalised, per unit time
  Eigen::VectorXd tau;                          // actuated torques (for the torque-rate term)
  double t = 0.0;
};

/// The full state of the robot at one instant, and the contact wrenches.
struct State {
  Eigen::VectorXd q, v, a, tau;  // tau: inverse dynamics without contacts (all coordinates)
  Eigen::VectorXd tau_act;       // actuator torques of the robot in contact (seed eq. 1)
  core::Vector6d wrench[2];      // [torque; force] about each sole origin, world frame
  bool contact[2] = {false, false};
  Eigen::Isometry3d sole[2];
  core::Vector6d W_O;  // total contact wrench about the world origin
  double ik_error = 0.0;
  double reach = 0.0;        // hip-ankle distance of the IK leg
  double ds_balance = 0.0;   // DS: unreachable ankle-moment balance about the feet's line, N m
  int lifting = -1;          // DS before a lift-off: the lifting foot
  double lift_weight = 1.0;  // and its share factor (1 - s) + eps
  double ik_seed_gap = 0.0;  // DS: |IK leg - its spline|^2, rad^2
};

}  // namespace detail

using namespace detail;  // NOLINT: internal header

struct OverstepProblem::Impl {
  robots::WholeBodyModel model_template;
  PlannerConfig cfg;
  core::ObstacleSpec obstacle;
  double height = 0.2;
  double cop_box = 0.01;
  /// The homotopy's last stage (the target CoP box): the lift-off rows at the check's scale and
  /// the pelvis at pelvis_margin.
  bool finalBox() const { return std::abs(cop_box - cfg.cop_box) < 1e-12; }
  VariableLayout lay;
  int n_ctrl = 0;  // control points per curve
  double mass = 0.0, mg = 0.0, toes_x = 0.13;
  std::array<int, 12> leg_coord{};  // model coordinates of RLEG_JOINT0-5, LLEG_JOINT0-5
  std::array<int, 12> leg_act{};    // actuated indices
  std::array<int, 4> flex_coord{};  // RLEG roll, pitch, LLEG roll, pitch
  int sole_frame[2]{};
  int hip_frame[2]{};                       // hip pitch link origin per leg (reach)
  int ankle_frame[2]{};                     // ankle pitch link origin per leg (reach)
  std::array<std::string, 3> leg_links[2];  // thigh, shank and foot bodies per leg
  int head_frame = -1;
  int base_frame = -1;
  core::FootDescription foot[2];
  std::vector<CapsuleRef> caps;
  std::vector<int> leg_caps[2];  // capsules of each leg (indices into caps)
  std::vector<std::pair<int, int>> self_pairs;
  robots::ObstacleGeometry obstacle_geom;
  Eigen::VectorXd q_rest;  // half-sitting (upper body posture held)

  std::vector<GridPoint> grid;  // (phase, s); t filled per evaluation
  std::vector<int> ineq_off, ineq_cnt, eq_off, eq_cnt;
  std::vector<Family> ineq_fam, eq_fam;
  int n_ineq = 0, n_eq = 0;
  static constexpr int kEvents = 4;
  static constexpr int kLiftOffRows = 3;  // the lifting foot's normal force and tipping moments
  int event_eq_off[kEvents]{};
  int event_eq_cnt[kEvents]{};
  // Per phase, the foot whose placement fixes the floating base (phaseTable()). At a switch the
  // leg changing representation (double-support inverse
  // kinematics <-> spline) is that double-support phase's other leg.
  int anchor_of[kPhaseCount]{};

  struct Workspace {
    std::unique_ptr<robots::WholeBodyModel> model;
    std::unique_ptr<PhaseSpline> spline;
    Eigen::MatrixXd legs_c, flex_c;  // full control points (12 x C, 4 x C)
    Eigen::Vector2d feet[3];         // right start, right landing, left landing
    std::unique_ptr<PhaseTiming> timing;
    State st;
  };
  std::vector<Workspace> ws;
  std::atomic<int> evaluations{0};
  WorkAccount work;

  // Baseline cache (for finite differences).
  std::vector<SampleOut> base_samples;
  std::vector<Eigen::VectorXd> base_events;
  Eigen::VectorXd base_x;

  Impl(const robots::WholeBodyModel& m, PlannerConfig c, core::ObstacleSpec o)
      : model_template(m), cfg(std::move(c)), obstacle(o) {}

  // -------------------------------------------------------------- set-up
  void setUp() {
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
    auto capIndex = [&](const std::string& link) {
      for (std::size_t i = 0; i < caps.size(); ++i)
        if (caps[i].link == link) return static_cast<int>(i);
      return -1;
    };
    for (int f = 0; f < 2; ++f)
      for (const std::string& l : leg_links[f])  // every capsule of the thigh, shank and foot
        for (std::size_t i = 0; i < caps.size(); ++i)
          if (caps[i].link == l) leg_caps[f].push_back(static_cast<int>(i));
    // Self-collision pairs that a stepping motion can bring together: legs with each other and
    // the hanging arms with the thighs.
    for (int a : leg_caps[kRight])
      for (int b : leg_caps[kLeft]) self_pairs.emplace_back(a, b);
    for (int f = 0; f < 2; ++f) {
      const std::string arm = f == kRight ? "RARM_" : "LARM_";
      for (const std::string& l : {arm + "LINK3", arm + "LINK6"}) {  // forearm, hand
        const int a = capIndex(l), b = capIndex(leg_links[f][0]);
        if (a >= 0 && b >= 0) self_pairs.emplace_back(a, b);
      }
    }
    {
      robots::WholeBodyModel tmp(model_template);
      q_rest = tmp.halfSitting();
    }
    height = obstacle.height;
    cop_box = cfg.cop_box;
    obstacle_geom = robots::ObstacleGeometry::fromSpec(obstacle, toes_x);

    PhaseSpline probe(cfg.spline_intervals);
    n_ctrl = probe.controlPointCount();
    lay.free_cp = n_ctrl - 4;
    if (lay.free_cp < 2) throw InputError("planner: spline_intervals too small");
    lay.durations = 0;
    lay.feet = kPhaseCount;
    lay.legs = lay.feet + 6;
    lay.flex = lay.legs + VariableLayout::kLegJoints * lay.free_cp;
    lay.total = lay.flex + VariableLayout::kFlex * lay.free_cp;

    // Grid and row layout.
    // Single-support phases are sampled on their closed interval (s = 0 .. 1): the stance ankle
    // obeys its dynamics right up to touchdown (without the s = 1 sample its residual reached
    // 10 N m in the last 85 ms; measured with overstep check). Double-support phases end at a
    // lift-off, where every contact row of the unloading foot degenerates (F = 0): they stop one
    // sample short (the lift-off event rows hold there), except the final phase.
    for (int i = 0; i < kPhaseCount; ++i) {
      const int nph = cfg.samples_per_phase[static_cast<std::size_t>(i)];
      const auto& ph = phaseTable()[static_cast<std::size_t>(i)];
      const bool closed = !(ph.right_contact && ph.left_contact) || i + 1 == kPhaseCount;
      for (int k = 0; k <= (closed ? nph : nph - 1); ++k)
        grid.push_back({i, static_cast<double>(k) / nph, 0.0});
    }
    for (const auto& g : grid) {
      const auto& ph = phaseTable()[static_cast<std::size_t>(g.phase)];
      const bool ds = ph.right_contact && ph.left_contact;
      ineq_off.push_back(n_ineq);
      eq_off.push_back(n_eq);
      const int contacts = ds ? 2 : 1;
      for (int c = 0; c < contacts; ++c) {
        for (int r = 0; r < 4; ++r) ineq_fam.push_back(Family::CoP);
        for (int r = 0; r < 6; ++r) ineq_fam.push_back(Family::Friction);
        ineq_fam.push_back(Family::Unilateral);
      }
      if (!ds)
        for (int r = 0; r < 4; ++r) ineq_fam.push_back(Family::Clearance);
      ineq_fam.push_back(Family::ObstacleCollision);
      ineq_fam.push_back(Family::SelfCollision);
      for (int r = 0; r < 4; ++r) ineq_fam.push_back(Family::Pelvis);
      ineq_fam.push_back(Family::Velocity);
      ineq_fam.push_back(Family::Torque);
      if (ds) {
        for (int r = 0; r < 12; ++r) ineq_fam.push_back(Family::JointLimits);
        ineq_fam.push_back(Family::Reach);
        for (int r = 0; r < 2; ++r) ineq_fam.push_back(Family::Dynamics);  // sway balance band
      }
      const int dyn_eq = ds ? 0 : 4;
      for (int r = 0; r < dyn_eq; ++r) eq_fam.push_back(Family::Dynamics);
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
      for (int r = 0; r < 12; ++r) eq_fam.push_back(Family::Switching);
      if (e == 0 || e == 2)
        for (int r = 0; r < kLiftOffRows; ++r) eq_fam.push_back(Family::LiftOff);

      event_eq_cnt[e] = static_cast<int>(eq_fam.size()) - n_eq;
      n_eq = static_cast<int>(eq_fam.size());
    }

    const int threads = std::max(1, cfg.solver.threads);
    ws.resize(static_cast<std::size_t>(threads));
    for (auto& w : ws) {
      w.model = std::make_unique<robots::WholeBodyModel>(model_template);
      w.spline = std::make_unique<PhaseSpline>(cfg.spline_intervals);
    }
  }

  // -------------------------------------------------------------- decoding x
  void expand(const Eigen::VectorXd& x, int offset,
              Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> c) const {
    const int F = lay.free_cp;
    c.head(3).setConstant(x(offset));
    for (int i = 1; i < F - 1; ++i) c(i + 2) = x(offset + i);
    c.tail(3).setConstant(x(offset + F - 1));
  }

  void decode(const Eigen::VectorXd& x, Workspace& w) const {
    w.timing = std::make_unique<PhaseTiming>(x.head(kPhaseCount));
    w.spline->setTiming(*w.timing);
    w.legs_c.resize(12, n_ctrl);
    w.flex_c.resize(4, n_ctrl);
    for (int j = 0; j < 12; ++j) expand(x, lay.legs + j * lay.free_cp, w.legs_c.row(j));
    for (int j = 0; j < 4; ++j) expand(x, lay.flex + j * lay.free_cp, w.flex_c.row(j));
    for (int f = 0; f < 3; ++f) w.feet[f] = x.segment<2>(lay.feet + 2 * f);
  }

  /// Where a foot stands in a phase in which it is in contact.
  Eigen::Isometry3d footPlacement(int phase, int foot_index, const Workspace& w) const {
    if (foot_index == kLeft)
      return phase <= 2 ? placement(0.0, cfg.start_half_width)  // left start
                        : placement(w.feet[2].x(), w.feet[2].y());
    return phase == 0 ? placement(w.feet[0].x(), w.feet[0].y())  // right start
                      : placement(w.feet[1].x(), w.feet[1].y());
  }
  Eigen::Isometry3d anchorPlacement(int phase, const Workspace& w) const {
    return footPlacement(phase, anchor_of[phase], w);
  }
  Eigen::Isometry3d otherPlacement(int phase, const Workspace& w) const {
    return footPlacement(phase, 1 - anchor_of[phase], w);
  }

  /// Builds the robot state at time t in the contact configuration of `phase`.
  void buildState(Workspace& w, int phase, double t) const {
    robots::WholeBodyModel& m = *w.model;
    State& st = w.st;
    const int n = m.dofs();
    st.q = q_rest;
    st.v.setZero(n);
    st.a.setZero(n);
    const PhaseSpline::Basis b = w.spline->evaluate(t);
    const int nb = static_cast<int>(b.value.size());
    const auto legs = w.legs_c.middleCols(b.first, nb);
    const auto flex = w.flex_c.middleCols(b.first, nb);
    const Eigen::VectorXd lq = legs * b.value, lv = legs * b.d1, la = legs * b.d2;
    const Eigen::VectorXd fq = flex * b.value, fv = flex * b.d1, fa = flex * b.d2;
    for (int j = 0; j < 12; ++j) {
      st.q(leg_coord[static_cast<std::size_t>(j)]) = lq(j);
      st.v(leg_coord[static_cast<std::size_t>(j)]) = lv(j);
      st.a(leg_coord[static_cast<std::size_t>(j)]) = la(j);
    }
    for (int j = 0; j < 4; ++j) {
      st.q(flex_coord[static_cast<std::size_t>(j)]) = fq(j);
      st.v(flex_coord[static_cast<std::size_t>(j)]) = fv(j);
      st.a(flex_coord[static_cast<std::size_t>(j)]) = fa(j);
    }
    const auto& ph = phaseTable()[static_cast<std::size_t>(phase)];
    const int anchor = anchor_of[phase];
    const int other = 1 - anchor;
    m.anchorBase(sole_frame[anchor], anchorPlacement(phase, w), st.q, st.v, st.a);
    st.contact[kRight] = ph.right_contact;
    st.contact[kLeft] = ph.left_contact;
    st.ik_error = 0.0;
    st.reach = 0.0;
    st.ik_seed_gap = 0.0;
    if (ph.right_contact && ph.left_contact) {
      Eigen::Matrix<double, 6, 1> seed;
      for (int j = 0; j < 6; ++j)
        seed(j) = st.q(leg_coord[static_cast<std::size_t>(6 * other + j)]);
      solveOtherLeg(w, other, otherPlacement(phase, w));
      for (int j = 0; j < 6; ++j) {
        const double gap = st.q(leg_coord[static_cast<std::size_t>(6 * other + j)]) - seed(j);
        st.ik_seed_gap += gap * gap;
      }
    }
    st.tau = m.inverseDynamics();
    st.W_O = m.contactWrenchFromBase(st.tau);
    for (int f = 0; f < 2; ++f) st.sole[f] = m.framePose(sole_frame[f]);
    st.lifting = liftingFoot(phase);
    st.lift_weight = liftWeight(w, phase, t);
    distributeWrench(w);
    contactTorques(w);
  }

  /// Actuator torques of the robot in contact (seed eq. 1): the actuated rows of inverse dynamics
  /// minus the feet's J^T w (the torque rows, seed eq. 27 and the plan file use these).
  void contactTorques(Workspace& w) const {
    State& st = w.st;
    st.tau_act = w.model
                     ->torquesInContact(st.tau, {{sole_frame[kRight], st.wrench[kRight]},
                                                 {sole_frame[kLeft], st.wrench[kLeft]}})
                     .segment(6, model_template.actuatedCount());
  }

  /// Damped-Newton inverse kinematics of one leg (6 joints, base fixed) putting its sole frame
  /// at `target`; each joint is clamped to [lower, upper] of `safe` ? the planner's safe range :
  /// the mechanical range. Stops below `tol` or after `iterations`; returns the final pose error.
  /// Damping keeps steps finite at the reach limit.
  double solveLegIk(robots::WholeBodyModel& m, int leg, const Eigen::Isometry3d& target,
                    Eigen::VectorXd& q, double damping, int iterations, double tol,
                    bool safe) const {
    const int f = sole_frame[leg];
    const auto& joints = model_template.description().actuated;
    double err = 0.0;
    Eigen::Matrix<double, 6, 6> J;
    for (int it = 0; it < iterations; ++it) {
      m.setPositions(q);
      const core::Vector6d e = poseError(target, m.framePose(f));
      err = e.norm();
      if (err < tol) break;
      const Eigen::MatrixXd Jf = m.frameJacobian(f);
      for (int j = 0; j < 6; ++j)
        J.col(j) = Jf.col(leg_coord[static_cast<std::size_t>(6 * leg + j)]);
      const Eigen::Matrix<double, 6, 6> A =
          J.transpose() * J + damping * Eigen::Matrix<double, 6, 6>::Identity();
      const Eigen::Matrix<double, 6, 1> dq = A.ldlt().solve(J.transpose() * e);
      for (int j = 0; j < 6; ++j) {
        const int c = leg_coord[static_cast<std::size_t>(6 * leg + j)];
        const auto& aj =
            joints[static_cast<std::size_t>(leg_act[static_cast<std::size_t>(6 * leg + j)])];
        q(c) = std::clamp(q(c) + dq(j), safe ? aj.safeLower() : aj.lower,
                          safe ? aj.safeUpper() : aj.upper);
      }
    }
    return err;
  }

  void solveOtherLeg(Workspace& w, int leg, const Eigen::Isometry3d& target) const {
    robots::WholeBodyModel& m = *w.model;
    State& st = w.st;
    const int f = sole_frame[leg];
    int cols[6];
    for (int j = 0; j < 6; ++j) cols[j] = leg_coord[static_cast<std::size_t>(6 * leg + j)];
    Eigen::Matrix<double, 6, 6> J;
    // From the leg's spline (a seed the optimizer moves freely), and if that does not converge
    // (a seed far off can lead damped Newton astray: measured, a foot 0.6 m up on a restored
    // point), again from half-sitting; the better result is kept.
    st.ik_error = solveLegIk(m, leg, target, st.q, 1e-8, 30, 1e-11, false);
    if (st.ik_error > 1e-9) {
      Eigen::VectorXd q_seed = st.q;  // the leg IK changes only the leg's joints
      for (int j = 0; j < 6; ++j) q_seed(cols[j]) = q_rest(cols[j]);
      const double e2 = solveLegIk(m, leg, target, q_seed, 1e-8, 60, 1e-11, false);
      if (e2 < st.ik_error) {
        st.q = q_seed;
        st.ik_error = e2;
      }
    }
    m.setPositions(st.q);
    const Eigen::MatrixXd Jf = m.frameJacobian(f);
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
    st.reach =
        (m.framePose(ankle_frame[leg]).translation() - m.framePose(hip_frame[leg]).translation())
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
    st.tau = m.inverseDynamics();
    st.W_O = m.contactWrenchFromBase(st.tau);
    for (int f = 0; f < 2; ++f) st.sole[f] = m.framePose(sole_frame[f]);
    st.lifting = liftingFoot(phase);
    st.lift_weight = liftWeight(w, phase, t);
    distributeWrench(w);
    contactTorques(w);
  }

  /// The passive (elastic) equations of motion at the current state: in single support the four
  /// elastic joints' residuals (N m), in double support the sway balance about the feet's line.
  Eigen::VectorXd passiveResidual(Workspace& w, int phase) const {
    const State& st = w.st;
    const auto& ph = phaseTable()[static_cast<std::size_t>(phase)];
    if (ph.right_contact && ph.left_contact) return Eigen::VectorXd::Constant(1, st.ds_balance);
    const int stance = ph.right_contact ? kRight : kLeft;
    const Eigen::MatrixXd J = w.model->frameJacobian(sole_frame[stance]);
    Eigen::VectorXd r(4);
    for (int f = 0; f < 2; ++f)
      for (int e = 0; e < 2; ++e) {
        const int c = flex_coord[static_cast<std::size_t>(2 * f + e)];
        r(2 * f + e) = st.tau(c) - (f == stance ? J.col(c).dot(st.wrench[f]) : 0.0);
      }
    return r;
  }

  /// Directions (columns, tangent space) in which the passive coordinates can move with every
  /// actuated joint held and the stance sole(s) fixed: single support, each elastic joint with the
  /// base following the stance foot; double support, the whole body rotating about the line
  /// through both bushing centres (both bushings deflect along it, the joints stay).
  Eigen::MatrixXd passiveDirections(Workspace& w, int phase, const Eigen::VectorXd& q) const {
    robots::WholeBodyModel& m = *w.model;
    const auto& ph = phaseTable()[static_cast<std::size_t>(phase)];
    const int anchor = anchor_of[phase];
    const bool ds = ph.right_contact && ph.left_contact;
    m.setPositions(q);
    const Eigen::Isometry3d X = m.framePose(sole_frame[anchor]);
    const double eps = 1e-6;
    const int cols = ds ? 1 : 4;
    Eigen::MatrixXd U(m.dofs(), cols);
    Eigen::Vector4d dir[4];
    if (ds) {
      const Eigen::Vector3d line = (m.framePose(sole_frame[kLeft]).translation() -
                                    m.framePose(sole_frame[kRight]).translation())
                                       .normalized();
      Eigen::Vector4d d4;
      for (int f = 0; f < 2; ++f) {
        const Eigen::Matrix3d R = m.framePose(sole_frame[f]).linear();
        d4(2 * f) = R.col(0).dot(line);      // roll: about the foot's x
        d4(2 * f + 1) = R.col(1).dot(line);  // pitch: about the foot's y
      }
      dir[0] = d4;
    } else {
      for (int i = 0; i < 4; ++i) dir[i] = Eigen::Vector4d::Unit(i);
    }
    Eigen::VectorXd v0 = Eigen::VectorXd::Zero(m.dofs()), a0 = v0;
    for (int c = 0; c < cols; ++c) {
      Eigen::VectorXd qp = q;
      for (int i = 0; i < 4; ++i) qp(flex_coord[static_cast<std::size_t>(i)]) += eps * dir[c](i);
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
  /// the dense motion leaves a residual F(t) (N m). This integrates the linearised correction
  /// delta along the passive directions U (A delta'' + B delta' + C delta = -F, A, B, C by finite
  /// differences at every dense sample; Newmark average acceleration, 1 ms steps) and adds
  /// U delta to q (U delta', U delta'' to v, a): the motion the robot's passive joints make under
  /// the planned actuated trajectories. Corrections are of the order of 1e-4 rad; the actuated
  /// joints are untouched. At a contact switch delta is carried over by least squares.
  /// Before a lift-off the correction is blended back to zero (quintic Hermite over the double-
  /// support phase: value, rate and acceleration): there the unloading foot's whole wrench must
  /// vanish, and the correction's spring torque (k delta) would reappear as a moment on a foot that
  /// carries no load (measured: 0.27 N m under 2 N, a CoP 11 cm off, 4 ms before the first
  /// lift-off). The blend leaves that torque as a residual of the passive dynamics instead, spread
  /// over the phase.
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
      U[k] = passiveDirections(w, phase, q[k]);
      const int c = static_cast<int>(U[k].cols());
      stateFrom(w, phase, when[k].first, q[k], v[k], a[k]);
      F[k] = passiveResidual(w, phase);
      A[k].resize(c, c);
      B[k].resize(c, c);
      C[k].resize(c, c);
      for (int j = 0; j < c; ++j) {
        stateFrom(w, phase, when[k].first, q[k], v[k], a[k] + h * U[k].col(j));
        A[k].col(j) = (passiveResidual(w, phase) - F[k]) / h;
        stateFrom(w, phase, when[k].first, q[k], v[k] + h * U[k].col(j), a[k]);
        B[k].col(j) = (passiveResidual(w, phase) - F[k]) / h;
        stateFrom(w, phase, when[k].first, m.integrate(q[k], U[k].col(j), h), v[k], a[k]);
        C[k].col(j) = (passiveResidual(w, phase) - F[k]) / h;
      }
    }
    // Newmark (beta 1/4, gamma 1/2) on each interval between dense samples, in <= 1 ms steps.
    Eigen::VectorXd d = Eigen::VectorXd::Zero(U[0].cols()), dv = d, da = d;
    da = -A[0].fullPivLu().solve(F[0]);
    std::vector<Eigen::VectorXd> D(n), DV(n), DA(n);
    auto store = [&](std::size_t k) {
      D[k] = d;
      DV[k] = dv;
      DA[k] = da;
    };
    std::size_t phase_first = 0;  // first sample of the current phase
    auto blendToZero = [&](std::size_t k_end) {
      const double t0 = when[phase_first].first, L = when[k_end].first - t0;
      if (L <= 1e-9) return;
      // Quintic blend: the correction, its rate and its acceleration all reach zero at the
      // lift-off and all start from zero at the phase's start.
      const Eigen::VectorXd dT = D[k_end], vT = DV[k_end], aT = DA[k_end];
      for (std::size_t k = phase_first; k <= k_end; ++k) {
        const double x = (when[k].first - t0) / L, x2 = x * x, x3 = x2 * x;
        const double hv = 10 * x3 - 15 * x3 * x + 6 * x3 * x2;
        const double hv1 = 30 * x2 - 60 * x3 + 30 * x3 * x, hv2 = 60 * x - 180 * x2 + 120 * x3;
        const double hd = -4 * x3 + 7 * x3 * x - 3 * x3 * x2;
        const double hd1 = -12 * x2 + 28 * x3 - 15 * x3 * x, hd2 = -24 * x + 84 * x2 - 60 * x3;
        const double ha = 0.5 * x3 - x3 * x + 0.5 * x3 * x2;
        const double ha1 = 1.5 * x2 - 4 * x3 + 2.5 * x3 * x, ha2 = 3 * x - 12 * x2 + 10 * x3;
        D[k] -= dT * hv + vT * (L * hd) + aT * (L * L * ha);
        DV[k] -= (dT * hv1 + vT * (L * hd1) + aT * (L * L * ha1)) / L;
        DA[k] -= (dT * hv2 + vT * (L * hd2) + aT * (L * L * ha2)) / (L * L);
      }
      d = D[k_end];
      dv = DV[k_end];
      da = DA[k_end];
    };
    auto apply = [&](std::size_t k) {
      d = D[k];
      dv = DV[k];
      da = DA[k];
      // U keeps the anchor sole fixed to first order; re-anchoring the base keeps it exactly.
      const auto& ph = phaseTable()[static_cast<std::size_t>(when[k].second)];
      const int anchor = anchor_of[when[k].second];
      m.setPositions(q[k]);
      const Eigen::Isometry3d X = m.framePose(sole_frame[anchor]);
      q[k] = m.integrate(q[k], U[k] * d, 1.0);
      v[k] += U[k] * dv;
      a[k] += U[k] * da;
      m.anchorBase(sole_frame[anchor], X, q[k], v[k], a[k]);
      if (ph.right_contact && ph.left_contact) {
        // The other sole back onto its placement exactly (the correction moves it by second-order
        // amounts): its leg's joints by inverse kinematics, as buildState() does.
        w.st.q = q[k];
        w.st.v = v[k];
        w.st.a = a[k];
        solveOtherLeg(w, 1 - anchor, otherPlacement(when[k].second, w));
        q[k] = w.st.q;
        v[k] = w.st.v;
        a[k] = w.st.a;
      }
    };
    store(0);
    for (std::size_t k = 0; k + 1 < n; ++k) {
      if (when[k + 1].second != when[k].second) {
        blendToZero(k);
        phase_first = k + 1;
        // Contact switch: carry the correction over by least squares in the new directions.
        const auto ls = U[k + 1].colPivHouseholderQr();
        const Eigen::VectorXd d2 = ls.solve(U[k] * d), dv2 = ls.solve(U[k] * dv);
        d = d2;
        dv = dv2;
        // The acceleration from the new phase's equations (the contact wrench may jump).
        da = A[k + 1].fullPivLu().solve(-F[k + 1] - B[k + 1] * dv - C[k + 1] * d);
        store(k + 1);
        continue;
      }
      const double T = when[k + 1].first - when[k].first;
      const int steps = std::max(1, static_cast<int>(std::ceil(T / 1e-3)));
      const double dt = T / steps;
      for (int s = 1; s <= steps; ++s) {
        const double f = static_cast<double>(s) / steps;
        const Eigen::MatrixXd As = (1 - f) * A[k] + f * A[k + 1];
        const Eigen::MatrixXd Bs = (1 - f) * B[k] + f * B[k + 1];
        const Eigen::MatrixXd Cs = (1 - f) * C[k] + f * C[k + 1];
        const Eigen::VectorXd Fs = (1 - f) * F[k] + f * F[k + 1];
        const Eigen::VectorXd vp = dv + 0.5 * dt * da;
        const Eigen::VectorXd dp = d + dt * dv + 0.25 * dt * dt * da;
        const Eigen::MatrixXd K = As + 0.5 * dt * Bs + 0.25 * dt * dt * Cs;
        const Eigen::VectorXd an = K.fullPivLu().solve(-Fs - Bs * vp - Cs * dp);
        d = dp + 0.25 * dt * dt * an;
        dv = vp + 0.5 * dt * an;
        da = an;
      }
      store(k + 1);
    }
    clearDoubleSupport(when, D, DV, DA);
    for (std::size_t k = 0; k < n; ++k) apply(k);
  }

  /// No correction in double support. There the solver's own motion leaves
  /// only the sway-balance band (ds_balance_band) as the passive residual, while the integrated
  /// correction moved the lightly loaded landing foot's moments: 1.3 mm of CoP beyond the box
  /// 40 ms after the 20 cm run's second touchdown, even ramped in over 0.1 s (measured).
  static void clearDoubleSupport(const std::vector<std::pair<double, int>>& when,
                                 std::vector<Eigen::VectorXd>& D, std::vector<Eigen::VectorXd>& DV,
                                 std::vector<Eigen::VectorXd>& DA) {
    for (std::size_t k = 0; k < when.size(); ++k) {
      const auto& ph = phaseTable()[static_cast<std::size_t>(when[k].second)];
      if (!(ph.right_contact && ph.left_contact)) continue;
      D[k].setZero();
      DV[k].setZero();
      DA[k].setZero();
    }
  }

  /// The lifting foot's share factor in a double support that ends with a lift-off: (1 - s) + a
  /// floor, s the phase fraction; 1 otherwise. It is fixed at each sample (s does not depend on
  /// the variables), so the split stays smooth in them. Only in the homotopy's last stage, like
  /// the tight lift-off rows: from the first stage on, the 5 cm stage took 286 SLSQP iterations
  /// instead of 56 and the 20 cm run reached its 20 cm stage after 394 s instead of 127 s
  /// (measured).
  double liftWeight(const Workspace& w, int phase, double t) const {
    if (liftingFoot(phase) < 0 || !finalBox()) return 1.0;
    const double s =
        std::clamp((t - w.timing->start(phase)) / w.timing->durations()(phase), 0.0, 1.0);
    return (1.0 - s) + kLiftWeightFloor;
  }

  /// The foot that lifts at the end of double-support `phase` (-1: none).
  static int liftingFoot(int phase) { return phase == 0 ? kRight : phase == 2 ? kLeft : -1; }

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
    robots::WholeBodyModel& m = *w.model;
    st.wrench[kRight].setZero();
    st.wrench[kLeft].setZero();
    if (st.contact[kRight] != st.contact[kLeft]) {
      const int f = st.contact[kRight] ? kRight : kLeft;
      st.wrench[f] = core::shiftWrench(st.W_O, Eigen::Vector3d::Zero(), st.sole[f].translation());
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
      const Eigen::MatrixXd J = m.frameJacobian(sole_frame[f]);
      for (int e = 0; e < 2; ++e) {
        const int c = flex_coord[static_cast<std::size_t>(2 * f + e)];
        A.block<1, 6>(6 + 2 * f + e, 6 * f) = J.col(c).transpose();
        b(6 + 2 * f + e) = st.tau(c);
      }
    }
    b.head<6>() = st.W_O;
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
        rho(f) = 0.5 * (fz + std::sqrt(fz * fz + kLoadFloor * kLoadFloor)) *
                 (f == st.lifting ? st.lift_weight : 1.0);
      }
    }
    st.wrench[kRight] = z.head<6>();
    st.wrench[kLeft] = z.segment<6>(6);
  }

  // -------------------------------------------------------------- rows of one sample
  /// The swing sole corners' minimal height: swing_clearance sin(pi s), whose slope at the
  /// contact switches keeps the last samples before a touchdown a few millimetres up (at
  /// sin^2 the sample 8 % of the swing before touchdown asked for 1.3 mm, and a corner dipped
  /// 1.8 mm below the ground between it and the touchdown; measured, docs/planner.md).
  double minHeight(double s) const { return cfg.swing_clearance * std::sin(M_PI * s); }

  void sampleRows(Workspace& w, int k, SampleOut& out) const {
    const GridPoint& g = grid[static_cast<std::size_t>(k)];
    const double t = w.timing->timeOf(g.phase, g.s);
    buildState(w, g.phase, t);
    robots::WholeBodyModel& m = *w.model;
    const State& st = w.st;
    const auto& d = model_template.description();
    out.t = t;
    out.ineq.resize(ineq_cnt[static_cast<std::size_t>(k)]);
    out.eq.resize(eq_cnt[static_cast<std::size_t>(k)]);
    int r = 0;
    const double h = 0.5 * cop_box * cfg.limit_margin;
    const double mu = cfg.friction / std::sqrt(2.0) * cfg.limit_margin;
    const double tors = cfg.torsion * cfg.limit_margin;
    const bool ds = st.contact[kRight] && st.contact[kLeft];
    for (int f = 0; f < 2; ++f) {
      if (!st.contact[f]) continue;
      const Eigen::Matrix3d Rt = st.sole[f].linear().transpose();
      const Eigen::Vector3d mo = Rt * st.wrench[f].head<3>();
      const Eigen::Vector3d fo = Rt * st.wrench[f].tail<3>();
      const double s_cop = 1.0 / (mg * kCopScale);
      out.ineq(r++) = (-mo.y() - h * fo.z()) * s_cop;  // cop_x <= h
      out.ineq(r++) = (mo.y() - h * fo.z()) * s_cop;   // cop_x >= -h
      out.ineq(r++) = (mo.x() - h * fo.z()) * s_cop;   // cop_y <= h
      out.ineq(r++) = (-mo.x() - h * fo.z()) * s_cop;  // cop_y >= -h
      out.ineq(r++) = (fo.x() - mu * fo.z()) / mg;
      out.ineq(r++) = (-fo.x() - mu * fo.z()) / mg;
      out.ineq(r++) = (fo.y() - mu * fo.z()) / mg;
      out.ineq(r++) = (-fo.y() - mu * fo.z()) / mg;
      out.ineq(r++) = (mo.z() - tors * fo.z()) / (mg * cfg.torsion);
      out.ineq(r++) = (-mo.z() - tors * fo.z()) / (mg * cfg.torsion);
      // Unilateral with a minimal normal force; an unloading foot may reach zero at lift-off.
      double fmin = cfg.min_normal_force;
      if (f == liftingFoot(g.phase)) fmin *= (1.0 - g.s);
      out.ineq(r++) = (fmin - fo.z()) / mg;
    }
    if (!ds) {
      const int sw = st.contact[kRight] ? kLeft : kRight;
      const auto& sole = foot[sw].sole;
      // At touchdown (s = 1) the switching rows pin the sole to the ground: corner rows there
      // would duplicate them (degenerate constraints stall SLSQP), so they are kept inactive.
      const double hmin = g.s == 1.0 ? -kDistScale : minHeight(g.s);
      const double xs[2] = {sole.x_front, -sole.x_back};
      const double ys[2] = {foot[sw].yMin(), foot[sw].yMax()};
      for (double cx : xs)
        for (double cy : ys) {
          const Eigen::Vector3d c = st.sole[sw] * Eigen::Vector3d(cx, cy, 0.0);
          out.ineq(r++) = (hmin - c.z()) / kDistScale;
        }
    }
    // Capsules in the world, and how far each can travel before the nearer sample (swept
    // clearance; 0 when off).
    std::vector<robots::Capsule> wc(caps.size());
    std::vector<double> sweep(caps.size(), 0.0);
    const double half_h = 0.5 * w.timing->durations()(g.phase) /
                          cfg.samples_per_phase[static_cast<std::size_t>(g.phase)];
    for (std::size_t i = 0; i < caps.size(); ++i) {
      const Eigen::Isometry3d X = m.framePose(caps[i].frame);
      wc[i] = {X * caps[i].p0, X * caps[i].p1, caps[i].radius};
      if (cfg.swept_clearance > 0.0) {
        const core::Vector6d V = m.frameVelocity(caps[i].frame);
        const Eigen::Vector3d w0 = V.head<3>(), v0 = V.tail<3>();
        const double s0 = (v0 + w0.cross(wc[i].p0 - X.translation())).norm();
        const double s1 = (v0 + w0.cross(wc[i].p1 - X.translation())).norm();
        sweep[i] = cfg.swept_clearance * half_h * std::max(s0, s1);
      }
    }
    {
      Eigen::VectorXd dist(static_cast<Eigen::Index>(leg_caps[0].size() + leg_caps[1].size()));
      Eigen::Index i = 0;
      core::ObstacleSpec spec = obstacle;
      spec.height = height;
      const robots::ObstacleGeometry og = robots::ObstacleGeometry::fromSpec(spec, toes_x);
      for (int f = 0; f < 2; ++f)
        for (int c : leg_caps[f])
          dist(i++) = robots::obstacleDistance(wc[static_cast<std::size_t>(c)], og) -
                      sweep[static_cast<std::size_t>(c)];
      out.ineq(r++) =
          (cfg.obstacle_clearance - robots::smoothMin(dist, cfg.smooth_min_rho)) / kDistScale;
    }
    {
      Eigen::VectorXd dist(static_cast<Eigen::Index>(self_pairs.size()));
      for (std::size_t i = 0; i < self_pairs.size(); ++i)
        dist(static_cast<Eigen::Index>(i)) =
            robots::capsuleDistance(wc[static_cast<std::size_t>(self_pairs[i].first)],
                                    wc[static_cast<std::size_t>(self_pairs[i].second)]) -
            sweep[static_cast<std::size_t>(self_pairs[i].first)] -
            sweep[static_cast<std::size_t>(self_pairs[i].second)];
      out.ineq(r++) =
          (cfg.self_clearance - robots::smoothMin(dist, cfg.smooth_min_rho)) / kDistScale;
    }
    const Eigen::Matrix3d Rb = m.framePose(base_frame).linear();
    const double roll = rollOf(Rb), pitch = pitchOf(Rb),
                 eps = cfg.pelvis_tilt * (finalBox() ? cfg.pelvis_margin : cfg.limit_margin);
    out.ineq(r++) = (roll - eps) / eps;
    out.ineq(r++) = (-roll - eps) / eps;
    out.ineq(r++) = (pitch - eps) / eps;
    out.ineq(r++) = (-pitch - eps) / eps;
    {
      Eigen::VectorXd ratio(24);
      for (int j = 0; j < 12; ++j) {
        const auto& aj = d.actuated[static_cast<std::size_t>(leg_act[static_cast<std::size_t>(j)])];
        const double qd = st.v(leg_coord[static_cast<std::size_t>(j)]);
        ratio(2 * j) = qd / aj.velocity;
        ratio(2 * j + 1) = -qd / aj.velocity;
      }
      out.ineq(r++) = smoothMax(ratio, kKsSharpness) - cfg.velocity_margin;
    }
    {
      const int na = model_template.actuatedCount();
      Eigen::VectorXd ratio(2 * na);
      for (int j = 0; j < na; ++j) {
        const double tq = st.tau_act(j);
        ratio(2 * j) = tq / d.actuated[static_cast<std::size_t>(j)].torque;
        ratio(2 * j + 1) = -ratio(2 * j);
      }
      out.ineq(r++) = smoothMax(ratio, kKsSharpness) - 1.0;
    }
    int e = 0;
    if (ds) {
      const int leg = 1 - anchor_of[g.phase];
      for (int j = 0; j < 6; ++j) {
        const int a = leg_act[static_cast<std::size_t>(6 * leg + j)];
        const auto& aj = d.actuated[static_cast<std::size_t>(a)];
        const double qj = st.q(model_template.actuatedCoordinate(a));
        out.ineq(r++) = (qj - aj.safeUpper()) / kJointScale;
        out.ineq(r++) = (aj.safeLower() - qj) / kJointScale;
      }
      out.ineq(r++) = (st.reach - cfg.leg_reach) / kDistScale;
      out.ineq(r++) = (st.ds_balance - cfg.ds_balance_band) / kFlexTorqueScale;
      out.ineq(r++) = (-st.ds_balance - cfg.ds_balance_band) / kFlexTorqueScale;
    } else {
      const int stance = st.contact[kRight] ? kRight : kLeft;
      const Eigen::MatrixXd J = m.frameJacobian(sole_frame[stance]);
      for (int f = 0; f < 2; ++f) {
        for (int k2 = 0; k2 < 2; ++k2) {
          const int c = flex_coord[static_cast<std::size_t>(2 * f + k2)];
          double res = st.tau(c);
          if (f == stance) res -= J.col(c).dot(st.wrench[f]);
          out.eq(e++) = res / kFlexTorqueScale;
        }
      }
    }
    // Objective terms (per unit time, normalised).
    auto& T = out.terms;
    T.fill(0.0);
    for (int j = 0; j < 4; ++j) {
      const int c = flex_coord[static_cast<std::size_t>(j)];
      T[0] += st.a(c) * st.a(c);
      T[1] += st.v(c) * st.v(c) / 0.01;
      T[2] += st.q(c) * st.q(c) / 1e-4;
    }
    const core::Vector6d hc = m.centroidalMomentum();
    T[3] = (hc(2) / (mass * 0.1)) * (hc(2) / (mass * 0.1));
    const Eigen::Vector3d cdd = m.comAcceleration();
    T[4] = cdd.z() * cdd.z();
    const Eigen::Vector3d com = m.com();
    const core::Vector6d Wc = core::shiftWrench(st.W_O, Eigen::Vector3d::Zero(), com);
    T[5] = (Wc(2) / 10.0) * (Wc(2) / 10.0);
    for (int f = 0; f < 2; ++f) {
      if (!st.contact[f]) continue;
      const double mz = (st.sole[f].linear().transpose() * st.wrench[f].head<3>()).z();
      T[6] += (mz / 5.0) * (mz / 5.0);
    }
    const Eigen::Vector2d zwb = core::zmpFromWrench(st.W_O);
    const Eigen::Vector2d ztc = core::tableCartZmp(com, cdd, d.gravity);
    T[7] = (zwb - ztc).squaredNorm() / 1e-4;
    if (head_frame >= 0) {
      const Eigen::Matrix3d Rh = m.framePose(head_frame).linear();
      const double hy = yawOf(Rh), hp = pitchOf(Rh) - cfg.head_pitch_offset, hr = rollOf(Rh);
      T[9] = (hy * hy + hp * hp + hr * hr) / 0.0025;
    }
    T[11] = st.ik_seed_gap / 0.0025;
    out.tau = st.tau_act;
  }

  /// Switching rows at event e (instants t1..t4): the spline of the leg that changes
  /// representation matches the double-support IK in position and velocity; lift-off forces.
  void eventRows(Workspace& w, int e, Eigen::VectorXd& out) const {
    // e: 0 -> t1 (end of phase 0), 1 -> t2 (start of phase 2), 2 -> t3 (end of phase 2),
    //    3 -> t4 (start of phase 4). The DS phase whose IK is matched, and the leg.
    static const int ds_phase[4] = {0, 2, 2, 4};
    static const int boundary[4] = {1, 2, 3, 4};
    const double t = w.timing->start(boundary[e]);
    buildState(w, ds_phase[e], t);
    const State& st = w.st;
    const PhaseSpline::Basis b = w.spline->evaluate(t);
    const int leg = 1 - anchor_of[ds_phase[e]];
    out.resize(event_eq_cnt[e]);
    int r = 0;
    for (int j = 0; j < 6; ++j) {
      const int row = 6 * leg + j;
      const double qs = w.legs_c.row(row).segment(b.first, 4).dot(b.value);
      out(r++) = (qs - st.q(leg_coord[static_cast<std::size_t>(row)])) / kJointScale;
    }
    for (int j = 0; j < 6; ++j) {
      const int row = 6 * leg + j;
      const double vs = w.legs_c.row(row).segment(b.first, 4).dot(b.d1);
      out(r++) = (vs - st.v(leg_coord[static_cast<std::size_t>(row)])) / 1.0;
    }
    if (e == 0 || e == 2) {
      // Lift-off: the unloading foot's wrench vanishes. Rows for its normal force and its two
      // tipping moments (the moments come from its bushing, not from the load). Its shear and
      // twist need no rows: the split shares them in proportion to the normal loads
      // (distributeWrench), so they vanish with the normal force by construction, and rows for
      // them had gradients of ~1e-5 of the others (singular values of the equality Jacobian
      // 4e-6 against 65): SLSQP's steps to meet them were ~20 scaled units long, half of them
      // rejected (measured, docs/history/planner.md).
      // In the last stage scaled to the check's linear CoP form at zero load (a row at the
      // solver's tolerance 1e-2 is 0.17 N of normal force and 0.014 N m of moment); earlier
      // stages keep the weight's scale: tight rows from the first stage on left the 15 cm stage
      // at 0.21 (measured, docs/history/planner.md).
      const int lifting = liftingFoot(e == 0 ? 0 : 2);
      const Eigen::Matrix3d Rt = st.sole[lifting].linear().transpose();
      const Eigen::Vector3d fo = Rt * st.wrench[lifting].tail<3>();
      const Eigen::Vector3d mo = Rt * st.wrench[lifting].head<3>();
      const double fn = finalBox() ? kLiftOffNormal * mg : mg;
      const double ms = (finalBox() ? 0.5 : 1.0) * mg * kCopScale;
      out(r++) = fo.z() / fn;
      out(r++) = mo.x() / ms;
      out(r++) = mo.y() / ms;
    }
  }

  // -------------------------------------------------------------- assembly
  /// Trapezoid quadrature weight of grid point k within its phase.
  double sampleWeight(const Workspace& w, int k) const {
    const GridPoint& g = grid[static_cast<std::size_t>(k)];
    const double h =
        w.timing->durations()(g.phase) / cfg.samples_per_phase[static_cast<std::size_t>(g.phase)];
    const auto& ph = phaseTable()[static_cast<std::size_t>(g.phase)];
    const bool closed = !(ph.right_contact && ph.left_contact) || g.phase + 1 == kPhaseCount;
    if (g.s == 1.0 || (g.s == 0.0 && closed)) return 0.5 * h;
    return h;
  }

  double objective(const Workspace& w, const std::vector<const SampleOut*>& s,
                   std::array<double, kObjectiveTerms>* terms) const {
    std::array<double, kObjectiveTerms> acc{};
    const auto& names = objectiveTermNames();
    for (std::size_t k = 0; k < s.size(); ++k) {
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
