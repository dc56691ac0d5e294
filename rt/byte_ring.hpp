#pragma once
// Lock-free single-producer single-consumer ring of variable-length records (a byte ring
// sized at start-up), for the flight recorder: the control thread pushes one encoded cycle
// per period, the service thread pops them. A record is a 4-byte length and its bytes,
// never split: when it does not fit before the end of the buffer, the rest of the buffer
// is skipped (a length of kWrap marks it). push() fails and counts a drop when the ring is
// full: the real-time producer never waits. No allocation after construction.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>
#include <vector>

namespace staa::rt {

class ByteRing {
 public:
  // `capacity` bytes, rounded up to a power of two (at least 64).
  explicit ByteRing(std::size_t capacity) : buffer_(roundUp(capacity)), mask_(buffer_.size() - 1) {}
  ByteRing(const ByteRing&) = delete;
  ByteRing& operator=(const ByteRing&) = delete;

  // The longest record that can ever be pushed.
  std::size_t maxRecord() const { return buffer_.size() / 2 - kHeader; }

  // Producer. False (and a counted drop) when the record does not fit now or ever.
  bool push(std::span<const std::byte> record) {
    const std::size_t n = record.size();
    if (n > maxRecord()) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    const std::size_t size = buffer_.size();
    std::size_t offset = head & mask_;
    std::size_t need = align(kHeader + n);
    std::size_t skip = 0;
    if (offset + need > size) skip = size - offset;  // not split: skip to the start
    if (head + skip + need - tail > size) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    if (skip > 0) {
      writeLength(offset, kWrap);
      head += skip;
      offset = 0;
    }
    writeLength(offset, static_cast<std::uint32_t>(n));
    if (n > 0) std::memcpy(buffer_.data() + offset + kHeader, record.data(), n);
    head_.store(head + need, std::memory_order_release);
    return true;
  }

  // Consumer: copies the next record into `out` (resized: the consumer may allocate). False
  // when the ring is empty.
  bool pop(std::vector<std::byte>& out) {
    std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t head = head_.load(std::memory_order_acquire);
    if (tail == head) return false;
    std::size_t offset = tail & mask_;
    std::uint32_t n = readLength(offset);
    if (n == kWrap) {
      tail += buffer_.size() - offset;
      offset = 0;
      n = readLength(offset);
    }
    out.resize(n);
    if (n > 0) std::memcpy(out.data(), buffer_.data() + offset + kHeader, n);
    tail_.store(tail + align(kHeader + n), std::memory_order_release);
    return true;
  }

  std::size_t capacity() const { return buffer_.size(); }
  // Bytes in use (exact from the producer or the consumer, an estimate from elsewhere).
  std::size_t used() const {
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    const std::size_t head = head_.load(std::memory_order_acquire);
    return head >= tail ? head - tail : 0;
  }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::size_t kHeader = 4;
  static constexpr std::uint32_t kWrap = 0xFFFFFFFFu;
  static std::size_t roundUp(std::size_t n) {
    if (n > (std::size_t{1} << 40)) throw std::invalid_argument("ByteRing: capacity too large");
    std::size_t c = 64;
    while (c < n) c <<= 1;
    return c;
  }
  // Records start on 8-byte boundaries, so a length never straddles the end.
  static std::size_t align(std::size_t n) { return (n + 7) & ~std::size_t{7}; }
  void writeLength(std::size_t offset, std::uint32_t n) { std::memcpy(buffer_.data() + offset, &n, kHeader); }
  std::uint32_t readLength(std::size_t offset) const {
    std::uint32_t n = 0;
    std::memcpy(&n, buffer_.data() + offset, kHeader);
    return n;
  }

  std::vector<std::byte> buffer_;
  std::size_t mask_;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
  alignas(64) std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace staa::rt
