#pragma once
// obstacles: depth: the perception thread's obstacle sensor over a depth camera
// (docs/ARCHITECTURE.md sections 3-4). Each read(now):
//   1. takes the robot's latest odometry (OdometrySlot, below);
//   2. takes a new depth frame: camera.backend sim renders one (DepthRenderer) from the
//      simulated world's latest movers and that pose; openni2 takes the Xtion's newest frame;
//   3. with a scanner (scanner.backend sim or ros), takes its scan: sim renders one
//      (ScanRenderer) from the same movers and pose as the frame; ros takes the newest scan
//      the transport delivered (RosLaserScanner). A scan whose stamp is more than
//      scanner.max_age_s from the frame's is not used (counted: scansTooOld);
//   4. runs DepthObstacleDetector on the frame (and the scan's returns, in the same grid)
//      with that pose, into the ObstacleFrame.
// The pose used for a frame is the latest odometry, not an interpolation at the frame's
// stamp: at most one base period (10 ms) apart, 2 mm at the HSR's 0.22 m/s. The sim backend
// renders and detects with the very same pose, so its frames are exact in that respect.
//
// Where the pose comes from: Channels::base is a triple buffer with one reader, the control
// thread (a second reader's update() would swap the slot under it). The base is therefore
// wrapped in an OdometryTap, which publishes every odometry the base thread reads into an
// OdometrySlot of its own: one writer (base thread), one reader (perception thread).
//
// A scan is perceived only with a depth frame (the camera's rate decides when perception
// runs), from the frame's robot pose; the scanner's own mount is the config's.
//
// Everything is allocated at construction (the scanner when it is added, before the thread
// starts): the 600 KB frame, the 8 KB scan, the renderers' rays and bins, the detector's
// grid. read() allocates nothing, takes no lock and never blocks. (One caveat
// of hal::DepthRenderer: its bin list grows on a frame that needs more than it was sized for,
// 8 entries per edge and 16 per bin; the tests count no allocation over 1,000 frames.)

#include "app/staad/config.hpp"
#include "app/staad/status.hpp"
#include "hal/base.hpp"
#include "hal/depth_camera.hpp"
#include "hal/laser_scanner.hpp"
#include "hal/obstacles.hpp"
#include "world/sim_depth_camera.hpp"
#include "world/sim_laser_scan.hpp"
#include "map/polygon_map.hpp"
#include "perception/depth_obstacles.hpp"
#include "rt/triple_buffer.hpp"

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <stdexcept>

namespace staa::hal {
class SimHal;
}

namespace staa::staad {

// The robot's latest odometry, from the base thread to the perception thread.
class OdometrySlot {
 public:
  void publish(const hal::Odometry& odometry) {
    buffer_.writeBuffer() = odometry;
    buffer_.publish();
  }
  // The newest odometry published, else the one before (stamp < 0: none yet). One reader.
  const hal::Odometry& latest() {
    buffer_.update();
    return buffer_.readBuffer();
  }
  std::uint64_t published() const { return buffer_.published(); }

 private:
  rt::TripleBuffer<hal::Odometry> buffer_;
};

// A Base that passes every call to `base` and publishes its odometry into `slot` after each
// read() and each accepted setPose(). Used by the base thread only, like any Base.
class OdometryTap final : public hal::Base {
 public:
  OdometryTap(hal::Base& base, OdometrySlot& slot) : base_(base), slot_(slot) {}

  void read(rt::Nanos now) override {
    base_.read(now);
    slot_.publish(base_.odometry());
  }
  void write(rt::Nanos now, const hal::VelocityCommand& command) override { base_.write(now, command); }
  hal::Odometry odometry() const override { return base_.odometry(); }
  hal::BaseStatus status() const override { return base_.status(); }
  bool setPose(const Pose2& pose) override {
    const bool accepted = base_.setPose(pose);
    if (accepted) slot_.publish(base_.odometry());
    return accepted;
  }

 private:
  hal::Base& base_;
  OdometrySlot& slot_;
};

// The depth camera cannot be opened (camera.backend openni2 without a device, or a staad
// built without OpenNI2): staad exits 3. what() says why.
class DepthCameraError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The sim backend's renderer settings from the camera config: the mount and intrinsics, the
// noise, and only the pixels perception samples rendered (pixel_stride = perception's).
hal::SimDepthConfig simDepthConfig(const CameraConfig& camera, std::uint64_t seed);
// The sim scanner's settings from the scanner config: its mount, the sweep centred on the
// mount's yaw (a full turn one increment short, so that no beam repeats), the beams, ranges
// and noise.
hal::SimScanConfig simScanConfig(const ScannerConfig& scanner, std::uint64_t seed);

class DepthSensor final : public hal::ObstacleSensor {
 public:
  // camera.backend sim: frames rendered from the latest movers that `movers` (the SimHal's
  // obstacle sensor, polled on this thread) reports, and the pose in `pose`. Throws
  // std::invalid_argument for a bad camera or perception value (naming the field).
  DepthSensor(const PolygonMap& map, const CameraConfig& camera, std::uint64_t seed, hal::ObstacleSensor& movers,
              OdometrySlot& pose);
  // Any other camera (openni2; a scripted one in tests).
  DepthSensor(const PolygonMap& map, const CameraConfig& camera, std::unique_ptr<hal::DepthCamera> device,
              OdometrySlot& pose);
  ~DepthSensor() override;
  DepthSensor(const DepthSensor&) = delete;
  DepthSensor& operator=(const DepthSensor&) = delete;

  // The base's laser scanner beside the camera, added before the perception thread starts
  // (these allocate). Sim: a scan rendered with each simulated frame, from the same movers
  // and pose (only over the sim camera: throws std::logic_error otherwise; std::invalid_argument
  // naming the field for a bad value). Any other (ros; a scripted one in tests): its newest
  // scan with each frame.
  void addSimScanner(const PolygonMap& map, const ScannerConfig& scanner, std::uint64_t seed);
  void addScanner(const ScannerConfig& scanner, std::unique_ptr<hal::LaserScanner> device);

  // A new obstacle frame when the camera has a new depth frame and a pose is known.
  bool read(rt::Nanos now, hal::ObstacleFrame& out) override;

  std::uint64_t frames() const { return frames_; }
  // Frames not taken because no odometry had arrived yet.
  std::uint64_t framesWithoutPose() const { return without_pose_; }
  const DepthObstaclesStats& lastStats() const { return stats_; }

  // The scanner's counts (any thread: the service thread reads them for the status).
  bool hasScanner() const { return scanner_config_.backend != ScannerBackend::kNone; }
  std::uint64_t scansUsed() const { return scans_used_.load(std::memory_order_relaxed); }
  std::uint64_t scansTooOld() const { return scans_too_old_.load(std::memory_order_relaxed); }
  std::uint64_t framesWithoutScan() const { return without_scan_.load(std::memory_order_relaxed); }
  std::uint64_t lastScanPoints() const { return last_scan_points_.load(std::memory_order_relaxed); }
  ScannerStatus scannerStatus() const;

 private:
  bool renderSimFrame(rt::Nanos now, const Pose2& robot);
  // The scan to perceive with the frame just taken (scan null: none, or none recent enough).
  ScanInput scanFor(rt::Nanos now, const Pose2& robot);

  OdometrySlot& pose_;
  DepthObstacleDetector detector_;
  std::unique_ptr<hal::DepthFrame> frame_;
  // openni2 (or a test's camera)
  std::unique_ptr<hal::DepthCamera> device_;
  // sim
  hal::ObstacleSensor* movers_ = nullptr;
  std::unique_ptr<hal::DepthRenderer> renderer_;
  hal::ObstacleFrame mover_frame_;
  std::array<hal::PrismView, hal::ObstacleFrame::kMaxObstacles> prisms_{};
  std::size_t prism_count_ = 0;  // of prisms_, this frame's movers
  std::uint64_t sequence_ = 0;
  // the scanner (backend none: neither)
  ScannerConfig scanner_config_;
  std::unique_ptr<hal::LaserScanner> scanner_;      // ros (or a test's)
  std::unique_ptr<hal::ScanRenderer> scan_renderer_;  // sim
  std::unique_ptr<hal::LaserScan> scan_;            // the newest scan (stamp < 0: none yet)
  rt::Nanos scan_max_age_ = 0;

  std::uint64_t frames_ = 0;
  std::uint64_t without_pose_ = 0;
  DepthObstaclesStats stats_;
  std::atomic<std::uint64_t> scans_used_{0};
  std::atomic<std::uint64_t> scans_too_old_{0};
  std::atomic<std::uint64_t> without_scan_{0};
  std::atomic<std::uint64_t> last_scan_points_{0};
};

// The sensor of `config.camera`: sim over `sim` (the daemon's SimHal; required for sim),
// openni2 opened here (OpenNI2Camera: waits up to 2 s for a first frame). Throws
// DepthCameraError when the camera cannot be opened or OpenNI2 is not built in, and
// std::invalid_argument for a bad value.
// `ros_camera`: camera.backend ros's camera (the ROS link made it and feeds it), taken over;
// `ros_scanner` likewise for scanner.backend ros.
std::unique_ptr<DepthSensor> makeDepthSensor(const DaemonConfig& config, hal::SimHal* sim, OdometrySlot& pose,
                                             std::unique_ptr<hal::DepthCamera> ros_camera = nullptr,
                                             std::unique_ptr<hal::LaserScanner> ros_scanner = nullptr);

}  // namespace staa::staad
