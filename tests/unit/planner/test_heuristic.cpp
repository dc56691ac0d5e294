#include "planner/heuristic.hpp"

#include "geometry/clipper_ops.hpp"

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

// Issue 16: a 0.65 m slot in a wall (x = 6) that the local paths' own obstacles L (grown by
// 0.33 m) close and the passage map M'' (grown by 0.27 m) leaves open. With M'' the local path
// runs straight through the slot, as the route does; with L it goes round the wall's end.
TEST(HeuristicPassage, TheLocalPathsFollowTheRouteThroughThePassageMap) {
  const std::vector<Polygon> real = {{{5.9, 0.0}, {6.1, 0.0}, {6.1, 3.675}, {5.9, 3.675}},
                                     {{5.9, 4.325}, {6.1, 4.325}, {6.1, 8.0}, {5.9, 8.0}}};
  const std::vector<Polygon> local = inflateEachToSimple(real, 0.33, 0.03);
  const std::vector<Polygon> passage = inflateEachToSimple(real, 0.27, 0.01);
  PolygonSet real_set;
  real_set.assign(std::span<const Polygon>(real), PolygonSet::Options{});
  LocalMap map;
  const Vec2 route[] = {{4.0, 4.0}, {8.0, 4.0}};
  map.update({4.0, 4.0, 0.0}, real_set, route, 0.0);
  ASSERT_TRUE(map.intermediateGoal().is_final);
  Heuristic h(HeuristicConfig{}, kPaper, local, LocalMapConfig{});
  h.setPassageObstacles(passage, 0.26);
  const DynamicObstacleSet none(1);
  const UnicycleState s{5.0, 4.0, 0.0, 0.0, 0.0};

  h.prepare(map.intermediateGoal().pose, none, 0.3, map);
  const double around = h.evaluate(s, 0);
  EXPECT_FALSE(h.usingPassageObstacles());
  h.usePassageObstacles(true);
  h.prepare(map.intermediateGoal().pose, none, 0.3, map);
  const double through = h.evaluate(s, 0);
  EXPECT_TRUE(h.usingPassageObstacles());
  // 3 m straight at 2 m/s, standing at the goal: 1.5 s.
  EXPECT_NEAR(through, 1.5, 1e-9);
  // Round the wall's end 4 m up and back: more than 8 m.
  EXPECT_GT(around, 4.0);
  EXPECT_LT(around, HeuristicConfig{}.unreachable_penalty_s);
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
