#include "overstep/stabilizer/stabilizer.hpp"

#include <algorithm>
#include <cmath>

#include "overstep/core/error.hpp"
#include "overstep/core/rotation.hpp"

namespace overstep::stabilizer {
namespace {

template <int R, int C>
bool finiteFixed(const Eigen::Matrix<double, R, C>& m) {
  return m.allFinite();
}

bool finitePose(const Eigen::Isometry3d& X) { return X.matrix().allFinite(); }

bool finiteQuat(const Eigen::Quaterniond& q) {
  return q.coeffs().allFinite() && std::abs(q.norm() - 1.0) < 0.1;
}

/// Roll and pitch (x-y-z fixed-axis convention) of a world orientation.
Eigen::Vector2d rollPitch(const Eigen::Quaterniond& q) {
  return core::rollPitch(q.normalized().toRotationMatrix());
}

/// C1 ramp 0 -> 1.
double smooth(double r) {
  r = std::clamp(r, 0.0, 1.0);
  return r * r * (3.0 - 2.0 * r);
}

/// Integrates x' = rate with |rate| <= max_rate and |x| <= max_x; sets flags on saturation.
double integrateClamped(double x, double rate, double dt, double max_rate, double max_x,
                        std::uint32_t& flags, std::uint32_t rate_flag, std::uint32_t value_flag) {
  if (rate_flag != 0 && std::abs(rate) > max_rate) {
    rate = std::copysign(max_rate, rate);
    flags |= rate_flag;
  }
  x += rate * dt;
  if (std::abs(x) > max_x) {
    x = std::copysign(max_x, x);
    flags |= value_flag;
  }
  return x;
}

void scaleInto(const Output& raw, double s, Output& out) {
  out.com_offset = s * raw.com_offset;
  for (std::size_t f = 0; f < 2; ++f) {
    out.foot_rotation[f] = s * raw.foot_rotation[f];
    out.foot_height[f] = s * raw.foot_height[f];
    out.landing_height[f] = s * raw.landing_height[f];
  }
  out.body_attitude = s * raw.body_attitude;
}

}  // namespace

const char* toString(Mode m) {
  switch (m) {
    case Mode::Off:
      return "off";
    case Mode::RampIn:
      return "ramp_in";
    case Mode::On:
      return "on";
    case Mode::RampOut:
      return "ramp_out";
    case Mode::Hold:
      return "hold";
  }
  return "?";
}

const char* toString(Fault f) {
  switch (f) {
    case Fault::None:
      return "none";
    case Fault::NonFiniteReference:
      return "non-finite reference";
    case Fault::NonFiniteMeasurement:
      return "non-finite or invalid measurement";
    case Fault::BadTimeStep:
      return "time step out of range";
    case Fault::ComErrorTooLarge:
      return "CoM error too large";
    case Fault::TorsoTiltTooLarge:
      return "torso tilt too large";
    case Fault::NoSupport:
      return "reference has no foot in contact";
  }
  return "?";
}

Stabilizer::Stabilizer(const Params& params) : params_(params) {
  const std::string err = validate(params);
  if (!err.empty()) throw InputError(err);
  reset();
}

bool Stabilizer::configure(const Params& params) {
  if (status_.mode != Mode::Off && status_.mode != Mode::Hold) return false;
  if (!validate(params).empty()) return false;
  params_ = params;
  return true;
}

void Stabilizer::reset() {
  status_ = Status{};
  ramp_ = 0.0;
  raw_ = Output{};
  held_ = Output{};
  last_ = Output{};
  dcm_integral_.setZero();
  com_offset_vel_.setZero();
  from_hold_ = false;
  swung_ = {false, false};
  found_ = {false, false};
  since_touchdown_ = {0.0, 0.0};
}

bool Stabilizer::enable() {
  if (status_.fault != Fault::None) return false;
  switch (status_.mode) {
    case Mode::Off:
      raw_ = Output{};
      dcm_integral_.setZero();
      com_offset_vel_.setZero();
      ramp_ = 0.0;
      status_.mode = Mode::RampIn;
      return true;
    case Mode::RampOut:
      if (from_hold_) return false;  // the frozen output has no live controller behind it
      status_.mode = Mode::RampIn;
      return true;
    case Mode::Hold:
      status_.mode = ramp_ >= 1.0 ? Mode::On : Mode::RampIn;
      return true;
    case Mode::RampIn:
    case Mode::On:
      return true;
  }
  return false;
}

void Stabilizer::disable() {
  switch (status_.mode) {
    case Mode::Hold:
      held_ = last_;
      ramp_ = 1.0;
      from_hold_ = true;
      status_.mode = Mode::RampOut;
      break;
    case Mode::RampIn:
    case Mode::On:
      status_.mode = Mode::RampOut;
      break;
    case Mode::Off:
    case Mode::RampOut:
      break;
  }
}

void Stabilizer::hold() {
  if (status_.mode == Mode::Off || status_.mode == Mode::Hold) {
    if (status_.mode == Mode::Off) held_ = Output{};
    status_.mode = Mode::Hold;
    return;
  }
  held_ = last_;
  status_.mode = Mode::Hold;
}

void Stabilizer::enterHold(Fault f) {
  status_.fault = f;
  if (status_.mode != Mode::Hold) {
    held_ = last_;
    status_.mode = Mode::Hold;
  }
  from_hold_ = false;
}

Fault Stabilizer::validateInputs(const Measurement& m, double dt) const {
  if (!(dt > 0.0 && dt <= params_.max_dt)) return Fault::BadTimeStep;
  const Reference& r = ref_;
  bool ok = finiteFixed(r.com) && finiteFixed(r.com_vel) && finiteFixed(r.com_acc) &&
            finiteFixed(r.zmp) && finiteFixed(r.zmp_vel) && finiteFixed(r.zmp_wholebody) &&
            finiteFixed(r.zmp_wholebody_vel) && std::isfinite(r.ground_z) && finiteQuat(r.torso) &&
            r.com.z() - r.ground_z > 0.05;
  for (const auto& f : r.foot) ok = ok && finitePose(f.pose) && f.wrench.allFinite();
  if (!ok) return Fault::NonFiniteReference;
  if (!r.foot[0].contact && !r.foot[1].contact) return Fault::NoSupport;
  bool mok = finiteFixed(m.com) && finiteFixed(m.com_vel) && finiteQuat(m.torso);
  for (std::size_t f = 0; f < 2; ++f)
    mok = mok && m.foot_wrench[f].allFinite() && finitePose(m.foot_pose[f]);
  if (!mok) return Fault::NonFiniteMeasurement;
  if ((m.com - r.com).head<2>().norm() > params_.max_com_error) return Fault::ComErrorTooLarge;
  const Eigen::Vector3d z = m.torso.normalized() * Eigen::Vector3d::UnitZ();
  if (std::acos(std::clamp(z.z(), -1.0, 1.0)) > params_.max_torso_tilt)
    return Fault::TorsoTiltTooLarge;
  return Fault::None;
}

void Stabilizer::landing(const std::array<double, 2>& fz, double dt, Output& o) {
  const Params& p = params_;
  for (std::size_t f = 0; f < 2; ++f) {
    const bool contact = ref_.foot[f].contact;
    const bool loaded = fz[f] > p.contact_force;
    if (!contact) {
      swung_[f] = true;
      found_[f] = false;
      since_touchdown_[f] = 0.0;
    } else {
      since_touchdown_[f] += dt;
    }
    // The landing window: after a touchdown of the reference, until the sole first carries load
    // (at most landing_time).
    const bool window = contact && swung_[f] && since_touchdown_[f] <= p.landing_time;
    if (window && loaded) found_[f] = true;
    double rate = -o.landing_height[f] / p.landing_time_constant;
    if (p.landing_damping > 0.0) {
      if (window && !found_[f]) {
        // Late: lowered onto the ground at the rate its planned force asks for.
        const double fz_d = std::max(o.distribution.wrench[f].force.z(), p.contact_force);
        rate = -fz_d / p.landing_damping;
      } else if (!contact && loaded) {
        // Early (the reference has the foot in the air): yields, its desired force being 0.
        rate += fz[f] / p.landing_damping;
      }
    }
    o.landing_height[f] =
        integrateClamped(o.landing_height[f], rate, dt, p.max_landing_rate, p.max_foot_height,
                         status_.saturation, kFootHeight, kFootHeight);
    o.landing_height[f] = std::max(o.landing_height[f], -p.landing_search_depth);
  }
}

void Stabilizer::runFeedback(const Measurement& m, double dt, Output& o) {
  const Params& p = params_;
  const Reference& r = ref_;
  std::uint32_t& sat = status_.saturation;
  const double h = r.com.z() - r.ground_z;
  const double omega = std::sqrt(p.gravity / h);

  // Measured ZMP from the foot wrenches.
  core::Wrench w_sum = core::Wrench::zero(core::Axes::kWorld);  // about the world origin
  std::array<double, 2> fz{{0.0, 0.0}};
  for (std::size_t f = 0; f < 2; ++f) {
    fz[f] = m.foot_wrench[f].force.z();
    if (fz[f] > 0.0) w_sum += m.foot_wrench[f].expressedIn(m.foot_pose[f], core::Axes::kWorld);
  }
  const bool whole_body = p.zmp_reference == ZmpReference::WholeBody;
  const Eigen::Vector2d& zmp_ref = whole_body ? r.zmp_wholebody : r.zmp;
  const Eigen::Vector2d& zmp_ref_vel = whole_body ? r.zmp_wholebody_vel : r.zmp_vel;
  o.zmp_reference = zmp_ref;
  const bool have_zmp = w_sum.force.z() > p.contact_force;
  o.zmp_measured = have_zmp ? core::zmpFromWrench(w_sum, r.ground_z) : zmp_ref;
  if (!have_zmp) sat |= kNoMeasuredZmp;

  o.com_error = (m.com - r.com).head<2>();
  o.com_vel_error = (m.com_vel - r.com_vel).head<2>();
  o.zmp_error = o.zmp_measured - zmp_ref;
  o.dcm_error = o.com_error + o.com_vel_error / omega;

  // 1. CoM feedback -> desired ZMP.
  Eigen::Vector2d u;
  if (p.feedback == Feedback::Lipm) {
    o.gains = gainsFromPoles(p.lipm_poles, omega, p.zmp_delay);
    u = zmp_ref + p.zmp_feedforward * p.zmp_delay * zmp_ref_vel + o.gains[0] * o.com_error +
        o.gains[1] * o.com_vel_error + o.gains[2] * o.zmp_error;
  } else {
    dcm_integral_ += (o.dcm_error - dcm_integral_ / p.dcm_integral_time) * dt;
    o.gains = {1.0 + p.dcm_kp / omega, p.dcm_ki / omega, 0.0};
    u = zmp_ref + p.zmp_feedforward * p.zmp_delay * zmp_ref_vel + o.gains[0] * o.dcm_error +
        o.gains[1] * dcm_integral_;
  }

  // 2. Distribution over the measured feet with the plan's force share as the preference.
  const std::array<bool, 2> contact{{r.foot[0].contact, r.foot[1].contact}};
  const double fr = std::max(r.foot[0].wrench.force.z(), 0.0);
  const double fl = std::max(r.foot[1].wrench.force.z(), 0.0);
  const double alpha_pref = fr + fl > 1e-6 ? fr / (fr + fl) : 0.5;
  const Eigen::Vector3d force = p.mass * (r.com_acc + Eigen::Vector3d(0.0, 0.0, p.gravity));
  const double mz = r.foot[0].wrench.moment.z() + r.foot[1].wrench.moment.z();
  o.distribution = distributeWrench(u, force, mz, contact, m.foot_pose, p.sole, p.cop_margin,
                                    p.min_ds_force, alpha_pref);
  o.zmp_desired = o.distribution.zmp;
  if (o.distribution.clamped) sat |= kZmpClamped;

  // 3. Foot damping: each loaded foot rotates until its measured moment is the desired one.
  for (std::size_t f = 0; f < 2; ++f) {
    const bool loaded = contact[f] && fz[f] > p.contact_force;
    Eigen::Vector2d& th = o.foot_rotation[f];
    for (int a = 0; a < 2; ++a) {
      const double D = a == 0 ? p.damping_roll : p.damping_pitch;
      const double rate =
          loaded ? (m.foot_wrench[f].moment(a) - o.distribution.wrench[f].moment(a)) / D -
                       th(a) / p.damping_time_constant
                 : -th(a) / p.swing_time_constant;
      th(a) = integrateClamped(th(a), rate, dt, p.max_foot_rotation_rate, p.max_foot_rotation, sat,
                               kFootRotationRate, kFootRotation);
    }
  }

  // 4. Foot force difference (double support): z = height of the left foot minus the right one
  // (the landing offsets, below, are kept apart).
  double z = (o.foot_height[1] - o.landing_height[1]) - (o.foot_height[0] - o.landing_height[0]);
  double zrate = -z / p.force_difference_time_constant;
  if (contact[0] && contact[1] && fz[0] > p.contact_force && fz[1] > p.contact_force) {
    const double dF = fz[1] - fz[0];
    const double dF_d = o.distribution.wrench[1].force.z() - o.distribution.wrench[0].force.z();
    zrate += p.force_difference_gain * (dF - dF_d);
  }
  z = integrateClamped(z, zrate, dt, 0.0, 2.0 * p.max_foot_height, sat, 0, kFootHeight);
  landing(fz, dt, o);
  o.foot_height = {-0.5 * z + o.landing_height[0], 0.5 * z + o.landing_height[1]};

  // 5. Body posture from the IMU.
  const Eigen::Vector2d att_err = rollPitch(r.torso) - rollPitch(m.torso);
  for (int a = 0; a < 2; ++a) {
    const double rate = p.posture_gain * att_err(a) - o.body_attitude(a) / p.posture_time_constant;
    o.body_attitude(a) = integrateClamped(o.body_attitude(a), rate, dt, 0.0, p.max_body_attitude,
                                          sat, 0, kBodyAttitude);
  }

  // 6. CoM admittance: accelerate the CoM against the ZMP tracking error (leaky double integral).
  if (p.com_admittance > 0.0 && have_zmp) {
    const Eigen::Vector2d acc = -p.com_admittance * (o.zmp_desired - o.zmp_measured);
    com_offset_vel_ += (acc - com_offset_vel_ / p.com_leak_time) * dt;
  } else {
    com_offset_vel_ -= com_offset_vel_ * std::min(dt / p.com_leak_time, 1.0);
  }
  Eigen::Vector2d c =
      o.com_offset.head<2>() + (com_offset_vel_ - o.com_offset.head<2>() / p.com_leak_time) * dt;
  if (c.norm() > p.max_com_offset) {
    c *= p.max_com_offset / c.norm();
    com_offset_vel_.setZero();  // anti-windup
    sat |= kComOffset;
  }
  o.com_offset << c, 0.0;
}

Status Stabilizer::step(const Measurement& meas, double dt, Output& out) {
  status_.saturation = 0;
  if (status_.mode == Mode::Hold) {
    out = held_;
    out.ramp = smooth(ramp_);
    last_ = out;
    return status_;
  }
  if (from_hold_) {  // ramping a frozen output out: needs no inputs, survives bad ones
    const double h = dt > 0.0 && dt <= params_.max_dt ? dt : 0.0;
    ramp_ = std::max(0.0, ramp_ - h / params_.ramp_time);
    const double s = smooth(ramp_);
    out = held_;
    scaleInto(held_, s, out);
    out.ramp = s;
    if (ramp_ <= 0.0) {
      status_.mode = Mode::Off;
      from_hold_ = false;
      raw_ = Output{};
    }
    last_ = out;
    return status_;
  }
  const Fault f = validateInputs(meas, dt);
  if (status_.mode == Mode::Off) {  // not acting: zero output; a bad input is still reported
    if (f != Fault::None) status_.fault = f;
    out = Output{};
    last_ = out;
    return status_;
  }
  if (f != Fault::None) {
    enterHold(f);
    out = held_;
    last_ = out;
    return status_;
  }
  runFeedback(meas, dt, raw_);
  if (status_.mode == Mode::RampIn) {
    ramp_ = std::min(1.0, ramp_ + dt / params_.ramp_time);
    if (ramp_ >= 1.0) status_.mode = Mode::On;
  } else if (status_.mode == Mode::RampOut) {
    ramp_ = std::max(0.0, ramp_ - dt / params_.ramp_time);
  }
  const double scale = smooth(ramp_);
  out = raw_;
  scaleInto(raw_, scale, out);
  out.ramp = scale;
  if (status_.mode == Mode::RampOut && ramp_ <= 0.0) {
    status_.mode = Mode::Off;
    raw_ = Output{};
    dcm_integral_.setZero();
    com_offset_vel_.setZero();
  }
  last_ = out;
  return status_;
}

}  // namespace overstep::stabilizer
