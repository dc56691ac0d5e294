#include "experiment/multi_sim.hpp"
#include "experiment/sight_obstacles.hpp"

#include "geometry/polygon.hpp"
#include "robot/robot_profile.hpp"
#include "world/multi_world.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace staa {
namespace {

Polygon rect(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

Polygon moved(const Polygon& p, const Vec2& by) {
  Polygon out = p;
  for (Vec2& v : out) v += by;
  return out;
}

bool equal(PolygonView a, PolygonView b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin());
}

// A wall from the floor to y = 4 between the eye at (2, 1) and a body at (8, 1).
const std::vector<Polygon> kWall{rect(4.0, 0.0, 5.0, 4.0)};

TEST(SightObstacles, ABodyBehindAWallIsNotReportedOneInTheOpenIsExactly) {
  const LineOfSight sight(kWall);
  SightObstacles s(sight, 2, 4, SightConfig{8.0, 1.5});
  const Vec2 eye(2.0, 1.0);
  const Polygon hidden = rect(7.8, 0.8, 8.2, 1.2);
  EXPECT_FALSE(s.observe(0.0, eye, 0, hidden, Vec2(0.0, 1.0), 0.0));
  EXPECT_FALSE(s.inSight(0));
  // Above the wall's top, in the open: its exact footprint, velocity and turn rate.
  const Polygon open = rect(3.0, 5.0, 3.4, 5.4);
  ASSERT_TRUE(s.observe(0.0, eye, 1, open, Vec2(-1.0, 0.5), 0.25));
  EXPECT_TRUE(s.inSight(1));
  EXPECT_TRUE(equal(s.footprint(1), open));
  EXPECT_EQ(s.velocity(1), Vec2(-1.0, 0.5));
  EXPECT_EQ(s.turnRate(1), 0.25);
  // Behind the wall, one vertex peeking past its corner (4, 4) is enough: the line from the
  // eye over that corner reaches y = 6.4 at x = 5.6.
  EXPECT_FALSE(s.observe(0.0, eye, 0, rect(5.6, 5.9, 6.0, 6.3), Vec2(0.0, 0.0), 0.0));
  EXPECT_TRUE(s.observe(0.0, eye, 0, rect(5.6, 6.2, 6.0, 6.6), Vec2(0.0, 0.0), 0.0));
}

TEST(SightObstacles, ABodyThatLeavesTheSightIsKeptMovingOnThenForgotten) {
  const LineOfSight sight(kWall);
  SightObstacles s(sight, 1, 4, SightConfig{8.0, 1.5});
  const Vec2 eye(2.0, 1.0);
  const Polygon seen = rect(3.0, 5.0, 3.4, 5.4);  // in the open
  ASSERT_TRUE(s.observe(10.0, eye, 0, seen, Vec2(0.0, -1.0), 0.5));
  // 1 s later it stands behind the wall: reported where its velocity took it.
  ASSERT_TRUE(s.observe(11.0, eye, 0, rect(6.8, 2.0, 7.2, 2.4), Vec2(0.0, 0.0), 0.0));
  EXPECT_FALSE(s.inSight(0));
  EXPECT_TRUE(equal(s.footprint(0), moved(seen, Vec2(0.0, -1.0))));
  EXPECT_EQ(s.velocity(0), Vec2(0.0, -1.0));  // the last seen ones
  EXPECT_EQ(s.turnRate(0), 0.5);
  EXPECT_TRUE(s.observe(11.5, eye, 0, rect(6.8, 2.0, 7.2, 2.4), Vec2(0.0, 0.0), 0.0));
  EXPECT_TRUE(equal(s.footprint(0), moved(seen, Vec2(0.0, -1.5))));
  // Unseen for more than keep_s: forgotten.
  EXPECT_FALSE(s.observe(11.6, eye, 0, rect(6.8, 2.0, 7.2, 2.4), Vec2(0.0, 0.0), 0.0));
}

TEST(SightObstacles, ABodyBeyondRangeIsNotSeenAndBadSettingsAreRefused) {
  const LineOfSight sight{};
  SightObstacles s(sight, 1, 4, SightConfig{3.0, 0.0});
  EXPECT_FALSE(s.observe(0.0, Vec2(0.0, 0.0), 0, rect(3.1, -0.2, 3.5, 0.2), Vec2(0.0, 0.0), 0.0));
  EXPECT_TRUE(s.observe(0.0, Vec2(0.0, 0.0), 0, rect(2.9, -0.2, 3.3, 0.2), Vec2(0.0, 0.0), 0.0));
  // keep_s 0: out of sight is forgotten at once.
  EXPECT_FALSE(s.observe(0.1, Vec2(0.0, 0.0), 0, rect(3.1, -0.2, 3.5, 0.2), Vec2(0.0, 0.0), 0.0));
  EXPECT_THROW(SightObstacles(sight, 1, 4, SightConfig{0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(SightObstacles(sight, 1, 4, SightConfig{8.0, -1.0}), std::invalid_argument);
}

// A ghost walks from behind a wall round its end into the observed agent's sight. With
// --obstacles sight the agent's planner gets nothing while every vertex of the ghost is hidden
// (as checked here edge by edge), and the ghost's exact footprint and velocity from the first
// cycle one is in the open; with the truth it gets the ghost all along.
TEST(MultiSim, SightGivesTheOthersInTheLineOfSightExactly) {
  PolygonMap map;
  map.name = "wall";
  map.bounds = Box{Vec2(0.0, 0.0), Vec2(10.0, 7.0)};
  map.obstacles = kWall;
  MultiSimOptions o;
  o.agents = 2;
  o.mode = SimMode::kGhost;
  o.controller = ControllerKind::kStaa;
  o.duration_s = 6.0;
  o.budget = BudgetSpec::expansionsOf(200);
  o.starts = {Pose2{2.0, 1.0, 0.0}, Pose2{7.5, 1.0, 0.5 * kPi}};
  o.goal_sequences = {{Vec2(2.0, 1.0)}, {Vec2(7.5, 5.5), Vec2(2.0, 5.5)}};
  o.obstacles = ObstacleSource::kSight;

  const Polygon wall = kWall[0];
  auto visible = [&](PolygonView body, const Vec2& eye) {
    for (const Vec2& p : body) {
      bool blocked = false;
      for (std::size_t e = 0; e < wall.size(); ++e) {
        blocked = blocked || segmentsIntersect(eye, p, wall[e], wall[(e + 1) % wall.size()]);
      }
      if (!blocked) return true;
    }
    return false;
  };
  Polygon ghost;
  Vec2 ghost_velocity(0.0, 0.0);
  Vec2 eye(0.0, 0.0);
  o.on_step = [&](const MultiWorld& w) {
    ghost = w.footprint(1);
    ghost_velocity = w.velocity(1);
    eye = w.agent(0).pose.position();
  };
  int hidden_cycles = 0, visible_cycles = 0, mismatches = 0;
  bool ever_seen = false;
  int cycle = 0;
  o.on_obstacles = [&](std::size_t agent, std::span<const PolygonView> seen, std::span<const Vec2> velocities) {
    ASSERT_EQ(agent, 0u);
    if (cycle++ == 0) return;  // before the first step: the start poses (not yet in on_step)
    if (visible(ghost, eye)) {
      ever_seen = true;
      ++visible_cycles;
      mismatches += !(seen.size() == 1 && equal(seen[0], ghost) && velocities[0] == ghost_velocity);
    } else if (!ever_seen) {
      ++hidden_cycles;
      mismatches += !seen.empty();
    }
  };
  const MultiSimResult r = runMultiAgent(map, paperAgentProfile(), o);
  std::printf("sight: %d cycles hidden, %d in sight\n", hidden_cycles, visible_cycles);
  EXPECT_GT(hidden_cycles, 30);   // over a second behind the wall
  EXPECT_GT(visible_cycles, 15);  // half a second in the open
  EXPECT_EQ(mismatches, 0);
  EXPECT_GE(r.agents[1].goals_reached, 1);  // it did walk round the wall's end

  o.obstacles = ObstacleSource::kTruth;
  std::size_t fewest = 99;
  o.on_step = nullptr;
  o.on_obstacles = [&](std::size_t, std::span<const PolygonView> seen, std::span<const Vec2>) {
    fewest = std::min(fewest, seen.size());
  };
  (void)runMultiAgent(map, paperAgentProfile(), o);
  EXPECT_EQ(fewest, 1u);
}

}  // namespace
}  // namespace staa
