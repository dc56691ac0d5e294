#include "app/staad/config.hpp"

#include "io/config_reader.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "hal/camera_model.hpp"
#include "hal/obstacles.hpp"
#include "perception/depth_obstacles.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
#include <string_view>
#include <type_traits>
#include <utility>

namespace staa::staad {

std::string_view toString(HalBackend hal) { return io::nameOf<HalBackend>(kHalBackends, hal); }
std::string_view toString(ObstacleSource obstacles) { return io::nameOf<ObstacleSource>(kObstacleSources, obstacles); }
std::string_view toString(CameraBackend backend) { return io::nameOf<CameraBackend>(kCameraBackends, backend); }
std::string_view toString(ScannerBackend backend) { return io::nameOf<ScannerBackend>(kScannerBackends, backend); }

namespace {

namespace fs = std::filesystem;
using io::ConfigValue;
using io::Range;

constexpr std::string_view kFormat = "staad-config/1";

// Ranges that are part of the documented format (config/staad.yaml says the same).
constexpr double kMaxRateHz = 1000.0;
constexpr long long kMaxPriority = 99;    // SCHED_FIFO's range on Linux is 1..99
constexpr long long kMaxCpu = 1023;       // CPU_SETSIZE - 1
constexpr long long kMinTelemetryRecords = 16;
constexpr long long kMaxTelemetryRecords = 1 << 20;
constexpr long long kMaxHeapPrefaultMb = 4096;
// The prefault touches the calling (main) thread's stack: it must stay well inside the
// default 8 MiB stack limit, or the prefault itself overflows the stack.
constexpr long long kMaxStackPrefaultKb = 4096;
// debug.extra_cycle_us: up to a second of busy-waiting per cycle (far beyond any period).
constexpr long long kMaxExtraCycleUs = 1'000'000;
// The service polls every client each round: a few hundred stay cheap.
constexpr long long kMaxSocketClients = 256;
constexpr double kMinIdleTimeoutS = 0.1;
constexpr double kMaxIdleTimeoutS = 3600.0;
// sockaddr_un::sun_path holds 108 bytes including the terminating NUL.
constexpr std::size_t kMaxSocketPathBytes = 107;

std::string number(double v) { return io::numberText(v); }

// A file the config names, read by its own loader: an existing regular file (named with
// where it was looked for when it is not there), and the loader's error (which names that
// file) under the config's key.
template <class Load>
auto loadNamedFile(const ConfigValue& key, const fs::path& file, Load&& load) {
  std::error_code ec;
  const auto status = fs::status(file, ec);
  const std::string as_written = key.text();
  const std::string resolved = fs::path(as_written).is_absolute() ? "" : " (" + as_written + " relative to the config's directory)";
  if (!fs::exists(status)) key.fail("file not found: " + file.string() + resolved);
  if (fs::is_directory(status)) key.fail("is a directory, not a file: " + file.string());
  try {
    return load(file);
  } catch (const std::exception& e) {  // the format's error, or an I/O error of the library
    key.fail(e.what());
  }
}

// A module's FieldError for the value at `value` (read from the file, or left at its default).
[[noreturn]] void failField(const ConfigValue& value, const io::FieldError& e) {
  if (value.present()) value.failRule(e.rule());
  value.fail("must be " + e.rule() + ", got " + number(e.value()) + " (the default)");
}

// An integer from the file into a field of type T, saturated: a value beyond T lies beyond
// every rule of the field too, and the rule's message shows the value as written.
template <class T>
T saturated(long long v) {
  if (std::in_range<T>(v)) return static_cast<T>(v);
  return v < 0 ? std::numeric_limits<T>::min() : std::numeric_limits<T>::max();
}

void readRobotAndMap(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue robot = root.required("robot", "the robot profile file, staa-robot/1");
  config.robot_file = robot.path().lexically_normal();
  config.robot = loadNamedFile(robot, config.robot_file, [](const fs::path& f) { return loadRobotProfile(f); });

  const ConfigValue map = root.required("map", "the polygon map file, staa-polygon-map/1, or ros (the map from ros.map.topic)");
  if (map.node().IsScalar() && map.node().Scalar() == "ros") {
    config.map_from_ros = true;  // the map arrives at start-up (RosBridge::waitFirstMap)
    return;
  }
  config.map_file = map.path().lexically_normal();
  config.map = loadNamedFile(map, config.map_file, [](const fs::path& f) { return loadPolygonMap(f); });
}

void readRates(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue rates = root.section("rates", {"control_hz", "base_hz", "perception_hz"});
  const Range rate = Range::leftOpen(0.0, kMaxRateHz, "Hz");
  auto read = [&](std::string_view key, double& out) {
    if (const ConfigValue n = rates.get(key); n.given()) out = n.number(rate);
  };
  read("control_hz", config.control_hz);
  read("base_hz", config.base_hz);
  read("perception_hz", config.perception_hz);
}

void readBudget(const ConfigValue& root, DaemonConfig& config) {
  const double period_ms = 1000.0 / config.control_hz;
  const std::string period = number(period_ms) + " ms at control_hz " + number(config.control_hz);
  const ConfigValue budget = root.section("budget", {"ms", "expansions"});
  if (!budget.given()) {
    // The built-in 19 ms fits 30 Hz; at a faster rate it would overrun every cycle.
    if (!(config.budget.ms < period_ms)) {
      budget.fail("missing, and the default " + number(config.budget.ms) + " ms does not fit the control period (" + period +
                  "): give budget.ms or budget.expansions");
    }
    return;
  }
  const ConfigValue ms = budget.get("ms");
  const ConfigValue expansions = budget.get("expansions");
  if (ms.given() && expansions.given()) {
    budget.failAtKey("give either ms (wall clock) or expansions (reproducible), not both; got ms " + ms.text() +
                     " and expansions " + expansions.text());
  }
  if (!ms.given() && !expansions.given()) budget.failAtKey("expected ms (wall clock) or expansions (reproducible), got neither");
  if (ms.given()) {
    // The planner's budget is part of the cycle: it must leave the rest of the cycle time.
    const double v = ms.number();
    if (!(v > 0.0 && v < period_ms)) ms.failRule("> 0 and shorter than the control period (" + period + ")");
    config.budget = BudgetSpec::wallClockMs(v);
  } else {
    config.budget = BudgetSpec::expansionsOf(
        static_cast<std::uint32_t>(expansions.integer(1, std::numeric_limits<std::uint32_t>::max())));
  }
}

// camera.perception: the DepthObstaclesConfig fields a robot is tuned with (the tracker's
// noise model stays at its defaults), checked by perception's own rules. `stride` is
// pixel_stride.
void readPerception(const ConfigValue& camera, CameraConfig& c) {
  const ConfigValue perception = camera.section(
      "perception", {"stride", "min_depth_m", "max_range_m", "scan_range_m", "min_height_m", "max_height_m", "cell_m", "min_points_per_cell",
                     "min_cluster_points", "cluster_gap_m", "static_margin_m", "max_vertices", "gate_m", "max_speed_mps",
                     "max_missed_frames"});
  DepthObstaclesConfig& p = c.perception;
  auto real = [&](std::string_view key, double& out) {
    if (const ConfigValue n = perception.get(key); n.given()) out = n.number();
  };
  auto count = [&](std::string_view key, auto& out) {
    if (const ConfigValue n = perception.get(key); n.given()) out = saturated<std::remove_reference_t<decltype(out)>>(n.integer());
  };
  count("stride", p.pixel_stride);
  real("min_depth_m", p.min_depth_m);
  real("max_range_m", p.max_range_m);
  real("scan_range_m", p.scan_range_m);
  real("min_height_m", p.min_height_m);
  real("max_height_m", p.max_height_m);
  real("cell_m", p.cell_m);
  count("min_points_per_cell", p.min_points_per_cell);
  count("min_cluster_points", p.min_cluster_points);
  real("cluster_gap_m", p.cluster_gap_m);
  real("static_margin_m", p.static_margin_m);
  count("max_vertices", p.max_vertices);
  real("gate_m", p.gate_m);
  real("max_speed_mps", p.max_speed_mps);
  count("max_missed_frames", p.max_missed_frames);
  try {
    validateDepthObstaclesConfig(p, cameraOffset(c.mount));
  } catch (const io::FieldError& e) {
    failField(perception.get(e.field() == "pixel_stride" ? std::string_view("stride") : std::string_view(e.field())), e);
  }
}

// obstacles: depth: the camera section, checked by the camera model's and perception's rules.
void readCamera(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue camera =
      root.section("camera", {"backend", "uri", "intrinsics", "mount", "sim_noise_mm_per_m2", "perception"});
  if (config.obstacles != ObstacleSource::kDepth) return;  // checked for typos only
  if (!camera.given()) {
    camera.failAt(root.get("obstacles"),
                  "missing (obstacles: depth needs camera.backend: sim, frames rendered from the simulated world, or openni2, "
                  "the Xtion)");
  }
  CameraConfig& c = config.camera;
  c.backend = camera.required("backend", "sim, openni2 or ros").choice<CameraBackend>(kCameraBackends);
  if (const ConfigValue n = camera.get("uri"); n.given()) {
    c.uri = n.present() ? n.string("an OpenNI2 device URI, or \"\" for any device") : std::string();
  }
  const ConfigValue k = camera.section("intrinsics", {"fx", "fy", "cx", "cy"});
  const ConfigValue m = camera.section("mount", {"x", "y", "z", "roll", "pitch", "yaw"});
  auto real = [](const ConfigValue& section, std::string_view key, double& out) {
    if (const ConfigValue n = section.get(key); n.given()) out = n.number();
  };
  real(k, "fx", c.intrinsics.fx);
  real(k, "fy", c.intrinsics.fy);
  real(k, "cx", c.intrinsics.cx);
  real(k, "cy", c.intrinsics.cy);
  real(m, "x", c.mount.x);
  real(m, "y", c.mount.y);
  real(m, "z", c.mount.z);
  real(m, "roll", c.mount.roll);
  real(m, "pitch", c.mount.pitch);
  real(m, "yaw", c.mount.yaw);
  try {
    validateCamera(c.intrinsics, c.mount);
  } catch (const io::FieldError& e) {  // "intrinsics.fx", "mount.z"
    const std::string& field = e.field();
    const std::size_t dot = field.find('.');
    failField(camera.get(std::string_view(field).substr(0, dot)).get(std::string_view(field).substr(dot + 1)), e);
  }
  if (const ConfigValue n = camera.get("sim_noise_mm_per_m2"); n.given()) {
    c.sim_noise_mm_per_m2 = n.number(Range::atLeast(0.0, {}, "0: exact depths"));
  }
  readPerception(camera, c);
}

}  // namespace

ScannerConfig scannerConfigOf(const ScannerProfile& p) {
  ScannerConfig c;
  c.mount = hal::ScanMount{p.x, p.y, p.z, p.yaw};
  c.fov_deg = p.fov_deg;
  c.beams = p.beams;
  c.range_min_m = p.min_range_m;
  c.range_max_m = p.max_range_m;
  c.noise_m = p.noise_m;
  return c;
}

namespace {

// obstacles: depth: the base's laser scanner (after the camera: backend sim scans the world
// the camera renders).
void readScanner(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue scanner =
      root.section("scanner", {"backend", "mount", "max_age_s", "fov_deg", "beams", "range_m", "noise_m"});
  const ConfigValue m = scanner.section("mount", {"x", "y", "z", "yaw"});
  if (config.obstacles != ObstacleSource::kDepth) return;  // checked for typos only
  ScannerConfig& c = config.scanner;
  const ConfigValue backend = scanner.get("backend");
  if (backend.given()) c.backend = backend.choice<ScannerBackend>(kScannerBackends);
  // The simulated scanner scans the movers the simulated camera renders, at its frames.
  if (c.backend == ScannerBackend::kSim && config.camera.backend != CameraBackend::kSim) {
    backend.fail("sim scans the simulated world the camera renders: it needs camera.backend: sim, got camera.backend " +
                 std::string(toString(config.camera.backend)) + " (use scanner.backend: ros or none)");
  }
  // The robot profile's scanner is the default (its mount and sweep); the section's keys
  // override it. A profile without one gives no mount to guess: it must be given.
  if (config.robot.has_scanner) {
    const ScannerBackend chosen = c.backend;
    c = scannerConfigOf(config.robot.scanner);
    c.backend = chosen;
  } else if (c.backend != ScannerBackend::kNone && !m.get("z").given()) {
    m.get("z").fail("required: the robot profile " + config.robot_file.string() +
                    " has no scanner section to take the scanner's mount from");
  }
  auto read = [](const ConfigValue& section, std::string_view key, double& out, const Range& range) {
    if (const ConfigValue n = section.get(key); n.given()) out = n.number(range);
  };
  const Range offset = Range::closed(-RobotProfile::kMaxFootprintM, RobotProfile::kMaxFootprintM, "m", "on the base");
  read(m, "x", c.mount.x, offset);
  read(m, "y", c.mount.y, offset);
  read(m, "z", c.mount.z, Range::above(0.0, "m", "the scan plane above the floor"));
  read(m, "yaw", c.mount.yaw, Range::closed(-kPi, kPi, "rad"));
  read(scanner, "max_age_s", c.max_age_s, Range::leftOpen(0.0, 1.0, "s", "from the depth frame's stamp"));
  read(scanner, "fov_deg", c.fov_deg, Range::closed(1.0, 360.0, "degrees"));
  if (const ConfigValue n = scanner.get("beams"); n.given()) {
    c.beams = static_cast<int>(n.integer(2, static_cast<long long>(hal::LaserScan::kMaxBeams), " (beams over the sweep)"));
  }
  if (const ConfigValue range = scanner.get("range_m"); range.given()) {
    range.numbers<2>("[min, max] range in metres");
    c.range_min_m = range[0].number(Range::atLeast(0.0, "m"));
    c.range_max_m = range[1].number(Range::leftOpen(c.range_min_m, 100.0, "m", "above min"));
  }
  read(scanner, "noise_m", c.noise_m, Range::closed(0.0, 1.0, "m"));
}

void readSim(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue sim = root.section("sim", {"start", "movers", "mover_speed", "mover_radius", "seed", "sensor_range_m"});
  // The simulated obstacles arrive at the perception rate, like a depth camera's frames.
  config.sim.obstacle_rate_hz = config.perception_hz;
  // obstacles: depth with camera.backend: sim renders the simulated world's movers too.
  const bool sim_camera = config.obstacles == ObstacleSource::kDepth && config.camera.backend == CameraBackend::kSim;
  // A real base without simulated obstacles ignores the section (it is still checked for typos).
  if (config.hal != HalBackend::kSim && config.obstacles != ObstacleSource::kSim && !sim_camera) return;
  // With a real base the simulated world only moves its movers (the simulated camera): its
  // own robot stands at sim.start, where the movers' walks keep away from.
  config.sim.movers_only = config.hal != HalBackend::kSim;
  if (!sim.given()) {
    if (config.hal == HalBackend::kSim) {
      sim.failAt(root.get("hal"), "missing (hal: sim needs at least sim.start: [x, y, theta], free in the map)");
    }
    if (sim_camera) {
      sim.failAt(root.get("camera"),
                 "missing (camera.backend: sim renders the simulated world: it needs at least sim.start: [x, y, theta], free "
                 "in the map, where that world is anchored; or camera.backend: openni2)");
    }
    sim.failAt(root.get("obstacles"),
               "missing (obstacles: sim needs at least sim.start: [x, y, theta], free in the map, where the simulated world "
               "is anchored; or obstacles: none)");
  }

  const ConfigValue start = sim.required("start", "the simulated robot's start pose [x, y, theta], free in the map");
  const auto s = start.numbers<3>("[x, y, theta] (metres, radians)");
  config.sim.start = Pose2{s[0], s[1], s[2]};
  // The simulated robot must not begin in collision: its whole footprint is checked, as the
  // simulator would otherwise refuse to start (or start stuck) with a vaguer message.
  Polygon body;
  for (const Vec2& p : config.robot.footprint) body.push_back(config.sim.start.transform(p));
  const std::string at = "[" + number(s[0]) + ", " + number(s[1]) + ", " + number(s[2]) + "]";
  if (const auto& bounds = config.map.bounds) {
    for (const Vec2& p : body) {
      if (!(p.x() > bounds->min.x() && p.x() < bounds->max.x() && p.y() > bounds->min.y() && p.y() < bounds->max.y())) {
        start.fail("the robot's footprint reaches outside the map's bounds, got " + at);
      }
    }
  }
  const Box body_box = boundingBox(body);
  for (std::size_t i = 0; i < config.map.obstacles.size(); ++i) {
    const Polygon& obstacle = config.map.obstacles[i];
    if (body_box.overlaps(boundingBox(obstacle)) && polygonsOverlap(body, obstacle)) {
      start.fail("the robot's footprint overlaps obstacle " + std::to_string(i) + " of the map " + config.map_file.string() +
                 ", got " + at);
    }
  }

  if (const ConfigValue n = sim.get("movers"); n.given()) {
    config.sim.movers = static_cast<int>(n.integer(0, static_cast<long long>(hal::ObstacleFrame::kMaxObstacles)));
  }
  if (const ConfigValue n = sim.get("mover_speed"); n.given()) config.sim.mover_speed = n.number(Range::atLeast(0.0, "m/s"));
  if (const ConfigValue n = sim.get("mover_radius"); n.given()) config.sim.mover_radius = n.number(Range::above(0.0, "m"));
  if (const ConfigValue n = sim.get("seed"); n.given()) config.sim.seed = n.unsignedInteger();
  if (const ConfigValue n = sim.get("sensor_range_m"); n.given()) config.sim.sensor_range_m = n.number(Range::above(0.0, "m"));
  // The depth camera sees what its own range (and the walls) let it see: every mover is
  // rendered (with a real base sensor_range_m would be measured from sim.start).
  if (sim_camera) config.sim.sensor_range_m = std::numeric_limits<double>::infinity();
}

// A network interface name as the kernel takes it (dev_valid_name): 1..15 bytes, not "." or
// "..", no '/', ':' or white space.
bool validInterfaceName(std::string_view name) {
  if (name.empty() || name.size() > 15 || name == "." || name == "..") return false;
  return std::none_of(name.begin(), name.end(), [](char c) {
    return c == '/' || c == ':' || std::isspace(static_cast<unsigned char>(c)) || static_cast<unsigned char>(c) < 0x20;
  });
}

void readSocketCan(const ConfigValue& root, const fs::path& base, DaemonConfig& config) {
  const ConfigValue can = root.section("socketcan", {"interface", "profile"});
  if (config.hal != HalBackend::kSocketCan) return;  // checked for typos only
  if (!can.given()) {
    can.failAt(root.get("hal"),
               "missing (hal: socketcan needs socketcan.interface: can0 or unix:/path, and socketcan.profile: a "
               "staa-can-profile/1 file such as can/hsr_base.yaml)");
  }
  const ConfigValue iface = can.required("interface", "can0, or unix:/path for a SOCK_SEQPACKET socket");
  const std::string text = iface.string("a CAN interface name such as can0, or unix:/path");
  constexpr std::string_view kUnix = "unix:";
  if (text.rfind(kUnix, 0) == 0) {
    const std::string rest = text.substr(kUnix.size());
    if (rest.empty()) iface.fail("unix: needs a socket path after it, got " + iface.described());
    const fs::path p(rest);
    const std::string path = (p.is_absolute() ? p : base / p).lexically_normal().string();
    if (path.size() > kMaxSocketPathBytes) {
      iface.fail("the socket path is longer than " + std::to_string(kMaxSocketPathBytes) +
                 " bytes (the limit of a Unix socket address), got " + std::to_string(path.size()) + " bytes: " + path);
    }
    config.socketcan.interface = std::string(kUnix) + path;
  } else {
    if (!validInterfaceName(text)) {
      iface.fail("expected a CAN interface name (1..15 characters, no '/', ':' or spaces, e.g. can0) or unix:/path, got " +
                 iface.described());
    }
    config.socketcan.interface = text;
  }

  const ConfigValue profile = can.required("profile", "a staa-can-profile/1 file such as can/hsr_base.yaml");
  config.socketcan.profile_file = profile.path().lexically_normal();
  config.socketcan.profile =
      loadNamedFile(profile, config.socketcan.profile_file, [](const fs::path& f) { return hal::loadCanProfile(f); });
}

// A ROS graph resource name as ros::names::validate takes it: a letter, '/' or '~' first, then
// letters, digits, '_' and '/'. An empty one turns its feature off where the key allows it.
bool validRosName(std::string_view name) {
  if (name.empty()) return false;
  const unsigned char first = static_cast<unsigned char>(name[0]);
  if (!(std::isalpha(first) || name[0] == '/' || name[0] == '~')) return false;
  return std::all_of(name.begin() + 1, name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/';
  });
}

void readRos(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue ros = root.section("ros", {"master_uri", "node_name", "master_wait_s", "frames", "base", "localization",
                                              "goals", "map", "camera", "scanner", "markers", "diagnostics"});
  RosConfig& r = config.ros;
  ros::TransportConfig& t = r.transport;
  const bool camera_ros = config.obstacles == ObstacleSource::kDepth && config.camera.backend == CameraBackend::kRos;
  // config.scanner is read only with obstacles: depth (its backend stays none otherwise).
  const bool scanner_ros = config.scanner.backend == ScannerBackend::kRos;
  r.enabled = ros.given() || config.hal == HalBackend::kRos || config.map_from_ros || camera_ros || scanner_ros;
  // A name, or "" for off where `may_be_off`.
  auto name = [](const ConfigValue& section, std::string_view key, std::string& out, bool may_be_off) {
    const ConfigValue n = section.get(key);
    if (!n.given()) return;
    const std::string text = n.present() ? n.string("a ROS name such as /hsrb/odom") : std::string();
    if (text.empty() && may_be_off) {
      out.clear();
      return;
    }
    if (!validRosName(text)) {
      n.fail("expected a ROS name (a letter, '/' or '~' first, then letters, digits, '_' and '/')" +
             std::string(may_be_off ? ", or \"\" for off" : "") + ", got " + n.described());
    }
    out = text;
  };
  auto positive = [](const ConfigValue& section, std::string_view key, double& out, const char* unit) {
    if (const ConfigValue n = section.get(key); n.given()) out = n.number(Range::above(0.0, unit));
  };
  auto rate = [](const ConfigValue& section, std::string_view key, double& out) {
    if (const ConfigValue n = section.get(key); n.given()) out = n.number(Range::closed(0.0, kMaxRateHz, "Hz", "0: off"));
  };
  if (const ConfigValue n = ros.get("master_uri"); n.given()) {
    t.master_uri = n.present() ? n.string("http://host:port, or \"\" for $ROS_MASTER_URI") : std::string();
    if (!t.master_uri.empty() && t.master_uri.rfind("http://", 0) != 0) {
      n.fail("expected http://host:port (or \"\" for $ROS_MASTER_URI), got " + n.described());
    }
  }
  name(ros, "node_name", t.node_name, false);
  if (t.node_name.find('/') != std::string::npos) ros.get("node_name").fail("a node name has no '/', got " + t.node_name);
  positive(ros, "master_wait_s", t.master_wait_s, "s");

  const ConfigValue frames = ros.section("frames", {"map", "base"});
  name(frames, "map", t.map_frame, false);
  name(frames, "base", t.base_frame, false);

  const ConfigValue base = ros.section("base", {"cmd_vel", "odom", "queue_size"});
  name(base, "cmd_vel", t.cmd_vel_topic, false);
  name(base, "odom", t.odom_topic, false);
  if (const ConfigValue n = base.get("queue_size"); n.given()) t.queue_size = static_cast<int>(n.integer(1, 100));

  const ConfigValue loc = ros.section("localization", {"source", "topic", "tf_hz"});
  if (const ConfigValue n = loc.get("source"); n.given()) {
    static constexpr io::Choice<ros::LocalizationSource> kSources[] = {
        {"pose", ros::LocalizationSource::kPoseStamped, "geometry_msgs/PoseStamped on localization.topic"},
        {"pose_with_covariance", ros::LocalizationSource::kPoseWithCovarianceStamped,
         "geometry_msgs/PoseWithCovarianceStamped on localization.topic"},
        {"tf", ros::LocalizationSource::kTf, "tf from frames.map to frames.base"},
        {"none", ros::LocalizationSource::kNone, "odometry is the map frame"}};
    t.localization = n.choice<ros::LocalizationSource>(kSources);
  }
  name(loc, "topic", t.localization_topic, false);
  positive(loc, "tf_hz", t.tf_localization_hz, "Hz");

  const ConfigValue goals = ros.section("goals", {"action", "simple_goal", "tf_timeout_s"});
  name(goals, "action", t.action_name, true);
  name(goals, "simple_goal", t.simple_goal_topic, true);
  positive(goals, "tf_timeout_s", t.goal_tf_timeout_s, "s");

  const ConfigValue map = ros.section("map", {"topic", "wait_s", "occupied_thresh", "free_thresh", "simplify_m"});
  name(map, "topic", t.map_topic, false);
  positive(map, "wait_s", r.map_wait_s, "s");
  if (const ConfigValue n = map.get("occupied_thresh"); n.given()) r.occupied_thresh = n.number(Range::closed(0.0, 1.0, {}));
  if (const ConfigValue n = map.get("free_thresh"); n.given()) r.free_thresh = n.number(Range::closed(0.0, 1.0, {}));
  if (!(r.free_thresh < r.occupied_thresh)) {
    map.failAtKey("free_thresh (" + number(r.free_thresh) + ") must be below occupied_thresh (" + number(r.occupied_thresh) + ")");
  }
  if (const ConfigValue n = map.get("simplify_m"); n.given()) r.simplify_m = n.number(Range::atLeast(0.0, "m", "0: every cell corner"));

  const ConfigValue camera = ros.section("camera", {"image", "info", "tf_timeout_s"});
  name(camera, "image", t.image_topic, false);
  name(camera, "info", t.camera_info_topic, false);
  positive(camera, "tf_timeout_s", t.camera_tf_timeout_s, "s");

  const ConfigValue scanner = ros.section("scanner", {"topic"});
  name(scanner, "topic", t.scan_topic, false);

  const ConfigValue markers = ros.section("markers", {"topic", "rate_hz", "tree_hz"});
  name(markers, "topic", t.markers_topic, false);
  rate(markers, "rate_hz", r.markers_hz);
  rate(markers, "tree_hz", r.tree_hz);
  const ConfigValue diagnostics = ros.section("diagnostics", {"topic", "rate_hz"});
  name(diagnostics, "topic", t.diagnostics_topic, false);
  rate(diagnostics, "rate_hz", r.diagnostics_hz);

  // The simulated world is anchored in the map the config names: it cannot wait for one.
  if (config.map_from_ros) {
    const bool sim_camera = config.obstacles == ObstacleSource::kDepth && config.camera.backend == CameraBackend::kSim;
    if (config.hal == HalBackend::kSim || config.obstacles == ObstacleSource::kSim || sim_camera) {
      root.get("map").fail("map: ros needs a real base and real obstacles (hal: ros or socketcan; obstacles: depth with a "
                           "real camera, or none): the simulated world is built on a map file");
    }
  }
}

void readDebug(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue debug = root.section("debug", {"faults", "extra_cycle_us"});
  if (const ConfigValue n = debug.get("faults"); n.given()) config.debug_faults = n.boolean();
  if (const ConfigValue n = debug.get("extra_cycle_us"); n.given()) {
    const long long us = n.integer(0, kMaxExtraCycleUs, " (us the control cycle busy-waits each cycle)");
    // A fault cue like the socket's debug requests: never in a robot's config by accident.
    if (us != 0 && !config.debug_faults) {
      n.fail("a fault cue for tests, taken only with debug.faults: true, got " + std::to_string(us) +
             " with debug.faults false");
    }
    config.debug_extra_cycle_us = static_cast<std::uint32_t>(us);
  }
}

void readThreads(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue threads = root.section("threads", {"control", "base", "perception", "service"});
  auto thread = [&](std::string_view key, rt::ThreadSpec& spec) {
    const ConfigValue t = threads.section(key, {"priority", "cpu"});
    if (const ConfigValue p = t.get("priority"); p.given()) {
      spec.priority = static_cast<int>(p.integer(0, kMaxPriority, " (0: normal scheduling, 1..99: SCHED_FIFO)"));
    }
    if (const ConfigValue c = t.get("cpu"); c.given()) spec.cpu = static_cast<int>(c.integer(-1, kMaxCpu, " (-1: any CPU)"));
  };
  thread("control", config.control_thread);
  thread("base", config.base_thread);
  thread("perception", config.perception_thread);
  const ConfigValue service = threads.section("service", {"nice"});
  if (const ConfigValue n = service.get("nice"); n.given()) {
    config.service_nice = static_cast<int>(n.integer(-20, 19, " (the service thread's nice value)"));
  }
}

// Permission bits as people write them for chmod: octal with a leading 0 ("0660", also YAML
// 1.2's "0o660"). A plain integer without the 0 is taken as decimal (432 = 0660), which the
// range check turns into an error for a forgotten 0 ("660" > 0777).
std::optional<unsigned> permissionBits(const ConfigValue& m) {
  if (!m.node().IsScalar()) return std::nullopt;
  std::string_view t = m.node().Scalar();
  int radix = 10;
  if (t.size() > 2 && t[0] == '0' && (t[1] == 'o' || t[1] == 'O')) {
    t.remove_prefix(2);
    radix = 8;
  } else if (t.size() > 1 && t[0] == '0') {
    radix = 8;
  }
  unsigned v = 0;
  const auto res = std::from_chars(t.data(), t.data() + t.size(), v, radix);
  if (t.empty() || res.ec != std::errc{} || res.ptr != t.data() + t.size() || v > 0777u) return std::nullopt;
  return v;
}

void readSocket(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue socket = root.section("socket", {"path", "mode", "max_clients", "idle_timeout_s"});
  if (const ConfigValue p = socket.get("path"); p.given()) {
    config.socket_path = p.path().lexically_normal().string();
    if (config.socket_path.size() > kMaxSocketPathBytes) {
      p.fail("longer than " + std::to_string(kMaxSocketPathBytes) + " bytes (the limit of a Unix socket address), got " +
             std::to_string(config.socket_path.size()) + " bytes: " + config.socket_path);
    }
  }
  if (const ConfigValue m = socket.get("mode"); m.given()) {
    const std::optional<unsigned> mode = permissionBits(m);
    if (!mode) m.fail("expected permission bits as an octal string like \"0660\" (0000..0777), got " + m.text());
    config.socket_mode = *mode;
  }
  if (const ConfigValue n = socket.get("max_clients"); n.given()) {
    config.socket_max_clients = static_cast<std::size_t>(n.integer(1, kMaxSocketClients));
  }
  // Long enough for a person typing a request by hand (socat), short enough that silent
  // connections cannot hold the slots for long.
  if (const ConfigValue n = socket.get("idle_timeout_s"); n.given()) {
    config.socket_idle_timeout_s = n.number(Range::closed(kMinIdleTimeoutS, kMaxIdleTimeoutS, "s"));
  }
}

void readLimits(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue limits = root.section("limits", {"odometry_timeout_s", "obstacles_timeout_s"});
  const Range positive = Range::above(0.0, "s");
  if (const ConfigValue n = limits.get("odometry_timeout_s"); n.given()) config.odometry_timeout_s = n.number(positive);
  if (const ConfigValue n = limits.get("obstacles_timeout_s"); n.given()) config.obstacles_timeout_s = n.number(positive);
  // A timeout shorter than its input's period would hold the robot in a fault forever.
  auto longerThanPeriod = [&](std::string_view key, double timeout, double hz, const char* rate) {
    const double period = 1.0 / hz;
    if (!(timeout > period)) {
      limits.get(key).fail("must be longer than one period of its input (" + number(period) + " s at rates." + rate + " " +
                           number(hz) + "), got " + number(timeout));
    }
  };
  longerThanPeriod("odometry_timeout_s", config.odometry_timeout_s, config.base_hz, "base_hz");
  longerThanPeriod("obstacles_timeout_s", config.obstacles_timeout_s, config.perception_hz, "perception_hz");
}

void readGoal(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue goal = root.section("goal", {"tolerance_m", "heading_tolerance"});
  if (const ConfigValue n = goal.get("tolerance_m"); n.given()) config.control.goal_tolerance_m = n.number(Range::above(0.0, "m"));
  if (const ConfigValue n = goal.get("heading_tolerance"); n.given()) {
    config.control.goal_heading_tolerance = n.number(Range::above(0.0, "rad", "> pi ignores the heading"));
  }
}

void readBlindCorners(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue section = root.section(
      "blind_corners", {"enabled", "reaction_s", "decel", "clearance_m", "min_speed", "range_m", "lateral_m"});
  BlindCornerConfig& b = config.control.blind_corners;
  if (const ConfigValue n = section.get("enabled"); n.given()) b.enabled = n.boolean();
  if (const ConfigValue n = section.get("reaction_s"); n.given()) b.reaction_s = n.number(Range::closed(0.0, 5.0, "s"));
  if (const ConfigValue n = section.get("decel"); n.given()) {
    b.decel = n.number(Range::closed(0.0, 100.0, "m/s^2", "0: the robot's a_max"));
  }
  if (const ConfigValue n = section.get("clearance_m"); n.given()) {
    b.clearance_m = n.number(Range::closed(0.0, 10.0, "m", "0: the footprint's circumradius"));
  }
  if (const ConfigValue n = section.get("min_speed"); n.given()) b.min_speed = n.number(Range::closed(0.0, 100.0, "m/s"));
  if (const ConfigValue n = section.get("range_m"); n.given()) b.range_m = n.number(Range::leftOpen(0.0, 100.0, "m"));
  if (const ConfigValue n = section.get("lateral_m"); n.given()) b.lateral_m = n.number(Range::closed(0.0, 100.0, "m"));
}

void readTelemetry(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue telemetry = root.section("telemetry", {"path", "records", "svg"});
  // A file path, or "" (or nothing) for off.
  auto optionalPath = [&](std::string_view key, fs::path& out) {
    const ConfigValue p = telemetry.get(key);
    if (!p.given()) return;
    const std::string text = p.present() ? p.string("a file path, or \"\" for off") : std::string();
    out = text.empty() ? fs::path() : p.path().lexically_normal();
  };
  optionalPath("path", config.telemetry_path);
  optionalPath("svg", config.svg_path);
  if (const ConfigValue n = telemetry.get("records"); n.given()) {
    config.telemetry_records = static_cast<std::size_t>(n.integer(kMinTelemetryRecords, kMaxTelemetryRecords));
  }
}

void readRecorder(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue r = root.section("recorder", {"enabled", "seconds", "path", "max_file_mb", "max_files", "fault_dir",
                                                  "fault_after_s", "ring_kb"});
  RecorderConfig& c = config.recorder;
  if (const ConfigValue v = r.get("enabled"); v.given()) c.enabled = v.boolean();
  if (const ConfigValue v = r.get("seconds"); v.given()) c.seconds = v.number(Range::closed(1.0, 3600.0, "s"));
  for (const auto& [key, out] : {std::pair<std::string_view, fs::path*>{"path", &c.path}, {"fault_dir", &c.fault_dir}}) {
    const ConfigValue p = r.get(key);
    if (!p.given()) continue;
    const std::string text = p.present() ? p.string("a path, or \"\" for off") : std::string();
    *out = text.empty() ? fs::path() : p.path().lexically_normal();
  }
  if (const ConfigValue v = r.get("max_file_mb"); v.given()) c.max_file_mb = static_cast<std::uint64_t>(v.integer(1, 65536));
  if (const ConfigValue v = r.get("max_files"); v.given()) c.max_files = static_cast<std::size_t>(v.integer(1, 10000));
  if (const ConfigValue v = r.get("fault_after_s"); v.given()) c.fault_after_s = v.number(Range::closed(0.0, 60.0, "s"));
  if (const ConfigValue v = r.get("ring_kb"); v.given()) {
    c.ring_kb = static_cast<std::size_t>(v.integer(256, 262144, " (the ring between the control and service threads)"));
  }
}

void readMemory(const ConfigValue& root, DaemonConfig& config) {
  const ConfigValue memory = root.section("memory", {"heap_prefault_mb", "stack_prefault_kb"});
  if (const ConfigValue n = memory.get("heap_prefault_mb"); n.given()) {
    config.heap_prefault_bytes = static_cast<std::size_t>(n.integer(0, kMaxHeapPrefaultMb)) << 20;
  }
  if (const ConfigValue n = memory.get("stack_prefault_kb"); n.given()) {
    config.stack_prefault_bytes = static_cast<std::size_t>(n.integer(0, kMaxStackPrefaultKb, " (inside the 8 MiB default stack)")) << 10;
  }
}

}  // namespace

DaemonConfig parseDaemonConfig(const std::string& yaml_text, const fs::path& source, std::optional<HalBackend> hal_override) {
  // Anchored absolutely: the daemon may change its working directory after loading.
  std::error_code ec;
  const fs::path absolute = fs::absolute(source, ec);
  const fs::path base = (ec ? source : absolute).parent_path();
  const io::ConfigDocument doc = io::ConfigDocument::parse(yaml_text, source.string(), base);
  const ConfigValue& root = doc.root(kFormat, {"format", "robot", "map", "hal", "sim", "socketcan", "obstacles", "camera",
                                               "scanner", "rates", "budget", "threads", "socket", "limits", "goal", "blind_corners",
                                               "telemetry", "recorder", "memory", "debug", "ros"});
  DaemonConfig config;
  config.file = source;
  if (const ConfigValue hal = root.get("hal"); hal.given()) config.hal = hal.choice<HalBackend>(kHalBackends);
  if (hal_override) config.hal = *hal_override;
  if (const ConfigValue obstacles = root.get("obstacles"); obstacles.given()) {
    config.obstacles = obstacles.choice<ObstacleSource>(kObstacleSources);
  }
  readRobotAndMap(root, config);
  readRates(root, config);
  readBudget(root, config);
  readCamera(root, config);
  readScanner(root, config);
  readSim(root, config);
  readSocketCan(root, base, config);
  readThreads(root, config);
  readSocket(root, config);
  readLimits(root, config);
  readGoal(root, config);
  readBlindCorners(root, config);
  readTelemetry(root, config);
  readRecorder(root, config);
  readMemory(root, config);
  readDebug(root, config);
  readRos(root, config);
  config.control.rate_hz = config.control_hz;
  config.text = yaml_text;
  return config;
}

DaemonConfig loadDaemonConfig(const fs::path& file, std::optional<HalBackend> hal) {
  return parseDaemonConfig(io::ConfigDocument::readFile(file, "config file"), file, hal);
}

}  // namespace staa::staad
