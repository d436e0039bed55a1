#include "overstep/planner/phases.hpp"

#include <cmath>
#include <cstdio>

#include "overstep/core/error.hpp"

namespace overstep::planner {

const std::array<PhaseInfo, kPhaseCount>& phaseTable() {
  static const std::array<PhaseInfo, kPhaseCount> table = {{
      {"ds_start", true, true, Foot::Left},
      {"ss_right_swing", false, true, Foot::Left},
      {"ds_transfer", true, true, Foot::Right},
      {"ss_left_swing", true, false, Foot::Right},
      {"ds_end", true, true, Foot::Right},
  }};
  return table;
}

PhaseTiming::PhaseTiming(const Eigen::VectorXd& durations) : durations_(durations) {
  if (durations.size() != kPhaseCount) {
    throw InputError("phase durations: expected " + std::to_string(kPhaseCount) + " values, got " +
                     std::to_string(durations.size()));
  }
  starts_.setZero(kPhaseCount + 1);
  for (int i = 0; i < kPhaseCount; ++i) {
    if (!std::isfinite(durations(i)) || !(durations(i) > 0.0)) {
      char b[96];
      std::snprintf(b, sizeof b, "phase %s duration: expected > 0 s, got %g", phaseTable()[i].name,
                    durations(i));
      throw InputError(b);
    }
    starts_(i + 1) = starts_(i) + durations(i);
  }
}

GridPoint PhaseTiming::locate(double t) const {
  GridPoint g;
  if (!(t > 0.0)) {
    g.t = 0.0;
    return g;
  }
  if (t >= total()) {
    g.phase = kPhaseCount - 1;
    g.s = 1.0;
    g.t = total();
    return g;
  }
  int i = 0;
  while (i + 1 < kPhaseCount && t >= starts_(i + 1)) ++i;
  g.phase = i;
  g.s = (t - starts_(i)) / durations_(i);
  g.t = t;
  return g;
}

Eigen::VectorXd PhaseTiming::timeGradient(int phase, double s) const {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(kPhaseCount);
  g.head(phase).setOnes();
  g(phase) = s;
  return g;
}

std::vector<GridPoint> PhaseTiming::grid(const std::array<int, kPhaseCount>& per_phase) const {
  std::vector<GridPoint> out;
  for (int i = 0; i < kPhaseCount; ++i) {
    const int n = per_phase[static_cast<std::size_t>(i)];
    if (n < 1) throw InputError("phase grid: expected >= 1 point per phase");
    for (int k = 0; k < n; ++k) {
      const double s = static_cast<double>(k) / n;
      out.push_back({i, s, timeOf(i, s)});
    }
  }
  out.push_back({kPhaseCount - 1, 1.0, total()});
  return out;
}

}  // namespace overstep::planner
