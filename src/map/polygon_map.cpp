#include "map/polygon_map.hpp"

#include "io/yaml_support.hpp"

#include "geometry/polygon.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>
#include <system_error>

namespace staa {
namespace {

constexpr std::string_view kFormat = "staa-polygon-map/1";
// Maps are metric and robot-sized; a coordinate beyond 1000 km is a corrupt file, and the
// bound keeps every cross product in the checks below far from overflow.
constexpr double kMaxCoordinate = 1e6;

using yaml_support::describe;
using yaml_support::formatNumber;
using yaml_support::lineOf;
using yaml_support::readNumber;
std::string point(const Vec2& p) { return yaml_support::formatPoint(p); }

[[noreturn]] void fail(const std::string& source, const std::string& where, const std::string& what) {
  throw MapError(source + ": " + (where.empty() ? "" : where + ": ") + what);
}

// ---- checks shared by the parser (which adds line numbers) and validatePolygonMap ----

std::optional<std::string> coordinateProblem(const Vec2& p) {
  if (!std::isfinite(p.x()) || !std::isfinite(p.y())) return "is not finite " + point(p);
  if (std::abs(p.x()) > kMaxCoordinate || std::abs(p.y()) > kMaxCoordinate) {
    return "is out of range " + point(p) + " (|x|, |y| <= " + formatNumber(kMaxCoordinate) + " m)";
  }
  return std::nullopt;
}

std::optional<std::string> polygonProblem(PolygonView poly) {
  const std::size_t n = poly.size();
  if (n < 3) return "has " + std::to_string(n) + " vertices, needs at least 3";
  for (std::size_t k = 0; k < n; ++k) {
    if (auto p = coordinateProblem(poly[k])) return "vertex " + std::to_string(k) + " " + *p;
  }
  // Edge k runs from vertex k to vertex k+1 (the last one back to vertex 0). A repeated
  // vertex is checked first: findSelfIntersection would report it as touching edges.
  for (std::size_t i = 0; i < n; ++i) {
    if (poly[i] == poly[(i + 1) % n]) {
      return "vertex " + std::to_string((i + 1) % n) + " repeats vertex " + std::to_string(i) + " " +
             point(poly[i]) + " (zero-length edge " + std::to_string(i) + ")";
    }
  }
  if (const auto e = findSelfIntersection(poly)) {
    const std::size_t i = e->first, j = e->second;
    const bool adjacent = (j == i + 1) || (i == 0 && j == n - 1);
    const char* how = adjacent ? " fold back over each other)"
                      : segmentsCrossProperly(poly[i], poly[(i + 1) % n], poly[j], poly[(j + 1) % n])
                          ? " cross)"
                          : " touch)";
    return "self-intersecting (edges " + std::to_string(i) + " and " + std::to_string(j) + how;
  }
  // Collinear vertices pass the edge test when no two edges overlap (a triangle on a line);
  // the area, relative to the polygon's size, catches them.
  const Box box = boundingBox(poly);
  const double size = std::max(box.width(), box.height());
  if (std::abs(signedArea(poly)) <= 1e-12 * size * size) return std::string("has zero area (all vertices on one line)");
  return std::nullopt;
}

std::optional<std::string> boundsProblem(const Box& b) {
  for (const Vec2& p : {b.min, b.max}) {
    if (auto e = coordinateProblem(p)) return "corner " + *e;
  }
  if (!(b.min.x() < b.max.x())) {
    return "xmin (" + formatNumber(b.min.x()) + ") must be less than xmax (" + formatNumber(b.max.x()) + ")";
  }
  if (!(b.min.y() < b.max.y())) {
    return "ymin (" + formatNumber(b.min.y()) + ") must be less than ymax (" + formatNumber(b.max.y()) + ")";
  }
  return std::nullopt;
}

std::string indexed(const char* list, std::size_t i) { return std::string(list) + "[" + std::to_string(i) + "]"; }

// ---- parsing ----

// A [x, y] pair of numbers; `where` and `what` name it in the error.
Vec2 readPair(const YAML::Node& node, const std::string& source, const std::string& where, const std::string& what) {
  if (node.IsSequence() && node.size() == 2) {
    const auto x = readNumber(node[0]);
    const auto y = readNumber(node[1]);
    if (x && y) return {*x, *y};
  }
  fail(source, where, what + " is not a pair of numbers [x, y]: got " + describe(node) + lineOf(node));
}

std::optional<Box> readBounds(const YAML::Node& node, const std::string& source) {
  if (node.IsNull()) return std::nullopt;  // `bounds:` left empty means no bounds
  if (!node.IsSequence() || node.size() != 4) {
    fail(source, "bounds", "expected 4 numbers [xmin, ymin, xmax, ymax], got " + describe(node) + lineOf(node));
  }
  double v[4];
  for (std::size_t k = 0; k < 4; ++k) {
    const auto x = readNumber(node[k]);
    if (!x) fail(source, "bounds", "item " + std::to_string(k) + " is not a number: got " + describe(node[k]) + lineOf(node));
    v[k] = *x;
  }
  const Box box{{v[0], v[1]}, {v[2], v[3]}};
  if (auto e = boundsProblem(box)) fail(source, "bounds", *e + lineOf(node));
  return box;
}

std::vector<Polygon> readObstacles(const YAML::Node& node, const std::string& source) {
  std::vector<Polygon> out;
  if (node.IsNull()) return out;
  if (!node.IsSequence()) fail(source, "obstacles", "expected a list of polygons, got " + describe(node) + lineOf(node));
  out.reserve(node.size());
  for (std::size_t i = 0; i < node.size(); ++i) {
    const YAML::Node poly = node[i];
    const std::string where = indexed("obstacles", i);
    if (!poly.IsSequence()) fail(source, where, "expected a list of [x, y] vertices, got " + describe(poly) + lineOf(poly));
    Polygon p;
    p.reserve(poly.size());
    for (std::size_t k = 0; k < poly.size(); ++k) p.push_back(readPair(poly[k], source, where, "vertex " + std::to_string(k)));
    if (auto e = polygonProblem(p)) fail(source, where, *e + lineOf(poly));
    out.push_back(std::move(p));
  }
  return out;
}

std::vector<Vec2> readGoals(const YAML::Node& node, const std::string& source) {
  std::vector<Vec2> out;
  if (node.IsNull()) return out;
  if (!node.IsSequence()) fail(source, "goals", "expected a list of [x, y] points, got " + describe(node) + lineOf(node));
  out.reserve(node.size());
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string where = indexed("goals", i);
    const Vec2 g = readPair(node[i], source, where, "goal");
    // A goal inside an obstacle is kept: whether it is reachable is the scenario's business.
    if (auto e = coordinateProblem(g)) fail(source, where, "goal " + *e + lineOf(node[i]));
    out.push_back(g);
  }
  return out;
}

PolygonMap readDocument(const YAML::Node& root, const std::string& source) {
  if (!root.IsMap()) {
    fail(source, "", std::string("not a ") + std::string(kFormat) + " document (expected a mapping with 'format', got " +
                         describe(root) + ")");
  }
  // Keys first: a misspelt key ("obstacle:") would otherwise silently give an empty map.
  constexpr std::string_view kKeys[] = {"format", "name", "bounds", "obstacles", "goals"};
  std::vector<std::string> seen;
  for (const auto& kv : root) {
    if (!kv.first.IsScalar()) fail(source, "", "a top-level key is not a plain name" + lineOf(kv.first));
    const std::string& key = kv.first.Scalar();
    if (std::find(std::begin(kKeys), std::end(kKeys), key) == std::end(kKeys)) {
      fail(source, "", "unknown key '" + key + "' (expected format, name, bounds, obstacles, goals)" + lineOf(kv.first));
    }
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) fail(source, "", "duplicate key '" + key + "'" + lineOf(kv.first));
    seen.push_back(key);
  }

  const YAML::Node format = root["format"];
  if (!format) fail(source, "", "missing 'format: " + std::string(kFormat) + "'");
  if (!format.IsScalar() || format.Scalar() != kFormat) {
    fail(source, "", "unknown format " + describe(format) + " (expected " + std::string(kFormat) + ")" + lineOf(format));
  }

  PolygonMap map;
  if (const YAML::Node name = root["name"]) {
    if (name.IsScalar()) {
      map.name = name.Scalar();
    } else if (!name.IsNull()) {
      fail(source, "name", "expected a string, got " + describe(name) + lineOf(name));
    }
  }
  if (const YAML::Node bounds = root["bounds"]) map.bounds = readBounds(bounds, source);
  if (const YAML::Node obstacles = root["obstacles"]) map.obstacles = readObstacles(obstacles, source);
  if (const YAML::Node goals = root["goals"]) map.goals = readGoals(goals, source);
  return map;
}

}  // namespace

PolygonMap parsePolygonMap(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    std::string where;
    if (e.mark.line >= 0) {
      where = "line " + std::to_string(e.mark.line + 1) + ", column " + std::to_string(e.mark.column + 1);
    }
    fail(source, where, "YAML syntax error: " + e.msg);
  }
  try {
    return readDocument(root, source);
  } catch (const YAML::Exception& e) {
    // The reader checks every node's kind before using it; this is the safety net that
    // keeps a yaml-cpp surprise a MapError rather than a crash.
    fail(source, "", std::string("unreadable map: ") + e.what());
  }
}

PolygonMap loadPolygonMap(const std::filesystem::path& path) {
  const std::string source = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) fail(source, "", "file not found");
  if (std::filesystem::is_directory(status)) fail(source, "", "is a directory, not a map file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(source, "", "cannot open the file for reading");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) fail(source, "", "read error");
  return parsePolygonMap(text.str(), source);
}

std::string toYaml(const PolygonMap& map) {
  std::ostringstream out;
  out << "format: " << kFormat << "\n";
  // Always double-quoted, escaped by yaml-cpp: a name such as `~`, `yes` or `a: b` then reads
  // back as the same string rather than as null, a boolean or a syntax error.
  YAML::Emitter name;
  name << YAML::DoubleQuoted << map.name;
  out << "name: " << name.c_str() << "\n";
  if (map.bounds) {
    const Box& b = *map.bounds;
    out << "bounds: [" << formatNumber(b.min.x()) << ", " << formatNumber(b.min.y()) << ", " << formatNumber(b.max.x())
        << ", " << formatNumber(b.max.y()) << "]\n";
  }
  if (map.obstacles.empty()) {
    out << "obstacles: []\n";
  } else {
    out << "obstacles:\n";
    for (const Polygon& poly : map.obstacles) {
      out << "  - [";
      for (std::size_t k = 0; k < poly.size(); ++k) {
        out << (k ? ", [" : "[") << formatNumber(poly[k].x()) << ", " << formatNumber(poly[k].y()) << "]";
      }
      out << "]\n";
    }
  }
  if (!map.goals.empty()) {
    out << "goals:\n";
    for (const Vec2& g : map.goals) out << "  - [" << formatNumber(g.x()) << ", " << formatNumber(g.y()) << "]\n";
  }
  return out.str();
}

void savePolygonMap(const PolygonMap& map, const std::filesystem::path& path) {
  const std::string source = path.string();
  // Never write a file that loadPolygonMap would refuse.
  validatePolygonMap(map, source);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) fail(source, "", "cannot open the file for writing");
  out << toYaml(map);
  out.close();
  if (!out) fail(source, "", "write error");
}

void validatePolygonMap(const PolygonMap& map, const std::string& source) {
  if (map.bounds) {
    if (auto e = boundsProblem(*map.bounds)) fail(source, "bounds", *e);
  }
  for (std::size_t i = 0; i < map.obstacles.size(); ++i) {
    if (auto e = polygonProblem(map.obstacles[i])) fail(source, indexed("obstacles", i), *e);
  }
  for (std::size_t i = 0; i < map.goals.size(); ++i) {
    if (auto e = coordinateProblem(map.goals[i])) fail(source, indexed("goals", i), "goal " + *e);
  }
}

}  // namespace staa
