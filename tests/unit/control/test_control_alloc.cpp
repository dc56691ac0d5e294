// The 30 Hz cycle allocates nothing after start-up: 1,000 cycles of a busy scene (the office,
// three people walking through it) with operator new counted around every step.
#include "control/control_cycle.hpp"
#include "map/generate.hpp"
#include "sim/world.hpp"

#include "alloc_counter.hpp"
#include "scenarios.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

TEST(ControlAllocations, ThousandBusyCyclesAllocateNothing) {
  Scenario s;
  s.map = generateOfficeMap();
  s.robot = paperAgentProfile();
  s.start = {4.5, 1.5 + 3.0, 0.0};
  s.goal = {22.5, 4.5, 0.0};
  for (int k = 0; k < 3; ++k) {
    Mover m;
    m.polygon = test::box(-0.25, -0.25, 0.25, 0.25);
    m.waypoints = {{6.0 + 5.0 * k, 3.5}, {6.0 + 5.0 * k, 5.5}, {10.0 + 4.0 * k, 4.5}};
    m.speed = 1.0;
    s.movers.push_back(m);
  }
  World world(s);
  for (const auto& heuristic : {HeuristicKind::kPathRtr, HeuristicKind::kDijkstraRtr}) {
    ControlConfig config;
    config.staa.heuristic.kind = heuristic;
    ControlCycle cycle(s.map, s.robot, config);
    cycle.setGoal(s.goal);
    DynamicObstacleSet obstacles(config.max_dynamic_obstacles);
    std::vector<Polygon> polys(world.moverCount());
    std::vector<PolygonView> views(world.moverCount());
    std::vector<Vec2> velocities(world.moverCount());
    std::size_t allocations = 0;
    int planned = 0;
    for (int k = 0; k < 1000; ++k) {
      for (std::size_t i = 0; i < world.moverCount(); ++i) {
        polys[i] = world.moverPolygon(i);  // the simulator's side: may allocate
        views[i] = polys[i];
        velocities[i] = world.moverVelocity(i);
      }
      CycleInputs in;
      const RobotState& r = world.robot();
      in.robot = UnicycleState{r.pose.x, r.pose.y, r.pose.theta, r.v, r.w};
      in.obstacles = &obstacles;
      test::AllocationScope scope;
      obstacles.set(views, velocities);
      const CycleOutput out = cycle.step(in, PlannerBudget::expansions(300));
      allocations += scope.count();
      planned += out.planned;
      world.step(1.0 / 30.0, out.v_cmd, out.w_cmd);
      if (out.state == CycleState::kReached) {  // drive back and forth to keep it busy
        cycle.setGoal(cycle.goal()->x > 10.0 ? s.start : s.goal);
      }
    }
    EXPECT_EQ(allocations, 0u) << toString(heuristic);
    EXPECT_GT(planned, 900) << toString(heuristic);
  }
}

}  // namespace
}  // namespace staa
