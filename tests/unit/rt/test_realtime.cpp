#include "rt/realtime.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <pthread.h>
#include <sched.h>
#include <stdexcept>
#include <string>
#include <sys/resource.h>
#include <unistd.h>

namespace staa::rt {
namespace {

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// The scheduling policy of the calling thread, as the kernel has it.
int currentPolicy() {
  int policy = -1;
  sched_param param{};
  if (pthread_getschedparam(pthread_self(), &policy, &param) != 0) return -1;
  return policy;
}

TEST(RtThread, RunsItsBodyAndJoins) {
  std::atomic<int> runs{0};
  RtThread t;
  EXPECT_FALSE(t.running());
  t.start(ThreadSpec{"rt-test", 0, -1, 64 * 1024}, [&] { runs.fetch_add(1); });
  EXPECT_TRUE(t.running());
  t.join();
  EXPECT_FALSE(t.running());
  EXPECT_EQ(runs.load(), 1);
  t.join();  // joining twice is harmless

  // Startable again once joined.
  t.start(ThreadSpec{"rt-test", 0, -1, 64 * 1024}, [&] { runs.fetch_add(1); });
  t.join();
  EXPECT_EQ(runs.load(), 2);
}

TEST(RtThread, DestructorJoins) {
  std::atomic<bool> ran{false};
  {
    RtThread t;
    t.start(ThreadSpec{"rt-dtor", 0, -1, 64 * 1024}, [&] {
      usleep(1000);
      ran.store(true);
    });
  }
  EXPECT_TRUE(ran.load());
}

TEST(RtThread, NamesTheThreadTruncatedTo15Characters) {
  char short_name[16] = {};
  char long_name[16] = {};
  {
    RtThread t;
    t.start(ThreadSpec{"rt-named", 0, -1, 64 * 1024},
            [&] { pthread_getname_np(pthread_self(), short_name, sizeof short_name); });
  }
  {
    RtThread t;
    t.start(ThreadSpec{"a-very-long-thread-name", 0, -1, 64 * 1024},
            [&] { pthread_getname_np(pthread_self(), long_name, sizeof long_name); });
  }
  EXPECT_STREQ(short_name, "rt-named");
  EXPECT_STREQ(long_name, "a-very-long-thr");
}

TEST(RtThread, PriorityZeroRunsWithNormalSchedulingAndNoWarning) {
  int policy = -1;
  RtThread t;
  t.start(ThreadSpec{"rt-normal", 0, -1, 64 * 1024}, [&] { policy = currentPolicy(); });
  t.join();
  EXPECT_FALSE(t.realtime());
  EXPECT_EQ(t.warning(), "");
  EXPECT_EQ(policy, SCHED_OTHER);
}

TEST(RtThread, FifoPriorityIsGrantedOrFallsBackWithAWarning) {
  int policy = -1;
  int priority = -1;
  RtThread t;
  t.start(ThreadSpec{"rt-fifo", 50, -1, 64 * 1024}, [&] {
    sched_param param{};
    pthread_getschedparam(pthread_self(), &policy, &param);
    priority = param.sched_priority;
  });
  t.join();
  // Root (or CAP_SYS_NICE / RLIMIT_RTPRIO) gets SCHED_FIFO; anyone else runs normally and is
  // told so. Exactly one of the two, and realtime() agrees with the kernel.
  const bool granted = t.realtime() && t.warning().empty();
  const bool refused = !t.realtime() && contains(t.warning(), "SCHED_FIFO");
  EXPECT_NE(granted, refused) << "realtime=" << t.realtime() << " warning='" << t.warning() << "'";
  if (t.realtime()) {
    EXPECT_EQ(policy, SCHED_FIFO);
    EXPECT_EQ(priority, 50);
  } else {
    EXPECT_EQ(policy, SCHED_OTHER);
    EXPECT_TRUE(contains(t.warning(), "thread rt-fifo: SCHED_FIFO priority 50 not permitted")) << t.warning();
  }
}

TEST(RtThread, RefusedPriorityFallsBackWithAWarningForEveryUser) {
  // 100 is beyond SCHED_FIFO's range (1..99): refused even for root, so the fallback runs.
  int policy = -1;
  RtThread t;
  t.start(ThreadSpec{"rt-refused", 100, -1, 64 * 1024}, [&] { policy = currentPolicy(); });
  t.join();
  EXPECT_FALSE(t.realtime());
  EXPECT_EQ(policy, SCHED_OTHER);
  EXPECT_TRUE(contains(t.warning(), "thread rt-refused: SCHED_FIFO priority 100 not permitted")) << t.warning();
  EXPECT_TRUE(contains(t.warning(), "running with normal scheduling")) << t.warning();
  EXPECT_FALSE(contains(t.warning(), "\n"));

  RtThread negative;
  negative.start(ThreadSpec{"rt-negative", -3, -1, 64 * 1024}, [] {});
  negative.join();
  EXPECT_FALSE(negative.realtime());
  EXPECT_TRUE(contains(negative.warning(), "priority -3")) << negative.warning();
}

TEST(RtThread, PinsToAnExistingCpuOrWarns) {
  int cpu_seen = -1;
  RtThread t;
  t.start(ThreadSpec{"rt-pinned", 0, 0, 64 * 1024}, [&] { cpu_seen = sched_getcpu(); });
  t.join();
  // CPU 0 may be outside this container's cpuset: then a warning, never an exception.
  if (t.pinned()) {
    EXPECT_EQ(cpu_seen, 0);
    EXPECT_EQ(t.warning(), "");
  } else {
    EXPECT_TRUE(contains(t.warning(), "CPU 0")) << t.warning();
  }

  RtThread nowhere;
  nowhere.start(ThreadSpec{"rt-nowhere", 0, 100000, 64 * 1024}, [] {});
  nowhere.join();
  EXPECT_FALSE(nowhere.pinned());
  EXPECT_TRUE(contains(nowhere.warning(), "CPU 100000 does not exist")) << nowhere.warning();
}

TEST(RtThread, BodyHasTheRequestedStack) {
  // A body using most of its 1 MiB stack runs (the stack was sized and prefaulted for it).
  std::atomic<int> sum{0};
  RtThread t;
  t.start(ThreadSpec{"rt-stack", 0, -1, 1024 * 1024}, [&] {
    volatile char big[768 * 1024];
    for (std::size_t i = 0; i < sizeof big; i += 4096) big[i] = static_cast<char>(i / 4096);
    sum.store(big[4096 * 3]);
  });
  t.join();
  EXPECT_EQ(sum.load(), 3);
  EXPECT_EQ(t.warning(), "");
}

TEST(RtThread, RejectsAnEmptyBodyAndASecondStart) {
  RtThread t;
  EXPECT_THROW(t.start(ThreadSpec{"rt-empty", 0, -1, 64 * 1024}, nullptr), std::invalid_argument);
  EXPECT_FALSE(t.running());

  std::atomic<bool> release{false};
  t.start(ThreadSpec{"rt-twice", 0, -1, 64 * 1024}, [&] {
    while (!release.load()) usleep(100);
  });
  EXPECT_THROW(t.start(ThreadSpec{"rt-twice", 0, -1, 64 * 1024}, [] {}), std::logic_error);
  release.store(true);
  t.join();
}

TEST(LockMemory, PrefaultsTheHeapAndLocksOrSaysWhy) {
  const MemoryReport r = lockMemory(8 * 1024 * 1024, 64 * 1024);
  EXPECT_EQ(r.heap_prefaulted, 8u * 1024 * 1024);
  // Locked, or a warning line explains why not (no right to lock, a sanitizer build, ...).
  EXPECT_TRUE(r.locked || !r.warnings.empty());
  EXPECT_TRUE(r.malloc_tuned || !r.warnings.empty());
  for (const std::string& w : r.warnings) {
    EXPECT_FALSE(w.empty());
    EXPECT_FALSE(contains(w, "\n")) << w;
  }
  if (!r.locked) {
    bool explained = false;
    for (const std::string& w : r.warnings) explained = explained || contains(w, "mlockall");
    EXPECT_TRUE(explained);
  }
}

TEST(LockMemory, AStackRequestBeyondTheStackIsClampedWithAWarning) {
  rlimit limit{};
  ASSERT_EQ(getrlimit(RLIMIT_STACK, &limit), 0);
  if (limit.rlim_cur == RLIM_INFINITY || limit.rlim_cur > 64u * 1024 * 1024) {
    GTEST_SKIP() << "the main stack is unlimited or large here: nothing to clamp";
  }
  const MemoryReport r = lockMemory(0, 1024u * 1024 * 1024);
  EXPECT_EQ(r.heap_prefaulted, 0u);
  bool clamped = false;
  for (const std::string& w : r.warnings) clamped = clamped || contains(w, "exceeds the stack left");
  EXPECT_TRUE(clamped);
}

}  // namespace
}  // namespace staa::rt
