#include "robot/unicycle.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

const MotionLimits kPaper{2.0, -1.0, 3.0, 2.0, 6.0};

TEST(ActionSet, SpansTheAccelerationLimitsInSevenByseven) {
  const ActionSet set(kPaper, 7);
  ASSERT_EQ(set.size(), 49u);
  EXPECT_DOUBLE_EQ(set[0].a, -2.0);
  EXPECT_DOUBLE_EQ(set[0].b, -6.0);
  EXPECT_DOUBLE_EQ(set[48].a, 2.0);
  EXPECT_DOUBLE_EQ(set[48].b, 6.0);
  EXPECT_DOUBLE_EQ(set[24].a, 0.0);  // the middle action keeps the velocities
  EXPECT_DOUBLE_EQ(set[24].b, 0.0);
  EXPECT_NEAR(set[1].b - set[0].b, 2.0, 1e-12);  // (6 - -6) / 6
}

TEST(PredictArc, StraightAheadWithConstantVelocity) {
  const UnicycleState s{1, 2, 0.5, 1.0, 0.0};
  const UnicycleState n = predictArc(s, Action{0, 0}, 0.3, kPaper);
  EXPECT_NEAR(n.x, 1 + 0.3 * std::cos(0.5), 1e-12);
  EXPECT_NEAR(n.y, 2 + 0.3 * std::sin(0.5), 1e-12);
  EXPECT_DOUBLE_EQ(n.theta, 0.5);
  EXPECT_DOUBLE_EQ(n.v, 1.0);
}

TEST(PredictArc, FollowsTheArcOfEquationTwo) {
  // v = 1, w = 1 for 0.3 s: an arc of radius 1 about (0, 1).
  const UnicycleState s{0, 0, 0, 1.0, 1.0};
  const UnicycleState n = predictArc(s, Action{0, 0}, 0.3, kPaper);
  EXPECT_NEAR(n.x, std::sin(0.3), 1e-12);
  EXPECT_NEAR(n.y, 1.0 - std::cos(0.3), 1e-12);
  EXPECT_NEAR(n.theta, 0.3, 1e-12);
  // With acceleration, the radius comes from the mid-interval velocities (Eq. 2).
  const UnicycleState m = predictArc(s, Action{2.0, 0.0}, 0.3, kPaper);
  EXPECT_NEAR(m.v, 1.6, 1e-12);
  const double r = 1.3 / 1.0;
  EXPECT_NEAR(m.x, r * std::sin(0.3), 1e-12);
  EXPECT_NEAR(m.y, r * (1.0 - std::cos(0.3)), 1e-12);
}

TEST(PredictArc, ClampsVelocitiesToTheLimits) {
  const UnicycleState s{0, 0, 0, 1.9, 2.9};
  const UnicycleState n = predictArc(s, Action{2.0, 6.0}, 0.3, kPaper);
  EXPECT_DOUBLE_EQ(n.v, 2.0);
  EXPECT_DOUBLE_EQ(n.w, 3.0);
  const UnicycleState b = predictArc(UnicycleState{0, 0, 0, -0.9, 0}, Action{-2.0, 0}, 0.3, kPaper);
  EXPECT_DOUBLE_EQ(b.v, -1.0);
  EXPECT_LT(b.x, 0.0);
}

TEST(PoseAlongArc, IsContinuousAndMeetsTheEndPose) {
  const UnicycleState s{0, 0, 1.0, 1.5, -2.0};
  const ArcVelocities v = arcVelocities(s, Action{-1, 3}, 0.3, kPaper);
  const UnicycleState end = predictArc(s, Action{-1, 3}, 0.3, kPaper);
  const Pose2 p = poseAlongArc(s, v.v_mid, v.w_mid, 0.3);
  EXPECT_NEAR(p.x, end.x, 1e-12);
  EXPECT_NEAR(p.y, end.y, 1e-12);
  Pose2 prev = poseAlongArc(s, v.v_mid, v.w_mid, 0.0);
  EXPECT_NEAR(prev.x, 0.0, 1e-15);
  for (int k = 1; k <= 30; ++k) {
    const Pose2 q = poseAlongArc(s, v.v_mid, v.w_mid, 0.01 * k);
    EXPECT_NEAR((q.position() - prev.position()).norm(), std::abs(v.v_mid) * 0.01, 1e-6);  // chord vs arc
    prev = q;
  }
}

}  // namespace
}  // namespace staa
