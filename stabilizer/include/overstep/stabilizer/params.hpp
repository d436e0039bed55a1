#pragma once
/// \file
/// Stabilizer parameters: the `stabilizer:` section of the robot YAML plus the sole rectangles of
/// its `feet:` section. Every gain and output limit has a safety range (kParamTable) that the
/// loader and validate() enforce. Units: SI (m, s, rad, N, N m).

#include <array>
#include <string>

namespace overstep::stabilizer {

/// Which CoM feedback law turns CoM/ZMP errors into the desired ZMP.
enum class Feedback {
  Lipm,  ///< Kajita 2010: state feedback on CoM position, CoM velocity and ZMP error (ZMP lag
         ///< model)
  Dcm,   ///< Caron 2019: DCM proportional + leaky-integral feedback
};

/// Which of the plan's ZMPs the CoM feedback and the distributor aim at.
enum class ZmpReference {
  TableCart,  ///< the table-cart (LIPM) ZMP of the planned CoM motion (HRP-2's stabilizer)
  WholeBody,  ///< the plan's whole-body ZMP: its contact wrenches, with the centroidal angular
              ///< momentum the whole-body motion carries
};

/// A sole rectangle in its sole frame (x forward, y left), m.
struct Sole {
  double x_min = -0.10, x_max = 0.13, y_min = -0.075, y_max = 0.056;
};

struct Params {
  // ---- robot (filled by the caller from the model; not in the YAML section)
  double mass = 0.0;           ///< kg, total
  double gravity = 9.81;       ///< m/s^2
  std::array<Sole, 2> sole{};  ///< [right, left]

  // ---- CoM feedback
  Feedback feedback = Feedback::Lipm;
  ZmpReference zmp_reference = ZmpReference::TableCart;  ///< YAML: tablecart or wholebody
  double zmp_delay = 0.05;  ///< s, first-order lag of the realised ZMP behind the command (Tp)
  /// 1/s, closed-loop decay rates (-poles) of the CoM-ZMP-lag error dynamics for the LIPM law;
  /// the gains follow from the CoM height each tick (gainsFromPoles). The defaults give
  /// k = (1.41, 0.41, 0.08) at z = 0.8 m, close to hrpsys-base's 0.9 x (1.414, 0.404, 0.18).
  std::array<double, 3> lipm_poles{{2.5, 4.0, 12.0}};
  double dcm_kp = 4.0;              ///< 1/s, DCM proportional gain (Caron 2019: 4 for HRP-2Kai)
  double dcm_ki = 15.0;             ///< 1/s^2, gain of the leaky DCM error integral
  double dcm_integral_time = 10.0;  ///< s, leak time constant of the DCM error integral
  double zmp_feedforward = 1.0;     ///< 0..1, fraction of Tp * zmp_rate added to the ZMP command

  // ---- wrench distribution
  double cop_margin = 0.005;    ///< m, the desired CoPs stay this far inside the sole edges
  double min_ds_force = 15.0;   ///< N, least normal force per foot in double support
  double contact_force = 30.0;  ///< N, measured Fz above which a foot counts as loaded

  // ---- foot damping (ankle torque) control, per foot: d(theta)/dt = (M - M_d)/D - theta/T
  /// N m s/rad (D for the sole-frame x / y moment). On the flexible-ankle pendulum at 200 Hz
  /// (tests/unit/test_stabilizer.cpp) D = 30-120 is stable for bushings of 300-502 N m/rad and
  /// D <= 20 oscillates or drifts (measured); 60 sits in the middle, and 240 holds it too. The
  /// HRP-2 model uses 240: in the simulator (servo lag, the sensors' 5 ms window, the rubber
  /// contact) 60 left a 20-30 Hz limit cycle of 3 N m RMS in the stance moments (docs/runtime.md).
  double damping_roll = 60.0;
  double damping_pitch = 60.0;
  double damping_time_constant = 1.0;   ///< s (T), leak back to the reference
  double swing_time_constant = 0.1;     ///< s, return to zero while the foot is in the air
  double max_foot_rotation = 0.17;      ///< rad, |roll|, |pitch| correction (about 10 deg)
  double max_foot_rotation_rate = 0.5;  ///< rad/s

  // ---- foot force difference control: d(z)/dt = K ((F_L - F_R) - (F_L - F_R)_d) - z / T
  double force_difference_gain = 1.0e-4;        ///< m/(N s)
  double force_difference_time_constant = 1.0;  ///< s
  double max_foot_height = 0.02;                ///< m, |height offset| per foot

  // ---- landing (per foot, around each planned touchdown), height offset z (m, up):
  /// late (the reference has landed the foot, its sole carries no load yet): the foot is lowered,
  ///   dz/dt = -max(F_d, contact_force) / D, F_d its desired normal force, down to
  ///   -landing_search_depth, until the sole carries load (at most landing_time);
  /// early (the reference has the foot in the air, its sole carries load): it yields,
  ///   dz/dt = F_z / D - z / T;
  /// otherwise z returns to zero, dz/dt = -z / T. D in N s/m (0: off). Both ways a sole that
  /// meets the ground millimetres from the plan lands at its planned force instead of stamping
  /// or bouncing (docs/runtime.md).
  double landing_damping = 0.0;
  double landing_time = 0.5;            ///< s after the planned touchdown
  double landing_time_constant = 0.5;   ///< s (T)
  double max_landing_rate = 0.1;        ///< m/s (|z| itself within max_foot_height)
  double landing_search_depth = 0.015;  ///< m, deepest a late foot is lowered below the plan

  // ---- body posture control from the IMU: d(phi)/dt = K (ref - measured) - phi / T
  double posture_gain = 0.5;           ///< 1/s
  double posture_time_constant = 1.5;  ///< s
  double max_body_attitude = 0.1;      ///< rad, |roll|, |pitch|

  // ---- CoM admittance (0 = off): d2(dc)/dt2 = -A (zmp_desired - zmp_measured)
  double com_admittance = 0.0;   ///< 1/s^2
  double com_leak_time = 1.0;    ///< s
  double max_com_offset = 0.05;  ///< m

  // ---- modes and safety
  double ramp_time = 1.0;       ///< s, ramp-in / ramp-out duration
  double max_com_error = 0.10;  ///< m, larger horizontal CoM error -> fault + hold
  double max_torso_tilt = 0.5;  ///< rad, larger measured torso tilt -> fault + hold
  double max_dt = 0.05;         ///< s, longest tick accepted
};

/// One row of the parameter table: YAML key, field, safety range (inclusive).
struct ParamSpec {
  const char* key;
  double Params::*field;
  double min;
  double max;
  const char* unit;
};

/// The tunable numeric parameters with their safety ranges (lipm_poles and feedback aside).
const std::array<ParamSpec, 33>& paramTable();

/// Empty when every value is finite and inside its safety range and the soles are proper;
/// otherwise a one-line reason naming the parameter.
std::string validate(const Params& p);

/// Loads the `stabilizer:` section (optional keys; defaults above) and the feet's soles from a
/// robot YAML. Throws InputError with a one-line reason on a missing file, malformed YAML, an
/// unknown key or a value outside its safety range. mass is left at 0: the caller sets it from
/// the robot model before use.
Params loadParams(const std::string& robot_yaml);

/// LIPM feedback gains (k1, k2, k3) of zmp_cmd = zmp_ref + k1 dc + k2 dcd + k3 dzmp that place the
/// closed-loop poles of the CoM-ZMP-lag model (cdd = w^2 (c - p), pd = (zmp_cmd - p) / Tp) at
/// -lambda_i. omega = sqrt(g / z_com); Tp > 0.
std::array<double, 3> gainsFromPoles(const std::array<double, 3>& lambda, double omega, double tp);

}  // namespace overstep::stabilizer
