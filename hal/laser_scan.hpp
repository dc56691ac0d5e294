#pragma once
// A planar laser scan (docs/ARCHITECTURE.md section 4): the fields of sensor_msgs/LaserScan
// that perception uses, and where the scanner sits on the base. The HSR-B carries one in its
// base (`/hsrb/base_scan`) besides the head's Xtion: it sees all round the base but the back,
// where the camera sees a 58 degree wedge. Backends: the simulated scanner
// (src/world/sim_laser_scan.hpp) and ROS (the transport in src/app/staad/ros fills one).
// Fixed size: a scan is copied through the perception thread's buffers without allocation.

#include "rt/clock.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace staa::hal {

// The scanner on the base (base frame): its position (m), the height of its scan plane above
// the floor (m), and the yaw (rad) of its zero bearing.
struct ScanMount {
  double x = 0.0, y = 0.0, z = 0.2;
  double yaw = 0.0;
};

struct LaserScan {
  // A Hokuyo UST-20LX gives 1,081 beams (270 degrees at 0.25 degrees); SICK and Hokuyo
  // scanners on mobile bases give up to about 2,000.
  static constexpr std::size_t kMaxBeams = 2048;
  rt::Nanos stamp = -1;  // when the scan was taken (its first beam; the sweep's time is not modelled)
  std::uint64_t sequence = 0;
  // Beam i looks along angle_min + i * angle_increment (rad, counter-clockwise from the
  // mount's yaw), i < count.
  double angle_min = 0.0;
  double angle_increment = 0.0;
  // A range outside [range_min, range_max] (or not finite) is no return.
  double range_min = 0.0;
  double range_max = 0.0;
  std::size_t count = 0;
  std::array<float, kMaxBeams> ranges{};
};

// What makes a scan's geometry unusable, in words naming the field and its value (empty when
// none): count in 1..kMaxBeams, a finite angle_min, an angle_increment that is finite, not 0
// and spans at most one turn over the beams, 0 <= range_min < range_max (finite). A negative
// increment (a scanner mounted upside down) is fine.
std::string scanProblem(const LaserScan& scan);

}  // namespace staa::hal
