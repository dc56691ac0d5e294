// DepthObstacleDetector::process on arbitrary depth frames (any millimetre values), robot
// poses and per-frame mounts (NaN and infinities included), in the office map: two frames a
// control period apart (the second one tracks); with flag 8 also staa-sim's agents' settings
// over 8 frames that turn away from what was seen (kept tracks). The obstacles are finite
// convex outlines of at most max_vertices with finite velocities no faster than
// max_speed_mps, kept no longer than keep_unseen_s. With flag 16 each frame comes with a scan
// (ScanInput) of arbitrary geometry, pose and mount, its ranges the same bytes read as floats:
// the same holds. No exception.
#include "fuzz_support.hpp"
#include "map/polygon_map.hpp"
#include "perception/depth_obstacles.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

namespace {
using namespace staa;

void requireSound(const hal::ObstacleFrame& out, const DepthObstaclesConfig& config) {
  fuzz::require(out.count <= hal::ObstacleFrame::kMaxObstacles, "more obstacles than the frame holds");
  for (std::size_t i = 0; i < out.count; ++i) {
    const auto& o = out.obstacles[i];
    fuzz::require(o.n >= 3 && o.n <= config.max_vertices, "an outline with too few or too many vertices");
    for (std::size_t k = 0; k < o.n; ++k) {
      fuzz::require(std::isfinite(o.vertices[k].x()) && std::isfinite(o.vertices[k].y()), "a vertex not finite");
    }
    fuzz::require(std::isfinite(o.velocity.x()) && std::isfinite(o.velocity.y()) && std::isfinite(o.turn_rate),
                  "a velocity not finite");
    fuzz::require(o.velocity.norm() <= config.max_speed_mps * (1.0 + 1e-9), "faster than max_speed_mps");
    fuzz::require(o.unseen_s >= 0.0 && o.unseen_s <= config.keep_unseen_s + 1e-6, "kept longer than keep_unseen_s");
  }
}

// staa-sim's agents' settings (experiment/agent_camera.cpp, agentPerceptionConfig): tracks
// kept out of view with growing outlines, new tracks grown by their velocity's uncertainty,
// the hidden side extended, the robot's own disc kept clear.
DepthObstaclesConfig agentConfig() {
  DepthObstaclesConfig c;
  c.min_depth_m = 0.5;
  c.max_speed_mps = 2.5;
  c.acceleration_mps2 = 4.0;
  c.hidden_depth_m = 0.5;
  c.self_clearance_m = 0.47;
  c.uncertainty_horizon_s = 1.0 / 3.0;
  return c;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const PolygonMap map = loadPolygonMap(std::filesystem::path(STAA_SOURCE_DIR) / "config/maps/office.yaml");
  static const hal::CameraMount mount{0.0, 0.0, 1.0, 0.0, 0.3, 0.0};
  static DepthObstacleDetector detector(map, hal::CameraIntrinsics{}, mount);
  static const auto frame = std::make_unique<hal::DepthFrame>();
  static hal::ObstacleFrame out;

  fuzz::Fields in(data, size);
  Pose2 robot{in.take<double>(), in.take<double>(), in.take<double>()};
  const std::uint8_t flags = in.take<std::uint8_t>();
  frame->has_mount = (flags & 1) != 0;
  frame->mount = {in.take<double>(), in.take<double>(), in.take<double>(),
                  in.take<double>(), in.take<double>(), in.take<double>()};
  if ((flags & 2) == 0) robot = {2.0, 4.5, 0.0};  // mostly a pose inside the office
  if ((flags & 4) == 0) frame->mount = mount;
  static const auto scan = std::make_unique<hal::LaserScan>();
  ScanInput scan_input;
  if ((flags & 16) != 0) {
    scan->angle_min = in.take<double>();
    scan->angle_increment = in.take<double>();
    scan->range_min = in.take<double>();
    scan->range_max = in.take<double>();
    scan->count = in.take<std::uint16_t>();
    scan_input = ScanInput{scan.get(),
                           hal::ScanMount{in.take<double>(), in.take<double>(), in.take<double>(), in.take<double>()},
                           Pose2{in.take<double>(), in.take<double>(), in.take<double>()}};
    if ((flags & 32) == 0) {  // mostly a sweep that passes hal::scanProblem, from the frame's pose
      scan->angle_min = -2.356;
      scan->angle_increment = 0.0043633;
      scan->range_min = 0.05;
      scan->range_max = 20.0;
      scan->count = 1081;
      scan_input.robot = robot;
    }
    const std::size_t m = in.restSize() / 4;
    for (std::size_t i = 0; i < scan->ranges.size(); ++i) {
      float r = 0.0F;
      if (m > 0) std::memcpy(&r, in.rest() + 4 * (i % m), sizeof r);
      scan->ranges[i] = r;
    }
  }
  // The rest, tiled over the frame: a small input is a repeating pattern of depths.
  const std::size_t n = in.restSize() / 2;
  for (std::size_t i = 0; i < frame->depth_mm.size(); ++i) {
    frame->depth_mm[i] = n == 0 ? 0 : static_cast<std::uint16_t>(in.rest()[2 * (i % n)] | (in.rest()[2 * (i % n) + 1] << 8));
  }
  detector.resetTracks();
  for (int k = 0; k < 2; ++k) {
    frame->stamp = 1'000'000'000 + k * 33'000'000;
    frame->sequence = static_cast<std::uint64_t>(k);
    detector.process(*frame, robot, out, scan_input);
    requireSound(out, detector.config());
  }
  // Flag 8: staa-sim's settings over more frames: the same depths seen 4 times (tracks are
  // confirmed), then with the robot turned away (they leave the view and are kept, grown),
  // then an empty frame.
  if ((flags & 8) != 0) {
    static DepthObstacleDetector agent(map, hal::CameraIntrinsics{}, mount, agentConfig());
    agent.resetTracks();
    for (int k = 0; k < 8; ++k) {
      Pose2 at = robot;
      if (k >= 4) at.theta += 0.8 * (k - 3);
      if (k == 7) std::fill(frame->depth_mm.begin(), frame->depth_mm.end(), std::uint16_t{0});
      frame->stamp = 2'000'000'000LL + k * 33'333'333LL;
      frame->sequence = static_cast<std::uint64_t>(k);
      agent.process(*frame, at, out, scan_input);
      requireSound(out, agent.config());
    }
  }
  return 0;
}
