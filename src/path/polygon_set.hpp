#pragma once
// A set of obstacle polygons prepared for the queries that shortest-path search asks many
// times: "does this segment pass through an obstacle's interior (and which)?", "is this
// point free?", "where is the nearest free point?". Polygons are stored counter-clockwise
// in one flat array; an optional uniform grid indexes edges and bounding boxes so that a
// query touches only the polygons near it.
//
// Touching is free: a path may slide along an edge or turn at a corner; only the open
// interior of a polygon blocks. Polygons may overlap.
//
// Building allocates; queries do not (callers pass fixed-capacity output spans).

#include "geometry/types.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace staa {

class PolygonSet {
 public:
  struct Options {
    // Edge grid cell size in metres; 0 disables the grid (linear scans, for small sets).
    double cell_size = 0.0;
  };

  PolygonSet() = default;

  // Reserves room for `max_polygons` polygons with `max_vertices` vertices in total so that
  // later assign() calls within that capacity do not allocate (used for D', rebuilt per cycle).
  void reserve(std::size_t max_polygons, std::size_t max_vertices);

  // Replaces the contents. Polygons with fewer than 3 vertices or zero area are skipped.
  // Allocates only when the capacity is exceeded (or a grid is requested).
  void assign(std::span<const PolygonView> polygons, const Options& options);
  void assign(std::span<const Polygon> polygons, const Options& options);  // load time: allocates
  void clear();

  std::size_t polygonCount() const { return polys_.size(); }
  std::size_t vertexCount() const { return vertices_.size(); }
  PolygonView polygon(std::size_t i) const {
    return {vertices_.data() + polys_[i].first, polys_[i].count};
  }
  const Box& polygonBox(std::size_t i) const { return polys_[i].box; }
  // Index of the polygon that vertex v belongs to, and the vertex's neighbours (CCW order).
  std::uint32_t polygonOfVertex(std::size_t v) const { return vertex_polygon_[v]; }
  const Vec2& vertex(std::size_t v) const { return vertices_[v]; }
  std::size_t prevVertex(std::size_t v) const;
  std::size_t nextVertex(std::size_t v) const;
  // A corner whose interior angle is below 180 degrees: the only corners a shortest path
  // can turn at.
  bool isConvexCorner(std::size_t v) const { return convex_[v] != 0; }

  // True when the point lies strictly inside some polygon (boundary is free).
  bool pointBlocked(const Vec2& p) const;
  // As pointBlocked, but ignores polygon `skip` (a corner lies on its own polygon).
  bool pointBlockedExcept(const Vec2& p, std::uint32_t skip) const;
  // Writes the polygons (other than `skip`) that contain p strictly into `out`; returns how
  // many were written (at most out.size()).
  std::size_t coveringPolygons(const Vec2& p, std::uint32_t skip, std::span<std::uint32_t> out) const;

  // True when the closed segment [a, b] passes through the interior of some polygon.
  bool segmentBlocked(const Vec2& a, const Vec2& b) const;
  // Writes the indices of all polygons whose interior the segment enters into `out`
  // (at most out.size(); extra blockers are dropped) and returns their number. A polygon
  // is listed once.
  std::size_t segmentBlockers(const Vec2& a, const Vec2& b, std::span<std::uint32_t> out) const;

  // Calls visit(v) once for every edge (by start vertex v) whose bounding box may overlap
  // `box` (all edges when there is no grid). Stops early when visit returns true.
  template <typename Visitor>
  bool forEachEdgeInBox(const Box& box, Visitor&& visit) const;
  const Box& extent() const { return extent_; }
  // The largest coordinate magnitude of any vertex (0 when empty).
  double maxCoordinate() const { return max_abs_; }

  // Distance from p to the nearest polygon edge (inside or outside); infinity when empty.
  double distanceToNearestEdge(const Vec2& p) const;

  // The free point nearest to p (p itself when free): the closest point on any polygon's
  // boundary that is not inside another polygon, nudged outwards by `nudge` metres.
  // Returns false when there is no free point (everything is covered).
  bool nearestFreePoint(const Vec2& p, Vec2& out, double nudge = 1e-6) const;

 private:
  struct PolyRec {
    std::uint32_t first = 0;
    std::uint32_t count = 0;
    Box box;
  };

  // An edge as the segment tests read it: its end points, its start vertex and its polygon.
  struct CellEdge {
    Vec2 c{0.0, 0.0};
    Vec2 d{0.0, 0.0};
    std::uint32_t v = 0;
    std::uint32_t k = 0;
  };
  // Does the segment enter the interior of polygon `k` through the boundary near edge
  // starting at vertex c? (the per-edge part of the exact test, see polygon_set.cpp).
  bool edgeBlocks(const Vec2& a, const Vec2& b, const CellEdge& e, double bound) const;
  // edgeBlocks past its common rejection (the edge strictly on one side of the segment's line).
  bool edgeNearLineBlocks(const Vec2& a, const Vec2& b, std::size_t c, double bound) const;
  // The static orientation bound (geometry/predicates.hpp) for this set's vertices and the
  // query points a and b.
  double orientBound(const Vec2& a, const Vec2& b) const;

  template <typename Visitor>
  bool forEachEdgeNearSegment(const Vec2& a, const Vec2& b, Visitor&& visit) const;
  template <typename Visitor>
  bool forEachPolygonNearPoint(const Vec2& p, Visitor&& visit) const;
  // The edges listed in one grid cell that this query has not visited yet.
  template <typename Visitor>
  bool visitCellEdges(std::size_t cell, Visitor&& visit) const {
    for (std::uint32_t i = cell_edge_offsets_[cell]; i < cell_edge_offsets_[cell + 1]; ++i) {
      const std::uint32_t v = cell_edges_[i];
      if (edge_stamp_[v] == stamp_) continue;
      edge_stamp_[v] = stamp_;
      if (visit(static_cast<std::size_t>(v))) return true;
    }
    return false;
  }

  void buildGrid(double cell_size);

  std::vector<Vec2> vertices_;
  std::vector<std::uint32_t> vertex_polygon_;
  std::vector<std::uint8_t> convex_;
  std::vector<PolyRec> polys_;

  // Uniform grid over the set's extent: per cell, the edges (by start vertex) that overlap
  // the cell's box and the polygons whose box overlaps it. CSR layout (offsets + items).
  Box extent_;
  double max_abs_ = 0.0;
  bool has_grid_ = false;
  double cell_ = 1.0;
  Vec2 grid_origin_{0.0, 0.0};
  int grid_w_ = 0;
  int grid_h_ = 0;
  std::vector<std::uint32_t> cell_edge_offsets_;
  std::vector<std::uint32_t> cell_edges_;
  std::vector<CellEdge> cell_edge_recs_;  // cell_edges_' edges as records, in the same order
  std::vector<std::uint32_t> cell_poly_offsets_;
  std::vector<std::uint32_t> cell_polys_;
  // Per-query visit stamps so that an edge or polygon listed in several cells is tested once.
  mutable std::vector<std::uint32_t> edge_stamp_;
  mutable std::vector<std::uint32_t> poly_stamp_;
  mutable std::uint32_t stamp_ = 0;
};

template <typename Visitor>
bool PolygonSet::forEachEdgeInBox(const Box& box, Visitor&& visit) const {
  if (++stamp_ == 0) {
    std::fill(edge_stamp_.begin(), edge_stamp_.end(), 0);
    std::fill(poly_stamp_.begin(), poly_stamp_.end(), 0);
    stamp_ = 1;
  }
  if (!has_grid_) {
    for (std::size_t k = 0; k < polys_.size(); ++k) {
      if (!polys_[k].box.overlaps(box)) continue;
      for (std::uint32_t v = polys_[k].first; v < polys_[k].first + polys_[k].count; ++v) {
        if (visit(static_cast<std::size_t>(v))) return true;
      }
    }
    return false;
  }
  const int x0 = std::max(static_cast<int>(std::floor((box.min.x() - grid_origin_.x()) / cell_)), 0);
  const int y0 = std::max(static_cast<int>(std::floor((box.min.y() - grid_origin_.y()) / cell_)), 0);
  const int x1 = std::min(static_cast<int>(std::floor((box.max.x() - grid_origin_.x()) / cell_)), grid_w_ - 1);
  const int y1 = std::min(static_cast<int>(std::floor((box.max.y() - grid_origin_.y()) / cell_)), grid_h_ - 1);
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const std::size_t cell = static_cast<std::size_t>(y) * static_cast<std::size_t>(grid_w_) + static_cast<std::size_t>(x);
      if (visitCellEdges(cell, visit)) return true;
    }
  }
  return false;
}

}  // namespace staa
