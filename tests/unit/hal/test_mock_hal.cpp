// The scripted base and obstacle sensor: a perfect unicycle under the profile's limits,
// stalled odometry, faults, the command log, and pushed / stalled / empty obstacle frames.
#include "hal/mock/mock_hal.hpp"

#include "rt/alloc_count.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

namespace staa::hal {
namespace {

constexpr rt::Nanos kTenth = 100 * rt::kNanosPerMilli;

VelocityCommand command(double v, double w, bool brake = false) {
  VelocityCommand c;
  c.v = v;
  c.w = w;
  c.brake = brake;
  return c;
}

TEST(MockBase, VelocityRampsByAmaxDtAndThePoseFollowsTheUnicycle) {
  const RobotProfile robot = paperAgentProfile();  // a_max 2 m/s^2, b_max 6 rad/s^2
  MockBase base(robot, {1.0, 2.0, 0.0});
  base.write(0, command(1.0, 0.0));
  base.read(0);  // sets the time only
  EXPECT_EQ(base.odometry().v, 0.0);
  double x = 1.0;
  for (int k = 1; k <= 8; ++k) {
    base.read(k * kTenth);
    const double v = std::min(1.0, 0.2 * k);  // + a_max * 0.1 s per read
    x += v * 0.1;
    EXPECT_NEAR(base.odometry().v, v, 1e-12) << "read " << k;
    EXPECT_NEAR(base.odometry().pose.x, x, 1e-12);
    EXPECT_EQ(base.odometry().pose.y, 2.0);
    EXPECT_EQ(base.odometry().stamp, k * kTenth);
  }
  // Turning: w ramps by b_max * dt = 0.6 rad/s per read; the pose follows the arc.
  base.write(0, command(1.0, 1.0));
  base.read(9 * kTenth);
  EXPECT_NEAR(base.odometry().w, 0.6, 1e-12);
  const double half = 0.5 * 0.6 * 0.1;
  const double chord = 1.0 * 0.1 * std::sin(half) / half;
  EXPECT_NEAR(base.odometry().pose.x, x + chord * std::cos(half), 1e-12);
  EXPECT_NEAR(base.odometry().pose.y, 2.0 + chord * std::sin(half), 1e-12);
  EXPECT_NEAR(base.odometry().pose.theta, 0.06, 1e-12);
}

TEST(MockBase, CommandsAreClampedToTheLimits) {
  const RobotProfile robot = paperAgentProfile();  // v in [-1, 2], |w| <= 3
  MockBase base(robot);
  base.read(0);
  base.write(0, command(5.0, -9.0));
  for (int k = 1; k <= 20; ++k) base.read(k * kTenth);
  EXPECT_DOUBLE_EQ(base.odometry().v, 2.0);
  EXPECT_DOUBLE_EQ(base.odometry().w, -3.0);
  base.write(0, command(-5.0, 0.0));
  for (int k = 21; k <= 40; ++k) base.read(k * kTenth);
  EXPECT_DOUBLE_EQ(base.odometry().v, -1.0);
  EXPECT_DOUBLE_EQ(base.odometry().w, 0.0);
  // A brake: both to zero at the full deceleration (1 m/s at 2 m/s^2 in 0.5 s; within one
  // more read, as 5 x 0.2 may round to a hair under 1).
  base.write(0, command(1.0, 1.0, true));
  for (int k = 41; k <= 44; ++k) base.read(k * kTenth);
  EXPECT_NEAR(base.odometry().v, -0.2, 1e-12);
  for (int k = 45; k <= 46; ++k) base.read(k * kTenth);
  EXPECT_EQ(base.odometry().v, 0.0);
  EXPECT_EQ(base.odometry().w, 0.0);
}

TEST(MockBase, FrozenOdometryKeepsItsStampAndLastReport) {
  MockBase base(paperAgentProfile());
  EXPECT_LT(base.odometry().stamp, 0);  // never measured
  base.write(0, command(0.5, 0.0));
  for (int k = 0; k <= 5; ++k) base.read(k * kTenth);
  const Odometry before = base.odometry();
  EXPECT_EQ(before.stamp, 5 * kTenth);
  base.freezeOdometry(true);
  for (int k = 6; k <= 12; ++k) base.read(k * kTenth);
  EXPECT_EQ(base.odometry().stamp, before.stamp);
  EXPECT_EQ(base.odometry().pose.x, before.pose.x);
  EXPECT_EQ(base.status().stamp, 12 * kTenth);
  base.freezeOdometry(false);
  EXPECT_EQ(base.odometry().stamp, 12 * kTenth);
  EXPECT_NEAR(base.odometry().pose.x, before.pose.x + 0.5 * 0.7, 1e-12);  // it kept moving
}

TEST(MockBase, HeldOdometryIsReportedAsSetWithFreshStamps) {
  MockBase base(paperAgentProfile());
  base.setIntegrate(false);
  Odometry o;
  o.pose = {3.0, -1.0, 0.5};
  o.v = 0.7;
  o.w = 0.1;
  base.setOdometry(o);
  base.write(0, command(2.0, 0.0));
  base.read(kTenth);
  base.read(2 * kTenth);
  EXPECT_EQ(base.odometry().pose.x, 3.0);
  EXPECT_EQ(base.odometry().v, 0.7);
  EXPECT_EQ(base.odometry().stamp, 2 * kTenth);
  EXPECT_TRUE(base.setPose({-4.0, 5.0, 1.0}));
  EXPECT_EQ(base.odometry().pose.x, -4.0);
  EXPECT_EQ(base.odometry().v, 0.7);  // re-anchored, not stopped
}

TEST(MockBase, FaultsAreReportedAndStopTheDrives) {
  MockBase base(paperAgentProfile());
  EXPECT_TRUE(base.status().enabled);
  EXPECT_EQ(base.status().fault, BaseFault::kNone);
  base.write(0, command(1.0, 0.0));
  for (int k = 0; k <= 5; ++k) base.read(k * kTenth);
  ASSERT_DOUBLE_EQ(base.odometry().v, 1.0);
  base.setFault(BaseFault::kDriverFault, 0x2310);
  base.read(6 * kTenth);
  BaseStatus s = base.status();
  EXPECT_EQ(s.fault, BaseFault::kDriverFault);
  EXPECT_EQ(s.fault_code, 0x2310u);
  EXPECT_EQ(s.stamp, 6 * kTenth);
  EXPECT_STREQ(toString(s.fault), "driver fault");
  EXPECT_NEAR(base.odometry().v, 0.8, 1e-12);  // braking at a_max despite the command
  base.setFault(BaseFault::kNone, 99);
  EXPECT_EQ(base.status().fault_code, 0u);
  base.setEnabled(false);
  for (int k = 7; k <= 12; ++k) base.read(k * kTenth);
  EXPECT_FALSE(base.status().enabled);
  EXPECT_EQ(base.odometry().v, 0.0);
  base.setEnabled(true);
  base.read(13 * kTenth);
  EXPECT_NEAR(base.odometry().v, 0.2, 1e-12);
}

TEST(BaseFault, EveryFaultHasItsOwnName) {
  std::set<std::string> names;
  for (BaseFault f : {BaseFault::kNone, BaseFault::kEmergencyStop, BaseFault::kHeartbeatLost, BaseFault::kBusOff,
                      BaseFault::kWriteFailed, BaseFault::kDriverFault}) {
    names.insert(toString(f));
  }
  EXPECT_EQ(names.size(), 6u);
  EXPECT_STREQ(toString(BaseFault::kBusOff), "bus off");
  EXPECT_STREQ(toString(static_cast<BaseFault>(200)), "unknown");
}

TEST(MockBase, CommandsLogsEveryWriteInOrderUpToItsCapacity) {
  MockBase base(paperAgentProfile(), {}, 3);
  base.write(1, command(0.1, 0.0));
  base.write(2, command(0.2, 0.5));
  base.write(3, command(0.0, 0.0, true));
  base.write(4, command(0.4, 0.0));  // beyond max_commands: not logged, still the latest
  const std::vector<VelocityCommand> log = base.commands();
  ASSERT_EQ(log.size(), 3u);
  EXPECT_EQ(log[0].v, 0.1);
  EXPECT_EQ(log[1].w, 0.5);
  EXPECT_TRUE(log[2].brake);
  EXPECT_EQ(base.lastCommand().v, 0.4);
}

TEST(MockBase, ReadAndWriteAllocateNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_mock_hal must link staa_rt_alloc_hook";
  MockBase base(paperAgentProfile(), {}, 2000);
  base.read(0);
  rt::AllocationScope scope;
  for (int k = 1; k <= 1000; ++k) {
    base.write(k, command(0.5, 0.2));
    base.read(k * rt::kNanosPerMilli);
    (void)base.odometry();
    (void)base.status();
  }
  EXPECT_EQ(scope.count(), 0u);
}

TEST(MockObstacles, EmptyFramesEveryCallWithIncreasingSequence) {
  MockObstacles sensor;
  ObstacleFrame f;
  f.count = 5;  // stale content of the caller's buffer
  ASSERT_TRUE(sensor.read(100, f));
  EXPECT_EQ(f.count, 0u);
  EXPECT_EQ(f.stamp, 100);
  EXPECT_EQ(f.sequence, 1u);
  ASSERT_TRUE(sensor.read(200, f));
  EXPECT_EQ(f.sequence, 2u);
  EXPECT_EQ(f.stamp, 200);
}

TEST(MockObstacles, PushedFrameComesOnceStampedWhenUnstamped) {
  MockObstacles sensor;
  ObstacleFrame pushed;
  pushed.count = 1;
  pushed.obstacles[0].n = 3;
  pushed.obstacles[0].vertices[0] = {1.0, 1.0};
  pushed.obstacles[0].vertices[1] = {2.0, 1.0};
  pushed.obstacles[0].vertices[2] = {1.5, 2.0};
  pushed.obstacles[0].velocity = {0.4, -0.1};
  sensor.push(pushed);
  ObstacleFrame f;
  ASSERT_TRUE(sensor.read(500, f));
  EXPECT_EQ(f.count, 1u);
  EXPECT_EQ(f.obstacles[0].vertices[2], Vec2(1.5, 2.0));
  EXPECT_EQ(f.obstacles[0].velocity, Vec2(0.4, -0.1));
  EXPECT_EQ(f.stamp, 500);
  EXPECT_EQ(f.sequence, 1u);
  ASSERT_TRUE(sensor.read(600, f));  // back to seeing nothing
  EXPECT_EQ(f.count, 0u);
  // A frame with its own stamp and sequence keeps them (an old frame, a repeated number).
  pushed.stamp = 42;
  pushed.sequence = 9;
  sensor.push(pushed);
  ASSERT_TRUE(sensor.read(700, f));
  EXPECT_EQ(f.stamp, 42);
  EXPECT_EQ(f.sequence, 9u);
  ASSERT_TRUE(sensor.read(800, f));
  EXPECT_EQ(f.sequence, 10u);
}

TEST(MockObstacles, StalledSensorGivesNothingAndKeepsThePushedFrame) {
  MockObstacles sensor;
  ObstacleFrame pushed;
  pushed.count = 2;
  sensor.stall(true);
  sensor.push(pushed);
  ObstacleFrame f;
  EXPECT_FALSE(sensor.read(100, f));
  EXPECT_FALSE(sensor.read(200, f));
  sensor.stall(false);
  ASSERT_TRUE(sensor.read(300, f));
  EXPECT_EQ(f.count, 2u);
  EXPECT_EQ(f.stamp, 300);
}

}  // namespace
}  // namespace staa::hal
