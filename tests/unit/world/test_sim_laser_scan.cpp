// The simulated planar scanner: ranges to the walls of a box room, the map's obstacles and
// movers, computed by hand; movers lower than the scan plane unseen; its noise and dropouts.
#include "world/sim_laser_scan.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

namespace staa::hal {
namespace {

constexpr double kDeg = kPi / 180.0;

// A 10 x 6 m room, nothing in it.
PolygonMap room() {
  PolygonMap m;
  m.bounds = Box{Vec2(0.0, 0.0), Vec2(10.0, 6.0)};
  return m;
}

// A UST-20LX-like sweep (270 degrees, 0.25 degrees apart) 0.5 m ahead of the base centre,
// without noise.
SimScanConfig exact() {
  SimScanConfig c;
  c.mount = ScanMount{0.5, 0.0, 0.2, 0.0};
  c.noise_m = 0.0;
  return c;
}

// The beam looking `deg` degrees left of the mount's yaw.
std::size_t beam(const SimScanConfig& c, double deg) {
  return static_cast<std::size_t>(std::lround((deg * kDeg - c.angle_min) / ((c.angle_max - c.angle_min) / (c.beams - 1))));
}

TEST(SimLaserScan, RangesToTheWallsOfABoxRoom) {
  const SimScanConfig c = exact();
  ScanRenderer scanner(room(), c);
  auto scan = std::make_unique<LaserScan>();
  // The base at (3, 2) facing east: the scanner at (3.5, 2).
  scanner.render(Pose2{3.0, 2.0, 0.0}, {}, *scan);
  ASSERT_EQ(scan->count, 1081u);
  EXPECT_NEAR(scan->angle_increment, 0.25 * kDeg, 1e-12);
  EXPECT_NEAR(scan->ranges[beam(c, 0.0)], 6.5, 1e-5);              // east wall
  EXPECT_NEAR(scan->ranges[beam(c, 90.0)], 4.0, 1e-5);             // north wall
  EXPECT_NEAR(scan->ranges[beam(c, -90.0)], 2.0, 1e-5);            // south wall
  EXPECT_NEAR(scan->ranges[beam(c, 45.0)], 4.0 * std::sqrt(2.0), 1e-5);  // north wall at x = 7.5
  EXPECT_NEAR(scan->ranges[beam(c, -135.0)], 2.0 * std::sqrt(2.0), 1e-5);  // south wall at x = 1.5
  // Every beam: the distance to the box's boundary along it.
  for (std::size_t i = 0; i < scan->count; ++i) {
    const double a = scan->angle_min + scan->angle_increment * static_cast<double>(i);
    const double dx = std::cos(a), dy = std::sin(a);
    double t = 1e9;
    if (dx > 0) t = std::min(t, (10.0 - 3.5) / dx);
    if (dx < 0) t = std::min(t, (0.0 - 3.5) / dx);
    if (dy > 0) t = std::min(t, (6.0 - 2.0) / dy);
    if (dy < 0) t = std::min(t, (0.0 - 2.0) / dy);
    ASSERT_NEAR(scan->ranges[i], t, 1e-5) << "beam " << i;
  }
  // Turned to face north: the mount is 0.5 m north of the base, beam 0 degrees meets y = 6.
  scanner.render(Pose2{3.0, 2.0, 0.5 * kPi}, {}, *scan);
  EXPECT_NEAR(scan->ranges[beam(c, 0.0)], 3.5, 1e-5);
  EXPECT_NEAR(scan->ranges[beam(c, 90.0)], 3.0, 1e-5);  // west wall from x = 3
}

TEST(SimLaserScan, MapObstaclesAndMoversTallerThanThePlaneStopTheBeams) {
  PolygonMap m = room();
  m.obstacles.push_back({{7.0, 1.0}, {8.0, 1.0}, {8.0, 3.0}, {7.0, 3.0}});  // a cabinet east of the scanner
  const SimScanConfig c = exact();
  ScanRenderer scanner(m, c);
  auto scan = std::make_unique<LaserScan>();
  scanner.render(Pose2{3.0, 2.0, 0.0}, {}, *scan);
  EXPECT_NEAR(scan->ranges[beam(c, 0.0)], 3.5, 1e-5);
  // A 0.4 m square person at (5.5, 2), 1.7 m tall: its west face is 1.8 m from the scanner.
  const Polygon body{{-0.2, -0.2}, {0.2, -0.2}, {0.2, 0.2}, {-0.2, 0.2}};
  const std::vector<PrismView> person{PrismView{PolygonView(body), Vec2(5.5, 2.0), 1.7}};
  scanner.render(Pose2{3.0, 2.0, 0.0}, person, *scan);
  EXPECT_NEAR(scan->ranges[beam(c, 0.0)], 1.8, 1e-5);
  // Its north-west corner at (5.3, 2.2) is at atan(0.2 / 1.8) = 6.34 degrees: 6 is on it, 7 is not.
  EXPECT_LT(scan->ranges[beam(c, 6.0)], 1.9);
  EXPECT_NEAR(scan->ranges[beam(c, 7.0)], 3.5 / std::cos(7.0 * kDeg), 1e-4);  // the cabinet
  // A box lower than the scan plane (0.1 m) is not seen.
  const std::vector<PrismView> low{PrismView{PolygonView(body), Vec2(5.5, 2.0), 0.1}};
  scanner.render(Pose2{3.0, 2.0, 0.0}, low, *scan);
  EXPECT_NEAR(scan->ranges[beam(c, 0.0)], 3.5, 1e-5);
}

TEST(SimLaserScan, BeyondTheRangeAndNearerThanItsMinimumThereIsNoReturn) {
  SimScanConfig c = exact();
  c.range_max = 3.0;
  ScanRenderer scanner(room(), c);
  auto scan = std::make_unique<LaserScan>();
  scanner.render(Pose2{3.0, 2.0, 0.0}, {}, *scan);
  EXPECT_EQ(scan->ranges[beam(c, 0.0)], 0.0F);  // 6.5 m: beyond 3 m
  EXPECT_NEAR(scan->ranges[beam(c, -90.0)], 2.0, 1e-5);
  c.range_min = 2.5;
  ScanRenderer near(room(), c);
  near.render(Pose2{3.0, 2.0, 0.0}, {}, *scan);
  EXPECT_EQ(scan->ranges[beam(c, -90.0)], 0.0F);  // 2 m: nearer than 2.5 m
}

TEST(SimLaserScan, NoiseAndDropoutsAreWhatTheConfigSaysAndRepeatWithTheSeed) {
  SimScanConfig c = exact();
  ScanRenderer clean(room(), c);
  auto truth = std::make_unique<LaserScan>();
  clean.render(Pose2{3.0, 2.0, 0.3}, {}, *truth);
  c.noise_m = 0.02;
  c.dropout = 0.1;
  c.seed = 7;
  ScanRenderer noisy(room(), c), again(room(), c);
  auto a = std::make_unique<LaserScan>(), b = std::make_unique<LaserScan>();
  double sum = 0.0, sum2 = 0.0;
  std::size_t returns = 0, dropped = 0;
  for (int frame = 0; frame < 20; ++frame) {
    noisy.render(Pose2{3.0, 2.0, 0.3}, {}, *a);
    again.render(Pose2{3.0, 2.0, 0.3}, {}, *b);
    for (std::size_t i = 0; i < a->count; ++i) {
      ASSERT_EQ(a->ranges[i], b->ranges[i]);
      if (a->ranges[i] == 0.0F) {
        ++dropped;
        continue;
      }
      const double e = a->ranges[i] - truth->ranges[i];
      sum += e;
      sum2 += e * e;
      ++returns;
    }
  }
  const double n = static_cast<double>(returns);
  EXPECT_NEAR(sum / n, 0.0, 0.002);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.02, 0.002);
  EXPECT_NEAR(static_cast<double>(dropped) / static_cast<double>(returns + dropped), 0.1, 0.01);
}

TEST(SimLaserScan, ABadConfigIsRefusedNamingTheField) {
  SimScanConfig c = exact();
  c.beams = 1;
  EXPECT_THROW({ ScanRenderer s(room(), c); }, std::invalid_argument);
  c = exact();
  c.angle_max = c.angle_min;
  try {
    ScanRenderer s(room(), c);
    FAIL() << "angle_max == angle_min accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("angle_max"), std::string::npos) << e.what();
  }
  c = exact();
  c.range_max = std::nan("");
  EXPECT_THROW({ ScanRenderer s(room(), c); }, std::invalid_argument);
}

TEST(LaserScan, ScanProblemNamesTheField) {
  auto s = std::make_unique<LaserScan>();
  s->count = 1081;
  s->angle_min = -2.356;
  s->angle_increment = 0.25 * kDeg;
  s->range_min = 0.02;
  s->range_max = 20.0;
  EXPECT_EQ(scanProblem(*s), "");
  s->angle_increment = -s->angle_increment;  // upside down: fine
  EXPECT_EQ(scanProblem(*s), "");
  s->count = 4000;
  EXPECT_NE(scanProblem(*s).find("count"), std::string::npos);
  s->count = 1081;
  s->angle_increment = 0.01;  // 10.8 rad over the beams
  EXPECT_NE(scanProblem(*s).find("angle_increment"), std::string::npos);
  s->angle_increment = 0.25 * kDeg;
  s->range_max = 0.01;
  EXPECT_NE(scanProblem(*s).find("range_max"), std::string::npos);
  s->range_max = std::numeric_limits<double>::infinity();
  EXPECT_NE(scanProblem(*s).find("range_max"), std::string::npos);
}

}  // namespace
}  // namespace staa::hal
