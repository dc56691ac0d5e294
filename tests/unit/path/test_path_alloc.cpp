// Proves that a warm Minimal Construct query allocates nothing (its own executable: the
// counting operator new replaces the global one).
#include "path/global_path.hpp"

#include "rt/alloc_count.hpp"
#include "posts_scene.hpp"
#include "random_scenes.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

TEST(PathAllocations, WarmQueriesAllocateNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_path_alloc must link staa_rt_alloc_hook";
  std::mt19937_64 rng(5);
  PolygonMap map;
  map.bounds = Box{{0, 0}, {20, 20}};
  map.obstacles = test::makeRandomScene(rng, false, 25, 25, 20.0).polygons;
  GlobalPathPlanner planner(map, GlobalPathOptions{});
  const Polygon person{{9, 9}, {10, 9}, {10, 10}, {9, 10}};
  const PolygonView views[1] = {person};
  std::uniform_real_distribution<double> u(0.5, 19.5);
  std::vector<std::pair<Vec2, Vec2>> queries;
  for (int i = 0; i < 200; ++i) queries.push_back({{u(rng), u(rng)}, {u(rng), u(rng)}});
  // Warm up (first queries may size nothing more, but keep the rule: measure after warm-up).
  for (const auto& [s, g] : queries) planner.plan(s, g, views);
  int found = 0;
  rt::AllocationScope scope;
  for (const auto& [s, g] : queries) {
    found += planner.plan(s, g, views).status == PathStatus::kFound;
    found += planner.plan(s, g).status == PathStatus::kFound;
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(found, 100);
}

// A start inside M' whose nearest free point is cut off (three posts around a hole, as in
// GlobalPath.AStartWhoseNearestFreePointIsACutOffSliverGetsThePathFromAroundIt): the queries
// around it and the path with the start in front allocate nothing either.
TEST(PathAllocations, NudgedStartsAllocateNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_path_alloc must link staa_rt_alloc_hook";
  const Vec2 c(5.0, 2.0);
  const PolygonMap map = test::postsAroundAHole(c);
  GlobalPathOptions options;
  options.inflation_radius_m = 0.472;
  GlobalPathPlanner planner(map, options);
  const Vec2 starts[2] = {test::startBelowTheHole(c), test::startBelowTheHole(c) + Vec2(0.0, 0.005)};
  const Vec2 goals[2] = {{1.0, 1.0}, {9.0, 4.0}};
  for (const Vec2& g : goals) {
    for (const Vec2& s : starts) planner.plan(s, g);
  }
  int nudged = 0;
  rt::AllocationScope scope;
  for (int round = 0; round < 3; ++round) {
    for (const Vec2& g : goals) {
      for (const Vec2& s : starts) nudged += planner.plan(s, g).start_nudged ? 1 : 0;
    }
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GE(nudged, 6);
}

}  // namespace
}  // namespace staa
