#include "perception/static_map_mask.hpp"

#include "geometry/polygon.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace staa {

StaticMapMask::StaticMapMask(const PolygonMap& map, double cell_m, double margin_m)
    : cell_m_(cell_m), margin_m_(margin_m) {
  if (!(cell_m > 0.0) || !std::isfinite(cell_m)) {
    throw std::invalid_argument("static map mask: cell_m must be finite and > 0, got " + std::to_string(cell_m));
  }
  if (!(margin_m >= 0.0) || !std::isfinite(margin_m)) {
    throw std::invalid_argument("static map mask: margin_m must be finite and >= 0, got " + std::to_string(margin_m));
  }
  // The raster: the bounds (outside them is blocked anyway), else the obstacles' box grown by
  // the margin (outside it is free).
  outside_blocked_ = map.bounds.has_value();
  Box area;
  if (map.bounds) {
    area = *map.bounds;
  } else if (!map.obstacles.empty()) {
    area = boundingBox(map.obstacles.front());
    for (const Polygon& o : map.obstacles) {
      const Box b = boundingBox(o);
      area.min = area.min.cwiseMin(b.min);
      area.max = area.max.cwiseMax(b.max);
    }
    area.min -= Vec2(margin_m, margin_m);
    area.max += Vec2(margin_m, margin_m);
  } else {
    return;  // nothing static: every cell is free
  }
  i0_ = cellIndex(area.min.x());
  j0_ = cellIndex(area.min.y());
  width_ = cellIndex(area.max.x()) - i0_ + 1;
  height_ = cellIndex(area.max.y()) - j0_ + 1;
  if (width_ * height_ > kMaxCells) {
    throw std::invalid_argument("static map mask: map '" + map.name + "' (" + std::to_string(area.width()) + " x " +
                                std::to_string(area.height()) + " m) needs " + std::to_string(width_ * height_) +
                                " cells of " + std::to_string(cell_m) + " m, more than " + std::to_string(kMaxCells) +
                                ": use larger cells");
  }
  cells_.assign(static_cast<std::size_t>(width_ * height_), 0);

  if (map.bounds) {
    // Cells whose centre is outside the bounds shrunk by the margin.
    const Box inner{map.bounds->min + Vec2(margin_m, margin_m), map.bounds->max - Vec2(margin_m, margin_m)};
    for (std::int64_t j = 0; j < height_; ++j) {
      for (std::int64_t i = 0; i < width_; ++i) {
        const Vec2 c((static_cast<double>(i0_ + i) + 0.5) * cell_m, (static_cast<double>(j0_ + j) + 0.5) * cell_m);
        if (!inner.contains(c)) mark(i0_ + i, j0_ + j);
      }
    }
  }
  std::vector<double> crossings;
  for (const Polygon& o : map.obstacles) {
    fillPolygon(o, crossings);
    markNearEdges(o);
  }
}

std::int64_t StaticMapMask::cellIndex(double coordinate) const {
  // A coordinate beyond any map (a pose from a lost localisation, NaN) names a cell far
  // outside the mask: converting it unclamped to an integer would be undefined.
  constexpr double kFar = 1e15;
  const double c = std::floor(coordinate / cell_m_);
  if (std::isnan(c)) return static_cast<std::int64_t>(kFar);
  return static_cast<std::int64_t>(std::clamp(c, -kFar, kFar));
}

void StaticMapMask::mark(std::int64_t i, std::int64_t j) {
  const std::int64_t ci = i - i0_, cj = j - j0_;
  if (ci < 0 || cj < 0 || ci >= width_ || cj >= height_) return;
  std::uint8_t& c = cells_[static_cast<std::size_t>(cj * width_ + ci)];
  if (c == 0) ++blocked_count_;
  c = 1;
}

// Scanline fill at the cell centres' heights: cells whose centre is inside (even-odd rule,
// which is the inside of a simple polygon).
void StaticMapMask::fillPolygon(const Polygon& poly, std::vector<double>& crossings) {
  const Box b = boundingBox(poly);
  const std::int64_t j_lo = cellIndex(b.min.y()), j_hi = cellIndex(b.max.y());
  for (std::int64_t j = j_lo; j <= j_hi; ++j) {
    const double yc = (static_cast<double>(j) + 0.5) * cell_m_;
    crossings.clear();
    for (std::size_t k = 0; k < poly.size(); ++k) {
      const Vec2& a = poly[k];
      const Vec2& c = poly[(k + 1) % poly.size()];
      if ((a.y() <= yc) != (c.y() <= yc)) crossings.push_back(a.x() + (yc - a.y()) * (c.x() - a.x()) / (c.y() - a.y()));
    }
    std::sort(crossings.begin(), crossings.end());
    for (std::size_t k = 0; k + 1 < crossings.size(); k += 2) {
      // Cells whose centre x lies in [x0, x1].
      const auto i_lo = static_cast<std::int64_t>(std::ceil(crossings[k] / cell_m_ - 0.5));
      const auto i_hi = static_cast<std::int64_t>(std::floor(crossings[k + 1] / cell_m_ - 0.5));
      for (std::int64_t i = i_lo; i <= i_hi; ++i) mark(i, j);
    }
  }
}

// Cells whose centre lies within the margin of an edge.
void StaticMapMask::markNearEdges(const Polygon& poly) {
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const Vec2& a = poly[k];
    const Vec2& c = poly[(k + 1) % poly.size()];
    const Vec2 lo = a.cwiseMin(c) - Vec2(margin_m_, margin_m_);
    const Vec2 hi = a.cwiseMax(c) + Vec2(margin_m_, margin_m_);
    for (std::int64_t j = cellIndex(lo.y()); j <= cellIndex(hi.y()); ++j) {
      for (std::int64_t i = cellIndex(lo.x()); i <= cellIndex(hi.x()); ++i) {
        const Vec2 centre((static_cast<double>(i) + 0.5) * cell_m_, (static_cast<double>(j) + 0.5) * cell_m_);
        if (distancePointSegment(centre, a, c) <= margin_m_) mark(i, j);
      }
    }
  }
}

}  // namespace staa
