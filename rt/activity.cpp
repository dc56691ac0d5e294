#include "rt/activity.hpp"

#include "rt/alloc_count.hpp"

#include <cstdio>
#include <exception>
#include <stdexcept>
#include <utility>

namespace staa::rt {

PeriodicActivity::PeriodicActivity(std::string name, Runnable& runnable, Clock& clock, Nanos period,
                                   std::uint32_t histogram_bound_us)
    : name_(std::move(name)),
      runnable_(runnable),
      clock_(clock),
      period_(period),
      histogram_bound_us_(histogram_bound_us) {
  if (period <= 0) {
    throw std::invalid_argument("activity " + name_ + ": period must be > 0 ns, got " + std::to_string(period) +
                                " ns");
  }
}

PeriodicActivity::~PeriodicActivity() {
  try {
    stop();
  } catch (const std::exception& e) {
    // A destructor must not throw; the failure is still worth a line.
    std::fprintf(stderr, "activity %s: %s\n", name_.c_str(), e.what());
  }
}

void PeriodicActivity::start(const ThreadSpec& spec) {
  stop_requested_.store(false, std::memory_order_release);
  thread_.start(spec, [this] { run(); });
}

void PeriodicActivity::requestStop() { stop_requested_.store(true, std::memory_order_release); }

void PeriodicActivity::stop() {
  requestStop();
  if (thread_.running()) thread_.join();
}

ActivityTiming PeriodicActivity::timing() const {
  ActivityTiming t;
  t.realtime = realtime();
  if (!started()) return t;
  t.counters = counters();
  t.execution = execution().summary();
  t.wake = wakeLatency().summary();
  return t;
}

void PeriodicActivity::run() {
  // Set-up (allocates: the loop's histograms), then real-time from here on.
  PeriodicLoop& loop = loop_.emplace(clock_, period_, clock_.now() + period_, histogram_bound_us_);
  runnable_.start(loop);
  markRealtimeThread(true);
  started_.store(true, std::memory_order_release);
  while (!stop_requested_.load(std::memory_order_acquire)) {
    const Wake wake = loop.wait();
    // The body's own CPU time and its measured stalls tell an execution overrun (ours) from
    // a body kept off the CPU (the platform's: preemption, a virtual machine's stolen time).
    // Voluntary switches tell a body that blocked (ours) from one that was stopped.
    // Page faults beside them: a blocked cycle that also faulted waited on memory, not a lock.
    const std::int64_t sw0 = clock_.voluntarySwitches();
    const std::int64_t pf0 = clock_.pageFaults();
    const Nanos cpu0 = clock_.threadCpuTime();
    runnable_.step(wake.woke);
    const Nanos cpu1 = clock_.threadCpuTime();
    const std::int64_t pf1 = clock_.pageFaults();
    const std::int64_t sw1 = clock_.voluntarySwitches();
    loop.finish(cpu0 >= 0 && cpu1 >= 0 ? cpu1 - cpu0 : -1, runnable_.lastStall(),
                sw0 >= 0 && sw1 >= 0 ? sw1 - sw0 : -1, pf0 >= 0 && pf1 >= 0 ? pf1 - pf0 : -1);
    counters_.store(loop.counters());
  }
  runnable_.stop(clock_.now());
  markRealtimeThread(false);
}

}  // namespace staa::rt
