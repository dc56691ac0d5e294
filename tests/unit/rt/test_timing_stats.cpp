#include "rt/timing_stats.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace staa::rt {
namespace {

constexpr Nanos kMicro = 1000;

TEST(LatencyHistogram, PercentilesOfKnownSamplesAreBinUpperEdgesCappedAtTheMax) {
  LatencyHistogram h(1000);
  for (Nanos us = 1; us <= 100; ++us) h.record(us * kMicro);  // 1, 2, ..., 100 us
  // Nearest rank: p50 is the 50th sample (50 us, bin [50, 51) us), reported as 51.
  EXPECT_EQ(h.percentileUs(50.0), 51.0);
  EXPECT_EQ(h.percentileUs(99.0), 100.0);
  EXPECT_EQ(h.percentileUs(100.0), 100.0);  // bin edge 101, capped at the exact max 100
  EXPECT_EQ(h.percentileUs(0.0), 2.0);      // the smallest sample
  EXPECT_EQ(h.percentileUs(150.0), 100.0);  // clamped to 100
  EXPECT_EQ(h.percentileUs(-3.0), 2.0);    // clamped to 0

  const TimingSummary s = h.summary();
  EXPECT_EQ(s.count, 100u);
  EXPECT_EQ(s.overflow, 0u);
  EXPECT_EQ(s.p50_us, 51.0);
  EXPECT_EQ(s.p99_us, 100.0);
  EXPECT_EQ(s.max_us, 100.0);
  EXPECT_DOUBLE_EQ(s.mean_us, 50.5);
  EXPECT_EQ(h.boundUs(), 1000u);
}

TEST(LatencyHistogram, SubMicrosecondDetailKeepsExactMaxAndMean) {
  LatencyHistogram h(100);
  h.record(1500);  // bin [1, 2) us
  h.record(2500);  // bin [2, 3) us
  const TimingSummary s = h.summary();
  EXPECT_EQ(s.p50_us, 2.0);
  EXPECT_EQ(s.p99_us, 2.5);  // bin edge 3, capped at the exact max
  EXPECT_EQ(s.max_us, 2.5);
  EXPECT_DOUBLE_EQ(s.mean_us, 2.0);
}

TEST(LatencyHistogram, SamplesAtOrBeyondTheBoundOverflowAndReportTheMaximum) {
  LatencyHistogram h(10);
  h.record(5 * kMicro);
  h.record(10 * kMicro);  // exactly the bound: overflow
  h.record(50 * kMicro + 250);
  const TimingSummary s = h.summary();
  EXPECT_EQ(s.count, 3u);
  EXPECT_EQ(s.overflow, 2u);
  EXPECT_EQ(h.percentileUs(0.0), 6.0);
  EXPECT_EQ(s.p50_us, 50.25);  // in the overflow: the exact maximum
  EXPECT_EQ(s.p99_us, 50.25);
  EXPECT_EQ(s.max_us, 50.25);
  EXPECT_DOUBLE_EQ(s.mean_us, (5.0 + 10.0 + 50.25) / 3.0);
}

TEST(LatencyHistogram, NegativeDurationsCountAsZero) {
  LatencyHistogram h(10);
  h.record(-5 * kMicro);
  const TimingSummary s = h.summary();
  EXPECT_EQ(s.count, 1u);
  EXPECT_EQ(s.max_us, 0.0);
  EXPECT_EQ(s.mean_us, 0.0);
  EXPECT_EQ(s.p50_us, 0.0);  // bin edge 1 us, capped at the max
}

TEST(LatencyHistogram, EmptyAndResetReadAsZero) {
  LatencyHistogram h(10);
  TimingSummary s = h.summary();
  EXPECT_EQ(s.count, 0u);
  EXPECT_EQ(s.p99_us, 0.0);
  EXPECT_EQ(s.mean_us, 0.0);

  h.record(3 * kMicro);
  h.record(30 * kMicro);
  h.reset();
  s = h.summary();
  EXPECT_EQ(s.count, 0u);
  EXPECT_EQ(s.overflow, 0u);
  EXPECT_EQ(s.max_us, 0.0);
  EXPECT_EQ(s.p50_us, 0.0);
  EXPECT_EQ(h.percentileUs(100.0), 0.0);

  h.record(7 * kMicro);  // usable again after the reset
  s = h.summary();
  EXPECT_EQ(s.count, 1u);
  EXPECT_EQ(s.p50_us, 7.0);  // bin edge 8, capped at the max 7
  EXPECT_EQ(s.max_us, 7.0);
}

TEST(LatencyHistogram, ZeroBoundPutsEverythingInOverflow) {
  LatencyHistogram h(0);
  h.record(0);
  h.record(4 * kMicro);
  EXPECT_EQ(h.summary().overflow, 2u);
  EXPECT_EQ(h.percentileUs(50.0), 4.0);
}

TEST(LatencyHistogram, ReaderOnAnotherThreadSeesConsistentSnapshots) {
  LatencyHistogram h(100);
  constexpr int kSamples = 200'000;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (int i = 0; i < kSamples; ++i) h.record(static_cast<Nanos>(i % 50) * kMicro);
    done.store(true, std::memory_order_release);
  });
  std::uint64_t last_count = 0;
  bool monotonic = true;
  bool in_range = true;
  while (!done.load(std::memory_order_acquire)) {
    const TimingSummary s = h.summary();
    monotonic = monotonic && s.count >= last_count;
    last_count = s.count;
    // Every sample is below 50 us: no snapshot may report beyond that.
    in_range = in_range && s.p99_us <= 50.0 && s.max_us <= 49.0 && s.overflow == 0;
  }
  writer.join();
  EXPECT_TRUE(monotonic);
  EXPECT_TRUE(in_range);
  const TimingSummary s = h.summary();
  EXPECT_EQ(s.count, static_cast<std::uint64_t>(kSamples));
  EXPECT_EQ(s.max_us, 49.0);
  EXPECT_EQ(s.p50_us, 25.0);  // 50 equally likely values 0..49 us: the 25th is 24 us
}

}  // namespace
}  // namespace staa::rt
