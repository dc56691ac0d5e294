#pragma once
// staad's ROS port: what the daemon needs from a ROS transport, in plain C++17 values (ROS 1's
// message headers do not compile as C++20, so the transport is its own C++17 library and this
// header is all the daemon sees of it). ROS 1 implements it today (ros1_transport.cpp); a
// ROS 2 transport implements the same class (docs/ros.md, "ROS 2").
//
// Threads: the transport runs roscpp's own normal-priority threads (callbacks, the map on a
// queue of its own so that a long import never delays odometry). Odometry and localization
// go to the base backend's BaseSink, depth images to the camera's DepthImageSink, laser
// scans to the scanner's LaserScanSink, maps to the MapSink, all from those threads.
// publishTwist() is called by the daemon's publisher thread; the rest by the service thread.

#include "hal/ros/base_port.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace staa::hal {
class DepthImageSink;  // hal/ros/depth_image.hpp
class LaserScanSink;   // hal/ros/laser_scan_port.hpp
}  // namespace staa::hal

namespace staa::staad::ros {

// The transport could not start (no master at the URI, a bad topic name): staad exits 3.
class TransportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class LocalizationSource { kNone, kPoseStamped, kPoseWithCovarianceStamped, kTf };

struct TransportConfig {
  std::string master_uri;  // empty: the environment's ROS_MASTER_URI
  std::string node_name = "staad";
  // NAME:=VALUE from the command line (roslaunch's __name, __log, __ns and remaps), as
  // ros::init takes them; __master here overrides master_uri.
  std::vector<std::pair<std::string, std::string>> remappings;
  double master_wait_s = 10.0;  // how long start() waits for the master
  std::string map_frame = "map";
  std::string base_frame = "base_footprint";
  // hal: ros
  bool base = false;
  std::string cmd_vel_topic = "/hsrb/command_velocity";
  std::string odom_topic = "/hsrb/odom";
  int queue_size = 1;
  LocalizationSource localization = LocalizationSource::kPoseStamped;
  std::string localization_topic = "/global_pose";
  double tf_localization_hz = 10.0;  // kTf: how often map -> base is looked up
  // Goals (empty: not offered).
  std::string action_name = "move_base";
  std::string simple_goal_topic = "/move_base_simple/goal";
  double goal_tf_timeout_s = 0.2;
  // map: ros (cleared: not subscribed).
  std::string map_topic = "/map";
  // camera.backend: ros (cleared: not subscribed).
  std::string image_topic = "/hsrb/head_rgbd_sensor/depth_registered/image_rect_raw";
  std::string camera_info_topic = "/hsrb/head_rgbd_sensor/depth_registered/camera_info";
  double camera_tf_timeout_s = 0.05;
  // scanner.backend: ros (cleared: not subscribed). The HSR-B's base scanner.
  std::string scan_topic = "/hsrb/base_scan";
  // RViz and diagnostics.
  std::string markers_topic = "/staad/markers";
  std::string diagnostics_topic = "/diagnostics";
};

// A goal or a cancel from ROS. `refused`: the goal could not be taken (its frame has no
// transform to the map frame, a NaN): the reason, for the action's abort text and the log.
struct GoalEvent {
  enum class Kind { kGoal, kCancel } kind = Kind::kGoal;
  bool from_action = false;  // the move_base action (else /move_base_simple/goal)
  double x = 0.0, y = 0.0, theta = 0.0;  // in the map frame
  std::string refused;
};

// nav_msgs/OccupancyGrid as it arrived: row 0 is the bottom row; -1 unknown, 0..100.
struct GridSample {
  std::int64_t stamp_ns = 0;
  std::string frame_id;
  std::uint32_t width = 0, height = 0;
  double resolution = 0.0;
  double origin_x = 0.0, origin_y = 0.0, origin_yaw = 0.0;
  std::vector<std::int8_t> data;
};

class MapSink {
 public:
  virtual ~MapSink() = default;
  // Called from the transport's map thread, which may take its time.
  virtual void offerMap(GridSample grid) = 0;
};

using Point2 = std::array<double, 2>;

// What RViz draws (visualization_msgs/MarkerArray in the map frame).
struct VizFrame {
  std::int64_t stamp_ns = 0;                       // ROS time; 0: now
  std::vector<Point2> path;                        // the global path
  std::vector<std::array<double, 3>> trajectory;   // the chosen trajectory (x, y, theta)
  bool has_subgoal = false;
  std::array<double, 3> subgoal{};                 // G~ (x, y, theta)
  std::vector<Point2> footprint;                   // at the robot's pose
  std::vector<std::vector<Point2>> obstacles;      // the moving obstacles, now
  std::vector<std::vector<Point2>> predicted;      // ... where they are predicted at the horizon
  std::vector<std::array<double, 4>> tree;         // search tree edges (x0, y0, x1, y1); empty: not sent
};

// diagnostic_msgs/DiagnosticStatus: level 0 OK, 1 WARN, 2 ERROR, 3 STALE.
struct Diagnostics {
  int level = 0;
  std::string message;
  std::vector<std::pair<std::string, std::string>> values;
};

// Counters of what the transport refused (read from any thread).
struct TransportCounters {
  std::uint64_t odometry_in = 0;
  std::uint64_t localization_in = 0;
  std::uint64_t goals_in = 0;
  std::uint64_t goals_refused = 0;
  std::uint64_t maps_in = 0;
  std::uint64_t twists_out = 0;
  std::uint64_t localization_tf_failures = 0;
};

struct TransportSinks {
  hal::BaseSink* base = nullptr;           // config.base
  hal::DepthImageSink* camera = nullptr;   // config.image_topic
  hal::LaserScanSink* scanner = nullptr;   // config.scan_topic
  MapSink* map = nullptr;                  // config.map_topic
};

class Transport {
 public:
  virtual ~Transport() = default;
  // The publisher thread.
  virtual void publishTwist(double v, double w) = 0;
  // ROS time now (ns): what publishTwist's message carries.
  virtual std::int64_t now() const = 0;
  // The service thread: goals and cancels in the order they came.
  virtual bool takeGoalEvent(GoalEvent& out) = 0;
  virtual void goalFeedback(double x, double y, double theta) = 0;
  virtual void goalSucceeded(const std::string& text) = 0;
  virtual void goalAborted(const std::string& text) = 0;
  virtual void goalPreempted(const std::string& text) = 0;
  virtual void publishViz(const VizFrame& frame) = 0;
  virtual void publishDiagnostics(const Diagnostics& status) = 0;
  virtual TransportCounters counters() const = 0;
  // Whether the master still answers (the service thread, at most once a second).
  virtual bool masterReachable() const = 0;
};

// Starts the ROS 1 node (ros1_transport.cpp): waits up to master_wait_s for the master, then
// subscribes and advertises. Throws TransportError naming the master URI or the topic.
std::unique_ptr<Transport> startRos1Transport(const TransportConfig& config, const TransportSinks& sinks);

}  // namespace staa::staad::ros
