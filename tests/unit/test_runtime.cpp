// The replay runtime without transport: the plan track (sampling, corrections through the leg
// Jacobians, the estimator) and the replay state machine (lifecycle, watchdog, faults, limits).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "overstep/core/error.hpp"
#include "overstep/robots/leg.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/runtime/loop_stats.hpp"
#include "overstep/runtime/plan_track.hpp"
#include "overstep/runtime/replay.hpp"
#include "overstep/stabilizer/params.hpp"
#include "plan_fixtures.hpp"
#include "test_util.hpp"

namespace overstep {
namespace {

using runtime::FaultReason;
using runtime::State;

class RuntimeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    model_ = new robots::WholeBodyModel(robots::WholeBodyModel::fromFile(test::hrp2Yaml()));
    plan_ = new core::Plan(test::standingPlan(*model_, 1.0));
  }
  static void TearDownTestSuite() {
    delete plan_;
    delete model_;
  }
  static stabilizer::Params params() {
    stabilizer::Params p = stabilizer::loadParams(test::hrp2Yaml());
    p.mass = model_->totalMass();
    return p;
  }
  static core::RobotState perfectState(const core::Plan& plan, int k) {
    return test::perfectState(*model_, plan, k);
  }
  static robots::WholeBodyModel* model_;
  static core::Plan* plan_;
};
robots::WholeBodyModel* RuntimeTest::model_ = nullptr;
core::Plan* RuntimeTest::plan_ = nullptr;

TEST_F(RuntimeTest, TrackSamplesReproduceThePlan) {
  runtime::PlanTrack track(*plan_, *model_);
  EXPECT_EQ(track.samples(), plan_->samples());
  EXPECT_NEAR(track.duration(), plan_->duration(), 1e-12);
  runtime::TrackSample s = track.makeSample();
  for (int k : {0, 7, plan_->samples() - 1}) {
    track.sample(plan_->t(k), s);
    EXPECT_EQ(s.index, k);
    // The joints are the plan's with each loaded leg lengthened by its sole's compression under the
    // planned load (the bushings' vertical give, which the plan's model lacks): with the base where
    // the plan has it, each sole sits F_z / k below its planned placement, the rest unchanged.
    const double kv = model_->description().bushing_vertical_stiffness;
    ASSERT_GT(kv, 0.0);
    Eigen::VectorXd q = plan_->q.col(k);
    q.segment(6, track.joints()) = s.q;
    for (int f = 0; f < 2; ++f) {
      const int sole =
          model_->frameIndex(model_->description().foot(f == 0 ? "right" : "left")->sole_frame);
      model_->setPositions(plan_->q.col(k));
      const Eigen::Isometry3d planned = model_->framePose(sole);
      model_->setPositions(q);
      const Eigen::Isometry3d X = model_->framePose(sole);
      const double dz = s.ref.foot[static_cast<std::size_t>(f)].wrench.force.z() / kv;
      EXPECT_GT(dz, 5e-4) << "foot " << f;
      EXPECT_NEAR(X.translation().z(), planned.translation().z() - dz, 2e-5) << "foot " << f;
      EXPECT_LT((X.translation() - planned.translation()).head<2>().norm(), 2e-5) << "foot " << f;
      EXPECT_LT(Eigen::AngleAxisd(X.linear().transpose() * planned.linear()).angle(), 1e-4);
    }
    Eigen::VectorXd off_legs = s.q - plan_->q.col(k).segment(6, track.joints());
    for (const auto& leg : robots::legChains(*model_))
      for (int j : leg.actuated) off_legs(j) = 0.0;
    EXPECT_EQ(off_legs.cwiseAbs().maxCoeff(), 0.0) << "only the legs";
    EXPECT_LT((s.ref.com - plan_->com.col(k)).norm(), 1e-9);
    EXPECT_TRUE(s.ref.foot[0].contact && s.ref.foot[1].contact);
    // The planned wrench in the sole frame: Fz carries the load.
    EXPECT_NEAR(s.ref.foot[0].wrench.force.z() + s.ref.foot[1].wrench.force.z(),
                model_->totalMass() * model_->description().gravity, 1e-6);
  }
  // Out-of-range and non-finite times clamp.
  track.sample(-1.0, s);
  EXPECT_EQ(s.t, 0.0);
  track.sample(1e9, s);
  EXPECT_EQ(s.t, track.duration());
  track.sample(std::nan(""), s);
  EXPECT_EQ(s.t, 0.0);
}

// A contact switch is written as two samples 1 us apart, the phase before and the one after,
// and the switching foot's planned load differs between them. The track lengthens each loaded
// leg by its load / the bushings' vertical stiffness and commands that offset's rate: taken over
// the microsecond it read as rad/s in the leg (sent clamped at the velocity limit for a tick).
// The ZMP references' rates are differences too: over the microsecond they read as zero.
TEST_F(RuntimeTest, TrackVelocitiesStaySmoothAcrossAContactSwitch) {
  const core::Plan& base = *plan_;
  // The switch: base sample kb written twice, 1 us before its time (phase 0) and at it (1).
  const int kb = base.samples() / 2;
  core::Plan p = base;
  p.resize(base.samples() + 1, model_->dofs(), model_->actuatedCount());
  auto src = [kb](int k) { return k <= kb ? k : k - 1; };
  auto copy = [&](const auto& from, auto& to) {
    for (int k = 0; k < p.samples(); ++k) to.col(k) = from.col(src(k));
  };
  copy(base.q, p.q);
  copy(base.v, p.v);
  copy(base.a, p.a);
  copy(base.tau, p.tau);
  copy(base.com, p.com);
  copy(base.zmp_wholebody, p.zmp_wholebody);
  copy(base.zmp_tablecart, p.zmp_tablecart);
  copy(base.right_foot, p.right_foot);
  copy(base.left_foot, p.left_foot);
  copy(base.right_wrench, p.right_wrench);
  copy(base.left_wrench, p.left_wrench);
  for (int k = 0; k < p.samples(); ++k) {
    p.t(k) = base.t(src(k));
    p.phase(k) = k <= kb ? 0 : 1;
  }
  p.t(kb) -= 1e-6;
  p.phases.push_back(p.phases.front());
  p.phases.back().name = "after";
  // 5 N more on the right sole just before the switch (and 5 N less on the left).
  core::Wrench w_r = p.wrench(0, kb), w_l = p.wrench(1, kb);
  w_r.force.z() += 5.0;
  w_l.force.z() -= 5.0;
  p.setWrench(0, kb, w_r);
  p.setWrench(1, kb, w_l);
  // Both ZMP references move forward at 2 cm/s.
  const double zmp_speed = 0.02;
  for (int k = 0; k < p.samples(); ++k) {
    p.zmp_tablecart(0, k) += zmp_speed * p.t(k);
    p.zmp_wholebody(0, k) += zmp_speed * p.t(k);
  }
  runtime::PlanTrack track(p, *model_);
  runtime::TrackSample s = track.makeSample();
  // The offsets move by ~5 N / k_vertical (~20 um at the sole) over a sample period at most:
  // a joint rate of the order of 0.01 rad/s; over 1 us it would be 5000 times that.
  double worst = 0.0;
  for (int k = 0; k < p.samples(); ++k) {
    track.sample(p.t(k), s);
    worst = std::max(worst, (s.qd - p.v.col(k).segment(6, track.joints())).cwiseAbs().maxCoeff());
    EXPECT_NEAR(s.ref.zmp_vel.x(), zmp_speed, 1e-9) << "sample " << k;
    EXPECT_NEAR(s.ref.zmp_wholebody_vel.x(), zmp_speed, 1e-9) << "sample " << k;
  }
  EXPECT_GT(worst, 1e-4) << "the load change must show in the rates";
  EXPECT_LT(worst, 0.05);
}

TEST_F(RuntimeTest, TrackRejectsPlansForAnotherRobotOrOutsideLimits) {
  core::Plan other = *plan_;
  other.robot_hash = "0123456789abcdef";
  EXPECT_THROW(runtime::PlanTrack(other, *model_), InputError);
  core::Plan bad = *plan_;
  bad.q(6 + 3, 5) = 10.0;  // a knee far beyond its range
  try {
    runtime::PlanTrack t(bad, *model_);
    FAIL() << "accepted a joint outside its limits";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("outside its limits"), std::string::npos) << e.what();
  }
  core::Plan short_plan = *plan_;
  short_plan.resize(1, model_->dofs(), model_->actuatedCount());
  EXPECT_THROW(runtime::PlanTrack(short_plan, *model_), InputError);
}

TEST_F(RuntimeTest, CorrectionsMoveTheSolesAsCommanded) {
  runtime::PlanTrack track(*plan_, *model_);
  runtime::TrackSample s = track.makeSample();
  track.sample(0.5, s);
  const auto& d = model_->description();
  const int sole[2] = {model_->frameIndex(d.foot("right")->sole_frame),
                       model_->frameIndex(d.foot("left")->sole_frame)};
  const int base = model_->frameIndex(d.base_link);
  auto soleInBase = [&](const Eigen::VectorXd& qa, int f) {
    Eigen::VectorXd q = plan_->q.col(s.index);
    q.segment(6, track.joints()) = qa;
    model_->setPositions(q);
    return Eigen::Isometry3d(model_->framePose(base).inverse() * model_->framePose(sole[f]));
  };
  const Eigen::Isometry3d X0[2] = {soleInBase(s.q, 0), soleInBase(s.q, 1)};
  // 1 cm higher right foot, 0.02 rad left pitch, 1 cm CoM offset forward.
  stabilizer::Output c;
  c.foot_height[0] = 0.01;
  c.foot_rotation[1] = Eigen::Vector2d(0.0, 0.02);
  c.com_offset = Eigen::Vector3d(0.01, 0.0, 0.0);
  Eigen::VectorXd q = s.q;
  track.applyCorrections(s, c, q);
  const Eigen::Isometry3d X1[2] = {soleInBase(q, 0), soleInBase(q, 1)};
  // Relative to the base (world-aligned here: the pelvis is level), each sole moves by its own
  // change minus the base's shift; first-order accurate (second-order errors: < 1 mm for 1 cm).
  const Eigen::Vector3d dr = X1[0].translation() - X0[0].translation();
  EXPECT_NEAR(dr.z(), 0.01, 1e-3);
  EXPECT_NEAR(dr.x(), -0.01, 1e-3);
  const Eigen::Vector3d dl = X1[1].translation() - X0[1].translation();
  EXPECT_NEAR(dl.x(), -0.01, 1e-3);
  EXPECT_NEAR(dl.z(), 0.0, 1e-3);
  const Eigen::AngleAxisd rot(X0[1].linear().transpose() * X1[1].linear());
  const Eigen::Vector3d rv = rot.axis() * rot.angle();
  EXPECT_NEAR(rv.y(), 0.02, 1e-3);
  EXPECT_NEAR(rv.x(), 0.0, 1e-3);
  // Only the legs moved.
  for (int j = 0; j < track.joints(); ++j) {
    bool leg = false;
    for (const auto& l : track.legJoints())
      for (int i : l) leg = leg || i == j;
    if (!leg) {
      EXPECT_EQ(q(j), s.q(j)) << j;
    }
  }
}

TEST_F(RuntimeTest, EstimatorRecoversThePlanFromAPerfectRobot) {
  runtime::PlanTrack track(*plan_, *model_);
  runtime::TrackSample s = track.makeSample();
  const int k = 40;
  track.sample(plan_->t(k), s);
  core::RobotState st = perfectState(*plan_, k);
  st.q = s.q;  // a perfect robot's encoders read the track's joints (with the compression offsets)
  stabilizer::Measurement m;
  track.estimate(s, st, m);
  EXPECT_LT((m.com - s.ref.com).norm(), 1e-9);
  for (int f = 0; f < 2; ++f)
    EXPECT_LT(
        (m.foot_wrench[std::size_t(f)] - s.ref.foot[std::size_t(f)].wrench).forceMoment().norm(),
        1e-6)
        << f;
}

TEST_F(RuntimeTest, EstimatorFollowsJointErrorsWithTheFeetHeld) {
  // A perturbed knee bends the robot over its stance feet: the estimated CoM must follow the
  // model's CoM with the left sole held in place, to first order.
  runtime::PlanTrack track(*plan_, *model_);
  runtime::TrackSample s = track.makeSample();
  const int k = 10;
  track.sample(plan_->t(k), s);
  core::RobotState st = perfectState(*plan_, k);
  const int knee = model_->description().actuatedIndex("LLEG_JOINT3");
  const int hip = model_->description().actuatedIndex("LLEG_JOINT2");
  st.q(knee) += 0.01;
  st.q(hip) -= 0.004;
  stabilizer::Measurement m;
  track.estimate(s, st, m);
  // Truth: left sole anchored where the plan has it.
  Eigen::VectorXd q = plan_->q.col(k), v = Eigen::VectorXd::Zero(q.size()), a = v;
  q.segment(6, track.joints()) = st.q;
  Eigen::Isometry3d Xl = Eigen::Isometry3d::Identity();
  Xl.translation() = plan_->left_foot.col(k).head<3>();
  Xl.linear() = Eigen::Quaterniond(plan_->left_foot(3, k), plan_->left_foot(4, k),
                                   plan_->left_foot(5, k), plan_->left_foot(6, k))
                    .toRotationMatrix();
  model_->anchorBase(model_->frameIndex(model_->description().foot("left")->sole_frame), Xl, q, v,
                     a);
  const Eigen::Vector3d truth = model_->com();
  // The estimate weights both feet; with only the left leg perturbed the right-anchored estimate
  // differs, so compare the x motion (sagittal), which both see the same way to first order.
  EXPECT_GT(std::abs(truth.x() - s.ref.com.x()), 1e-3);  // the perturbation is visible
  EXPECT_LT(std::abs((m.com.x() - s.ref.com.x()) - 0.5 * (truth.x() - s.ref.com.x())), 2e-4);
}

TEST_F(RuntimeTest, EstimatorRotatesTheCoMWithTheImuTilt) {
  runtime::PlanTrack track(*plan_, *model_);
  runtime::TrackSample s = track.makeSample();
  track.sample(0.2, s);
  core::RobotState st = perfectState(*plan_, s.index);
  const double tilt = 0.01;  // the whole robot pitched forward on its elastic ankles
  st.imu_orientation = Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitY()) * st.imu_orientation;
  stabilizer::Measurement m;
  track.estimate(s, st, m);
  const double h = s.ref.com.z();
  EXPECT_NEAR(m.com.x() - s.ref.com.x(), tilt * h, 2e-4);
}

/// One control period as the replay process runs it: the between-ticks work, then the tick.
const runtime::TickOutput& tickP(runtime::Replay& r, const core::RobotState* st) {
  r.prepare();
  return r.tick(st);
}

runtime::ReplayOptions fastOptions() {
  runtime::ReplayOptions o;
  o.rate = 200.0;
  o.min_move_time = 0.1;
  return o;
}

TEST_F(RuntimeTest, LifecycleRunsThePlanToTheEnd) {
  runtime::PlanTrack track(*plan_, *model_);
  runtime::Replay r(track, params(), fastOptions());
  core::RobotState st = perfectState(*plan_, 0);
  // Idle without a state: nothing is sent; with a state but no start: still nothing.
  EXPECT_FALSE(tickP(r, nullptr).send_command);
  EXPECT_EQ(r.state(), State::Idle);
  EXPECT_FALSE(tickP(r, &st).send_command);
  r.start();
  int ticks = 0, moving = 0;
  std::int64_t last_seq = -1;
  bool first_running = true;
  while (r.state() != State::Finished && ticks < 2000) {
    const auto& out = tickP(r, &st);
    if (out.state == State::MovingToStart) ++moving;
    if (out.state == State::Running && first_running) {
      // The plan starts with the stabilizer on in full: it ramped in at the first posture.
      first_running = false;
      EXPECT_EQ(out.stab_status.mode, stabilizer::Mode::On);
      EXPECT_DOUBLE_EQ(out.stab.ramp, 1.0);
      EXPECT_EQ(out.plan_time, 0.0);
    }
    ASSERT_TRUE(out.send_command);
    EXPECT_GT(out.command.seq, last_seq);
    last_seq = out.command.seq;
    ++ticks;
  }
  ASSERT_EQ(r.state(), State::Finished) << runtime::toString(r.fault());
  EXPECT_GE(moving, 19 + 200 * params().ramp_time);  // the 0.1 s move, then the ramp, at 200 Hz
  EXPECT_NEAR(r.output().plan_time, track.duration(), 1e-9);
  // A perfect robot needs no correction: the command is the plan.
  EXPECT_LT((r.output().command.q_ref - track.makeSample().q).norm(), 1e-3);
}

// With the robot's clock (lcm, lockstep) the plan advances by the states' time stamps: the
// watchdog's tick without a state holds the plan's time, a late state after a lost one catches
// up both periods, a repeated time stamp advances nothing. The timer clock advances a period a
// tick whatever arrives (measured under load: 16 watchdog ticks ran the plan 80 ms ahead of the
// robot in a 1.5 s lcm-clock replay).
TEST_F(RuntimeTest, RobotClockPacesThePlanByTheStatesTimeStamps) {
  runtime::PlanTrack track(*plan_, *model_);
  runtime::ReplayOptions o = fastOptions();
  o.robot_clock = true;
  runtime::Replay r(track, params(), o);
  core::RobotState st = perfectState(*plan_, 0);
  st.utime = 1000000;
  const std::int64_t period_us = 5000;  // 200 Hz
  tickP(r, &st);
  r.start();
  for (int i = 0; i < 2000 && r.state() != State::Running; ++i) {
    st.utime += period_us;
    tickP(r, &st);
  }
  ASSERT_EQ(r.state(), State::Running) << runtime::toString(r.fault());
  st.utime += period_us;
  const double p0 = tickP(r, &st).plan_time;
  EXPECT_DOUBLE_EQ(tickP(r, nullptr).plan_time, p0) << "a tick without a state held the plan";
  st.utime += 2 * period_us;  // the late state, one lost before it
  EXPECT_NEAR(tickP(r, &st).plan_time, p0 + 0.010, 1e-12);
  EXPECT_NEAR(tickP(r, &st).plan_time, p0 + 0.010, 1e-12) << "same time stamp, same plan time";
  EXPECT_EQ(r.state(), State::Running);
  // The timer clock: a period a tick, with or without a state.
  runtime::Replay t(track, params(), fastOptions());
  tickP(t, &st);
  t.start();
  for (int i = 0; i < 2000 && t.state() != State::Running; ++i) tickP(t, &st);
  ASSERT_EQ(t.state(), State::Running);
  const double q0 = tickP(t, &st).plan_time;
  EXPECT_NEAR(tickP(t, nullptr).plan_time, q0 + 0.005, 1e-12);
}

TEST_F(RuntimeTest, MoveToStartKeepsTheFeetAndTheLimits) {
  // The robot stands on the plan's start placements but in half-sitting (the plan leans its
  // legs) with its arms 0.05 rad away: the move must be smooth, within the velocity limits, and
  // keep the soles' relative pose fixed all the way (the closed chain of double support).
  runtime::PlanTrack track(*plan_, *model_);
  runtime::Replay r(track, params(), fastOptions());
  core::RobotState st = perfectState(*plan_, 0);
  st.q = model_->halfSitting().segment(6, track.joints());
  for (int j = 12; j < track.joints(); ++j) st.q(j) += 0.05;
  const auto& d = model_->description();
  const int rs = model_->frameIndex(d.foot("right")->sole_frame);
  const int ls = model_->frameIndex(d.foot("left")->sole_frame);
  auto rightInLeft = [&](const Eigen::VectorXd& qa) {
    Eigen::VectorXd q = plan_->q.col(0);
    q.segment(6, track.joints()) = qa;
    model_->setPositions(q);
    return Eigen::Isometry3d(model_->framePose(ls).inverse() * model_->framePose(rs));
  };
  const Eigen::Isometry3d X0 = rightInLeft(track.makeSample().q);
  r.start();
  Eigen::VectorXd prev = st.q;
  double max_rate = 0.0, max_foot_error = 0.0;
  int moving = 0;
  for (int i = 0; i < 2000 && r.state() != State::Running; ++i) {
    const auto& out = tickP(r, &st);
    // The move itself (then the stabilizer ramps in at the plan's first posture).
    if (out.state != State::MovingToStart || out.stab_status.mode != stabilizer::Mode::Off)
      continue;
    ++moving;
    for (int j = 0; j < st.q.size(); ++j)
      max_rate = std::max(
          max_rate, std::abs(out.command.q_ref(j) - prev(j)) * 200.0 / track.velocityLimit()(j));
    prev = out.command.q_ref;
    const Eigen::Isometry3d X = rightInLeft(out.command.q_ref);
    max_foot_error = std::max(max_foot_error, (X.translation() - X0.translation()).norm());
  }
  EXPECT_EQ(r.state(), State::Running) << runtime::toString(r.fault());
  EXPECT_GT(moving, 10);
  EXPECT_LT(max_rate, runtime::ReplayOptions{}.move_speed + 1e-6);
  // Relative to each other the soles move only by the difference of their compressions under the
  // plan's first loads (the legs are lengthened by them over the move).
  const runtime::TrackSample s0 = track.makeSample();
  const double kv = model_->description().bushing_vertical_stiffness;
  const double dc =
      std::abs(s0.ref.foot[0].wrench.force.z() - s0.ref.foot[1].wrench.force.z()) / kv;
  EXPECT_LT(max_foot_error, dc + 1e-6) << "the feet moved relative to each other during the move";
  // The last moving tick is one step of the quintic's flat end before the plan's first sample.
  EXPECT_LT((prev - track.makeSample().q).norm(), 1e-4);
}

TEST_F(RuntimeTest, StartFromAnotherStanceIsRefused) {
  // Every joint 0.05 rad away: the feet are not on the plan's start placements.
  runtime::PlanTrack track(*plan_, *model_);
  runtime::Replay r(track, params(), fastOptions());
  core::RobotState st = perfectState(*plan_, 0);
  st.q += Eigen::VectorXd::Constant(st.q.size(), 0.05);
  r.start();
  for (int i = 0; i < 5; ++i) tickP(r, &st);
  EXPECT_EQ(r.state(), State::Hold);
  EXPECT_EQ(r.fault(), FaultReason::StartUnreachable);
}

TEST_F(RuntimeTest, WatchdogHoldsAfterThreeMissedPeriods) {
  runtime::PlanTrack track(*plan_, *model_);
  runtime::Replay r(track, params(), fastOptions());
  core::RobotState st = perfectState(*plan_, 0);
  r.start();
  for (int i = 0; i < 2000 && r.state() != State::Running; ++i) tickP(r, &st);
  ASSERT_EQ(r.state(), State::Running);
  tickP(r, nullptr);
  tickP(r, nullptr);
  EXPECT_EQ(r.state(), State::Running);
  const auto& out = tickP(r, nullptr);
  EXPECT_EQ(out.state, State::Hold);
  EXPECT_EQ(out.fault, FaultReason::NoState);
  // Holding: the command stays finite and still goes out; a late state does not resume.
  EXPECT_TRUE(out.command.q_ref.allFinite());
  tickP(r, &st);
  EXPECT_EQ(r.state(), State::Hold);
  EXPECT_EQ(r.fault(), FaultReason::NoState);
}

TEST_F(RuntimeTest, StatesPausingBeforeTheFirstCommandOnlyDelayTheStart) {
  runtime::PlanTrack track(*plan_, *model_);
  runtime::Replay r(track, params(), fastOptions());
  core::RobotState st = perfectState(*plan_, 0);
  r.start();
  tickP(r, &st);  // the first state: the move to the start is planned from it
  // The robot's states pause for ten periods: nothing is commanded, nothing faults.
  for (int i = 0; i < 10; ++i) {
    const auto& out = tickP(r, nullptr);
    EXPECT_EQ(out.state, State::Idle);
    EXPECT_FALSE(out.send_command);
  }
  EXPECT_EQ(r.fault(), FaultReason::None);
  // The next state starts the move; from then on the watchdog guards the commands.
  EXPECT_EQ(tickP(r, &st).state, State::MovingToStart);
  for (int i = 0; i < 2; ++i) EXPECT_EQ(tickP(r, nullptr).state, State::MovingToStart);
  EXPECT_EQ(tickP(r, nullptr).state, State::Hold);
  EXPECT_EQ(r.fault(), FaultReason::NoState);
}

TEST_F(RuntimeTest, BadStatesFaultAndHold) {
  runtime::PlanTrack track(*plan_, *model_);
  const core::RobotState good = perfectState(*plan_, 0);
  struct Case {
    const char* name;
    std::function<void(core::RobotState&)> corrupt;
    FaultReason expect;
  };
  const std::vector<Case> cases = {
      {"nan joint", [](core::RobotState& s) { s.q(3) = std::nan(""); },
       FaultReason::NonFiniteState},
      {"inf force", [](core::RobotState& s) { s.ft_left.force.z() = INFINITY; },
       FaultReason::NonFiniteState},
      {"joint beyond limit", [](core::RobotState& s) { s.q(3) = 10.0; }, FaultReason::JointLimit},
      {"wrong size", [](core::RobotState& s) { s.resize(12); }, FaultReason::BadStateSize},
  };
  for (const auto& c : cases) {
    runtime::Replay r(track, params(), fastOptions());
    r.start();
    for (int i = 0; i < 50; ++i) tickP(r, &good);
    core::RobotState bad = good;
    c.corrupt(bad);
    const auto& out = tickP(r, &bad);
    EXPECT_EQ(out.state, State::Hold) << c.name;
    EXPECT_EQ(out.fault, c.expect) << c.name;
    EXPECT_TRUE(out.command.q_ref.allFinite()) << c.name;
  }
}

TEST_F(RuntimeTest, PauseResumeStop) {
  runtime::PlanTrack track(*plan_, *model_);
  runtime::Replay r(track, params(), fastOptions());
  const core::RobotState st = perfectState(*plan_, 0);
  r.start();
  while (r.state() != State::Running) tickP(r, &st);
  for (int i = 0; i < 20; ++i) tickP(r, &st);
  r.pause();
  const double t_pause = tickP(r, &st).plan_time;
  for (int i = 0; i < 30; ++i) EXPECT_EQ(tickP(r, &st).plan_time, t_pause);
  EXPECT_EQ(r.state(), State::Paused);
  r.resume();
  EXPECT_GT(tickP(r, &st).plan_time, t_pause);
  r.stop();
  const auto& out = tickP(r, &st);
  EXPECT_EQ(out.state, State::Hold);
  EXPECT_EQ(out.fault, FaultReason::Stopped);
  // The stabilizer ramps out: after its ramp time it is off and the command is the frozen sample.
  for (int i = 0; i < 400; ++i) tickP(r, &st);
  EXPECT_EQ(r.output().stab_status.mode, stabilizer::Mode::Off);
}

TEST_F(RuntimeTest, CommandsStayInsideLimitsWhateverTheCorrection) {
  // A robot leaning far forward (IMU 0.2 rad) drives the stabilizer into its limits: the command
  // must stay inside the joint limits and move no faster than the velocity limits.
  runtime::PlanTrack track(*plan_, *model_);
  runtime::Replay r(track, params(), fastOptions());
  core::RobotState st = perfectState(*plan_, 0);
  r.start();
  while (r.state() != State::Running) tickP(r, &st);
  st.imu_orientation = Eigen::AngleAxisd(0.08, Eigen::Vector3d::UnitY()) * st.imu_orientation;
  Eigen::VectorXd prev = r.output().command.q_ref;
  for (int i = 0; i < 300; ++i) {
    const auto& out = tickP(r, &st);
    for (int j = 0; j < st.q.size(); ++j) {
      EXPECT_GE(out.command.q_ref(j), track.lower()(j));
      EXPECT_LE(out.command.q_ref(j), track.upper()(j));
      EXPECT_LE(std::abs(out.command.q_ref(j) - prev(j)), track.velocityLimit()(j) / 200.0 + 1e-12);
    }
    prev = out.command.q_ref;
  }
}

TEST(LoopStats, WindowStatistics) {
  runtime::LoopStats s;
  for (int i = 0; i < 100; ++i) s.record(5000.0 + (i == 50 ? 3000.0 : 0.0), 10.0, 5000.0);
  s.record(5000.0, 6000.0, 5000.0);  // an overrun
  const auto w = s.summary(101, false);
  EXPECT_EQ(w.count, 101);
  EXPECT_DOUBLE_EQ(w.period_min, 5000.0);
  EXPECT_DOUBLE_EQ(w.period_max, 8000.0);
  EXPECT_NEAR(w.period_mean, 5000.0 + 3000.0 / 101.0, 1e-9);
  EXPECT_DOUBLE_EQ(w.period_p99, 5000.0);  // one outlier in 101 is above the 99th percentile
  EXPECT_EQ(s.overruns(), 1);
  EXPECT_DOUBLE_EQ(w.processing_max, 6000.0);
  // The whole run: 101 ticks, one 8 ms outlier above the 99th percentile.
  const auto all = s.run();
  EXPECT_EQ(all.count, 101);
  EXPECT_DOUBLE_EQ(all.period_max, 8000.0);
  EXPECT_NEAR(all.period_p99, 5010.0, 1e-9);  // upper edge of the 10 us bin holding 5000 us
}

}  // namespace
}  // namespace overstep
