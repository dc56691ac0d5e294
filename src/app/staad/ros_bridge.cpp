#include "app/staad/ros_bridge.hpp"

#include "app/staad/control_task.hpp"
#include "app/staad/protocol.hpp"
#include "app/staad/service.hpp"
#include "rt/alloc_count.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <stdexcept>
#include <thread>

namespace staa::staad {

namespace {

rt::Nanos periodOfHz(double hz) { return hz > 0.0 ? static_cast<rt::Nanos>(std::llround(1e9 / hz)) : 0; }

rt::Nanos monotonicNow() { return rt::MonotonicClock().now(); }

std::string fixed(double value, int digits = 3) {
  char text[48];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}

// Why the robot stopped pursuing the action's goal, for its abort text.
std::string abortReason(const Status& s) {
  switch (s.state) {
    case DaemonState::kUnreachable:
      return "unreachable: " + std::string(s.reason != nullptr ? s.reason : "no path") + " from (" + fixed(s.pose.x) +
             ", " + fixed(s.pose.y) + ") to the goal (" + fixed(s.goal.x) + ", " + fixed(s.goal.y) + ") in the map";
    case DaemonState::kFault: return "fault: " + statusJson(s, 0)["fault"].dump();
    case DaemonState::kStopped: return "stopped: a stop request (staactl stop) dropped the goal";
    default: return {};
  }
}

}  // namespace

OccupancyGrid occupancyGridFrom(const ros::GridSample& g, double occupied_thresh, double free_thresh) {
  if (g.width == 0 || g.height == 0) {
    throw std::invalid_argument("the grid is empty (" + std::to_string(g.width) + " x " + std::to_string(g.height) + ")");
  }
  const std::size_t cells = static_cast<std::size_t>(g.width) * g.height;
  if (g.data.size() != cells) {
    throw std::invalid_argument("the grid has " + std::to_string(g.data.size()) + " cells, its info says " +
                                std::to_string(g.width) + " x " + std::to_string(g.height) + " = " + std::to_string(cells));
  }
  if (!(std::isfinite(g.resolution) && g.resolution > 0.0)) {
    throw std::invalid_argument("the resolution must be a positive number of metres, got " + fixed(g.resolution, 6));
  }
  if (!(std::isfinite(g.origin_x) && std::isfinite(g.origin_y) && std::isfinite(g.origin_yaw))) {
    throw std::invalid_argument("the origin is not finite");
  }
  OccupancyGrid out;
  out.width = static_cast<int>(g.width);
  out.height = static_cast<int>(g.height);
  out.resolution = g.resolution;
  out.origin = Pose2{g.origin_x, g.origin_y, g.origin_yaw};
  out.cells.resize(cells);
  for (std::size_t i = 0; i < cells; ++i) {
    const int v = g.data[i];
    if (v < 0 || v > 100) {
      out.cells[i] = OccupancyGrid::kUnknown;
      continue;
    }
    const double occ = v / 100.0;
    out.cells[i] = occ > occupied_thresh ? OccupancyGrid::kOccupied
                   : occ < free_thresh   ? OccupancyGrid::kFree
                                         : OccupancyGrid::kUnknown;
  }
  return out;
}

RosBridge::RosBridge(const DaemonConfig& config, Channels& channels)
    : config_(config), ch_(channels), transport_config_(config.ros.transport) {
  transport_config_.base = config.hal == HalBackend::kRos;
  if (!config.map_from_ros) transport_config_.map_topic.clear();
  if (!(config.obstacles == ObstacleSource::kDepth && config.camera.backend == CameraBackend::kRos)) {
    transport_config_.image_topic.clear();
  }
  if (!(config.obstacles == ObstacleSource::kDepth && config.scanner.backend == ScannerBackend::kRos)) {
    transport_config_.scan_topic.clear();
  }
  if (!transport_config_.scan_topic.empty()) {
    scanner_owned_ = std::make_unique<hal::RosLaserScanner>();
    scanner_ = scanner_owned_.get();
  }
  if (!transport_config_.image_topic.empty()) {
    hal::RosDepthCameraConfig c;
    c.intrinsics = config.camera.intrinsics;
    c.mount = config.camera.mount;
    camera_owned_ = std::make_unique<hal::RosDepthCamera>(c);
    camera_ = camera_owned_.get();
  }
  if (transport_config_.base) {
    hal::RosBaseOptions o;
    o.twist_period = periodOfHz(config.control_hz);
    o.localization = config.ros.transport.localization != ros::LocalizationSource::kNone;
    base_ = std::make_unique<hal::RosBase>(o);
  }
}

RosBridge::~RosBridge() { stop(); }

void RosBridge::start() {
  ros::TransportSinks sinks;
  sinks.base = base_.get();
  sinks.camera = camera_owned_ ? camera_owned_.get() : nullptr;
  sinks.scanner = scanner_owned_ ? scanner_owned_.get() : nullptr;
  sinks.map = this;
  transport_ = ros::startRos1Transport(transport_config_, sinks);
  master_ = true;
  if (base_) {
    running_.store(true, std::memory_order_release);
    publisher_.start(rt::ThreadSpec{"staad-ros-pub", 0, -1}, [this] { publishTwists(); });
  }
  ch_.plan_tree_every.store(
      config_.ros.tree_hz > 0.0 ? static_cast<std::uint32_t>(std::max(1.0, std::round(config_.control_hz / config_.ros.tree_hz))) : 0,
      std::memory_order_relaxed);
  ch_.plan_wanted.store(config_.ros.markers_hz > 0.0, std::memory_order_relaxed);
}

void RosBridge::stop() {
  if (running_.exchange(false)) {
    publisher_.join();
    // The base thread's last command (a brake), then a zero twist whatever it was: the base
    // stops now, not 0.5 s later by its own timeout.
    hal::TwistSample t;
    if (base_->takeTwist(t)) transport_->publishTwist(t.v, t.w);
    transport_->publishTwist(0.0, 0.0);
  }
  transport_.reset();  // the map thread ends with it
  // The control thread has stopped: maps handed over but not taken, and the retired ones.
  MapBundle* bundle = nullptr;
  while (ch_.maps.pop(bundle)) delete bundle;
  while (ch_.retired_maps.pop(bundle)) delete bundle;
  std::lock_guard<std::mutex> lock(maps_mutex_);
  pending_map_.reset();
}

// The publisher thread: each twist the base thread wrote goes out as it comes.
void RosBridge::publishTwists() {
  hal::TwistSample t;
  while (running_.load(std::memory_order_acquire)) {
    if (!base_->waitTwist(100 * rt::kNanosPerMilli)) continue;
    if (!base_->takeTwist(t)) continue;
    transport_->publishTwist(t.v, t.w);
    const rt::Nanos sent = monotonicNow();
    base_->twistSent(t.command_stamp_ns, sent);
    if (t.odometry_stamp_ns >= 0) odometry_to_twist_.record(sent - t.odometry_stamp_ns);
  }
}

void RosBridge::offerMap(ros::GridSample grid) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string source = "ROS map '" + transport_config_.map_topic + "'";
  std::unique_ptr<MapBundle> bundle;
  try {
    if (!grid.frame_id.empty() && grid.frame_id != transport_config_.map_frame) {
      throw std::invalid_argument("its frame is '" + grid.frame_id + "', not the map frame '" +
                                  transport_config_.map_frame + "' (ros.map_frame)");
    }
    const OccupancyGrid classified = occupancyGridFrom(grid, config_.ros.occupied_thresh, config_.ros.free_thresh);
    ImportOptions options;
    options.simplify_m = config_.ros.simplify_m;
    bundle = std::make_unique<MapBundle>();
    bundle->map = importOccupancyGrid(classified, options, transport_config_.map_topic);
    if (maps_for_control_.load(std::memory_order_acquire)) {
      bundle->cycle = std::make_unique<ControlCycle>(bundle->map, config_.robot, controlConfigFor(config_));
    }
  } catch (const std::exception& e) {
    maps_refused_.fetch_add(1, std::memory_order_relaxed);
    std::lock_guard<std::mutex> lock(maps_mutex_);
    map_messages_.push_back("warning: " + source + " refused, the map planned on stays: " + e.what());
    return;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  map_import_s_.store(seconds, std::memory_order_relaxed);
  bundle->sequence = ++map_sequence_;
  maps_built_.fetch_add(1, std::memory_order_relaxed);
  std::lock_guard<std::mutex> lock(maps_mutex_);
  map_messages_.push_back(source + " " + std::to_string(bundle->sequence) + ": " + std::to_string(grid.width) + " x " +
                          std::to_string(grid.height) + " cells at " + fixed(grid.resolution) + " m, " +
                          std::to_string(bundle->map.obstacles.size()) + " obstacles, imported in " + fixed(seconds, 2) +
                          " s");
  pending_map_ = std::move(bundle);  // a newer map replaces one not yet handed over
}

std::optional<PolygonMap> RosBridge::waitFirstMap(rt::Nanos timeout, std::ostream& log) {
  const rt::Nanos deadline = monotonicNow() + timeout;
  for (;;) {
    std::unique_ptr<MapBundle> first;
    {
      std::lock_guard<std::mutex> lock(maps_mutex_);
      for (const std::string& m : map_messages_) log << "staad: " << m << std::endl;
      map_messages_.clear();
      first = std::move(pending_map_);
    }
    if (first) return std::move(first->map);
    if (monotonicNow() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void RosBridge::pollMaps(std::ostream& log) {
  MapBundle* retired = nullptr;
  while (ch_.retired_maps.pop(retired)) delete retired;
  std::lock_guard<std::mutex> lock(maps_mutex_);
  for (const std::string& m : map_messages_) log << "staad: " << m << std::endl;
  map_messages_.clear();
  if (!pending_map_ || !pending_map_->cycle) return;
  if (!ch_.maps.push(pending_map_.get())) return;  // the control thread takes it next cycle
  pending_map_.release();
  ++maps_handed_;
}

void RosBridge::pollGoals(Service& service, std::ostream& log) {
  ros::GoalEvent e;
  while (transport_->takeGoalEvent(e)) {
    const char* from = e.from_action ? "move_base action" : "/move_base_simple/goal";
    if (e.kind == ros::GoalEvent::Kind::kCancel) {
      if (!action_active_) continue;
      Request stop;
      stop.kind = RequestKind::kStop;
      const Service::Submitted s = service.submit(stop);
      transport_->goalPreempted(s.error.empty() ? "cancelled: the robot stops" : "cancelled, but " + s.error);
      action_active_ = false;
      log << "staad: ROS: the action's goal " << action_goal_id_ << " was cancelled: stopping" << std::endl;
      continue;
    }
    if (!e.refused.empty()) {
      log << "staad: ROS: a goal from the " << from << " refused: " << e.refused << std::endl;
      if (e.from_action) transport_->goalAborted("refused: " + e.refused);
      continue;
    }
    Request goal;
    goal.kind = RequestKind::kGoal;
    goal.pose = Pose2{e.x, e.y, e.theta};
    const Service::Submitted s = service.submit(goal);
    if (!s.error.empty()) {
      log << "staad: ROS: a goal from the " << from << " refused: " << s.error << std::endl;
      if (e.from_action) transport_->goalAborted("refused: " + s.error);
      continue;
    }
    log << "staad: ROS: goal " << s.goal_id << " (" << fixed(e.x) << ", " << fixed(e.y) << ", " << fixed(e.theta)
        << ") from the " << from << std::endl;
    if (e.from_action) {
      action_active_ = true;
      action_goal_id_ = s.goal_id;
    } else if (action_active_) {
      transport_->goalPreempted("preempted by goal " + std::to_string(s.goal_id) + " from /move_base_simple/goal");
      action_active_ = false;
    }
  }
}

void RosBridge::trackActionGoal(rt::Nanos now, const Status& s, std::ostream& log) {
  if (!action_active_) return;
  if (s.goal_id > action_goal_id_) {
    // Another client's goal (the control socket) replaced it.
    transport_->goalPreempted("preempted by goal " + std::to_string(s.goal_id) + " from another client");
    action_active_ = false;
    return;
  }
  if (s.goal_id != action_goal_id_) return;  // not yet taken by the control thread
  if (s.state == DaemonState::kReached) {
    transport_->goalSucceeded("reached (" + fixed(s.pose.x) + ", " + fixed(s.pose.y) + ", " + fixed(s.pose.theta) + ")");
    action_active_ = false;
    return;
  }
  const std::string reason = abortReason(s);
  if (!reason.empty()) {
    transport_->goalAborted(reason);
    log << "staad: ROS: the action's goal " << action_goal_id_ << " aborted: " << reason << std::endl;
    action_active_ = false;
    return;
  }
  if (now >= next_feedback_) {
    transport_->goalFeedback(s.pose.x, s.pose.y, s.pose.theta);
    next_feedback_ = now + 100 * rt::kNanosPerMilli;
  }
}

void RosBridge::publishViz() {
  if (!ch_.plan.update()) return;
  const PlanSnapshot& p = ch_.plan.readBuffer();
  ros::VizFrame f;
  for (std::size_t i = 0; i < p.path_n; ++i) f.path.push_back({p.path[i].x(), p.path[i].y()});
  for (std::size_t i = 0; i < p.trajectory_n; ++i) f.trajectory.push_back({p.trajectory[i].x, p.trajectory[i].y, p.trajectory[i].theta});
  f.has_subgoal = p.has_subgoal;
  f.subgoal = {p.subgoal.x, p.subgoal.y, p.subgoal.theta};
  for (const Vec2& v : config_.robot.footprint) {
    const Vec2 w = p.robot.transform(v);
    f.footprint.push_back({w.x(), w.y()});
  }
  for (std::size_t i = 0; i < p.obstacles_n; ++i) {
    const hal::ObstacleFrame::Obstacle& o = p.obstacles[i];
    std::vector<ros::Point2> now_ring, ahead;
    for (std::size_t k = 0; k < o.n; ++k) {
      now_ring.push_back({o.vertices[k].x(), o.vertices[k].y()});
      ahead.push_back({o.vertices[k].x() + o.velocity.x() * p.horizon_s, o.vertices[k].y() + o.velocity.y() * p.horizon_s});
    }
    f.obstacles.push_back(std::move(now_ring));
    f.predicted.push_back(std::move(ahead));
  }
  for (std::size_t i = 0; i < p.tree_n; ++i) f.tree.push_back({p.tree[i][0].x(), p.tree[i][0].y(), p.tree[i][1].x(), p.tree[i][1].y()});
  transport_->publishViz(f);
}

void RosBridge::publishDiagnostics(Service& service) {
  const Status& s = service.status();
  const nlohmann::json j = statusJson(s, rt::realtimeAllocations());
  ros::Diagnostics d;
  d.level = s.state == DaemonState::kFault ? 2 : s.state == DaemonState::kUnreachable ? 1 : 0;
  d.message = std::string(toString(s.state)) + (s.fault != FaultKind::kNone ? ": " + j["fault"].get<std::string>() : "");
  auto add = [&d](const char* key, const std::string& value) { d.values.emplace_back(key, value); };
  add("state", toString(s.state));
  add("fault", s.fault == FaultKind::kNone ? "none" : j["fault"].get<std::string>());
  add("base_fault", hal::toString(s.base.fault));
  add("cycles", std::to_string(s.cycles));
  add("cycle_p50_us", fixed(s.control_thread.execution.p50_us, 0));
  add("cycle_p99_us", fixed(s.control_thread.execution.p99_us, 0));
  add("cycle_max_us", fixed(s.control_thread.execution.max_us, 0));
  add("overruns", std::to_string(s.control_thread.counters.overruns));
  add("rt_allocations", std::to_string(rt::realtimeAllocations()));
  add("odometry_age_s", s.odometry_age_s < 0.0 ? "never" : fixed(s.odometry_age_s));
  add("obstacles_age_s", s.obstacles_age_s < 0.0 ? "never" : fixed(s.obstacles_age_s));
  add("goal_id", std::to_string(s.goal_id));
  add("odometry_to_twist_p99_us", fixed(s.ros.odometry_to_twist.p99_us, 0));
  add("localization_fixes", std::to_string(s.base.localization_fixes));
  add("last_jump_m", fixed(s.base.last_jump_m));
  transport_->publishDiagnostics(d);
}

void RosBridge::poll(rt::Nanos now, Service& service, std::ostream& log) {
  if (!transport_) return;
  const Status& status = service.latest();
  pollGoals(service, log);
  trackActionGoal(now, status, log);
  pollMaps(log);
  if (config_.ros.markers_hz > 0.0 && now >= next_viz_) {
    publishViz();
    next_viz_ = now + periodOfHz(config_.ros.markers_hz);
  }
  if (config_.ros.diagnostics_hz > 0.0 && now >= next_diagnostics_) {
    publishDiagnostics(service);
    next_diagnostics_ = now + periodOfHz(config_.ros.diagnostics_hz);
  }
  if (now >= next_master_check_) {
    const bool reachable = transport_->masterReachable();
    if (reachable != master_) {
      log << "staad: ROS: " << (reachable ? "the master answers again" : "the master does not answer") << std::endl;
    }
    master_ = reachable;
    next_master_check_ = now + rt::kNanosPerSecond;
  }
}

void RosBridge::fillStatus(Status& s) const {
  s.ros.enabled = transport_ != nullptr;
  if (!transport_) return;
  s.ros.master = master_;
  s.ros.odometry_to_twist = odometry_to_twist_.summary();
  const ros::TransportCounters c = transport_->counters();
  s.ros.odometry_in = c.odometry_in;
  s.ros.localization_in = c.localization_in;
  s.ros.twists_out = c.twists_out;
  s.ros.goals_in = c.goals_in;
  s.ros.goals_refused = c.goals_refused;
  s.ros.maps_in = c.maps_in;
  s.ros.maps_applied = ch_.maps_taken.load(std::memory_order_acquire);
  s.ros.maps_refused = maps_refused_.load(std::memory_order_relaxed);
  s.ros.map_import_s = map_import_s_.load(std::memory_order_relaxed);
  if (camera_ != nullptr) {
    s.ros.images_in = camera_->accepted() + camera_->droppedTotal();
    s.ros.images_dropped = camera_->droppedTotal();
  }
  if (scanner_ != nullptr) {
    s.ros.scans_in = scanner_->accepted() + scanner_->droppedTotal();
    s.ros.scans_dropped = scanner_->droppedTotal();
    for (std::size_t i = 0; i < hal::kRosScanDropReasons; ++i) {
      s.ros.scans_dropped_by[i] = scanner_->dropped(static_cast<hal::RosScanDrop>(i));
    }
  }
}

}  // namespace staa::staad
