#pragma once
// A robot profile (`staa-robot/1`, docs/ARCHITECTURE.md section 6): footprint, limits, the
// body's height and, optionally, its depth camera.

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

// The depth camera on the robot (staa-sim --obstacles depth renders its frames): where it sits,
// what it sees and how it fails. Plain values: the simulator turns them into a camera model
// and a renderer (src/world), perception into its rays.
struct DepthCameraProfile {
  // Mount in the base frame (REP-103): position (m) and roll/pitch/yaw (rad), pitch > 0
  // looks down (hal/camera_model.hpp).
  double x = 0.0, y = 0.0, z = 1.0;
  double roll = 0.0, pitch = 0.3, yaw = 0.0;
  // Field of view (degrees, horizontal x vertical) of the 640 x 480 depth image.
  double fov_h_deg = 58.0, fov_v_deg = 45.0;
  // Depth readings from min_range_m to max_range_m (optical z); outside, no reading.
  double min_range_m = 0.5, max_range_m = 4.5;
  double rate_hz = 30.0;
  // Depth noise: sigma = noise_mm_per_m2 * depth^2 (depth in m).
  double noise_mm_per_m2 = 1.5;
  // Pixels without a reading: this fraction at random, and every surface seen at more than
  // grazing_deg from its normal (the projected pattern does not come back).
  double dropout = 0.02;
  double grazing_deg = 80.0;
  // Whole frames lost (the USB link), as a fraction.
  double frame_loss = 0.0;
  // From the exposure to the obstacles in the planner (s): whole frames at rate_hz, at most
  // kMaxLatencyFrames (the frames staa-sim's AgentCamera keeps in flight).
  double latency_s = 0.0;
  static constexpr int kMaxLatencyFrames = 7;
  // How far the mount may sit from the base centre (m): a camera on the robot (perception's
  // grid spans the range plus this offset).
  static constexpr double kMaxMountOffsetM = 10.0;
  // The head pans towards the direction of travel (where the robot will be look_ahead_m on,
  // experiment/agent_camera.hpp) within +-pan_max (rad) at up to pan_rate (rad/s); pan_max 0:
  // a fixed camera.
  double pan_max = 0.0;
  double pan_rate = 1.0;
  double look_ahead_m = 1.5;
  // The head sweeps this far (rad) to either side of the direction of travel and back, at
  // pan_rate: a wider view than the camera's, each side seen every 4 scan / pan_rate s. 0: none.
  double scan = 0.0;
};

// A planar laser scanner in the base (staa-sim --obstacles depth+scan scans with it beside the
// camera): the HSR-B has one in its base (`/hsrb/base_scan`). Plain values, as the camera's.
struct ScannerProfile {
  // Mount in the base frame: position (m), the scan plane's height (m), the yaw (rad) of the
  // middle of its sweep.
  double x = 0.0, y = 0.0, z = 0.2, yaw = 0.0;
  // The sweep (degrees, centred on the yaw) and its beams, both ends included.
  double fov_deg = 270.0;
  int beams = 1081;
  static constexpr int kMaxBeams = 2048;  // hal::LaserScan::kMaxBeams (static_assert in agent_camera.cpp)
  double min_range_m = 0.05, max_range_m = 20.0;
  double noise_m = 0.01;  // range noise, standard deviation
  double dropout = 0.0;   // fraction of the beams with no return
};

struct RobotProfile {
  std::string name;
  Polygon footprint;  // robot frame, metres, counter-clockwise after loading
  // How far a footprint vertex may lie from the robot's origin (m, each coordinate): a base,
  // not a building. Unbounded, coordinates near 1e307 overflow the footprint's area.
  static constexpr double kMaxFootprintM = 10.0;
  MotionLimits limits;
  // How tall the body is (m): other robots' depth cameras see the footprint as a prism this tall.
  double height_m = 1.0;
  bool has_camera = false;  // the profile has a `camera` section
  DepthCameraProfile camera;
  bool has_scanner = false;  // the profile has a `scanner` section
  ScannerProfile scanner;

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
// Its depth camera (not in the paper: an Xtion on a panning head, as config/robots/paper-agent.yaml says).
DepthCameraProfile paperAgentCamera();

}  // namespace staa
