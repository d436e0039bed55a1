#include "overstep/sysid/identify.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "overstep/core/error.hpp"
#include "overstep/core/plan.hpp"
#include "overstep/core/rotation.hpp"
#include "overstep/robots/leg.hpp"

namespace overstep::sysid {
namespace {

struct Row {
  int channel = 0;  // 0 position, 1 torque, 2 force, 3 moment, 4 torso orientation
  int joint = -1;   // actuated index (position, torque); axis 0 = x, 1 = y (moment, orientation)
  int record = 0;
  int span = 1;  // records the row averages (from `record` on)
};

constexpr int kChannels = 5;
const char* const kChannelName[kChannels] = {"joint_position", "joint_torque", "force_sum",
                                             "ground_moment", "torso_orientation"};
const char* const kChannelUnit[kChannels] = {"rad", "N m", "N", "N m", "rad"};

using core::pitchOf;
using core::rollOf;
/// A channel whose held-out residual exceeds this many noise levels (RMS) shows an effect.
constexpr double kResidualLevel = 1.5;
constexpr double kGroundWindow = 0.05;  ///< s, averaging window of a ground-channel row
/// Bushing deflection = kBushingSign x (sensor moment about its axis) / stiffness.
constexpr double kBushingSign = 1.0;

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// Lag-1 autocorrelation of x over consecutive rows of the same signal.
double lag1(const Eigen::VectorXd& x, const std::vector<Row>& rows, const std::vector<int>& idx) {
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < idx.size(); ++i) {
    const double a = x(idx[i]);
    den += a * a;
    if (i + 1 < idx.size()) {
      const Row& r0 = rows[static_cast<std::size_t>(idx[i])];
      const Row& r1 = rows[static_cast<std::size_t>(idx[i + 1])];
      if (r0.channel == r1.channel && r0.joint == r1.joint && r1.record == r0.record + r0.span)
        num += a * x(idx[i + 1]);
    }
  }
  return den > 0.0 ? num / den : 0.0;
}

struct Candidate {
  Candidate() = default;
  Candidate(std::string n, std::vector<std::string> p, Eigen::MatrixXd x, std::vector<int> nn)
      : name(std::move(n)), params(std::move(p)), X(std::move(x)), nonneg(std::move(nn)) {}
  std::string name;
  std::vector<std::string> params;
  Eigen::MatrixXd X;        // rows x params, physical units
  std::vector<int> nonneg;  // parameters that must be >= 0 to be physical
  // A nonlinear parameter found by a scan on the training rows (X is built at its best value):
  // name, value and the half-width of its interval.
  std::string scanned;
  double scanned_value = 0.0, scanned_ci = 0.0;
};

/// The link a payload candidate sits on: the option, else the robot file's `torso` frame's link,
/// else the base link.
std::string payloadLink(const core::RobotDescription& d, const std::string& option) {
  if (!option.empty()) return option;
  for (const auto& f : d.frames)
    if (f.name == "torso") return f.link;
  return d.base_link;
}

}  // namespace

Identification identify(const Dataset& data, const core::Plan& plan,
                        const robots::WholeBodyModel& model_in, const IdentifyOptions& o) {
  const int N = data.size();
  if (N < 2 + static_cast<int>(2.0 / data.period))
    throw InputError("identify: " + std::to_string(N) + " ticks (" +
                     std::to_string(N * data.period) + " s) is too short: at least 2 s needed");
  robots::WholeBodyModel model(model_in);
  const auto& d = model.description();
  const int nA = model.actuatedCount();
  if (data.joints() != nA)
    throw InputError("identify: the data have " + std::to_string(data.joints()) +
                     " joints, the robot " + std::to_string(nA));
  if (plan.q.rows() != model.dofs()) throw InputError("identify: the plan is for another robot");

  // Moving joints: those whose command varies.
  std::vector<int> moving;
  for (int j = 0; j < nA; ++j) {
    double s = 0.0, s2 = 0.0;
    for (const auto& r : data.records) {
      s += r.q_ref(j);
      s2 += r.q_ref(j) * r.q_ref(j);
    }
    const double var = s2 / N - (s / N) * (s / N);
    if (std::sqrt(std::max(var, 0.0)) > o.moving_threshold) moving.push_back(j);
  }
  // The servo over one control period: the error to the (extrapolated) target decays by rho.
  const int steps = std::max(1, static_cast<int>(std::lround(data.period / o.servo_step)));
  const double rho = std::pow(1.0 - o.servo_gain * o.servo_step, steps);

  const int sensor_frame[2] = {model.frameIndex(d.foot("right")->force_sensor_frame),
                               model.frameIndex(d.foot("left")->force_sensor_frame)};
  const std::string payload_link = payloadLink(d, o.payload_link);
  if (!model.hasFrame(payload_link))
    throw InputError("identify: payload link '" + payload_link + "' is not in the model");
  const int payload_frame = model.frameIndex(payload_link);

  // ---- rows (channel-major, then joint, then time) and residuals
  // Torques only where inverse dynamics needs no contact force: joints off the legs (the
  // kinematic tree's chains from the base to the feet).
  std::vector<bool> on_leg(d.actuated.size(), false);
  for (const robots::LegChain& c : robots::legChains(model))
    for (int a : c.actuated) on_leg[static_cast<std::size_t>(a)] = true;
  auto offLeg = [&](int j) { return !on_leg[static_cast<std::size_t>(j)]; };
  std::vector<Row> rows;
  for (int ch = 0; ch < 2; ++ch)
    for (int j : moving)
      if (ch == 0 || (o.use_torque && offLeg(j)))
        for (int k = 1; k + 1 < N; ++k) rows.push_back({ch, j, k});
  // Ground rows average kGroundWindow s of records: the prediction differentiates measured
  // velocities (joint encoders, gyro) and is noisy per tick (measured on clean simulated data:
  // 20-30 N m of ground-moment noise per tick against 3 N m of signal), while the effects these
  // channels reveal (a payload, a sensor's bias or scale) are slow.
  const int gw = std::max(1, static_cast<int>(std::lround(kGroundWindow / data.period)));
  if (o.use_force) {
    for (int k = 1; k + gw < N; k += gw) rows.push_back({2, -1, k, gw});
    for (int axis = 0; axis < 2; ++axis)
      for (int k = 1; k + gw < N; k += gw) rows.push_back({3, axis, k, gw});
    // The torso's roll and pitch (IMU) against the kinematics of the encoders with the bushings
    // deflected by the sensors' moments over their stiffness and the stance soles flat.
    for (int axis = 0; axis < 2; ++axis)
      for (int k = 1; k + gw < N; k += gw) rows.push_back({4, axis, k, gw});
  }
  const int R = static_cast<int>(rows.size());
  Eigen::VectorXd res(R);
  // Per record: inverse-dynamics torques of the measured motion, payload torque regressors.
  std::vector<Eigen::VectorXd> tau_id(static_cast<std::size_t>(N));

  std::vector<Eigen::MatrixXd> pay(static_cast<std::size_t>(N));  // nA x 4
  const Eigen::Vector3d gvec(0.0, 0.0, d.gravity);
  const int imu_frame = model.frameIndex("imu");
  const int base_frame = model.frameIndex(d.base_link);
  const int soles[2] = {model.frameIndex(d.foot("right")->sole_frame),
                        model.frameIndex(d.foot("left")->sole_frame)};
  // Per record, in the world frame about the point between the soles: the sensors' summed
  // measured wrench, the model's prediction (the motion's contact wrench plus the weight of the
  // bodies below the sensors), and the lever arms the candidates need.
  struct Ground {
    Eigen::Vector3d F_meas, M_meas, F_pred, M_pred;
    Eigen::Vector3d sensor_p[2];  // sensor origins relative to the reference point
    Eigen::Matrix3d sensor_R[2];
    Eigen::Vector3d foot_force[2], foot_moment[2];        // each sensor's, moment about the point
    Eigen::Vector3d payload_p = Eigen::Vector3d::Zero();  // payload link origin, relative
    Eigen::Matrix3d payload_R = Eigen::Matrix3d::Identity();
    Eigen::Vector2d torso_meas = Eigen::Vector2d::Zero(), torso_pred = Eigen::Vector2d::Zero();
    /// d(torso roll, pitch) / d(compliance of the roll and pitch bushings): the moments they
    /// carry through the kinematics (columns: roll compliance, pitch compliance).
    Eigen::Matrix2d torso_dc = Eigen::Matrix2d::Zero();
    /// The same for a change of the bushings' damping (columns: roll, pitch): the damper takes
    /// delta' x more of the moment, delta' from the predicted deflection's rate.
    Eigen::Matrix2d torso_dd = Eigen::Matrix2d::Zero();
    /// The same for each foot's sensor: its scale (col. 0, per unit of scale - 1) and its tilting
    /// moment biases (col. 1 Mx, col. 2 My): they change the moments the prediction uses.
    Eigen::Matrix<double, 2, 3> torso_ft[2] = {Eigen::Matrix<double, 2, 3>::Zero(),
                                               Eigen::Matrix<double, 2, 3>::Zero()};
  };
  std::vector<Ground> ground(static_cast<std::size_t>(N));
  double spring[4] = {0.0, 0.0, 0.0, 0.0};  // bushing spring torques, N m (filtered moments)
  for (int k = 1; k + 1 < N; ++k) {
    const Record& r = data.records[static_cast<std::size_t>(k)];
    const int s = plan.sampleAt(r.plan_t);
    // The measured motion: joints from the encoders (accelerations by backward differences over the
    // period the motor torque is averaged on), the
    // elastic joints at the plan's, and the floating base from the IMU (orientation, gyro rate
    // and its derivative) with a stance sole that does not slide.
    Eigen::VectorXd q = plan.q.col(s), v = Eigen::VectorXd::Zero(model.dofs()), a = v;
    const Record& rp = data.records[static_cast<std::size_t>(k - 1)];
    for (int j = 0; j < nA; ++j) {
      const int c = model.actuatedCoordinate(j);
      q(c) = r.q(j);
      v(c) = r.qd(j);
      a(c) = (r.qd(j) - rp.qd(j)) / data.period;  // the motor torque is a period's average
    }
    model.setPositions(q);
    {
      const Eigen::Matrix3d R_imu = model.framePose(imu_frame).linear();
      Eigen::Isometry3d Xb = model.framePose(base_frame);
      Xb.linear() = r.imu.toRotationMatrix() * R_imu.transpose() * Xb.linear();
      Eigen::VectorXd v0 = v, a0 = a;
      model.anchorBase(base_frame, Xb, q, v0, a0);
    }
    const Eigen::Matrix3d R_w_imu = r.imu.toRotationMatrix();
    const Eigen::Vector3d w_now = R_w_imu * r.gyro;
    const Eigen::Vector3d alpha =
        (R_w_imu * r.gyro - rp.imu.toRotationMatrix() * rp.gyro) / data.period;
    const auto& ph = plan.phases[static_cast<std::size_t>(plan.phase(s))];
    const int stance = ph.left_contact ? soles[1] : soles[0];
    model.setState(q, v, Eigen::VectorXd::Zero(model.dofs()));
    Eigen::Matrix<double, 6, 6> Jb;
    Eigen::Matrix<double, 6, 1> rhs_v;
    {
      const Eigen::MatrixXd Ji = model.frameJacobian(imu_frame), Js = model.frameJacobian(stance);
      Jb.topRows<3>() = Ji.block(0, 0, 3, 6);
      Jb.bottomRows<3>() = Js.block(3, 0, 3, 6);
      Eigen::VectorXd vnb = v;
      vnb.head<6>().setZero();
      rhs_v.head<3>() = w_now - Ji.topRows<3>() * vnb;
      rhs_v.tail<3>() = -Js.bottomRows<3>() * vnb;
    }
    const Eigen::PartialPivLU<Eigen::Matrix<double, 6, 6>> lu(Jb);
    v.head<6>() = lu.solve(rhs_v);
    a.head<6>().setZero();
    model.setState(q, v, a);
    // Accelerations: the IMU's angular acceleration (gyro derivative) and a sole that does not
    // slide. (The accelerometer instead gave 117 N RMS of vertical-force residual on clean data
    // against 15 N: to be understood; docs/identification.md.)
    Eigen::Matrix<double, 6, 1> rhs_a;
    rhs_a.head<3>() = alpha - model.frameAcceleration(imu_frame).head<3>();
    rhs_a.tail<3>() = -model.frameAcceleration(stance).tail<3>();
    a.head<6>() = lu.solve(rhs_a);
    model.setState(q, v, a);
    const Eigen::VectorXd tau_full = model.inverseDynamics();
    tau_id[static_cast<std::size_t>(k)] = tau_full.segment(6, nA);

    if (o.use_force) {
      Ground& gr = ground[static_cast<std::size_t>(k)];
      const Eigen::Vector3d P =
          0.5 * (model.framePose(soles[0]).translation() + model.framePose(soles[1]).translation());
      const core::Wrench W = model.contactWrenchFromBase(tau_full).about(P);
      gr.F_pred = W.force;
      gr.M_pred = W.moment;
      gr.F_meas.setZero();
      gr.M_meas.setZero();
      for (int f = 0; f < 2; ++f) {
        Eigen::Vector3d c;
        const double mb = model.massBelow(sensor_frame[f], &c);
        const Eigen::Vector3d wb(0.0, 0.0, -mb * d.gravity);
        gr.F_pred += wb;
        gr.M_pred += (c - P).cross(wb);
        const Eigen::Isometry3d Xs = model.framePose(sensor_frame[f]);
        gr.sensor_p[f] = Xs.translation() - P;
        gr.sensor_R[f] = Xs.linear();
        // Readings through the model's calibration (an overlay's identified bias and scale).
        const core::Wrench w =
            d.effects.calibrated(f, r.ft[f]).expressedIn(Xs, core::Axes::kWorld).about(P);
        gr.foot_force[f] = w.force;
        gr.foot_moment[f] = w.moment;
        gr.F_meas += w.force;
        gr.M_meas += w.moment;
      }
      {
        // Torso orientation: measured (IMU) and predicted (encoders, bushings at moment /
        // stiffness, each stance sole flat at its planned pose; the mean over stance feet).
        const Eigen::Matrix3d R_base_meas = r.imu.toRotationMatrix() *
                                            model.framePose(imu_frame).linear().transpose() *
                                            model.framePose(base_frame).linear();
        gr.torso_meas = {rollOf(R_base_meas), pitchOf(R_base_meas)};
        // The spring carries the moment less the damper's share: k delta + c delta' = M, i.e.
        // k delta is M through a first-order low-pass of time constant c / k (exact per period).
        // (The static k delta = M left 0.85 mrad RMS of pitch residual on clean data, ~ c delta'.)
        double moment[4], rate[4];
        for (int f = 0; f < 2; ++f) {
          const core::Wrench ft = d.effects.calibrated(f, r.ft[f]);
          const double m_axis[2] = {ft.moment.x(), ft.moment.y()};  // sensor x (roll), y (pitch)
          for (int ax = 0; ax < 2; ++ax) {
            const int e = 2 * f + ax;
            const auto& ej = d.elastic[static_cast<std::size_t>(e)];
            const double keep =
                ej.damping > 0.0 ? std::exp(-ej.stiffness * data.period / ej.damping) : 0.0;
            const double previous = spring[e];
            spring[e] = k == 1 ? m_axis[ax] : keep * spring[e] + (1.0 - keep) * m_axis[ax];
            moment[e] = spring[e];
            // Deflection rate (rad/s) of the predicted bushing angle.
            rate[e] = k == 1 ? 0.0 : (spring[e] - previous) / (ej.stiffness * data.period);
          }
        }
        const auto& phs = plan.phases[static_cast<std::size_t>(plan.phase(s))];
        auto predict = [&](const double* deflection_delta) {
          Eigen::VectorXd qp = q;
          for (int e = 0; e < 4; ++e)
            qp(model.elasticCoordinate(e)) =
                kBushingSign * moment[e] / d.elastic[static_cast<std::size_t>(e)].stiffness +
                deflection_delta[e];
          Eigen::Vector2d tilt = Eigen::Vector2d::Zero();
          int n = 0;
          for (int f = 0; f < 2; ++f) {
            if (!(f == 0 ? phs.right_contact : phs.left_contact)) continue;
            const Eigen::MatrixXd& pose = f == 0 ? plan.right_foot : plan.left_foot;
            Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
            X.translation() = pose.col(s).head<3>();
            X.linear() = Eigen::Quaterniond(pose(3, s), pose(4, s), pose(5, s), pose(6, s))
                             .normalized()
                             .toRotationMatrix();
            Eigen::VectorXd qa = qp, v0 = Eigen::VectorXd::Zero(model.dofs()), a0 = v0;
            model.anchorBase(soles[f], X, qa, v0, a0);
            model.setPositions(qa);
            const Eigen::Matrix3d Rb = model.framePose(base_frame).linear();
            tilt += Eigen::Vector2d(rollOf(Rb), pitchOf(Rb));
            ++n;
          }
          return n > 0 ? Eigen::Vector2d(tilt / n) : tilt;
        };
        const double zero[4] = {0.0, 0.0, 0.0, 0.0};
        gr.torso_pred = predict(zero);
        const double h = 1e-5;  // rad
        for (int e = 0; e < 4; ++e) {
          double dd[4] = {0.0, 0.0, 0.0, 0.0};
          dd[e] = h;
          const Eigen::Vector2d de = (predict(dd) - gr.torso_pred) / h;  // d tilt / d deflection
          const double k_e = d.elastic[static_cast<std::size_t>(e)].stiffness;
          gr.torso_dc.col(e % 2) += de * kBushingSign * moment[e];
          gr.torso_dd.col(e % 2) -= de * kBushingSign * rate[e] / k_e;
          gr.torso_ft[e / 2].col(0) -= de * kBushingSign * moment[e] / k_e;
          gr.torso_ft[e / 2].col(1 + e % 2) -= de * kBushingSign / k_e;
        }
        model.setState(q, v, a);
      }
      if (payload_frame >= 0) {
        const Eigen::Isometry3d Xl = model.framePose(payload_frame);
        gr.payload_p = Xl.translation() - P;
        gr.payload_R = Xl.linear();
      }
    }
    Eigen::MatrixXd P = Eigen::MatrixXd::Zero(nA, 4);
    if (payload_frame >= 0) {
      const Eigen::MatrixXd J = model.frameJacobian(payload_frame);  // [angular; linear]
      const Eigen::Matrix3d Rl = model.framePose(payload_frame).linear();
      for (int j = 0; j < nA; ++j) {
        const int c = model.actuatedCoordinate(j);
        P(j, 0) = J.block<3, 1>(3, c).dot(gvec);
        for (int i = 0; i < 3; ++i) P(j, 1 + i) = J.block<3, 1>(0, c).dot((Rl.col(i)).cross(gvec));
      }
    }
    pay[static_cast<std::size_t>(k)] = P;
  }
  // Each ground row's window average (every quantity below enters linearly).
  if (o.use_force)
    for (int k = 1; k + gw < N; k += gw) {
      Ground& a = ground[static_cast<std::size_t>(k)];
      for (int i = 1; i < gw; ++i) {
        const Ground& b = ground[static_cast<std::size_t>(k + i)];
        a.F_meas += b.F_meas;
        a.M_meas += b.M_meas;
        a.F_pred += b.F_pred;
        a.M_pred += b.M_pred;
        a.payload_p += b.payload_p;
        a.payload_R += b.payload_R;
        a.torso_meas += b.torso_meas;
        a.torso_pred += b.torso_pred;
        a.torso_dc += b.torso_dc;
        a.torso_dd += b.torso_dd;
        a.torso_ft[0] += b.torso_ft[0];
        a.torso_ft[1] += b.torso_ft[1];
        for (int f = 0; f < 2; ++f) {
          a.sensor_p[f] += b.sensor_p[f];
          a.sensor_R[f] += b.sensor_R[f];
          a.foot_force[f] += b.foot_force[f];
          a.foot_moment[f] += b.foot_moment[f];
        }
      }
      const double inv = 1.0 / gw;
      a.F_meas *= inv;
      a.M_meas *= inv;
      a.F_pred *= inv;
      a.M_pred *= inv;
      a.payload_p *= inv;
      a.payload_R *= inv;
      a.torso_meas *= inv;
      a.torso_pred *= inv;
      a.torso_dc *= inv;
      a.torso_dd *= inv;
      a.torso_ft[0] *= inv;
      a.torso_ft[1] *= inv;
      for (int f = 0; f < 2; ++f) {
        a.sensor_p[f] *= inv;
        a.sensor_R[f] *= inv;
        a.foot_force[f] *= inv;
        a.foot_moment[f] *= inv;
      }
    }
  for (int i = 0; i < R; ++i) {
    const Row& w = rows[static_cast<std::size_t>(i)];
    const Record& r = data.records[static_cast<std::size_t>(w.record)];
    if (w.channel == 0) {
      const int j = w.joint;
      const double pred = r.q_ref(j) + r.qd_ref(j) * data.period - rho * (r.q_ref(j) - r.q0(j));
      res(i) = r.q(j) - pred;
    } else if (w.channel == 1) {
      res(i) = r.tau(w.joint) - tau_id[static_cast<std::size_t>(w.record)](w.joint);
    } else {
      // The sensors carry what the motion needs from the ground plus the weight below them.
      const Ground& gr = ground[static_cast<std::size_t>(w.record)];
      res(i) = w.channel == 2   ? gr.F_meas.z() - gr.F_pred.z()
               : w.channel == 3 ? gr.M_meas(w.joint) - gr.M_pred(w.joint)
                                : gr.torso_meas(w.joint) - gr.torso_pred(w.joint);
    }
  }
  if (!o.dump_residuals.empty()) {
    std::string csv = "channel,joint,t,residual,measured\n";
    for (int i = 0; i < R; ++i) {
      const Row& w = rows[static_cast<std::size_t>(i)];
      const Record& r = data.records[static_cast<std::size_t>(w.record)];
      const Ground& gr = ground[static_cast<std::size_t>(w.record)];
      const double meas = w.channel == 0   ? r.q(w.joint)
                          : w.channel == 1 ? r.tau(w.joint)
                          : w.channel == 2 ? gr.F_meas.z()
                          : w.channel == 3 ? gr.M_meas(w.joint)
                                           : gr.torso_meas(w.joint);
      csv += std::string(kChannelName[w.channel]) + "," +
             (w.channel >= 3 ? std::string(w.joint == 0 ? "x" : "y")
              : w.joint >= 0 ? d.actuated[static_cast<std::size_t>(w.joint)].name
                             : std::string()) +
             "," + std::to_string(r.t) + "," + std::to_string(res(i)) + "," + std::to_string(meas) +
             "\n";
    }
    core::writeFileAtomic(o.dump_residuals, csv);
  }
  // Noise per channel: robust, from consecutive differences (a smooth effect cancels there).
  double sigma[kChannels] = {1.0, 1.0, 1.0, 1.0, 1.0};
  for (int ch = 0; ch < kChannels; ++ch) {
    std::vector<double> dd;
    for (int i = 0; i + 1 < R; ++i) {
      const Row& a = rows[static_cast<std::size_t>(i)];
      const Row& b = rows[static_cast<std::size_t>(i + 1)];
      if (a.channel == ch && b.channel == ch && a.joint == b.joint)
        dd.push_back(std::abs(res(i + 1) - res(i)));
    }
    const double s = 1.4826 * median(dd) / std::sqrt(2.0);
    sigma[ch] = s > 0.0 ? s : 1.0;
  }
  {
    // The torso tilt is predicted to 0.5 % of its swing on clean data (the bushings' linear
    // spring-damper against the simulator's) while its noise is far smaller: the channel's scale
    // is at least 1 % of the tilt's RMS swing, so that this resolution is not read as an effect.
    double sum = 0.0, sum2 = 0.0;
    int n4 = 0;
    for (int i = 0; i < R; ++i) {
      const Row& w = rows[static_cast<std::size_t>(i)];
      if (w.channel != 4) continue;
      const double m = ground[static_cast<std::size_t>(w.record)].torso_meas(w.joint);
      sum += m;
      sum2 += m * m;
      ++n4;
    }
    if (n4 > 1) {
      const double sd = std::sqrt(std::max(sum2 / n4 - (sum / n4) * (sum / n4), 0.0));
      sigma[4] = std::max(sigma[4], 0.01 * sd);
    }
  }
  Eigen::VectorXd wgt(R);
  for (int i = 0; i < R; ++i) wgt(i) = 1.0 / sigma[rows[static_cast<std::size_t>(i)].channel];

  // ---- candidates
  auto col = [&](auto f) {
    Eigen::VectorXd c(R);
    for (int i = 0; i < R; ++i) c(i) = f(rows[static_cast<std::size_t>(i)]);
    return c;
  };
  auto recordOf = [&](const Row& w) -> const Record& {
    return data.records[static_cast<std::size_t>(w.record)];
  };
  std::vector<Candidate> cands;
  // Command delay and first-order lag: to first order both shift the references back in time by
  // their value: q one period later falls short by (1 - rho) d qd (a documented confusable pair).
  const Eigen::VectorXd shift = col([&](const Row& w) {
    return w.channel == 0 ? -(1.0 - rho) * recordOf(w).qd_ref(w.joint) : 0.0;
  });
  cands.push_back({"command_delay", {"delay"}, shift, {0}});
  cands.push_back({"command_lag", {"lag"}, shift, {0}});
  // Index among the moving joints of a joint-position or motor-torque row (-1: another row).
  auto movingJointOf = [&](const Row& w) -> Eigen::Index {
    if (w.channel > 1) return -1;
    const auto it = std::find(moving.begin(), moving.end(), w.joint);
    return it == moving.end() ? -1 : static_cast<Eigen::Index>(it - moving.begin());
  };
  // A candidate whose shape depends nonlinearly on one value (a width): the value is scanned on
  // a geometric grid (15 % steps) over [lo, hi) on the training rows, each column's gain fitted
  // linearly; the interval holds the values whose training residual is within a chi-square(1)
  // 95 % step of the best (residual variance from the best fit; the F statistic's correlation
  // correction is not applied here, so the interval is on the narrow side).
  const int split_rec = static_cast<int>(o.train_fraction * N);
  auto scanned = [&](const char* name, const char* value_name, double lo_value, double hi_value,
                     const auto& regressor) {
    std::vector<int> tr;
    for (int i = 0; i < R; ++i)
      if (rows[static_cast<std::size_t>(i)].record < split_rec) tr.push_back(i);
    std::vector<double> values, rss;
    for (double b = lo_value; b < hi_value; b *= 1.15) {
      const Eigen::MatrixXd X = regressor(b);
      Eigen::MatrixXd A(static_cast<Eigen::Index>(tr.size()), X.cols());
      Eigen::VectorXd y(static_cast<Eigen::Index>(tr.size()));
      for (std::size_t i = 0; i < tr.size(); ++i) {
        const double wt = 1.0 / sigma[rows[static_cast<std::size_t>(tr[i])].channel];
        A.row(static_cast<Eigen::Index>(i)) = X.row(tr[i]) * wt;
        y(static_cast<Eigen::Index>(i)) = res(tr[i]) * wt;
      }
      const Eigen::VectorXd th = A.colPivHouseholderQr().solve(y);
      values.push_back(b);
      rss.push_back((y - A * th).squaredNorm());
    }
    const auto best =
        static_cast<std::size_t>(std::min_element(rss.begin(), rss.end()) - rss.begin());
    const double s2 = rss[best] / std::max(static_cast<double>(tr.size()), 1.0);
    double lo = values[best], hi = values[best];
    for (std::size_t i = 0; i < values.size(); ++i)
      if (rss[i] - rss[best] <= 3.84 * s2) {
        lo = std::min(lo, values[i]);
        hi = std::max(hi, values[i]);
      }
    Candidate c;
    c.name = name;
    c.X = regressor(values[best]);
    c.scanned = value_name;
    c.scanned_value = values[best];
    c.scanned_ci = std::max(0.5 * (hi - lo), 0.5 * values[best] * (1.15 - 1.0));
    return c;
  };
  // Backlash: a dead band b between the motor (which the encoders read) and the load. After each
  // reversal of a joint's command the load waits until the motor has travelled b, and the servo's
  // velocity feed-forward is lost meanwhile: the encoder falls behind the prediction by a fraction
  // of the commanded velocity (measured on the simulator: a ramp of about -0.6 ms x qd_ref over
  // each crossing, then nothing). The band depends on b nonlinearly: b is scanned (1-80 mrad,
  // geometric) on the training rows; per moving joint a gain (s, >= 0) is fitted linearly.
  if (!moving.empty()) {
    const auto jointCount = static_cast<Eigen::Index>(moving.size());
    // The load follows a play operator on the motor (the command): L = clamp(L, m - h, m + h),
    // h = width / 2, starting centred. Inside the band (L held while the motor moves) the
    // position rows lose the feed-forward: one column per joint (a gain). The motor torques see
    // the load stop when it enters the band and catch up with the command when it leaves:
    // velocity steps of -qd_ref and +qd_ref within one period, i.e. torque impulses
    // I dv / T: a second column per joint (I, an effective inertia, kg m^2).
    auto bandRegressor = [&](double width) {
      const double h = 0.5 * width;
      Eigen::MatrixXd X = Eigen::MatrixXd::Zero(R, 2 * jointCount);
      std::vector<std::vector<char>> in_band(static_cast<std::size_t>(jointCount),
                                             std::vector<char>(static_cast<std::size_t>(N), 0));
      std::vector<std::vector<double>> dv(static_cast<std::size_t>(jointCount),
                                          std::vector<double>(static_cast<std::size_t>(N), 0.0));
      for (Eigen::Index m = 0; m < jointCount; ++m) {
        const int j = moving[static_cast<std::size_t>(m)];
        const auto mi = static_cast<std::size_t>(m);
        double L = data.records[0].q_ref(j);
        for (int k = 0; k < N; ++k) {
          const auto ki = static_cast<std::size_t>(k);
          const Record& rec = data.records[ki];
          const double motor = rec.q_ref(j), before = L;
          L = std::clamp(L, motor - h, motor + h);
          in_band[mi][ki] = L == before && std::abs(rec.qd_ref(j)) > 1e-6;
          // The load's measured acceleration over the crossing's entry and exit periods (and the
          // next, the servo's catch-up spilling over).
          if (k > 0 && in_band[mi][ki] != in_band[mi][ki - 1])
            for (int kk = std::max(k - 1, 1); kk < std::min(k + 3, N); ++kk)
              dv[mi][static_cast<std::size_t>(kk)] =
                  data.records[static_cast<std::size_t>(kk)].qd(j) -
                  data.records[static_cast<std::size_t>(kk - 1)].qd(j);
        }
      }
      for (int i = 0; i < R; ++i) {
        const Row& w = rows[static_cast<std::size_t>(i)];
        const Eigen::Index m = movingJointOf(w);
        if (m < 0) continue;
        const auto mi = static_cast<std::size_t>(m), ki = static_cast<std::size_t>(w.record);
        if (w.channel == 0 && in_band[mi][ki]) X(i, m) = -recordOf(w).qd_ref(w.joint);
        if (w.channel == 1) X(i, jointCount + m) = dv[mi][ki] / data.period;
      }
      return X;
    };
    Candidate c = scanned("backlash", "width", 0.001, 0.12, bandRegressor);
    for (const char* kind : {"gain[", "inertia["})
      for (Eigen::Index m = 0; m < jointCount; ++m) {
        if (kind[0] == 'g') c.nonneg.push_back(static_cast<int>(c.params.size()));
        c.params.push_back(
            kind + d.actuated[static_cast<std::size_t>(moving[static_cast<std::size_t>(m)])].name +
            "]");
      }
    cands.push_back(std::move(c));
  }
  // Viscous joint friction per moving joint: the motor torque carries f v, and the position loop
  // lags by f v / stiffness.
  if (!moving.empty()) {
    Candidate c{"joint_viscous_friction", {}, Eigen::MatrixXd::Zero(R, 0), {}};
    c.X = Eigen::MatrixXd::Zero(R, static_cast<Eigen::Index>(moving.size()));
    for (std::size_t m = 0; m < moving.size(); ++m) {
      const int j = moving[m];
      c.params.push_back("viscous[" + d.actuated[static_cast<std::size_t>(j)].name + "]");
      c.nonneg.push_back(static_cast<int>(m));
      for (int i = 0; i < R; ++i) {
        const Row& w = rows[static_cast<std::size_t>(i)];
        if (w.joint != j) continue;
        const double v = recordOf(w).qd(j);
        c.X(i, static_cast<Eigen::Index>(m)) =
            w.channel == 1 ? v : -(1.0 - rho) * v / o.servo_stiffness;
      }
    }
    cands.push_back(std::move(c));
  }
  // Coulomb joint friction F (stick-slip): the joint sticks until the servo's error reaches
  // F / stiffness, i.e. the target follows a play operator of half-width F / k on the command
  // (over each period the command runs from q_ref to q_ref + qd_ref T), and the motor torque
  // carries f = k (q_ref - stick), between -F and F. Positions: the servo tracks the stuck target,
  // q(k+1) - prediction = -(f_end - rho f_start) / k; torques: the period's mean of f. F sets the
  // play's width (scanned, 0.2-20 N m) and, per moving joint, the gain (~F) is fitted.
  if (!moving.empty()) {
    const auto jointCount = static_cast<Eigen::Index>(moving.size());
    auto stickRegressor = [&](double F) {
      const double h = F / o.servo_stiffness;
      Eigen::MatrixXd f0(N, jointCount), f1(N, jointCount);  // normalised f at start / end
      for (Eigen::Index m = 0; m < jointCount; ++m) {
        const int j = moving[static_cast<std::size_t>(m)];
        double st = data.records[0].q_ref(j);
        for (int k = 0; k < N; ++k) {
          const Record& rec = data.records[static_cast<std::size_t>(k)];
          const double q_start = rec.q_ref(j), q_end = rec.q_ref(j) + rec.qd_ref(j) * data.period;
          st = std::clamp(st, q_start - h, q_start + h);
          f0(k, m) = (q_start - st) / h;
          st = std::clamp(st, q_end - h, q_end + h);
          f1(k, m) = (q_end - st) / h;
        }
      }
      Eigen::MatrixXd X = Eigen::MatrixXd::Zero(R, jointCount);
      for (int i = 0; i < R; ++i) {
        const Row& w = rows[static_cast<std::size_t>(i)];
        const Eigen::Index m = movingJointOf(w);
        if (m < 0) continue;
        const auto k = static_cast<Eigen::Index>(w.record);
        X(i, m) = w.channel == 1 ? 0.5 * (f0(k, m) + f1(k, m))
                                 : -(f1(k, m) - rho * f0(k, m)) / o.servo_stiffness;
      }
      return X;
    };
    Candidate c = scanned("joint_coulomb_friction", "friction", 0.2, 20.0, stickRegressor);
    for (Eigen::Index m = 0; m < jointCount; ++m) {
      c.params.push_back(
          "coulomb[" +
          d.actuated[static_cast<std::size_t>(moving[static_cast<std::size_t>(m)])].name + "]");
      c.nonneg.push_back(static_cast<int>(m));
    }
    cands.push_back(std::move(c));
  }
  // A payload (mass m at offset c in the link frame): the sensors carry m g more, and the joints
  // holding the link its gravity torque (linear in m and m c).
  if (payload_frame >= 0) {
    Candidate c{"payload",
                {"mass", "mass*offset_x", "mass*offset_y", "mass*offset_z"},
                Eigen::MatrixXd::Zero(R, 4),
                {0}};
    const Eigen::Vector3d up(0.0, 0.0, d.gravity);
    for (int i = 0; i < R; ++i) {
      const Row& w = rows[static_cast<std::size_t>(i)];
      if (w.channel == 2) c.X(i, 0) = d.gravity;
      if (w.channel == 1) c.X.row(i) = pay[static_cast<std::size_t>(w.record)].row(w.joint);
      if (w.channel == 3) {
        // The ground carries the payload's weight where it is: m (p + R c) x g.
        const Ground& gr = ground[static_cast<std::size_t>(w.record)];
        c.X(i, 0) = gr.payload_p.cross(up)(w.joint);
        for (int a = 0; a < 3; ++a) c.X(i, 1 + a) = gr.payload_R.col(a).cross(up)(w.joint);
      }
    }
    cands.push_back(std::move(c));
  }
  // Ankle bushings: a change of compliance (1/k) and of damping of the roll and of the pitch
  // bushings (both feet) tilts the torso by the moments they carry and their rate.
  {
    Candidate c{"ankle_bushing",
                {"compliance_roll", "compliance_pitch", "damping_roll", "damping_pitch"},
                Eigen::MatrixXd::Zero(R, 4),
                {}};
    for (int i = 0; i < R; ++i) {
      const Row& w = rows[static_cast<std::size_t>(i)];
      if (w.channel != 4) continue;
      const Ground& gr = ground[static_cast<std::size_t>(w.record)];
      c.X.block<1, 2>(i, 0) = gr.torso_dc.row(w.joint);
      c.X.block<1, 2>(i, 2) = gr.torso_dd.row(w.joint);
    }
    cands.push_back(std::move(c));
  }
  // Force sensor bias (normal force and the two tilting moments, sensor frame) and scale, per
  // foot: what the sensor adds, carried to the world frame and the reference point.
  for (int f = 0; f < 2; ++f) {
    const std::string side = f == 0 ? "right" : "left";
    Candidate bias{
        "ft_bias_" + side, {"fz_bias", "mx_bias", "my_bias"}, Eigen::MatrixXd::Zero(R, 3), {}};
    Candidate scale{"ft_scale_" + side, {"scale_minus_1"}, Eigen::MatrixXd::Zero(R, 1), {}};
    for (int i = 0; i < R; ++i) {
      const Row& w = rows[static_cast<std::size_t>(i)];
      if (w.channel < 2) continue;
      const Ground& gr = ground[static_cast<std::size_t>(w.record)];
      const Eigen::Matrix3d& Rs = gr.sensor_R[f];
      if (w.channel == 4) {
        bias.X(i, 1) = gr.torso_ft[f](w.joint, 1);
        bias.X(i, 2) = gr.torso_ft[f](w.joint, 2);
        scale.X(i, 0) = gr.torso_ft[f](w.joint, 0);
      } else if (w.channel == 2) {
        bias.X(i, 0) = Rs(2, 2);
        scale.X(i, 0) = gr.foot_force[f].z();
      } else {
        bias.X(i, 0) = gr.sensor_p[f].cross(Rs.col(2))(w.joint);
        bias.X(i, 1) = Rs(w.joint, 0);
        bias.X(i, 2) = Rs(w.joint, 1);
        scale.X(i, 0) = gr.foot_moment[f](w.joint);
      }
    }
    cands.push_back(std::move(bias));
    cands.push_back(std::move(scale));
  }

  cands.erase(std::remove_if(cands.begin(), cands.end(),
                             [](const Candidate& c) { return c.X.cwiseAbs().maxCoeff() == 0.0; }),
              cands.end());
  if (cands.empty()) throw InputError("identify: no candidate effect is visible in these data");
  // ---- fit on the training part, score on the held-out part
  const int split = static_cast<int>(o.train_fraction * N);
  std::vector<int> train, test;
  for (int i = 0; i < R; ++i)
    (rows[static_cast<std::size_t>(i)].record < split ? train : test).push_back(i);
  const Eigen::VectorXd rw = res.cwiseProduct(wgt);
  auto rms = [](const Eigen::VectorXd& x, const std::vector<int>& idx) {
    double s = 0.0;
    for (int i : idx) s += x(i) * x(i);
    return idx.empty() ? 0.0 : std::sqrt(s / static_cast<double>(idx.size()));
  };
  // Channels that show an effect: held-out residual above kResidualLevel noise levels. Candidates
  // are scored on those channels' held-out rows (all held-out rows when none shows one), so that
  // an effect seen by one channel is not diluted by the others.
  std::vector<int> eval;
  for (int ch = 0; ch < kChannels; ++ch) {
    std::vector<int> idx;
    for (int i : test)
      if (rows[static_cast<std::size_t>(i)].channel == ch) idx.push_back(i);
    if (!idx.empty() && rms(rw, idx) > kResidualLevel)
      eval.insert(eval.end(), idx.begin(), idx.end());
  }
  const bool residual_seen = !eval.empty();
  if (!residual_seen) eval = test;
  std::sort(eval.begin(), eval.end());
  Identification out;
  out.payload_link = payload_link;
  out.samples = N;
  out.moving_joints = static_cast<int>(moving.size());
  out.error_before = rms(rw, eval);
  out.whiteness = lag1(rw, rows, eval);
  std::vector<Eigen::VectorXd> fitted_resid;
  std::vector<Eigen::MatrixXd> design;        // per candidate: weighted training regressors
  std::vector<Eigen::VectorXd> fitted_train;  // and its fitted effect on the training rows
  for (const Candidate& c : cands) {
    const int p = static_cast<int>(c.X.cols());
    Eigen::MatrixXd A(static_cast<Eigen::Index>(train.size()), p);
    Eigen::VectorXd b(static_cast<Eigen::Index>(train.size()));
    for (std::size_t i = 0; i < train.size(); ++i) {
      A.row(static_cast<Eigen::Index>(i)) = c.X.row(train[i]) * wgt(train[i]);
      b(static_cast<Eigen::Index>(i)) = rw(train[i]);
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
    const Eigen::VectorXd theta = qr.solve(b);
    const Eigen::VectorXd after = rw - (c.X * theta).cwiseProduct(wgt);
    CandidateFit fit;
    fit.name = c.name;
    fit.parameter_names = c.params;
    fit.parameters.assign(theta.data(), theta.data() + p);
    const double rss0 = b.squaredNorm(), rss1 = (b - A * theta).squaredNorm();
    const double ntr = static_cast<double>(train.size());
    const double phi = std::clamp(lag1(after, rows, train), 0.0, 0.99);
    const double neff = std::max(ntr * (1.0 - phi) / (1.0 + phi), p + 2.0);
    fit.f_statistic = ((rss0 - rss1) / p) / std::max(rss1 / (neff - p), 1e-300);
    fit.train_reduction = 1.0 - std::sqrt(rss1 / std::max(rss0, 1e-300));
    const double before = rms(rw, eval), aft = rms(after, eval);
    fit.reduction = before > 0.0 ? 1.0 - aft / before : 0.0;
    // Covariance of theta, inflated for correlated residuals (N / N_eff).
    const double s2 = rss1 / std::max(ntr - p, 1.0) * (ntr / neff);
    const Eigen::MatrixXd AtA = A.transpose() * A;
    const Eigen::MatrixXd cov = s2 * AtA.completeOrthogonalDecomposition().pseudoInverse();
    fit.plausible = true;
    for (int i = 0; i < p; ++i) {
      const double half = 1.96 * std::sqrt(std::max(cov(i, i), 0.0));
      fit.ci95.push_back(half);
      const bool must_pos = std::find(c.nonneg.begin(), c.nonneg.end(), i) != c.nonneg.end();
      if (must_pos && theta(i) < -half) fit.plausible = false;
    }
    if (p == 1 && std::abs(theta(0)) > 0.0 && fit.ci95[0] / 1.96 > 0.3 * std::abs(theta(0)))
      fit.plausible = false;
    // A payload sits on the link: mass positive, offset within half a metre.
    if (c.name == "payload" && (theta(0) <= 0.0 || theta.tail(3).norm() > 0.5 * theta(0)))
      fit.plausible = false;
    if (!c.scanned.empty()) {
      fit.parameter_names.push_back(c.scanned);
      fit.parameters.push_back(c.scanned_value);
      fit.ci95.push_back(c.scanned_ci);
    }
    for (int i : test) fit.held_out_rss += after(i) * after(i);
    design.push_back(A);
    fitted_train.push_back(A * theta);
    out.candidates.push_back(fit);
    fitted_resid.push_back(after);
  }
  std::vector<std::size_t> order(out.candidates.size());
  std::iota(order.begin(), order.end(), 0);
  // Best: the smallest held-out residual over every channel (a channel below the residual level
  // can still tell candidates apart, e.g. the ground moment a left or a right sensor's bias makes).
  // Implausible fits (unphysical signs or sizes) rank after every plausible one.
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const CandidateFit &ca = out.candidates[a], &cb = out.candidates[b];
    if (ca.plausible != cb.plausible) return ca.plausible;
    return ca.held_out_rss < cb.held_out_rss;
  });
  std::vector<CandidateFit> sorted;
  for (std::size_t i : order) sorted.push_back(out.candidates[i]);
  const std::size_t best_index = order.front();
  out.candidates = sorted;

  // ---- decision rule (docs/identification.md)
  const CandidateFit& best = out.candidates.front();
  const bool significant = best.f_statistic > 30.0 && best.reduction > 0.1;
  Eigen::VectorXd final_resid = rw;
  if (!significant) {
    out.verdict = residual_seen ? "unexplained" : "none";
  } else if (!best.plausible || best.reduction < 0.3) {
    out.verdict = "unexplained";
  } else {
    out.effect = best.name;
    final_resid = fitted_resid[best_index];
    for (std::size_t i = 0; i < best.parameter_names.size(); ++i) {
      out.parameters[best.parameter_names[i]] = best.parameters[i];
      out.ci95[best.parameter_names[i]] = best.ci95[i];
    }
    // Confusable: explains most of what the best explains, and its held-out residual is not
    // significantly larger (likelihood ratio with the effective sample size, > 10 ~ p < 0.002).
    const double phi = std::clamp(lag1(final_resid, rows, test), 0.0, 0.99);
    const double s2 = best.held_out_rss / std::max<double>(static_cast<double>(test.size()), 1.0);
    // Or its regressors reproduce the winner's fitted effect on the training rows (>= 98 % of
    // its norm): the experiment cannot tell them apart, whatever the residual says (e.g. a
    // payload and a sensor's normal-force bias while both feet are on the ground).
    const Eigen::VectorXd& sb = fitted_train[best_index];
    for (std::size_t i = 1; i < out.candidates.size(); ++i) {
      CandidateFit& c = out.candidates[i];
      c.distinction =
          (c.held_out_rss - best.held_out_rss) / std::max(s2, 1e-300) * (1.0 - phi) / (1.0 + phi);
      const Eigen::MatrixXd& Ac = design[order[i]];
      const Eigen::VectorXd proj = Ac * Ac.colPivHouseholderQr().solve(sb);
      const double mimic = sb.norm() > 0.0 ? proj.norm() / sb.norm() : 0.0;
      if (c.plausible && c.reduction >= 0.8 * best.reduction &&
          (c.distinction < 10.0 || mimic >= 0.98))
        out.confusable.push_back(c.name);
    }
    out.verdict = out.confusable.empty() ? "identified" : "ambiguous";
    if (!out.confusable.empty()) out.confusable.insert(out.confusable.begin(), best.name);
  }
  if (out.candidates.size() > 1) out.runner_up = out.candidates[1].name;
  out.error_after = rms(final_resid, eval);
  auto aboveNoise = [](double e) { return std::sqrt(std::max(e * e - 1.0, 0.0)); };
  out.excess_before = aboveNoise(out.error_before);
  out.excess_after = aboveNoise(out.error_after);
  out.residuals.reserve(static_cast<std::size_t>(R));
  for (int i = 0; i < R; ++i) {
    const Row& w = rows[static_cast<std::size_t>(i)];
    ResidualRow row;
    row.channel = kChannelName[w.channel];
    row.label = w.channel >= 3 ? std::string(w.joint == 0 ? "x" : "y")
                : w.joint >= 0 ? d.actuated[static_cast<std::size_t>(w.joint)].name
                               : std::string();
    row.t = data.records[static_cast<std::size_t>(w.record)].plan_t;
    row.held_out = w.record >= split;
    row.before = res(i);
    row.after = final_resid(i) / wgt(i);
    out.residuals.push_back(row);
  }
  for (int ch = 0; ch < kChannels; ++ch) {
    std::vector<int> idx;
    for (int i : test)
      if (rows[static_cast<std::size_t>(i)].channel == ch) idx.push_back(i);
    if (idx.empty()) continue;
    ChannelError e;
    e.unit = kChannelUnit[ch];
    e.noise = sigma[ch];
    e.rms_before = rms(rw, idx) * sigma[ch];
    e.rms_after = rms(final_resid, idx) * sigma[ch];
    out.channels[kChannelName[ch]] = e;
  }
  return out;
}

}  // namespace overstep::sysid
