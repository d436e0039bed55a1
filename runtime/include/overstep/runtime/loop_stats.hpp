#pragma once
/// \file
/// Loop timing statistics for the runtime status: period and processing time over a sliding
/// window (min / mean / max / 99th percentile), cumulative overruns. Fixed capacity: recording
/// and summarising never allocate.

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>

namespace overstep::runtime {

class LoopStats {
 public:
  static constexpr int kCapacity = 1024;

  struct Summary {
    double period_min = 0, period_mean = 0, period_max = 0, period_p99 = 0;  ///< us
    double processing_mean = 0, processing_max = 0;                          ///< us
    int count = 0;
  };

  /// One tick: the time since the previous tick and the time the tick's work took (us).
  void record(double period_us, double processing_us, double nominal_period_us) {
    period_[static_cast<std::size_t>(head_)] = period_us;
    processing_[static_cast<std::size_t>(head_)] = processing_us;
    head_ = (head_ + 1) % kCapacity;
    count_ = std::min(count_ + 1, kCapacity);
    if (processing_us > nominal_period_us) ++overruns_;
  }
  /// Statistics of the last `window` ticks (at most kCapacity); the window is then cleared if
  /// `reset` is true.
  Summary summary(int window, bool reset) {
    Summary s;
    const int n = std::min(window, count_);
    s.count = n;
    if (n == 0) return s;
    s.period_min = std::numeric_limits<double>::infinity();
    double psum = 0.0, qsum = 0.0;
    for (int i = 0; i < n; ++i) {
      const auto idx = static_cast<std::size_t>((head_ - 1 - i + kCapacity) % kCapacity);
      const double p = period_[idx];
      scratch_[static_cast<std::size_t>(i)] = p;
      s.period_min = std::min(s.period_min, p);
      s.period_max = std::max(s.period_max, p);
      psum += p;
      qsum += processing_[idx];
      s.processing_max = std::max(s.processing_max, processing_[idx]);
    }
    s.period_mean = psum / n;
    s.processing_mean = qsum / n;
    const int rank = std::min(n - 1, static_cast<int>(0.99 * n));
    std::nth_element(scratch_.begin(), scratch_.begin() + rank, scratch_.begin() + n);
    s.period_p99 = scratch_[static_cast<std::size_t>(rank)];
    if (reset) count_ = 0;
    return s;
  }
  std::int64_t overruns() const { return overruns_; }

 private:
  std::array<double, kCapacity> period_{}, processing_{}, scratch_{};
  int head_ = 0, count_ = 0;
  std::int64_t overruns_ = 0;
};

}  // namespace overstep::runtime
