#pragma once
// A robot profile (`staa-robot/1`, docs/ARCHITECTURE.md section 6): footprint and limits.

#include "geometry/types.hpp"
#include "io/config_rules.hpp"

#include <algorithm>
#include <filesystem>
#include <string>

namespace staa {

struct MotionLimits {
  double v_max = 2.0;   // m/s forward
  double v_min = -1.0;  // m/s (negative: backward)
  double w_max = 3.0;   // rad/s, symmetric
  double a_max = 2.0;   // m/s^2, symmetric (a_min = -a_max)
  double b_max = 6.0;   // rad/s^2, symmetric
};

struct RobotProfile {
  std::string name;
  Polygon footprint;  // robot frame, metres, counter-clockwise after loading
  MotionLimits limits;

  // Radius of the smallest circle about the robot's origin that holds the footprint: the
  // least inflation of the map for the global path.
  double circumradius() const;
  // Radius of the largest circle about the robot's origin inside the footprint (the nearest
  // edge's distance): an obstacle closer to the origin than this touches the robot in every
  // heading, so no passage narrower than twice it can be driven (issue 16).
  double inscribedRadius() const;
  // The growth of the map a route for this footprint may use (issue 16, the passage map):
  // the inscribed radius plus `margin`, at most the circumradius (a round robot: its M').
  double passageRadius(double margin = kDefaultPassageMargin) const {
    return std::min(inscribedRadius() + margin, circumradius());
  }
  // The default margin: a 0.5 m wide robot's route passes slots from about 0.54 m.
  static constexpr double kDefaultPassageMargin = 0.01;
};

class ProfileError : public io::ConfigError {
 public:
  using io::ConfigError::ConfigError;
};

// Errors name the file, the line, the key and the value (e.g. "hsr.yaml:9: limits.v_max:
// must be > 0, got -1"; io/config_reader.hpp).
RobotProfile parseRobotProfile(const std::string& yaml_text, const std::string& source);
RobotProfile loadRobotProfile(const std::filesystem::path& path);

// The paper's simulated agent (docs/paper-worlds.md, "The agent"), also in config/robots/paper-agent.yaml.
RobotProfile paperAgentProfile();

}  // namespace staa
