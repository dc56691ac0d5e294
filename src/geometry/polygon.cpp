#include "geometry/polygon.hpp"

#include "geometry/predicates.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <set>
#include <span>
#include <vector>

namespace staa {

double signedArea(PolygonView poly) {
  const std::size_t n = poly.size();
  if (n < 3) return 0.0;
  double a = 0.0;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) a += cross(poly[j], poly[i]);
  return 0.5 * a;
}

Box boundingBox(PolygonView poly) {
  Box b;
  if (poly.empty()) return b;
  b.min = b.max = poly[0];
  for (const Vec2& p : poly) {
    b.min = b.min.cwiseMin(p);
    b.max = b.max.cwiseMax(p);
  }
  return b;
}

Containment locatePoint(const Vec2& p, PolygonView poly, double eps) {
  const std::size_t n = poly.size();
  if (n < 3) return Containment::kOutside;
  bool inside = false;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vec2& a = poly[j];
    const Vec2& b = poly[i];
    if (distancePointSegment(p, a, b) <= eps) return Containment::kBoundary;
    // Crossing-number test with the half-open rule on y, so vertices count once.
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double x = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (x > p.x()) inside = !inside;
    }
  }
  return inside ? Containment::kInside : Containment::kOutside;
}

namespace {
bool onSegment(const Vec2& p, const Vec2& a, const Vec2& b) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}
}  // namespace

bool segmentsIntersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const int o1 = orientSign(a, b, c), o2 = orientSign(a, b, d);
  const int o3 = orientSign(c, d, a), o4 = orientSign(c, d, b);
  if (o1 != o2 && o3 != o4) return true;
  if (o1 == 0 && onSegment(c, a, b)) return true;
  if (o2 == 0 && onSegment(d, a, b)) return true;
  if (o3 == 0 && onSegment(a, c, d)) return true;
  if (o4 == 0 && onSegment(b, c, d)) return true;
  return false;
}

bool segmentsCrossProperly(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const int o1 = orientSign(a, b, c), o2 = orientSign(a, b, d);
  const int o3 = orientSign(c, d, a), o4 = orientSign(c, d, b);
  return o1 * o2 < 0 && o3 * o4 < 0;
}

std::optional<double> segmentIntersectionParam(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const Vec2 r = b - a, s = d - c;
  const double denom = cross(r, s);
  if (denom == 0.0) return std::nullopt;  // parallel or collinear: no single point
  const double t = cross(c - a, s) / denom;
  const double u = cross(c - a, r) / denom;
  if (t < 0.0 || t > 1.0 || u < 0.0 || u > 1.0) return std::nullopt;
  return t;
}

Vec2 closestPointOnSegment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 == 0.0) return a;
  const double t = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
  return a + t * ab;
}

double distancePointSegment(const Vec2& p, const Vec2& a, const Vec2& b) {
  return (p - closestPointOnSegment(p, a, b)).norm();
}

double distanceToEdges(const Vec2& p, PolygonView poly) {
  const std::size_t n = poly.size();
  if (n == 0) return std::numeric_limits<double>::infinity();
  if (n == 1) return (p - poly[0]).norm();
  double best2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    best2 = std::min(best2, (p - closestPointOnSegment(p, poly[j], poly[i])).squaredNorm());
  }
  return std::sqrt(best2);
}

namespace {
// Whether edges i < j of a polygon of n >= 3 vertices offend simplicity: adjacent edges
// fold back over each other, other edges share a point.
bool edgesOffend(PolygonView poly, std::size_t i, std::size_t j) {
  const std::size_t n = poly.size();
  const Vec2& a = poly[i];
  const Vec2& b = poly[(i + 1) % n];
  const Vec2& c = poly[j];
  const Vec2& d = poly[(j + 1) % n];
  const bool adjacent_next = (j == i + 1);
  const bool adjacent_prev = (i == 0 && j == n - 1);
  if (adjacent_next || adjacent_prev) {
    if (n == 3) return false;  // a triangle's edges are all adjacent
    // Adjacent edges share one vertex; they must not fold back over each other.
    const Vec2& shared = adjacent_next ? b : a;
    const Vec2& p = adjacent_next ? a : b;  // the other end of edge i
    const Vec2& q = adjacent_next ? d : c;  // the other end of edge j
    return orientSign(shared, p, q) == 0 && (p - shared).dot(q - shared) > 0.0;
  }
  return segmentsIntersect(a, b, c, d);
}

// Uniform grid over the polygon's box with about one cell per edge; each edge is listed in
// every cell its bounding box covers (CSR layout). Two edges that share a point share a
// cell: the point lies in both boxes and the cell index is monotone in the coordinate.
class EdgeGrid {
 public:
  explicit EdgeGrid(PolygonView poly) : poly_(poly) {
    const Box box = boundingBox(poly);
    origin_ = box.min;
    const double n = static_cast<double>(poly.size());
    const double w = box.width(), h = box.height();
    const double side = std::sqrt(w * h / n);
    // A degenerate box (all on a line) gets one row or column of n cells.
    const double cell = side > 0.0 ? side : std::max(w, h) / n;
    inv_ = cell > 0.0 ? 1.0 / cell : 0.0;
    cols_ = cellsAlong(w);
    rows_ = cellsAlong(h);
    // Edges whose boxes cover many cells (the spikes of a star) would list each edge in a
    // large share of the grid: count the entries first, without visiting them.
    for (std::size_t e = 0; e < poly.size(); ++e) entries_ += cellsOf(e);
    if (!useful()) return;
    offsets_.assign(static_cast<std::size_t>(cols_) * static_cast<std::size_t>(rows_) + 1, 0);
    forEachEdgeCell([&](std::size_t, std::size_t c) { ++offsets_[c + 1]; });
    for (std::size_t c = 1; c < offsets_.size(); ++c) offsets_[c] += offsets_[c - 1];
    edges_.resize(offsets_.back());
    std::vector<std::size_t> cursor(offsets_.begin(), offsets_.end() - 1);
    forEachEdgeCell([&](std::size_t e, std::size_t c) { edges_[cursor[c]++] = static_cast<std::uint32_t>(e); });
    // The pairs a scan of the cells tests: edges crowded into few cells (a fine outline in a
    // large box) make it quadratic although each edge covers few cells.
    for (std::size_t c = 0; c + 1 < offsets_.size(); ++c) {
      const double k = static_cast<double>(offsets_[c + 1] - offsets_[c]);
      pairs_ += k * k;
    }
  }

  // Calls visit(c) for every cell index covered by edge e's box.
  template <typename Visit>
  void forEachCellOf(std::size_t e, Visit&& visit) const {
    const Vec2& a = poly_[e];
    const Vec2& b = poly_[(e + 1) % poly_.size()];
    const std::size_t x0 = column(std::min(a.x(), b.x())), x1 = column(std::max(a.x(), b.x()));
    const std::size_t y0 = row(std::min(a.y(), b.y())), y1 = row(std::max(a.y(), b.y()));
    for (std::size_t y = y0; y <= y1; ++y) {
      for (std::size_t x = x0; x <= x1; ++x) visit(y * static_cast<std::size_t>(cols_) + x);
    }
  }
  // Whether the grid was built: at most kMaxEntriesPerEdge entries per edge on average.
  // Otherwise the boxes overlap so much that the grid would cost as much memory as the
  // quadratic scan costs time, and the caller takes that scan.
  static constexpr double kMaxEntriesPerEdge = 64.0;
  bool useful() const { return entries_ <= kMaxEntriesPerEdge * static_cast<double>(poly_.size()); }
  // Built, and its cells hold at most kMaxPairsPerEdge pairs per edge (each pair counted
  // twice). The sweep costs about as many instructions as 16 edge tests per edge: a fine
  // outline (a 200,000-vertex circle, ~140 edges a cell) takes it, a map's polygon does not.
  static constexpr double kMaxPairsPerEdge = 32.0;
  bool fast() const { return useful() && pairs_ <= kMaxPairsPerEdge * static_cast<double>(poly_.size()); }
  std::span<const std::uint32_t> cellEdges(std::size_t c) const {
    return {edges_.data() + offsets_[c], offsets_[c + 1] - offsets_[c]};
  }

 private:
  // Cells are capped at 2^20 per axis (and so at about n in total, see the constructor).
  int cellsAlong(double extent) const {
    return static_cast<int>(std::clamp(std::floor(extent * inv_) + 1.0, 1.0, 1048576.0));
  }
  std::size_t index(double offset, int count) const {
    const double k = std::floor(offset * inv_);
    return static_cast<std::size_t>(std::clamp(k, 0.0, static_cast<double>(count - 1)));
  }
  double cellsOf(std::size_t e) const {
    const Vec2& a = poly_[e];
    const Vec2& b = poly_[(e + 1) % poly_.size()];
    const double nx = static_cast<double>(column(std::max(a.x(), b.x())) - column(std::min(a.x(), b.x())) + 1);
    const double ny = static_cast<double>(row(std::max(a.y(), b.y())) - row(std::min(a.y(), b.y())) + 1);
    return nx * ny;
  }
  std::size_t column(double x) const { return index(x - origin_.x(), cols_); }
  std::size_t row(double y) const { return index(y - origin_.y(), rows_); }
  template <typename Visit>
  void forEachEdgeCell(Visit&& visit) const {
    for (std::size_t e = 0; e < poly_.size(); ++e) forEachCellOf(e, [&](std::size_t c) { visit(e, c); });
  }

  PolygonView poly_;
  Vec2 origin_;
  double inv_ = 0.0;
  int cols_ = 1;
  int rows_ = 1;
  double entries_ = 0.0;
  double pairs_ = 0.0;
  std::vector<std::size_t> offsets_;
  std::vector<std::uint32_t> edges_;
};
}  // namespace

std::optional<EdgePair> findSelfIntersectionQuadratic(PolygonView poly) {
  const std::size_t n = poly.size();
  if (n < 3) return std::nullopt;
  for (std::size_t i = 0; i < n; ++i) {
    if (poly[i] == poly[(i + 1) % n]) return EdgePair{i, i};  // zero-length edge: a repeated vertex
    for (std::size_t j = i + 1; j < n; ++j) {
      if (edgesOffend(poly, i, j)) return EdgePair{i, j};
    }
  }
  return std::nullopt;
}

namespace {

// Shamos and Hoey's sweep: is the polygon simple, in O(n log n) for any shape? Vertices in
// (x, y) order; the status holds the edges the sweep line crosses, ordered by where they
// cross it; an edge is tested against its neighbours whenever it gains new ones. With all
// vertices distinct, the only points two edges may share are the vertices adjacent edges
// share, and the first point where edges offend is found before the status order breaks.
// Returns an offending pair (the one met first, not necessarily the smallest), or nothing.
std::optional<EdgePair> sweepSelfIntersection(PolygonView poly) {
  const std::size_t n = poly.size();
  auto less = [&](std::uint32_t a, std::uint32_t b) {
    const Vec2& p = poly[a];
    const Vec2& q = poly[b];
    return p.x() < q.x() || (p.x() == q.x() && (p.y() < q.y() || (p.y() == q.y() && a < b)));
  };
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), less);
  auto ordered = [](std::size_t a, std::size_t b) { return EdgePair{std::min(a, b), std::max(a, b)}; };
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const std::size_t a = order[k], b = order[k + 1];
    if (poly[a] != poly[b]) continue;
    // A vertex repeated: a zero-length edge, or two edges that start at the same point.
    if ((a + 1) % n == b) return EdgePair{a, a};
    if ((b + 1) % n == a) return EdgePair{b, b};
    return ordered(a, b);
  }
  // Edge e runs from vertex e to vertex e + 1; its left end is the one first in the order.
  std::vector<std::uint32_t> rank(n);
  for (std::size_t k = 0; k < n; ++k) rank[order[k]] = static_cast<std::uint32_t>(k);
  auto leftEnd = [&](std::size_t e) { return rank[e] < rank[(e + 1) % n] ? e : (e + 1) % n; };
  auto rightEnd = [&](std::size_t e) { return rank[e] < rank[(e + 1) % n] ? (e + 1) % n : e; };

  std::optional<EdgePair> found;
  std::size_t inserting = n;  // the edge being inserted: every comparison is with it
  // Is edge s (being inserted at its left end p) below edge t, on the sweep line through p?
  auto below = [&](std::size_t s, std::size_t t) {
    const Vec2& p = poly[leftEnd(s)];
    int o = 0;
    if (leftEnd(t) == leftEnd(s)) {
      o = orientSign(p, poly[rightEnd(t)], poly[rightEnd(s)]);  // both start at p: by direction
    } else {
      o = orientSign(poly[leftEnd(t)], poly[rightEnd(t)], p);   // p's side of t
    }
    if (o == 0 && !found) found = ordered(s, t);  // p on t, or both leave p along one line
    return o < 0;
  };
  auto cmp = [&](std::uint32_t a, std::uint32_t b) {
    if (a == b) return false;
    if (a == inserting) return below(a, b);
    if (b == inserting) return !below(b, a);
    return a < b;  // never asked: only the new edge is compared
  };
  std::set<std::uint32_t, decltype(cmp)> status(cmp);
  std::vector<std::set<std::uint32_t, decltype(cmp)>::iterator> where(n, status.end());
  auto check = [&](std::size_t a, std::size_t b) {
    if (!found && edgesOffend(poly, std::min(a, b), std::max(a, b))) found = ordered(a, b);
  };
  for (const std::uint32_t v : order) {
    const std::size_t edges[2] = {(v + n - 1) % n, v};
    for (const std::size_t e : edges) {  // edges ending here leave the status first
      if (rightEnd(e) != v) continue;
      auto it = where[e];
      const bool has_below = it != status.begin();
      const auto above = std::next(it);
      if (has_below && above != status.end()) check(*std::prev(it), *above);
      status.erase(it);
      where[e] = status.end();
    }
    for (const std::size_t e : edges) {
      if (leftEnd(e) != v) continue;
      inserting = e;
      const auto it = status.insert(static_cast<std::uint32_t>(e)).first;
      inserting = n;
      where[e] = it;
      if (it != status.begin()) check(e, *std::prev(it));
      if (std::next(it) != status.end()) check(e, *std::next(it));
    }
    if (found) return found;
  }
  return std::nullopt;
}

}  // namespace

std::optional<EdgePair> findSelfIntersection(PolygonView poly) {
  const std::size_t n = poly.size();
  if (n < 3) return std::nullopt;
  // Small polygons: the grid would cost more than it saves.
  if (n <= 32) return findSelfIntersectionQuadratic(poly);
  const EdgeGrid grid(poly);
  // Without a grid that pays, the sweep decides in O(n log n) (a star's long spikes, a fine
  // outline crowded into a few cells): the pair it names offends, but may not be the first.
  if (!grid.fast()) return sweepSelfIntersection(poly);
  // The same pairs in the same order as the quadratic scan, less those whose boxes share no
  // cell (they cannot touch): the first offending pair is the same one.
  for (std::size_t i = 0; i < n; ++i) {
    if (poly[i] == poly[(i + 1) % n]) return EdgePair{i, i};
    std::size_t first = n;
    grid.forEachCellOf(i, [&](std::size_t c) {
      for (const std::uint32_t j : grid.cellEdges(c)) {
        if (j > i && j < first && edgesOffend(poly, i, j)) first = j;
      }
    });
    if (first < n) return EdgePair{i, first};
  }
  return std::nullopt;
}

std::optional<EdgePair> findSelfIntersectionSweep(PolygonView poly) {
  return poly.size() < 3 ? std::nullopt : sweepSelfIntersection(poly);
}

}  // namespace staa
