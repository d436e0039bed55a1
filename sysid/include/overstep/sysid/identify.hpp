#pragma once
/// \file
/// Residual -> candidate effect -> parameters (docs/identification.md). The model predicts, for
/// the commands that were sent, four measured channels: joint positions one control period
/// later (the servo model), motor torques of the moving joints (inverse dynamics of the measured
/// motion), and the ankle sensors' summed normal force and ground moment about the point between
/// the soles (the measured motion's contact wrench plus the weight below the sensors). Each
/// candidate effect is a block of regressor columns on the stacked, noise-normalised residual,
/// linear in its parameters; each is fitted on the first part of the run and scored on the rest
/// (held out).

#include <map>
#include <string>
#include <vector>

#include "overstep/core/plan.hpp"
#include "overstep/robots/whole_body_model.hpp"
#include "overstep/sysid/dataset.hpp"

namespace overstep::sysid {

struct IdentifyOptions {
  double train_fraction = 0.6;  ///< first part fits, the rest is held out
  /// The joint servo as the model knows it (the simulator's; hardware: its position loop):
  /// velocity gain Kv (1/s) at `servo_step` s, and the position stiffness against load torques.
  double servo_gain = 300.0, servo_step = 0.001, servo_stiffness = 3000.0;
  /// Where a payload candidate is attached ("": the link of the robot file's `torso` frame, else
  /// its base link).
  std::string payload_link;
  double moving_threshold = 0.01;  ///< rad, std of a joint's command for it to count as moving
  std::string dump_residuals;      ///< CSV path: every residual row (channel, joint, t, value)
  /// Channels besides the joint positions: motor torques of the moving joints off the legs, and
  /// the ground channels (the ankle sensors' summed normal force and tilting moments against the
  /// motion's contact wrench; at their noise floor on clean simulated data since the simulator's
  /// sensors filter over the control period, docs/identification.md).
  bool use_torque = true, use_force = true;
};

struct CandidateFit {
  std::string name;
  std::vector<std::string> parameter_names;
  std::vector<double> parameters, ci95;  ///< value and half-width of its 95 % interval
  double reduction = 0.0;  ///< held-out: 1 - RMS after / RMS before (normalised residual)
  double train_reduction = 0.0;
  double f_statistic = 0.0;   ///< partial F on the training part with an effective sample size
  bool plausible = true;      ///< signs and ranges physical, relative std < 30 %
  double held_out_rss = 0.0;  ///< sum of squares of the normalised held-out residual, all channels
  /// Against the winner: held-out RSS excess in noise units, corrected for correlation (> 10:
  /// distinguishable).
  double distinction = 0.0;
};

struct ChannelError {
  std::string unit;
  double rms_before = 0.0, rms_after = 0.0;  ///< held out, physical units
  double noise = 0.0;                        ///< estimated noise level, physical units
};

/// One residual row in physical units: before (the model as it is) and after the chosen effect.
struct ResidualRow {
  std::string channel, label;  ///< e.g. "joint_position", "RARM_JOINT0"; "ground_moment", "x"
  double t = 0.0;              ///< plan time, s (a window's start for the windowed channels)
  bool held_out = false;
  double before = 0.0, after = 0.0;
};

struct Identification {
  std::string verdict;                  ///< identified, ambiguous, none, unexplained
  std::string effect;                   ///< the winning candidate ("" for none / unexplained)
  std::vector<std::string> confusable;  ///< with ambiguous: every candidate that explains as much
  std::string runner_up;
  std::map<std::string, double> parameters, ci95;
  double error_before = 0.0, error_after = 0.0;  ///< held-out RMS of the normalised residual
  /// The same above the measurement noise, sqrt(max(RMS^2 - 1, 0)): the model error alone (an
  /// effect that is small against the noise cannot drop the raw RMS below ~1).
  double excess_before = 0.0, excess_after = 0.0;
  double whiteness = 0.0;  ///< lag-1 autocorrelation of the held-out residual before
  std::map<std::string, ChannelError> channels;
  std::vector<CandidateFit> candidates;  ///< best first
  std::vector<ResidualRow> residuals;    ///< every row (for plots and --residuals)
  std::string payload_link;              ///< the link the payload candidate is attached to
  int samples = 0, moving_joints = 0;
};

/// InputError when the data are too short (< 2 s) or do not match the model.
Identification identify(const Dataset& data, const core::Plan& plan,
                        const robots::WholeBodyModel& model, const IdentifyOptions& options = {});

}  // namespace overstep::sysid
