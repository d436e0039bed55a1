#pragma once
/// \file
/// Cubic B-spline basis whose knots move with the phase durations (the planner's joint
/// parametrization). Phase i is split into `intervals[i]` equal knot spans; the knot vector is
/// clamped at both ends, so the curve starts at the first control point and ends at the last.
/// The curve is C2 everywhere, including across phase boundaries. Basis functions come from
/// Eigen's (unsupported) Splines module.
///
/// A trajectory is x(t) = sum_k B_k(t) c_k; its derivatives use dB_k/dt and d2B_k/dt2.

#include <Eigen/Core>
#include <array>

#include "overstep/planner/phases.hpp"

namespace overstep::planner {

class PhaseSpline {
 public:
  static constexpr int kDegree = 3;

  /// intervals[i] >= 1 knot spans in phase i. Throws InputError otherwise.
  explicit PhaseSpline(const std::array<int, kPhaseCount>& intervals);

  int controlPointCount() const { return spans_ + kDegree; }
  /// Rebuilds the knots for new phase durations.
  void setTiming(const PhaseTiming& timing);
  const Eigen::ArrayXd& knots() const { return knots_; }

  /// The (at most) 4 non-zero basis functions at t: index of the first and value / first /
  /// second time derivative of each.
  struct Basis {
    int first = 0;
    Eigen::Vector4d value = Eigen::Vector4d::Zero();
    Eigen::Vector4d d1 = Eigen::Vector4d::Zero();
    Eigen::Vector4d d2 = Eigen::Vector4d::Zero();
  };
  Basis evaluate(double t) const;

  /// Evaluates a curve with control points as columns of `ctrl` (rows = dimensions).
  void evaluate(const Eigen::MatrixXd& ctrl, double t, Eigen::VectorXd* x, Eigen::VectorXd* xd,
                Eigen::VectorXd* xdd) const;

 private:
  std::array<int, kPhaseCount> intervals_;
  int spans_ = 0;
  Eigen::ArrayXd knots_;
  double t_end_ = 0.0;
};

}  // namespace overstep::planner
