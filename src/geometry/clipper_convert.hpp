#pragma once
// Conversions between our polygons and Clipper's integer paths, for the files that call
// Clipper directly (geometry/clipper_ops.cpp, map/goals.cpp). Include only from .cpp files:
// it brings in <clipper.hpp>.

#include "geometry/polygon.hpp"

#include <clipper.hpp>

#include <cmath>

namespace staa::clipper_convert {

// Clipper works on integers: 1 unit = 1 micrometre keeps every map far inside its range.
inline constexpr double kScale = 1e6;

inline ClipperLib::Path toPath(const Polygon& poly) {
  ClipperLib::Path path;
  path.reserve(poly.size());
  for (const Vec2& p : poly) {
    path.emplace_back(static_cast<ClipperLib::cInt>(std::llround(p.x() * kScale)),
                      static_cast<ClipperLib::cInt>(std::llround(p.y() * kScale)));
  }
  return path;
}

inline Polygon toPolygon(const ClipperLib::Path& path) {
  Polygon poly;
  poly.reserve(path.size());
  for (const ClipperLib::IntPoint& p : path) {
    poly.emplace_back(static_cast<double>(p.X) / kScale, static_cast<double>(p.Y) / kScale);
  }
  return poly;
}

}  // namespace staa::clipper_convert
