// parseDaemonConfig (staad-config/1), as if the file were config/fuzz.yaml: its relative
// robot, map and CAN profile paths reach the repository's config/ files. What parses has
// finite positive rates and a valid map. Errors: ConfigError (and the formats' errors
// derived from it) only.
#include "fuzz_support.hpp"
#include "app/staad/config.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace staa;
  static const std::filesystem::path source = std::filesystem::path(STAA_SOURCE_DIR) / "config" / "fuzz.yaml";
  try {
    const staad::DaemonConfig c = staad::parseDaemonConfig(fuzz::text(data, size), source);
    for (const double hz : {c.control_hz, c.base_hz, c.perception_hz}) {
      fuzz::require(std::isfinite(hz) && hz > 0.0, "a rate not finite and > 0");
    }
    if (!c.map_from_ros) {
      try {
        validatePolygonMap(c.map, "fuzz config's map");
      } catch (const MapError& e) {
        fuzz::violated("the config's map does not validate", e.what());
      }
    }
  } catch (const staad::ConfigError&) {
  }
  return 0;
}
