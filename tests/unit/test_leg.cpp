// robots: the legs read from the kinematic tree and their closed-form inverse kinematics, against
// DART's forward kinematics and Jacobians, central differences and malformed legs.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "overstep/core/error.hpp"
#include "overstep/robots/leg.hpp"
#include "test_util.hpp"

namespace overstep::robots {
namespace {

class Legs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    model_ = new WholeBodyModel(WholeBodyModel::fromFile(test::hrp2Yaml()));
  }
  static void TearDownTestSuite() {
    delete model_;
    model_ = nullptr;
  }
  /// Seeded random leg angles inside the safe limits, knee bent at least 10 deg.
  static Vector6d randomLeg(std::mt19937& rng, const LegChain& c) {
    const auto& d = model_->description();
    Vector6d q;
    for (int i = 0; i < 6; ++i) {
      const auto& j = d.actuated[static_cast<std::size_t>(c.actuated[i])];
      std::uniform_real_distribution<double> u(j.safeLower(), j.safeUpper());
      q(i) = u(rng);
    }
    q(3) = std::max(q(3), 10.0 * M_PI / 180.0);
    return q;
  }
  /// The model at the zero posture with leg c at q: the ankle link's pose (base at the origin).
  static Eigen::Isometry3d dartAnkle(const LegChain& c, const Vector6d& q,
                                     Eigen::MatrixXd* J = nullptr) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(model_->dofs());
    for (int i = 0; i < 6; ++i) x(model_->actuatedCoordinate(c.actuated[i])) = q(i);
    model_->setPositions(x);
    if (J) *J = model_->frameJacobian(c.ankle_frame);
    return model_->framePose(c.ankle_frame);
  }
  static WholeBodyModel* model_;
};
WholeBodyModel* Legs::model_ = nullptr;

TEST_F(Legs, ChainsComeFromTheKinematicTree) {
  const auto legs = legChains(*model_);
  ASSERT_EQ(legs.size(), 2u);
  const auto& d = model_->description();
  for (const auto& c : legs) {
    const std::string p = c.side == "right" ? "RLEG_" : "LLEG_";
    for (int i = 0; i < 6; ++i)
      EXPECT_EQ(d.actuated[static_cast<std::size_t>(c.actuated[i])].name,
                p + "JOINT" + std::to_string(i));
    ASSERT_EQ(c.elastic.size(), 2u);
    EXPECT_EQ(d.elastic[static_cast<std::size_t>(c.elastic[0])].name, p + "ELASTIC_ROLL");
    EXPECT_EQ(d.elastic[static_cast<std::size_t>(c.elastic[1])].name, p + "ELASTIC_PITCH");
    EXPECT_EQ(c.ankle_link, p + "LINK5");
    EXPECT_EQ(c.foot_link, p + "FOOT");
    EXPECT_EQ(c.links.front(), p + "LINK0");
    EXPECT_EQ(c.links.back(), p + "FOOT");
  }
}

TEST_F(Legs, ForwardKinematicsAndJacobianMatchDart) {
  std::mt19937 rng(11);
  for (const auto& c : legChains(*model_)) {
    const LegIk ik(*model_, c);
    for (int trial = 0; trial < 50; ++trial) {
      const Vector6d q = randomLeg(rng, c);
      Eigen::MatrixXd J;
      const Eigen::Isometry3d X = dartAnkle(c, q, &J);
      EXPECT_TRUE(ik.forward(q).isApprox(X, 1e-12)) << c.side << " trial " << trial;
      const Eigen::Matrix<double, 6, 6> Jl = ik.jacobian(q);
      for (int i = 0; i < 6; ++i)
        EXPECT_LT((Jl.col(i) - J.col(model_->actuatedCoordinate(c.actuated[i]))).norm(), 1e-12)
            << c.side << " joint " << i;
    }
  }
}

TEST_F(Legs, ClosedFormRecoversEveryPostureExactly) {
  // Every solution is exact (its forward kinematics is the target); for the postures of
  // stepping (knee <= 100 deg) it is the posture itself; with the knee folded further another
  // branch can exist inside the limits, and a reference posture selects the one wanted.
  std::mt19937 rng(12);
  for (const auto& c : legChains(*model_)) {
    const LegIk ik(*model_, c);
    for (int trial = 0; trial < 500; ++trial) {
      const Vector6d q = randomLeg(rng, c);
      const Eigen::Isometry3d X = dartAnkle(c, q);
      const LegIkResult r = ik.solve(X);
      EXPECT_TRUE(r.reachable);
      EXPECT_TRUE(ik.forward(r.q).isApprox(X, 1e-12)) << c.side << " trial " << trial;
      if (q(3) <= 100.0 * M_PI / 180.0) {
        EXPECT_LT((r.q - q).cwiseAbs().maxCoeff(), 1e-9) << c.side << " trial " << trial;
      }
      EXPECT_LT((ik.solve(X, &q).q - q).cwiseAbs().maxCoeff(), 1e-9) << c.side << " " << trial;
      EXPECT_LE(r.hip_ankle, ik.maxReach() + 1e-12);
      EXPECT_GE(r.hip_ankle, ik.minReach() - 1e-12);
    }
  }
}

TEST_F(Legs, DerivativeIsTheInverseLegJacobian) {
  // Implicit-function theorem: d q = J^-1 [d theta; d p], checked by central differences of the
  // closed form along random pose directions (rotation vector and translation, base frame).
  std::mt19937 rng(13);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const auto& c : legChains(*model_)) {
    const LegIk ik(*model_, c);
    for (int trial = 0; trial < 50; ++trial) {
      Vector6d q = randomLeg(rng, c);
      q(3) = std::min(q(3), 100.0 * M_PI / 180.0);  // away from the folded-knee branch point
      const Eigen::Isometry3d X = ik.forward(q);
      Vector6d dir;
      for (int i = 0; i < 6; ++i) dir(i) = n(rng);
      auto moved = [&](double h) {
        Eigen::Isometry3d Y = X;
        Y.linear() =
            Eigen::AngleAxisd(h * dir.head<3>().norm(), dir.head<3>().normalized()) * X.linear();
        Y.translation() += h * dir.tail<3>();
        return ik.solve(Y, &q).q;
      };
      const double h = 1e-6;
      const Vector6d fd = (moved(h) - moved(-h)) / (2.0 * h);
      const Vector6d exact = ik.jacobian(q).partialPivLu().solve(dir);
      EXPECT_LT((fd - exact).norm(), 1e-6 * (1.0 + exact.norm())) << c.side << " trial " << trial;
    }
  }
}

TEST_F(Legs, BeyondReachPointsTheStretchedLegAtTheTarget) {
  const auto legs = legChains(*model_);
  const LegIk ik(*model_, legs[0]);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = ik.hipCentre() + Eigen::Vector3d(0.1, 0.0, -1.0);  // 1 m below the hip
  const LegIkResult r = ik.solve(X);
  EXPECT_FALSE(r.reachable);
  EXPECT_TRUE(r.q.allFinite());
  EXPECT_NEAR(r.q(3), 0.0, 1e-9);  // knee straight
  const Eigen::Vector3d A = ik.forward(r.q) * ik.ankleCentre() - ik.hipCentre();
  const Eigen::Vector3d want = X * ik.ankleCentre() - ik.hipCentre();
  EXPECT_NEAR(A.norm(), ik.maxReach(), 1e-9);
  EXPECT_GT(A.normalized().dot(want.normalized()), 0.99);
}

// The planner's continuation beyond reach: within reach the same angles as the pose solve; past
// it the knee bends the other way, from straight at the boundary, further the further the target,
// every angle finite (a constant knee there gave an optimiser's joint-limit row no gradient).
TEST_F(Legs, ContinuationBeyondReachBendsTheKneePastStraight) {
  for (const LegChain& c : legChains(*model_)) {
    const LegIk ik(*model_, c);
    const Eigen::Vector3d dir = Eigen::Vector3d(0.1, 0.0, -1.0).normalized();
    // The ankle link placed so that its ankle centre lies `dist` from the hip centre along dir.
    auto target = [&](double dist) {
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      X.translation() = ik.hipCentre() + dist * dir - ik.ankleCentre();
      return X;
    };
    const double R = ik.maxReach();
    for (const double dist : {R - 0.05, R - 0.01}) {
      const LegIkResult pose = ik.solve(target(dist));
      const LegIkResult cont = ik.solve(target(dist), nullptr, BeyondReach::Continue);
      ASSERT_TRUE(pose.reachable) << c.side << " " << dist;
      EXPECT_EQ((pose.q - cont.q).cwiseAbs().maxCoeff(), 0.0) << c.side << " " << dist;
    }
    double last_knee = 0.0;
    for (const double excess : {1e-9, 1e-4, 1e-3, 1e-2, 5e-2}) {
      const LegIkResult pose = ik.solve(target(R + excess));
      const LegIkResult cont = ik.solve(target(R + excess), nullptr, BeyondReach::Continue);
      EXPECT_FALSE(cont.reachable) << c.side << " " << excess;
      EXPECT_TRUE(cont.q.allFinite()) << c.side << " " << excess;
      EXPECT_NEAR(pose.q(3), 0.0, 1e-9) << c.side << " " << excess;
      EXPECT_LT(cont.q(3), last_knee) << c.side << " " << excess;
      if (excess == 1e-9) {
        EXPECT_GT(cont.q(3), -1e-3) << c.side;  // continuous at the boundary
      }
      last_knee = cont.q(3);
    }
  }
}

TEST(LegShape, AnkleAxesThatDoNotMeetAreRefused) {
  test::TempDir dir;
  // Move the right ankle roll 1 cm below the ankle pitch: no closed form any more.
  std::string urdf = test::slurp(test::hrp2Urdf());
  const std::string from =
      "<parent link=\"RLEG_LINK4\"/><child link=\"RLEG_LINK5\"/>\n    <origin xyz=\"0 -0 0\"";
  urdf = test::replaceOnce(urdf, from,
                           "<parent link=\"RLEG_LINK4\"/><child link=\"RLEG_LINK5\"/>\n    "
                           "<origin xyz=\"0 -0 -0.01\"");
  test::writeText(dir.path() / "hrp2.urdf", urdf);
  test::writeText(dir.path() / "hrp2.yaml", test::slurp(test::hrp2Yaml()));
  const WholeBodyModel m = WholeBodyModel::fromFile(dir.file("hrp2.yaml"));
  const auto legs = legChains(m);
  try {
    LegIk ik(m, legs[0]);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ankle axes do not meet"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(LegIk(m, legs[1]));  // the left leg is untouched
}

}  // namespace
}  // namespace overstep::robots
