// An agent's depth camera in the simulator (AgentCamera, staa-sim --obstacles depth): a panned
// head renders the same frame as a camera mounted turned by the pan; the obstacles reach the
// planner one frame after the exposure; lost frames are counted; the head follows the
// command's arc within its limits and rate; the frames' obstacles are where the bodies are.
#include "experiment/agent_camera.hpp"

#include "geometry/polygon.hpp"
#include "map/polygon_map.hpp"
#include "world/footprint.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace staa {
namespace {

constexpr double kDt = 1.0 / 30.0;

Polygon rect(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

// A 10 x 10 m room with a pillar.
PolygonMap room() {
  PolygonMap m;
  m.name = "room";
  m.bounds = Box{Vec2(0.0, 0.0), Vec2(10.0, 10.0)};
  m.obstacles = {rect(7.0, 6.0, 7.5, 6.5)};
  return m;
}

// The paper's agent with an ideal camera (no noise, no dropouts, no loss, no latency).
RobotProfile idealAgent() {
  RobotProfile p = paperAgentProfile();
  p.camera.noise_mm_per_m2 = 0.0;
  p.camera.dropout = 0.0;
  p.camera.grazing_deg = 90.0;
  p.camera.frame_loss = 0.0;
  p.camera.latency_s = 0.0;
  p.camera.scan = 0.0;
  return p;
}

TEST(AgentCamera, APannedHeadSeesWhatACameraTurnedByThePanSees) {
  const PolygonMap map = room();
  RobotProfile agent = idealAgent();
  const DepthObstaclesConfig perception = agentPerceptionConfig(agent);
  AgentCamera camera(map, agent, perception, 1);
  // Off-centre, so that the turn about the camera's axis is not a turn about the base's.
  agent.camera.x = 0.2;
  AgentCamera offset(map, agent, perception, 1);
  const Pose2 robot{3.0, 3.0, 0.3};
  // Turn the heads left: a slow robot looks along a path that goes left.
  const std::vector<Vec2> path{{3.0, 3.0}, {3.0, 8.0}};
  for (int k = 0; k < 60; ++k) {
    camera.aimHead(robot, 0.0, 0.0, path, kDt);
    offset.aimHead(robot, 0.0, 0.0, path, kDt);
  }
  const double pan = camera.pan();
  EXPECT_NEAR(pan, kPi / 2.0 - 0.3, 1e-9);  // the path's direction, reached at 2 rad/s within 2 s
  // Seen from 0.2 m ahead of the base centre the path's point 1.5 m on lies more to the left.
  EXPECT_GT(offset.pan(), pan + 0.1);
  const Polygon body = footprintAt(paperAgentProfile().footprint, Pose2{3.0, 6.0, 0.0});
  const std::vector<hal::PrismView> others{{PolygonView(body), Vec2(0.0, 0.0), 1.0}};
  for (AgentCamera* cam : {&camera, &offset}) {
    ASSERT_TRUE(cam->perceive(0.0, robot, others));
    hal::SimDepthConfig turned;
    const DepthCameraProfile& c = cam == &camera ? idealAgent().camera : agent.camera;
    turned.intrinsics = cameraIntrinsics(c);
    turned.mount = cameraMount(c);
    turned.mount.yaw = cam->pan();
    // The camera body turned about the vertical axis through it: the same position.
    turned.mover_height_m = 1.0;
    turned.min_depth_m = c.min_range_m;
    turned.max_depth_m = c.max_range_m;
    turned.pixel_stride = perception.pixel_stride;
    hal::DepthRenderer renderer(map, turned);
    auto expected = std::make_unique<hal::DepthFrame>();
    renderer.render(robot, others, *expected);
    int differ = 0, readings = 0;
    for (std::size_t i = 0; i < expected->depth_mm.size(); ++i) {
      readings += expected->depth_mm[i] != 0 ? 1 : 0;
      const bool d = std::abs(int(expected->depth_mm[i]) - int(cam->image().depth_mm[i])) > 1;
      differ += d ? 1 : 0;
    }
    EXPECT_GT(readings, 10000);
    EXPECT_EQ(differ, 0) << (cam == &camera ? "centred camera" : "camera 0.2 m ahead");
  }
  // And the other agent, 3 m to the robot's left, is one obstacle at its place.
  const hal::ObstacleFrame& f = camera.frame();
  ASSERT_EQ(f.count, 1u);
  EXPECT_LT(polygonDistance(body, PolygonView(f.obstacles[0].vertices.data(), f.obstacles[0].n)), 1e-9);
}

TEST(AgentCamera, ObstaclesReachThePlannerLatencyAfterTheExposureAndLostFramesAreCounted) {
  const PolygonMap map = room();
  RobotProfile agent = idealAgent();
  agent.camera.latency_s = 1.0 / 30.0;
  AgentCamera camera(map, agent, agentPerceptionConfig(agent), 1);
  const std::vector<hal::PrismView> none;
  EXPECT_EQ(camera.delivered(0.0), nullptr);
  ASSERT_TRUE(camera.perceive(0.0, Pose2{3.0, 3.0, 0.0}, none));
  EXPECT_EQ(camera.delivered(0.0), nullptr);  // exposed now, arrives a frame later
  for (int k = 1; k <= 30; ++k) {
    const double t = k * kDt;
    ASSERT_TRUE(camera.perceive(t, Pose2{3.0, 3.0, 0.0}, none));
    const hal::ObstacleFrame* f = camera.delivered(t);
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(f->sequence, static_cast<std::uint64_t>(k));  // the previous frame (sequence k of k + 1)
    // Not due again within the same period.
    EXPECT_FALSE(camera.perceive(t + 0.3 * kDt, Pose2{3.0, 3.0, 0.0}, none));
  }

  agent.camera.frame_loss = 0.5;
  AgentCamera lossy(map, agent, agentPerceptionConfig(agent), 7);
  int taken = 0;
  for (int k = 0; k < 600; ++k) taken += lossy.perceive(k * kDt, Pose2{3.0, 3.0, 0.0}, none) ? 1 : 0;
  EXPECT_EQ(lossy.frames() + lossy.framesLost(), 600u);
  EXPECT_EQ(lossy.frames(), static_cast<std::uint64_t>(taken));
  EXPECT_NEAR(static_cast<double>(lossy.framesLost()), 300.0, 45.0);  // 3 sigma of a fair coin
}

TEST(AgentCamera, TheHeadFollowsTheCommandsArcWithinItsLimitsAndRate) {
  const PolygonMap map = room();
  const RobotProfile agent = idealAgent();  // pan +-2.8 rad at 2 rad/s
  AgentCamera camera(map, agent, agentPerceptionConfig(agent), 1);
  const Pose2 robot{5.0, 5.0, 0.0};
  // Driving a left turn at 1 m/s, 1 rad/s: the arc's point 1.5 m on is 0.75 rad to the left.
  camera.aimHead(robot, 1.0, 1.0, {}, kDt);
  EXPECT_NEAR(camera.pan(), 2.0 * kDt, 1e-12);  // one step of the rate
  for (int k = 0; k < 30; ++k) camera.aimHead(robot, 1.0, 1.0, {}, kDt);
  EXPECT_NEAR(camera.pan(), 0.75, 1e-6);
  // Reversing straight: it looks back as far as it can (+-2.8 rad), from where it is.
  for (int k = 0; k < 90; ++k) camera.aimHead(robot, -1.0, 0.0, {}, kDt);
  EXPECT_NEAR(std::abs(camera.pan()), 2.8, 1e-9);
  // Standing without a path: to the front again.
  for (int k = 0; k < 90; ++k) camera.aimHead(robot, 0.0, 0.0, {}, kDt);
  EXPECT_EQ(camera.pan(), 0.0);
  // A fixed camera never turns.
  RobotProfile fixed = agent;
  fixed.camera.pan_max = 0.0;
  AgentCamera still(map, fixed, agentPerceptionConfig(fixed), 1);
  still.aimHead(robot, 1.0, 1.0, {}, kDt);
  EXPECT_EQ(still.pan(), 0.0);
}

TEST(AgentCamera, AScanningHeadSweepsAroundTheDirectionOfTravel) {
  RobotProfile agent = idealAgent();
  agent.camera.scan = 0.6;  // at 2 rad/s: from side to side in 0.6 s
  AgentCamera camera(room(), agent, agentPerceptionConfig(agent), 1);
  const Pose2 robot{5.0, 5.0, 0.0};
  double lo = 0.0, hi = 0.0;
  int turns = 0;
  double previous = 0.0, direction = 0.0;
  for (int k = 0; k < 90; ++k) {  // 3 s driving straight on
    camera.aimHead(robot, 1.0, 0.0, {}, kDt);
    const double d = camera.pan() - previous;
    if (k > 0 && d * direction < 0.0) ++turns;
    if (d != 0.0) direction = d;
    previous = camera.pan();
    if (k >= 15) {  // after the first sweep out
      lo = std::min(lo, camera.pan());
      hi = std::max(hi, camera.pan());
    }
    EXPECT_LE(std::abs(camera.pan()), 0.6 + 1e-9);
  }
  EXPECT_NEAR(lo, -0.6, 1e-9);
  EXPECT_NEAR(hi, 0.6, 1e-9);
  // 0.3 s out, then a turn every 0.6 s: 5 turns in 3 s.
  EXPECT_EQ(turns, 5);
}

TEST(AgentCamera, TheRobotDrivesFastOnlyWhereItsCameraHasLookedLately) {
  const PolygonMap map = room();
  const RobotProfile agent = idealAgent();
  AgentCamera camera(map, agent, agentPerceptionConfig(agent), 1);
  const Pose2 robot{5.0, 5.0, 0.0};
  const std::vector<hal::PrismView> none;
  // Nothing seen yet: every direction is blind.
  EXPECT_EQ(camera.limitSpeed(0.0, robot, 2.0, 0.0), AgentCamera::kBlindSpeedMps);
  EXPECT_EQ(camera.limitSpeed(0.0, robot, 0.2, 0.0), 0.2);  // slow is always allowed
  ASSERT_TRUE(camera.perceive(0.0, robot, none));  // looking ahead
  EXPECT_EQ(camera.limitSpeed(0.1, robot, 2.0, 0.0), 2.0);
  EXPECT_EQ(camera.limitSpeed(0.1, robot, 2.0, 0.5), 2.0);  // a gentle left arc: ahead
  EXPECT_EQ(camera.limitSpeed(0.1, robot, -1.0, 0.0), -AgentCamera::kBlindSpeedMps);  // backwards: unseen
  EXPECT_EQ(camera.limitSpeed(0.1, robot, 2.0, 3.0), AgentCamera::kBlindSpeedMps);    // a sharp left turn
  // What it saw ages: 0.6 s later the way ahead counts as unseen again.
  EXPECT_EQ(camera.limitSpeed(0.6, robot, 2.0, 0.0), AgentCamera::kBlindSpeedMps);
  // The head turns to where the controller wants to go (backwards), a frame is taken: allowed.
  for (int k = 1; k <= 60; ++k) camera.aimHead(robot, -1.0, 0.0, {}, kDt);  // 1.4 s at 2 rad/s
  EXPECT_NEAR(std::abs(camera.pan()), 2.8, 1e-9);
  ASSERT_TRUE(camera.perceive(2.0, robot, none));
  EXPECT_EQ(camera.limitSpeed(2.0, robot, -1.0, 0.0), -1.0);
}

TEST(AgentCamera, AProfileWithoutACameraIsRefusedNamingIt) {
  RobotProfile agent = paperAgentProfile();
  agent.has_camera = false;
  try {
    AgentCamera camera(room(), agent, DepthObstaclesConfig{}, 1);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'paper-agent' has no camera"), std::string::npos) << e.what();
  }
}

// The mean velocity error of the track of an agent that drives the manoeuvre (a, w), from
// start at 2 m/s, before a robot standing at (1, 5) facing it, camera and scan: over the
// frames from the manoeuvre's start (after 0.5 s of straight driving) to 0.5 s after its end.
double manoeuvreError(const DepthObstaclesConfig& perception, Pose2 body, double a, double w) {
  const PolygonMap map = room();
  const RobotProfile agent = paperAgentProfile();
  AgentCamera camera(map, agent, perception, 3, true);
  const Pose2 robot{1.0, 5.0, 0.0};
  double v = 2.0, sum = 0.0;
  int frames = 0;
  for (int k = 0; k <= 60; ++k) {  // 0.5 s straight, 1 s of manoeuvre, 0.5 s after
    const double t = k * kDt;
    const bool manoeuvre = t >= 0.5 && t < 1.5;
    const Polygon shape = footprintAt(agent.footprint, body);
    const std::vector<hal::PrismView> others{{PolygonView(shape), Vec2(0.0, 0.0), agent.height_m}};
    camera.aimHead(robot, 0.0, 0.0, {}, kDt);
    EXPECT_TRUE(camera.perceive(t, robot, others));
    const hal::ObstacleFrame& f = camera.frame();
    const Vec2 truth = v * Vec2(std::cos(body.theta), std::sin(body.theta));
    double error = std::numeric_limits<double>::infinity();  // of the obstacle nearest the body
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < f.count; ++i) {
      const auto& o = f.obstacles[i];
      Vec2 c = Vec2::Zero();
      for (std::size_t j = 0; j < o.n; ++j) c += o.vertices[j];
      c /= static_cast<double>(o.n);
      const double d = (c - body.position()).norm();
      if (d < nearest) {
        nearest = d;
        error = (o.velocity - truth).norm();
      }
    }
    EXPECT_LT(nearest, 0.6) << "at " << t << " s the agent is not seen";
    if (t >= 0.5) {
      sum += error;
      ++frames;
    }
    // The body moves on: a unicycle with the manoeuvre's acceleration and turn rate.
    const double wk = manoeuvre ? w : 0.0;
    body = Pose2{body.x + v * std::cos(body.theta) * kDt, body.y + v * std::sin(body.theta) * kDt,
                 body.theta + wk * kDt};
    if (manoeuvre) v = std::max(0.0, v + a * kDt);
  }
  return sum / frames;
}

// The agents' filter is told of twice their a_max: an agent braking at a_max, or turning at
// speed, is followed within about a tenth of its speed on average (2 m/s). Told of a_max
// alone, it lags by more.
TEST(AgentCamera, TheTrackOfABrakingOrTurningAgentFollowsItsManoeuvre) {
  const RobotProfile agent = paperAgentProfile();
  const DepthObstaclesConfig shipped = agentPerceptionConfig(agent, true);
  EXPECT_EQ(shipped.acceleration_mps2, 2.0 * agent.limits.a_max);
  DepthObstaclesConfig lagging = shipped;
  lagging.acceleration_mps2 = agent.limits.a_max;
  // Towards the robot from 4.5 m, braking at a_max after 1 m to a stop 2.5 m from it.
  const Pose2 towards{5.5, 5.2, kPi};
  const double braking = manoeuvreError(shipped, towards, -agent.limits.a_max, 0.0);
  const double braking_lagged = manoeuvreError(lagging, towards, -agent.limits.a_max, 0.0);
  // Across the view 4 m ahead, turning left at 1.5 rad/s (3 m/s^2 across) at a constant 2 m/s.
  const Pose2 across{5.0, 3.2, kPi / 2.0};
  const double turning = manoeuvreError(shipped, across, 0.0, 1.5);
  const double turning_lagged = manoeuvreError(lagging, across, 0.0, 1.5);
  std::printf("mean velocity error, braking %.2f (a_max: %.2f), turning %.2f (a_max: %.2f) m/s\n", braking,
              braking_lagged, turning, turning_lagged);
  EXPECT_LT(braking, 0.25);
  EXPECT_LT(turning, 0.38);
  EXPECT_GT(braking_lagged, braking + 0.05);
  EXPECT_GT(turning_lagged, turning + 0.05);
}

}  // namespace
}  // namespace staa
