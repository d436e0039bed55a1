#include "overstep/planner/spline.hpp"

#include <algorithm>
#include <unsupported/Eigen/Splines>

#include "overstep/core/error.hpp"

namespace overstep::planner {

namespace {

template <int Degree>
PhaseSpline::Basis basisOf(const Eigen::Spline<double, 1, Degree>& s, double u) {
  PhaseSpline::Basis b;
  b.first = static_cast<int>(s.span(u)) - Degree;
  const auto ders = s.template basisFunctionDerivatives<2>(u, 2);
  b.value.resize(Degree + 1);
  b.d1.resize(Degree + 1);
  b.d2.resize(Degree + 1);
  for (int j = 0; j <= Degree; ++j) {
    b.value(j) = ders(0, j);
    b.d1(j) = ders(1, j);
    b.d2(j) = ders(2, j);
  }
  return b;
}

template <int Degree>
Eigen::Spline<double, 1, Degree> splineOver(const Eigen::ArrayXd& knots) {
  using S = Eigen::Spline<double, 1, Degree>;
  const typename S::KnotVectorType kv = knots.transpose();
  const typename S::ControlPointVectorType ctrl =
      S::ControlPointVectorType::Zero(1, knots.size() - Degree - 1);
  return S(kv, ctrl);
}

}  // namespace

PhaseSpline::PhaseSpline(const std::array<int, kPhaseCount>& intervals, int degree)
    : intervals_(intervals), degree_(degree) {
  if (degree != 3 && degree != 5) throw InputError("spline: degree must be 3 or 5");
  for (int n : intervals) {
    if (n < 1) throw InputError("spline: expected >= 1 knot span per phase");
    spans_ += n;
  }
  Eigen::VectorXd unit = Eigen::VectorXd::Ones(kPhaseCount);
  setTiming(PhaseTiming(unit));
}

void PhaseSpline::setTiming(const PhaseTiming& timing) {
  knots_.resize(spans_ + 1 + 2 * degree_);
  int k = 0;
  for (int r = 0; r < degree_; ++r) knots_(k++) = 0.0;
  for (int i = 0; i < kPhaseCount; ++i) {
    const int n = intervals_[static_cast<std::size_t>(i)];
    for (int j = 0; j < n; ++j) knots_(k++) = timing.timeOf(i, static_cast<double>(j) / n);
  }
  t_end_ = timing.total();
  for (int r = 0; r <= degree_; ++r) knots_(k++) = t_end_;
  if (degree_ == 3)
    cubic_ = splineOver<3>(knots_);
  else
    quintic_ = splineOver<5>(knots_);
}

PhaseSpline::Basis PhaseSpline::evaluate(double t) const {
  const double u = std::clamp(t, 0.0, t_end_);
  return degree_ == 3 ? basisOf(cubic_, u) : basisOf(quintic_, u);
}

void PhaseSpline::evaluate(const Eigen::MatrixXd& ctrl, double t, Eigen::VectorXd* x,
                           Eigen::VectorXd* xd, Eigen::VectorXd* xdd) const {
  const Basis b = evaluate(t);
  const auto block = ctrl.middleCols(b.first, degree_ + 1);
  if (x) *x = block * b.value;
  if (xd) *xd = block * b.d1;
  if (xdd) *xdd = block * b.d2;
}

}  // namespace overstep::planner
