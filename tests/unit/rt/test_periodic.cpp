#include "rt/periodic.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace staa::rt {
namespace {

constexpr Nanos kPeriod = 10 * kNanosPerMilli;
constexpr Nanos kT0 = 5 * kNanosPerSecond;  // an arbitrary clock origin, not 0

// One cycle in lockstep: sleep to the deadline, "run" a body that takes `exec`, finish.
struct Cycle {
  Wake wake;
  std::uint64_t skipped = 0;
};
Cycle runCycle(PeriodicLoop& loop, ManualClock& clock, Nanos exec) {
  Cycle c;
  c.wake = loop.wait();
  clock.advance(exec);
  c.skipped = loop.finish();
  return c;
}

TEST(PeriodicLoop, NormalCyclesWakeExactlyOnEveryDeadline) {
  ManualClock clock(kT0);
  const Nanos start = clock.now() + kPeriod;
  PeriodicLoop loop(clock, kPeriod, start);
  for (std::uint64_t k = 0; k < 100; ++k) {
    const Cycle c = runCycle(loop, clock, 3 * kNanosPerMilli);
    ASSERT_EQ(c.wake.index, k);
    ASSERT_EQ(c.wake.deadline, start + static_cast<Nanos>(k) * kPeriod);
    ASSERT_EQ(c.wake.woke, c.wake.deadline);
    ASSERT_EQ(c.wake.latency, 0);
    ASSERT_EQ(c.wake.error, 0);
    ASSERT_EQ(c.skipped, 0u);
    ASSERT_EQ(loop.lastExecution(), 3 * kNanosPerMilli);
  }
  EXPECT_EQ(loop.nextDeadline(), start + 100 * kPeriod);
  const PeriodicCounters& n = loop.counters();
  EXPECT_EQ(n.cycles, 100u);
  EXPECT_EQ(n.overruns, 0u);
  EXPECT_EQ(n.execution_overruns, 0u);
  EXPECT_EQ(n.late_wakeups, 0u);
  EXPECT_EQ(n.skipped_periods, 0u);
  EXPECT_EQ(n.sleep_errors, 0u);

  const TimingSummary wake = loop.wakeLatency().summary();
  EXPECT_EQ(wake.count, 100u);
  EXPECT_EQ(wake.max_us, 0.0);
  EXPECT_EQ(wake.mean_us, 0.0);
  EXPECT_EQ(wake.p99_us, 0.0);  // bin [0, 1) us: its upper edge capped at the exact max 0
  const TimingSummary exec = loop.execution().summary();
  EXPECT_EQ(exec.count, 100u);
  EXPECT_EQ(exec.overflow, 0u);
  EXPECT_EQ(exec.max_us, 3000.0);
  EXPECT_EQ(exec.mean_us, 3000.0);
  EXPECT_EQ(exec.p50_us, 3000.0);  // bin [3000, 3001) us, capped at the exact max
}

TEST(PeriodicLoop, ExecutionOverrunSkipsMissedPeriodsWithoutBurst) {
  ManualClock clock(kT0);
  const Nanos start = clock.now() + kPeriod;
  PeriodicLoop loop(clock, kPeriod, start);
  for (int k = 0; k < 5; ++k) runCycle(loop, clock, kPeriod / 2);

  // Cycle 5 wakes at start + 5P and its body takes 2.5 periods: it ends at start + 7.5P,
  // past deadlines 6 and 7; the next is deadline 8.
  const Cycle slow = runCycle(loop, clock, 5 * kPeriod / 2);
  EXPECT_EQ(slow.wake.index, 5u);
  EXPECT_EQ(slow.skipped, 2u);
  EXPECT_EQ(loop.lastExecution(), 5 * kPeriod / 2);
  EXPECT_EQ(loop.nextDeadline(), start + 8 * kPeriod);
  const PeriodicCounters& n = loop.counters();
  EXPECT_EQ(n.overruns, 1u);
  EXPECT_EQ(n.execution_overruns, 1u);
  EXPECT_EQ(n.late_wakeups, 0u);
  EXPECT_EQ(n.skipped_periods, 2u);

  // No burst of catch-up cycles: every following wake sleeps to a future deadline, one period
  // after the previous wake.
  Nanos previous_woke = slow.wake.woke;
  for (std::uint64_t i = 0; i < 10; ++i) {
    const Nanos before = clock.now();
    const Cycle c = runCycle(loop, clock, kPeriod / 2);
    EXPECT_EQ(c.wake.index, 8 + i);
    EXPECT_EQ(c.wake.deadline, start + static_cast<Nanos>(8 + i) * kPeriod);
    EXPECT_GT(c.wake.deadline, before);  // it really slept
    EXPECT_EQ(c.wake.latency, 0);
    EXPECT_EQ(c.skipped, 0u);
    EXPECT_GT(c.wake.woke, previous_woke);
    if (i > 0) {
      EXPECT_EQ(c.wake.woke - previous_woke, kPeriod);
    }
    previous_woke = c.wake.woke;
  }
  EXPECT_EQ(n.overruns, 1u);
  EXPECT_EQ(n.cycles, 16u);

  // The histograms saw all 16 cycles; the slow one is the maximum execution.
  const TimingSummary exec = loop.execution().summary();
  EXPECT_EQ(exec.count, 16u);
  EXPECT_EQ(exec.max_us, 25000.0);
  EXPECT_EQ(exec.p50_us, 5001.0);
  EXPECT_EQ(loop.execution().percentileUs(100.0), 25000.0);
  EXPECT_EQ(loop.wakeLatency().summary().count, 16u);
}

TEST(PeriodicLoop, LateWakeupOverrunIsAttributedToThePlatform) {
  ManualClock clock(kT0);
  const Nanos start = clock.now() + kPeriod;
  PeriodicLoop loop(clock, kPeriod, start);
  runCycle(loop, clock, kPeriod / 10);

  // A late wake-up that still ends before the next deadline is no overrun.
  clock.delayNextWake(kPeriod / 2);
  const Cycle fits = runCycle(loop, clock, 3 * kPeriod / 10);
  EXPECT_EQ(fits.wake.latency, kPeriod / 2);
  EXPECT_EQ(fits.skipped, 0u);
  EXPECT_EQ(loop.counters().overruns, 0u);

  // 0.8 period late plus a 0.3-period body ends 0.1 period past the next deadline: the body
  // fit in its period, the platform woke us late.
  clock.delayNextWake(8 * kPeriod / 10);
  const Cycle late = runCycle(loop, clock, 3 * kPeriod / 10);
  EXPECT_EQ(late.wake.index, 2u);
  EXPECT_EQ(late.wake.latency, 8 * kPeriod / 10);
  EXPECT_EQ(late.skipped, 1u);
  const PeriodicCounters& n = loop.counters();
  EXPECT_EQ(n.overruns, 1u);
  EXPECT_EQ(n.late_wakeups, 1u);
  EXPECT_EQ(n.execution_overruns, 0u);
  EXPECT_EQ(n.skipped_periods, 1u);
  EXPECT_EQ(loop.nextDeadline(), start + 4 * kPeriod);

  // The delay applied once: the next wake is on time.
  const Cycle next = runCycle(loop, clock, kPeriod / 10);
  EXPECT_EQ(next.wake.deadline, start + 4 * kPeriod);
  EXPECT_EQ(next.wake.latency, 0);

  // Wake latencies: 0, 5000, 8000, 0 us.
  const LatencyHistogram& wake = loop.wakeLatency();
  const TimingSummary s = wake.summary();
  EXPECT_EQ(s.count, 4u);
  EXPECT_EQ(s.max_us, 8000.0);
  EXPECT_EQ(s.mean_us, 3250.0);
  EXPECT_EQ(s.p50_us, 1.0);
  EXPECT_EQ(wake.percentileUs(75.0), 5001.0);
  EXPECT_EQ(s.p99_us, 8000.0);
}

TEST(PeriodicLoop, EndingExactlyOnTheNextDeadlineIsNoOverrun) {
  ManualClock clock(kT0);
  PeriodicLoop loop(clock, kPeriod, kT0);
  const Cycle c = runCycle(loop, clock, kPeriod);
  EXPECT_EQ(c.skipped, 0u);
  EXPECT_EQ(loop.counters().overruns, 0u);
  EXPECT_EQ(loop.nextDeadline(), kT0 + kPeriod);
  EXPECT_EQ(loop.wait().latency, 0);
}

TEST(PeriodicLoop, OverflowingBodyBeyondTheHistogramBoundCountsOverflow) {
  ManualClock clock(kT0);
  PeriodicLoop loop(clock, kPeriod, kT0, /*histogram_bound_us=*/1000);
  runCycle(loop, clock, 4 * kPeriod + kPeriod / 4);  // 42.5 ms: beyond the 1 ms bound
  const TimingSummary exec = loop.execution().summary();
  EXPECT_EQ(exec.overflow, 1u);
  EXPECT_EQ(exec.p99_us, 42500.0);  // in the overflow: the exact maximum
  EXPECT_EQ(loop.counters().skipped_periods, 4u);
  EXPECT_EQ(loop.nextDeadline(), kT0 + 5 * kPeriod);
}

TEST(PeriodicLoop, RejectsANonPositivePeriodNamingIt) {
  ManualClock clock;
  try {
    PeriodicLoop loop(clock, -5, 0);
    FAIL() << "a negative period was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("-5"), std::string::npos) << e.what();
  }
  EXPECT_THROW(PeriodicLoop(clock, 0, 0), std::invalid_argument);
}

// A clock whose sleeps fail (as clock_nanosleep does with EINVAL on a bad deadline).
class FailingClock final : public Clock {
 public:
  Nanos now() const override { return now_; }
  int sleepUntil(Nanos) override { return 22; }
  Nanos now_ = 0;
};

TEST(PeriodicLoop, CountsSleepErrorsAndKeepsTheSchedule) {
  FailingClock clock;
  PeriodicLoop loop(clock, kPeriod, kPeriod);
  const Wake w = loop.wait();
  EXPECT_EQ(w.error, 22);
  loop.finish();
  EXPECT_EQ(loop.counters().sleep_errors, 1u);
  EXPECT_EQ(loop.counters().cycles, 1u);
  EXPECT_EQ(loop.wakeLatency().summary().count, 0u);  // no latency recorded for a failed sleep
  EXPECT_EQ(loop.nextDeadline(), 2 * kPeriod);
}

TEST(ManualClock, SleepingNeverMovesTimeBackwards) {
  ManualClock clock(100);
  EXPECT_EQ(clock.sleepUntil(50), 0);
  EXPECT_EQ(clock.now(), 100);
  clock.delayNextWake(7);
  clock.sleepUntil(200);
  EXPECT_EQ(clock.now(), 207);
  clock.sleepUntil(300);
  EXPECT_EQ(clock.now(), 300);  // the delay was for one sleep only
}

TEST(PeriodicLoop, RunsOnTheMonotonicClock) {
  MonotonicClock clock;
  constexpr Nanos kRealPeriod = 2 * kNanosPerMilli;
  const Nanos start = clock.now() + kRealPeriod;
  PeriodicLoop loop(clock, kRealPeriod, start);
  std::uint64_t expected_index = 0;
  for (int i = 0; i < 20; ++i) {
    const Wake w = loop.wait();
    ASSERT_EQ(w.error, 0);
    ASSERT_EQ(w.index, expected_index);
    ASSERT_EQ(w.deadline, start + static_cast<Nanos>(w.index) * kRealPeriod);
    ASSERT_GE(w.woke, w.deadline);  // an absolute sleep never returns early
    expected_index += 1 + loop.finish();
  }
  // Logic only (timings are not asserted: the machine is shared): every deadline is on the
  // grid, and each one was either run or counted as skipped.
  const PeriodicCounters& n = loop.counters();
  EXPECT_EQ(n.cycles, 20u);
  EXPECT_EQ(n.sleep_errors, 0u);
  EXPECT_EQ(n.overruns, n.execution_overruns + n.late_wakeups);
  EXPECT_EQ(loop.nextDeadline(), start + static_cast<Nanos>(20 + n.skipped_periods) * kRealPeriod);
  EXPECT_GE(clock.now(), start + 19 * kRealPeriod);
}

}  // namespace
// With the body's CPU time: a body that took 2.5 periods of wall time but only a fifth of a
// period of CPU was kept off the CPU (the platform's), not an execution overrun; one that
// used 1.2 periods of CPU is ours.
TEST(PeriodicLoop, CpuTimeTellsPreemptionFromAnExecutionOverrun) {
  constexpr Nanos kPeriod = 10 * kNanosPerMilli;
  ManualClock clock(0);
  PeriodicLoop loop(clock, kPeriod, kPeriod);
  loop.wait();
  clock.advance(kPeriod * 5 / 2);
  EXPECT_EQ(loop.finish(kPeriod / 5), 2u);
  EXPECT_EQ(loop.counters().preempted, 1u);
  EXPECT_EQ(loop.counters().execution_overruns, 0u);
  loop.wait();
  clock.advance(kPeriod * 5 / 2);
  loop.finish(kPeriod * 6 / 5);
  EXPECT_EQ(loop.counters().execution_overruns, 1u);
  EXPECT_EQ(loop.counters().preempted, 1u);
  EXPECT_EQ(loop.counters().overruns, 2u);
  loop.wait();
  clock.advance(kPeriod / 2);
  EXPECT_EQ(loop.finish(kPeriod / 2), 0u);  // on time: nothing counted
  EXPECT_EQ(loop.counters().overruns, 2u);
  EXPECT_GE(threadCpuTime(), 0);
}

}  // namespace staa::rt
