#pragma once
// Elementary polygon predicates and measures. None of them allocates.

#include "geometry/types.hpp"

#include <optional>

namespace staa {

// Shoelace area: positive for counter-clockwise winding.
double signedArea(PolygonView poly);
inline bool isCounterClockwise(PolygonView poly) { return signedArea(poly) > 0.0; }

Box boundingBox(PolygonView poly);

// Where a point lies relative to a polygon; the boundary is reported separately so that
// callers decide whether touching counts (a path may slide along a wall, a robot may not).
enum class Containment { kOutside, kBoundary, kInside };
Containment locatePoint(const Vec2& p, PolygonView poly, double eps = 1e-9);
// True for points strictly inside (boundary excluded).
inline bool pointInPolygon(const Vec2& p, PolygonView poly) {
  return locatePoint(p, poly) == Containment::kInside;
}

// Closed segments [a, b] and [c, d] share at least one point.
bool segmentsIntersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);
// The segments cross at a single point interior to both (no touching, no collinear overlap).
bool segmentsCrossProperly(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);
// Intersection point of the lines through [a,b] and [c,d] as the parameter along [a,b],
// if the closed segments intersect at a single point.
std::optional<double> segmentIntersectionParam(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);

Vec2 closestPointOnSegment(const Vec2& p, const Vec2& a, const Vec2& b);
double distancePointSegment(const Vec2& p, const Vec2& a, const Vec2& b);
// Distance from p to the nearest edge or vertex of the polygon (0 on the boundary; the
// same value inside and outside: the caller combines it with locatePoint when it matters).
double distanceToEdges(const Vec2& p, PolygonView poly);

// A simple polygon: no two non-adjacent edges touch, adjacent edges meet only at their shared
// vertex. Returns the first offending edge pair (i < j, smallest i, then smallest j; {i, i}
// for a zero-length edge i), or nullopt when simple. Load-time validation, not for the cycle:
// it allocates an edge grid, and tests only edge pairs whose boxes share a grid cell (about
// linear in n for real outlines). When the grid would not pay (more than 64 entries or 256
// cell pairs per edge: a star's spikes, a fine outline crowded into few cells of its box), a
// sweep (Shamos-Hoey) decides in O(n log n) instead; a pair it reports offends but need not
// be the first.
struct EdgePair {
  std::size_t first;
  std::size_t second;
};
std::optional<EdgePair> findSelfIntersection(PolygonView poly);
// The same answer by testing every pair, O(n^2): the tests' oracle.
std::optional<EdgePair> findSelfIntersectionQuadratic(PolygonView poly);
// The sweep alone, for any polygon: whether it is simple, and an offending pair if not.
std::optional<EdgePair> findSelfIntersectionSweep(PolygonView poly);

}  // namespace staa
