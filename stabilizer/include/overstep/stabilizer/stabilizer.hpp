#pragma once
/// \file
/// HRP-2-style balance stabilizer as a pure per-tick library: no clock, no I/O, no threads, no heap
/// allocation and no exceptions in step(). The runtime feeds one reference sample and one
/// measurement per control period and turns the corrections into joint references (IK).
///
/// Blocks (Kajita et al. IROS 2010; Caron et al. ICRA 2019):
///  1. CoM feedback -> desired ZMP: LIPM state feedback with the ZMP-lag model, or DCM P + leaky I.
///  2. ZMP distributor -> desired foot wrenches (normal-force share and one CoP per foot).
///  3. Foot damping control: each sole rotates so that its measured moment follows the desired one
///     (on HRP-2 this works through the elastic ankle bushings).
///  4. Foot force difference control (double support): relative foot height.
///     Landing control (each foot around its planned touchdown): its height follows its normal
///     force error, so a foot that touches early yields and one that is late is lowered.
///  5. Body posture control from the IMU (torso roll and pitch).
///  6. Optional CoM admittance: CoM offset from the ZMP tracking error.
/// Conventions: index 0 = right foot, 1 = left foot. Foot wrenches (core::Wrench) are in the sole's
/// axes about its origin. Foot rotation corrections are roll (about the
/// sole x axis) and pitch (about y) applied to the sole's reference orientation: +pitch lowers the
/// toes and moves the CoP forward, +roll lowers the right edge (-y) and moves the CoP to -y.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "overstep/core/wrench.hpp"
#include "overstep/stabilizer/distributor.hpp"
#include "overstep/stabilizer/params.hpp"

namespace overstep::stabilizer {

enum class Mode : std::uint8_t { Off = 0, RampIn = 1, On = 2, RampOut = 3, Hold = 4 };
enum class Fault : std::uint8_t {
  None = 0,
  NonFiniteReference = 1,
  NonFiniteMeasurement = 2,
  BadTimeStep = 3,
  ComErrorTooLarge = 4,
  TorsoTiltTooLarge = 5,
  NoSupport = 6,  ///< the reference has no foot in contact
};
const char* toString(Mode m);
const char* toString(Fault f);

/// Saturation flags (bitmask in Status::saturation).
enum Saturation : std::uint32_t {
  kZmpClamped = 1u << 0,        ///< desired ZMP outside the support polygon
  kFootRotation = 1u << 1,      ///< a foot rotation hit max_foot_rotation
  kFootRotationRate = 1u << 2,  ///< a foot rotation rate hit max_foot_rotation_rate
  kFootHeight = 1u << 3,        ///< the height offset hit max_foot_height
  kBodyAttitude = 1u << 4,      ///< the posture correction hit max_body_attitude
  kComOffset = 1u << 5,         ///< the CoM offset hit max_com_offset
  kNoMeasuredZmp = 1u << 6,     ///< measured normal force too small: ZMP feedback skipped
};

struct FootReference {
  bool contact = true;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();       ///< sole frame in the world
  core::Wrench wrench = core::Wrench::zero(core::Axes::kSole);  ///< planned, about the sole origin
};

/// One sample of the plan (world frame, ground plane z = ground_z).
struct Reference {
  Eigen::Vector3d com = Eigen::Vector3d(0, 0, 0.8);
  Eigen::Vector3d com_vel = Eigen::Vector3d::Zero();
  Eigen::Vector3d com_acc = Eigen::Vector3d::Zero();
  Eigen::Vector2d zmp = Eigen::Vector2d::Zero();      ///< table-cart ZMP
  Eigen::Vector2d zmp_vel = Eigen::Vector2d::Zero();  ///< its rate (feed-forward through the lag)
  /// The plan's whole-body ZMP (from its contact wrenches) and its rate; used instead of the two
  /// above with Params::zmp_reference = WholeBody.
  Eigen::Vector2d zmp_wholebody = Eigen::Vector2d::Zero();
  Eigen::Vector2d zmp_wholebody_vel = Eigen::Vector2d::Zero();
  double ground_z = 0.0;
  std::array<FootReference, 2> foot{};
  Eigen::Quaterniond torso = Eigen::Quaterniond::Identity();
};

struct Measurement {
  Eigen::Vector3d com = Eigen::Vector3d(0, 0, 0.8);  ///< estimated (encoders + IMU)
  Eigen::Vector3d com_vel = Eigen::Vector3d::Zero();
  /// Contact wrenches, sole axes about the sole origin.
  std::array<core::Wrench, 2> foot_wrench{
      {core::Wrench::zero(core::Axes::kSole), core::Wrench::zero(core::Axes::kSole)}};
  std::array<Eigen::Isometry3d, 2> foot_pose{
      {Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity()}};  ///< measured soles
  Eigen::Quaterniond torso = Eigen::Quaterniond::Identity();            ///< IMU orientation (world)
};

/// Corrections for the runtime (already scaled by the ramp) and telemetry.
struct Output {
  Eigen::Vector3d com_offset = Eigen::Vector3d::Zero();  ///< m, world
  std::array<Eigen::Vector2d, 2> foot_rotation{{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()}};
  std::array<double, 2> foot_height{{0.0, 0.0}};            ///< m, along world z (both terms below)
  std::array<double, 2> landing_height{{0.0, 0.0}};         ///< m, the landing control's part of it
  Eigen::Vector2d body_attitude = Eigen::Vector2d::Zero();  ///< rad, torso roll, pitch

  // telemetry
  double ramp = 0.0;                                        ///< 0..1, feedback scale in use
  Eigen::Vector2d zmp_reference = Eigen::Vector2d::Zero();  ///< the plan's ZMP in use (world)
  Eigen::Vector2d zmp_desired = Eigen::Vector2d::Zero();    ///< after clamping (world)
  Eigen::Vector2d zmp_measured = Eigen::Vector2d::Zero();   ///< from the foot wrenches
  Eigen::Vector2d com_error = Eigen::Vector2d::Zero();      ///< measured - reference
  Eigen::Vector2d com_vel_error = Eigen::Vector2d::Zero();
  Eigen::Vector2d dcm_error = Eigen::Vector2d::Zero();
  Eigen::Vector2d zmp_error = Eigen::Vector2d::Zero();  ///< measured - reference
  std::array<double, 3> gains{{0, 0, 0}};  ///< LIPM k1, k2, k3 or DCM (1 + kp/w), ki/w, 0
  Distribution distribution{};
};

struct Status {
  Mode mode = Mode::Off;
  Fault fault = Fault::None;
  std::uint32_t saturation = 0;
  bool ok() const { return fault == Fault::None; }
};

class Stabilizer {
 public:
  /// Starts Off. Throws InputError if validate(params) fails (configuration time, not per tick).
  explicit Stabilizer(const Params& params);

  /// Replaces the parameters (Off or Hold only; returns false otherwise or if invalid).
  bool configure(const Params& params);
  /// Back to Off with all internal states zero and the fault cleared.
  void reset();
  /// Off -> RampIn -> On. From Hold (no fault) resumes On. Returns false when refused (fault).
  bool enable();
  /// On/RampIn/Hold -> RampOut -> Off, continuously from the current output.
  void disable();
  /// Freezes the outputs and the internal states (continuous). A fault does this by itself.
  void hold();

  void setReference(const Reference& ref) { ref_ = ref; }
  /// One control period. Never throws, never allocates.
  Status step(const Measurement& meas, double dt, Output& out);

  const Params& params() const { return params_; }
  Status status() const { return status_; }

 private:
  void enterHold(Fault f);
  Fault validateInputs(const Measurement& meas, double dt) const;
  void runFeedback(const Measurement& meas, double dt, Output& raw);
  /// The landing control's offsets (raw.landing_height) from the feet's normal forces fz.
  void landing(const std::array<double, 2>& fz, double dt, Output& raw);

  Params params_;
  Reference ref_{};
  Status status_{};
  double ramp_ = 0.0;  ///< linear ramp parameter 0..1
  Output raw_{};       ///< unscaled controller state/outputs (integrators live here)
  Output held_{};      ///< frozen output in Hold
  Output last_{};      ///< last published output
  Eigen::Vector2d dcm_integral_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d com_offset_vel_ = Eigen::Vector2d::Zero();
  bool from_hold_ = false;  ///< ramping out from a frozen output
  /// Per foot: the reference has had the foot in the air (so its contact is a touchdown), and the
  /// time since the reference's last touchdown.
  std::array<bool, 2> swung_{{false, false}};
  std::array<bool, 2> found_{{false, false}};  ///< the ground met since the touchdown
  std::array<double, 2> since_touchdown_{{0.0, 0.0}};
};

}  // namespace overstep::stabilizer
