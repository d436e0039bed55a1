// `overstep identify`'s core on data with undeclared effects: the simulator runs the excitation
// plan with a truth the identification never sees (seeded noise on every sensor); the verdict must
// name the effect (or a documented confusable pair containing it), the true value must lie in the
// reported interval or within 15 %, and the held-out error must drop by at least 70 %. Clean runs
// give "none".
#include <gtest/gtest.h>

#include <cmath>

#include "overstep/sysid/identify.hpp"
#include "sysid_runs.hpp"
#include "test_util.hpp"

namespace overstep {
namespace {

class Identify : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    model_ = new robots::WholeBodyModel(robots::WholeBodyModel::fromFile(test::hrp2Yaml()));
    params_ = new stabilizer::Params(stabilizer::loadParams(test::hrp2Yaml()));
    params_->mass = model_->totalMass();
    plan_ = new core::Plan(planner::excitationPlan(*model_, 8.0));
  }
  static void TearDownTestSuite() {
    delete plan_;
    delete params_;
    delete model_;
  }
  static sysid::Identification run(const sim::TruthEffects& truth, unsigned seed) {
    const sysid::Dataset data = test::recordExcitation(*model_, *plan_, *params_, truth, seed);
    EXPECT_GT(data.size(), 1400);  // the whole 8 s plan executed
    sysid::IdentifyOptions o;
    if (const char* dump = std::getenv("OVERSTEP_SYSID_DUMP")) o.dump_residuals = dump;
    if (std::getenv("OVERSTEP_SYSID_ALL")) o.use_torque = o.use_force = true;
    return sysid::identify(data, *plan_, *model_, o);
  }
  /// Per actuated joint: `value` on both arms, 0 elsewhere.
  static Eigen::VectorXd onArms(double value) {
    const auto& d = model_->description();
    Eigen::VectorXd v = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(d.actuated.size()));
    for (std::size_t j = 0; j < d.actuated.size(); ++j)
      if (d.actuated[j].name.rfind("RARM", 0) == 0 || d.actuated[j].name.rfind("LARM", 0) == 0)
        v(static_cast<Eigen::Index>(j)) = value;
    return v;
  }
  static std::string describe(const sysid::Identification& r) {
    std::string s = r.verdict + " " + r.effect + " (before " + std::to_string(r.error_before) +
                    ", after " + std::to_string(r.error_after) + "; above the noise " +
                    std::to_string(r.excess_before) + " -> " + std::to_string(r.excess_after) +
                    "); channels:";
    for (const auto& [n, c] : r.channels)
      s += " " + n + " " + std::to_string(c.rms_before) + "->" + std::to_string(c.rms_after) + "/" +
           std::to_string(c.noise) + " " + c.unit + ";";
    s += " candidates:";
    for (const auto& c : r.candidates)
      s += " " + c.name + " " + std::to_string(c.reduction) + (c.plausible ? "" : "?") + " F " +
           std::to_string(c.f_statistic) + " D " + std::to_string(c.distinction) + ";";
    return s;
  }
  /// The verdict names `effect`, alone or in a confusable pair.
  static bool names(const sysid::Identification& r, const std::string& effect) {
    if (r.verdict == "identified") return r.effect == effect;
    if (r.verdict != "ambiguous") return false;
    return std::find(r.confusable.begin(), r.confusable.end(), effect) != r.confusable.end();
  }
  /// The named candidate's fitted parameter (from the candidate list: with an ambiguous verdict
  /// the true effect need not be the first) is the truth within its 95 % interval or 15 %.
  static void expectValue(const sysid::Identification& r, const std::string& candidate,
                          const std::string& param, double truth) {
    const sysid::CandidateFit* fit = nullptr;
    for (const auto& c : r.candidates)
      if (c.name == candidate) fit = &c;
    ASSERT_NE(fit, nullptr) << candidate;
    std::size_t i = 0;
    while (i < fit->parameter_names.size() && fit->parameter_names[i] != param) ++i;
    ASSERT_LT(i, fit->parameter_names.size()) << param;
    const double v = fit->parameters[i], ci = fit->ci95[i];
    EXPECT_TRUE(std::abs(v - truth) <= ci || std::abs(v - truth) <= 0.15 * std::abs(truth))
        << param << " = " << v << " +- " << ci << ", truth " << truth;
  }
  static robots::WholeBodyModel* model_;
  static stabilizer::Params* params_;
  static core::Plan* plan_;
};
robots::WholeBodyModel* Identify::model_ = nullptr;
stabilizer::Params* Identify::params_ = nullptr;
core::Plan* Identify::plan_ = nullptr;

// The false-positive rate: clean runs over 20 seeds give "none" in at least 95 % of them.
TEST_F(Identify, CleanRunsFindNothing) {
  int none = 0;
  const int runs = 20;
  for (unsigned seed = 1; seed <= static_cast<unsigned>(runs); ++seed) {
    const auto r = run(sim::noTruthEffects(*model_), seed);
    none += r.verdict == "none";
    if (r.verdict != "none") std::printf("seed %u: %s\n", seed, describe(r).c_str());
  }
  std::printf("clean runs: %d of %d none\n", none, runs);
  EXPECT_GE(none, 19);
}

TEST_F(Identify, CommandDelayAndLagAreTheDocumentedPair) {
  for (double d : {0.01, 0.02}) {
    for (bool lag : {false, true}) {
      sim::TruthEffects t = sim::noTruthEffects(*model_);
      (lag ? t.command_lag : t.command_delay) = d;
      const auto r = run(t, 7);
      const std::string effect = lag ? "command_lag" : "command_delay";
      EXPECT_TRUE(names(r, effect)) << d << " s: " << describe(r);
      if (!names(r, effect)) continue;
      expectValue(r, effect, lag ? "lag" : "delay", d);
      EXPECT_LT(r.error_after, 0.3 * r.error_before) << describe(r);
    }
  }
}

TEST_F(Identify, BacklashIsIdentified) {
  for (double width : {0.03, 0.06}) {
    sim::TruthEffects t = sim::noTruthEffects(*model_);
    t.backlash = onArms(width);
    const auto r = run(t, 19);
    std::printf("backlash %g: %s\n", width, describe(r).c_str());
    EXPECT_TRUE(names(r, "backlash")) << width << ": " << describe(r);
    if (!names(r, "backlash")) continue;
    expectValue(r, "backlash", "width", width);
    // The joint positions come back near their noise and the motor torques to the clean run's
    // level; the effect is small against the noise (raw RMS 2.9 and 4.5 noise units), so the
    // drop is asserted on the error above the noise (docs/identification.md: raw 57-66 %).
    const auto& pos = r.channels.at("joint_position");
    EXPECT_LT(pos.rms_after, 2.0 * pos.noise) << describe(r);
    EXPECT_LT(r.excess_after, 0.3 * r.excess_before) << describe(r);
  }
}

// An effect outside the library (bent links: the upper arms' elbow joints sit rotated on their
// parents, a kinematic error) must not come back as a clean fit of another effect.
TEST_F(Identify, AnEffectOutsideTheLibraryIsNotFittedAsAnother) {
  sim::TruthEffects t = sim::noTruthEffects(*model_);
  for (const char* link : {"RARM_LINK3", "LARM_LINK3"}) {
    sim::Bend b;
    b.link = link;
    b.rotation = Eigen::Vector3d(0.0, 0.15, 0.0);
    t.bends.push_back(b);
  }
  const auto r = run(t, 19);
  std::printf("bent links: %s\n", describe(r).c_str());
  EXPECT_TRUE(r.verdict == "unexplained" || r.verdict == "none") << describe(r);
}

// The payload's weight shows in the ground channels (force and moment) and in the chest's
// gravity torque.
TEST_F(Identify, PayloadOnTheChestIsIdentified) {
  for (double m : {2.0, 4.0}) {
    sim::TruthEffects t = sim::noTruthEffects(*model_);
    sim::Payload p;
    p.link = "CHEST_LINK1";
    p.mass = m;
    p.offset = Eigen::Vector3d(0.05, 0.0, 0.10);
    t.payloads.push_back(p);
    const auto r = run(t, 11);
    std::printf("payload %g kg: %s\n", m, describe(r).c_str());
    EXPECT_TRUE(names(r, "payload")) << m << " kg: " << describe(r);
    if (!names(r, "payload")) continue;
    expectValue(r, "payload", "mass", m);
    EXPECT_LT(r.error_after, 0.3 * r.error_before) << describe(r);
  }
}

TEST_F(Identify, ArmFrictionIsIdentified) {
  for (double fv : {3.0, 6.0}) {
    sim::TruthEffects t = sim::noTruthEffects(*model_);
    t.viscous = onArms(fv);
    const auto r = run(t, 13);
    std::printf("friction %g: %s\n", fv, describe(r).c_str());
    EXPECT_TRUE(names(r, "joint_viscous_friction")) << fv << ": " << describe(r);
    if (!names(r, "joint_viscous_friction")) continue;
    expectValue(r, "joint_viscous_friction", "viscous[RARM_JOINT0]", fv);
    EXPECT_LT(r.error_after, 0.3 * r.error_before) << describe(r);
  }
}

TEST_F(Identify, ArmCoulombFrictionIsIdentified) {
  for (double fc : {2.0, 4.0}) {
    sim::TruthEffects t = sim::noTruthEffects(*model_);
    t.coulomb = onArms(fc);
    const auto r = run(t, 31);
    std::printf("coulomb %g: %s\n", fc, describe(r).c_str());
    EXPECT_TRUE(names(r, "joint_coulomb_friction")) << fc << ": " << describe(r);
    if (!names(r, "joint_coulomb_friction")) continue;
    expectValue(r, "joint_coulomb_friction", "coulomb[RARM_JOINT0]", fc);
    EXPECT_LT(r.error_after, 0.3 * r.error_before) << describe(r);
  }
}

TEST_F(Identify, ForceSensorBiasIsNamed) {
  for (double b : {10.0, 20.0}) {
    sim::TruthEffects t = sim::noTruthEffects(*model_);
    t.ft[1].bias.force.z() = b;  // left sensor
    const auto r = run(t, 17);
    std::printf("left Fz bias %g N: %s\n", b, describe(r).c_str());
    // In double support the normal-force biases of the two sensors are confusable (and a scale
    // error at nearly constant load): the verdict must include the left bias.
    EXPECT_TRUE(names(r, "ft_bias_left")) << b << " N: " << describe(r);
    expectValue(r, "ft_bias_left", "fz_bias", b);
    EXPECT_LT(r.error_after, 0.3 * r.error_before) << describe(r);
  }
}

// Softer or stiffer ankle bushings tilt the torso more or less under the moments the ankle
// sensors measure.
TEST_F(Identify, AnkleStiffnessIsIdentified) {
  for (double factor : {0.7, 1.4}) {
    sim::TruthEffects t = sim::noTruthEffects(*model_);
    for (auto& k : t.elastic_stiffness) k *= factor;
    t.elastic_changed = true;
    const auto r = run(t, 29);
    std::printf("ankle stiffness x%g: %s\n", factor, describe(r).c_str());
    EXPECT_TRUE(names(r, "ankle_bushing")) << factor << ": " << describe(r);
    if (!names(r, "ankle_bushing")) continue;
    const auto& d = model_->description();
    // Compliance change of the roll (index 0) and pitch (index 1) bushings.
    expectValue(r, "ankle_bushing", "compliance_roll",
                1.0 / (factor * d.elastic[0].stiffness) - 1.0 / d.elastic[0].stiffness);
    expectValue(r, "ankle_bushing", "compliance_pitch",
                1.0 / (factor * d.elastic[1].stiffness) - 1.0 / d.elastic[1].stiffness);
    EXPECT_LT(r.error_after, 0.3 * r.error_before) << describe(r);
  }
}

// Weaker bushing dampers let the torso tilt lag the ankle moments less.
TEST_F(Identify, AnkleDampingIsIdentified) {
  for (double factor : {0.5, 0.25}) {
    sim::TruthEffects t = sim::noTruthEffects(*model_);
    for (auto& c : t.elastic_damping) c *= factor;
    t.elastic_changed = true;
    const auto r = run(t, 37);
    std::printf("ankle damping x%g: %s\n", factor, describe(r).c_str());
    EXPECT_TRUE(names(r, "ankle_bushing")) << factor << ": " << describe(r);
    if (!names(r, "ankle_bushing")) continue;
    const auto& d = model_->description();
    expectValue(r, "ankle_bushing", "damping_roll", (factor - 1.0) * d.elastic[0].damping);
    expectValue(r, "ankle_bushing", "damping_pitch", (factor - 1.0) * d.elastic[1].damping);
    EXPECT_LT(r.error_after, 0.3 * r.error_before) << describe(r);
  }
}

TEST_F(Identify, ForceSensorScaleIsNamed) {
  for (double sc : {1.03, 1.06}) {
    sim::TruthEffects t = sim::noTruthEffects(*model_);
    t.ft[0].scale = sc;  // right sensor
    const auto r = run(t, 23);
    std::printf("right scale %g: %s\n", sc, describe(r).c_str());
    EXPECT_TRUE(names(r, "ft_scale_right")) << sc << ": " << describe(r);
    if (!names(r, "ft_scale_right")) continue;
    expectValue(r, "ft_scale_right", "scale_minus_1", sc - 1.0);
    EXPECT_LT(r.error_after, 0.3 * r.error_before) << describe(r);
  }
}

}  // namespace
}  // namespace overstep
