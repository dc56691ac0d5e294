#pragma once
// The step of the control cycle that turns the local picture into a velocity command, as an
// interface, so that the paper's baselines (a PD controller with a force field, a predictive
// Dynamic Window Approach) run in the same cycle as STAA*: same global path, same local map,
// same moving obstacles, same robot limits. STAA* itself stays a concrete member of the cycle
// (it has its own budget and statistics).
//
// compute() runs in the 30 Hz cycle: it must not allocate, lock or block.

#include "robot/robot_profile.hpp"
#include "local/dynamic_obstacles.hpp"
#include "local/local_map.hpp"
#include "robot/unicycle.hpp"

#include <span>

namespace staa {

struct LocalContext {
  UnicycleState robot;                  // pose and velocities now
  const LocalMap* map = nullptr;        // updated for this cycle: grid C, costmap C', G~
  std::span<const Vec2> path;           // the global path (dynamic where found), robot .. goal
  const DynamicObstacleSet* obstacles = nullptr;  // D now, with velocities
  Pose2 goal;                           // the final goal
  double period_s = 1.0 / 30.0;         // until the next cycle
};

struct LocalCommand {
  double v = 0.0;  // velocity command for the next cycle, within the limits
  double w = 0.0;
};

class LocalController {
 public:
  virtual ~LocalController() = default;
  virtual const char* name() const = 0;
  virtual LocalCommand compute(const LocalContext& context) = 0;
};

}  // namespace staa
