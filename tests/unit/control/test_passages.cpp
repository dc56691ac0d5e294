// Passages narrower than the circumscribed circle (issue 16): a 0.5 x 0.8 m robot (circumradius
// 0.47 m, so M' closes every gap below about 1 m) drives through slots, a slanted slot, a door
// with a turn behind it and the issue's building, with the real control cycle in the simulated
// world at the reproducible expansion budget; a slot narrower than the robot is reported
// unreachable in the first cycle, and the round HSR plans exactly as before.
#include "experiment/sim_runner.hpp"
#include "map/ros_import.hpp"
#include "robot/robot_profile.hpp"

#include "scenarios.hpp"
#include "shared_dir.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace staa {
namespace {

struct PassageDrive {
  SimResult result;
  int passage_cycles = 0;  // cycles whose route ran in the passage map M''
  int exact_cycles = 0;    // ... and through a passage the local paths' obstacles L close
};

PassageDrive drive(const Scenario& s, double duration_s, const ControlConfig& control = {}) {
  SimOptions o;
  o.duration_s = duration_s;
  o.budget = BudgetSpec::expansionsOf(1000);
  o.control = control;
  PassageDrive run;
  o.on_cycle = [&](const World&, const CycleOutput& out, int) {
    run.passage_cycles += out.path_passage;
    run.exact_cycles += out.passage_mode;
  };
  run.result = runSingleRobot(s, o);
  return run;
}

void expectReached(const PassageDrive& run, const Scenario& s, double max_time_s) {
  const SimResult& r = run.result;
  EXPECT_TRUE(r.reached_goal) << s.name << " ended " << r.final_state << " " << r.reason << " at (" << r.final_pose.x
                              << ", " << r.final_pose.y << ", " << r.final_pose.theta << ")";
  EXPECT_EQ(r.collisions, 0) << s.name;
  EXPECT_LE(r.time_to_goal_s, max_time_s) << s.name;
  EXPECT_LE((r.final_pose.position() - s.goal.position()).norm(), 0.2 + 1e-9) << s.name;
}

TEST(Passages, RectangleIsNotRoundTheHsrIs) {
  const RobotProfile rect = test::rectangleRobot(0.8, 0.5);
  EXPECT_NEAR(rect.circumradius(), std::hypot(0.4, 0.25), 1e-12);
  EXPECT_NEAR(rect.inscribedRadius(), 0.25, 1e-12);
  EXPECT_NEAR(rect.passageRadius(), 0.26, 1e-12);
  const RobotProfile hsr = loadRobotProfile(test::sourceDir() / "config/robots/hsr.yaml");
  // 0.2109 + 0.01 > 0.215: the HSR's passage map would be its M'.
  EXPECT_DOUBLE_EQ(hsr.passageRadius(), hsr.circumradius());
}

class SlotWidth : public ::testing::TestWithParam<double> {};

TEST_P(SlotWidth, TheRectangleDrivesThroughWithoutTouching) {
  const double width = GetParam();
  const Scenario s = test::slot(width);
  const PassageDrive run = drive(s, 30.0);
  expectReached(run, s, 20.0);
  // The clearance it kept is reported, and it is that of the slot: at most the slot's slack
  // on each side (it passed through the slot, not round the wall), never zero.
  const double slack = 0.5 * (width - 0.5);
  EXPECT_GT(run.result.min_clearance_m, 0.0) << width;
  EXPECT_LE(run.result.min_clearance_m, slack + 1e-6) << width;
  // M' (grown by 0.47 m + 3 cm) closes all three: the route ran in the passage map.
  EXPECT_GT(run.passage_cycles, 0) << width;
}

INSTANTIATE_TEST_SUITE_P(Passages, SlotWidth, ::testing::Values(0.55, 0.65, 0.8));

TEST(Passages, ASlotNarrowerThanTheFootprintIsUnreachableInTheFirstCycle) {
  const Scenario s = test::slot(0.45);
  ControlCycle cycle(s.map, s.robot, ControlConfig{});
  cycle.setGoal(s.goal);
  CycleInputs in;
  in.robot = UnicycleState{s.start.x, s.start.y, s.start.theta, 0.0, 0.0};
  const CycleOutput out = cycle.step(in, PlannerBudget::expansions(1000));
  EXPECT_EQ(out.state, CycleState::kUnreachable);
  EXPECT_EQ(out.path_status, PathStatus::kNoPassage);
  EXPECT_STREQ(toString(out.path_status), "no passage wider than the footprint");
  EXPECT_EQ(out.v_cmd, 0.0);
  // The simulated run reports the same reason and never moves.
  const PassageDrive run = drive(s, 2.0);
  EXPECT_EQ(run.result.final_state, "unreachable");
  EXPECT_EQ(run.result.reason, "no passage wider than the footprint");
  EXPECT_EQ(run.result.calls, 0);
  EXPECT_NEAR((run.result.final_pose.position() - s.start.position()).norm(), 0.0, 1e-12);
}

TEST(Passages, WithoutThePassageMapTheSameSlotIsUnreachable) {
  // The behaviour before issue 16, still selectable: M' alone closes a 0.65 m slot.
  const Scenario s = test::slot(0.65);
  ControlConfig config;
  config.passages = false;
  const PassageDrive run = drive(s, 2.0, config);
  EXPECT_EQ(run.result.final_state, "unreachable");
  EXPECT_EQ(run.result.reason, "no path");
}

TEST(Passages, ASlotAtFortyFiveDegrees) {
  const Scenario s = test::slotAt45(0.6);
  const PassageDrive run = drive(s, 30.0);
  expectReached(run, s, 20.0);
  EXPECT_GT(run.result.min_clearance_m, 0.0);
  EXPECT_LE(run.result.min_clearance_m, 0.05 + 1e-6);
  EXPECT_GT(run.passage_cycles, 0);
}

TEST(Passages, ADoorFollowedByANinetyDegreeTurn) {
  const Scenario s = test::doorThenTurn();
  const PassageDrive run = drive(s, 40.0);
  expectReached(run, s, 30.0);
  EXPECT_GT(run.result.min_clearance_m, 0.0);
  EXPECT_GT(run.passage_cycles, 0);
}

TEST(Passages, TheIssuesBuildingAGoalThreeRoomsAway) {
  const Scenario s = test::buildingOfFourRooms();
  // M' alone: unreachable from the first cycle (the issue's report).
  ControlConfig before;
  before.passages = false;
  EXPECT_EQ(drive(s, 1.0, before).result.final_state, "unreachable");
  const PassageDrive run = drive(s, 60.0);
  expectReached(run, s, 45.0);
  EXPECT_GT(run.result.min_clearance_m, 0.0);
  EXPECT_GT(run.passage_cycles, 0);
}

TEST(Passages, TheRoundHsrPlansInMPrimeAloneAsBefore) {
  const RobotProfile hsr = loadRobotProfile(test::sourceDir() / "config/robots/hsr.yaml");
  Scenario s = test::slot(0.65);
  ControlCycle cycle(s.map, hsr, ControlConfig{});
  EXPECT_FALSE(cycle.pathPlanner().hasPassageMap());
  EXPECT_DOUBLE_EQ(cycle.pathPlanner().options().passage_inflation_m, hsr.circumradius());
  // The same route, bit for bit, as M' alone without any passage option; a goal it cannot
  // reach is the footprint's kNoPassage.
  GlobalPathOptions plain = cycle.pathPlanner().options();
  plain.passage_inflation_m = 0.0;
  GlobalPathPlanner before(s.map, plain);
  GlobalPathPlanner& after = const_cast<GlobalPathPlanner&>(cycle.pathPlanner());
  for (const Vec2& to : {Vec2(10.0, 4.0), Vec2(10.0, 1.0), Vec2(3.0, 7.0)}) {
    const GlobalPath a = before.plan({2.0, 4.0}, to);
    const GlobalPath b = after.plan({2.0, 4.0}, to);
    ASSERT_EQ(a.status, PathStatus::kFound);
    ASSERT_EQ(b.status, PathStatus::kFound);
    ASSERT_EQ(a.path.size(), b.path.size());
    for (std::size_t i = 0; i < a.path.size(); ++i) EXPECT_EQ(a.path[i], b.path[i]);
    EXPECT_EQ(a.length, b.length);
    EXPECT_FALSE(b.passage);
  }
  Scenario closed = test::slot(0.3);
  ControlCycle closed_cycle(closed.map, hsr, ControlConfig{});
  closed_cycle.setGoal(closed.goal);
  CycleInputs in;
  in.robot = UnicycleState{closed.start.x, closed.start.y, 0.0, 0.0, 0.0};
  const CycleOutput out = closed_cycle.step(in, PlannerBudget::expansions(100));
  EXPECT_EQ(out.state, CycleState::kUnreachable);
  EXPECT_EQ(out.path_status, PathStatus::kNoPassage);
}

// The depot junction of docs/results.md ("Open"): the paper's agent drove north up an aisle to
// a 0.70 m slot M' closes, the route looped south round the boxes, and the first exit of the
// robot-aligned box jumped with every small turn: it rocked in place. It arrives from all
// three starts now, with the passage map (through the slot) and, without it, with the steady
// G~ alone (round the boxes).
TEST(Passages, TheDepotJunctionArrivesFromAllThreeStarts) {
  const auto yaml = test::sharedDir() / "maps/ros/depot.yaml";
  STAA_REQUIRE_SHARED_FILE(yaml);
  Scenario s;
  s.name = "depot";
  s.map = importRosMap(yaml, ImportOptions{});
  s.robot = paperAgentProfile();
  s.goal = {20.0, 11.0, 0.0};
  for (const bool passages : {true, false}) {
    ControlConfig config;
    config.passages = passages;
    for (const Pose2& start : {Pose2{19.5, 1.5, 1.57}, Pose2{17.2, 4.4, 0.0}, Pose2{21.5, 4.4, 3.14}}) {
      s.start = start;
      const PassageDrive run = drive(s, 30.0, config);
      SCOPED_TRACE(std::string(passages ? "passages" : "M' alone") + " from (" + std::to_string(start.x) + ", " +
                   std::to_string(start.y) + ")");
      expectReached(run, s, 30.0);
    }
  }
}

}  // namespace
}  // namespace staa
