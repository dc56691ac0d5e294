// hal: ros without ROS: the base backend fed as a transport feeds it (odometry and
// localization samples), read and written as the base thread does.
#include "hal/ros/ros_base.hpp"

#include "rt/alloc_count.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace staa::hal {
namespace {

constexpr std::int64_t kMs = rt::kNanosPerMilli;

// An odometry sample stamped at `t_ms` (ROS time), arrived 2 ms later on the monotonic clock
// offset by 1 s (the two clocks have different origins).
OdometrySample odom(std::int64_t t_ms, double x, double y, double yaw, double v = 0.0, double w = 0.0) {
  OdometrySample s;
  s.stamp_ns = t_ms * kMs;
  s.age_ns = 2 * kMs;
  s.arrival_ns = rt::kNanosPerSecond + s.stamp_ns + s.age_ns;
  s.x = x;
  s.y = y;
  s.yaw = yaw;
  s.v = v;
  s.w = w;
  return s;
}

PoseSample fix(std::int64_t t_ms, double x, double y, double yaw) {
  PoseSample p;
  p.stamp_ns = t_ms * kMs;
  p.arrival_ns = rt::kNanosPerSecond + p.stamp_ns;
  p.x = x;
  p.y = y;
  p.yaw = yaw;
  return p;
}

VelocityCommand command(rt::Nanos stamp, double v, double w, bool brake = false) {
  VelocityCommand c;
  c.stamp = stamp;
  c.v = v;
  c.w = w;
  c.brake = brake;
  c.odometry_stamp = stamp - 5 * kMs;
  return c;
}

TEST(RosBase, OdometryIsTheMapPoseWithTheMeasurementTimeOnTheMonotonicClock) {
  RosBase base;
  EXPECT_EQ(base.odometry().stamp, -1);
  base.offerOdometry(odom(1000, 1.5, -2.0, 0.25, 0.2, -0.1));
  base.read(0);
  const Odometry o = base.odometry();
  EXPECT_EQ(o.pose.x, 1.5);
  EXPECT_EQ(o.pose.y, -2.0);
  EXPECT_EQ(o.pose.theta, 0.25);
  EXPECT_EQ(o.v, 0.2);
  EXPECT_EQ(o.w, -0.1);
  // arrival - age: when it was measured, not when it came.
  EXPECT_EQ(o.stamp, rt::kNanosPerSecond + 1000 * kMs);
  EXPECT_EQ(base.status().fault, BaseFault::kNone);
}

TEST(RosBase, AnAgeThatCannotBeTrustedLeavesTheArrivalAsTheStamp) {
  RosBase base;
  OdometrySample s = odom(1000, 0, 0, 0);
  s.age_ns = -3 * kMs;  // the publisher's clock is ahead of ours
  base.offerOdometry(s);
  base.read(0);
  EXPECT_EQ(base.odometry().stamp, s.arrival_ns);
}

TEST(RosBase, ANonFiniteValueIsDroppedCountedAndAFaultUntilTheNextGoodSample) {
  RosBase base;
  base.offerOdometry(odom(1000, 1.0, 2.0, 0.0));
  base.read(0);
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    base.offerOdometry(odom(1020, bad, 2.0, 0.0));
    base.read(0);
    EXPECT_EQ(base.status().fault, BaseFault::kOdometryInvalid);
    EXPECT_EQ(base.odometry().pose.x, 1.0) << "the last good pose is kept";
    base.offerOdometry(odom(1020, 1.0, 2.0, 0.0, bad));  // a NaN velocity too
    base.read(0);
    EXPECT_EQ(base.status().fault, BaseFault::kOdometryInvalid);
  }
  EXPECT_EQ(base.status().bad_frames, 4u);
  EXPECT_EQ(base.odometry().stamp, rt::kNanosPerSecond + 1000 * kMs) << "a dropped sample does not freshen the odometry";
  base.offerOdometry(odom(1040, 1.1, 2.0, 0.0));
  base.read(0);
  EXPECT_EQ(base.odometry().pose.x, 1.1);
  base.offerOdometry(odom(1060, 1.2, 2.0, 0.0));
  base.read(0);
  EXPECT_EQ(base.status().fault, BaseFault::kNone) << "good odometry after the bad one clears it";
}

TEST(RosBase, EveryBadMessageCountsAndFaultsEvenWhenAGoodOneFollowsBeforeTheRead) {
  RosBase base;
  base.offerOdometry(odom(1000, 1.0, 0.0, 0.0));
  base.read(0);
  // Between two base-thread reads: a NaN, then good odometry from the base.
  base.offerOdometry(odom(1010, std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0));
  base.offerOdometry(odom(1020, 1.1, 0.0, 0.0));
  base.read(0);
  EXPECT_EQ(base.status().bad_frames, 1u);
  EXPECT_EQ(base.status().fault, BaseFault::kOdometryInvalid) << "the bad message is not hidden by the good one";
  EXPECT_EQ(base.odometry().pose.x, 1.1);
  base.read(0);
  EXPECT_EQ(base.status().fault, BaseFault::kOdometryInvalid) << "no newer odometry yet";
  base.offerOdometry(odom(1040, 1.2, 0.0, 0.0));
  base.read(0);
  EXPECT_EQ(base.status().fault, BaseFault::kNone);
}

TEST(RosBase, AStampGoingBackIsAFaultAndARepeatedStampIsOnlyDropped) {
  RosBase base;
  base.offerOdometry(odom(1000, 1.0, 0.0, 0.0));
  base.read(0);
  base.offerOdometry(odom(1000, 5.0, 0.0, 0.0));
  base.read(0);
  EXPECT_EQ(base.status().fault, BaseFault::kNone);
  EXPECT_EQ(base.status().bad_frames, 1u);
  EXPECT_EQ(base.odometry().pose.x, 1.0);
  base.offerOdometry(odom(980, 5.0, 0.0, 0.0));
  base.read(0);
  EXPECT_EQ(base.status().fault, BaseFault::kOdometryStampBack);
  EXPECT_EQ(base.odometry().pose.x, 1.0);
  base.offerOdometry(odom(1020, 1.2, 0.0, 0.0));
  base.read(0);
  base.offerOdometry(odom(1040, 1.3, 0.0, 0.0));
  base.read(0);
  EXPECT_EQ(base.status().fault, BaseFault::kNone);
  EXPECT_EQ(base.status().bad_frames, 2u);
}

TEST(RosBase, ALocalizationFixCorrectsTheOdometryAtTheFixStampAndReportsTheJump) {
  RosBase base;
  // Driving along x at 1 m/s in the odometry frame, 20 ms samples.
  for (int k = 0; k <= 10; ++k) {
    base.offerOdometry(odom(1000 + 20 * k, 0.02 * k, 0.0, 0.0));
    base.read(0);
  }
  // At t = 1.11 s (between samples 5 and 6: odometry x = 0.11) localization says the robot
  // was at (5.11, 3.0) facing +y: T_map_odom is a rotation by pi/2 and a shift.
  base.offerPose(fix(1110, 5.11, 3.0, M_PI / 2));
  base.read(0);
  const Odometry o = base.odometry();
  // Now (odometry x = 0.2): 0.09 m further along the map's +y.
  EXPECT_NEAR(o.pose.x, 5.11, 1e-12);
  EXPECT_NEAR(o.pose.y, 3.09, 1e-12);
  EXPECT_NEAR(o.pose.theta, M_PI / 2, 1e-12);
  const BaseStatus s = base.status();
  EXPECT_EQ(s.localization_fixes, 1u);
  EXPECT_NEAR(s.last_jump_m, std::hypot(5.11 - 0.2, 3.09), 1e-12);
  EXPECT_NEAR(s.last_jump_rad, M_PI / 2, 1e-12);
  // The next odometry moves on in the corrected frame.
  base.offerOdometry(odom(1220, 0.22, 0.0, 0.0));
  base.read(0);
  EXPECT_NEAR(base.odometry().pose.y, 3.11, 1e-12);
}

TEST(RosBase, AFixOlderThanTheOdometryKeptOrNotFiniteIsDropped) {
  RosBase base;
  for (std::size_t k = 0; k < RosBase::kHistory + 10; ++k) {
    base.offerOdometry(odom(1000 + 20 * static_cast<std::int64_t>(k), 0.0, 0.0, 0.0));
    base.read(0);
  }
  base.offerPose(fix(1000, 9.0, 9.0, 0.0));  // 2.7 s old: beyond the 128 samples kept
  base.read(0);
  base.offerPose(fix(3000, std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0));
  base.read(0);
  EXPECT_EQ(base.status().localization_fixes, 0u);
  EXPECT_EQ(base.status().localization_dropped, 2u);
  EXPECT_EQ(base.odometry().pose.x, 0.0);
}

TEST(RosBase, WithLocalizationOffFixesAreIgnored) {
  RosBaseOptions options;
  options.localization = false;
  RosBase base(options);
  base.offerOdometry(odom(1000, 1.0, 0.0, 0.0));
  base.read(0);
  base.offerPose(fix(1000, 9.0, 9.0, 0.0));
  base.read(0);
  EXPECT_EQ(base.odometry().pose.x, 1.0);
  EXPECT_EQ(base.status().localization_fixes, 0u);
}

TEST(RosBase, SetPoseReanchorsTheOdometryOnceThereIsSome) {
  RosBase base;
  EXPECT_FALSE(base.setPose({1.0, 1.0, 0.0}));
  base.offerOdometry(odom(1000, 3.0, 4.0, 0.5));
  base.read(0);
  ASSERT_TRUE(base.setPose({1.0, 1.0, 0.0}));
  EXPECT_NEAR(base.odometry().pose.x, 1.0, 1e-12);
  base.offerOdometry(odom(1020, 3.0 + std::cos(0.5), 4.0 + std::sin(0.5), 0.5));  // 1 m ahead
  base.read(0);
  EXPECT_NEAR(base.odometry().pose.x, 2.0, 1e-12);
  EXPECT_NEAR(base.odometry().pose.y, 1.0, 1e-12);
}

TEST(RosBase, ATwistGoesOutForEachNewCommandAndOncePerPeriodOtherwiseABrakeAsZero) {
  RosBaseOptions options;
  options.twist_period = 33 * kMs;
  RosBase base(options);
  TwistSample t;
  EXPECT_FALSE(base.takeTwist(t));
  base.write(0, command(0, 0.2, 0.1));
  ASSERT_TRUE(base.waitTwist(0));
  ASSERT_TRUE(base.takeTwist(t));
  EXPECT_EQ(t.v, 0.2);
  EXPECT_EQ(t.w, 0.1);
  EXPECT_EQ(t.command_stamp_ns, 0);
  EXPECT_EQ(t.odometry_stamp_ns, -5 * kMs);
  // The same command again within the period (the base thread runs at 100 Hz): nothing.
  base.write(10 * kMs, command(0, 0.2, 0.1));
  base.write(20 * kMs, command(0, 0.2, 0.1));
  EXPECT_FALSE(base.takeTwist(t));
  base.write(33 * kMs, command(0, 0.2, 0.1));  // a period since the last twist: again
  EXPECT_TRUE(base.takeTwist(t));
  base.write(40 * kMs, command(40 * kMs, 0.3, 0.0, true));  // a new command at once
  ASSERT_TRUE(base.takeTwist(t));
  EXPECT_EQ(t.v, 0.0) << "a brake is a zero twist";
  EXPECT_EQ(t.w, 0.0);
  EXPECT_TRUE(t.brake);
  base.twistSent(40 * kMs, 41 * kMs);
  EXPECT_EQ(base.lastCommandSent().command_stamp, 40 * kMs);
  EXPECT_EQ(base.lastCommandSent().sent_at, 41 * kMs);
}

TEST(RosBase, TheBaseThreadsCallsAllocateNothing) {
  ASSERT_TRUE(rt::hookInstalled());
  RosBase base;
  base.offerOdometry(odom(1000, 0.0, 0.0, 0.0));
  base.read(0);
  TwistSample t;
  const rt::AllocationScope scope;
  for (int k = 1; k <= 1000; ++k) {
    base.offerOdometry(odom(1000 + 20 * k, 0.02 * k, 0.0, 0.0));
    if (k % 10 == 0) base.offerPose(fix(1000 + 20 * k - 30, 0.02 * k, 0.1, 0.0));
    base.read(k * 10 * kMs);
    base.write(k * 10 * kMs, command(k * 10 * kMs, 0.2, 0.0));
    base.takeTwist(t);
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(base.status().localization_fixes, 100u);
}

}  // namespace
}  // namespace staa::hal
