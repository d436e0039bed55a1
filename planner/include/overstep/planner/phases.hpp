#pragma once
/// \file
/// The seed's fixed phase sequence over the obstacle and its timing.
///
///   0 ds_start        both feet on the ground, unload the right foot (lift-off when its Fz = 0)
///   1 ss_right_swing  left stance, right foot swings over the obstacle; ends in touchdown
///   2 ds_transfer     short double support, unload the left foot
///   3 ss_left_swing   right stance, left foot swings over; ends in touchdown
///   4 ds_end          re-stabilisation to a static posture
///
/// Phase durations are decision variables; each phase is sampled on a fixed number of points in
/// normalized phase time, so sample times move with the durations.

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace overstep::planner {

enum class Foot { Right = 0, Left = 1 };

struct PhaseInfo {
  const char* name;
  bool right_contact;
  bool left_contact;
  Foot base_foot;  ///< the foot whose fixed pose places the floating base in this phase
};

constexpr int kPhaseCount = 5;
/// The phase table (contacts and which stance foot anchors the base).
const std::array<PhaseInfo, kPhaseCount>& phaseTable();

/// Sample of the time grid: phase index, normalized time in [0, 1] and absolute time.
struct GridPoint {
  int phase = 0;
  double s = 0.0;  ///< normalized time in the phase
  double t = 0.0;  ///< s since the start of the motion
  /// A mesh-refinement point (OverstepProblem's check_points): rows only, at the check's bounds.
  bool refinement = false;
};

class PhaseTiming {
 public:
  /// durations: one positive value per phase (s). Throws InputError otherwise.
  explicit PhaseTiming(const Eigen::VectorXd& durations);

  const Eigen::VectorXd& durations() const { return durations_; }
  double total() const { return starts_(kPhaseCount); }
  /// Start time of phase i (i = kPhaseCount gives the end time).
  double start(int i) const { return starts_(i); }
  /// The phase containing t (a boundary belongs to the later phase; t >= total gives the last)
  /// and the normalized time in it. t < 0 clamps to 0.
  GridPoint locate(double t) const;
  /// Absolute time of normalized time s in phase i.
  double timeOf(int phase, double s) const { return starts_(phase) + s * durations_(phase); }
  /// d t / d durations for a point at normalized s in phase i: 1 for earlier phases, s for its own.
  Eigen::VectorXd timeGradient(int phase, double s) const;

  /// Grid with `per_phase[i]` points in phase i at s = k / per_phase[i], k = 0..per_phase[i]-1,
  /// plus the final instant (s = 1 of the last phase).
  std::vector<GridPoint> grid(const std::array<int, kPhaseCount>& per_phase) const;

 private:
  Eigen::VectorXd durations_;
  Eigen::VectorXd starts_;
};

}  // namespace overstep::planner
