#include "experiment/sight_obstacles.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace staa {

SightObstacles::SightObstacles(const LineOfSight& sight, std::size_t bodies, std::size_t max_vertices,
                               SightConfig config)
    : sight_(&sight),
      config_(config),
      seen_(bodies, Polygon(max_vertices)),
      shown_(bodies, Polygon(max_vertices)),
      count_(bodies, 0),
      velocity_(bodies, Vec2(0.0, 0.0)),
      turn_rate_(bodies, 0.0),
      seen_at_(bodies, -std::numeric_limits<double>::infinity()),
      in_sight_(bodies, 0) {
  if (!(config.range_m > 0.0) || !(config.keep_s >= 0.0)) {
    throw std::invalid_argument("SightObstacles: range_m must be > 0 and keep_s >= 0");
  }
}

bool SightObstacles::observe(double now, const Vec2& eye, std::size_t k, PolygonView footprint, const Vec2& velocity,
                             double turn_rate) {
  const std::size_t n = std::min(footprint.size(), seen_[k].size());
  if (sight_->seesAny(eye, footprint, config_.range_m)) {
    std::copy_n(footprint.begin(), n, seen_[k].begin());
    std::copy_n(footprint.begin(), n, shown_[k].begin());
    count_[k] = n;
    velocity_[k] = velocity;
    turn_rate_[k] = turn_rate;
    seen_at_[k] = now;
    in_sight_[k] = 1;
    return true;
  }
  in_sight_[k] = 0;
  const double unseen = now - seen_at_[k];
  if (!(unseen <= config_.keep_s)) return false;
  // Where it would be had it kept its velocity (the planner predicts on from there).
  const Vec2 moved = velocity_[k] * unseen;
  for (std::size_t v = 0; v < count_[k]; ++v) shown_[k][v] = seen_[k][v] + moved;
  return true;
}

}  // namespace staa
