#pragma once
// The clock the runtime runs on, injected (docs/ARCHITECTURE.md section 3): the daemon uses the
// monotonic clock and sleeps on absolute deadlines; tests use a manual clock and step it, so
// a periodic thread runs thousands of cycles deterministically in lockstep.

#include <atomic>
#include <cstdint>

namespace staa::rt {

using Nanos = std::int64_t;  // nanoseconds on CLOCK_MONOTONIC (or a test's time line)

constexpr Nanos kNanosPerMilli = 1'000'000;
constexpr Nanos kNanosPerSecond = 1'000'000'000;

// CLOCK_MONOTONIC now (MonotonicClock::nowFunction() returns this function).
Nanos monotonicNow();

// CPU time consumed by the calling thread so far (CLOCK_THREAD_CPUTIME_ID), -1 if unavailable.
Nanos threadCpuTime();

// Voluntary context switches of the calling thread so far (getrusage RUSAGE_THREAD's
// ru_nvcsw: the thread slept, waited on a lock or for I/O), -1 if unavailable. A virtual
// machine's stolen time and preemption never count here, which is what tells a body that
// blocked (ours) from one the platform stopped.
std::int64_t threadVoluntarySwitches();

// Page faults of the calling thread so far (getrusage RUSAGE_THREAD's ru_minflt + ru_majflt),
// -1 if unavailable. With memory locked and prefaulted a cycle should take none: one that did
// touched memory never touched before, or the kernel moved a locked page (compaction), and a
// fault that waited is also a voluntary switch.
std::int64_t threadPageFaults();

class Clock {
 public:
  // The clock read through a plain function pointer (path/deadline.hpp's ClockFn is one).
  using NowFunction = Nanos (*)();

  virtual ~Clock() = default;
  virtual Nanos now() const = 0;
  // Blocks until now() >= deadline (absolute). Returns 0, or the error code of the sleep
  // (clock_nanosleep returns it; it does not set errno). EINTR is retried inside.
  virtual int sleepUntil(Nanos deadline) = 0;
  // The CPU time the calling thread has used, on this clock's terms; -1 when it has none (a
  // test's time line, where a body's execution is only what the test advanced).
  virtual Nanos threadCpuTime() const { return -1; }
  // The calling thread's voluntary context switches so far; -1 when the clock has none.
  virtual std::int64_t voluntarySwitches() const { return -1; }
  // The calling thread's page faults so far; -1 when the clock has none.
  virtual std::int64_t pageFaults() const { return -1; }
  // now() as a plain function, or nullptr when the clock lives in an object (a test's).
  virtual NowFunction nowFunction() const { return nullptr; }
};

// CLOCK_MONOTONIC; sleepUntil = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME).
class MonotonicClock final : public Clock {
 public:
  Nanos now() const override;
  int sleepUntil(Nanos deadline) override;
  Nanos threadCpuTime() const override { return rt::threadCpuTime(); }
  std::int64_t voluntarySwitches() const override { return rt::threadVoluntarySwitches(); }
  std::int64_t pageFaults() const override { return rt::threadPageFaults(); }
  NowFunction nowFunction() const override;
};

// A test's clock: now() is what the test set; sleepUntil(d) jumps time to d when d is later
// (lockstep: a sleeping thread "wakes" exactly on time), plus an optional injected wake-up
// delay for the next sleep. Thread-safe (atomics), so a test may read it from another thread.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(Nanos start = 0) : now_(start) {}
  Nanos now() const override { return now_.load(std::memory_order_acquire); }
  int sleepUntil(Nanos deadline) override;
  void set(Nanos t) { now_.store(t, std::memory_order_release); }
  void advance(Nanos d) { now_.fetch_add(d, std::memory_order_acq_rel); }
  // The next sleepUntil wakes this much after its deadline (a late wake-up), then resets.
  void delayNextWake(Nanos d) { next_delay_.store(d, std::memory_order_release); }

 private:
  std::atomic<Nanos> now_;
  std::atomic<Nanos> next_delay_{0};
};

}  // namespace staa::rt
