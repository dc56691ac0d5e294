#pragma once
// Which cells of the plane belong to the static map M: the map's obstacles grown by a margin,
// and everything outside its bounds. Depth points there are walls, furniture and the like
// that the planner already knows; perception reports only what the map does not explain.
//
// A raster over the whole map in cells of `cell_m` whose corners lie on multiples of cell_m
// (cell (i, j) covers [i, i+1) x [j, j+1) cells), so a grid anchored on the same lattice looks
// cells up by index. Built once at start-up; blocked() is a lookup (no allocation).

#include "geometry/types.hpp"
#include "map/polygon_map.hpp"

#include <cstdint>
#include <vector>

namespace staa {

class StaticMapMask {
 public:
  // Largest raster accepted (cells, one byte each): 1 km^2 at 0.1 m.
  static constexpr std::int64_t kMaxCells = 100'000'000;

  // A cell is blocked when its centre lies inside an obstacle, within margin_m of one's
  // edges, or outside the bounds shrunk by margin_m. Throws std::invalid_argument naming the
  // value for cell_m <= 0, margin_m < 0, or a raster beyond kMaxCells.
  StaticMapMask(const PolygonMap& map, double cell_m, double margin_m);

  double cellSize() const { return cell_m_; }
  // Cell index of a coordinate on the lattice (floor(x / cell_m)).
  std::int64_t cellIndex(double coordinate) const;
  // Cells outside the raster are blocked when the map has bounds (outside is blocked), free
  // otherwise.
  bool blocked(std::int64_t i, std::int64_t j) const {
    const std::int64_t ci = i - i0_, cj = j - j0_;
    if (ci < 0 || cj < 0 || ci >= width_ || cj >= height_) return outside_blocked_;
    return cells_[static_cast<std::size_t>(cj * width_ + ci)] != 0;
  }
  bool blockedAt(const Vec2& p) const { return blocked(cellIndex(p.x()), cellIndex(p.y())); }
  std::int64_t blockedCount() const { return blocked_count_; }

 private:
  void mark(std::int64_t i, std::int64_t j);
  void fillPolygon(const Polygon& poly, std::vector<double>& crossings);
  void markNearEdges(const Polygon& poly);

  double cell_m_;
  double margin_m_;
  std::int64_t i0_ = 0, j0_ = 0, width_ = 0, height_ = 0;
  bool outside_blocked_ = false;
  std::vector<std::uint8_t> cells_;
  std::int64_t blocked_count_ = 0;
};

}  // namespace staa
