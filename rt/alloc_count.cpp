#include "rt/alloc_count.hpp"

#include <atomic>

namespace staa::rt {

namespace {
// Constant-initialized (no dynamic initializer, no TLS init function): the hook may call in
// here from the first operator new of the program, before any static constructor has run.
std::atomic<std::uint64_t> g_realtime_allocations{0};
std::atomic<bool> g_hook_installed{false};
thread_local bool t_realtime = false;
thread_local std::uint64_t t_allocations = 0;
}  // namespace

void markRealtimeThread(bool realtime) { t_realtime = realtime; }
bool isRealtimeThread() { return t_realtime; }

std::uint64_t realtimeAllocations() { return g_realtime_allocations.load(std::memory_order_relaxed); }
void resetRealtimeAllocations() { g_realtime_allocations.store(0, std::memory_order_relaxed); }

std::uint64_t threadAllocations() { return t_allocations; }

bool hookInstalled() { return g_hook_installed.load(std::memory_order_relaxed); }

void noteAllocation() {
  ++t_allocations;
  if (t_realtime) g_realtime_allocations.fetch_add(1, std::memory_order_relaxed);
}
void noteHookInstalled() { g_hook_installed.store(true, std::memory_order_relaxed); }

}  // namespace staa::rt
