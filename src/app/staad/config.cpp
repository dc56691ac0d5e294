#include "app/staad/config.hpp"

#include "io/yaml_support.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "hal/obstacles.hpp"
#include "hal/camera_model.hpp"
#include "perception/depth_obstacles.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace staa::staad {
namespace {

namespace fs = std::filesystem;

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
// sockaddr_un::sun_path holds 108 bytes including the terminating NUL.
constexpr std::size_t kMaxSocketPathBytes = 107;

using yaml_support::describe;
using yaml_support::readNumber;
std::string number(double v) { return yaml_support::formatNumber(v); }

std::string joined(std::initializer_list<std::string_view> keys) {
  std::string out;
  for (std::string_view k : keys) {
    if (!out.empty()) out += ", ";
    out += k;
  }
  return out;
}

// Reads one config file: every message is "FILE:LINE: key.path: what is wrong, got VALUE".
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const YAML::Node& at, const std::string& key, const std::string& what) const {
    std::string msg = source_;
    if (at.IsDefined() && at.Mark().line >= 0) msg += ":" + std::to_string(at.Mark().line + 1);
    msg += ": ";
    if (!key.empty()) msg += key + ": ";
    msg += what;
    throw ConfigError(msg);
  }

  // Rejects keys not in `keys` (a typo must never be silently ignored) and keys given twice
  // (yaml-cpp keeps both, and which one wins would be an accident).
  void onlyKeys(const YAML::Node& map, const std::string& where, std::initializer_list<std::string_view> keys) const {
    std::vector<std::pair<std::string, int>> seen;
    for (const auto& kv : map) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : std::string();
      const std::string path = where.empty() ? key : where + "." + key;
      if (!kv.first.IsScalar() || std::find(keys.begin(), keys.end(), key) == keys.end()) {
        fail(kv.first, kv.first.IsScalar() ? path : (where.empty() ? std::string("(top level)") : where),
             "unknown key " + describe(kv.first) + " (expected " + joined(keys) + ")");
      }
      for (const auto& [k, line] : seen) {
        if (k == key) fail(kv.first, path, "given twice (first on line " + std::to_string(line) + ")");
      }
      seen.emplace_back(key, kv.first.Mark().line + 1);
    }
  }

  static bool present(const YAML::Node& node) { return node.IsDefined() && !node.IsNull(); }

  // The key node of `key` in `map` (its line is where a person looks for the whole section;
  // a block mapping's own mark is its first entry's line).
  static YAML::Node keyOf(const YAML::Node& map, const char* key) {
    for (const auto& kv : map) {
      if (kv.first.IsScalar() && kv.first.Scalar() == key) return kv.first;
    }
    return map;
  }

  // An optional section: absent (undefined node) or a mapping of known keys.
  YAML::Node section(const YAML::Node& parent, const char* key, const std::string& where,
                     std::initializer_list<std::string_view> keys) const {
    const YAML::Node node = parent[key];
    if (!node.IsDefined()) return node;
    if (!node.IsMap()) fail(node, where, "expected a mapping {" + joined(keys) + "}, got " + describe(node));
    onlyKeys(node, where, keys);
    return node;
  }

  YAML::Node required(const YAML::Node& parent, const char* key, const std::string& where, const std::string& what) const {
    const YAML::Node node = parent[key];
    if (!present(node)) fail(parent, where, "missing (" + what + ")");
    return node;
  }

  double finite(const YAML::Node& node, const std::string& where) const {
    const auto v = readNumber(node);
    if (!v) fail(node, where, "expected a number, got " + describe(node));
    if (!std::isfinite(*v)) fail(node, where, "must be finite, got " + node.Scalar());
    return *v;
  }

  // A finite number above `lo`; `rule` says so in the message ("must be > 0 m").
  double above(const YAML::Node& node, const std::string& where, double lo, const std::string& rule) const {
    const double v = finite(node, where);
    if (!(v > lo)) fail(node, where, rule + ", got " + node.Scalar());
    return v;
  }

  long long integer(const YAML::Node& node, const std::string& where, long long lo, long long hi,
                    const std::string& meaning = "") const {
    std::optional<long long> v;
    if (node.IsScalar()) {
      std::string_view s = node.Scalar();
      if (!s.empty() && s.front() == '+') s.remove_prefix(1);
      long long x = 0;
      const auto res = std::from_chars(s.data(), s.data() + s.size(), x);
      if (!s.empty() && res.ec == std::errc{} && res.ptr == s.data() + s.size()) v = x;
    }
    if (!v || *v < lo || *v > hi) {
      fail(node, where, "must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + meaning + ", got " +
                            (node.IsScalar() ? node.Scalar() : describe(node)));
    }
    return *v;
  }

  std::string string(const YAML::Node& node, const std::string& where, const std::string& what) const {
    if (!node.IsScalar()) fail(node, where, "expected " + what + ", got " + describe(node));
    return node.Scalar();
  }

  // A file path; relative paths are relative to the config file's directory, so a config
  // works from whatever directory staad is started in (systemd starts it in /).
  fs::path path(const YAML::Node& node, const std::string& where, const fs::path& base) const {
    const std::string text = string(node, where, "a file path");
    if (text.empty()) fail(node, where, "expected a file path, got an empty string");
    const fs::path p(text);
    return (p.is_absolute() ? p : base / p).lexically_normal();
  }

  // An existing regular file, named with where it was looked for when it is not there.
  void existingFile(const YAML::Node& node, const std::string& where, const fs::path& file) const {
    std::error_code ec;
    const auto status = fs::status(file, ec);
    std::string as_written = node.Scalar();
    std::string resolved;
    if (!fs::path(as_written).is_absolute()) resolved = " (" + as_written + " relative to the config's directory)";
    if (!fs::exists(status)) fail(node, where, "file not found: " + file.string() + resolved);
    if (fs::is_directory(status)) fail(node, where, "is a directory, not a file: " + file.string());
  }

  std::array<double, 3> triple(const YAML::Node& node, const std::string& where) const {
    if (!node.IsSequence() || node.size() != 3) fail(node, where, "expected [x, y, theta] (metres, radians), got " + describe(node));
    std::array<double, 3> out{};
    for (std::size_t k = 0; k < 3; ++k) out[k] = finite(node[k], where + "[" + std::to_string(k) + "]");
    return out;
  }

 private:
  std::string source_;
};

void readRobotAndMap(const Reader& r, const YAML::Node& root, const fs::path& base, DaemonConfig& config) {
  const YAML::Node robot = r.required(root, "robot", "robot", "the robot profile file, staa-robot/1");
  config.robot_file = r.path(robot, "robot", base);
  r.existingFile(robot, "robot", config.robot_file);
  try {
    config.robot = loadRobotProfile(config.robot_file);
  } catch (const std::exception& e) {  // ProfileError, or an I/O error from the library
    r.fail(robot, "robot", e.what());
  }

  const YAML::Node map = r.required(root, "map", "map", "the polygon map file, staa-polygon-map/1");
  config.map_file = r.path(map, "map", base);
  r.existingFile(map, "map", config.map_file);
  try {
    config.map = loadPolygonMap(config.map_file);
  } catch (const std::exception& e) {  // MapError
    r.fail(map, "map", e.what());
  }
}

void readRates(const Reader& r, const YAML::Node& root, DaemonConfig& config) {
  const YAML::Node rates = r.section(root, "rates", "rates", {"control_hz", "base_hz", "perception_hz"});
  if (!rates.IsDefined()) return;
  auto rate = [&](const char* key, double& out) {
    const YAML::Node node = rates[key];
    if (!node.IsDefined()) return;
    const std::string where = std::string("rates.") + key;
    out = r.finite(node, where);
    if (!(out > 0.0 && out <= kMaxRateHz)) r.fail(node, where, "must be in (0, 1000] Hz, got " + node.Scalar());
  };
  rate("control_hz", config.control_hz);
  rate("base_hz", config.base_hz);
  rate("perception_hz", config.perception_hz);
}

void readBudget(const Reader& r, const YAML::Node& root, DaemonConfig& config) {
  const double period_ms = 1000.0 / config.control_hz;
  const std::string period = number(period_ms) + " ms at control_hz " + number(config.control_hz);
  const YAML::Node budget = r.section(root, "budget", "budget", {"ms", "expansions"});
  if (!budget.IsDefined()) {
    // The built-in 19 ms fits 30 Hz; at a faster rate it would overrun every cycle.
    if (!(config.budget.ms < period_ms)) {
      r.fail(root, "budget", "missing, and the default " + number(config.budget.ms) + " ms does not fit the control period (" +
                                 period + "): give budget.ms or budget.expansions");
    }
    return;
  }
  const YAML::Node ms = budget["ms"];
  const YAML::Node expansions = budget["expansions"];
  if (ms.IsDefined() && expansions.IsDefined()) {
    r.fail(Reader::keyOf(root, "budget"), "budget", "give either ms (wall clock) or expansions (reproducible), not both; got ms " + ms.Scalar() +
                                 " and expansions " + expansions.Scalar());
  }
  if (!ms.IsDefined() && !expansions.IsDefined()) {
    r.fail(Reader::keyOf(root, "budget"), "budget", "expected ms (wall clock) or expansions (reproducible), got neither");
  }
  if (ms.IsDefined()) {
    config.budget = BudgetSpec::wallClockMs(r.finite(ms, "budget.ms"));
    // The planner's budget is part of the cycle: it must leave the rest of the cycle time.
    if (!(config.budget.ms > 0.0 && config.budget.ms < period_ms)) {
      r.fail(ms, "budget.ms", "must be > 0 and shorter than the control period (" + period + "), got " + ms.Scalar());
    }
  } else {
    config.budget = BudgetSpec::expansionsOf(
        static_cast<std::uint32_t>(r.integer(expansions, "budget.expansions", 1, std::numeric_limits<std::uint32_t>::max())));
  }
}

void readObstacles(const Reader& r, const YAML::Node& root, DaemonConfig& config) {
  const YAML::Node n = root["obstacles"];
  if (!n.IsDefined()) return;
  config.obstacles = r.string(n, "obstacles", "sim, depth or none");
  if (config.obstacles != "sim" && config.obstacles != "depth" && config.obstacles != "none") {
    r.fail(n, "obstacles", "expected sim (the simulator's movers), depth (a depth camera: the camera section) or none (no "
                           "obstacle sensor: empty frames), got " + describe(n));
  }
}

// camera.perception: the DepthObstaclesConfig fields a robot is tuned with (the tracker's
// noise model stays at its defaults). `stride` is pixel_stride.
void readPerception(const Reader& r, const YAML::Node& camera, CameraConfig& c) {
  DepthObstaclesConfig& p = c.perception;
  const YAML::Node perception = r.section(camera, "perception", "camera.perception",
                                          {"stride", "min_depth_m", "max_range_m", "min_height_m", "max_height_m", "cell_m",
                                           "min_points_per_cell", "min_cluster_points", "cluster_gap_m", "static_margin_m",
                                           "max_vertices", "gate_m", "max_speed_mps", "max_missed_frames"});
  if (perception.IsDefined()) {
    const std::string w = "camera.perception.";
    auto positive = [&](const char* key, const char* unit, double& out) {
      if (const YAML::Node n = perception[key]; n.IsDefined()) out = r.above(n, w + key, 0.0, std::string("must be > 0 ") + unit);
    };
    auto nonNegative = [&](const char* key, double& out) {
      const YAML::Node n = perception[key];
      if (!n.IsDefined()) return;
      out = r.finite(n, w + key);
      if (out < 0.0) r.fail(n, w + key, "must be >= 0 m, got " + n.Scalar());
    };
    auto count = [&](const char* key, long long lo, long long hi, const char* meaning) {
      const YAML::Node n = perception[key];
      return n.IsDefined() ? std::optional<long long>(r.integer(n, w + key, lo, hi, meaning)) : std::nullopt;
    };
    if (const auto v = count("stride", 1, 16, " (every n-th pixel of every n-th row)")) p.pixel_stride = static_cast<int>(*v);
    nonNegative("min_depth_m", p.min_depth_m);
    positive("max_range_m", "m", p.max_range_m);
    if (const YAML::Node n = perception["min_height_m"]; n.IsDefined()) p.min_height_m = r.finite(n, w + "min_height_m");
    if (const YAML::Node n = perception["max_height_m"]; n.IsDefined()) p.max_height_m = r.finite(n, w + "max_height_m");
    positive("cell_m", "m", p.cell_m);
    if (const auto v = count("min_points_per_cell", 1, 65535, "")) p.min_points_per_cell = static_cast<int>(*v);
    if (const auto v = count("min_cluster_points", 1, 1'000'000, "")) p.min_cluster_points = static_cast<int>(*v);
    if (const YAML::Node n = perception["cluster_gap_m"]; n.IsDefined()) p.cluster_gap_m = r.finite(n, w + "cluster_gap_m");
    nonNegative("static_margin_m", p.static_margin_m);
    if (const auto v = count("max_vertices", 4, static_cast<long long>(hal::ObstacleFrame::kMaxVertices), "")) {
      p.max_vertices = static_cast<std::size_t>(*v);
    }
    positive("gate_m", "m", p.gate_m);
    positive("max_speed_mps", "m/s", p.max_speed_mps);
    if (const auto v = count("max_missed_frames", 0, 1000, "")) p.max_missed_frames = static_cast<int>(*v);
  }

  // Rules between fields: named at the key that breaks them (or the section, for defaults).
  const auto at = [&](const char* key) -> YAML::Node {
    if (perception.IsDefined() && perception[key].IsDefined()) return perception[key];
    return perception.IsDefined() ? Reader::keyOf(camera, "perception") : Reader::keyOf(camera, "backend");
  };
  if (!(p.max_height_m > p.min_height_m)) {
    r.fail(at("max_height_m"), "camera.perception.max_height_m",
           "must be > min_height_m (" + number(p.min_height_m) + " m), got " + number(p.max_height_m));
  }
  if (!(p.cluster_gap_m >= p.cell_m && p.cluster_gap_m <= 5.0 * p.cell_m)) {
    r.fail(at("cluster_gap_m"), "camera.perception.cluster_gap_m",
           "must be in [cell_m, 5 * cell_m] = [" + number(p.cell_m) + ", " + number(5.0 * p.cell_m) + "] m, got " +
               number(p.cluster_gap_m));
  }
  // The occupancy grid spans max_range_m (plus the mount's offset) around the robot: at most
  // 998 cells of it (the detector's 2000 x 2000 cells).
  const double reach = p.max_range_m + std::hypot(c.mount.x, c.mount.y);
  if (reach / p.cell_m > 998.0) {
    r.fail(at("cell_m"), "camera.perception.cell_m",
           "too small for max_range_m " + number(p.max_range_m) + " m (+ the mount's " + number(reach - p.max_range_m) +
               " m offset): at most 998 cells of range, got " + number(p.cell_m));
  }
  try {
    validateDepthObstaclesConfig(p);
    validateCamera(c.intrinsics, c.mount);
  } catch (const std::invalid_argument& e) {
    r.fail(Reader::keyOf(camera, perception.IsDefined() ? "perception" : "backend"), "camera", e.what());
  }
}

// obstacles: depth: the camera section. Every value is checked here with its key and line
// (the perception library's own validation runs last, as a backstop for a rule added there).
void readCamera(const Reader& r, const YAML::Node& root, DaemonConfig& config) {
  const YAML::Node camera =
      r.section(root, "camera", "camera", {"backend", "uri", "intrinsics", "mount", "sim_noise_mm_per_m2", "perception"});
  if (config.obstacles != "depth") return;  // checked for typos only
  if (!camera.IsDefined()) {
    r.fail(Reader::keyOf(root, "obstacles"), "camera",
           "missing (obstacles: depth needs camera.backend: sim, frames rendered from the simulated world, or openni2, "
           "the Xtion)");
  }
  CameraConfig& c = config.camera;
  const YAML::Node backend = r.required(camera, "backend", "camera.backend", "sim or openni2");
  c.backend = r.string(backend, "camera.backend", "sim or openni2");
  if (c.backend != "sim" && c.backend != "openni2") {
    r.fail(backend, "camera.backend",
           "expected sim (frames rendered from the simulated world) or openni2 (the Xtion), got " + describe(backend));
  }
  if (const YAML::Node n = camera["uri"]; n.IsDefined()) {
    c.uri = n.IsNull() ? std::string() : r.string(n, "camera.uri", "an OpenNI2 device URI, or \"\" for any device");
  }

  if (const YAML::Node k = r.section(camera, "intrinsics", "camera.intrinsics", {"fx", "fy", "cx", "cy"}); k.IsDefined()) {
    if (const YAML::Node n = k["fx"]; n.IsDefined()) c.intrinsics.fx = r.above(n, "camera.intrinsics.fx", 0.0, "must be > 0 pixels");
    if (const YAML::Node n = k["fy"]; n.IsDefined()) c.intrinsics.fy = r.above(n, "camera.intrinsics.fy", 0.0, "must be > 0 pixels");
    auto centre = [&](const char* key, double size, double& out) {
      const YAML::Node n = k[key];
      if (!n.IsDefined()) return;
      const std::string where = std::string("camera.intrinsics.") + key;
      out = r.finite(n, where);
      if (!(out >= 0.0 && out < size)) r.fail(n, where, "must be inside the image, in [0, " + number(size) + ") pixels, got " + n.Scalar());
    };
    centre("cx", hal::DepthFrame::kWidth, c.intrinsics.cx);
    centre("cy", hal::DepthFrame::kHeight, c.intrinsics.cy);
  }

  if (const YAML::Node m = r.section(camera, "mount", "camera.mount", {"x", "y", "z", "roll", "pitch", "yaw"}); m.IsDefined()) {
    auto metres = [&](const char* key, double& out) {
      if (const YAML::Node n = m[key]; n.IsDefined()) out = r.finite(n, std::string("camera.mount.") + key);
    };
    metres("x", c.mount.x);
    metres("y", c.mount.y);
    if (const YAML::Node n = m["z"]; n.IsDefined()) c.mount.z = r.above(n, "camera.mount.z", 0.0, "must be > 0 m (above the floor)");
    // Radians: a value beyond pi is most likely degrees.
    auto angle = [&](const char* key, double& out) {
      const YAML::Node n = m[key];
      if (!n.IsDefined()) return;
      const std::string where = std::string("camera.mount.") + key;
      out = r.finite(n, where);
      if (!(std::abs(out) <= kPi)) r.fail(n, where, "must be in [-pi, pi] rad (degrees? 17 deg is 0.297 rad), got " + n.Scalar());
    };
    angle("roll", c.mount.roll);
    angle("pitch", c.mount.pitch);
    angle("yaw", c.mount.yaw);
  }

  if (const YAML::Node n = camera["sim_noise_mm_per_m2"]; n.IsDefined()) {
    c.sim_noise_mm_per_m2 = r.finite(n, "camera.sim_noise_mm_per_m2");
    if (c.sim_noise_mm_per_m2 < 0.0) r.fail(n, "camera.sim_noise_mm_per_m2", "must be >= 0 (0: exact depths), got " + n.Scalar());
  }

  readPerception(r, camera, c);
}

void readSim(const Reader& r, const YAML::Node& root, DaemonConfig& config) {
  const YAML::Node sim = r.section(root, "sim", "sim", {"start", "movers", "mover_speed", "mover_radius", "seed", "sensor_range_m"});
  // The simulated obstacles arrive at the perception rate, like a depth camera's frames.
  config.sim.obstacle_rate_hz = config.perception_hz;
  // obstacles: depth with camera.backend: sim renders the simulated world's movers too.
  const bool sim_camera = config.obstacles == "depth" && config.camera.backend == "sim";
  // A real base without simulated obstacles ignores the section (it is still checked for typos).
  if (config.hal != "sim" && config.obstacles != "sim" && !sim_camera) return;
  // With a real base the simulated world only moves its movers (the simulated camera): its
  // own robot stands at sim.start, where the movers' walks keep away from.
  config.sim.movers_only = config.hal != "sim";
  if (!sim.IsDefined()) {
    if (config.hal == "sim") {
      r.fail(Reader::keyOf(root, "hal"), "sim", "missing (hal: sim needs at least sim.start: [x, y, theta], free in the map)");
    }
    if (sim_camera) {
      r.fail(Reader::keyOf(root, "camera"), "sim",
             "missing (camera.backend: sim renders the simulated world: it needs at least sim.start: [x, y, theta], free "
             "in the map, where that world is anchored; or camera.backend: openni2)");
    }
    r.fail(Reader::keyOf(root, "obstacles"), "sim",
           "missing (obstacles: sim needs at least sim.start: [x, y, theta], free in the map, where the simulated world "
           "is anchored; or obstacles: none)");
  }

  const YAML::Node start = r.required(sim, "start", "sim.start", "the simulated robot's start pose [x, y, theta], free in the map");
  const auto s = r.triple(start, "sim.start");
  config.sim.start = Pose2{s[0], s[1], s[2]};
  // The simulated robot must not begin in collision: its whole footprint is checked, as the
  // simulator would otherwise refuse to start (or start stuck) with a vaguer message.
  Polygon body;
  for (const Vec2& p : config.robot.footprint) body.push_back(config.sim.start.transform(p));
  const std::string at = "[" + number(s[0]) + ", " + number(s[1]) + ", " + number(s[2]) + "]";
  if (const auto& bounds = config.map.bounds) {
    for (const Vec2& p : body) {
      if (!(p.x() > bounds->min.x() && p.x() < bounds->max.x() && p.y() > bounds->min.y() && p.y() < bounds->max.y())) {
        r.fail(start, "sim.start", "the robot's footprint reaches outside the map's bounds, got " + at);
      }
    }
  }
  const Box body_box = boundingBox(body);
  for (std::size_t i = 0; i < config.map.obstacles.size(); ++i) {
    const Polygon& obstacle = config.map.obstacles[i];
    if (body_box.overlaps(boundingBox(obstacle)) && polygonsOverlap(body, obstacle)) {
      r.fail(start, "sim.start", "the robot's footprint overlaps obstacle " + std::to_string(i) + " of the map " +
                                     config.map_file.string() + ", got " + at);
    }
  }

  if (const YAML::Node n = sim["movers"]; n.IsDefined()) {
    config.sim.movers = static_cast<int>(r.integer(n, "sim.movers", 0, static_cast<long long>(hal::ObstacleFrame::kMaxObstacles)));
  }
  if (const YAML::Node n = sim["mover_speed"]; n.IsDefined()) {
    config.sim.mover_speed = r.finite(n, "sim.mover_speed");
    if (config.sim.mover_speed < 0.0) r.fail(n, "sim.mover_speed", "must be >= 0 m/s, got " + n.Scalar());
  }
  if (const YAML::Node n = sim["mover_radius"]; n.IsDefined()) {
    config.sim.mover_radius = r.above(n, "sim.mover_radius", 0.0, "must be > 0 m");
  }
  if (const YAML::Node n = sim["seed"]; n.IsDefined()) {
    std::optional<std::uint64_t> seed;
    if (n.IsScalar()) {
      const std::string& t = n.Scalar();
      std::uint64_t v = 0;
      const auto res = std::from_chars(t.data(), t.data() + t.size(), v);
      if (!t.empty() && res.ec == std::errc{} && res.ptr == t.data() + t.size()) seed = v;
    }
    if (!seed) r.fail(n, "sim.seed", "must be an integer >= 0, got " + (n.IsScalar() ? n.Scalar() : describe(n)));
    config.sim.seed = *seed;
  }
  if (const YAML::Node n = sim["sensor_range_m"]; n.IsDefined()) {
    config.sim.sensor_range_m = r.above(n, "sim.sensor_range_m", 0.0, "must be > 0 m");
  }
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

void readSocketCan(const Reader& r, const YAML::Node& root, const fs::path& base, DaemonConfig& config) {
  const YAML::Node can = r.section(root, "socketcan", "socketcan", {"interface", "profile"});
  if (config.hal != "socketcan") return;  // checked for typos only
  if (!can.IsDefined()) {
    r.fail(Reader::keyOf(root, "hal"), "socketcan",
           "missing (hal: socketcan needs socketcan.interface: can0 or unix:/path, and socketcan.profile: a "
           "staa-can-profile/1 file such as can/hsr_base.yaml)");
  }
  const YAML::Node iface = r.required(can, "interface", "socketcan.interface", "can0, or unix:/path for a SOCK_SEQPACKET socket");
  const std::string text = r.string(iface, "socketcan.interface", "a CAN interface name such as can0, or unix:/path");
  constexpr std::string_view kUnix = "unix:";
  if (text.rfind(kUnix, 0) == 0) {
    const std::string rest = text.substr(kUnix.size());
    if (rest.empty()) r.fail(iface, "socketcan.interface", "unix: needs a socket path after it, got " + describe(iface));
    const fs::path p(rest);
    const std::string path = (p.is_absolute() ? p : base / p).lexically_normal().string();
    if (path.size() > kMaxSocketPathBytes) {
      r.fail(iface, "socketcan.interface", "the socket path is longer than " + std::to_string(kMaxSocketPathBytes) +
                                               " bytes (the limit of a Unix socket address), got " +
                                               std::to_string(path.size()) + " bytes: " + path);
    }
    config.socketcan.interface = std::string(kUnix) + path;
  } else {
    if (!validInterfaceName(text)) {
      r.fail(iface, "socketcan.interface",
             "expected a CAN interface name (1..15 characters, no '/', ':' or spaces, e.g. can0) or unix:/path, got " +
                 describe(iface));
    }
    config.socketcan.interface = text;
  }

  const YAML::Node profile = r.required(can, "profile", "socketcan.profile", "a staa-can-profile/1 file such as can/hsr_base.yaml");
  config.socketcan.profile_file = r.path(profile, "socketcan.profile", base);
  r.existingFile(profile, "socketcan.profile", config.socketcan.profile_file);
  try {
    config.socketcan.profile = hal::loadCanProfile(config.socketcan.profile_file);
  } catch (const std::exception& e) {  // CanProfileError, or an I/O error
    r.fail(profile, "socketcan.profile", e.what());
  }
}

void readDebug(const Reader& r, const YAML::Node& root, DaemonConfig& config) {
  const YAML::Node debug = r.section(root, "debug", "debug", {"faults"});
  if (!debug.IsDefined()) return;
  if (const YAML::Node n = debug["faults"]; n.IsDefined()) {
    bool on = false;
    if (!n.IsScalar() || !YAML::convert<bool>::decode(n, on)) {
      r.fail(n, "debug.faults", "expected true or false, got " + describe(n));
    }
    config.debug_faults = on;
  }
}

void readThreads(const Reader& r, const YAML::Node& root, DaemonConfig& config) {
  const YAML::Node threads = r.section(root, "threads", "threads", {"control", "base", "perception"});
  if (!threads.IsDefined()) return;
  auto thread = [&](const char* key, rt::ThreadSpec& spec) {
    const std::string where = std::string("threads.") + key;
    const YAML::Node t = r.section(threads, key, where, {"priority", "cpu"});
    if (!t.IsDefined()) return;
    if (const YAML::Node p = t["priority"]; p.IsDefined()) {
      spec.priority = static_cast<int>(r.integer(p, where + ".priority", 0, kMaxPriority, " (0: normal scheduling, 1..99: SCHED_FIFO)"));
    }
    if (const YAML::Node c = t["cpu"]; c.IsDefined()) {
      spec.cpu = static_cast<int>(r.integer(c, where + ".cpu", -1, kMaxCpu, " (-1: any CPU)"));
    }
  };
  thread("control", config.control_thread);
  thread("base", config.base_thread);
  thread("perception", config.perception_thread);
}

void readSocket(const Reader& r, const YAML::Node& root, const fs::path& base, DaemonConfig& config) {
  const YAML::Node socket = r.section(root, "socket", "socket", {"path", "mode"});
  if (!socket.IsDefined()) return;
  if (const YAML::Node p = socket["path"]; p.IsDefined()) {
    const fs::path path = r.path(p, "socket.path", base);
    config.socket_path = path.string();
    if (config.socket_path.size() > kMaxSocketPathBytes) {
      r.fail(p, "socket.path", "longer than " + std::to_string(kMaxSocketPathBytes) + " bytes (the limit of a Unix socket address), got " +
                                   std::to_string(config.socket_path.size()) + " bytes: " + config.socket_path);
    }
  }
  if (const YAML::Node m = socket["mode"]; m.IsDefined()) {
    // Permission bits as people write them for chmod: octal with a leading 0 ("0660",
    // also YAML 1.2's "0o660"). A plain integer without the 0 is taken as decimal (432 =
    // 0660), which the range check turns into an error for a forgotten 0 ("660" > 0777).
    std::optional<unsigned> mode;
    if (m.IsScalar()) {
      std::string_view t = m.Scalar();
      int radix = 10;
      if (t.size() > 2 && t[0] == '0' && (t[1] == 'o' || t[1] == 'O')) {
        t.remove_prefix(2);
        radix = 8;
      } else if (t.size() > 1 && t[0] == '0') {
        radix = 8;
      }
      unsigned v = 0;
      const auto res = std::from_chars(t.data(), t.data() + t.size(), v, radix);
      if (!t.empty() && res.ec == std::errc{} && res.ptr == t.data() + t.size() && v <= 0777u) mode = v;
    }
    if (!mode) {
      r.fail(m, "socket.mode", "expected permission bits as an octal string like \"0660\" (0000..0777), got " +
                                   (m.IsScalar() ? m.Scalar() : describe(m)));
    }
    config.socket_mode = *mode;
  }
}

void readLimits(const Reader& r, const YAML::Node& root, DaemonConfig& config) {
  const YAML::Node limits = r.section(root, "limits", "limits", {"odometry_timeout_s", "obstacles_timeout_s"});
  if (limits.IsDefined()) {
    if (const YAML::Node n = limits["odometry_timeout_s"]; n.IsDefined()) {
      config.odometry_timeout_s = r.above(n, "limits.odometry_timeout_s", 0.0, "must be > 0 s");
    }
    if (const YAML::Node n = limits["obstacles_timeout_s"]; n.IsDefined()) {
      config.obstacles_timeout_s = r.above(n, "limits.obstacles_timeout_s", 0.0, "must be > 0 s");
    }
  }
  // A timeout shorter than its input's period would hold the robot in a fault forever.
  auto longerThanPeriod = [&](const char* key, double timeout, double hz, const char* rate) {
    const double period = 1.0 / hz;
    if (!(timeout > period)) {
      const YAML::Node n = limits.IsDefined() ? limits[key] : YAML::Node();
      r.fail(n.IsDefined() ? n : root, std::string("limits.") + key,
             "must be longer than one period of its input (" + number(period) + " s at rates." + rate + " " + number(hz) + "), got " +
                 number(timeout));
    }
  };
  longerThanPeriod("odometry_timeout_s", config.odometry_timeout_s, config.base_hz, "base_hz");
  longerThanPeriod("obstacles_timeout_s", config.obstacles_timeout_s, config.perception_hz, "perception_hz");
}

void readGoal(const Reader& r, const YAML::Node& root, DaemonConfig& config) {
  const YAML::Node goal = r.section(root, "goal", "goal", {"tolerance_m", "heading_tolerance"});
  if (goal.IsDefined()) {
    if (const YAML::Node n = goal["tolerance_m"]; n.IsDefined()) {
      config.control.goal_tolerance_m = r.above(n, "goal.tolerance_m", 0.0, "must be > 0 m");
    }
    if (const YAML::Node n = goal["heading_tolerance"]; n.IsDefined()) {
      config.control.goal_heading_tolerance = r.above(n, "goal.heading_tolerance", 0.0, "must be > 0 rad (> pi ignores the heading)");
    }
  }
}

void readTelemetry(const Reader& r, const YAML::Node& root, const fs::path& base, DaemonConfig& config) {
  const YAML::Node telemetry = r.section(root, "telemetry", "telemetry", {"path", "records", "svg"});
  if (!telemetry.IsDefined()) return;
  // A file path, or "" (or nothing) for off.
  auto optionalPath = [&](const char* key, fs::path& out) {
    const YAML::Node p = telemetry[key];
    if (!p.IsDefined()) return;
    const std::string where = std::string("telemetry.") + key;
    const std::string text = p.IsNull() ? std::string() : r.string(p, where, "a file path, or \"\" for off");
    out = text.empty() ? fs::path() : r.path(p, where, base);
  };
  optionalPath("path", config.telemetry_path);
  optionalPath("svg", config.svg_path);
  if (const YAML::Node n = telemetry["records"]; n.IsDefined()) {
    config.telemetry_records = static_cast<std::size_t>(r.integer(n, "telemetry.records", kMinTelemetryRecords, kMaxTelemetryRecords));
  }
}

void readMemory(const Reader& r, const YAML::Node& root, DaemonConfig& config) {
  const YAML::Node memory = r.section(root, "memory", "memory", {"heap_prefault_mb", "stack_prefault_kb"});
  if (!memory.IsDefined()) return;
  if (const YAML::Node n = memory["heap_prefault_mb"]; n.IsDefined()) {
    config.heap_prefault_bytes = static_cast<std::size_t>(r.integer(n, "memory.heap_prefault_mb", 0, kMaxHeapPrefaultMb)) << 20;
  }
  if (const YAML::Node n = memory["stack_prefault_kb"]; n.IsDefined()) {
    config.stack_prefault_bytes =
        static_cast<std::size_t>(r.integer(n, "memory.stack_prefault_kb", 0, kMaxStackPrefaultKb, " (inside the 8 MiB default stack)")) << 10;
  }
}

}  // namespace

DaemonConfig parseDaemonConfig(const std::string& yaml_text, const fs::path& source,
                               const std::optional<std::string>& hal_override) {
  const Reader r(source.string());
  // Anchored absolutely: the daemon may change its working directory after loading.
  std::error_code ec;
  const fs::path absolute = fs::absolute(source, ec);
  const fs::path base = (ec ? source : absolute).parent_path();
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    std::string msg = source.string();
    if (e.mark.line >= 0) msg += ":" + std::to_string(e.mark.line + 1);
    throw ConfigError(msg + ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) {
    throw ConfigError(source.string() + ": expected a mapping with format: " + std::string(kFormat) + ", robot, map, ..., got " +
                      describe(root));
  }
  r.onlyKeys(root, "", {"format", "robot", "map", "hal", "sim", "socketcan", "obstacles", "camera", "rates", "budget", "threads",
                        "socket", "limits", "goal", "telemetry", "memory", "debug"});
  const YAML::Node format = root["format"];
  if (!Reader::present(format)) r.fail(root, "format", "missing (expected " + std::string(kFormat) + ")");
  if (!format.IsScalar() || format.Scalar() != kFormat) {
    r.fail(format, "format", "unknown format, expected " + std::string(kFormat) + ", got " + describe(format));
  }

  DaemonConfig config;
  config.file = source;
  if (const YAML::Node hal = root["hal"]; hal.IsDefined()) {
    config.hal = r.string(hal, "hal", "sim or socketcan");
    if (config.hal != "sim" && config.hal != "socketcan") r.fail(hal, "hal", "expected sim or socketcan, got " + describe(hal));
  }
  if (hal_override) {
    if (*hal_override != "sim" && *hal_override != "socketcan") {
      throw ConfigError("--hal: expected sim or socketcan, got '" + *hal_override + "'");
    }
    config.hal = *hal_override;
  }
  readRobotAndMap(r, root, base, config);
  readRates(r, root, config);
  readBudget(r, root, config);
  readObstacles(r, root, config);
  readCamera(r, root, config);
  readSim(r, root, config);
  readSocketCan(r, root, base, config);
  readThreads(r, root, config);
  readSocket(r, root, base, config);
  readLimits(r, root, config);
  readGoal(r, root, config);
  readTelemetry(r, root, base, config);
  readMemory(r, root, config);
  readDebug(r, root, config);
  config.control.rate_hz = config.control_hz;
  return config;
}

DaemonConfig loadDaemonConfig(const fs::path& file, const std::optional<std::string>& hal) {
  std::error_code ec;
  const auto status = fs::status(file, ec);
  if (!fs::exists(status)) throw ConfigError(file.string() + ": config file not found");
  if (fs::is_directory(status)) throw ConfigError(file.string() + ": is a directory, not a config file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(file.string() + ": cannot open the config file: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(file.string() + ": read error");
  return parseDaemonConfig(text.str(), file, hal);
}

}  // namespace staa::staad
