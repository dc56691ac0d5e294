// The simulated HAL on the paper's office map: start validation, movers that walk free
// paths as squares at their speed, the robot's motion under the acceleration limit, brake,
// stalled inputs, the obstacle rate, determinism, and no allocation in read()/write().
#include "world/sim_hal.hpp"

#include "geometry/polygon.hpp"
#include "map/generate.hpp"
#include "world/world.hpp"

#include "rt/alloc_count.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace staa::hal {
namespace {

constexpr rt::Nanos kTick = 10 * rt::kNanosPerMilli;  // the base thread's 100 Hz
// A free spot in the office's corridor ring (cell (1, 1)), facing +x along the corridor.
constexpr Pose2 kCorridor{4.5, 4.5, 0.0};

SimHalConfig officeConfig(int movers) {
  SimHalConfig c;
  c.start = kCorridor;
  c.movers = movers;
  return c;
}

// The error message of constructing a SimHal, or "" when it did not throw.
std::string constructionError(const PolygonMap& map, const SimHalConfig& config) {
  try {
    SimHal hal(map, paperAgentProfile(), config, 0);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(SimHal, CollidingStartThrowsNamingThePose) {
  const PolygonMap office = generatePaperMap("office", 1);
  SimHalConfig c = officeConfig(3);
  c.start = {1.5, 1.5, 0.25};  // inside the solid 3 x 3 m corner block
  const std::string what = constructionError(office, c);
  EXPECT_NE(what.find("(1.5, 1.5, 0.25)"), std::string::npos) << what;
  EXPECT_NE(what.find("office"), std::string::npos) << what;
  // Half outside the bounds.
  c.start = {0.1, 13.5, 0.0};
  EXPECT_NE(constructionError(office, c).find("(0.1, 13.5, 0)"), std::string::npos);
}

TEST(SimHal, OutOfRangeFieldsThrowNamingTheFieldAndValue) {
  const PolygonMap office = generatePaperMap("office", 1);
  struct Case {
    const char* field;
    void (*set)(SimHalConfig&);
    const char* value;
  };
  const Case cases[] = {
      {"config.movers", [](SimHalConfig& c) { c.movers = 33; }, "33"},
      {"config.movers", [](SimHalConfig& c) { c.movers = -1; }, "-1"},
      {"config.mover_speed", [](SimHalConfig& c) { c.mover_speed = 0.0; }, "got 0"},
      {"config.mover_speed", [](SimHalConfig& c) { c.mover_speed = std::numeric_limits<double>::infinity(); }, "inf"},
      {"config.mover_radius", [](SimHalConfig& c) { c.mover_radius = -0.25; }, "-0.25"},
      {"config.obstacle_rate_hz", [](SimHalConfig& c) { c.obstacle_rate_hz = 0.0; }, "got 0"},
      {"config.sensor_range_m", [](SimHalConfig& c) { c.sensor_range_m = std::nan(""); }, "nan"},
      {"config.max_step_s", [](SimHalConfig& c) { c.max_step_s = 0.0; }, "got 0"},
      {"config.start", [](SimHalConfig& c) { c.start.theta = std::nan(""); }, "nan"},
  };
  for (const Case& k : cases) {
    SimHalConfig c = officeConfig(3);
    k.set(c);
    const std::string what = constructionError(office, c);
    EXPECT_NE(what.find(k.field), std::string::npos) << what;
    EXPECT_NE(what.find(k.value), std::string::npos) << what;
  }
}

TEST(SimHal, MoversTooWideToStandAtAnyGoalThrowNamingTheRadius) {
  SimHalConfig c = officeConfig(3);
  c.mover_radius = 1.0;  // a 2 m square reaches 1.41 m: no room's centre is that far from its walls
  const std::string what = constructionError(generatePaperMap("office", 1), c);
  EXPECT_NE(what.find("mover_radius = 1"), std::string::npos) << what;
  EXPECT_NE(what.find("free walks for only 0 of"), std::string::npos) << what;
}

// The map's obstacles with their boxes, so a check looks only at the walls near a point.
struct Walls {
  explicit Walls(const PolygonMap& m) : map(m) {
    for (const Polygon& o : map.obstacles) boxes.push_back(boundingBox(o));
  }
  // Distance from p to the nearest obstacle or bound (0 inside), looking `within` metres.
  double distance(const Vec2& p, double within) const {
    double best = within;
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const Box& b = boxes[i];
      if (p.x() < b.min.x() - within || p.x() > b.max.x() + within || p.y() < b.min.y() - within ||
          p.y() > b.max.y() + within) {
        continue;
      }
      best = std::min(best, pointInPolygon(p, map.obstacles[i]) ? 0.0 : distanceToEdges(p, map.obstacles[i]));
    }
    if (map.bounds) {
      const Box& b = *map.bounds;
      best = std::min({best, p.x() - b.min.x(), b.max.x() - p.x(), p.y() - b.min.y(), b.max.y() - p.y()});
    }
    return best;
  }
  const PolygonMap& map;
  std::vector<Box> boxes;
};

// Exact distance between segment [a, b] and a polygon (0 when it enters or crosses it): for
// disjoint shapes the nearest pair has an endpoint of one segment at one end.
double segmentPolygonDistance(const Vec2& a, const Vec2& b, const Polygon& poly) {
  if (pointInPolygon(a, poly)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    if (segmentsIntersect(a, b, poly[j], poly[i])) return 0.0;
    best = std::min({best, distancePointSegment(poly[i], a, b), distancePointSegment(a, poly[j], poly[i]),
                     distancePointSegment(b, poly[j], poly[i])});
  }
  return best;
}

// Checks the movers' walks exactly (every segment keeps the square's corners, r*sqrt(2) from
// the centre, off every wall), then runs `seconds` of reads at `read_hz` with the obstacle
// sensor polled at the same times and checks every frame's movers: squares of half-size r,
// moving at the speed, centres at least r (less 2 cm) from every wall, never touching one.
void checkMoversWalkFree(const PolygonMap& map, const SimHalConfig& c, double seconds, double read_hz) {
  SimHal hal(map, paperAgentProfile(), c, 0);
  const double r = c.mover_radius;
  const double reach = r * std::sqrt(2.0);
  ASSERT_EQ(hal.world().moverCount(), static_cast<std::size_t>(c.movers));
  for (std::size_t i = 0; i < hal.world().moverCount(); ++i) {
    const std::vector<Vec2>& w = hal.world().mover(i).waypoints;
    ASSERT_GE(w.size(), 2u);
    EXPECT_GE((w.front() - c.start.position()).norm(), 1.0);
    EXPECT_GE((w.back() - c.start.position()).norm(), 1.0);
    for (std::size_t k = 1; k < w.size(); ++k) {
      for (const Polygon& wall : map.obstacles) {
        ASSERT_GE(segmentPolygonDistance(w[k - 1], w[k], wall), reach)
            << "mover " << i << " segment " << w[k - 1].transpose() << " -> " << w[k].transpose();
      }
    }
    if (map.bounds) {
      for (const Vec2& p : w) EXPECT_TRUE(map.bounds->contains(p));
    }
  }

  const Walls walls(map);
  ObstacleFrame frame;
  std::vector<Box> travelled(static_cast<std::size_t>(c.movers));
  int frames = 0;
  const rt::Nanos tick = std::llround(1e9 / read_hz);
  const int reads = static_cast<int>(std::lround(seconds * read_hz));
  for (int k = 0; k <= reads; ++k) {
    const rt::Nanos now = k * tick;
    hal.base().read(now);
    if (!hal.obstacles().read(now, frame)) continue;
    ++frames;
    ASSERT_EQ(frame.count, static_cast<std::size_t>(c.movers)) << "sensor range covers the map";
    for (std::size_t i = 0; i < frame.count; ++i) {
      const ObstacleFrame::Obstacle& o = frame.obstacles[i];
      ASSERT_EQ(o.n, 4u);
      Vec2 centre{0.0, 0.0};
      for (std::size_t v = 0; v < 4; ++v) centre += o.vertices[v] / 4.0;
      const Polygon square(o.vertices.begin(), o.vertices.begin() + 4);
      // A square of half-size r about its centre, never rotated.
      for (const Vec2& v : square) {
        EXPECT_NEAR(std::abs(v.x() - centre.x()), r, 1e-9);
        EXPECT_NEAR(std::abs(v.y() - centre.y()), r, 1e-9);
      }
      EXPECT_NEAR(std::abs(signedArea(square)), 4.0 * r * r, 1e-9);
      EXPECT_NEAR(o.velocity.norm(), c.mover_speed, 1e-9);
      // The centre keeps the mover's radius from every wall (2 cm for the inflated corners'
      // chords; in fact it keeps the corners' reach), so the square never touches one.
      ASSERT_GE(walls.distance(centre, 2.0), r - 0.02)
          << "mover " << i << " at " << centre.transpose() << ", t = " << static_cast<double>(now) * 1e-9 << " s";
      ASSERT_GT(walls.distance(centre, 2.0), reach);
      Box& box = travelled[i];
      if (frames == 1) box = Box{centre, centre};
      box.min = box.min.cwiseMin(centre);
      box.max = box.max.cwiseMax(centre);
    }
  }
  EXPECT_NEAR(frames, std::min(30.0, read_hz) * seconds, 2.0);
  // They walk: each covers more than a metre in that time.
  for (const Box& b : travelled) EXPECT_GT(std::hypot(b.width(), b.height()), 1.0);
}

TEST(SimHal, OfficeMoversAreSquaresAtTheirSpeedAndNeverTouchTheMapOverAMinute) {
  SimHalConfig c = officeConfig(3);
  c.sensor_range_m = 100.0;  // see all of them
  // Reads at 10 Hz keep the sanitizer run short; the walks themselves are checked exactly.
  c.max_step_s = 0.1;
  checkMoversWalkFree(generatePaperMap("office", 1), c, 60.0, 10.0);
}

TEST(SimHal, MapWithoutGoalsWalksMoversBetweenRandomFreePoints) {
  PolygonMap map;
  map.name = "no-goals";
  map.bounds = Box{{0.0, 0.0}, {12.0, 10.0}};
  map.obstacles = {{{3.0, 2.0}, {5.0, 2.0}, {5.0, 8.0}, {3.0, 8.0}},
                   {{7.0, 0.0}, {8.0, 0.0}, {8.0, 6.0}, {7.0, 6.0}},
                   {{9.0, 7.0}, {11.0, 7.0}, {10.0, 9.0}}};
  SimHalConfig c;
  c.start = {1.5, 1.5, 0.0};
  c.movers = 5;
  c.mover_radius = 0.3;
  c.sensor_range_m = 100.0;
  c.max_step_s = 0.1;
  checkMoversWalkFree(map, c, 20.0, 10.0);
}

TEST(SimHal, SensorRangeHidesFarMovers) {
  const PolygonMap office = generatePaperMap("office", 1);
  SimHalConfig c = officeConfig(8);
  c.sensor_range_m = 6.0;
  c.max_step_s = 0.1;
  SimHal hal(office, paperAgentProfile(), c, 0);
  ObstacleFrame frame;
  std::size_t fewest = 8, most = 0;
  for (int k = 0; k <= 300; ++k) {  // 30 s at 10 Hz
    hal.base().read(k * 10 * kTick);
    if (!hal.obstacles().read(k * 10 * kTick, frame)) continue;
    // Exactly the movers within range of the robot, checked against the world itself.
    std::size_t in_range = 0;
    const Vec2 robot = hal.world().robot().pose.position();
    for (std::size_t i = 0; i < hal.world().moverCount(); ++i) {
      if ((hal.world().moverPosition(i) - robot).norm() <= c.sensor_range_m) ++in_range;
    }
    ASSERT_EQ(frame.count, in_range);
    for (std::size_t i = 0; i < frame.count; ++i) {
      Vec2 centre{0.0, 0.0};
      for (std::size_t v = 0; v < 4; ++v) centre += frame.obstacles[i].vertices[v] / 4.0;
      EXPECT_LE((centre - robot).norm(), c.sensor_range_m + 1e-9);
    }
    fewest = std::min(fewest, frame.count);
    most = std::max(most, frame.count);
  }
  EXPECT_LT(fewest, 8u);  // the range hides some, some of the time
  EXPECT_GT(most, 0u);
}

// Distance covered from rest in `steps` equal steps of dt with v commanded: as World::step
// does it, v rises by at most a_max*dt, then the step is driven at the new v.
double rampDistance(double v_cmd, double a_max, double dt, int steps) {
  double v = 0.0, d = 0.0;
  for (int k = 0; k < steps; ++k) {
    v = std::min(v_cmd, v + a_max * dt);
    d += v * dt;
  }
  return d;
}

TEST(SimHal, HalfMetrePerSecondForTwoSecondsDrivesTheRampedDistanceAlongTheHeading) {
  const PolygonMap office = generatePaperMap("office", 1);
  const RobotProfile robot = paperAgentProfile();
  for (const double heading : {0.0, 0.3}) {
    SimHalConfig c = officeConfig(0);
    c.start.theta = heading;
    SimHal hal(office, robot, c, 0);
    VelocityCommand cmd;
    cmd.v = 0.5;
    for (int k = 0; k <= 200; ++k) {
      hal.base().write(k * kTick, cmd);
      hal.base().read(k * kTick);  // the first read only sets the time: 200 steps of 10 ms
    }
    const Odometry odo = hal.base().odometry();
    // 0.25 s ramp at a_max = 2 m/s^2, then 1.75 s at 0.5 m/s: 0.065 + 0.875 m.
    const double expected = rampDistance(0.5, robot.limits.a_max, 0.01, 200);
    EXPECT_NEAR(expected, 0.94, 1e-9);
    EXPECT_NEAR(expected, 0.5 * 2.0 - 0.5 * 0.5 * (0.5 / robot.limits.a_max), 0.01);  // the continuous ramp
    EXPECT_NEAR(odo.pose.x, kCorridor.x + expected * std::cos(heading), 1e-9);
    EXPECT_NEAR(odo.pose.y, kCorridor.y + expected * std::sin(heading), 1e-9);
    EXPECT_NEAR(odo.pose.theta, heading, 1e-12);
    EXPECT_DOUBLE_EQ(odo.v, 0.5);
    EXPECT_EQ(odo.w, 0.0);
    EXPECT_EQ(odo.stamp, 200 * kTick);
    EXPECT_EQ(hal.collisions(), 0);
  }
}

TEST(SimHal, LongGapIsIntegratedInStepsOfAtMostMaxStep) {
  const PolygonMap office = generatePaperMap("office", 1);
  const RobotProfile robot = paperAgentProfile();
  SimHal hal(office, robot, officeConfig(0), 0);
  VelocityCommand cmd;
  cmd.v = 0.5;
  hal.base().write(0, cmd);
  hal.base().read(0);
  hal.base().read(rt::kNanosPerSecond);  // one late wake-up: 50 steps of 20 ms
  EXPECT_NEAR(hal.base().odometry().pose.x, kCorridor.x + rampDistance(0.5, robot.limits.a_max, 0.02, 50), 1e-9);
}

TEST(SimHal, BrakeStopsWithinVOverAmaxPlusOneStep) {
  const PolygonMap office = generatePaperMap("office", 1);
  const RobotProfile robot = paperAgentProfile();
  SimHal hal(office, robot, officeConfig(0), 0);
  VelocityCommand go;
  go.v = 0.5;
  int k = 0;
  for (; k <= 100; ++k) {
    hal.base().write(k * kTick, go);
    hal.base().read(k * kTick);
  }
  ASSERT_DOUBLE_EQ(hal.base().odometry().v, 0.5);
  const double x_brake = hal.base().odometry().pose.x;
  VelocityCommand brake;
  brake.v = 0.5;  // ignored: a brake is v = w = 0
  brake.brake = true;
  const int allowed = static_cast<int>(std::ceil((0.5 / robot.limits.a_max + 0.01) / 0.01 - 1e-9));
  int reads = 0;
  while (hal.base().odometry().v > 0.0 && reads < 1000) {
    hal.base().write(k * kTick, brake);
    hal.base().read(k * kTick);
    ++k;
    ++reads;
  }
  EXPECT_LE(reads, allowed);
  EXPECT_EQ(hal.base().odometry().v, 0.0);
  // v^2 / (2 a) = 0.0625 m, less the half-step of the discrete ramp.
  EXPECT_NEAR(hal.base().odometry().pose.x - x_brake, 0.0625, 0.01);
  // Stays stopped.
  hal.base().read(k * kTick + rt::kNanosPerSecond);
  EXPECT_EQ(hal.base().odometry().v, 0.0);
}

TEST(SimHal, NonFiniteCommandIsAStopNotACrash) {
  SimHal hal(generatePaperMap("office", 1), paperAgentProfile(), officeConfig(0), 0);
  VelocityCommand bad;
  bad.v = std::nan("");
  bad.w = std::numeric_limits<double>::infinity();
  hal.base().write(0, bad);
  hal.base().read(0);
  hal.base().read(kTick);
  EXPECT_EQ(hal.base().odometry().v, 0.0);
  EXPECT_EQ(hal.base().odometry().pose.x, kCorridor.x);
}

TEST(SimHal, FrozenOdometryKeepsItsStampAndResumesWhenThawed) {
  SimHal hal(generatePaperMap("office", 1), paperAgentProfile(), officeConfig(0), 7);
  EXPECT_EQ(hal.base().odometry().stamp, 7);  // the start time until the first read
  VelocityCommand cmd;
  cmd.v = 0.5;
  hal.base().write(0, cmd);
  for (int k = 0; k <= 10; ++k) hal.base().read(k * kTick);
  const Odometry before = hal.base().odometry();
  EXPECT_EQ(before.stamp, 10 * kTick);
  hal.freezeOdometry(true);
  for (int k = 11; k <= 30; ++k) hal.base().read(k * kTick);
  EXPECT_EQ(hal.base().odometry().stamp, before.stamp);
  EXPECT_EQ(hal.base().odometry().pose.x, before.pose.x);  // a stalled stream: the last report
  EXPECT_EQ(hal.base().status().stamp, 30 * kTick);        // the base itself still answers
  EXPECT_TRUE(hal.base().status().enabled);
  EXPECT_EQ(hal.base().status().fault, BaseFault::kNone);
  hal.freezeOdometry(false);
  hal.base().read(31 * kTick);
  EXPECT_EQ(hal.base().odometry().stamp, 31 * kTick);
  // The world moved on meanwhile: 31 steps of the ramp from rest.
  EXPECT_NEAR(hal.base().odometry().pose.x, kCorridor.x + rampDistance(0.5, 2.0, 0.01, 31), 1e-9);
  EXPECT_GT(hal.base().odometry().pose.x, before.pose.x + 0.05);
}

TEST(SimHal, FrozenObstaclesReadFalseUntilThawed) {
  SimHal hal(generatePaperMap("office", 1), paperAgentProfile(), officeConfig(3), 0);
  ObstacleFrame frame;
  hal.freezeObstacles(true);
  for (int k = 0; k <= 30; ++k) {
    hal.base().read(k * kTick);
    EXPECT_FALSE(hal.obstacles().read(k * kTick, frame));
  }
  hal.freezeObstacles(false);
  EXPECT_TRUE(hal.obstacles().read(31 * kTick, frame));
  EXPECT_EQ(frame.stamp, 31 * kTick);
}

TEST(SimHal, PolledAtHundredHertzGivesThirtyFramesPerSecond) {
  SimHal hal(generatePaperMap("office", 1), paperAgentProfile(), officeConfig(3), 0);
  ObstacleFrame frame;
  int frames = 0;
  std::uint64_t last_sequence = 0;
  for (int k = 0; k < 200; ++k) {  // 2 s
    hal.base().read(k * kTick);
    if (!hal.obstacles().read(k * kTick, frame)) continue;
    ++frames;
    EXPECT_EQ(frame.sequence, last_sequence + 1);
    EXPECT_EQ(frame.stamp, k * kTick);
    last_sequence = frame.sequence;
  }
  EXPECT_GE(frames, 59);
  EXPECT_LE(frames, 61);
  // The sensor's own first frame comes before the base thread's first read.
  SimHalConfig all = officeConfig(3);
  all.sensor_range_m = 100.0;
  SimHal fresh(generatePaperMap("office", 1), paperAgentProfile(), all, 0);
  EXPECT_TRUE(fresh.obstacles().read(0, frame));
  EXPECT_EQ(frame.count, 3u);
}

TEST(SimHal, SameSeedGivesIdenticalFramesAndAnotherSeedOtherWalks) {
  const PolygonMap office = generatePaperMap("office", 1);
  SimHalConfig c = officeConfig(4);
  c.sensor_range_m = 100.0;
  SimHal a(office, paperAgentProfile(), c, 0);
  SimHal b(office, paperAgentProfile(), c, 0);
  c.seed = 2;
  SimHal other(office, paperAgentProfile(), c, 0);
  ObstacleFrame fa, fb, fo;
  int compared = 0;
  bool differs = false;
  VelocityCommand cmd;
  cmd.v = 0.3;
  cmd.w = 0.2;
  for (int k = 0; k <= 100; ++k) {
    for (SimHal* h : {&a, &b, &other}) {
      h->base().write(k * kTick, cmd);
      h->base().read(k * kTick);
    }
    const bool ra = a.obstacles().read(k * kTick, fa);
    ASSERT_EQ(ra, b.obstacles().read(k * kTick, fb));
    ASSERT_EQ(ra, other.obstacles().read(k * kTick, fo));
    if (!ra) continue;
    ++compared;
    ASSERT_EQ(fa.count, fb.count);
    for (std::size_t i = 0; i < fa.count; ++i) {
      ASSERT_EQ(fa.obstacles[i].n, fb.obstacles[i].n);
      for (std::size_t v = 0; v < fa.obstacles[i].n; ++v) ASSERT_EQ(fa.obstacles[i].vertices[v], fb.obstacles[i].vertices[v]);
      ASSERT_EQ(fa.obstacles[i].velocity, fb.obstacles[i].velocity);
      if (fa.obstacles[i].vertices[0] != fo.obstacles[i].vertices[0]) differs = true;
    }
  }
  EXPECT_GE(compared, 30);
  EXPECT_EQ(a.base().odometry().pose.x, b.base().odometry().pose.x);
  EXPECT_EQ(a.base().odometry().pose.y, b.base().odometry().pose.y);
  EXPECT_TRUE(differs);
}

TEST(SimHal, SetPoseMovesTheRobotOnlyToFreePoses) {
  const PolygonMap office = generatePaperMap("office", 1);
  SimHal hal(office, paperAgentProfile(), officeConfig(0), 0);
  VelocityCommand cmd;
  cmd.v = 0.5;
  hal.base().write(0, cmd);
  for (int k = 0; k <= 50; ++k) hal.base().read(k * kTick);
  ASSERT_GT(hal.base().odometry().v, 0.0);
  EXPECT_TRUE(hal.base().setPose({22.5, 4.5, 1.0}));
  EXPECT_EQ(hal.base().odometry().pose.x, 22.5);
  EXPECT_EQ(hal.base().odometry().v, 0.0);
  EXPECT_EQ(hal.world().robot().pose.theta, 1.0);
  // Into the central block, and half through a wall: refused, nothing changes.
  EXPECT_FALSE(hal.base().setPose({13.5, 13.5, 0.0}));
  EXPECT_FALSE(hal.base().setPose({3.5, 3.1, 0.0}));
  EXPECT_FALSE(hal.base().setPose({std::nan(""), 4.5, 0.0}));
  EXPECT_EQ(hal.world().robot().pose.x, 22.5);
  EXPECT_EQ(hal.world().robot().pose.y, 4.5);
}

TEST(SimHal, DrivingIntoAWallCountsACollisionAndStops) {
  SimHal hal(generatePaperMap("office", 1), paperAgentProfile(), officeConfig(0), 0);
  VelocityCommand cmd;
  cmd.v = 1.0;
  // Facing south at the wall piece beside the door of room (1, 0), whose top is y = 3.
  ASSERT_TRUE(hal.base().setPose({3.6, 4.5, -kPi / 2.0}));
  for (int k = 0; k <= 200; ++k) {  // contact after 1.1 m, about 1.35 s
    hal.base().write(k * kTick, cmd);
    hal.base().read(k * kTick);
  }
  EXPECT_EQ(hal.collisions(), 1);
  // Stopped at the contact: the footprint's front (0.4 m ahead) on the wall.
  EXPECT_NEAR(hal.base().odometry().pose.y, 3.4, 1e-6);
  EXPECT_EQ(hal.base().odometry().v, 0.0);
}

TEST(SimHal, BaseAndPerceptionThreadsShareOnlyWholeFrames) {
  // The base thread steps the world while the perception thread polls: every frame it gets
  // is a whole one (3 squares of the right size, stamps that never go back), never torn.
  SimHalConfig c = officeConfig(3);
  c.sensor_range_m = 100.0;
  SimHal hal(generatePaperMap("office", 1), paperAgentProfile(), c, 0);
  std::atomic<rt::Nanos> clock{0};
  std::atomic<bool> done{false};
  std::atomic<int> frames{0};
  std::thread base([&] {
    VelocityCommand cmd;
    cmd.v = 0.4;
    cmd.w = 0.3;
    // 300 steps, and on until the reader has had a few frames: on a loaded machine the
    // reader may not run at all while 300 quick steps go by (a bound keeps a broken reader
    // from hanging the test).
    for (int k = 0; k <= 300 || (frames.load() < 3 && k < 3'000'000); ++k) {
      clock.store(k * kTick);
      hal.base().write(k * kTick, cmd);
      hal.base().read(k * kTick);
      if (k > 300) std::this_thread::yield();
    }
    done.store(true);
  });
  ObstacleFrame frame;
  rt::Nanos last_stamp = -1;
  while (!done.load()) {
    if (!hal.obstacles().read(clock.load(), frame)) {
      std::this_thread::yield();
      continue;
    }
    frames.fetch_add(1);
    // EXPECT, not ASSERT: returning here would leave the base thread running.
    EXPECT_EQ(frame.count, 3u);
    EXPECT_GE(frame.stamp, last_stamp);
    last_stamp = frame.stamp;
    for (std::size_t i = 0; i < frame.count && i < 3; ++i) {
      const ObstacleFrame::Obstacle& o = frame.obstacles[i];
      EXPECT_EQ(o.n, 4u);
      if (o.n != 4u) continue;
      EXPECT_NEAR((o.vertices[2] - o.vertices[0]).norm(), 2.0 * std::sqrt(2.0) * c.mover_radius, 1e-9);
      EXPECT_NEAR(o.velocity.norm(), c.mover_speed, 1e-9);
    }
  }
  base.join();
  EXPECT_GE(frames.load(), 3);
}

TEST(SimHal, ReadWriteAndObstacleReadsAllocateNothingAfterWarmUp) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_sim_hal must link staa_rt_alloc_hook";
  const PolygonMap office = generatePaperMap("office", 1);
  SimHalConfig c = officeConfig(3);
  SimHal hal(office, paperAgentProfile(), c, 0);
  ObstacleFrame frame;
  VelocityCommand cmd;
  cmd.v = 0.6;
  cmd.w = 0.25;  // a circle of 2.4 m in a 3 m corridor: walls, bisection, movers, all of it
  auto cycle = [&](int k) {
    const rt::Nanos now = k * kTick;
    hal.base().read(now);
    const Odometry odo = hal.base().odometry();
    const BaseStatus st = hal.base().status();
    cmd.stamp = odo.stamp + (st.enabled ? 0 : 1);
    hal.base().write(now, cmd);
    hal.obstacles().read(now, frame);
  };
  for (int k = 0; k < 20; ++k) cycle(k);
  std::size_t allocations = 0;
  for (int k = 20; k < 1020; ++k) {
    rt::AllocationScope scope;
    cycle(k);
    allocations += scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(hal.base().odometry().stamp, 0);
}

// The simulated base steps the World in a real-time thread: the world's scratch polygons are
// sized at construction, so not even the first step that brings a mover near allocates (the
// daemon once counted 1 real-time allocation there, the first time a person came close).
TEST(SimHal, WorldStepsAllocateNothingFromTheFirstOneEvenWhenAMoverComesNear) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_sim_hal must link staa_rt_alloc_hook";
  const Polygon square{{-0.25, -0.25}, {0.25, -0.25}, {0.25, 0.25}, {-0.25, 0.25}};
  const Mover mover{square, {{12.0, 0.0}, {1.0, 0.0}}, 1.0};  // starts far, walks up to the robot
  PolygonMap map;
  map.name = "open";
  map.obstacles.push_back(Polygon{{-3.0, 2.0}, {15.0, 2.0}, {15.0, 2.2}, {-3.0, 2.2}});
  World world(map, paperAgentProfile(), Pose2{}, {mover});
  std::size_t allocations = 0;
  double nearest = 1e9;
  for (int k = 0; k < 400; ++k) {  // 13 s: the mover arrives after ~10.5 s
    rt::AllocationScope scope;
    world.step(1.0 / 30.0, 0.0, 0.0);
    allocations += scope.count();
    nearest = std::min(nearest, (world.moverPosition(0) - world.robot().pose.position()).norm());
  }
  EXPECT_LT(nearest, 1.5);  // it did come near
  EXPECT_EQ(allocations, 0u);
}

}  // namespace
}  // namespace staa::hal
