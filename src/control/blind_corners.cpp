#include "control/blind_corners.hpp"

#include "geometry/predicates.hpp"

#include <algorithm>
#include <cmath>

namespace staa {

double blindCornerSpeed(double room, double reaction_s, double decel, double min_speed) {
  if (!(room > 0.0)) return min_speed;
  // v * t + v^2 / (2 a) = room, for v >= 0.
  const double v = decel * (-reaction_s + std::sqrt(reaction_s * reaction_s + 2.0 * room / decel));
  return std::max(v, min_speed);
}

BlindCorners::BlindCorners(std::span<const Polygon> polygons, const BlindCornerConfig& config, double clearance,
                           double decel)
    : config_(config), clearance_(clearance), decel_(decel > 0.0 ? decel : 1.0), sight_(polygons) {
  for (const Polygon& poly : polygons) {
    const std::size_t n = poly.size();
    if (n < 3) continue;
    const double orientation = signedArea(poly) >= 0.0 ? 1.0 : -1.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2& prev = poly[(i + n - 1) % n];
      const Vec2& p = poly[i];
      const Vec2& next = poly[(i + 1) % n];
      // Only convex corners hide anything beside them: at a reflex one the line of sight
      // runs on into the obstacle.
      if (orientation * orientDeterminant(prev, p, next) > 0.0) vertices_.push_back(Vertex{p, prev, next});
    }
  }
}

bool BlindCorners::visible(const Vec2& from, const Vec2& corner) const {
  // The line of sight stops just short of the corner: the corner's own edges touch it there.
  const Vec2 d = corner - from;
  const double len = d.norm();
  if (len <= 1e-9) return true;
  return sight_.clear(from, from + d * ((len - 1e-6) / len));
}

BlindCorners::Cap BlindCorners::speedCap(const Pose2& pose) const {
  Cap cap;
  if (!config_.enabled) return cap;
  const Vec2 p{pose.x, pose.y};
  const Vec2 u{std::cos(pose.theta), std::sin(pose.theta)};
  const double range2 = config_.range_m * config_.range_m;
  const double lateral = clearance_ + config_.lateral_m;
  double best = std::numeric_limits<double>::infinity();  // the least room ahead so far
  for (const Vertex& v : vertices_) {
    const Vec2 d = v.p - p;
    if (d.squaredNorm() > range2) continue;
    // Ahead, beyond the robot's own clearance (closer, the robot is in the crossing already and
    // braking would only keep it there), and near the line of travel.
    const double ahead = d.dot(u);
    const double room = ahead - clearance_;
    if (!(room > 0.0) || room >= best) continue;
    if (std::abs(u.x() * d.y() - u.y() * d.x()) > lateral) continue;
    // Both edges on one side of the line of sight: the corner hides what lies behind it.
    const double a = orientDeterminant(p, v.p, v.prev);
    const double b = orientDeterminant(p, v.p, v.next);
    if (!(a * b > 0.0)) continue;
    if (!visible(p, v.p)) continue;
    best = room;
    cap.corner = v.p;
    cap.room = room;
  }
  if (std::isfinite(best)) cap.speed = blindCornerSpeed(best, config_.reaction_s, decel_, config_.min_speed);
  return cap;
}

}  // namespace staa
