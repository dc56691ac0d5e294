#include "rt/timing_stats.hpp"

#include <algorithm>
#include <cmath>

namespace staa::rt {

namespace {

constexpr Nanos kNanosPerMicro = 1000;

// One writer: a relaxed load and store is enough (and cheaper than a locked read-modify-write);
// readers only need each value untorn.
void bump(std::atomic<std::uint64_t>& a, std::uint64_t by = 1) {
  a.store(a.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
}

}  // namespace

LatencyHistogram::LatencyHistogram(std::uint32_t bound_us)
    : bound_us_(bound_us), bins_(std::make_unique<std::atomic<std::uint64_t>[]>(bound_us)) {}

void LatencyHistogram::record(Nanos duration) {
  if (duration < 0) duration = 0;
  const auto us = static_cast<std::uint64_t>(duration / kNanosPerMicro);
  if (us >= bound_us_) {
    bump(overflow_);
  } else {
    bump(bins_[us]);
  }
  sum_ns_.store(sum_ns_.load(std::memory_order_relaxed) + duration, std::memory_order_relaxed);
  if (duration > max_ns_.load(std::memory_order_relaxed)) max_ns_.store(duration, std::memory_order_relaxed);
  // count_ last: a reader that sees the count has (usually) seen the sample's bin too; the
  // percentile walk does not rely on it, it totals the bins it reads.
  bump(count_);
}

void LatencyHistogram::reset() {
  for (std::uint32_t i = 0; i < bound_us_; ++i) bins_[i].store(0, std::memory_order_relaxed);
  count_.store(0, std::memory_order_relaxed);
  overflow_.store(0, std::memory_order_relaxed);
  max_ns_.store(0, std::memory_order_relaxed);
  sum_ns_.store(0, std::memory_order_relaxed);
}

double LatencyHistogram::percentileUs(double p) const {
  if (std::isnan(p)) p = 0.0;
  p = std::clamp(p, 0.0, 100.0);
  // Total what this read sees (bins and overflow), so a snapshot taken while the writer
  // records stays self-consistent instead of walking past a count it has not seen yet.
  std::uint64_t total = overflow_.load(std::memory_order_relaxed);
  for (std::uint32_t i = 0; i < bound_us_; ++i) total += bins_[i].load(std::memory_order_relaxed);
  if (total == 0) return 0.0;
  // Nearest rank: the smallest sample with at least p% of the samples at or below it.
  auto rank = static_cast<std::uint64_t>(std::ceil(p / 100.0 * static_cast<double>(total)));
  rank = std::clamp<std::uint64_t>(rank, 1, total);
  std::uint64_t seen = 0;
  for (std::uint32_t i = 0; i < bound_us_; ++i) {
    seen += bins_[i].load(std::memory_order_relaxed);
    if (seen >= rank) {
      // The bin's upper edge, but never above the exact maximum (a p99 above the max reads
      // as a bug in a report).
      const double max_us =
          static_cast<double>(max_ns_.load(std::memory_order_relaxed)) / static_cast<double>(kNanosPerMicro);
      return std::min(static_cast<double>(i) + 1.0, max_us);
    }
  }
  // In the overflow: the bins know nothing finer than "beyond the bound", the maximum is exact.
  return static_cast<double>(max_ns_.load(std::memory_order_relaxed)) / static_cast<double>(kNanosPerMicro);
}

TimingSummary LatencyHistogram::summary() const {
  TimingSummary s;
  s.count = count_.load(std::memory_order_relaxed);
  s.overflow = overflow_.load(std::memory_order_relaxed);
  s.p50_us = percentileUs(50.0);
  s.p99_us = percentileUs(99.0);
  s.max_us = static_cast<double>(max_ns_.load(std::memory_order_relaxed)) / static_cast<double>(kNanosPerMicro);
  if (s.count > 0) {
    s.mean_us = static_cast<double>(sum_ns_.load(std::memory_order_relaxed)) / static_cast<double>(s.count) /
                static_cast<double>(kNanosPerMicro);
  }
  return s;
}

}  // namespace staa::rt
