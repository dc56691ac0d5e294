#pragma once
// A triple buffer: one writer publishes whole values, one reader always gets the latest
// complete one, neither waits, nothing is allocated after construction. Used for the latest
// odometry, obstacle frames, the command and the status between threads.
//
//   writer: T& w = tb.writeBuffer(); fill w; tb.publish();
//   reader: if (tb.update()) { use tb.readBuffer(); }  // readBuffer() stays valid until update()

#include <array>
#include <atomic>
#include <cstdint>

namespace staa::rt {

template <typename T>
class TripleBuffer {
 public:
  TripleBuffer() = default;
  explicit TripleBuffer(const T& initial) : buffers_{initial, initial, initial} {}

  T& writeBuffer() { return buffers_[write_]; }
  void publish() {
    const std::uint8_t old = shared_.exchange(static_cast<std::uint8_t>(write_ | kFresh), std::memory_order_acq_rel);
    write_ = old & kIndex;
    published_.fetch_add(1, std::memory_order_relaxed);
  }
  // Reader: takes the newest published value if there is one; true when it is new.
  bool update() {
    if ((shared_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    const std::uint8_t old = shared_.exchange(read_, std::memory_order_acq_rel);
    read_ = old & kIndex;
    return true;
  }
  const T& readBuffer() const { return buffers_[read_]; }
  // How many values the writer has published (for staleness checks and tests).
  std::uint64_t published() const { return published_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::uint8_t kIndex = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;
  std::array<T, 3> buffers_{};
  std::uint8_t write_ = 0;
  std::uint8_t read_ = 1;
  std::atomic<std::uint8_t> shared_{2};
  std::atomic<std::uint64_t> published_{0};
};

}  // namespace staa::rt
