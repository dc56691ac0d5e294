#pragma once
// staad over ROS (docs/ros.md): the daemon's side of the ROS transport (ros/transport.hpp).
// It owns the transport, the base backend of hal: ros (hal/ros/ros_base.hpp), the thread that
// publishes its twists, and the service thread's ROS duties, run by poll() each service round:
//
//   goals      move_base action goals and /move_base_simple/goal queued like the control
//              socket's (Service::submit, same numbering); the action's goal succeeds when
//              the robot reaches it, aborts with the reason when unreachable, on a fault or a
//              stop, is preempted by a cancel (which stops the robot) or by a newer goal;
//              feedback carries the pose;
//   maps       each OccupancyGrid from map_server imported by the importer of `staa-map
//              import` and a control cycle built on it, on the transport's map thread; the
//              bundle passed to the control thread (Channels::maps), swapped in at a cycle
//              boundary; replaced bundles freed here;
//   RViz       the control thread's plan snapshot as markers (markers_hz; the search tree at
//              tree_hz);
//   diagnostics the status as a DiagnosticArray (diagnostics_hz).
//
// Nothing here runs in a real-time thread: roscpp's threads and the publisher thread are
// normal-priority; they meet the real-time threads only in the triple buffers and rings.

#include "app/staad/channels.hpp"
#include "app/staad/config.hpp"
#include "app/staad/ros/transport.hpp"
#include "hal/ros/ros_base.hpp"
#include "hal/ros/ros_depth_camera.hpp"
#include "hal/ros/ros_laser_scanner.hpp"
#include "map/ros_import.hpp"
#include "rt/clock.hpp"
#include "rt/realtime.hpp"
#include "rt/timing_stats.hpp"

#include <atomic>
#include <iosfwd>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace staa::staad {

class Service;

// nav_msgs/OccupancyGrid values (-1 unknown, 0..100) classified with map_server's thresholds
// (`occ = value / 100`), as `staa-map import` classifies an image in raw mode. Throws
// std::invalid_argument naming what is wrong with the grid (size, resolution, origin).
OccupancyGrid occupancyGridFrom(const ros::GridSample& grid, double occupied_thresh, double free_thresh);

class RosBridge final : public ros::MapSink {
 public:
  // Builds the base backend (hal: ros) but starts nothing.
  RosBridge(const DaemonConfig& config, Channels& channels);
  ~RosBridge() override;
  RosBridge(const RosBridge&) = delete;
  RosBridge& operator=(const RosBridge&) = delete;

  // Starts the transport (throws ros::TransportError: no master, ...) and, with hal: ros, the
  // publisher thread.
  void start();
  hal::RosBase* base() { return base_.get(); }
  // camera.backend: ros: the camera the transport feeds, handed to perception (which owns it
  // from then on and outlives the bridge); null otherwise.
  std::unique_ptr<hal::RosDepthCamera> takeCamera() { return std::move(camera_owned_); }
  // scanner.backend: ros: the base's laser scanner the transport feeds, handed over likewise.
  std::unique_ptr<hal::RosLaserScanner> takeScanner() { return std::move(scanner_owned_); }

  // map: ros at start-up: the first map that imports (the ones that fail are logged), or
  // nothing after `timeout`. Service thread, before the real-time threads start.
  std::optional<PolygonMap> waitFirstMap(rt::Nanos timeout, std::ostream& log);
  // From then on maps become bundles for the control thread (after the control task exists).
  void acceptMapsForControl() { maps_for_control_.store(true, std::memory_order_release); }

  // One service round: goals, maps, markers, diagnostics.
  void poll(rt::Nanos now, Service& service, std::ostream& log);
  // The status's ros fields.
  void fillStatus(Status& status) const;
  // Stops the publisher thread and the transport; frees the maps not taken. After the
  // real-time threads stopped.
  void stop();

  // ros::MapSink (the transport's map thread).
  void offerMap(ros::GridSample grid) override;

 private:
  void publishTwists();
  void pollGoals(Service& service, std::ostream& log);
  void trackActionGoal(rt::Nanos now, const Status& status, std::ostream& log);
  void pollMaps(std::ostream& log);
  void publishViz();
  void publishDiagnostics(Service& service);

  const DaemonConfig& config_;
  Channels& ch_;
  ros::TransportConfig transport_config_;
  std::unique_ptr<hal::RosBase> base_;
  std::unique_ptr<hal::RosDepthCamera> camera_owned_;  // until takeCamera()
  const hal::RosDepthCamera* camera_ = nullptr;        // for the status's counts
  std::unique_ptr<hal::RosLaserScanner> scanner_owned_;  // until takeScanner()
  const hal::RosLaserScanner* scanner_ = nullptr;        // for the status's counts
  std::unique_ptr<ros::Transport> transport_;
  rt::RtThread publisher_;
  std::atomic<bool> running_{false};
  rt::LatencyHistogram odometry_to_twist_{1'000'000};

  // The action's goal: the id the service gave it while it is active.
  bool action_active_ = false;
  std::uint64_t action_goal_id_ = 0;
  rt::Nanos next_feedback_ = 0;

  // Maps: built on the map thread, handed over by the service thread.
  std::mutex maps_mutex_;
  std::unique_ptr<MapBundle> pending_map_;  // the newest built, not yet handed over
  std::vector<std::string> map_messages_;   // for the log, from the map thread
  std::atomic<bool> maps_for_control_{false};
  std::uint64_t map_sequence_ = 0;          // map thread
  std::atomic<std::uint64_t> maps_refused_{0};
  std::atomic<std::uint64_t> maps_built_{0};
  std::atomic<double> map_import_s_{0.0};
  std::uint64_t maps_handed_ = 0;

  rt::Nanos next_viz_ = 0;
  rt::Nanos next_diagnostics_ = 0;
  rt::Nanos next_master_check_ = 0;
  bool master_ = false;
};

}  // namespace staa::staad
