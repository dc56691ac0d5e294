#pragma once
// Polygon measures the simulator shares between scenario checks and the world: the robot's
// footprint placed at a pose, and exact polygon-polygon distance.

#include "geometry/types.hpp"

namespace staa {

// The footprint's vertices (robot frame) mapped into the world frame at `pose`.
Polygon footprintAt(PolygonView footprint, const Pose2& pose);
// The same into a caller-owned polygon (resized to fit), so a loop reuses one buffer.
void footprintAt(PolygonView footprint, const Pose2& pose, Polygon& out);

// Exact distance between two simple polygons: 0 when they overlap or touch
// (polygonsOverlap), otherwise the smallest vertex-to-edge distance taken both ways.
double polygonDistance(PolygonView a, PolygonView b);

// Distance between two boxes (0 when they overlap): a lower bound of the distance between
// anything inside them, for pruning.
double boxDistance(const Box& a, const Box& b);

}  // namespace staa
