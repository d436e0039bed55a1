#include "overstep/sysid/dataset.hpp"

#include <algorithm>

namespace overstep::sysid {

void Dataset::add(double plan_t, const core::RobotCommand& cmd, const core::RobotState& before,
                  const core::RobotState& after) {
  Record r;
  r.t = static_cast<double>(after.utime) * 1e-6;
  r.plan_t = plan_t;
  r.q_ref = cmd.q_ref;
  r.qd_ref = cmd.qd_ref;
  r.q0 = before.q;
  r.q = after.q;
  r.qd = after.qd;
  r.tau = after.tau;
  r.ft[0] = after.ft_right;
  r.ft[1] = after.ft_left;
  r.imu = after.imu_orientation;
  r.gyro = after.imu_angular_velocity;
  r.accel = after.imu_linear_acceleration;
  records.push_back(std::move(r));
}

Dataset Dataset::slice(int begin, int end) const {
  Dataset d;
  d.period = period;
  begin = std::clamp(begin, 0, size());
  end = std::clamp(end, begin, size());
  d.records.assign(records.begin() + begin, records.begin() + end);
  return d;
}

}  // namespace overstep::sysid
