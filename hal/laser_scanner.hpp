#pragma once
// A planar laser scanner as a source of scans for the perception thread (docs/ARCHITECTURE.md
// section 4), shaped like DepthCamera's read(): the HSR-B's base scanner over ROS
// (hal/ros/ros_laser_scanner.hpp). The simulated scanner is not a source of its own: it is
// rendered with each simulated depth frame, from the same movers and pose
// (src/world/sim_laser_scan.hpp, src/app/staad/depth_sensor.hpp).

#include "hal/laser_scan.hpp"
#include "rt/clock.hpp"

namespace staa::hal {

class LaserScanner {
 public:
  virtual ~LaserScanner() = default;
  // The perception thread: the newest scan when one arrived since the last call (true), into
  // `out`; false leaves `out` as it was. Allocates nothing, takes no lock, never waits.
  virtual bool read(rt::Nanos now, LaserScan& out) = 0;
};

}  // namespace staa::hal
