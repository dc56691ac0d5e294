#pragma once
// What runs, apart from when it runs (Orocos RTT's RunnableInterface and PeriodicActivity).
// A Runnable is one cycle of work, stepped with the time its cycle woke; it knows nothing of
// threads, so a test steps it in lockstep on its own time line. A PeriodicActivity owns the
// thread that steps it: the thread's priority, CPU and name (rt::RtThread), the schedule on
// absolute deadlines with its overrun attribution (rt::PeriodicLoop: the body's CPU time from
// the clock, its stalls from the runnable), and the timing other threads read while it runs.
//
// On the activity's thread, in order: the loop is created (deadline 0 = now + period; its
// histograms are allocated here), Runnable::start(loop), the thread marks itself real-time
// (rt/alloc_count.hpp); then, until a stop is asked, wait for the deadline, step(woke),
// finish (a stop asked during the sleep lets that cycle run); then Runnable::stop(now), and
// the real-time mark is cleared.

#include "rt/clock.hpp"
#include "rt/periodic.hpp"
#include "rt/realtime.hpp"
#include "rt/seqlock.hpp"
#include "rt/timing_stats.hpp"

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

namespace staa::rt {

class Runnable {
 public:
  virtual ~Runnable() = default;
  // Before the first step, on the stepping thread, not yet real-time (may allocate). `loop`
  // is the schedule that steps this runnable, alive until stop() returns: its counters are
  // this thread's to read.
  virtual void start(const PeriodicLoop& loop) { (void)loop; }
  // One cycle at `now`, the time the cycle woke. Real-time: no allocation, lock or blocking.
  virtual void step(Nanos now) = 0;
  // After the last step, on the same thread, still real-time.
  virtual void stop(Nanos now) { (void)now; }
  // The largest gap between two clock reads of the last step (rt/stall_probe.hpp), 0 when
  // the runnable does not measure it: the periodic loop tells a stall of the platform from
  // an overrun of ours with it.
  virtual Nanos lastStall() const { return 0; }
};

// A periodic thread's timing as other threads read it.
struct ActivityTiming {
  PeriodicCounters counters;  // as of the last cycle's end
  TimingSummary execution;    // of a cycle's body
  TimingSummary wake;         // wake-up latency
  bool realtime = false;      // runs under SCHED_FIFO
};

class PeriodicActivity {
 public:
  // `name` labels the activity in reports (the thread's own name is in its ThreadSpec).
  // period > 0, else std::invalid_argument. The histograms have 1 us bins up to
  // `histogram_bound_us`.
  PeriodicActivity(std::string name, Runnable& runnable, Clock& clock, Nanos period,
                   std::uint32_t histogram_bound_us = 100'000);
  PeriodicActivity(const PeriodicActivity&) = delete;
  PeriodicActivity& operator=(const PeriodicActivity&) = delete;
  ~PeriodicActivity();  // stops and joins

  // Starts the thread with `spec` (once) and returns once it runs with the attributes it got
  // (warning() says what was refused). Throws std::system_error when it cannot start.
  void start(const ThreadSpec& spec);
  // Asks the thread to end after the cycle it is in or sleeping toward (returns at once).
  void requestStop();
  // requestStop(), then waits until the thread has ended (Runnable::stop has run).
  void stop();

  const std::string& name() const { return name_; }
  Nanos period() const { return period_; }
  bool running() const { return thread_.running(); }
  bool realtime() const { return thread_.realtime(); }
  const std::string& warning() const { return thread_.warning(); }

  // From any thread. started(): the loop exists and Runnable::start has run (acquire); the
  // histograms and timing() may be read from then on, also after stop().
  bool started() const { return started_.load(std::memory_order_acquire); }
  PeriodicCounters counters() const { return counters_.load(); }
  const LatencyHistogram& execution() const { return loop_->execution(); }
  const LatencyHistogram& wakeLatency() const { return loop_->wakeLatency(); }
  // The counters and the histograms' summaries (a walk over the bins: not for a real-time
  // thread).
  ActivityTiming timing() const;

 private:
  void run();

  std::string name_;
  Runnable& runnable_;
  Clock& clock_;
  Nanos period_;
  std::uint32_t histogram_bound_us_;
  RtThread thread_;
  std::optional<PeriodicLoop> loop_;
  std::atomic<bool> started_{false};
  std::atomic<bool> stop_requested_{false};
  SeqLock<PeriodicCounters> counters_;
};

}  // namespace staa::rt
