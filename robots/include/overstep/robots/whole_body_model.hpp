#pragma once
/// \file
/// The whole-body model: a robot description (URDF + YAML) loaded into a DART skeleton with a
/// floating base, behind an interface that speaks only Eigen and model coordinates.
///
/// Model coordinates (positions q, velocities v, accelerations a all have size dofs()):
///   [0, 6)               floating base (DART FreeJoint: rotation as exponential coordinates, then
///                        translation, of the base link in the world; velocities are the base's
///                        spatial velocity [angular; linear] in the base frame). Absent for a
///                        fixed-base robot.
///   [6, 6 + nA)          actuated joints, in the order of the YAML's actuated_joints
///   [6 + nA, 6 + nA + nE) passive elastic joints, in the order of elastic_joints
/// World: z up, gravity -g z. Wrenches are [torque; force].
///
/// Call order: set positions (then velocities, then accelerations) before any query that needs
/// them. An instance is a mutable workspace: use one per thread (copying clones the skeleton).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "overstep/core/robot_description.hpp"
#include "overstep/core/wrench.hpp"

namespace dart::dynamics {
class Skeleton;
}

namespace overstep::robots {

using core::Vector6d;

/// A contact constraint for the impact map: a point contact constrains the frame origin's linear
/// velocity (3 rows); a flat contact constrains the frame's full spatial velocity (6 rows).
/// A contact wrench acting on the robot at a frame (world axes, any reference point).
struct FrameWrench {
  int frame = -1;
  core::Wrench wrench;
};

struct ContactConstraint {
  enum class Type { Point, Flat };
  int frame = -1;
  Type type = Type::Flat;
};

class WholeBodyModel {
 public:
  /// Loads the URDF named by the description, validates it against the description (every joint
  /// the YAML names exists and is a 1-DOF revolute joint, no other movable joints, positive masses
  /// and inertias) and builds the skeleton. Throws InputError with a one-line message.
  explicit WholeBodyModel(core::RobotDescription description);
  /// Loads robots/<robot>/<robot>.yaml and its URDF.
  static WholeBodyModel fromFile(const std::string& yaml_path);

  WholeBodyModel(const WholeBodyModel& other);  ///< deep copy (clones the DART skeleton)
  WholeBodyModel& operator=(const WholeBodyModel& other);
  WholeBodyModel(WholeBodyModel&&) noexcept;
  WholeBodyModel& operator=(WholeBodyModel&&) noexcept;
  ~WholeBodyModel();

  const core::RobotDescription& description() const;

  int dofs() const;           ///< total generalized coordinates
  int baseDofs() const;       ///< 6 with a floating base, else 0
  int actuatedCount() const;  ///< nA
  int elasticCount() const;   ///< nE
  int actuatedCoordinate(int i) const { return baseDofs() + i; }
  int elasticCoordinate(int i) const { return baseDofs() + actuatedCount() + i; }
  /// Name of each model coordinate ("base_rx".."base_z" for the base, then joint names).
  std::vector<std::string> coordinateNames() const;
  double totalMass() const;  ///< kg

  // ------------------------------------------------------------------ state
  void setPositions(const Eigen::VectorXd& q);
  void setVelocities(const Eigen::VectorXd& v);
  void setAccelerations(const Eigen::VectorXd& a);
  void setState(const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& a);
  Eigen::VectorXd positions() const;
  Eigen::VectorXd velocities() const;
  Eigen::VectorXd accelerations() const;
  /// q + v dt on the configuration manifold (the base integrates on SE(3)).
  Eigen::VectorXd integrate(const Eigen::VectorXd& q, const Eigen::VectorXd& v, double dt) const;
  /// v such that integrate(q0, v, 1) = q1 (tangent-space difference q1 - q0).
  Eigen::VectorXd difference(const Eigen::VectorXd& q1, const Eigen::VectorXd& q0) const;

  /// The half-sitting configuration: actuated joints at half_sitting, elastic joints at rest, and
  /// (floating base) the base placed so that both soles lie flat on z = 0 with the midpoint of the
  /// two sole frames at the world origin. Uses this workspace and restores its positions.
  Eigen::VectorXd halfSitting();

  /// Floating-base closure: overwrites the base entries of q, v and a (joint entries are kept) so
  /// that `frame` sits at X_WF and is stationary (zero velocity and classical acceleration), then
  /// sets that state. This is how a plan places the base on its stance foot.
  void anchorBase(int frame, const Eigen::Isometry3d& X_WF, Eigen::VectorXd& q, Eigen::VectorXd& v,
                  Eigen::VectorXd& a);

  // ------------------------------------------------------------------ frames
  /// Index of a frame named in the YAML or of a link (link frames are registered under the link
  /// name). Throws InputError for an unknown name.
  int frameIndex(const std::string& name) const;
  bool hasFrame(const std::string& name) const;
  Eigen::Isometry3d framePose(int frame) const;  ///< X_WF
  /// World pose of a joint's frame (its axis passes through the origin), by joint name: e.g. the
  /// centre of an elastic bushing. Throws InputError for an unknown joint.
  Eigen::Isometry3d jointPose(const std::string& joint) const;
  /// World-aligned Jacobian of the frame: rows [angular; linear velocity of the frame origin].
  Eigen::MatrixXd frameJacobian(int frame) const;
  /// The same into J (resized to 6 x dofs; no allocation once it has that size).
  void frameJacobian(int frame, Eigen::MatrixXd& J) const;
  /// World-aligned velocity [angular; linear of the origin].
  Vector6d frameVelocity(int frame) const;
  /// Classical world acceleration [angular; linear of the origin] (needs accelerations set).
  Vector6d frameAcceleration(int frame) const;

  // ------------------------------------------------------------------ centre of mass
  Eigen::Vector3d com() const;
  Eigen::Vector3d comVelocity() const;
  Eigen::Vector3d comAcceleration() const;
  Eigen::MatrixXd comJacobian() const;  ///< 3 x dofs
  /// Mass (kg) and world centre of mass of the bodies below the frame's body (its descendants,
  /// not the body itself): what a force sensor on that body carries. Zero mass for a leaf.
  double massBelow(int frame, Eigen::Vector3d* com_world) const;
  /// Centroidal momentum in the world frame: [linear (kg m/s); angular about the CoM (kg m^2/s)].
  Vector6d centroidalMomentum() const;

  // ------------------------------------------------------------------ dynamics
  /// Joint-space inertia including the reflected rotor inertias on the actuated rows (seed eqs.
  /// 3-4). with_rotor = false gives the rigid-body inertia only.
  Eigen::MatrixXd massMatrix(bool with_rotor = true) const;
  /// Coriolis, centrifugal and gravity forces plus the elastic joints' spring and damper torques
  /// (seed eq. 5 with C(q)): M a + nonlinearEffects() = tau + J^T f.
  Eigen::VectorXd nonlinearEffects() const;
  /// Inverse dynamics with no external forces: tau = M a + NLE (RNEA, rotor term included).
  /// Actuated rows: joint torques. Elastic rows: zero when the motion is dynamically consistent.
  /// Base rows: the generalized contact force the motion requires.
  Eigen::VectorXd inverseDynamics() const;
  /// The same into tau (resized to dofs; no allocation once it has that size, DART's own
  /// recursion aside).
  void inverseDynamics(Eigen::VectorXd& tau) const;
  /// Generalized forces of the robot in contact (seed eq. 1): tau_id - sum_c J_c^T w_c, with
  /// tau_id = inverseDynamics() at the current state and J_c the world-aligned Jacobian of
  /// contact c's frame. Actuated rows: the actuator torques (the robot hanging from its base
  /// when `contacts` is empty); elastic rows: the bushings' residual (zero for a consistent
  /// motion); base rows: zero when the wrenches balance the motion.
  Eigen::VectorXd torquesInContact(const Eigen::VectorXd& tau_id,
                                   const std::vector<FrameWrench>& contacts) const;
  /// Total contact wrench the motion requires, from the base rows of `tau` (as returned by
  /// inverseDynamics()): world axes, about the world origin. Floating base only.
  core::Wrench contactWrenchFromBase(const Eigen::VectorXd& tau) const;
  /// Whole-body ZMP on z = ground_z from the motion (RNEA base rows).
  Eigen::Vector2d zmpFromMotion(double ground_z = 0.0) const;
  /// Table-cart (3D-LIPM) ZMP from the CoM and its acceleration.
  Eigen::Vector2d tableCartZmp(double ground_z = 0.0) const;
  /// Inelastic impact map (seed eq. 11): solves [M -J^T; J 0][v+; L] = [M v-; 0] at the current
  /// positions. Returns v+; writes the stacked impulses (N s / N m s) to `impulse` if given.
  Eigen::VectorXd impactMap(const Eigen::VectorXd& v_minus,
                            const std::vector<ContactConstraint>& contacts,
                            Eigen::VectorXd* impulse = nullptr) const;
  /// Stacked constraint Jacobian of a contact set (rows as in ContactConstraint).
  Eigen::MatrixXd contactJacobian(const std::vector<ContactConstraint>& contacts) const;

  /// The DART skeleton (in DART's own coordinate order!). For the planner's and the simulator's
  /// use only; see dartIndex() for the permutation.
  std::shared_ptr<dart::dynamics::Skeleton> skeleton() const;
  /// Merges a point mass at `offset` (link frame) into the body `link` of `skel` (mass, CoM and
  /// rotational inertia): a payload. InputError when the body does not exist.
  static void attachPointMass(dart::dynamics::Skeleton& skel, const std::string& link, double mass,
                              const Eigen::Vector3d& offset);
  /// DART generalized-coordinate index of model coordinate i.
  int dartIndex(int i) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace overstep::robots
