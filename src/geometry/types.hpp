#pragma once
// Basic 2-D types: points and poses on Eigen, polygons as vertex lists.
// REP-103 frame: x forward/east, y left/north, angles counter-clockwise, metres and radians.

#include <Eigen/Core>

#include <cmath>
#include <span>
#include <vector>

namespace staa {

using Vec2 = Eigen::Vector2d;

// A polygon is its vertex list, closed implicitly (last vertex connects to the first).
// Either winding; may be non-convex. Owning form for load time; views for the hot path.
using Polygon = std::vector<Vec2>;
using PolygonView = std::span<const Vec2>;

constexpr double kPi = 3.14159265358979323846;

// z-component of the 3-D cross product: > 0 when b is counter-clockwise of a.
inline double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Orientation of the triangle (a, b, c): > 0 counter-clockwise, < 0 clockwise, 0 collinear.
inline double orient(const Vec2& a, const Vec2& b, const Vec2& c) { return cross(b - a, c - a); }

// Wraps an angle to (-pi, pi].
inline double wrapAngle(double a) {
  // Angles in the planner stay within a few turns: subtract whole turns (no libm call).
  if (a > -kPi && a <= kPi) return a;
  a -= 2.0 * kPi * std::floor((a + kPi) / (2.0 * kPi));
  return a <= -kPi ? a + 2.0 * kPi : (a > kPi ? a - 2.0 * kPi : a);
}

struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;

  Vec2 position() const { return {x, y}; }
  // Maps a point from this pose's frame into the parent frame.
  Vec2 transform(const Vec2& p) const {
    const double c = std::cos(theta), s = std::sin(theta);
    return {x + c * p.x() - s * p.y(), y + s * p.x() + c * p.y()};
  }
  // Maps a point from the parent frame into this pose's frame.
  Vec2 inverseTransform(const Vec2& p) const {
    const double c = std::cos(theta), s = std::sin(theta);
    const double dx = p.x() - x, dy = p.y() - y;
    return {c * dx + s * dy, -s * dx + c * dy};
  }
};

// Axis-aligned box [min, max].
struct Box {
  Vec2 min{0.0, 0.0};
  Vec2 max{0.0, 0.0};

  bool contains(const Vec2& p) const {
    return p.x() >= min.x() && p.x() <= max.x() && p.y() >= min.y() && p.y() <= max.y();
  }
  bool overlaps(const Box& o) const {
    return min.x() <= o.max.x() && o.min.x() <= max.x() && min.y() <= o.max.y() && o.min.y() <= max.y();
  }
  double width() const { return max.x() - min.x(); }
  double height() const { return max.y() - min.y(); }
};

}  // namespace staa
