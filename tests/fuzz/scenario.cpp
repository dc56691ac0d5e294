// parseScenario (staa-scenario/1), as if the file were config/fuzz.yaml: its relative map
// and robot profile paths reach the repository's config/maps and config/robots. A scenario
// that parses has a valid map, a finite start and goal and movers with >= 1 waypoint and a
// finite speed >= 0. Errors: ScenarioError only.
#include "fuzz_support.hpp"
#include "world/scenario.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace staa;
  static const std::filesystem::path source = std::filesystem::path(STAA_SOURCE_DIR) / "config" / "fuzz.yaml";
  try {
    const Scenario s = parseScenario(fuzz::text(data, size), source);
    try {
      validatePolygonMap(s.map, "fuzz scenario's map");
    } catch (const MapError& e) {
      fuzz::violated("a scenario's map does not validate", e.what());
    }
    for (const Pose2& p : {s.start, s.goal}) {
      fuzz::require(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta), "start or goal not finite");
    }
    for (const Mover& m : s.movers) {
      fuzz::require(!m.waypoints.empty() && std::isfinite(m.speed) && m.speed >= 0.0, "a mover out of its rules");
    }
  } catch (const ScenarioError&) {
  }
  return 0;
}
