#include "rt/byte_ring.hpp"
#include "rt/log_ring.hpp"
#include "rt/seqlock.hpp"
#include "rt/spsc_ring.hpp"
#include "rt/triple_buffer.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <thread>
#include <vector>

namespace staa::rt {
namespace {

std::vector<std::byte> record(std::size_t n, std::uint8_t fill) { return std::vector<std::byte>(n, std::byte{fill}); }

TEST(ByteRing, KeepsRecordsWholeAndInOrderAcrossTheWrapAndDropsWhatDoesNotFit) {
  ByteRing ring(256);  // a power of two already
  EXPECT_EQ(ring.capacity(), 256u);
  EXPECT_EQ(ring.maxRecord(), 124u);
  std::vector<std::byte> out;
  EXPECT_FALSE(ring.pop(out));
  // 100-byte records take 104 bytes each: two fit, the third waits for room.
  ASSERT_TRUE(ring.push(record(100, 1)));
  ASSERT_TRUE(ring.push(record(100, 2)));
  EXPECT_FALSE(ring.push(record(100, 3)));
  EXPECT_EQ(ring.dropped(), 1u);
  ASSERT_TRUE(ring.pop(out));
  EXPECT_EQ(out, record(100, 1));
  // The next one does not fit before the end (48 bytes left there): it starts at the front.
  ASSERT_TRUE(ring.push(record(100, 4)));
  ASSERT_TRUE(ring.pop(out));
  EXPECT_EQ(out, record(100, 2));
  ASSERT_TRUE(ring.pop(out));
  EXPECT_EQ(out, record(100, 4));
  EXPECT_FALSE(ring.pop(out));
  EXPECT_FALSE(ring.push(record(125, 5))) << "longer than half the ring: never";
  ASSERT_TRUE(ring.push(record(0, 0)));
  ASSERT_TRUE(ring.pop(out));
  EXPECT_TRUE(out.empty());
}

TEST(ByteRing, TwoThreadsOfVaryingRecordsLoseNothingWhenTheProducerRetries) {
  ByteRing ring(4096);
  constexpr int kRecords = 200000;
  std::thread producer([&] {
    std::vector<std::byte> r;
    for (int i = 0; i < kRecords; ++i) {
      r.assign(static_cast<std::size_t>(i % 300), std::byte{static_cast<std::uint8_t>(i)});
      while (!ring.push(r)) std::this_thread::yield();
    }
  });
  std::vector<std::byte> out;
  for (int i = 0; i < kRecords; ++i) {
    while (!ring.pop(out)) std::this_thread::yield();
    ASSERT_EQ(out.size(), static_cast<std::size_t>(i % 300));
    if (!out.empty()) {
      ASSERT_EQ(out.back(), std::byte{static_cast<std::uint8_t>(i)});
    }
  }
  producer.join();
  EXPECT_FALSE(ring.pop(out));
}

TEST(SpscRing, PushesAndPopsInOrderAndCountsDropsWhenFull) {
  SpscRing<int, 4> ring;
  EXPECT_EQ(ring.capacity(), 4u);
  int out = 0;
  EXPECT_FALSE(ring.pop(out));
  for (int i = 1; i <= 4; ++i) EXPECT_TRUE(ring.push(i));
  EXPECT_EQ(ring.size(), 4u);
  EXPECT_FALSE(ring.push(5));  // full: dropped, not waited for
  EXPECT_FALSE(ring.push(6));
  EXPECT_EQ(ring.dropped(), 2u);
  for (int i = 1; i <= 4; ++i) {
    ASSERT_TRUE(ring.pop(out));
    EXPECT_EQ(out, i);
  }
  EXPECT_FALSE(ring.pop(out));
  EXPECT_EQ(ring.size(), 0u);
}

TEST(SpscRing, WrapsAroundManyTimes) {
  SpscRing<int, 4> ring;
  int out = 0;
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(ring.push(i));
    ASSERT_TRUE(ring.push(i + 1));
    ASSERT_TRUE(ring.pop(out));
    ASSERT_EQ(out, i);
    ASSERT_TRUE(ring.pop(out));
    ASSERT_EQ(out, i + 1);
  }
  EXPECT_EQ(ring.dropped(), 0u);
}

constexpr std::uint64_t kStressCount = 1'000'000;

TEST(SpscRing, TwoThreadsWithRetryLoseNothing) {
  SpscRing<std::uint64_t, 1024> ring;
  std::uint64_t failed_pushes = 0;
  std::thread producer([&] {
    for (std::uint64_t v = 0; v < kStressCount; ++v) {
      while (!ring.push(v)) {
        ++failed_pushes;
        std::this_thread::yield();
      }
    }
  });
  std::uint64_t expected = 0;
  bool in_order = true;
  while (expected < kStressCount) {
    std::uint64_t v = 0;
    if (!ring.pop(v)) {
      std::this_thread::yield();
      continue;
    }
    in_order = in_order && v == expected;
    ++expected;
  }
  producer.join();
  EXPECT_TRUE(in_order);
  EXPECT_EQ(expected, kStressCount);
  // Every refused push was counted as a drop, and then retried.
  EXPECT_EQ(ring.dropped(), failed_pushes);
  EXPECT_EQ(ring.size(), 0u);
}

TEST(SpscRing, TwoThreadsWithoutRetryCountEveryLostValue) {
  SpscRing<std::uint64_t, 256> ring;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (std::uint64_t v = 1; v <= kStressCount; ++v) ring.push(v);  // a real-time producer never waits
    done.store(true, std::memory_order_release);
  });
  std::uint64_t received = 0;
  std::uint64_t last = 0;
  bool increasing = true;
  for (;;) {
    const bool finished = done.load(std::memory_order_acquire);
    std::uint64_t v = 0;
    bool got = false;
    while (ring.pop(v)) {
      got = true;
      increasing = increasing && v > last;
      last = v;
      ++received;
    }
    if (finished && !got) break;
    if (!got) std::this_thread::yield();
  }
  producer.join();
  EXPECT_TRUE(increasing);
  EXPECT_EQ(received + ring.dropped(), kStressCount);
}

TEST(LogRing, CarriesARecordWithItsStaticMessage) {
  LogRing ring;
  LogRecord r;
  r.time = 42;
  r.level = LogLevel::kWarning;
  r.message = "overrun";
  r.values[0] = 1.5;
  r.value_count = 1;
  ASSERT_TRUE(ring.push(r));
  LogRecord out;
  ASSERT_TRUE(ring.pop(out));
  EXPECT_EQ(out.time, 42);
  EXPECT_EQ(out.level, LogLevel::kWarning);
  EXPECT_STREQ(out.message, "overrun");
  EXPECT_EQ(out.values[0], 1.5);
  EXPECT_EQ(out.value_count, 1u);
  EXPECT_EQ(LogRing::capacity(), 256u);
}

TEST(TripleBuffer, ReaderGetsTheLatestAndKeepsItUntilUpdate) {
  TripleBuffer<int> tb(-1);
  EXPECT_FALSE(tb.update());  // nothing published yet
  EXPECT_EQ(tb.readBuffer(), -1);
  EXPECT_EQ(tb.published(), 0u);

  tb.writeBuffer() = 1;
  tb.publish();
  EXPECT_TRUE(tb.update());
  EXPECT_EQ(tb.readBuffer(), 1);
  EXPECT_FALSE(tb.update());  // nothing new
  EXPECT_EQ(tb.readBuffer(), 1);

  for (int v = 2; v <= 4; ++v) {
    tb.writeBuffer() = v;
    tb.publish();
  }
  EXPECT_EQ(tb.readBuffer(), 1);  // stable until the reader updates
  EXPECT_TRUE(tb.update());
  EXPECT_EQ(tb.readBuffer(), 4);  // latest wins; 2 and 3 were overwritten
  EXPECT_FALSE(tb.update());
  EXPECT_EQ(tb.published(), 4u);

  // The writer's buffer is never the one being read.
  tb.writeBuffer() = 99;
  EXPECT_EQ(tb.readBuffer(), 4);
  tb.publish();
  EXPECT_TRUE(tb.update());
  EXPECT_EQ(tb.readBuffer(), 99);
}

// 256 bytes whose fields must agree: any torn read breaks the relation.
struct Frame {
  std::uint64_t seq = 0;
  std::uint64_t a = 0;
  std::uint64_t b = 0;  // a * 2
  std::uint64_t c = 0;  // a * 3
  std::uint64_t fill[28] = {};  // each = seq
};
static_assert(sizeof(Frame) == 256);

bool consistent(const Frame& f) {
  if (f.a != f.seq || f.b != f.a * 2 || f.c != f.a * 3) return false;
  for (std::uint64_t x : f.fill) {
    if (x != f.seq) return false;
  }
  return true;
}

TEST(TripleBuffer, ReaderNeverSeesATornValueAcrossThreads) {
  TripleBuffer<Frame> tb;
  constexpr std::uint64_t kFrames = 200'000;
  std::thread writer([&] {
    for (std::uint64_t s = 1; s <= kFrames; ++s) {
      Frame& f = tb.writeBuffer();
      f.seq = s;
      f.a = s;
      f.b = s * 2;
      f.c = s * 3;
      for (std::uint64_t& x : f.fill) x = s;
      tb.publish();
    }
  });
  std::uint64_t last = 0;
  std::uint64_t updates = 0;
  bool torn = false;
  bool went_back = false;
  while (last < kFrames) {
    if (!tb.update()) {
      std::this_thread::yield();
      continue;
    }
    const Frame& f = tb.readBuffer();
    torn = torn || !consistent(f);
    went_back = went_back || f.seq <= last;  // each update brings a newer value
    last = f.seq;
    ++updates;
    if (torn || went_back) break;
  }
  writer.join();
  EXPECT_FALSE(torn);
  EXPECT_FALSE(went_back);
  EXPECT_EQ(last, kFrames);  // the final value always arrives
  EXPECT_GE(updates, 1u);
  EXPECT_EQ(tb.published(), kFrames);
}

// A periodic thread's counters read by the service thread: every copy is one the writer
// stored, whole, however the two threads interleave.
TEST(SeqLock, ReadersNeverSeeATornValueAcrossThreads) {
  struct Counters {
    std::uint64_t a = 0, b = 0, c = 0, d = 0, e = 0, f = 0, g = 0;
  };
  SeqLock<Counters> shared;
  EXPECT_EQ(shared.load().g, 0u);
  // The writer stores until the reader has read enough (on a loaded machine the two may
  // barely overlap; they always do for some reads).
  constexpr std::uint64_t kReads = 100'000;
  std::atomic<bool> enough{false};
  std::atomic<std::uint64_t> stored{0};
  std::thread writer([&] {
    for (std::uint64_t k = 1; !enough.load(std::memory_order_acquire); ++k) {
      shared.store(Counters{k, k, k, k, k, k, k});
      stored.store(k, std::memory_order_release);
    }
  });
  while (stored.load(std::memory_order_acquire) == 0) {
  }
  std::uint64_t last = 0;
  bool torn = false;
  bool backwards = false;
  for (std::uint64_t r = 0; r < kReads; ++r) {
    const Counters c = shared.load();
    torn |= c.a != c.b || c.a != c.c || c.a != c.d || c.a != c.e || c.a != c.f || c.a != c.g;
    backwards |= c.a < last;
    last = c.a;
  }
  enough.store(true, std::memory_order_release);
  writer.join();
  EXPECT_FALSE(torn);
  EXPECT_FALSE(backwards);
  EXPECT_GT(last, 0u);
  EXPECT_EQ(shared.load().g, stored.load());
}

}  // namespace
}  // namespace staa::rt
