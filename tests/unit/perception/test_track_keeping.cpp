// Tracks that leave the camera's view (DepthObstaclesConfig::keep_unseen_s), on frames of the
// simulated camera in the office map's corridor: a person walking out of the view and back is
// kept while unseen, at its predicted place with a growing outline, and the same track goes on
// when it reappears; a person the robot turns away from and back to is kept where it walks; one
// that stays away is dropped after keep_unseen_s; without keeping (0) the track is forgotten
// and starts again at rest.
#include "perception/depth_obstacles.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "world/footprint.hpp"
#include "world/sim_depth_camera.hpp"
#include "depth_scenes.hpp"
#include "world/world.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace staa {
namespace {

constexpr double kDt = 1.0 / 30.0;
constexpr rt::Nanos kPeriod = 33'333'333;
constexpr double kHalf = 0.2;  // the person: a 0.4 m square

PolygonView view(const hal::ObstacleFrame::Obstacle& o) { return {o.vertices.data(), o.n}; }

struct ViewRun {
  ViewRun(std::vector<Mover> movers, const DepthObstaclesConfig& config, const RobotProfile& robot = test::hsrProfile())
      : world(test::officeMap(), robot, test::kCorridorStart, std::move(movers)),
        camera(world, cameraConfig()),
        detector(test::officeMap(), camera.intrinsics(), camera.mount(), config),
        frame(test::newFrame()) {}

  static hal::SimDepthConfig cameraConfig() {
    hal::SimDepthConfig c;
    c.mount = test::hsrHeadMount();
    c.noise_mm_per_m2 = 1.5;
    return c;
  }

  void step(double w = 0.0) {
    world.step(kDt, 0.0, w);
    now += kPeriod;
    ASSERT_TRUE(camera.read(now, *frame));
    detector.process(*frame, world.robot().pose, out);
  }

  // The person's body now.
  Polygon truth() const {
    Polygon body = test::square(kHalf);
    for (Vec2& v : body) v += world.moverPosition(0);
    return body;
  }

  // Whether any of the person is in the camera's image within its range: a corner at some
  // height from the floor to 1.7 m projected into the image (a pitched camera's view is wider
  // at its bottom rows than at its middle).
  bool anyInView() const {
    const Pose2& r = world.robot().pose;
    const CameraModel& cam = detector.camera();
    const double c = std::cos(r.theta), s = std::sin(r.theta);
    for (const Vec2& v : truth()) {
      const Vec2 d = v - r.position();
      for (double h = 0.0; h <= 1.7; h += 0.1) {
        const Vec3 p = cam.project(Vec3(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), h));
        if (p.z() > 0.45 && p.x() >= 0.0 && p.x() < hal::DepthFrame::kWidth && p.y() >= 0.0 &&
            p.y() < hal::DepthFrame::kHeight) {
          return true;
        }
      }
    }
    return false;
  }

  World world;
  hal::SimDepthCamera camera;
  DepthObstacleDetector detector;
  std::unique_ptr<hal::DepthFrame> frame;
  hal::ObstacleFrame out;
  rt::Nanos now = 0;
};

// 1 m ahead of the robot the head's view is about 1.3 m wide at the person's knees: a person
// walking from the corridor's middle to y = 5.75 and back is wholly out of it for a moment of
// each turn.
Mover outAndBack() { return Mover{test::square(kHalf), {{5.5, 4.5}, {5.5, 5.75}}, 0.8}; }

TEST(TrackKeeping, APersonWalkingOutOfTheViewAndBackIsKeptAndTheSameTrackGoesOn) {
  ViewRun run({outAndBack()}, DepthObstaclesConfig{});
  int out_frames = 0, out_phases = 0, returns = 0;
  double last_area = 0.0, largest_unseen = 0.0, farthest = 0.0, slowest_settle = 0.0;
  bool out = false;
  int since_return = -1;
  for (int k = 1; k <= 10 * 30; ++k) {  // 10 s: the person walks out of the view and back 3 times
    run.step();
    SCOPED_TRACE("frame " + std::to_string(k));
    if (k < 15) continue;  // the first track settles
    const Polygon truth = run.truth();
    if (!run.anyInView()) {
      // Out of view: one obstacle, kept (not seen in this frame), where the person is.
      ++out_frames;
      out_phases += out ? 0 : 1;
      out = true;
      ASSERT_EQ(run.out.count, 1u);
      const auto& o = run.out.obstacles[0];
      EXPECT_GT(o.unseen_s, 0.0);
      EXPECT_TRUE(isConvex(view(o)));
      farthest = std::max(farthest, polygonDistance(truth, view(o)));
      // Its outline grows the longer it is unseen.
      const double area = signedArea(view(o));
      if (o.unseen_s > largest_unseen) {
        EXPECT_GE(area, last_area - 1e-9);
        last_area = area;
        largest_unseen = o.unseen_s;
      }
      continue;
    }
    out = false;
    if (run.out.count == 1 && run.out.obstacles[0].unseen_s == 0.0 && largest_unseen > 0.0) {
      // Seen again after being kept: the same track, so its velocity is the filter's, not the
      // rest a new track starts at.
      ++returns;
      EXPECT_NE(run.out.obstacles[0].velocity, Vec2(0.0, 0.0));
      since_return = 0;
      largest_unseen = 0.0;
      last_area = 0.0;
    } else if (since_return >= 0 && run.out.count == 1) {
      // It turned back while unseen: the velocity follows it again.
      ++since_return;
      if ((run.out.obstacles[0].velocity - run.world.moverVelocity(0)).norm() < 0.3) {
        slowest_settle = std::max(slowest_settle, since_return * kDt);
        since_return = -1;
      }
    }
  }
  EXPECT_GE(out_phases, 2);
  EXPECT_GT(out_frames, 20);
  EXPECT_EQ(returns, out_phases);
  EXPECT_EQ(since_return, -1);  // every return settled
  EXPECT_LT(slowest_settle, 1.5);  // a turn back it did not see: from +0.8 to -0.8 m/s
  // The kept outline (the last one seen, moved on at the track's velocity and grown) stays on
  // the person although it turned back unseen.
  EXPECT_LT(farthest, 0.05);
  std::printf("out of view %d frames in %d phases; kept outline at most %.3f m from the person; velocity settled "
              "%.2f s after it came back\n",
              out_frames, out_phases, farthest, slowest_settle);
}

TEST(TrackKeeping, WithoutKeepingTheTrackIsForgottenAndStartsAgainAtRest) {
  DepthObstaclesConfig forget;
  forget.keep_unseen_s = 0.0;
  ViewRun run({outAndBack()}, forget);
  bool was_out = false;
  int empty_out_frames = 0, restarts = 0;
  for (int k = 1; k <= 4 * 30; ++k) {
    run.step();
    if (k < 15) continue;
    if (!run.anyInView()) {
      was_out = true;
      empty_out_frames += run.out.count == 0 ? 1 : 0;
    } else if (was_out && run.out.count == 1) {
      EXPECT_EQ(run.out.obstacles[0].velocity, Vec2(0.0, 0.0)) << "frame " << k;
      ++restarts;
      was_out = false;
    }
  }
  EXPECT_GT(empty_out_frames, 3);
  EXPECT_EQ(restarts, 1);
}

TEST(TrackKeeping, APersonTheRobotTurnsAwayFromIsKeptWhereItWalks) {
  // A person 2 m ahead walks across the corridor at 0.5 m/s; the robot turns 1.2 rad to the
  // left and back at 1 rad/s: the person is out of the view for about a second, walking
  // straight, so the kept track is where it is, and seen again its track goes on. The HSR's
  // profile turns at most 0.5 rad/s (0.5 rad/s^2): too slow to look away and back while the
  // person is still crossing, so this robot has its footprint and camera but turns faster.
  RobotProfile quick = test::hsrProfile();
  quick.limits.w_max = 1.0;
  quick.limits.b_max = 1.5;
  ViewRun run({test::boxMover({6.5, 3.6}, {6.5, 5.4}, 0.5)}, DepthObstaclesConfig{}, quick);
  int kept = 0;
  double worst = 0.0, worst_v_back = 0.0;
  bool was_out = false;
  for (int k = 1; k <= 90; ++k) {
    const double w = k <= 20 ? 0.0 : (k <= 56 ? 1.0 : (k <= 92 ? -1.0 : 0.0));
    run.step(w);
    if (k < 15) continue;
    SCOPED_TRACE("frame " + std::to_string(k));
    ASSERT_EQ(run.out.count, 1u);
    const auto& o = run.out.obstacles[0];
    if (!run.anyInView()) {
      was_out = true;
      ++kept;
      EXPECT_GT(o.unseen_s, 0.0);
      worst = std::max(worst, polygonDistance(run.truth(), view(o)));
      EXPECT_LT((o.velocity - run.world.moverVelocity(0)).norm(), 0.2);
    } else if (was_out && o.unseen_s == 0.0) {
      worst_v_back = std::max(worst_v_back, (o.velocity - run.world.moverVelocity(0)).norm());
    }
  }
  EXPECT_GT(kept, 15);
  EXPECT_LT(worst, 0.05);
  EXPECT_LT(worst_v_back, 0.3);
}

TEST(TrackKeeping, APersonLeftOutOfViewIsDroppedAfterKeepUnseen) {
  // A person stands 2 m ahead; the robot turns 1.5 rad to the left and stays so: the track is
  // kept for keep_unseen_s after the person left the view, then dropped.
  DepthObstaclesConfig config;
  ViewRun run({test::boxMover({6.5, 4.5}, {6.5, 4.5}, 0.0)}, config);
  double left_s = -1.0, dropped_s = -1.0;
  for (int k = 1; k <= 5 * 30; ++k) {
    run.step(k > 20 && run.world.robot().pose.theta < 1.5 ? 1.0 : 0.0);
    const double t = k * kDt;
    if (k <= 20) {
      ASSERT_EQ(run.out.count, 1u);
      continue;
    }
    if (left_s < 0.0 && !run.anyInView()) left_s = t;
    if (left_s >= 0.0 && dropped_s < 0.0 && run.out.count == 0) dropped_s = t;
    if (left_s >= 0.0 && dropped_s < 0.0) {
      ASSERT_EQ(run.out.count, 1u) << "frame " << k;
      EXPECT_GT(run.out.obstacles[0].unseen_s, 0.0);
      // Standing still: kept where it stands (grown, not moved).
      EXPECT_EQ(polygonDistance(run.truth(), view(run.out.obstacles[0])), 0.0);
    }
  }
  ASSERT_GT(left_s, 0.0);
  ASSERT_GT(dropped_s, 0.0);
  // The track was last seen a little before the whole person left the image (inView's margin
  // of 8 pixels): it is dropped keep_unseen_s after that, within a few frames.
  EXPECT_NEAR(dropped_s - left_s, config.keep_unseen_s, 0.25);
  std::printf("left the view at %.2f s, dropped at %.2f s\n", left_s, dropped_s);
}

}  // namespace
}  // namespace staa
