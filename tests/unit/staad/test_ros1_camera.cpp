// camera.backend ros's ROS 1 transport against a real ROS master (rosmaster --core on a free
// port of its own): images and camera_info published on their topics reach the sink with the
// latest camera_info and the camera's pose from tf, interpolated at the image's stamp; an
// image whose transform is missing is still offered, without a pose. scanner.backend ros's
// likewise: a sensor_msgs/LaserScan reaches its sink as a plain view, every field as sent.
// C++17 (ROS 1 headers).
#include "app/staad/ros/ros1_camera.hpp"
#include "app/staad/ros/ros1_scanner.hpp"

#include "child_process.hpp"
#include "temp_dir.hpp"

#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/buffer.h>

#include <gtest/gtest.h>

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace staa::staad {
namespace {

using namespace std::chrono_literals;

// A TCP port nobody listens on now (the kernel's choice).
int freePort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t n = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
  ::close(fd);
  return ntohs(a.sin_port);
}

bool waitFor(const std::function<bool()>& done, std::chrono::milliseconds timeout = 5s) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(2ms);
  }
  return true;
}

// What the transport offered, copied in the spinner's thread.
struct Offered {
  std::int64_t stamp_ns = 0, received_ns = 0, arrival_mono_ns = 0;
  std::string encoding;
  std::uint32_t width = 0, height = 0, step = 0;
  std::vector<std::uint8_t> data;
  bool has_info = false;
  hal::CameraInfoView info;
  hal::CameraPoseSample pose;
};

class RecordingSink final : public hal::DepthImageSink {
 public:
  void offer(const hal::DepthImageView& image, const hal::CameraInfoView* info, const hal::CameraPoseSample& pose,
             std::int64_t arrival_mono_ns) override {
    Offered o;
    o.stamp_ns = image.stamp_ns;
    o.received_ns = image.received_ns;
    o.arrival_mono_ns = arrival_mono_ns;
    o.encoding = image.encoding;
    o.width = image.width;
    o.height = image.height;
    o.step = image.step;
    o.data.assign(image.data, image.data + image.size);
    o.has_info = info != nullptr;
    if (info != nullptr) o.info = *info;
    o.pose = pose;
    const std::lock_guard<std::mutex> lock(mutex_);
    offered_.push_back(std::move(o));
  }
  std::size_t count() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return offered_.size();
  }
  Offered at(std::size_t i) {
    const std::lock_guard<std::mutex> lock(mutex_);
    return offered_.at(i);
  }

 private:
  std::mutex mutex_;
  std::vector<Offered> offered_;
};

geometry_msgs::TransformStamped transform(const std::string& parent, const std::string& child, const ros::Time& t,
                                          double x, double y, double z, double qx, double qy, double qz, double qw) {
  geometry_msgs::TransformStamped m;
  m.header.frame_id = parent;
  m.header.stamp = t;
  m.child_frame_id = child;
  m.transform.translation.x = x;
  m.transform.translation.y = y;
  m.transform.translation.z = z;
  m.transform.rotation.x = qx;
  m.transform.rotation.y = qy;
  m.transform.rotation.z = qz;
  m.transform.rotation.w = qw;
  return m;
}

// The head turned by `pan` about z and tilted down by `tilt` about y: Rz(pan) * Ry(tilt).
geometry_msgs::TransformStamped head(const ros::Time& t, double pan, double tilt) {
  const double cp = std::cos(pan / 2), sp = std::sin(pan / 2), ct = std::cos(tilt / 2), st = std::sin(tilt / 2);
  // (0, 0, sp, cp) * (0, st, 0, ct)
  return transform("base_footprint", "head_tilt_link", t, 0.0, 0.0, 1.0, -sp * st, cp * st, sp * ct, cp * ct);
}

class Ros1Camera : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(test::freshDir("test_ros1_camera", "master").string());
    const int port = freePort();
    const std::string uri = "http://127.0.0.1:" + std::to_string(port);
    ::setenv("ROS_MASTER_URI", uri.c_str(), 1);
    ::setenv("ROS_IP", "127.0.0.1", 1);
    ::unsetenv("ROS_HOSTNAME");
    ::setenv("ROS_HOME", dir_->c_str(), 1);
    ::setenv("ROS_LOG_DIR", dir_->c_str(), 1);
    master_ = new test::Child({"/usr/bin/rosmaster", "--core", "-p", std::to_string(port)},
                              test::daemonEnvironment({"ROS_MASTER_URI=" + uri, "ROS_HOME=" + *dir_}),
                              *dir_ + "/master.out", *dir_ + "/master.err");
    int argc = 1;
    char name[] = "test_ros1_camera";
    char* argv[] = {name, nullptr};
    ros::init(argc, argv, "test_ros1_camera", ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
    ASSERT_TRUE(master_->started());
    ASSERT_TRUE(waitFor([] { return ros::master::check(); }, 20s)) << "rosmaster did not come up on " << uri;
  }
  static void TearDownTestSuite() {
    ros::shutdown();
    delete master_;  // kills and reaps it
    master_ = nullptr;
  }

  static std::string* dir_;
  static test::Child* master_;
};
std::string* Ros1Camera::dir_ = nullptr;
test::Child* Ros1Camera::master_ = nullptr;

TEST_F(Ros1Camera, ImagesReachTheSinkWithTheLatestInfoAndThePoseAtTheirStamp) {
  ros::NodeHandle node;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  tf2_ros::Buffer tf;
  tf.setUsingDedicatedThread(true);  // as a TransformListener's spin thread sets it: canTransform waits
  RecordingSink sink;
  Ros1CameraTopics topics;
  topics.image_topic = "/test/depth/image_raw";
  topics.info_topic = "/test/depth/camera_info";
  topics.tf_timeout_s = 0.05;
  Ros1CameraInput input(node, tf, topics, sink);

  // The head panned 0.4 rad at t1 and 0.6 rad at t2, tilted 0.3 rad down; the optical frame
  // 0.1 m above the tilt axis, x right, y down, z forward (rpy -pi/2, 0, -pi/2).
  const ros::Time t1(1000, 0), t2(1000, 200'000'000), mid(1000, 100'000'000);
  ASSERT_TRUE(tf.setTransform(head(t1, 0.4, 0.3), "test"));
  ASSERT_TRUE(tf.setTransform(head(t2, 0.6, 0.3), "test"));
  ASSERT_TRUE(tf.setTransform(
      transform("head_tilt_link", "head_rgbd_sensor_rgb_frame", ros::Time(0), 0.0, 0.0, 0.1, -0.5, 0.5, -0.5, 0.5),
      "test", true));

  ros::Publisher info_pub = node.advertise<sensor_msgs::CameraInfo>(topics.info_topic, 1);
  ros::Publisher image_pub = node.advertise<sensor_msgs::Image>(topics.image_topic, 1);
  ASSERT_TRUE(waitFor([&] { return info_pub.getNumSubscribers() > 0 && image_pub.getNumSubscribers() > 0; }));

  sensor_msgs::CameraInfo info;
  info.header.stamp = mid;
  info.width = 640;
  info.height = 480;
  info.K = {570.3, 0.0, 319.5, 0.0, 570.3, 239.5, 0.0, 0.0, 1.0};
  info_pub.publish(info);
  ASSERT_TRUE(waitFor([&] { return input.infos() == 1; }));

  sensor_msgs::Image image;
  image.header.stamp = mid;
  image.header.frame_id = "head_rgbd_sensor_rgb_frame";
  image.encoding = "16UC1";
  image.width = 640;
  image.height = 480;
  image.step = 1280;
  image.data.assign(1280 * 480, 0);
  image.data[0] = 0x34;  // pixel (0, 0): 0x1234 mm little endian
  image.data[1] = 0x12;
  image_pub.publish(image);
  ASSERT_TRUE(waitFor([&] { return sink.count() == 1; }));

  const Offered o = sink.at(0);
  EXPECT_EQ(o.stamp_ns, static_cast<std::int64_t>(mid.toNSec()));
  EXPECT_GT(o.received_ns, 0);
  EXPECT_GT(o.arrival_mono_ns, 0);
  EXPECT_EQ(o.encoding, "16UC1");
  EXPECT_EQ(o.width, 640u);
  EXPECT_EQ(o.height, 480u);
  EXPECT_EQ(o.step, 1280u);
  ASSERT_EQ(o.data.size(), 1280u * 480u);
  EXPECT_EQ(o.data[0], 0x34);
  EXPECT_EQ(o.data[1], 0x12);
  ASSERT_TRUE(o.has_info);
  EXPECT_EQ(o.info.width, 640u);
  EXPECT_EQ(o.info.K[0], 570.3);
  EXPECT_EQ(o.info.K[2], 319.5);
  EXPECT_EQ(o.info.K[5], 239.5);
  // Interpolated halfway: panned 0.5, tilted 0.3 down; the camera 0.1 m up the tilted axis.
  ASSERT_TRUE(o.pose.valid) << input.lastTfError();
  EXPECT_NEAR(o.pose.yaw, 0.5, 1e-9);
  EXPECT_NEAR(o.pose.pitch, 0.3, 1e-9);
  EXPECT_NEAR(o.pose.roll, 0.0, 1e-9);
  EXPECT_NEAR(o.pose.x, 0.1 * std::sin(0.3) * std::cos(0.5), 1e-9);
  EXPECT_NEAR(o.pose.y, 0.1 * std::sin(0.3) * std::sin(0.5), 1e-9);
  EXPECT_NEAR(o.pose.z, 1.0 + 0.1 * std::cos(0.3), 1e-9);
  EXPECT_EQ(input.tfFailures(), 0u);

  // No transform for its frame, or none yet at its stamp: offered without a pose, after at
  // most tf_timeout_s.
  image.header.frame_id = "unknown_frame";
  image.header.stamp = ros::Time(1000, 150'000'000);
  image_pub.publish(image);
  ASSERT_TRUE(waitFor([&] { return sink.count() == 2; }));
  EXPECT_FALSE(sink.at(1).pose.valid);
  image.header.frame_id = "head_rgbd_sensor_rgb_frame";
  image.header.stamp = ros::Time(1001, 0);  // after the head's last transform
  const auto sent = std::chrono::steady_clock::now();
  image_pub.publish(image);
  ASSERT_TRUE(waitFor([&] { return sink.count() == 3; }));
  EXPECT_FALSE(sink.at(2).pose.valid);
  EXPECT_LT(std::chrono::steady_clock::now() - sent, 1s);
  EXPECT_EQ(input.tfFailures(), 2u);
  EXPECT_FALSE(input.lastTfError().empty());
  EXPECT_EQ(input.images(), 3u);
  spinner.stop();
}

TEST_F(Ros1Camera, WithoutADedicatedTfThreadItLooksUpWithoutWaiting) {
  ros::NodeHandle node;
  ros::AsyncSpinner spinner(1);
  spinner.start();
  tf2_ros::Buffer tf;  // filled by hand here: tf2 would refuse a timeout
  RecordingSink sink;
  Ros1CameraTopics topics;
  topics.image_topic = "/test2/image";
  topics.info_topic = "/test2/info";
  Ros1CameraInput input(node, tf, topics, sink);
  ASSERT_TRUE(tf.setTransform(head(ros::Time(5, 0), 0.0, 0.3), "test", true));
  ASSERT_TRUE(tf.setTransform(
      transform("head_tilt_link", "optical", ros::Time(0), 0.0, 0.0, 0.0, -0.5, 0.5, -0.5, 0.5), "test", true));
  ros::Publisher image_pub = node.advertise<sensor_msgs::Image>(topics.image_topic, 1);
  ASSERT_TRUE(waitFor([&] { return image_pub.getNumSubscribers() > 0; }));
  sensor_msgs::Image image;
  image.header.stamp = ros::Time(7, 0);
  image.header.frame_id = "optical";
  image.encoding = "32FC1";
  image_pub.publish(image);
  ASSERT_TRUE(waitFor([&] { return sink.count() == 1; }));
  const Offered o = sink.at(0);
  ASSERT_TRUE(o.pose.valid) << input.lastTfError();
  EXPECT_NEAR(o.pose.pitch, 0.3, 1e-9);
  EXPECT_FALSE(o.has_info);  // no camera_info published: the sink is told so
  EXPECT_EQ(o.encoding, "32FC1");
  spinner.stop();
}

TEST_F(Ros1Camera, RejectsBadTopics) {
  ros::NodeHandle node;
  tf2_ros::Buffer tf;
  RecordingSink sink;
  Ros1CameraTopics topics;
  topics.image_topic = "";
  EXPECT_THROW(Ros1CameraInput(node, tf, topics, sink), std::invalid_argument);
  topics = Ros1CameraTopics{};
  topics.queue_size = 0;
  EXPECT_THROW(Ros1CameraInput(node, tf, topics, sink), std::invalid_argument);
  EXPECT_EQ(Ros1CameraTopics{}.image_topic, "/hsrb/head_rgbd_sensor/depth_registered/image_rect_raw");
}

// What the scanner's transport offered, copied in the spinner's thread.
struct OfferedScan {
  hal::LaserScanView view;  // its ranges pointer is stale after offer(): see `ranges`
  std::vector<float> ranges;
  std::int64_t arrival_mono_ns = 0;
};

class RecordingScanSink final : public hal::LaserScanSink {
 public:
  void offer(const hal::LaserScanView& scan, std::int64_t arrival_mono_ns) override {
    OfferedScan o;
    o.view = scan;
    o.ranges.assign(scan.ranges, scan.ranges + scan.count);
    o.arrival_mono_ns = arrival_mono_ns;
    const std::lock_guard<std::mutex> lock(mutex_);
    offered_.push_back(std::move(o));
  }
  std::size_t count() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return offered_.size();
  }
  OfferedScan at(std::size_t i) {
    const std::lock_guard<std::mutex> lock(mutex_);
    return offered_.at(i);
  }

 private:
  std::mutex mutex_;
  std::vector<OfferedScan> offered_;
};

TEST_F(Ros1Camera, TheBaseScannersLaserScansReachTheSinkAsPlainViews) {
  ros::NodeHandle node;
  ros::AsyncSpinner spinner(1);
  spinner.start();
  RecordingScanSink sink;
  Ros1ScannerTopics topics;
  topics.topic = "/test/base_scan";
  Ros1ScannerInput input(node, topics, sink);
  ros::Publisher pub = node.advertise<sensor_msgs::LaserScan>(topics.topic, 1);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }));

  // The HSR-B's: 270 degrees in 1,081 beams; a NaN and an inf among the ranges.
  sensor_msgs::LaserScan scan;
  scan.header.stamp = ros::Time(2000, 5'000'000);
  scan.header.frame_id = "base_range_sensor_link";  // not looked up: the config's mount places it
  scan.angle_min = -2.356194f;
  scan.angle_max = 2.356194f;
  scan.angle_increment = 0.004363323f;
  scan.time_increment = 1.7e-5f;
  scan.scan_time = 0.025f;
  scan.range_min = 0.05f;
  scan.range_max = 20.0f;
  scan.ranges.resize(1081);
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) scan.ranges[i] = 1.0f + 0.002f * static_cast<float>(i);
  scan.ranges[3] = std::numeric_limits<float>::quiet_NaN();
  scan.ranges[4] = std::numeric_limits<float>::infinity();
  scan.intensities.assign(1081, 100.0f);
  pub.publish(scan);
  ASSERT_TRUE(waitFor([&] { return sink.count() == 1; }));

  const OfferedScan o = sink.at(0);
  EXPECT_EQ(o.view.stamp_ns, static_cast<std::int64_t>(scan.header.stamp.toNSec()));
  EXPECT_GT(o.view.received_ns, 0);
  EXPECT_GT(o.arrival_mono_ns, 0);
  EXPECT_EQ(o.view.angle_min, scan.angle_min);
  EXPECT_EQ(o.view.angle_max, scan.angle_max);
  EXPECT_EQ(o.view.angle_increment, scan.angle_increment);
  EXPECT_EQ(o.view.range_min, scan.range_min);
  EXPECT_EQ(o.view.range_max, scan.range_max);
  EXPECT_EQ(o.view.count, 1081u);
  ASSERT_EQ(o.ranges.size(), 1081u);
  EXPECT_TRUE(std::isnan(o.ranges[3]));
  EXPECT_TRUE(std::isinf(o.ranges[4]));
  EXPECT_EQ(o.ranges[0], 1.0f);
  EXPECT_EQ(o.ranges[1080], scan.ranges[1080]);

  // An empty scan is offered as it is (the sink drops it, counted).
  scan.header.stamp = ros::Time(2000, 30'000'000);
  scan.ranges.clear();
  pub.publish(scan);
  ASSERT_TRUE(waitFor([&] { return sink.count() == 2; }));
  EXPECT_EQ(sink.at(1).view.count, 0u);
  EXPECT_EQ(input.scans(), 2u);
  spinner.stop();
}

TEST_F(Ros1Camera, TheScannerRejectsBadTopics) {
  ros::NodeHandle node;
  RecordingScanSink sink;
  Ros1ScannerTopics topics;
  topics.topic = "";
  EXPECT_THROW(Ros1ScannerInput(node, topics, sink), std::invalid_argument);
  topics = Ros1ScannerTopics{};
  topics.queue_size = 0;
  EXPECT_THROW(Ros1ScannerInput(node, topics, sink), std::invalid_argument);
  EXPECT_EQ(Ros1ScannerTopics{}.topic, "/hsrb/base_scan");
}

}  // namespace
}  // namespace staa::staad
