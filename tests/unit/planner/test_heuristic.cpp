#include "planner/heuristic.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

const MotionLimits kPaper{2.0, -1.0, 3.0, 2.0, 6.0};

TEST(PathRtr, StraightAheadIsDistanceOverTopSpeed) {
  const Vec2 path[] = {{0, 0}, {4, 0}};
  EXPECT_DOUBLE_EQ(pathRtr(path, 0.0, 0.0, kPaper), 2.0);
}

TEST(PathRtr, RotatesAtTheStartAndAtTheGoal) {
  const Vec2 path[] = {{0, 0}, {0, 2}};
  // Turn 90 degrees (0.5236 s), drive 2 m (1 s), turn back to heading 0 (0.5236 s).
  EXPECT_NEAR(pathRtr(path, 0.0, 0.0, kPaper), kPi / 2 / 3 + 1.0 + kPi / 2 / 3, 1e-12);
}

TEST(PathRtr, BacksUpWhenTheGoalIsCloseBehind) {
  const Vec2 path[] = {{0, 0}, {-1, 0}};
  // Backwards: 1 m at 1 m/s and no rotation, instead of two half turns and 0.5 s.
  EXPECT_DOUBLE_EQ(pathRtr(path, 0.0, 0.0, kPaper), 1.0);
}

TEST(PathRtr, SumsTheTurnsAlongAPath) {
  const Vec2 path[] = {{0, 0}, {2, 0}, {2, 2}, {4, 2}};
  // 6 m at 2 m/s plus a left and a right turn of 90 degrees.
  EXPECT_NEAR(pathRtr(path, 0.0, 0.0, kPaper), 3.0 + 2 * (kPi / 2) / 3.0, 1e-12);
  // Arriving with heading pi/2 instead: one more quarter turn at the end.
  EXPECT_NEAR(pathRtr(path, 0.0, kPi / 2, kPaper), 3.0 + 3 * (kPi / 2) / 3.0, 1e-12);
}

TEST(PathRtr, StandingAtTheGoalCostsOnlyTheTurn) {
  const Vec2 path[] = {{1, 1}, {1, 1}};
  EXPECT_NEAR(pathRtr(path, 0.0, 1.5, kPaper), 0.5, 1e-12);
}

TEST(HeuristicKind, ParsesItsNames) {
  HeuristicKind k{};
  EXPECT_TRUE(parseHeuristicKind("dijkstra-rtr", k));
  EXPECT_EQ(k, HeuristicKind::kDijkstraRtr);
  EXPECT_TRUE(parseHeuristicKind("path-euclid", k));
  EXPECT_EQ(k, HeuristicKind::kPathEuclid);
  EXPECT_FALSE(parseHeuristicKind("euclid", k));
}

}  // namespace
}  // namespace staa
