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
#include "robot/robot_profile.hpp"
#include "viz/map_drawing.hpp"
#include "viz/svg.hpp"

#include "app/cli_support.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using staa::Box;
using staa::PolygonMap;
using staa::Vec2;
using Json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

using staa::cli::InputError;
using staa::cli::kExitBadInput;

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

// What `info` says of a map's obstacles.
struct ObstacleStats {
  std::size_t vertices = 0;
  std::size_t convex = 0;
  std::size_t non_convex = 0;
  std::optional<Box> extent;
  double area = 0.0;  // the area the obstacles cover, overlaps counted once
};

ObstacleStats obstacleStats(const PolygonMap& map) {
  ObstacleStats st;
  for (const auto& poly : map.obstacles) {
    st.vertices += poly.size();
    if (staa::isConvex(poly)) ++st.convex;
    const Box b = staa::boundingBox(poly);
    if (!st.extent) {
      st.extent = b;
    } else {
      st.extent->min = st.extent->min.cwiseMin(b.min);
      st.extent->max = st.extent->max.cwiseMax(b.max);
    }
  }
  st.area = staa::unionArea(map.obstacles);
  st.non_convex = map.obstacles.size() - st.convex;
  return st;
}

Json infoJson(const std::string& map_file, const PolygonMap& map, const ObstacleStats& st) {
  Json j;
  j["file"] = map_file;
  j["name"] = map.name;
  j["bounds"] = map.bounds ? boxJson(*map.bounds) : Json(nullptr);
  j["polygons"] = map.obstacles.size();
  j["vertices"] = st.vertices;
  j["convex"] = st.convex;
  j["non_convex"] = st.non_convex;
  j["extent"] = st.extent ? boxJson(*st.extent) : Json(nullptr);
  j["goals"] = map.goals.size();
  j["obstacle_area_m2"] = std::round(st.area * 1e4) / 1e4;
  return j;
}

void printInfo(const std::string& map_file, const PolygonMap& map, const ObstacleStats& st) {
  std::cout << "map:       " << map.name << "  (" << map_file << ")\n"
            << "bounds:    " << (map.bounds ? boxText(*map.bounds) : std::string("none (unbounded)")) << '\n'
            << "polygons:  " << map.obstacles.size() << " (" << st.convex << " convex, " << st.non_convex
            << " non-convex), " << st.vertices << " vertices\n"
            << "extent:    " << (st.extent ? boxText(*st.extent) : std::string("none (no obstacles)")) << '\n'
            << "goals:     " << map.goals.size() << '\n'
            << "obstacles: " << fmt(st.area, 2) << " m^2 (union)\n";
}

int runInfo(const std::string& map_file, bool json) {
  const PolygonMap map = staa::loadPolygonMap(map_file);
  const ObstacleStats st = obstacleStats(map);
  if (json) {
    printJson(infoJson(map_file, map, st));
  } else {
    printInfo(map_file, map, st);
  }
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

struct ImportArgs {
  std::string ros_map, out_file;
  staa::ImportOptions options;
  staa::GoalPlacement placement{.count = 0};
  const CLI::Option* clearance_option = nullptr;
};

int runImport(ImportArgs& a) {
  staa::GoalPlacement& placement = a.placement;
  if (a.clearance_option->count() > 0 && placement.count == 0) {
    throw InputError("--goal-clearance " + staa::cli::given(a.clearance_option) +
                     " places nothing without --goals N (N > 0)");
  }
  std::cout << "importing " << a.ros_map << " (simplify " << fmt(a.options.simplify_m, 3) << " m) ..." << std::endl;
  const auto t0 = Clock::now();
  PolygonMap map = staa::importRosMap(a.ros_map, a.options);
  const double ms = microsecondsSince(t0) / 1000.0;
  if (placement.count > 0) placeGoalsInto(map, a.ros_map, placement);
  staa::savePolygonMap(map, a.out_file);
  std::size_t vertices = 0;
  for (const auto& p : map.obstacles) vertices += p.size();
  std::cout << "imported " << map.name << ": " << map.obstacles.size() << " polygons, " << vertices
            << " vertices in " << fmt(ms, 1) << " ms";
  if (placement.count > 0) std::cout << "; " << placedText(map, placement);
  std::cout << " -> " << a.out_file << '\n';
  return 0;
}

int runGoals(const std::string& map_file, const std::string& out_file, const staa::GoalPlacement& placement) {
  PolygonMap map = staa::loadPolygonMap(map_file);
  const std::size_t replaced = map.goals.size();
  placeGoalsInto(map, map_file, placement);
  staa::savePolygonMap(map, out_file);
  std::cout << placedText(map, placement) << " in " << (map.name.empty() ? map_file : map.name);
  if (replaced > 0) std::cout << ", replacing " << replaced;
  std::cout << " -> " << out_file << '\n';
  return 0;
}

int runGenerate(const std::string& name, std::uint64_t seed, const std::string& out_file) {
  const PolygonMap map = staa::generatePaperMap(name, seed);
  staa::savePolygonMap(map, out_file);
  std::size_t vertices = 0;
  for (const auto& p : map.obstacles) vertices += p.size();
  std::cout << "generated " << map.name << ": " << map.obstacles.size() << " polygons, " << vertices << " vertices, "
            << map.goals.size() << " goals -> " << out_file << '\n';
  return 0;
}

// ---- path ----

Vec2 point(const std::string& checked_text) {
  const auto p = staa::cli::parsePoint<2>(checked_text).value();
  return {p[0], p[1]};
}

// Says on stderr why an answer is "no path" when the cause lies in the request itself.
void explainEndpoint(staa::PathStatus status, const Vec2& from, const Vec2& to) {
  if (status == staa::PathStatus::kGoalInObstacle) {
    std::cerr << "staa-map: --to " << fmtPoint(to) << " lies inside an obstacle or outside the bounds\n";
  } else if (status == staa::PathStatus::kStartBlocked) {
    std::cerr << "staa-map: --from " << fmtPoint(from) << ": no free space near the start\n";
  }
}

int runPath(const std::string& map_file, const Vec2& from, const Vec2& to, const staa::GlobalPathOptions& options,
            bool json) {
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
    if (options.passage_inflation_m > 0.0) {
      // For a footprint (--robot): the passage map's growth, whether the route runs in it,
      // and the route's length in the band (inside M').
      j["passage_inflate_m"] = options.passage_inflation_m;
      j["passage"] = result.passage;
      j["band_m"] = found ? planner.bandLength(result.path) : 0.0;
    }
    printJson(j);
    return 0;
  }
  if (found) {
    std::cout << "path " << fmtPoint(from) << " -> " << fmtPoint(to) << ": length " << fmt(result.length, 3)
              << " m, " << result.path.size() << " vertices, query " << fmt(time_us, 1) << " us (build "
              << fmt(build_us, 1) << " us, " << result.expansions << " expansions, " << result.edge_checks
              << " edge checks" << (result.start_moved ? ", start moved" : "")
              << (result.goal_moved ? ", goal moved" : "")
              << (result.passage ? ", through a passage M' closes: " + fmt(planner.bandLength(result.path), 2) + " m in the band"
                                 : std::string())
              << ")\n";
  } else {
    std::cout << "no path " << fmtPoint(from) << " -> " << fmtPoint(to) << ": " << staa::toString(result.status)
              << " (inflate " << fmt(options.inflation_radius_m, 2) << " m, query " << fmt(time_us, 1) << " us)\n";
  }
  return 0;
}

// ---- svg ----

struct SvgArgs {
  std::string map_file, out_file, from_text, to_text, robot_file;
  staa::GlobalPathOptions options;
  double scale = 0.0;
  const CLI::Option* scale_option = nullptr;
};

int runSvg(const SvgArgs& a) {
  const bool with_path = !a.from_text.empty();
  const Vec2 from = with_path ? point(a.from_text) : Vec2::Zero();
  const Vec2 to = with_path ? point(a.to_text) : Vec2::Zero();
  const staa::GlobalPathOptions& options = a.options;
  const PolygonMap map = staa::loadPolygonMap(a.map_file);

  staa::GlobalPathPlanner planner(map, options);
  const bool with_inflated = options.inflation_radius_m > 0.0;
  const bool with_passage = planner.hasPassageMap();
  const double px_per_m = a.scale_option->count() > 0 ? a.scale : staa::autoScale(staa::mapDrawingBox(map));
  staa::SvgCanvas canvas = staa::makeMapCanvas(map, px_per_m);
  staa::drawMap(canvas, map, with_inflated ? &planner.inflatedObstacles() : nullptr,
                with_passage ? &planner.passageObstacles() : nullptr);

  std::string caption = map.name;
  if (with_path) {
    const staa::GlobalPath result = planner.plan(from, to);
    explainEndpoint(result.status, from, to);
    staa::drawPath(canvas, result.path, from, to);
    caption += result.status == staa::PathStatus::kFound
                   ? ": path " + fmtPoint(from) + " to " + fmtPoint(to) + ", " + fmt(result.length, 2) + " m" +
                         (result.passage ? " through M'' (" + fmt(planner.bandLength(result.path), 2) + " m in the band)"
                                         : std::string())
                   : std::string(": ") + staa::toString(result.status);
    if (result.status != staa::PathStatus::kFound) {
      std::cout << "no path " << fmtPoint(from) << " -> " << fmtPoint(to) << ": " << staa::toString(result.status)
                << '\n';
    }
  }
  if (with_inflated) {
    caption += with_passage ? " (M' " + fmt(options.inflation_radius_m, 2) + " m, M'' " +
                                  fmt(options.passage_inflation_m, 2) + " m)"
                            : " (inflated " + fmt(options.inflation_radius_m, 2) + " m)";
  }
  canvas.scaleBar();
  const auto legend = staa::mapLegend(with_inflated, !map.goals.empty(), with_path, with_passage);
  canvas.legend(legend);
  canvas.title(caption);
  canvas.save(a.out_file);
  std::cout << "wrote " << a.out_file << " (" << fmt(canvas.widthPx(), 0) << " x " << fmt(canvas.heightPx(), 0)
            << " px, " << fmt(px_per_m, 1) << " px/m)\n";
  return 0;
}

// ---- command line: one subcommand, parsed, then run ----

constexpr const char* kPointForm = "X,Y (two finite numbers in metres)";

struct InfoArgs {
  std::string map_file;
  bool json = false;
};

CLI::App* addInfo(CLI::App& app, InfoArgs& a) {
  auto* info = app.add_subcommand("info", "Describe a polygon map: name, bounds, polygon and vertex counts, "
                                          "convex/non-convex counts, extent, goals, obstacle area.");
  info->add_option("MAP", a.map_file, "Polygon map (staa-polygon-map/1 YAML)")->required();
  info->add_flag("--json", a.json, "Machine-readable output (one JSON object)");
  return info;
}

CLI::App* addImport(CLI::App& app, ImportArgs& a) {
  namespace cli = staa::cli;
  auto* import = app.add_subcommand("import", "Convert a ROS map_server occupancy map (YAML + PGM) into a "
                                              "polygon map; prints the polygon and vertex counts and the time.");
  import->add_option("ROS_MAP", a.ros_map, "map_server YAML file (its image is found beside it)")->required();
  import->add_option("-o,--output", a.out_file, "Polygon map to write")->required();
  import->add_option("--simplify", a.options.simplify_m, "Douglas-Peucker tolerance in metres (0: every pixel corner)")
      ->transform(cli::nonNegative("a tolerance in metres"))
      ->capture_default_str();
  import->add_option("--goals", a.placement.count, "Goal locations to place in the map (0: none; see the goals "
                                                   "subcommand)")
      ->transform(cli::count("a number of goals to place", 0, 100000))
      ->capture_default_str();
  a.clearance_option = import->add_option("--goal-clearance", a.placement.clearance_m,
                                          "Clearance of the goals from obstacles and bounds in metres")
                           ->transform(cli::nonNegative("a clearance in metres"))
                           ->capture_default_str();
  return import;
}

struct GenerateArgs {
  std::string name, out_file;
  std::uint64_t seed = 1;
};

CLI::App* addGenerate(CLI::App& app, GenerateArgs& a) {
  auto* generate = app.add_subcommand("generate", "Write one of the paper's maps: office, apartment, clutter "
                                                  "(clutter is random from --seed).");
  generate->add_option("NAME", a.name, "office, apartment or clutter")->required();
  generate->add_option("--seed", a.seed, "Seed of the clutter map")
      ->transform(staa::cli::count("a seed", 0, std::numeric_limits<std::uint64_t>::max()))
      ->capture_default_str();
  generate->add_option("-o,--output", a.out_file, "Polygon map to write")->required();
  return generate;
}

struct GoalsArgs {
  std::string map_file, out_file;
  staa::GoalPlacement placement;
};

CLI::App* addGoals(CLI::App& app, GoalsArgs& a) {
  namespace cli = staa::cli;
  auto* goals = app.add_subcommand(
      "goals", "Place goal locations in a polygon map (replacing any): lattice points with --clearance to every "
               "obstacle and the bounds, in the largest connected free region (so every goal is reachable from "
               "every other), spread by farthest-point sampling from a seeded first goal, at least --spacing "
               "apart. Fewer than --count when no more fit.");
  staa::GoalPlacement& p = a.placement;
  goals->add_option("MAP", a.map_file, "Polygon map")->required();
  goals->add_option("-o,--output", a.out_file, "Polygon map to write (may be MAP itself)")->required();
  goals->add_option("--count", p.count, "Number of goals")
      ->transform(cli::count("a number of goals", 1, 100000))
      ->capture_default_str();
  goals->add_option("--clearance", p.clearance_m, "Distance from every obstacle and the bounds in metres")
      ->transform(cli::nonNegative("a clearance in metres"))
      ->capture_default_str();
  goals->add_option("--spacing", p.min_spacing_m, "Least distance between two goals in metres")
      ->transform(cli::positive("a distance in metres"))
      ->capture_default_str();
  goals->add_option("--seed", p.seed, "Seed of the first goal")
      ->transform(cli::count("a seed", 0, std::numeric_limits<std::uint64_t>::max()))
      ->capture_default_str();
  return goals;
}

struct PathArgs {
  std::string map_file, from_text, to_text, robot_file;
  staa::GlobalPathOptions options;
  bool json = false;
};

CLI::App* addPath(CLI::App& app, PathArgs& a) {
  namespace cli = staa::cli;
  auto* path = app.add_subcommand("path", "Plan the shortest path between two points in the map inflated by "
                                          "--inflate. Exit status 0 also when no path exists (status says why).");
  path->add_option("MAP", a.map_file, "Polygon map")->required();
  path->add_option("--from", a.from_text, "Start X,Y in metres")
      ->required()
      ->check(cli::point<2>(kPointForm))
      ->type_name("X,Y");
  path->add_option("--to", a.to_text, "Goal X,Y in metres")
      ->required()
      ->check(cli::point<2>(kPointForm))
      ->type_name("X,Y");
  auto* inflate = path->add_option("--inflate", a.options.inflation_radius_m, "Inflation radius in metres (the robot's radius)")
                      ->transform(cli::nonNegative("a radius in metres"))
                      ->capture_default_str();
  path->add_option("--robot", a.robot_file,
                   "Robot profile (staa-robot/1): plan as the control cycle does, in the map grown by the footprint's "
                   "circumradius and in the passage map grown by its inscribed radius + 1 cm")
      ->excludes(inflate);
  path->add_flag("--json", a.json,
                 "Print {\"found\", \"length\", \"path\", \"time_us\", \"status\", \"start_moved\", \"goal_moved\", "
                 "\"expansions\", \"edge_checks\", \"build_us\", \"inflate_m\"}, with --robot also \"passage_inflate_m\", "
                 "\"passage\" (the route runs through a passage the circumradius closes) and \"band_m\" (its length "
                 "there); time_us is the query alone");
  return path;
}

CLI::App* addSvg(staa::cli::CommandLine& cl, SvgArgs& a) {
  namespace cli = staa::cli;
  auto* svg = cl.app.add_subcommand("svg", "Draw a map as SVG: obstacles, inflated obstacles, goals, and with "
                                        "--from/--to the shortest path.");
  svg->add_option("MAP", a.map_file, "Polygon map")->required();
  svg->add_option("-o,--output", a.out_file, "SVG file to write")->required();
  auto* from = svg->add_option("--from", a.from_text, "Start X,Y of a path to draw")
                   ->check(cli::point<2>(kPointForm))
                   ->type_name("X,Y");
  auto* to = svg->add_option("--to", a.to_text, "Goal X,Y of a path to draw")
                 ->check(cli::point<2>(kPointForm))
                 ->type_name("X,Y");
  cl.need(from, to, "a path needs both --from and --to");
  cl.need(to, from, "a path needs both --from and --to");
  auto* inflate = svg->add_option("--inflate", a.options.inflation_radius_m,
                                  "Inflation radius in metres (0: do not draw inflated obstacles)")
                      ->transform(cli::nonNegative("a radius in metres"))
                      ->capture_default_str();
  svg->add_option("--robot", a.robot_file,
                  "Robot profile (staa-robot/1): draw M' (its circumradius) and the passage map (its inscribed "
                  "radius + 1 cm), and plan the path as the control cycle does")
      ->excludes(inflate);
  a.scale_option = svg->add_option("--scale", a.scale, "Pixels per metre (default: about 900 px across)")
                       ->transform(cli::positive("pixels per metre"));
  return svg;
}

// --robot: M' grown by the footprint's circumradius, the passage map by its inscribed radius
// + 1 cm, as the control cycle plans its route.
void setRobotOptions(const std::string& robot_file, staa::GlobalPathOptions& options) {
  const staa::RobotProfile robot = staa::loadRobotProfile(robot_file);
  options.inflation_radius_m = robot.circumradius();
  options.passage_inflation_m = robot.passageRadius();
}

// CLI11 reports an unknown subcommand as "a subcommand is required"; name it instead.
void rejectUnknownSubcommand(const CLI::App& app, int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return;
  const std::string first = argv[1];
  for (const auto* sub : app.get_subcommands({})) {
    if (sub->check_name(first)) return;
  }
  throw InputError("unknown subcommand '" + first + "' (expected info, import, generate, goals, path or svg)");
}

int run(int argc, char** argv) {
  staa::cli::CommandLine cl(
      "staa-map", "staa-map: map tools for the STAA* motion controller: describe, import, generate, plan, draw.");
  cl.app.require_subcommand(1);
  cl.app.set_help_all_flag("--help-all", "Print the help of every subcommand");
  InfoArgs info;
  ImportArgs import;
  GenerateArgs generate;
  GoalsArgs goals;
  PathArgs path;
  SvgArgs svg;
  const CLI::App* info_cmd = addInfo(cl.app, info);
  const CLI::App* import_cmd = addImport(cl.app, import);
  const CLI::App* generate_cmd = addGenerate(cl.app, generate);
  const CLI::App* goals_cmd = addGoals(cl.app, goals);
  const CLI::App* path_cmd = addPath(cl.app, path);
  const CLI::App* svg_cmd = addSvg(cl, svg);
  rejectUnknownSubcommand(cl.app, argc, argv);
  if (const auto exit = cl.parse(argc, argv)) return *exit;

  if (*info_cmd) return runInfo(info.map_file, info.json);
  if (*import_cmd) return runImport(import);
  if (*generate_cmd) return runGenerate(generate.name, generate.seed, generate.out_file);
  if (*goals_cmd) return runGoals(goals.map_file, goals.out_file, goals.placement);
  if (*path_cmd) {
    if (!path.robot_file.empty()) setRobotOptions(path.robot_file, path.options);
    return runPath(path.map_file, point(path.from_text), point(path.to_text), path.options, path.json);
  }
  if (*svg_cmd) {
    if (!svg.robot_file.empty()) setRobotOptions(svg.robot_file, svg.options);
    return runSvg(svg);
  }
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
