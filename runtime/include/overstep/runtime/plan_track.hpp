#pragma once
/// \file
/// The plan as the fixed-rate loop consumes it. Everything that needs the robot model (DART) is
/// computed once, when the plan is loaded: per sample, the stabilizer's reference (CoM, table-cart
/// ZMP, sole poses, sole-frame wrenches, torso orientation), the leg Jacobians that turn the
/// stabilizer's corrections into joint references, the CoM Jacobian with a stance foot held, and
/// the force sensors' placement. Sampling and the estimator are then plain fixed-size Eigen
/// arithmetic: no allocation, no exceptions, no DART in the tick.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "overstep/core/plan.hpp"
#include "overstep/core/robot_io.hpp"
#include "overstep/stabilizer/stabilizer.hpp"

namespace overstep::robots {
class WholeBodyModel;
class LegIk;
}  // namespace overstep::robots

namespace overstep::runtime {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// The plan at one instant (linear interpolation between samples; the model-derived matrices are
/// those of the nearest sample). Sized once by PlanTrack::makeSample().
struct TrackSample {
  double t = 0.0;
  int index = 0;  ///< nearest plan sample
  int phase = 0;
  Eigen::VectorXd q;   ///< actuated joint positions, rad
  Eigen::VectorXd qd;  ///< actuated joint velocities, rad/s
  stabilizer::Reference ref;
  Eigen::Vector3d imu_angular_velocity = Eigen::Vector3d::Zero();  ///< world, planned
  Eigen::Vector3d base_position = Eigen::Vector3d::Zero();         ///< world, planned
  Eigen::Vector2d zmp_wholebody = Eigen::Vector2d::Zero();
};

/// Stabilizer corrections turned into joint offsets (actuated order), and the estimator's state.
class PlanTrack {
 public:
  /// Validates the plan against the model (robot hash, sizes, joint limits within the mechanical
  /// range, contact in every phase) and precomputes the per-sample data. InputError with a
  /// one-line reason otherwise. Not real-time.
  PlanTrack(const core::Plan& plan, robots::WholeBodyModel& model);
  ~PlanTrack();
  PlanTrack(const PlanTrack&) = delete;
  PlanTrack& operator=(const PlanTrack&) = delete;

  int samples() const { return static_cast<int>(t_.size()); }
  int joints() const { return joints_; }
  double duration() const { return duration_; }
  double rate() const { return rate_; }
  const std::string& phaseName(int phase) const;
  const std::vector<std::string>& jointNames() const { return joint_names_; }
  const Eigen::VectorXd& lower() const { return lower_; }  ///< mechanical limits, rad
  const Eigen::VectorXd& upper() const { return upper_; }
  const Eigen::VectorXd& safeLower() const { return safe_lower_; }  ///< planner safety limits
  const Eigen::VectorXd& safeUpper() const { return safe_upper_; }
  const Eigen::VectorXd& velocityLimit() const { return vmax_; }  ///< rad/s
  /// Leg joints of each foot (actuated indices), right then left.
  const std::array<std::array<int, 6>, 2>& legJoints() const { return leg_; }

  /// A sample with every vector sized (allocates; call once, outside the loop).
  TrackSample makeSample() const;
  /// The plan at time t (clamped to [0, duration]). Never allocates.
  void sample(double t, TrackSample& out) const;

  /// Adds the stabilizer's corrections to out->q (actuated joint references): per leg, the sole
  /// rotation (about the centre of the ankle bushing, so that a foot held flat by the ground takes
  /// it as a bushing deflection and the closed chain of double support stays consistent) and
  /// height change, and the base shift (CoM offset) and rotation (body attitude), through the
  /// inverse leg Jacobian at the nearest sample. Never allocates.
  void applyCorrections(const TrackSample& s, const stabilizer::Output& c,
                        Eigen::VectorXd& q) const;

  /// The stabilizer's measurement from the robot state: sole-frame contact wrenches from the
  /// ankle force sensors (the weight of the bodies below each sensor removed), the planned sole
  /// poses, the IMU orientation, and the CoM estimated from the joint encoders (stance foot(s)
  /// held, weighted by the planned normal forces) plus the body's rotation about the stance sole
  /// that the IMU sees beyond the plan (the elastic-ankle sway). Never allocates.
  void estimate(const TrackSample& s, const core::RobotState& st,
                stabilizer::Measurement& out) const;

  /// Foot f's contact wrench (sole axes, about the sole origin) at sample `index` from its sensor
  /// reading (sensor axes, about the sensor origin), less the static weight below the sensor.
  core::Wrench soleWrench(int index, int f, const core::Wrench& ft) const;

  /// Plans the move from the measured posture (actuated joints `q_now`) to the plan's first
  /// sample over `samples` points (a quintic time law): the base pose relative to the feet and
  /// the joints off the legs are interpolated and each leg's joints solved by inverse kinematics
  /// so that both soles stay where the plan's first sample has them. (A joint-space blend between
  /// two double-support postures moves the feet relative to each other, which the closed chain
  /// turns into large internal forces: measured 6 cm of opposite CoP shifts, docs/runtime.md.)
  /// Writes joints x samples into `out`. Not real-time (model, allocation): call outside the
  /// tick. Returns false if a leg cannot reach (the move is then not safe to make).
  bool planMove(const Eigen::VectorXd& q_now, int samples, Eigen::MatrixXd& out) const;

 private:
  /// Adds to the joint references the offsets that make up for the soles' compression.
  void compensateVerticalGive(double stiffness);
  /// The sample a backward difference at sample k > 0 takes its step from: the latest one at
  /// least half a period earlier (a contact switch is two samples 1 us apart; a difference over
  /// that microsecond is noise over 1e-6 s). -1 when there is none.
  int differenceBase(int k) const;

  int joints_ = 0;
  double duration_ = 0.0, rate_ = 200.0;
  std::vector<std::string> joint_names_, phase_names_;
  Eigen::VectorXd lower_, upper_, safe_lower_, safe_upper_, vmax_;
  std::array<std::array<int, 6>, 2> leg_{};
  Eigen::VectorXd t_;
  Eigen::VectorXi phase_;
  std::vector<std::array<bool, 2>> contact_;
  Eigen::MatrixXd q_, qd_;  ///< joints x N
  Eigen::MatrixXd com_, com_vel_, com_acc_, zmp_, zmp_vel_, zmp_wb_, zmp_wb_vel_;
  Eigen::MatrixXd sole_pose_[2];         ///< 7 x N [x y z qw qx qy qz]
  std::vector<core::Wrench> wrench_[2];  ///< N planned wrenches, sole axes about the origin
  Eigen::MatrixXd imu_quat_, imu_omega_, base_pos_;
  std::vector<Matrix6d> leg_inv_[2];      ///< (d sole twist / d leg joints)^-1, world-aligned
  Eigen::MatrixXd sole_from_base_[2];     ///< 3 x N, p_sole - p_base
  Eigen::MatrixXd sole_from_bushing_[2];  ///< 3 x N, p_sole - centre of the ankle bushing
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> com_jac_[2];  ///< 3 x joints, foot held
  Eigen::MatrixXd sensor_pose_[2];  ///< 7 x N sensor frame in the world
  Eigen::MatrixXd below_com_[2];    ///< 3 x N, CoM of the bodies below each sensor
  double below_mass_[2] = {0.0, 0.0};
  double gravity_ = 9.81;
  /// Force-sensor calibration from a model overlay (bias and scale; identity without one).
  std::array<core::ForceSensorModel, 2> ft_{};
  std::unique_ptr<robots::WholeBodyModel> model_;  ///< for planMove (not used in the tick)
  Eigen::VectorXd q0_;                             ///< the plan's first sample (all coordinates)
  /// m, each sole's compression under the plan's first load (the bushings' vertical give, which
  /// the plan's model lacks): the move to the start ends with the legs lengthened by it.
  std::array<double, 2> start_compression_{{0.0, 0.0}};
  int sole_frame_[2] = {-1, -1};
  int sensor_frame_[2] = {-1, -1};  ///< F/T frames: on the ankle links, at the bushing centres
  int ankle_frame_[2] = {-1, -1};   ///< the ankle links (above the bushings)
  std::unique_ptr<robots::LegIk> ik_[2];  ///< closed-form leg solvers (planMove)
};

}  // namespace overstep::runtime
