#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <random>

namespace staa {
namespace {

Polygon translated(const Polygon& p, const Vec2& d) {
  Polygon q = p;
  for (Vec2& v : q) v += d;
  return q;
}

Polygon reversed(const Polygon& p) { return Polygon(p.rbegin(), p.rend()); }

// ---- hulls ----

TEST(ConvexHull, SquareWithCollinearInteriorAndRepeatedPointsGivesItsFourCornersCcw) {
  const Polygon points{{1, 1}, {2, 2}, {0, 0}, {1, 0}, {2, 0}, {2, 1}, {0, 2}, {1, 2},
                       {0, 1}, {0.5, 1.5}, {2, 2}, {0, 0}, {1, 0}, {2, 0.5}};
  const Polygon hull = convexHull(points);
  ASSERT_EQ(hull.size(), 4u);
  EXPECT_EQ(hull[0], Vec2(0, 0));
  EXPECT_EQ(hull[1], Vec2(2, 0));
  EXPECT_EQ(hull[2], Vec2(2, 2));
  EXPECT_EQ(hull[3], Vec2(0, 2));
  EXPECT_DOUBLE_EQ(signedArea(hull), 4.0);
}

TEST(ConvexHull, DegenerateSetsGiveDegenerateHulls) {
  EXPECT_TRUE(convexHull(Polygon{}).empty());
  const Polygon same = convexHull(Polygon{{1, 2}, {1, 2}, {1, 2}});
  ASSERT_EQ(same.size(), 1u);
  EXPECT_EQ(same[0], Vec2(1, 2));
  const Polygon line = convexHull(Polygon{{2, 2}, {0, 0}, {1, 1}, {3, 3}, {1, 1}, {0.5, 0.5}});
  ASSERT_EQ(line.size(), 2u);
  EXPECT_EQ(line[0], Vec2(0, 0));
  EXPECT_EQ(line[1], Vec2(3, 3));
  const Polygon triangle = convexHull(Polygon{{0, 0}, {4, 0}, {0, 3}, {2, 0}, {0, 3}});
  ASSERT_EQ(triangle.size(), 3u);
  EXPECT_DOUBLE_EQ(signedArea(triangle), 6.0);
}

TEST(ConvexHull, InPlaceFormRefusesAnOutputWithoutWorkingRoom) {
  std::array<Vec2, 4> points{Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  std::array<Vec2, 4> small_out{};
  EXPECT_EQ(convexHullInPlace(points, small_out), 0u);
  std::array<Vec2, 5> out{};
  ASSERT_EQ(convexHullInPlace(points, out), 4u);
  EXPECT_DOUBLE_EQ(signedArea(std::span<const Vec2>(out.data(), 4)), 1.0);
}

TEST(ConvexHull, RandomHullsAreConvexCcwAndContainEveryPoint) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> count(3, 40);
  for (int trial = 0; trial < 300; ++trial) {
    Polygon pts(static_cast<std::size_t>(count(rng)));
    // Snap to a coarse grid so that collinear and repeated points are common.
    for (Vec2& p : pts) p = Vec2(std::round(u(rng) * 4) / 4, std::round(u(rng) * 4) / 4);
    const Polygon hull = convexHull(pts);
    if (hull.size() < 3) continue;
    EXPECT_TRUE(isConvex(hull));
    EXPECT_GT(signedArea(hull), 0.0);
    for (std::size_t i = 0; i < hull.size(); ++i)  // no collinear hull vertices
      EXPECT_GT(orient(hull[i], hull[(i + 1) % hull.size()], hull[(i + 2) % hull.size()]), 0.0);
    for (const Vec2& p : pts) EXPECT_NE(locatePoint(p, hull), Containment::kOutside);
  }
}

TEST(IsConvex, AcceptsConvexOfEitherWindingAndRejectsLStarsFoldsAndSegments) {
  const Polygon square{{0, 0}, {2, 0}, {2, 2}, {0, 2}};
  EXPECT_TRUE(isConvex(square));
  EXPECT_TRUE(isConvex(reversed(square)));
  EXPECT_TRUE(isConvex(Polygon{{0, 0}, {1, 0}, {2, 0}, {2, 2}, {0, 2}}));          // collinear vertex
  EXPECT_TRUE(isConvex(Polygon{{0, 0}, {2, 0}, {2, 0}, {2, 2}, {0, 2}, {0, 0}}));  // repeated vertices
  EXPECT_FALSE(isConvex(Polygon{{0, 0}, {0, 3}, {1, 3}, {1, 1}, {3, 1}, {3, 0}}));  // L
  // Pentagram: every turn has the same sign but it winds twice.
  Polygon star;
  for (int i = 0; i < 5; ++i) star.emplace_back(std::cos(i * 4 * kPi / 5), std::sin(i * 4 * kPi / 5));
  EXPECT_FALSE(isConvex(star));
  EXPECT_FALSE(isConvex(Polygon{{0, 0}, {2, 0}, {1, 0}, {1, 1}}));  // folds back along an edge
  EXPECT_FALSE(isConvex(Polygon{{0, 0}, {1, 1}, {2, 2}}));          // zero area
  EXPECT_FALSE(isConvex(Polygon{{0, 0}, {1, 1}}));
  EXPECT_FALSE(isConvex(Polygon{}));
}

// ---- convex-convex tests: SAT, GJK and MPR on exact hand-made cases ----

using ConvexTest = bool (*)(PolygonView, PolygonView);
struct NamedTest {
  const char* name;
  ConvexTest test;
};
const NamedTest kConvexTests[] = {{"SAT", convexIntersectSat},
                                  {"GJK", convexIntersectGjk},
                                  {"MPR", convexIntersectMpr},
                                  {"convexIntersect", convexIntersect}};

const Polygon kUnitSquare{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
const Polygon kTriangle{{0, 0}, {2, 0}, {1, 1.5}};

TEST(ConvexIntersect, ClearOverlapSeparationContainmentAndIdentityAgreeForAllMethods) {
  for (const NamedTest& t : kConvexTests) {
    SCOPED_TRACE(t.name);
    EXPECT_TRUE(t.test(kUnitSquare, translated(kUnitSquare, {0.5, 0.3})));
    EXPECT_TRUE(t.test(kUnitSquare, reversed(translated(kTriangle, {0.4, 0.4}))));  // mixed windings
    EXPECT_FALSE(t.test(kUnitSquare, translated(kUnitSquare, {1.2, 0.0})));
    EXPECT_FALSE(t.test(kUnitSquare, translated(kTriangle, {1.1, 1.1})));
    // Separated only along a diagonal axis (the triangle's edge normal), not in x or y.
    EXPECT_FALSE(t.test(kUnitSquare, Polygon{{1.6, 0.5}, {0.5, 1.6}, {2, 2}}));
    // One containing the other, in both argument orders, and identical polygons.
    const Polygon inner{{0.4, 0.4}, {0.6, 0.4}, {0.6, 0.6}, {0.4, 0.6}};
    EXPECT_TRUE(t.test(kUnitSquare, inner));
    EXPECT_TRUE(t.test(inner, kUnitSquare));
    EXPECT_TRUE(t.test(kUnitSquare, kUnitSquare));
    EXPECT_TRUE(t.test(kTriangle, reversed(kTriangle)));
    EXPECT_FALSE(t.test(kUnitSquare, Polygon{}));
  }
}

TEST(ConvexIntersect, TouchingEdgeToEdgeAndVertexToEdgeCountsAsIntersectingForSat) {
  // Exact arithmetic on these coordinates, so the contact is exactly representable. Only SAT
  // (and so convexIntersect) is exact there; libccd's GJK and MPR answer a tie either way.
  const Polygon edge_to_edge = translated(kUnitSquare, {1.0, 0.5});
  const Polygon vertex_to_edge{{1.0, 0.5}, {2.0, 0.0}, {2.0, 1.0}};
  const Polygon vertex_to_vertex = translated(kUnitSquare, {1.0, 1.0});
  for (ConvexTest test : {convexIntersectSat, convexIntersect}) {
    EXPECT_TRUE(test(kUnitSquare, edge_to_edge));
    EXPECT_TRUE(test(kUnitSquare, vertex_to_edge));
    EXPECT_TRUE(test(vertex_to_edge, reversed(kUnitSquare)));
    EXPECT_TRUE(test(kUnitSquare, vertex_to_vertex));
  }
  // A micrometre either side of those contacts every method gets right.
  for (const NamedTest& t : kConvexTests) {
    SCOPED_TRACE(t.name);
    EXPECT_TRUE(t.test(kUnitSquare, translated(edge_to_edge, {-1e-6, 0.0})));
    EXPECT_FALSE(t.test(kUnitSquare, translated(edge_to_edge, {1e-6, 0.0})));
    EXPECT_TRUE(t.test(kUnitSquare, translated(vertex_to_edge, {-1e-6, 0.0})));
    EXPECT_FALSE(t.test(kUnitSquare, translated(vertex_to_edge, {1e-6, 0.0})));
    EXPECT_TRUE(t.test(kUnitSquare, translated(vertex_to_vertex, {-1e-6, -1e-6})));
    EXPECT_FALSE(t.test(kUnitSquare, translated(vertex_to_vertex, {1e-6, 1e-6})));
  }
}

TEST(ConvexIntersectSat, ExactToTheLastBitAtAContact) {
  // Next representable double beyond the contact: separated.
  const double gap = std::nextafter(1.0, 2.0) - 1.0;
  EXPECT_TRUE(convexIntersectSat(kUnitSquare, translated(kUnitSquare, {1.0, 0.0})));
  EXPECT_FALSE(convexIntersectSat(kUnitSquare, translated(kUnitSquare, {1.0 + gap, 0.0})));
}

TEST(ConvexIntersectSat, PointsAndSegmentsIntersectWhatTheyTouch) {
  const Polygon point_inside{{0.5, 0.5}};
  const Polygon point_on_edge{{1.0, 0.5}};
  const Polygon point_outside{{1.5, 0.5}};
  EXPECT_TRUE(convexIntersectSat(point_inside, kUnitSquare));
  EXPECT_TRUE(convexIntersectSat(kUnitSquare, point_on_edge));
  EXPECT_FALSE(convexIntersectSat(point_outside, kUnitSquare));
  EXPECT_TRUE(convexIntersectSat(point_inside, point_inside));
  EXPECT_FALSE(convexIntersectSat(point_inside, point_outside));

  const Polygon crossing{{-1, 0.5}, {2, 0.5}};           // a segment through the square
  const Polygon grazing{{-1, 1}, {2, 1}};                // along the top edge
  const Polygon touching_corner{{1, 1}, {2, 3}};         // starting at a corner
  const Polygon beside{{1.1, -1}, {1.1, 2}};             // parallel, 0.1 m away
  const Polygon three_collinear{{1, 2}, {1.5, 2.5}, {2, 3}};  // zero area with 3 vertices
  EXPECT_TRUE(convexIntersectSat(crossing, kUnitSquare));
  EXPECT_TRUE(convexIntersectSat(kUnitSquare, grazing));
  EXPECT_TRUE(convexIntersectSat(touching_corner, kUnitSquare));
  EXPECT_FALSE(convexIntersectSat(beside, kUnitSquare));
  EXPECT_FALSE(convexIntersectSat(three_collinear, kUnitSquare));

  // Collinear segments: only the axis along their line separates them.
  EXPECT_FALSE(convexIntersectSat(Polygon{{0, 0}, {1, 0}}, Polygon{{2, 0}, {3, 0}}));
  EXPECT_TRUE(convexIntersectSat(Polygon{{0, 0}, {1, 0}}, Polygon{{1, 0}, {3, 0}}));
  EXPECT_TRUE(convexIntersectSat(Polygon{{0, 0}, {2, 0}}, Polygon{{1, 0}}));
  EXPECT_FALSE(convexIntersectSat(Polygon{{0, 0}, {2, 0}}, Polygon{{3, 0}}));
  // Crossing segments (an X) and skew separated ones.
  EXPECT_TRUE(convexIntersectSat(Polygon{{0, 0}, {2, 2}}, Polygon{{0, 2}, {2, 0}}));
  EXPECT_FALSE(convexIntersectSat(Polygon{{0, 0}, {2, 2}}, Polygon{{0, 2}, {0.9, 1.1}}));
}

TEST(ConvexIntersectCcd, SegmentsAndPointsAgainstASquareDoNotDegenerate) {
  // The prism lifting keeps libccd's simplex 3-D even for a flat segment or a point.
  for (ConvexTest test : {convexIntersectGjk, convexIntersectMpr}) {
    EXPECT_TRUE(test(Polygon{{-1, 0.5}, {2, 0.5}}, kUnitSquare));
    EXPECT_FALSE(test(Polygon{{1.1, -1}, {1.1, 2}}, kUnitSquare));
    EXPECT_TRUE(test(Polygon{{0.5, 0.5}}, kUnitSquare));
    EXPECT_FALSE(test(Polygon{{1.5, 0.5}}, kUnitSquare));
    EXPECT_TRUE(test(Polygon{{0, 0}, {2, 2}}, Polygon{{0, 2}, {2, 0}}));
    EXPECT_FALSE(test(Polygon{{0, 0}, {2, 2}}, Polygon{{0, 2}, {0.9, 1.1}}));
  }
}

// ---- SAT vs GJK vs MPR on random pairs ----

// A random convex polygon: the hull of 3..12 random points, scaled, rotated, placed.
Polygon randomConvex(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> count(3, 12);
  const double scale = std::exp(std::uniform_real_distribution<double>(std::log(0.05), std::log(3.0))(rng));
  const double stretch = std::uniform_real_distribution<double>(0.1, 1.0)(rng);  // thin shapes too
  const Pose2 pose{unit(rng), unit(rng), kPi * unit(rng)};
  Polygon pts;
  for (int i = count(rng); i > 0; --i) pts.push_back(pose.transform({scale * unit(rng), stretch * scale * unit(rng)}));
  return convexHull(pts);
}

// Exact overlap, independent of the code under test: boundaries meet (exact orientation
// predicates) or one polygon holds a vertex of the other strictly inside.
bool overlapsExactly(const Polygon& a, const Polygon& b) {
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t k = 0; k < b.size(); ++k)
      if (segmentsIntersect(a[i], a[(i + 1) % a.size()], b[k], b[(k + 1) % b.size()])) return true;
  return locatePoint(a[0], b, 0.0) == Containment::kInside || locatePoint(b[0], a, 0.0) == Containment::kInside;
}

// Exact signed clearance: the boundary distance when apart, minus the penetration depth (the
// least overlap over the unit edge normals of both, exact for convex polygons) when overlapping.
double signedClearance(const Polygon& a, const Polygon& b) {
  if (!overlapsExactly(a, b)) {
    double d = std::numeric_limits<double>::infinity();
    for (const Vec2& p : a) d = std::min(d, distanceToEdges(p, b));
    for (const Vec2& p : b) d = std::min(d, distanceToEdges(p, a));
    return d;
  }
  double depth = std::numeric_limits<double>::infinity();
  for (const Polygon* poly : {&a, &b}) {
    const std::size_t n = poly->size();
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2 e = (*poly)[(i + 1) % n] - (*poly)[i];
      const Vec2 axis = Vec2(-e.y(), e.x()).normalized();
      double a_lo = 1e300, a_hi = -1e300, b_lo = 1e300, b_hi = -1e300;
      for (const Vec2& p : a) a_lo = std::min(a_lo, axis.dot(p)), a_hi = std::max(a_hi, axis.dot(p));
      for (const Vec2& p : b) b_lo = std::min(b_lo, axis.dot(p)), b_hi = std::max(b_hi, axis.dot(p));
      depth = std::min(depth, std::min(a_hi, b_hi) - std::max(a_lo, b_lo));
    }
  }
  return -depth;
}

// Moves b along `dir` from a's centre outwards to where it just stops touching a (bisection on
// the exact overlap test), then by `delta` further: the pair ends up grazing at any angle.
Polygon placedAtContact(const Polygon& a, const Polygon& b, const Vec2& dir, double delta) {
  Vec2 ca{0, 0}, cb{0, 0};
  for (const Vec2& p : a) ca += p;
  for (const Vec2& p : b) cb += p;
  const Polygon centred = translated(b, ca / static_cast<double>(a.size()) - cb / static_cast<double>(b.size()));
  double lo = 0.0, hi = 20.0;  // overlapping at lo, apart at hi (all shapes are < 7 m across)
  for (int i = 0; i < 200 && lo < hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (mid == lo || mid == hi) break;
    (overlapsExactly(a, translated(centred, mid * dir)) ? lo : hi) = mid;
  }
  return translated(centred, (hi + delta) * dir);
}

// SAT and GJK must match the exact answer on every pair more than 1e-9 m from contact. MPR
// (libccd 2.1's, not used by the cycle) is allowed one kind of error only, rarely: calling a
// pair intersecting that is apart (by up to 0.75 mm here, on sliver-thin shapes). It must
// never miss an overlap.
TEST(ConvexIntersect, SatGjkAndMprAgreeWithTheExactAnswerOnRandomAndNearTouchingPairs) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  constexpr int kPairs = 8000;
  constexpr double kExcluded = 1e-9;
  int compared = 0, near = 0, overlapping = 0, sat_wrong = 0, gjk_wrong = 0, mpr_wrong = 0;
  for (int i = 0; i < kPairs; ++i) {
    const Polygon a = randomConvex(rng);
    Polygon b = randomConvex(rng);
    if (a.size() < 3 || b.size() < 3) continue;
    if (i % 4 != 0) {
      // Three pairs in four are placed at contact, then moved a tiny +/- delta (or not at
      // all): touching, grazing or barely overlapping at random angles.
      const double angle = 2 * kPi * unit(rng);
      const double magnitude = std::pow(10.0, -12.0 + 10.0 * unit(rng));
      const double delta = i % 20 == 1 ? 0.0 : (unit(rng) < 0.5 ? -magnitude : magnitude);
      b = placedAtContact(a, b, Vec2(std::cos(angle), std::sin(angle)), delta);
    }
    const double clearance = signedClearance(a, b);
    if (std::abs(clearance) < kExcluded) continue;
    ++compared;
    if (std::abs(clearance) < 1e-6) ++near;
    const bool truth = clearance < 0.0;
    overlapping += truth;
    if (convexIntersectSat(a, b) != truth) {
      ++sat_wrong;
      ADD_FAILURE() << "SAT wrong at clearance " << clearance << " for pair " << i;
    }
    if (convexIntersectGjk(a, b) != truth) {
      ++gjk_wrong;
      ADD_FAILURE() << "GJK wrong at clearance " << clearance << " for pair " << i;
    }
    if (convexIntersectMpr(a, b) != truth) {
      ++mpr_wrong;
      if (truth) ADD_FAILURE() << "MPR missed an overlap of " << -clearance << " for pair " << i;
    }
  }
  std::printf("compared %d pairs (%d within 1e-6 m of contact, %d overlapping); MPR false alarms: %d\n",
              compared, near, overlapping, mpr_wrong);
  EXPECT_EQ(sat_wrong, 0);
  EXPECT_EQ(gjk_wrong, 0);
  EXPECT_LE(mpr_wrong, compared / 500);
  // The comparison is meaningful: over 5,000 pairs, many within a micrometre, both outcomes.
  EXPECT_GE(compared, 5000);
  EXPECT_GE(near, kPairs / 5);
  EXPECT_GE(overlapping, compared / 4);
  EXPECT_LE(overlapping, compared * 3 / 4);
}

// ---- non-convex pairs ----

TEST(CornerContainment, MissesTheCrossWhichPolygonsOverlapCatches) {
  // Two thin bars forming a "+": they overlap in the middle but no corner is inside the other.
  const Polygon horizontal{{-2, -0.1}, {2, -0.1}, {2, 0.1}, {-2, 0.1}};
  const Polygon vertical{{-0.1, -2}, {0.1, -2}, {0.1, 2}, {-0.1, 2}};
  EXPECT_FALSE(cornerContainment(horizontal, vertical));
  EXPECT_TRUE(polygonsOverlap(horizontal, vertical));
  EXPECT_TRUE(convexIntersect(horizontal, vertical));
}

TEST(CornerContainment, HandlesNonConvexPolygonsInsideOnAndInTheNotch) {
  const Polygon l_shape{{0, 0}, {0, 3}, {1, 3}, {1, 1}, {3, 1}, {3, 0}};  // clockwise
  const Polygon in_notch{{1.5, 1.5}, {2.5, 1.5}, {2.5, 2.5}, {1.5, 2.5}};
  const Polygon on_arm{{2, 0.5}, {4, 0.5}, {4, 2}, {2, 2}};  // corner (2, 0.5) inside the L
  const Polygon on_edge{{1, 1.5}, {1.5, 1.5}, {1.5, 2}};     // corner on the L's inner edge
  const Polygon around{{-1, -1}, {4, -1}, {4, 4}, {-1, 4}};  // contains the whole L
  EXPECT_FALSE(cornerContainment(l_shape, in_notch));
  EXPECT_FALSE(polygonsOverlap(l_shape, in_notch));
  EXPECT_TRUE(cornerContainment(l_shape, on_arm));
  EXPECT_TRUE(polygonsOverlap(on_arm, l_shape));
  EXPECT_TRUE(cornerContainment(on_edge, l_shape));
  EXPECT_TRUE(polygonsOverlap(l_shape, on_edge));
  EXPECT_TRUE(cornerContainment(l_shape, around));
  EXPECT_TRUE(polygonsOverlap(around, l_shape));
}

TEST(PolygonsOverlap, DegenerateInputsTouchWhatTheyMeetAndEmptyMeetsNothing) {
  const Polygon segment_through{{-1, 0.5}, {2, 0.5}};
  EXPECT_FALSE(cornerContainment(segment_through, kUnitSquare));  // both ends outside
  EXPECT_TRUE(polygonsOverlap(segment_through, kUnitSquare));
  EXPECT_TRUE(cornerContainment(Polygon{{1, 0.5}}, kUnitSquare));        // point on the edge
  EXPECT_TRUE(cornerContainment(kUnitSquare, Polygon{{1, 1}, {2, 2}}));  // corner on a segment
  EXPECT_FALSE(polygonsOverlap(Polygon{{1.5, 0.5}}, kUnitSquare));
  EXPECT_TRUE(polygonsOverlap(Polygon{{0, 0}, {2, 2}}, Polygon{{0, 2}, {2, 0}}));
  EXPECT_FALSE(polygonsOverlap(Polygon{}, kUnitSquare));
  EXPECT_FALSE(cornerContainment(kUnitSquare, Polygon{}));
}

}  // namespace
}  // namespace staa
