#pragma once
/// \file
/// The plan: the planner -> runtime / checker contract, and its file format (JSON, versioned,
/// documented in docs/plan-format.md). Samples are dense at `rate` Hz from t = 0 to the duration.
/// Coordinates follow the robot's model order [base 6 | actuated | elastic]. The planned contact
/// wrenches are read and written as core::Wrench (world axes, about each sole origin) through
/// Plan::wrench() and Plan::setWrench(); the file stores them force first, [fx fy fz mx my mz],
/// like the sensors.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "overstep/core/obstacle.hpp"
#include "overstep/core/wrench.hpp"

namespace overstep::core {

struct PlanPhase {
  std::string name;
  double start = 0.0;     ///< s
  double duration = 0.0;  ///< s
  bool right_contact = true;
  bool left_contact = true;
};

struct Plan {
  /// 2: `tau` holds the actuator torques of the robot in contact (inverse dynamics minus the
  /// feet's J^T f); version 1 files held the torques of the robot hanging from its pelvis and
  /// are refused.
  static constexpr int kFormatVersion = 2;
  /// Bounds of a trustworthy plan: a motion of at most kMaxDuration s sampled at most at
  /// kMaxRate Hz (the check's grid, at most the same rate, then has at most 6e6 points).
  static constexpr double kMaxDuration = 600.0;  ///< s
  static constexpr double kMaxRate = 10000.0;    ///< Hz

  std::string robot_name;
  std::string robot_file;
  std::string robot_hash;  ///< RobotDescription::hashHex() of the model that planned it
  ObstacleSpec obstacle;
  double toes_x = 0.0;             ///< x of the start toes (the obstacle's gap is measured from it)
  std::string config_json = "{}";  ///< the planner configuration used (JSON object text)
  std::string summary_json = "{}";  ///< the planner's summary (JSON object text)
  std::vector<PlanPhase> phases;
  double rate = 200.0;  ///< Hz of the samples
  std::vector<std::string> coordinates;

  Eigen::VectorXd t;              ///< N sample times, s
  Eigen::VectorXi phase;          ///< N phase indices
  Eigen::MatrixXd q;              ///< dofs x N positions
  Eigen::MatrixXd v;              ///< dofs x N velocities
  Eigen::MatrixXd a;              ///< dofs x N accelerations
  Eigen::MatrixXd tau;            ///< actuated x N actuator torques (robot in contact), N m
  Eigen::MatrixXd com;            ///< 3 x N, m
  Eigen::MatrixXd zmp_wholebody;  ///< 2 x N, m
  Eigen::MatrixXd zmp_tablecart;  ///< 2 x N, m
  Eigen::MatrixXd right_foot;     ///< 7 x N sole-frame pose [x y z qw qx qy qz]
  Eigen::MatrixXd left_foot;      ///< 7 x N
  /// 6 x N spatial columns [moment; force] (world axes, about the sole origin): the storage
  /// behind wrench() and setWrench().
  Eigen::MatrixXd right_wrench;
  Eigen::MatrixXd left_wrench;  ///< 6 x N, as right_wrench

  int samples() const { return static_cast<int>(t.size()); }
  /// Foot `foot`'s (0 right, 1 left) planned contact wrench at sample k: world axes, about the
  /// foot's sole origin at that sample.
  Wrench wrench(int foot, int k) const;
  /// Sets it (any reference point; stored about the sole origin of sample k, so set the feet's
  /// poses first).
  void setWrench(int foot, int k, const Wrench& w);
  /// The sample nearest to time `t` (clamped to the plan). The samples are not evenly spaced: a
  /// phase switch adds its own time off the grid, once per phase (1 us apart), so round(t * rate)
  /// falls behind by two or three samples per switch. At a switch the sample of `phase` is taken
  /// when given (>= 0), else the later one. -1 for an empty plan.
  int sampleAt(double t, int phase = -1) const;
  double duration() const { return t.size() ? t(t.size() - 1) : 0.0; }
  /// Resizes every sample array for n samples of `dofs` coordinates, `actuated` joints.
  void resize(int n, int dofs, int actuated);
};

/// Throws InputError "where: key: expected ..., got ..." unless the plan's layout can be trusted:
/// rate in (0, kMaxRate], at least 2 samples and every array as long, times from 0, finite,
/// strictly increasing, at most 1 / rate apart (the samples are at k / rate plus the phase
/// boundaries), duration <= kMaxDuration, phases with start and duration in [0, kMaxDuration],
/// phase indices in range, unit foot quaternions, a valid obstacle (core::validate).
void validatePlan(const Plan& plan, const std::string& where);

/// Writes the plan atomically (temporary file in the same directory, then rename).
void savePlan(const Plan& plan, const std::string& path);
/// Reads and validates a plan file (JSON nested at most 16 deep, format, version, types, array
/// sizes, finite values within physical bounds, then validatePlan). InputError on any problem,
/// one line naming the file and the field.
Plan loadPlan(const std::string& path);

/// Writes `text` to `path` atomically: a temporary file beside it, flushed, then renamed over.
/// Nothing is left half-written; throws InputError naming the path when it cannot write.
void writeFileAtomic(const std::string& path, const std::string& text);

}  // namespace overstep::core
