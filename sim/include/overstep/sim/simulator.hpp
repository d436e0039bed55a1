#pragma once
/// \file
/// The simulated robot: a DART world (ground + the robot from robots/) stepped at a fixed time
/// step. Actuated joints are position servos (DART SERVO actuators: desired velocity
/// Kv (q_ref - q) + qd_ref, torque-limited by the constraint solver, as runtime.md measured
/// stable at 1 ms); the elastic ankle bushings are passive joints whose spring and damper act as an
/// explicit torque (DART's implicit spring is too soft under contact and its implicit damping
/// tipped the robot over; measured, see simulator.cpp). Only the feet
/// collide with the ground, through DART's own detector (4 contacts per flat foot).
/// Sensors: encoders, a 6-axis F/T sensor above each bushing, a chest IMU; the true base state
/// is reported only in the flagged ground-truth fields.

#include <Eigen/Geometry>
#include <array>
#include <memory>

#include "overstep/core/obstacle.hpp"
#include "overstep/core/robot_io.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/sim/truth.hpp"

namespace overstep::sim {

struct SimOptions {
  double dt = 0.001;          ///< s, physics step
  double servo_gain = 300.0;  ///< 1/s, Kv of the velocity servo (Kv dt <= 1)
  /// N m/rad, position stiffness of a joint servo: a load torque tau (here joint friction) makes
  /// the joint lag its reference by tau / stiffness, as a PD position loop does [est].
  double servo_stiffness = 3000.0;
  double ground_friction = 1.0;
  /// Steps over which the reported motor torques and force-sensor wrenches are averaged (the
  /// sensors' filters; 5 = one 200 Hz control period at 1 ms). 1: the last step alone.
  int torque_window = 5;
  /// DART contact constraint-force mixing: the compliance of the soles on the ground (rubber soles
  /// and the bushings' translational give, which the rigid model lacks). With DART's default
  /// (1e-5) double support is a rigid closed chain: a 1e-6 rad knee command offset moved each
  /// foot's CoP 4 cm in opposite directions; at 3e-3 (with the error reduction set by the
  /// simulator) a 3e-4 rad offset moves them about 1 cm; 1 diverged (measured, docs/runtime.md).
  /// Global to DART: every Simulator sets the same value.
  double contact_softness = 3e-3;
  /// The bar to step over (its envelope, placed spec.gap ahead of the start toes). It is a
  /// physical box for the feet; contact of any leg capsule with it is detected (collisions()).
  bool has_obstacle = false;
  core::ObstacleSpec obstacle;
};

/// Geometric checks of the current posture against the obstacle and the ground.
struct CollisionStatus {
  double obstacle_distance = 1e9;  ///< m, smallest leg-capsule to obstacle distance (< 0: overlap)
  std::string obstacle_link;       ///< which link
  double ground_clearance = 1e9;   ///< m, lowest point of any non-foot capsule above the ground
  std::string ground_link;
  bool obstacleContact() const { return obstacle_distance <= 0.0; }
  bool nonFootGroundContact() const { return ground_clearance <= 0.0; }
};

/// Ground-truth contact summary of the last step.
struct ContactInfo {
  /// Ground reaction on each foot, world axes, about the world origin.
  std::array<core::Wrench, 2> foot_wrench{};
  std::array<bool, 2> foot_contact{{false, false}};
  int contact_points = 0;
};

class Simulator {
 public:
  /// Builds the world with the robot standing in half-sitting on the ground (feet flat, z = 0).
  Simulator(const robots::WholeBodyModel& model, const TruthEffects& truth,
            const SimOptions& options = {});
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  /// Joint references for the servos (actuated joints, model order), held until replaced.
  void setCommand(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref);
  /// One physics step.
  void step();
  /// Relaxes the robot into static equilibrium holding the current commands (`steps` physics
  /// steps of dynamic relaxation), then restarts the clock at 0. Without it the robot starts
  /// with undeflected bushings and sways for seconds on their light damping.
  void settle(int steps = 2000);
  double time() const;

  /// Sensor readings now (noise-free; noise is the caller's concern), with ground truth filled.
  core::RobotState state() const;
  const ContactInfo& contacts() const { return contacts_; }
  /// Obstacle and ground checks of the current posture (capsules of the robot YAML).
  CollisionStatus collisions() const;
  /// Base (pelvis) pose in the world: ground truth.
  Eigen::Isometry3d basePose() const;
  /// Ground truth: world pose of any model frame or link (e.g. a sole frame), linear speed of the
  /// base. For verdicts and tests; nothing published depends on them.
  Eigen::Isometry3d framePose(const std::string& frame) const;
  double baseSpeed() const;
  /// Extent of the obstacle envelope along x (world), {0, 0} without one.
  std::array<double, 2> obstacleRangeX() const;
  /// Whole-body CoM in the world: ground truth.
  Eigen::Vector3d com() const;
  double totalMass() const;
  /// Mass below each F/T sensor (bushing links and foot), kg.
  double massBelowSensor(int foot) const;
  /// Ground truth: load-side joint angles (actuated, model order), rad. The encoders (state().q)
  /// sit on the motor side and differ from these by the backlash.
  Eigen::VectorXd jointPositions() const;
  /// Current bushing angles [R roll, R pitch, L roll, L pitch], rad.
  Eigen::Vector4d elasticPositions() const;
  /// Ground truth: moment about each bushing axis of the external forces on the bodies below it
  /// (ground reaction and their weight), N m. In statics it equals stiffness x deflection.
  Eigen::Vector4d elasticExternalTorque() const;

 private:
  /// Foot f's sensor wrench, sensor axes about its origin, after the last step (before the
  /// filter).
  core::Wrench sensorWrench(int f) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
  ContactInfo contacts_;
};

}  // namespace overstep::sim
