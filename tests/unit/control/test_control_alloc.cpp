// The 30 Hz cycle allocates nothing after start-up: 1,000 cycles of a busy scene (the office,
// three people walking through it) with operator new counted around every step, for STAA*
// with both heuristics, for the PD and DWA baselines, and with the blind-corner limit; and
// the cycles of a robot that starts in contact with a moving obstacle and backs away from it.
#include "control/control_cycle.hpp"
#include "control/dwa_controller.hpp"
#include "control/pd_controller.hpp"
#include "map/generate.hpp"
#include "world/world.hpp"

#include "rt/alloc_count.hpp"
#include "scenarios.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

// The simulated robot's state as the control cycle takes it.
UnicycleState stateOf(const RobotState& r) { return UnicycleState{r.pose.x, r.pose.y, r.pose.theta, r.v, r.w}; }

TEST(ControlAllocations, ThousandBusyCyclesAllocateNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_control_alloc must link staa_rt_alloc_hook";
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
  // STAA* with two heuristics, then the two baselines in the same cycle.
  PdController pd(s.robot);
  DwaController dwa(s.robot, LocalMapConfig{});
  struct Variant {
    const char* name;
    HeuristicKind heuristic;
    LocalController* baseline;
    bool blind_corners = false;
  };
  for (const Variant& variant : {Variant{"staa path-rtr", HeuristicKind::kPathRtr, nullptr},
                                 Variant{"staa dijkstra-rtr", HeuristicKind::kDijkstraRtr, nullptr},
                                 Variant{"pd", HeuristicKind::kPathRtr, &pd}, Variant{"dwa", HeuristicKind::kPathRtr, &dwa},
                                 Variant{"staa with the blind-corner limit", HeuristicKind::kPathRtr, nullptr, true}}) {
    ControlConfig config;
    config.staa.heuristic.kind = variant.heuristic;
    config.blind_corners.enabled = variant.blind_corners;
    ControlCycle cycle(s.map, s.robot, config);
    cycle.setLocalController(variant.baseline);
    cycle.setGoal(s.goal);
    DynamicObstacleSet obstacles(config.max_moving_obstacles);
    std::vector<Polygon> polys(world.moverCount());
    std::vector<PolygonView> views(world.moverCount());
    std::vector<Vec2> velocities(world.moverCount());
    std::size_t allocations = 0;
    int planned = 0;
    // 1,000 cycles for STAA* with its own heuristic (the test); 300 for the variants,
    // which keeps the sanitizer run in CI short.
    const int cycles =
        variant.baseline == nullptr && variant.heuristic == HeuristicKind::kPathRtr && !variant.blind_corners ? 1000 : 300;
    int capped = 0;
    for (int k = 0; k < cycles; ++k) {
      for (std::size_t i = 0; i < world.moverCount(); ++i) {
        polys[i] = world.moverPolygon(i);  // the simulator's side: may allocate
        views[i] = polys[i];
        velocities[i] = world.moverVelocity(i);
      }
      CycleInputs in;
      in.robot = stateOf(world.robot());
      in.obstacles = &obstacles;
      rt::AllocationScope scope;
      obstacles.set(views, velocities);
      const CycleOutput out = cycle.step(in, PlannerBudget::expansions(300));
      allocations += scope.count();
      capped += out.speed_capped ? 1 : 0;
      planned += out.planned || (variant.baseline != nullptr && out.state == CycleState::kDriving);
      world.step(1.0 / 30.0, out.v_cmd, out.w_cmd);
      if (out.state == CycleState::kReached) {  // drive back and forth to keep it busy
        cycle.setGoal(cycle.goal()->x > 10.0 ? s.start : s.goal);
      }
    }
    EXPECT_EQ(allocations, 0u) << variant.name;
    EXPECT_GT(planned, cycles * 9 / 10) << variant.name;
    if (variant.blind_corners) {
      EXPECT_GT(capped, 10) << "the office's doors really capped the speed";
    }
  }
}

// Issue 16: cycles whose route runs through passages only the passage map M'' opens (both
// route searches, the band's cost, the local paths in M'', the exact static collision checks)
// allocate nothing either: the 0.5 x 0.65 m robot through the building's three narrowed doors.
TEST(ControlAllocations, PassageCyclesAllocateNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_control_alloc must link staa_rt_alloc_hook";
  const Scenario s = test::buildingOfFourRooms();
  World world(s);
  ControlConfig config;
  ControlCycle cycle(s.map, s.robot, config);
  ASSERT_TRUE(cycle.pathPlanner().hasPassageMap());
  cycle.setGoal(s.goal);
  std::size_t allocations = 0;
  int passage_cycles = 0, planned = 0;
  for (int k = 0; k < 600; ++k) {
    CycleInputs in;
    in.robot = stateOf(world.robot());
    rt::AllocationScope scope;
    const CycleOutput out = cycle.step(in, PlannerBudget::expansions(300));
    allocations += scope.count();
    passage_cycles += out.passage_mode;
    planned += out.planned;
    world.step(1.0 / 30.0, out.v_cmd, out.w_cmd);
    if (out.state == CycleState::kReached) cycle.setGoal(cycle.goal()->x > 8.0 ? s.start : s.goal);
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(passage_cycles, 30);
  EXPECT_GT(planned, 500);
}

// StaaConfig::separate_contacts (off by default): a robot whose front touches another body (standing, in its
// way) backs away from it, and those cycles (the obstacle left out, the first actions kept to
// those that move away) allocate nothing.
TEST(ControlAllocations, CyclesInContactWithAMovingObstacleAllocateNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_control_alloc must link staa_rt_alloc_hook";
  Scenario s;
  s.map = generateOfficeMap();
  s.robot = paperAgentProfile();
  s.start = {4.5, 4.5, 0.0};
  s.goal = {22.5, 4.5, 0.0};
  World world(s);
  ControlConfig config;
  config.staa.separate_contacts = true;
  ControlCycle cycle(s.map, s.robot, config);
  cycle.setGoal(s.goal);
  // The robot's front edge is x = 4.9: the other body touches it.
  const Polygon other = test::box(4.9, 4.2, 5.7, 4.8);
  const PolygonView views[] = {PolygonView(other)};
  const Vec2 velocities[] = {Vec2(0.0, 0.0)};
  DynamicObstacleSet obstacles(config.max_moving_obstacles);
  std::size_t allocations = 0;
  int in_contact = 0;
  for (int k = 0; k < 60; ++k) {
    CycleInputs in;
    in.robot = stateOf(world.robot());
    in.obstacles = &obstacles;
    rt::AllocationScope scope;
    obstacles.set(views, velocities);
    const CycleOutput out = cycle.step(in, PlannerBudget::expansions(300));
    allocations += scope.count();
    in_contact += out.planned && out.plan.contacts > 0 ? 1 : 0;
    world.step(1.0 / 30.0, out.v_cmd, out.w_cmd);
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(in_contact, 0);
  // Backed out of contact: the robot's centre 3 cm or more farther from the other's (0.8 m at
  // the start; without separate_contacts it brakes and stays there).
  EXPECT_GT((world.robot().pose.position() - Vec2(5.3, 4.5)).norm(), 0.83);
}

}  // namespace
}  // namespace staa
