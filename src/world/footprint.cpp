#include "world/footprint.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {

Polygon footprintAt(PolygonView footprint, const Pose2& pose) {
  Polygon out;
  footprintAt(footprint, pose, out);
  return out;
}

void footprintAt(PolygonView footprint, const Pose2& pose, Polygon& out) {
  out.resize(footprint.size());
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  for (std::size_t k = 0; k < footprint.size(); ++k) {
    const Vec2& p = footprint[k];
    out[k] = Vec2(pose.x + c * p.x() - s * p.y(), pose.y + s * p.x() + c * p.y());
  }
}

double polygonDistance(PolygonView a, PolygonView b) {
  if (a.empty() || b.empty()) return std::numeric_limits<double>::infinity();
  if (polygonsOverlap(a, b)) return 0.0;
  // Disjoint polygons: the closest pair of points has a vertex of one of them at one end.
  double best = std::numeric_limits<double>::infinity();
  for (const Vec2& p : a) best = std::min(best, distanceToEdges(p, b));
  for (const Vec2& p : b) best = std::min(best, distanceToEdges(p, a));
  return best;
}

double boxDistance(const Box& a, const Box& b) {
  const double dx = std::max({0.0, a.min.x() - b.max.x(), b.min.x() - a.max.x()});
  const double dy = std::max({0.0, a.min.y() - b.max.y(), b.min.y() - a.max.y()});
  return std::hypot(dx, dy);
}

}  // namespace staa
