#pragma once
// scanner.backend ros over ROS 1 (roscpp): the base scanner's sensor_msgs/LaserScan
// subscription, each message handed to a LaserScanSink (hal::RosLaserScanner) as a plain view
// onto it. As ros1_camera.hpp: the only code of the scanner's path that includes ROS headers
// (in ros1_scanner.cpp, C++17), this header names ROS types only by declaration.
//
// The scan's frame (header.frame_id) is not looked up in tf: the scanner is fixed to the base,
// where the config's scanner.mount puts it. Callbacks run in roscpp's spinner thread (normal
// priority); the callbacks of one subscription never overlap, so offer() is called from one
// thread at a time.

#include "hal/ros/laser_scan_port.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace ros {
class NodeHandle;
}

namespace staa::staad {

// The HSR's ROS 1 name (its base scanner).
struct Ros1ScannerTopics {
  std::string topic = "/hsrb/base_scan";
  int queue_size = 1;  // the newest scan only: an older one is no use to perception
};

class Ros1ScannerInput {
 public:
  // Subscribes on `node`; `sink` must outlive this object. Throws std::invalid_argument for an
  // empty topic or queue_size < 1.
  Ros1ScannerInput(::ros::NodeHandle& node, const Ros1ScannerTopics& topics, hal::LaserScanSink& sink);
  ~Ros1ScannerInput();
  Ros1ScannerInput(const Ros1ScannerInput&) = delete;
  Ros1ScannerInput& operator=(const Ros1ScannerInput&) = delete;

  // Messages received so far (any thread).
  std::uint64_t scans() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace staa::staad
