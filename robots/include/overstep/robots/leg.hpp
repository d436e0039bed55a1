#pragma once
/// \file
/// The legs of a biped, read from its kinematic tree, and their closed-form inverse kinematics.
///
/// A leg is the chain of joints from the base to a foot body (robots/<robot>.yaml `feet:`): its
/// six actuated joints (hip, knee, ankle) and the passive elastic joints below them (the ankle
/// bushing). Joint names, link names and geometry all come from the robot description and the
/// URDF; nothing here names a joint of a particular robot.
///
/// The closed form needs the structure of HRP-2-class legs, checked when a LegIk is built: at the
/// zero posture the six joint axes are (up to sign) z, x, y, y, y, x of the base frame, the hip's
/// three axes meet in one point H and the two ankle axes meet in one point A. The three pitch
/// joints then form a planar two-link chain (thigh H -> knee, shank knee -> A, with any constant
/// lateral offset), and the solution is exact: the ankle roll from the lateral offset, the knee
/// from the hip-ankle distance, the ankle pitch from the planar chain, the hip's yaw, roll and
/// pitch from the remaining rotation. Of the two knee branches the one on the side of the
/// half-sitting knee is returned; of the two ankle-roll branches, the one inside the joint
/// limits and nearer a reference posture (half-sitting unless given). They coincide for the
/// postures of walking and stepping; with the knee folded beyond ~110 deg both can be inside the
/// limits, and the reference (e.g. the previous solution) decides.

#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "overstep/robots/whole_body_model.hpp"

namespace overstep::robots {

using Vector6d = core::Vector6d;

/// One leg of the robot, from the kinematic tree.
struct LegChain {
  std::string side;                ///< "right" or "left" (the foot's side)
  std::array<int, 6> actuated{};   ///< actuated joint indices (description order), hip to ankle
  std::vector<int> elastic;        ///< elastic joint indices between the ankle and the foot
  std::vector<std::string> links;  ///< bodies from the first hip link down to the foot body
  std::string ankle_link;          ///< child body of the sixth actuated joint (above the bushing)
  std::string foot_link;           ///< the foot body (below the bushing)
  int ankle_frame = -1;            ///< model frame index of ankle_link
  int sole_frame = -1;             ///< model frame index of the sole frame
};

/// The legs of the robot, right first, then left (the description's feet order). Throws
/// InputError when a foot's chain to the base does not have exactly six actuated joints.
std::vector<LegChain> legChains(const WholeBodyModel& model);

/// Result of a closed-form leg solve.
struct LegIkResult {
  Vector6d q = Vector6d::Zero();  ///< joint angles, rad, chain order (LegChain::actuated)
  /// False when the ankle lies beyond the reach of the stretched leg (or nearer the hip than the
  /// folded one): the angles then point the leg at the target, at the limit of its reach.
  bool reachable = true;
  double hip_ankle = 0.0;  ///< m, distance from the hip centre H to the ankle centre A
};

/// What LegIk::solve returns for an ankle beyond the stretched leg's reach.
enum class BeyondReach {
  /// The knee straight, the leg pointing at the target: the nearest pose (the runtime's).
  Stretch,
  /// The knee past straight by sqrt(2 (c - 1)), c > 1 the knee's cosine the target asks for
  /// (the continuation of acos(c) ~ sqrt(2 (1 - c)) below 1): not a pose, but every angle keeps
  /// changing with the target, so that an optimiser's joint-limit rows still see how far beyond
  /// reach it lies (the planner's).
  Continue,
};

/// Closed-form inverse kinematics of one leg (see the file comment). Immutable after
/// construction; safe to share between threads.
class LegIk {
 public:
  /// Reads the geometry of `chain` from `model` at the zero posture. Throws InputError naming
  /// the joint when the leg lacks the structure the closed form needs.
  LegIk(const WholeBodyModel& model, const LegChain& chain);

  /// Joint angles that put the ankle link at X_BA (its pose in the base frame); `reference`
  /// (chain order, rad) chooses between the ankle-roll branches, half-sitting if null. Never
  /// throws.
  LegIkResult solve(const Eigen::Isometry3d& X_BA, const Vector6d* reference = nullptr,
                    BeyondReach beyond = BeyondReach::Stretch) const;

  /// Forward kinematics of the same geometry: the ankle link's pose in the base frame.
  Eigen::Isometry3d forward(const Vector6d& q) const;

  /// The leg Jacobian at q: column i is the ankle link's twist [angular; linear of its origin],
  /// base-frame axes, per unit rate of joint i. Differentiating solve() gives dq = J^-1 dX
  /// (implicit-function theorem), dX = [rotation vector; translation] in the base frame.
  Eigen::Matrix<double, 6, 6> jacobian(const Vector6d& q) const;

  /// Hip centre H (base frame) and ankle centre A (ankle-link frame), m.
  const Eigen::Vector3d& hipCentre() const { return p_BH_; }
  const Eigen::Vector3d& ankleCentre() const { return p_AC_; }
  /// Shortest and longest hip-ankle distances the knee allows, m.
  double minReach() const { return reach_min_; }
  double maxReach() const { return reach_max_; }

 private:
  std::array<double, 6> sign_{};   // joint axis sign relative to z, x, y, y, y, x
  Eigen::Vector3d p_BH_;           // hip centre, base frame
  Eigen::Vector3d p_AC_;           // ankle centre in the ankle-link frame
  Eigen::Matrix3d R_BA0_;          // ankle-link orientation at the zero posture
  Eigen::Vector3d thigh_, shank_;  // H -> knee axis point, knee -> A, at the zero posture
  LegIkResult solveGivenRoll(const Eigen::Matrix3d& R, const Eigen::Vector3d& r5, double q5,
                             BeyondReach beyond) const;

  double knee_side_ = 1.0;              // sign of the knee angle on the half-sitting branch
  Vector6d lower_, upper_, reference_;  // mechanical limits and half-sitting, rad
  double reach_min_ = 0.0, reach_max_ = 0.0;
};

}  // namespace overstep::robots
