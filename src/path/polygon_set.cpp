#include "path/polygon_set.hpp"

#include "geometry/predicates.hpp"

#include "geometry/polygon.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {

namespace {

// Grids beyond this many cells cost more memory than they save time; the cell grows instead.
constexpr double kMaxGridCells = 1 << 20;

// Does the way from vertex c towards point t start strictly inside the interior angle at c
// of a counter-clockwise polygon (prev -> c -> next)? Exact orientations of the points
// themselves, as in every test here (a point exactly on an edge's line is on it, never "a
// hair to its left").
bool entersInterior(const Vec2& prev, const Vec2& c, const Vec2& next, const Vec2& t, double bound) {
  const int turn = orientSign(prev, c, next, bound);
  const int l1 = orientSign(prev, c, t, bound);
  const int l2 = orientSign(c, next, t, bound);
  if (turn > 0) return l1 > 0 && l2 > 0;  // convex corner: the cone between the edges
  if (turn < 0) return l1 > 0 || l2 > 0;  // reflex corner: everything but the outside cone
  // Straight-through vertex (collinear edges) or a spike: left of the outgoing edge.
  return (c - prev).dot(next - c) > 0.0 ? l2 > 0 : false;
}

bool withinBox(const Vec2& p, const Vec2& a, const Vec2& b) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}

// Strict containment with no tolerance, so that it agrees exactly with the segment test
// below: a point the least bit inside counts as inside (and gets moved out by the planner)
// instead of as "on the boundary", where every segment leaving it would be blocked.
bool strictlyInside(const Vec2& p, PolygonView poly, double bound) {
  bool inside = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec2& a = poly[j];
    const Vec2& b = poly[i];
    const int o = orientSign(a, b, p, bound);
    if (o == 0 && withinBox(p, a, b)) return false;  // exactly on the boundary
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      // Which side of the edge p is on, decided by the sign of an orientation (no division).
      if ((b.y() > a.y()) == (o > 0)) inside = !inside;
    }
  }
  return inside;
}

}  // namespace

void PolygonSet::reserve(std::size_t max_polygons, std::size_t max_vertices) {
  vertices_.reserve(max_vertices);
  vertex_polygon_.reserve(max_vertices);
  convex_.reserve(max_vertices);
  edge_stamp_.reserve(max_vertices);
  polys_.reserve(max_polygons);
  poly_stamp_.reserve(max_polygons);
}

void PolygonSet::clear() {
  vertices_.clear();
  vertex_polygon_.clear();
  convex_.clear();
  polys_.clear();
  edge_stamp_.clear();
  poly_stamp_.clear();
  has_grid_ = false;
}

void PolygonSet::assign(std::span<const Polygon> polygons, const Options& options) {
  std::vector<PolygonView> views(polygons.begin(), polygons.end());
  assign(std::span<const PolygonView>(views), options);
}

void PolygonSet::assign(std::span<const PolygonView> polygons, const Options& options) {
  clear();
  for (const PolygonView poly : polygons) {
    const double area = signedArea(poly);
    if (poly.size() < 3 || area == 0.0 || !std::isfinite(area)) continue;
    PolyRec rec;
    rec.first = static_cast<std::uint32_t>(vertices_.size());
    rec.count = static_cast<std::uint32_t>(poly.size());
    rec.box = boundingBox(poly);
    const auto id = static_cast<std::uint32_t>(polys_.size());
    // Store counter-clockwise so that "left of an edge" is always the interior.
    if (area > 0.0) {
      vertices_.insert(vertices_.end(), poly.begin(), poly.end());
    } else {
      vertices_.insert(vertices_.end(), poly.rbegin(), poly.rend());
    }
    vertex_polygon_.insert(vertex_polygon_.end(), poly.size(), id);
    polys_.push_back(rec);
  }
  convex_.resize(vertices_.size());
  for (std::size_t v = 0; v < vertices_.size(); ++v) {
    const Vec2& p = vertices_[prevVertex(v)];
    const Vec2& c = vertices_[v];
    const Vec2& n = vertices_[nextVertex(v)];
    convex_[v] = orientSign(p, c, n) > 0 ? 1 : 0;
  }
  edge_stamp_.assign(vertices_.size(), 0);
  poly_stamp_.assign(polys_.size(), 0);
  stamp_ = 0;
  extent_ = Box{};
  max_abs_ = 0.0;
  for (const Vec2& v : vertices_) max_abs_ = std::max(max_abs_, maxAbsCoordinate(v));
  if (!polys_.empty()) {
    extent_ = polys_[0].box;
    for (const PolyRec& r : polys_) {
      extent_.min = extent_.min.cwiseMin(r.box.min);
      extent_.max = extent_.max.cwiseMax(r.box.max);
    }
  }
  if (options.cell_size > 0.0 && !polys_.empty()) buildGrid(options.cell_size);
}

std::size_t PolygonSet::prevVertex(std::size_t v) const {
  const PolyRec& r = polys_[vertex_polygon_[v]];
  return v == r.first ? r.first + r.count - 1 : v - 1;
}

std::size_t PolygonSet::nextVertex(std::size_t v) const {
  const PolyRec& r = polys_[vertex_polygon_[v]];
  return v + 1 == r.first + r.count ? r.first : v + 1;
}

void PolygonSet::buildGrid(double cell_size) {
  const Box ext = extent_;
  cell_ = cell_size;
  while ((ext.width() / cell_ + 1.0) * (ext.height() / cell_ + 1.0) > kMaxGridCells) cell_ *= 2.0;
  grid_origin_ = ext.min;
  grid_w_ = static_cast<int>(std::floor(ext.width() / cell_)) + 1;
  grid_h_ = static_cast<int>(std::floor(ext.height() / cell_)) + 1;
  const std::size_t cells = static_cast<std::size_t>(grid_w_) * static_cast<std::size_t>(grid_h_);

  auto cellRange = [&](const Vec2& lo, const Vec2& hi, int& x0, int& y0, int& x1, int& y1) {
    x0 = std::clamp(static_cast<int>(std::floor((lo.x() - grid_origin_.x()) / cell_)), 0, grid_w_ - 1);
    y0 = std::clamp(static_cast<int>(std::floor((lo.y() - grid_origin_.y()) / cell_)), 0, grid_h_ - 1);
    x1 = std::clamp(static_cast<int>(std::floor((hi.x() - grid_origin_.x()) / cell_)), 0, grid_w_ - 1);
    y1 = std::clamp(static_cast<int>(std::floor((hi.y() - grid_origin_.y()) / cell_)), 0, grid_h_ - 1);
  };

  // Two passes (count, then fill) into compressed rows.
  auto fill = [&](std::vector<std::uint32_t>& offsets, std::vector<std::uint32_t>& items, std::size_t n,
                  auto&& boxOf) {
    offsets.assign(cells + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
      Box b = boxOf(i);
      int x0, y0, x1, y1;
      cellRange(b.min, b.max, x0, y0, x1, y1);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) ++offsets[static_cast<std::size_t>(y) * grid_w_ + x + 1];
    }
    for (std::size_t c = 0; c < cells; ++c) offsets[c + 1] += offsets[c];
    items.assign(offsets[cells], 0);
    std::vector<std::uint32_t> cursor(offsets.begin(), offsets.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {
      Box b = boxOf(i);
      int x0, y0, x1, y1;
      cellRange(b.min, b.max, x0, y0, x1, y1);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) items[cursor[static_cast<std::size_t>(y) * grid_w_ + x]++] = static_cast<std::uint32_t>(i);
    }
  };
  fill(cell_edge_offsets_, cell_edges_, vertices_.size(), [&](std::size_t v) {
    const Vec2& a = vertices_[v];
    const Vec2& b = vertices_[nextVertex(v)];
    return Box{a.cwiseMin(b), a.cwiseMax(b)};
  });
  fill(cell_poly_offsets_, cell_polys_, polys_.size(), [&](std::size_t k) { return polys_[k].box; });
  cell_edge_recs_.resize(cell_edges_.size());
  for (std::size_t i = 0; i < cell_edges_.size(); ++i) {
    const std::uint32_t v = cell_edges_[i];
    cell_edge_recs_[i] = CellEdge{vertices_[v], vertices_[nextVertex(v)], v, vertex_polygon_[v]};
  }
  has_grid_ = true;
}

template <typename Visitor>
bool PolygonSet::forEachEdgeNearSegment(const Vec2& a, const Vec2& b, Visitor&& visit) const {
  // The edges of the cells the segment crosses, each once, as records (end points and
  // polygon at hand); without a grid every edge of the polygons whose box the segment's meets.
  if (++stamp_ == 0) {  // wrapped: forget old stamps
    std::fill(edge_stamp_.begin(), edge_stamp_.end(), 0);
    std::fill(poly_stamp_.begin(), poly_stamp_.end(), 0);
    stamp_ = 1;
  }
  const Box seg{a.cwiseMin(b), a.cwiseMax(b)};
  if (!has_grid_) {
    for (std::size_t k = 0; k < polys_.size(); ++k) {
      const PolyRec& r = polys_[k];
      if (!r.box.overlaps(seg)) continue;
      for (std::uint32_t v = r.first; v < r.first + r.count; ++v) {
        if (visit(CellEdge{vertices_[v], vertices_[nextVertex(v)], v, static_cast<std::uint32_t>(k)})) return true;
      }
    }
    return false;
  }
  // Walk the rows of cells the segment's box spans; in each row only the cells that the
  // segment's slab crosses (conservatively widened by a hair).
  const double eps = 1e-9;
  const int y0 = static_cast<int>(std::floor((seg.min.y() - grid_origin_.y()) / cell_));
  const int y1 = static_cast<int>(std::floor((seg.max.y() - grid_origin_.y()) / cell_));
  const double dy = b.y() - a.y();
  for (int y = std::max(y0, 0); y <= std::min(y1, grid_h_ - 1); ++y) {
    double xlo = seg.min.x(), xhi = seg.max.x();
    if (dy != 0.0) {
      const double sy0 = grid_origin_.y() + y * cell_, sy1 = sy0 + cell_;
      double t0 = (sy0 - a.y()) / dy, t1 = (sy1 - a.y()) / dy;
      if (t0 > t1) std::swap(t0, t1);
      t0 = std::clamp(t0, 0.0, 1.0);
      t1 = std::clamp(t1, 0.0, 1.0);
      const double xa = a.x() + t0 * (b.x() - a.x()), xb = a.x() + t1 * (b.x() - a.x());
      xlo = std::min(xa, xb);
      xhi = std::max(xa, xb);
    }
    const int x0 = std::max(static_cast<int>(std::floor((xlo - eps - grid_origin_.x()) / cell_)), 0);
    const int x1 = std::min(static_cast<int>(std::floor((xhi + eps - grid_origin_.x()) / cell_)), grid_w_ - 1);
    for (int x = x0; x <= x1; ++x) {
      const std::size_t cell = static_cast<std::size_t>(y) * grid_w_ + x;
      for (std::uint32_t i = cell_edge_offsets_[cell]; i < cell_edge_offsets_[cell + 1]; ++i) {
        const CellEdge& e = cell_edge_recs_[i];
        if (edge_stamp_[e.v] == stamp_) continue;
        edge_stamp_[e.v] = stamp_;
        if (visit(e)) return true;
      }
    }
  }
  return false;
}

template <typename Visitor>
bool PolygonSet::forEachPolygonNearPoint(const Vec2& p, Visitor&& visit) const {
  if (!has_grid_) {
    for (std::size_t k = 0; k < polys_.size(); ++k) {
      if (polys_[k].box.contains(p) && visit(static_cast<std::uint32_t>(k))) return true;
    }
    return false;
  }
  const int x = static_cast<int>(std::floor((p.x() - grid_origin_.x()) / cell_));
  const int y = static_cast<int>(std::floor((p.y() - grid_origin_.y()) / cell_));
  if (x < 0 || y < 0 || x >= grid_w_ || y >= grid_h_) {
    // Outside the grid's extent no box can contain the point, unless it lies on the edge.
    for (std::size_t k = 0; k < polys_.size(); ++k) {
      if (polys_[k].box.contains(p) && visit(static_cast<std::uint32_t>(k))) return true;
    }
    return false;
  }
  const std::size_t cell = static_cast<std::size_t>(y) * grid_w_ + x;
  for (std::uint32_t i = cell_poly_offsets_[cell]; i < cell_poly_offsets_[cell + 1]; ++i) {
    const std::uint32_t k = cell_polys_[i];
    if (polys_[k].box.contains(p) && visit(k)) return true;
  }
  return false;
}

// The exact local test for one edge (c, d) of a counter-clockwise polygon with the vertex p
// before c. Together over all edges of a polygon it decides whether the segment [a, b] meets
// the polygon's open interior, provided neither a nor b lies strictly inside it (the
// planners guarantee that by moving such points out first):
//  - the segment crosses the edge at a point interior to both; or
//  - the segment passes through vertex c heading into the interior angle at c; or
//  - an end of the segment lies inside the edge and the other end lies left of it.
// Any first entry into the interior happens at one of these, so no containment test of a
// sample point is needed.
//
// Inline in the edge loops: the edge strictly on one side of the segment's line means no
// crossing, c not on the segment, and no end of the segment on the edge (the line through
// it would separate c and d). Most edges near a segment are, and the filter alone says so;
// the rest of the test is out of line, so this path saves no registers.
inline bool PolygonSet::edgeBlocks(const Vec2& a, const Vec2& b, const CellEdge& e, double bound) const {
  if (strictlySameSideFiltered(a, b, e.c, e.d, bound)) return false;
  return edgeNearLineBlocks(a, b, e.v, bound);
}

[[gnu::noinline]] bool PolygonSet::edgeNearLineBlocks(const Vec2& a, const Vec2& b, std::size_t ci,
                                                      double bound) const {
  const Vec2& c = vertices_[ci];
  const Vec2& d = vertices_[nextVertex(ci)];
  const int oc = orientSign(a, b, c, bound);
  const int od = orientSign(a, b, d, bound);
  if (oc * od > 0) return false;
  const int oa = orientSign(c, d, a, bound);
  const int ob = orientSign(c, d, b, bound);
  if (oc * od < 0 && oa * ob < 0) return true;
  if (oc == 0 && a != b && withinBox(c, a, b)) {
    const Vec2& p = vertices_[prevVertex(ci)];
    if (c != b && entersInterior(p, c, d, b, bound)) return true;
    if (c != a && entersInterior(p, c, d, a, bound)) return true;
  }
  // An end on the edge: the segment enters when its other end lies left of the edge.
  if (oa == 0 && a != c && a != d && withinBox(a, c, d) && ob > 0) return true;
  if (ob == 0 && b != c && b != d && withinBox(b, c, d) && oa > 0) return true;
  return false;
}

double PolygonSet::orientBound(const Vec2& a, const Vec2& b) const {
  return orientStaticBound(std::max({max_abs_, maxAbsCoordinate(a), maxAbsCoordinate(b)}));
}

bool PolygonSet::segmentBlocked(const Vec2& a, const Vec2& b) const {
  const double bound = orientBound(a, b);
  return forEachEdgeNearSegment(a, b, [&](const CellEdge& e) { return edgeBlocks(a, b, e, bound); });
}

std::size_t PolygonSet::segmentBlockers(const Vec2& a, const Vec2& b, std::span<std::uint32_t> out) const {
  const double bound = orientBound(a, b);
  std::size_t n = 0;
  forEachEdgeNearSegment(a, b, [&](const CellEdge& e) {
    const std::uint32_t k = e.k;
    if (poly_stamp_[k] == stamp_) return false;  // already listed
    if (edgeBlocks(a, b, e, bound)) {
      poly_stamp_[k] = stamp_;
      if (n < out.size()) out[n++] = k;
    }
    return false;
  });
  return n;
}

bool PolygonSet::pointBlocked(const Vec2& p) const {
  const double bound = orientBound(p, p);
  return forEachPolygonNearPoint(p, [&](std::uint32_t k) { return strictlyInside(p, polygon(k), bound); });
}

bool PolygonSet::pointBlockedExcept(const Vec2& p, std::uint32_t skip) const {
  const double bound = orientBound(p, p);
  return forEachPolygonNearPoint(
      p, [&](std::uint32_t k) { return k != skip && strictlyInside(p, polygon(k), bound); });
}

std::size_t PolygonSet::coveringPolygons(const Vec2& p, std::uint32_t skip, std::span<std::uint32_t> out) const {
  const double bound = orientBound(p, p);
  std::size_t n = 0;
  forEachPolygonNearPoint(p, [&](std::uint32_t k) {
    if (k != skip && n < out.size() && strictlyInside(p, polygon(k), bound)) out[n++] = k;
    return false;
  });
  return n;
}

double PolygonSet::distanceToNearestEdge(const Vec2& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < vertices_.size(); ++v) {
    best = std::min(best, distancePointSegment(p, vertices_[v], vertices_[nextVertex(v)]));
  }
  return best;
}

bool PolygonSet::nearestFreePoint(const Vec2& p, Vec2& out, double nudge) const {
  if (!pointBlocked(p)) {
    out = p;
    return true;
  }
  // Candidates are the closest points on every edge, tried nearest first. A boundary point
  // that no other polygon covers is free once nudged outwards, away from p. Repeated
  // minimum selection instead of sorting keeps this allocation-free; it runs only when the
  // robot or a goal sits inside an inflated obstacle, and usually succeeds on the first try.
  double floor_d = -1.0;
  std::size_t floor_v = std::numeric_limits<std::size_t>::max();
  for (std::size_t attempt = 0; attempt < vertices_.size(); ++attempt) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_v = std::numeric_limits<std::size_t>::max();
    Vec2 best_q = p;
    for (std::size_t v = 0; v < vertices_.size(); ++v) {
      const Vec2 q = closestPointOnSegment(p, vertices_[v], vertices_[nextVertex(v)]);
      const double d = (q - p).norm();
      // Strictly after the previous candidate in (distance, index) order.
      if (d < floor_d || (d == floor_d && v <= floor_v)) continue;
      if (d < best || (d == best && v < best_v)) {
        best = d;
        best_v = v;
        best_q = q;
      }
    }
    if (best_v == std::numeric_limits<std::size_t>::max()) break;
    floor_d = best;
    floor_v = best_v;
    Vec2 dir = best_q - p;
    const double len = dir.norm();
    if (len > 0.0) {
      dir /= len;
    } else {
      const Vec2 e = vertices_[nextVertex(best_v)] - vertices_[best_v];
      dir = Vec2(e.y(), -e.x()).normalized();  // outward normal of a CCW edge
    }
    const Vec2 candidate = best_q + nudge * dir;
    if (!pointBlocked(candidate)) {
      out = candidate;
      return true;
    }
  }
  return false;
}

}  // namespace staa
