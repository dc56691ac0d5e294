#pragma once
// A simulator scenario (`staa-scenario/1`, docs/ARCHITECTURE.md section 6): one robot with a start
// and a goal in a polygon map, among scripted moving obstacles ("movers") that walk their
// waypoints back and forth at a constant speed, oblivious of the robot.

#include "robot/robot_profile.hpp"
#include "geometry/types.hpp"
#include "io/config_rules.hpp"
#include "map/polygon_map.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace staa {

struct Mover {
  Polygon polygon;              // around the mover's origin; translated, never rotated
  std::vector<Vec2> waypoints;  // >= 1; one waypoint (or speed 0) stands still
  double speed = 0.0;           // m/s along the waypoint polyline, >= 0
};

struct Scenario {
  std::string name;                    // optional `name:`, else the file's stem
  std::filesystem::path map_path;      // resolved against the scenario file's folder
  std::filesystem::path profile_path;  // likewise
  PolygonMap map;
  RobotProfile robot;
  Pose2 start;
  Pose2 goal;
  std::vector<Mover> movers;
};

// Every problem with a scenario, including those of the map and profile it names, is a
// ScenarioError: what() names the scenario file, the key (e.g. "movers[1].speed") and the
// offending value; for a bad map or profile it carries the MapError/ProfileError message
// (which names that file) after the scenario's own "file: map:" prefix. Tools map it to
// exit code 2.
class ScenarioError : public io::ConfigError {
 public:
  using io::ConfigError::ConfigError;
};

// Parses YAML text; `source` is the scenario's path: relative `map` and `robot.profile` paths
// are resolved against its folder, and it names the file in error messages.
// Checks: known format and keys; start and goal finite; the start's footprint free of the
// map's obstacles and inside its bounds; the goal point not inside (or on) an obstacle nor
// outside the bounds; movers with a simple polygon, >= 1 finite waypoint, finite speed >= 0.
Scenario parseScenario(const std::string& yaml_text, const std::filesystem::path& source);
Scenario loadScenario(const std::filesystem::path& path);

}  // namespace staa
