#include "rt/alloc_count.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <new>
#include <thread>
#include <vector>

namespace staa::rt {
namespace {

// The compiler may elide a new/delete pair whose pointer goes nowhere ([expr.new]); storing
// it in a volatile makes every allocation below real.
void* volatile g_sink = nullptr;
template <typename T>
T* kept(T* p) {
  g_sink = p;
  return p;
}

// Runs `f` on a fresh thread marked real-time and returns the allocations it counted.
template <typename F>
std::uint64_t countedOnRealtimeThread(F&& f) {
  std::uint64_t counted = 0;
  std::thread t([&] {
    markRealtimeThread(true);
    resetRealtimeAllocations();
    f();
    counted = realtimeAllocations();
    markRealtimeThread(false);
  });
  t.join();
  return counted;
}

TEST(AllocHook, IsInstalled) { EXPECT_TRUE(hookInstalled()); }

TEST(AllocHook, MarkedThreadAllocationsAreCounted) {
  const std::uint64_t one = countedOnRealtimeThread([] {
    int* p = kept(new int(5));
    delete p;  // frees are not allocations
  });
  EXPECT_EQ(one, 1u);

  std::uint64_t growths = 0;
  const std::uint64_t vector = countedOnRealtimeThread([&] {
    std::vector<int> v;
    std::size_t capacity = v.capacity();
    for (int i = 0; i < 100; ++i) {
      v.push_back(i);
      if (v.capacity() != capacity) {
        ++growths;
        capacity = v.capacity();
      }
    }
  });
  EXPECT_GT(growths, 1u);
  EXPECT_EQ(vector, growths);  // one allocation per growth

  struct alignas(64) Wide {
    char bytes[64];
  };
  const std::uint64_t forms = countedOnRealtimeThread([] {
    delete[] kept(new int[10]);
    delete kept(new (std::nothrow) int(1));
    delete[] kept(new (std::nothrow) int[3]);
    delete kept(new Wide);     // aligned
    delete[] kept(new Wide[2]);  // aligned array
    ::operator delete(kept(::operator new(8, std::align_val_t{128}, std::nothrow)), std::align_val_t{128});
  });
  EXPECT_EQ(forms, 6u);
}

TEST(AllocHook, UnmarkedThreadsAreNotCounted) {
  resetRealtimeAllocations();
  std::thread t([] {
    EXPECT_FALSE(isRealtimeThread());
    auto v = std::make_unique<std::vector<int>>(1000, 7);
    delete kept(new int(1));
  });
  t.join();
  delete kept(new int(3));
  EXPECT_EQ(realtimeAllocations(), 0u);
}

TEST(AllocHook, UnmarkingStopsCountingAndResetClears) {
  std::uint64_t while_marked = 0;
  std::uint64_t after_unmark = 0;
  std::uint64_t after_reset = 0;
  bool flag_marked = false;
  bool flag_unmarked = true;
  std::thread t([&] {
    markRealtimeThread(true);
    flag_marked = isRealtimeThread();
    resetRealtimeAllocations();
    delete kept(new int(1));
    delete kept(new int(2));
    while_marked = realtimeAllocations();
    markRealtimeThread(false);
    flag_unmarked = isRealtimeThread();
    delete kept(new int(3));
    after_unmark = realtimeAllocations();
    resetRealtimeAllocations();
    after_reset = realtimeAllocations();
  });
  t.join();
  EXPECT_TRUE(flag_marked);
  EXPECT_FALSE(flag_unmarked);
  EXPECT_EQ(while_marked, 2u);
  EXPECT_EQ(after_unmark, 2u);
  EXPECT_EQ(after_reset, 0u);
}

// The tests' scopes: the calling thread's allocations, marked real-time or not; another
// thread's never.
TEST(AllocHook, AScopeCountsTheCallingThreadsAllocationsOnly) {
  ASSERT_TRUE(hookInstalled());
  std::atomic<bool> go{false};
  std::uint64_t inner = 0;
  std::thread other([&] {
    while (!go.load(std::memory_order_acquire)) {
    }
    AllocationScope own;
    markRealtimeThread(true);
    delete kept(new int(3));
    markRealtimeThread(false);
    delete kept(new int(4));
    delete[] kept(new int[5]);
    inner = own.count();
  });
  AllocationScope scope;
  EXPECT_EQ(scope.count(), 0u);
  delete kept(new int(1));
  delete[] kept(new int[4]);
  go.store(true, std::memory_order_release);
  other.join();
  EXPECT_EQ(scope.count(), 2u);  // not the other thread's three
  EXPECT_EQ(inner, 3u);          // marked real-time or not
}

}  // namespace
}  // namespace staa::rt
