#include "app/staad/run_picture.hpp"
#include "app/staad/text.hpp"

#include "viz/map_drawing.hpp"
#include "viz/svg.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <system_error>

namespace staa::staad {

namespace {

namespace fs = std::filesystem;

// The map drawing's palette (viz/map_drawing.cpp) for the path; goals and robot added here.
constexpr const char* kPath = "#e8590c";
constexpr const char* kStart = "#1971c2";
constexpr const char* kReached = "#2b8a3e";
constexpr const char* kMissed = "#c92a2a";
constexpr const char* kRobot = "#2c3e50";
constexpr double kGoalMarkerPx = 6.0;

fs::path tempPathOf(const fs::path& path) {
  fs::path tmp = path;
  tmp += ".tmp";
  return tmp;
}

SvgStyle goalStyle(bool reached) {
  SvgStyle s = svgFill(reached ? kReached : "#ffffff");
  s.stroke = reached ? "#ffffff" : kMissed;
  s.stroke_width_px = reached ? 1.5 : 2.0;
  return s;
}

SvgStyle startStyle() {
  SvgStyle s = svgFill(kStart);
  s.stroke = "#ffffff";
  s.stroke_width_px = 2.0;
  return s;
}

// The box the picture shows: the map's, grown to hold everything the run visited.
Box pictureBox(const PolygonMap& map, const RunRecord& run, const std::vector<std::vector<Vec2>>& path,
               const Polygon& robot) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Box run_box{{kInf, kInf}, {-kInf, -kInf}};
  auto grow = [&run_box](const Vec2& p) {
    run_box.min = run_box.min.cwiseMin(p);
    run_box.max = run_box.max.cwiseMax(p);
  };
  for (const auto& line : path) {
    for (const Vec2& p : line) grow(p);
  }
  for (const RunRecord::Goal& g : run.goals()) grow(g.pose.position());
  for (const Vec2& p : robot) grow(p);
  const bool has_run = run_box.min.x() <= run_box.max.x();
  if (has_run) {
    run_box.min -= Vec2{0.5, 0.5};
    run_box.max += Vec2{0.5, 0.5};
  }

  Box box = run_box;
  try {
    const Box map_box = mapDrawingBox(map);
    if (has_run) {
      box.min = map_box.min.cwiseMin(run_box.min);
      box.max = map_box.max.cwiseMax(run_box.max);
    } else {
      box = map_box;
    }
  } catch (const std::invalid_argument&) {  // an empty map: the run alone
    if (!has_run) box = Box{{-1.0, -1.0}, {1.0, 1.0}};
  }
  return box;
}

}  // namespace

void RunRecord::addPose(double t_s, const Pose2& pose) {
  const Vec2 p = pose.position();
  if (records_ == 0) {
    segments_.push_back({p});
    t_start_ = t_s;
  } else {
    const Vec2 last = end_.position();
    const double step = (p - last).norm();
    const double dt = t_s - t_end_;
    if (step > kJumpM && step > kMaxSpeed * dt) {
      // Relocated: close the polyline at the last pose, start another here.
      if (segments_.back().back() != last) segments_.back().push_back(last);
      segments_.push_back({p});
      travel_since_kept_m_ = 0.0;
    } else {
      distance_m_ += step;
      travel_since_kept_m_ += step;
      if (travel_since_kept_m_ >= kMinStepM) {
        segments_.back().push_back(p);
        travel_since_kept_m_ = 0.0;
      }
    }
  }
  end_ = pose;
  t_end_ = t_s;
  ++records_;
}

void RunRecord::addGoal(std::uint64_t id, const Pose2& pose) { goals_.push_back({id, pose, false}); }

void RunRecord::observe(const Status& status) {
  if (status.state != DaemonState::kReached || status.goal_id == 0 || status.goal_id == last_reached_id_) return;
  last_reached_id_ = status.goal_id;
  ++goals_reached_;
  for (auto it = goals_.rbegin(); it != goals_.rend(); ++it) {
    if (it->id == status.goal_id) {
      it->reached = true;
      break;
    }
  }
}

std::vector<std::vector<Vec2>> RunRecord::path() const {
  std::vector<std::vector<Vec2>> out = segments_;
  if (!out.empty() && out.back().back() != end_.position()) out.back().push_back(end_.position());
  return out;
}

std::string runSvg(const RunRecord& run, const PolygonMap& map, const Polygon& footprint) {
  // The map's own goals are scenario drop-off points: numbered from 0 they would read as the
  // run's goal ids, so they are left out.
  PolygonMap drawn = map;
  drawn.goals.clear();

  const std::vector<std::vector<Vec2>> path = run.path();
  Polygon robot;
  if (run.hasPose()) {
    for (const Vec2& p : footprint) robot.push_back(run.endPose().transform(p));
  }

  const Box box = pictureBox(drawn, run, path, robot);
  SvgCanvasOptions options;
  options.px_per_m = autoScale(box);
  options.margin_px = 16.0;
  options.header_px = 22.0;
  options.footer_px = 30.0;
  SvgCanvas canvas(box, options);
  drawMap(canvas, drawn, nullptr);

  // The path driven, with a white halo so it reads over obstacles and the grid.
  for (const std::vector<Vec2>& line : path) {
    if (line.size() < 2) continue;
    SvgStyle halo = svgStroke("#ffffff", 5.0);
    halo.extra = "stroke-linejoin=\"round\" stroke-linecap=\"round\"";
    halo.opacity = 0.8;
    canvas.polyline(line, halo);
    SvgStyle stroke = svgStroke(kPath, 2.6);
    stroke.extra = "stroke-linejoin=\"round\" stroke-linecap=\"round\"";
    canvas.polyline(line, stroke);
  }
  if (!path.empty()) canvas.marker(path.front().front(), 6.0, startStyle());

  // Every goal with its id: filled once reached, hollow red if never reached.
  for (const RunRecord::Goal& g : run.goals()) {
    canvas.arrow(g.pose, 0.45, svgStroke(g.reached ? kReached : kMissed, 1.5), 5.0);
    canvas.marker(g.pose.position(), kGoalMarkerPx, goalStyle(g.reached));
    SvgStyle label;
    label.fill = g.reached ? kReached : kMissed;
    label.extra = "font-weight=\"bold\"";
    canvas.text(g.pose.position(), std::to_string(g.id), 11.0, TextAnchor::kStart, label, kGoalMarkerPx + 2.0,
                -kGoalMarkerPx);
  }

  // The robot where the run ended, on top (translucent: a goal it stands on shows through).
  if (!robot.empty()) {
    canvas.polygon(robot, svgFill(kRobot, 0.7));
    canvas.arrow(run.endPose(), 0.4, svgStroke("#ffffff", 2.0), 6.0);
  }

  char title[256];
  const std::size_t goals = run.goals().size();
  std::snprintf(title, sizeof title, "staad run%s%s: %.1f s, %.2f m driven, %zu of %zu goal%s reached",
                map.name.empty() ? "" : " on ", map.name.c_str(), run.durationS(), run.distanceM(),
                run.goalsReached(), goals, goals == 1 ? "" : "s");
  canvas.title(title, 13.0);
  canvas.scaleBar();
  std::vector<LegendEntry> legend = mapLegend(false, false, false);
  SvgStyle path_style = svgStroke(kPath, 2.6);
  legend.push_back({"driven", path_style, LegendSymbol::kLine});
  legend.push_back({"start", startStyle(), LegendSymbol::kMarker});
  legend.push_back({"goal reached", goalStyle(true), LegendSymbol::kMarker});
  legend.push_back({"goal not reached", goalStyle(false), LegendSymbol::kMarker});
  legend.push_back({"robot at the end", svgFill(kRobot, 0.7), LegendSymbol::kArea});
  canvas.legend(legend);
  return canvas.str();
}

void writeFileAtomically(const fs::path& path, std::string_view text) {
  const fs::path tmp = tempPathOf(path);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + quoted(tmp.string()) + ": " + std::strerror(errno));
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.close();
    if (!out) {
      std::error_code ignored;
      fs::remove(tmp, ignored);
      throw std::runtime_error("cannot write " + quoted(tmp.string()) + ": write failed (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    std::string message = "cannot rename ";
    message.append(quoted(tmp.string())).append(" to ").append(quoted(path.string())).append(": ").append(ec.message());
    throw std::runtime_error(message);
  }
}

void checkWritable(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw std::runtime_error(quoted(path.string()) + " is a directory");
  const fs::path tmp = tempPathOf(path);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + quoted(tmp.string()) + ": " + std::strerror(errno));
  }
  fs::remove(tmp, ec);
}

}  // namespace staa::staad
