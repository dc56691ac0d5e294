#pragma once
// Conservative simplification of big polygons (issue 18): fewer vertices, never less
// obstacle. A CAD export of a round room or an unsimplified import can give one polygon
// hundreds of thousands of vertices; Clipper's inflation and the visibility-graph search
// grow faster than linearly in them. The simplified outline S of a polygon P satisfies
//   P ⊆ S ⊆ P ⊕ tolerance
// (S contains P, and every point of S lies within `tolerance` of P), so a path that avoids
// S avoids P, and a path around S is at most a little longer than one around P. S is simple.
// Load-time only: allocates.

#include "geometry/types.hpp"

#include <cstddef>

namespace staa {

// The rule the planners' inflation applies (geometry/clipper_ops.hpp, inflatePolygons): a
// polygon of more than kSimplifyAboveVertices vertices is simplified within
// kSimplifyTolerance_m before it is inflated. Every polygon of the repository's and the
// imported ROS maps has at most 668 vertices (an import without --simplify), so their paths
// do not change. 2 cm is under a ROS map's resolution (3-5 cm), the local grid's cell (5 cm)
// and the inflation's own arc tolerance (3 cm); it fills the notches of a toothed ring of
// radius 5 m from about 1,600 vertices on (their mouths are 4 cm wide there; 1 cm would
// wait until 6,300 vertices, and the search takes seconds from 3,000 on).
inline constexpr std::size_t kSimplifyAboveVertices = 1000;
inline constexpr double kSimplifyTolerance_m = 0.02;

// S as above, counter-clockwise, for a simple polygon of either winding (a polygon that is
// not simple, or has fewer than 4 vertices, comes back unchanged). Greedy, smallest error
// first, O(n log n) for the shapes of the tests (see simplify.cpp for the steps).
Polygon simplifyOutward(PolygonView poly, double tolerance);

// Whether the rule applies: more than kSimplifyAboveVertices vertices.
inline bool isBigPolygon(PolygonView poly) { return poly.size() > kSimplifyAboveVertices; }

// simplifyOutward(poly, kSimplifyTolerance_m) for a big polygon, else the polygon as it is
// (a copy: callers that keep the original test isBigPolygon first).
Polygon simplifyIfBig(PolygonView poly);

}  // namespace staa
