#include "path/global_path.hpp"

#include "map/generate.hpp"
#include "map/ros_import.hpp"
#include "shared_dir.hpp"

#include <cmath>
#include <random>

#include "posts_scene.hpp"
#include "visibility_reference.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

// Two rooms side by side, 4 x 4 m each, a 1.2 m door in the wall between them (x = 4).
PolygonMap twoRooms() {
  PolygonMap m;
  m.name = "two-rooms";
  m.bounds = Box{{0, 0}, {8, 4}};
  m.obstacles = {{{3.9, 0}, {4.1, 0}, {4.1, 1.4}, {3.9, 1.4}}, {{3.9, 2.6}, {4.1, 2.6}, {4.1, 4}, {3.9, 4}}};
  return m;
}

TEST(GlobalPath, GoesThroughTheDoorAndStaysInsideTheBounds) {
  GlobalPathOptions opt;
  opt.inflation_radius_m = 0.3;
  GlobalPathPlanner planner(twoRooms(), opt);
  const GlobalPath p = planner.plan({1, 0.5}, {7, 0.5});
  ASSERT_EQ(p.status, PathStatus::kFound);
  // The path climbs to the door and passes the lower jamb's inflated corner at
  // y = 1.4 + 0.3 (+ up to the 3 cm arc tolerance).
  double max_y = 0.0;
  for (const Vec2& q : p.path) {
    EXPECT_GE(q.x(), 0.3 - 1e-6);
    EXPECT_LE(q.x(), 7.7 + 1e-6);
    EXPECT_GE(q.y(), 0.3 - 1e-6);
    max_y = std::max(max_y, q.y());
  }
  EXPECT_GE(max_y, 1.70);
  EXPECT_LE(max_y, 1.73 + 1e-9);
  EXPECT_FALSE(p.dynamic);
}

TEST(GlobalPath, DoorNarrowerThanTheRobotIsNoPath) {
  GlobalPathOptions opt;
  opt.inflation_radius_m = 0.65;  // 1.2 m door < 2 * 0.65
  GlobalPathPlanner planner(twoRooms(), opt);
  EXPECT_EQ(planner.plan({1, 2}, {7, 2}).status, PathStatus::kNoPath);
}

// ---- The passage map M'' (issue 16) ----

// A wall across a 12 x 12 m room (x = 6, 0.2 m thick) with a slot of `slot` at y = 6 and,
// when `door_y` > 0, a 1.5 m door centred at door_y.
PolygonMap wallWithSlot(double slot, double door_y = 0.0) {
  PolygonMap m;
  m.name = "slot";
  m.bounds = Box{{0, 0}, {12, 12}};
  auto wall = [](double y0, double y1) { return Polygon{{5.9, y0}, {6.1, y0}, {6.1, y1}, {5.9, y1}}; };
  const double lo = 6.0 - 0.5 * slot, hi = 6.0 + 0.5 * slot;
  if (door_y <= 0.0) {
    m.obstacles = {wall(0.0, lo), wall(hi, 12.0)};
  } else {
    m.obstacles = {wall(0.0, lo), wall(hi, door_y - 0.75), wall(door_y + 0.75, 12.0)};
  }
  return m;
}

// The 0.5 x 0.8 m rectangle: circumradius 0.472 m, passage map grown by 0.25 + 0.01 m.
GlobalPathOptions rectangleOptions() {
  GlobalPathOptions opt;
  opt.inflation_radius_m = std::hypot(0.4, 0.25);
  opt.passage_inflation_m = 0.26;
  return opt;
}

TEST(GlobalPath, ThePassageMapOpensASlotMPrimeClosesAndNamesWhyNothingFits) {
  for (double slot : {0.55, 0.65, 0.8}) {
    GlobalPathOptions wide_only = rectangleOptions();
    wide_only.passage_inflation_m = 0.0;
    GlobalPathPlanner before(wallWithSlot(slot), wide_only);
    EXPECT_EQ(before.plan({3, 6}, {9, 6}).status, PathStatus::kNoPath) << slot;
    GlobalPathPlanner planner(wallWithSlot(slot), rectangleOptions());
    ASSERT_TRUE(planner.hasPassageMap());
    const GlobalPath p = planner.plan({3, 6}, {9, 6});
    ASSERT_EQ(p.status, PathStatus::kFound) << slot;
    EXPECT_TRUE(p.passage);
    // Straight through the slot: 6 m, all of the wall's 0.2 m and the approach inside M'.
    EXPECT_NEAR(p.length, 6.0, 1e-9) << slot;
    const double band = planner.bandLength(p.path);
    EXPECT_GT(band, 0.2) << slot;
    EXPECT_LT(band, 2.0 * 0.5 + 0.2) << slot;
  }
  GlobalPathPlanner planner(wallWithSlot(0.45), rectangleOptions());
  const GlobalPath p = planner.plan({3, 6}, {9, 6});
  EXPECT_EQ(p.status, PathStatus::kNoPassage);
  EXPECT_STREQ(toString(p.status), "no passage wider than the footprint");
}

TEST(GlobalPath, TheBandsCostPrefersAWideDoorUnlessTheDetourCostsMore) {
  // The door 1.5 m above the slot: the detour (about 0.8 m) costs less than the slot's band.
  {
    GlobalPathPlanner planner(wallWithSlot(0.7, 7.5), rectangleOptions());
    const GlobalPath p = planner.plan({3, 6}, {9, 6});
    ASSERT_EQ(p.status, PathStatus::kFound);
    EXPECT_FALSE(p.passage);
    EXPECT_GT(p.length, 6.5);
    EXPECT_EQ(p.band_m, 0.0);
  }
  // The door 5 m above: a 6 m detour. The slot's route is taken, its band weighed.
  {
    GlobalPathPlanner planner(wallWithSlot(0.7, 11.0), rectangleOptions());
    const GlobalPath p = planner.plan({3, 6}, {9, 6});
    ASSERT_EQ(p.status, PathStatus::kFound);
    EXPECT_TRUE(p.passage);
    EXPECT_NEAR(p.length, 6.0, 1e-9);
    EXPECT_GT(p.band_m, 0.2);
    EXPECT_NEAR(p.band_m, planner.bandLength(p.path), 1e-12);
  }
  // Without the band's cost the shorter route always wins.
  {
    GlobalPathOptions opt = rectangleOptions();
    opt.band_cost = 0.0;
    GlobalPathPlanner planner(wallWithSlot(0.7, 7.5), opt);
    EXPECT_TRUE(planner.plan({3, 6}, {9, 6}).passage);
  }
}

TEST(GlobalPath, TheRouteKeepsItsMapForAGoalUntilTheOtherIsCheaperByTheHysteresis) {
  // From (3, 6) the slot wins; from (5, 10.5), beside the door 5 m up, the door wins by far.
  const PolygonMap m = wallWithSlot(0.7, 11.0);
  GlobalPathOptions sticky = rectangleOptions();
  sticky.route_hysteresis_m = 100.0;
  GlobalPathPlanner planner(m, sticky);
  EXPECT_TRUE(planner.plan({3, 6}, {9, 6}).passage);
  EXPECT_TRUE(planner.plan({5, 10.5}, {9, 6}).passage);  // held
  EXPECT_FALSE(planner.plan({5, 10.5}, {9, 6.5}).passage);  // a new goal chooses afresh
  GlobalPathPlanner loose(m, rectangleOptions());
  EXPECT_TRUE(loose.plan({3, 6}, {9, 6}).passage);
  EXPECT_FALSE(loose.plan({5, 10.5}, {9, 6}).passage);
}

TEST(GlobalPath, ARoundRobotsPassageMapIsItsMPrime) {
  GlobalPathOptions opt;
  opt.inflation_radius_m = 0.3;
  opt.passage_inflation_m = 0.3;  // inscribed radius + margin reaches the circumradius
  GlobalPathPlanner planner(twoRooms(), opt);
  EXPECT_FALSE(planner.hasPassageMap());
  GlobalPathOptions plain = opt;
  plain.passage_inflation_m = 0.0;
  GlobalPathPlanner before(twoRooms(), plain);
  const GlobalPath a = planner.plan({1, 0.5}, {7, 0.5});
  const GlobalPath b = before.plan({1, 0.5}, {7, 0.5});
  ASSERT_EQ(a.path.size(), b.path.size());
  for (std::size_t i = 0; i < a.path.size(); ++i) EXPECT_EQ(a.path[i], b.path[i]);
  // Its failure is the footprint's.
  opt.inflation_radius_m = opt.passage_inflation_m = 0.65;
  GlobalPathPlanner closed(twoRooms(), opt);
  EXPECT_EQ(closed.plan({1, 2}, {7, 2}).status, PathStatus::kNoPassage);
}

TEST(GlobalPath, GoalInsideARealObstacleIsAnErrorGoalNearAWallIsMoved) {
  GlobalPathPlanner planner(twoRooms(), GlobalPathOptions{});
  EXPECT_EQ(planner.plan({1, 2}, {4.0, 0.5}).status, PathStatus::kGoalInObstacle);
  EXPECT_EQ(planner.plan({1, 2}, {9.0, 2.0}).status, PathStatus::kGoalInObstacle);  // outside the bounds
  const GlobalPath p = planner.plan({1, 2}, {7.9, 2.0});  // 0.1 m from the east wall
  ASSERT_EQ(p.status, PathStatus::kFound);
  EXPECT_TRUE(p.goal_moved);
  EXPECT_EQ(p.path.back(), Vec2(7.9, 2.0));
  EXPECT_NEAR(p.path[p.path.size() - 2].x(), 8.0 - 0.3, 0.04);
}

// Three posts whose inflated shapes close the gaps between them but leave a small hole in
// the middle: M''s free space there is a sliver cut off from the rest. A robot centre inside
// M' next to the hole (its nearest free point in the hole) still gets its path out.
TEST(GlobalPath, AStartWhoseNearestFreePointIsACutOffSliverGetsThePathFromAroundIt) {
  const Vec2 c(5.0, 2.0);
  const PolygonMap m = test::postsAroundAHole(c);
  GlobalPathOptions opt;
  opt.inflation_radius_m = 0.472;  // the paper agent's circumradius
  GlobalPathPlanner planner(m, opt);
  const Vec2 goal(1.0, 1.0);
  // The hole is free and cut off: from its middle there is no path (M' says so, and rightly
  // for a robot of that radius).
  const GlobalPath inside = planner.plan(c, goal);
  EXPECT_EQ(inside.status, PathStatus::kNoPath);
  EXPECT_FALSE(inside.start_moved);
  // Just below the hole: inside M', its nearest free point in the hole. Without trying
  // the points around it: no path.
  const Vec2 start = test::startBelowTheHole(c);
  GlobalPathOptions plain = opt;
  plain.nudge_start = false;
  GlobalPathPlanner stuck(m, plain);
  const GlobalPath none = stuck.plan(start, goal);
  EXPECT_EQ(none.status, PathStatus::kNoPath);
  EXPECT_TRUE(none.start_moved);
  const GlobalPath out = planner.plan(start, goal);
  ASSERT_EQ(out.status, PathStatus::kFound);
  EXPECT_TRUE(out.start_moved);
  EXPECT_TRUE(out.start_nudged);
  ASSERT_GE(out.path.size(), 2u);
  EXPECT_EQ(out.path.front(), start);
  EXPECT_EQ(out.path.back(), goal);
  // Out from a point within the inflation radius, then (nearly) straight to the goal.
  EXPECT_LE((out.path[1] - start).norm(), 0.472 + 1e-9);
  double length = 0.0;
  for (std::size_t i = 1; i < out.path.size(); ++i) length += (out.path[i] - out.path[i - 1]).norm();
  EXPECT_NEAR(out.length, length, 1e-9);
  EXPECT_GE(out.length, (goal - start).norm() - 1e-9);
  EXPECT_LE(out.length, (goal - start).norm() + 0.8);  // out of the posts first
  // Far from the posts nothing changes: the start is free, not nudged.
  const GlobalPath free_start = planner.plan({8.0, 4.0}, goal);
  ASSERT_EQ(free_start.status, PathStatus::kFound);
  EXPECT_FALSE(free_start.start_nudged);
  EXPECT_EQ(free_start.path.front(), Vec2(8.0, 4.0));
}

TEST(GlobalPath, PersonInTheDoorFallsBackToTheStaticPath) {
  GlobalPathPlanner planner(twoRooms(), GlobalPathOptions{});
  // An inflated person filling the door.
  const Polygon person{{3.5, 1.2}, {4.5, 1.2}, {4.5, 2.8}, {3.5, 2.8}};
  const PolygonView view(person);
  const GlobalPath p = planner.plan({1, 2}, {7, 2}, std::span<const PolygonView>(&view, 1));
  ASSERT_EQ(p.status, PathStatus::kFound);
  EXPECT_FALSE(p.dynamic);
  EXPECT_NEAR(p.length, 6.0, 1e-9);  // straight through the door, as if the person were not there
  // A person beside the path is avoided by the dynamic path.
  const Polygon aside{{1.8, 1.8}, {2.2, 1.8}, {2.2, 2.2}, {1.8, 2.2}};
  const PolygonView v2(aside);
  const GlobalPath q = planner.plan({1, 2}, {7, 2}, std::span<const PolygonView>(&v2, 1));
  ASSERT_EQ(q.status, PathStatus::kFound);
  EXPECT_TRUE(q.dynamic);
  EXPECT_GT(q.length, 6.0);
}

// A robot that follows its path sits on segments that graze inflated corners and slide along
// inflated walls, a rounding error inside or outside them. Every cycle must still find the
// path (regression: a start a hair inside a wall once blocked every way out).
TEST(GlobalPath, FindsThePathFromEveryPointAlongItAcrossTheOffice) {
  const PolygonMap office = generateOfficeMap();
  GlobalPathPlanner planner(office, GlobalPathOptions{});
  const Vec2 start{1.5, 4.5}, goal{25.5, 22.5};  // two room centres far apart
  const GlobalPath first = planner.plan(start, goal);
  ASSERT_EQ(first.status, PathStatus::kFound);
  const double total = first.length;
  EXPECT_GT(total, (goal - start).norm());
  const std::vector<Vec2> path(first.path.begin(), first.path.end());
  int queries = 0;
  double travelled = 0.0;
  for (std::size_t k = 0; k + 1 < path.size(); ++k) {
    const double len = (path[k + 1] - path[k]).norm();
    for (double t = 0.0; t < len; t += 0.05) {
      const Vec2 p = path[k] + (path[k + 1] - path[k]) * (t / len);
      const GlobalPath r = planner.plan(p, goal);
      ASSERT_EQ(r.status, PathStatus::kFound) << "at " << p.transpose();
      // The rest of the same path is still the shortest (a start a rounding error inside a
      // wall is nudged out by 1e-6 m, which the length then includes).
      EXPECT_NEAR(r.length, total - travelled - t, 1e-5) << "at " << p.transpose();
      ++queries;
    }
    travelled += len;
  }
  EXPECT_GT(queries, 500);
}

// The same on a real map: a robot following paths across the imported warehouse, with its
// thousands of short, nearly collinear edges. Regression: a start exactly on an edge's line
// once counted as "a hair to the left" of it in one test and "on it" in another.
TEST(GlobalPath, FindsThePathFromEveryPointAlongItAcrossTheWarehouse) {
  const auto yaml = test::sharedDir() / "maps/ros/warehouse.yaml";
  STAA_REQUIRE_SHARED_FILE(yaml);
  const PolygonMap map = importRosMap(yaml, ImportOptions{});
  GlobalPathPlanner planner(map, GlobalPathOptions{});
  std::vector<Vec2> free_points;
  const Box b = *map.bounds;
  for (double x = b.min.x() + 0.5; x < b.max.x(); x += 1.0) {
    for (double y = b.min.y() + 0.5; y < b.max.y(); y += 1.0) {
      const GlobalPath p = planner.plan({x, y}, {x, y});
      if (!planner.insideRealObstacle({x, y}) && p.status == PathStatus::kFound && !p.start_moved) free_points.push_back({x, y});
    }
  }
  ASSERT_GT(free_points.size(), 300u);
  std::mt19937_64 rng(2);
  int trips = 0, queries = 0;
  const double far = 0.5 * std::hypot(b.width(), b.height());
  while (trips < 16) {
    const Vec2 a = free_points[rng() % free_points.size()], goal = free_points[rng() % free_points.size()];
    if ((a - goal).norm() < far) continue;
    ++trips;
    const GlobalPath first = planner.plan(a, goal);
    ASSERT_EQ(first.status, PathStatus::kFound);
    const std::vector<Vec2> path(first.path.begin(), first.path.end());
    for (std::size_t k = 0; k + 1 < path.size(); ++k) {
      const double len = (path[k + 1] - path[k]).norm();
      for (double t = 0.0; t < len; t += 0.05, ++queries) {
        const Vec2 p = path[k] + (path[k + 1] - path[k]) * (t / len);
        ASSERT_EQ(planner.plan(p, goal).status, PathStatus::kFound) << "at " << p.transpose() << " to " << goal.transpose();
      }
    }
  }
  EXPECT_GT(queries, 5000);
}

TEST(GlobalPath, BoundsWallsEncloseTheBox) {
  const auto walls = boundsWalls(Box{{0, 0}, {2, 1}}, 1.0);
  ASSERT_EQ(walls.size(), 4u);
  EXPECT_TRUE(test::referencePointFree({1, 0.5}, walls));
  EXPECT_FALSE(test::referencePointFree({-0.5, 0.5}, walls));
  EXPECT_FALSE(test::referencePointFree({2.5, 0.5}, walls));
  EXPECT_FALSE(test::referencePointFree({1, -0.5}, walls));
  EXPECT_FALSE(test::referencePointFree({1, 1.5}, walls));
}

}  // namespace
}  // namespace staa
