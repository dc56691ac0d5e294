#include "world/world.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "map/polygon_map.hpp"
#include "shared_dir.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace staa {
namespace {

constexpr double kDt = 1.0 / 30.0;  // the controller's cycle

Polygon rect(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

PolygonMap mapWith(std::vector<Polygon> obstacles, std::optional<Box> bounds = std::nullopt) {
  PolygonMap m;
  m.name = "test";
  m.obstacles = std::move(obstacles);
  m.bounds = bounds;
  return m;
}

TEST(World, StraightDriveReachesVmaxAfterVmaxOverAmaxAndCoversTheExactDistance) {
  World world(mapWith({}), paperAgentProfile(), Pose2{});
  const double dt = 0.01;
  // v_max / a_max = 2 / 2 = 1 s = 100 steps; the command beyond v_max is clamped.
  for (int k = 1; k <= 100; ++k) {
    world.step(dt, 5.0, 0.0);
    if (k == 99) {
      EXPECT_LT(world.robot().v, 2.0 - 1e-3);
    }
  }
  EXPECT_NEAR(world.robot().v, 2.0, 1e-12);
  EXPECT_NEAR(world.time(), 1.0, 1e-12);
  // Each step first raises v by a*dt, then drives dt at that speed: sum_k k*a*dt^2.
  EXPECT_NEAR(world.robot().pose.x, 2.0 * dt * dt * (100.0 * 101.0 / 2.0), 1e-9);
  EXPECT_EQ(world.robot().pose.y, 0.0);
  EXPECT_EQ(world.robot().pose.theta, 0.0);
  for (int k = 0; k < 50; ++k) world.step(dt, 5.0, 0.0);
  EXPECT_EQ(world.robot().v, 2.0);
  EXPECT_NEAR(world.robot().pose.x, 1.01 + 1.0, 1e-9);
  EXPECT_EQ(world.collisionEpisodes(), 0);
}

TEST(World, ConstantCommandTracesACircleOfRadiusVOverW) {
  World world(mapWith({}), paperAgentProfile(), Pose2{});
  const double v = 1.0, w = 0.5, radius = v / w;
  world.setRobotState({Pose2{}, v, w});
  // A quarter turn takes (pi/2)/w; the centre of the circle is (0, radius).
  const int steps = 1000;
  const double dt = (kPi / 2.0 / w) / steps;
  for (int k = 0; k < steps; ++k) {
    world.step(dt, v, w);
    const Pose2& p = world.robot().pose;
    ASSERT_NEAR(std::hypot(p.x, p.y - radius), radius, 1e-9) << "step " << k;
  }
  EXPECT_NEAR(world.robot().pose.x, radius, 1e-9);
  EXPECT_NEAR(world.robot().pose.y, radius, 1e-9);
  EXPECT_NEAR(world.robot().pose.theta, kPi / 2.0, 1e-9);
}

TEST(World, ArcIntegrationIsContinuousAsTurnRateVanishes) {
  const Pose2 from{1.0, 2.0, 0.3};
  const Pose2 straight = integrateArc(from, 1.5, 0.0, 2.0);
  EXPECT_NEAR(straight.x, 1.0 + 3.0 * std::cos(0.3), 1e-15);
  EXPECT_NEAR(straight.y, 2.0 + 3.0 * std::sin(0.3), 1e-15);
  for (double w : {1e-15, 1e-9, -1e-7, 1e-5}) {
    const Pose2 p = integrateArc(from, 1.5, w, 2.0);
    // The arc deviates from the line by about s^2 * w / 2.
    EXPECT_NEAR(p.x, straight.x, 9.0 * std::abs(w) + 1e-14) << w;
    EXPECT_NEAR(p.y, straight.y, 9.0 * std::abs(w) + 1e-14) << w;
  }
  // Exact against the closed form away from zero.
  const Pose2 q = integrateArc(from, 1.5, 0.7, 2.0);
  EXPECT_NEAR(q.x, 1.0 + 1.5 / 0.7 * (std::sin(0.3 + 1.4) - std::sin(0.3)), 1e-13);
  EXPECT_NEAR(q.y, 2.0 - 1.5 / 0.7 * (std::cos(0.3 + 1.4) - std::cos(0.3)), 1e-13);
}

TEST(World, VelocityLimitsAndAccelerationLimitsAreRespected) {
  const RobotProfile profile = paperAgentProfile();
  const MotionLimits& lim = profile.limits;
  World world(mapWith({}), profile, Pose2{});
  double v_prev = 0.0, w_prev = 0.0;
  const auto check = [&](double v_cmd, double w_cmd, int steps) {
    for (int k = 0; k < steps; ++k) {
      world.step(kDt, v_cmd, w_cmd);
      const double v = world.robot().v, w = world.robot().w;
      ASSERT_LE(v, lim.v_max);
      ASSERT_GE(v, lim.v_min);
      ASSERT_LE(std::abs(w), lim.w_max);
      ASSERT_LE(std::abs(v - v_prev), lim.a_max * kDt + 1e-12);
      ASSERT_LE(std::abs(w - w_prev), lim.b_max * kDt + 1e-12);
      v_prev = v;
      w_prev = w;
    }
  };
  check(100.0, 100.0, 60);
  EXPECT_EQ(world.robot().v, lim.v_max);
  EXPECT_EQ(world.robot().w, lim.w_max);
  check(-100.0, -100.0, 120);
  EXPECT_EQ(world.robot().v, lim.v_min);
  EXPECT_EQ(world.robot().w, -lim.w_max);
  // A command between the steps is met exactly once reachable.
  check(0.5, -0.25, 60);
  EXPECT_NEAR(world.robot().v, 0.5, 1e-12);
  EXPECT_NEAR(world.robot().w, -0.25, 1e-12);
}

TEST(World, MoverPingPongsBetweenTwoWaypointsWithTheRightPeriod) {
  // 5 m at 1.25 m/s: 4 s out, 4 s back.
  const Mover mover{rect(-0.25, -0.25, 0.25, 0.25), {{10.0, 0.0}, {10.0, 5.0}}, 1.25};
  World world(mapWith({}), paperAgentProfile(), Pose2{}, {mover});
  EXPECT_DOUBLE_EQ(world.moverPeriod(0), 8.0);
  EXPECT_EQ(world.moverPosition(0), Vec2(10.0, 0.0));
  const double dt = 0.01;
  const auto runTo = [&](double t) {
    while (world.time() < t - 1e-9) world.step(dt, 0.0, 0.0);
  };
  runTo(2.0);
  EXPECT_NEAR((world.moverPosition(0) - Vec2(10.0, 2.5)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((world.moverVelocity(0) - Vec2(0.0, 1.25)).norm(), 0.0, 1e-12);
  const Polygon poly = world.moverPolygon(0);
  EXPECT_NEAR((poly[0] - Vec2(9.75, 2.25)).norm(), 0.0, 1e-9);  // translated, not rotated
  runTo(4.0);
  EXPECT_NEAR((world.moverPosition(0) - Vec2(10.0, 5.0)).norm(), 0.0, 1e-9);
  runTo(6.0);
  EXPECT_NEAR((world.moverPosition(0) - Vec2(10.0, 2.5)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((world.moverVelocity(0) - Vec2(0.0, -1.25)).norm(), 0.0, 1e-12);
  runTo(8.0);
  EXPECT_NEAR((world.moverPosition(0) - Vec2(10.0, 0.0)).norm(), 0.0, 1e-9);
  runTo(9.0);
  EXPECT_NEAR((world.moverPosition(0) - Vec2(10.0, 1.25)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((world.moverVelocity(0) - Vec2(0.0, 1.25)).norm(), 0.0, 1e-12);
}

TEST(World, MoverWalksAPolylineAndOneWaypointStandsStill) {
  // An L: 3 m east then 4 m north at 1 m/s; period 14 s.
  const Mover walker{rect(-0.1, -0.1, 0.1, 0.1), {{5.0, 5.0}, {8.0, 5.0}, {8.0, 9.0}}, 1.0};
  const Mover statue{rect(-0.1, -0.1, 0.1, 0.1), {{-5.0, -5.0}}, 2.0};
  World world(mapWith({}), paperAgentProfile(), Pose2{}, {walker, statue});
  EXPECT_DOUBLE_EQ(world.moverPeriod(0), 14.0);
  EXPECT_EQ(world.moverPeriod(1), 0.0);
  for (int k = 0; k < 500; ++k) world.step(0.01, 0.0, 0.0);  // t = 5: 2 m up the second leg
  EXPECT_NEAR((world.moverPosition(0) - Vec2(8.0, 7.0)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((world.moverVelocity(0) - Vec2(0.0, 1.0)).norm(), 0.0, 1e-12);
  for (int k = 0; k < 700; ++k) world.step(0.01, 0.0, 0.0);  // t = 12: 5 m back from the end at t = 7
  EXPECT_NEAR((world.moverPosition(0) - Vec2(7.0, 5.0)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((world.moverVelocity(0) - Vec2(-1.0, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(world.moverPosition(1), Vec2(-5.0, -5.0));
  EXPECT_EQ(world.moverVelocity(1), Vec2(0.0, 0.0));
}

TEST(World, PushingIntoAWallIsOneEpisodeWithoutPenetrationAndASecondContactIsASecond) {
  const Polygon wall = rect(3.0, -2.0, 3.2, 2.0);
  World world(mapWith({wall}), paperAgentProfile(), Pose2{});
  // Drive at the wall (the nose is at x = 0.4, 2.6 m away) until contact.
  int steps = 0;
  while (!world.inContact()) {
    world.step(kDt, 1.0, 0.0);
    ASSERT_FALSE(polygonsOverlap(world.footprint(), wall));
    ASSERT_LT(++steps, 200) << "never reached the wall";
  }
  EXPECT_EQ(world.collisionEpisodes(), 1);
  EXPECT_EQ(world.robot().v, 0.0);
  EXPECT_EQ(world.robot().w, 0.0);
  // It stopped at the contact, not a step short of it.
  EXPECT_LT(world.robot().pose.x + 0.4, 3.0);
  EXPECT_NEAR(world.robot().pose.x + 0.4, 3.0, 1e-6);
  EXPECT_EQ(world.minClearance(), 0.0);
  // Keep pushing for 2 s: still the same episode, never inside the wall.
  for (int k = 0; k < 60; ++k) {
    world.step(kDt, 1.0, 0.0);
    ASSERT_FALSE(polygonsOverlap(world.footprint(), wall)) << "penetrated at push step " << k;
    ASSERT_LT(world.robot().pose.x + 0.4, 3.0);
  }
  EXPECT_EQ(world.collisionEpisodes(), 1);
  // Back off for 1 s, then drive in again: a second episode.
  for (int k = 0; k < 30; ++k) world.step(kDt, -0.5, 0.0);
  EXPECT_FALSE(world.inContact());
  EXPECT_GT(world.clearance(), 0.1);
  EXPECT_EQ(world.collisionEpisodes(), 1);
  steps = 0;
  while (!world.inContact()) {
    world.step(kDt, 1.0, 0.0);
    ASSERT_LT(++steps, 200) << "never reached the wall again";
  }
  EXPECT_EQ(world.collisionEpisodes(), 2);
  EXPECT_FALSE(polygonsOverlap(world.footprint(), wall));
}

TEST(World, AThinWallIsNotTunnelledThroughInOneLongStep) {
  // 5 mm thick; at 2 m/s a 0.1 s step travels 20 cm, far beyond it.
  const Polygon wall = rect(3.0, -2.0, 3.005, 2.0);
  World world(mapWith({wall}), paperAgentProfile(), Pose2{});
  world.setRobotState({Pose2{}, 2.0, 0.0});
  for (int k = 0; k < 40; ++k) {
    world.step(0.1, 2.0, 0.0);
    ASSERT_FALSE(polygonsOverlap(world.footprint(), wall));
  }
  EXPECT_LT(world.robot().pose.x, 3.0);
  EXPECT_EQ(world.collisionEpisodes(), 1);
}

TEST(World, TheMapBoundsBlockLikeAWall) {
  World world(mapWith({}, Box{{-1.0, -1.0}, {5.0, 5.0}}), paperAgentProfile(), Pose2{});
  for (int k = 0; k < 150; ++k) world.step(kDt, 2.0, 0.0);
  EXPECT_EQ(world.collisionEpisodes(), 1);
  EXPECT_LT(world.robot().pose.x + 0.4, 5.0);
  EXPECT_NEAR(world.robot().pose.x + 0.4, 5.0, 1e-6);
}

TEST(World, AMoverRunningIntoTheStandingRobotIsOneEpisode) {
  // A 0.5 m square walks along y = 0 from x = 3 to x = -3 and back, through the robot.
  const Mover mover{rect(-0.25, -0.25, 0.25, 0.25), {{3.0, 0.0}, {-3.0, 0.0}}, 1.0};
  World world(mapWith({}), paperAgentProfile(), Pose2{}, {mover});
  for (int k = 0; k < 180; ++k) world.step(kDt, 0.0, 0.0);  // 6 s: the mover has passed once
  EXPECT_EQ(world.collisionEpisodes(), 1);
  EXPECT_EQ(world.robot().pose.x, 0.0);
  EXPECT_EQ(world.minClearance(), 0.0);
  for (int k = 0; k < 180; ++k) world.step(kDt, 0.0, 0.0);  // and on the way back
  EXPECT_EQ(world.collisionEpisodes(), 2);
}

TEST(World, ClearanceToAWallAtAKnownDistanceIsExact) {
  // The paper agent's nose is at x = 0.4, its widest part (the rear) at |y| = 0.25.
  World world(mapWith({rect(1.5, -1.0, 1.7, 1.0)}), paperAgentProfile(), Pose2{});
  EXPECT_NEAR(world.clearance(), 1.1, 1e-9);
  EXPECT_NEAR(world.minClearance(), 1.1, 1e-9);
  world.setRobotState({Pose2{0.0, 0.0, kPi / 2.0}, 0.0, 0.0});  // rear corner (0.25, -0.4)
  EXPECT_NEAR(world.clearance(), 1.25, 1e-9);
  // An obstacle's vertex against the robot's edge: a triangle pointing at the nose.
  World tip(mapWith({{{2.0, 0.1}, {3.0, 1.0}, {3.0, -1.0}}}), paperAgentProfile(), Pose2{});
  EXPECT_NEAR(tip.clearance(), 1.6, 1e-9);
  // The bounds: the rear is 0.6 m from x = -1.
  World bounded(mapWith({}, Box{{-1.0, -1.0}, {5.0, 5.0}}), paperAgentProfile(), Pose2{});
  EXPECT_NEAR(bounded.clearance(), 0.6, 1e-9);
  // A mover 1.5 m to the left of the robot's side (rear corner at y = 0.25).
  const Mover mover{rect(-0.25, -0.25, 0.25, 0.25), {{-0.4, 2.0}}, 0.0};
  World near_mover(mapWith({}), paperAgentProfile(), Pose2{}, {mover});
  EXPECT_NEAR(near_mover.clearance(), 1.5, 1e-9);
}

TEST(World, MinClearanceIsTheSmallestClearanceOfTheRun) {
  World world(mapWith({rect(3.0, -2.0, 3.2, 2.0)}), paperAgentProfile(), Pose2{});
  double smallest = world.clearance();
  for (int k = 0; k < 30; ++k) {
    world.step(kDt, 1.0, 0.0);
    smallest = std::min(smallest, world.clearance());
  }
  for (int k = 0; k < 60; ++k) {
    world.step(kDt, -1.0, 0.0);  // decelerates for 1 s, still closing in, then backs off
    smallest = std::min(smallest, world.clearance());
  }
  EXPECT_GT(world.clearance(), smallest);
  EXPECT_EQ(world.minClearance(), smallest);
  EXPECT_EQ(world.collisionEpisodes(), 0);
}

TEST(World, RunsAreBitForBitReproducible) {
  const Mover mover{rect(-0.25, -0.25, 0.25, 0.25), {{4.0, -3.0}, {4.0, 3.0}}, 1.2};
  const auto run = [&] {
    World world(mapWith({rect(6.0, -2.0, 6.2, 2.0)}), paperAgentProfile(), Pose2{}, {mover});
    for (int k = 0; k < 300; ++k) world.step(kDt, 1.5 * std::sin(0.05 * k), 2.0 * std::cos(0.03 * k));
    return world;
  };
  const World a = run(), b = run();
  EXPECT_EQ(a.robot().pose.x, b.robot().pose.x);
  EXPECT_EQ(a.robot().pose.y, b.robot().pose.y);
  EXPECT_EQ(a.robot().pose.theta, b.robot().pose.theta);
  EXPECT_EQ(a.collisionEpisodes(), b.collisionEpisodes());
  EXPECT_EQ(a.minClearance(), b.minClearance());
}

TEST(World, BuildsFromAScenarioAndRejectsBadSteps) {
  Scenario sc;
  sc.map = mapWith({rect(3.0, -2.0, 3.2, 2.0)});
  sc.robot = paperAgentProfile();
  sc.start = Pose2{0.5, 0.5, 0.25};
  sc.movers.push_back({rect(-0.25, -0.25, 0.25, 0.25), {{8.0, 1.0}, {8.0, 6.0}}, 1.2});
  World world(sc);
  EXPECT_EQ(world.robot().pose.x, 0.5);
  EXPECT_EQ(world.robot().pose.theta, 0.25);
  EXPECT_EQ(world.moverCount(), 1u);
  EXPECT_EQ(world.moverPosition(0), Vec2(8.0, 1.0));
  EXPECT_THROW(world.step(0.0, 1.0, 0.0), std::invalid_argument);
  EXPECT_THROW(world.step(kDt, std::nan(""), 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace staa
