#pragma once
// Several agents in one world (the paper's Sec. IV-B): each drives to random goal locations
// of the map (a new one when within goal_radius_m of its current one), with its own
// controller, stepped at the control rate.
//
//   cooperative: every agent runs the evaluated controller and avoids the others (which it
//                sees as moving polygons with velocities), without communicating; physical
//                collisions between agents and with walls; collisions of all agents count.
//   ghost:       agent 0 (the observed one) runs the evaluated controller; the others follow
//                their shortest path with the PD controller, pass through each other and
//                through agent 0, and only agent 0's collisions count (walls and ghosts).
//
// The agents see each other through a DynamicObstacleSet: built from the simulation (ground
// truth: every other agent's exact polygon, velocity and turn rate), or with
// ObstacleSource::kDepth from what each evaluated agent's depth camera sees, through the same
// perception code as staad (experiment/agent_camera.hpp). Deterministic for a given seed with
// an expansion budget. How contacts are resolved (agents stop at the last free point of
// their motion and can always back away): sim/multi_world.hpp.

#include "control/control_cycle.hpp"
#include "experiment/obstacle_source.hpp"
#include "experiment/perception_score.hpp"
#include "perception/depth_obstacles.hpp"
#include "planner/budget.hpp"
#include "map/polygon_map.hpp"
#include "planner/heuristic.hpp"
#include "experiment/sim_runner.hpp"

#include <cstdint>
#include <functional>
#include <span>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace staa {

class MultiWorld;

enum class SimMode : std::uint8_t { kCooperative, kGhost };
enum class ControllerKind : std::uint8_t { kStaa, kDwa, kPd };
const char* toString(SimMode mode);
const char* toString(ControllerKind kind);
bool parseSimMode(const std::string& text, SimMode& out);
bool parseControllerKind(const std::string& text, ControllerKind& out);

struct MultiSimOptions {
  int agents = 1;
  SimMode mode = SimMode::kCooperative;
  ControllerKind controller = ControllerKind::kStaa;
  double duration_s = 60.0;
  double rate_hz = 30.0;
  BudgetSpec budget;  // default: 19 ms of wall clock
  std::uint64_t seed = 1;          // start poses and goal sequences
  double goal_radius_m = 0.5;      // a goal counts as reached within this distance
  ControlConfig control;           // heuristic kind in control.staa.heuristic.kind
  ObstacleSource obstacles = ObstacleSource::kTruth;
  // kDepth: perception's settings (empty: agentPerceptionConfig of the robot profile, whose
  // camera section mounts the camera).
  std::optional<DepthObstaclesConfig> perception;
  // Called once per simulated second (progress); may be empty.
  std::function<void(double sim_time_s)> on_second;

  // Scripted runs (tests, demonstrations). `starts`: one start pose per agent (empty: distinct
  // random goal locations of the map with random headings). `goal_sequences`: per agent, the
  // goals it drives to in turn, cycling (empty: random goals of the map). With a
  // sequence the map needs no goals.
  std::vector<Pose2> starts;
  std::vector<std::vector<Vec2>> goal_sequences;
  // Called after every simulation step with the world (tests, drawing); may be empty.
  std::function<void(const MultiWorld& world)> on_step;
  // As on_step, with the goal each agent drives to now (one per agent; an agent with nowhere
  // left to go keeps its last goal) and the cycle index (0 for the first step); may be empty.
  std::function<void(const MultiWorld& world, std::span<const Vec2> current_goals, int cycle)> on_step_goals;
  // Called after every agent's control cycle with what it decided (diagnostics); may be empty.
  std::function<void(std::size_t agent, const CycleOutput& out)> on_cycle;
  // kDepth: called before every camera agent's control cycle with the obstacle frame its
  // planner gets (null before the first has arrived) and its head's pan (diagnostics).
  std::function<void(std::size_t agent, const hal::ObstacleFrame* frame, double pan)> on_perceived;
  // Called before every perceiving agent's control cycle with the moving obstacles its planner
  // gets (whatever the source; diagnostics, tests); may be empty.
  std::function<void(std::size_t agent, std::span<const PolygonView> obstacles, std::span<const Vec2> velocities)>
      on_obstacles;
  // Every agent's cycles recorded into this MCAP file, the contacts beside them (staa-sim
  // --record; empty: off). kDepth: the obstacles recorded are those perception gave the
  // planner. The runner completes the session.
  std::filesystem::path record_path;
  record::Session record_session;
};

// One counted contact episode, as it began: who touched what, how fast both were going in
// the step before, and the braking-safety tier of the first action each one's STAA* chose in
// that step's cycle (2 passive, 1 braking hypothesis, 0 none passed; -1: not STAA*, or no plan
// was made). Tells a robot driving into another apart from one being driven into.
struct ContactRecord {
  double time_s = 0.0;
  int agent = 0;
  int other = -1;  // the other agent's index, or -1 for the map
  double speed = 0.0;        // |v| of `agent` before the step, m/s
  double other_speed = 0.0;  // |v| of the other agent before the step (0 for the map)
  int tier = -1;
  int other_tier = -1;
  // kDepth, another agent: what `agent`'s perception knew of `other` (PerceptionScorer::sighting;
  // why a camera robot met it: never seen, seen too late, or seen and met all the same).
  bool perceived = false;  // the fields below are filled
  PerceptionScorer::Sighting sighting;
};

struct AgentResult {
  int goals_reached = 0;
  int collisions = 0;  // contact episodes
  double distance_m = 0.0;
};

struct MultiSimResult {
  int goals_reached = 0;  // observed agent (ghost) or all agents (cooperative)
  int collisions = 0;     // likewise
  int score = 0;          // goals_reached - collisions
  double duration_s = 0.0;
  std::vector<AgentResult> agents;
  // STAA* statistics over the evaluated agents' planner calls (zero for PD and DWA).
  int calls = 0;
  Distribution expansions;
  Distribution successors;
  double finished_early_ratio = 0.0;
  double depth_mean = 0.0;
  Distribution plan_us;
  std::vector<ContactRecord> contacts;  // the counted contact episodes, in time order
  // kDepth: how well the evaluated agents' perception saw the others.
  std::optional<PerceptionAccuracy> perception;
};

// Runs the agents on `map` (which must have goals). Throws std::invalid_argument for bad
// options (no goals, agents < 1, ...).
MultiSimResult runMultiAgent(const PolygonMap& map, const RobotProfile& robot, const MultiSimOptions& options);

}  // namespace staa
