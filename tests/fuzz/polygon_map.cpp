// parsePolygonMap (staa-polygon-map/1): a map that parses validates, and writes out
// (toYaml) to a text that parses back to the same map bit for bit. Errors: MapError only.
#include "fuzz_support.hpp"
#include "map/polygon_map.hpp"

namespace {
bool sameMap(const staa::PolygonMap& a, const staa::PolygonMap& b) {
  if (a.name != b.name || a.bounds.has_value() != b.bounds.has_value()) return false;
  if (a.bounds && (a.bounds->min != b.bounds->min || a.bounds->max != b.bounds->max)) return false;
  return a.obstacles == b.obstacles && a.goals == b.goals;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace staa;
  PolygonMap map;
  try {
    map = parsePolygonMap(fuzz::text(data, size), "fuzz.yaml");
  } catch (const MapError&) {
    return 0;
  }
  try {
    validatePolygonMap(map, "fuzz.yaml");
  } catch (const MapError& e) {
    fuzz::violated("a parsed map does not validate", e.what());
  }
  const std::string yaml = toYaml(map);
  try {
    fuzz::require(sameMap(parsePolygonMap(yaml, "again.yaml"), map), "toYaml does not read back to the same map", yaml);
  } catch (const MapError& e) {
    fuzz::violated("toYaml of a parsed map does not parse", std::string(e.what()) + "\n" + yaml);
  }
  return 0;
}
