// Publishes and receives every LCM type over udpm. Must run inside the private network namespace
// made by tests/integration/netns_run.sh (CTest does that); refuses to run outside it.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cstdlib>

#include "msg_fixtures.hpp"

namespace overstep {
namespace {

class Udpm : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::getenv("OVERSTEP_NETNS")) {
      FAIL()
          << "run through tests/integration/netns_run.sh: udpm tests stay in a private namespace";
    }
  }
};

template <typename T>
void roundTrip(lcm::LCM& bus, const std::string& channel, const T& sent) {
  struct Sink {
    int count = 0;
    std::vector<char> bytes;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      ++count;
      bytes.assign(static_cast<const char*>(rbuf->data),
                   static_cast<const char*>(rbuf->data) + rbuf->data_size);
    }
  } sink;
  lcm::Subscription* sub = bus.subscribe(channel, &Sink::on, &sink);
  ASSERT_EQ(bus.publish(channel, &sent), 0) << channel;
  for (int i = 0; i < 20 && sink.count == 0; ++i) bus.handleTimeout(100);
  bus.unsubscribe(sub);
  ASSERT_EQ(sink.count, 1) << channel;
  T got;
  ASSERT_EQ(got.decode(sink.bytes.data(), 0, static_cast<int>(sink.bytes.size())),
            static_cast<int>(sink.bytes.size()));
  std::vector<char> a(static_cast<std::size_t>(sent.getEncodedSize()));
  std::vector<char> b(static_cast<std::size_t>(got.getEncodedSize()));
  sent.encode(a.data(), 0, static_cast<int>(a.size()));
  got.encode(b.data(), 0, static_cast<int>(b.size()));
  EXPECT_EQ(a, b) << channel;
}

TEST_F(Udpm, EveryTypeCrossesTheBus) {
  lcm::LCM bus(std::getenv("LCM_DEFAULT_URL"));
  ASSERT_TRUE(bus.good());
  roundTrip(bus, "OVERSTEP_COMMAND", test::makeCommand(30));
  roundTrip(bus, "OVERSTEP_STATE", test::makeState(30));
  roundTrip(bus, "OVERSTEP_PLAN_REF", test::makePlanReference());
  roundTrip(bus, "OVERSTEP_STABILIZER", test::makeStabilizerStatus());
  roundTrip(bus, "OVERSTEP_RUNTIME", test::makeRuntimeStatus());
  roundTrip(bus, "OVERSTEP_REPLAY_CONTROL", test::makeReplayControl());
  roundTrip(bus, "OVERSTEP_SIM_STATUS", test::makeSimStatus());
}

}  // namespace
}  // namespace overstep
