#include "robot/unicycle.hpp"

#include <algorithm>
#include <cmath>

namespace staa {

namespace {
// sin(x)/x, with its Taylor series near 0 where the quotient loses precision.
double sinc(double x) {
  if (std::abs(x) < 1e-4) return 1.0 - x * x / 6.0;
  return std::sin(x) / x;
}
}  // namespace

Pose2 integrateArc(const Pose2& from, double v, double w, double t) {
  // The chord of an arc of angle phi and length s is s*sinc(phi/2), along the mean heading.
  const double half = 0.5 * w * t;
  const double chord = v * t * sinc(half);
  const double heading = from.theta + half;
  return {from.x + chord * std::cos(heading), from.y + chord * std::sin(heading), wrapAngle(from.theta + w * t)};
}

ActionSet::ActionSet(const MotionLimits& limits, std::size_t notches) {
  notches_ = std::clamp<std::size_t>(notches, 2, kMaxNotches);
  const double n1 = static_cast<double>(notches_ - 1);
  for (std::size_t i = 0; i < notches_; ++i) {
    for (std::size_t j = 0; j < notches_; ++j) {
      // Eq. (1) with a_min = -a_max and b_min = -b_max.
      actions_[count_++] = Action{-limits.a_max + static_cast<double>(i) / n1 * 2.0 * limits.a_max,
                                  -limits.b_max + static_cast<double>(j) / n1 * 2.0 * limits.b_max};
    }
  }
}

ArcVelocities arcVelocities(const UnicycleState& s, const Action& action, double dt, const MotionLimits& limits) {
  ArcVelocities out;
  out.v_end = std::clamp(s.v + dt * action.a, limits.v_min, limits.v_max);
  out.w_end = std::clamp(s.w + dt * action.b, -limits.w_max, limits.w_max);
  // The mean velocity over the interval when the acceleration stops at the limit: the average
  // of start and end is exact for an unclamped ramp and close otherwise.
  out.v_mid = 0.5 * (s.v + out.v_end);
  out.w_mid = 0.5 * (s.w + out.w_end);
  return out;
}

Pose2 poseAlongArc(const UnicycleState& s, double v_mid, double w_mid, double t) {
  // Eq. (2): x + r (sin(theta + t w) - sin theta), y - r (cos(theta + t w) - cos theta), with
  // r = v / w; its limit for w -> 0 is the straight line (evaluated stably below).
  const double dth = w_mid * t;
  double fx, fy;  // displacement divided by v t, in the heading frame
  if (std::abs(dth) < 1e-6) {
    fx = 1.0 - dth * dth / 6.0;
    fy = 0.5 * dth;
  } else {
    fx = std::sin(dth) / dth;
    fy = (1.0 - std::cos(dth)) / dth;
  }
  const double d = v_mid * t;
  const double c = std::cos(s.theta), sn = std::sin(s.theta);
  return Pose2{s.x + d * (c * fx - sn * fy), s.y + d * (sn * fx + c * fy), s.theta + dth};
}

ArcMotion makeArcMotion(const UnicycleState& s, double c0, double s0, double v_mid, double w_mid, double dt, double cd,
                        double sd) {
  ArcMotion m{};
  m.x0 = s.x;
  m.y0 = s.y;
  m.c0 = c0;
  m.s0 = s0;
  m.v_mid = v_mid;
  m.w_mid = w_mid;
  m.dt = dt;
  const double dth = w_mid * dt;
  m.c1 = c0 * cd - s0 * sd;
  m.s1 = s0 * cd + c0 * sd;
  m.theta1 = s.theta + dth;
  const double d = v_mid * dt;
  if (std::abs(dth) < 1e-6) {
    const double fx = 1.0 - dth * dth / 6.0, fy = 0.5 * dth;
    m.x1 = s.x + d * (c0 * fx - s0 * fy);
    m.y1 = s.y + d * (s0 * fx + c0 * fy);
  } else {
    // r (sin(theta + dth) - sin theta), -r (cos(theta + dth) - cos theta), r = v / w.
    const double r = v_mid / w_mid;
    m.x1 = s.x + r * (m.s1 - s0);
    m.y1 = s.y - r * (m.c1 - c0);
  }
  return m;
}

UnicycleState predictArc(const UnicycleState& s, const Action& action, double dt, const MotionLimits& limits) {
  const ArcVelocities av = arcVelocities(s, action, dt, limits);
  const Pose2 p = poseAlongArc(s, av.v_mid, av.w_mid, dt);
  return UnicycleState{p.x, p.y, p.theta, av.v_end, av.w_end};
}

}  // namespace staa
