// The simulated depth camera against geometry worked out by hand: depths of walls, the floor
// and a low box's top, heights where a wall ends, the robot's heading, noise and frame rate.
#include "world/sim_depth_camera.hpp"

#include "depth_scenes.hpp"
#include "world/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

namespace staa {
namespace {

using hal::DepthFrame;

Polygon rect(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

PolygonMap mapOf(std::vector<Polygon> obstacles) {
  PolygonMap m;
  m.name = "test";
  m.obstacles = std::move(obstacles);
  return m;
}

std::uint16_t at(const DepthFrame& f, int u, int v) {
  return f.depth_mm[static_cast<std::size_t>(v) * DepthFrame::kWidth + static_cast<std::size_t>(u)];
}

hal::SimDepthConfig config(const hal::CameraMount& mount) {
  hal::SimDepthConfig c;
  c.intrinsics = hal::CameraIntrinsics{570.0, 570.0, 320.0, 240.0};
  c.mount = mount;
  return c;
}

TEST(SimDepthCamera, WallAheadHasOneDepthUpToItsTopAndNothingAbove) {
  // A 2 m wall 3 m ahead, perpendicular to the optical axis: every pixel on it has optical
  // depth 3000 mm. Its top edge, 1 m above the camera, is at row cy - fy / 3 = 50; above it
  // the camera sees nothing (no floor upwards, nothing within 8 m).
  hal::DepthRenderer renderer(mapOf({rect(3.0, -10.0, 3.2, 10.0)}), config(test::levelMount()));
  auto frame = test::newFrame();
  renderer.render(Pose2{0.0, 0.0, 0.0}, {}, *frame);
  for (int u : {0, 160, 320, 639}) {
    for (int v : {52, 120, 240, 300}) EXPECT_EQ(at(*frame, u, v), 3000) << "u " << u << " v " << v;
    EXPECT_EQ(at(*frame, u, 48), 0) << "u " << u;
  }
  // The row 57 px below centre would meet the floor at 1 / 0.1 = 10 m, beyond the wall, so it
  // sees the wall; the bottom row meets the floor at depth 1 m / (239 / 570) = 2.385 m, in
  // front of the wall's foot.
  EXPECT_EQ(at(*frame, 320, 297), 3000);
  EXPECT_EQ(at(*frame, 320, 479), 2385);
}

TEST(SimDepthCamera, TiltedHeadSeesTheFloorAtTheDepthTrigonometryGives) {
  hal::DepthRenderer renderer(mapOf({}), config(test::hsrHeadMount()));
  auto frame = test::newFrame();
  renderer.render(Pose2{2.0, -1.0, 0.7}, {}, *frame);
  // The centre ray meets the floor at optical depth 1 / sin(0.3) = 3.3839 m.
  EXPECT_EQ(at(*frame, 320, 240), 3384);
  // The top row looks atan(240 / 570) - 0.3 = 0.099 rad above the horizon: no floor.
  EXPECT_EQ(at(*frame, 320, 0), 0);
  // A row looking 0.1 rad below the horizon would meet the floor 10 m away: beyond 8 m.
  const int v_far = 240 - static_cast<int>(std::lround(570.0 * std::tan(0.2)));
  EXPECT_EQ(at(*frame, 320, v_far), 0);
}

TEST(SimDepthCamera, LowBoxShowsItsTopToACameraAboveIt) {
  // A 0.3 m box under the tilted head's centre ray: the ray falls to 0.3 m at 0.7 / tan(0.3)
  // = 2.255 m ahead, inside the box (2.0..2.6 m), at optical depth 0.7 / sin(0.3) = 2.3687 m.
  hal::DepthRenderer renderer(mapOf({}), config(test::hsrHeadMount()));
  const Polygon box = rect(-0.3, -0.5, 0.3, 0.5);
  const hal::PrismView prism{box, Vec2(2.3, 0.0), 0.3};
  auto frame = test::newFrame();
  renderer.render(Pose2{0.0, 0.0, 0.0}, std::span<const hal::PrismView>(&prism, 1), *frame);
  EXPECT_EQ(at(*frame, 320, 240), 2369);
  // Its front face at x = 2.0: the row looking at z = 0.15 there has depth (optical z)
  // 2.0 * cos(0.3) + 0.85 * sin(0.3).
  const Vec3 p(2.0, 0.0, 0.15);
  const Vec3 pixel = renderer.camera().project(p);
  const int v = static_cast<int>(std::lround(pixel.y()));
  const Vec3 seen = renderer.camera().position() + at(*frame, 320, v) * 1e-3 * renderer.camera().ray(320, v);
  EXPECT_NEAR(seen.x(), 2.0, 0.002);
}

TEST(SimDepthCamera, RobotHeadingTurnsTheView) {
  // A wall 3 m north of a robot facing north (theta = pi/2); the camera sits 0.1 m ahead of
  // the base centre, so the wall is 2.9 m from it.
  hal::CameraMount mount = test::levelMount();
  mount.x = 0.1;
  hal::DepthRenderer renderer(mapOf({rect(-10.0, 3.0, 10.0, 3.2)}), config(mount));
  auto frame = test::newFrame();
  renderer.render(Pose2{1.0, 0.0, kPi / 2}, {}, *frame);
  EXPECT_EQ(at(*frame, 320, 240), 2900);
  EXPECT_EQ(at(*frame, 100, 200), 2900);
}

TEST(SimDepthCamera, NoiseHasTheConfiguredSpreadAroundTheTruth) {
  // 1.5 mm/m^2 at 4 m: sigma = 24 mm.
  hal::SimDepthConfig c = config(test::levelMount());
  c.noise_mm_per_m2 = 1.5;
  c.floor = false;
  hal::DepthRenderer renderer(mapOf({rect(4.0, -10.0, 4.2, 10.0)}), c);
  auto frame = test::newFrame();
  renderer.render(Pose2{}, {}, *frame);
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  for (int v = 100; v < 380; ++v) {
    for (int u = 0; u < DepthFrame::kWidth; ++u) {
      const double d = at(*frame, u, v) - 4000.0;
      sum += d;
      sum2 += d * d;
      ++n;
    }
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 0.0, 0.5);
  EXPECT_NEAR(std::sqrt(sum2 / n - mean * mean), 24.0, 1.0);
}

TEST(SimDepthCamera, PixelStrideRendersOnlyTheSampledPixels) {
  hal::SimDepthConfig c = config(test::levelMount());
  c.pixel_stride = 4;
  hal::DepthRenderer renderer(mapOf({rect(3.0, -10.0, 3.2, 10.0)}), c);
  auto frame = test::newFrame();
  frame->depth_mm.fill(7);
  renderer.render(Pose2{}, {}, *frame);
  EXPECT_EQ(at(*frame, 322, 242), 3000);  // stride 4 samples 2, 6, 10, ...
  EXPECT_EQ(at(*frame, 320, 240), 0);
  EXPECT_EQ(at(*frame, 323, 242), 0);
}

TEST(SimDepthCamera, SeesTheWorldsMoversAndRunsAtItsRate) {
  // A standing mover (0.4 m box) 2 m ahead in an empty world: its front face is 1.8 m away.
  PolygonMap empty = mapOf({});
  World world(empty, test::hsrProfile(), Pose2{0.0, 0.0, 0.0}, {test::boxMover({2.0, 0.0}, {2.0, 0.0}, 0.0)});
  hal::SimDepthConfig c = config(test::levelMount());
  c.floor = false;
  hal::SimDepthCamera camera(world, c);
  EXPECT_DOUBLE_EQ(camera.mount().z, 1.0);
  EXPECT_DOUBLE_EQ(camera.intrinsics().fx, 570.0);
  auto frame = test::newFrame();
  // Polled at 100 Hz for one second: 30 frames on a 30 Hz schedule, stamped when read.
  int frames = 0;
  rt::Nanos last = -1;
  for (int k = 0; k < 100; ++k) {
    const rt::Nanos now = k * 10 * rt::kNanosPerMilli;
    if (camera.read(now, *frame)) {
      ++frames;
      EXPECT_EQ(frame->stamp, now);
      EXPECT_EQ(frame->sequence, static_cast<std::uint64_t>(frames));
      last = now;
    }
  }
  EXPECT_EQ(frames, 30);
  EXPECT_GE(last, 960 * rt::kNanosPerMilli);
  EXPECT_EQ(at(*frame, 320, 240), 1800);
  EXPECT_EQ(at(*frame, 0, 240), 0);  // beside the box: nothing
}

TEST(SimDepthCamera, RejectsABadConfigNamingTheField) {
  hal::SimDepthConfig c = config(test::levelMount());
  c.max_depth_m = 0.1;
  try {
    hal::DepthRenderer renderer(mapOf({}), c);
    FAIL() << "max_depth_m below min_depth_m accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_depth_m"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace staa
