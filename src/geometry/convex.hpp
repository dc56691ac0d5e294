#pragma once
// Convex hulls and the polygon-polygon collision tests of the cycle (the robot footprint
// against obstacles and moving obstacles at each predicted pose).
//
// Which convex test the cycle uses: our SAT (convexIntersect below). It is the fastest on the
// cycle's pairs and the only exact one. bench_geometry, footprint quad vs 0.5 m square or
// ~0.4 m octagon, median CPU ns per call over 5 repetitions (Release, shared 2-core x86-64):
//                 colliding   near   far   mix
//   SAT               87       56     14    49
//   libccd GJK       187      147     36   129
//   libccd MPR       163      130     40   114
// Exactness (test_convex, 5,825 random pairs, 1,669 within 1 um of contact): SAT and GJK
// match the exact answer beyond 1e-9 m; MPR calls 7 separated pairs (up to 0.75 mm apart,
// sliver shapes) intersecting; at an exact contact GJK and MPR answer either way.
// (build/geom/tests/bench/bench_geometry --benchmark_repetitions=5
//  --benchmark_report_aggregates_only=true)
//
// Convention for every test here: touching counts as intersecting. A robot whose footprint
// touches a wall is in collision; a conservative answer on the boundary is the safe one.
// Either winding is accepted. None of the tests below allocates or throws.

#include "geometry/types.hpp"

#include <cstddef>

namespace staa {

// ---- hulls (Andrew's monotone chain) ----

// Counter-clockwise convex hull without collinear or repeated vertices. Degenerate sets give
// degenerate hulls: no points -> empty, all points equal -> 1 vertex, all collinear -> the 2
// end points. Allocates: for load time and tools.
Polygon convexHull(std::span<const Vec2> points);

// The same without allocating: sorts `points` in place (and drops duplicates among them)
// and writes the hull into `out`. Returns the hull's vertex count, or 0 when out.size() <
// points.size() + 1 (the chain needs that much working room; nothing is written then).
std::size_t convexHullInPlace(std::span<Vec2> points, std::span<Vec2> out);

// True for a simple convex polygon of either winding with non-zero area. Collinear and
// repeated consecutive vertices are allowed; a fold-back or a second winding (a star) is not.
bool isConvex(PolygonView poly);

// ---- convex-convex intersection (both inputs convex; behaviour is undefined otherwise) ----
//
// Degenerate inputs are defined: an empty polygon intersects nothing; a polygon of 1 vertex
// is a point, of collinear vertices a segment, and these intersect whatever they touch.

// Our 2-D Separating Axis Theorem: the polygons are disjoint iff their projections on some
// edge normal are disjoint. Exact comparisons, normals unnormalised (no division, no sqrt).
bool convexIntersectSat(PolygonView a, PolygonView b);

// libccd's GJK and MPR on the polygons lifted to prisms z in [-h, h] (a flat polygon would
// make the 3-D simplex degenerate), in millimetres. The views travel through libccd's void*
// object pointer, so nothing is copied or allocated. An exact contact may be reported either
// way; MPR also rarely reports near-miss slivers as intersecting (never the reverse, tested).
bool convexIntersectGjk(PolygonView a, PolygonView b);
bool convexIntersectMpr(PolygonView a, PolygonView b);

// The test the cycle uses (see the decision at the top of this file).
bool convexIntersect(PolygonView a, PolygonView b);

// ---- non-convex pairs ----

// The paper's approximate test for non-convex polygons: true when a corner (vertex) of one
// lies inside or on (within 1e-9 m) the other. Misses pairs that cross without a corner
// inside, e.g. two thin bars forming a "+"; polygonsOverlap is the exact alternative.
bool cornerContainment(PolygonView a, PolygonView b);

// Exact overlap test for simple polygons of any shape: corner containment OR a pair of edges
// crossing or touching. O(n m); the same touching-counts convention as above.
bool polygonsOverlap(PolygonView a, PolygonView b);

}  // namespace staa
