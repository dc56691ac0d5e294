#pragma once
// The real-time threads' "no cycle blocked" (a thread's status: blocked_cycles,
// blocked_faulted_cycles, faulted_cycles, last_blocked_cycle). A cycle that blocked without a
// page fault waited on a lock or for I/O: ours in every build. Under AddressSanitizer the
// shadow memory and the sanitizer's allocator are not prefaulted: the first cycles fault, and
// a fault can wait (on the address space's lock while another thread maps memory), so there a
// blocked cycle that faulted is the sanitizer's. Everywhere else no cycle may block at all.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace staa::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#else
inline constexpr bool kAddressSanitizer = false;
#endif

inline ::testing::AssertionResult noBlockedCycle(const nlohmann::json& thread) {
  const auto blocked = thread.value("blocked_cycles", -1);
  const auto on_memory = thread.value("blocked_faulted_cycles", -1);
  const auto ours = kAddressSanitizer ? blocked - on_memory : blocked;
  if (blocked >= 0 && on_memory >= 0 && ours == 0) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << blocked << " cycles blocked, " << on_memory
                                       << " of them with a page fault (last: cycle index + 1 = "
                                       << thread.value("last_blocked_cycle", -1) << "; faulted cycles "
                                       << thread.value("faulted_cycles", -1) << ")"
                                       << (kAddressSanitizer ? "; under ASan only those without a fault count" : "");
}

}  // namespace staa::test
