#pragma once
// Where a wall-clock budget cut a cycle short, as a number a replay can repeat.
//
// Every search of a cycle gives up when a read of the budget's clock reaches the deadline
// (the path queries and the heuristic's queries through Deadline::passed, STAA* at every pop
// through PlannerBudget::exhausted). The clock is monotonic, so once a read has passed the
// deadline every later one has too: a cycle's whole behaviour under its budget is fixed by
// the index of the first read that passed it. Recording, BudgetTap is the budget's clock: it
// reads the real clock and notes that index (the cut). Replaying, ReplayClock is the budget's
// clock: it answers "not yet" up to the recorded cut and "passed" from it on, so the rerun
// stops every search exactly where the original stopped, on any machine at any speed.
//
// Both are plain functions (ClockFn) over thread-local state: no allocation, no lock; one
// cycle at a time per thread (staad's control thread, a simulation's thread).

#include "path/deadline.hpp"

#include <cstdint>

namespace staa::record {

struct BudgetCut {
  std::int64_t cut_read = -1;  // index of the first read at or past the deadline; -1: never
  std::uint32_t reads = 0;     // reads of the budget's clock in the cycle
};

class BudgetTap {
 public:
  // The real clock behind the tap on this thread (staad: the stall probe's; sims: steady).
  static void install(ClockFn underlying);
  // Before a cycle: its budget's limit (the first read is the budget's start).
  static void arm(std::int64_t limit_ns);
  // After the cycle.
  static BudgetCut result();
  // The budget's clock (a ClockFn).
  static std::int64_t now();
};

class ReplayClock {
 public:
  // Before a rerun cycle: the recorded cut (-1: the deadline never passes).
  static void arm(std::int64_t cut_read);
  static std::uint32_t reads();
  // The budget's clock (a ClockFn): 0 before the cut, far past any limit from it on.
  static std::int64_t now();
};

}  // namespace staa::record
