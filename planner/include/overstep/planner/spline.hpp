#pragma once
/// \file
/// B-spline basis (cubic or quintic) whose knots move with the phase durations (the planner's
/// joint parametrization). Phase i is split into `intervals[i]` equal knot spans; the knot vector
/// is clamped at both ends, so the curve starts at the first control point and ends at the last.
/// A degree-p curve is C(p-1) everywhere, including across phase boundaries: cubic curves have
/// accelerations that are only continuous (kinks at the knots), quintic ones continuous jerk.
/// Basis functions come from Eigen's (unsupported) Splines module.
///
/// A trajectory is x(t) = sum_k B_k(t) c_k; its derivatives use dB_k/dt and d2B_k/dt2.

#include <Eigen/Core>
#include <array>
#include <unsupported/Eigen/Splines>

#include "overstep/planner/phases.hpp"

namespace overstep::planner {

class PhaseSpline {
 public:
  static constexpr int kMaxDegree = 5;
  using Coefficients = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxDegree + 1, 1>;

  /// intervals[i] >= 1 knot spans in phase i; degree 3 or 5. Throws InputError otherwise.
  explicit PhaseSpline(const std::array<int, kPhaseCount>& intervals, int degree = 3);

  int degree() const { return degree_; }
  int controlPointCount() const { return spans_ + degree_; }
  /// Rebuilds the knots for new phase durations.
  void setTiming(const PhaseTiming& timing);
  const Eigen::ArrayXd& knots() const { return knots_; }

  /// The degree + 1 non-zero basis functions at t: index of the first and value / first /
  /// second time derivative of each.
  struct Basis {
    int first = 0;
    Coefficients value, d1, d2;
  };
  Basis evaluate(double t) const;

  /// Evaluates a curve with control points as columns of `ctrl` (rows = dimensions).
  void evaluate(const Eigen::MatrixXd& ctrl, double t, Eigen::VectorXd* x, Eigen::VectorXd* xd,
                Eigen::VectorXd* xdd) const;

 private:
  std::array<int, kPhaseCount> intervals_;
  int spans_ = 0;
  int degree_ = 3;
  Eigen::ArrayXd knots_;
  double t_end_ = 0.0;
  // Eigen's splines over the knots (control points unused): the compile-time degree keeps the
  // basis evaluation off the heap.
  Eigen::Spline<double, 1, 3> cubic_;
  Eigen::Spline<double, 1, 5> quintic_;
};

}  // namespace overstep::planner
