// scanner.backend ros without ROS: RosLaserScanner fed through its port
// (hal/ros/laser_scan_port.hpp) as a transport would:
//   - a good scan (the HSR's 1,081 beams, no returns among them) read back exactly;
//   - every bad scan dropped, counted under its first failed check, and read() returns
//     nothing new (the last good scan is not handed out again);
//   - the stamp mapped to the monotonic clock;
//   - read() allocates nothing.
#include "hal/ros/ros_laser_scanner.hpp"

#include "rt/alloc_count.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>
#include <vector>

namespace staa::hal {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// A sensor_msgs/LaserScan's fields and the view onto them: the HSR-B's base scanner (270
// degrees in 1,081 beams, 0.05..20 m).
struct Message {
  std::vector<float> ranges;
  LaserScanView view;

  Message(std::int64_t stamp_ns, std::size_t beams = 1081) {
    const float half = static_cast<float>(0.75 * std::numbers::pi);
    ranges.resize(beams);
    for (std::size_t i = 0; i < beams; ++i) ranges[i] = 0.5f + 0.001f * static_cast<float>(i);
    view.stamp_ns = stamp_ns;
    view.received_ns = stamp_ns + 10'000'000;  // 10 ms old on arrival
    view.angle_min = -half;
    view.angle_max = half;
    view.angle_increment = beams > 1 ? 2.0f * half / static_cast<float>(beams - 1) : 0.01f;
    view.range_min = 0.05f;
    view.range_max = 20.0f;
    sync();
  }
  void sync() {
    view.ranges = ranges.data();
    view.count = ranges.size();
  }
};

TEST(RosLaserScanner, AGoodScanIsReadBackExactlyOnce) {
  RosLaserScanner scanner;
  Message m(100 * kSecond);
  m.ranges[0] = kNaN;    // no return
  m.ranges[1] = kInf;    // no return (REP 117: out of range)
  m.ranges[2] = 0.01f;   // below range_min: no return, kept as it is
  m.ranges[1080] = 25.0f;
  auto scan = std::make_unique<LaserScan>();
  EXPECT_FALSE(scanner.read(0, *scan)) << "nothing offered yet";
  scanner.offer(m.view, 7 * kSecond);
  ASSERT_TRUE(scanner.read(0, *scan));
  EXPECT_EQ(scan->count, 1081u);
  EXPECT_EQ(scan->angle_min, static_cast<double>(m.view.angle_min));
  EXPECT_EQ(scan->angle_increment, static_cast<double>(m.view.angle_increment));
  EXPECT_EQ(scan->range_min, static_cast<double>(0.05f));
  EXPECT_EQ(scan->range_max, 20.0);
  EXPECT_EQ(scan->stamp, 7 * kSecond - 10'000'000) << "the arrival less the message's age";
  EXPECT_EQ(scan->sequence, 1u);
  EXPECT_TRUE(std::isnan(scan->ranges[0]));
  EXPECT_TRUE(std::isinf(scan->ranges[1]));
  EXPECT_EQ(std::memcmp(scan->ranges.data() + 2, m.ranges.data() + 2, (1081 - 2) * sizeof(float)), 0);
  EXPECT_EQ(scan->ranges[1081], 0.0f) << "past the beams: nothing";
  EXPECT_TRUE(scanProblem(*scan).empty()) << scanProblem(*scan);
  EXPECT_FALSE(scanner.read(0, *scan)) << "read once";
  EXPECT_EQ(scanner.accepted(), 1u);
  EXPECT_EQ(scanner.droppedTotal(), 0u);

  // The next one replaces it; of two offered between reads, the newer is read.
  Message a(101 * kSecond), b(102 * kSecond, 720);
  scanner.offer(a.view, 8 * kSecond);
  scanner.offer(b.view, 9 * kSecond);
  ASSERT_TRUE(scanner.read(0, *scan));
  EXPECT_EQ(scan->count, 720u);
  EXPECT_EQ(scan->sequence, 3u);
  EXPECT_EQ(scan->ranges[719], b.ranges[719]);
  EXPECT_EQ(scan->ranges[720], 0.0f) << "the longer scan's beams beyond 720 were cleared";
}

TEST(RosLaserScanner, DropsBadScansCountingEachReasonAndReadsNothingNew) {
  RosLaserScanner scanner;
  auto scan = std::make_unique<LaserScan>();
  const std::int64_t t0 = 50 * kSecond;
  scanner.offer(Message(t0).view, kSecond);
  ASSERT_TRUE(scanner.read(0, *scan));
  const rt::Nanos good_stamp = scan->stamp;

  std::int64_t stamp = t0;
  const auto next = [&stamp] { return stamp += kSecond / 40; };
  const auto expectDropped = [&](const char* what, RosScanDrop reason, const LaserScanView& view) {
    SCOPED_TRACE(what);
    const std::uint64_t before = scanner.dropped(reason), total = scanner.droppedTotal();
    scanner.offer(view, 2 * kSecond);
    EXPECT_EQ(scanner.dropped(reason), before + 1) << toString(reason);
    EXPECT_EQ(scanner.droppedTotal(), total + 1);
    EXPECT_EQ(scanner.accepted(), 1u);
    EXPECT_FALSE(scanner.read(0, *scan));
    EXPECT_EQ(scan->stamp, good_stamp);
  };

  Message empty(next());
  empty.ranges.clear();
  empty.sync();
  expectDropped("no ranges", RosScanDrop::kBeams, empty.view);
  Message many(next(), 2049);
  expectDropped("2049 ranges", RosScanDrop::kBeams, many.view);
  Message null(next());
  null.view.ranges = nullptr;
  expectDropped("no range data", RosScanDrop::kBeams, null.view);

  Message nan_increment(next());
  nan_increment.view.angle_increment = kNaN;
  expectDropped("NaN angle_increment", RosScanDrop::kGeometry, nan_increment.view);
  Message zero_increment(next());
  zero_increment.view.angle_increment = 0.0f;
  expectDropped("0 angle_increment", RosScanDrop::kGeometry, zero_increment.view);
  Message over_a_turn(next());
  over_a_turn.view.angle_increment *= 3.0f;
  over_a_turn.view.angle_max = over_a_turn.view.angle_min + over_a_turn.view.angle_increment * 1080.0f;
  expectDropped("over a turn", RosScanDrop::kGeometry, over_a_turn.view);
  Message inf_min(next());
  inf_min.view.angle_min = -kInf;
  expectDropped("angle_min -inf", RosScanDrop::kGeometry, inf_min.view);
  Message equal_ranges(next());
  equal_ranges.view.range_max = equal_ranges.view.range_min;
  expectDropped("range_max == range_min", RosScanDrop::kGeometry, equal_ranges.view);
  Message inverted(next());
  inverted.view.range_max = 0.01f;
  expectDropped("range_max < range_min", RosScanDrop::kGeometry, inverted.view);
  Message negative(next());
  negative.view.range_min = -1.0f;
  expectDropped("range_min < 0", RosScanDrop::kGeometry, negative.view);

  Message truncated(next());
  truncated.ranges.resize(1000);  // the angles still say 1,081 beams
  truncated.sync();
  expectDropped("1000 ranges for a sweep of 1081 beams", RosScanDrop::kSweep, truncated.view);
  Message two_short(next());
  two_short.ranges.resize(1079);
  two_short.sync();
  expectDropped("two beams fewer than the sweep", RosScanDrop::kSweep, two_short.view);
  Message nan_max(next());
  nan_max.view.angle_max = kNaN;
  expectDropped("NaN angle_max", RosScanDrop::kSweep, nan_max.view);

  expectDropped("stamp equal", RosScanDrop::kStamp, Message(t0).view);
  expectDropped("stamp going back", RosScanDrop::kStamp, Message(t0 - 1).view);
  expectDropped("stamp unset", RosScanDrop::kStamp, Message(0).view);

  EXPECT_EQ(scanner.dropped(RosScanDrop::kBeams), 3u);
  EXPECT_EQ(scanner.dropped(RosScanDrop::kGeometry), 7u);
  EXPECT_EQ(scanner.dropped(RosScanDrop::kSweep), 3u);
  EXPECT_EQ(scanner.dropped(RosScanDrop::kStamp), 3u);
  EXPECT_EQ(scanner.droppedTotal(), 16u);
  EXPECT_EQ(scanner.dropped(RosScanDrop::kCount), 0u);

  // One beam more or less than the sweep says (drivers differ on angle_max), a negative
  // increment (mounted upside down), and after the drops scans flow again.
  Message one_short(next(), 1081);
  one_short.ranges.pop_back();
  one_short.sync();
  scanner.offer(one_short.view, 3 * kSecond);
  ASSERT_TRUE(scanner.read(0, *scan));
  EXPECT_EQ(scan->count, 1080u);
  Message upside_down(next());
  std::swap(upside_down.view.angle_min, upside_down.view.angle_max);
  upside_down.view.angle_increment = -upside_down.view.angle_increment;
  scanner.offer(upside_down.view, 4 * kSecond);
  ASSERT_TRUE(scanner.read(0, *scan));
  EXPECT_LT(scan->angle_increment, 0.0);
  EXPECT_EQ(scanner.accepted(), 3u);
  EXPECT_EQ(scan->sequence, 3u);
  EXPECT_STREQ(toString(RosScanDrop::kBeams), "beams");
  EXPECT_STREQ(toString(RosScanDrop::kGeometry), "geometry");
  EXPECT_STREQ(toString(RosScanDrop::kSweep), "sweep");
  EXPECT_STREQ(toString(RosScanDrop::kStamp), "stamp");
}

TEST(RosLaserScanner, StampsAreArrivalMinusASaneAgeAndAlwaysIncrease) {
  RosLaserScanner scanner(RosLaserScannerConfig{0.5});
  auto scan = std::make_unique<LaserScan>();
  const auto stampOf = [&](std::int64_t ros_stamp, std::int64_t received, std::int64_t arrival) {
    Message m(ros_stamp);
    m.view.received_ns = received;
    scanner.offer(m.view, arrival);
    EXPECT_TRUE(scanner.read(0, *scan));
    return scan->stamp;
  };
  const std::int64_t t = 1000 * kSecond;
  EXPECT_EQ(stampOf(t, t + 30'000'000, 10 * kSecond), 10 * kSecond - 30'000'000);  // 30 ms old
  EXPECT_EQ(stampOf(t + kSecond, t + 2 * kSecond, 11 * kSecond), 11 * kSecond);    // 1 s: not believed
  EXPECT_EQ(stampOf(t + 2 * kSecond, t + kSecond, 12 * kSecond), 12 * kSecond);    // from the future
  // A mapped stamp at or before the previous one is moved just after it.
  EXPECT_EQ(stampOf(t + 3 * kSecond, t + 3 * kSecond + 400'000'000, 12 * kSecond + 100'000'000), 12 * kSecond + 1);
}

TEST(RosLaserScanner, ReadAllocatesNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_ros_laser_scanner must link staa_rt_alloc_hook";
  RosLaserScanner scanner;
  Message m(kSecond);
  auto scan = std::make_unique<LaserScan>();
  std::uint64_t read_allocations = 0;
  int reads = 0;
  for (int k = 1; k <= 400; ++k) {
    m.view.stamp_ns = k * kSecond / 40;
    m.view.received_ns = m.view.stamp_ns + 5'000'000;
    scanner.offer(m.view, k * kSecond / 40);
    rt::AllocationScope scope;
    reads += scanner.read(0, *scan) ? 1 : 0;
    reads += scanner.read(0, *scan) ? 1 : 0;
    read_allocations += scope.count();
  }
  EXPECT_EQ(reads, 400);
  EXPECT_EQ(read_allocations, 0u);
}

TEST(RosLaserScanner, RejectsABadConfig) {
  EXPECT_THROW(RosLaserScanner(RosLaserScannerConfig{-0.1}), std::invalid_argument);
  EXPECT_THROW(RosLaserScanner(RosLaserScannerConfig{std::numeric_limits<double>::quiet_NaN()}), std::invalid_argument);
  EXPECT_NO_THROW(RosLaserScanner(RosLaserScannerConfig{0.0}));
}

}  // namespace
}  // namespace staa::hal
