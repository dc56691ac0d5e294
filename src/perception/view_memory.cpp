#include "perception/view_memory.hpp"

#include "geometry/types.hpp"

#include <cmath>

namespace staa {

int ViewMemory::binOf(double direction) {
  const double unit = (wrapAngle(direction) + kPi) / (2.0 * kPi);  // [0, 1]
  const int b = static_cast<int>(std::floor(unit * kBins));
  return b >= kBins ? b - kBins : (b < 0 ? b + kBins : b);
}

void ViewMemory::look(double time_s, double direction, double half_fov) {
  // Every bin whose centre lies within the view.
  const double width = 2.0 * kPi / kBins;
  const int reach = static_cast<int>(std::floor(half_fov / width));
  const int centre = binOf(direction);
  for (int k = -reach - 1; k <= reach + 1; ++k) {
    const int b = ((centre + k) % kBins + kBins) % kBins;
    const double bin_centre = -kPi + (b + 0.5) * width;
    if (std::abs(wrapAngle(bin_centre - direction)) <= half_fov) last_[static_cast<std::size_t>(b)] = time_s;
  }
}

double ViewMemory::unseenFor(double time_s, double direction) const {
  return time_s - last_[static_cast<std::size_t>(binOf(direction))];
}

}  // namespace staa
