#pragma once
// A simulated planar laser scanner (staa-sim --obstacles depth+scan): each beam's range to the
// nearest wall, map obstacle or mover cut by the scan plane, with range noise and dropouts.
// The map's obstacles and bounds reach above every scan plane; a mover is hit when it is
// taller than the plane. Everything is sized at construction; render() allocates nothing.

#include "geometry/splitmix64.hpp"
#include "geometry/types.hpp"
#include "hal/laser_scan.hpp"
#include "map/polygon_map.hpp"
#include "world/sim_depth_camera.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace staa::hal {

struct SimScanConfig {
  ScanMount mount;
  // Beams from angle_min to angle_max (rad, from the mount's yaw), both included.
  double angle_min = -0.75 * kPi;
  double angle_max = 0.75 * kPi;
  int beams = 1081;
  double range_min = 0.05;  // m: nearer, no return
  double range_max = 20.0;  // m: farther, no return
  double noise_m = 0.01;    // range noise, standard deviation (m)
  double dropout = 0.0;     // fraction of the beams with no return, at random
  std::uint64_t seed = 1;

  // `beams` over a sweep of fov_deg centred on the mount's yaw (a full turn's last beam one
  // increment short of its first, which it would repeat).
  void centredSweep(double fov_deg, int beam_count) {
    const double half = 0.5 * fov_deg * kPi / 180.0;
    angle_min = -half;
    angle_max = fov_deg >= 360.0 ? half - 2.0 * half / beam_count : half;
    beams = beam_count;
  }
};

class ScanRenderer {
 public:
  static constexpr std::size_t kMaxMoverVertices = 64;  // per mover (a larger one is unseen)

  // Throws std::invalid_argument naming the field for a bad config value.
  ScanRenderer(const PolygonMap& map, const SimScanConfig& config);

  // The scan from a robot whose base is at `robot` (map frame) among `movers`: every field of
  // `out` but stamp and sequence (the caller's).
  void render(const Pose2& robot, std::span<const PrismView> movers, LaserScan& out);

  const SimScanConfig& config() const { return config_; }

 private:
  // The segment [a, b] (map frame) seen from `sensor`: each beam it crosses takes the nearer
  // of its range and the segment's.
  void castEdge(const Vec2& a, const Vec2& b, const Vec2& sensor, double zero_bearing);

  SimScanConfig config_;
  double increment_ = 0.0;
  StaticPrisms static_;
  std::vector<double> range_;  // per beam, this frame: the nearest hit (range_max + 1: none)
  std::vector<Vec2> local_;      // per beam: its direction in the base frame
  std::vector<Vec2> direction_;  // ... in the map frame, this frame
  SplitMix64 rng_;
};

}  // namespace staa::hal
