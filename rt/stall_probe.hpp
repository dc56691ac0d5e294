#pragma once
// How long the calling thread did not run, measured rather than inferred: a clock the
// thread reads often anyway (the planner reads its budget's clock at every pop) records the
// largest gap between two consecutive reads of the current cycle. A gap much longer than
// the work between two reads is time the thread was off the CPU (a platform stall: a
// virtual machine's stolen time, a higher-priority thread). Busy-waits read it too, so
// their gaps stay tiny and their time stays counted as the thread's own work.
//
// One probe per thread (thread_local): begin(woke) opens a cycle, now() reads the monotonic
// clock through it (a ClockFn, path/deadline.hpp), end(now) closes the cycle; lastGap() is
// the largest gap of the cycle closed last. No allocation, no lock.

#include "rt/clock.hpp"

namespace staa::rt {

class StallProbe {
 public:
  // Opens a cycle that woke at `woke`: the first read's gap is measured from it.
  void begin(Nanos woke);
  // Records a read at `t` (the clock's value) and returns it.
  Nanos read(Nanos t);
  // Closes the cycle with a last read at `now`; returns the cycle's largest gap.
  Nanos end(Nanos now);
  // The largest gap of the last cycle closed by end() (0 before any).
  Nanos lastGap() const { return last_gap_; }
  // The largest gap so far in the open cycle.
  Nanos currentGap() const { return gap_; }

  // The calling thread's probe.
  static StallProbe& local();
  // The monotonic clock read through the calling thread's probe (a ClockFn).
  static Nanos now();

 private:
  Nanos last_read_ = 0;
  Nanos gap_ = 0;
  Nanos last_gap_ = 0;
  bool open_ = false;
};

}  // namespace staa::rt
