#include "world/scenario.hpp"

#include "io/yaml_support.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "world/footprint.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <sstream>
#include <string_view>

namespace staa {
namespace {

namespace fs = std::filesystem;

constexpr std::string_view kFormat = "staa-scenario/1";

using yaml_support::describe;
using yaml_support::lineOf;
std::string number(double v) { return yaml_support::formatNumber(v); }
std::string point(const Vec2& p) { return yaml_support::formatPoint(p); }





std::string indexed(const std::string& list, std::size_t i) { return list + "[" + std::to_string(i) + "]"; }

class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw ScenarioError(source_ + ": " + key + ": " + what);
  }

  void onlyKeys(const YAML::Node& map, const std::string& where, std::initializer_list<std::string_view> keys) const {
    for (const auto& kv : map) {
      const std::string key = kv.first.Scalar();
      if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
        std::string expected;
        for (std::string_view k : keys) expected += (expected.empty() ? "" : ", ") + std::string(k);
        fail(where.empty() ? key : where + "." + key, "unknown key (expected " + expected + ")" + lineOf(kv.first));
      }
    }
  }

  YAML::Node required(const YAML::Node& map, const char* key, const std::string& where) const {
    const YAML::Node n = map[key];
    if (!n.IsDefined() || n.IsNull()) fail(where, "missing" + lineOf(map));
    return n;
  }

  double finiteNumber(const YAML::Node& node, const std::string& where) const {
    std::optional<double> v;
    if (node.IsScalar()) {
      try {
        v = node.as<double>();
      } catch (const YAML::Exception&) {
      }
    }
    if (!v) fail(where, "expected a number, got " + describe(node) + lineOf(node));
    if (!std::isfinite(*v)) fail(where, "must be finite, got " + node.Scalar() + lineOf(node));
    return *v;
  }

  // A list of exactly n finite numbers.
  std::vector<double> numbers(const YAML::Node& node, std::size_t n, const std::string& where, const char* shape) const {
    if (!node.IsSequence() || node.size() != n) fail(where, std::string("expected ") + shape + ", got " + describe(node) + lineOf(node));
    std::vector<double> out;
    for (std::size_t k = 0; k < n; ++k) out.push_back(finiteNumber(node[k], indexed(where, k)));
    return out;
  }

  Vec2 pair(const YAML::Node& node, const std::string& where) const {
    const auto v = numbers(node, 2, where, "[x, y]");
    return {v[0], v[1]};
  }

  Pose2 pose(const YAML::Node& node, const std::string& where) const {
    const auto v = numbers(node, 3, where, "[x, y, theta]");
    return {v[0], v[1], v[2]};
  }

  Polygon polygon(const YAML::Node& node, const std::string& where) const {
    if (!node.IsSequence()) fail(where, "expected a list of [x, y] vertices, got " + describe(node) + lineOf(node));
    Polygon poly;
    for (std::size_t k = 0; k < node.size(); ++k) poly.push_back(pair(node[k], indexed(where, k)));
    const std::size_t n = poly.size();
    if (n < 3) fail(where, "has " + std::to_string(n) + " vertices, needs at least 3" + lineOf(node));
    for (std::size_t i = 0; i < n; ++i) {
      if (poly[i] == poly[(i + 1) % n]) {
        fail(where, "vertex " + std::to_string((i + 1) % n) + " repeats vertex " + std::to_string(i) + " " + point(poly[i]) + lineOf(node));
      }
    }
    if (const auto e = findSelfIntersection(poly)) {
      fail(where, "self-intersecting (edges " + std::to_string(e->first) + " and " + std::to_string(e->second) + " meet)" + lineOf(node));
    }
    return poly;
  }

  fs::path path(const YAML::Node& node, const std::string& where, const fs::path& base) const {
    if (!node.IsScalar() || node.Scalar().empty()) fail(where, "expected a file path, got " + describe(node) + lineOf(node));
    const fs::path p(node.Scalar());
    return p.is_absolute() ? p : base / p;
  }

 private:
  std::string source_;
};

Mover readMover(const Reader& r, const YAML::Node& node, const std::string& where) {
  if (!node.IsMap()) r.fail(where, "expected a mapping {polygon, waypoints, speed}, got " + describe(node) + lineOf(node));
  r.onlyKeys(node, where, {"polygon", "waypoints", "speed"});
  Mover m;
  m.polygon = r.polygon(r.required(node, "polygon", where + ".polygon"), where + ".polygon");
  const YAML::Node wps = r.required(node, "waypoints", where + ".waypoints");
  if (!wps.IsSequence() || wps.size() == 0) {
    r.fail(where + ".waypoints", "expected a list of at least one [x, y] point, got " + describe(wps) + lineOf(wps));
  }
  for (std::size_t k = 0; k < wps.size(); ++k) m.waypoints.push_back(r.pair(wps[k], indexed(where + ".waypoints", k)));
  const YAML::Node speed = r.required(node, "speed", where + ".speed");
  m.speed = r.finiteNumber(speed, where + ".speed");
  if (m.speed < 0.0) r.fail(where + ".speed", "must be >= 0, got " + number(m.speed) + lineOf(speed));
  return m;
}

// Where a point lies against the map: the index of an obstacle that holds it (boundary
// included), -1 when outside the bounds, nullopt when free.
std::optional<long> blockedAt(const PolygonMap& map, const Vec2& p) {
  if (map.bounds && !(p.x() > map.bounds->min.x() && p.x() < map.bounds->max.x() && p.y() > map.bounds->min.y() &&
                      p.y() < map.bounds->max.y())) {
    return -1;
  }
  for (std::size_t i = 0; i < map.obstacles.size(); ++i) {
    if (locatePoint(p, map.obstacles[i]) != Containment::kOutside) return static_cast<long>(i);
  }
  return std::nullopt;
}

}  // namespace

Scenario parseScenario(const std::string& yaml_text, const fs::path& source) {
  const Reader r(source.string());
  const fs::path base = source.parent_path();
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ScenarioError(source.string() + ": not valid YAML: " + e.what());
  }
  if (!root.IsMap()) throw ScenarioError(source.string() + ": expected a mapping with format, map, robot, movers, got " + describe(root));
  r.onlyKeys(root, "", {"format", "name", "map", "robot", "movers"});
  const YAML::Node format = root["format"];
  if (!format.IsScalar() || format.Scalar() != kFormat) {
    r.fail("format", "unknown format " + describe(format) + ", expected " + std::string(kFormat) + lineOf(format));
  }

  Scenario sc;
  sc.name = source.stem().string();
  if (const YAML::Node name = root["name"]; name.IsDefined() && !name.IsNull()) {
    if (!name.IsScalar()) r.fail("name", "expected a string, got " + describe(name) + lineOf(name));
    sc.name = name.Scalar();
  }
  sc.map_path = r.path(r.required(root, "map", "map"), "map", base);
  try {
    sc.map = loadPolygonMap(sc.map_path);
  } catch (const MapError& e) {
    r.fail("map", e.what());
  }

  const YAML::Node robot = r.required(root, "robot", "robot");
  if (!robot.IsMap()) r.fail("robot", "expected a mapping {profile, start, goal}, got " + describe(robot) + lineOf(robot));
  r.onlyKeys(robot, "robot", {"profile", "start", "goal"});
  sc.profile_path = r.path(r.required(robot, "profile", "robot.profile"), "robot.profile", base);
  try {
    sc.robot = loadRobotProfile(sc.profile_path);
  } catch (const ProfileError& e) {
    r.fail("robot.profile", e.what());
  }
  const YAML::Node start = r.required(robot, "start", "robot.start");
  const YAML::Node goal = r.required(robot, "goal", "robot.goal");
  sc.start = r.pose(start, "robot.start");
  sc.goal = r.pose(goal, "robot.goal");

  // The robot must not begin in collision: its whole footprint, not just its origin, is free.
  const Polygon body = footprintAt(sc.robot.footprint, sc.start);
  if (sc.map.bounds) {
    for (const Vec2& p : body) {
      if (!(p.x() > sc.map.bounds->min.x() && p.x() < sc.map.bounds->max.x() && p.y() > sc.map.bounds->min.y() &&
            p.y() < sc.map.bounds->max.y())) {
        r.fail("robot.start", "the robot's footprint at " + point(sc.start.position()) + " reaches outside the map bounds" + lineOf(start));
      }
    }
  }
  const Box body_box = boundingBox(body);
  for (std::size_t i = 0; i < sc.map.obstacles.size(); ++i) {
    if (body_box.overlaps(boundingBox(sc.map.obstacles[i])) && polygonsOverlap(body, sc.map.obstacles[i])) {
      r.fail("robot.start", "the robot's footprint at " + point(sc.start.position()) + ", theta " + number(sc.start.theta) +
                                " overlaps obstacle " + std::to_string(i) + " of the map" + lineOf(start));
    }
  }
  if (const auto hit = blockedAt(sc.map, sc.goal.position())) {
    r.fail("robot.goal", point(sc.goal.position()) +
                             (*hit < 0 ? std::string(" is outside the map bounds") : " is inside obstacle " + std::to_string(*hit) + " of the map") +
                             lineOf(goal));
  }

  const YAML::Node movers = root["movers"];
  if (movers.IsDefined() && !movers.IsNull()) {
    if (!movers.IsSequence()) r.fail("movers", "expected a list of movers, got " + describe(movers) + lineOf(movers));
    for (std::size_t i = 0; i < movers.size(); ++i) sc.movers.push_back(readMover(r, movers[i], indexed("movers", i)));
  }
  return sc;
}

Scenario loadScenario(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ScenarioError(path.string() + ": cannot open scenario");
  std::ostringstream text;
  text << in.rdbuf();
  return parseScenario(text.str(), path);
}

}  // namespace staa
