#pragma once
// Lock-free single-producer single-consumer ring of N slots (N a power of two), for passing
// requests, telemetry and log records between threads without locks or allocation. push()
// fails (and counts a drop) when the ring is full: a real-time producer never waits.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace staa::rt {

template <typename T, std::size_t N>
class SpscRing {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "SpscRing: N must be a power of two");
  static_assert(std::is_trivially_copyable_v<T>, "SpscRing: T must be trivially copyable");

 public:
  // Producer.
  bool push(const T& value) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) == N) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    slots_[head & (N - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  // Consumer.
  bool pop(T& out) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = slots_[tail & (N - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  // Exact from the producer or the consumer; from a third thread (a monitor) an estimate:
  // tail is read first, so the result never underflows (it is at most N).
  std::size_t size() const {
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    const std::size_t head = head_.load(std::memory_order_acquire);
    return head >= tail ? head - tail : 0;
  }
  static constexpr std::size_t capacity() { return N; }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
  alignas(64) std::atomic<std::uint64_t> dropped_{0};
  std::array<T, N> slots_{};
};

}  // namespace staa::rt
