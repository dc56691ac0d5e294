#pragma once
// camera.backend ros over ROS 1 (roscpp): the depth image and camera_info subscriptions and
// the camera's pose from tf, handed to a DepthImageSink (hal::RosDepthCamera). The only code
// of the camera path that includes ROS headers (in ros1_camera.cpp, compiled as C++17: ROS 1's
// message headers do not compile as C++20); this header names ROS types only by declaration,
// so C++17 and C++20 code alike can include it.
//
// For each image: tf base_frame <- image.header.frame_id (the optical frame) at the image's
// stamp, tf2 interpolating between the head's joint states, waiting at most tf_timeout_s for
// the transform to arrive (canTransform; only when the buffer is filled by a thread of its
// own, as tf2_ros::TransformListener's spin thread does, else tf2 refuses to wait); no transform: the image is still offered, with an
// invalid pose, so that the sink counts it (no_pose). Callbacks run in roscpp's spinner
// threads (normal priority); the callbacks of one subscription never overlap, so offer() is
// called from one thread at a time.

#include "hal/ros/depth_image.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace ros {
class NodeHandle;
}
namespace tf2_ros {
class Buffer;
}

namespace staa::staad {

// The HSR's ROS 1 names (its head Xtion, registered to the RGB camera).
struct Ros1CameraTopics {
  std::string image_topic = "/hsrb/head_rgbd_sensor/depth_registered/image_rect_raw";
  std::string info_topic = "/hsrb/head_rgbd_sensor/depth_registered/camera_info";
  std::string base_frame = "base_footprint";
  int queue_size = 1;  // the newest image only: an older one is no use to perception
  double tf_timeout_s = 0.05;
};

class Ros1CameraInput {
 public:
  // Subscribes both topics on `node`; `tf` and `sink` must outlive this object. Throws
  // std::invalid_argument for an empty topic or frame, queue_size < 1 or tf_timeout_s
  // outside [0, 1] s.
  Ros1CameraInput(::ros::NodeHandle& node, ::tf2_ros::Buffer& tf, const Ros1CameraTopics& topics,
                  hal::DepthImageSink& sink);
  ~Ros1CameraInput();
  Ros1CameraInput(const Ros1CameraInput&) = delete;
  Ros1CameraInput& operator=(const Ros1CameraInput&) = delete;

  // Messages received so far, and images whose tf lookup failed (any thread).
  std::uint64_t images() const;
  std::uint64_t infos() const;
  std::uint64_t tfFailures() const;
  // The last tf error ("" when none), for a log line (any thread).
  std::string lastTfError() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace staa::staad
