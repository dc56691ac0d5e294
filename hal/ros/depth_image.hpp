#pragma once
// The port between a ROS transport and staa's depth camera (docs/ARCHITECTURE.md, "Hardware",
// hal/ros): what a transport (ROS 1's roscpp now, ROS 2's rclcpp later) hands over for each
// depth image, without a ROS type. A plain C++17 header on purpose: ROS 1's message headers
// do not compile as C++20, so the transport's translation units are C++17 and include this
// header and no other of the project's.
//
// The transport fills the views from its messages (pointers into them, valid only during
// offer()), looks up the camera's pose at the image's stamp and calls DepthImageSink::offer()
// from one thread at a time. RosDepthCamera (hal/ros/ros_depth_camera.hpp) is the sink.

#include <cstddef>
#include <cstdint>

namespace staa::hal {

// A sensor_msgs/Image, its fields as the message has them.
struct DepthImageView {
  std::int64_t stamp_ns = 0;     // header.stamp (ns on the transport's clock: ROS time)
  std::int64_t received_ns = 0;  // the transport's clock (ROS time) when the message arrived
  const char* encoding = "";     // "16UC1" (mm) or "32FC1" (m, NaN: no reading)
  std::uint32_t width = 0, height = 0;
  std::uint32_t step = 0;        // bytes per row
  bool big_endian = false;       // is_bigendian
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;          // bytes at data
};

// A sensor_msgs/CameraInfo's size and K (the 3 x 3 intrinsic matrix, row-major:
// fx 0 cx / 0 fy cy / 0 0 1).
struct CameraInfoView {
  std::uint32_t width = 0, height = 0;
  double K[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
};

// The camera's pose in the robot's base frame at the image's stamp, in hal::CameraMount's
// convention (hal/camera_model.hpp: the camera BODY frame x forward, y left, z up; base <-
// body is Rz(yaw) * Ry(pitch) * Rx(roll); pitch > 0 looks down), not the optical frame's.
// valid false: the transport had no pose (tf had no transform at that stamp).
struct CameraPoseSample {
  bool valid = false;
  double x = 0.0, y = 0.0, z = 0.0;
  double roll = 0.0, pitch = 0.0, yaw = 0.0;
};

// The pose of a camera whose OPTICAL frame (x right, y down, z forward: a sensor_msgs/Image's
// header.frame_id) sits in the base frame at translation t with rotation q (base <- optical,
// as tf gives base_frame <- frame_id; q = x, y, z, w, normalised here). valid is false for a
// non-finite or zero quaternion.
CameraPoseSample cameraPoseFromOpticalFrame(double tx, double ty, double tz, double qx, double qy, double qz,
                                            double qw);

class DepthImageSink {
 public:
  virtual ~DepthImageSink() = default;
  // One depth image: `info` the latest camera_info received (null: none yet), `pose` the
  // camera at image.stamp_ns, arrival_mono_ns CLOCK_MONOTONIC when the image arrived. Called
  // from one thread at a time (the transport's, normal priority); may take a few ms.
  virtual void offer(const DepthImageView& image, const CameraInfoView* info, const CameraPoseSample& pose,
                     std::int64_t arrival_mono_ns) = 0;
};

}  // namespace staa::hal
