// The ROS laser scan adapter (hal/ros): RosLaserScanner::offer on any sensor_msgs/LaserScan-
// like view (beam counts, angles and ranges of every float value, stamps), several scans in a
// row, then read(): a scan that comes out passes hal::scanProblem, holds no more than its
// beams, and its stamp comes after the previous one's; every scan offered is either accepted
// or dropped under a reason, never read out of bounds. No exception.
#include "fuzz_support.hpp"
#include "hal/ros/ros_laser_scanner.hpp"

#include <memory>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace staa::hal;
  staa::fuzz::Fields in(data, size);
  RosLaserScanner scanner;
  const auto out = std::make_unique<LaserScan>();
  std::vector<float> ranges;
  staa::rt::Nanos last = -1;
  const int scans = 1 + in.take<std::uint8_t>() % 4;
  for (int s = 0; s < scans; ++s) {
    LaserScanView view;
    view.stamp_ns = in.take<std::int64_t>();
    view.received_ns = in.take<std::int64_t>();
    view.angle_min = in.take<float>();
    view.angle_max = in.take<float>();
    view.angle_increment = in.take<float>();
    view.range_min = in.take<float>();
    view.range_max = in.take<float>();
    // Up to a little over the largest scan (4096 beams): most are dropped as too many.
    const std::size_t count = in.take<std::uint16_t>() % 4097;
    ranges.assign(count, 0.0f);
    const std::uint8_t* rest = in.rest();
    const std::size_t n = in.restSize() / 4;
    for (std::size_t i = 0; n > 0 && i < count; ++i) std::memcpy(&ranges[i], rest + 4 * (i % n), 4);
    view.ranges = ranges.data();
    view.count = count;
    scanner.offer(view, 1'000'000'000LL + s * 25'000'000LL + in.take<std::uint16_t>());
    if (scanner.read(2'000'000'000LL, *out)) {
      staa::fuzz::require(scanProblem(*out).empty(), "a scan read out fails scanProblem", scanProblem(*out));
      staa::fuzz::require(out->count <= LaserScan::kMaxBeams, "more beams than a scan holds");
      staa::fuzz::require(out->stamp > last, "a stamp not after the previous scan's");
      last = out->stamp;
    }
  }
  staa::fuzz::require(scanner.accepted() + scanner.droppedTotal() == static_cast<std::uint64_t>(scans),
                      "a scan neither accepted nor dropped");
  return 0;
}
