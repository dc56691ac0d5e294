#pragma once
// Polygon union, offsetting (inflation) and hole removal through Clipper (libpolyclipping).
// Load-time only: these allocate freely and must never run inside the 30 Hz cycle.

#include "geometry/types.hpp"

#include <vector>

namespace staa {

// A region of the plane: one outer boundary (counter-clockwise) and its holes (clockwise).
struct PolygonWithHoles {
  Polygon outer;
  std::vector<Polygon> holes;
};

// Union of arbitrary simple polygons (either winding, may overlap), nonzero fill.
std::vector<PolygonWithHoles> unitePolygons(const std::vector<Polygon>& polygons);

// The area the polygons cover, overlaps counted once (unitePolygons' regions, outer areas less
// holes). A polygon whose box overlaps no other polygon's box counts its own area, without
// Clipper: Clipper 6's union grows with the square of a polygon's vertex count (a 20,000-
// vertex star took 0.2 s, 200,000 vertices 46 s); only groups of overlapping boxes are united.
double unionArea(const std::vector<Polygon>& polygons);

// The union of the polygons grown by `radius` metres (round corners whose chords stay within
// `arc_tolerance` of the true arc). A negative radius shrinks. Outer boundaries only grow, so
// a room whose door is narrower than 2 * radius becomes a hole. Growing (radius >= 0), a
// polygon of more than kSimplifyAboveVertices (1,000) vertices is first replaced by its
// outward simplification within kSimplifyTolerance_m (2 cm; geometry/simplify.hpp): the
// result then contains the polygon grown by the radius and lies within the radius plus 2 cm.
std::vector<PolygonWithHoles> inflatePolygons(const std::vector<Polygon>& polygons, double radius,
                                              double arc_tolerance = 0.01);

// Rewrites regions with holes as simple polygons without holes whose union is the same
// region: each hole is opened by cutting the region along a vertical line through it. The
// pieces on either side of a cut overlap by `overlap` metres, so no zero-width seam is left
// for a path to slip through.
std::vector<Polygon> removeHoles(const std::vector<PolygonWithHoles>& regions, double overlap = 1e-3);

// Convenience: inflatePolygons followed by removeHoles; the form the path planner takes (M').
std::vector<Polygon> inflateToSimple(const std::vector<Polygon>& polygons, double radius,
                                     double arc_tolerance = 0.01);

// Inflates every polygon on its own (no union), each result made simple by removeHoles. The
// pieces overlap where the inputs were close. Preferred for shortest-path search: a lazy
// visibility graph then discovers one small polygon at a time instead of a building-sized one.
std::vector<Polygon> inflateEachToSimple(const std::vector<Polygon>& polygons, double radius,
                                         double arc_tolerance = 0.01);

}  // namespace staa
