#pragma once
// A small SVG writer of our own: a canvas over a world box (metres, y up) drawn into pixels
// (y down), with the elements the tools and the simulator need: polygons, polylines, many
// segments in one <path>, circles and fixed-size markers, labels, pose arrows, a scale bar
// and a legend. Coordinates are rounded to 3 decimals so that frames with thousands of
// search-tree edges stay small. Tools only: it allocates freely, never use it in the cycle.

#include "geometry/types.hpp"

#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace staa {

// How an element looks. Empty strings and negative numbers are not emitted, so an element
// may take its look from a CSS class alone (SvgCanvas::addCss) or from inline attributes.
struct SvgStyle {
  std::string css_class;
  std::string fill;            // "none" for outlines only
  std::string stroke;
  double stroke_width_px = -1.0;
  double opacity = -1.0;
  double fill_opacity = -1.0;
  std::string dash;            // stroke-dasharray, in px, e.g. "4 2"
  std::string extra;           // further attributes as written, e.g. "stroke-linejoin=\"round\""
};

// Shorthands for the common looks.
SvgStyle svgFill(std::string fill, double fill_opacity = -1.0);
SvgStyle svgStroke(std::string stroke, double width_px, std::string dash = {});

struct SvgCanvasOptions {
  double px_per_m = 30.0;
  double margin_px = 20.0;      // on every side of the world box
  double header_px = 0.0;       // above the world box: room for a title
  double footer_px = 34.0;      // below the world box: room for the scale bar
  double side_panel_px = 0.0;   // right of the world box: room for a legend
  std::string background = "#ffffff";  // empty: transparent
  std::string font_family = "DejaVu Sans, Helvetica, Arial, sans-serif";
};

enum class TextAnchor { kStart, kMiddle, kEnd };

enum class LegendSymbol { kArea, kLine, kMarker };
struct LegendEntry {
  std::string label;
  SvgStyle style;
  LegendSymbol symbol = LegendSymbol::kArea;
};

class SvgCanvas {
 public:
  // `world` is the box that maps onto the drawing area; it must have a positive extent.
  SvgCanvas(const Box& world, const SvgCanvasOptions& options = {});

  double widthPx() const { return width_px_; }
  double heightPx() const { return height_px_; }
  const Box& world() const { return world_; }
  const SvgCanvasOptions& options() const { return options_; }

  // World (metres, y up) to pixels (y down): the world's min corner lands at the drawing
  // area's bottom-left, (margin, header + margin + height * scale).
  Vec2 toPixel(const Vec2& world) const;
  double toPixels(double metres) const { return metres * options_.px_per_m; }

  // A rule for the <style> block, e.g. ".obstacle{fill:#444}".
  void addCss(std::string_view css);

  // <g> with a style; `clip_to_world` clips its content to the world box.
  void beginGroup(const SvgStyle& style, bool clip_to_world = false);
  void endGroup();

  void polygon(PolygonView poly, const SvgStyle& style);
  // Many polygons as one <path>, each wound counter-clockwise so the nonzero fill draws their
  // union: overlaps are neither darker (translucent fills) nor seamed.
  void polygons(std::span<const Polygon> polys, const SvgStyle& style);
  void polyline(std::span<const Vec2> points, const SvgStyle& style);
  void line(const Vec2& a, const Vec2& b, const SvgStyle& style);
  // Many separate segments as one <path> (a search tree of short edges).
  void segments(std::span<const std::pair<Vec2, Vec2>> segs, const SvgStyle& style);
  void rect(const Box& box, const SvgStyle& style);
  // Many cells as one <path> (a collision grid).
  void rects(std::span<const Box> boxes, const SvgStyle& style);
  void circle(const Vec2& centre, double radius_m, const SvgStyle& style);
  // A circle whose size is in pixels, independent of the scale.
  void marker(const Vec2& centre, double radius_px, const SvgStyle& style);
  // A pose: a shaft of `length_m` from (x, y) along theta with a head sized in pixels.
  void arrow(const Pose2& pose, double length_m, const SvgStyle& style, double head_px = 7.0);
  // Text at a world point, shifted by (dx_px, dy_px) in pixels (dy down).
  void text(const Vec2& at, std::string_view label, double font_px = 11.0,
            TextAnchor anchor = TextAnchor::kStart, const SvgStyle& style = {}, double dx_px = 0.0,
            double dy_px = 0.0);
  // Text at a pixel position (titles, captions in the margins).
  void textPx(const Vec2& at_px, std::string_view label, double font_px = 11.0,
              TextAnchor anchor = TextAnchor::kStart, const SvgStyle& style = {});
  // A title in the header (or, without one, in the top margin), at the left edge.
  void title(std::string_view text, double font_px = 14.0);
  // A scale bar in the footer, at the drawing area's left edge: 1 m, or 5 m when 1 m would be
  // shorter than 40 px (0 picks so; a positive length is used as given).
  void scaleBar(double length_m = 0.0);
  // The legend in the side panel (or, without one, in the footer to the right of the scale
  // bar), one row per entry.
  void legend(std::span<const LegendEntry> entries);

  // The complete document.
  std::string str() const;
  // Writes str() to `path`; throws std::runtime_error naming the path when it cannot.
  void save(const std::filesystem::path& path) const;

 private:
  void open(std::string_view tag, const SvgStyle& style);
  void point(const Vec2& world);      // "x,y" in pixels
  void pathData(PolygonView poly, bool close, bool ccw);
  void pixelNumber(double v);

  Box world_;
  SvgCanvasOptions options_;
  double width_px_ = 0.0;
  double height_px_ = 0.0;
  std::string css_;
  std::string body_;
  bool uses_world_clip_ = false;
  double footer_cursor_px_ = 0.0;  // where the next footer item (the legend) may start
  int open_groups_ = 0;
};

// A number rounded to 3 decimals without trailing zeros ("12.5", "-0.125", "3").
std::string svgNumber(double v);
// Text with &, <, >, " and ' escaped for SVG content and attributes.
std::string svgEscape(std::string_view text);

}  // namespace staa
