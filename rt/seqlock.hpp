#pragma once
// A value that one thread publishes whole and any number of threads read whole (a sequence
// lock): store() never waits and never allocates (a real-time writer); load() returns a copy
// that is never torn, retrying while a store is under way (readers are not real-time). The
// value lives in relaxed atomic words, so there is no data race; the sequence's fences order
// them (Boehm, "Can seqlocks get along with programming language memory models?", 2012).

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace staa::rt {

template <typename T>
class SeqLock {
  static_assert(std::is_trivially_copyable_v<T>, "SeqLock: T must be trivially copyable");
  static constexpr std::size_t kWords = (sizeof(T) + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t);
  using Words = std::array<std::uint64_t, kWords>;

 public:
  SeqLock() : SeqLock(T{}) {}
  explicit SeqLock(const T& initial) { write(initial); }

  // The one writer.
  void store(const T& value) {
    const std::uint64_t seq = seq_.load(std::memory_order_relaxed);
    seq_.store(seq + 1, std::memory_order_relaxed);  // odd: a store is under way
    std::atomic_thread_fence(std::memory_order_release);
    write(value);
    seq_.store(seq + 2, std::memory_order_release);
  }

  // Any thread.
  T load() const {
    Words words;
    for (;;) {
      const std::uint64_t before = seq_.load(std::memory_order_acquire);
      if ((before & 1) != 0) continue;
      for (std::size_t i = 0; i < kWords; ++i) words[i] = words_[i].load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) == before) break;
    }
    T value;
    std::memcpy(static_cast<void*>(&value), words.data(), sizeof(T));  // T is trivially copyable
    return value;
  }

 private:
  void write(const T& value) {
    Words words{};
    std::memcpy(words.data(), &value, sizeof(T));
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(words[i], std::memory_order_relaxed);
  }

  std::atomic<std::uint64_t> seq_{0};
  std::array<std::atomic<std::uint64_t>, kWords> words_{};
};

}  // namespace staa::rt
