#pragma once
// A depth camera (docs/ARCHITECTURE.md section 4): 640 x 480 depth frames of 16-bit millimetres
// at 30 Hz, its intrinsics and its pose on the robot. Backends: hal/openni2 (the HSR's head
// Xtion), hal/ros (frames from a ROS transport, the pose per frame from tf), the simulated
// camera (src/world/sim_depth_camera.hpp); perception (src/perception)
// turns frames into an ObstacleFrame (hal/obstacles.hpp).

#include "rt/clock.hpp"

#include <array>
#include <cstdint>

namespace staa::hal {

struct CameraIntrinsics {
  double fx = 570.3, fy = 570.3;  // pixels (Xtion defaults)
  double cx = 319.5, cy = 239.5;
};

// The camera's pose on the robot: position (m) and roll/pitch/yaw (rad) in the base frame.
struct CameraMount {
  double x = 0.0, y = 0.0, z = 1.0;
  double roll = 0.0, pitch = 0.0, yaw = 0.0;
};

struct DepthFrame {
  static constexpr int kWidth = 640;
  static constexpr int kHeight = 480;
  rt::Nanos stamp = -1;
  std::uint64_t sequence = 0;
  // The camera's pose when the frame was taken, for a camera that moves on the robot (the
  // HSR's head pans and tilts: backend ros, from tf at the frame's stamp). has_mount false:
  // the camera's fixed mount() (sim, openni2). Perception uses whichever the frame says.
  bool has_mount = false;
  CameraMount mount;
  std::array<std::uint16_t, static_cast<std::size_t>(kWidth) * kHeight> depth_mm{};  // 0: no reading
};

class DepthCamera {
 public:
  virtual ~DepthCamera() = default;
  // Fills `out` with a new frame when one arrived since the last call; true then.
  virtual bool read(rt::Nanos now, DepthFrame& out) = 0;
  virtual CameraIntrinsics intrinsics() const = 0;
  virtual CameraMount mount() const = 0;
};

}  // namespace staa::hal
