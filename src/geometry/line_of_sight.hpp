#pragma once
// Line of sight among polygons: whether a segment touches none of their edges. Built once (the
// edges, and each polygon's box to skip the polygons a segment cannot reach); clear()
// allocates nothing, so the control cycle (the blind-corner limit) and the simulator (what an
// agent can see of the others) both ask it.

#include "geometry/types.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace staa {

class LineOfSight {
 public:
  LineOfSight() = default;
  // Polygons of fewer than 3 vertices block nothing.
  explicit LineOfSight(std::span<const Polygon> polygons);

  // The closed segment [from, to] touches no edge. A segment wholly inside a polygon touches
  // none: the callers look from free space.
  bool clear(const Vec2& from, const Vec2& to) const;
  // Some point of `points` lies within `range` of `eye` on a clear segment from it.
  bool seesAny(const Vec2& eye, PolygonView points, double range) const;

  bool empty() const { return edge_a_.empty(); }

 private:
  std::vector<Vec2> edge_a_, edge_b_;
  std::vector<Box> box_;                 // per polygon: its edges' box
  std::vector<std::uint32_t> first_;     // per polygon: its first edge; one past the last at the end
};

}  // namespace staa
