// The scenarios of the STAA* issue, each driven by the real control cycle through the
// simulated world with the reproducible expansion budget (1,000 pops per cycle): the robot
// must arrive, collide with nothing, and be quick enough.
#include "experiment/sim_runner.hpp"

#include "scenarios.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

struct Drive {
  SimResult result;
  double min_speed_before_x = 1e9;  // smallest |v| while the robot's centre was left of a line
};

Drive drive(const Scenario& s, double duration_s, double line_x = 1e9) {
  SimOptions o;
  o.duration_s = duration_s;
  o.budget = BudgetSpec::expansionsOf(1000);
  Drive run;
  o.on_cycle = [&](const World& w, const CycleOutput&, int) {
    if (w.time() > 0.5 && w.robot().pose.x < line_x) run.min_speed_before_x = std::min(run.min_speed_before_x, std::abs(w.robot().v));
  };
  run.result = runSingleRobot(s, o);
  return run;
}

void expectArrived(const SimResult& r, const Scenario& s, double max_time_s) {
  EXPECT_TRUE(r.reached_goal) << s.name << " ended " << r.final_state << " at (" << r.final_pose.x << ", " << r.final_pose.y << ")";
  EXPECT_EQ(r.collisions, 0) << s.name;
  EXPECT_LE(r.time_to_goal_s, max_time_s) << s.name;
  // Arrived means at the goal, facing its way, and (nearly) standing.
  EXPECT_LE((r.final_pose.position() - s.goal.position()).norm(), 0.2 + 1e-9) << s.name;
  EXPECT_LE(std::abs(wrapAngle(r.final_pose.theta - s.goal.theta)), 0.4 + 1e-9) << s.name;
}

TEST(Scenario, OpenSpace) {
  const Scenario s = test::openSpace();
  const Drive run = drive(s, 20.0);
  // 14.2 m at 2 m/s is 7.1 s plus accelerating, turning and stopping.
  expectArrived(run.result, s, 11.0);
  EXPECT_GT(run.result.min_clearance_m, 1.0);
}

TEST(Scenario, ThroughADoorWithANinetyDegreeTurn) {
  const Scenario s = test::doorTurn();
  const Drive run = drive(s, 20.0);
  expectArrived(run.result, s, 9.0);
  EXPECT_GT(run.result.min_clearance_m, 0.0);
}

TEST(Scenario, GoalBehindTheRobot) {
  const Scenario s = test::goalBehind();
  const Drive run = drive(s, 10.0);
  // Backing up 2 m (1 m/s backwards) beats turning around twice.
  expectArrived(run.result, s, 4.0);
}

TEST(Scenario, EscapesAUShapedTrapWhosePocketFacesTheStart) {
  const Scenario s = test::uTrap();
  const Drive run = drive(s, 25.0);
  expectArrived(run.result, s, 12.0);
}

TEST(Scenario, PassesAPersonWalkingTowardsItInATwoMetreCorridor) {
  const Scenario s = test::corridorPerson();
  const Drive run = drive(s, 30.0);
  expectArrived(run.result, s, 16.0);
}

TEST(Scenario, AvoidsAMoverCrossingItsPathAtRightAngles) {
  const Scenario s = test::crossing();
  const Drive run = drive(s, 25.0);
  expectArrived(run.result, s, 12.0);
}

TEST(Scenario, BrakesForAClosingGapAndPassesWhenItOpens) {
  const Scenario s = test::closingGap();
  const Drive run = drive(s, 30.0, 7.0);
  expectArrived(run.result, s, 14.0);
  // It had to stand (almost) still in front of the closed gap.
  EXPECT_LT(run.min_speed_before_x, 0.1);
}

}  // namespace
}  // namespace staa
