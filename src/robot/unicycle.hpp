#pragma once
// The unicycle state, the action set of accelerations and the arc prediction of the paper's
// Sec. III-E-1 (Eq. 1 and 2).

#include "robot/robot_profile.hpp"
#include "geometry/types.hpp"

#include <array>
#include <cmath>
#include <cstddef>

namespace staa {

// s = (x, y, theta, v, w).
struct UnicycleState {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
  double v = 0.0;
  double w = 0.0;

  Vec2 position() const { return {x, y}; }
  Pose2 pose() const { return {x, y, theta}; }
};

// An action: linear and angular acceleration (a, b), held for the prediction time.
struct Action {
  double a = 0.0;
  double b = 0.0;
};

// Eq. (1): n x n accelerations spanning [-a_max, a_max] x [-b_max, b_max]. n = 7 gives the
// paper's 49 actions; the middle one (i = j = (n-1)/2) is (0, 0) for odd n.
class ActionSet {
 public:
  static constexpr std::size_t kMaxNotches = 15;

  ActionSet() = default;
  ActionSet(const MotionLimits& limits, std::size_t notches);

  std::size_t size() const { return count_; }
  const Action& operator[](std::size_t i) const { return actions_[i]; }
  std::size_t notches() const { return notches_; }

 private:
  std::array<Action, kMaxNotches * kMaxNotches> actions_{};
  std::size_t count_ = 0;
  std::size_t notches_ = 0;
};

// Eq. (2): the state after applying (a, b) for dt, along an arc whose radius comes from the
// velocities in the middle of the interval; the velocities are clamped to the limits (the
// position uses the clamped mid-interval velocities too, so a clamped action does not
// predict motion the robot cannot make).
UnicycleState predictArc(const UnicycleState& s, const Action& action, double dt, const MotionLimits& limits);

// The pose at time t in [0, dt] along the same motion (for checking the swept motion).
Pose2 poseAlongArc(const UnicycleState& s, double v_mid, double w_mid, double t);

// The velocities a state reaches from s under (a, b) after dt, clamped, and the mid-interval
// velocities that drive the arc.
struct ArcVelocities {
  double v_end, w_end, v_mid, w_mid;
};
ArcVelocities arcVelocities(const UnicycleState& s, const Action& action, double dt, const MotionLimits& limits);

// The pose after driving for `t` seconds at constant (v, w) from `from`: exactly along the
// arc (a straight line when w = 0), numerically stable as w -> 0.
Pose2 integrateArc(const Pose2& from, double v, double w, double t);

// One predicted motion with the trigonometry already done: the start (with its heading's
// cosine and sine), the mid-interval velocities, and the end pose (likewise). The planner
// builds these from per-expansion tables (7 rotations per node, not 49), and the collision
// checker samples along them without calling sin or cos again.
struct ArcMotion {
  double x0, y0, c0, s0;  // start position and heading
  double v_mid, w_mid, dt;
  double x1, y1, c1, s1;  // end position and heading
  double theta1;          // end heading, unwrapped
};

// cos and sin of a small angle by their series (exact to ~1e-10 below 0.3 rad), else libm.
inline void sinCos(double a, double& c, double& s) {
  if (a > -0.3 && a < 0.3) {
    const double a2 = a * a;
    c = 1.0 - a2 / 2.0 * (1.0 - a2 / 12.0 * (1.0 - a2 / 30.0 * (1.0 - a2 / 56.0)));
    s = a * (1.0 - a2 / 6.0 * (1.0 - a2 / 20.0 * (1.0 - a2 / 42.0 * (1.0 - a2 / 72.0))));
    return;
  }
  c = std::cos(a);
  s = std::sin(a);
}

// The motion from `s` with the given mid-interval velocities, whose total rotation
// w_mid * dt has cosine cd and sine sd: Eq. (2) written with the rotated heading.
ArcMotion makeArcMotion(const UnicycleState& s, double c0, double s0, double v_mid, double w_mid, double dt, double cd,
                        double sd);

}  // namespace staa
