#include "hal/laser_scan.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

namespace staa::hal {

std::string scanProblem(const LaserScan& scan) {
  std::ostringstream why;
  if (scan.count < 1 || scan.count > LaserScan::kMaxBeams) {
    why << "count must be in 1.." << LaserScan::kMaxBeams << ", got " << scan.count;
  } else if (!std::isfinite(scan.angle_min)) {
    why << "angle_min must be finite, got " << scan.angle_min;
  } else if (!std::isfinite(scan.angle_increment) || scan.angle_increment == 0.0 ||
             std::abs(scan.angle_increment) * static_cast<double>(scan.count - 1) > 2.0 * std::numbers::pi + 1e-6) {
    why << "angle_increment must be finite, not 0, and span at most one turn over the " << scan.count
        << " beams, got " << scan.angle_increment;
  } else if (!(scan.range_min >= 0.0) || !std::isfinite(scan.range_min)) {
    why << "range_min must be finite and >= 0, got " << scan.range_min;
  } else if (!(scan.range_max > scan.range_min) || !std::isfinite(scan.range_max)) {
    why << "range_max must be finite and > range_min " << scan.range_min << ", got " << scan.range_max;
  }
  return why.str();
}

}  // namespace staa::hal
