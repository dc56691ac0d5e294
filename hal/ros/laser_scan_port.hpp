#pragma once
// The port between a ROS transport and staa's laser scanner (docs/ARCHITECTURE.md, "Hardware",
// hal/ros), as depth_image.hpp is the camera's: what a transport hands over for each
// sensor_msgs/LaserScan, without a ROS type. A plain C++17 header on purpose: ROS 1's message
// headers do not compile as C++20, so the transport's translation units are C++17 and include
// this header and no other of the project's but depth_image.hpp.
//
// The transport fills the view from its message (pointers into it, valid only during offer())
// and calls LaserScanSink::offer() from one thread at a time. The scan's frame is not looked
// up: the scanner sits still on the base, where the config's scanner.mount says.
// RosLaserScanner (hal/ros/ros_laser_scanner.hpp) is the sink.

#include <cstddef>
#include <cstdint>

namespace staa::hal {

// A sensor_msgs/LaserScan, its fields as the message has them (float32 there).
struct LaserScanView {
  std::int64_t stamp_ns = 0;     // header.stamp (ns on the transport's clock: ROS time)
  std::int64_t received_ns = 0;  // the transport's clock (ROS time) when the message arrived
  float angle_min = 0.0f, angle_max = 0.0f, angle_increment = 0.0f;  // rad
  float range_min = 0.0f, range_max = 0.0f;                          // m
  const float* ranges = nullptr;  // m; NaN, inf or outside [range_min, range_max]: no return
  std::size_t count = 0;          // ranges at `ranges`
};

class LaserScanSink {
 public:
  virtual ~LaserScanSink() = default;
  // One scan; arrival_mono_ns CLOCK_MONOTONIC when it arrived. Called from one thread at a
  // time (the transport's, normal priority).
  virtual void offer(const LaserScanView& scan, std::int64_t arrival_mono_ns) = 0;
};

}  // namespace staa::hal
