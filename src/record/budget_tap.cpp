#include "record/budget_tap.hpp"

namespace staa::record {

namespace {

struct TapState {
  ClockFn underlying = &steadyClockNs;
  std::int64_t limit_ns = 0;
  std::int64_t start_ns = 0;
  std::int64_t cut = -1;
  std::uint32_t reads = 0;
};
thread_local TapState tap;

struct ReplayState {
  std::int64_t cut = -1;
  std::uint32_t reads = 0;
};
thread_local ReplayState replay;

// Far past any budget (a day), with room left before overflow in `start + limit`.
constexpr std::int64_t kPassed = std::int64_t{1} << 46;

}  // namespace

void BudgetTap::install(ClockFn underlying) { tap.underlying = underlying != nullptr ? underlying : &steadyClockNs; }

void BudgetTap::arm(std::int64_t limit_ns) {
  tap.limit_ns = limit_ns;
  tap.start_ns = 0;
  tap.cut = -1;
  tap.reads = 0;
}

BudgetCut BudgetTap::result() { return BudgetCut{tap.cut, tap.reads}; }

std::int64_t BudgetTap::now() {
  const std::int64_t t = tap.underlying();
  if (tap.reads == 0) {
    tap.start_ns = t;  // the budget's start() is its first read
  } else if (tap.cut < 0 && t - tap.start_ns >= tap.limit_ns) {
    tap.cut = tap.reads;  // the comparison of PlannerBudget::exhausted and Deadline::passed
  }
  ++tap.reads;
  return t;
}

void ReplayClock::arm(std::int64_t cut_read) {
  replay.cut = cut_read;
  replay.reads = 0;
}

std::uint32_t ReplayClock::reads() { return replay.reads; }

std::int64_t ReplayClock::now() {
  const std::int64_t index = replay.reads++;
  return replay.cut >= 0 && index >= replay.cut ? kPassed : 0;
}

}  // namespace staa::record
