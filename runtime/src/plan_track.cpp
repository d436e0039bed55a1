#include "overstep/runtime/plan_track.hpp"

#include <algorithm>
#include <cmath>

#include "overstep/core/error.hpp"
#include "overstep/robots/leg.hpp"
#include "overstep/robots/whole_body_model.hpp"

namespace overstep::runtime {
namespace {

Eigen::Quaterniond quatAt(const Eigen::MatrixXd& pose, int k) {
  return Eigen::Quaterniond(pose(3, k), pose(4, k), pose(5, k), pose(6, k));
}

Eigen::Matrix<double, 7, 1> poseColumn(const Eigen::Isometry3d& X) {
  const Eigen::Quaterniond qt(X.linear());
  Eigen::Matrix<double, 7, 1> c;
  c << X.translation(), qt.w(), qt.x(), qt.y(), qt.z();
  return c;
}

/// Rotation vector of a small rotation (roll/pitch part only: heading is not estimated).
Eigen::Vector3d tiltVector(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(q);
  Eigen::Vector3d v = aa.axis() * aa.angle();
  v.z() = 0.0;
  return v;
}

}  // namespace

PlanTrack::PlanTrack(const core::Plan& plan, robots::WholeBodyModel& model) {
  const auto& d = model.description();
  if (plan.robot_hash != d.hashHex())
    throw InputError("plan was made for robot '" + plan.robot_name + "' (hash " + plan.robot_hash +
                     "), not for " + d.yaml_path + " (hash " + d.hashHex() + ")");
  if (plan.q.rows() != model.dofs() || plan.tau.rows() != model.actuatedCount())
    throw InputError("plan has " + std::to_string(plan.q.rows()) + " coordinates, the robot " +
                     std::to_string(model.dofs()));
  if (plan.samples() < 2) throw InputError("plan has fewer than 2 samples");
  if (!(plan.rate >= 50.0 && plan.rate <= 1000.0))
    throw InputError("plan rate " + std::to_string(plan.rate) + " Hz outside 50-1000 Hz");
  if (plan.phases.empty()) throw InputError("plan has no phases");
  const int N = plan.samples();
  const int nA = model.actuatedCount();
  joints_ = nA;
  duration_ = plan.duration();
  rate_ = plan.rate;
  gravity_ = d.gravity;
  ft_ = d.effects.ft;
  for (const auto& p : plan.phases) {
    if (!p.right_contact && !p.left_contact)
      throw InputError("plan phase '" + p.name + "' has no foot in contact");
    phase_names_.push_back(p.name);
  }
  lower_.resize(nA);
  upper_.resize(nA);
  safe_lower_.resize(nA);
  safe_upper_.resize(nA);
  vmax_.resize(nA);
  for (int j = 0; j < nA; ++j) {
    const auto& aj = d.actuated[static_cast<std::size_t>(j)];
    joint_names_.push_back(aj.name);
    lower_(j) = aj.lower;
    upper_(j) = aj.upper;
    safe_lower_(j) = aj.safeLower();
    safe_upper_(j) = aj.safeUpper();
    vmax_(j) = aj.velocity;
  }
  t_ = plan.t;
  phase_ = plan.phase;
  q_ = plan.q.middleRows(model.actuatedCoordinate(0), nA);
  qd_ = plan.v.middleRows(model.actuatedCoordinate(0), nA);
  for (int k = 0; k < N; ++k) {
    if (phase_(k) < 0 || phase_(k) >= static_cast<int>(plan.phases.size()))
      throw InputError("plan sample " + std::to_string(k) + " names phase " +
                       std::to_string(phase_(k)) + " of " + std::to_string(plan.phases.size()));
    for (int j = 0; j < nA; ++j) {
      if (q_(j, k) < lower_(j) || q_(j, k) > upper_(j))
        throw InputError("plan sample " + std::to_string(k) + ": " + joint_names_[std::size_t(j)] +
                         " = " + std::to_string(q_(j, k)) + " rad outside its limits [" +
                         std::to_string(lower_(j)) + ", " + std::to_string(upper_(j)) + "]");
    }
    const auto& ph = plan.phases[static_cast<std::size_t>(phase_(k))];
    contact_.push_back({ph.right_contact, ph.left_contact});
  }

  const core::FootDescription* feet[2] = {d.foot("right"), d.foot("left")};
  if (!feet[0] || !feet[1]) throw InputError("the runtime needs a right and a left foot");
  int sole[2], sensor[2];
  for (int f = 0; f < 2; ++f) {
    sole[f] = model.frameIndex(feet[f]->sole_frame);
    sensor[f] = model.frameIndex(feet[f]->force_sensor_frame);
  }
  const int imu = model.frameIndex("imu");
  const int base = model.frameIndex(d.base_link);

  // Leg joints and the elastic joints above each sole (their common centre is where a foot
  // rotation is applied), from the kinematic tree; the closed-form leg solver for the move to
  // the plan's start.
  std::vector<std::string> bushing_joints[2];
  const std::vector<robots::LegChain> legs = robots::legChains(model);
  for (int f = 0; f < 2; ++f) {
    const robots::LegChain& c = legs[static_cast<std::size_t>(f)];
    if (c.side != (f == 0 ? "right" : "left"))
      throw InputError("the runtime needs the right foot first, then the left");
    for (int i = 0; i < 6; ++i)
      leg_[static_cast<std::size_t>(f)][static_cast<std::size_t>(i)] =
          c.actuated[static_cast<std::size_t>(i)];
    for (int e : c.elastic)
      bushing_joints[f].push_back(d.elastic[static_cast<std::size_t>(e)].name);
    ik_[f] = std::make_unique<robots::LegIk>(model, c);
    ankle_frame_[f] = c.ankle_frame;
  }

  com_.resize(3, N);
  com_vel_.resize(3, N);
  com_acc_.resize(3, N);
  zmp_ = plan.zmp_tablecart;
  zmp_wb_ = plan.zmp_wholebody;
  zmp_vel_.setZero(2, N);
  zmp_wb_vel_.setZero(2, N);
  imu_quat_.resize(4, N);
  imu_omega_.resize(3, N);
  base_pos_.resize(3, N);
  for (int f = 0; f < 2; ++f) {
    sole_pose_[f] = f == 0 ? plan.right_foot : plan.left_foot;
    wrench_[f].resize(static_cast<std::size_t>(N));
    sole_from_base_[f].resize(3, N);
    sole_from_bushing_[f].setZero(3, N);
    sensor_pose_[f].resize(7, N);
    below_com_[f].resize(3, N);
    leg_inv_[f].resize(static_cast<std::size_t>(N));
    com_jac_[f].assign(static_cast<std::size_t>(N),
                       Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, nA));
  }
  for (int k = 0; k < N; ++k) {
    model.setState(plan.q.col(k), plan.v.col(k), plan.a.col(k));
    com_.col(k) = model.com();
    com_vel_.col(k) = model.comVelocity();
    com_acc_.col(k) = model.comAcceleration();
    const Eigen::Isometry3d Xi = model.framePose(imu);
    const Eigen::Quaterniond qi(Xi.linear());
    imu_quat_.col(k) << qi.w(), qi.x(), qi.y(), qi.z();
    imu_omega_.col(k) = model.frameVelocity(imu).head<3>();
    const Eigen::Vector3d pb = model.framePose(base).translation();
    base_pos_.col(k) = pb;
    if (const int a = differenceBase(k); a >= 0) {
      const double dt = t_(k) - t_(a);
      zmp_vel_.col(k) = (zmp_.col(k) - zmp_.col(a)) / dt;
      zmp_wb_vel_.col(k) = (zmp_wb_.col(k) - zmp_wb_.col(a)) / dt;
    }
    const Eigen::MatrixXd Jc = model.comJacobian();
    for (int f = 0; f < 2; ++f) {
      const Eigen::Isometry3d Xs = model.framePose(sole[f]);
      wrench_[f][static_cast<std::size_t>(k)] = plan.wrench(f, k).inFrame(Xs, core::Axes::kSole);
      sole_from_base_[f].col(k) = Xs.translation() - pb;
      if (!bushing_joints[f].empty()) {
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        for (const auto& j : bushing_joints[f]) c += model.jointPose(j).translation();
        c /= static_cast<double>(bushing_joints[f].size());
        sole_from_bushing_[f].col(k) = Xs.translation() - c;
      }
      sensor_pose_[f].col(k) = poseColumn(model.framePose(sensor[f]));
      Eigen::Vector3d c;
      below_mass_[f] = model.massBelow(sensor[f], &c);
      below_com_[f].col(k) = c;
      const Eigen::MatrixXd J = model.frameJacobian(sole[f]);
      Matrix6d Jl;
      for (int i = 0; i < 6; ++i)
        Jl.col(i) = J.col(model.actuatedCoordinate(leg_[std::size_t(f)][std::size_t(i)]));
      // Damped inverse: exact away from the stretched knee, bounded near it.
      leg_inv_[f][std::size_t(k)] =
          (Jl.transpose() * Jl + 1e-6 * Matrix6d::Identity()).ldlt().solve(Jl.transpose());
      // CoM Jacobian with this sole held still: the base follows the joints.
      const Matrix6d Jb = J.leftCols<6>();
      const Eigen::MatrixXd Ja = J.middleCols(model.actuatedCoordinate(0), nA);
      com_jac_[f][std::size_t(k)] = Jc.middleCols(model.actuatedCoordinate(0), nA) -
                                    Jc.leftCols<6>() * Jb.partialPivLu().solve(Ja);
    }
  }
  // The samples of the first half period have no difference of their own: the first rate.
  int first = 0;
  while (first < N && differenceBase(first) < 0) ++first;
  for (int k = 0; k < first && first < N; ++k) {
    zmp_vel_.col(k) = zmp_vel_.col(first);
    zmp_wb_vel_.col(k) = zmp_wb_vel_.col(first);
  }
  compensateVerticalGive(d.bushing_vertical_stiffness);
  model_ = std::make_unique<robots::WholeBodyModel>(model);
  q0_ = plan.q.col(0);
  sole_frame_[0] = sole[0];
  sole_frame_[1] = sole[1];
  sensor_frame_[0] = sensor[0];
  sensor_frame_[1] = sensor[1];
}

PlanTrack::~PlanTrack() = default;

void PlanTrack::compensateVerticalGive(double stiffness) {
  const int N = samples();
  start_compression_ = {0.0, 0.0};
  if (!(stiffness > 0.0)) return;
  // The plan's model has no vertical give in the bushings: each leg in contact is lengthened by
  // its planned normal force / stiffness along the sole normal (through the leg Jacobian's
  // inverse: a few mrad), so the robot, whose soles do give, stands where the plan puts it.
  // Velocities get the offsets' rate (backward differences over the samples).
  Eigen::MatrixXd dq = Eigen::MatrixXd::Zero(joints_, N);
  for (int k = 0; k < N; ++k)
    for (int f = 0; f < 2; ++f) {
      const double c = std::max(0.0, wrench_[f][std::size_t(k)].force.z()) / stiffness;
      if (k == 0) start_compression_[std::size_t(f)] = c;
      core::Vector6d dx = core::Vector6d::Zero();
      dx(5) = -c;
      const Eigen::Matrix<double, 6, 1> dql = leg_inv_[f][std::size_t(k)] * dx;
      for (int i = 0; i < 6; ++i) dq(leg_[std::size_t(f)][std::size_t(i)], k) += dql(i);
    }
  q_ += dq;
  // The offsets of a switch's two samples differ by the switching foot's last planned load:
  // over the microsecond between them that read as several rad/s in the stance leg, which the
  // replay sent for one tick clamped at the joints' velocity limits (measured: 3.8-6.1 rad/s, the
  // stance foot rocking edge to edge at the 5 cm bar's lift-off).
  for (int k = 1; k < N; ++k)
    if (const int a = differenceBase(k); a >= 0)
      qd_.col(k) += (dq.col(k) - dq.col(a)) / (t_(k) - t_(a));
}

int PlanTrack::differenceBase(int k) const {
  int a = k - 1;
  while (a >= 0 && t_(k) - t_(a) < 0.5 / rate_) --a;
  return a;
}

bool PlanTrack::planMove(const Eigen::VectorXd& q_now, int samples, Eigen::MatrixXd& out) const {
  robots::WholeBodyModel& m = *model_;
  const int nA = joints_;
  if (q_now.size() != nA || samples < 2) return false;
  out.resize(nA, samples);
  const Eigen::VectorXd q_to = q_.col(0);  // with the compression offsets
  const bool both = contact_[0][0] && contact_[0][1];
  // Feet where the plan's first sample has them; the base pose now from the measured joints
  // with the anchor (left if loaded) sole there.
  const int anchor = contact_[0][1] ? 1 : 0;
  Eigen::Isometry3d soles[2];
  m.setPositions(q0_);
  for (int f = 0; f < 2; ++f) soles[f] = m.framePose(sole_frame_[f]);
  const Eigen::Isometry3d base_to = m.framePose(m.frameIndex(m.description().base_link));
  Eigen::VectorXd q = q0_, v = Eigen::VectorXd::Zero(q0_.size()), a = v;
  q.segment(m.actuatedCoordinate(0), nA) = q_now;
  m.anchorBase(sole_frame_[anchor], soles[anchor], q, v, a);
  const Eigen::Isometry3d base_from = m.framePose(m.frameIndex(m.description().base_link));
  const Eigen::Quaterniond r_from(base_from.linear()), r_to(base_to.linear());
  // Each leg is solved, in closed form, for its ankle link (above the bushing): from where the
  // measured joints put it to where the plan's first sample has it. The bushings take the change
  // of orientation between the ankle and the flat foot, so the move starts exactly at the
  // measured joints whatever the bushings' deflection.
  Eigen::Isometry3d ankle_from[2], ankle_to[2];
  for (int f = 0; f < 2; ++f) ankle_from[f] = m.framePose(ankle_frame_[f]);
  m.setPositions(q0_);
  for (int f = 0; f < 2; ++f) ankle_to[f] = m.framePose(ankle_frame_[f]);
  // The ankles (bushing centres) sit on the feet: if the measured joints put the other one more
  // than 2 mm from where the plan's start has it, the robot does not stand on the plan's start
  // placements, and no motion in double support can get it there.
  if (both &&
      (ankle_from[1 - anchor].translation() - ankle_to[1 - anchor].translation()).norm() > 2e-3)
    return false;
  // The move ends with each loaded leg lengthened by its sole's compression (as q_to is).
  for (int f = 0; f < 2; ++f) ankle_to[f].translation().z() -= start_compression_[std::size_t(f)];
  for (int k = 0; k < samples; ++k) {
    const double u = static_cast<double>(k) / (samples - 1);
    const double b = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
    Eigen::VectorXd qa = q_now + b * (q_to - q_now);
    if (both) {
      // Base at the interpolated pose, then each leg solved onto its (interpolated) ankle pose.
      Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
      base.linear() = r_from.slerp(b, r_to).toRotationMatrix();
      base.translation() = (1.0 - b) * base_from.translation() + b * base_to.translation();
      for (int f = 0; f < 2; ++f) {
        const auto& leg = leg_[static_cast<std::size_t>(f)];
        Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
        target.linear() = Eigen::Quaterniond(ankle_from[f].linear())
                              .slerp(b, Eigen::Quaterniond(ankle_to[f].linear()))
                              .toRotationMatrix();
        target.translation() =
            (1.0 - b) * ankle_from[f].translation() + b * ankle_to[f].translation();
        robots::Vector6d prev;  // the previous point's solution picks the branch
        for (int i = 0; i < 6; ++i)
          prev(i) = k > 0 ? out(leg[std::size_t(i)], k - 1) : q_now(leg[std::size_t(i)]);
        const robots::LegIkResult r = ik_[f]->solve(base.inverse() * target, &prev);
        if (!r.reachable) return false;
        for (int i = 0; i < 6; ++i) qa(leg[std::size_t(i)]) = r.q(i);
        for (int i = 0; i < 6; ++i) {
          const int j = leg[std::size_t(i)];
          if (qa(j) < lower_(j) || qa(j) > upper_(j)) return false;
        }
      }
    }
    // The last point is the plan's own first posture (the solution differs by the IK's
    // tolerance only: ~1e-6 rad).
    if (k == samples - 1) {
      if ((qa - q_to).cwiseAbs().maxCoeff() > 1e-3) return false;
      qa = q_to;
    }
    out.col(k) = qa;
  }
  return true;
}

const std::string& PlanTrack::phaseName(int phase) const {
  static const std::string none = "none";
  if (phase < 0 || phase >= static_cast<int>(phase_names_.size())) return none;
  return phase_names_[static_cast<std::size_t>(phase)];
}

TrackSample PlanTrack::makeSample() const {
  TrackSample s;
  s.q.setZero(joints_);
  s.qd.setZero(joints_);
  sample(0.0, s);
  return s;
}

void PlanTrack::sample(double t, TrackSample& out) const {
  const int N = samples();
  const double tc = std::isfinite(t) ? std::clamp(t, 0.0, duration_) : 0.0;
  int k = static_cast<int>(std::floor(tc * rate_));
  k = std::clamp(k, 0, N - 1);
  while (k + 1 < N && t_(k + 1) <= tc) ++k;
  while (k > 0 && t_(k) > tc) --k;
  const int k1 = std::min(k + 1, N - 1);
  const double span = t_(k1) - t_(k);
  const double s = span > 0.0 ? std::clamp((tc - t_(k)) / span, 0.0, 1.0) : 0.0;
  const int near = s < 0.5 ? k : k1;
  out.t = tc;
  out.index = near;
  // Contact flags and phase switch at the sample itself (no blending across a switch).
  out.phase = phase_(near);
  auto lerp = [s](const auto& a, const auto& b) { return (1.0 - s) * a + s * b; };
  out.q = lerp(q_.col(k), q_.col(k1));
  out.qd = lerp(qd_.col(k), qd_.col(k1));
  stabilizer::Reference& r = out.ref;
  r.com = lerp(com_.col(k), com_.col(k1));
  r.com_vel = lerp(com_vel_.col(k), com_vel_.col(k1));
  r.com_acc = lerp(com_acc_.col(k), com_acc_.col(k1));
  r.zmp = lerp(zmp_.col(k), zmp_.col(k1));
  r.zmp_vel = lerp(zmp_vel_.col(k), zmp_vel_.col(k1));
  r.zmp_wholebody = lerp(zmp_wb_.col(k), zmp_wb_.col(k1));
  r.zmp_wholebody_vel = lerp(zmp_wb_vel_.col(k), zmp_wb_vel_.col(k1));
  r.ground_z = 0.0;
  for (int f = 0; f < 2; ++f) {
    auto& fr = r.foot[static_cast<std::size_t>(f)];
    fr.contact = contact_[static_cast<std::size_t>(near)][static_cast<std::size_t>(f)];
    const Eigen::Quaterniond qa = quatAt(sole_pose_[f], k), qb = quatAt(sole_pose_[f], k1);
    fr.pose.setIdentity();
    fr.pose.linear() = qa.slerp(s, qb).toRotationMatrix();
    fr.pose.translation() = lerp(sole_pose_[f].col(k).head<3>(), sole_pose_[f].col(k1).head<3>());
    fr.wrench = fr.contact ? wrench_[f][static_cast<std::size_t>(near)]
                           : core::Wrench::zero(core::Axes::kSole);
  }
  const Eigen::Quaterniond ia(imu_quat_(0, k), imu_quat_(1, k), imu_quat_(2, k), imu_quat_(3, k));
  const Eigen::Quaterniond ib(imu_quat_(0, k1), imu_quat_(1, k1), imu_quat_(2, k1),
                              imu_quat_(3, k1));
  r.torso = ia.slerp(s, ib);
  out.imu_angular_velocity = lerp(imu_omega_.col(k), imu_omega_.col(k1));
  out.base_position = lerp(base_pos_.col(k), base_pos_.col(k1));
  out.zmp_wholebody = lerp(zmp_wb_.col(k), zmp_wb_.col(k1));
}

void PlanTrack::applyCorrections(const TrackSample& s, const stabilizer::Output& c,
                                 Eigen::VectorXd& q) const {
  const std::size_t k = static_cast<std::size_t>(s.index);
  // Base motion: shifted by the CoM offset, rotated by the posture correction (roll, pitch).
  const Eigen::Vector3d dpb = c.com_offset;
  const Eigen::Vector3d dthb(c.body_attitude.x(), c.body_attitude.y(), 0.0);
  for (int f = 0; f < 2; ++f) {
    const Eigen::Matrix3d Rs = s.ref.foot[static_cast<std::size_t>(f)].pose.linear();
    const Eigen::Vector2d& rot = c.foot_rotation[static_cast<std::size_t>(f)];
    const Eigen::Vector3d dths = Rs * Eigen::Vector3d(rot.x(), rot.y(), 0.0);
    const Eigen::Vector3d dps(0.0, 0.0, c.foot_height[static_cast<std::size_t>(f)]);
    core::Vector6d dx;
    dx.head<3>() = dths - dthb;
    dx.tail<3>() = dps + dths.cross(Eigen::Vector3d(sole_from_bushing_[f].col(s.index))) - dpb -
                   dthb.cross(Eigen::Vector3d(sole_from_base_[f].col(s.index)));
    const Eigen::Matrix<double, 6, 1> dq = leg_inv_[f][k] * dx;
    for (int i = 0; i < 6; ++i) q(leg_[std::size_t(f)][std::size_t(i)]) += dq(i);
  }
}

core::Wrench PlanTrack::soleWrench(int index, int f, const core::Wrench& ft) const {
  Eigen::Isometry3d X_WS = Eigen::Isometry3d::Identity();  // the sensor
  X_WS.linear() = quatAt(sensor_pose_[f], index).toRotationMatrix();
  X_WS.translation() = sensor_pose_[f].col(index).head<3>();
  core::Wrench w_W = ft.expressedIn(X_WS, core::Axes::kWorld);  // about the sensor origin
  // The sensor also carries the bodies below it: remove their (static) weight.
  const Eigen::Vector3d weight(0.0, 0.0, -below_mass_[f] * gravity_);
  w_W -=
      core::Wrench(weight, Eigen::Vector3d::Zero(), below_com_[f].col(index), core::Axes::kWorld);
  Eigen::Isometry3d X_WF = Eigen::Isometry3d::Identity();  // the sole
  X_WF.linear() = quatAt(sole_pose_[f], index).toRotationMatrix();
  X_WF.translation() = sole_pose_[f].col(index).head<3>();
  return w_W.inFrame(X_WF, core::Axes::kSole);
}

void PlanTrack::estimate(const TrackSample& s, const core::RobotState& st,
                         stabilizer::Measurement& out) const {
  const std::size_t k = static_cast<std::size_t>(s.index);
  // Sensor readings corrected by the model's calibration (an identified bias and scale).
  out.foot_wrench[0] = soleWrench(s.index, 0, ft_[0].calibrated(st.ft_right));
  out.foot_wrench[1] = soleWrench(s.index, 1, ft_[1].calibrated(st.ft_left));
  for (int f = 0; f < 2; ++f)
    out.foot_pose[static_cast<std::size_t>(f)] = s.ref.foot[static_cast<std::size_t>(f)].pose;
  out.torso = st.imu_orientation;
  // Stance weights: the planned normal forces of the feet in contact.
  double w[2] = {0.0, 0.0};
  for (int f = 0; f < 2; ++f)
    if (s.ref.foot[std::size_t(f)].contact)
      w[f] = std::max(s.ref.foot[std::size_t(f)].wrench.force.z(), 1e-3);
  const double wsum = w[0] + w[1];
  // Body rotation beyond the plan, seen by the IMU (heading ignored).
  const Eigen::Vector3d dth = tiltVector(st.imu_orientation * s.ref.torso.conjugate());
  const Eigen::Vector3d om_w = st.imu_orientation * st.imu_angular_velocity;
  Eigen::Vector3d dom = om_w - s.imu_angular_velocity;
  dom.z() = 0.0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero(), cv = Eigen::Vector3d::Zero();
  for (int f = 0; f < 2; ++f) {
    if (w[f] <= 0.0) continue;
    const auto& J = com_jac_[f][k];
    const Eigen::Vector3d p = s.ref.foot[std::size_t(f)].pose.translation();
    Eigen::Vector3d cf = s.ref.com;
    Eigen::Vector3d vf = s.ref.com_vel;
    for (int j = 0; j < joints_; ++j) {
      cf += J.col(j) * (st.q(j) - s.q(j));
      vf += J.col(j) * (st.qd(j) - s.qd(j));
    }
    cf += dth.cross(cf - p);
    vf += dom.cross(cf - p);
    c += (w[f] / wsum) * cf;
    cv += (w[f] / wsum) * vf;
  }
  out.com = c;
  out.com_vel = cv;
}

}  // namespace overstep::runtime
