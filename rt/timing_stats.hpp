#pragma once
// Timing statistics for real-time threads: a histogram of 1 us bins up to a bound, with an
// overflow count and the exact maximum; percentiles read from the bins (to 1 us; a
// percentile that falls into the overflow reports the maximum). The bins are allocated at
// construction; record() never allocates. One writer; readers on other threads take a
// snapshot() (relaxed atomics: a snapshot may be a few samples behind, never torn per bin).

#include "rt/clock.hpp"

#include <atomic>
#include <cstdint>
#include <memory>

namespace staa::rt {

struct TimingSummary {
  std::uint64_t count = 0;
  std::uint64_t overflow = 0;  // samples >= the bound
  double p50_us = 0.0;
  double p99_us = 0.0;
  double max_us = 0.0;
  double mean_us = 0.0;
};

class LatencyHistogram {
 public:
  explicit LatencyHistogram(std::uint32_t bound_us = 100'000);
  LatencyHistogram(const LatencyHistogram&) = delete;
  LatencyHistogram& operator=(const LatencyHistogram&) = delete;

  // Negative durations count as 0.
  void record(Nanos duration);
  void reset();  // writer thread only
  // Percentile p in [0, 100] in microseconds (the upper edge of the bin it falls in).
  double percentileUs(double p) const;
  TimingSummary summary() const;
  std::uint32_t boundUs() const { return bound_us_; }
  // f(us, count) for every non-empty bin in increasing order (bin us: [us, us + 1) us); the
  // samples at or beyond the bound are summary().overflow. A walk over all bins: not for a
  // real-time thread.
  template <class F>
  void forEachBin(F&& f) const {
    for (std::uint32_t i = 0; i < bound_us_; ++i) {
      const std::uint64_t n = bins_[i].load(std::memory_order_relaxed);
      if (n != 0) f(i, n);
    }
  }

 private:
  std::uint32_t bound_us_;
  std::unique_ptr<std::atomic<std::uint64_t>[]> bins_;
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::uint64_t> overflow_{0};
  std::atomic<std::int64_t> max_ns_{0};
  std::atomic<std::int64_t> sum_ns_{0};
};

}  // namespace staa::rt
