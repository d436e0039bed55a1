// The execution-fidelity figures (monitor/fidelity.hpp) on synthetic runs whose answers follow
// from their construction: a standing run as planned, a bounce after a touchdown, a stamping
// touchdown, CoP offsets of known distribution, moment oscillations above and below the chatter
// band, the settling of a decaying base speed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "overstep/monitor/fidelity.hpp"

namespace overstep::monitor {
namespace {

constexpr double kDt = 0.005;  // the runtime's 200 Hz
constexpr double kWeight = 570.0;
constexpr double kPi = 3.14159265358979323846;

/// A run of `duration` s plus `hold` s after it: both feet planned in contact and loaded with
/// half the weight each, measured exactly so, CoP at the sole origin, the base static.
RunSeries standing(double duration, double hold) {
  RunSeries r;
  const auto n = static_cast<std::size_t>(std::lround((duration + hold) / kDt)) + 1;
  r.resize(n);
  r.plan_end = duration;
  r.weight = kWeight;
  for (std::size_t i = 0; i < n; ++i) {
    r.t[i] = static_cast<double>(i) * kDt;
    for (auto& f : r.foot) {
      f.fz_plan[i] = f.fz_meas[i] = kWeight / 2;
      f.cop_plan[i] = f.cop_meas[i] = Eigen::Vector2d::Zero();
      f.moment_meas[i] = Eigen::Vector2d::Zero();
      f.plan_contact[i] = 1;
    }
    r.base_speed[i] = 0.0;
    r.tilt_plan[i] = r.tilt_meas[i] = Eigen::Vector2d::Zero();
  }
  return r;
}

/// The right foot planned in the air over [t0, t1) (and unloaded there, as measured), touching
/// down at t1: the left foot carries the weight meanwhile.
void swingRight(RunSeries& r, double t0, double t1) {
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (r.t[i] < t0 || r.t[i] >= t1) continue;
    r.foot[0].plan_contact[i] = 0;
    r.foot[0].fz_plan[i] = r.foot[0].fz_meas[i] = 0.0;
    r.foot[1].fz_plan[i] = r.foot[1].fz_meas[i] = kWeight;
  }
  r.touchdowns[0].push_back(t1);
}

void setMeasuredFz(RunSeries& r, int foot, double t0, double t1, double fz) {
  for (std::size_t i = 0; i < r.size(); ++i)
    if (r.t[i] >= t0 && r.t[i] < t1) r.foot[static_cast<std::size_t>(foot)].fz_meas[i] = fz;
}

TEST(Fidelity, LocalCopIsWhereAPointForceWithTheSameWrenchActs) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d p(0.1 * u(rng), 0.07 * u(rng), 0.0);  // on the sole
    const Eigen::Vector3d F(60 * u(rng), 60 * u(rng), 300 + 200 * u(rng));
    const core::Wrench w(F, p.cross(F), Eigen::Vector3d::Zero(), core::Axes::kSole);
    EXPECT_LT((loadedCop(w, 10.0) - p.head<2>()).norm(), 1e-12) << w.forceMoment().transpose();
  }
  const core::Wrench unloaded({0.0, 0.0, 5.0}, {1.0, 1.0, 0.0}, Eigen::Vector3d::Zero(),
                              core::Axes::kSole);
  EXPECT_TRUE(loadedCop(unloaded, 10.0).hasNaN());
}

TEST(Fidelity, AStandingRunAsPlannedMeetsEveryTarget) {
  const RunSeries r = standing(2.0, 3.0);
  const Fidelity f = computeFidelity(r);
  for (const auto& foot : f.foot) {
    EXPECT_EQ(foot.contact_losses, 0);
    EXPECT_TRUE(std::isnan(foot.peak_touchdown_load));  // no touchdown
    EXPECT_EQ(foot.cop_max, 0.0);
    EXPECT_EQ(foot.chatter_rms, 0.0);
    EXPECT_EQ(foot.cop_samples, static_cast<int>(r.size()));
  }
  EXPECT_TRUE(f.settled);
  EXPECT_NEAR(f.settling_time, 0.0, 1e-12);
  EXPECT_NEAR(f.hold_duration, 3.0, 1e-9);
  const nlohmann::json j = fidelityJson(f);
  EXPECT_TRUE(j["meets_targets"].get<bool>()) << j.dump(1);
  EXPECT_TRUE(j["feet"]["right"]["peak_touchdown_load"].is_null());
}

TEST(Fidelity, ABounceAfterTouchdownIsAContactLossAndAShortDipIsNot) {
  RunSeries r = standing(3.0, 1.0);
  swingRight(r, 1.0, 2.0);
  EXPECT_EQ(computeFidelity(r).foot[0].contact_losses, 0);
  // Lands, leaves the ground for 50 ms, lands again.
  setMeasuredFz(r, 0, 2.03, 2.08, 0.0);
  EXPECT_EQ(computeFidelity(r).foot[0].contact_losses, 1);
  // A 5 ms dip (one tick) is below the 10 ms a loss must last.
  RunSeries dip = standing(3.0, 1.0);
  swingRight(dip, 1.0, 2.0);
  setMeasuredFz(dip, 0, 2.03, 2.034, 0.0);
  EXPECT_EQ(computeFidelity(dip).foot[0].contact_losses, 0);
  // Lands 110 ms early (inside the 0.2 s look-back), leaves for 300 ms, lands: a loss.
  RunSeries early = standing(3.0, 1.0);
  swingRight(early, 1.0, 2.0);
  setMeasuredFz(early, 0, 1.89, 2.0, 100.0);
  setMeasuredFz(early, 0, 2.0, 2.3, 0.0);
  EXPECT_EQ(computeFidelity(early).foot[0].contact_losses, 1);
  EXPECT_NEAR(computeFidelity(early).foot[0].touchdown_timing, -0.11, kDt / 2);
  // Late by 90 ms: its timing, no loss.
  RunSeries late = standing(3.0, 1.0);
  swingRight(late, 1.0, 2.0);
  setMeasuredFz(late, 0, 2.0, 2.09, 0.0);
  EXPECT_NEAR(computeFidelity(late).foot[0].touchdown_timing, 0.09, kDt / 2);
  EXPECT_EQ(computeFidelity(late).foot[0].contact_losses, 0);
  EXPECT_NEAR(computeFidelity(dip).foot[0].touchdown_timing, 0.0, kDt / 2);
  // A plan that ramps the landing foot's load in (0 -> 100 % over 0.2 s): the timing is against
  // the plan's own first load above the contact level (5 % of the weight, at 20 ms), so a foot
  // that follows the ramp 15 ms behind it is 15 ms late, not 35.
  RunSeries ramp = standing(3.0, 1.0);
  swingRight(ramp, 1.0, 2.0);
  for (std::size_t i = 0; i < ramp.size(); ++i) {
    const double s = std::clamp((ramp.t[i] - 2.0) / 0.2, 0.0, 1.0);
    const double s_meas = std::clamp((ramp.t[i] - 2.015) / 0.2, 0.0, 1.0);
    if (ramp.t[i] < 2.0) continue;
    ramp.foot[0].fz_plan[i] = 0.5 * kWeight * s;
    ramp.foot[0].fz_meas[i] = 0.5 * kWeight * s_meas;
  }
  EXPECT_NEAR(computeFidelity(ramp).foot[0].touchdown_timing, 0.015, kDt);
  // Never lands while the plan has it down: a loss.
  RunSeries never = standing(3.0, 1.0);
  swingRight(never, 1.0, 2.0);
  setMeasuredFz(never, 0, 2.0, 4.1, 0.0);
  EXPECT_EQ(computeFidelity(never).foot[0].contact_losses, 1);
  const nlohmann::json j = fidelityJson(computeFidelity(never));
  EXPECT_FALSE(j["meets_targets"].get<bool>());
  EXPECT_EQ(j["misses"][0], "right.contact_losses") << j.dump(1);
}

// The plan ramps a lifting foot's load to zero before its lift-off: a foot that leaves the ground
// 40 ms early, where the plan asks less than the contact level (5 % of the weight), lifts off
// early; the same 40 ms off the ground where the plan asks 100 N is a loss.
TEST(Fidelity, AnEarlyLiftOffIsNotAContactLossButTheSameDipUnderPlannedLoadIs) {
  auto ramped = [](double dip_start) {
    RunSeries r = standing(3.0, 1.0);
    swingRight(r, 1.0, 2.0);
    for (std::size_t i = 0; i < r.size(); ++i) {
      const double t = r.t[i];
      if (t < 0.8 || t >= 1.0) continue;
      r.foot[0].fz_plan[i] = r.foot[0].fz_meas[i] = 100.0 * (1.0 - t) / 0.2;  // 100 N -> 0
      r.foot[1].fz_plan[i] = r.foot[1].fz_meas[i] = kWeight - r.foot[0].fz_plan[i];
    }
    setMeasuredFz(r, 0, dip_start, dip_start + 0.04, 0.0);
    return computeFidelity(r).foot[0].contact_losses;
  };
  // The plan's load is below 0.05 x 570 N = 28.5 N from t = 0.943 s on.
  EXPECT_EQ(ramped(0.96), 0);
  EXPECT_EQ(ramped(0.80), 1);
}

TEST(Fidelity, PeakTouchdownLoadIsTheLargestLoadAroundATouchdown) {
  RunSeries r = standing(3.0, 1.0);
  swingRight(r, 1.0, 2.0);
  setMeasuredFz(r, 0, 2.02, 2.04, 1.73 * kWeight);
  // Outside the touchdown's window (0.2 s before to 0.5 s after): not a touchdown load.
  setMeasuredFz(r, 0, 2.7, 2.71, 3.0 * kWeight);
  const Fidelity f = computeFidelity(r);
  EXPECT_NEAR(f.foot[0].peak_touchdown_load, 1.73, 1e-12);
  EXPECT_EQ(f.foot[0].touchdowns, 1);
  const nlohmann::json j = fidelityJson(f);
  EXPECT_FALSE(j["feet"]["right"]["peak_touchdown_load"]["met"].get<bool>());
}

TEST(Fidelity, CopDeviationPercentilesOverTicksWherePlanAndMeasurementLoadTheFoot) {
  RunSeries r = standing(2.0, 0.0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(0.0, 2 * kPi);
  std::vector<double> dev;
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double d = 0.001 * static_cast<double>(i % 50);  // 0 to 49 mm, in any direction
    const double a = angle(rng);
    r.foot[1].cop_meas[i] = r.foot[1].cop_plan[i] + d * Eigen::Vector2d(std::cos(a), std::sin(a));
    dev.push_back(d);
  }
  // An unloaded measurement is left out, however far its CoP.
  r.foot[1].fz_meas[3] = 0.05 * kWeight;
  r.foot[1].cop_meas[3] << 1.0, 1.0;
  dev.erase(dev.begin() + 3);
  std::sort(dev.begin(), dev.end());
  auto pct = [&](double p) {
    const double u = p * static_cast<double>(dev.size() - 1);
    const auto k = static_cast<std::size_t>(u);
    return dev[k] + (u - static_cast<double>(k)) * (dev[std::min(k + 1, dev.size() - 1)] - dev[k]);
  };
  const Fidelity f = computeFidelity(r);
  EXPECT_EQ(f.foot[1].cop_samples, static_cast<int>(dev.size()));
  EXPECT_NEAR(f.foot[1].cop_p50, pct(0.5), 1e-12);
  EXPECT_NEAR(f.foot[1].cop_p95, pct(0.95), 1e-12);
  EXPECT_NEAR(f.foot[1].cop_max, 0.049, 1e-12);
  EXPECT_EQ(f.foot[0].cop_max, 0.0);
}

TEST(Fidelity, HighPassHasTheButterworthResponseTwice) {
  // Forward and backward: the squared magnitude of the bilinear-transformed Butterworth filter,
  // 1 / (1 + (tan(w_c / 2) / tan(w / 2))^4), at zero phase.
  const double fc = 20.0;
  for (double f : {5.0, 15.0, 20.0, 30.0, 60.0}) {
    std::vector<double> x(4000);
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] = std::sin(2 * kPi * f * static_cast<double>(i) * kDt + 0.3);
    const std::vector<double> y = highPass(x, kDt, fc);
    double sx = 0, sy = 0, sxy = 0;
    for (std::size_t i = 1000; i < 3000; ++i) {  // away from the ends
      sx += x[i] * x[i];
      sy += y[i] * y[i];
      sxy += x[i] * y[i];
    }
    const double r = std::pow(std::tan(kPi * fc * kDt) / std::tan(kPi * f * kDt), 4);
    EXPECT_NEAR(std::sqrt(sy / sx), 1.0 / (1.0 + r), 2e-3) << f << " Hz";
    EXPECT_NEAR(sxy / std::sqrt(sx * sy), 1.0, 1e-3) << f << " Hz: not zero phase";
  }
}

TEST(Fidelity, ChatterIsTheStanceMomentAboveTheCutoffInSingleSupport) {
  RunSeries r = standing(3.0, 1.0);
  swingRight(r, 1.0, 2.0);
  const double amplitude = 5.0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double t = r.t[i];
    // 30 Hz on the stance (left) foot's Mx in its single support; 2 Hz sway on its My; 30 Hz on
    // both feet in the double supports (not single support: not counted).
    r.foot[1].moment_meas[i] << amplitude * std::sin(2 * kPi * 30 * t),
        8.0 * std::sin(2 * kPi * 2 * t);
    r.foot[0].moment_meas[i] << amplitude * std::sin(2 * kPi * 30 * t), 0.0;
    if (t >= 1.0 && t < 2.0) r.foot[0].moment_meas[i].setZero();
  }
  const Fidelity f = computeFidelity(r);
  // The 30 Hz RMS is amplitude / sqrt(2), times the filter's 30 Hz gain; 2 Hz adds next to
  // nothing.
  const double r30 = std::pow(std::tan(kPi * 20 * kDt) / std::tan(kPi * 30 * kDt), 4);
  EXPECT_NEAR(f.foot[1].chatter_rms, amplitude / std::sqrt(2.0) / (1 + r30), 0.05);
  EXPECT_EQ(f.foot[0].chatter_rms, 0.0);  // the right foot has no single support as stance
  RunSeries slow = standing(3.0, 1.0);
  swingRight(slow, 1.0, 2.0);
  for (std::size_t i = 0; i < slow.size(); ++i)
    slow.foot[1].moment_meas[i] << 0.0, 8.0 * std::sin(2 * kPi * 2 * slow.t[i]);
  EXPECT_LT(computeFidelity(slow).foot[1].chatter_rms, 0.05);
}

TEST(Fidelity, SettlingTimeIsWhenTheBaseStaysBelowOneCentimetrePerSecond) {
  RunSeries r = standing(2.0, 3.0);
  for (std::size_t i = 0; i < r.size(); ++i)
    r.base_speed[i] = r.t[i] < 2.4 ? 0.05 : 0.009 * std::exp(-(r.t[i] - 2.4));
  Fidelity f = computeFidelity(r);
  EXPECT_TRUE(f.settled);
  EXPECT_NEAR(f.settling_time, 0.4, kDt / 2);
  // Moving again at the end: not settled.
  r.base_speed.back() = 0.02;
  f = computeFidelity(r);
  EXPECT_FALSE(f.settled);
  EXPECT_TRUE(std::isnan(f.settling_time));
  EXPECT_FALSE(fidelityJson(f)["settling_time"]["met"].get<bool>());
  // Without a base speed measurement (hardware without an estimate): not measured.
  for (double& v : r.base_speed) v = std::nan("");
  EXPECT_FALSE(computeFidelity(r).settled);
}

TEST(Fidelity, PelvisDeviationIsTheLargestRollOrPitchDifference) {
  RunSeries r = standing(2.0, 1.0);
  r.tilt_meas[100] << 0.004, -0.012;
  r.tilt_plan[200] << 0.02, 0.0;
  EXPECT_NEAR(computeFidelity(r).pelvis_deviation_max, 0.02, 1e-15);
}

}  // namespace
}  // namespace overstep::monitor
