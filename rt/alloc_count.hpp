#pragma once
// Counting heap allocations, for the daemon and for tests, through one replacement of the
// global operator new/delete (rt/alloc_hook.cpp, target staa_rt_alloc_hook: linked into
// staad and into every test that counts allocations). It counts every allocation twice over:
//   - per thread, always: AllocationScope counts what the calling thread allocated in a
//     scope (a test proving that a code path allocates nothing);
//   - in total, for threads marked real-time: the daemon reports the count as
//     rt_allocations, which must stay 0 after READY=1.
// Without the hook linked, the counts stay 0 and hookInstalled() is false: a test that counts
// asserts hookInstalled() first.

#include <cstdint>

namespace staa::rt {

// Marks (or unmarks) the calling thread as real-time.
void markRealtimeThread(bool realtime);
bool isRealtimeThread();
// Allocations by marked threads since the last reset.
std::uint64_t realtimeAllocations();
void resetRealtimeAllocations();
// Allocations by the calling thread since it started.
std::uint64_t threadAllocations();
// Whether the counting operator new is linked into this program.
bool hookInstalled();

// The calling thread's allocations between construction and count().
class AllocationScope {
 public:
  AllocationScope() : start_(threadAllocations()) {}
  std::uint64_t count() const { return threadAllocations() - start_; }

 private:
  std::uint64_t start_;
};

// Called by the hook (not by users).
void noteAllocation();
void noteHookInstalled();

}  // namespace staa::rt
