// A planar scan perceived with the depth frames (ScanInput): the HSR's base scanner sees a
// person beside the robot, where the head camera does not; its returns give the same kind of
// obstacle and track as the camera's points (an outline on the person, a settled velocity),
// the track stays seen while the person walks past beside the robot, and a scan that fails
// its checks changes nothing. Frames and scans rendered in the office map's corridor.
#include "perception/depth_obstacles.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "world/sim_depth_camera.hpp"
#include "world/sim_laser_scan.hpp"
#include "depth_scenes.hpp"
#include "world/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace staa {
namespace {

constexpr double kDt = 1.0 / 30.0;
constexpr rt::Nanos kPeriod = 33'333'333;
constexpr double kPersonHeight = 1.7;


Vec2 centroidOf(const hal::ObstacleFrame::Obstacle& o) {
  Vec2 c = Vec2::Zero();
  for (std::size_t k = 0; k < o.n; ++k) c += o.vertices[k];
  return c / static_cast<double>(o.n);
}

// The robot stands in the corridor facing east; the camera is the HSR's head (58 degrees), the
// scanner a UST-20LX-like sweep at the base centre.
struct Scene {
  explicit Scene(std::vector<Mover> movers)
      : world(test::officeMap(), test::hsrProfile(), test::kCorridorStart, std::move(movers)),
        camera(world, cameraConfig()),
        scanner(test::officeMap(), test::baseScannerConfig()),
        with_scan(test::officeMap(), camera.intrinsics(), camera.mount()),
        camera_only(test::officeMap(), camera.intrinsics(), camera.mount()),
        frame(test::newFrame()),
        scan(std::make_unique<hal::LaserScan>()) {
    for (std::size_t i = 0; i < world.moverCount(); ++i) {
      prisms.push_back(hal::PrismView{PolygonView(world.mover(i).polygon), world.moverPosition(i), kPersonHeight});
    }
  }
  static hal::SimDepthConfig cameraConfig() {
    hal::SimDepthConfig c;
    c.mount = test::hsrHeadMount();
    c.noise_mm_per_m2 = 1.5;
    return c;
  }

  void step() {
    world.step(kDt, 0.0, 0.0);
    now += kPeriod;
    ASSERT_TRUE(camera.read(now, *frame));
    for (std::size_t i = 0; i < prisms.size(); ++i) prisms[i].position = world.moverPosition(i);
    scanner.render(world.robot().pose, prisms, *scan);
    scan->stamp = now;
    with_scan.process(*frame, world.robot().pose, fused, ScanInput{scan.get(), scanner.config().mount, world.robot().pose});
    camera_only.process(*frame, world.robot().pose, seen);
  }

  World world;
  hal::SimDepthCamera camera;
  hal::ScanRenderer scanner;
  DepthObstacleDetector with_scan, camera_only;
  std::unique_ptr<hal::DepthFrame> frame;
  std::unique_ptr<hal::LaserScan> scan;
  std::vector<hal::PrismView> prisms;
  hal::ObstacleFrame fused, seen;
  rt::Nanos now = 0;
};

TEST(ScanFusion, APersonBesideTheRobotIsSeenByTheScanNotByTheCamera) {
  // Standing 1 m north of the robot, 90 degrees off the camera's axis.
  Scene s({test::boxMover({4.5, 5.5}, {4.5, 5.5}, 0.0)});
  for (int k = 0; k < 5; ++k) s.step();
  EXPECT_EQ(s.seen.count, 0u);
  ASSERT_EQ(s.fused.count, 1u);
  const Polygon body = s.world.moverPolygon(0);
  const hal::ObstacleFrame::Obstacle& o = s.fused.obstacles[0];
  // The outline lies on the person's near (south) face: within a cell of it, centred on it.
  Polygon grown(o.vertices.begin(), o.vertices.begin() + static_cast<std::ptrdiff_t>(o.n));
  growOutline(grown, 0.1);
  EXPECT_TRUE(polygonsOverlap(PolygonView(grown), PolygonView(body)));
  EXPECT_NEAR(centroidOf(o).x(), 4.5, 0.1);
  EXPECT_NEAR(centroidOf(o).y(), 5.3, 0.15);
  EXPECT_EQ(o.unseen_s, 0.0);
  EXPECT_LT(o.velocity.norm(), 0.1);
}

TEST(ScanFusion, APersonWalkingPastBesideTheRobotStaysSeenWithItsVelocity) {
  // 1 m/s eastwards along y = 5.5, from 2 m behind the robot to 2.5 m ahead of it. The scan
  // sweeps 135 degrees to either side: it sees the person from x = 3.66 (1 m to the side at
  // 50 degrees behind abeam); the camera's 58 degrees only from x = 6.3.
  Scene s({test::boxMover({2.5, 5.5}, {7.0, 5.5}, 1.0)});
  int beside = 0, beside_camera_seen = 0;
  for (int k = 0; k < 120; ++k) {
    s.step();
    const double x = s.world.moverPosition(0).x();
    // From 0.45 m into the sweep (the track's first frames) to the turn at the end.
    if (x < 4.1 || x > 7.0 - 0.2) continue;
    ASSERT_GE(s.fused.count, 1u) << "frame " << k << ", person at x = " << x;
    const hal::ObstacleFrame::Obstacle& o = s.fused.obstacles[0];
    EXPECT_EQ(o.unseen_s, 0.0) << "frame " << k;
    EXPECT_NEAR(o.velocity.x(), 1.0, 0.3) << "frame " << k << ", person at x = " << x;
    EXPECT_NEAR(o.velocity.y(), 0.0, 0.3) << "frame " << k;
    if (x < 5.3) {
      ++beside;
      for (std::size_t i = 0; i < s.seen.count; ++i) beside_camera_seen += s.seen.obstacles[i].unseen_s == 0.0 ? 1 : 0;
    }
  }
  EXPECT_GE(beside, 33);               // 1.2 m at 1 m/s, 30 frames a second
  EXPECT_EQ(beside_camera_seen, 0);    // the camera alone saw none of it
}

TEST(ScanFusion, ScanRangeSetsHowFarTheScanIsUsed) {
  // A person standing 6 m down the corridor ahead, beyond the 4.5 m the camera's depth is used
  // to; the scan (20 m) reaches it, the grid only with scan_range_m.
  Scene s({test::boxMover({10.5, 5.5}, {10.5, 5.5}, 0.0)});
  DepthObstaclesConfig far;
  far.scan_range_m = 8.0;
  DepthObstacleDetector wide(test::officeMap(), s.camera.intrinsics(), s.camera.mount(), far);
  hal::ObstacleFrame out;
  for (int k = 0; k < 5; ++k) {
    s.step();
    wide.process(*s.frame, s.world.robot().pose, out, ScanInput{s.scan.get(), s.scanner.config().mount, s.world.robot().pose});
  }
  EXPECT_EQ(s.fused.count, 0u);  // the default grid: 4.5 m
  ASSERT_EQ(out.count, 1u);
  EXPECT_NEAR(centroidOf(out.obstacles[0]).x(), 10.3, 0.15);  // its west face
  EXPECT_NEAR(centroidOf(out.obstacles[0]).y(), 5.5, 0.15);
  // A negative range is refused naming the field.
  far.scan_range_m = -1.0;
  try {
    validateDepthObstaclesConfig(far);
    FAIL() << "scan_range_m -1 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("scan_range_m"), std::string::npos) << e.what();
  }
}

TEST(ScanFusion, AScanThatFailsItsChecksChangesNothing) {
  Scene s({test::boxMover({6.5, 4.5}, {6.5, 4.5}, 0.0)});  // 2 m ahead: the camera sees it
  s.step();
  auto bad = std::make_unique<hal::LaserScan>(*s.scan);
  const Pose2 pose = s.world.robot().pose;
  DepthObstacleDetector a(test::officeMap(), s.camera.intrinsics(), s.camera.mount());
  DepthObstacleDetector b(test::officeMap(), s.camera.intrinsics(), s.camera.mount());
  hal::ObstacleFrame out_a, out_b;
  a.process(*s.frame, pose, out_a);
  for (int variant = 0; variant < 4; ++variant) {
    *bad = *s.scan;
    if (variant == 0) bad->count = 0;
    if (variant == 1) bad->count = hal::LaserScan::kMaxBeams + 1;
    if (variant == 2) bad->angle_increment = std::numeric_limits<double>::quiet_NaN();
    if (variant == 3) bad->range_max = std::numeric_limits<double>::infinity();
    b.resetTracks();
    const DepthObstaclesStats stats = b.process(*s.frame, pose, out_b, ScanInput{bad.get(), hal::ScanMount{}, pose});
    EXPECT_EQ(stats.scan_points, 0u) << "variant " << variant;
    ASSERT_EQ(out_b.count, out_a.count) << "variant " << variant;
    for (std::size_t i = 0; i < out_a.count; ++i) {
      ASSERT_EQ(out_b.obstacles[i].n, out_a.obstacles[i].n);
      for (std::size_t v = 0; v < out_a.obstacles[i].n; ++v) {
        EXPECT_EQ(out_b.obstacles[i].vertices[v], out_a.obstacles[i].vertices[v]);
      }
    }
  }
  EXPECT_EQ(out_a.count, 1u);
}

}  // namespace
}  // namespace staa
