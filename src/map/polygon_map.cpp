#include "map/polygon_map.hpp"

#include "io/config_reader.hpp"
#include "io/yaml_support.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string_view>

namespace staa {
namespace {

// The index of the first byte that breaks UTF-8 in `text`, or text.size(): a name is written
// back out through yaml-cpp, which replaces such bytes (the map would not read back the same).
std::size_t firstInvalidUtf8(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size()) {
    const auto b = static_cast<unsigned char>(text[i]);
    const std::size_t n = b < 0x80 ? 1 : (b >> 5) == 0x6 && b >= 0xC2 ? 2 : (b >> 4) == 0xE ? 3 : (b >> 3) == 0x1E && b <= 0xF4 ? 4 : 0;
    if (n == 0 || i + n > text.size()) return i;
    for (std::size_t k = 1; k < n; ++k) {
      if ((static_cast<unsigned char>(text[i + k]) & 0xC0) != 0x80) return i;
    }
    const auto b1 = static_cast<unsigned char>(text[i + 1 < text.size() ? i + 1 : i]);
    if ((n == 3 && ((b == 0xE0 && b1 < 0xA0) || (b == 0xED && b1 >= 0xA0))) ||
        (n == 4 && ((b == 0xF0 && b1 < 0x90) || (b == 0xF4 && b1 >= 0x90)))) {
      return i;  // overlong, a surrogate or beyond U+10FFFF
    }
    i += n;
  }
  return i;
}

constexpr std::string_view kFormat = "staa-polygon-map/1";
// Maps are metric and robot-sized; a coordinate beyond 1000 km is a corrupt file, and the
// bound keeps every cross product in the checks below far from overflow.
constexpr double kMaxCoordinate = 1e6;

using yaml_support::formatNumber;
std::string point(const Vec2& p) { return yaml_support::formatPoint(p); }

// ---- checks shared by the reader (which adds the line) and validatePolygonMap ----

std::string coordinateProblem(const Vec2& p) {
  if (!std::isfinite(p.x()) || !std::isfinite(p.y())) return "is not finite " + point(p);
  if (std::abs(p.x()) > kMaxCoordinate || std::abs(p.y()) > kMaxCoordinate) {
    return "is out of range " + point(p) + " (|x|, |y| <= " + formatNumber(kMaxCoordinate) + " m)";
  }
  return "";
}

// A simple polygon (io::polygonProblem) within the coordinate range.
std::string polygonProblem(PolygonView poly) {
  if (poly.size() >= 3) {
    for (std::size_t k = 0; k < poly.size(); ++k) {
      if (std::isfinite(poly[k].x()) && std::isfinite(poly[k].y())) {
        if (std::string p = coordinateProblem(poly[k]); !p.empty()) return "vertex " + std::to_string(k) + " " + p;
      }
    }
  }
  return io::polygonProblem(poly);
}

std::string boundsProblem(const Box& b) {
  for (const Vec2& p : {b.min, b.max}) {
    if (std::string e = coordinateProblem(p); !e.empty()) return "corner " + e;
  }
  if (!(b.min.x() < b.max.x())) {
    return "xmin (" + formatNumber(b.min.x()) + ") must be less than xmax (" + formatNumber(b.max.x()) + ")";
  }
  if (!(b.min.y() < b.max.y())) {
    return "ymin (" + formatNumber(b.min.y()) + ") must be less than ymax (" + formatNumber(b.max.y()) + ")";
  }
  return "";
}

std::string indexed(const char* list, std::size_t i) { return std::string(list) + "[" + std::to_string(i) + "]"; }

// ---- reading ----

PolygonMap readDocument(const io::ConfigValue& root) {
  PolygonMap map;
  if (const io::ConfigValue name = root.get("name"); name.present()) {
    map.name = name.string("a string");
    if (const std::size_t at = firstInvalidUtf8(map.name); at < map.name.size()) {
      name.fail("not valid UTF-8 (byte " + std::to_string(at) + " of the name is " +
                std::to_string(static_cast<unsigned char>(map.name[at])) + ")");
    }
  }
  // `bounds:` left empty means no bounds.
  if (const io::ConfigValue bounds = root.get("bounds"); bounds.present()) {
    const auto v = bounds.numbers<4>("4 numbers [xmin, ymin, xmax, ymax]");
    const Box box{{v[0], v[1]}, {v[2], v[3]}};
    if (std::string e = boundsProblem(box); !e.empty()) bounds.fail(e);
    map.bounds = box;
  }
  if (const io::ConfigValue obstacles = root.get("obstacles"); obstacles.present()) {
    obstacles.list("a list of polygons");
    if (obstacles.size() > kMaxMapPolygons) {
      obstacles.fail("has " + std::to_string(obstacles.size()) + " polygons, beyond the bound of " +
                     std::to_string(kMaxMapPolygons) + " per map");
    }
    map.obstacles.reserve(obstacles.size());
    for (std::size_t i = 0; i < obstacles.size(); ++i) {
      const io::ConfigValue poly = obstacles[i];
      Polygon p = poly.points("a list of [x, y] vertices", kMaxPolygonVertices, " vertices per polygon");
      if (std::string e = polygonProblem(p); !e.empty()) poly.fail(e);
      map.obstacles.push_back(std::move(p));
    }
  }
  if (const io::ConfigValue goals = root.get("goals"); goals.present()) {
    goals.list("a list of [x, y] points");
    if (goals.size() > kMaxMapGoals) {
      goals.fail("has " + std::to_string(goals.size()) + " goals, beyond the bound of " + std::to_string(kMaxMapGoals) + " per map");
    }
    map.goals.reserve(goals.size());
    for (std::size_t i = 0; i < goals.size(); ++i) {
      // A goal inside an obstacle is kept: whether it is reachable is the scenario's business.
      const Vec2 g = goals[i].point();
      if (std::string e = coordinateProblem(g); !e.empty()) goals[i].fail("goal " + e);
      map.goals.push_back(g);
    }
  }
  return map;
}

}  // namespace

PolygonMap parsePolygonMap(const std::string& yaml_text, const std::string& source) {
  return io::readAs<MapError>(source, [&] {
    const io::ConfigDocument doc = io::ConfigDocument::parse(yaml_text, source);
    return readDocument(doc.root(kFormat, {"format", "name", "bounds", "obstacles", "goals"}));
  });
}

PolygonMap loadPolygonMap(const std::filesystem::path& path) {
  const std::string source = path.string();
  return io::readAs<MapError>(source, [&] { return parsePolygonMap(io::ConfigDocument::readFile(path, "map file"), source); });
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
  if (!out) throw MapError(source + ": cannot open the file for writing");
  out << toYaml(map);
  out.close();
  if (!out) throw MapError(source + ": write error");
}

void validatePolygonMap(const PolygonMap& map, const std::string& source) {
  if (map.obstacles.size() > kMaxMapPolygons) {
    throw MapError(source + ": obstacles: has " + std::to_string(map.obstacles.size()) + " polygons, beyond the bound of " +
                   std::to_string(kMaxMapPolygons) + " per map");
  }
  if (map.goals.size() > kMaxMapGoals) {
    throw MapError(source + ": goals: has " + std::to_string(map.goals.size()) + " goals, beyond the bound of " +
                   std::to_string(kMaxMapGoals) + " per map");
  }
  if (map.bounds) {
    if (std::string e = boundsProblem(*map.bounds); !e.empty()) throw MapError(source + ": bounds: " + e);
  }
  for (std::size_t i = 0; i < map.obstacles.size(); ++i) {
    if (map.obstacles[i].size() > kMaxPolygonVertices) {
      throw MapError(source + ": " + indexed("obstacles", i) + ": has " + std::to_string(map.obstacles[i].size()) +
                     " points, beyond the bound of " + std::to_string(kMaxPolygonVertices) + " vertices per polygon");
    }
    if (std::string e = polygonProblem(map.obstacles[i]); !e.empty()) throw MapError(source + ": " + indexed("obstacles", i) + ": " + e);
  }
  for (std::size_t i = 0; i < map.goals.size(); ++i) {
    if (std::string e = coordinateProblem(map.goals[i]); !e.empty()) throw MapError(source + ": " + indexed("goals", i) + ": goal " + e);
  }
}

}  // namespace staa
