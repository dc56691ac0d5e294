#pragma once
// What a ROS transport (ROS 1 today, ROS 2 later) hands the base backend and takes from it:
// plain values, no ROS types and nothing newer than C++17 (ROS 1's message headers do not
// compile as C++20, so the transport's translation units are C++17 and include only this).
// Times: *_stamp_ns is the message's own header stamp (ROS time); *_arrival_ns and
// *_age_ns are measured by the transport when the message arrived: arrival on the
// monotonic clock, age = ROS now - header stamp.

#include <cstdint>

namespace staa::hal {

// nav_msgs/Odometry, the pose in the odometry frame, the twist in the base frame.
struct OdometrySample {
  std::int64_t stamp_ns = 0;
  std::int64_t arrival_ns = 0;
  std::int64_t age_ns = 0;
  double x = 0.0, y = 0.0, yaw = 0.0;
  double v = 0.0, w = 0.0;
};

// A localization fix: the base's pose in the map frame at stamp_ns (PoseStamped,
// PoseWithCovarianceStamped, or tf map -> base).
struct PoseSample {
  std::int64_t stamp_ns = 0;
  std::int64_t arrival_ns = 0;
  double x = 0.0, y = 0.0, yaw = 0.0;
};

// The velocity command to publish (geometry_msgs/Twist: linear.x = v, angular.z = w).
struct TwistSample {
  double v = 0.0, w = 0.0;
  bool brake = false;
  std::int64_t command_stamp_ns = -1;   // the control command it carries (monotonic)
  std::int64_t odometry_stamp_ns = -1;  // the odometry that command was planned on (monotonic)
};

// The transport's side of the base: called from the transport's own (normal-priority)
// callback thread, one caller at a time.
class BaseSink {
 public:
  virtual ~BaseSink() = default;
  virtual void offerOdometry(const OdometrySample& sample) = 0;
  virtual void offerPose(const PoseSample& sample) = 0;
};

}  // namespace staa::hal
