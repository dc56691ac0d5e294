// Moving obstacles: hulls of what perception reports, D(t) moved by v t, and D'(t) grown by
// a radius with chords outside the true round corners (contains the exact Minkowski sum, and
// not much more).
#include "local/dynamic_obstacles.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace staa {
namespace {

double perimeter(PolygonView p) {
  double s = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) s += (p[(i + 1) % p.size()] - p[i]).norm();
  return s;
}

// Distance from q to the closed convex polygon (0 inside).
double distanceTo(const Vec2& q, PolygonView p) {
  if (p.size() == 1) return (q - p[0]).norm();
  if (p.size() == 2) return distancePointSegment(q, p[0], p[1]);
  return locatePoint(q, p) == Containment::kOutside ? distanceToEdges(q, p) : 0.0;
}

bool covers(PolygonView poly, const Vec2& q) { return locatePoint(q, poly, 1e-9) != Containment::kOutside; }

// Checks D' against the exact grown shape of `base`: every point within r is covered (dense
// samples at distance exactly r around the boundary, plus random points), and every vertex of
// D' lies at least r and at most sqrt(2) r from the base.
void expectContainsGrownShape(PolygonView base, PolygonView inflated, double r) {
  ASSERT_GE(inflated.size(), 3u);
  EXPECT_TRUE(isConvex(inflated));
  EXPECT_GT(signedArea(inflated), 0.0);
  int samples = 0;
  for (std::size_t i = 0; i < base.size(); ++i) {
    // Around every vertex, and along every edge at its outward normal.
    for (int k = 0; k < 720; ++k) {
      const double a = 2.0 * kPi * k / 720.0;
      const Vec2 q = base[i] + r * Vec2{std::cos(a), std::sin(a)};
      EXPECT_TRUE(covers(inflated, q)) << "around vertex " << i << " at " << a;
      ++samples;
    }
    if (base.size() >= 3) {
      const Vec2 e = base[(i + 1) % base.size()] - base[i];
      const Vec2 n = Vec2{e.y(), -e.x()}.normalized();
      for (int k = 0; k <= 50; ++k) {
        EXPECT_TRUE(covers(inflated, base[i] + (k / 50.0) * e + r * n)) << "along edge " << i;
        ++samples;
      }
    }
  }
  std::mt19937_64 rng(11);
  Box b{base[0], base[0]};
  for (const Vec2& v : base) {
    b.min = b.min.cwiseMin(v);
    b.max = b.max.cwiseMax(v);
  }
  std::uniform_real_distribution<double> ux(b.min.x() - r, b.max.x() + r), uy(b.min.y() - r, b.max.y() + r);
  for (int k = 0; k < 5000; ++k) {
    const Vec2 q{ux(rng), uy(rng)};
    if (distanceTo(q, base) <= r) {
      EXPECT_TRUE(covers(inflated, q)) << q.transpose();
    }
  }
  for (const Vec2& v : inflated) {
    const double d = distanceTo(v, base);
    EXPECT_GE(d, r - 1e-9);
    EXPECT_LE(d, std::sqrt(2.0) * r + 1e-9);
  }
  EXPECT_GT(samples, 700);
}

TEST(DynamicObstacles, ObservedPolygonsBecomeTheirConvexHulls) {
  const Polygon l_shape{{0, 0}, {2, 0}, {2, 0.5}, {0.5, 0.5}, {0.5, 2}, {0, 2}};
  const Polygon clockwise_square{{5, 5}, {5, 6}, {6, 6}, {6, 5}};
  const PolygonView views[2] = {l_shape, clockwise_square};
  const Vec2 vel[2] = {{1.0, 0.0}, {0.0, -0.5}};
  DynamicObstacleSet set(4);
  set.set(views, vel);
  ASSERT_EQ(set.size(), 2u);
  EXPECT_EQ(set.dropped(), 0u);
  const FixedPolygon& h = set.observed(0);
  EXPECT_EQ(h.n, 5u);
  EXPECT_TRUE(isConvex(h.view()));
  EXPECT_NEAR(signedArea(h.view()), signedArea(convexHull(l_shape)), 1e-12);  // CCW, hull area
  for (const Vec2& p : l_shape) EXPECT_TRUE(covers(h.view(), p));
  EXPECT_EQ(h.box.min, Vec2(0, 0));
  EXPECT_EQ(h.box.max, Vec2(2, 2));
  EXPECT_NEAR(signedArea(set.observed(1).view()), 1.0, 1e-12);
  EXPECT_EQ(set.velocity(1), Vec2(0.0, -0.5));
}

TEST(DynamicObstacles, PredictionMovesByVelocityTimesTExactly) {
  const Polygon person{{1.0, 1.0}, {1.4, 0.9}, {1.6, 1.3}, {1.2, 1.6}, {0.9, 1.4}};
  const PolygonView views[1] = {person};
  const Vec2 vel[1] = {{0.7, -1.3}};
  DynamicObstacleSet set;
  set.set(views, vel);
  FixedPolygon out;
  for (double t : {0.0, 0.3, 0.6, 0.9, 2.5}) {
    set.predict(0, t, out);
    const FixedPolygon& o = set.observed(0);
    ASSERT_EQ(out.n, o.n);
    for (std::size_t i = 0; i < o.n; ++i) {
      EXPECT_DOUBLE_EQ(out.v[i].x(), o.v[i].x() + 0.7 * t);
      EXPECT_DOUBLE_EQ(out.v[i].y(), o.v[i].y() - 1.3 * t);
    }
    EXPECT_NEAR(out.box.min.x(), 0.9 + 0.7 * t, 1e-12);
    EXPECT_NEAR(out.box.max.y(), 1.6 - 1.3 * t, 1e-12);
    EXPECT_NEAR(signedArea(out.view()), signedArea(o.view()), 1e-12);
  }
}

TEST(DynamicObstacles, InflatedContainsEverythingWithinRadiusAndAreaIsNearExact) {
  const std::vector<Polygon> shapes{
      Polygon{{0, 0}, {0.6, 0}, {0.6, 0.4}, {0, 0.4}},                      // a cart
      Polygon{{0, 0}, {1.0, 0.1}, {0.2, 0.3}},                               // a sharp sliver
      Polygon{{0, 0}, {0.5, -0.1}, {0.8, 0.3}, {0.4, 0.7}, {-0.1, 0.4}},     // irregular pentagon
  };
  const double r = 0.3;
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const PolygonView views[1] = {shapes[s]};
    const Vec2 vel[1] = {{-0.4, 0.25}};
    DynamicObstacleSet set;
    set.set(views, vel);
    FixedPolygon moved, grown;
    const double t = 0.9;
    set.predict(0, t, moved);
    set.predictInflated(0, t, r, 8, grown);
    SCOPED_TRACE("shape " + std::to_string(s));
    expectContainsGrownShape(moved.view(), grown.view(), r);
    const double a = signedArea(moved.view()), p = perimeter(moved.view());
    const double exact = a + p * r + kPi * r * r;
    const double area = signedArea(grown.view());
    EXPECT_GE(area, exact - 1e-12);
    EXPECT_LT((area - exact) / exact, 0.03) << area << " vs " << exact;
    EXPECT_LE(grown.n, FixedPolygon::kCapacity);
    EXPECT_EQ(grown.n, std::max<std::size_t>(moved.n, 4) * 8);  // 8 arc segments per corner on average
    const Box bb = boundingBox(grown.view());
    EXPECT_EQ(grown.box.min, bb.min);
    EXPECT_EQ(grown.box.max, bb.max);
  }
}

TEST(DynamicObstacles, PointAndSegmentObstaclesGrowToCircleAndStadium) {
  const Polygon point{{2.0, 1.0}, {2.0, 1.0}, {2.0, 1.0}};
  const Polygon segment{{0.0, 0.0}, {1.0, 0.5}, {0.5, 0.25}};
  const PolygonView views[2] = {point, segment};
  DynamicObstacleSet set;
  set.set(views, {});  // no velocities: standing still
  ASSERT_EQ(set.observed(0).n, 1u);
  ASSERT_EQ(set.observed(1).n, 2u);
  EXPECT_EQ(set.velocity(0), Vec2::Zero());
  const double r = 0.25;
  for (std::size_t k = 0; k < 2; ++k) {
    FixedPolygon moved, grown;
    set.predict(k, 1.0, moved);
    set.predictInflated(k, 1.0, r, 8, grown);
    SCOPED_TRACE("obstacle " + std::to_string(k));
    expectContainsGrownShape(moved.view(), grown.view(), r);
    const double exact = 2.0 * perimeter(moved.view()) / 2.0 * r + kPi * r * r;  // 2 L r + pi r^2
    EXPECT_LT((signedArea(grown.view()) - exact) / exact, 0.03);
  }
}

// A hull with more vertices than kMaxHullVertices (a 500-gon person outline, say) is
// simplified outwards; D' then fits FixedPolygon::kCapacity and still contains the grown shape.
TEST(DynamicObstacles, ManyVerticesStayWithinCapacityAndConservative) {
  Polygon circle;
  for (int k = 0; k < 500; ++k) {
    const double a = 2.0 * kPi * k / 500.0;
    circle.push_back(Vec2{3.0, -1.0} + 0.4 * Vec2{std::cos(a), 0.7 * std::sin(a)});
  }
  const PolygonView views[1] = {circle};
  const Vec2 vel[1] = {{0.0, 1.0}};
  DynamicObstacleSet set;
  set.set(views, vel);
  const FixedPolygon& h = set.observed(0);
  EXPECT_LE(h.n, DynamicObstacleSet::kMaxHullVertices);
  EXPECT_GE(h.n, 8u);
  EXPECT_TRUE(isConvex(h.view()));
  for (const Vec2& p : circle) EXPECT_TRUE(covers(h.view(), p));
  EXPECT_LT(signedArea(h.view()) / signedArea(circle), 1.02);  // grown, but barely
  FixedPolygon moved, grown;
  set.predict(0, 0.5, moved);
  for (int steps : {1, 8, 64}) {
    set.predictInflated(0, 0.5, 0.3, steps, grown);
    EXPECT_LE(grown.n, FixedPolygon::kCapacity);
    expectContainsGrownShape(moved.view(), grown.view(), 0.3);
  }
}

TEST(DynamicObstacles, ObstaclesBeyondCapacityAreDroppedAndCounted) {
  const Polygon sq{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const PolygonView views[5] = {sq, sq, sq, sq, sq};
  DynamicObstacleSet set(3);
  set.set(views, {});
  EXPECT_EQ(set.size(), 3u);
  EXPECT_EQ(set.dropped(), 2u);
  set.clear();
  EXPECT_EQ(set.size(), 0u);
  EXPECT_EQ(set.dropped(), 0u);
}

TEST(DynamicObstacles, ZeroRadiusInflationIsThePrediction) {
  const Polygon sq{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const PolygonView views[1] = {sq};
  const Vec2 vel[1] = {{1.0, 2.0}};
  DynamicObstacleSet set;
  set.set(views, vel);
  FixedPolygon a, b;
  set.predict(0, 0.3, a);
  set.predictInflated(0, 0.3, 0.0, 8, b);
  ASSERT_EQ(a.n, b.n);
  for (std::size_t i = 0; i < a.n; ++i) EXPECT_EQ(a.v[i], b.v[i]);
}

// A body driving a circle: 0.8 x 0.4 m, centred at the origin, heading +x at 1 m/s and
// turning left at pi/2 rad/s (radius 2/pi m). After 1 s it has gone a quarter circle: centre at
// (2/pi, 2/pi), turned by 90 degrees (0.4 x 0.8 m); after 2 s half a circle: centre (0, 4/pi),
// heading -x. The braking hypothesis shortens the distance along the same circle.
TEST(DynamicObstacles, PredictTurningFollowsTheCircleAndTurnsThePolygonWithIt) {
  const Polygon body{{-0.4, -0.2}, {0.4, -0.2}, {0.4, 0.2}, {-0.4, 0.2}};
  const PolygonView views[1] = {body};
  const Vec2 vel[1] = {{1.0, 0.0}};
  const double turn[1] = {kPi / 2.0};
  DynamicObstacleSet set;
  set.set(views, vel, turn);
  EXPECT_DOUBLE_EQ(set.turnRate(0), kPi / 2.0);
  FixedPolygon out;
  const double r = 2.0 / kPi;
  set.predictTurning(0, 1.0, out);
  ASSERT_EQ(out.n, 4u);
  EXPECT_NEAR(0.5 * (out.box.min.x() + out.box.max.x()), r, 1e-12);
  EXPECT_NEAR(0.5 * (out.box.min.y() + out.box.max.y()), r, 1e-12);
  EXPECT_NEAR(out.box.max.x() - out.box.min.x(), 0.4, 1e-12);  // turned by 90 degrees
  EXPECT_NEAR(out.box.max.y() - out.box.min.y(), 0.8, 1e-12);
  EXPECT_NEAR(signedArea(out.view()), signedArea(set.observed(0).view()), 1e-12);
  set.predictTurning(0, 2.0, out);
  EXPECT_NEAR(0.5 * (out.box.min.x() + out.box.max.x()), 0.0, 1e-12);
  EXPECT_NEAR(0.5 * (out.box.min.y() + out.box.max.y()), 2.0 * r, 1e-12);
  EXPECT_NEAR(out.box.max.x() - out.box.min.x(), 0.8, 1e-12);
  // At t = 0 and with no turn rate: the straight prediction.
  FixedPolygon straight;
  set.predictTurning(0, 0.0, out);
  set.predict(0, 0.0, straight);
  for (std::size_t i = 0; i < out.n; ++i) EXPECT_NEAR((out.v[i] - straight.v[i]).norm(), 0.0, 1e-12);
  DynamicObstacleSet no_turn;
  no_turn.set(views, vel);
  EXPECT_EQ(no_turn.turnRate(0), 0.0);
  no_turn.predictTurning(0, 1.0, out);
  no_turn.predict(0, 1.0, straight);
  for (std::size_t i = 0; i < out.n; ++i) EXPECT_EQ(out.v[i], straight.v[i]);
  // Braking (no reaction time, 1 m/s^2): 0.5 m travelled by t = 1 s and no more after; along
  // the circle that is pi/4 of turn.
  set.setBraking(0.0, 1.0);
  set.predictTurning(0, 3.0, out);
  const double phi = kPi / 4.0;
  EXPECT_NEAR(0.5 * (out.box.min.x() + out.box.max.x()), r * std::sin(phi), 1e-12);
  EXPECT_NEAR(0.5 * (out.box.min.y() + out.box.max.y()), r * (1.0 - std::cos(phi)), 1e-12);
  // A copy keeps the turn rates; a non-finite one counts as 0.
  DynamicObstacleSet copy;
  copy.copyFrom(set);
  EXPECT_DOUBLE_EQ(copy.turnRate(0), kPi / 2.0);
  const double bad[1] = {std::nan("")};
  set.set(views, vel, bad);
  EXPECT_EQ(set.turnRate(0), 0.0);
}

}  // namespace
}  // namespace staa
