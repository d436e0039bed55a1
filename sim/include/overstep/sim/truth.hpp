#pragma once
/// \file
/// "Truth" effects: how the simulated robot differs from the model that the planner, runtime and
/// identification use. Read from a truth YAML (schema and units: docs/truth-file.md) by the
/// simulator only; nothing the simulator publishes reveals it.

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "overstep/core/robot_description.hpp"
#include "overstep/core/wrench.hpp"
#include "overstep/robots/whole_body_model.hpp"

namespace overstep::sim {

/// A point mass on a link (kg; offset m in the link frame), as in model overlays.
using Payload = core::PayloadDescription;

/// A bent link: the joint that carries `link` sits rotated on its parent by `rotation`
/// (rotation vector, rad): a kinematic error no identification candidate models.
struct Bend {
  std::string link;
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();
};

struct TruthEffects {
  /// Per elastic joint (model order): stiffness and damping actually simulated.
  std::vector<double> elastic_stiffness;  ///< N m/rad
  std::vector<double> elastic_damping;    ///< N m s/rad
  bool elastic_changed = false;           ///< an ankle entry differs from the model
  /// Per actuated joint (model order).
  Eigen::VectorXd viscous;   ///< N m s/rad, joint viscous friction
  Eigen::VectorXd coulomb;   ///< N m, joint Coulomb friction
  Eigen::VectorXd backlash;  ///< rad, total dead band between motor and joint
  std::vector<Payload> payloads;
  double command_delay = 0.0;  ///< s, pure delay of every command
  double command_lag = 0.0;    ///< s, first-order lag time constant of the servo references
  std::array<core::ForceSensorModel, 2> ft{};  ///< [right, left]
  std::vector<Bend> bends;

  /// True when nothing differs from the model.
  bool none() const;
  /// One line per effect, for logs of the simulator (never published).
  std::string describe() const;
};

/// The model's own values: no effect.
TruthEffects noTruthEffects(const robots::WholeBodyModel& model);

/// Loads a truth YAML against the model. Throws InputError (one line, naming the key) on a
/// missing or malformed file, an unknown key, joint, group or link, or a negative or non-finite
/// value (mass, stiffness, damping, friction, delay, lag, backlash) or a non-positive scale.
TruthEffects loadTruth(const std::string& path, const robots::WholeBodyModel& model);

}  // namespace overstep::sim
