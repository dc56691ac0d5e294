#pragma once
// When STAA* must stop, as a small object handed to the search (like OMPL's
// PlannerTerminationCondition): a number of queue pops, or a wall-clock limit read from an
// injected clock. The expansion budget makes a run reproducible bit for bit.

#include "path/deadline.hpp"

#include <cmath>
#include <cstdint>
#include <string>

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
  ClockFn clock() const { return clock_; }

 private:
  Kind kind_ = Kind::kExpansions;
  std::uint32_t max_pops_ = 1000;
  std::int64_t limit_ns_ = 19'000'000;
  std::int64_t start_ns_ = 0;
  bool started_ = false;
  ClockFn clock_ = &steadyClockNs;
};

// A budget as configured and reported (config files, command lines, results.json): a
// wall-clock limit per cycle or a number of queue pops. make() gives the search's
// PlannerBudget; the same value is converted, named and written the same way everywhere.
struct BudgetSpec {
  enum class Kind : std::uint8_t { kWallClock, kExpansions };

  static BudgetSpec wallClockMs(double ms) { return {Kind::kWallClock, ms, 0}; }
  static BudgetSpec expansionsOf(std::uint32_t pops) { return {Kind::kExpansions, 0.0, pops}; }
  // The paper's 19 ms of the 33 ms period at 30 Hz, scaled with the rate.
  static BudgetSpec defaultWallClock(double rate_hz) { return wallClockMs(19.0 * 30.0 / rate_hz); }

  bool isExpansions() const { return kind == Kind::kExpansions; }
  std::int64_t limitNs() const { return std::llround(ms * 1e6); }
  PlannerBudget make(ClockFn clock = &steadyClockNs) const {
    return isExpansions() ? PlannerBudget::expansions(expansions) : PlannerBudget::wallClock(limitNs(), clock);
  }
  // "1000 expansions" or "19.00 ms".
  std::string describe() const;
  // The results' spelling of the kind: "expansions" or "wall_ms".
  const char* kindName() const { return isExpansions() ? "expansions" : "wall_ms"; }

  Kind kind = Kind::kWallClock;
  double ms = 19.0;              // kWallClock: milliseconds per cycle
  std::uint32_t expansions = 0;  // kExpansions: queue pops per cycle
};

}  // namespace staa
