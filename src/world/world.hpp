#pragma once
// The simulator's world for one robot: a unicycle with the profile's limits in a polygon map,
// among scripted movers, with exact collision and clearance measurement. Not the real-time
// cycle: it allocates at construction and keeps scratch buffers, and it is deterministic
// (the same calls give the same states bit for bit).

#include "geometry/types.hpp"
#include "map/polygon_map.hpp"
#include "robot/robot_profile.hpp"
#include "robot/unicycle.hpp"
#include "world/scenario.hpp"

#include <cstddef>
#include <vector>

namespace staa {

struct RobotState {
  Pose2 pose;
  double v = 0.0;  // m/s
  double w = 0.0;  // rad/s
};

struct StepOutcome {
  bool collided = false;     // the motion hit an obstacle, a mover or the map bounds
  bool new_episode = false;  // ... and that started a new collision episode
};

class World {
 public:
  World(PolygonMap map, RobotProfile profile, const Pose2& start, std::vector<Mover> movers = {});
  explicit World(const Scenario& scenario);

  // Advances time by dt (> 0, finite; throws std::invalid_argument otherwise; non-finite
  // commands too). The commands, clamped to [v_min, v_max] and [-w_max, w_max], are
  // approached by at most a_max*dt and b_max*dt; the robot then drives the arc at the new
  // (v, w) for dt while the movers walk to their positions at the new time. If the swept
  // motion touches anything (checked at samples <= 1 cm of travel apart against the movers'
  // new positions, so a thin wall is not tunnelled through), the robot stops at the last
  // free point of its arc (found by bisection, within ~1e-9 of the step) with v = w = 0; it
  // stays where it was when a mover ran into it. A collision episode is counted once per
  // contact: a new one starts only after a step without collision.
  StepOutcome step(double dt, double v_cmd, double w_cmd);

  double time() const { return time_; }
  const RobotState& robot() const { return robot_; }
  // Places the robot (tests, tools); velocities are clamped to the limits. Does not count a
  // collision and does not touch min_clearance.
  void setRobotState(const RobotState& state);
  const RobotProfile& profile() const { return profile_; }
  const PolygonMap& map() const { return map_; }

  std::size_t moverCount() const { return movers_.size(); }
  const Mover& mover(std::size_t i) const { return movers_[i].spec; }
  Vec2 moverPosition(std::size_t i) const { return movers_[i].position; }
  Vec2 moverVelocity(std::size_t i) const { return movers_[i].velocity; }
  // The mover's polygon in the world frame at the current time.
  Polygon moverPolygon(std::size_t i) const;
  // Time for one round trip along the waypoints (0 for a mover that stands still).
  double moverPeriod(std::size_t i) const;

  // The robot's footprint in the world frame at its current pose.
  Polygon footprint() const;
  // Whether the footprint at `pose` touches an obstacle, a mover (at the current time) or
  // reaches the map bounds. Touching counts.
  bool collides(const Pose2& pose) const;
  // Smallest distance between the footprint and any obstacle, mover or the bounds, now
  // (0 when touching or overlapping; infinity in an empty unbounded world).
  double clearance() const;
  // Smallest clearance seen since construction, over the states after every step; 0 once a
  // collision has happened.
  double minClearance() const { return min_clearance_; }
  int collisionEpisodes() const { return episodes_; }
  bool inContact() const { return in_contact_; }

 private:
  struct MoverTrack {
    Mover spec;
    std::vector<double> cumulative;  // arc length at each waypoint
    double length = 0.0;             // one way
    Box box;                         // of the polygon about its origin
    Vec2 position{0.0, 0.0};
    Vec2 velocity{0.0, 0.0};
  };

  void updateMovers();
  void placeMover(MoverTrack& m) const;

  PolygonMap map_;
  RobotProfile profile_;
  std::vector<Box> obstacle_boxes_;
  std::vector<MoverTrack> movers_;
  RobotState robot_;
  double time_ = 0.0;
  double min_clearance_ = 0.0;
  int episodes_ = 0;
  bool in_contact_ = false;
  // Scratch polygons reused by the const queries (a World is not shared between threads).
  mutable Polygon body_;
  mutable Polygon other_;
};

}  // namespace staa
