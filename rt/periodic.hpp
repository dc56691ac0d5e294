#pragma once
// A periodic schedule on absolute deadlines (docs/ARCHITECTURE.md section 3): deadline k is
// start + k * period. After a cycle's body the next deadline is the first one still in the
// future: when the body ran past one or more deadlines, an overrun is counted and the missed
// periods are skipped (no burst of catch-up cycles). Every missed deadline is attributed, in
// this order (exec: the body's wall-clock time from its wake-up to its end):
//   - late wake-up (the platform's): exec fit in a period, but the body woke so late that it
//     ended past the next deadline;
//   - blocked (ours): the body made a voluntary context switch (it slept, waited on a lock or
//     for I/O; finish(cpu_time, stall, switches)); counted as an execution overrun, since
//     the time off the CPU was the body's own doing, never a stall or preemption;
//   - stall (the platform's): given the largest gap between two clock reads of the body
//     (finish(cpu_time, stall), rt/stall_probe.hpp), a gap of at least kStallGap during
//     which the thread did not run, without which exec would have fit in a period;
//   - preempted (the platform's): given the body's own CPU time (finish(cpu_time)), the body
//     needed less than a period of CPU but was kept off the CPU (preemption, a virtual
//     machine's stolen time) until it ended past the next deadline;
//   - execution overrun (ours): the body's own work took longer than the period. Without
//     the CPU time, a body longer than a period counts as one.
// No allocation; not thread-safe (one thread owns a loop).

#include "rt/clock.hpp"
#include "rt/timing_stats.hpp"

#include <cstdint>

namespace staa::rt {

// A gap between two clock reads of a body at least this long is a stall of the platform: far
// above the work between two reads (a planner pop, a step of the cycle: microseconds), and
// above a scheduler's tick, so a few ordinary preemptions never add up to one.
constexpr Nanos kStallGap = 3 * kNanosPerMilli;

struct PeriodicCounters {
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;             // cycles that ended after the next deadline
  std::uint64_t execution_overruns = 0;   // ... of them, because the body took > period
  std::uint64_t late_wakeups = 0;         // ... of them, because the wake-up was late
  std::uint64_t preempted = 0;            // ... of them, because the body was kept off the CPU
  std::uint64_t stalls = 0;               // ... of them, because of a measured stall (>= kStallGap)
  std::uint64_t skipped_periods = 0;      // deadlines dropped in all
  std::uint64_t sleep_errors = 0;         // sleepUntil returned non-zero
  // Cycles whose body blocked (a voluntary context switch), overrun or not: a real-time
  // body never should, so any is a defect to find, like an allocation.
  std::uint64_t blocked_cycles = 0;
  // Cycles whose body took a page fault, and the index of the last cycle that blocked (0: none;
  // k + 1 for cycle k): what a blocked cycle's report needs to tell a fault's wait from a lock's.
  std::uint64_t faulted_cycles = 0;
  std::uint64_t last_blocked_cycle = 0;
  // Cycles that blocked and faulted: waits on memory (a fault that waited), not on a lock.
  std::uint64_t blocked_faulted_cycles = 0;
  // The longest body less its stall (a gap >= kStallGap, when one was measured): the
  // longest the body's own work took, the platform's stalls taken out.
  Nanos max_own_execution = 0;
};

// What one wait returned.
struct Wake {
  Nanos deadline = 0;       // the deadline slept to
  Nanos woke = 0;           // clock time after waking
  Nanos latency = 0;        // woke - deadline (>= 0 on a correct clock)
  std::uint64_t index = 0;  // k of the deadline
  int error = 0;            // sleepUntil's error, 0 normally
};

class PeriodicLoop {
 public:
  // Deadline 0 is `start` (usually clock.now() + period). period > 0, else
  // std::invalid_argument. Statistics: histograms of wake-up latency and execution time,
  // 1 us bins up to `histogram_bound_us` (allocated here, never after).
  PeriodicLoop(Clock& clock, Nanos period, Nanos start, std::uint32_t histogram_bound_us = 100'000);

  // Sleeps until the current deadline and returns what happened.
  Wake wait();
  // Ends the cycle started by the last wait(): records the execution time (now - woke),
  // attributes and counts an overrun, and moves the deadline to the next one in the future
  // (skipping missed ones). Returns the number of periods skipped (0 normally).
  std::uint64_t finish();
  // The same, with the body's own CPU time (e.g. CLOCK_THREAD_CPUTIME_ID around it): an
  // overrun whose body used less than a period of CPU is the platform's (preempted or a late
  // wake-up), never an execution overrun.
  std::uint64_t finish(Nanos cpu_time);
  // The same, with the largest gap between two clock reads of the body (`stall`, 0 when not
  // measured): an overrun whose body, without a gap of at least kStallGap, fits in a period
  // is a stall of the platform. cpu_time < 0: not measured.
  std::uint64_t finish(Nanos cpu_time, Nanos stall);
  // The same, with the body's voluntary context switches (`switches`, < 0 when not measured):
  // a body that switched is counted in blocked_cycles, and its overrun is ours.
  std::uint64_t finish(Nanos cpu_time, Nanos stall, std::int64_t switches);
  // The same, with the body's page faults (`faults`, < 0 when not measured), counted in
  // faulted_cycles.
  std::uint64_t finish(Nanos cpu_time, Nanos stall, std::int64_t switches, std::int64_t faults);

  Nanos period() const { return period_; }
  Nanos nextDeadline() const { return deadline_; }
  const PeriodicCounters& counters() const { return counters_; }
  const LatencyHistogram& wakeLatency() const { return wake_; }
  const LatencyHistogram& execution() const { return exec_; }
  // The last cycle's execution time.
  Nanos lastExecution() const { return last_exec_; }

 private:
  Clock& clock_;
  Nanos period_;
  Nanos start_;
  Nanos deadline_;
  std::uint64_t index_ = 0;
  Wake last_wake_;
  Nanos last_exec_ = 0;
  PeriodicCounters counters_;
  LatencyHistogram wake_;
  LatencyHistogram exec_;
};

}  // namespace staa::rt
