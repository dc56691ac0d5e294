#pragma once
// scanner.backend ros (docs/ARCHITECTURE.md, "Hardware"): the HSR-B's base scanner
// (`/hsrb/base_scan`, sensor_msgs/LaserScan) from a ROS transport as a LaserScanner.
//
// offer() runs in the transport's thread: it checks the scan, converts it into the write slot
// of a preallocated triple buffer and publishes it. read() runs in the real-time perception
// thread: it takes the newest scan, allocating nothing, taking no lock, never waiting. A scan
// that fails a check is dropped, counted under its first failed check (RosScanDrop, in the
// order below), and read() returns nothing new.
//
// The scan's stamp (on CLOCK_MONOTONIC, to compare with the depth frames'): as
// RosDepthCamera's, the arrival time minus the message's age when that age is in
// [0, max_age_s], else the arrival time; stamps handed to read() always increase.

#include "hal/laser_scan.hpp"
#include "hal/laser_scanner.hpp"
#include "hal/ros/laser_scan_port.hpp"
#include "rt/triple_buffer.hpp"

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace staa::hal {

struct RosLaserScannerConfig {
  // Longest believable message age (s): more, or negative, and the clocks disagree.
  double max_age_s = 0.5;
};

// Why a scan was dropped: the checks in the order offer() makes them.
enum class RosScanDrop : std::size_t {
  kBeams,     // no ranges, or more than LaserScan::kMaxBeams
  kGeometry,  // hal::scanProblem: angle_min or angle_increment not finite, increment 0 or
              // over a turn, range_max <= range_min, ...
  kSweep,     // the ranges' count disagrees with (angle_max - angle_min) / angle_increment + 1
              // by more than one beam (drivers differ on whether angle_max is the last beam's)
  kStamp,     // stamp 0 (unset), or not after the previous accepted scan's
  kCount
};
const char* toString(RosScanDrop reason);  // "beams", "geometry", "sweep", "stamp"
inline constexpr std::size_t kRosScanDropReasons = static_cast<std::size_t>(RosScanDrop::kCount);

class RosLaserScanner final : public LaserScanner, public LaserScanSink {
 public:
  // Throws std::invalid_argument for max_age_s outside [0, 10] s.
  explicit RosLaserScanner(const RosLaserScannerConfig& config = {});
  RosLaserScanner(const RosLaserScanner&) = delete;
  RosLaserScanner& operator=(const RosLaserScanner&) = delete;

  // LaserScanSink: the transport's thread, one at a time.
  void offer(const LaserScanView& scan, std::int64_t arrival_mono_ns) override;

  // LaserScanner: the perception thread.
  bool read(rt::Nanos now, LaserScan& out) override;

  // Any thread.
  std::uint64_t accepted() const { return accepted_.load(std::memory_order_relaxed); }
  std::uint64_t dropped(RosScanDrop reason) const;
  std::uint64_t droppedTotal() const;

 private:
  // Whether `scan` (its header already copied into `header`) passes every check; else it is
  // counted under the first it fails.
  bool check(const LaserScanView& scan, const LaserScan& header);
  void drop(RosScanDrop reason);
  rt::Nanos monotonicStamp(const LaserScanView& scan, std::int64_t arrival_mono_ns);

  RosLaserScannerConfig config_;
  std::unique_ptr<rt::TripleBuffer<LaserScan>> scans_;  // 3 x 8 KB, allocated once
  // The transport's thread only.
  std::int64_t last_stamp_ns_ = 0;
  rt::Nanos last_mono_ = -1;
  std::atomic<std::uint64_t> accepted_{0};
  std::array<std::atomic<std::uint64_t>, kRosScanDropReasons> dropped_{};
};

}  // namespace staa::hal
