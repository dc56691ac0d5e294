// Depth perception on frames of the simulated camera in the office map's corridor: a walking
// box becomes one obstacle where it is, moving as it moves; walls, doors and the floor do not;
// the robot's own motion gives standing things no velocity; a box walking a circle turns at
// its rate, one walking straight does not; the nearest 32 obstacles are kept.
#include "perception/depth_obstacles.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "world/sim_depth_camera.hpp"
#include "perception/static_map_mask.hpp"
#include "depth_scenes.hpp"
#include "world/world.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace staa {
namespace {

constexpr double kDt = 1.0 / 30.0;
constexpr rt::Nanos kPeriod = 33'333'333;

PolygonView view(const hal::ObstacleFrame::Obstacle& o) { return {o.vertices.data(), o.n}; }

// Distance from p to a polygon: 0 inside.
double distanceTo(const Vec2& p, PolygonView poly) {
  return locatePoint(p, poly) == Containment::kOutside ? distanceToEdges(p, poly) : 0.0;
}

Vec2 centroidOf(PolygonView poly) {
  Vec2 c(0.0, 0.0);
  for (const Vec2& v : poly) c += v;
  return c / static_cast<double>(poly.size());
}

// For failure messages: each obstacle's vertex centroid, extent and velocity.
std::string describe(const hal::ObstacleFrame& f) {
  std::string s;
  for (std::size_t i = 0; i < f.count; ++i) {
    const auto& o = f.obstacles[i];
    const Box b = boundingBox(view(o));
    const Vec2 c = centroidOf(view(o));
    char line[200];
    std::snprintf(line, sizeof line, "\n  #%zu at (%.2f, %.2f), box %.2f..%.2f x %.2f..%.2f, v (%.2f, %.2f)", i, c.x(),
                  c.y(), b.min.x(), b.max.x(), b.min.y(), b.max.y(), o.velocity.x(), o.velocity.y());
    s += line;
  }
  return s;
}

// The simulator world, its camera and the detector, stepped together at 30 Hz.
struct CorridorRun {
  CorridorRun(const hal::CameraMount& mount, std::vector<Mover> movers, double mover_height = 1.7,
              const DepthObstaclesConfig& detector_config = {}, const Pose2& start = test::kCorridorStart)
      : world(test::officeMap(), test::hsrProfile(), start, std::move(movers)),
        camera(world, cameraConfig(mount, mover_height)),
        detector(test::officeMap(), camera.intrinsics(), camera.mount(), detector_config),
        frame(test::newFrame()) {}

  static hal::SimDepthConfig cameraConfig(const hal::CameraMount& mount, double mover_height) {
    hal::SimDepthConfig c;
    c.mount = mount;
    c.mover_height_m = mover_height;
    c.noise_mm_per_m2 = 1.5;  // a Kinect-class sensor
    return c;
  }

  // One 30 Hz period: the world moves, the camera renders it, perception processes it.
  void step(double v = 0.0, double w = 0.0) {
    world.step(kDt, v, w);
    now += kPeriod;
    ASSERT_TRUE(camera.read(now, *frame));
    stats = detector.process(*frame, world.robot().pose, obstacles);
  }

  World world;
  hal::SimDepthCamera camera;
  DepthObstacleDetector detector;
  std::unique_ptr<hal::DepthFrame> frame;
  hal::ObstacleFrame obstacles;
  DepthObstaclesStats stats;
  rt::Nanos now = 0;
};

void expectMoverSeen(const hal::CameraMount& mount, const char* name) {
  SCOPED_TRACE(name);
  // A 0.4 m box 2 m ahead of the robot, walking across the corridor at 0.5 m/s.
  CorridorRun run(mount, {test::boxMover({6.5, 3.9}, {6.5, 5.1}, 0.5)});
  const Polygon truth_shape = test::square(0.2);
  for (int k = 1; k <= 30; ++k) {
    run.step();
    if (k < 10) continue;  // the velocity settles over the first frames (a new track starts at 0)
    SCOPED_TRACE("frame " + std::to_string(k));
    const Vec2 centre = run.world.moverPosition(0);
    Polygon truth;
    for (const Vec2& v : truth_shape) truth.push_back(v + centre);
    ASSERT_EQ(run.obstacles.count, 1u) << describe(run.obstacles);
    EXPECT_EQ(run.obstacles.dropped, 0u);
    const auto& o = run.obstacles.obstacles[0];
    ASSERT_GE(o.n, 3u);
    EXPECT_TRUE(isConvex(view(o)));
    // Near the true position: every vertex within 0.15 m of the true box, the face the camera
    // sees (x = 6.3) covered to within 0.15 m, the lateral position within 0.15 m.
    for (std::size_t i = 0; i < o.n; ++i) EXPECT_LE(distanceTo(o.vertices[i], truth), 0.15);
    EXPECT_LE(distanceTo(Vec2(centre.x() - 0.2, centre.y()), view(o)), 0.15);
    EXPECT_NEAR(centroidOf(view(o)).y(), centre.y(), 0.15);
    // Its velocity: 0.5 m/s along +y, not turning.
    EXPECT_LE((o.velocity - Vec2(0.0, 0.5)).norm(), 0.15) << o.velocity.transpose();
    EXPECT_LE(std::abs(o.turn_rate), 0.3);
    // The corridor's walls were in view and explained by the map.
    EXPECT_GT(run.stats.map_cells, 20u);
  }
}

TEST(DepthObstacles, CorridorWalkerIsOneObstacleAtItsPlaceWithItsVelocity) {
  expectMoverSeen(test::levelMount(), "level camera");
  expectMoverSeen(test::hsrHeadMount(), "HSR head, pitched 0.3 rad down");
}

TEST(DepthObstacles, WallsDoorsAndRoomsOfTheCorridorAreNotObstacles) {
  // Turning on the spot in the corridor: walls, door jambs and rooms seen through the doors
  // are all in the map.
  CorridorRun run(test::levelMount(), {});
  std::size_t map_cells = 0;
  for (int k = 1; k <= 60; ++k) {
    run.step(0.0, 0.8);
    EXPECT_EQ(run.obstacles.count, 0u) << "frame " << k << describe(run.obstacles);
    map_cells += run.stats.map_cells;
  }
  EXPECT_GT(run.world.robot().pose.theta, 0.5);  // it really turned
  EXPECT_GT(map_cells, 60u * 20u);
}

TEST(DepthObstacles, TiltedHeadDoesNotReportTheFloorButSeesALowBox) {
  // The HSR head looks at the floor from 1 m. With the floor inside the height band (a
  // detector that keeps points from 0.1 m below it), the floor would be obstacles; with the
  // default band it is not.
  DepthObstaclesConfig floor_too;
  floor_too.min_height_m = -0.1;
  CorridorRun run(test::hsrHeadMount(), {});
  DepthObstacleDetector naive(test::officeMap(), run.camera.intrinsics(), run.camera.mount(), floor_too);
  hal::ObstacleFrame naive_out;
  for (int k = 1; k <= 10; ++k) {
    run.step(0.1, 0.0);
    EXPECT_EQ(run.obstacles.count, 0u) << "frame " << k;
    naive.process(*run.frame, run.world.robot().pose, naive_out);
    EXPECT_GE(naive_out.count, 1u) << "frame " << k;
  }

  // A 0.3 m high box (a footstool) 1.8 m ahead is in the band: one obstacle around it.
  CorridorRun low(test::hsrHeadMount(), {test::boxMover({6.3, 4.5}, {6.3, 4.5}, 0.0)}, 0.3);
  for (int k = 1; k <= 5; ++k) low.step();
  ASSERT_EQ(low.obstacles.count, 1u);
  const auto& o = low.obstacles.obstacles[0];
  EXPECT_LE(distanceTo(Vec2(6.3, 4.5), view(o)), 0.15);
  for (std::size_t i = 0; i < o.n; ++i) {
    EXPECT_LE(distanceTo(o.vertices[i], Polygon{{6.1, 4.3}, {6.5, 4.3}, {6.5, 4.7}, {6.1, 4.7}}), 0.15);
  }
  EXPECT_LT(o.velocity.norm(), 0.1);
}

TEST(DepthObstacles, RobotDrivingPastAStandingBoxGivesItNoVelocity) {
  CorridorRun run(test::levelMount(), {test::boxMover({7.5, 4.0}, {7.5, 4.0}, 0.0)});
  for (int k = 1; k <= 60; ++k) {
    run.step(0.22, 0.0);
    if (k < 5) continue;
    ASSERT_EQ(run.obstacles.count, 1u) << "frame " << k << describe(run.obstacles);
    EXPECT_LT(run.obstacles.obstacles[0].velocity.norm(), 0.1) << "frame " << k;
    EXPECT_LE(distanceTo(Vec2(7.3, 4.0), view(run.obstacles.obstacles[0])), 0.15);
  }
  EXPECT_GT(run.world.robot().pose.x, 4.5 + 0.3);  // it really drove
}

// A box walking a circle of radius 0.8 m at 0.8 m/s (1 rad/s) in the corridor ahead, first
// counter-clockwise, then back clockwise: the turn rate follows, its sign with it.
TEST(DepthObstacles, ABoxWalkingACircleTurnsAtItsRate) {
  const Vec2 centre(7.3, 4.5);
  const double radius = 0.8, speed = 0.8;
  std::vector<Vec2> circle;
  for (int k = 0; k <= 72; ++k) {
    const double a = -kPi / 2.0 + 2.0 * kPi * k / 72.0;  // from the circle's south point
    circle.push_back(centre + radius * Vec2(std::cos(a), std::sin(a)));
  }
  CorridorRun run(test::levelMount(), {Mover{test::square(0.2), circle, speed}});
  const double lap = 2.0 * kPi * radius / speed;  // 6.3 s, then the way back
  const int frames = static_cast<int>(2.0 * lap * 30.0);
  int checked_ccw = 0, checked_cw = 0;
  double worst = 0.0;
  for (int k = 1; k <= frames; ++k) {
    run.step();
    const double t = k * kDt;
    // The velocity and its direction settle first (a new track starts at rest); around the
    // lap's end the mover reverses (a standstill, the turn rate resets).
    const bool ccw = t > 1.5 && t < lap - 0.3, cw = t > lap + 1.5 && t < 2.0 * lap - 0.3;
    if (!ccw && !cw) continue;
    SCOPED_TRACE("frame " + std::to_string(k));
    ASSERT_EQ(run.obstacles.count, 1u) << describe(run.obstacles);
    const double expected = (ccw ? 1.0 : -1.0) * speed / radius;
    const double got = run.obstacles.obstacles[0].turn_rate;
    EXPECT_NEAR(got, expected, 0.35);
    worst = std::max(worst, std::abs(got - expected));
    (ccw ? checked_ccw : checked_cw) += 1;
  }
  EXPECT_GT(checked_ccw, 100);
  EXPECT_GT(checked_cw, 100);
  std::printf("circle walker: largest turn rate error %.2f rad/s of 1 rad/s\n", worst);
}

TEST(DepthObstacles, AStampGapForgetsTheTracks) {
  CorridorRun run(test::levelMount(), {test::boxMover({6.5, 3.9}, {6.5, 5.1}, 0.5)});
  for (int k = 1; k <= 15; ++k) run.step();
  ASSERT_EQ(run.obstacles.count, 1u) << describe(run.obstacles);
  EXPECT_GT(run.obstacles.obstacles[0].velocity.norm(), 0.3);
  // The next frame comes 1 s late (longer than max_frame_gap_s): its velocity restarts at 0.
  run.frame->stamp += rt::kNanosPerSecond;
  run.detector.process(*run.frame, run.world.robot().pose, run.obstacles);
  ASSERT_EQ(run.obstacles.count, 1u);
  EXPECT_EQ(run.obstacles.obstacles[0].velocity, Vec2(0.0, 0.0));
  EXPECT_EQ(run.obstacles.obstacles[0].turn_rate, 0.0);
  EXPECT_EQ(run.obstacles.stamp, run.frame->stamp);
}

TEST(DepthObstacles, KeepsTheNearestObstaclesAndCountsTheRest) {
  // 40 small things in an empty map, painted into a synthetic frame as 9 x 9 pixel patches
  // on an 8 x 5 grid of the image; each image row at its own depth (2.2..3.8 m, a row's band
  // height allowing), so they lie at least 0.3 m apart on the floor plan: 40 clusters, the
  // 32 nearest (depths 2.2..3.4 m) reported nearest first, the 8 at 3.8 m dropped.
  PolygonMap empty;
  empty.name = "empty";
  DepthObstaclesConfig every_pixel;
  every_pixel.pixel_stride = 1;
  every_pixel.cluster_gap_m = 0.1;  // neighbouring cells only: the things are 0.3 m apart
  DepthObstacleDetector detector(empty, hal::CameraIntrinsics{}, test::levelMount(), every_pixel);
  auto frame = test::newFrame();
  const int rows[] = {100, 170, 240, 310, 380};
  const double depths_mm[] = {2200, 3800, 3400, 3000, 2600};
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 8; ++c) {
      const int u0 = 40 + 80 * c, v0 = rows[r];
      for (int v = v0 - 4; v <= v0 + 4; ++v) {
        for (int u = u0 - 4; u <= u0 + 4; ++u) {
          frame->depth_mm[static_cast<std::size_t>(v) * hal::DepthFrame::kWidth + static_cast<std::size_t>(u)] =
              static_cast<std::uint16_t>(depths_mm[r]);
        }
      }
    }
  }
  frame->stamp = kPeriod;
  hal::ObstacleFrame out;
  const DepthObstaclesStats stats = detector.process(*frame, Pose2{}, out);
  EXPECT_EQ(stats.clusters, 40u);
  ASSERT_EQ(out.count, hal::ObstacleFrame::kMaxObstacles);
  EXPECT_EQ(out.dropped, 8u);
  // At 3.4 m the farthest (image edge) thing is 3.4 * hypot(1, 280 / 570.3) = 3.79 m away;
  // every one at 3.8 m is farther.
  double previous = 0.0;
  for (std::size_t i = 0; i < out.count; ++i) {
    const double d = centroidOf(view(out.obstacles[i])).norm();
    EXPECT_GE(d, previous - 0.05);
    EXPECT_LE(d, 3.79 + 0.05);
    EXPECT_GE(d, 2.2 - 0.05);
    previous = d;
  }
}

TEST(DepthObstacles, GrowToFewerVerticesContainsThePolygonAndStaysClose) {
  std::vector<Vec2> circle;
  for (int i = 0; i < 40; ++i) circle.emplace_back(std::cos(2 * kPi * i / 40), std::sin(2 * kPi * i / 40));
  std::vector<Vec2> grown = circle;
  const std::size_t n = growToFewerVertices(grown, grown.size(), 16);
  ASSERT_EQ(n, 16u);
  const PolygonView g(grown.data(), n);
  EXPECT_TRUE(isConvex(g));
  for (const Vec2& v : circle) EXPECT_NE(locatePoint(v, g), Containment::kOutside);
  EXPECT_LT(signedArea(g), 1.03 * kPi);  // a circumscribed 16-gon: 3.18 vs pi = 3.14
  EXPECT_GT(signedArea(g), signedArea(circle));
  // Already small enough: untouched.
  EXPECT_EQ(growToFewerVertices(grown, 16, 16), 16u);
}

TEST(StaticMapMask, MarksTheOfficeWallsWithTheirMarginAndLeavesTheCorridorFree) {
  const StaticMapMask mask(test::officeMap(), 0.1, 0.15);
  EXPECT_FALSE(mask.blockedAt({4.5, 4.5}));   // the corridor
  EXPECT_TRUE(mask.blockedAt({3.4, 2.95}));   // inside the wall piece y 2.88..3, x 3..3.825
  EXPECT_TRUE(mask.blockedAt({3.4, 3.05}));   // 5 cm in front of it
  EXPECT_FALSE(mask.blockedAt({3.4, 3.25}));  // 0.25 m in front of it
  EXPECT_FALSE(mask.blockedAt({4.5, 2.95}));  // the door in that wall
  EXPECT_TRUE(mask.blockedAt({-1.0, 4.5}));   // outside the bounds
  EXPECT_TRUE(mask.blockedAt({13.0, 13.0}));  // the solid centre block
  PolygonMap no_bounds;
  no_bounds.obstacles = {{{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}}};
  const StaticMapMask open(no_bounds, 0.1, 0.15);
  EXPECT_TRUE(open.blockedAt({0.5, 0.5}));
  EXPECT_FALSE(open.blockedAt({50.0, -3.0}));
  EXPECT_THROW(StaticMapMask(no_bounds, 0.0, 0.1), std::invalid_argument);
}

TEST(DepthObstacles, RejectsABadConfigNamingTheField) {
  DepthObstaclesConfig c;
  c.max_vertices = 40;
  try {
    DepthObstacleDetector d(test::officeMap(), hal::CameraIntrinsics{}, test::levelMount(), c);
    FAIL() << "max_vertices 40 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_vertices"), std::string::npos) << e.what();
  }
  c = DepthObstaclesConfig{};
  c.max_height_m = 0.0;
  EXPECT_THROW(DepthObstacleDetector(test::officeMap(), hal::CameraIntrinsics{}, test::levelMount(), c),
               std::invalid_argument);
  const auto rejects = [](const DepthObstaclesConfig& bad, const char* field) {
    try {
      validateDepthObstaclesConfig(bad);
      ADD_FAILURE() << field << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  c = DepthObstaclesConfig{};
  c.turn_rate_time_s = 0.0;
  rejects(c, "turn_rate_time_s");
  c = DepthObstaclesConfig{};
  c.turn_min_speed_mps = -0.1;
  rejects(c, "turn_min_speed_mps");
  c = DepthObstaclesConfig{};
  c.max_turn_rate_rps = std::numeric_limits<double>::quiet_NaN();
  rejects(c, "max_turn_rate_rps");
}

}  // namespace
}  // namespace staa
