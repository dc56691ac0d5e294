#include "geometry/simplify.hpp"

#include "geometry/polygon.hpp"
#include "geometry/splitmix64.hpp"
#include "tests/support/big_polygons.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {
namespace {

using test::alternating;
using test::roundRoomWall;

// A star-shaped outline with radii 4.95 + U(0, 0.05) m: the noise of an unsimplified scan.
Polygon noisyCircle(std::size_t n, std::uint64_t seed) {
  SplitMix64 rng(seed);
  Polygon p;
  for (std::size_t k = 0; k < n; ++k) {
    const double a = 2.0 * kPi * static_cast<double>(k) / static_cast<double>(n);
    const double r = 4.95 + 0.05 * rng.uniform();
    p.push_back({r * std::cos(a), r * std::sin(a)});
  }
  return p;
}

double distanceToBoundary(const Vec2& q, const Polygon& poly) {
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < poly.size(); ++i) {
    d = std::min(d, distancePointSegment(q, poly[i], poly[(i + 1) % poly.size()]));
  }
  return d;
}

// S is simple, contains P (every vertex and edge midpoint of P in the closed S, no edge of
// P crossing one of S), and every point of S lies within `tol` of P: S's vertices and points
// along its edges (they lie on P or outside it), and points strewn over S's box that are in
// S but not in P.
void expectConservative(const Polygon& p, const Polygon& s, double tol) {
  ASSERT_GE(s.size(), 3u);
  EXPECT_FALSE(findSelfIntersection(s).has_value());
  EXPECT_GT(signedArea(s), 0.0);
  std::size_t outside = 0, crossings = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec2& a = p[i];
    const Vec2& b = p[(i + 1) % p.size()];
    if (locatePoint(a, s) == Containment::kOutside || locatePoint(0.5 * (a + b), s) == Containment::kOutside) ++outside;
    for (std::size_t j = 0; j < s.size(); ++j) crossings += segmentsCrossProperly(a, b, s[j], s[(j + 1) % s.size()]);
  }
  EXPECT_EQ(outside, 0u);
  EXPECT_EQ(crossings, 0u);
  double worst = 0.0;
  for (std::size_t j = 0; j < s.size(); ++j) {
    for (int k = 0; k < 8; ++k) {
      const Vec2 q = s[j] + (k / 8.0) * (s[(j + 1) % s.size()] - s[j]);
      if (locatePoint(q, p) != Containment::kInside) worst = std::max(worst, distanceToBoundary(q, p));
    }
  }
  const Box box = boundingBox(s);
  SplitMix64 rng(7);
  for (int k = 0; k < 400; ++k) {
    const Vec2 q{box.min.x() + rng.uniform() * box.width(), box.min.y() + rng.uniform() * box.height()};
    if (pointInPolygon(q, s) && !pointInPolygon(q, p)) worst = std::max(worst, distanceToBoundary(q, p));
  }
  EXPECT_LE(worst, tol);
}

TEST(SimplifyOutward, ToothedRingBecomesAFewDozenCornersAroundItsTips) {
  const Polygon ring = alternating(20000, 5.0, 4.9);  // notches 1.6 mm wide, 10 cm deep
  const Polygon s = simplifyOutward(ring, 0.01);
  expectConservative(ring, s, 0.01);
  // A polygon circumscribed about r = 5 m within 1 cm needs pi / acos(5 / 5.01) = 50 corners.
  EXPECT_GE(s.size(), 50u);
  EXPECT_LE(s.size(), 60u);
}

TEST(SimplifyOutward, SpikyStarBecomesItsHullCircumscribed) {
  const Polygon star = alternating(20000, 5.0, 0.5);  // 10,000 spikes 4.5 m long
  const Polygon s = simplifyOutward(star, 0.01);
  expectConservative(star, s, 0.01);
  EXPECT_GE(s.size(), 50u);
  EXPECT_LE(s.size(), 60u);
}

TEST(SimplifyOutward, FineCircleBecomesACircumscribedPolygon) {
  const Polygon circle = alternating(20000, 5.0, 5.0);
  const Polygon s = simplifyOutward(circle, 0.01);
  expectConservative(circle, s, 0.01);
  EXPECT_GE(s.size(), 50u);
  EXPECT_LE(s.size(), 55u);
  // Circumscribed: no corner inside the circle, none beyond 1 cm outside it.
  for (const Vec2& q : s) {
    EXPECT_GE(q.norm(), 5.0 - 1e-9);
    EXPECT_LE(q.norm(), 5.01);
  }
}

TEST(SimplifyOutward, RoundRoomKeepsItsDoorAndItsRoom) {
  const Polygon wall = roundRoomWall(10000);
  const Polygon s = simplifyOutward(wall, 0.01);
  expectConservative(wall, s, 0.01);
  EXPECT_LE(s.size(), 200u);
  // The room and the door stay free: the centre, the middle of the doorway.
  EXPECT_FALSE(pointInPolygon({0.0, 0.0}, s));
  EXPECT_FALSE(pointInPolygon({5.1, 0.0}, s));
  EXPECT_FALSE(pointInPolygon({4.98, 0.0}, s));
  EXPECT_TRUE(pointInPolygon({0.0, 5.1}, s));
}

TEST(SimplifyOutward, NoiseDeeperThanTheToleranceStays) {
  // 5 cm of radial noise at 1.6 mm spacing: notches narrower than 2 cm are filled, the
  // rest of the noise is deeper than 1 cm and stays; whatever is done stays conservative.
  const Polygon noisy = noisyCircle(4000, 3);
  const Polygon s = simplifyOutward(noisy, 0.01);
  expectConservative(noisy, s, 0.01);
  EXPECT_LT(s.size(), noisy.size() * 3 / 4);
}

TEST(SimplifyOutward, ClockwiseInputComesBackCounterClockwise) {
  Polygon circle = alternating(4000, 5.0, 5.0);
  std::reverse(circle.begin(), circle.end());
  const Polygon s = simplifyOutward(circle, 0.01);
  expectConservative(circle, s, 0.01);
  EXPECT_LE(s.size(), 55u);
}

TEST(SimplifyOutward, SelfIntersectingOrTinyInputComesBackUnchanged) {
  const Polygon bowtie{{0, 0}, {1, 1}, {1, 0}, {0, 1}};
  EXPECT_EQ(simplifyOutward(bowtie, 0.01), bowtie);
  const Polygon triangle{{0, 0}, {1, 0}, {0, 1}};
  EXPECT_EQ(simplifyOutward(triangle, 0.01), triangle);
}

TEST(SimplifyIfBig, LeavesPolygonsUpToTheBoundAsTheyAre) {
  const Polygon at_bound = alternating(kSimplifyAboveVertices, 5.0, 5.0);
  EXPECT_EQ(simplifyIfBig(at_bound), at_bound);
  const Polygon past = alternating(kSimplifyAboveVertices + 2, 5.0, 5.0);
  const Polygon s = simplifyIfBig(past);
  EXPECT_LT(s.size(), past.size() / 4);
  expectConservative(past, s, kSimplifyTolerance_m);
}

}  // namespace
}  // namespace staa
