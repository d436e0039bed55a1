// planner building blocks: phase timing, moving-knot B-splines, capsule/obstacle distances.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "overstep/core/error.hpp"
#include "overstep/core/obstacle.hpp"
#include "overstep/planner/phases.hpp"
#include "overstep/planner/spline.hpp"
#include "overstep/robots/collision.hpp"

namespace overstep::planner {
using namespace robots;  // the collision geometry under test lives in robots/
namespace {

Eigen::VectorXd durations() {
  Eigen::VectorXd d(kPhaseCount);
  d << 0.6, 1.2, 0.3, 1.1, 0.9;
  return d;
}

TEST(Phases, TableFollowsTheSeedSequence) {
  const auto& t = phaseTable();
  EXPECT_TRUE(t[0].right_contact && t[0].left_contact);
  EXPECT_TRUE(!t[1].right_contact && t[1].left_contact);  // right foot swings
  EXPECT_TRUE(t[2].right_contact && t[2].left_contact);
  EXPECT_TRUE(t[3].right_contact && !t[3].left_contact);  // left foot swings
  EXPECT_TRUE(t[4].right_contact && t[4].left_contact);
  // The base is anchored on a foot that is in contact in every phase.
  for (const auto& p : t)
    EXPECT_TRUE(p.base_foot == Foot::Right ? p.right_contact : p.left_contact);
}

TEST(Phases, LocateAndTimeGradient) {
  const PhaseTiming timing(durations());
  EXPECT_DOUBLE_EQ(timing.total(), 4.1);
  EXPECT_DOUBLE_EQ(timing.start(2), 1.8);
  GridPoint g = timing.locate(1.8);  // a boundary belongs to the later phase
  EXPECT_EQ(g.phase, 2);
  EXPECT_NEAR(g.s, 0.0, 1e-12);
  g = timing.locate(2.65);
  EXPECT_EQ(g.phase, 3);
  EXPECT_NEAR(g.s, 0.5, 1e-12);
  EXPECT_EQ(timing.locate(-1.0).phase, 0);
  EXPECT_EQ(timing.locate(99.0).phase, 4);
  EXPECT_DOUBLE_EQ(timing.locate(99.0).s, 1.0);
  // dt/dT by finite differences.
  const double s = 0.3;
  const Eigen::VectorXd grad = timing.timeGradient(3, s);
  for (int i = 0; i < kPhaseCount; ++i) {
    Eigen::VectorXd d = durations();
    d(i) += 1e-6;
    EXPECT_NEAR((PhaseTiming(d).timeOf(3, s) - timing.timeOf(3, s)) / 1e-6, grad(i), 1e-8);
  }
}

TEST(Phases, GridCoversTheMotion) {
  const PhaseTiming timing(durations());
  const auto grid = timing.grid({2, 3, 1, 3, 2});
  ASSERT_EQ(grid.size(), 12u);
  EXPECT_DOUBLE_EQ(grid.front().t, 0.0);
  EXPECT_DOUBLE_EQ(grid.back().t, timing.total());
  for (std::size_t i = 1; i < grid.size(); ++i) EXPECT_GT(grid[i].t, grid[i - 1].t);
}

TEST(Phases, RejectsBadDurations) {
  Eigen::VectorXd d = durations();
  d(2) = -0.1;
  EXPECT_THROW(PhaseTiming{d}, InputError);
  d(2) = std::nan("");
  EXPECT_THROW(PhaseTiming{d}, InputError);
  EXPECT_THROW(PhaseTiming{Eigen::VectorXd::Ones(3)}, InputError);
}

TEST(Spline, PartitionOfUnityAndDerivativesMatchFiniteDifferences) {
  PhaseSpline sp({3, 6, 2, 6, 3});
  sp.setTiming(PhaseTiming(durations()));
  EXPECT_EQ(sp.controlPointCount(), 23);
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd ctrl(2, sp.controlPointCount());
  for (int i = 0; i < ctrl.size(); ++i) ctrl(i) = u(rng);
  for (double t = 0.013; t < 4.1; t += 0.097) {
    const auto b = sp.evaluate(t);
    EXPECT_NEAR(b.value.sum(), 1.0, 1e-12);
    EXPECT_NEAR(b.d1.sum(), 0.0, 1e-9);
    Eigen::VectorXd x, xd, xdd, xp, xm, xdp, xdm;
    const double h = 1e-5;
    sp.evaluate(ctrl, t, &x, &xd, &xdd);
    sp.evaluate(ctrl, t + h, &xp, &xdp, nullptr);
    sp.evaluate(ctrl, t - h, &xm, &xdm, nullptr);
    EXPECT_LT((xd - (xp - xm) / (2 * h)).norm(), 1e-6) << "t = " << t;
    EXPECT_LT((xdd - (xdp - xdm) / (2 * h)).norm(), 1e-4) << "t = " << t;
  }
}

TEST(Spline, C2AcrossPhaseBoundariesAndClampedEnds) {
  PhaseSpline sp({2, 4, 1, 4, 2});
  const PhaseTiming timing(durations());
  sp.setTiming(timing);
  Eigen::MatrixXd ctrl(1, sp.controlPointCount());
  for (int i = 0; i < ctrl.cols(); ++i) ctrl(0, i) = std::sin(1.3 * i);
  for (int p = 1; p < kPhaseCount; ++p) {
    const double tb = timing.start(p), e = 1e-9;
    Eigen::VectorXd a, ad, add, b, bd, bdd;
    sp.evaluate(ctrl, tb - e, &a, &ad, &add);
    sp.evaluate(ctrl, tb + e, &b, &bd, &bdd);
    EXPECT_NEAR(a(0), b(0), 1e-7);
    EXPECT_NEAR(ad(0), bd(0), 1e-6);
    EXPECT_NEAR(add(0), bdd(0), 1e-4);
  }
  Eigen::VectorXd x0, xT;
  sp.evaluate(ctrl, 0.0, &x0, nullptr, nullptr);
  sp.evaluate(ctrl, timing.total(), &xT, nullptr, nullptr);
  EXPECT_NEAR(x0(0), ctrl(0, 0), 1e-12);
  EXPECT_NEAR(xT(0), ctrl(0, ctrl.cols() - 1), 1e-12);
  // Three equal leading control points: rest (zero velocity and acceleration) at the start.
  ctrl(0, 1) = ctrl(0, 2) = ctrl(0, 0);
  Eigen::VectorXd xd, xdd;
  sp.evaluate(ctrl, 0.0, nullptr, &xd, &xdd);
  EXPECT_NEAR(xd(0), 0.0, 1e-12);
  EXPECT_NEAR(xdd(0), 0.0, 1e-9);
}

// Closed-form segment-segment distance for the cases below.
TEST(Collision, CapsuleDistancesMatchClosedForms) {
  // Parallel capsules along x, 0.3 m apart in y, radii 0.05 and 0.07.
  Capsule a{{0, 0, 0}, {1, 0, 0}, 0.05};
  Capsule b{{0.2, 0.3, 0}, {0.8, 0.3, 0}, 0.07};
  EXPECT_NEAR(capsuleDistance(a, b), 0.3 - 0.12, 1e-6);
  // Crossing segments (x axis and a y-parallel segment 0.2 above): distance 0.2 - radii.
  Capsule c{{0.5, -1, 0.2}, {0.5, 1, 0.2}, 0.04};
  EXPECT_NEAR(capsuleDistance(a, c), 0.2 - 0.09, 1e-6);
  // Collinear, end to end: segments 0.18 apart, radii 0.05 + 0.03.
  Capsule d{{1.18, 0, 0}, {2, 0, 0}, 0.03};
  EXPECT_NEAR(capsuleDistance(a, d), 0.18 - 0.08, 1e-6);
  // Skew: endpoint of one to the interior of the other.
  Capsule e{{0.3, 0.5, 0.0}, {0.3, 0.9, 0.0}, 0.01};
  EXPECT_NEAR(capsuleDistance(a, e), 0.5 - 0.06, 1e-6);
  // Overlap: negative (penetration).
  Capsule f{{0.5, 0.06, 0}, {0.5, 1, 0}, 0.05};
  EXPECT_LT(capsuleDistance(a, f), 0.0);
}

TEST(Collision, ObstacleDistancesMatchClosedForms) {
  core::ObstacleSpec box;
  box.height = 0.2;
  box.width = 0.11;
  box.gap = 0.05;
  const ObstacleGeometry g = ObstacleGeometry::fromSpec(box, 0.13);  // near face x = 0.18
  // A vertical capsule 0.1 m in front of the near face.
  Capsule front{{0.08, 0, 0.05}, {0.08, 0, 0.3}, 0.02};
  EXPECT_NEAR(obstacleDistance(front, g), 0.10 - 0.02, 1e-6);
  // A horizontal capsule (sole) above the bar: distance to its top.
  Capsule above{{0.1, 0.0, 0.26}, {0.4, 0.0, 0.26}, 0.03};
  EXPECT_NEAR(obstacleDistance(above, g), 0.06 - 0.03, 1e-6);
  // Cylinder bar of diameter 0.11 whose top is at 0.2: a sphere above its axis.
  core::ObstacleSpec cyl = box;
  cyl.shape = core::ObstacleSpec::Shape::Cylinder;
  const ObstacleGeometry gc = ObstacleGeometry::fromSpec(cyl, 0.13);
  EXPECT_NEAR(gc.centre.x(), 0.18 + 0.055, 1e-12);
  EXPECT_NEAR(gc.centre.z(), 0.2 - 0.055, 1e-12);
  Capsule ball{{gc.centre.x(), 0.0, 0.35}, {gc.centre.x(), 0.0, 0.35}, 0.05};
  EXPECT_NEAR(obstacleDistance(ball, gc), 0.35 - 0.2 - 0.05, 1e-6);
  // Diagonal from the axis at 45 degrees in the x-z plane: distance = |p - axis| - r - radius.
  const Eigen::Vector3d p = gc.centre + 0.2 * Eigen::Vector3d(1, 0, 1).normalized();
  Capsule diag{p, p, 0.01};
  EXPECT_NEAR(obstacleDistance(diag, gc), 0.2 - 0.055 - 0.01, 1e-6);
  // A shin through the bar: negative distance (penetration), no abort.
  Capsule through{{0.2, 0.0, 0.05}, {0.3, 0.0, 0.05}, 0.02};
  const double pen = obstacleDistance(through, g);
  EXPECT_LT(pen, -0.02);
  EXPECT_GT(pen, -0.2);
  // Margin grows the envelope.
  core::ObstacleSpec wide = box;
  wide.margin = 0.02;
  EXPECT_NEAR(obstacleDistance(front, ObstacleGeometry::fromSpec(wide, 0.13)), 0.08 - 0.02, 1e-6);
}

// The planner's closed-form capsule-box distance against FCL's GJK / EPA (the check's), on
// random capsules around the default bar: clear of it, touching and through it, long and
// degenerate (spheres), every orientation. Witness points: on the capsule's and the box's
// surfaces, as far apart as the distance says (along the separating direction when they overlap).
TEST(Collision, BoxDistanceMatchesFclAndItsWitnessPoints) {
  core::ObstacleSpec spec;
  spec.height = 0.2;
  spec.width = 0.11;
  spec.gap = 0.05;
  const ObstacleGeometry g = ObstacleGeometry::fromSpec(spec, 0.13);
  const Eigen::Vector3d h = 0.5 * g.size;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int overlapping = 0, clear = 0;
  double worst_fcl_clear = 0.0, worst_fcl_overlap = 0.0;
  for (int k = 0; k < 4000; ++k) {
    const Eigen::Vector3d c =
        g.centre + Eigen::Vector3d(u(rng) * (h.x() + 0.15), u(rng) * 0.3, u(rng) * (h.z() + 0.15));
    const Eigen::Vector3d dir = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const double len = k % 10 == 0 ? 0.0 : 0.3 * std::abs(u(rng));
    const Capsule a{c - 0.5 * len * dir, c + 0.5 * len * dir, 0.01 + 0.05 * std::abs(u(rng))};
    Eigen::Vector3d pa, pb;
    const double d = boxDistance(a, g, &pa, &pb);
    const double d_fcl = obstacleDistanceFcl(a, g);
    ASSERT_TRUE(std::isfinite(d));
    double& worst = d > 0.0 ? worst_fcl_clear : worst_fcl_overlap;
    worst = std::max(worst, std::abs(d - d_fcl));
    if (d > 0.0) {  // clear: the least of the segment's points' exact distances to the box
      auto at = [&](double s) {
        const Eigen::Vector3d x = a.p0 + (a.p1 - a.p0) * s - g.centre;
        return (x - x.cwiseMax(-h).cwiseMin(h)).norm() - a.radius;
      };
      double ref = 1e9, s_ref = 0.0;
      for (int i = 0; i <= 1000; ++i)
        if (at(i / 1000.0) < ref) ref = at(i / 1000.0), s_ref = i / 1000.0;
      for (int i = -1000; i <= 1000; ++i)  // refined around the best sample
        ref = std::min(ref, at(std::clamp(s_ref + i * 1e-6, 0.0, 1.0)));
      ASSERT_LE(d, ref + 1e-12) << "capsule " << k;
      ASSERT_NEAR(d, ref, 1e-7) << "capsule " << k;
    }
    EXPECT_DOUBLE_EQ(obstacleDistance(a, g), d);
    // pb on the box's surface; pa - pb as long as |d|.
    const Eigen::Vector3d b = pb - g.centre;
    EXPECT_LE((b.cwiseAbs() - h).maxCoeff(), 1e-12);
    EXPECT_NEAR((b.cwiseAbs() - h).maxCoeff(), 0.0, 1e-12) << "capsule " << k;
    EXPECT_NEAR((pa - pb).norm(), std::abs(d), 1e-9) << "capsule " << k;
    // pa on the capsule's surface: a radius from its segment.
    const Capsule point{pa, pa, 0.0}, axis{a.p0, a.p1, 0.0};
    EXPECT_NEAR(capsuleDistance(point, axis), a.radius, 1e-9) << "capsule " << k;
    (d < 0.0 ? overlapping : clear)++;
  }
  EXPECT_LT(std::max(worst_fcl_clear, worst_fcl_overlap), 1e-4);  // libccd's GJK / EPA
  std::printf("closed form vs FCL, worst: clear %.2e m, overlapping %.2e m\n", worst_fcl_clear,
              worst_fcl_overlap);
  EXPECT_GT(overlapping, 500);  // both cases well sampled
  EXPECT_GT(clear, 500);
}

// The log-sum-exp minimum (KS) of the self-clearance row: below the minimum by at most
// log(n) / rho, its softmax weights its gradient.
TEST(Collision, SmoothMinBoundsAndGradient) {
  Eigen::VectorXd d(4);
  d << 0.3, 0.05, 0.2, 0.051;
  Eigen::VectorXd w = Eigen::VectorXd::Constant(4, std::nan(""));
  const double rho = 200.0;
  const double s = smoothMin(d, rho, &w);
  EXPECT_LE(s, d.minCoeff());
  EXPECT_GE(s, d.minCoeff() - std::log(4.0) / rho);
  EXPECT_NEAR(w.sum(), 1.0, 1e-12);
  for (int i = 0; i < 4; ++i) {
    Eigen::VectorXd dp = d;
    dp(i) += 1e-7;
    EXPECT_NEAR((smoothMin(dp, rho) - s) / 1e-7, w(i), 1e-5);
  }
}

TEST(Collision, SoftMinIsExactOnTiesBoundedAboveTheMinimumWithItsGradient) {
  const double rho = 1000.0;
  // Six tied distances (a start stance's foot capsules facing the bar): exactly their value,
  // where the log-sum-exp minimum would be log(6) / rho = 1.8 mm below it.
  EXPECT_NEAR(softMin(Eigen::VectorXd::Constant(6, 0.0105), rho), 0.0105, 1e-15);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 0.01);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 2 + trial % 9;
    Eigen::VectorXd d(n);
    for (int i = 0; i < n; ++i) d(i) = 0.02 + u(rng) * (trial % 3 == 0 ? 0.3 : 1.0);
    Eigen::VectorXd g = Eigen::VectorXd::Constant(n, std::nan(""));
    const double s = softMin(d, rho, &g);
    EXPECT_GE(s, d.minCoeff() - 1e-15);
    EXPECT_LE(s, d.minCoeff() + (n - 1) / (std::exp(1.0) * rho) + 1e-15);
    ASSERT_TRUE(g.allFinite());
    for (int i = 0; i < n; ++i) {
      Eigen::VectorXd dp = d, dm = d;
      dp(i) += 1e-8;
      dm(i) -= 1e-8;
      EXPECT_NEAR((softMin(dp, rho) - softMin(dm, rho)) / 2e-8, g(i), 1e-6) << trial << " " << i;
    }
  }
  // One distance nearest by far: that distance.
  Eigen::VectorXd far(3);
  far << 0.01, 0.05, 0.08;
  EXPECT_NEAR(softMin(far, rho), 0.01, 1e-12);
}

TEST(Obstacle, RejectsBadSizes) {
  core::ObstacleSpec s;
  s.height = -0.2;
  EXPECT_THROW(core::validate(s), InputError);
  s.height = 0.2;
  s.width = std::nan("");
  EXPECT_THROW(core::validate(s), InputError);
  s.width = 0.3;
  s.shape = core::ObstacleSpec::Shape::Cylinder;
  EXPECT_THROW(core::validate(s), InputError);  // diameter above its top height
  EXPECT_THROW(core::parseObstacleShape("sphere"), InputError);
  EXPECT_EQ(core::parseObstacleShape("cylinder"), core::ObstacleSpec::Shape::Cylinder);
}

// Issue 20: a 1e20 m wide bar reached FCL (an exception: exit 1); every size is capped at 100 m.
TEST(Obstacle, RejectsSizesBeyondAHundredMetres) {
  for (double core::ObstacleSpec::*field :
       {&core::ObstacleSpec::height, &core::ObstacleSpec::width, &core::ObstacleSpec::length,
        &core::ObstacleSpec::gap, &core::ObstacleSpec::margin}) {
    core::ObstacleSpec s;
    s.*field = 1e20;
    EXPECT_THROW(core::validate(s), InputError);
    s.*field = 100.0;  // a box: no cylinder rule
    EXPECT_NO_THROW(core::validate(s));
  }
}

}  // namespace
}  // namespace overstep::planner
