// C++17: includes ROS 1 headers (and of the project only hal/ros/laser_scan_port.hpp).
#include "app/staad/ros/ros1_scanner.hpp"

#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>

#include <atomic>
#include <chrono>
#include <stdexcept>

namespace staa::staad {

class Ros1ScannerInput::Impl {
 public:
  Impl(ros::NodeHandle& node, const Ros1ScannerTopics& topics, hal::LaserScanSink& sink) : sink_(sink) {
    if (topics.topic.empty()) throw std::invalid_argument("ros scanner: topic must not be empty");
    if (topics.queue_size < 1) {
      throw std::invalid_argument("ros scanner: queue_size must be >= 1, got " + std::to_string(topics.queue_size));
    }
    sub_ = node.subscribe(topics.topic, static_cast<std::uint32_t>(topics.queue_size), &Impl::onScan, this,
                          ros::TransportHints().tcpNoDelay());
  }

  void onScan(const sensor_msgs::LaserScanConstPtr& msg) {
    // CLOCK_MONOTONIC (libstdc++'s steady_clock on Linux), the daemon's clock.
    const std::int64_t arrival_mono =
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
            .count();
    scans_.fetch_add(1, std::memory_order_relaxed);
    hal::LaserScanView scan;
    scan.stamp_ns = static_cast<std::int64_t>(msg->header.stamp.toNSec());
    scan.received_ns = static_cast<std::int64_t>(ros::Time::now().toNSec());
    scan.angle_min = msg->angle_min;
    scan.angle_max = msg->angle_max;
    scan.angle_increment = msg->angle_increment;
    scan.range_min = msg->range_min;
    scan.range_max = msg->range_max;
    scan.ranges = msg->ranges.data();
    scan.count = msg->ranges.size();
    sink_.offer(scan, arrival_mono);
  }

  hal::LaserScanSink& sink_;
  ros::Subscriber sub_;
  std::atomic<std::uint64_t> scans_{0};
};

Ros1ScannerInput::Ros1ScannerInput(ros::NodeHandle& node, const Ros1ScannerTopics& topics, hal::LaserScanSink& sink)
    : impl_(std::make_unique<Impl>(node, topics, sink)) {}

// Shutting the subscriber down waits for its running callback (roscpp), so the sink is not
// called after this returns.
Ros1ScannerInput::~Ros1ScannerInput() { impl_->sub_.shutdown(); }

std::uint64_t Ros1ScannerInput::scans() const { return impl_->scans_.load(std::memory_order_relaxed); }

}  // namespace staa::staad
