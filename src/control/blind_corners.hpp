#pragma once
// A speed limit for blind corners. Perception sees only what lies in its sensors' line of
// sight; an agent behind a wall's corner appears when the line of sight passes that corner,
// and where it comes out it crosses the robot's way about level with the corner. The limit
// keeps the robot able to stop (after reaction_s) before it is level with the corner, less
// its clearance: two agents that meet at a corner, a junction or a door under the same rule
// each stop short of the crossing.
//
// The corners come from the known map, not from a sensor: a convex map vertex within range_m
// whose two edges lie on one side of the line of sight (it hides what is behind it), that the
// robot sees (no map edge crosses the line of sight), ahead of the robot by more than its
// clearance (nearer, the robot is in the crossing already: braking would keep it there) and
// within clearance + lateral_m of its line of travel (from a corner farther aside, an agent
// crosses open view before it reaches the robot's way, and the planner sees it coming). The
// limit is a command filter: the controller plans as before, and its command's speed is
// lowered to the cap, never faster than the robot can brake (a_max per cycle), along the same
// arc (w scaled with v).
//
// Built once from the map; speedCap() allocates nothing (the control cycle calls it).

#include "geometry/line_of_sight.hpp"
#include "geometry/polygon.hpp"
#include "geometry/types.hpp"

#include <limits>
#include <span>
#include <vector>

namespace staa {

struct BlindCornerConfig {
  bool enabled = false;
  double reaction_s = 0.2;   // from the other agent entering the line of sight to braking
  double decel = 0.0;        // m/s^2 assumed for the stop; 0: the robot's a_max
  double clearance_m = 0.0;  // taken from the corner's distance; 0: the footprint's circumradius
  double min_speed = 0.3;    // the cap never goes below this (m/s): the robot creeps round the corner
  double range_m = 3.0;      // corners farther than this are not considered
  double lateral_m = 0.5;    // ... nor those farther aside of the line of travel than clearance + this
};

// The cap for `room` metres to stop in: the speed v with v * reaction + v^2 / (2 decel) = room,
// at least min_speed. Pure; exposed for tests.
double blindCornerSpeed(double room, double reaction_s, double decel, double min_speed);

class BlindCorners {
 public:
  BlindCorners() = default;
  // `polygons`: the real obstacles (the map's, unenlarged). The config's zeros are resolved by
  // the caller (clearance, decel).
  BlindCorners(std::span<const Polygon> polygons, const BlindCornerConfig& config, double clearance, double decel);

  struct Cap {
    double speed = std::numeric_limits<double>::infinity();  // no corner: no cap
    Vec2 corner{0.0, 0.0};  // the corner that sets it
    double room = 0.0;      // how far ahead of the robot, less the clearance, it is
  };
  // The cap for a robot at `pose` driving forwards (heading theta).
  Cap speedCap(const Pose2& pose) const;

  bool enabled() const { return config_.enabled && !vertices_.empty(); }
  const BlindCornerConfig& config() const { return config_; }

 private:
  struct Vertex {
    Vec2 p, prev, next;
  };
  bool visible(const Vec2& from, const Vec2& corner) const;

  BlindCornerConfig config_;
  double clearance_ = 0.0;
  double decel_ = 1.0;
  std::vector<Vertex> vertices_;
  LineOfSight sight_;  // every map edge
};

}  // namespace staa
