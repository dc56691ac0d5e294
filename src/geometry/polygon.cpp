#include "geometry/polygon.hpp"

#include "geometry/predicates.hpp"

#include <algorithm>
#include <limits>

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

std::optional<EdgePair> findSelfIntersection(PolygonView poly) {
  const std::size_t n = poly.size();
  if (n < 3) return std::nullopt;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[(i + 1) % n];
    if (a == b) return EdgePair{i, i};  // zero-length edge: a repeated vertex
    for (std::size_t j = i + 1; j < n; ++j) {
      const Vec2& c = poly[j];
      const Vec2& d = poly[(j + 1) % n];
      const bool adjacent_next = (j == i + 1);
      const bool adjacent_prev = (i == 0 && j == n - 1);
      if (adjacent_next || adjacent_prev) {
        // Adjacent edges share one vertex; they must not fold back over each other.
        const Vec2& shared = adjacent_next ? b : a;
        const Vec2& p = adjacent_next ? a : b;  // the other end of edge i
        const Vec2& q = adjacent_next ? d : c;  // the other end of edge j
        if (n == 3) continue;                   // a triangle's edges are all adjacent
        if (orientSign(shared, p, q) == 0 && (p - shared).dot(q - shared) > 0.0) return EdgePair{i, j};
        continue;
      }
      if (segmentsIntersect(a, b, c, d)) return EdgePair{i, j};
    }
  }
  return std::nullopt;
}

}  // namespace staa
