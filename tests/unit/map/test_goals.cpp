// Goal placement for maps without goals (map/goals.hpp): on the generated office with its
// goals removed and on the imported depot (a real ROS map), every goal keeps its clearance
// and spacing, lies inside the bounds and is reachable from every other one.

#include "map/goals.hpp"

#include "geometry/polygon.hpp"
#include "map/generate.hpp"
#include "map/ros_import.hpp"
#include "path/global_path.hpp"
#include "shared_dir.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace staa {
namespace {

using ::testing::HasSubstr;

PolygonMap officeWithoutGoals() {
  PolygonMap map = generatePaperMap("office", 1);
  map.goals.clear();
  return map;
}

// Distance from p to the nearest obstacle (0 inside one) and to the bounds, computed here
// from the polygons, independently of the placement's own test.
double clearanceOf(const PolygonMap& map, const Vec2& p) {
  double d = std::numeric_limits<double>::infinity();
  for (const Polygon& o : map.obstacles) {
    if (locatePoint(p, o) != Containment::kOutside) return 0.0;
    d = std::min(d, distanceToEdges(p, o));
  }
  if (map.bounds) {
    const Box& b = *map.bounds;
    d = std::min({d, p.x() - b.min.x(), b.max.x() - p.x(), p.y() - b.min.y(), b.max.y() - p.y()});
  }
  return d;
}

void expectClearanceSpacingAndBounds(const PolygonMap& map, const std::vector<Vec2>& goals, const GoalPlacement& o) {
  for (std::size_t i = 0; i < goals.size(); ++i) {
    EXPECT_GE(clearanceOf(map, goals[i]), o.clearance_m - 1e-9) << "goal " << i << " " << goals[i].transpose();
    if (map.bounds) {
      EXPECT_TRUE(map.bounds->contains(goals[i])) << "goal " << i;
    }
    for (std::size_t j = 0; j < i; ++j) {
      EXPECT_GE((goals[i] - goals[j]).norm(), o.min_spacing_m - 1e-9) << "goals " << j << " and " << i;
    }
  }
}

// Every goal is reachable from goal 0 for a robot of radius 0.5 m (the paper's agent has a
// circumradius of 0.47 m; the goals keep 0.6 m).
void expectMutuallyReachable(const PolygonMap& map, const std::vector<Vec2>& goals) {
  GlobalPathOptions options;
  options.inflation_radius_m = 0.5;
  GlobalPathPlanner planner(map, options);
  for (std::size_t i = 1; i < goals.size(); ++i) {
    const GlobalPath path = planner.plan(goals[0], goals[i]);
    EXPECT_EQ(path.status, PathStatus::kFound) << "goal 0 " << goals[0].transpose() << " to goal " << i << " "
                                               << goals[i].transpose() << ": " << toString(path.status);
    EXPECT_FALSE(path.start_moved) << "goal 0 lies in the inflated map";
    EXPECT_FALSE(path.goal_moved) << "goal " << i << " lies in the inflated map";
  }
}

TEST(PlaceGoals, OfficeGets40GoalsWithClearanceSpacingInsideTheBounds) {
  const PolygonMap map = officeWithoutGoals();
  const GoalPlacement options;
  const std::vector<Vec2> goals = placeGoals(map, options);
  ASSERT_EQ(goals.size(), 40U);
  expectClearanceSpacingAndBounds(map, goals, options);
  // Spread over the map, not bunched in one corridor: goals in each quadrant.
  for (const Vec2& corner : {Vec2{0.0, 0.0}, Vec2{13.5, 0.0}, Vec2{0.0, 13.5}, Vec2{13.5, 13.5}}) {
    const Box q{corner, corner + Vec2{13.5, 13.5}};
    EXPECT_GE(std::count_if(goals.begin(), goals.end(), [&](const Vec2& g) { return q.contains(g); }), 5)
        << "quadrant at " << corner.transpose();
  }
}

TEST(PlaceGoals, OfficeGoalsAreAllReachableFromTheFirst) {
  const PolygonMap map = officeWithoutGoals();
  const std::vector<Vec2> goals = placeGoals(map, GoalPlacement{});
  ASSERT_EQ(goals.size(), 40U);
  expectMutuallyReachable(map, goals);
}

TEST(PlaceGoals, SameSeedGivesTheSameGoalsAnotherSeedOthers) {
  const PolygonMap map = officeWithoutGoals();
  GoalPlacement options;
  options.seed = 7;
  const std::vector<Vec2> a = placeGoals(map, options);
  const std::vector<Vec2> b = placeGoals(map, options);
  EXPECT_EQ(a, b);
  options.seed = 8;
  const std::vector<Vec2> c = placeGoals(map, options);
  ASSERT_EQ(c.size(), a.size());
  EXPECT_NE(a, c);
  // Lattice points: multiples of 0.25 m, exact in binary, so the same numbers on every machine.
  for (const Vec2& g : a) {
    EXPECT_EQ(g.x() * 4.0, std::round(g.x() * 4.0));
    EXPECT_EQ(g.y() * 4.0, std::round(g.y() * 4.0));
  }
}

TEST(PlaceGoals, StopsWhenNoPlaceIsFarEnoughFromTheChosenOnes) {
  // A 4 x 4 m room: at 0.6 m clearance the free square is 2.8 m wide; 2 m apart, at most 4
  // goals fit (its corners), though 40 are asked for.
  const PolygonMap map{"closet", Box{{0.0, 0.0}, {4.0, 4.0}}, {}, {}};
  GoalPlacement options;
  options.min_spacing_m = 2.0;
  const std::vector<Vec2> goals = placeGoals(map, options);
  EXPECT_GE(goals.size(), 2U);
  EXPECT_LE(goals.size(), 4U);
  expectClearanceSpacingAndBounds(map, goals, options);
}

TEST(PlaceGoals, KeepsOnlyTheLargestConnectedRegion) {
  // A 10 x 6 m hall and, behind a wall with a 0.8 m gap (closed at 0.6 m clearance), a
  // 3 x 6 m room: every goal is in the hall.
  const PolygonMap map{"two-rooms",
                       Box{{0.0, 0.0}, {13.2, 6.0}},
                       {{{10.0, 0.0}, {10.2, 0.0}, {10.2, 2.6}, {10.0, 2.6}},
                        {{10.0, 3.4}, {10.2, 3.4}, {10.2, 6.0}, {10.0, 6.0}}},
                       {}};
  GoalPlacement options;
  options.min_spacing_m = 1.0;
  const std::vector<Vec2> goals = placeGoals(map, options);
  ASSERT_GE(goals.size(), 20U);  // the hall's free 8.8 x 4.8 m at 1 m spacing
  for (const Vec2& g : goals) EXPECT_LT(g.x(), 10.0) << g.transpose();
  expectClearanceSpacingAndBounds(map, goals, options);

  // With a smaller clearance the 0.8 m gap is open: the room behind it gets goals too.
  options.clearance_m = 0.3;
  const std::vector<Vec2> open = placeGoals(map, options);
  EXPECT_TRUE(std::any_of(open.begin(), open.end(), [](const Vec2& g) { return g.x() > 10.2; }));
}

TEST(PlaceGoals, MapWithoutBoundsUsesTheObstaclesExtent) {
  const PolygonMap clutter = generatePaperMap("clutter", 1);
  ASSERT_FALSE(clutter.bounds.has_value());
  PolygonMap map = clutter;
  map.goals.clear();
  const GoalPlacement options;
  const std::vector<Vec2> goals = placeGoals(map, options);
  EXPECT_EQ(goals.size(), 40U);
  Box extent = boundingBox(map.obstacles.front());
  for (const Polygon& p : map.obstacles) {
    extent.min = extent.min.cwiseMin(boundingBox(p).min);
    extent.max = extent.max.cwiseMax(boundingBox(p).max);
  }
  for (const Vec2& g : goals) EXPECT_TRUE(extent.contains(g)) << g.transpose();
  expectClearanceSpacingAndBounds(map, goals, options);
}

TEST(PlaceGoals, MapWithoutFreeSpaceThrowsNamingTheMap) {
  // Bounds narrower than twice the clearance.
  const PolygonMap narrow{"broom-cupboard", Box{{0.0, 0.0}, {1.0, 5.0}}, {}, {}};
  try {
    placeGoals(narrow, GoalPlacement{});
    ADD_FAILURE() << "no error for a map without free space";
  } catch (const MapError& e) {
    EXPECT_THAT(e.what(), HasSubstr("'broom-cupboard'"));
    EXPECT_THAT(e.what(), HasSubstr("0.6 m clearance"));
  }
  // Bounds filled by one obstacle.
  const PolygonMap full{
      "solid", Box{{0.0, 0.0}, {5.0, 5.0}}, {{{-1.0, -1.0}, {6.0, -1.0}, {6.0, 6.0}, {-1.0, 6.0}}}, {}};
  try {
    placeGoals(full, GoalPlacement{});
    ADD_FAILURE() << "no error for a map filled by an obstacle";
  } catch (const MapError& e) {
    EXPECT_THAT(e.what(), HasSubstr("'solid'"));
  }
  // Neither bounds nor obstacles: nowhere to place anything.
  EXPECT_THROW(placeGoals(PolygonMap{"void", std::nullopt, {}, {}}, GoalPlacement{}), MapError);
}

TEST(PlaceGoals, BadOptionsAreRejectedNamingTheOption) {
  const PolygonMap map{"room", Box{{0.0, 0.0}, {5.0, 5.0}}, {}, {}};
  auto message = [&](GoalPlacement o) {
    try {
      placeGoals(map, o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  GoalPlacement o;
  o.count = 0;
  EXPECT_THAT(message(o), HasSubstr("count"));
  o = GoalPlacement{};
  o.clearance_m = -0.1;
  EXPECT_THAT(message(o), HasSubstr("clearance_m"));
  o = GoalPlacement{};
  o.min_spacing_m = 0.0;
  EXPECT_THAT(message(o), HasSubstr("min_spacing_m"));
}

TEST(PlaceGoals, ImportedDepotGets40ReachableGoals) {
  const std::filesystem::path yaml = test::sharedDir() / "maps/ros/depot.yaml";
  STAA_REQUIRE_SHARED_FILE(yaml);
  const PolygonMap map = importRosMap(yaml, ImportOptions{});
  ASSERT_TRUE(map.goals.empty());
  const GoalPlacement options;
  const std::vector<Vec2> goals = placeGoals(map, options);
  ASSERT_EQ(goals.size(), 40U);
  expectClearanceSpacingAndBounds(map, goals, options);
  expectMutuallyReachable(map, goals);
}

}  // namespace
}  // namespace staa
