// The blind-corner speed limit (control/blind_corners.hpp): which map corners count, the speed
// each allows, and the control cycle's command under it.
#include "control/blind_corners.hpp"
#include "control/control_cycle.hpp"
#include "map/generate.hpp"
#include "world/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace staa {
namespace {

Polygon rect(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

BlindCornerConfig on() {
  BlindCornerConfig c;
  c.enabled = true;
  return c;
}

TEST(BlindCornerSpeed, StopsWithinTheRoomAfterTheReaction) {
  // 2 m/s: 0.4 m of reaction and 1 m of braking at 2 m/s^2.
  EXPECT_NEAR(blindCornerSpeed(1.4, 0.2, 2.0, 0.3), 2.0, 1e-12);
  for (const double room : {0.1, 0.5, 1.0, 3.0}) {
    const double v = blindCornerSpeed(room, 0.25, 1.5, 0.0);
    EXPECT_NEAR(v * 0.25 + v * v / (2.0 * 1.5), room, 1e-12) << room;
  }
  EXPECT_EQ(blindCornerSpeed(0.0, 0.2, 2.0, 0.3), 0.3);   // no room: the creep speed
  EXPECT_EQ(blindCornerSpeed(-1.0, 0.2, 2.0, 0.3), 0.3);
  EXPECT_EQ(blindCornerSpeed(0.01, 0.2, 2.0, 0.3), 0.3);  // below the creep speed: the creep speed
}

TEST(BlindCorners, AWallEndAheadCapsTheSpeedByItsDistanceLessTheClearance) {
  // A wall at x 2..2.2 along y 0.6..5, seen from the origin heading +x: its lower edge faces
  // the robot, so the corner that hides what comes down behind the wall is (2.2, 0.6), 2.2 m
  // ahead and 0.6 m aside.
  const std::vector<Polygon> map{rect(2.0, 0.6, 2.2, 5.0)};
  const BlindCorners corners(map, on(), 0.5, 2.0);
  const BlindCorners::Cap cap = corners.speedCap({0.0, 0.0, 0.0});
  EXPECT_EQ(cap.corner, Vec2(2.2, 0.6));
  EXPECT_NEAR(cap.room, 1.7, 1e-12);
  EXPECT_NEAR(cap.speed, blindCornerSpeed(1.7, 0.2, 2.0, 0.3), 1e-12);
  // Heading away, or with the corner ahead by less than the clearance (0.5 m): no cap.
  EXPECT_TRUE(std::isinf(corners.speedCap({0.0, 0.0, kPi}).speed));
  EXPECT_TRUE(std::isinf(corners.speedCap({1.75, 0.0, 0.0}).speed));
  // Farther aside than clearance + lateral_m (0.5 + 0.5 m): no cap.
  EXPECT_TRUE(std::isinf(corners.speedCap({0.0, -0.5, 0.0}).speed));
  // Beyond range_m (3 m): no cap.
  EXPECT_TRUE(std::isinf(corners.speedCap({-1.5, 0.0, 0.0}).speed));
  // Off: no cap.
  BlindCornerConfig off = on();
  off.enabled = false;
  EXPECT_TRUE(std::isinf(BlindCorners(map, off, 0.5, 2.0).speedCap({0.0, 0.0, 0.0}).speed));
}

TEST(BlindCorners, OnlyVisibleConvexSilhouetteCornersCount) {
  // A box at x 1..1.2, y 0.1..1 in the line of sight hides the wall's end (2.2, 0.6); of its
  // own corners, (1, 1) hides what is behind it (both its edges below the line of sight) and is
  // the nearest ahead; (1, 0.1) is not a silhouette (its lower edge faces the robot).
  const std::vector<Polygon> hidden{rect(2.0, 0.6, 2.2, 5.0), rect(1.0, 0.1, 1.2, 1.0)};
  const BlindCorners corners(hidden, on(), 0.5, 2.0);
  const BlindCorners::Cap cap = corners.speedCap({0.0, 0.0, 0.0});
  EXPECT_EQ(cap.corner, Vec2(1.0, 1.0));
  EXPECT_NEAR(cap.room, 0.5, 1e-12);
  // Turned so that only the wall's end is near the line of travel, the box still hides it.
  const Pose2 towards_wall_end{0.0, 0.0, std::atan2(0.6, 2.2)};
  EXPECT_NE(corners.speedCap(towards_wall_end).corner, Vec2(2.2, 0.6));
  EXPECT_EQ(BlindCorners(std::vector<Polygon>{hidden[0]}, on(), 0.5, 2.0).speedCap(towards_wall_end).corner, Vec2(2.2, 0.6));

  // An L's reflex (inner) corner hides nothing: the line of sight runs on into the obstacle.
  const Polygon ell{{2.0, 0.3}, {4.0, 0.3}, {4.0, 3.0}, {3.8, 3.0}, {3.8, 0.5}, {2.0, 0.5}};
  const BlindCorners l_corners(std::vector<Polygon>{ell}, on(), 0.5, 2.0);
  const BlindCorners::Cap l_cap = l_corners.speedCap({3.0, 0.9, 0.0});
  // From inside the L's arm, the reflex corner (3.8, 0.5) is ahead and near the line: not it.
  EXPECT_NE(l_cap.corner, Vec2(3.8, 0.5));
  // The same polygon clockwise gives the same answers.
  Polygon cw(ell.rbegin(), ell.rend());
  const BlindCorners cw_corners(std::vector<Polygon>{cw}, on(), 0.5, 2.0);
  EXPECT_EQ(cw_corners.speedCap({0.0, 0.0, 0.0}).corner, l_corners.speedCap({0.0, 0.0, 0.0}).corner);
  EXPECT_EQ(cw_corners.speedCap({0.0, 0.0, 0.0}).speed, l_corners.speedCap({0.0, 0.0, 0.0}).speed);
}

// Through the office's doors with the limit on: the command never exceeds the cap by more
// than the robot can brake in a cycle, it keeps the arc, and the robot still arrives.
TEST(BlindCorners, TheCycleCommandsNoMoreThanTheCapAndStillArrives) {
  const PolygonMap map = generateOfficeMap();
  const RobotProfile robot = paperAgentProfile();
  ControlConfig config;
  config.blind_corners.enabled = true;
  ControlCycle cycle(map, robot, config);
  ControlCycle free_cycle(map, robot, ControlConfig{});
  // From a room north of the corridor to one south of it: out of one door, in at another.
  const Pose2 start{13.6, 25.4, -0.86}, goal{24.6, 19.6, 0.0};
  for (ControlCycle* c : {&cycle, &free_cycle}) c->setGoal(goal);
  World world(map, robot, start);
  World free_world(map, robot, start);
  const double period = 1.0 / config.rate_hz;
  int capped = 0, k = 0, free_arrival = -1, arrival = -1;
  for (; k < 1200 && (arrival < 0 || free_arrival < 0); ++k) {
    const RobotState& s = world.robot();
    CycleInputs in;
    in.robot = UnicycleState{s.pose.x, s.pose.y, s.pose.theta, s.v, s.w};
    const CycleOutput out = cycle.step(in, PlannerBudget::expansions(1000));
    if (out.state == CycleState::kReached && arrival < 0) arrival = k;
    if (out.speed_capped) {
      ++capped;
      EXPECT_LE(out.v_cmd, std::max(out.speed_cap, s.v - robot.limits.a_max * period) + 1e-12) << k;
    }
    EXPECT_FALSE(world.step(period, out.v_cmd, out.w_cmd).new_episode) << "collision at cycle " << k;
    const RobotState& f = free_world.robot();
    CycleInputs fin;
    fin.robot = UnicycleState{f.pose.x, f.pose.y, f.pose.theta, f.v, f.w};
    const CycleOutput fout = free_cycle.step(fin, PlannerBudget::expansions(1000));
    if (fout.state == CycleState::kReached && free_arrival < 0) free_arrival = k;
    EXPECT_TRUE(std::isinf(fout.speed_cap));
    free_world.step(period, fout.v_cmd, fout.w_cmd);
  }
  ASSERT_GT(arrival, 0) << "the capped robot did not arrive";
  ASSERT_GT(free_arrival, 0);
  EXPECT_GT(capped, 10);
  EXPECT_GT(arrival, free_arrival);  // the doors cost time
}

TEST(BlindCorners, ABadConfigIsRefusedNamingTheKey) {
  const PolygonMap map = generateOfficeMap();
  ControlConfig config;
  config.blind_corners.reaction_s = -1.0;
  try {
    ControlCycle cycle(map, paperAgentProfile(), config);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("blind_corners.reaction_s"), std::string::npos) << e.what();
  }
  config.blind_corners.reaction_s = 0.2;
  config.blind_corners.range_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ControlCycle(map, paperAgentProfile(), config), std::invalid_argument);
}

}  // namespace
}  // namespace staa
