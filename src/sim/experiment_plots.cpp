#include "sim/experiment_plots.hpp"

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
// one scale for both axes.
constexpr double kPxPerUnit = 16.0;
constexpr double kPlotH = 10.0;
constexpr double kLeft = 3.0;    // y tick labels
constexpr double kRight = 1.0;
constexpr double kBelow = 2.2;   // group labels
constexpr double kAbove = 1.8;   // panel title

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

std::string renderFigure(const Figure& f) {
  const double groups = static_cast<double>(std::max<std::size_t>(1, f.agents.size()));
  const double n_series = static_cast<double>(f.series.size());
  // At least 4 units per group, so that the group's label fits under two bars.
  const double per_group = std::max(n_series + 1.0, 4.0);
  const double plot_w = groups * per_group + 1.0;
  const double pitch_x = kLeft + plot_w + kRight;
  const double pitch_y = kBelow + kPlotH + kAbove;
  const double cols = static_cast<double>(std::max<std::size_t>(1, f.maps.size()));
  const double rows = static_cast<double>(std::max<std::size_t>(1, f.modes.size()));

  SvgCanvasOptions options;
  options.px_per_m = kPxPerUnit;
  options.margin_px = 12.0;
  options.header_px = 28.0;
  options.footer_px = 30.0;
  // Wide enough for the title and the legend in one line (about 0.6 em per character).
  std::vector<LegendEntry> entries;
  for (const Series& s : f.series) entries.push_back({s.label, svgFill(s.colour), LegendSymbol::kArea});
  entries.push_back({"collisions (subtracted)", svgFill("#111"), LegendSymbol::kArea});
  double legend_px = 0.0;
  for (const LegendEntry& e : entries) legend_px += 38.0 + 7.2 * static_cast<double>(e.label.size());
  const double title_px = 8.3 * static_cast<double>(f.title.size());
  const double width = std::max(cols * pitch_x, std::max(legend_px, title_px) / kPxPerUnit);
  SvgCanvas canvas(Box{{0.0, 0.0}, {width, rows * pitch_y}}, options);
  canvas.title(f.title, 15.0);

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
      const double x0 = static_cast<double>(col) * pitch_x + kLeft;
      const double y0 = (rows - 1.0 - static_cast<double>(row)) * pitch_y + kBelow;

      // The panel's value range: 0 .. the tallest bar, extended down to a negative score.
      double vmax = 0.0, vmin = 0.0;
      for (const auto& group : panel) {
        for (const Bar& b : group) {
          if (!b.present) continue;
          vmax = std::max({vmax, b.goals, b.goals - b.collisions});
          vmin = std::min(vmin, b.goals - b.collisions);
        }
      }
      const double step = tickStep(std::max(1.0, vmax - vmin));
      const double lo = std::floor(vmin / step) * step;
      const double hi = std::max(lo + step, std::ceil(vmax / step) * step);
      auto y = [&](double v) { return y0 + (v - lo) / (hi - lo) * kPlotH; };

      for (double t = lo; t <= hi + 1e-9; t += step) {
        canvas.line({x0, y(t)}, {x0 + plot_w, y(t)}, grid);
        canvas.text({x0, y(t)}, svgNumber(t), 10.0, TextAnchor::kEnd, label, -4.0, 3.5);
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
        const int n = f.agents[g];
        canvas.text({gx + 0.5 * n_series, y0}, std::to_string(n) + (n == 1 ? " agent" : " agents"),
                    11.0, TextAnchor::kMiddle, label, 0.0, 16.0);
      }
      canvas.line({x0, y(0.0)}, {x0 + plot_w, y(0.0)}, axis);
      canvas.line({x0, y0}, {x0, y0 + kPlotH}, axis);
      canvas.text({x0 + 0.5 * plot_w, y0 + kPlotH}, capitalized(f.maps[col]) + " \u2014 " + toString(f.modes[row]),
                  12.0, TextAnchor::kMiddle, heading, 0.0, -9.0);
      if (col == 0) {
        const Vec2 p = canvas.toPixel({x0 - kLeft, y0 + 0.5 * kPlotH}) + Vec2{10.0, 0.0};
        SvgStyle rotated = label;
        rotated.extra = "transform=\"rotate(-90 " + svgNumber(p.x()) + " " + svgNumber(p.y()) + ")\"";
        canvas.textPx(p, "score (mean)", 11.0, TextAnchor::kMiddle, rotated);
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

std::string controllerScoresSvg(const std::vector<ExperimentCell>& cells, HeuristicKind staa_heuristic) {
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
            "; STAA* with " + toString(staa_heuristic);
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
  save(dir / "scores.svg", controllerScoresSvg(cells, first));
  if (spec.heuristics.size() > 1) save(dir / "heuristics.svg", heuristicScoresSvg(cells));

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
