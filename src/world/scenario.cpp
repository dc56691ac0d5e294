#include "world/scenario.hpp"

#include "io/config_reader.hpp"
#include "io/yaml_support.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "world/footprint.hpp"

#include <optional>
#include <string_view>

namespace staa {
namespace {

namespace fs = std::filesystem;

constexpr std::string_view kFormat = "staa-scenario/1";

std::string number(double v) { return yaml_support::formatNumber(v); }
std::string point(const Vec2& p) { return yaml_support::formatPoint(p); }

Mover readMover(const io::ConfigValue& node) {
  node.mapping({"polygon", "waypoints", "speed"});
  Mover m;
  m.polygon = node.required("polygon").polygon();
  const io::ConfigValue wps = node.required("waypoints");
  wps.list("a list of at least one [x, y] point", 1);
  for (std::size_t k = 0; k < wps.size(); ++k) m.waypoints.push_back(wps[k].point());
  m.speed = node.required("speed").number(io::Range::atLeast(0.0));
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
  return io::readAs<ScenarioError>(source.string(), [&] {
    const io::ConfigDocument doc = io::ConfigDocument::parse(yaml_text, source.string());
    const io::ConfigValue& root = doc.root(kFormat, {"format", "name", "map", "robot", "movers"});
    Scenario sc;
    sc.name = source.stem().string();
    if (const io::ConfigValue name = root.get("name"); name.present()) sc.name = name.string("a string");

    const io::ConfigValue map = root.required("map");
    sc.map_path = map.path();
    try {
      sc.map = loadPolygonMap(sc.map_path);
    } catch (const MapError& e) {
      map.fail(e.what());
    }

    const io::ConfigValue robot = root.required("robot");
    robot.mapping({"profile", "start", "goal"});
    const io::ConfigValue profile = robot.required("profile");
    sc.profile_path = profile.path();
    try {
      sc.robot = loadRobotProfile(sc.profile_path);
    } catch (const ProfileError& e) {
      profile.fail(e.what());
    }
    const io::ConfigValue start = robot.required("start");
    const io::ConfigValue goal = robot.required("goal");
    sc.start = start.pose();
    sc.goal = goal.pose();

    // The robot must not begin in collision: its whole footprint, not just its origin, is free.
    const Polygon body = footprintAt(sc.robot.footprint, sc.start);
    if (sc.map.bounds) {
      for (const Vec2& p : body) {
        if (!(p.x() > sc.map.bounds->min.x() && p.x() < sc.map.bounds->max.x() && p.y() > sc.map.bounds->min.y() &&
              p.y() < sc.map.bounds->max.y())) {
          start.fail("the robot's footprint at " + point(sc.start.position()) + " reaches outside the map bounds");
        }
      }
    }
    const Box body_box = boundingBox(body);
    for (std::size_t i = 0; i < sc.map.obstacles.size(); ++i) {
      if (body_box.overlaps(boundingBox(sc.map.obstacles[i])) && polygonsOverlap(body, sc.map.obstacles[i])) {
        start.fail("the robot's footprint at " + point(sc.start.position()) + ", theta " + number(sc.start.theta) +
                   " overlaps obstacle " + std::to_string(i) + " of the map");
      }
    }
    if (const auto hit = blockedAt(sc.map, sc.goal.position())) {
      goal.fail(point(sc.goal.position()) +
                (*hit < 0 ? std::string(" is outside the map bounds") : " is inside obstacle " + std::to_string(*hit) + " of the map"));
    }

    if (const io::ConfigValue movers = root.get("movers"); movers.present()) {
      movers.list("a list of movers");
      for (std::size_t i = 0; i < movers.size(); ++i) sc.movers.push_back(readMover(movers[i]));
    }
    return sc;
  });
}

Scenario loadScenario(const fs::path& path) {
  return io::readAs<ScenarioError>(path.string(), [&] { return parseScenario(io::ConfigDocument::readFile(path, "scenario"), path); });
}

}  // namespace staa
