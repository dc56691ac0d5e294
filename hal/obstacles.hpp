#pragma once
// What perception hands the control thread each frame: the moving (and unmapped) obstacles
// around the robot as polygons in the map frame with velocities, fixed capacity, passed by
// a triple buffer. The sim backend fills it from the simulator's ground truth; a depth
// camera fills it through perception (src/perception). Staleness is judged from `stamp`.

#include "geometry/types.hpp"
#include "rt/clock.hpp"

#include <array>
#include <cstddef>
#include <cstdint>

namespace staa::hal {

struct ObstacleFrame {
  static constexpr std::size_t kMaxObstacles = 32;
  static constexpr std::size_t kMaxVertices = 32;
  struct Obstacle {
    std::array<Vec2, kMaxVertices> vertices{};
    std::size_t n = 0;
    Vec2 velocity{0.0, 0.0};
    // How fast the velocity turns (rad/s, counter-clockwise positive): the planner also
    // predicts the obstacle along that circle (StaaConfig::predict_turning). 0: going
    // straight, or not known.
    double turn_rate = 0.0;
    // 0: seen in this frame; else how long ago (s) perception last saw it (a track kept while
    // it is out of view, at its predicted place with its outline grown).
    double unseen_s = 0.0;
  };
  rt::Nanos stamp = -1;          // when the frame was taken; < 0: never
  std::uint64_t sequence = 0;
  std::array<Obstacle, kMaxObstacles> obstacles{};
  std::size_t count = 0;
  std::size_t dropped = 0;       // obstacles beyond kMaxObstacles (counted, not passed)
};

// A source of obstacle frames, polled by the perception thread. read() returns true and
// fills `out` when a new frame is available; never allocates.
class ObstacleSensor {
 public:
  virtual ~ObstacleSensor() = default;
  virtual bool read(rt::Nanos now, ObstacleFrame& out) = 0;
};

}  // namespace staa::hal
