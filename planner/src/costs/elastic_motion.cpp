// Seed eq. (20): the elastic ankle joints' motion small: their accelerations (reference
// 1 rad/s^2), velocities (0.1 rad/s) and deflections (0.01 rad), summed over the four bushings.
#include "cost_term.hpp"

namespace overstep::planner::detail {
namespace {

enum class Order { kPosition, kVelocity, kAcceleration };

class ElasticMotion final : public SampleCost {
 public:
  explicit ElasticMotion(Order o) : order_(o) {}
  const char* name() const override {
    return order_ == Order::kPosition   ? "elastic_pos"
           : order_ == Order::kVelocity ? "elastic_vel"
                                        : "elastic_acc";
  }
  double value(const ProblemModel& p, const SampleData& d) const override {
    const State& st = *d.st;
    double sum = 0.0;
    for (int j = 0; j < 4; ++j) {
      const int c = p.flex_coord[static_cast<std::size_t>(j)];
      switch (order_) {
        case Order::kAcceleration:
          sum += st.a(c) * st.a(c);
          break;
        case Order::kVelocity:
          sum += st.v(c) * st.v(c) / 0.01;
          break;
        case Order::kPosition:
          sum += st.q(c) * st.q(c) / 1e-4;
          break;
      }
    }
    return sum;
  }

 private:
  Order order_;
};

}  // namespace

std::unique_ptr<SampleCost> makeElasticAcceleration() {
  return std::make_unique<ElasticMotion>(Order::kAcceleration);
}
std::unique_ptr<SampleCost> makeElasticVelocity() {
  return std::make_unique<ElasticMotion>(Order::kVelocity);
}
std::unique_ptr<SampleCost> makeElasticPosition() {
  return std::make_unique<ElasticMotion>(Order::kPosition);
}

}  // namespace overstep::planner::detail
