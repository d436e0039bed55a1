// The simulated robot standing: physics invariants of the DART world with servoed joints and
// elastic ankle bushings.
#include <gtest/gtest.h>

#include "overstep/core/error.hpp"
#include "overstep/core/wrench.hpp"
#include "overstep/sim/simulator.hpp"
#include "test_util.hpp"

namespace {

const overstep::robots::WholeBodyModel& model() {
  static const auto m = overstep::robots::WholeBodyModel::fromFile(overstep::test::hrp2Yaml());
  return m;
}

}  // namespace

TEST(Sim, StandsTenSecondsInHalfSittingWithStaticsHolding) {
  overstep::sim::Simulator sim(model(), overstep::sim::noTruthEffects(model()));
  const double g = model().description().gravity;
  const double z0 = sim.basePose().translation().z();
  const auto st0 = sim.state();
  auto sum_late = overstep::core::Wrench::zero(overstep::core::Axes::kWorld);
  int n_late = 0;
  for (int i = 0; i < 10000; ++i) {  // 10 s at 1 ms, commands held at the initial posture
    if (i % 5 == 0) sim.setCommand(st0.q, Eigen::VectorXd::Zero(st0.q.size()));
    sim.step();
    ASSERT_GT(sim.basePose().translation().z(), z0 - 0.02) << "fell at t = " << sim.time();
    if (i >= 9000) {
      sum_late += sim.contacts().foot_wrench[0] + sim.contacts().foot_wrench[1];
      ++n_late;
    }
  }
  EXPECT_NEAR(sim.time(), 10.0, 1e-9);
  const overstep::core::Wrench W = sum_late / n_late;
  const double weight = sim.totalMass() * g;
  EXPECT_NEAR(W.force.z(), weight, 0.01 * weight) << "ground reaction = weight";
  EXPECT_TRUE(sim.contacts().foot_contact[0] && sim.contacts().foot_contact[1]);
  // CoP where statics puts it: under the CoM.
  const Eigen::Vector2d zmp = overstep::core::zmpFromWrench(W);
  EXPECT_LT((zmp - sim.com().head<2>()).norm(), 0.005);
  // The F/T sensors carry the weight minus what hangs below them.
  const auto st = sim.state();
  const double expected = (sim.totalMass() - sim.massBelowSensor(0) - sim.massBelowSensor(1)) * g;
  EXPECT_NEAR(st.ft_right.force.z() + st.ft_left.force.z(), expected, 0.01 * expected);
  // Each bushing's deflection equals the moment about its axis divided by its stiffness.
  const Eigen::Vector4d q = sim.elasticPositions(), tau = sim.elasticExternalTorque();
  for (int e = 0; e < 4; ++e) {
    const double k = model().description().elastic[static_cast<std::size_t>(e)].stiffness;
    EXPECT_NEAR(q(e), tau(e) / k, 2e-4 + 0.02 * std::abs(tau(e) / k)) << "bushing " << e;
  }
  // Each sole gives along its normal by its load over the bushing's vertical stiffness: the foot
  // link (whose sole frame the model places) sits that far below the ground (the contact's own
  // penetration is ~0.01 mm).
  const double kz = model().description().bushing_vertical_stiffness;
  ASSERT_GT(kz, 0.0);
  for (int f = 0; f < 2; ++f) {
    const double fz = sim.contacts().foot_wrench[static_cast<std::size_t>(f)].force.z();
    const double link_z = sim.framePose(f == 0 ? "right_sole" : "left_sole").translation().z();
    EXPECT_GT(fz / kz, 5e-4) << "foot " << f << ": a millimetre, not nothing";
    EXPECT_NEAR(-link_z, fz / kz, 5e-5 + 0.02 * fz / kz) << "foot " << f;
  }
  // The posture is held: joints track their references.
  EXPECT_LT((st.q - st0.q).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_TRUE(st.has_ground_truth);
}

TEST(Sim, BadOptionsAreRefused) {
  overstep::sim::SimOptions o;
  o.servo_gain = 2000.0;  // Kv dt > 1
  EXPECT_THROW(overstep::sim::Simulator(model(), overstep::sim::noTruthEffects(model()), o),
               overstep::InputError);
}

namespace {

/// Runs `seconds` holding the initial posture; returns the ground reaction and the CoM averaged
/// over the last 1.6 s (about one period of the lightly damped sway on the bushings, so that the
/// inertial part of the ZMP averages out).
std::pair<overstep::core::Wrench, Eigen::Vector3d> holdAndMeasure(overstep::sim::Simulator& sim,
                                                                  double seconds) {
  const auto st0 = sim.state();
  auto sum = overstep::core::Wrench::zero(overstep::core::Axes::kWorld);
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  int n = 0;
  const int steps = static_cast<int>(seconds / 0.001);
  for (int i = 0; i < steps; ++i) {
    if (i % 5 == 0) sim.setCommand(st0.q, Eigen::VectorXd::Zero(st0.q.size()));
    sim.step();
    if (i >= steps - 1600) {
      sum += sim.contacts().foot_wrench[0] + sim.contacts().foot_wrench[1];
      com += sim.com();
      ++n;
    }
  }
  return {sum / n, com / n};
}

}  // namespace

TEST(SimTruth, PayloadAddsItsWeightAndMomentAndBiasIsAConstantOffset) {
  auto clean = overstep::sim::noTruthEffects(model());
  auto loaded = clean;
  loaded.payloads.push_back({"CHEST_LINK1", 3.0, Eigen::Vector3d(0.05, 0.0, 0.1)});
  loaded.ft[1].bias.force << 1.0, -2.0, 3.0;
  loaded.ft[1].bias.moment << 0.1, -0.2, 0.3;
  overstep::sim::Simulator a(model(), clean), b(model(), loaded);
  const double g = model().description().gravity;
  const auto [Wa, ca] = holdAndMeasure(a, 4.0);
  const auto [Wb, cb] = holdAndMeasure(b, 4.0);
  EXPECT_NEAR(b.totalMass() - a.totalMass(), 3.0, 1e-12);
  EXPECT_NEAR(Wb.force.z() - Wa.force.z(), 3.0 * g, 0.01 * 3.0 * g)
      << "+m g on the summed normal force";
  // The matching moment: the support moment about the world origin follows the new CoM.
  const Eigen::Vector2d za = overstep::core::zmpFromWrench(Wa),
                        zb = overstep::core::zmpFromWrench(Wb);
  EXPECT_LT((za - ca.head<2>()).norm(), 0.002);
  EXPECT_LT((zb - cb.head<2>()).norm(), 0.002);
  EXPECT_GT(cb.x() - ca.x(), 0.001) << "a payload 5 cm ahead of the chest moves the CoM";
  // Bias: the left sensor reads the clean reading of the same state plus the bias. Same robot,
  // same state: compare the bias-free right sensor as a control.
  auto loaded_no_bias = loaded;
  loaded_no_bias.ft[1].bias = overstep::core::Wrench::zero(overstep::core::Axes::kSensor);
  overstep::sim::Simulator c(model(), loaded_no_bias);
  holdAndMeasure(c, 4.0);
  const auto sb = b.state(), sc = c.state();
  EXPECT_LT(((sb.ft_left - sc.ft_left - loaded.ft[1].bias).forceMoment()).norm(), 1e-9);
  EXPECT_LT(((sb.ft_right - sc.ft_right).forceMoment()).norm(), 1e-9)
      << "lockstep runs are bit-identical";
}

namespace {

constexpr int kArm = 16;  // RARM_JOINT0: moving it does not disturb the balance much

/// Runs `seconds` with RARM_JOINT0 following ref(t) (and its rate) from the initial posture,
/// commanded every 5 ms; calls probe(t, sim, reference of the joint at t) after every step.
template <typename Ref, typename Probe>
void driveArm(overstep::sim::Simulator& sim, double seconds, Ref ref, Probe probe) {
  const auto st0 = sim.state();
  const int steps = static_cast<int>(std::lround(seconds / 0.001));
  Eigen::VectorXd q = st0.q, qd = Eigen::VectorXd::Zero(st0.q.size());
  for (int i = 0; i < steps; ++i) {
    const double t = i * 0.001;
    if (i % 5 == 0) {
      const auto [r, rd] = ref(t);
      q(kArm) = st0.q(kArm) + r;
      qd(kArm) = rd;
      sim.setCommand(q, qd);
    }
    sim.step();
    probe(sim.time(), sim, st0.q(kArm) + ref(sim.time()).first);
  }
}

}  // namespace

TEST(SimTruth, CommandDelayShiftsTheJointResponseByTheDelay) {
  auto onset = [](double delay) {
    auto truth = overstep::sim::noTruthEffects(model());
    truth.command_delay = delay;
    overstep::sim::Simulator sim(model(), truth);
    const double q0 = sim.jointPositions()(kArm);
    double first = -1.0;
    driveArm(
        sim, 0.6, [](double t) { return std::make_pair(t >= 0.2 ? 0.05 : 0.0, 0.0); },
        [&](double t, const overstep::sim::Simulator& s, double) {
          if (first < 0.0 && std::abs(s.jointPositions()(kArm) - q0) > 1e-3) first = t;
        });
    return first;
  };
  const double clean = onset(0.0), delayed = onset(0.02);
  ASSERT_GT(clean, 0.0);
  EXPECT_NEAR(delayed - clean, 0.02, 0.0015);
}

TEST(SimTruth, JointFrictionMakesTheTrackingErrorGrowWithSpeed) {
  const double viscous = 3.0, coulomb = 2.0;
  auto worstError = [&](double omega, bool with_friction) {
    auto truth = overstep::sim::noTruthEffects(model());
    if (with_friction) {
      truth.viscous(kArm) = viscous;
      truth.coulomb(kArm) = coulomb;
    }
    overstep::sim::Simulator sim(model(), truth);
    double worst = 0.0;
    const double amp = 0.1;
    driveArm(
        sim, 2.0,
        [&](double t) {
          return std::make_pair(amp * std::sin(omega * t), amp * omega * std::cos(omega * t));
        },
        [&](double t, const overstep::sim::Simulator& s, double q_ref) {
          // at the velocity peaks (sin crosses zero), after the first second
          if (t > 1.0 && std::abs(std::sin(omega * t)) < 0.05)
            worst = std::max(worst, std::abs(s.state().q(kArm) - q_ref));
        });
    return worst;
  };
  const double slow = worstError(2.0, true), fast = worstError(8.0, true);
  const double k = overstep::sim::SimOptions{}.servo_stiffness;
  // Steady state of a position loop with stiffness k: error = (viscous v + coulomb) / k.
  EXPECT_NEAR(slow, (viscous * 0.2 + coulomb) / k, 0.25 * (viscous * 0.2 + coulomb) / k);
  EXPECT_NEAR(fast, (viscous * 0.8 + coulomb) / k, 0.25 * (viscous * 0.8 + coulomb) / k);
  EXPECT_GT(fast, slow);
  EXPECT_LT(worstError(8.0, false), 0.1 * fast) << "no friction, no such error";
}

TEST(SimTruth, BacklashHoldsTheLoadSideUntilTheDeadBandIsCrossed) {
  auto truth = overstep::sim::noTruthEffects(model());
  const double width = 0.02;
  truth.backlash(kArm) = width;
  overstep::sim::Simulator sim(model(), truth);
  const double q0 = sim.jointPositions()(kArm);
  // Up 0.1 rad in 0.5 s, then back down at the same speed.
  auto ref = [](double t) {
    return t < 0.5 ? std::make_pair(0.2 * t, 0.2) : std::make_pair(0.1 - 0.2 * (t - 0.5), -0.2);
  };
  double load_at_turn = 0.0, load_after_half_band = 0.0, load_after_band = 0.0;
  driveArm(sim, 1.0, ref, [&](double t, const overstep::sim::Simulator& s, double) {
    const double load = s.jointPositions()(kArm) - q0;
    if (std::abs(t - 0.5) < 5e-4) load_at_turn = load;
    if (std::abs(t - (0.5 + 0.5 * width / 0.2)) < 5e-4) load_after_half_band = load;
    if (std::abs(t - (0.5 + 1.5 * width / 0.2)) < 5e-4) load_after_band = load;
  });
  // Going up the load trails the motor by half the band; after the turn it stays put until the
  // motor has crossed the whole band, then follows again (half a band later: 0.5 width lower).
  EXPECT_NEAR(load_at_turn, 0.1 - 0.5 * width, 1e-3);
  EXPECT_NEAR(load_after_half_band, 0.1 - 0.5 * width, 1e-3);
  EXPECT_NEAR(load_after_band, 0.1 - width, 1e-3);
}

TEST(SimObstacle, StandingClearOfTheBarAndAnOverlappingBarIsDetected) {
  overstep::sim::SimOptions o;
  o.has_obstacle = true;  // the default 20 cm x 11 cm bar, 3 cm ahead of the toes
  overstep::sim::Simulator clear(model(), overstep::sim::noTruthEffects(model()), o);
  holdAndMeasure(clear, 0.5);
  const auto c = clear.collisions();
  EXPECT_FALSE(c.obstacleContact());
  EXPECT_GT(c.obstacle_distance, 0.0);
  EXPECT_LT(c.obstacle_distance, 0.03) << "the nearest capsule is a foot, less than the gap away";
  EXPECT_GT(c.ground_clearance, 0.0) << "only the feet touch the ground";
  EXPECT_TRUE(clear.contacts().foot_wrench[0].allFinite());
  // A round bar whose margin reaches back over the toes (detection only, no physical body).
  o.obstacle.shape = overstep::core::ObstacleSpec::Shape::Cylinder;
  o.obstacle.gap = 0.0;
  o.obstacle.margin = 0.05;
  overstep::sim::Simulator overlap(model(), overstep::sim::noTruthEffects(model()), o);
  const auto c2 = overlap.collisions();
  EXPECT_TRUE(c2.obstacleContact());
  EXPECT_NE(c2.obstacle_link.find("LEG"), std::string::npos) << c2.obstacle_link;
}

TEST(Sim, SettleStartsInStaticEquilibrium) {
  overstep::sim::Simulator sim(model(), overstep::sim::noTruthEffects(model()));
  sim.settle();
  EXPECT_DOUBLE_EQ(sim.time(), 0.0);
  const auto st0 = sim.state();
  double lo = 1e9, hi = -1e9;
  for (int i = 0; i < 3000; ++i) {
    if (i % 5 == 0) sim.setCommand(st0.q, Eigen::VectorXd::Zero(st0.q.size()));
    sim.step();
    lo = std::min(lo, sim.com().x());
    hi = std::max(hi, sim.com().x());
  }
  EXPECT_LT(hi - lo, 5e-4) << "no sway after settling (without it: about 4 mm)";
  const Eigen::Vector4d q = sim.elasticPositions(), tau = sim.elasticExternalTorque();
  for (int e = 0; e < 4; ++e)
    EXPECT_NEAR(q(e), tau(e) / model().description().elastic[static_cast<std::size_t>(e)].stiffness,
                2e-4);
}

// The bushing damper through a swing and a hard touchdown: the right foot is lifted (hip, knee
// and ankle pitch) for 0.2 s while the robot stands on both feet; with its CoM between the feet
// the robot starts tipping to the right and the foot comes down on its edge (about 2 kN). In the
// air and on the edge the damper runs implicitly on the foot's inertia; it is explicit only once
// the foot is held flat. Counting any contact, then any load, as held both spiked the bushing to
// about 10 rad within two steps (measured). The deflections must stay small and finite.
TEST(Sim, BushingDamperStaysStableThroughSwingAndHardTouchdown) {
  overstep::sim::Simulator sim(model(), overstep::sim::noTruthEffects(model()));
  sim.settle();
  const auto& d = model().description();
  const Eigen::VectorXd q0 = sim.state().q;
  const int hip = d.actuatedIndex("RLEG_JOINT2"), knee = d.actuatedIndex("RLEG_JOINT3"),
            ankle = d.actuatedIndex("RLEG_JOINT4");
  double worst = 0.0, peak_force = 0.0;
  bool lifted = false, landed = false;
  for (int i = 0; i < 1200; ++i) {  // 1.2 s at 1 ms, commands every 5 ms
    const double t = i * 0.001;
    if (i % 5 == 0) {
      const double up = 0.5 * (t < 0.2   ? 0.0
                               : t < 0.3 ? (t - 0.2) / 0.1
                               : t < 0.4 ? 1.0
                               : t < 0.5 ? 1.0 - (t - 0.4) / 0.1
                                         : 0.0);
      Eigen::VectorXd q = q0;
      q(hip) -= 0.25 * up;
      q(knee) += 0.5 * up;
      q(ankle) -= 0.25 * up;
      sim.setCommand(q, Eigen::VectorXd::Zero(q.size()));
    }
    sim.step();
    const Eigen::Vector4d e = sim.elasticPositions();
    ASSERT_TRUE(e.allFinite()) << "t = " << t;
    worst = std::max(worst, e.cwiseAbs().maxCoeff());
    lifted = lifted || !sim.contacts().foot_contact[0];
    if (lifted && t > 0.45 && sim.contacts().foot_contact[0]) {
      landed = true;
      peak_force = std::max(peak_force, sim.contacts().foot_wrench[0].force.z());
    }
  }
  EXPECT_TRUE(lifted) << "the right foot left the ground";
  EXPECT_TRUE(landed) << "and came down again";
  EXPECT_GT(peak_force, 1000.0) << "hard: more than the robot's weight";
  EXPECT_LT(worst, 0.3) << "largest bushing deflection, rad (the spikes were 1-10 rad)";
  EXPECT_GT(sim.basePose().translation().z(), 0.5) << "still standing";
}
