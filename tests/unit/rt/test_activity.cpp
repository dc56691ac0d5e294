// The periodic activity on an injected clock: its thread wakes only when the test lets it
// (GatedClock), so every deadline, every step's time and every counter is exact, while the
// activity runs on its own thread as it does in the daemon.
#include "rt/activity.hpp"
#include "rt/alloc_count.hpp"

#include <gtest/gtest.h>

#include <sys/mman.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace staa::rt {
namespace {

constexpr Nanos kMs = kNanosPerMilli;
constexpr Nanos kPeriod = 10 * kMs;
constexpr Nanos kT0 = 7 * kNanosPerSecond;  // an arbitrary clock origin, not 0

// A lockstep clock whose sleepUntil blocks until the test grants a wake-up, then jumps time
// to the deadline (as ManualClock does). Without a CPU clock: a body's execution is what it
// advanced the time by, and one longer than a period is an execution overrun.
class GatedClock final : public Clock {
 public:
  explicit GatedClock(Nanos start) : now_(start) {}

  Nanos now() const override {
    std::lock_guard lock(mutex_);
    return now_;
  }
  int sleepUntil(Nanos deadline) override {
    std::unique_lock lock(mutex_);
    ++sleeps_;
    cv_.notify_all();
    cv_.wait(lock, [&] { return open_ || grants_ > 0; });
    if (!open_) --grants_;
    if (now_ < deadline) now_ = deadline;
    return 0;
  }
  void advance(Nanos d) {
    std::lock_guard lock(mutex_);
    now_ += d;
  }
  // Lets `n` more sleeps end.
  void grant(int n) {
    std::lock_guard lock(mutex_);
    grants_ += n;
    cv_.notify_all();
  }
  // Every sleep from now on ends at once.
  void open() {
    std::lock_guard lock(mutex_);
    open_ = true;
    cv_.notify_all();
  }
  // Blocks until the sleeper has begun its `n`-th sleep.
  void awaitSleeps(int n) {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [&] { return sleeps_ >= n; });
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  Nanos now_;
  int grants_ = 0;
  int sleeps_ = 0;
  bool open_ = false;
};

// Records what the activity did with it, from the activity's thread.
class Recorder final : public Runnable {
 public:
  explicit Recorder(GatedClock& clock) : clock_(clock) {}

  void start(const PeriodicLoop& loop) override {
    started_on = std::this_thread::get_id();
    loop_period = loop.period();
    realtime_at_start = isRealtimeThread();
  }
  void step(Nanos now) override {
    steps.push_back(now);
    realtime_in_step = isRealtimeThread();
    if (steps.size() == 3) clock_.advance(25 * kMs);  // the third cycle runs past two deadlines
  }
  void stop(Nanos now) override {
    stopped_at = now;
    stopped_on = std::this_thread::get_id();
  }

  std::thread::id started_on;
  std::thread::id stopped_on;
  Nanos loop_period = 0;
  bool realtime_at_start = true;
  bool realtime_in_step = false;
  std::vector<Nanos> steps;  // reserved by the test: no allocation in a step
  Nanos stopped_at = -1;

 private:
  GatedClock& clock_;
};

ThreadSpec normalThread() {
  ThreadSpec spec;
  spec.name = "test-activity";
  spec.priority = 0;  // normal scheduling: the test runs anywhere
  spec.stack_bytes = 64 * 1024;
  return spec;
}

TEST(PeriodicActivity, StepsTheRunnableOnItsThreadOnEveryDeadlineAndSkipsMissedOnes) {
  GatedClock clock(kT0);
  Recorder recorder(clock);
  recorder.steps.reserve(16);
  PeriodicActivity activity("test", recorder, clock, kPeriod, 1000);
  EXPECT_FALSE(activity.started());
  activity.start(normalThread());
  EXPECT_TRUE(activity.running());
  EXPECT_FALSE(activity.realtime());
  clock.awaitSleeps(1);
  ASSERT_TRUE(activity.started());
  EXPECT_NE(recorder.started_on, std::this_thread::get_id());
  EXPECT_EQ(recorder.loop_period, kPeriod);
  EXPECT_FALSE(recorder.realtime_at_start);  // start() may allocate: not yet real-time
  EXPECT_EQ(activity.counters().cycles, 0u);

  clock.grant(5);
  clock.awaitSleeps(6);  // five cycles done, the sixth waiting
  // Deadline k is start + k * period (start = the clock at start-up + a period); the third
  // cycle ended at start + 4.5 periods, past deadlines 3 and 4, so the fourth woke on 5.
  const Nanos start = kT0 + kPeriod;
  const std::vector<Nanos> expected = {start, start + kPeriod, start + 2 * kPeriod, start + 5 * kPeriod,
                                       start + 6 * kPeriod};
  EXPECT_EQ(recorder.steps, expected);
  EXPECT_TRUE(recorder.realtime_in_step);

  // The status's `threads.base`: the counters as the activity's thread last published them.
  const PeriodicCounters c = activity.counters();
  EXPECT_EQ(c.cycles, 5u);
  EXPECT_EQ(c.overruns, 1u);
  EXPECT_EQ(c.execution_overruns, 1u);
  EXPECT_EQ(c.late_wakeups, 0u);
  EXPECT_EQ(c.skipped_periods, 2u);
  const ActivityTiming t = activity.timing();
  EXPECT_EQ(t.counters.overruns, 1u);
  EXPECT_EQ(t.execution.count, 5u);
  EXPECT_EQ(t.execution.max_us, 25'000.0);
  EXPECT_EQ(t.wake.count, 5u);
  EXPECT_EQ(t.wake.max_us, 0.0);
  EXPECT_FALSE(t.realtime);

  // A stop asked while the thread sleeps takes effect after that cycle: one more step, then
  // Runnable::stop on the same thread.
  activity.requestStop();
  clock.open();
  activity.stop();
  EXPECT_FALSE(activity.running());
  ASSERT_EQ(recorder.steps.size(), 6u);
  EXPECT_EQ(recorder.steps.back(), start + 7 * kPeriod);
  EXPECT_EQ(recorder.stopped_at, start + 7 * kPeriod);
  EXPECT_EQ(recorder.stopped_on, recorder.started_on);
  EXPECT_EQ(activity.counters().cycles, 6u);  // still readable after the thread ended
}

TEST(PeriodicActivity, ARunnableIsSteppedInLockstepWithoutAnActivity) {
  GatedClock clock(kT0);
  Recorder recorder(clock);
  for (Nanos now = 0; now < 4 * kPeriod; now += kPeriod) recorder.step(now);
  recorder.stop(4 * kPeriod);
  EXPECT_EQ(recorder.steps, (std::vector<Nanos>{0, kPeriod, 2 * kPeriod, 3 * kPeriod}));
  EXPECT_EQ(recorder.stopped_on, std::this_thread::get_id());
}

// On the monotonic clock the activity counts the voluntary context switches of each body:
// a body that sleeps blocks in every cycle, one that only computes never does.
class Sleeper final : public Runnable {
 public:
  explicit Sleeper(bool sleeps) : sleeps_(sleeps) {}
  void start(const PeriodicLoop&) override {}
  void step(Nanos) override {
    if (sleeps_) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    } else {
      volatile std::uint64_t x = 0;
      for (int i = 0; i < 10'000; ++i) x = x + static_cast<std::uint64_t>(i);
    }
    steps.fetch_add(1, std::memory_order_relaxed);
  }
  void stop(Nanos) override {}
  std::atomic<int> steps{0};

 private:
  bool sleeps_;
};

// Runs `body` (with a `steps` counter) every 2 ms on the monotonic clock until it has been
// stepped 20 times, and returns the activity's counters.
template <class Body>
PeriodicCounters runTwentySteps(const char* name, Body& body) {
  MonotonicClock clock;
  PeriodicActivity activity(name, body, clock, 2 * kMs);
  activity.start(normalThread());
  while (body.steps.load(std::memory_order_relaxed) < 20) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  activity.stop();
  return activity.counters();
}

TEST(PeriodicActivity, CountsTheCyclesWhoseBodyBlockedOnTheMonotonicClock) {
  if (threadVoluntarySwitches() < 0) GTEST_SKIP() << "getrusage(RUSAGE_THREAD) is not available here";
  for (const bool sleeps : {true, false}) {
    Sleeper body(sleeps);
    const PeriodicCounters c = runTwentySteps(sleeps ? "sleeper" : "computer", body);
    ASSERT_GE(c.cycles, 20u);
    if (sleeps) {
      EXPECT_EQ(c.blocked_cycles, c.cycles) << "every body slept";
      EXPECT_EQ(c.last_blocked_cycle, c.cycles) << "the last cycle (index cycles - 1, reported + 1) blocked";
    } else {
      EXPECT_EQ(c.blocked_cycles, 0u) << "no body of pure arithmetic may count as blocked";
      EXPECT_EQ(c.last_blocked_cycle, 0u);
    }
  }
}

// A body that touches a page it never touched before faults in that cycle; one that only
// computes on its registers does not.
class Toucher final : public Runnable {
 public:
  explicit Toucher(bool touches) : touches_(touches) {}
  void start(const PeriodicLoop&) override {}
  ~Toucher() override {
    if (pages_ != MAP_FAILED) ::munmap(pages_, kBytes);
  }
  void step(Nanos) override {
    if (touches_ && pages_ != MAP_FAILED && next_ < kPages) {
      static_cast<volatile char*>(pages_)[next_ * kPage] = 1;
      ++next_;
    }
    steps.fetch_add(1, std::memory_order_relaxed);
  }
  void stop(Nanos) override {}
  static constexpr std::size_t kPage = 4096, kPages = 64, kBytes = kPages * kPage;
  std::atomic<int> steps{0};

 private:
  bool touches_;
  // Fresh anonymous pages, mapped on first touch, one at a time (no huge pages): not heap,
  // whose first page may share a header already touched.
  void* pages_ = [] {
    void* p = ::mmap(nullptr, kBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p != MAP_FAILED) ::madvise(p, kBytes, MADV_NOHUGEPAGE);
    return p;
  }();
  std::size_t next_ = 0;
};

TEST(PeriodicActivity, CountsTheCyclesWhoseBodyTookAPageFault) {
  if (threadPageFaults() < 0) GTEST_SKIP() << "getrusage(RUSAGE_THREAD) is not available here";
  for (const bool touches : {true, false}) {
    Toucher body(touches);
    const PeriodicCounters c = runTwentySteps(touches ? "toucher" : "computer", body);
    ASSERT_GE(c.cycles, 20u);
    if (touches) {
      EXPECT_GE(c.faulted_cycles, 20u) << "a new page in each of the first 64 cycles";
    } else {
      EXPECT_EQ(c.faulted_cycles, 0u) << "no body that touches no new memory may count as faulted";
    }
  }
}

TEST(PeriodicActivity, RefusesAPeriodThatIsNotPositive) {
  GatedClock clock(kT0);
  Recorder recorder(clock);
  try {
    PeriodicActivity activity("control", recorder, clock, 0);
    FAIL() << "a period of 0 was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "activity control: period must be > 0 ns, got 0 ns");
  }
}

TEST(PeriodicActivity, StoppingAnActivityThatNeverStartedIsANoOp) {
  GatedClock clock(kT0);
  Recorder recorder(clock);
  PeriodicActivity activity("idle", recorder, clock, kPeriod);
  activity.stop();
  EXPECT_FALSE(activity.running());
  EXPECT_EQ(activity.timing().counters.cycles, 0u);
  EXPECT_EQ(recorder.stopped_at, -1);
}

}  // namespace
}  // namespace staa::rt
