#pragma once
// The static polygon map M (docs/ARCHITECTURE.md section 6, format `staa-polygon-map/1`).

#include "geometry/types.hpp"
#include "io/config_rules.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace staa {

// Bounds of a map file (docs/ARCHITECTURE.md, "Input bounds"); a file beyond one is refused
// naming it. Far above any real map: the office has 40 polygons of at most 40 vertices.
inline constexpr std::size_t kMaxPolygonVertices = 1'000'000;
inline constexpr std::size_t kMaxMapPolygons = 100'000;
inline constexpr std::size_t kMaxMapGoals = 100'000;

struct PolygonMap {
  std::string name;
  // Optional bounds [xmin, ymin, xmax, ymax]; everything outside is blocked.
  std::optional<Box> bounds;
  // Simple polygons, >= 3 vertices, either winding, may be non-convex, may overlap.
  std::vector<Polygon> obstacles;
  // Optional drop-off locations for scenarios and the simulator.
  std::vector<Vec2> goals;
};

// Raised for unreadable or invalid map files; what() names the file, the polygon's index
// where one is at fault, and what is wrong. Tools turn it into exit code 2.
class MapError : public io::ConfigError {
 public:
  using io::ConfigError::ConfigError;
};

// Parses YAML text; `source` names where it came from (a path) for error messages.
PolygonMap parsePolygonMap(const std::string& yaml_text, const std::string& source);
PolygonMap loadPolygonMap(const std::filesystem::path& path);
std::string toYaml(const PolygonMap& map);
void savePolygonMap(const PolygonMap& map, const std::filesystem::path& path);

// Checks every polygon (>= 3 vertices, finite, simple, non-zero area), the bounds and the
// goals; throws MapError naming `source`, the polygon's index and the problem.
void validatePolygonMap(const PolygonMap& map, const std::string& source);

}  // namespace staa
