#pragma once
// Goal locations for a map that has none (an imported ROS map): well spread points with room
// for the robot around them, all in one connected part of the free space, so that agents
// driving between random goals (the multi-agent experiment, Sec. IV-B) can reach every one.

#include "map/polygon_map.hpp"

#include <cstdint>
#include <vector>

namespace staa {

struct GoalPlacement {
  int count = 40;              // at most this many goals (fewer when the free space is small)
  // Distance every goal keeps from every obstacle and from the bounds. 0.6 m leaves the
  // paper's agent (circumradius 0.47 m) room to stand at a goal in any heading.
  double clearance_m = 0.6;
  double min_spacing_m = 1.5;  // between any two goals
  std::uint64_t seed = 1;      // picks the first goal; the rest follow from it
  double lattice_m = 0.25;     // candidate spacing (coarsened on huge maps)
};

// Candidates are the points of a lattice (multiples of lattice_m) inside the bounds (or, for
// a map without bounds, the obstacles' bounding box) with at least clearance_m to every
// obstacle and to the bounds, in the largest connected part of the free space at that
// clearance (so every goal is reachable from every other by a disc of radius clearance_m).
// From a seeded first candidate, farthest-point sampling adds the candidate farthest from the
// goals chosen so far until `count` goals or none is min_spacing_m away from them.
// Deterministic on every platform for a seed (SplitMix64, integer lattice, no std
// distributions). Throws MapError naming the map when no place has the clearance, and
// std::invalid_argument naming the option for a bad option.
std::vector<Vec2> placeGoals(const PolygonMap& map, const GoalPlacement& options);

}  // namespace staa
