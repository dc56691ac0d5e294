// Paths around one polygon of 200,000 vertices (issue 18). The planner simplifies such a
// polygon outwards within 2 cm before inflating it (geometry/simplify.hpp); these tests hold
// the result to the original polygon: the path never comes nearer to it than the inflation
// radius, and it is no shorter than the true shortest path around it and longer by at most
// what the planner's margins allow (its 3 cm arc tolerance and the 2 cm simplification, each
// times the path's turning around the polygon).

#include "path/global_path.hpp"

#include "geometry/polygon.hpp"
#include "geometry/simplify.hpp"
#include "tests/support/big_polygons.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {
namespace {

constexpr std::size_t kVertices = 200000;

Polygon alternating(std::size_t n, double inner) { return test::alternating(n, 5.0, inner); }

PolygonMap mapOf(const Polygon& p) {
  PolygonMap map;
  map.name = "big polygon";
  map.bounds = Box{{-10.0, -10.0}, {10.0, 10.0}};
  map.obstacles.push_back(p);
  return map;
}

// The shortest path from a to b around the disk of radius r about the origin: the two
// tangents and the arc between their touching points.
double aroundDisk(const Vec2& a, const Vec2& b, double r) {
  const double angle = std::acos(std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0));
  const double arc = angle - std::acos(r / a.norm()) - std::acos(r / b.norm());
  if (arc <= 0.0) return (b - a).norm();
  return std::sqrt(a.squaredNorm() - r * r) + std::sqrt(b.squaredNorm() - r * r) + r * arc;
}

double segmentDistance(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  if (segmentsIntersect(a, b, c, d)) return 0.0;
  return std::min({distancePointSegment(a, c, d), distancePointSegment(b, c, d), distancePointSegment(c, a, b),
                   distancePointSegment(d, a, b)});
}

// The path's least distance to the polygon's boundary (every pair of segments).
double clearance(std::span<const Vec2> path, const Polygon& p) {
  double least = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < path.size(); ++i) {
    for (std::size_t j = 0; j < p.size(); ++j) {
      least = std::min(least, segmentDistance(path[i - 1], path[i], p[j], p[(j + 1) % p.size()]));
    }
  }
  return least;
}

// From (-8, 0) to (8, 0.1) around a polygon whose convex hull is the regular `hull`-gon
// inscribed in the 5 m circle: the true shortest path around the polygon grown by r lies
// between the paths around the disks of radius 5 cos(pi / hull) + r and 5 + r.
void expectShortPathAround(const Polygon& p, std::size_t hull) {
  const GlobalPathOptions opt;  // inflation 0.3 m, arc tolerance 3 cm
  GlobalPathPlanner planner(mapOf(p), opt);
  // M': the polygon's inflated outline first (then the bounds' four walls), a few dozen corners.
  ASSERT_EQ(planner.inflatedObstacles().size(), 5u);
  EXPECT_LT(planner.inflatedObstacles().front().size(), 200u);

  const Vec2 from{-8.0, 0.0}, to{8.0, 0.1};
  const GlobalPath path = planner.plan(from, to);
  ASSERT_EQ(path.status, PathStatus::kFound);
  ASSERT_GE(path.path.size(), 3u);
  EXPECT_EQ(path.path.front(), from);
  EXPECT_EQ(path.path.back(), to);

  // Never inside the polygon (the start is outside and the path never comes near its
  // boundary), and nowhere nearer to it than the inflation radius.
  EXPECT_EQ(locatePoint(from, p), Containment::kOutside);
  EXPECT_GE(clearance(path.path, p), opt.inflation_radius_m - 1e-9);

  const double shortest = aroundDisk(from, to, 5.0 * std::cos(kPi / static_cast<double>(hull)) + opt.inflation_radius_m);
  const double margins = aroundDisk(from, to, 5.0 + opt.inflation_radius_m + opt.arc_tolerance_m + kSimplifyTolerance_m);
  EXPECT_GE(path.length, shortest - 1e-9);
  EXPECT_LE(path.length, margins);
  // The margins' share: 5 cm times the 1.45 rad the path turns round the polygon.
  EXPECT_LT(margins - shortest, 0.075);
  ::testing::Test::RecordProperty("length_m", std::to_string(path.length));
  ::testing::Test::RecordProperty("shortest_m", std::to_string(shortest));
}

TEST(BigPolygon, PathAroundAToothedRingKeepsClearOfItAndIsNearlyShortest) {
  expectShortPathAround(alternating(kVertices, 4.9), kVertices / 2);
}

TEST(BigPolygon, PathAroundASpikyStarKeepsClearOfItAndIsNearlyShortest) {
  expectShortPathAround(alternating(kVertices, 0.5), kVertices / 2);
}

TEST(BigPolygon, PathAroundAFineCircleKeepsClearOfItAndIsNearlyShortest) {
  expectShortPathAround(alternating(kVertices, 5.0), kVertices);
}

TEST(BigPolygon, PathIntoARoundRoomGoesThroughItsDoor) {
  // A round room's wall: an annulus from 5.0 to 5.2 m, 100,000 vertices along each arc, a
  // 1 m door facing +x. From outside on the -x side to a point inside the room.
  const Polygon wall = test::roundRoomWall(kVertices / 2);
  const GlobalPathOptions opt;
  GlobalPathPlanner planner(mapOf(wall), opt);
  EXPECT_LT(planner.inflatedObstacles().front().size(), 400u);
  const Vec2 from{-8.0, 0.0}, to{-2.0, 0.5};
  const GlobalPath path = planner.plan(from, to);
  ASSERT_EQ(path.status, PathStatus::kFound);
  EXPECT_GE(clearance(path.path, wall), opt.inflation_radius_m - 1e-9);
  // Within the wall's radial band (5.0 to 5.2 m from the centre) it is in the doorway only.
  std::size_t through_door = 0;
  for (std::size_t i = 1; i < path.path.size(); ++i) {
    for (int k = 0; k <= 64; ++k) {
      const Vec2 q = path.path[i - 1] + (k / 64.0) * (path.path[i] - path.path[i - 1]);
      if (q.norm() >= 5.0 && q.norm() <= 5.2) {
        EXPECT_GT(q.x(), 4.9);
        EXPECT_LT(std::abs(q.y()), 0.5 - opt.inflation_radius_m + 0.05);
        ++through_door;
      }
    }
  }
  EXPECT_GT(through_door, 0u);
  EXPECT_GT(path.length, 2.0 * 5.5 + 5.5);
}

}  // namespace
}  // namespace staa
