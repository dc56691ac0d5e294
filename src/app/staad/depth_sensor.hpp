#pragma once
// obstacles: depth: the perception thread's obstacle sensor over a depth camera
// (docs/ARCHITECTURE.md sections 3-4). Each read(now):
//   1. takes the robot's latest odometry (OdometrySlot, below);
//   2. takes a new depth frame: camera.backend sim renders one (DepthRenderer) from the
//      simulated world's latest movers and that pose; openni2 takes the Xtion's newest frame;
//   3. runs DepthObstacleDetector on the frame with that pose, into the ObstacleFrame.
// The pose used for a frame is the latest odometry, not an interpolation at the frame's
// stamp: at most one base period (10 ms) apart, 2 mm at the HSR's 0.22 m/s. The sim backend
// renders and detects with the very same pose, so its frames are exact in that respect.
//
// Where the pose comes from: Channels::base is a triple buffer with one reader, the control
// thread (a second reader's update() would swap the slot under it). The base is therefore
// wrapped in an OdometryTap, which publishes every odometry the base thread reads into an
// OdometrySlot of its own: one writer (base thread), one reader (perception thread).
//
// Everything is allocated at construction: the 600 KB frame, the renderer's rays and bins,
// the detector's grid. read() allocates nothing, takes no lock and never blocks. (One caveat
// of hal::DepthRenderer: its bin list grows on a frame that needs more than it was sized for,
// 8 entries per edge and 16 per bin; the tests count no allocation over 1,000 frames.)

#include "app/staad/config.hpp"
#include "hal/base.hpp"
#include "hal/depth_camera.hpp"
#include "hal/obstacles.hpp"
#include "world/sim_depth_camera.hpp"
#include "map/polygon_map.hpp"
#include "perception/depth_obstacles.hpp"
#include "rt/triple_buffer.hpp"

#include <array>
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

  // A new obstacle frame when the camera has a new depth frame and a pose is known.
  bool read(rt::Nanos now, hal::ObstacleFrame& out) override;

  std::uint64_t frames() const { return frames_; }
  // Frames not taken because no odometry had arrived yet.
  std::uint64_t framesWithoutPose() const { return without_pose_; }
  const DepthObstaclesStats& lastStats() const { return stats_; }

 private:
  bool renderSimFrame(rt::Nanos now, const Pose2& robot);

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
  std::uint64_t sequence_ = 0;

  std::uint64_t frames_ = 0;
  std::uint64_t without_pose_ = 0;
  DepthObstaclesStats stats_;
};

// The sensor of `config.camera`: sim over `sim` (the daemon's SimHal; required for sim),
// openni2 opened here (OpenNI2Camera: waits up to 2 s for a first frame). Throws
// DepthCameraError when the camera cannot be opened or OpenNI2 is not built in, and
// std::invalid_argument for a bad value.
// `ros_camera`: camera.backend ros's camera (the ROS link made it and feeds it), taken over.
std::unique_ptr<DepthSensor> makeDepthSensor(const DaemonConfig& config, hal::SimHal* sim, OdometrySlot& pose,
                                             std::unique_ptr<hal::DepthCamera> ros_camera = nullptr);

}  // namespace staa::staad
