#pragma once
// Scenes for the perception tests: the office map's south corridor (config/maps/office.yaml,
// 3 m wide between y = 3 and y = 6, doors into the rooms on both sides) with the HSR's
// profile, and the two camera mounts the tests use.

#include "robot/robot_profile.hpp"
#include "geometry/types.hpp"
#include "hal/depth_camera.hpp"
#include "map/polygon_map.hpp"
#include "shared_dir.hpp"
#include "world/scenario.hpp"
#include "world/sim_laser_scan.hpp"

#include <memory>

namespace staa::test {

inline const PolygonMap& officeMap() {
  static const PolygonMap map = loadPolygonMap(sourceDir() / "config/maps/office.yaml");
  return map;
}
inline const RobotProfile& hsrProfile() {
  static const RobotProfile robot = loadRobotProfile(sourceDir() / "config/robots/hsr.yaml");
  return robot;
}

// A level camera 1 m up on the base centre.
inline hal::CameraMount levelMount() { return hal::CameraMount{0.0, 0.0, 1.0, 0.0, 0.0, 0.0}; }
// The HSR's head: 1 m up, looking down at the floor ahead (pitch > 0 is down).
inline hal::CameraMount hsrHeadMount() { return hal::CameraMount{0.0, 0.0, 1.0, 0.0, 0.3, 0.0}; }

// The corridor, facing east along it from its middle.
inline const Pose2 kCorridorStart{4.5, 4.5, 0.0};

inline Polygon square(double half) { return {{-half, -half}, {half, -half}, {half, half}, {-half, half}}; }

// A box walking back and forth between two points (one point: standing still).
inline Mover boxMover(const Vec2& from, const Vec2& to, double speed, double half = 0.2) {
  return Mover{square(half), {from, to}, speed};
}

inline std::unique_ptr<hal::DepthFrame> newFrame() { return std::make_unique<hal::DepthFrame>(); }

// A UST-20LX-like base scanner at the base centre, 0.2 m up, 1 cm range noise.
inline hal::SimScanConfig baseScannerConfig() {
  hal::SimScanConfig c;
  c.mount = hal::ScanMount{0.0, 0.0, 0.2, 0.0};
  c.noise_m = 0.01;
  return c;
}

}  // namespace staa::test
