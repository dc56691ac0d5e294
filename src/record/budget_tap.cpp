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
thread_local TapState tap_state;

struct ReplayState {
  std::int64_t cut = -1;
  std::uint32_t reads = 0;
};
thread_local ReplayState replay_state;

// Far past any budget (a day), with room left before overflow in `start + limit`.
constexpr std::int64_t kPassed = std::int64_t{1} << 46;

}  // namespace

void BudgetTap::install(ClockFn underlying) { tap_state.underlying = underlying != nullptr ? underlying : &steadyClockNs; }

void BudgetTap::arm(std::int64_t limit_ns) {
  tap_state.limit_ns = limit_ns;
  tap_state.start_ns = 0;
  tap_state.cut = -1;
  tap_state.reads = 0;
}

BudgetCut BudgetTap::result() { return BudgetCut{tap_state.cut, tap_state.reads}; }

std::int64_t BudgetTap::now() {
  const std::int64_t t = tap_state.underlying();
  if (tap_state.reads == 0) {
    tap_state.start_ns = t;  // the budget's start() is its first read
  } else if (tap_state.cut < 0 && t - tap_state.start_ns >= tap_state.limit_ns) {
    tap_state.cut = tap_state.reads;  // the comparison of PlannerBudget::exhausted and Deadline::passed
  }
  ++tap_state.reads;
  return t;
}

void ReplayClock::arm(std::int64_t cut_read) {
  replay_state.cut = cut_read;
  replay_state.reads = 0;
}

std::uint32_t ReplayClock::reads() { return replay_state.reads; }

std::int64_t ReplayClock::now() {
  const std::int64_t index = replay_state.reads++;
  return replay_state.cut >= 0 && index >= replay_state.cut ? kPassed : 0;
}

}  // namespace staa::record
