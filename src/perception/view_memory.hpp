#pragma once
// Where the robot's camera has looked lately: for each direction around the robot (map-frame
// bearings in 5 degree bins) the last time it lay in the camera's horizontal field of view.
// Perception's advice to whoever commands the robot: a camera with a narrow view sees nothing
// beside or behind the robot, so the robot should not drive fast in a direction it has not
// looked in lately (it would drive into whatever is there unseen: reversing, a sharp turn).
// Fixed size, no allocation.

#include <array>
#include <limits>

namespace staa {

class ViewMemory {
 public:
  static constexpr int kBins = 72;

  // The camera looked along map-frame bearing `direction` (rad) with half its horizontal
  // field of view `half_fov` (rad) at `time_s`.
  void look(double time_s, double direction, double half_fov);
  // Seconds from the last look along `direction` to `time_s` (infinity: never).
  double unseenFor(double time_s, double direction) const;
  void clear() { last_.fill(-std::numeric_limits<double>::infinity()); }

 private:
  static int binOf(double direction);
  std::array<double, kBins> last_ = [] {
    std::array<double, kBins> a{};
    a.fill(-std::numeric_limits<double>::infinity());
    return a;
  }();
};

}  // namespace staa
