#pragma once
// The step of the control cycle that turns the local picture into a velocity command, as one
// interface for STAA* (StaaController) and the paper's baselines (a PD controller with a
// force field, a predictive Dynamic Window Approach): the cycle runs "the local controller"
// with the same global path, local map, moving obstacles, robot limits and budget for each.
//
// compute() and safeStop() run in the 30 Hz cycle: they must not allocate, lock or block.

#include "local/dynamic_obstacles.hpp"
#include "local/local_map.hpp"
#include "planner/budget.hpp"
#include "planner/staa_star.hpp"
#include "robot/robot_profile.hpp"
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
  PlannerBudget budget;                 // the cycle's budget, already started
};

struct LocalCommand {
  double v = 0.0;  // velocity command for the next cycle (the cycle clamps it to the limits)
  double w = 0.0;
  // The search behind the command, for controllers that search (STAA*): valid until the next
  // compute(); null for the others.
  const PlanResult* plan = nullptr;
};

class LocalController {
 public:
  virtual ~LocalController() = default;
  virtual const char* name() const = 0;
  virtual LocalCommand compute(const LocalContext& context) = 0;
  // Whether the controller has a stop of its own for a moving robot without a route (no path,
  // or out of time); when not, the cycle brakes at the limits.
  virtual bool hasSafeStop() const { return false; }
  // That stop, on a local map updated around the robot (context.path is empty).
  virtual LocalCommand safeStop(const LocalContext& context) { return {context.robot.v, context.robot.w, nullptr}; }
};

}  // namespace staa
