// Proves that Stabilizer::step() never touches the heap: this executable replaces the global
// operator new/delete with counting versions (its own binary, so no other test is affected).
#include <gtest/gtest.h>

#include <cmath>

#include "alloc_counter.hpp"
#include "overstep/stabilizer/stabilizer.hpp"
#include "stabilizer_plants.hpp"

namespace st = overstep::stabilizer;

TEST(StabilizerRealTime, StepNeverAllocates) {
  for (auto feedback : {st::Feedback::Lipm, st::Feedback::Dcm}) {
    st::Params p = overstep::test::plantParams();
    p.feedback = feedback;
    p.com_admittance = 2.0;
    const auto feet = overstep::test::feetAt(0.1);
    st::Stabilizer s(p);
    st::Reference ds = overstep::test::staticReference(Eigen::Vector2d(0.0, 0.0), feet);
    st::Reference ss =
        overstep::test::staticReference(Eigen::Vector2d(0.0, -0.1), feet, {{true, false}});
    st::Output out;
    st::Measurement m = overstep::test::measurementWithZmp(Eigen::Vector3d(0.01, 0, 0.8),
                                                           Eigen::Vector3d(0.05, 0, 0),
                                                           Eigen::Vector2d(0.3, 0.2), feet);
    st::Measurement bad = m;
    bad.com.x() = std::nan("");
    s.enable();
    const long before = overstep::test::allocations();
    for (int i = 0; i < 2000; ++i) {
      s.setReference(i % 400 < 200 ? ds : ss);  // double and single support, clamped ZMP requests
      if (i == 1500)
        s.step(bad, 0.005, out);  // fault -> hold
      else
        s.step(m, 0.005, out);
      if (i == 1600) s.disable();  // ramp out of the hold
    }
    EXPECT_EQ(overstep::test::allocations() - before, 0) << "heap allocations inside step()";
    EXPECT_EQ(s.status().mode, st::Mode::Off);
  }
}

TEST(StabilizerRealTime, TheCounterWorks) {
  const long before = overstep::test::allocations();
  auto* v = new std::vector<int>(100);
  delete v;
  EXPECT_GE(overstep::test::allocations() - before, 2);
}
