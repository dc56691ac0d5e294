#pragma once
// staad's configuration (YAML, default config/staad.yaml): robot profile, map, HAL, rates,
// budgets, thread priorities, the control socket, staleness limits, telemetry. Relative
// paths are relative to the config file. Any bad value stops start-up: ConfigError's
// message names the file, the line, the key and the value ("staad.yaml:12: rates.control_hz:
// must be in (0, 1000], got -3"); staad exits 2.
//
//   format: staad-config/1
//   robot: ../robots/paper-agent.yaml        # staa-robot/1
//   map: ../maps/office.yaml                 # staa-polygon-map/1
//   hal: sim                                 # sim | socketcan | ros
//   sim: {start: [1.5, 4.5, 0.0], movers: 3, mover_speed: 0.8, seed: 1}
//   socketcan: {interface: can0, profile: can/hsr_base.yaml}  # hal: socketcan ("unix:/path" in tests)
//   obstacles: sim                           # sim (the simulator's movers) | depth | none
//   camera:                                  # obstacles: depth (backend required then)
//     backend: sim                           # sim (rendered frames of the sim world) | openni2
//     uri: ""                                # openni2 device URI; empty: any
//     intrinsics: {fx: 570.3, fy: 570.3, cx: 319.5, cy: 239.5}
//     mount: {x: 0.0, y: 0.0, z: 1.0, roll: 0.0, pitch: 0.3, yaw: 0.0}  # rad; pitch > 0: down
//     sim_noise_mm_per_m2: 1.5               # backend sim: depth noise (sigma per depth^2)
//     perception: {stride: 4, min_depth_m: 0.45, max_range_m: 4.5, scan_range_m: 0, min_height_m: 0.05,
//                  max_height_m: 1.8, cell_m: 0.1, min_points_per_cell: 3,
//                  min_cluster_points: 8, cluster_gap_m: 0.3, static_margin_m: 0.15,
//                  max_vertices: 16, gate_m: 0.5, max_speed_mps: 2.5, max_missed_frames: 5}
//   scanner:                                 # obstacles: depth: the base's laser scanner beside
//     backend: none                          # none | sim (camera.backend sim's world) | ros (ros.scanner)
//     mount: {x: 0.1675, y: 0.0, z: 0.1844, yaw: 0.0}  # base frame (m, rad): the HSR-B's
//     max_age_s: 0.1                         # a scan older than this at a depth frame is not used
//     fov_deg: 270                           # backend sim: the sweep, centred on the yaw,
//     beams: 1081                            #   its beams (both ends included),
//     range_m: [0.05, 20.0]                  #   the ranges that return,
//     noise_m: 0.01                          #   the range noise (standard deviation)
//   rates: {control_hz: 30, base_hz: 100, perception_hz: 30}
//   budget: {ms: 19}                         # or {expansions: 1000}
//   threads:                                 # priority 0: normal scheduling; cpu -1: any
//     control: {priority: 80, cpu: -1}
//     base: {priority: 85, cpu: -1}
//     perception: {priority: 70, cpu: -1}
//   socket: {path: /run/staad/staad.sock, mode: "0660", max_clients: 16, idle_timeout_s: 5}
//   limits: {odometry_timeout_s: 0.1, obstacles_timeout_s: 0.2}
//   goal: {tolerance_m: 0.2, heading_tolerance: 0.4}
//   telemetry: {path: "", records: 4096, svg: ""}  # empty path: off; svg: the run's picture
//   recorder: {enabled: true, seconds: 30, path: "", max_file_mb: 64, max_files: 8,
//              fault_dir: "", fault_after_s: 2, ring_kb: 4096}  # the flight recorder
//   memory: {heap_prefault_mb: 64, stack_prefault_kb: 256}
//   debug: {faults: false}                   # true: the socket's fault-injection requests (tests)
//   debug: {faults: true, extra_cycle_us: 0}  # 0..1000000: the control cycle busy-waits that long
//                                            # each cycle (tests: a slower cycle; needs faults)
//   ros:                                     # the ROS link (docs/ros.md; HSR ROS 1 defaults)
//     master_uri: ""                         # empty: $ROS_MASTER_URI
//     node_name: staad
//     master_wait_s: 10
//     frames: {map: map, base: base_footprint}
//     base: {cmd_vel: /hsrb/command_velocity, odom: /hsrb/odom, queue_size: 1}
//     localization: {source: pose, topic: /global_pose, tf_hz: 10}  # pose | pose_with_covariance | tf | none
//     goals: {action: move_base, simple_goal: /move_base_simple/goal, tf_timeout_s: 0.2}  # "": off
//     map: {topic: /map, wait_s: 30, occupied_thresh: 0.65, free_thresh: 0.196, simplify_m: 0.05}
//     camera: {image: /hsrb/head_rgbd_sensor/depth_registered/image_rect_raw,
//              info: /hsrb/head_rgbd_sensor/depth_registered/camera_info, tf_timeout_s: 0.05}
//     scanner: {topic: /hsrb/base_scan}      # sensor_msgs/LaserScan (scanner.backend: ros)
//     markers: {topic: /staad/markers, rate_hz: 10, tree_hz: 1}
//     diagnostics: {topic: /diagnostics, rate_hz: 1}
//   map: ros                                 # instead of a file: the latched map on ros.map.topic

#include "control/control_cycle.hpp"
#include "robot/robot_profile.hpp"
#include "world/sim_hal.hpp"
#include "hal/socketcan/can_profile.hpp"
#include "hal/depth_camera.hpp"
#include "hal/laser_scan.hpp"
#include "map/polygon_map.hpp"
#include "perception/depth_obstacles.hpp"
#include "rt/realtime.hpp"
#include "io/config_rules.hpp"
#include "app/staad/ros/transport.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace staa::staad {

// A bad config (or environment): staad exits 2. The config reader's own error type.
using ConfigError = io::ConfigError;

// The selectors, parsed at the edge (the file, --hal) and compared as enums from then on.
// hal: the base staad drives.
enum class HalBackend { kSim, kSocketCan, kRos };
inline constexpr io::Choice<HalBackend> kHalBackends[] = {{"sim", HalBackend::kSim},
                                                          {"socketcan", HalBackend::kSocketCan},
                                                          {"ros", HalBackend::kRos, "the base over ROS: the ros section"}};
// obstacles: where the moving obstacles come from.
enum class ObstacleSource { kSim, kDepth, kNone };
inline constexpr io::Choice<ObstacleSource> kObstacleSources[] = {
    {"sim", ObstacleSource::kSim, "the simulator's movers"},
    {"depth", ObstacleSource::kDepth, "a depth camera: the camera section"},
    {"none", ObstacleSource::kNone, "no obstacle sensor: empty frames"}};
// camera.backend: where the depth frames come from.
enum class CameraBackend { kSim, kOpenNI2, kRos };
inline constexpr io::Choice<CameraBackend> kCameraBackends[] = {
    {"sim", CameraBackend::kSim, "frames rendered from the simulated world"},
    {"openni2", CameraBackend::kOpenNI2, "the Xtion"},
    {"ros", CameraBackend::kRos, "sensor_msgs/Image over ROS: ros.camera"}};

// scanner.backend: where the base's laser scans come from (obstacles: depth only).
enum class ScannerBackend { kNone, kSim, kRos };
inline constexpr io::Choice<ScannerBackend> kScannerBackends[] = {
    {"none", ScannerBackend::kNone, "the camera alone"},
    {"sim", ScannerBackend::kSim, "scans of the simulated world the camera renders"},
    {"ros", ScannerBackend::kRos, "sensor_msgs/LaserScan over ROS: ros.scanner"}};

std::string_view toString(HalBackend hal);          // "sim", "socketcan", "ros"
std::string_view toString(ObstacleSource obstacles);  // "sim", "depth", "none"
std::string_view toString(CameraBackend backend);   // "sim", "openni2", "ros"
std::string_view toString(ScannerBackend backend);  // "none", "sim", "ros"

// hal: socketcan: the base over SocketCAN (hal/socketcan).
struct SocketCanConfig {
  // "can0" (a network interface, PF_CAN raw socket) or "unix:/abs/path" (a SOCK_SEQPACKET
  // socket carrying struct can_frame records: the simulated base of the tests). A relative
  // unix: path is made absolute against the config's directory.
  std::string interface;
  std::filesystem::path profile_file;  // staa-can-profile/1
  hal::CanProfile profile;
};

// obstacles: depth: the depth camera and the perception that turns its frames into the
// obstacle frames (src/app/staad/depth_sensor.hpp).
struct CameraConfig {
  CameraBackend backend = CameraBackend::kSim;  // frames rendered from the sim world | the Xtion
  std::string uri;              // openni2: the device's URI; empty: any device
  hal::CameraIntrinsics intrinsics;
  hal::CameraMount mount{0.0, 0.0, 1.0, 0.0, 0.3, 0.0};  // the HSR's head, looking down ahead
  double sim_noise_mm_per_m2 = 1.5;  // backend sim: depth noise, Kinect-class (SimDepthConfig)
  DepthObstaclesConfig perception;   // camera.perception (stride = pixel_stride)
};

// obstacles: depth: the base's laser scanner beside the camera (the HSR-B's
// /hsrb/base_scan): each depth frame is perceived with the newest scan, its returns in the
// same grid as the frame's points (depth_sensor.hpp). Its pose is the mount (no tf lookup:
// the scanner does not move on the base).
struct ScannerConfig {
  ScannerBackend backend = ScannerBackend::kNone;
  // Where the robot profile's `scanner` section puts it (config/robots/hsr.yaml: the HSR-B's
  // base_range_sensor_joint); without one, scanner.mount must be given.
  hal::ScanMount mount{0.0, 0.0, 0.0, 0.0};
  // A scan farther than this from a depth frame's stamp is not perceived with it (s).
  double max_age_s = 0.1;
  // backend sim: the sweep (degrees, centred on the mount's yaw), its beams (both ends
  // included), the ranges that return (m) and the range noise (m, standard deviation); the
  // robot profile's when it has a scanner.
  double fov_deg = 270.0;
  int beams = 1081;
  double range_min_m = 0.05;
  double range_max_m = 20.0;
  double noise_m = 0.01;
};

// A robot profile's scanner as staad's (backend none): the defaults of the scanner section.
ScannerConfig scannerConfigOf(const ScannerProfile& profile);

// The ros section (docs/ros.md): topics, frames and rates of the ROS link. Defaults are the
// HSR-B's ROS 1 names. The link runs when the section is given or anything is taken over ROS
// (hal: ros, map: ros, camera.backend: ros, scanner.backend: ros); goals, markers and
// diagnostics come with it.
struct RosConfig {
  bool enabled = false;
  ros::TransportConfig transport;
  double map_wait_s = 30.0;  // map: ros: how long start-up waits for the first map
  double occupied_thresh = 0.65;  // map_server's defaults, as staa-map import
  double free_thresh = 0.196;
  double simplify_m = 0.05;
  double markers_hz = 10.0;  // 0: no markers
  double tree_hz = 1.0;      // the search tree in the markers (0: never)
  double diagnostics_hz = 1.0;
};

// The flight recorder (docs/staad.md, "Flight recorder"): every cycle into a ring the
// service thread drains; the last `seconds` kept for `staactl record save` and fault files.
struct RecorderConfig {
  bool enabled = true;
  double seconds = 30.0;
  std::filesystem::path path;          // continuous recording, rotating files; empty: off
  std::uint64_t max_file_mb = 64;
  std::size_t max_files = 8;
  std::filesystem::path fault_dir;     // a file per fault; empty: off
  double fault_after_s = 2.0;
  std::size_t ring_kb = 4096;          // control thread -> service thread
};

struct DaemonConfig {
  std::filesystem::path file;        // where it was loaded from
  std::filesystem::path robot_file;
  RobotProfile robot;
  std::filesystem::path map_file;    // empty with map: ros
  PolygonMap map;                    // map: ros: the first map from the topic (set at start-up)
  bool map_from_ros = false;         // map: ros (ros.map.topic)
  HalBackend hal = HalBackend::kSim;
  hal::SimHalConfig sim;              // hal: sim, obstacles: sim, or obstacles: depth with camera.backend: sim
  SocketCanConfig socketcan;          // hal: socketcan
  RosConfig ros;                      // the ROS link
  ObstacleSource obstacles = ObstacleSource::kSim;  // the sim world's movers | camera | empty frames
  CameraConfig camera;                // obstacles: depth
  ScannerConfig scanner;              // obstacles: depth (backend none: the camera alone)
  double control_hz = 30.0;
  double base_hz = 100.0;
  double perception_hz = 30.0;
  BudgetSpec budget;  // default: 19 ms of wall clock
  rt::ThreadSpec control_thread{"staad-control", 80, -1};
  rt::ThreadSpec base_thread{"staad-base", 85, -1};
  rt::ThreadSpec perception_thread{"staad-percept", 70, -1};
  // The service (main) thread's nice value: it answers the control socket, and a stop must
  // not wait behind every other normal process of the machine (busy clients among them).
  int service_nice = -10;
  std::string socket_path = "/run/staad/staad.sock";
  unsigned socket_mode = 0660;
  // The control socket's clients at once (a new one makes room by dropping the longest idle),
  // and how long a client may take to complete a request line before it is dropped.
  std::size_t socket_max_clients = 16;
  double socket_idle_timeout_s = 5.0;
  double odometry_timeout_s = 0.1;
  double obstacles_timeout_s = 0.2;
  std::filesystem::path telemetry_path;  // empty: off
  std::size_t telemetry_records = 4096;  // ring capacity (records)
  std::filesystem::path svg_path;        // the run's picture, written at shutdown; empty: off
  RecorderConfig recorder;
  std::string text;                      // the config file as read (the recordings keep it)
  std::size_t heap_prefault_bytes = 64u << 20;
  std::size_t stack_prefault_bytes = 256u << 10;
  ControlConfig control;  // rate_hz = control_hz; goal tolerances from `goal`
  bool debug_faults = false;  // the control socket takes {"debug": ...} fault injections
  std::uint32_t debug_extra_cycle_us = 0;  // debug.extra_cycle_us (only with debug_faults)
};

// Parses the YAML text; `source` names it in errors and anchors relative paths. `hal`, when
// given (staad --hal), replaces the file's hal before the sections that depend on it are read.
DaemonConfig parseDaemonConfig(const std::string& yaml_text, const std::filesystem::path& source,
                               std::optional<HalBackend> hal = std::nullopt);
DaemonConfig loadDaemonConfig(const std::filesystem::path& file, std::optional<HalBackend> hal = std::nullopt);

}  // namespace staa::staad
