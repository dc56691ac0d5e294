// staa-map: map tools (docs/ARCHITECTURE.md section 6). Import a ROS occupancy map, generate the
// paper's maps, place goal locations in a map without them, describe a map, plan a shortest
// path, draw a map as SVG.
// Exit status: 0 on a valid answer (including "no path"), 2 on bad input, with one line on
// stderr naming the value and where it came from.

#include "geometry/clipper_ops.hpp"
#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "map/generate.hpp"
#include "map/goals.hpp"
#include "map/polygon_map.hpp"
#include "map/ros_import.hpp"
#include "path/global_path.hpp"
#include "viz/map_drawing.hpp"
#include "viz/svg.hpp"

#include "app/cli_support.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace {

using staa::Box;
using staa::PolygonMap;
using staa::Vec2;
using Json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

constexpr int kExitBadInput = 2;

using staa::cli::InputError;

// ---- parsing of values (std::from_chars: no locale, no trailing garbage) ----

using staa::cli::parseDouble;

Vec2 parseXY(const std::string& option, const std::string& text) {
  const auto comma = text.find(',');
  if (comma != std::string::npos) {
    const auto x = parseDouble(std::string_view(text).substr(0, comma));
    const auto y = parseDouble(std::string_view(text).substr(comma + 1));
    if (x && y) return {*x, *y};
  }
  throw InputError(option + ": expected X,Y (two finite numbers in metres), got '" + text + "'");
}

double parseNonNegative(const std::string& option, const std::string& text, std::string_view what) {
  const auto v = parseDouble(text);
  if (!v || *v < 0.0) {
    throw InputError(option + ": expected " + std::string(what) + " (a finite number >= 0), got '" + text + "'");
  }
  return *v;
}

double parsePositive(const std::string& option, const std::string& text, std::string_view what) {
  const auto v = parseDouble(text);
  if (!v || *v <= 0.0) {
    throw InputError(option + ": expected " + std::string(what) + " (a finite number > 0), got '" + text + "'");
  }
  return *v;
}

int parseCount(const std::string& option, const std::string& text, int min, int max, std::string_view what) {
  const auto v = staa::cli::parseUnsigned(text);
  if (!v || *v < static_cast<std::uint64_t>(min) || *v > static_cast<std::uint64_t>(max)) {
    throw InputError(option + ": expected " + std::string(what) + " (an integer from " + std::to_string(min) + " to " +
                     std::to_string(max) + "), got '" + text + "'");
  }
  return static_cast<int>(*v);
}

std::uint64_t parseSeed(const std::string& option, const std::string& text) {
  std::uint64_t v = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, v);
  if (ec != std::errc{} || ptr != end || text.empty()) {
    throw InputError(option + ": expected a non-negative integer, got '" + text + "'");
  }
  return v;
}

// ---- output helpers ----

// One-line JSON in the documented look: {"found": true, "length": 1.5, "path": [[0, 1], ...]}.
void writeJson(std::string& out, const Json& j) {
  if (j.is_object()) {
    out += '{';
    bool first = true;
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (!first) out += ", ";
      first = false;
      out += Json(it.key()).dump();
      out += ": ";
      writeJson(out, it.value());
    }
    out += '}';
  } else if (j.is_array()) {
    out += '[';
    for (std::size_t k = 0; k < j.size(); ++k) {
      if (k > 0) out += ", ";
      writeJson(out, j[k]);
    }
    out += ']';
  } else {
    out += j.dump();
  }
}

void printJson(const Json& j) {
  std::string out;
  writeJson(out, j);
  std::cout << out << '\n';
}

std::string fmt(double v, int decimals = 3) {
  if (std::abs(v) < 0.5 * std::pow(10.0, -decimals)) v = 0.0;  // no "-0.00"
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << v;
  return s.str();
}

std::string fmtPoint(const Vec2& p) { return "(" + fmt(p.x(), 2) + ", " + fmt(p.y(), 2) + ")"; }

double microsecondsSince(Clock::time_point t0) {
  const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
  return std::round(us * 10.0) / 10.0;
}

// ---- info ----

Json boxJson(const Box& b) { return Json::array({b.min.x(), b.min.y(), b.max.x(), b.max.y()}); }
std::string boxText(const Box& b) {
  return "[" + fmt(b.min.x(), 2) + ", " + fmt(b.min.y(), 2) + ", " + fmt(b.max.x(), 2) + ", " + fmt(b.max.y(), 2) +
         "] (" + fmt(b.width(), 2) + " x " + fmt(b.height(), 2) + " m)";
}

int runInfo(const std::string& map_file, bool json) {
  const PolygonMap map = staa::loadPolygonMap(map_file);
  std::size_t vertices = 0, convex = 0;
  std::optional<Box> extent;
  for (const auto& poly : map.obstacles) {
    vertices += poly.size();
    if (staa::isConvex(poly)) ++convex;
    const Box b = staa::boundingBox(poly);
    if (!extent) {
      extent = b;
    } else {
      extent->min = extent->min.cwiseMin(b.min);
      extent->max = extent->max.cwiseMax(b.max);
    }
  }
  // The area the obstacles cover, overlaps counted once.
  double area = 0.0;
  for (const auto& region : staa::unitePolygons(map.obstacles)) {
    area += std::abs(staa::signedArea(region.outer));
    for (const auto& hole : region.holes) area -= std::abs(staa::signedArea(hole));
  }
  const std::size_t non_convex = map.obstacles.size() - convex;

  if (json) {
    Json j;
    j["file"] = map_file;
    j["name"] = map.name;
    j["bounds"] = map.bounds ? boxJson(*map.bounds) : Json(nullptr);
    j["polygons"] = map.obstacles.size();
    j["vertices"] = vertices;
    j["convex"] = convex;
    j["non_convex"] = non_convex;
    j["extent"] = extent ? boxJson(*extent) : Json(nullptr);
    j["goals"] = map.goals.size();
    j["obstacle_area_m2"] = std::round(area * 1e4) / 1e4;
    printJson(j);
    return 0;
  }
  std::cout << "map:       " << map.name << "  (" << map_file << ")\n"
            << "bounds:    " << (map.bounds ? boxText(*map.bounds) : std::string("none (unbounded)")) << '\n'
            << "polygons:  " << map.obstacles.size() << " (" << convex << " convex, " << non_convex
            << " non-convex), " << vertices << " vertices\n"
            << "extent:    " << (extent ? boxText(*extent) : std::string("none (no obstacles)")) << '\n'
            << "goals:     " << map.goals.size() << '\n'
            << "obstacles: " << fmt(area, 2) << " m^2 (union)\n";
  return 0;
}

// ---- import, generate, goals ----

// Goals for a map (replacing any it has); a map without room for them is bad input, named by
// the file it came from.
void placeGoalsInto(PolygonMap& map, const std::string& source, const staa::GoalPlacement& placement) {
  try {
    map.goals = staa::placeGoals(map, placement);
  } catch (const staa::MapError& e) {
    throw InputError(source + ": " + e.what());
  }
}

// "placed 40 goals (clearance 0.6 m, spacing 1.5 m)", saying so when fewer fit than asked.
std::string placedText(const PolygonMap& map, const staa::GoalPlacement& placement) {
  const auto placed = static_cast<int>(map.goals.size());
  std::string s = "placed " + std::to_string(placed);
  if (placed < placement.count) s += " of " + std::to_string(placement.count);
  s += placed == 1 ? " goal" : " goals";
  s += " (clearance " + fmt(placement.clearance_m, 2) + " m, spacing " + fmt(placement.min_spacing_m, 2) +
       " m, seed " + std::to_string(placement.seed) + ")";
  if (placed < placement.count) s += "; no more fit that far apart";
  return s;
}

int runImport(const std::string& ros_yaml, const std::string& out_file, const std::string& simplify_text,
              const std::string& goals_text, const std::string& clearance_text) {
  staa::ImportOptions options;
  options.simplify_m = parseNonNegative("--simplify", simplify_text, "a tolerance in metres");
  staa::GoalPlacement placement;
  placement.count = parseCount("--goals", goals_text, 0, 100000, "a number of goals to place");
  if (!clearance_text.empty()) {
    placement.clearance_m = parseNonNegative("--goal-clearance", clearance_text, "a clearance in metres");
    if (placement.count == 0) {
      throw InputError("--goal-clearance " + clearance_text + " places nothing without --goals N (N > 0)");
    }
  }
  std::cout << "importing " << ros_yaml << " (simplify " << fmt(options.simplify_m, 3) << " m) ..." << std::endl;
  const auto t0 = Clock::now();
  PolygonMap map = staa::importRosMap(ros_yaml, options);
  const double ms = microsecondsSince(t0) / 1000.0;
  if (placement.count > 0) placeGoalsInto(map, ros_yaml, placement);
  staa::savePolygonMap(map, out_file);
  std::size_t vertices = 0;
  for (const auto& p : map.obstacles) vertices += p.size();
  std::cout << "imported " << map.name << ": " << map.obstacles.size() << " polygons, " << vertices
            << " vertices in " << fmt(ms, 1) << " ms";
  if (placement.count > 0) std::cout << "; " << placedText(map, placement);
  std::cout << " -> " << out_file << '\n';
  return 0;
}

int runGoals(const std::string& map_file, const std::string& out_file, const std::string& count_text,
             const std::string& clearance_text, const std::string& spacing_text, const std::string& seed_text) {
  staa::GoalPlacement placement;
  placement.count = parseCount("--count", count_text, 1, 100000, "a number of goals");
  placement.clearance_m = parseNonNegative("--clearance", clearance_text, "a clearance in metres");
  placement.min_spacing_m = parsePositive("--spacing", spacing_text, "a distance in metres");
  placement.seed = parseSeed("--seed", seed_text);
  PolygonMap map = staa::loadPolygonMap(map_file);
  const std::size_t replaced = map.goals.size();
  placeGoalsInto(map, map_file, placement);
  staa::savePolygonMap(map, out_file);
  std::cout << placedText(map, placement) << " in " << (map.name.empty() ? map_file : map.name);
  if (replaced > 0) std::cout << ", replacing " << replaced;
  std::cout << " -> " << out_file << '\n';
  return 0;
}

int runGenerate(const std::string& name, const std::string& seed_text, const std::string& out_file) {
  const std::uint64_t seed = parseSeed("--seed", seed_text);
  const PolygonMap map = staa::generatePaperMap(name, seed);
  staa::savePolygonMap(map, out_file);
  std::size_t vertices = 0;
  for (const auto& p : map.obstacles) vertices += p.size();
  std::cout << "generated " << map.name << ": " << map.obstacles.size() << " polygons, " << vertices << " vertices, "
            << map.goals.size() << " goals -> " << out_file << '\n';
  return 0;
}

// ---- path ----

staa::GlobalPathOptions pathOptions(const std::string& inflate_text) {
  staa::GlobalPathOptions options;
  options.inflation_radius_m = parseNonNegative("--inflate", inflate_text, "a radius in metres");
  return options;
}

// Says on stderr why an answer is "no path" when the cause lies in the request itself.
void explainEndpoint(staa::PathStatus status, const Vec2& from, const Vec2& to) {
  if (status == staa::PathStatus::kGoalInObstacle) {
    std::cerr << "staa-map: --to " << fmtPoint(to) << " lies inside an obstacle or outside the bounds\n";
  } else if (status == staa::PathStatus::kStartBlocked) {
    std::cerr << "staa-map: --from " << fmtPoint(from) << ": no free space near the start\n";
  }
}

int runPath(const std::string& map_file, const std::string& from_text, const std::string& to_text,
            const std::string& inflate_text, bool json) {
  const Vec2 from = parseXY("--from", from_text);
  const Vec2 to = parseXY("--to", to_text);
  const staa::GlobalPathOptions options = pathOptions(inflate_text);
  const PolygonMap map = staa::loadPolygonMap(map_file);

  // Building M' is load-time work; time_us is the query alone.
  const auto t_build = Clock::now();
  staa::GlobalPathPlanner planner(map, options);
  const double build_us = microsecondsSince(t_build);
  const auto t_query = Clock::now();
  const staa::GlobalPath result = planner.plan(from, to);
  const double time_us = microsecondsSince(t_query);

  const bool found = result.status == staa::PathStatus::kFound;
  explainEndpoint(result.status, from, to);
  if (json) {
    Json j;
    j["found"] = found;
    j["length"] = found ? result.length : 0.0;
    Json path = Json::array();
    for (const Vec2& p : result.path) path.push_back(Json::array({p.x(), p.y()}));
    j["path"] = std::move(path);
    j["time_us"] = time_us;
    j["status"] = staa::toString(result.status);
    j["start_moved"] = result.start_moved;
    j["goal_moved"] = result.goal_moved;
    j["expansions"] = result.expansions;
    j["edge_checks"] = result.edge_checks;
    j["build_us"] = build_us;
    j["inflate_m"] = options.inflation_radius_m;
    printJson(j);
    return 0;
  }
  if (found) {
    std::cout << "path " << fmtPoint(from) << " -> " << fmtPoint(to) << ": length " << fmt(result.length, 3)
              << " m, " << result.path.size() << " vertices, query " << fmt(time_us, 1) << " us (build "
              << fmt(build_us, 1) << " us, " << result.expansions << " expansions, " << result.edge_checks
              << " edge checks" << (result.start_moved ? ", start moved" : "")
              << (result.goal_moved ? ", goal moved" : "") << ")\n";
  } else {
    std::cout << "no path " << fmtPoint(from) << " -> " << fmtPoint(to) << ": " << staa::toString(result.status)
              << " (inflate " << fmt(options.inflation_radius_m, 2) << " m, query " << fmt(time_us, 1) << " us)\n";
  }
  return 0;
}

// ---- svg ----

int runSvg(const std::string& map_file, const std::string& out_file, const std::string& from_text,
           const std::string& to_text, const std::string& inflate_text, const std::string& scale_text) {
  if (from_text.empty() != to_text.empty()) {
    throw InputError(std::string(from_text.empty() ? "--to" : "--from") + ": a path needs both --from and --to");
  }
  const bool with_path = !from_text.empty();
  const Vec2 from = with_path ? parseXY("--from", from_text) : Vec2::Zero();
  const Vec2 to = with_path ? parseXY("--to", to_text) : Vec2::Zero();
  const staa::GlobalPathOptions options = pathOptions(inflate_text);
  std::optional<double> scale;
  if (!scale_text.empty()) scale = parsePositive("--scale", scale_text, "pixels per metre");
  const PolygonMap map = staa::loadPolygonMap(map_file);

  staa::GlobalPathPlanner planner(map, options);
  const bool with_inflated = options.inflation_radius_m > 0.0;
  const double px_per_m = scale ? *scale : staa::autoScale(staa::mapDrawingBox(map));
  staa::SvgCanvas canvas = staa::makeMapCanvas(map, px_per_m);
  staa::drawMap(canvas, map, with_inflated ? &planner.inflatedObstacles() : nullptr);

  std::string caption = map.name;
  if (with_path) {
    const staa::GlobalPath result = planner.plan(from, to);
    explainEndpoint(result.status, from, to);
    staa::drawPath(canvas, result.path, from, to);
    caption += result.status == staa::PathStatus::kFound
                   ? ": path " + fmtPoint(from) + " to " + fmtPoint(to) + ", " + fmt(result.length, 2) + " m"
                   : std::string(": ") + staa::toString(result.status);
    if (result.status != staa::PathStatus::kFound) {
      std::cout << "no path " << fmtPoint(from) << " -> " << fmtPoint(to) << ": " << staa::toString(result.status)
                << '\n';
    }
  }
  if (with_inflated) caption += " (inflated " + fmt(options.inflation_radius_m, 2) + " m)";
  canvas.scaleBar();
  const auto legend = staa::mapLegend(with_inflated, !map.goals.empty(), with_path);
  canvas.legend(legend);
  canvas.title(caption);
  canvas.save(out_file);
  std::cout << "wrote " << out_file << " (" << fmt(canvas.widthPx(), 0) << " x " << fmt(canvas.heightPx(), 0)
            << " px, " << fmt(px_per_m, 1) << " px/m)\n";
  return 0;
}

// ---- command line ----

int run(int argc, char** argv) {
  CLI::App app{"staa-map: map tools for the STAA* motion controller: describe, import, generate, plan, draw."};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Print the help of every subcommand");

  std::string map_file, out_file, from_text, to_text, inflate_text = "0.3", simplify_text = "0.05",
                                                     seed_text = "1", scale_text, name, goals_text = "0",
                                                     goal_clearance_text, count_text = "40", clearance_text = "0.6",
                                                     spacing_text = "1.5";
  bool json = false;

  auto* info = app.add_subcommand("info", "Describe a polygon map: name, bounds, polygon and vertex counts, "
                                          "convex/non-convex counts, extent, goals, obstacle area.");
  info->add_option("MAP", map_file, "Polygon map (staa-polygon-map/1 YAML)")->required();
  info->add_flag("--json", json, "Machine-readable output (one JSON object)");

  auto* import = app.add_subcommand("import", "Convert a ROS map_server occupancy map (YAML + PGM) into a "
                                              "polygon map; prints the polygon and vertex counts and the time.");
  import->add_option("ROS_MAP", map_file, "map_server YAML file (its image is found beside it)")->required();
  import->add_option("-o,--output", out_file, "Polygon map to write")->required();
  import->add_option("--simplify", simplify_text, "Douglas-Peucker tolerance in metres (0: every pixel corner)")
      ->capture_default_str();
  import->add_option("--goals", goals_text, "Goal locations to place in the map (0: none; see the goals "
                                            "subcommand)")
      ->capture_default_str();
  import->add_option("--goal-clearance", goal_clearance_text,
                     "Clearance of the goals from obstacles and bounds in metres (default 0.6)");

  auto* generate = app.add_subcommand("generate", "Write one of the paper's maps: office, apartment, clutter "
                                                  "(clutter is random from --seed).");
  generate->add_option("NAME", name, "office, apartment or clutter")->required();
  generate->add_option("--seed", seed_text, "Seed of the clutter map (non-negative integer)")->capture_default_str();
  generate->add_option("-o,--output", out_file, "Polygon map to write")->required();

  auto* goals = app.add_subcommand(
      "goals", "Place goal locations in a polygon map (replacing any): lattice points with --clearance to every "
               "obstacle and the bounds, in the largest connected free region (so every goal is reachable from "
               "every other), spread by farthest-point sampling from a seeded first goal, at least --spacing "
               "apart. Fewer than --count when no more fit.");
  goals->add_option("MAP", map_file, "Polygon map")->required();
  goals->add_option("-o,--output", out_file, "Polygon map to write (may be MAP itself)")->required();
  goals->add_option("--count", count_text, "Number of goals")->capture_default_str();
  goals->add_option("--clearance", clearance_text, "Distance from every obstacle and the bounds in metres")
      ->capture_default_str();
  goals->add_option("--spacing", spacing_text, "Least distance between two goals in metres")->capture_default_str();
  goals->add_option("--seed", seed_text, "Seed of the first goal (non-negative integer)")->capture_default_str();

  auto* path = app.add_subcommand("path", "Plan the shortest path between two points in the map inflated by "
                                          "--inflate. Exit status 0 also when no path exists (status says why).");
  path->add_option("MAP", map_file, "Polygon map")->required();
  path->add_option("--from", from_text, "Start X,Y in metres")->required();
  path->add_option("--to", to_text, "Goal X,Y in metres")->required();
  path->add_option("--inflate", inflate_text, "Inflation radius in metres (the robot's radius)")
      ->capture_default_str();
  path->add_flag("--json", json,
                 "Print {\"found\", \"length\", \"path\", \"time_us\", \"status\", \"start_moved\", \"goal_moved\", "
                 "\"expansions\", \"edge_checks\", \"build_us\", \"inflate_m\"}; time_us is the query alone");

  auto* svg = app.add_subcommand("svg", "Draw a map as SVG: obstacles, inflated obstacles, goals, and with "
                                        "--from/--to the shortest path.");
  svg->add_option("MAP", map_file, "Polygon map")->required();
  svg->add_option("-o,--output", out_file, "SVG file to write")->required();
  svg->add_option("--from", from_text, "Start X,Y of a path to draw");
  svg->add_option("--to", to_text, "Goal X,Y of a path to draw");
  svg->add_option("--inflate", inflate_text, "Inflation radius in metres (0: do not draw inflated obstacles)")
      ->capture_default_str();
  svg->add_option("--scale", scale_text, "Pixels per metre (default: about 900 px across)");

  // CLI11 reports an unknown subcommand as "a subcommand is required"; name it instead.
  if (argc > 1 && argv[1][0] != '-') {
    const std::string first = argv[1];
    bool known = false;
    for (const auto* sub : app.get_subcommands({})) known = known || sub->check_name(first);
    if (!known) {
      throw InputError("unknown subcommand '" + first + "' (expected info, import, generate, goals, path or svg)");
    }
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help: the help of the subcommand given
  } catch (const CLI::ParseError& e) {
    std::cerr << "staa-map: " << e.what() << " (see staa-map --help)\n";
    return kExitBadInput;
  }

  if (*info) return runInfo(map_file, json);
  if (*import) return runImport(map_file, out_file, simplify_text, goals_text, goal_clearance_text);
  if (*generate) return runGenerate(name, seed_text, out_file);
  if (*goals) return runGoals(map_file, out_file, count_text, clearance_text, spacing_text, seed_text);
  if (*path) return runPath(map_file, from_text, to_text, inflate_text, json);
  if (*svg) return runSvg(map_file, out_file, from_text, to_text, inflate_text, scale_text);
  return kExitBadInput;
}

}  // namespace

int main(int argc, char** argv) {
  // Every failure is one line on stderr and exit status 2, never an uncaught exception.
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "staa-map: " << e.what() << '\n';
  } catch (...) {
    std::cerr << "staa-map: unexpected error\n";
  }
  return kExitBadInput;
}
