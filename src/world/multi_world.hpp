#pragma once
// The simulator's world for several agents (the multi-agent experiment, paper Sec. IV-B):
// unicycles with one robot profile in a polygon map, stepped together. Solid agents are
// stopped by the map and by each other (exact footprint polygons, swept motion); ghosts pass
// through everything. Not the real-time cycle: scratch buffers are sized at construction
// (and when agents are added), and a step allocates nothing. Deterministic: the same calls
// give the same states bit for bit.
//
// How contact is resolved (one step):
//   1. every agent's velocities approach its (clamped) command within a_max*dt and b_max*dt;
//   2. the agents move one after the other in index order (agent i sees agents < i at their
//      new poses, agents > i at their old ones). A ghost drives its arc unchecked. A solid
//      agent sweeps its arc (samples <= 1 cm of travel apart) against the map, its bounds and
//      the other solid agents; at the first contact it stops at the last free point of the
//      arc (bisection, like World) with v = w = 0. The agent it ran into is in contact too.
//   3. An agent that starts a step already overlapping something (placed so, or never in
//      normal running since sweeps stop short) may move only so that it does not sink in
//      further: its centre must not approach the other agent's centre (or the wall's nearest
//      point; for the bounds, no vertex may get farther outside); any other motion keeps it
//      where it is with v = w = 0. So two agents in contact can always back away.
//   4. A solid agent overlapping a ghost after the step is in contact with it (no blocking).
// Contact episodes: a solid agent's episode starts at a step with contact and ends once its
// footprint is kContactRelease_m clear of everything it can touch (walls, bounds, solid
// agents, ghosts); each episode counts one collision. Ghosts never count.

#include "robot/robot_profile.hpp"
#include "geometry/types.hpp"
#include "map/polygon_map.hpp"
#include "world/world.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace staa {

enum class AgentBody : std::uint8_t {
  kSolid,  // stopped by the map and by solid agents; its contacts count
  kGhost,  // passes through everything, never in contact
};

struct AgentCommand {
  double v = 0.0;  // m/s
  double w = 0.0;  // rad/s
};

class MultiWorld {
 public:
  // A contact episode ends once the agent is this far from everything it can touch.
  static constexpr double kContactRelease_m = 0.01;

  MultiWorld(PolygonMap map, RobotProfile profile);

  // Adds an agent at `start` (standing still); returns its index. Not counted as a collision
  // even when it overlaps something (a later step will count it).
  std::size_t addAgent(const Pose2& start, AgentBody body);

  // Advances time by dt (> 0, finite) with one command per agent (commands.size() ==
  // size()); throws std::invalid_argument otherwise or for non-finite commands.
  void step(double dt, std::span<const AgentCommand> commands);

  std::size_t size() const { return agents_.size(); }
  double time() const { return time_; }
  const RobotState& agent(std::size_t i) const { return agents_[i].state; }
  AgentBody body(std::size_t i) const { return agents_[i].body; }
  // The agent's footprint in the world frame at its current pose.
  const Polygon& footprint(std::size_t i) const { return agents_[i].footprint; }
  // Its velocity vector (v along the heading).
  Vec2 velocity(std::size_t i) const;
  // Places an agent (tests, tools): velocities clamped to the limits; contact state and
  // counts untouched.
  void setAgentState(std::size_t i, const RobotState& state);

  // Whether agent i's motion was stopped, or it touched something, in the last step.
  bool collidedLastStep(std::size_t i) const { return agents_[i].hit; }
  // What agent i touched in the last step when collidedLastStep(i): another agent's index, or
  // -1 for the map (its obstacles or bounds).
  int touchedLastStep(std::size_t i) const { return agents_[i].touched; }
  bool inContact(std::size_t i) const { return agents_[i].in_contact; }
  int collisionEpisodes(std::size_t i) const { return agents_[i].episodes; }
  double distance(std::size_t i) const { return agents_[i].distance; }

  // Whether the footprint at `pose` touches the map (obstacles or bounds). Touching counts.
  bool touchesMap(const Pose2& pose) const;
  // Whether the footprint at `pose` touches the map or any agent's footprint.
  bool touchesAnything(const Pose2& pose) const;
  // Whether the footprints of agents i and j overlap or touch now.
  bool overlapping(std::size_t i, std::size_t j) const;

  const PolygonMap& map() const { return map_; }
  const RobotProfile& profile() const { return profile_; }

 private:
  struct Agent {
    RobotState state;
    AgentBody body = AgentBody::kSolid;
    Polygon footprint;
    Box box;
    bool hit = false;
    int touched = -1;  // what was hit: an agent's index, or -1 for the map
    bool in_contact = false;
    int episodes = 0;
    double distance = 0.0;
  };
  // What a footprint touched: nothing, the bounds, obstacle `index`, or agent `index`.
  struct Contact {
    enum class Kind : std::uint8_t { kNone, kBounds, kObstacle, kAgent } kind = Kind::kNone;
    std::size_t index = 0;
    explicit operator bool() const { return kind != Kind::kNone; }
  };

  void placeFootprint(Agent& a);
  // Moves solid agent i along its arc with contact handling (see the top of the file).
  void moveSolid(std::size_t i, double dt);
  // The first candidate (obstacles_near_, agents_near_) that the footprint in body_ touches,
  // skipping the ones overlapped at the step's start (start_*).
  Contact touchesCandidates(std::size_t self) const;
  // Whether the end pose `to` sinks deeper into what the agent overlapped at `from`.
  bool sinksDeeper(const Pose2& from, const Pose2& to) const;
  // Whether agent i is within kContactRelease_m of anything it can touch.
  bool nearAnything(std::size_t i) const;
  static double boundsViolation(const Box& bounds, PolygonView poly);

  PolygonMap map_;
  RobotProfile profile_;
  std::vector<Box> obstacle_boxes_;
  std::vector<Agent> agents_;
  double time_ = 0.0;
  // Per-step scratch (sized at construction and addAgent; no allocation in step()).
  std::vector<std::size_t> obstacles_near_;
  std::vector<std::size_t> agents_near_;
  std::vector<std::uint8_t> start_obstacle_;  // per obstacles_near_ entry: overlapped at start
  std::vector<std::uint8_t> start_agent_;     // per agents_near_ entry
  bool start_bounds_ = false;
  std::vector<Vec2> start_ref_;               // per obstacles_near_ entry: nearest point at start
  std::vector<std::uint8_t> start_ref_inside_;
  mutable Polygon body_;
};

}  // namespace staa
