// Proves that the local map's update and the dynamic obstacles' set/predict calls allocate
// nothing once constructed (its own executable: the counting operator new replaces the global
// one).
#include "local/dynamic_obstacles.hpp"
#include "local/local_map.hpp"

#include "map/generate.hpp"

#include "rt/alloc_count.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace staa {
namespace {

TEST(LocalAllocations, ThousandUpdatesAndPredictionsAllocateNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_local_alloc must link staa_rt_alloc_hook";
  const PolygonMap office = generateOfficeMap();
  PolygonSet walls;
  walls.assign(std::span<const Polygon>(office.obstacles), PolygonSet::Options{});
  LocalMap map;
  DynamicObstacleSet dynamic(8);

  // Poses along the bottom corridor (y 3..6), then up the left one (x 3..6), with a global
  // path ahead of the robot so G~ is computed on real input.
  std::vector<Pose2> poses;
  for (int k = 0; k < 500; ++k) poses.push_back({4.5 + 0.036 * k, 4.5 + 0.2 * std::sin(0.1 * k), 0.3 * std::sin(0.02 * k)});
  for (int k = 0; k < 500; ++k) poses.push_back({4.5 + 0.2 * std::sin(0.1 * k), 4.5 + 0.036 * k, 0.5 * kPi + 0.7 * std::sin(0.013 * k)});
  std::vector<Vec2> path(3);
  const Polygon person{{0, 0}, {0.4, 0}, {0.5, 0.3}, {0.2, 0.5}, {-0.1, 0.3}};
  Polygon moved(person.size());
  const PolygonView views[1] = {moved};
  const Vec2 velocity[1] = {{0.5, -0.2}};
  FixedPolygon predicted, inflated;

  int occupied = 0, inflated_vertices = 0;
  rt::AllocationScope scope;
  for (const Pose2& robot : poses) {
    path[0] = robot.position();
    path[1] = robot.transform({3.0, 0.5});
    path[2] = robot.transform({12.0, -1.0});
    map.update(robot, walls, path, 0.0);
    occupied += map.occupied(robot.transform({1.0, 1.6}));
    for (std::size_t i = 0; i < person.size(); ++i) moved[i] = person[i] + robot.transform({2.0, 0.0});
    dynamic.set(views, velocity);
    for (int depth = 0; depth <= 3; ++depth) {
      dynamic.predict(0, 0.3 * depth, predicted);
      dynamic.predictInflated(0, 0.3 * depth, 0.35, 8, inflated);
      inflated_vertices += static_cast<int>(inflated.n);
    }
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_FALSE(map.intermediateGoal().is_final);
  EXPECT_EQ(inflated_vertices, 1000 * 4 * 40);
  EXPECT_GE(occupied, 0);
}

// G~'s reach test (issue 16) runs when the path leaves the box and comes back: a loop behind
// the robot and ahead again, 1,000 updates among the office's walls, allocating nothing.
TEST(LocalAllocations, LoopingPathsReachTestAllocatesNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_local_alloc must link staa_rt_alloc_hook";
  const PolygonMap office = generateOfficeMap();
  PolygonSet walls;
  walls.assign(std::span<const Polygon>(office.obstacles), PolygonSet::Options{});
  LocalMap map;
  std::vector<Vec2> path(5);
  int later_piece = 0;
  rt::AllocationScope scope;
  for (int k = 0; k < 1000; ++k) {
    const Pose2 robot{4.5 + 0.018 * k, 4.5 + 0.2 * std::sin(0.1 * k), 0.4 * std::sin(0.02 * k)};
    path[0] = robot.position();
    path[1] = robot.transform({-3.0, 0.0});
    path[2] = robot.transform({-3.0, 1.0});
    path[3] = robot.transform({3.0, 1.0});
    path[4] = robot.transform({12.0, 1.0});
    map.update(robot, walls, path, 0.0, 0.3);
    later_piece += map.intermediateGoal().segment == 3;
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(later_piece, 0);  // the flood ran and found the later piece
}

}  // namespace
}  // namespace staa
