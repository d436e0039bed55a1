// The kinematic initial guess of the overstep problem (see OverstepProblem::initialGuess).
#include <Eigen/QR>

#include "problem_impl.hpp"

namespace overstep::planner {
namespace {

double smooth(double s) {
  const double u = std::clamp(s, 0.0, 1.0);
  return u * u * u * (10.0 + u * (-15.0 + 6.0 * u));  // quintic, zero vel/acc at the ends
}

Eigen::Vector2d lerp(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double s) {
  return a + (b - a) * smooth(s);
}

}  // namespace

/// The guess's pelvis height (base z) with the pelvis at (x, y) and the soles flat at the feet's
/// placements (lifted by `lift`): as high as both legs allow, each hip-ankle distance (the leg
/// solution's centres H and A) at most leg_reach less guess_reach_margin, and at most
/// half-sitting. A lower pelvis bends the knees: in the double support between the steps the
/// rear leg's shank then leans over the bar (measured: the guess's restoration stuck at a
/// violation of 0.9 there with the pelvis 0.19 m down throughout). The ankle centre follows from
/// the sole placement and the bushing deflection in q, not from the leg's joints.
double OverstepProblem::Impl::pelvisHeight(robots::WholeBodyModel& model, const Eigen::VectorXd& q,
                                           const Eigen::Vector2d& pelvis,
                                           const Eigen::Vector2d feet2[2],
                                           const double lift[2]) const {
  model.setPositions(q);
  const double R = cfg.leg_reach - cfg.guess_reach_margin;
  double z = q_rest(5);
  for (int f = 0; f < 2; ++f) {
    const Eigen::Isometry3d X_SA =
        model.framePose(sole_frame[f]).inverse() * model.framePose(ankle_link_frame[f]);
    const Eigen::Vector3d p_WS(feet2[f].x(), feet2[f].y(), lift[f]);
    const Eigen::Vector3d p_WA =
        p_WS + X_SA.linear() * leg_ik[f]->ankleCentre() + X_SA.translation();
    const Eigen::Vector3d p_BH = leg_ik[f]->hipCentre();  // base frame, unrotated in the guess
    const double d2 = (pelvis + p_BH.head<2>() - p_WA.head<2>()).squaredNorm();
    // Out of reach at any height (a step beyond the leg): the hip at the ankle's height.
    const double rise = d2 < R * R ? std::sqrt(R * R - d2) : 0.0;
    z = std::min(z, p_WA.z() + rise - p_BH.z());
  }
  return z;
}

Eigen::VectorXd OverstepProblem::initialGuess() {
  Impl& m = *impl_;
  const auto& c = m.cfg;
  const auto& lay = m.lay;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(lay.total);
  for (int i = 0; i < kPhaseCount; ++i) x(i) = c.duration_guess[static_cast<std::size_t>(i)];
  const Eigen::Vector2d L0(0.0, c.start_half_width), R0(0.0, -c.start_half_width);
  const Eigen::Vector2d R1(c.guess_step_length, -c.guess_half_width);
  const Eigen::Vector2d L1(c.guess_step_length, c.guess_half_width);
  x.segment<2>(lay.feet) = R0;
  x.segment<2>(lay.feet + 2) = R1;
  x.segment<2>(lay.feet + 4) = L1;

  const PhaseTiming timing(x.head(kPhaseCount));
  PhaseSpline spline(c.spline_intervals), flex_spline(c.flex_spline_intervals);
  spline.setTiming(timing);
  flex_spline.setTiming(timing);
  robots::WholeBodyModel& model = *m.ws.front().model;
  const double z_top = m.height + c.guess_swing_clearance;

  const int M = 240;
  Eigen::MatrixXd Y(16, M);
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(M, m.n_ctrl),
                  Bf = Eigen::MatrixXd::Zero(M, m.n_ctrl_flex);
  Eigen::VectorXd q = m.q_rest;
  for (int k = 0; k < M; ++k) {
    const double t = timing.total() * k / (M - 1);
    const GridPoint g = timing.locate(t);
    const double s = g.s;
    Eigen::Vector2d com_target;
    Eigen::Vector2d feet2[2] = {R0, L0};
    double lift[2] = {0.0, 0.0};
    auto swing = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b, int f) {
      feet2[f] = lerp(a, b, (s - 0.25) / 0.5);
      lift[f] = z_top * (smooth(s / 0.3) - smooth((s - 0.7) / 0.3));
    };
    switch (g.phase) {
      case 0:
        com_target = lerp(0.5 * (L0 + R0), L0, s);
        break;
      case 1:
        com_target = L0;
        swing(R0, R1, kRight);
        break;
      case 2:
        com_target = lerp(L0, R1, s);
        feet2[kRight] = R1;
        break;
      case 3:
        com_target = R1;
        feet2[kRight] = R1;
        swing(L0, L1, kLeft);
        break;
      default:
        com_target = lerp(R1, 0.5 * (R1 + L1), s);
        feet2[kRight] = R1;
        feet2[kLeft] = L1;
        break;
    }
    Eigen::Vector2d pelvis = com_target;
    auto solveLegs = [&]() {
      for (int f = 0; f < 2; ++f) {
        Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
        target.translation() << feet2[f].x(), feet2[f].y(), lift[f];
        // Closed form, the previous solution choosing the branch, kept inside the safe range.
        const auto& d = model.description();
        robots::Vector6d prev;
        for (int j = 0; j < 6; ++j) prev(j) = q(m.leg_coord[static_cast<std::size_t>(6 * f + j)]);
        const robots::LegIkResult ik =
            m.legToSole(model, f, target, q, prev, robots::BeyondReach::Stretch);
        for (int j = 0; j < 6; ++j) {
          const auto& aj =
              d.actuated[static_cast<std::size_t>(m.leg_act[static_cast<std::size_t>(6 * f + j)])];
          q(m.leg_coord[static_cast<std::size_t>(6 * f + j)]) =
              std::clamp(ik.q(j), aj.safeLower(), aj.safeUpper());
        }
      }
    };
    auto placeBase = [&]() {
      q.head<6>().setZero();
      q(3) = pelvis.x();
      q(4) = pelvis.y();
      q(5) = m.pelvisHeight(model, q, pelvis, feet2, lift);
    };
    for (int iter = 0; iter < 6; ++iter) {
      placeBase();
      solveLegs();
      model.setPositions(q);
      pelvis += com_target - model.com().head<2>();
      // Quasi-static ankle deflection: the elastic joints carry the moment of their foot's share
      // of the contact wrench (one Newton step per pass: d residual / d q_e = k).
      const int n = model.dofs();
      model.setVelocities(Eigen::VectorXd::Zero(n));
      model.setAccelerations(Eigen::VectorXd::Zero(n));
      State& st = m.ws.front().st;
      st.q = q;
      st.tau = model.inverseDynamics();
      st.W_O = model.contactWrenchFromBase(st.tau);
      const auto& ph = phaseTable()[static_cast<std::size_t>(g.phase)];
      st.contact[kRight] = ph.right_contact;
      st.contact[kLeft] = ph.left_contact;
      for (int f = 0; f < 2; ++f) st.sole[f] = model.framePose(m.sole_frame[f]);
      m.soleJacobians(m.ws.front());
      m.distributeWrench(m.ws.front());
      for (int f = 0; f < 2; ++f) {
        const Eigen::MatrixXd J = model.frameJacobian(m.sole_frame[f]);
        for (int e = 0; e < 2; ++e) {
          const int fc = m.flex_coord[static_cast<std::size_t>(2 * f + e)];
          double r = st.tau(fc);
          if (st.contact[f]) r -= J.col(fc).dot(st.wrench[f].spatial());
          const double stiff =
              model.description().elastic[static_cast<std::size_t>(2 * f + e)].stiffness;
          q(fc) = std::clamp(q(fc) - r / stiff, -0.1, 0.1);
        }
      }
    }
    placeBase();
    solveLegs();  // the feet flat again over the final ankle deflection
    for (int j = 0; j < 12; ++j) Y(j, k) = q(m.leg_coord[static_cast<std::size_t>(j)]);
    for (int j = 0; j < 4; ++j) Y(12 + j, k) = q(m.flex_coord[static_cast<std::size_t>(j)]);
    const PhaseSpline::Basis b = spline.evaluate(t);
    B.block(k, b.first, 1, b.value.size()) = b.value.transpose();
    const PhaseSpline::Basis bf = flex_spline.evaluate(t);
    Bf.block(k, bf.first, 1, bf.value.size()) = bf.value.transpose();
  }
  // Least-squares fit of the free control points (ties: first three, last three), regularised
  // toward each curve's mean.
  Eigen::VectorXd lo, hi;
  bounds(lo, hi);
  auto fit = [&](const Eigen::MatrixXd& basis, int rows_from, int count, int offset, int F) {
    const int n_ctrl = static_cast<int>(basis.cols());
    Eigen::MatrixXd P = Eigen::MatrixXd::Zero(n_ctrl, F);
    P.block(0, 0, 3, 1).setOnes();
    for (int i = 1; i < F - 1; ++i) P(i + 2, i) = 1.0;
    P.block(n_ctrl - 3, F - 1, 3, 1).setOnes();
    Eigen::MatrixXd A(M + F, F);
    A.topRows(M) = basis * P;
    A.bottomRows(F) = 1e-3 * Eigen::MatrixXd::Identity(F, F);
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
    for (int j = 0; j < count; ++j) {
      Eigen::VectorXd rhs = Eigen::VectorXd::Zero(M + F);
      rhs.head(M) = Y.row(rows_from + j).transpose();
      rhs.tail(F).setConstant(1e-3 * Y.row(rows_from + j).mean());
      x.segment(offset + j * F, F) = qr.solve(rhs);
    }
  };
  fit(B, 0, 12, lay.legs, lay.free_cp);
  fit(Bf, 12, 4, lay.flex, lay.flex_free_cp);
  return x.cwiseMax(lo).cwiseMin(hi);
}

}  // namespace overstep::planner
