#include "control/control_cycle.hpp"
#include "robot/robot_profile.hpp"
#include "map/generate.hpp"
#include "experiment/sim_runner.hpp"
#include "world/world.hpp"

#include "scenarios.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace staa {
namespace {

TEST(ControlCycle, IdleWithoutAGoalAndBrakesTowardsStandstill) {
  const Scenario s = test::openSpace();
  ControlCycle cycle(s.map, s.robot, ControlConfig{});
  CycleInputs in;
  in.robot = UnicycleState{2, 2, 0, 1.0, 0.5};
  const CycleOutput out = cycle.step(in, PlannerBudget::expansions(100));
  EXPECT_EQ(out.state, CycleState::kIdle);
  EXPECT_FALSE(out.planned);
  // One control period (1/30 s) of braking at a_max = 2 and b_max = 6.
  EXPECT_NEAR(out.v_cmd, 1.0 - 2.0 / 30.0, 1e-12);
  EXPECT_NEAR(out.w_cmd, 0.5 - 6.0 / 30.0, 1e-12);
}

TEST(ControlCycle, GoalInsideAWallIsUnreachableAndTheRobotStops) {
  Scenario s = test::doorTurn();
  ControlCycle cycle(s.map, s.robot, ControlConfig{});
  cycle.setGoal(Pose2{6.0, 6.0, 0.0});  // inside the wall x in [5.94, 6.06]
  CycleInputs in;
  in.robot = UnicycleState{2, 2.7, 0, 0.5, 0.0};
  const CycleOutput out = cycle.step(in, PlannerBudget::expansions(100));
  EXPECT_EQ(out.state, CycleState::kUnreachable);
  EXPECT_EQ(out.path_status, PathStatus::kGoalInObstacle);
  EXPECT_LT(out.v_cmd, 0.5);
  EXPECT_FALSE(out.planned);
}

TEST(ControlCycle, GoalInAClosedRoomIsUnreachable) {
  Scenario s = test::openSpace();
  s.map.obstacles = {test::box(8, 8, 12, 8.2), test::box(8, 11.8, 12, 12), test::box(8, 8, 8.2, 12), test::box(11.8, 8, 12, 12)};
  ControlCycle cycle(s.map, s.robot, ControlConfig{});
  cycle.setGoal(Pose2{10, 10, 0});
  CycleInputs in;
  in.robot = UnicycleState{2, 2, 0, 0, 0};
  const CycleOutput out = cycle.step(in, PlannerBudget::expansions(100));
  EXPECT_EQ(out.state, CycleState::kUnreachable);
  // Not even the passage map (grown by the inscribed radius) has a way in: the footprint's.
  EXPECT_EQ(out.path_status, PathStatus::kNoPassage);
}

TEST(ControlCycle, CommandIsTheFirstActionHeldForOnePeriodWithinTheLimits) {
  const Scenario s = test::openSpace();
  ControlCycle cycle(s.map, s.robot, ControlConfig{});
  cycle.setGoal(s.goal);
  CycleInputs in;
  in.robot = UnicycleState{2, 2, 0, 1.98, 0.0};
  const CycleOutput out = cycle.step(in, PlannerBudget::expansions(300));
  ASSERT_TRUE(out.planned);
  EXPECT_EQ(out.state, CycleState::kDriving);
  const double period = 1.0 / 30.0;
  EXPECT_NEAR(out.v_cmd, std::min(2.0, 1.98 + out.plan.first_action.a * period), 1e-12);
  EXPECT_NEAR(out.w_cmd, out.plan.first_action.b * period, 1e-12);
  EXPECT_LE(out.v_cmd, s.robot.limits.v_max);
}

// The expansion budget makes whole runs reproducible bit for bit: same scene, same budget,
// same trace (moving obstacles included).
TEST(ControlCycle, ExpansionBudgetRunsAreReproducibleBitForBit) {
  const Scenario s = test::crossing();
  SimOptions o;
  o.duration_s = 6.0;
  o.budget = BudgetSpec::expansionsOf(400);
  const SimResult a = runSingleRobot(s, o);
  const SimResult b = runSingleRobot(s, o);
  ASSERT_EQ(a.trace.size(), b.trace.size());
  ASSERT_GT(a.trace.size(), 100u);
  for (std::size_t i = 0; i < a.trace.size(); ++i) {
    ASSERT_EQ(a.trace[i].x, b.trace[i].x) << i;
    ASSERT_EQ(a.trace[i].y, b.trace[i].y) << i;
    ASSERT_EQ(a.trace[i].theta, b.trace[i].theta) << i;
  }
  EXPECT_EQ(a.expansions.mean, b.expansions.mean);
  EXPECT_EQ(a.successors.mean, b.successors.mean);
}

TEST(ControlCycle, CrossesTheOfficeWithoutCollision) {
  Scenario s;
  s.name = "office";
  s.map = generateOfficeMap();
  s.robot = paperAgentProfile();
  s.start = {1.5, 4.5, 0.0};
  s.goal = {25.5, 22.5, 0.0};
  SimOptions o;
  o.duration_s = 40.0;
  o.budget = BudgetSpec::expansionsOf(600);
  const SimResult r = runSingleRobot(s, o);
  EXPECT_TRUE(r.reached_goal) << r.final_state << " at " << r.final_pose.x << ", " << r.final_pose.y;
  EXPECT_EQ(r.collisions, 0);
  EXPECT_LT(r.time_to_goal_s, 30.0);  // a 36 m shortest path
}

// The HSR (0.22 m/s, 0.3 m/s^2, 0.5 rad/s^2) from standstill towards a room that needs a turn:
// with the paper's 0.3 s step its first actions all fell into the start's closed cell and it
// never moved; the step adapted to its limits (0.63 s, set by the angular acceleration) lets
// it start at once.
TEST(ControlCycle, TheSlowHsrStartsFromStandstillAndTurnsIntoARoom) {
  Scenario s;
  s.name = "office";
  s.map = generateOfficeMap();
  s.robot = loadRobotProfile(std::filesystem::path(STAA_SOURCE_DIR) / "config/robots/hsr.yaml");
  s.start = {1.5, 4.5, 0.0};
  s.goal = {4.5, 1.5, 0.0};
  SimOptions o;
  o.duration_s = 3.0;
  o.budget = BudgetSpec::expansionsOf(300);
  const SimResult r = runSingleRobot(s, o);
  const double moved = (r.final_pose.position() - s.start.position()).norm();
  EXPECT_GT(moved, 0.3);  // 3 s at up to 0.22 m/s after a 0.73 s ramp: about 0.6 m
  EXPECT_EQ(r.collisions, 0);
  ControlConfig config;
  ControlCycle cycle(s.map, s.robot, config);
  EXPECT_NEAR(cycle.planner().config().dt, std::sqrt(2.0 * 0.1 / 0.5), 1e-12);
}

}  // namespace
}  // namespace staa

namespace staa {
namespace {

// Drives `cycle` from `start` in a World of `map` for `cycles` control periods (expansion
// budget 1000); returns the number of collision episodes and the final state.
struct Drive {
  int collisions = 0;
  RobotState end;
  int unreachable_cycles = 0;
  int held_cycles = 0;
  double reached_speed = -1.0;  // |v| when the cycle first said reached; < 0: never
  Pose2 reached_pose;
};
Drive drive(ControlCycle& cycle, const PolygonMap& map, const RobotProfile& robot, const RobotState& start, int cycles) {
  World world(map, robot, start.pose);
  world.setRobotState(start);
  Drive d;
  for (int k = 0; k < cycles; ++k) {
    const RobotState& s = world.robot();
    CycleInputs in;
    in.robot = UnicycleState{s.pose.x, s.pose.y, s.pose.theta, s.v, s.w};
    const CycleOutput out = cycle.step(in, PlannerBudget::expansions(1000));
    d.unreachable_cycles += out.state == CycleState::kUnreachable ? 1 : 0;
    d.held_cycles += out.path_held ? 1 : 0;
    if (out.state == CycleState::kReached && d.reached_speed < 0.0) {
      d.reached_speed = std::abs(s.v);
      d.reached_pose = s.pose;
    }
    const StepOutcome o = world.step(1.0 / cycle.config().rate_hz, out.v_cmd, out.w_cmd);
    d.collisions += o.new_episode ? 1 : 0;
  }
  d.end = world.robot();
  return d;
}

// Found in the 5-agent clutter runs of docs/results.md: an agent squeezed at 1.7 m/s into a
// gap narrower than M' allows; the path query failed (no path from there), the cycle braked
// straight ahead and ran into the obstacle it had been steering around. Without a path the
// cycle now stops the way STAA* checks its first actions (braking-safe, the least speed).
TEST(ControlCycle, WithoutAPathAMovingRobotStopsClearOfTheObstacleAhead) {
  const PolygonMap map = generatePaperMap("clutter", 1);
  const RobotProfile robot = paperAgentProfile();
  const RobotState start{Pose2{10.95, 10.26, -1.58}, 1.73, 0.13};
  const Pose2 goal{9.42, 1.49, 0.0};

  // The scene's failed path came from a start inside M' whose nearest free point is cut off;
  // the path planner now tries points around such a start and finds the way on, and the
  // passage map (issue 16) has the gap open anyway. Without both (a path that really fails,
  // as for a robot shut in) the stop is what is tested.
  ControlConfig config;
  config.path.nudge_start = false;
  config.passages = false;
  ControlCycle safe(map, robot, config);
  safe.setGoal(goal);
  const Drive with = drive(safe, map, robot, start, 60);
  EXPECT_GT(with.unreachable_cycles, 0) << "the scene no longer has the failed path it was made for";
  EXPECT_EQ(with.collisions, 0);
  // (Where it turned away, a path exists again and it drives on: no standstill to assert.)
  EXPECT_GT(std::hypot(with.end.pose.x - start.pose.x, with.end.pose.y - start.pose.y), 0.3);

  // The plain brake (braking safety off) hits: the scene really tests the stop.
  ControlConfig plain_config = config;
  plain_config.staa.brake_safety = false;
  ControlCycle plain(map, robot, plain_config);
  plain.setGoal(goal);
  const Drive without = drive(plain, map, robot, start, 60);
  EXPECT_GT(without.collisions, 0);

  // With the default (nudge_start): the path never fails here, and nothing is hit.
  ControlCycle nudged(map, robot, ControlConfig{});
  nudged.setGoal(goal);
  const Drive on = drive(nudged, map, robot, start, 60);
  EXPECT_EQ(on.unreachable_cycles, 0);
  EXPECT_EQ(on.collisions, 0);
}

// `reached` means stopped at the goal for a slow robot too: the HSR's top speed (0.22 m/s)
// is below the paper agent's speed tolerance (0.25 m/s), which made it report `reached` at
// full speed, 0.2 m before the goal; the tolerance now scales with the robot.
TEST(ControlCycle, TheHsrReportsReachedOnlyWhenNearlyStoppedAtTheGoal) {
  const PolygonMap map = generateOfficeMap();
  const RobotProfile robot = loadRobotProfile(std::filesystem::path(STAA_SOURCE_DIR) / "config/robots/hsr.yaml");
  ControlCycle cycle(map, robot, ControlConfig{});
  const Pose2 goal{4.0, 4.5, 0.0};
  cycle.setGoal(goal);
  const Drive d = drive(cycle, map, robot, RobotState{Pose2{1.5, 4.5, 0.0}, 0.0, 0.0}, 30 * 30);
  ASSERT_GE(d.reached_speed, 0.0) << "never reached; ended at " << d.end.pose.x << ", " << d.end.pose.y;
  EXPECT_LE(d.reached_speed, 0.2 * 0.22 + 1e-9);
  EXPECT_LE((d.reached_pose.position() - goal.position()).norm(), ControlConfig{}.goal_tolerance_m);
  EXPECT_EQ(d.collisions, 0);
  EXPECT_NEAR(d.end.v, 0.0, 0.02);
}

}  // namespace
}  // namespace staa
