#pragma once
// Polygon clipping to an axis-aligned box and rigid transforms, without allocating: both run
// in the cycle (obstacles cut to the local window, the footprint placed at a predicted pose).

#include "geometry/types.hpp"

#include <cstddef>

namespace staa {

// Outcome of writing a polygon into a caller-provided fixed-capacity span. When the span is
// too small, ok is false, size is 0 and nothing is written past the span's end.
struct FixedResult {
  bool ok = true;
  std::size_t size = 0;
};

// Sutherland-Hodgman clipping of `in` (either winding, may be non-convex) to the closed box.
// The result goes to `out`; `scratch` holds the intermediate stages; neither may alias `in`.
// For a convex input in.size() + 4 vertices of each suffice; a non-convex one gains a vertex
// per boundary crossing, so size both for the worst input expected (on overflow: ok false).
// A result with fewer than 3 vertices means nothing of `in` has area inside the box.
//
// On a non-convex input whose inside parts the box cuts apart, the output is one polygon with
// zero-width bridges running along the box edges between the parts. The bridges have no area,
// so the area (and point-in-polygon away from the box edges) is still right, but the output
// is not simple.
FixedResult clipToBox(PolygonView in, const Box& box, std::span<Vec2> out, std::span<Vec2> scratch);

// Writes `in` mapped from the pose's frame into the parent frame (Pose2::transform) to `out`.
// Needs out.size() >= in.size(); `out` may be the same memory as `in`.
FixedResult transformPolygon(PolygonView in, const Pose2& pose, std::span<Vec2> out);

}  // namespace staa
