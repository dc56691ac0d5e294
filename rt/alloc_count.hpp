#pragma once
// Counting heap allocations made by real-time threads (the daemon reports the count as
// rt_allocations; it must stay 0 after READY=1). A thread marks itself real-time; the
// replacement operator new/delete in rt/alloc_hook.cpp (linked into staad and the daemon's
// tests only: target staa_rt_alloc_hook) counts every allocation made while the calling
// thread is marked. Without the hook linked, the count stays 0 and hookInstalled() is false.

#include <cstdint>

namespace staa::rt {

// Marks (or unmarks) the calling thread as real-time.
void markRealtimeThread(bool realtime);
bool isRealtimeThread();
// Allocations by marked threads since the last reset.
std::uint64_t realtimeAllocations();
void resetRealtimeAllocations();
// Whether the counting operator new is linked into this program.
bool hookInstalled();

// Called by the hook (not by users).
void noteAllocation();
void noteHookInstalled();

}  // namespace staa::rt
