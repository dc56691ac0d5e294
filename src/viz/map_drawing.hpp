#pragma once
// Drawing a polygon map (and a path over it) on an SvgCanvas: obstacles dark grey, the
// inflated obstacles M' light and translucent beneath them, the bounds outlined, goals as
// small numbered markers, a path in a strong colour with its start and goal marked.

#include "map/polygon_map.hpp"
#include "viz/svg.hpp"

#include <optional>
#include <span>
#include <vector>

namespace staa {

// The world box a map is drawn over: its bounds, else the extent of its obstacles and goals
// with a 0.5 m border. Throws std::invalid_argument for a map with nothing to draw.
Box mapDrawingBox(const PolygonMap& map);

// The scale that draws the map about `target_px` wide or tall (whichever is longer),
// clamped to [1, 100] px per metre.
double autoScale(const Box& world, double target_px = 900.0);

// A canvas over mapDrawingBox(map) with room for a title above and the scale bar and legend
// below.
SvgCanvas makeMapCanvas(const PolygonMap& map, double px_per_m);

// Grid lines every metre (only when they are at least 8 px apart), the inflated obstacles
// (when given; clipped to the drawing box, since bounds walls extend beyond it), over them the
// passage map M'' (when given: the obstacles grown by the footprint's inscribed radius), the
// obstacles, the bounds and the goals numbered from 0 in the map's order.
void drawMap(SvgCanvas& canvas, const PolygonMap& map, const std::vector<Polygon>* inflated,
             const std::vector<Polygon>* passage = nullptr);

// A path as one polyline with round joins, then start and goal markers. `start` and `goal`
// are the requested points (drawn even when the path is empty, i.e. no path was found).
void drawPath(SvgCanvas& canvas, std::span<const Vec2> path, const Vec2& start, const Vec2& goal);

// The legend rows that match what drawMap and drawPath drew.
std::vector<LegendEntry> mapLegend(bool with_inflated, bool with_goals, bool with_path, bool with_passage = false);

}  // namespace staa
