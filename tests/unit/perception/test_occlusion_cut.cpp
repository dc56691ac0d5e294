// A body cut off by something nearer (findCuts): a person walking out from behind a box, seen
// by the scan. While part of it is hidden its centroid moves with the cut, at a fraction of its
// speed; its free end, the silhouette on the scan, moves with it and gives the velocity. Frames
// and scans rendered; the camera looks away, so the scan alone sees the person.
#include "perception/depth_obstacles.hpp"

#include "world/sim_depth_camera.hpp"
#include "world/sim_laser_scan.hpp"
#include "depth_scenes.hpp"
#include "world/world.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

namespace staa {
namespace {

constexpr double kDt = 1.0 / 30.0;
constexpr rt::Nanos kPeriod = 33'333'333;
constexpr double kHalf = 0.2;  // the person: a 0.4 m square

// The robot at the origin facing north (its camera looks away); a box at x 2..3, y 0.2..1.2
// hides the line x = 4.5 between y = 0.3 and y = 2.7 from the scanner at the base centre.
PolygonMap boxRoom() {
  PolygonMap m;
  m.name = "box room";
  m.bounds = Box{Vec2(-3.0, -4.0), Vec2(8.0, 6.0)};
  m.obstacles.push_back({{2.0, 0.2}, {3.0, 0.2}, {3.0, 1.2}, {2.0, 1.2}});
  return m;
}

struct Scene {
  // The person walks from `from` to `to` at `speed`.
  Scene(const Vec2& from, const Vec2& to, double speed, const DepthObstaclesConfig& config = {})
      : map(boxRoom()),
        world(map, test::hsrProfile(), Pose2{0.0, 0.0, 0.5 * kPi}, {Mover{test::square(kHalf), {from, to}, speed}}),
        camera(world, cameraConfig()),
        scanner(map, test::baseScannerConfig()),
        detector(map, camera.intrinsics(), camera.mount(), config),
        frame(test::newFrame()),
        scan(std::make_unique<hal::LaserScan>()) {}
  static hal::SimDepthConfig cameraConfig() {
    hal::SimDepthConfig c;
    c.mount = test::hsrHeadMount();
    return c;
  }
  void step() {
    world.step(kDt, 0.0, 0.0);
    now += kPeriod;
    ASSERT_TRUE(camera.read(now, *frame));
    const std::vector<hal::PrismView> prisms{
        hal::PrismView{PolygonView(world.mover(0).polygon), world.moverPosition(0), 1.7}};
    scanner.render(world.robot().pose, prisms, *scan);
    scan->stamp = now;
    const Pose2 pose = world.robot().pose;
    detector.process(*frame, pose, out, ScanInput{scan.get(), scanner.config().mount, pose});
  }

  PolygonMap map;
  World world;
  hal::SimDepthCamera camera;
  hal::ScanRenderer scanner;
  DepthObstacleDetector detector;
  std::unique_ptr<hal::DepthFrame> frame;
  std::unique_ptr<hal::LaserScan> scan;
  hal::ObstacleFrame out;
  rt::Nanos now = 0;
};

// Where the person is on the scan: hidden (its bottom above the box's shadow), partly hidden,
// or in the open. The shadow's edge is the line from the scanner over the box's corner (3, 0.2).
enum class Sight { kHidden, kPart, kOpen };
Sight sightOf(double y) {
  const double shadow_near = (4.5 - kHalf) * 0.2 / 3.0, shadow_far = (4.5 + kHalf) * 0.2 / 3.0;
  if (y - kHalf > shadow_far) return Sight::kHidden;
  if (y + kHalf > shadow_near) return Sight::kPart;
  return Sight::kOpen;
}

TEST(OcclusionCut, APersonComingOutFromBehindABoxHasItsVelocityWhilePartlyHidden) {
  Scene s(Vec2(4.5, 3.6), Vec2(4.5, -3.0), 1.0);  // south along x = 4.5
  int part = 0, part_checked = 0;
  double worst = 0.0;
  for (int k = 0; k < 150; ++k) {
    s.step();
    const double y = s.world.moverPosition(0).y();
    if (y < -2.5) break;
    const Sight sight = sightOf(y);
    if (sight != Sight::kPart) continue;
    ++part;
    // From the sixth frame the person is partly in view: the free end has moved four times.
    // The centroid alone gives half the speed here (the visible half moves with the cut).
    if (part < 6) continue;
    ASSERT_EQ(s.out.count, 1u) << "frame " << k << ", person at y = " << y;
    const Vec2 v = s.out.obstacles[0].velocity;
    worst = std::max(worst, (v - Vec2(0.0, -1.0)).norm());
    EXPECT_NEAR(v.x(), 0.0, 0.25) << "frame " << k << ", y = " << y;
    EXPECT_NEAR(v.y(), -1.0, 0.25) << "frame " << k << ", y = " << y;
    ++part_checked;
  }
  // 0.4 m of coming out at 1 m/s: 12 or 13 frames, the last 7 or 8 checked.
  EXPECT_GE(part, 12);
  EXPECT_GE(part_checked, 7);
  std::printf("partly hidden: %d frames, worst velocity error from the sixth: %.2f m/s\n", part, worst);
}

// The same person standing half behind the box: cut, but still, its free end does not move.
TEST(OcclusionCut, APersonStandingHalfBehindTheBoxStaysStill) {
  Scene s(Vec2(4.5, 0.3), Vec2(4.5, 0.3), 0.0);
  for (int k = 0; k < 30; ++k) s.step();
  ASSERT_EQ(s.out.count, 1u);
  EXPECT_LT(s.out.obstacles[0].velocity.norm(), 0.15);
}

}  // namespace
}  // namespace staa
