// robots: the whole-body model against physics invariants, finite differences and closed forms.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>

#include "overstep/core/error.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "test_util.hpp"

namespace overstep::robots {
namespace {

using Eigen::VectorXd;

class Hrp2Model : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    shared_ = new WholeBodyModel(WholeBodyModel::fromFile(test::hrp2Yaml()));
  }
  static void TearDownTestSuite() {
    delete shared_;
    shared_ = nullptr;
  }
  void SetUp() override { model_ = std::make_unique<WholeBodyModel>(*shared_); }

  /// A seeded random state around half-sitting.
  void randomState(std::mt19937& rng, VectorXd& q, VectorXd& v, VectorXd& a) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int n = model_->dofs();
    q = model_->halfSitting();
    v.resize(n);
    a.resize(n);
    for (int i = 0; i < n; ++i) {
      q(i) += 0.3 * u(rng);
      v(i) = u(rng);
      a(i) = 3.0 * u(rng);
    }
  }

  static WholeBodyModel* shared_;
  std::unique_ptr<WholeBodyModel> model_;
};
WholeBodyModel* Hrp2Model::shared_ = nullptr;

TEST_F(Hrp2Model, CoordinateCountsAndNames) {
  EXPECT_EQ(model_->dofs(), 40);
  EXPECT_EQ(model_->baseDofs(), 6);
  EXPECT_EQ(model_->actuatedCount(), 30);
  EXPECT_EQ(model_->elasticCount(), 4);
  const auto names = model_->coordinateNames();
  ASSERT_EQ(names.size(), 40u);
  EXPECT_EQ(names[6], "RLEG_JOINT0");
  EXPECT_EQ(names[11], "RLEG_JOINT5");
  EXPECT_EQ(names[12], "LLEG_JOINT0");
  EXPECT_EQ(names[18], "CHEST_JOINT0");
  EXPECT_EQ(names[20], "HEAD_JOINT0");
  EXPECT_EQ(names[22], "RARM_JOINT0");
  EXPECT_EQ(names[35], "LARM_JOINT6");
  EXPECT_EQ(names[36], "RLEG_ELASTIC_ROLL");
  EXPECT_EQ(names[39], "LLEG_ELASTIC_PITCH");
  // Model order maps to distinct DART coordinates.
  std::vector<int> seen;
  for (int i = 0; i < 40; ++i) seen.push_back(model_->dartIndex(i));
  std::sort(seen.begin(), seen.end());
  for (int i = 0; i < 40; ++i) EXPECT_EQ(seen[static_cast<std::size_t>(i)], i);
}

TEST_F(Hrp2Model, JointAxesFollowHrp2Convention) {
  // Hip pitch about +y: a negative hip pitch swings the knee forward (+x).
  VectorXd q = model_->halfSitting();
  q.segment(6, 30).setZero();
  model_->setPositions(q);
  const int knee = model_->frameIndex("RLEG_LINK3");
  const double x0 = model_->framePose(knee).translation().x();
  q(model_->actuatedCoordinate(2)) = -0.3;
  model_->setPositions(q);
  EXPECT_GT(model_->framePose(knee).translation().x(), x0 + 0.05);
  // Hip roll about +x: a negative right hip roll moves the right foot outward (-y).
  q(model_->actuatedCoordinate(2)) = 0.0;
  q(model_->actuatedCoordinate(1)) = -0.2;
  model_->setPositions(q);
  EXPECT_LT(model_->framePose(model_->frameIndex("right_sole")).translation().y(), -0.2);
}

TEST_F(Hrp2Model, MassAndHalfSittingCom) {
  EXPECT_GE(model_->totalMass(), 56.0);
  EXPECT_LE(model_->totalMass(), 59.0);
  model_->setPositions(model_->halfSitting());
  const Eigen::Vector3d c = model_->com();
  EXPECT_GE(c.z(), 0.78);
  EXPECT_LE(c.z(), 0.84);
  EXPECT_NEAR(c.y(), 0.0, 0.005);
  // The CoM projects inside the support polygon, near the feet's centre line.
  EXPECT_GT(c.x(), -0.10);
  EXPECT_LT(c.x(), 0.13);
}

TEST_F(Hrp2Model, HalfSittingPutsSolesFlatOnGround) {
  model_->setPositions(model_->halfSitting());
  const Eigen::Isometry3d r = model_->framePose(model_->frameIndex("right_sole"));
  const Eigen::Isometry3d l = model_->framePose(model_->frameIndex("left_sole"));
  EXPECT_NEAR(r.translation().z(), 0.0, 1e-12);
  EXPECT_NEAR(l.translation().z(), 0.0, 1e-12);
  EXPECT_TRUE(r.linear().isIdentity(1e-12));
  EXPECT_TRUE(l.linear().isIdentity(1e-12));
  EXPECT_NEAR((r.translation() + l.translation()).norm(), 0.0, 1e-12);
  // Feet 0.19 m apart (hip 0.06 + 0.035 each side).
  EXPECT_NEAR(l.translation().y() - r.translation().y(), 0.19, 1e-9);
  // Pelvis height 0.105 + 0.3 cos 26 + 0.3 cos 24 = 0.6487 m.
  const double z = model_->framePose(model_->frameIndex("pelvis")).translation().z();
  EXPECT_NEAR(z, 0.105 + 0.3 * std::cos(26 * M_PI / 180) + 0.3 * std::cos(24 * M_PI / 180), 1e-9);
}

TEST_F(Hrp2Model, StaticsZmpIsComProjectionAndForceIsWeight) {
  const int n = model_->dofs();
  model_->setState(model_->halfSitting(), VectorXd::Zero(n), VectorXd::Zero(n));
  const VectorXd tau = model_->inverseDynamics();
  const core::Wrench w = model_->contactWrenchFromBase(tau);
  EXPECT_EQ(w.axes, core::Axes::kWorld);
  EXPECT_TRUE(w.point.isZero(0.0));
  const double weight = model_->totalMass() * model_->description().gravity;
  EXPECT_NEAR(w.force.z(), weight, 1e-9 * weight);  // the feet's wrench sum carries the weight
  EXPECT_NEAR(w.force.x(), 0.0, 1e-9);
  EXPECT_NEAR(w.force.y(), 0.0, 1e-9);
  const Eigen::Vector3d c = model_->com();
  const Eigen::Vector2d zmp = model_->zmpFromMotion();
  EXPECT_NEAR(zmp.x(), c.x(), 1e-10);
  EXPECT_NEAR(zmp.y(), c.y(), 1e-10);
  const Eigen::Vector2d tc = model_->tableCartZmp();
  EXPECT_NEAR(tc.x(), c.x(), 1e-12);
  EXPECT_NEAR(tc.y(), c.y(), 1e-12);
  // Elastic joints at rest carry only their foot's own weight moment: small, not zero.
  for (int i = 0; i < 4; ++i) EXPECT_LT(std::abs(tau(model_->elasticCoordinate(i))), 1.0);
}

TEST_F(Hrp2Model, InverseDynamicsEqualsMassMatrixTimesAccelerationPlusBias) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 5; ++trial) {
    VectorXd q, v, a;
    randomState(rng, q, v, a);
    model_->setState(q, v, a);
    const VectorXd tau = model_->inverseDynamics();
    const VectorXd expect = model_->massMatrix() * a + model_->nonlinearEffects();
    EXPECT_LT((tau - expect).norm(), 1e-8 * (1.0 + expect.norm())) << "trial " << trial;
    // The rotor term appears only on actuated rows, as N^2 I_m a.
    const VectorXd rigid = model_->massMatrix(false) * a + model_->nonlinearEffects();
    const auto& d = model_->description();
    for (int i = 0; i < model_->actuatedCount(); ++i) {
      const int c = model_->actuatedCoordinate(i);
      EXPECT_NEAR(tau(c) - rigid(c),
                  d.actuated[static_cast<std::size_t>(i)].reflectedInertia() * a(c), 1e-8);
    }
    for (int c = 0; c < 6; ++c) EXPECT_NEAR(tau(c), rigid(c), 1e-8);
  }
}

TEST_F(Hrp2Model, MassMatrixIsSymmetricPositiveDefinite) {
  std::mt19937 rng(11);
  VectorXd q, v, a;
  randomState(rng, q, v, a);
  model_->setPositions(q);
  const Eigen::MatrixXd M = model_->massMatrix();
  EXPECT_LT((M - M.transpose()).norm(), 1e-10);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M).eigenvalues().minCoeff(), 0.0);
}

TEST_F(Hrp2Model, LinearMomentumMatchesComFiniteDifference) {
  std::mt19937 rng(3);
  VectorXd q, v, a;
  randomState(rng, q, v, a);
  const double dt = 1e-6;
  model_->setPositions(model_->integrate(q, v, dt));
  const Eigen::Vector3d cp = model_->com();
  model_->setPositions(model_->integrate(q, v, -dt));
  const Eigen::Vector3d cm = model_->com();
  model_->setState(q, v, a);
  const Vector6d h = model_->centroidalMomentum();
  const Eigen::Vector3d fd = model_->totalMass() * (cp - cm) / (2 * dt);
  EXPECT_LT((h.head<3>() - fd).norm(), 1e-6 * (1 + fd.norm()));
  EXPECT_LT((model_->comVelocity() * model_->totalMass() - fd).norm(), 1e-6 * (1 + fd.norm()));
}

TEST_F(Hrp2Model, MomentumRateEqualsContactWrenchPlusGravity) {
  // Newton-Euler for the whole robot: d/dt [p; H_c] = [F - m g; tau_c] with the contact wrench
  // from the base rows of RNEA. Finite differences along the motion (q, v, a).
  std::mt19937 rng(5);
  VectorXd q, v, a;
  randomState(rng, q, v, a);
  const double dt = 1e-5;
  auto momentumAt = [&](double t) {
    model_->setPositions(model_->integrate(q, v * t + 0.5 * a * t * t, 1.0));
    model_->setVelocities(v + a * t);
    return model_->centroidalMomentum();
  };
  const Vector6d rate = (momentumAt(dt) - momentumAt(-dt)) / (2 * dt);
  model_->setState(q, v, a);
  const core::Wrench w_O = model_->contactWrenchFromBase(model_->inverseDynamics());
  const core::Wrench w_c = w_O.about(model_->com());
  const double mg = model_->totalMass() * model_->description().gravity;
  Eigen::Vector3d force = w_c.force;
  force.z() -= mg;
  EXPECT_LT((rate.head<3>() - force).norm(), 1e-4 * (1 + force.norm()));
  EXPECT_LT((rate.tail<3>() - w_c.moment).norm(), 1e-4 * (1 + w_c.moment.norm()));
}

TEST_F(Hrp2Model, ComJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(13);
  VectorXd q, v, a;
  randomState(rng, q, v, a);
  model_->setPositions(q);
  const Eigen::MatrixXd J = model_->comJacobian();
  const double eps = 1e-6;
  for (int i = 0; i < model_->dofs(); ++i) {
    VectorXd e = VectorXd::Zero(model_->dofs());
    e(i) = 1.0;
    model_->setPositions(model_->integrate(q, e, eps));
    const Eigen::Vector3d cp = model_->com();
    model_->setPositions(model_->integrate(q, e, -eps));
    const Eigen::Vector3d cm = model_->com();
    EXPECT_LT((J.col(i) - (cp - cm) / (2 * eps)).norm(), 1e-7) << "column " << i;
  }
}

TEST_F(Hrp2Model, FrameJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(17);
  VectorXd q, v, a;
  randomState(rng, q, v, a);
  for (const char* frame : {"right_sole", "left_ft", "imu", "head"}) {
    const int f = model_->frameIndex(frame);
    model_->setState(q, v, a);
    const Eigen::MatrixXd J = model_->frameJacobian(f);
    EXPECT_LT((J * v - model_->frameVelocity(f)).norm(), 1e-10) << frame;
    const double eps = 1e-6;
    model_->setPositions(model_->integrate(q, v, eps));
    const Eigen::Isometry3d Xp = model_->framePose(f);
    model_->setPositions(model_->integrate(q, v, -eps));
    const Eigen::Isometry3d Xm = model_->framePose(f);
    const Eigen::Vector3d lin = (Xp.translation() - Xm.translation()) / (2 * eps);
    const Eigen::AngleAxisd dR(Xp.linear() * Xm.linear().transpose());
    const Eigen::Vector3d ang = dR.axis() * dR.angle() / (2 * eps);
    EXPECT_LT(((J * v).tail<3>() - lin).norm(), 1e-6) << frame;
    EXPECT_LT(((J * v).head<3>() - ang).norm(), 1e-6) << frame;
    // Into a buffer (the planner's allocation-free form): every entry written, NaN-prefilled
    // buffers of the right size and of another size alike.
    model_->setState(q, v, a);
    for (const Eigen::Index cols : {Eigen::Index(model_->dofs()), Eigen::Index(3)}) {
      Eigen::MatrixXd Jb = Eigen::MatrixXd::Constant(6, cols, std::nan(""));
      model_->frameJacobian(f, Jb);
      ASSERT_EQ(Jb.cols(), model_->dofs());
      EXPECT_TRUE(Jb.allFinite()) << frame;
      EXPECT_EQ((Jb - J).cwiseAbs().maxCoeff(), 0.0) << frame;
    }
  }
  VectorXd tau = VectorXd::Constant(model_->dofs(), std::nan(""));
  model_->inverseDynamics(tau);
  EXPECT_EQ((tau - model_->inverseDynamics()).cwiseAbs().maxCoeff(), 0.0);
}

TEST_F(Hrp2Model, SpringTermOfElasticAnkle) {
  // At rest, deflecting an elastic joint by theta adds k theta to its required torque (plus the
  // foot's own small gravity change): the passive joint is in equilibrium when the moment it
  // transmits is k theta.
  const int n = model_->dofs();
  VectorXd q = model_->halfSitting();
  const auto& d = model_->description();
  for (int i = 0; i < model_->elasticCount(); ++i) {
    const int c = model_->elasticCoordinate(i);
    model_->setState(q, VectorXd::Zero(n), VectorXd::Zero(n));
    const double t0 = model_->inverseDynamics()(c);
    VectorXd qd = q;
    const double theta = 0.01;
    qd(c) = theta;
    model_->setPositions(qd);
    const double t1 = model_->inverseDynamics()(c);
    const double k = d.elastic[static_cast<std::size_t>(i)].stiffness;
    EXPECT_NEAR(t1 - t0, k * theta, 0.01 * k * theta)
        << d.elastic[static_cast<std::size_t>(i)].name;
    // Damping: a velocity on the joint adds d * qdot.
    VectorXd v = VectorXd::Zero(n);
    v(c) = 0.2;
    model_->setState(q, v, VectorXd::Zero(n));
    const double t2 = model_->inverseDynamics()(c);
    EXPECT_NEAR(t2 - t0, d.elastic[static_cast<std::size_t>(i)].damping * 0.2, 1e-3);
  }
}

TEST_F(Hrp2Model, ImpactMapStopsContactAndConservesMomentumAboutIt) {
  // Rigid-body model (no rotor term) so that momentum about the contact point is the full
  // angular momentum of the system.
  core::RobotDescription d = model_->description();
  for (auto& a : d.actuated) a.rotor_inertia = 0.0;
  WholeBodyModel rigid(d);
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const VectorXd q = rigid.halfSitting();
  VectorXd v(rigid.dofs());
  for (int i = 0; i < v.size(); ++i) v(i) = 0.5 * u(rng);
  rigid.setPositions(q);
  rigid.setVelocities(v);
  const int sole = rigid.frameIndex("left_sole");
  const Eigen::Vector3d p = rigid.framePose(sole).translation();
  auto momentumAbout = [&](const VectorXd& vel) {
    rigid.setVelocities(vel);
    const Vector6d h = rigid.centroidalMomentum();
    return Eigen::Vector3d(h.tail<3>() + (rigid.com() - p).cross(h.head<3>()));
  };
  const Eigen::Vector3d L0 = momentumAbout(v);
  const VectorXd vp = rigid.impactMap(v, {{sole, ContactConstraint::Type::Point}});
  rigid.setVelocities(vp);
  EXPECT_LT(rigid.frameVelocity(sole).tail<3>().norm(), 1e-10);
  EXPECT_LT((momentumAbout(vp) - L0).norm(), 1e-9 * (1 + L0.norm()));
  // Flat contact stops the whole foot; an inelastic impact never adds kinetic energy.
  const VectorXd vf = rigid.impactMap(v, {{sole, ContactConstraint::Type::Flat}});
  rigid.setVelocities(vf);
  EXPECT_LT(rigid.frameVelocity(sole).norm(), 1e-10);
  const Eigen::MatrixXd M = rigid.massMatrix();
  EXPECT_LE(vf.dot(M * vf), v.dot(M * v));
}

TEST_F(Hrp2Model, CopyIsIndependentWorkspace) {
  WholeBodyModel copy(*model_);
  VectorXd q = model_->halfSitting();
  model_->setPositions(q);
  q(model_->actuatedCoordinate(3)) += 0.5;
  copy.setPositions(q);
  EXPECT_GT((copy.com() - model_->com()).norm(), 1e-3);
}

// ------------------------------------------------------------------------- two-link closed forms
constexpr double kM1 = 2.0, kM2 = 1.0, kL1 = 0.5, kLc1 = 0.25,
                 kLc2 = 0.2;  // tests/data/two_link.urdf
constexpr double kI1 = 0.05, kI2 = 0.01, kK = 100.0, kD = 2.0, kRotor = 10.0 * 10.0 * 0.001,
                 kG = 9.81;

TEST(TwoLink, MassMatrixGravityAndSpringInClosedForm) {
  WholeBodyModel m = WholeBodyModel::fromFile(test::twoLinkYaml());
  ASSERT_EQ(m.dofs(), 2);
  ASSERT_EQ(m.baseDofs(), 0);
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Vector2d q(u(rng), 0.5 * u(rng)), v(u(rng), u(rng)), a(u(rng), u(rng));
    m.setState(q, v, a);
    const double c2 = std::cos(q(1)), s2 = std::sin(q(1));
    Eigen::Matrix2d M;
    M(0, 0) = kI1 + kM1 * kLc1 * kLc1 + kI2 +
              kM2 * (kL1 * kL1 + kLc2 * kLc2 + 2 * kL1 * kLc2 * c2) + kRotor;
    M(0, 1) = M(1, 0) = kI2 + kM2 * (kLc2 * kLc2 + kL1 * kLc2 * c2);
    M(1, 1) = kI2 + kM2 * kLc2 * kLc2;
    EXPECT_LT((m.massMatrix() - M).norm(), 1e-10) << "trial " << trial;
    const double t1 = q(0), t2 = q(0) + q(1);
    Eigen::Vector2d h;
    h(0) = -kM2 * kL1 * kLc2 * s2 * (2 * v(0) * v(1) + v(1) * v(1)) -
           kM1 * kG * kLc1 * std::cos(t1) - kM2 * kG * (kL1 * std::cos(t1) + kLc2 * std::cos(t2));
    h(1) = kM2 * kL1 * kLc2 * s2 * v(0) * v(0) - kM2 * kG * kLc2 * std::cos(t2) + kK * q(1) +
           kD * v(1);
    EXPECT_LT((m.nonlinearEffects() - h).norm(), 1e-9) << "trial " << trial;
    EXPECT_LT((m.inverseDynamics() - (M * a + h)).norm(), 1e-9) << "trial " << trial;
  }
}

TEST(TwoLink, ActuatorTorqueWithItsTipOnASupportInClosedForm) {
  // The arm at rest with its tip on a support that pushes with force F and moment M_y: the
  // shoulder motor holds gravity minus the support's moment about the shoulder, the bushing its
  // share about the elbow. Without the contact term the shoulder would hold the whole weight.
  WholeBodyModel m = WholeBodyModel::fromFile(test::twoLinkYaml());
  const int tip = m.frameIndex("tip");
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Vector2d q(u(rng), 0.5 * u(rng));
    m.setState(q, Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero());
    const double Fx = 20.0 * u(rng), Fz = 30.0 + 10.0 * u(rng), My = 2.0 * u(rng);
    FrameWrench w;
    w.frame = tip;
    m.setState(q, Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero());
    w.wrench = core::Wrench({Fx, 0.0, Fz}, {0.0, My, 0.0}, m.framePose(tip).translation(),
                            core::Axes::kWorld);
    const Eigen::VectorXd tau = m.torquesInContact(m.inverseDynamics(), {w});
    // A rotation q about +y turns a link along +x to (cos q, 0, -sin q).
    const double t1 = q(0), t2 = q(0) + q(1);
    const Eigen::Vector3d elbow(kL1 * std::cos(t1), 0.0, -kL1 * std::sin(t1));
    const Eigen::Vector3d p = elbow + Eigen::Vector3d(0.4 * std::cos(t2), 0.0, -0.4 * std::sin(t2));
    auto supportMomentY = [&](const Eigen::Vector3d& r) { return My + r.z() * Fx - r.x() * Fz; };
    const double gravity1 =
        -kM1 * kG * kLc1 * std::cos(t1) - kM2 * kG * (kL1 * std::cos(t1) + kLc2 * std::cos(t2));
    const double gravity2 = -kM2 * kG * kLc2 * std::cos(t2) + kK * q(1);
    EXPECT_NEAR(tau(0), gravity1 - supportMomentY(p), 1e-9) << "trial " << trial;
    EXPECT_NEAR(tau(1), gravity2 - supportMomentY(p - elbow), 1e-9) << "trial " << trial;
    EXPECT_GT(std::abs(tau(0) - m.inverseDynamics()(0)), 1.0);  // the contact term matters
  }
}

TEST(TwoLink, StaticMomentDeflectsElasticJointByMomentOverStiffness) {
  WholeBodyModel m = WholeBodyModel::fromFile(test::twoLinkYaml());
  // Upper link horizontal; find the flex angle where the passive joint is in equilibrium
  // (inverse-dynamics residual zero) by Newton on the model, then compare with M / k.
  double q2 = 0.0;
  for (int it = 0; it < 30; ++it) {
    auto residual = [&](double x) {
      m.setState(Eigen::Vector2d(0.0, x), Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero());
      return m.inverseDynamics()(1);
    };
    const double r = residual(q2);
    const double dr = (residual(q2 + 1e-7) - residual(q2 - 1e-7)) / 2e-7;
    q2 -= r / dr;
  }
  const double moment = kM2 * kG * kLc2 * std::cos(q2);  // gravity moment of the lower link
  EXPECT_GT(q2, 0.01);                                   // it sags (rotation about +y is downward)
  EXPECT_NEAR(q2, moment / kK, 1e-9);
}

// ------------------------------------------------------------------------- bad robot files
void expectModelError(const std::string& urdf_from, const std::string& urdf_to,
                      const std::string& expect) {
  test::TempDir dir;
  test::writeText(dir.path() / "hrp2.urdf",
                  test::replaceOnce(test::slurp(test::hrp2Urdf()), urdf_from, urdf_to));
  test::writeText(dir.path() / "hrp2.yaml", test::slurp(test::hrp2Yaml()));
  try {
    WholeBodyModel::fromFile(dir.file("hrp2.yaml"));
    FAIL() << "expected InputError containing '" << expect << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
  }
}

TEST(BadRobotFiles, UrdfMissingAJointTheYamlNames) {
  expectModelError("<joint name=\"LLEG_JOINT3\"", "<joint name=\"LLEG_KNEE\"",
                   "has no joint 'LLEG_JOINT3'");
}

TEST(BadRobotFiles, NegativeLinkMass) {
  expectModelError("<mass value=\"3.2\"/>", "<mass value=\"-3.2\"/>", "mass: expected > 0");
}

TEST(BadRobotFiles, MalformedUrdf) { expectModelError("</robot>", "</robt>", "malformed URDF"); }

// Issue 20, found by fuzz_robot's long run (seed 27): a shape of size 0 reached DART's BoxShape
// assertion (the process aborted); every shape size is checked first.
TEST(BadRobotFiles, ShapesOfSizeZeroAreBadInputNotAnAbort) {
  expectModelError(
      "<collision><origin xyz=\"0 0 0.08\" rpy=\"0 0 0\"/><geometry><box "
      "size=\"0.2 0.24 0.22\"/>",
      "<collision><origin xyz=\"0 0 0.08\" rpy=\"0 0 0\"/><geometry><box "
      "size=\"0.2 0 0.22\"/>",
      "collision box size: expected finite and > 0");
  expectModelError("<cylinder radius=\"0.045\" length=\"0.08\"/>",
                   "<cylinder radius=\"-0.045\" length=\"0.08\"/>",
                   "cylinder size: expected finite and > 0");
}

}  // namespace
}  // namespace overstep::robots

namespace overstep::robots {
namespace {

TEST(AnchorBase, StanceFootIsPlacedAndStationary) {
  WholeBodyModel m = WholeBodyModel::fromFile(test::hrp2Yaml());
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd q = m.halfSitting(), v(m.dofs()), a(m.dofs());
  for (int i = 0; i < m.dofs(); ++i) {
    q(i) += 0.2 * u(rng);
    v(i) = u(rng);
    a(i) = 2.0 * u(rng);
  }
  const Eigen::VectorXd joints = q.tail(m.dofs() - 6);
  Eigen::Isometry3d X_WF = Eigen::Isometry3d::Identity();
  X_WF.translation() << 0.4, -0.1, 0.0;
  X_WF.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const int foot = m.frameIndex("right_sole");
  m.anchorBase(foot, X_WF, q, v, a);
  EXPECT_TRUE(m.framePose(foot).isApprox(X_WF, 1e-12));
  EXPECT_LT(m.frameVelocity(foot).norm(), 1e-10);
  EXPECT_LT(m.frameAcceleration(foot).norm(), 1e-9);
  EXPECT_EQ(q.tail(m.dofs() - 6), joints);  // joint entries untouched
  // Integrating the anchored motion keeps the foot in place to second order.
  const double dt = 1e-4;
  m.setPositions(m.integrate(q, v * dt + 0.5 * a * dt * dt, 1.0));
  EXPECT_LT((m.framePose(foot).translation() - X_WF.translation()).norm(), 1e-9);
}

}  // namespace
}  // namespace overstep::robots
