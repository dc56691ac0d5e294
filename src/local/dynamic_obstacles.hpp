#pragma once
// Moving obstacles D with velocities, their constant-velocity predictions D(t) and inflated
// copies D'(t) (paper, Sec. III-D). Fixed capacity, sized at start-up; no allocation after.

#include "geometry/types.hpp"

#include <array>
#include <cstddef>
#include <span>
#include <vector>

namespace staa {

// One predicted or inflated polygon, fixed capacity.
struct FixedPolygon {
  static constexpr std::size_t kCapacity = 64;
  std::array<Vec2, kCapacity> v;
  std::size_t n = 0;
  PolygonView view() const { return {v.data(), n}; }
  Box box;
};

class DynamicObstacleSet {
 public:
  explicit DynamicObstacleSet(std::size_t max_obstacles = 32);

  // Sets the observed obstacles: each polygon is replaced by its convex hull (moving things
  // are compact; convexity allows SAT), truncated to FixedPolygon::kCapacity. Obstacles beyond
  // max_obstacles are dropped and counted. No allocation.
  void set(std::span<const PolygonView> polygons, std::span<const Vec2> velocities);
  void clear();
  std::size_t size() const { return count_; }
  std::size_t dropped() const { return dropped_; }

  // D(t): obstacle k moved by velocity * t. Writes into `out` (no allocation).
  void predict(std::size_t k, double t, FixedPolygon& out) const;
  // D'(t): D(t) grown by `radius` (convex: every vertex offset along the outward normals with
  // round corners approximated by chords outside the true arc, so D'(t) contains the exact
  // grown shape). `arc_steps` segments per corner. No allocation.
  void predictInflated(std::size_t k, double t, double radius, int arc_steps, FixedPolygon& out) const;

  const FixedPolygon& observed(std::size_t k) const { return obstacles_[k]; }
  Vec2 velocity(std::size_t k) const { return velocities_[k]; }

 private:
  std::vector<FixedPolygon> obstacles_;
  std::vector<Vec2> velocities_;
  std::vector<Vec2> hull_scratch_;
  std::vector<Vec2> hull_out_;
  std::size_t count_ = 0;
  std::size_t dropped_ = 0;
};

}  // namespace staa
