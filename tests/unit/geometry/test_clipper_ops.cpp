#include "geometry/clipper_ops.hpp"
#include "geometry/polygon.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

double totalArea(const std::vector<Polygon>& polys) {
  double a = 0.0;
  for (const Polygon& p : polys) a += std::abs(signedArea(p));
  return a;
}

TEST(ClipperOps, UnionOfOverlappingSquaresHasTheirCombinedArea) {
  const std::vector<Polygon> in{{{0, 0}, {2, 0}, {2, 2}, {0, 2}}, {{1, 1}, {1, 3}, {3, 3}, {3, 1}}};  // second is CW
  const auto regions = unitePolygons(in);
  ASSERT_EQ(regions.size(), 1u);
  EXPECT_TRUE(regions[0].holes.empty());
  EXPECT_NEAR(signedArea(regions[0].outer), 7.0, 1e-9);
}

TEST(ClipperOps, RingOfWallsKeepsItsRoomAsAHoleAndRemoveHolesOpensIt) {
  // Four walls around a 2 x 2 m room.
  const std::vector<Polygon> walls{{{0, 0}, {3, 0}, {3, 0.5}, {0, 0.5}},
                                   {{0, 2.5}, {3, 2.5}, {3, 3}, {0, 3}},
                                   {{0, 0}, {0.5, 0}, {0.5, 3}, {0, 3}},
                                   {{2.5, 0}, {3, 0}, {3, 3}, {2.5, 3}}};
  const auto regions = unitePolygons(walls);
  ASSERT_EQ(regions.size(), 1u);
  ASSERT_EQ(regions[0].holes.size(), 1u);
  EXPECT_NEAR(std::abs(signedArea(regions[0].holes[0])), 4.0, 1e-9);

  const auto simple = removeHoles(regions, 1e-3);
  EXPECT_GE(simple.size(), 2u);
  for (const Polygon& p : simple) {
    EXPECT_FALSE(findSelfIntersection(p).has_value());
    // The room's centre stays free, the walls stay blocked.
    EXPECT_NE(locatePoint({1.5, 1.5}, p), Containment::kInside);
  }
  bool wall_covered = false;
  for (const Polygon& p : simple) wall_covered |= pointInPolygon({1.5, 0.25}, p);
  EXPECT_TRUE(wall_covered);
  // The pieces overlap by a sliver along each cut, never leave a gap.
  EXPECT_GT(totalArea(simple), 9.0 - 4.0);
  EXPECT_LT(totalArea(simple), 9.0 - 4.0 + 0.01);
}

TEST(ClipperOps, InflationGrowsByTheRadius) {
  const std::vector<Polygon> box{{{0, 0}, {1, 0}, {1, 1}, {0, 1}}};
  const auto grown = inflatePolygons(box, 0.5, 0.001);
  ASSERT_EQ(grown.size(), 1u);
  // A unit square grown by r has area 1 + 4r + pi r^2.
  EXPECT_NEAR(signedArea(grown[0].outer), 1.0 + 4 * 0.5 + kPi * 0.25, 0.01);
  EXPECT_TRUE(pointInPolygon({-0.45, 0.5}, grown[0].outer));
  EXPECT_FALSE(pointInPolygon({-0.55, 0.5}, grown[0].outer));
}

TEST(ClipperOps, InflationClosesADoorNarrowerThanTwiceTheRadius) {
  // A U of walls with a 0.4 m door; r = 0.3 closes it, so the room becomes a hole.
  const std::vector<Polygon> u{{{0, 0}, {3, 0}, {3, 0.2}, {0, 0.2}},
                               {{0, 0}, {0.2, 0}, {0.2, 3}, {0, 3}},
                               {{2.8, 0}, {3, 0}, {3, 3}, {2.8, 3}},
                               {{0, 2.8}, {1.3, 2.8}, {1.3, 3}, {0, 3}},
                               {{1.7, 2.8}, {3, 2.8}, {3, 3}, {1.7, 3}}};
  const auto open = inflatePolygons(u, 0.1);
  ASSERT_EQ(open.size(), 1u);
  EXPECT_TRUE(open[0].holes.empty());
  const auto closed = inflatePolygons(u, 0.3);
  ASSERT_EQ(closed.size(), 1u);
  EXPECT_EQ(closed[0].holes.size(), 1u);
}

}  // namespace
}  // namespace staa
