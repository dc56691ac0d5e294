#pragma once
// A brute-force shortest path among polygons, independent of the library's own predicates:
// the complete visibility graph over every convex corner in free space, each edge decided by
// splitting the segment at every boundary contact and testing each piece's midpoint for
// strict containment, then Dijkstra. O(n^2) edges: for property tests only. Compiled in its
// own library (staa_test_reference) with the libraries' optimisation, not the test files'
// (STAA_TEST_CXX_FLAGS): at -O0 under ASan it made one property test take minutes.

#include "geometry/polygon.hpp"

#include <optional>
#include <vector>

namespace staa::test {

// Whether the open segment a-b stays out of every polygon's interior.
bool referenceSegmentFree(const Vec2& a, const Vec2& b, const std::vector<Polygon>& polys);

// Whether p lies outside every polygon's interior.
bool referencePointFree(const Vec2& p, const std::vector<Polygon>& polys);

// Length of the shortest path, or nullopt when none exists. Start and goal must be free.
std::optional<double> referenceShortestPath(const Vec2& start, const Vec2& goal, const std::vector<Polygon>& polys);

}  // namespace staa::test
