#include "path/root_horizon.hpp"

#include "geometry/clipper_ops.hpp"
#include "map/generate.hpp"
#include "path/minimal_construct.hpp"
#include "path/polygon_set.hpp"
#include "random_scenes.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

namespace staa {
namespace {

PolygonSet setOf(const std::vector<Polygon>& polygons, double cell = 0.0) {
  PolygonSet set;
  PolygonSet::Options o;
  o.cell_size = cell;
  set.assign(polygons, o);
  return set;
}

std::vector<Polygon> officeGrown() { return inflateEachToSimple(generateOfficeMap().obstacles, 0.38, 0.01); }

// Free segments the horizon certified, and free segments in all.
struct Tally {
  int certified = 0;
  int free = 0;
};

// Builds the table for root and region and checks that every segment it certifies is free by
// the exact test (the property the search relies on); adds to the tally.
void checkSound(const PolygonSet& set, const Vec2& root, const Box& region, std::mt19937_64& rng, int queries,
                Tally& t) {
  RootHorizon h;
  h.build(set, root, region);
  ASSERT_TRUE(h.builtFor(root));
  std::uniform_real_distribution<double> ux(region.min.x(), region.max.x()), uy(region.min.y(), region.max.y());
  std::uint32_t out[64];
  for (int q = 0; q < queries; ++q) {
    const Vec2 p{ux(rng), uy(rng)};
    const bool free = set.segmentBlockers(root, p, out) == 0;
    const bool certified = h.certifiesFree(p);
    if (certified) {
      EXPECT_TRUE(free) << "root " << root.transpose() << " p " << p.transpose();
      EXPECT_FALSE(set.segmentBlocked(root, p));
    }
    t.free += free ? 1 : 0;
    t.certified += certified ? 1 : 0;
  }
}

TEST(RootHorizon, EverySegmentItCertifiesIsFreeByTheExactTestOnRandomScenes) {
  std::mt19937_64 rng(16);
  Tally all;
  for (int scene_i = 0; scene_i < 60; ++scene_i) {
    // Half of them on a lattice: collinear edges, touching corners, roots on boundaries.
    const bool lattice = scene_i % 2 == 1;
    const test::RandomScene scene = test::makeRandomScene(rng, lattice, 4, 14, 12.0);
    const PolygonSet set = setOf(scene.polygons, scene_i % 3 == 0 ? 0.0 : 1.0);
    std::uniform_real_distribution<double> u(0.0, 12.0);
    for (int r = 0; r < 6; ++r) {
      Vec2 root{u(rng), u(rng)};
      if (lattice) root = (root * 2.0).array().round().matrix() / 2.0;
      if (set.pointBlocked(root)) continue;
      checkSound(set, root, Box{{1.0, 1.0}, {11.0, 11.0}}, rng, 300, all);
    }
  }
  // Not a certificate that never says yes: most free segments are vouched for (93 % here).
  ASSERT_GT(all.free, 10000);
  EXPECT_GT(all.certified, all.free * 8 / 10);
}

TEST(RootHorizon, VouchesForMostFreeEdgesFromGoalsInTheOffice) {
  const std::vector<Polygon> grown = officeGrown();
  const PolygonSet set = setOf(grown, 1.0);
  std::mt19937_64 rng(49);
  std::uniform_real_distribution<double> u(2.0, 26.0);
  Tally all;
  for (int r = 0; r < 40; ++r) {
    Vec2 root;
    do { root = {u(rng), u(rng)}; } while (set.pointBlocked(root));
    // A local box's worth around a point 4 m away, as the heuristic's region is.
    checkSound(set, root, Box{root - Vec2(8.0, 5.0), root + Vec2(1.0, 5.0)}, rng, 400, all);
  }
  ASSERT_GT(all.free, 2000);
  EXPECT_GT(all.certified, all.free * 9 / 10);
}

TEST(RootHorizon, SaysNothingOutsideItsRegionNorFromARootInsideAnObstacle) {
  const PolygonSet set = setOf({Polygon{{4.0, 4.0}, {6.0, 4.0}, {6.0, 6.0}, {4.0, 6.0}}});
  RootHorizon h;
  const Box region{{0.0, 0.0}, {3.0, 3.0}};
  h.build(set, Vec2(1.0, 1.0), region);
  EXPECT_TRUE(h.certifiesFree(Vec2(2.0, 2.5)));
  // Free, but beyond the region: the edges there were never looked at.
  EXPECT_FALSE(h.certifiesFree(Vec2(3.5, 1.0)));
  // A wider region: beside the square yes; behind it (the segment crosses it) or in it, no.
  RootHorizon wide;
  wide.build(set, Vec2(1.0, 1.0), Box{{0.0, 0.0}, {10.0, 10.0}});
  EXPECT_TRUE(wide.certifiesFree(Vec2(3.9, 1.0)));
  EXPECT_FALSE(wide.certifiesFree(Vec2(8.0, 8.0)));
  EXPECT_FALSE(wide.certifiesFree(Vec2(5.0, 5.0)));
  // The segment touching the square's corner only is free by the exact test; the table, which
  // keeps clear of every boundary, does not vouch for it (it need not).
  EXPECT_FALSE(wide.certifiesFree(Vec2(4.0, 4.0)));
  EXPECT_TRUE(wide.certifiesFree(Vec2(3.0, 3.0)));
  RootHorizon inside;
  inside.build(set, Vec2(5.0, 5.0), Box{{0.0, 0.0}, {10.0, 10.0}});
  EXPECT_FALSE(inside.certifiesFree(Vec2(5.5, 5.5)));
  EXPECT_FALSE(inside.certifiesFree(Vec2(9.0, 9.0)));
}

TEST(RootHorizon, TheSearchFindsTheSamePathsToTheBitWithAndWithoutIt) {
  const std::vector<Polygon> grown = officeGrown();
  const PolygonSet set = setOf(grown);
  MinimalConstruct a, b;
  a.setStaticObstacles(grown);
  b.setStaticObstacles(grown);
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-4.0, 4.0), g(1.0, 27.0);
  int found = 0;
  for (int goal_i = 0; goal_i < 12; ++goal_i) {
    Vec2 goal;
    do { goal = {g(rng), g(rng)}; } while (set.pointBlocked(goal));
    const Box region{goal - Vec2(5.0, 5.0), goal + Vec2(5.0, 5.0)};
    a.setStartRegion(region);
    // Many starts near one another for one goal, as STAA*'s states are: the table is built
    // after the first few and answers the rest.
    for (int q = 0; q < 80; ++q) {
      // Within the office's bounds (0 to 27 m); two statements, so that the draws come in the
      // same order on every compiler (a constructor's arguments have none).
      Vec2 start;
      do {
        const double dx = u(rng);
        const double dy = u(rng);
        start = goal + Vec2(dx, dy);
      } while (start.minCoeff() < 0.5 || start.maxCoeff() > 26.5 || set.pointBlocked(start));
      const MinimalConstruct::Result ra = a.query(start, goal, false);
      const MinimalConstruct::Result rb = b.query(start, goal, false);
      ASSERT_EQ(ra.status, rb.status) << "goal " << goal_i << " query " << q;
      EXPECT_EQ(ra.expansions, rb.expansions) << "goal " << goal_i << " query " << q;
      ASSERT_EQ(ra.path.size(), rb.path.size()) << "goal " << goal_i << " query " << q;
      EXPECT_EQ(std::memcmp(&ra.length, &rb.length, sizeof(double)), 0);
      for (std::size_t i = 0; i < ra.path.size(); ++i) {
        EXPECT_EQ(std::memcmp(ra.path[i].data(), rb.path[i].data(), 2 * sizeof(double)), 0) << "vertex " << i;
      }
      found += ra.status == MinimalConstruct::Status::kFound ? 1 : 0;
    }
  }
  EXPECT_GT(found, 900);
}

}  // namespace
}  // namespace staa
