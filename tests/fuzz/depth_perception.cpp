// DepthObstacleDetector::process on arbitrary depth frames (any millimetre values), robot
// poses and per-frame mounts (NaN and infinities included), in the office map: two frames a
// control period apart (the second one tracks). The obstacles are finite convex outlines of
// at most max_vertices with finite velocities no faster than max_speed_mps. No exception.
#include "fuzz_support.hpp"
#include "map/polygon_map.hpp"
#include "perception/depth_obstacles.hpp"

#include <cmath>
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
  }
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
  // The rest, tiled over the frame: a small input is a repeating pattern of depths.
  const std::size_t n = in.restSize() / 2;
  for (std::size_t i = 0; i < frame->depth_mm.size(); ++i) {
    frame->depth_mm[i] = n == 0 ? 0 : static_cast<std::uint16_t>(in.rest()[2 * (i % n)] | (in.rest()[2 * (i % n) + 1] << 8));
  }
  detector.resetTracks();
  for (int k = 0; k < 2; ++k) {
    frame->stamp = 1'000'000'000 + k * 33'000'000;
    frame->sequence = static_cast<std::uint64_t>(k);
    detector.process(*frame, robot, out);
    requireSound(out, detector.config());
  }
  return 0;
}
