#include "rt/clock.hpp"

#include <cerrno>
#include <ctime>

#include <sys/resource.h>

namespace staa::rt {

namespace {

timespec toTimespec(Nanos t) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t / kNanosPerSecond);
  ts.tv_nsec = static_cast<long>(t % kNanosPerSecond);
  if (ts.tv_nsec < 0) {  // a deadline before the clock's epoch: keep tv_nsec in [0, 1e9)
    ts.tv_nsec += kNanosPerSecond;
    ts.tv_sec -= 1;
  }
  return ts;
}

}  // namespace

Nanos monotonicNow() {
  timespec ts{};
  // CLOCK_MONOTONIC cannot fail with a valid pointer; the result is not checked.
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<Nanos>(ts.tv_sec) * kNanosPerSecond + ts.tv_nsec;
}

Nanos threadCpuTime() {
  timespec ts{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0) return -1;
  return static_cast<Nanos>(ts.tv_sec) * kNanosPerSecond + ts.tv_nsec;
}

std::int64_t threadVoluntarySwitches() {
  rusage ru{};
  if (getrusage(RUSAGE_THREAD, &ru) != 0) return -1;
  return static_cast<std::int64_t>(ru.ru_nvcsw);
}

std::int64_t threadPageFaults() {
  rusage ru{};
  if (getrusage(RUSAGE_THREAD, &ru) != 0) return -1;
  return static_cast<std::int64_t>(ru.ru_minflt) + static_cast<std::int64_t>(ru.ru_majflt);
}

Nanos MonotonicClock::now() const { return monotonicNow(); }

Clock::NowFunction MonotonicClock::nowFunction() const { return &monotonicNow; }

int MonotonicClock::sleepUntil(Nanos deadline) {
  const timespec ts = toTimespec(deadline);
  // An absolute deadline: a signal interrupting the sleep does not shift the schedule, so the
  // same deadline is simply slept to again.
  int rc = 0;
  do {
    rc = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
  } while (rc == EINTR);
  return rc;
}

int ManualClock::sleepUntil(Nanos deadline) {
  const Nanos delay = next_delay_.exchange(0, std::memory_order_acq_rel);
  const Nanos wake = deadline + delay;
  // Time only moves forward: a deadline already passed wakes "now" (plus nothing), and a
  // test advancing the clock concurrently is never undone.
  Nanos current = now_.load(std::memory_order_acquire);
  while (current < wake &&
         !now_.compare_exchange_weak(current, wake, std::memory_order_acq_rel, std::memory_order_acquire)) {
  }
  return 0;
}

}  // namespace staa::rt
