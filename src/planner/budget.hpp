#pragma once
// When STAA* must stop, as a small object handed to the search (like OMPL's
// PlannerTerminationCondition): a number of queue pops, or a wall-clock limit read from an
// injected clock. The expansion budget makes a run reproducible bit for bit.

#include <chrono>
#include <cstdint>

namespace staa {

// A monotonic clock in nanoseconds. Injected so that tests and the simulator can run the
// planner under their own time.
using ClockFn = std::int64_t (*)();

inline std::int64_t steadyClockNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

class PlannerBudget {
 public:
  enum class Kind : std::uint8_t { kExpansions, kWallClock };

  static PlannerBudget expansions(std::uint32_t pops) {
    PlannerBudget b;
    b.kind_ = Kind::kExpansions;
    b.max_pops_ = pops;
    return b;
  }
  static PlannerBudget wallClock(std::int64_t limit_ns, ClockFn clock = &steadyClockNs) {
    PlannerBudget b;
    b.kind_ = Kind::kWallClock;
    b.limit_ns_ = limit_ns;
    b.clock_ = clock;
    return b;
  }

  // Called by the planner when it starts.
  void start() {
    if (kind_ == Kind::kWallClock) start_ns_ = clock_();
  }
  // Checked on every pop (paper, Sec. III-E-6). `pops` counts pops so far.
  bool exhausted(std::uint32_t pops) const {
    if (kind_ == Kind::kExpansions) return pops >= max_pops_;
    return clock_() - start_ns_ >= limit_ns_;
  }
  std::int64_t elapsedNs() const { return kind_ == Kind::kWallClock ? clock_() - start_ns_ : 0; }
  Kind kind() const { return kind_; }
  std::uint32_t maxPops() const { return max_pops_; }
  std::int64_t limitNs() const { return limit_ns_; }

 private:
  Kind kind_ = Kind::kExpansions;
  std::uint32_t max_pops_ = 1000;
  std::int64_t limit_ns_ = 19'000'000;
  std::int64_t start_ns_ = 0;
  ClockFn clock_ = &steadyClockNs;
};

}  // namespace staa
