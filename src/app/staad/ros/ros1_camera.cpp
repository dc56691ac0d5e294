// C++17: includes ROS 1 headers (and of the project only hal/ros/depth_image.hpp).
#include "app/staad/ros/ros1_camera.hpp"

#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2/exceptions.h>
#include <tf2_ros/buffer.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>

namespace staa::staad {

class Ros1CameraInput::Impl {
 public:
  Impl(ros::NodeHandle& node, tf2_ros::Buffer& tf, const Ros1CameraTopics& topics, hal::DepthImageSink& sink)
      : tf_(tf), topics_(topics), sink_(sink) {
    if (topics.image_topic.empty() || topics.info_topic.empty() || topics.base_frame.empty()) {
      throw std::invalid_argument("ros camera: image_topic, info_topic and base_frame must not be empty");
    }
    if (topics.queue_size < 1) {
      throw std::invalid_argument("ros camera: queue_size must be >= 1, got " + std::to_string(topics.queue_size));
    }
    if (!(topics.tf_timeout_s >= 0.0 && topics.tf_timeout_s <= 1.0)) {
      throw std::invalid_argument("ros camera: tf_timeout_s must be in [0, 1] s, got " +
                                  std::to_string(topics.tf_timeout_s));
    }
    const auto queue = static_cast<std::uint32_t>(topics.queue_size);
    info_sub_ = node.subscribe(topics.info_topic, queue, &Impl::onInfo, this);
    image_sub_ = node.subscribe(topics.image_topic, queue, &Impl::onImage, this);
  }

  void onInfo(const sensor_msgs::CameraInfoConstPtr& msg) {
    hal::CameraInfoView info;
    info.width = msg->width;
    info.height = msg->height;
    for (int i = 0; i < 9; ++i) info.K[i] = msg->K[static_cast<std::size_t>(i)];
    {
      const std::lock_guard<std::mutex> lock(info_mutex_);
      info_ = info;
      has_info_ = true;
    }
    infos_.fetch_add(1, std::memory_order_relaxed);
  }

  void onImage(const sensor_msgs::ImageConstPtr& msg) {
    // CLOCK_MONOTONIC (libstdc++'s steady_clock on Linux), the daemon's clock.
    const std::int64_t arrival_mono =
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
            .count();
    images_.fetch_add(1, std::memory_order_relaxed);
    hal::DepthImageView image;
    image.stamp_ns = static_cast<std::int64_t>(msg->header.stamp.toNSec());
    image.received_ns = static_cast<std::int64_t>(ros::Time::now().toNSec());
    image.encoding = msg->encoding.c_str();
    image.width = msg->width;
    image.height = msg->height;
    image.step = msg->step;
    image.big_endian = msg->is_bigendian != 0;
    image.data = msg->data.data();
    image.size = msg->data.size();

    const hal::CameraPoseSample pose = lookUpPose(msg->header.frame_id, msg->header.stamp);
    hal::CameraInfoView info;
    bool has_info = false;
    {
      const std::lock_guard<std::mutex> lock(info_mutex_);
      info = info_;
      has_info = has_info_;
    }
    sink_.offer(image, has_info ? &info : nullptr, pose, arrival_mono);
  }

  hal::CameraPoseSample lookUpPose(const std::string& frame, const ros::Time& stamp) {
    hal::CameraPoseSample pose;
    std::string error;
    if (frame.empty()) {
      return fail("the image has no header.frame_id");
    }
    // tf2 waits only for a buffer that a thread of its own fills (a TransformListener's);
    // without one (its timeout overload refuses), look up what is there.
    const bool can = tf_.isUsingDedicatedThread()
                         ? tf_.canTransform(topics_.base_frame, frame, stamp, ros::Duration(topics_.tf_timeout_s), &error)
                         : tf_.canTransform(topics_.base_frame, frame, stamp, &error);
    if (!can) {
      return fail(error.empty() ? "no transform " + topics_.base_frame + " <- " + frame : error);
    }
    try {
      const geometry_msgs::TransformStamped t = tf_.lookupTransform(topics_.base_frame, frame, stamp);
      const auto& p = t.transform.translation;
      const auto& q = t.transform.rotation;
      pose = hal::cameraPoseFromOpticalFrame(p.x, p.y, p.z, q.x, q.y, q.z, q.w);
    } catch (const tf2::TransformException& e) {
      return fail(e.what());
    }
    return pose;
  }

  hal::CameraPoseSample fail(const std::string& error) {
    tf_failures_.fetch_add(1, std::memory_order_relaxed);
    const std::lock_guard<std::mutex> lock(error_mutex_);
    last_tf_error_ = error;
    return hal::CameraPoseSample{};
  }

  tf2_ros::Buffer& tf_;
  Ros1CameraTopics topics_;
  hal::DepthImageSink& sink_;
  ros::Subscriber info_sub_, image_sub_;
  std::mutex info_mutex_;  // the info and the image callbacks may run in different threads
  hal::CameraInfoView info_;
  bool has_info_ = false;
  std::atomic<std::uint64_t> images_{0}, infos_{0}, tf_failures_{0};
  mutable std::mutex error_mutex_;
  std::string last_tf_error_;
};

Ros1CameraInput::Ros1CameraInput(ros::NodeHandle& node, tf2_ros::Buffer& tf, const Ros1CameraTopics& topics,
                                 hal::DepthImageSink& sink)
    : impl_(std::make_unique<Impl>(node, tf, topics, sink)) {}

// Shutting the subscribers down waits for their running callbacks (roscpp), so the sink is
// not called after this returns.
Ros1CameraInput::~Ros1CameraInput() {
  impl_->image_sub_.shutdown();
  impl_->info_sub_.shutdown();
}

std::uint64_t Ros1CameraInput::images() const { return impl_->images_.load(std::memory_order_relaxed); }
std::uint64_t Ros1CameraInput::infos() const { return impl_->infos_.load(std::memory_order_relaxed); }
std::uint64_t Ros1CameraInput::tfFailures() const { return impl_->tf_failures_.load(std::memory_order_relaxed); }
std::string Ros1CameraInput::lastTfError() const {
  const std::lock_guard<std::mutex> lock(impl_->error_mutex_);
  return impl_->last_tf_error_;
}

}  // namespace staa::staad
