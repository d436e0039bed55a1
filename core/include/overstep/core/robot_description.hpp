#pragma once
/// \file
/// Robot parameters that live beside the URDF in robots/<robot>/<robot>.yaml: joint tables with
/// limits and actuator data, the passive elastic joints, feet, named frames, collision capsules and
/// the reference posture. Eigen + yaml-cpp only (no DART): the stabilizer and runtime read it too.
/// Units: SI (m, kg, s, rad, N, N m).

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "overstep/core/wrench.hpp"

namespace overstep::core {

/// One actuated (position-servoed) joint. Angles in rad.
struct ActuatedJoint {
  std::string name;
  double lower = 0.0;          ///< mechanical lower limit, rad
  double upper = 0.0;          ///< mechanical upper limit, rad
  double safety_margin = 0.0;  ///< planner keeps this far inside [lower, upper], rad
  double velocity = 0.0;       ///< |qdot| limit, rad/s
  double torque = 0.0;         ///< |tau| limit, N m
  double gear_ratio = 1.0;     ///< reduction ratio N (motor turns per joint turn)
  double rotor_inertia = 0.0;  ///< motor-side rotor inertia I_m, kg m^2

  double safeLower() const { return lower + safety_margin; }
  double safeUpper() const { return upper - safety_margin; }
  /// Reflected rotor inertia N^2 I_m (seed eq. 4), kg m^2.
  double reflectedInertia() const { return gear_ratio * gear_ratio * rotor_inertia; }
};

/// A passive joint driven by a linear spring/damper about rest position 0.
struct ElasticJoint {
  std::string name;
  double stiffness = 0.0;  ///< N m/rad
  double damping = 0.0;    ///< N m s/rad
};

/// Sole rectangle in the sole frame, m. "outer" is away from the robot's sagittal plane.
struct SoleRectangle {
  double x_front = 0.0;
  double x_back = 0.0;
  double y_outer = 0.0;
  double y_inner = 0.0;
};

/// A foot: its body, frames and sole.
struct FootDescription {
  std::string side;                ///< "right" or "left"
  std::string link;                ///< foot body below the elastic joint
  std::string sole_frame;          ///< frame at the ankle projection on the sole plane
  std::string force_sensor_frame;  ///< 6-axis F/T sensor frame
  SoleRectangle sole;
  /// +1 for the left foot, -1 for the right foot (sign of the outer side in y).
  double sideSign() const { return side == "left" ? 1.0 : -1.0; }
  /// Sole bounds in the sole frame: y_min, y_max accounting for the side.
  double yMin() const { return side == "left" ? -sole.y_inner : -sole.y_outer; }
  double yMax() const { return side == "left" ? sole.y_outer : sole.y_inner; }
  /// Centre of the sole rectangle in the sole frame (x, y).
  Eigen::Vector2d centre() const {
    return {0.5 * (sole.x_front - sole.x_back), 0.5 * (yMin() + yMax())};
  }
};

/// A named frame rigidly attached to a link.
struct FrameDescription {
  std::string name;
  std::string link;
  Eigen::Isometry3d X_LF = Eigen::Isometry3d::Identity();  ///< frame pose in the link frame
};

/// A collision capsule: segment p0-p1 in the link frame with a radius.
struct CapsuleDescription {
  std::string link;
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d p1 = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

/// A named group of actuated joints (legs, arms, ...): how truth files and other inputs address
/// joints by kind, without naming a robot's joints in code.
struct JointGroup {
  std::string name;
  std::vector<int> joints;  ///< actuated indices, in the file's order
};

/// One joint the identification excitation swings: q = q_half_sitting + a sin(2 pi f t + phase)
/// under a fade-in/out envelope (amplitude scaled by the command's --amplitude).
struct ExcitationJoint {
  std::string joint;
  double amplitude = 0.0;  ///< rad
  double frequency = 0.0;  ///< Hz
  double phase = 0.0;      ///< rad
};

/// A point mass rigidly attached to a link (offset in the link frame), e.g. a payload.
struct PayloadDescription {
  std::string link;
  double mass = 0.0;  ///< kg
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
};

/// Effects a model overlay adds to the base description (docs/model-overlay.md): what
/// `overstep identify` found. The same keys as the simulator's truth file.
struct ModelEffects {
  std::vector<PayloadDescription> payloads;  ///< merged into their links' inertia by robots/
  Eigen::VectorXd viscous, coulomb;  ///< per actuated joint, N m s/rad and N m (size 0: none)
  Eigen::VectorXd backlash;          ///< per actuated joint, dead band width in rad (size 0: none)
  double command_delay = 0.0;        ///< s, from a command to its effect at the joints
  double command_lag = 0.0;          ///< s, first-order lag of the joint servos
  std::array<ForceSensorModel, 2> ft;  ///< force sensors (right, left)
  bool empty() const {
    return payloads.empty() && (viscous.size() == 0 || viscous.isZero()) &&
           (coulomb.size() == 0 || coulomb.isZero()) &&
           (backlash.size() == 0 || backlash.isZero()) && command_delay == 0.0 &&
           command_lag == 0.0 && ft[0].isIdentity() && ft[1].isIdentity();
  }
  /// The true force-sensor wrench from a measured one (foot 0 right, 1 left).
  Wrench calibrated(int foot, const Wrench& m) const {
    return ft[static_cast<std::size_t>(foot)].calibrated(m);
  }
};

/// Everything robots/<robot>/<robot>.yaml says. Loaded and validated by loadRobotDescription().
struct RobotDescription {
  std::string name;
  std::string yaml_path;  ///< file this was loaded from
  std::string urdf_path;  ///< absolute or relative to the working directory
  std::string base_link;
  bool floating_base = true;
  double gravity = 9.81;  ///< m/s^2, along -z
  std::vector<ActuatedJoint> actuated;
  std::vector<ElasticJoint> elastic;
  /// The elastic bushings' vertical give (along the sole normal), per foot: N/m and N s/m, 0 for a
  /// rigid foot. The planner's model leaves it out (as the seed does); the simulator has it and
  /// the runtime's plan track makes up for the planned loads' compression (docs/runtime.md).
  double bushing_vertical_stiffness = 0.0;
  double bushing_vertical_damping = 0.0;
  std::vector<FootDescription> feet;  ///< right first, then left (may be empty)
  std::vector<FrameDescription> frames;
  std::vector<CapsuleDescription> capsules;
  /// Link pairs whose capsules the planner keeps apart, besides the right leg's against the left
  /// leg's (which it takes from the kinematic tree). Every link carries a capsule.
  std::vector<std::pair<std::string, std::string>> self_collision;
  std::vector<JointGroup> joint_groups;
  std::vector<ExcitationJoint> excitation;  ///< the identification excitation's joints
  Eigen::VectorXd half_sitting;             ///< actuated joint angles, rad (size = actuated.size())
  double acceleration_limit = 30.0;         ///< rad/s^2, for planners
  /// FNV-1a of the URDF and of the YAML without its `stabilizer:`, `joint_groups:`,
  /// `excitation:` and `bushing_vertical:` sections (what shapes a plan: the runtime's gains, the
  /// identification's inputs and what the planner's model leaves out do not, so a plan stays
  /// valid while they are tuned).
  std::uint64_t content_hash = 0;
  /// Overlays (a YAML with `base: FILE`): the base description's file, and the effects added.
  std::string base_yaml;
  /// The robot file at the bottom of an overlay chain (yaml_path for a robot file): its
  /// sections that overlays cannot change (the stabilizer's gains) are read from there.
  std::string robot_yaml;
  ModelEffects effects;

  int actuatedIndex(const std::string& joint) const;             ///< -1 if absent
  int elasticIndex(const std::string& joint) const;              ///< -1 if absent
  const FootDescription* foot(const std::string& side) const;    ///< nullptr if absent
  const JointGroup* group(const std::string& group_name) const;  ///< nullptr if absent
  /// Hex string of content_hash (16 digits).
  std::string hashHex() const;
};

/// Loads and validates a robot YAML, or a model overlay (a YAML whose `base:` names the robot
/// YAML it modifies; docs/model-overlay.md): the base is loaded, then the overlay's elastic
/// joint parameters replace the base's and its effects are recorded; the hash covers both files.
/// Throws InputError with a one-line message naming the file and
/// the offending key on a missing file, malformed YAML, a key given twice, a missing key (`feet`
/// is required for a floating base) or an invalid value (negative stiffness, inverted or
/// non-finite limits, half-sitting outside the limits, acceleration limit <= 0, gravity outside
/// (0, 100] m/s^2, ...).
RobotDescription loadRobotDescription(const std::string& yaml_path);

/// 64-bit FNV-1a hash of a byte string (stable across platforms), for content fingerprints.
std::uint64_t fnv1a64(const std::string& bytes, std::uint64_t seed = 14695981039346656037ULL);

/// `yaml` without the top-level section `key:` (its line and the indented, blank and comment
/// lines under it), byte for byte otherwise.
std::string withoutSection(const std::string& yaml, const std::string& key);

/// Reads a whole file; throws InputError naming the path when it cannot be read.
std::string readFile(const std::string& path);

}  // namespace overstep::core
