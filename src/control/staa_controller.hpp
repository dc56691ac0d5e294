#pragma once
// STAA* (src/planner) as the cycle's local controller: plans from the robot's state to the
// local map's G~ within the cycle's budget and turns the plan's first action, held for one
// period, into the next velocity command.

#include "control/local_controller.hpp"
#include "planner/staa_star.hpp"

namespace staa {

class StaaController final : public LocalController {
 public:
  // Arguments as StaaStar's.
  StaaController(const StaaConfig& config, const RobotProfile& robot, const std::vector<Polygon>& inflated_static,
                 const LocalMapConfig& local, std::size_t max_obstacles);

  const char* name() const override { return "staa"; }
  LocalCommand compute(const LocalContext& context) override;
  // STAA*'s brake check picks the stop (staa.brake_safety); off, the cycle brakes at the limits.
  bool hasSafeStop() const override { return planner_.config().brake_safety; }
  LocalCommand safeStop(const LocalContext& context) override;

  StaaStar& planner() { return planner_; }
  const StaaStar& planner() const { return planner_; }

 private:
  StaaStar planner_;
  PlanResult plan_;
};

}  // namespace staa
