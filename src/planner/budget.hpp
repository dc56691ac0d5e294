#pragma once
// When STAA* must stop, as a small object handed to the search (like OMPL's
// PlannerTerminationCondition): a number of queue pops, or a wall-clock limit read from an
// injected clock. The expansion budget makes a run reproducible bit for bit.

#include "path/deadline.hpp"

#include <cstdint>

namespace staa {

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

  // Starts the clock of a wall-clock budget; once only (the control cycle starts it before
  // its path queries, so that the path, the local map and STAA* share one budget; the
  // planner's own call is then a no-op).
  void start() {
    if (kind_ == Kind::kWallClock && !started_) {
      start_ns_ = clock_();
      started_ = true;
    }
  }
  bool started() const { return started_; }
  // The budget's end as a Deadline for the searches it covers (path queries, the heuristic's
  // Minimal Construct queries). Never passes for an expansion budget (reproducible runs).
  Deadline deadline() const {
    if (kind_ != Kind::kWallClock) return Deadline{};
    return Deadline{clock_, start_ns_ + limit_ns_};
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
  bool started_ = false;
  ClockFn clock_ = &steadyClockNs;
};

}  // namespace staa
