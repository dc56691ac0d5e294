#pragma once
// Moving obstacles D with velocities, their constant-velocity predictions D(t) and inflated
// copies D'(t) (paper, Sec. III-D). Fixed capacity, sized at start-up; no allocation after.

#include "geometry/types.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
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

// How many moving obstacles a cycle plans against unless configured otherwise
// (ControlConfig::max_moving_obstacles, the one number every buffer is sized by).
inline constexpr std::size_t kDefaultMovingObstacleCapacity = 32;

class DynamicObstacleSet {
 public:
  // An observed hull with more vertices is simplified (conservatively: it only grows) to this
  // many, which leaves D'(t) room for at least one arc vertex per corner and a 90-degree
  // chord limit within FixedPolygon::kCapacity.
  static constexpr std::size_t kMaxHullVertices = 32;

  explicit DynamicObstacleSet(std::size_t max_obstacles = kDefaultMovingObstacleCapacity);
  std::size_t capacity() const { return obstacles_.size(); }

  // Sets the observed obstacles: each polygon is replaced by its convex hull (moving things
  // are compact; convexity allows SAT). A hull of more than kMaxHullVertices is simplified by
  // extending neighbouring edges over the cheapest edge, so it still contains the polygon;
  // polygons of any vertex count are accepted (hulled in chunks). Non-finite vertices are
  // ignored. velocities[k] belongs to polygons[k]; missing velocities count as zero.
  // turn_rates[k] (rad/s, counter-clockwise positive) is how fast obstacle k's velocity turns
  // (a unicycle's w; missing: 0); only predictTurning uses it.
  // Obstacles beyond max_obstacles are dropped and counted (per call). No allocation.
  void set(std::span<const PolygonView> polygons, std::span<const Vec2> velocities,
           std::span<const double> turn_rates = {});
  void clear();
  std::size_t size() const { return count_; }
  std::size_t dropped() const { return dropped_; }

  // D(t): obstacle k moved by velocity * t. Writes into `out` (no allocation).
  void predict(std::size_t k, double t, FixedPolygon& out) const;
  // D'(t): D(t) grown by `radius` (convex: every vertex offset along the outward normals with
  // round corners approximated by chords outside the true arc, so D'(t) contains the exact
  // grown shape). `arc_steps` segments per corner on average: the polygon gets
  // max(n, 4) * arc_steps arc vertices (at most FixedPolygon::kCapacity), shared among its
  // corners so that the widest chord angle is smallest (in proportion to the turning angles),
  // and never a chord spanning more than 90 degrees (a sharp corner gets no far-out spike).
  // A point (1 vertex) becomes a circumscribed circle, a segment a stadium. radius <= 0
  // gives D(t). k < size(). No allocation.
  void predictInflated(std::size_t k, double t, double radius, int arc_steps, FixedPolygon& out) const;

  // D(t) along a circle instead of a line: obstacle k keeps its speed (or the braking
  // hypothesis's distance, as displacement()) while its velocity turns at its turn rate, and
  // its polygon turns with it about its box centre (a unicycle driving at constant v and w).
  // Turn rate 0: predict(). No allocation.
  void predictTurning(std::size_t k, double t, FixedPolygon& out) const;

  const FixedPolygon& observed(std::size_t k) const { return obstacles_[k]; }
  Vec2 velocity(std::size_t k) const { return velocities_[k]; }
  double turnRate(std::size_t k) const { return turn_rates_[k]; }

  // How far obstacle k has moved at time t: velocity * t (constant velocity, the default), or
  // under the braking hypothesis (setBraking) at constant velocity for the reaction time and
  // then decelerating at `decel` to a stop. Every prediction (predict, predictInflated, and
  // the collision checks) goes through it.
  Vec2 displacement(std::size_t k, double t) const {
    const Vec2 v = velocities_[k];
    if (!(braking_decel_ > 0.0) || t <= reaction_s_) return v * t;
    const double speed = v.norm();
    if (speed <= 0.0) return v * t;
    const double tau = std::min(t - reaction_s_, speed / braking_decel_);
    const double d = speed * reaction_s_ + speed * tau - 0.5 * braking_decel_ * tau * tau;
    return v * (d / speed);
  }
  // The braking hypothesis: every obstacle keeps its velocity for `reaction_s`, then brakes at
  // `decel` (m/s^2) to a stop. decel <= 0: constant velocity again.
  void setBraking(double reaction_s, double decel) {
    reaction_s_ = std::max(0.0, reaction_s);
    braking_decel_ = decel;
  }
  // Copies the obstacles of `other` (up to this set's capacity; the rest are dropped and
  // counted) keeping this set's braking hypothesis. No allocation.
  void copyFrom(const DynamicObstacleSet& other);
  // The same without the obstacles k of `other` whose drop[k] is set (drop has other.size()
  // entries). No allocation.
  void copyExcept(const DynamicObstacleSet& other, std::span<const std::uint8_t> drop);

 private:
  static constexpr std::size_t kHullScratch = 128;  // points hulled per chunk
  void hullInto(PolygonView polygon, FixedPolygon& out);

  std::vector<FixedPolygon> obstacles_;
  std::vector<Vec2> velocities_;
  std::vector<double> turn_rates_;
  std::vector<Vec2> hull_scratch_;
  std::vector<Vec2> hull_out_;
  std::size_t count_ = 0;
  std::size_t dropped_ = 0;
  double reaction_s_ = 0.0;
  double braking_decel_ = 0.0;  // 0: constant velocity
};

}  // namespace staa
