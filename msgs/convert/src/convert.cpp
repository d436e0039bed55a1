#include "overstep/msgs/convert.hpp"

#include <cmath>
#include <cstdint>
#include <exception>

namespace overstep::msgs {
namespace {

void copyOut(const Eigen::VectorXd& v, std::vector<double>& out) {
  out.resize(static_cast<std::size_t>(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i) out[static_cast<std::size_t>(i)] = v(i);
}

bool finite(const std::vector<double>& v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

template <std::size_t N>
bool finite(const double (&v)[N]) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

bool fail(std::string* why, const char* msg) {
  if (why) *why = msg;
  return false;
}

std::int64_t bigEndian(const unsigned char* b, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | b[i];
  return static_cast<std::int64_t>(v);
}

/// `joints_at`: byte offset of num_joints (after the fingerprint and the int64 fields before it);
/// both types carry three joint arrays of doubles.
template <class T>
bool decodeWithJoints(const void* data, int size, int joints_at, T& out, std::string* why) {
  const auto* b = static_cast<const unsigned char*>(data);
  if (data == nullptr || size < joints_at + 4) return fail(why, "message too short");
  if (static_cast<std::uint64_t>(bigEndian(b, 8)) != static_cast<std::uint64_t>(T::getHash()))
    return fail(why, "not this message type (fingerprint)");
  const auto n = static_cast<std::int32_t>(bigEndian(b + joints_at, 4));
  if (n < 0 || std::int64_t{n} * 3 * 8 > size - joints_at - 4)
    return fail(why, "joint count does not fit the message");
  try {
    if (out.decode(data, 0, size) != size) return fail(why, "does not decode");
  } catch (const std::exception&) {
    return fail(why, "does not decode");
  }
  return true;
}

bool sizes(int n, int expected, std::size_t a, std::size_t b, std::size_t c, std::string* why) {
  if (n != expected) return fail(why, "wrong joint count");
  const auto un = static_cast<std::size_t>(n);
  if (a != un || b != un || c != un) return fail(why, "array length differs from num_joints");
  return true;
}

/// A sensor wrench about the sensor origin to the message's [Fx Fy Fz Mx My Mz], and back.
void wrenchOut(const core::Wrench& w, double (&out)[6]) {
  const core::Vector6d fm = w.about(Eigen::Vector3d::Zero()).forceMoment();
  for (int i = 0; i < 6; ++i) out[i] = fm(i);
}

core::Wrench wrenchIn(const double (&in)[6]) {
  return core::Wrench::fromForceMoment(Eigen::Map<const core::Vector6d>(in), core::Axes::kSensor);
}

}  // namespace

bool decodeChecked(const void* data, int size, overstep::robot_command_t& out, std::string* why) {
  return decodeWithJoints(data, size, 8 + 2 * 8, out, why);  // utime, seq
}

bool decodeChecked(const void* data, int size, overstep::robot_state_t& out, std::string* why) {
  return decodeWithJoints(data, size, 8 + 3 * 8, out, why);  // utime, seq, last_command_seq
}

void toLcm(const core::RobotCommand& in, overstep::robot_command_t& out) {
  out.utime = in.utime;
  out.seq = in.seq;
  out.num_joints = static_cast<int32_t>(in.q_ref.size());
  copyOut(in.q_ref, out.q_ref);
  copyOut(in.qd_ref, out.qd_ref);
  out.has_tau_ff = in.has_tau_ff;
  if (in.tau_ff.size() == in.q_ref.size()) {
    copyOut(in.tau_ff, out.tau_ff);
  } else {
    out.tau_ff.assign(static_cast<std::size_t>(out.num_joints), 0.0);
  }
}

bool fromLcm(const overstep::robot_command_t& in, int expected_joints, core::RobotCommand& out,
             std::string* why) {
  if (!sizes(in.num_joints, expected_joints, in.q_ref.size(), in.qd_ref.size(), in.tau_ff.size(),
             why))
    return false;
  if (!finite(in.q_ref) || !finite(in.qd_ref) || (in.has_tau_ff && !finite(in.tau_ff)))
    return fail(why, "non-finite value");
  out.utime = in.utime;
  out.seq = in.seq;
  out.q_ref = Eigen::Map<const Eigen::VectorXd>(in.q_ref.data(), in.num_joints);
  out.qd_ref = Eigen::Map<const Eigen::VectorXd>(in.qd_ref.data(), in.num_joints);
  out.has_tau_ff = in.has_tau_ff;
  out.tau_ff = Eigen::Map<const Eigen::VectorXd>(in.tau_ff.data(), in.num_joints);
  return true;
}

void toLcm(const core::RobotState& in, overstep::robot_state_t& out) {
  out.utime = in.utime;
  out.seq = in.seq;
  out.last_command_seq = in.last_command_seq;
  out.num_joints = static_cast<int32_t>(in.q.size());
  copyOut(in.q, out.q);
  copyOut(in.qd, out.qd);
  copyOut(in.tau, out.tau);
  wrenchOut(in.ft_right, out.ft_right);
  wrenchOut(in.ft_left, out.ft_left);
  const Eigen::Quaterniond& qi = in.imu_orientation;
  out.imu_quaternion[0] = qi.w();
  out.imu_quaternion[1] = qi.x();
  out.imu_quaternion[2] = qi.y();
  out.imu_quaternion[3] = qi.z();
  for (int i = 0; i < 3; ++i) {
    out.imu_angular_velocity[i] = in.imu_angular_velocity(i);
    out.imu_linear_acceleration[i] = in.imu_linear_acceleration(i);
    out.base_position[i] = in.base_pose.translation()(i);
    out.base_linear_velocity[i] = in.base_linear_velocity(i);
    out.base_angular_velocity[i] = in.base_angular_velocity(i);
  }
  out.has_ground_truth = in.has_ground_truth;
  const Eigen::Quaterniond qb(in.base_pose.linear());
  out.base_quaternion[0] = qb.w();
  out.base_quaternion[1] = qb.x();
  out.base_quaternion[2] = qb.y();
  out.base_quaternion[3] = qb.z();
}

bool fromLcm(const overstep::robot_state_t& in, int expected_joints, core::RobotState& out,
             std::string* why) {
  if (!sizes(in.num_joints, expected_joints, in.q.size(), in.qd.size(), in.tau.size(), why))
    return false;
  if (!finite(in.q) || !finite(in.qd) || !finite(in.tau) || !finite(in.ft_right) ||
      !finite(in.ft_left) || !finite(in.imu_quaternion) || !finite(in.imu_angular_velocity) ||
      !finite(in.imu_linear_acceleration))
    return fail(why, "non-finite value");
  if (in.has_ground_truth && (!finite(in.base_position) || !finite(in.base_quaternion)))
    return fail(why, "non-finite ground truth");
  const Eigen::Quaterniond qi(in.imu_quaternion[0], in.imu_quaternion[1], in.imu_quaternion[2],
                              in.imu_quaternion[3]);
  if (std::abs(qi.norm() - 1.0) > 1e-3) return fail(why, "IMU quaternion not unit");
  out.utime = in.utime;
  out.seq = in.seq;
  out.last_command_seq = in.last_command_seq;
  out.q = Eigen::Map<const Eigen::VectorXd>(in.q.data(), in.num_joints);
  out.qd = Eigen::Map<const Eigen::VectorXd>(in.qd.data(), in.num_joints);
  out.tau = Eigen::Map<const Eigen::VectorXd>(in.tau.data(), in.num_joints);
  out.ft_right = wrenchIn(in.ft_right);
  out.ft_left = wrenchIn(in.ft_left);
  out.imu_orientation = qi.normalized();
  for (int i = 0; i < 3; ++i) {
    out.imu_angular_velocity(i) = in.imu_angular_velocity[i];
    out.imu_linear_acceleration(i) = in.imu_linear_acceleration[i];
    out.base_linear_velocity(i) = in.base_linear_velocity[i];
    out.base_angular_velocity(i) = in.base_angular_velocity[i];
  }
  out.has_ground_truth = in.has_ground_truth;
  out.base_pose.setIdentity();
  out.base_pose.translation() << in.base_position[0], in.base_position[1], in.base_position[2];
  if (in.has_ground_truth) {
    out.base_pose.linear() = Eigen::Quaterniond(in.base_quaternion[0], in.base_quaternion[1],
                                                in.base_quaternion[2], in.base_quaternion[3])
                                 .normalized()
                                 .toRotationMatrix();
  }
  return true;
}

}  // namespace overstep::msgs
