// parseRobotProfile (staa-robot/1): a profile that parses has a counter-clockwise simple
// footprint and finite limits in their ranges. Errors: ProfileError only.
#include "fuzz_support.hpp"
#include "geometry/polygon.hpp"
#include "io/config_reader.hpp"
#include "robot/robot_profile.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace staa;
  try {
    const RobotProfile p = parseRobotProfile(fuzz::text(data, size), "fuzz.yaml");
    fuzz::require(io::polygonProblem(p.footprint).empty(), "footprint not simple", io::polygonProblem(p.footprint));
    fuzz::require(signedArea(p.footprint) > 0.0, "footprint not counter-clockwise");
    const MotionLimits& l = p.limits;
    fuzz::require(std::isfinite(l.v_max) && l.v_max > 0.0 && std::isfinite(l.v_min) && l.v_min <= 0.0,
                  "v limits out of range");
    fuzz::require(std::isfinite(l.w_max) && l.w_max > 0.0 && std::isfinite(l.a_max) && l.a_max > 0.0 &&
                      std::isfinite(l.b_max) && l.b_max > 0.0,
                  "w, a or b limits out of range");
    fuzz::require(std::isfinite(p.circumradius()) && p.circumradius() > 0.0, "circumradius not finite and > 0");
  } catch (const ProfileError&) {
  }
  return 0;
}
