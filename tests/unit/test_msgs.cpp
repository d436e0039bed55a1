// msgs: every LCM type round-trips through encode/decode and through memq://; msgs_convert
// round-trips core types and rejects bad messages.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "msg_fixtures.hpp"
#include "overstep/msgs/convert.hpp"
#include "overstep/plan_reference_t.hpp"
#include "overstep/replay_control_t.hpp"
#include "overstep/robot_command_t.hpp"
#include "overstep/robot_state_t.hpp"
#include "overstep/runtime_status_t.hpp"
#include "overstep/sim_status_t.hpp"
#include "overstep/stabilizer_status_t.hpp"

namespace overstep {
namespace {

template <typename T>
std::vector<char> encode(const T& m) {
  std::vector<char> buf(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return buf;
}

template <typename T>
void expectRoundTrip(const T& m) {
  const std::vector<char> a = encode(m);
  T back;
  ASSERT_EQ(back.decode(a.data(), 0, static_cast<int>(a.size())), static_cast<int>(a.size()));
  EXPECT_EQ(encode(back), a) << T::getTypeName();
  // A truncated buffer is rejected, not misread.
  T partial;
  EXPECT_LT(partial.decode(a.data(), 0, static_cast<int>(a.size()) - 1), 0) << T::getTypeName();
}

TEST(Msgs, EveryTypeRoundTripsThroughEncoding) {
  expectRoundTrip(test::makeCommand(3));
  expectRoundTrip(test::makeState(3));
  expectRoundTrip(test::makePlanReference());
  expectRoundTrip(test::makeStabilizerStatus());
  expectRoundTrip(test::makeRuntimeStatus());
  expectRoundTrip(test::makeReplayControl());
  expectRoundTrip(test::makeSimStatus());
}

TEST(Msgs, FingerprintsDifferAcrossTypes) {
  const std::vector<int64_t> fps = {robot_command_t::getHash(),  robot_state_t::getHash(),
                                    plan_reference_t::getHash(), stabilizer_status_t::getHash(),
                                    runtime_status_t::getHash(), replay_control_t::getHash(),
                                    sim_status_t::getHash()};
  for (std::size_t i = 0; i < fps.size(); ++i)
    for (std::size_t j = i + 1; j < fps.size(); ++j) EXPECT_NE(fps[i], fps[j]);
  // A message of one type does not decode as another (the fingerprint is checked).
  const auto buf = encode(test::makeReplayControl());
  sim_status_t wrong;
  EXPECT_LT(wrong.decode(buf.data(), 0, static_cast<int>(buf.size())), 0);
}

TEST(Msgs, PublishAndReceiveOverMemq) {
  lcm::LCM bus("memq://");
  ASSERT_TRUE(bus.good());
  struct Sink {
    int count = 0;
    std::vector<double> q;
    void onState(const lcm::ReceiveBuffer*, const std::string&, const robot_state_t* m) {
      ++count;
      q = m->q;
    }
  } sink;
  bus.subscribe("OVERSTEP_STATE", &Sink::onState, &sink);
  const robot_state_t sent = test::makeState(30);
  ASSERT_EQ(bus.publish("OVERSTEP_STATE", &sent), 0);
  ASSERT_GT(bus.handleTimeout(1000), 0);
  EXPECT_EQ(sink.count, 1);
  EXPECT_EQ(sink.q, sent.q);
}

TEST(MsgsConvert, CommandRoundTrip) {
  core::RobotCommand c;
  c.resize(30);
  c.utime = 1234;
  c.seq = 9;
  for (int i = 0; i < 30; ++i) {
    c.q_ref(i) = 0.01 * i;
    c.qd_ref(i) = -0.02 * i;
    c.tau_ff(i) = 0.5 * i;
  }
  c.has_tau_ff = true;
  robot_command_t m;
  msgs::toLcm(c, m);
  core::RobotCommand back;
  std::string why;
  ASSERT_TRUE(msgs::fromLcm(m, 30, back, &why)) << why;
  EXPECT_EQ(back.seq, 9);
  EXPECT_EQ(back.q_ref, c.q_ref);
  EXPECT_EQ(back.qd_ref, c.qd_ref);
  EXPECT_EQ(back.tau_ff, c.tau_ff);
  EXPECT_TRUE(back.has_tau_ff);
}

TEST(MsgsConvert, RejectsWrongJointCountAndNaN) {
  robot_command_t m = test::makeCommand(29);
  core::RobotCommand out;
  std::string why;
  EXPECT_FALSE(msgs::fromLcm(m, 30, out, &why));
  EXPECT_EQ(why, "wrong joint count");
  m = test::makeCommand(30);
  m.q_ref[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(msgs::fromLcm(m, 30, out, &why));
  EXPECT_EQ(why, "non-finite value");
  m = test::makeCommand(30);
  m.qd_ref.pop_back();  // array shorter than num_joints
  EXPECT_FALSE(msgs::fromLcm(m, 30, out, &why));
}

TEST(MsgsConvert, StateRoundTripAndValidation) {
  core::RobotState s;
  s.resize(30);
  s.seq = 77;
  s.q.setLinSpaced(30, -1.0, 1.0);
  s.ft_right.force << 1, 2, 300;
  s.ft_right.moment << 4, 5, 6;
  s.ft_left.force << -1, -2, 250;
  s.ft_left.moment << -4, -5, -6;
  s.imu_orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()));
  s.has_ground_truth = true;
  s.base_pose.translation() << 0.1, 0.0, 0.65;
  robot_state_t m;
  msgs::toLcm(s, m);
  core::RobotState back;
  std::string why;
  ASSERT_TRUE(msgs::fromLcm(m, 30, back, &why)) << why;
  EXPECT_EQ(back.seq, 77);
  EXPECT_EQ(back.q, s.q);
  EXPECT_EQ(back.ft_right.forceMoment(), s.ft_right.forceMoment());
  EXPECT_EQ(back.ft_left.forceMoment(), s.ft_left.forceMoment());
  EXPECT_EQ(back.ft_left.axes, core::Axes::kSensor);
  // The message's order is [Fx Fy Fz Mx My Mz].
  EXPECT_EQ(m.ft_left[2], 250.0);
  EXPECT_EQ(m.ft_left[3], -4.0);
  // A reading about another point goes out about the sensor origin.
  s.ft_right.point << 0.0, 0.0, 0.1;
  msgs::toLcm(s, m);
  EXPECT_NEAR(m.ft_right[3], 4.0 + 0.1 * -2.0, 1e-12);  // M_x + (p x F)_x = M_x - p_z F_y
  s.ft_right.point.setZero();
  EXPECT_TRUE(back.imu_orientation.isApprox(s.imu_orientation, 1e-12));
  EXPECT_TRUE(back.base_pose.isApprox(s.base_pose, 1e-12));
  m.imu_quaternion[0] = 3.0;  // not a rotation
  EXPECT_FALSE(msgs::fromLcm(m, 30, back, &why));
  msgs::toLcm(s, m);
  m.ft_left[2] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(msgs::fromLcm(m, 30, back, &why));
}

// Issue 20: the simulator's commands and the runtime's states were decoded by liblcm's typed
// subscriptions, whose generated decoder sizes the joint arrays before checking the bytes: a
// 50-byte command declaring 2^31 - 1 joints asked for 48 GB, a negative count threw.
template <class T>
void expectCheckedDecoding(const T& good_msg, int joints_at) {
  std::vector<std::uint8_t> good(static_cast<std::size_t>(good_msg.getEncodedSize()));
  good_msg.encode(good.data(), 0, static_cast<int>(good.size()));
  T out;
  std::string why;
  ASSERT_TRUE(overstep::msgs::decodeChecked(good.data(), static_cast<int>(good.size()), out, &why))
      << why;
  EXPECT_EQ(out.num_joints, good_msg.num_joints);
  std::uint32_t stored = 0;
  for (int i = 0; i < 4; ++i)
    stored = (stored << 8) | good[static_cast<std::size_t>(joints_at + i)];
  ASSERT_EQ(stored, static_cast<std::uint32_t>(good_msg.num_joints))
      << "num_joints not at " << joints_at;
  for (const std::uint32_t n : {0x7fffffffu, 0x80000000u, 0xffffffffu, 31u}) {
    auto bad = good;
    for (int i = 0; i < 4; ++i)
      bad[static_cast<std::size_t>(joints_at + i)] = static_cast<std::uint8_t>(n >> (24 - 8 * i));
    EXPECT_FALSE(overstep::msgs::decodeChecked(bad.data(), static_cast<int>(bad.size()), out, &why))
        << "num_joints " << n;
    // Cut to 50 bytes: the declared count cannot fit.
    EXPECT_FALSE(overstep::msgs::decodeChecked(bad.data(), 50, out, &why)) << n;
  }
  for (const int cut : {0, 7, joints_at + 2, static_cast<int>(good.size()) - 1})
    EXPECT_FALSE(overstep::msgs::decodeChecked(good.data(), cut, out, &why)) << "cut " << cut;
  auto other = good;
  other[0] ^= 0xff;  // another type's fingerprint
  EXPECT_FALSE(
      overstep::msgs::decodeChecked(other.data(), static_cast<int>(other.size()), out, &why));
  EXPECT_NE(why.find("fingerprint"), std::string::npos) << why;
}

TEST(MsgsConvert, CommandsAndStatesAreDecodedWithTheirJointCountChecked) {
  expectCheckedDecoding(overstep::test::makeCommand(30), 8 + 2 * 8);
  expectCheckedDecoding(overstep::test::makeState(30), 8 + 3 * 8);
}

}  // namespace
}  // namespace overstep
