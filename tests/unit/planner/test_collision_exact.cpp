// Issue 16: where the route runs through a passage only the footprint fits, a pose the
// collision grid rejects is decided exactly. A 0.5 m wide robot in a 0.55 m slot: the grid's
// 5 cm cells (drawn conservatively) close the slot; the exact test of the footprint grown by
// 1 cm passes the centred pose and still rejects one 2 cm off centre (0.5 cm from the wall)
// and one that overlaps the wall.
#include "planner/collision.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

TEST(CollisionExact, ASlotTheGridClosesIsDecidedExactlyWhenTheMapAsks) {
  RobotProfile robot;
  robot.footprint = {{0.4, -0.25}, {0.4, 0.25}, {-0.4, 0.25}, {-0.4, -0.25}};
  const std::vector<Polygon> real = {{{5.9, 0.0}, {6.1, 0.0}, {6.1, 3.725}, {5.9, 3.725}},
                                     {{5.9, 4.275}, {6.1, 4.275}, {6.1, 8.0}, {5.9, 8.0}}};
  PolygonSet set;
  set.assign(std::span<const Polygon>(real), PolygonSet::Options{});
  LocalMap map;
  const Pose2 centred{6.0, 4.0, 0.0};
  map.update(centred, set, {}, 0.0);
  CollisionChecker checker(robot, LocalMapConfig{});
  checker.prepare(map);
  EXPECT_FALSE(checker.exactStatic());
  EXPECT_FALSE(checker.poseFreeStatic(centred));  // the grid alone: closed

  map.setExactStatic(true);
  ASSERT_EQ(map.realObstacles(), &set);
  checker.prepare(map);
  EXPECT_TRUE(checker.exactStatic());
  EXPECT_TRUE(checker.poseFreeStatic(centred));
  EXPECT_TRUE(checker.poseFreeStatic({6.0, 4.01, 0.0}));    // 1.5 cm from the wall
  EXPECT_FALSE(checker.poseFreeStatic({6.0, 4.02, 0.0}));   // 0.5 cm: within the margin
  EXPECT_FALSE(checker.poseFreeStatic({6.0, 4.04, 0.0}));   // overlaps the wall
  EXPECT_FALSE(checker.poseFreeStatic({6.0, 4.0, 0.3}));    // turned: a corner in the wall
  // A small obstacle wholly inside the footprint, touching none of its edges.
  const std::vector<Polygon> pebble = {{{5.95, 3.95}, {6.05, 3.95}, {6.05, 4.05}, {5.95, 4.05}}};
  PolygonSet pebble_set;
  pebble_set.assign(std::span<const Polygon>(pebble), PolygonSet::Options{});
  map.update({2.0, 4.0, 0.0}, pebble_set, {}, 0.0);
  map.setExactStatic(true);
  checker.prepare(map);
  EXPECT_FALSE(checker.poseFreeStatic(centred));
  // Every update() clears the request.
  map.update(centred, set, {}, 0.0);
  EXPECT_FALSE(map.exactStatic());
}

}  // namespace
}  // namespace staa
