#pragma once
/// \file
/// Loop timing statistics for the runtime status: period and processing time over a sliding
/// window (min / mean / max / 99th percentile), cumulative overruns. Fixed capacity: recording
/// and summarising never allocate.

#include <algorithm>
#include <array>
#include <cmath>
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
    const double bin = std::clamp(period_us / kBinUs, 0.0, static_cast<double>(kBins - 1));
    ++hist_[static_cast<std::size_t>(bin)];
    ++total_;
    run_min_ = std::min(run_min_, period_us);
    run_max_ = std::max(run_max_, period_us);
    run_sum_ += period_us;
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

  /// Whole-run period statistics (every recorded tick; the percentile from a 10 us histogram).
  Summary run() const {
    Summary s;
    s.count = static_cast<int>(std::min<std::int64_t>(total_, std::numeric_limits<int>::max()));
    if (total_ == 0) return s;
    s.period_min = run_min_;
    s.period_max = run_max_;
    s.period_mean = run_sum_ / static_cast<double>(total_);
    const auto rank = static_cast<std::int64_t>(std::ceil(0.99 * static_cast<double>(total_)));
    std::int64_t seen = 0;
    for (int b = 0; b < kBins; ++b) {
      seen += hist_[static_cast<std::size_t>(b)];
      if (seen >= rank) {
        s.period_p99 = (b + 1) * kBinUs;
        break;
      }
    }
    return s;
  }

 private:
  static constexpr int kBins = 20000;  ///< 10 us bins up to 200 ms
  static constexpr double kBinUs = 10.0;
  std::array<std::uint32_t, kBins> hist_{};
  std::int64_t total_ = 0;
  double run_min_ = std::numeric_limits<double>::infinity(), run_max_ = 0.0, run_sum_ = 0.0;
  std::array<double, kCapacity> period_{}, processing_{}, scratch_{};
  int head_ = 0, count_ = 0;
  std::int64_t overruns_ = 0;
};

}  // namespace overstep::runtime
