// Perception with a per-frame camera mount (DepthFrame::has_mount, camera.backend ros: the
// HSR's head pans and tilts): an obstacle seen with the head panned is placed where it is;
// the frame's mount gives what a detector built for that mount gives; a frame without one is
// seen from the detector's fixed mount as before.
#include "perception/depth_obstacles.hpp"

#include "geometry/polygon.hpp"
#include "world/sim_depth_camera.hpp"
#include "depth_scenes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <span>

namespace staa {
namespace {

PolygonView view(const hal::ObstacleFrame::Obstacle& o) { return {o.vertices.data(), o.n}; }

double distanceTo(const Vec2& p, PolygonView poly) {
  return locatePoint(p, poly) == Containment::kOutside ? distanceToEdges(p, poly) : 0.0;
}

Vec2 centroidOf(PolygonView poly) {
  Vec2 c(0.0, 0.0);
  for (const Vec2& v : poly) c += v;
  return c / static_cast<double>(poly.size());
}

void expectSameObstacles(const hal::ObstacleFrame& a, const hal::ObstacleFrame& b) {
  ASSERT_EQ(a.count, b.count);
  for (std::size_t i = 0; i < a.count; ++i) {
    ASSERT_EQ(a.obstacles[i].n, b.obstacles[i].n);
    for (std::size_t k = 0; k < a.obstacles[i].n; ++k) EXPECT_EQ(a.obstacles[i].vertices[k], b.obstacles[i].vertices[k]);
  }
}

// The HSR's head panned 0.5 rad to the left and tilted 0.3 rad down, 1 m up; the robot in the
// corridor facing east; a 0.4 m box 2 m away in the head's direction.
constexpr double kPan = 0.5;
const hal::CameraMount kPanned{0.0, 0.0, 1.0, 0.0, 0.3, kPan};
Vec2 boxCentre() { return test::kCorridorStart.position() + 2.0 * Vec2(std::cos(kPan), std::sin(kPan)); }

std::unique_ptr<hal::DepthFrame> panned_frame() {
  hal::SimDepthConfig c;
  c.mount = kPanned;
  hal::DepthRenderer renderer(test::officeMap(), c);
  const Polygon box = test::square(0.2);
  const hal::PrismView prism{PolygonView(box.data(), box.size()), boxCentre(), 1.7};
  auto frame = test::newFrame();
  renderer.render(test::kCorridorStart, std::span<const hal::PrismView>(&prism, 1), *frame);
  frame->stamp = 1'000'000;
  frame->sequence = 1;
  return frame;
}

TEST(FrameMount, AnObstacleSeenWithTheHeadPannedIsWhereItIs) {
  const auto frame = panned_frame();
  frame->has_mount = true;
  frame->mount = kPanned;
  // The detector's own mount is the configured one, looking ahead: the frame's mount wins.
  DepthObstacleDetector detector(test::officeMap(), hal::CameraIntrinsics{}, test::hsrHeadMount());
  hal::ObstacleFrame out;
  detector.process(*frame, test::kCorridorStart, out);
  ASSERT_EQ(out.count, 1u);
  const auto& o = out.obstacles[0];
  const Vec2 kBox = boxCentre();
  // The face the camera sees (nearest the robot) is covered; every vertex near the true box.
  const Vec2 facing = kBox - 0.2 * Vec2(std::cos(kPan), std::sin(kPan));
  EXPECT_LE(distanceTo(facing, view(o)), 0.1);
  const Polygon truth{{kBox.x() - 0.2, kBox.y() - 0.2}, {kBox.x() + 0.2, kBox.y() - 0.2},
                      {kBox.x() + 0.2, kBox.y() + 0.2}, {kBox.x() - 0.2, kBox.y() + 0.2}};
  for (std::size_t i = 0; i < o.n; ++i) EXPECT_LE(distanceTo(o.vertices[i], truth), 0.15);
  const Vec2 c = centroidOf(view(o));
  EXPECT_NEAR(std::atan2(c.y() - test::kCorridorStart.y, c.x() - test::kCorridorStart.x), kPan, 0.06);

  // The same as a detector whose fixed mount is the panned one (bit for bit).
  DepthObstacleDetector fixed(test::officeMap(), hal::CameraIntrinsics{}, kPanned);
  hal::ObstacleFrame fixed_out;
  frame->has_mount = false;
  fixed.process(*frame, test::kCorridorStart, fixed_out);
  expectSameObstacles(out, fixed_out);
}

TEST(FrameMount, AFrameWithoutAMountIsSeenFromTheFixedMountAsBefore) {
  const auto frame = panned_frame();
  DepthObstacleDetector detector(test::officeMap(), hal::CameraIntrinsics{}, test::hsrHeadMount());
  DepthObstacleDetector fresh(test::officeMap(), hal::CameraIntrinsics{}, test::hsrHeadMount());
  hal::ObstacleFrame before, panned, after;
  // Seen from the fixed mount (looking ahead), the pan is unknown: the box appears turned
  // back about the camera's tilted axis, at (6.59, 4.88) instead of (6.26, 5.46), nearer the
  // robot's heading (and the corridor's wall turned with it off the map: another obstacle).
  fresh.process(*frame, test::kCorridorStart, before);
  ASSERT_GE(before.count, 1u);
  const Vec2 c = centroidOf(view(before.obstacles[0]));  // the nearest
  EXPECT_GT((c - boxCentre()).norm(), 0.5);
  EXPECT_LT(std::atan2(c.y() - test::kCorridorStart.y, c.x() - test::kCorridorStart.x), 0.3);
  // A frame with its mount, then one without on the same detector: the fixed mount's rays
  // are back, with the fresh detector's result.
  frame->has_mount = true;
  frame->mount = kPanned;
  detector.process(*frame, test::kCorridorStart, panned);
  ASSERT_EQ(panned.count, 1u);
  EXPECT_GT((centroidOf(view(panned.obstacles[0])) - c).norm(), 0.5);
  frame->has_mount = false;
  frame->stamp += 33'333'333;
  detector.process(*frame, test::kCorridorStart, after);
  // The obstacles seen in this frame come first and are the fresh detector's; after them the
  // panned frame's track, not seen now, is still reported (unseen, at its place).
  ASSERT_EQ(after.count, before.count + 1);
  hal::ObstacleFrame seen = after;
  seen.count = before.count;
  expectSameObstacles(seen, before);
  const auto& kept = after.obstacles[before.count];
  EXPECT_GT(kept.unseen_s, 0.0);
  EXPECT_LT((centroidOf(view(kept)) - centroidOf(view(panned.obstacles[0]))).norm(), 0.05);
}

}  // namespace
}  // namespace staa
