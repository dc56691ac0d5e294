// Overrun attribution from recorded traces of one cycle under an injected clock: the times
// (from the wake-up) at which the body read its clock, its CPU time and its wake-up delay.
// The stall probe measures the largest gap between two reads; the periodic loop attributes
// the overrun to us, a late wake-up, preemption or a stall of the platform.
#include "rt/periodic.hpp"
#include "rt/stall_probe.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace staa::rt {
namespace {

constexpr Nanos kMicro = 1000;
constexpr Nanos kPeriod = 33'333'333;  // 30 Hz
constexpr Nanos kT0 = 7 * kNanosPerSecond;

// A cycle as recorded: its wake-up delay, the clock reads of its body (from the wake-up),
// and the body's CPU time.
struct Trace {
  Nanos wake_delay = 0;
  std::vector<Nanos> reads;
  Nanos cpu = 0;
};

// Reads every `step` from `from` up to and including `to` (a planner popping).
void readsEvery(Trace& t, Nanos from, Nanos to, Nanos step = 100 * kMicro) {
  for (Nanos r = from; r <= to; r += step) t.reads.push_back(r);
}

struct Replay {
  ManualClock clock{kT0};
  PeriodicLoop loop{clock, kPeriod, kT0 + kPeriod};
  StallProbe probe;

  // Plays one cycle: returns the gap the probe measured.
  Nanos play(const Trace& t) {
    clock.delayNextWake(t.wake_delay);
    const Wake w = loop.wait();
    probe.begin(w.woke);
    for (const Nanos r : t.reads) {
      clock.set(w.woke + r);
      probe.read(clock.now());
    }
    const Nanos gap = probe.end(clock.now());
    loop.finish(t.cpu, probe.lastGap());
    return gap;
  }
};

void expectCounts(const PeriodicCounters& c, std::uint64_t ours, std::uint64_t late, std::uint64_t preempted,
                  std::uint64_t stalls) {
  EXPECT_EQ(c.execution_overruns, ours);
  EXPECT_EQ(c.late_wakeups, late);
  EXPECT_EQ(c.preempted, preempted);
  EXPECT_EQ(c.stalls, stalls);
  EXPECT_EQ(c.overruns, ours + late + preempted + stalls);
}

TEST(StallAttribution, BodyWorkingPastThePeriodIsOurs) {
  Replay r;
  Trace t;
  readsEvery(t, 0, 40 * kNanosPerMilli);  // 40 ms of pops, never off the CPU
  t.cpu = 40 * kNanosPerMilli;
  EXPECT_EQ(r.play(t), 100 * kMicro);
  expectCounts(r.loop.counters(), 1, 0, 0, 0);
  EXPECT_EQ(r.loop.counters().max_own_execution, 40 * kNanosPerMilli);
}

TEST(StallAttribution, ShortBodyWokenLateIsALateWakeup) {
  Replay r;
  Trace t;
  t.wake_delay = 30 * kNanosPerMilli;
  readsEvery(t, 0, 10 * kNanosPerMilli);
  t.cpu = 10 * kNanosPerMilli;
  r.play(t);
  expectCounts(r.loop.counters(), 0, 1, 0, 0);
}

TEST(StallAttribution, TenMillisecondGapWhoseRemainingWorkFitsIsAStall) {
  Replay r;
  Trace t;
  readsEvery(t, 0, 12 * kNanosPerMilli);
  readsEvery(t, 22 * kNanosPerMilli, 38 * kNanosPerMilli);  // 10 ms without a read
  t.cpu = 38 * kNanosPerMilli;  // the stall hid from the CPU clock too (a VM's stolen time)
  EXPECT_EQ(r.play(t), 10 * kNanosPerMilli);
  expectCounts(r.loop.counters(), 0, 0, 0, 1);
  EXPECT_EQ(r.loop.counters().max_own_execution, 28 * kNanosPerMilli);
}

TEST(StallAttribution, TenMillisecondGapWhoseRemainingWorkDoesNotFitIsOurs) {
  Replay r;
  Trace t;
  readsEvery(t, 0, 30 * kNanosPerMilli);
  readsEvery(t, 40 * kNanosPerMilli, 45 * kNanosPerMilli);  // 45 - 10 = 35 ms > the period
  t.cpu = 45 * kNanosPerMilli;
  EXPECT_EQ(r.play(t), 10 * kNanosPerMilli);
  expectCounts(r.loop.counters(), 1, 0, 0, 0);
  EXPECT_EQ(r.loop.counters().max_own_execution, 35 * kNanosPerMilli);
}

TEST(StallAttribution, ManySmallGapsWithLittleCpuArePreemption) {
  Replay r;
  Trace t;
  // 2 ms gaps (below kStallGap) all along: the thread was shared, never stalled.
  readsEvery(t, 0, 40 * kNanosPerMilli, 2 * kNanosPerMilli);
  t.cpu = 20 * kNanosPerMilli;
  EXPECT_EQ(r.play(t), 2 * kNanosPerMilli);
  expectCounts(r.loop.counters(), 0, 0, 1, 0);
  EXPECT_EQ(r.loop.counters().max_own_execution, 40 * kNanosPerMilli);  // no stall to take out
}

TEST(StallAttribution, AGapBelowTheStallThresholdIsNotAStall) {
  Replay r;
  Trace t;
  readsEvery(t, 0, 20 * kNanosPerMilli);
  readsEvery(t, 20 * kNanosPerMilli + kStallGap - kMicro, 36 * kNanosPerMilli);
  t.cpu = 36 * kNanosPerMilli;
  r.play(t);
  expectCounts(r.loop.counters(), 1, 0, 0, 0);
}

TEST(StallAttribution, TheGapFromTheWakeupAndToTheEndCount) {
  StallProbe p;
  p.begin(1000);
  p.read(1000 + 5 * kNanosPerMilli);  // the first read, 5 ms after waking
  EXPECT_EQ(p.currentGap(), 5 * kNanosPerMilli);
  p.read(1000 + 6 * kNanosPerMilli);
  EXPECT_EQ(p.end(1000 + 13 * kNanosPerMilli), 7 * kNanosPerMilli);  // the tail after the last read
  EXPECT_EQ(p.lastGap(), 7 * kNanosPerMilli);
  // The next cycle starts afresh; reads outside a cycle measure nothing.
  p.read(1000 + 100 * kNanosPerMilli);
  p.begin(1000 + 200 * kNanosPerMilli);
  EXPECT_EQ(p.end(1000 + 200 * kNanosPerMilli + kMicro), kMicro);
}

TEST(StallAttribution, AFinishWithoutAStallNeverCountsOne) {
  Replay r;
  r.loop.wait();
  r.clock.advance(38 * kNanosPerMilli);
  r.loop.finish(38 * kNanosPerMilli);  // the CPU time only, as before the probe
  expectCounts(r.loop.counters(), 1, 0, 0, 0);
}

// A body that blocked (a voluntary context switch: it slept, took a lock, waited for I/O) is
// ours even when its gap looks like a stall and its CPU time like preemption.
TEST(StallAttribution, ABodyThatBlockedIsOursNeverTheStallItsGapLooksLike) {
  // 2 ms of work, then 36 ms off the CPU: a stall by its gap alone.
  const auto play = [](Replay& r, std::int64_t switches) {
    r.loop.wait();
    r.probe.begin(r.clock.now());
    r.clock.advance(2 * kNanosPerMilli);
    r.probe.read(r.clock.now());
    r.clock.advance(36 * kNanosPerMilli);
    r.probe.read(r.clock.now());
    r.probe.end(r.clock.now());
    r.loop.finish(2 * kNanosPerMilli, r.probe.lastGap(), switches);
  };
  Replay r;
  play(r, 1);
  expectCounts(r.loop.counters(), 1, 0, 0, 0);
  EXPECT_EQ(r.loop.counters().blocked_cycles, 1u);
  // The same cycle without the switch: the platform's stall.
  Replay s;
  play(s, 0);
  expectCounts(s.loop.counters(), 0, 0, 0, 1);
  EXPECT_EQ(s.loop.counters().blocked_cycles, 0u);

  // A body that blocked within its period is no overrun, but it is counted.
  Replay q;
  q.loop.wait();
  q.clock.advance(5 * kNanosPerMilli);
  q.loop.finish(kNanosPerMilli, 4 * kNanosPerMilli, 3);
  expectCounts(q.loop.counters(), 0, 0, 0, 0);
  EXPECT_EQ(q.loop.counters().blocked_cycles, 1u);
  q.loop.wait();
  q.clock.advance(5 * kNanosPerMilli);
  q.loop.finish(kNanosPerMilli, 0, -1);  // not measured: never counted
  EXPECT_EQ(q.loop.counters().blocked_cycles, 1u);
  EXPECT_EQ(q.loop.counters().last_blocked_cycle, 1u) << "cycle 0 blocked";

  // Page faults: counted per cycle, and beside a block they say the wait was on memory.
  q.loop.wait();
  q.loop.finish(kNanosPerMilli, 0, 2, 5);  // blocked and faulted
  q.loop.wait();
  q.loop.finish(kNanosPerMilli, 0, 0, 1);  // faulted only
  q.loop.wait();
  q.loop.finish(kNanosPerMilli, 0, 1, 0);  // blocked only: a lock or I/O
  q.loop.wait();
  q.loop.finish(kNanosPerMilli, 0, 0, -1);  // faults not measured
  const PeriodicCounters& c = q.loop.counters();
  EXPECT_EQ(c.blocked_cycles, 3u);
  EXPECT_EQ(c.faulted_cycles, 2u);
  EXPECT_EQ(c.blocked_faulted_cycles, 1u);
  EXPECT_EQ(c.last_blocked_cycle, 5u) << "cycle 4 was the last that blocked";
}

// The thread's probe reads the monotonic clock: each read's gap is exactly the time since the
// previous read (no timing asserted: a shared machine may stall the test itself).
TEST(StallAttribution, TheThreadsProbeRecordsEveryMonotonicRead) {
  StallProbe& p = StallProbe::local();
  const Nanos t0 = monotonicNow();
  p.begin(t0);
  const Nanos a = StallProbe::now();
  EXPECT_GE(a, t0);
  EXPECT_EQ(p.currentGap(), a - t0);
  const Nanos b = StallProbe::now();
  EXPECT_GE(b, a);
  EXPECT_EQ(p.currentGap(), std::max(a - t0, b - a));
  const Nanos c = monotonicNow();
  EXPECT_EQ(p.end(c), std::max({a - t0, b - a, c - b}));
  EXPECT_LE(b, monotonicNow());
}

}  // namespace
}  // namespace staa::rt
