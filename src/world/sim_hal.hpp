#pragma once
// The simulated hardware (`staad --hal sim`, the default): the simulator's World (src/sim)
// with a few movers wandering between the map's free places, so staad runs anywhere out of
// the box. Two faces over one world:
//   - SimBase (base I/O thread): read(now) advances the world to `now` with the last
//     command (unicycle with the profile's limits, the world's exact collisions) and
//     publishes the movers through a triple buffer; odometry is the world's ground truth.
//   - SimObstacles (perception thread): the latest movers as an ObstacleFrame, at most
//     `obstacle_rate_hz`, each mover seen only within `sensor_range_m` of the robot.
// Everything is allocated at construction; read()/write() allocate nothing. Fault
// injection for tests: freezeOdometry / freezeObstacles stop the stamps from advancing.
//
// With `movers_only` (staad with a real base and `obstacles: sim`: the simulated camera)
// nobody drives the world's robot: it stands at `start` (the movers' walks keep away from
// it, the sensor range is measured from it), base() must not be used, and the obstacle
// sensor's read(now) advances the world (the movers) to `now` itself.

#include "robot/robot_profile.hpp"
#include "hal/base.hpp"
#include "hal/obstacles.hpp"
#include "map/polygon_map.hpp"
#include "rt/triple_buffer.hpp"

#include <atomic>
#include <cstdint>
#include <memory>

namespace staa {
class World;
}

namespace staa::hal {

struct SimHalConfig {
  Pose2 start;                    // the robot's start pose (must be free)
  int movers = 3;                 // wandering movers (people), 0..ObstacleFrame::kMaxObstacles
  double mover_speed = 0.8;       // m/s
  double mover_radius = 0.25;     // m (a square of this half-size)
  std::uint64_t seed = 1;         // where the movers walk
  double obstacle_rate_hz = 30.0;
  double sensor_range_m = 8.0;
  // Largest simulation step; a longer gap between read() calls is integrated in steps of
  // at most this (so a late wake-up does not teleport the robot).
  double max_step_s = 0.02;
  // The movers only: the obstacle sensor advances the world, no SimBase is used (above).
  bool movers_only = false;
};

class SimHal {
 public:
  // Throws std::invalid_argument naming the value when the start collides or a field is out
  // of range. The movers walk back and forth along shortest paths between goal locations of
  // the map (or random free points when it has none), at least 1 m from the start.
  SimHal(const PolygonMap& map, const RobotProfile& robot, const SimHalConfig& config, rt::Nanos start_time);
  ~SimHal();
  SimHal(const SimHal&) = delete;
  SimHal& operator=(const SimHal&) = delete;

  Base& base();  // throws std::logic_error with movers_only
  ObstacleSensor& obstacles();

  // Test hooks (any thread): freeze the odometry stamps / obstacle frames (a stalled input).
  void freezeOdometry(bool frozen) { freeze_odometry_.store(frozen); }
  void freezeObstacles(bool frozen) { freeze_obstacles_.store(frozen); }
  // Collision episodes of the robot so far (any thread; updated by read()).
  int collisions() const { return collisions_.load(); }
  // The world (for drawing after a run; not while the base thread runs).
  const World& world() const;

 private:
  class SimBase;
  class SimObstacles;
  std::unique_ptr<World> world_;
  std::unique_ptr<SimBase> base_;
  std::unique_ptr<SimObstacles> obstacles_;
  rt::TripleBuffer<ObstacleFrame> movers_;
  std::atomic<bool> freeze_odometry_{false};
  std::atomic<bool> freeze_obstacles_{false};
  std::atomic<int> collisions_{0};
  bool movers_only_ = false;
};

}  // namespace staa::hal
