#include "geometry/polygon.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

const Polygon kSquare{{0, 0}, {2, 0}, {2, 2}, {0, 2}};
// An L shape (non-convex), clockwise.
const Polygon kL{{0, 0}, {0, 3}, {1, 3}, {1, 1}, {3, 1}, {3, 0}};

TEST(Polygon, SignedAreaFollowsWinding) {
  EXPECT_DOUBLE_EQ(signedArea(kSquare), 4.0);
  EXPECT_DOUBLE_EQ(signedArea(kL), -5.0);
  EXPECT_TRUE(isCounterClockwise(kSquare));
  EXPECT_FALSE(isCounterClockwise(kL));
}

TEST(Polygon, LocatesPointsInsideOutsideAndOnTheBoundary) {
  EXPECT_EQ(locatePoint({1, 1}, kSquare), Containment::kInside);
  EXPECT_EQ(locatePoint({2, 1}, kSquare), Containment::kBoundary);
  EXPECT_EQ(locatePoint({2, 2}, kSquare), Containment::kBoundary);
  EXPECT_EQ(locatePoint({2.01, 1}, kSquare), Containment::kOutside);
  // The notch of the L is outside although it lies inside its bounding box.
  EXPECT_EQ(locatePoint({2, 2}, kL), Containment::kOutside);
  EXPECT_EQ(locatePoint({0.5, 2.5}, kL), Containment::kInside);
  EXPECT_EQ(locatePoint({2.5, 0.5}, kL), Containment::kInside);
  // A ray through a vertex (y = 1 passes the L's reflex corner) is counted once.
  EXPECT_EQ(locatePoint({0.5, 1.0}, kL), Containment::kInside);
  EXPECT_EQ(locatePoint({-1.0, 1.0}, kL), Containment::kOutside);
}

TEST(Polygon, SegmentsIntersectIncludingTouchingAndCollinear) {
  EXPECT_TRUE(segmentsIntersect({0, 0}, {2, 2}, {0, 2}, {2, 0}));
  EXPECT_TRUE(segmentsCrossProperly({0, 0}, {2, 2}, {0, 2}, {2, 0}));
  // T-junction: touching but not crossing.
  EXPECT_TRUE(segmentsIntersect({0, 0}, {2, 0}, {1, 0}, {1, 1}));
  EXPECT_FALSE(segmentsCrossProperly({0, 0}, {2, 0}, {1, 0}, {1, 1}));
  // Collinear overlap and collinear disjoint.
  EXPECT_TRUE(segmentsIntersect({0, 0}, {2, 0}, {1, 0}, {3, 0}));
  EXPECT_FALSE(segmentsIntersect({0, 0}, {1, 0}, {2, 0}, {3, 0}));
  EXPECT_FALSE(segmentsIntersect({0, 0}, {1, 1}, {0, 1}, {0.4, 0.6}));
  const auto t = segmentIntersectionParam({0, 0}, {4, 0}, {1, -1}, {1, 1});
  ASSERT_TRUE(t.has_value());
  EXPECT_DOUBLE_EQ(*t, 0.25);
}

TEST(Polygon, DistanceToEdgesMeasuresToNearestEdgeOrVertex) {
  EXPECT_DOUBLE_EQ(distanceToEdges({1, 1}, kSquare), 1.0);
  EXPECT_DOUBLE_EQ(distanceToEdges({3, 1}, kSquare), 1.0);
  EXPECT_NEAR(distanceToEdges({3, 3}, kSquare), std::sqrt(2.0), 1e-12);
  EXPECT_DOUBLE_EQ(distanceToEdges({2, 1}, kSquare), 0.0);
}

TEST(Polygon, FindsSelfIntersectionsAndAcceptsSimplePolygons) {
  EXPECT_FALSE(findSelfIntersection(kSquare).has_value());
  EXPECT_FALSE(findSelfIntersection(kL).has_value());
  const Polygon bowtie{{0, 0}, {2, 2}, {2, 0}, {0, 2}};
  EXPECT_TRUE(findSelfIntersection(bowtie).has_value());
  const Polygon repeated{{0, 0}, {1, 0}, {1, 0}, {1, 1}};
  EXPECT_TRUE(findSelfIntersection(repeated).has_value());
  // An edge that doubles back along its predecessor.
  const Polygon spike{{0, 0}, {2, 0}, {1, 0}, {1, 1}};
  EXPECT_TRUE(findSelfIntersection(spike).has_value());
  // Two lobes touching at a single vertex are not simple.
  const Polygon pinched{{0, 0}, {1, 1}, {2, 0}, {2, 2}, {1, 1}, {0, 2}};
  EXPECT_TRUE(findSelfIntersection(pinched).has_value());
}

}  // namespace
}  // namespace staa
