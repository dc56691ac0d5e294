#include "geometry/polygon.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <utility>

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

namespace staa {

namespace {
// A random star-shaped polygon (simple) of n vertices around the origin, from a seeded LCG.
Polygon randomStar(std::size_t n, std::uint64_t seed) {
  Polygon p;
  for (std::size_t k = 0; k < n; ++k) {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    const double r = 1.0 + static_cast<double>(seed >> 40) / static_cast<double>(1ULL << 24);
    const double a = 6.283185307179586 * static_cast<double>(k) / static_cast<double>(n);
    p.push_back({std::round(r * std::cos(a) * 64.0) / 64.0, std::round(r * std::sin(a) * 64.0) / 64.0});
  }
  return p;
}
}  // namespace

TEST(Polygon, GridSelfIntersectionMatchesQuadraticOracle) {
  // Random stars, some with two vertices swapped (a crossing pair), on a coarse lattice so that
  // touching vertices, collinear overlaps and repeated vertices occur.
  std::size_t rejected = 0;
  for (std::uint64_t s = 1; s <= 3000; ++s) {
    Polygon p = randomStar(33 + s % 60, s);
    if (s % 2 == 0) std::swap(p[s % p.size()], p[(s * 7 + 3) % p.size()]);
    const auto fast = findSelfIntersection(p);
    const auto slow = findSelfIntersectionQuadratic(p);
    ASSERT_EQ(fast.has_value(), slow.has_value()) << "seed " << s;
    if (fast) {
      ++rejected;
      EXPECT_EQ(fast->first, slow->first) << "seed " << s;
      EXPECT_EQ(fast->second, slow->second) << "seed " << s;
    }
  }
  EXPECT_GT(rejected, 1000u);
}

TEST(Polygon, GridSelfIntersectionBigCircle) {
  Polygon c;
  const std::size_t n = 200000;
  for (std::size_t k = 0; k < n; ++k) {
    const double a = 6.283185307179586 * static_cast<double>(k) / static_cast<double>(n);
    c.push_back({10.0 * std::cos(a), 10.0 * std::sin(a)});
  }
  EXPECT_FALSE(findSelfIntersection(c).has_value());
  // One crossing pair far from vertex 0: edges 100000 and 100001 become a bow-tie.
  std::swap(c[100001], c[100002]);
  const auto e = findSelfIntersection(c);
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->first, 100000u);
  EXPECT_EQ(e->second, 100002u);
}

namespace {
// Whether edges i <= j of poly offend simplicity, as the scan judges them.
bool offends(const Polygon& p, std::size_t i, std::size_t j) {
  const std::size_t n = p.size();
  if (i == j) return p[i] == p[(i + 1) % n];
  Polygon four{p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]};
  if (j == i + 1 || (i == 0 && j == n - 1)) {
    // adjacent: they fold back over each other
    const Vec2& shared = j == i + 1 ? p[j] : p[i];
    const Vec2& a = j == i + 1 ? p[i] : p[(i + 1) % n];
    const Vec2& b = j == i + 1 ? p[(j + 1) % n] : p[j];
    const double c = (a - shared).x() * (b - shared).y() - (a - shared).y() * (b - shared).x();
    return c == 0.0 && (a - shared).dot(b - shared) > 0.0;
  }
  return segmentsIntersect(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]);
}
}  // namespace

TEST(Polygon, SweepDecidesSimplicityAsTheScanAndNamesAnOffendingPair) {
  // Lattice stars (touching vertices, collinear overlaps, repeated vertices) and random
  // lattice polygons (mostly crossing), against the quadratic scan.
  std::size_t rejected = 0, accepted = 0;
  std::uint64_t seed = 7;
  for (std::uint64_t s = 1; s <= 4000; ++s) {
    Polygon p;
    if (s % 4 == 3) {
      for (std::size_t k = 0; k < 4 + s % 9; ++k) {
        seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
        p.push_back({static_cast<double>((seed >> 33) % 7), static_cast<double>((seed >> 45) % 7)});
      }
    } else {
      p = randomStar(5 + s % 60, s);
      if (s % 2 == 0) std::swap(p[s % p.size()], p[(s * 7 + 3) % p.size()]);
    }
    const auto sweep = findSelfIntersectionSweep(p);
    const auto scan = findSelfIntersectionQuadratic(p);
    ASSERT_EQ(sweep.has_value(), scan.has_value()) << "seed " << s;
    if (sweep) {
      ++rejected;
      EXPECT_TRUE(offends(p, sweep->first, sweep->second)) << "seed " << s << ": " << sweep->first << ", " << sweep->second;
    } else {
      ++accepted;
    }
  }
  EXPECT_GT(rejected, 1000u);
  EXPECT_GT(accepted, 1000u);
}

TEST(Polygon, SpikyStarIsDecidedByTheSweep) {
  // Long spikes from near the centre: every spike's box covers a large share of any grid, so
  // the grid is not built (its memory would grow with n^2) and the sweep decides.
  Polygon star;
  const std::size_t n = 4000;
  for (std::size_t k = 0; k < n; ++k) {
    const double a = 6.283185307179586 * static_cast<double>(k) / static_cast<double>(n);
    const double r = k % 2 == 0 ? 100.0 : 0.5;
    star.push_back({r * std::cos(a), r * std::sin(a)});
  }
  EXPECT_FALSE(findSelfIntersection(star).has_value());
  std::swap(star[1001], star[1003]);  // two inner vertices swapped: their spikes cross
  const auto fast = findSelfIntersection(star);
  ASSERT_TRUE(fast.has_value());
  ASSERT_TRUE(findSelfIntersectionQuadratic(star).has_value());
  // The edges around the swapped vertices are the ones that cross.
  EXPECT_TRUE(offends(star, fast->first, fast->second));
  EXPECT_GE(fast->first, 1000u);
  EXPECT_LE(fast->second, 1003u);
}

TEST(Polygon, SweepHandlesAFineRingOf200000VerticesCrowdedInItsBox) {
  // A toothed ring: its edges fill a thin band of its box, so the grid's cells are crowded.
  Polygon ring;
  const std::size_t n = 200000;
  for (std::size_t k = 0; k < n; ++k) {
    const double a = 6.283185307179586 * static_cast<double>(k) / static_cast<double>(n);
    const double r = k % 2 == 0 ? 5.0 : 4.9;
    ring.push_back({r * std::cos(a), r * std::sin(a)});
  }
  EXPECT_FALSE(findSelfIntersection(ring).has_value());
  ring[150001] = ring[50001];  // a vertex repeated far away: two edges touch there
  const auto e = findSelfIntersection(ring);
  ASSERT_TRUE(e.has_value());
  EXPECT_TRUE(offends(ring, e->first, e->second));
}

}  // namespace staa
