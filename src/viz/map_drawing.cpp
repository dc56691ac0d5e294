#include "viz/map_drawing.hpp"

#include "geometry/polygon.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace staa {
namespace {

// One palette for every map picture, so the README, the tools and the simulator agree.
constexpr const char* kObstacle = "#3d3d3d";
constexpr const char* kInflated = "#7fa7d9";
constexpr double kInflatedOpacity = 0.45;
constexpr const char* kPassage = "#3b6fb0";
constexpr double kPassageOpacity = 0.5;
constexpr const char* kGrid = "#e6e6e6";
constexpr const char* kBounds = "#1f1f1f";
constexpr const char* kGoal = "#2b8a3e";
constexpr const char* kPath = "#e8590c";
constexpr const char* kStart = "#1971c2";
constexpr const char* kEnd = "#c92a2a";

SvgStyle goalStyle() {
  SvgStyle s = svgFill("#ffffff");
  s.stroke = kGoal;
  s.stroke_width_px = 1.2;
  return s;
}

SvgStyle endpointStyle(const char* colour) {
  SvgStyle s = svgFill(colour);
  s.stroke = "#ffffff";
  s.stroke_width_px = 2.0;
  return s;
}

}  // namespace

Box mapDrawingBox(const PolygonMap& map) {
  if (map.bounds) return *map.bounds;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Box box{{kInf, kInf}, {-kInf, -kInf}};
  auto grow = [&box](const Vec2& p) {
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  };
  for (const Polygon& p : map.obstacles) {
    for (const Vec2& v : p) grow(v);
  }
  for (const Vec2& g : map.goals) grow(g);
  if (!(box.min.x() <= box.max.x())) {
    throw std::invalid_argument("map '" + map.name + "' has no bounds, obstacles or goals to draw");
  }
  box.min -= Vec2{0.5, 0.5};
  box.max += Vec2{0.5, 0.5};
  return box;
}

double autoScale(const Box& world, double target_px) {
  const double longest = std::max(world.width(), world.height());
  if (!(longest > 0.0)) return 30.0;
  return std::clamp(target_px / longest, 1.0, 100.0);
}

SvgCanvas makeMapCanvas(const PolygonMap& map, double px_per_m) {
  SvgCanvasOptions options;
  options.px_per_m = px_per_m;
  options.margin_px = 16.0;
  options.header_px = 22.0;
  options.footer_px = 30.0;
  return SvgCanvas(mapDrawingBox(map), options);
}

void drawMap(SvgCanvas& canvas, const PolygonMap& map, const std::vector<Polygon>* inflated,
             const std::vector<Polygon>* passage) {
  const Box& world = canvas.world();

  // Metre grid: a quiet reference for reading positions off the picture.
  if (canvas.toPixels(1.0) >= 8.0) {
    std::vector<std::pair<Vec2, Vec2>> lines;
    for (double x = std::ceil(world.min.x()); x <= world.max.x(); x += 1.0) {
      lines.push_back({{x, world.min.y()}, {x, world.max.y()}});
    }
    for (double y = std::ceil(world.min.y()); y <= world.max.y(); y += 1.0) {
      lines.push_back({{world.min.x(), y}, {world.max.x(), y}});
    }
    canvas.segments(lines, svgStroke(kGrid, 0.6));
  }

  if (inflated != nullptr && !inflated->empty()) {
    canvas.beginGroup({}, /*clip_to_world=*/true);
    canvas.polygons(*inflated, svgFill(kInflated, kInflatedOpacity));
    canvas.endGroup();
  }
  if (passage != nullptr && !passage->empty()) {
    canvas.beginGroup({}, /*clip_to_world=*/true);
    canvas.polygons(*passage, svgFill(kPassage, kPassageOpacity));
    canvas.endGroup();
  }

  SvgStyle obstacle = svgFill(kObstacle);
  canvas.polygons(map.obstacles, obstacle);

  if (map.bounds) canvas.rect(*map.bounds, svgStroke(kBounds, 1.5));

  // Goals: numbered rings, sized to the scale but readable at any zoom.
  const double r = std::clamp(canvas.toPixels(0.26), 5.0, 9.0);
  SvgStyle label;
  label.fill = kGoal;
  label.extra = "font-weight=\"bold\"";
  for (std::size_t k = 0; k < map.goals.size(); ++k) {
    canvas.marker(map.goals[k], r, goalStyle());
    canvas.text(map.goals[k], std::to_string(k), 0.9 * r, TextAnchor::kMiddle, label, 0.0, 0.32 * r);
  }
}

void drawPath(SvgCanvas& canvas, std::span<const Vec2> path, const Vec2& start, const Vec2& goal) {
  if (path.size() >= 2) {
    SvgStyle halo = svgStroke("#ffffff", 6.0);
    halo.extra = "stroke-linejoin=\"round\" stroke-linecap=\"round\"";
    halo.opacity = 0.8;
    canvas.polyline(path, halo);
    SvgStyle line = svgStroke(kPath, 3.2);
    line.extra = "stroke-linejoin=\"round\" stroke-linecap=\"round\"";
    canvas.polyline(path, line);
  }
  canvas.marker(start, 7.0, endpointStyle(kStart));
  canvas.marker(goal, 7.0, endpointStyle(kEnd));
}

std::vector<LegendEntry> mapLegend(bool with_inflated, bool with_goals, bool with_path, bool with_passage) {
  std::vector<LegendEntry> rows;
  rows.push_back({"obstacle", svgFill(kObstacle), LegendSymbol::kArea});
  if (with_inflated) rows.push_back({"inflated", svgFill(kInflated, kInflatedOpacity), LegendSymbol::kArea});
  if (with_passage) rows.push_back({"passage map", svgFill(kPassage, kPassageOpacity), LegendSymbol::kArea});
  if (with_goals) rows.push_back({"goal (index)", goalStyle(), LegendSymbol::kMarker});
  if (with_path) {
    rows.push_back({"path", svgStroke(kPath, 3.2), LegendSymbol::kLine});
    rows.push_back({"from", endpointStyle(kStart), LegendSymbol::kMarker});
    rows.push_back({"to", endpointStyle(kEnd), LegendSymbol::kMarker});
  }
  return rows;
}

}  // namespace staa
