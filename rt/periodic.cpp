#include "rt/periodic.hpp"

#include <stdexcept>
#include <string>

namespace staa::rt {

PeriodicLoop::PeriodicLoop(Clock& clock, Nanos period, Nanos start, std::uint32_t histogram_bound_us)
    : clock_(clock),
      period_(period),
      start_(start),
      deadline_(start),
      wake_(histogram_bound_us),
      exec_(histogram_bound_us) {
  if (period <= 0) {
    throw std::invalid_argument("PeriodicLoop: period must be > 0 ns, got " + std::to_string(period) + " ns");
  }
}

Wake PeriodicLoop::wait() {
  Wake w;
  w.deadline = deadline_;
  w.index = index_;
  w.error = clock_.sleepUntil(deadline_);
  w.woke = clock_.now();
  w.latency = w.woke - w.deadline;
  if (w.error != 0) {
    // The sleep failed (a bad deadline or clock): no latency to speak of, the cycle still
    // runs so the caller keeps its schedule and sees the error in the counters.
    ++counters_.sleep_errors;
  } else {
    wake_.record(w.latency);
  }
  last_wake_ = w;
  return w;
}

std::uint64_t PeriodicLoop::finish() { return finish(-1); }

std::uint64_t PeriodicLoop::finish(Nanos cpu_time) { return finish(cpu_time, 0); }

std::uint64_t PeriodicLoop::finish(Nanos cpu_time, Nanos stall) { return finish(cpu_time, stall, -1); }

std::uint64_t PeriodicLoop::finish(Nanos cpu_time, Nanos stall, std::int64_t switches) {
  return finish(cpu_time, stall, switches, -1);
}

std::uint64_t PeriodicLoop::finish(Nanos cpu_time, Nanos stall, std::int64_t switches, std::int64_t faults) {
  const Nanos now = clock_.now();
  const bool blocked = switches > 0;
  if (blocked) {
    ++counters_.blocked_cycles;
    counters_.last_blocked_cycle = counters_.cycles + 1;
  }
  if (faults > 0) ++counters_.faulted_cycles;
  if (blocked && faults > 0) ++counters_.blocked_faulted_cycles;
  last_exec_ = now - last_wake_.woke;
  exec_.record(last_exec_);
  ++counters_.cycles;
  const bool stalled = stall >= kStallGap;
  const Nanos own = stalled ? last_exec_ - stall : last_exec_;
  if (own > counters_.max_own_execution) counters_.max_own_execution = own;

  // Deadlines are computed from the start, never accumulated, so they stay exactly
  // start + k * period however many cycles run.
  std::uint64_t next = index_ + 1;
  Nanos next_deadline = start_ + static_cast<Nanos>(next) * period_;
  std::uint64_t skipped = 0;
  if (now > next_deadline) {
    // The cycle ended past the next deadline: skip to the first deadline strictly in the
    // future instead of running a burst of late cycles to catch up.
    ++counters_.overruns;
    if (last_exec_ <= period_) {
      ++counters_.late_wakeups;
    } else if (blocked) {
      ++counters_.execution_overruns;
    } else if (stalled && own <= period_) {
      ++counters_.stalls;
    } else if (cpu_time >= 0 && cpu_time <= period_) {
      ++counters_.preempted;
    } else {
      ++counters_.execution_overruns;
    }
    const auto first_future = static_cast<std::uint64_t>((now - start_) / period_) + 1;
    skipped = first_future - next;
    counters_.skipped_periods += skipped;
    next = first_future;
    next_deadline = start_ + static_cast<Nanos>(next) * period_;
  }
  index_ = next;
  deadline_ = next_deadline;
  return skipped;
}

}  // namespace staa::rt
