#include "experiment/experiment_plots.hpp"

#include "viz/svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <system_error>

namespace staa {
namespace {

namespace fs = std::filesystem;

// The figure in layout units (1 unit = one bar's width): each panel is a plot box of
// kPlotH units high, with room for the y ticks on its left, its title above and the agent
// labels below. Values map into the box per panel (y = score scaled), since the canvas has
// one scale for both axes. Widths that depend on text (tick labels, titles, legend) are
// estimated from the character count: kCharEm font sizes per character, kBoldCharEm for
// bold headings (DejaVu Sans bold runs wider), so that nothing overlaps whatever the number
// of maps and agent counts.
constexpr double kPxPerUnit = 16.0;
constexpr double kPlotH = 10.0;
constexpr double kRight = 1.0;
constexpr double kBelow = 2.2;   // group labels
constexpr double kAbove = 2.2;   // panel title
constexpr double kCharEm = 0.6;
constexpr double kBoldCharEm = 0.66;
constexpr double kTitleFont = 15.0;
constexpr double kHeadingFont = 12.0;
constexpr double kTickFont = 10.0;
constexpr double kLabelFont = 11.0;
constexpr double kHeadingGapPx = 14.0;  // least space between two panel titles
constexpr double kMinFigurePx = 480.0;  // below this a long figure title wraps instead

struct Series {
  std::string label;
  std::string colour;
};

struct Bar {
  bool present = false;
  double goals = 0.0;
  double collisions = 0.0;
};

struct Figure {
  std::string title;
  std::vector<std::string> maps;   // columns
  std::vector<SimMode> modes;      // rows, cooperative above ghost
  std::vector<int> agents;         // groups in a panel
  std::vector<Series> series;      // bars in a group
  // bars[mode][map][agents][series]
  std::vector<std::vector<std::vector<std::vector<Bar>>>> bars;
};

template <class T>
std::size_t indexOf(const std::vector<T>& v, const T& x) {
  return static_cast<std::size_t>(std::find(v.begin(), v.end(), x) - v.begin());
}

// Maps, modes and agent counts of the cells that `seriesOf` keeps (>= 0: the series index).
template <class SeriesOf>
Figure layoutFigure(const std::vector<ExperimentCell>& cells, std::vector<Series> series, SeriesOf seriesOf) {
  Figure f;
  f.series = std::move(series);
  for (const ExperimentCell& c : cells) {
    if (seriesOf(c) < 0) continue;
    if (indexOf(f.maps, c.map) == f.maps.size()) f.maps.push_back(c.map);
    if (indexOf(f.modes, c.mode) == f.modes.size()) f.modes.push_back(c.mode);
    if (indexOf(f.agents, c.agents) == f.agents.size()) f.agents.push_back(c.agents);
  }
  std::sort(f.modes.begin(), f.modes.end());  // kCooperative first: the paper's upper row
  std::sort(f.agents.begin(), f.agents.end());
  f.bars.assign(f.modes.size(),
                std::vector<std::vector<std::vector<Bar>>>(
                    f.maps.size(), std::vector<std::vector<Bar>>(f.agents.size(), std::vector<Bar>(f.series.size()))));
  for (const ExperimentCell& c : cells) {
    const int s = seriesOf(c);
    if (s < 0) continue;
    Bar& b = f.bars[indexOf(f.modes, c.mode)][indexOf(f.maps, c.map)][indexOf(f.agents, c.agents)]
                   [static_cast<std::size_t>(s)];
    b.present = true;
    b.goals = c.goals.mean;
    b.collisions = c.collisions.mean;
  }
  return f;
}

// A tick step of 1, 2 or 5 times a power of ten giving at most about five intervals.
double tickStep(double span) {
  const double raw = span / 5.0;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10.0 * p;
}

std::string capitalized(std::string s) {
  if (!s.empty() && s[0] >= 'a' && s[0] <= 'z') s[0] = static_cast<char>(s[0] - 'a' + 'A');
  return s;
}

// Characters as drawn (UTF-8 code points: the em dash of the panel titles is one).
double glyphs(std::string_view text) {
  double n = 0.0;
  for (const char c : text) n += (static_cast<unsigned char>(c) & 0xC0) != 0x80 ? 1.0 : 0.0;
  return n;
}

double textWidthPx(std::string_view text, double font_px, double em = kCharEm) { return em * font_px * glyphs(text); }

// Splits `text` into lines of at most `max_px`: at "; " where a line breaks anyway (the
// title's clauses stay whole), else at spaces (a word longer than a line keeps one of its own).
std::vector<std::string> wrapText(const std::string& text, double font_px, double em, double max_px) {
  if (textWidthPx(text, font_px, em) <= max_px) return {text};
  const std::size_t clause = text.find("; ");
  if (clause != std::string::npos) {
    std::vector<std::string> lines = wrapText(text.substr(0, clause + 1), font_px, em, max_px);
    for (std::string& rest : wrapText(text.substr(clause + 2), font_px, em, max_px)) lines.push_back(std::move(rest));
    return lines;
  }
  std::vector<std::string> lines;
  std::string line;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find(' ', pos);
    if (end == std::string::npos) end = text.size();
    const std::string word = text.substr(pos, end - pos);
    std::string candidate = line;
    if (!candidate.empty()) candidate.push_back(' ');
    candidate.append(word);
    if (!line.empty() && textWidthPx(candidate, font_px, em) > max_px) {
      lines.push_back(line);
      line = word;
    } else {
      line = std::move(candidate);
    }
    pos = end + 1;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

// One panel's value axis: 0 .. the tallest bar, extended down to a negative score.
struct Axis {
  double lo = 0.0;
  double hi = 1.0;
  double step = 1.0;
};

Axis panelAxis(const std::vector<std::vector<Bar>>& panel) {
  double vmax = 0.0, vmin = 0.0;
  for (const auto& group : panel) {
    for (const Bar& b : group) {
      if (!b.present) continue;
      vmax = std::max({vmax, b.goals, b.goals - b.collisions});
      vmin = std::min(vmin, b.goals - b.collisions);
    }
  }
  Axis a;
  a.step = tickStep(std::max(1.0, vmax - vmin));
  a.lo = std::floor(vmin / a.step) * a.step;
  a.hi = std::max(a.lo + a.step, std::ceil(vmax / a.step) * a.step);
  return a;
}

std::string groupLabel(int agents) { return std::to_string(agents) + (agents == 1 ? " agent" : " agents"); }

std::string panelTitle(const Figure& f, std::size_t row, std::size_t col) {
  return capitalized(f.maps[col]) + " \u2014 " + toString(f.modes[row]);
}

std::string renderFigure(const Figure& f) {
  const std::size_t n_cols = std::max<std::size_t>(1, f.maps.size());
  const std::size_t n_rows = std::max<std::size_t>(1, f.modes.size());
  const double groups = static_cast<double>(std::max<std::size_t>(1, f.agents.size()));
  const double n_series = static_cast<double>(f.series.size());
  const double cols = static_cast<double>(n_cols);
  const double rows = static_cast<double>(n_rows);

  std::vector<std::vector<Axis>> axes(f.modes.size(), std::vector<Axis>(f.maps.size()));
  double tick_px = 0.0;
  for (std::size_t row = 0; row < f.modes.size(); ++row) {
    for (std::size_t col = 0; col < f.maps.size(); ++col) {
      const Axis& a = axes[row][col] = panelAxis(f.bars[row][col]);
      for (double t = a.lo; t <= a.hi + 1e-9; t += a.step) {
        tick_px = std::max(tick_px, textWidthPx(svgNumber(t), kTickFont));
      }
    }
  }
  // Left of each plot box: the tick labels (4 px from the axis) and, in the first column, the
  // rotated axis label beside them.
  const double left = (4.0 + tick_px + 6.0 + kLabelFont + 8.0) / kPxPerUnit;

  // Each group fits its bars with a bar's gap and its "N agents" label.
  double label_px = 0.0;
  for (const int n : f.agents) label_px = std::max(label_px, textWidthPx(groupLabel(n), kLabelFont));
  const double min_group = std::max({n_series + 1.0, 4.0, (label_px + 8.0) / kPxPerUnit});
  double plot_w = groups * min_group + 1.0;

  // Panel titles are centred over their plot box: a pitch of the widest title plus a gap
  // keeps neighbours apart, and the first and last inside the figure.
  double heading_px = 0.0;
  for (std::size_t row = 0; row < f.modes.size(); ++row) {
    for (std::size_t col = 0; col < f.maps.size(); ++col) {
      heading_px = std::max(heading_px, textWidthPx(panelTitle(f, row, col), kHeadingFont, kBoldCharEm));
    }
  }
  plot_w = std::max({plot_w, (heading_px + kHeadingGapPx) / kPxPerUnit - left - kRight,
                     heading_px / kPxPerUnit - 2.0 * kRight + 0.5});
  double pitch_x = left + plot_w + kRight;
  const double pitch_y = kBelow + kPlotH + kAbove;

  SvgCanvasOptions options;
  options.px_per_m = kPxPerUnit;
  options.margin_px = 12.0;
  options.footer_px = 30.0;
  std::vector<LegendEntry> entries;
  for (const Series& s : f.series) entries.push_back({s.label, svgFill(s.colour), LegendSymbol::kArea});
  entries.push_back({"collisions (subtracted)", svgFill("#111"), LegendSymbol::kArea});
  // As SvgCanvas::legend lays out a footer row: symbol, label, gap.
  double legend_px = 0.0;
  for (const LegendEntry& e : entries) legend_px += 38.0 + textWidthPx(e.label, 12.0);

  // The figure is as wide as its panels, its legend or kMinFigurePx, whichever is widest; a
  // longer title wraps rather than stretching the panels.
  const double inner_px = std::max({cols * pitch_x * kPxPerUnit, legend_px, kMinFigurePx - 2.0 * options.margin_px});
  const std::vector<std::string> title = wrapText(f.title, kTitleFont, kBoldCharEm, inner_px);
  double title_px = 0.0;
  for (const std::string& line : title) title_px = std::max(title_px, textWidthPx(line, kTitleFont, kBoldCharEm));
  const double width_px = std::max(inner_px, title_px);
  if (width_px > cols * pitch_x * kPxPerUnit) {
    // Spread the panels over the width: wider plot boxes.
    pitch_x = width_px / kPxPerUnit / cols;
    plot_w = pitch_x - left - kRight;
  }
  // The groups evenly over the plot box (wider than they need when a title widened it).
  const double per_group = (plot_w - 1.0) / groups;
  const double line_px = 1.3 * kTitleFont;
  options.header_px = 8.0 + line_px * static_cast<double>(title.size());
  SvgCanvas canvas(Box{{0.0, 0.0}, {cols * pitch_x, rows * pitch_y}}, options);
  SvgStyle title_style;
  title_style.fill = "#222";
  title_style.extra = "font-weight=\"bold\"";
  for (std::size_t k = 0; k < title.size(); ++k) {
    canvas.textPx({options.margin_px, options.margin_px + kTitleFont + line_px * static_cast<double>(k)}, title[k],
                  kTitleFont, TextAnchor::kStart, title_style);
  }

  SvgStyle axis = svgStroke("#333", 1.0);
  SvgStyle grid = svgStroke("#ddd", 0.8);
  SvgStyle label;
  label.fill = "#333";
  SvgStyle heading = label;
  heading.extra = "font-weight=\"bold\"";
  SvgStyle black = svgFill("#111");
  black.css_class = "bar-collisions";

  for (std::size_t row = 0; row < f.modes.size(); ++row) {
    for (std::size_t col = 0; col < f.maps.size(); ++col) {
      const auto& panel = f.bars[row][col];
      const double x0 = static_cast<double>(col) * pitch_x + left;
      const double y0 = (rows - 1.0 - static_cast<double>(row)) * pitch_y + kBelow;
      const Axis& a = axes[row][col];
      auto y = [&](double v) { return y0 + (v - a.lo) / (a.hi - a.lo) * kPlotH; };

      for (double t = a.lo; t <= a.hi + 1e-9; t += a.step) {
        canvas.line({x0, y(t)}, {x0 + plot_w, y(t)}, grid);
        canvas.text({x0, y(t)}, svgNumber(t), kTickFont, TextAnchor::kEnd, label, -4.0, 3.5);
      }

      for (std::size_t g = 0; g < panel.size(); ++g) {
        const double gx = x0 + 0.5 + static_cast<double>(g) * per_group + 0.5 * (per_group - n_series);
        for (std::size_t s = 0; s < panel[g].size(); ++s) {
          const Bar& b = panel[g][s];
          if (!b.present) continue;
          const double bx = gx + static_cast<double>(s);
          const double score = b.goals - b.collisions;
          SvgStyle fill = svgFill(f.series[s].colour);
          fill.css_class = "bar-score";
          fill.extra = "data-goals=\"" + svgNumber(b.goals) + "\" data-collisions=\"" + svgNumber(b.collisions) + "\"";
          // Drawn also at zero height: every cell of the experiment has its element.
          canvas.rect(Box{{bx, y(std::min(0.0, score))}, {bx + 1.0, y(std::max(0.0, score))}}, fill);
          if (b.collisions > 0.0) {
            // On top of the score, up to the goals. A negative score's black part overlaps
            // its coloured part below zero: drawn narrower so that both stay visible.
            const double inset = score < 0.0 ? 0.25 : 0.0;
            canvas.rect(Box{{bx + inset, y(score)}, {bx + 1.0 - inset, y(b.goals)}}, black);
          }
        }
        canvas.text({gx + 0.5 * n_series, y0}, groupLabel(f.agents[g]), kLabelFont, TextAnchor::kMiddle, label, 0.0,
                    16.0);
      }
      canvas.line({x0, y(0.0)}, {x0 + plot_w, y(0.0)}, axis);
      canvas.line({x0, y0}, {x0, y0 + kPlotH}, axis);
      canvas.text({x0 + 0.5 * plot_w, y0 + kPlotH}, panelTitle(f, row, col), kHeadingFont, TextAnchor::kMiddle,
                  heading, 0.0, -12.0);
      if (col == 0) {
        // Beside the tick labels, clear of the longest one.
        const Vec2 p = canvas.toPixel({x0, y0 + 0.5 * kPlotH}) - Vec2{4.0 + tick_px + 6.0 + 0.2 * kLabelFont, 0.0};
        SvgStyle rotated = label;
        rotated.extra = "transform=\"rotate(-90 " + svgNumber(p.x()) + " " + svgNumber(p.y()) + ")\"";
        canvas.textPx(p, "score (mean)", kLabelFont, TextAnchor::kMiddle, rotated);
      }
    }
  }

  canvas.legend(entries);
  return canvas.str();
}

std::string runsNote(const std::vector<ExperimentCell>& cells) {
  int lo = 0, hi = 0;
  for (const ExperimentCell& c : cells) {
    lo = lo == 0 ? c.runs : std::min(lo, c.runs);
    hi = std::max(hi, c.runs);
  }
  return lo == hi ? std::to_string(hi) + (hi == 1 ? " run" : " runs") : std::to_string(lo) + "-" + std::to_string(hi) + " runs";
}

std::optional<fs::path> findOnPath(std::string_view program) {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return std::nullopt;
  std::string_view rest(path);
  while (!rest.empty()) {
    const std::size_t colon = rest.find(':');
    const std::string_view dir = rest.substr(0, colon);
    rest = colon == std::string_view::npos ? std::string_view() : rest.substr(colon + 1);
    if (dir.empty()) continue;
    std::error_code ec;
    const fs::path candidate = fs::path(dir) / program;
    if (fs::is_regular_file(candidate, ec)) return candidate;
  }
  return std::nullopt;
}

// 'text' for /bin/sh, with embedded single quotes closed, escaped and reopened.
std::string shellQuoted(const std::string& text) {
  std::string q = "'";
  for (const char c : text) {
    if (c == '\'') {
      q += "'\\''";
    } else {
      q += c;
    }
  }
  return q + "'";
}

}  // namespace

std::string controllerScoresSvg(const std::vector<ExperimentCell>& all_cells, HeuristicKind staa_heuristic,
                                ObstacleSource obstacles) {
  std::vector<ExperimentCell> cells;
  for (const ExperimentCell& c : all_cells) {
    if (c.obstacles == obstacles) cells.push_back(c);
  }
  const std::vector<ControllerKind> order{ControllerKind::kPd, ControllerKind::kDwa, ControllerKind::kStaa};
  const std::vector<Series> all{{"PD", "#e08a2c"}, {"DWA", "#5b7fc7"}, {"STAA*", "#2a9d6a"}};
  std::vector<ControllerKind> present;
  std::vector<Series> series;
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (const ExperimentCell& c : cells) {
      if (c.controller == order[i]) {
        present.push_back(order[i]);
        series.push_back(all[i]);
        break;
      }
    }
  }
  Figure f = layoutFigure(cells, series, [&](const ExperimentCell& c) {
    if (c.controller == ControllerKind::kStaa && c.heuristic && *c.heuristic != staa_heuristic) return -1;
    return static_cast<int>(indexOf(present, c.controller));
  });
  f.title = std::string("Controllers: score = goals reached - collisions (black), mean of ") + runsNote(cells) +
            "; STAA* with " + toString(staa_heuristic) +
            (obstacles == ObstacleSource::kTruth ? std::string() : "; obstacles from " + std::string(toString(obstacles)));
  return renderFigure(f);
}

std::string obstacleScoresSvg(const std::vector<ExperimentCell>& cells, HeuristicKind staa_heuristic) {
  struct Kind {
    ControllerKind controller;
    ObstacleSource obstacles;
    Series series;
  };
  const std::vector<Kind> order{
      {ControllerKind::kPd, ObstacleSource::kTruth, {"PD truth", "#e08a2c"}},
      {ControllerKind::kPd, ObstacleSource::kDepth, {"PD depth", "#f3c797"}},
      {ControllerKind::kPd, ObstacleSource::kDepthScan, {"PD depth+scan", "#f8e2c8"}},
      {ControllerKind::kPd, ObstacleSource::kSight, {"PD sight", "#b86a1c"}},
      {ControllerKind::kDwa, ObstacleSource::kTruth, {"DWA truth", "#5b7fc7"}},
      {ControllerKind::kDwa, ObstacleSource::kDepth, {"DWA depth", "#b3c4e6"}},
      {ControllerKind::kDwa, ObstacleSource::kDepthScan, {"DWA depth+scan", "#dde5f4"}},
      {ControllerKind::kDwa, ObstacleSource::kSight, {"DWA sight", "#35559a"}},
      {ControllerKind::kStaa, ObstacleSource::kTruth, {"STAA* truth", "#2a9d6a"}},
      {ControllerKind::kStaa, ObstacleSource::kDepth, {"STAA* depth", "#96d8b8"}},
      {ControllerKind::kStaa, ObstacleSource::kDepthScan, {"STAA* depth+scan", "#cdeedd"}},
      {ControllerKind::kStaa, ObstacleSource::kSight, {"STAA* sight", "#1b6b47"}},
  };
  std::vector<std::size_t> present;
  std::vector<Series> series;
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (const ExperimentCell& c : cells) {
      if (c.controller == order[i].controller && c.obstacles == order[i].obstacles) {
        present.push_back(i);
        series.push_back(order[i].series);
        break;
      }
    }
  }
  Figure f = layoutFigure(cells, series, [&](const ExperimentCell& c) {
    if (c.controller == ControllerKind::kStaa && c.heuristic && *c.heuristic != staa_heuristic) return -1;
    for (std::size_t s = 0; s < present.size(); ++s) {
      if (order[present[s]].controller == c.controller && order[present[s]].obstacles == c.obstacles) {
        return static_cast<int>(s);
      }
    }
    return -1;
  });
  f.title = "Obstacle sources side by side: score = goals reached - collisions (black), mean of " +
            runsNote(cells) + "; STAA* with " + toString(staa_heuristic);
  return renderFigure(f);
}

std::string heuristicScoresSvg(const std::vector<ExperimentCell>& cells) {
  const std::vector<HeuristicKind> order{HeuristicKind::kPathRtr, HeuristicKind::kPathEuclid,
                                         HeuristicKind::kDijkstraRtr};
  const std::vector<Series> all{{"Path RTR", "#2a9d6a"}, {"Path Euclid", "#d9a520"}, {"Dijkstra RTR", "#c2457a"}};
  std::vector<HeuristicKind> present;
  std::vector<Series> series;
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (const ExperimentCell& c : cells) {
      if (c.controller == ControllerKind::kStaa && c.heuristic == order[i]) {
        present.push_back(order[i]);
        series.push_back(all[i]);
        break;
      }
    }
  }
  Figure f = layoutFigure(cells, series, [&](const ExperimentCell& c) {
    if (c.controller != ControllerKind::kStaa || !c.heuristic) return -1;
    return static_cast<int>(indexOf(present, *c.heuristic));
  });
  f.title = "STAA* heuristics: score = goals reached - collisions (black), mean of " + runsNote(cells);
  return renderFigure(f);
}

ExperimentPlots writeExperimentPlots(const fs::path& dir, const ExperimentSpec& spec,
                                     const std::vector<ExperimentRun>& runs) {
  ExperimentPlots plots;
  const std::vector<ExperimentCell> cells = summarizeExperiment(runs);
  std::error_code ec;
  fs::create_directories(dir, ec);
  std::vector<fs::path> svgs;
  auto save = [&](const fs::path& file, const std::string& svg) {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out << svg;
    out.close();
    if (!out) throw std::runtime_error("cannot write '" + file.string() + "'");
    svgs.push_back(file);
    plots.files.push_back(file);
  };
  const HeuristicKind first = spec.heuristics.empty() ? HeuristicKind::kPathRtr : spec.heuristics.front();
  const ObstacleSource source = spec.obstacles.empty() ? ObstacleSource::kTruth : spec.obstacles.front();
  save(dir / "scores.svg", controllerScoresSvg(cells, first, source));
  if (spec.heuristics.size() > 1) save(dir / "heuristics.svg", heuristicScoresSvg(cells));
  if (spec.obstacles.size() > 1) save(dir / "obstacles.svg", obstacleScoresSvg(cells, first));

  const std::optional<fs::path> converter = findOnPath("rsvg-convert");
  if (!converter) {
    plots.notes.push_back("rsvg-convert is not on the PATH: SVG figures only, no PNGs");
    return plots;
  }
  for (const fs::path& svg : svgs) {
    fs::path png = svg;
    png.replace_extension(".png");
    const std::string command = shellQuoted(converter->string()) + " -b white -o " + shellQuoted(png.string()) + " " +
                                shellQuoted(svg.string());
    const int status = std::system(command.c_str());
    if (status != 0) {
      throw std::runtime_error("rsvg-convert failed (status " + std::to_string(status) + ") on '" + svg.string() +
                               "'");
    }
    plots.files.push_back(png);
  }
  return plots;
}

}  // namespace staa
