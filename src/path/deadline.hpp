#pragma once
// A point in time after which a search gives up, read from an injected monotonic clock. The
// control cycle shares one deadline between its path queries and STAA* (planner/budget.hpp
// makes it from the cycle's budget), so no search runs past the cycle's time.

#include <chrono>
#include <cstdint>
#include <limits>

namespace staa {

// A monotonic clock in nanoseconds. Injected so that tests and the simulator can run the
// searches under their own time.
using ClockFn = std::int64_t (*)();

inline std::int64_t steadyClockNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

struct Deadline {
  ClockFn clock = nullptr;  // null: never
  std::int64_t at_ns = std::numeric_limits<std::int64_t>::max();
  bool passed() const { return clock != nullptr && clock() >= at_ns; }
};

}  // namespace staa
