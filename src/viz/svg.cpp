#include "viz/svg.hpp"

#include "geometry/polygon.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace staa {

std::string svgNumber(double v) {
  if (!std::isfinite(v)) v = 0.0;
  std::array<char, 64> buf{};
  auto [end, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), v, std::chars_format::fixed, 3);
  if (ec != std::errc{}) return "0";
  std::string s(buf.data(), end);
  // Trim "12.500" to "12.5" and "3.000" to "3"; "-0" (a tiny negative) to "0".
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

std::string svgEscape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

SvgStyle svgFill(std::string fill, double fill_opacity) {
  SvgStyle s;
  s.fill = std::move(fill);
  s.stroke = "none";
  s.fill_opacity = fill_opacity;
  return s;
}

SvgStyle svgStroke(std::string stroke, double width_px, std::string dash) {
  SvgStyle s;
  s.fill = "none";
  s.stroke = std::move(stroke);
  s.stroke_width_px = width_px;
  s.dash = std::move(dash);
  return s;
}

SvgCanvas::SvgCanvas(const Box& world, const SvgCanvasOptions& options) : world_(world), options_(options) {
  if (!(world.width() > 0.0) || !(world.height() > 0.0) || !std::isfinite(world.width()) ||
      !std::isfinite(world.height())) {
    throw std::invalid_argument("SvgCanvas: the world box must have a positive, finite extent");
  }
  if (!(options.px_per_m > 0.0) || !std::isfinite(options.px_per_m)) {
    throw std::invalid_argument("SvgCanvas: px_per_m must be positive, got " + svgNumber(options.px_per_m));
  }
  width_px_ = 2.0 * options_.margin_px + toPixels(world.width()) + options_.side_panel_px;
  height_px_ = 2.0 * options_.margin_px + options_.header_px + toPixels(world.height()) + options_.footer_px;
}

Vec2 SvgCanvas::toPixel(const Vec2& w) const {
  return {options_.margin_px + (w.x() - world_.min.x()) * options_.px_per_m,
          options_.margin_px + options_.header_px + (world_.max.y() - w.y()) * options_.px_per_m};
}

void SvgCanvas::addCss(std::string_view css) {
  css_ += css;
  css_ += '\n';
}

void SvgCanvas::pixelNumber(double v) { body_ += svgNumber(v); }

void SvgCanvas::point(const Vec2& w) {
  const Vec2 p = toPixel(w);
  pixelNumber(p.x());
  body_ += ',';
  pixelNumber(p.y());
}

void SvgCanvas::open(std::string_view tag, const SvgStyle& s) {
  body_ += '<';
  body_ += tag;
  auto attr = [this](std::string_view name, const std::string& value) {
    if (value.empty()) return;
    body_ += ' ';
    body_ += name;
    body_ += "=\"";
    body_ += svgEscape(value);
    body_ += '"';
  };
  auto num = [this](std::string_view name, double value) {
    if (value < 0.0) return;
    body_ += ' ';
    body_ += name;
    body_ += "=\"";
    body_ += svgNumber(value);
    body_ += '"';
  };
  attr("class", s.css_class);
  attr("fill", s.fill);
  attr("stroke", s.stroke);
  num("stroke-width", s.stroke_width_px);
  num("opacity", s.opacity);
  num("fill-opacity", s.fill_opacity);
  attr("stroke-dasharray", s.dash);
  if (!s.extra.empty()) {
    body_ += ' ';
    body_ += s.extra;
  }
}

void SvgCanvas::beginGroup(const SvgStyle& style, bool clip_to_world) {
  open("g", style);
  if (clip_to_world) {
    body_ += " clip-path=\"url(#world)\"";
    uses_world_clip_ = true;
  }
  body_ += ">\n";
  ++open_groups_;
}

void SvgCanvas::endGroup() {
  if (open_groups_ == 0) return;
  body_ += "</g>\n";
  --open_groups_;
}

void SvgCanvas::pathData(PolygonView poly, bool close, bool ccw) {
  const std::size_t n = poly.size();
  for (std::size_t k = 0; k < n; ++k) {
    body_ += k == 0 ? "M" : (k == 1 ? "L" : " ");
    point(poly[ccw ? k : n - 1 - k]);
  }
  if (close) body_ += 'Z';
}

void SvgCanvas::polygon(PolygonView poly, const SvgStyle& style) {
  if (poly.empty()) return;
  open("polygon", style);
  body_ += " points=\"";
  for (std::size_t k = 0; k < poly.size(); ++k) {
    if (k > 0) body_ += ' ';
    point(poly[k]);
  }
  body_ += "\"/>\n";
}

void SvgCanvas::polygons(std::span<const Polygon> polys, const SvgStyle& style) {
  if (polys.empty()) return;
  open("path", style);
  body_ += " d=\"";
  for (const Polygon& p : polys) {
    if (p.size() < 3) continue;
    // Pixel y points down, so a world CCW polygon turns clockwise on screen; what matters for
    // the nonzero rule is only that every polygon turns the same way.
    pathData(p, true, signedArea(p) >= 0.0);
  }
  body_ += "\"/>\n";
}

void SvgCanvas::polyline(std::span<const Vec2> points, const SvgStyle& style) {
  if (points.empty()) return;
  open("polyline", style);
  body_ += " points=\"";
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (k > 0) body_ += ' ';
    point(points[k]);
  }
  body_ += "\"/>\n";
}

void SvgCanvas::line(const Vec2& a, const Vec2& b, const SvgStyle& style) {
  const Vec2 pa = toPixel(a), pb = toPixel(b);
  open("line", style);
  body_ += " x1=\"" + svgNumber(pa.x()) + "\" y1=\"" + svgNumber(pa.y()) + "\" x2=\"" + svgNumber(pb.x()) +
           "\" y2=\"" + svgNumber(pb.y()) + "\"/>\n";
}

void SvgCanvas::segments(std::span<const std::pair<Vec2, Vec2>> segs, const SvgStyle& style) {
  if (segs.empty()) return;
  open("path", style);
  body_ += " d=\"";
  for (const auto& [a, b] : segs) {
    body_ += 'M';
    point(a);
    body_ += 'L';
    point(b);
  }
  body_ += "\"/>\n";
}

void SvgCanvas::rect(const Box& box, const SvgStyle& style) {
  const Vec2 top_left = toPixel({box.min.x(), box.max.y()});
  open("rect", style);
  body_ += " x=\"" + svgNumber(top_left.x()) + "\" y=\"" + svgNumber(top_left.y()) + "\" width=\"" +
           svgNumber(toPixels(box.width())) + "\" height=\"" + svgNumber(toPixels(box.height())) + "\"/>\n";
}

void SvgCanvas::rects(std::span<const Box> boxes, const SvgStyle& style) {
  if (boxes.empty()) return;
  open("path", style);
  body_ += " d=\"";
  for (const Box& b : boxes) {
    body_ += 'M';
    point({b.min.x(), b.max.y()});
    const std::string w = svgNumber(toPixels(b.width())), h = svgNumber(toPixels(b.height()));
    body_ += 'h' + w + 'v' + h + "h-" + w + 'Z';
  }
  body_ += "\"/>\n";
}

void SvgCanvas::circle(const Vec2& centre, double radius_m, const SvgStyle& style) {
  marker(centre, toPixels(radius_m), style);
}

void SvgCanvas::marker(const Vec2& centre, double radius_px, const SvgStyle& style) {
  const Vec2 p = toPixel(centre);
  open("circle", style);
  body_ += " cx=\"" + svgNumber(p.x()) + "\" cy=\"" + svgNumber(p.y()) + "\" r=\"" + svgNumber(radius_px) + "\"/>\n";
}

void SvgCanvas::arrow(const Pose2& pose, double length_m, const SvgStyle& style, double head_px) {
  const Vec2 base = toPixel(pose.position());
  const Vec2 dir{std::cos(pose.theta), -std::sin(pose.theta)};  // y flips on screen
  const Vec2 normal{-dir.y(), dir.x()};
  const Vec2 tip = base + dir * toPixels(length_m);
  const Vec2 neck = tip - dir * head_px;
  const std::string& colour = !style.stroke.empty() && style.stroke != "none" ? style.stroke
                              : !style.fill.empty()                           ? style.fill
                                                                              : std::string("#000");
  auto xy = [](const Vec2& p) { return svgNumber(p.x()) + ',' + svgNumber(p.y()); };
  open("g", style);
  body_ += "><path fill=\"none\" d=\"M" + xy(base) + 'L' + xy(neck + dir * (0.3 * head_px)) + "\"/>";
  const Vec2 left = neck + normal * (0.5 * head_px), right = neck - normal * (0.5 * head_px);
  body_ += "<path stroke=\"none\" fill=\"" + svgEscape(colour) + "\" d=\"M" + xy(tip) + 'L' + xy(left) + ' ' +
           xy(right) + "Z\"/></g>\n";
}

void SvgCanvas::text(const Vec2& at, std::string_view label, double font_px, TextAnchor anchor, const SvgStyle& style,
                     double dx_px, double dy_px) {
  textPx(toPixel(at) + Vec2{dx_px, dy_px}, label, font_px, anchor, style);
}

void SvgCanvas::textPx(const Vec2& at_px, std::string_view label, double font_px, TextAnchor anchor,
                       const SvgStyle& style) {
  open("text", style);
  body_ += " x=\"" + svgNumber(at_px.x()) + "\" y=\"" + svgNumber(at_px.y()) + "\" font-size=\"" +
           svgNumber(font_px) + '"';
  if (anchor == TextAnchor::kMiddle) body_ += " text-anchor=\"middle\"";
  if (anchor == TextAnchor::kEnd) body_ += " text-anchor=\"end\"";
  body_ += '>';
  body_ += svgEscape(label);
  body_ += "</text>\n";
}

void SvgCanvas::title(std::string_view text, double font_px) {
  const double baseline = options_.header_px > 0.0 ? options_.margin_px + 0.5 * options_.header_px + 0.35 * font_px
                                                   : 0.5 * options_.margin_px + 0.35 * font_px;
  SvgStyle style;
  style.fill = "#222";
  style.extra = "font-weight=\"bold\"";
  textPx({options_.margin_px, baseline}, text, font_px, TextAnchor::kStart, style);
}

void SvgCanvas::scaleBar(double length_m) {
  if (!(length_m > 0.0)) {
    length_m = 1.0;
    for (const double l : {1.0, 5.0, 10.0, 50.0, 100.0, 500.0}) {
      length_m = l;
      if (toPixels(l) >= 40.0) break;
    }
  }
  const double len = toPixels(length_m);
  const double x0 = options_.margin_px;
  const double y = options_.margin_px + options_.header_px + toPixels(world_.height()) + 0.5 * options_.margin_px + 8.0;
  auto n = [](double v) { return svgNumber(v); };
  // A bar with end ticks, half black and half white like a surveyor's bar.
  body_ += "<g class=\"scale-bar\"><rect x=\"" + n(x0) + "\" y=\"" + n(y - 3) + "\" width=\"" + n(len) +
           "\" height=\"6\" fill=\"#fff\" stroke=\"#222\" stroke-width=\"1\"/><rect x=\"" + n(x0) + "\" y=\"" +
           n(y - 3) + "\" width=\"" + n(0.5 * len) + "\" height=\"6\" fill=\"#222\"/>";
  body_ += "</g>\n";
  const std::string label = svgNumber(length_m) + " m";
  textPx({x0 + len + 6.0, y + 4.0}, label, 12.0);
  footer_cursor_px_ = x0 + len + 6.0 + 0.6 * 12.0 * static_cast<double>(label.size()) + 24.0;
}

void SvgCanvas::legend(std::span<const LegendEntry> entries) {
  const double font = 12.0;
  const bool panel = options_.side_panel_px > 0.0;
  Vec2 at = panel ? Vec2{2.0 * options_.margin_px + toPixels(world_.width()),
                         options_.margin_px + options_.header_px + 10.0}
                  : Vec2{std::max(options_.margin_px, footer_cursor_px_),
                         options_.margin_px + options_.header_px + toPixels(world_.height()) +
                             0.5 * options_.margin_px + 8.0};
  for (const LegendEntry& e : entries) {
    const double sx = at.x(), sy = at.y();
    switch (e.symbol) {
      case LegendSymbol::kArea:
        open("rect", e.style);
        body_ += " x=\"" + svgNumber(sx) + "\" y=\"" + svgNumber(sy - 6) + "\" width=\"16\" height=\"12\"/>\n";
        break;
      case LegendSymbol::kLine:
        open("path", e.style);
        body_ += " d=\"M" + svgNumber(sx) + ',' + svgNumber(sy) + "h16\"/>\n";
        break;
      case LegendSymbol::kMarker:
        open("circle", e.style);
        body_ += " cx=\"" + svgNumber(sx + 8) + "\" cy=\"" + svgNumber(sy) + "\" r=\"5\"/>\n";
        break;
    }
    textPx({sx + 22.0, sy + 4.0}, e.label, font);
    if (panel) {
      at.y() += 20.0;
    } else {
      // Roughly 0.6 em per character in a sans-serif face.
      at.x() += 22.0 + 0.6 * font * static_cast<double>(e.label.size()) + 16.0;
    }
  }
}

std::string SvgCanvas::str() const {
  const std::string w = svgNumber(width_px_), h = svgNumber(height_px_);
  std::string out;
  out.reserve(body_.size() + css_.size() + 512);
  out += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + w + "\" height=\"" + h + "\" viewBox=\"0 0 " + w +
         ' ' + h + "\" font-family=\"" + svgEscape(options_.font_family) + "\">\n";
  if (!css_.empty()) out += "<style>\n" + css_ + "</style>\n";
  if (uses_world_clip_) {
    const Vec2 tl = toPixel({world_.min.x(), world_.max.y()});
    out += "<defs><clipPath id=\"world\"><rect x=\"" + svgNumber(tl.x()) + "\" y=\"" + svgNumber(tl.y()) +
           "\" width=\"" + svgNumber(toPixels(world_.width())) + "\" height=\"" +
           svgNumber(toPixels(world_.height())) + "\"/></clipPath></defs>\n";
  }
  if (!options_.background.empty()) {
    out += "<rect width=\"100%\" height=\"100%\" fill=\"" + svgEscape(options_.background) + "\"/>\n";
  }
  out += body_;
  for (int k = 0; k < open_groups_; ++k) out += "</g>\n";
  out += "</svg>\n";
  return out;
}

void SvgCanvas::save(const std::filesystem::path& path) const {
  const std::string doc = str();
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) {
    throw std::runtime_error("cannot write SVG file '" + path.string() + "': " + std::strerror(errno));
  }
  file.write(doc.data(), static_cast<std::streamsize>(doc.size()));
  file.close();
  if (!file) throw std::runtime_error("cannot write SVG file '" + path.string() + "': write failed");
}

}  // namespace staa
