#include "geometry/line_of_sight.hpp"

#include "geometry/polygon.hpp"

namespace staa {

LineOfSight::LineOfSight(std::span<const Polygon> polygons) {
  for (const Polygon& poly : polygons) {
    const std::size_t n = poly.size();
    if (n < 3) continue;
    first_.push_back(static_cast<std::uint32_t>(edge_a_.size()));
    box_.push_back(boundingBox(poly));
    for (std::size_t i = 0; i < n; ++i) {
      edge_a_.push_back(poly[i]);
      edge_b_.push_back(poly[(i + 1) % n]);
    }
  }
  first_.push_back(static_cast<std::uint32_t>(edge_a_.size()));
}

bool LineOfSight::clear(const Vec2& from, const Vec2& to) const {
  const Box sight{from.cwiseMin(to), from.cwiseMax(to)};
  for (std::size_t k = 0; k + 1 < first_.size(); ++k) {
    if (!box_[k].overlaps(sight)) continue;
    for (std::uint32_t e = first_[k]; e < first_[k + 1]; ++e) {
      if (segmentsIntersect(from, to, edge_a_[e], edge_b_[e])) return false;
    }
  }
  return true;
}

bool LineOfSight::seesAny(const Vec2& eye, PolygonView points, double range) const {
  const double range2 = range * range;
  for (const Vec2& p : points) {
    if ((p - eye).squaredNorm() <= range2 && clear(eye, p)) return true;
  }
  return false;
}

}  // namespace staa
