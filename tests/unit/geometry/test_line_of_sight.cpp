#include "geometry/line_of_sight.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace staa {
namespace {

Polygon rect(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

TEST(LineOfSight, AWallBlocksWhatLiesBehindItAndTouchingCounts) {
  const std::vector<Polygon> walls{rect(4.0, 0.0, 5.0, 4.0), rect(8.0, 8.0, 9.0, 9.0)};
  const LineOfSight sight(walls);
  EXPECT_FALSE(sight.empty());
  EXPECT_FALSE(sight.clear(Vec2(2.0, 1.0), Vec2(7.0, 1.0)));   // through the wall
  EXPECT_TRUE(sight.clear(Vec2(2.0, 5.0), Vec2(7.0, 5.0)));    // above it
  EXPECT_FALSE(sight.clear(Vec2(2.0, 4.0), Vec2(7.0, 4.0)));   // along its top edge
  EXPECT_FALSE(sight.clear(Vec2(3.0, 3.0), Vec2(5.0, 5.0)));   // grazing its corner (4, 4)
  EXPECT_TRUE(sight.clear(Vec2(3.0, 3.1), Vec2(4.9, 5.0)));    // just above that corner
  EXPECT_TRUE(sight.clear(Vec2(3.0, 1.0), Vec2(3.9, 1.0)));    // stopping short of it
  EXPECT_FALSE(sight.clear(Vec2(7.0, 7.0), Vec2(10.0, 10.0)));  // the second polygon
  EXPECT_TRUE(sight.clear(Vec2(2.0, 1.0), Vec2(2.0, 1.0)));    // a point in the open
}

TEST(LineOfSight, DegeneratePolygonsAndNoPolygonsBlockNothing) {
  const std::vector<Polygon> degenerate{{{0.0, -1.0}, {0.0, 1.0}}};
  EXPECT_TRUE(LineOfSight(degenerate).clear(Vec2(-1.0, 0.0), Vec2(1.0, 0.0)));
  EXPECT_TRUE(LineOfSight(degenerate).empty());
  EXPECT_TRUE(LineOfSight().clear(Vec2(-1.0, 0.0), Vec2(1.0, 0.0)));
}

}  // namespace
}  // namespace staa
