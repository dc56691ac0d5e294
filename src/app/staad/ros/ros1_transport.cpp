// The ROS 1 transport (roscpp from Debian 12): C++17, the only translation unit besides the
// camera's and the scanner's that includes ROS headers (transport.hpp says why).
#include "app/staad/ros/transport.hpp"

#include "app/staad/ros/ros1_camera.hpp"
#include "app/staad/ros/ros1_scanner.hpp"

#include <actionlib/server/simple_action_server.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/Twist.h>
#include <move_base_msgs/MoveBaseAction.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <mutex>
#include <thread>

namespace staa::staad::ros {

namespace {

using MoveBaseServer = actionlib::SimpleActionServer<move_base_msgs::MoveBaseAction>;

std::int64_t monotonicNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

double yawOf(const geometry_msgs::Quaternion& q) {
  // atan2 of the rotated x axis: NaN in, NaN out (the base backend refuses it).
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

geometry_msgs::Quaternion quaternionOf(double yaw) {
  geometry_msgs::Quaternion q;
  q.z = std::sin(yaw / 2.0);
  q.w = std::cos(yaw / 2.0);
  return q;
}

geometry_msgs::Point pointOf(double x, double y) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  return p;
}

class Ros1Transport final : public Transport {
 public:
  Ros1Transport(const TransportConfig& config, const TransportSinks& sinks);
  ~Ros1Transport() override;

  void publishTwist(double v, double w) override;
  std::int64_t now() const override { return static_cast<std::int64_t>(::ros::Time::now().toNSec()); }
  bool takeGoalEvent(GoalEvent& out) override;
  void goalFeedback(double x, double y, double theta) override;
  void goalSucceeded(const std::string& text) override;
  void goalAborted(const std::string& text) override;
  void goalPreempted(const std::string& text) override;
  void publishViz(const VizFrame& frame) override;
  void publishDiagnostics(const Diagnostics& status) override;
  TransportCounters counters() const override;
  bool masterReachable() const override { return ::ros::master::check(); }

 private:
  void onOdometry(const nav_msgs::Odometry::ConstPtr& msg);
  void onPose(const std_msgs::Header& header, const geometry_msgs::Pose& pose);
  void onTfTimer(const ::ros::TimerEvent&);
  void onActionGoal();
  void onActionPreempt();
  void onSimpleGoal(const geometry_msgs::PoseStamped::ConstPtr& msg);
  void onMap(const nav_msgs::OccupancyGrid::ConstPtr& msg);
  // The goal in the map frame, or why not.
  GoalEvent goalEvent(const geometry_msgs::PoseStamped& goal, bool from_action);
  void push(GoalEvent event);

  TransportConfig config_;
  TransportSinks sinks_;
  std::unique_ptr<::ros::NodeHandle> nh_;
  ::ros::CallbackQueue map_queue_;
  ::ros::CallbackQueue camera_queue_;
  std::unique_ptr<::ros::AsyncSpinner> spinner_;
  std::unique_ptr<::ros::AsyncSpinner> map_spinner_;
  std::unique_ptr<::ros::AsyncSpinner> camera_spinner_;
  std::unique_ptr<tf2_ros::Buffer> tf_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  ::ros::Publisher twist_pub_;
  ::ros::Publisher markers_pub_;
  ::ros::Publisher diagnostics_pub_;
  ::ros::Subscriber odom_sub_;
  ::ros::Subscriber pose_sub_;
  ::ros::Subscriber simple_goal_sub_;
  ::ros::Subscriber map_sub_;
  ::ros::Timer tf_timer_;
  std::unique_ptr<MoveBaseServer> action_;
  std::unique_ptr<Ros1CameraInput> camera_;
  std::unique_ptr<Ros1ScannerInput> scanner_;

  std::mutex events_mutex_;  // the callback threads and the service thread; never real-time
  std::deque<GoalEvent> events_;

  std::atomic<std::uint64_t> odometry_in_{0}, localization_in_{0}, goals_in_{0}, goals_refused_{0}, maps_in_{0},
      twists_out_{0}, localization_tf_failures_{0};
};

Ros1Transport::Ros1Transport(const TransportConfig& config, const TransportSinks& sinks)
    : config_(config), sinks_(sinks) {
  ::ros::M_string remappings;
  if (!config.master_uri.empty()) remappings["__master"] = config.master_uri;
  for (const auto& r : config.remappings) remappings[r.first] = r.second;
  // staad owns SIGINT/SIGTERM (signalfd); roscpp must not install its handler.
  ::ros::init(remappings, config.node_name, ::ros::init_options::NoSigintHandler);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(config.master_wait_s);
  while (!::ros::master::check()) {
    if (std::chrono::steady_clock::now() >= give_up) {
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, "%.1f", config.master_wait_s);
      throw TransportError("no ROS master answers at " + ::ros::master::getURI() + " (waited " + seconds +
                           " s; ros.master_uri or ROS_MASTER_URI)");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  nh_ = std::make_unique<::ros::NodeHandle>();
  tf_ = std::make_unique<tf2_ros::Buffer>(::ros::Duration(10.0));
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_, *nh_);

  const std::uint32_t queue = static_cast<std::uint32_t>(config.queue_size);
  if (config.base) {
    twist_pub_ = nh_->advertise<geometry_msgs::Twist>(config.cmd_vel_topic, queue);
    odom_sub_ = nh_->subscribe(config.odom_topic, queue, &Ros1Transport::onOdometry, this,
                               ::ros::TransportHints().tcpNoDelay());
    switch (config.localization) {
      case LocalizationSource::kNone: break;
      case LocalizationSource::kPoseStamped:
        pose_sub_ = nh_->subscribe<geometry_msgs::PoseStamped>(
            config.localization_topic, queue,
            [this](const geometry_msgs::PoseStamped::ConstPtr& m) { onPose(m->header, m->pose); });
        break;
      case LocalizationSource::kPoseWithCovarianceStamped:
        pose_sub_ = nh_->subscribe<geometry_msgs::PoseWithCovarianceStamped>(
            config.localization_topic, queue,
            [this](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) { onPose(m->header, m->pose.pose); });
        break;
      case LocalizationSource::kTf:
        tf_timer_ = nh_->createTimer(::ros::Duration(1.0 / config.tf_localization_hz), &Ros1Transport::onTfTimer, this);
        break;
    }
  }
  if (!config.action_name.empty()) {
    action_ = std::make_unique<MoveBaseServer>(*nh_, config.action_name, false);
    action_->registerGoalCallback([this] { onActionGoal(); });
    action_->registerPreemptCallback([this] { onActionPreempt(); });
    action_->start();
  }
  if (!config.simple_goal_topic.empty()) {
    simple_goal_sub_ = nh_->subscribe(config.simple_goal_topic, 4, &Ros1Transport::onSimpleGoal, this);
  }
  if (!config.map_topic.empty() && sinks.map != nullptr) {
    ::ros::NodeHandle map_nh;
    map_nh.setCallbackQueue(&map_queue_);
    map_sub_ = map_nh.subscribe(config.map_topic, 1, &Ros1Transport::onMap, this);
  }
  if (!config.image_topic.empty() && sinks.camera != nullptr) {
    ::ros::NodeHandle camera_nh;
    camera_nh.setCallbackQueue(&camera_queue_);
    Ros1CameraTopics topics;
    topics.image_topic = config.image_topic;
    topics.info_topic = config.camera_info_topic;
    topics.base_frame = config.base_frame;
    topics.tf_timeout_s = config.camera_tf_timeout_s;
    topics.queue_size = 1;
    camera_ = std::make_unique<Ros1CameraInput>(camera_nh, *tf_, topics, *sinks.camera);
  }
  if (!config.scan_topic.empty() && sinks.scanner != nullptr) {
    // On the main spinner: a scan's callback is a copy of its ranges, it never waits (no tf).
    Ros1ScannerTopics topics;
    topics.topic = config.scan_topic;
    topics.queue_size = 1;
    scanner_ = std::make_unique<Ros1ScannerInput>(*nh_, topics, *sinks.scanner);
  }
  markers_pub_ = nh_->advertise<visualization_msgs::MarkerArray>(config.markers_topic, 2);
  diagnostics_pub_ = nh_->advertise<diagnostic_msgs::DiagnosticArray>(config.diagnostics_topic, 2);

  spinner_ = std::make_unique<::ros::AsyncSpinner>(1);
  map_spinner_ = std::make_unique<::ros::AsyncSpinner>(1, &map_queue_);
  camera_spinner_ = std::make_unique<::ros::AsyncSpinner>(1, &camera_queue_);
  spinner_->start();
  map_spinner_->start();
  camera_spinner_->start();
}

Ros1Transport::~Ros1Transport() {
  for (auto* s : {spinner_.get(), map_spinner_.get(), camera_spinner_.get()}) {
    if (s != nullptr) s->stop();
  }
  if (action_) action_->shutdown();
  camera_.reset();
  scanner_.reset();
  action_.reset();
  tf_listener_.reset();
  nh_.reset();
  ::ros::shutdown();
}

void Ros1Transport::onOdometry(const nav_msgs::Odometry::ConstPtr& msg) {
  odometry_in_.fetch_add(1, std::memory_order_relaxed);
  hal::OdometrySample s;
  s.arrival_ns = monotonicNs();
  s.stamp_ns = static_cast<std::int64_t>(msg->header.stamp.toNSec());
  s.age_ns = static_cast<std::int64_t>((::ros::Time::now() - msg->header.stamp).toNSec());
  s.x = msg->pose.pose.position.x;
  s.y = msg->pose.pose.position.y;
  s.yaw = yawOf(msg->pose.pose.orientation);
  s.v = msg->twist.twist.linear.x;
  s.w = msg->twist.twist.angular.z;
  sinks_.base->offerOdometry(s);
}

void Ros1Transport::onPose(const std_msgs::Header& header, const geometry_msgs::Pose& pose) {
  localization_in_.fetch_add(1, std::memory_order_relaxed);
  geometry_msgs::PoseStamped in;
  in.header = header;
  in.pose = pose;
  geometry_msgs::PoseStamped in_map = in;
  if (!header.frame_id.empty() && header.frame_id != config_.map_frame) {
    try {
      in_map = tf_->transform(in, config_.map_frame, ::ros::Duration(0.05));
    } catch (const tf2::TransformException&) {
      localization_tf_failures_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
  }
  hal::PoseSample s;
  s.arrival_ns = monotonicNs();
  s.stamp_ns = static_cast<std::int64_t>(header.stamp.toNSec());
  s.x = in_map.pose.position.x;
  s.y = in_map.pose.position.y;
  s.yaw = yawOf(in_map.pose.orientation);
  sinks_.base->offerPose(s);
}

void Ros1Transport::onTfTimer(const ::ros::TimerEvent&) {
  geometry_msgs::TransformStamped t;
  try {
    t = tf_->lookupTransform(config_.map_frame, config_.base_frame, ::ros::Time(0));
  } catch (const tf2::TransformException&) {
    localization_tf_failures_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  localization_in_.fetch_add(1, std::memory_order_relaxed);
  hal::PoseSample s;
  s.arrival_ns = monotonicNs();
  s.stamp_ns = static_cast<std::int64_t>(t.header.stamp.toNSec());
  s.x = t.transform.translation.x;
  s.y = t.transform.translation.y;
  s.yaw = yawOf(t.transform.rotation);
  sinks_.base->offerPose(s);
}

GoalEvent Ros1Transport::goalEvent(const geometry_msgs::PoseStamped& goal, bool from_action) {
  GoalEvent e;
  e.kind = GoalEvent::Kind::kGoal;
  e.from_action = from_action;
  geometry_msgs::PoseStamped in_map = goal;
  if (!goal.header.frame_id.empty() && goal.header.frame_id != config_.map_frame) {
    try {
      // The goal where it is now: its frame's latest transform (a goal stamped in the past
      // must not be refused for tf's cache window).
      geometry_msgs::PoseStamped latest = goal;
      latest.header.stamp = ::ros::Time(0);
      in_map = tf_->transform(latest, config_.map_frame, ::ros::Duration(config_.goal_tf_timeout_s));
    } catch (const tf2::TransformException& ex) {
      e.refused = "no transform from the goal's frame '" + goal.header.frame_id + "' to '" + config_.map_frame +
                  "': " + ex.what();
      return e;
    }
  }
  e.x = in_map.pose.position.x;
  e.y = in_map.pose.position.y;
  e.theta = yawOf(in_map.pose.orientation);
  if (!(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.theta))) {
    e.refused = "the goal pose is not finite (NaN or infinite position or orientation)";
  }
  return e;
}

void Ros1Transport::push(GoalEvent event) {
  if (event.kind == GoalEvent::Kind::kGoal) {
    goals_in_.fetch_add(1, std::memory_order_relaxed);
    if (!event.refused.empty()) goals_refused_.fetch_add(1, std::memory_order_relaxed);
  }
  std::lock_guard<std::mutex> lock(events_mutex_);
  events_.push_back(std::move(event));
}

void Ros1Transport::onActionGoal() {
  const auto goal = action_->acceptNewGoal();
  if (!goal) return;
  push(goalEvent(goal->target_pose, true));
}

void Ros1Transport::onActionPreempt() {
  // A new goal preempts the old one too: its goal callback follows and replaces the goal.
  if (action_->isNewGoalAvailable()) return;
  GoalEvent e;
  e.kind = GoalEvent::Kind::kCancel;
  e.from_action = true;
  push(std::move(e));
}

void Ros1Transport::onSimpleGoal(const geometry_msgs::PoseStamped::ConstPtr& msg) {
  push(goalEvent(*msg, false));
}

void Ros1Transport::onMap(const nav_msgs::OccupancyGrid::ConstPtr& msg) {
  maps_in_.fetch_add(1, std::memory_order_relaxed);
  GridSample g;
  g.stamp_ns = static_cast<std::int64_t>(msg->header.stamp.toNSec());
  g.frame_id = msg->header.frame_id;
  g.width = msg->info.width;
  g.height = msg->info.height;
  g.resolution = msg->info.resolution;
  g.origin_x = msg->info.origin.position.x;
  g.origin_y = msg->info.origin.position.y;
  g.origin_yaw = yawOf(msg->info.origin.orientation);
  g.data = msg->data;
  sinks_.map->offerMap(std::move(g));
}

bool Ros1Transport::takeGoalEvent(GoalEvent& out) {
  std::lock_guard<std::mutex> lock(events_mutex_);
  if (events_.empty()) return false;
  out = std::move(events_.front());
  events_.pop_front();
  return true;
}

void Ros1Transport::publishTwist(double v, double w) {
  geometry_msgs::Twist t;
  t.linear.x = v;
  t.angular.z = w;
  twist_pub_.publish(t);
  twists_out_.fetch_add(1, std::memory_order_relaxed);
}

void Ros1Transport::goalFeedback(double x, double y, double theta) {
  if (!action_ || !action_->isActive()) return;
  move_base_msgs::MoveBaseFeedback f;
  f.base_position.header.stamp = ::ros::Time::now();
  f.base_position.header.frame_id = config_.map_frame;
  f.base_position.pose.position = pointOf(x, y);
  f.base_position.pose.orientation = quaternionOf(theta);
  action_->publishFeedback(f);
}

void Ros1Transport::goalSucceeded(const std::string& text) {
  if (action_ && action_->isActive()) action_->setSucceeded(move_base_msgs::MoveBaseResult(), text);
}

void Ros1Transport::goalAborted(const std::string& text) {
  if (action_ && action_->isActive()) action_->setAborted(move_base_msgs::MoveBaseResult(), text);
}

void Ros1Transport::goalPreempted(const std::string& text) {
  if (action_ && action_->isActive()) action_->setPreempted(move_base_msgs::MoveBaseResult(), text);
}

void Ros1Transport::publishViz(const VizFrame& frame) {
  visualization_msgs::MarkerArray array;
  const ::ros::Time stamp = frame.stamp_ns > 0 ? ::ros::Time().fromNSec(static_cast<std::uint64_t>(frame.stamp_ns))
                                               : ::ros::Time::now();
  // Markers left from the last frame (fewer obstacles now) go first.
  visualization_msgs::Marker clear;
  clear.header.frame_id = config_.map_frame;
  clear.header.stamp = stamp;
  clear.action = visualization_msgs::Marker::DELETEALL;
  array.markers.push_back(clear);
  int id = 0;
  auto marker = [&](const char* ns, int type, float r, float g, float b, double width) {
    visualization_msgs::Marker m;
    m.header.frame_id = config_.map_frame;
    m.header.stamp = stamp;
    m.ns = ns;
    m.id = id++;
    m.type = type;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.scale.x = width;
    m.scale.y = width;
    m.scale.z = width;
    m.color.r = r;
    m.color.g = g;
    m.color.b = b;
    m.color.a = 1.0f;
    return m;
  };
  auto ring = [&](const char* ns, const std::vector<Point2>& points, float r, float g, float b) {
    if (points.empty()) return;
    visualization_msgs::Marker m = marker(ns, visualization_msgs::Marker::LINE_STRIP, r, g, b, 0.02);
    for (const Point2& p : points) m.points.push_back(pointOf(p[0], p[1]));
    m.points.push_back(pointOf(points.front()[0], points.front()[1]));
    array.markers.push_back(std::move(m));
  };
  if (!frame.path.empty()) {
    visualization_msgs::Marker m = marker("global_path", visualization_msgs::Marker::LINE_STRIP, 0.1f, 0.4f, 1.0f, 0.03);
    for (const Point2& p : frame.path) m.points.push_back(pointOf(p[0], p[1]));
    array.markers.push_back(std::move(m));
  }
  if (!frame.trajectory.empty()) {
    visualization_msgs::Marker m = marker("trajectory", visualization_msgs::Marker::LINE_STRIP, 0.1f, 0.8f, 0.2f, 0.04);
    for (const auto& p : frame.trajectory) m.points.push_back(pointOf(p[0], p[1]));
    array.markers.push_back(std::move(m));
  }
  if (frame.has_subgoal) {
    visualization_msgs::Marker m = marker("subgoal", visualization_msgs::Marker::ARROW, 1.0f, 0.6f, 0.0f, 0.08);
    m.pose.position = pointOf(frame.subgoal[0], frame.subgoal[1]);
    m.pose.orientation = quaternionOf(frame.subgoal[2]);
    m.scale.x = 0.3;
    array.markers.push_back(std::move(m));
  }
  ring("footprint", frame.footprint, 0.9f, 0.9f, 0.9f);
  for (const auto& o : frame.obstacles) ring("moving_obstacles", o, 1.0f, 0.1f, 0.1f);
  for (const auto& o : frame.predicted) ring("predicted_obstacles", o, 1.0f, 0.5f, 0.5f);
  if (!frame.tree.empty()) {
    visualization_msgs::Marker m = marker("search_tree", visualization_msgs::Marker::LINE_LIST, 0.6f, 0.6f, 0.6f, 0.005);
    for (const auto& e : frame.tree) {
      m.points.push_back(pointOf(e[0], e[1]));
      m.points.push_back(pointOf(e[2], e[3]));
    }
    array.markers.push_back(std::move(m));
  }
  markers_pub_.publish(array);
}

void Ros1Transport::publishDiagnostics(const Diagnostics& status) {
  diagnostic_msgs::DiagnosticArray array;
  array.header.stamp = ::ros::Time::now();
  diagnostic_msgs::DiagnosticStatus s;
  s.level = static_cast<std::uint8_t>(status.level);
  s.name = config_.node_name + ": control";
  s.hardware_id = config_.node_name;
  s.message = status.message;
  for (const auto& kv : status.values) {
    diagnostic_msgs::KeyValue v;
    v.key = kv.first;
    v.value = kv.second;
    s.values.push_back(std::move(v));
  }
  array.status.push_back(std::move(s));
  diagnostics_pub_.publish(array);
}

TransportCounters Ros1Transport::counters() const {
  TransportCounters c;
  c.odometry_in = odometry_in_.load(std::memory_order_relaxed);
  c.localization_in = localization_in_.load(std::memory_order_relaxed);
  c.goals_in = goals_in_.load(std::memory_order_relaxed);
  c.goals_refused = goals_refused_.load(std::memory_order_relaxed);
  c.maps_in = maps_in_.load(std::memory_order_relaxed);
  c.twists_out = twists_out_.load(std::memory_order_relaxed);
  c.localization_tf_failures = localization_tf_failures_.load(std::memory_order_relaxed);
  return c;
}

}  // namespace

std::unique_ptr<Transport> startRos1Transport(const TransportConfig& config, const TransportSinks& sinks) {
  return std::make_unique<Ros1Transport>(config, sinks);
}

}  // namespace staa::staad::ros
