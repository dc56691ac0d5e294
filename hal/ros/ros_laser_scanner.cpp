#include "hal/ros/ros_laser_scanner.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace staa::hal {
namespace {

constexpr double kMaxScanAgeLimitS = 10.0;

}  // namespace

const char* toString(RosScanDrop reason) {
  switch (reason) {
    case RosScanDrop::kBeams: return "beams";
    case RosScanDrop::kGeometry: return "geometry";
    case RosScanDrop::kSweep: return "sweep";
    case RosScanDrop::kStamp: return "stamp";
    case RosScanDrop::kCount: break;
  }
  return "unknown";
}

RosLaserScanner::RosLaserScanner(const RosLaserScannerConfig& config)
    : config_(config), scans_(std::make_unique<rt::TripleBuffer<LaserScan>>()) {
  if (!(config.max_age_s >= 0.0 && config.max_age_s <= kMaxScanAgeLimitS)) {
    throw std::invalid_argument("ros laser scanner: max_age_s must be in [0, 10] s, got " +
                                std::to_string(config.max_age_s));
  }
}

void RosLaserScanner::drop(RosScanDrop reason) {
  dropped_[static_cast<std::size_t>(reason)].fetch_add(1, std::memory_order_relaxed);
}

bool RosLaserScanner::check(const LaserScanView& scan, const LaserScan& header) {
  if (scan.count < 1 || scan.count > LaserScan::kMaxBeams || scan.ranges == nullptr) {
    drop(RosScanDrop::kBeams);
    return false;
  }
  // scanProblem allocates its message: fine here, in the transport's thread.
  if (!scanProblem(header).empty()) {
    drop(RosScanDrop::kGeometry);
    return false;
  }
  // The increment is finite and not 0 (checked above): the sweep's beams are a number, off a
  // whole beam by the float32 angles' rounding at most (1,081 beams: about 1e-4).
  const double beams = (static_cast<double>(scan.angle_max) - header.angle_min) / header.angle_increment + 1.0;
  if (!(std::abs(beams - static_cast<double>(scan.count)) < 1.5)) {
    drop(RosScanDrop::kSweep);
    return false;
  }
  if (scan.stamp_ns <= 0 || scan.stamp_ns <= last_stamp_ns_) {
    drop(RosScanDrop::kStamp);
    return false;
  }
  return true;
}

rt::Nanos RosLaserScanner::monotonicStamp(const LaserScanView& scan, std::int64_t arrival_mono_ns) {
  rt::Nanos stamp = arrival_mono_ns;
  const auto max_age = static_cast<std::int64_t>(config_.max_age_s * 1e9);
  if (scan.received_ns >= 0) {  // stamp_ns > 0 (checked): no overflow
    const std::int64_t age = scan.received_ns - scan.stamp_ns;
    if (age >= 0 && age <= max_age) stamp = arrival_mono_ns - age;
  }
  if (last_mono_ >= 0 && stamp <= last_mono_) stamp = last_mono_ + 1;
  return stamp;
}

void RosLaserScanner::offer(const LaserScanView& scan, std::int64_t arrival_mono_ns) {
  // The header straight into the write slot, which is not published until it is complete.
  LaserScan& s = scans_->writeBuffer();
  s.angle_min = scan.angle_min;
  s.angle_increment = scan.angle_increment;
  s.range_min = scan.range_min;
  s.range_max = scan.range_max;
  s.count = scan.count;
  if (!check(scan, s)) return;
  std::copy(scan.ranges, scan.ranges + scan.count, s.ranges.begin());
  // Beyond count: no return, should a reader look past it.
  std::fill(s.ranges.begin() + static_cast<std::ptrdiff_t>(scan.count), s.ranges.end(), 0.0f);
  s.stamp = monotonicStamp(scan, arrival_mono_ns);
  s.sequence = accepted() + 1;
  last_stamp_ns_ = scan.stamp_ns;
  last_mono_ = s.stamp;
  scans_->publish();
  accepted_.fetch_add(1, std::memory_order_relaxed);
}

bool RosLaserScanner::read(rt::Nanos /*now*/, LaserScan& out) {
  if (!scans_->update()) return false;
  out = scans_->readBuffer();
  return true;
}

std::uint64_t RosLaserScanner::dropped(RosScanDrop reason) const {
  if (reason == RosScanDrop::kCount) return 0;
  return dropped_[static_cast<std::size_t>(reason)].load(std::memory_order_relaxed);
}

std::uint64_t RosLaserScanner::droppedTotal() const {
  std::uint64_t total = 0;
  for (const auto& d : dropped_) total += d.load(std::memory_order_relaxed);
  return total;
}

}  // namespace staa::hal
