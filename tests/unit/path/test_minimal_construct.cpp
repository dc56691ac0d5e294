#include "path/minimal_construct.hpp"

#include "random_scenes.hpp"
#include "visibility_reference.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

namespace staa {
namespace {

MinimalConstruct makeSearch(const std::vector<Polygon>& polys, double cell = 1.0) {
  MinimalConstruct::Options o;
  o.grid_cell_m = cell;
  MinimalConstruct mc(o);
  mc.setStaticObstacles(polys);
  return mc;
}

double pathLength(std::span<const Vec2> path) {
  double l = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) l += (path[i] - path[i - 1]).norm();
  return l;
}

TEST(MinimalConstruct, StraightLineWhenNothingIsInTheWay) {
  MinimalConstruct mc = makeSearch({{{5, 5}, {6, 5}, {6, 6}, {5, 6}}});
  const auto r = mc.query({0, 0}, {3, 4}, false);
  ASSERT_EQ(r.status, MinimalConstruct::Status::kFound);
  ASSERT_EQ(r.path.size(), 2u);
  EXPECT_DOUBLE_EQ(r.length, 5.0);
  EXPECT_EQ(r.discovered, 0u);  // the square was never needed
}

TEST(MinimalConstruct, WrapsAroundASquareAtItsCorner) {
  // Square [1,3] x [-1,1] between (0,0) and (4,0): the path goes over (1,1) and (3,1).
  MinimalConstruct mc = makeSearch({{{1, -1}, {3, -1}, {3, 1}, {1, 1}}});
  const auto r = mc.query({0, 0.1}, {4, 0.1}, false);
  ASSERT_EQ(r.status, MinimalConstruct::Status::kFound);
  ASSERT_EQ(r.path.size(), 4u);
  EXPECT_EQ(r.path[1], Vec2(1, 1));
  EXPECT_EQ(r.path[2], Vec2(3, 1));
  EXPECT_NEAR(r.length, 2.0 * std::hypot(1.0, 0.9) + 2.0, 1e-12);
  EXPECT_EQ(r.discovered, 1u);
}

TEST(MinimalConstruct, EscapesAUShapedTrapWhosePocketFacesTheStart) {
  // The pocket opens towards -x; the start sits in front of it, the goal behind the U.
  const Polygon u{{2, -2}, {5, -2}, {5, 2}, {2, 2}, {2, 1.5}, {4.5, 1.5}, {4.5, -1.5}, {2, -1.5}};
  MinimalConstruct mc = makeSearch({u});
  const auto r = mc.query({3, 0}, {7, 0}, false);
  ASSERT_EQ(r.status, MinimalConstruct::Status::kFound);
  const auto ref = test::referenceShortestPath({3, 0}, {7, 0}, {u});
  ASSERT_TRUE(ref.has_value());
  EXPECT_NEAR(r.length, *ref, 1e-9);
  EXPECT_GT(r.length, 8.0);  // out of the pocket and around an arm
}

TEST(MinimalConstruct, ReportsNoPathIntoAClosedRoom) {
  const std::vector<Polygon> walls{{{0, 0}, {4, 0}, {4, 0.2}, {0, 0.2}}, {{0, 3.8}, {4, 3.8}, {4, 4}, {0, 4}},
                                   {{0, 0}, {0.2, 0}, {0.2, 4}, {0, 4}}, {{3.8, 0}, {4, 0}, {4, 4}, {3.8, 4}}};
  MinimalConstruct mc = makeSearch(walls);
  EXPECT_EQ(mc.query({-1, 2}, {2, 2}, false).status, MinimalConstruct::Status::kNoPath);
  EXPECT_EQ(mc.query({1, 1}, {2, 3}, false).status, MinimalConstruct::Status::kFound);
}

TEST(MinimalConstruct, MovesAStartInsideAnObstacleToTheNearestFreePoint) {
  MinimalConstruct mc = makeSearch({{{0, 0}, {2, 0}, {2, 2}, {0, 2}}});
  const auto r = mc.query({1.9, 1.0}, {5, 1}, false);
  ASSERT_EQ(r.status, MinimalConstruct::Status::kFound);
  EXPECT_TRUE(r.start_moved);
  EXPECT_FALSE(r.goal_moved);
  ASSERT_EQ(r.path.size(), 3u);
  EXPECT_EQ(r.path[0], Vec2(1.9, 1.0));  // the original start comes first
  EXPECT_NEAR(r.path[1].x(), 2.0, 1e-5);
  EXPECT_NEAR(r.path[1].y(), 1.0, 1e-9);
}

TEST(MinimalConstruct, DynamicObstaclesAreAvoidedOnlyWhenAsked) {
  MinimalConstruct mc = makeSearch({});
  const Polygon person{{2, -0.5}, {3, -0.5}, {3, 0.5}, {2, 0.5}};
  const PolygonView view(person);
  mc.setDynamicObstacles(std::span<const PolygonView>(&view, 1));
  const auto dyn = mc.query({0, 0}, {5, 0}, true);
  ASSERT_EQ(dyn.status, MinimalConstruct::Status::kFound);
  EXPECT_NEAR(dyn.length, 2.0 * std::hypot(2.0, 0.5) + 1.0, 1e-12);
  const auto stat = mc.query({0, 0}, {5, 0}, false);
  ASSERT_EQ(stat.status, MinimalConstruct::Status::kFound);
  EXPECT_DOUBLE_EQ(stat.length, 5.0);
}

TEST(MinimalConstruct, ReusesDiscoveredPolygonsForTheSameGoal) {
  const std::vector<Polygon> polys{{{1, -1}, {3, -1}, {3, 1}, {1, 1}}, {{5, -1}, {7, -1}, {7, 1}, {5, 1}}};
  MinimalConstruct mc = makeSearch(polys);
  const auto first = mc.query({0, 0}, {8, 0}, false);
  ASSERT_EQ(first.status, MinimalConstruct::Status::kFound);
  const double len1 = first.length;
  const auto again = mc.query({0, 0.05}, {8, 0}, false);
  ASSERT_EQ(again.status, MinimalConstruct::Status::kFound);
  EXPECT_LE(again.edge_checks, first.edge_checks);  // no rediscovery needed
  EXPECT_NEAR(again.length, *test::referenceShortestPath({0, 0.05}, {8, 0}, polys), 1e-9);
  EXPECT_NEAR(len1, *test::referenceShortestPath({0, 0}, {8, 0}, polys), 1e-9);
}

// The property the issue asks for: on 1,000 random maps with non-convex and overlapping
// polygons (half of them on a lattice, full of collinear edges and touching corners), the
// lazy search returns exactly the brute-force visibility-graph shortest path, and the path
// it returns is collision-free and as long as it claims. Four starts per goal, so three of
// every four queries resume a kept search tree.
TEST(MinimalConstruct, MatchesBruteForceVisibilityGraphOnRandomMaps) {
  std::mt19937_64 rng(2018);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int found = 0, none = 0;
  MinimalConstruct::Options opt;
  opt.grid_cell_m = 1.3;
  MinimalConstruct mc(opt);
  for (int map = 0; map < 1000; ++map) {
    const bool lattice = map % 2 == 1;
    auto scene = test::makeRandomScene(rng, lattice, 3, 10, 12.0);
    // Every tenth map has a closed room of four overlapping walls; its last query ends inside.
    const bool room = map % 10 == 0;
    const Vec2 rc{2 + 8 * u(rng), 2 + 8 * u(rng)};
    if (room) {
      const double a = 1.2, t = 0.15;
      scene.polygons.push_back({{rc.x() - a, rc.y() - a}, {rc.x() + a, rc.y() - a}, {rc.x() + a, rc.y() - a + t}, {rc.x() - a, rc.y() - a + t}});
      scene.polygons.push_back({{rc.x() - a, rc.y() + a - t}, {rc.x() + a, rc.y() + a - t}, {rc.x() + a, rc.y() + a}, {rc.x() - a, rc.y() + a}});
      scene.polygons.push_back({{rc.x() - a, rc.y() - a}, {rc.x() - a + t, rc.y() - a}, {rc.x() - a + t, rc.y() + a}, {rc.x() - a, rc.y() + a}});
      scene.polygons.push_back({{rc.x() + a - t, rc.y() - a}, {rc.x() + a, rc.y() - a}, {rc.x() + a, rc.y() + a}, {rc.x() + a - t, rc.y() + a}});
    }
    mc.setStaticObstacles(scene.polygons);
    // Queries 1 and 2 keep the goal of query 0 with new starts: they resume the kept tree.
    Vec2 g;
    do { g = {-0.5 + 13 * u(rng), -0.5 + 13 * u(rng)}; } while (!test::referencePointFree(g, scene.polygons));
    if (lattice) g = {std::round(g.x()), std::round(g.y())};
    if (room) g = rc;
    if (!test::referencePointFree(g, scene.polygons)) continue;
    for (int q = 0; q < 4; ++q) {
      Vec2 s;
      do { s = {-0.5 + 13 * u(rng), -0.5 + 13 * u(rng)}; } while (!test::referencePointFree(s, scene.polygons));
      if (lattice && q == 0) {  // lattice start: exact collinear contacts
        s = {std::round(s.x()), std::round(s.y())};
        if (!test::referencePointFree(s, scene.polygons)) continue;
      }
      const auto ref = test::referenceShortestPath(s, g, scene.polygons);
      const auto r = mc.query(s, g, false);
      if (!ref) {
        EXPECT_EQ(r.status, MinimalConstruct::Status::kNoPath) << "map " << map << " query " << q;
        ++none;
        continue;
      }
      ASSERT_EQ(r.status, MinimalConstruct::Status::kFound) << "map " << map << " query " << q;
      ASSERT_NEAR(r.length, *ref, 1e-9 * (1.0 + *ref)) << "map " << map << " query " << q;
      EXPECT_NEAR(pathLength(r.path), r.length, 1e-9);
      for (std::size_t i = 1; i < r.path.size(); ++i) {
        ASSERT_TRUE(test::referenceSegmentFree(r.path[i - 1], r.path[i], scene.polygons)) << "map " << map;
      }
      ++found;
    }
  }
  EXPECT_GT(found, 2000);
  EXPECT_GT(none, 40);  // the closed rooms really separate start and goal
}

// A start walled in by a ring of posts with one gap, the goal's tree already grown outside:
// the kept tree offers the start dozens of parents whose edges the ring blocks before the one
// through the gap (reattachStart takes them in order from its candidates). Every answer is the
// exact shortest path, as a fresh search's, and a ring without a gap gives no path.
TEST(MinimalConstruct, AWalledInStartTriesTheKeptTreesParentsInOrder) {
  std::vector<Polygon> posts;
  const Vec2 centre{0.0, 0.0};
  const double ring = 2.0, half = 0.22;
  for (int k = 0; k < 36; ++k) {
    if (k == 9) continue;  // the gap, towards +y
    const double a = 2.0 * std::numbers::pi * k / 36.0;
    const Vec2 c = centre + ring * Vec2(std::cos(a), std::sin(a));  // posts 0.35 m apart, 0.44 m wide: they overlap
    posts.push_back({{c.x() - half, c.y() - half}, {c.x() + half, c.y() - half}, {c.x() + half, c.y() + half}, {c.x() - half, c.y() + half}});
  }
  // Clutter outside the ring: more closed nodes in the kept tree.
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double x = -6.0 + 2.0 * i, y = -6.0 + 1.5 * j;
      posts.push_back({{x, y}, {x + 0.4, y}, {x + 0.4, y + 0.3}, {x, y + 0.3}});
    }
  }
  const Vec2 goal{0.5, -8.0};
  MinimalConstruct kept = makeSearch(posts);
  // Grow the goal's tree from outside first: from far corners, so most of it is closed.
  for (const Vec2& s : {Vec2(-8.0, 6.0), Vec2(8.0, 6.0), Vec2(0.0, 6.0)}) {
    ASSERT_EQ(kept.query(s, goal, false).status, MinimalConstruct::Status::kFound);
  }
  std::size_t most_checks = 0;
  for (const Vec2& s : {Vec2(0.0, 0.0), Vec2(0.7, -0.9), Vec2(-1.1, 0.3), Vec2(0.4, 1.2), Vec2(-0.2, -1.4)}) {
    const auto r = kept.query(s, goal, false);
    ASSERT_EQ(r.status, MinimalConstruct::Status::kFound) << s.transpose();
    MinimalConstruct fresh = makeSearch(posts);
    const auto f = fresh.query(s, goal, false);
    ASSERT_EQ(f.status, MinimalConstruct::Status::kFound);
    const auto ref = test::referenceShortestPath(s, goal, posts);
    ASSERT_TRUE(ref.has_value());
    EXPECT_NEAR(r.length, *ref, 1e-9) << s.transpose();
    EXPECT_NEAR(f.length, *ref, 1e-9) << s.transpose();
    // Out through the gap: the path passes y > 1.5 before it turns south.
    double top = -1e9;
    for (const Vec2& p : r.path) top = std::max(top, p.y());
    EXPECT_GT(top, 1.5) << s.transpose();
    for (std::size_t i = 1; i < r.path.size(); ++i) EXPECT_TRUE(test::referenceSegmentFree(r.path[i - 1], r.path[i], posts));
    most_checks = std::max<std::size_t>(most_checks, r.edge_checks);
  }
  EXPECT_GT(most_checks, 10u);  // blocked parents were really tried
  // The gap closed: no path, from the kept tree as from a fresh one.
  const double a = 2.0 * std::numbers::pi * 9 / 36.0;
  const Vec2 c = centre + ring * Vec2(std::cos(a), std::sin(a));
  posts.push_back({{c.x() - half, c.y() - half}, {c.x() + half, c.y() - half}, {c.x() + half, c.y() + half}, {c.x() - half, c.y() + half}});
  MinimalConstruct closed = makeSearch(posts);
  ASSERT_EQ(closed.query({0.0, 6.0}, goal, false).status, MinimalConstruct::Status::kFound);
  for (const Vec2& s : {Vec2(0.0, 0.0), Vec2(0.7, -0.9), Vec2(-1.1, 0.3)}) {
    EXPECT_EQ(closed.query(s, goal, false).status, MinimalConstruct::Status::kNoPath) << s.transpose();
  }
  EXPECT_EQ(closed.query({-8.0, 6.0}, goal, false).status, MinimalConstruct::Status::kFound);
}

}  // namespace
}  // namespace staa

namespace staa {
namespace {

// A clock that advances by a fixed step on every read: a deadline passes after a known
// number of checks.
std::int64_t g_fake_ns = 0;
std::int64_t fakeClock() { return g_fake_ns += 1000; }

TEST(MinimalConstructDeadline, APassedDeadlineAbortsAndTheNextQueryResumesToTheSamePath) {
  // A maze of staggered walls: the path needs many expansions.
  std::vector<Polygon> walls;
  for (int k = 0; k < 12; ++k) {
    const double x = 2.0 + 2.0 * k;
    if (k % 2 == 0) walls.push_back({{x, 0.0}, {x + 0.2, 0.0}, {x + 0.2, 8.0}, {x, 8.0}});
    else walls.push_back({{x, 2.0}, {x + 0.2, 2.0}, {x + 0.2, 10.0}, {x, 10.0}});
  }
  MinimalConstruct fresh = makeSearch(walls);
  const MinimalConstruct::Result reference = fresh.query({1.0, 5.0}, {27.0, 5.0}, false);
  ASSERT_EQ(reference.status, MinimalConstruct::Status::kFound);
  const double reference_length = reference.length;
  ASSERT_GT(reference.expansions, 20u);

  MinimalConstruct mc = makeSearch(walls);
  g_fake_ns = 0;
  const Deadline already{&fakeClock, 0};  // passed at the first check
  const MinimalConstruct::Result aborted = mc.query({1.0, 5.0}, {27.0, 5.0}, false, already);
  EXPECT_EQ(aborted.status, MinimalConstruct::Status::kAborted);
  EXPECT_TRUE(aborted.path.empty());

  // A deadline that passes after a few checks: some progress, still aborted.
  g_fake_ns = 0;
  const Deadline soon{&fakeClock, 2500};  // the third check
  const MinimalConstruct::Result partial = mc.query({1.0, 5.0}, {27.0, 5.0}, false, soon);
  EXPECT_EQ(partial.status, MinimalConstruct::Status::kAborted);

  // Without a deadline the kept tree is resumed: the same shortest path as a fresh search.
  const MinimalConstruct::Result resumed = mc.query({1.0, 5.0}, {27.0, 5.0}, false);
  ASSERT_EQ(resumed.status, MinimalConstruct::Status::kFound);
  EXPECT_NEAR(resumed.length, reference_length, 1e-9);
  // And from another start, too (the tree is valid for the goal).
  const MinimalConstruct::Result other = mc.query({3.0, 9.0}, {27.0, 5.0}, false);
  MinimalConstruct fresh2 = makeSearch(walls);
  const MinimalConstruct::Result other_ref = fresh2.query({3.0, 9.0}, {27.0, 5.0}, false);
  ASSERT_EQ(other.status, MinimalConstruct::Status::kFound);
  EXPECT_NEAR(other.length, other_ref.length, 1e-9);
}

}  // namespace
}  // namespace staa
