// parseRosMapInfo (map_server's YAML): what parses is in range. Errors: MapError only.
#include "fuzz_support.hpp"
#include "map/ros_import.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace staa;
  try {
    const RosMapInfo info = parseRosMapInfo(fuzz::text(data, size), "fuzz.yaml", "/nonexistent-fuzz-dir");
    fuzz::require(std::isfinite(info.resolution) && info.resolution > 0.0, "resolution not finite and > 0");
    fuzz::require(std::isfinite(info.origin.x) && std::isfinite(info.origin.y) && std::isfinite(info.origin.theta),
                  "origin not finite");
    fuzz::require(std::isfinite(info.occupied_thresh) && std::isfinite(info.free_thresh), "thresholds not finite");
    fuzz::require(!info.image.empty(), "empty image path");
  } catch (const MapError&) {
  }
  return 0;
}
