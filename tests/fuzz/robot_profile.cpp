// parseRobotProfile (staa-robot/1): a profile that parses has a counter-clockwise simple
// footprint, finite limits in their ranges, a body height and, with a camera, values
// staa-sim's simulated camera can use. Errors: ProfileError only.
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
    fuzz::require(std::isfinite(p.height_m) && p.height_m > 0.0, "height not finite and > 0");
    if (p.has_camera) {
      // What staa-sim's AgentCamera and perception rely on (experiment/agent_camera.cpp).
      const DepthCameraProfile& c = p.camera;
      fuzz::require(std::isfinite(c.z) && c.z > 0.0, "camera below the floor");
      fuzz::require(std::hypot(c.x, c.y) <= DepthCameraProfile::kMaxMountOffsetM * std::sqrt(2.0) * (1 + 1e-12),
                    "camera mount off the base");
      fuzz::require(c.fov_h_deg >= 1.0 && c.fov_h_deg < 170.0 && c.fov_v_deg >= 1.0 && c.fov_v_deg < 170.0,
                    "field of view out of range");
      fuzz::require(c.min_range_m >= 0.0 && c.max_range_m > c.min_range_m && c.max_range_m <= 65.535,
                    "depth range out of order");
      fuzz::require(c.rate_hz > 0.0 && c.rate_hz <= 1000.0, "frame rate out of range");
      fuzz::require(c.latency_s >= 0.0 && c.latency_s <= DepthCameraProfile::kMaxLatencyFrames / c.rate_hz,
                    "latency beyond the frames in flight");
      fuzz::require(c.dropout >= 0.0 && c.dropout < 1.0 && c.frame_loss >= 0.0 && c.frame_loss < 1.0,
                    "a fraction out of [0, 1)");
      fuzz::require(std::isfinite(c.noise_mm_per_m2) && std::isfinite(c.pan_rate) && std::isfinite(c.look_ahead_m),
                    "a camera value not finite");
    }
    if (p.has_scanner) {
      // What staa-sim's ScanRenderer relies on (world/sim_laser_scan.cpp's checks).
      const ScannerProfile& c = p.scanner;
      fuzz::require(std::isfinite(c.z) && c.z > 0.0, "scan plane below the floor");
      fuzz::require(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.yaw), "scanner mount not finite");
      fuzz::require(c.fov_deg >= 1.0 && c.fov_deg <= 360.0, "sweep out of range");
      fuzz::require(c.beams >= 2 && c.beams <= ScannerProfile::kMaxBeams, "beams out of range");
      fuzz::require(c.min_range_m >= 0.0 && c.max_range_m > c.min_range_m && std::isfinite(c.max_range_m),
                    "scan range out of order");
      fuzz::require(c.noise_m >= 0.0 && c.noise_m <= 1.0 && c.dropout >= 0.0 && c.dropout < 1.0,
                    "scan noise or dropout out of range");
    }
  } catch (const ProfileError&) {
  }
  return 0;
}
