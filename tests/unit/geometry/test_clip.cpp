#include "geometry/clip.hpp"
#include "geometry/polygon.hpp"

#include <gtest/gtest.h>

#include <array>

namespace staa {
namespace {

constexpr std::size_t kCapacity = 32;

// Clips into fixed buffers and returns the result as an owning polygon for the assertions.
Polygon clipped(const Polygon& in, const Box& box) {
  std::array<Vec2, kCapacity> out{}, scratch{};
  const FixedResult r = clipToBox(in, box, out, scratch);
  EXPECT_TRUE(r.ok);
  return Polygon(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(r.size));
}

const Box kBox{{0, 0}, {2, 2}};

TEST(ClipToBox, SquarePartlyOutsideKeepsTheOverlapOnly) {
  const Polygon c = clipped({{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}, kBox);
  ASSERT_EQ(c.size(), 4u);
  EXPECT_DOUBLE_EQ(signedArea(c), 1.0);
  for (const Vec2& p : c) EXPECT_TRUE(kBox.contains(p));
  const Box bounds = boundingBox(c);
  EXPECT_EQ(bounds.min, Vec2(0, 0));
  EXPECT_EQ(bounds.max, Vec2(1, 1));
}

TEST(ClipToBox, PolygonFullyInsideIsUnchangedAndFullyOutsideIsEmpty) {
  const Polygon inside{{0.5, 0.5}, {1.5, 0.5}, {1.0, 1.5}};
  EXPECT_EQ(clipped(inside, kBox), inside);
  EXPECT_TRUE(clipped({{3, 3}, {4, 3}, {4, 4}, {3, 4}}, kBox).empty());
  // Outside although its bounding box overlaps the box: a thin diagonal sliver past the corner.
  EXPECT_TRUE(clipped({{3.2, 1.0}, {3.7, 1.0}, {1.0, 3.7}, {1.0, 3.2}}, kBox).empty());
}

TEST(ClipToBox, PolygonCoveringTheBoxBecomesTheBox) {
  const Polygon c = clipped({{-5, -5}, {5, -5}, {5, 5}, {-5, 5}}, kBox);
  EXPECT_DOUBLE_EQ(signedArea(c), 4.0);
  EXPECT_EQ(boundingBox(c).min, kBox.min);
  EXPECT_EQ(boundingBox(c).max, kBox.max);
}

TEST(ClipToBox, TriangleCutOnThreeSidesHasItsAnalyticArea) {
  // {x in [1, 3], y in [0, 2], x + y <= 4}: 2 (x in [1, 2]) + 1.5 (x in [2, 3]) = 3.5.
  const Polygon tri{{0, 0}, {4, 0}, {0, 4}};
  EXPECT_NEAR(signedArea(clipped(tri, Box{{1, 0}, {3, 2}})), 3.5, 1e-12);
  // Clockwise input keeps its winding.
  EXPECT_NEAR(signedArea(clipped(Polygon(tri.rbegin(), tri.rend()), Box{{1, 0}, {3, 2}})), -3.5, 1e-12);
}

TEST(ClipToBox, NonConvexLKeepsItsAreaInsideTheBox) {
  const Polygon l_shape{{0, 0}, {0, 3}, {1, 3}, {1, 1}, {3, 1}, {3, 0}};  // clockwise, area 5
  // Vertical arm 0.5 x 2 plus horizontal arm 1.5 x 0.5.
  const Polygon c = clipped(l_shape, Box{{0.5, 0.5}, {2.5, 2.5}});
  EXPECT_NEAR(signedArea(c), -1.75, 1e-12);
  EXPECT_EQ(locatePoint({0.75, 2.0}, c), Containment::kInside);
  EXPECT_EQ(locatePoint({2.0, 2.0}, c), Containment::kOutside);  // the notch stays empty
}

TEST(ClipToBox, UCutIntoTwoPartsGetsAZeroWidthBridgeButTheRightArea) {
  // A U whose two prongs are all that is left inside the box: Sutherland-Hodgman joins them
  // by a bridge running along the box's bottom edge y = 2.
  const Polygon u_shape{{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}};
  ASSERT_DOUBLE_EQ(signedArea(u_shape), 7.0);
  const Polygon c = clipped(u_shape, Box{{-1, 2}, {4, 4}});
  EXPECT_NEAR(signedArea(c), 2.0, 1e-12);  // two 1 x 1 prongs
  int on_bridge_line = 0;
  for (const Vec2& p : c) on_bridge_line += p.y() == 2.0;
  EXPECT_GE(on_bridge_line, 4);
  EXPECT_TRUE(findSelfIntersection(c).has_value());  // the bridge makes it non-simple
  EXPECT_EQ(locatePoint({0.5, 2.5}, c), Containment::kInside);
  EXPECT_EQ(locatePoint({2.5, 2.5}, c), Containment::kInside);
  EXPECT_EQ(locatePoint({1.5, 2.5}, c), Containment::kOutside);  // between the prongs
}

TEST(ClipToBox, ReportsOverflowWithoutWritingPastTheOutput) {
  const Polygon square{{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  std::array<Vec2, 8> out{}, scratch{};
  out.fill(Vec2(7, 7));
  const FixedResult r = clipToBox(square, kBox, std::span<Vec2>(out.data(), 3), scratch);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.size, 0u);
  for (std::size_t i = 3; i < out.size(); ++i) EXPECT_EQ(out[i], Vec2(7, 7));
  // A too-small scratch is reported the same way.
  EXPECT_FALSE(clipToBox(square, kBox, out, std::span<Vec2>(scratch.data(), 2)).ok);
  // Empty input: an empty, valid result.
  const FixedResult empty = clipToBox(PolygonView{}, kBox, out, scratch);
  EXPECT_TRUE(empty.ok);
  EXPECT_EQ(empty.size, 0u);
}

TEST(TransformPolygon, PlacesTheFootprintAtAPoseAndMayWorkInPlace) {
  const Polygon footprint{{0.4, 0.2}, {0.4, -0.2}, {-0.4, -0.25}, {-0.4, 0.25}};
  const Pose2 pose{1.0, 2.0, kPi / 2};
  std::array<Vec2, 4> out{};
  const FixedResult r = transformPolygon(footprint, pose, out);
  ASSERT_TRUE(r.ok);
  ASSERT_EQ(r.size, 4u);
  EXPECT_NEAR(out[0].x(), 0.8, 1e-12);
  EXPECT_NEAR(out[0].y(), 2.4, 1e-12);
  EXPECT_NEAR(out[2].x(), 1.25, 1e-12);
  EXPECT_NEAR(out[2].y(), 1.6, 1e-12);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR((out[i] - pose.transform(footprint[i])).norm(), 0.0, 1e-15);
  EXPECT_NEAR(signedArea(out), signedArea(footprint), 1e-12);  // rigid: area and winding kept

  Polygon in_place = footprint;
  ASSERT_TRUE(transformPolygon(in_place, pose, in_place).ok);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(in_place[i], out[i]);
}

TEST(TransformPolygon, RefusesAnOutputTooSmallAndLeavesItUntouched) {
  const Polygon footprint{{0.4, 0.2}, {0.4, -0.2}, {-0.4, -0.25}, {-0.4, 0.25}};
  std::array<Vec2, 3> out{Vec2(7, 7), Vec2(7, 7), Vec2(7, 7)};
  const FixedResult r = transformPolygon(footprint, Pose2{1, 1, 0.3}, out);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.size, 0u);
  for (const Vec2& p : out) EXPECT_EQ(p, Vec2(7, 7));
}

}  // namespace
}  // namespace staa
