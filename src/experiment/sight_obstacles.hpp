#pragma once
// staa-sim --obstacles sight: the ground truth within the line of sight. An agent gets the
// exact footprint, velocity and turn rate of every other body it could see from its centre
// (any vertex of the body within range_m on a segment that touches no map polygon; every
// direction, bodies do not hide each other), and keeps a body that went out of sight for
// keep_s at its last seen footprint moved on at its last velocity, then forgets it.
//
// It is the diagnostic between truth and depth+scan: a perfect sensor and tracker that only
// lack the truth's view through walls. Its gap to the truth is what occlusion costs; the gap
// from it to depth+scan is what the sensors' field, noise, latency and tracking cost.

#include "experiment/agent_camera.hpp"
#include "geometry/line_of_sight.hpp"
#include "geometry/types.hpp"
#include "perception/depth_obstacles.hpp"

#include <cstddef>
#include <vector>

namespace staa {

// The defaults are the depth+scan runs': the scanner's range, perception's keep_unseen_s.
struct SightConfig {
  double range_m = kScanRangeM;
  double keep_s = DepthObstaclesConfig{}.keep_unseen_s;
};

class SightObstacles {
 public:
  // `sight`: the map's line of sight, shared by every agent's filter (outlives it). `bodies`:
  // how many other bodies there are at most, each of up to max_vertices.
  SightObstacles(const LineOfSight& sight, std::size_t bodies, std::size_t max_vertices, SightConfig config);

  // Body k now, seen from `eye` at time now: remembered when in sight. Returns whether it is
  // reported this cycle (in sight, or out of sight for at most keep_s); its reported state is
  // then footprint(k), velocity(k) and turnRate(k) until the next observe of k.
  // Allocation-free.
  bool observe(double now, const Vec2& eye, std::size_t k, PolygonView footprint, const Vec2& velocity,
               double turn_rate);

  PolygonView footprint(std::size_t k) const { return PolygonView(shown_[k].data(), count_[k]); }
  Vec2 velocity(std::size_t k) const { return velocity_[k]; }
  double turnRate(std::size_t k) const { return turn_rate_[k]; }
  bool inSight(std::size_t k) const { return in_sight_[k] != 0; }

 private:

  const LineOfSight* sight_;
  SightConfig config_;
  std::vector<Polygon> seen_;   // per body: its footprint when last in sight
  std::vector<Polygon> shown_;  // per body: what observe reported
  std::vector<std::size_t> count_;
  std::vector<Vec2> velocity_;
  std::vector<double> turn_rate_;
  std::vector<double> seen_at_;  // when last in sight; -inf: never
  std::vector<unsigned char> in_sight_;
};

}  // namespace staa
