#pragma once
// What staad reports (docs/ARCHITECTURE.md section 6, `staactl status --json`, a contract) and
// the requests its control socket takes. Status is plain data: the control thread publishes
// it through a triple buffer every cycle; the service thread turns it into JSON.

#include "geometry/types.hpp"
#include "hal/base.hpp"
#include "hal/ros/ros_laser_scanner.hpp"
#include "rt/activity.hpp"
#include "rt/timing_stats.hpp"

#include <array>
#include <cstdint>
#include <limits>

namespace staa::staad {

enum class DaemonState : std::uint8_t { kIdle, kDriving, kReached, kUnreachable, kStopped, kFault };
const char* toString(DaemonState state);  // "idle", "driving", ...

// Why the robot is held (state kFault). Each one brakes the robot; each clears by itself when
// its cause goes away (the state returns to driving toward the goal, or idle).
enum class FaultKind : std::uint8_t {
  kNone,
  kStaleOdometry,   // no odometry for odometry_timeout
  kStaleObstacles,  // no obstacle (depth) frame for obstacles_timeout
  kBase,            // the base reports a fault (Status::base.fault says which)
};
const char* toString(FaultKind fault);  // "none", "stale_odometry", "stale_obstacles", "base"

// From a control command's stamp to the base driver's hand-over of the first frame carrying
// it to the kernel (BaseTask): one sample per command measured.
struct CommandToWire {
  rt::TimingSummary latency;
  std::uint64_t unsent = 0;  // control commands replaced before any frame carried them
};

// The ROS link (hal: ros, camera.backend: ros, map: ros, goals over ROS), filled in by the
// service thread from the ROS bridge; `enabled` false without one.
struct RosLinkStatus {
  bool enabled = false;
  bool master = false;  // the master answered when last asked (at most once a second)
  // From the stamp of the odometry a command was planned on to the twist's publication.
  rt::TimingSummary odometry_to_twist;
  std::uint64_t odometry_in = 0;
  std::uint64_t localization_in = 0;
  std::uint64_t twists_out = 0;
  std::uint64_t goals_in = 0;
  std::uint64_t goals_refused = 0;  // no transform to the map frame, not finite
  std::uint64_t maps_in = 0;
  std::uint64_t maps_applied = 0;   // swapped in at a cycle boundary
  std::uint64_t maps_refused = 0;   // the import failed (the message names why in the log)
  double map_import_s = 0.0;        // the last map's import and planner set-up
  std::uint64_t images_in = 0;
  std::uint64_t images_dropped = 0;
  // scanner.backend ros: the LaserScans received, and those dropped by their reason.
  std::uint64_t scans_in = 0;
  std::uint64_t scans_dropped = 0;
  std::array<std::uint64_t, hal::kRosScanDropReasons> scans_dropped_by{};
};

// obstacles: depth with the base's laser scanner (scanner.backend sim or ros), filled in by
// the service thread from the depth sensor's counters; `enabled` false without one.
struct ScannerStatus {
  bool enabled = false;
  const char* backend = "none";          // "sim", "ros"
  std::uint64_t scans_used = 0;          // depth frames perceived with a scan
  std::uint64_t scans_too_old = 0;       // ... alone: the newest scan was beyond max_age_s
  std::uint64_t frames_without_scan = 0; // ... alone: no scan had arrived yet
  std::uint64_t scan_points = 0;         // the last frame's scan returns in perception's grid
};

struct Status {
  DaemonState state = DaemonState::kIdle;
  Pose2 pose;
  double v = 0.0, w = 0.0;            // measured
  double v_cmd = 0.0, w_cmd = 0.0;    // commanded
  bool has_goal = false;
  Pose2 goal;
  // The id of the goal the control thread pursues or last pursued (0: none yet). Ids are
  // given by the service thread as it queues goal requests: 1, 2, ... (never reused).
  std::uint64_t goal_id = 0;
  FaultKind fault = FaultKind::kNone;
  // Why the goal is unreachable (state kUnreachable: the path's status, a static string such
  // as "no passage wider than the footprint"); null in every other state.
  const char* reason = nullptr;
  // The base driver's own view: its fault and code, enabled, what it refused on the bus.
  hal::BaseStatus base;
  // Control cycles run (the control task's own count, also when a test steps it).
  std::uint64_t cycles = 0;
  // Set by the service thread from the periodic activities (and BaseTask) when a status is
  // asked for; the control thread leaves them empty.
  rt::ActivityTiming control_thread;
  rt::ActivityTiming base_thread;
  CommandToWire command_to_wire;
  // Input staleness: seconds since the newest odometry / obstacle frame (-1: never seen).
  double odometry_age_s = -1.0;
  double obstacles_age_s = -1.0;
  // The planner's last call.
  std::uint32_t expansions = 0;
  double depth = 0.0;
  // The planner's wall-clock budget per cycle (0 with an expansion budget), and the longest
  // path and local-map steps of a cycle so far: a cycle's own work ends by the budget plus
  // those (the path step may run into its last query, the local map reads no deadline).
  double budget_ms = 0.0;
  std::int64_t path_max_ns = 0;
  std::int64_t local_max_ns = 0;
  // The blind-corner limit (blind_corners.enabled): the last cycle's cap (infinite: no blind
  // corner ahead) and the cycles whose command it lowered.
  bool blind_corners = false;
  double speed_cap = std::numeric_limits<double>::infinity();
  std::uint64_t capped_cycles = 0;
  double time_s = 0.0;    // monotonic time of the snapshot
  // Set by the service thread, not the control thread: the id of the newest goal it queued
  // (0: none yet). It runs ahead of goal_id until the control thread takes that goal (within
  // one control period), so a client that just sent a goal knows which id to wait for.
  std::uint64_t queued_goal_id = 0;
  // Set by the service thread: the ROS link.
  RosLinkStatus ros;
  // Set by the service thread: the base's laser scanner.
  ScannerStatus scanner;
};

enum class RequestKind : std::uint8_t { kGoal, kStop, kPose, kStatus, kDebug, kHistograms, kRecord };
// "goal", "stop", "pose", "status", "debug", "histograms", "record"
const char* toString(RequestKind kind);

// The longest file name of a `record` request (bytes).
constexpr std::size_t kMaxRecordFile = 511;

// Fault injection for tests ({"debug": ...}; only with debug.faults: true in the config).
enum class DebugKind : std::uint8_t {
  kNone,
  kOverrun,         // the next control cycle busy-waits debug_ms (a forced overrun)
  kStallObstacles,  // obstacle frames stop (debug_on) or resume: a depth stall
};
const char* toString(DebugKind kind);  // "none", "overrun", "stall_obstacles"

// At most this long a forced overrun (ms): long enough for the base thread to brake.
constexpr std::uint32_t kMaxDebugOverrunMs = 5000;

// A request from the control socket, passed to the control thread through an SpscRing
// (debug requests are carried out by the service thread through atomics of Channels).
struct Request {
  RequestKind kind = RequestKind::kStatus;
  Pose2 pose;  // goal or pose
  // A goal's id, given by the service thread as it queues the goal (1, 2, ...); never on the
  // wire from a client.
  std::uint64_t goal_id = 0;
  DebugKind debug = DebugKind::kNone;
  std::uint32_t debug_ms = 0;  // kOverrun
  bool debug_on = false;       // kStallObstacles
  // kRecord: the file the recorder's history is saved to (absolute, NUL-terminated; the
  // service thread answers it, it never reaches the control thread).
  std::array<char, kMaxRecordFile + 1> file{};
};

}  // namespace staa::staad
