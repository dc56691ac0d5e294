#pragma once
// One control cycle of the paper's Sec. III as a plain object: step(inputs, budget) ->
// command + stats. Threads, clocks and hardware stay outside: the daemon calls it from its
// 30 Hz thread, the simulator in simulated time, the tests in lockstep.
//
//   1. global path in M' ∪ D' (static fallback)             src/path
//   2. local map: box, G~, collision grid C, costmap C'       src/local
//   3. the local controller (STAA*, or a baseline) to G~     src/planner, here
//   4. the velocity command for the next cycle               here
//
// The phases are timed on the clock given at construction (the daemon's monotonic clock, a
// test's manual one).
//
// Everything is sized at construction; step() allocates nothing.

#include "control/blind_corners.hpp"
#include "control/local_controller.hpp"
#include "control/staa_controller.hpp"
#include "robot/robot_profile.hpp"
#include "local/dynamic_obstacles.hpp"
#include "local/local_map.hpp"
#include "map/polygon_map.hpp"
#include "path/global_path.hpp"
#include "planner/staa_star.hpp"

#include <array>
#include <cstdint>
#include <limits>
#include <optional>

namespace staa {

inline constexpr std::size_t kMaxMovingObstacleCapacity = 1024;

enum class CycleState : std::uint8_t {
  kIdle,         // no goal
  kDriving,      // on the way
  kReached,      // at the goal: stopped, reported
  kUnreachable,  // no path to the goal (or the goal is inside an obstacle): stopped, reported
};
const char* toString(CycleState state);

struct ControlConfig {
  double rate_hz = 30.0;
  double goal_tolerance_m = 0.2;        // position error that counts as arrived
  double goal_heading_tolerance = 0.4;  // rad; > pi ignores the heading
  // Arrival also needs the robot (nearly) stopped when the planner stops at goals
  // (staa.heuristic.stop_at_goal); |v| at most this. 0: a fifth of the robot's top speed, at
  // most 0.25 m/s (a fixed 0.25 m/s was above the HSR's top speed of 0.22 m/s: it reported
  // `reached` at full speed, 0.2 m before the goal).
  double goal_speed_tolerance = 0.0;
  double inflation_m = 0.0;             // M' growth; 0: the footprint's circumradius
  // D' growth (moving obstacles, for the paths only: collisions are checked exactly). 0: the
  // footprint's half-width plus 5 cm. Passing a person, the robot drives alongside, not
  // across: growing D' by the full circumradius would close every corridor a person walks in
  // and leave the heuristic no way around them.
  double dynamic_inflation_m = 0.0;
  // Growth of the static obstacles for the STAA* heuristic's local paths (L). 0: as D'. The
  // global path keeps the circumradius (it picks the route, in which any heading fits); the
  // local paths only guide a search whose collisions are checked on the real footprint, and
  // with the circumradius they could not pass a person in a 2 m corridor at all.
  double local_inflation_m = 0.0;
  // Passages narrower than M' (issue 16): the route may also run in the passage map M'',
  // grown by the footprint's inscribed radius plus this margin (GlobalPathOptions:
  // passage_inflation_m; the band's cost and hysteresis are in `path`), so a goal behind a
  // door M' closes but the footprint fits through lengthwise is reached, and a goal is
  // unreachable only where no passage is wider than the footprint (kNoPassage). A round robot
  // (inscribed radius + margin >= circumradius: the HSR) plans in M' alone, as before.
  // Off (false): M' alone for every robot.
  bool passages = true;
  double passage_margin_m = RobotProfile::kDefaultPassageMargin;
  StaaConfig staa;
  LocalMapConfig local;
  GlobalPathOptions path;
  // The moving-obstacle capacity: the most moving obstacles the cycle plans against. Every
  // buffer of the cycle is sized by it, and callers size their DynamicObstacleSet by it
  // (ControlCycle::obstacleCapacity()); more in a set are counted (obstacles_dropped), not
  // planned against. 1..kMaxMovingObstacleCapacity, checked at construction.
  std::size_t max_moving_obstacles = kDefaultMovingObstacleCapacity;
  // When the path query fails while the robot drives (it squeezed into a gap narrower than
  // M' allows, or the cycle's time ran out on a cold query), the last path found is followed
  // for up to this long before the goal counts as unreachable.
  double path_hold_s = 1.0;
  // The speed limit for blind corners (control/blind_corners.hpp): off by default; for a robot
  // whose perception sees only its line of sight among agents as fast as itself.
  BlindCornerConfig blind_corners;
};

struct CycleInputs {
  UnicycleState robot;                           // pose and velocities (odometry + localization)
  const DynamicObstacleSet* obstacles = nullptr;  // D at this cycle's time; may be null
};

struct CycleOutput {
  double v_cmd = 0.0;  // velocity command for the next cycle
  double w_cmd = 0.0;
  CycleState state = CycleState::kIdle;
  PathStatus path_status = PathStatus::kNoPath;
  bool path_dynamic = false;
  bool path_held = false;  // the query failed (path_status says why): the last path was followed
  bool path_passage = false;  // the route runs in the passage map M'' (GlobalPath::passage)
  // ... and up to G~ where the local paths' obstacles L are closed: the heuristic plans in
  // M'' and the static collisions are decided exactly this cycle.
  bool passage_mode = false;
  double path_length = 0.0;
  PlanResult plan;       // the search's result when the local controller searched (STAA*)
  bool planned = false;  // false when no search ran (idle, reached, unreachable, a baseline)
  std::int64_t path_ns = 0;
  std::int64_t local_ns = 0;
  std::int64_t plan_ns = 0;
  std::size_t obstacles_dropped = 0;  // moving obstacles beyond the capacity, not planned against
  // The blind-corner speed limit this cycle (infinite: none, or off) and whether it lowered
  // the command.
  double speed_cap = std::numeric_limits<double>::infinity();
  bool speed_capped = false;
};

class ControlCycle {
 public:
  ControlCycle(const PolygonMap& map, const RobotProfile& robot, const ControlConfig& config,
               ClockFn clock = &steadyClockNs);

  void setGoal(const Pose2& goal);
  void clearGoal();
  const std::optional<Pose2>& goal() const { return goal_; }

  CycleOutput step(const CycleInputs& inputs, PlannerBudget budget);

  // What a step carries to the next besides the searches' trees: the goal, the state, the
  // path held through failed queries (and whether it ran in the passage map), and the global
  // path's choice between M' and M'' for the goal (its hysteresis). The flight recorder records it every cycle; a replay
  // from the middle of a recording restores it. The trees (the global path's and the
  // heuristic's Minimal Construct searches) are forgotten by setGoal: from a cycle with
  // searchesFresh() a replay repeats the work, and with it the deadline's cut, exactly.
  struct Memory {
    std::optional<Pose2> goal;
    CycleState state = CycleState::kIdle;
    bool held_valid = false;
    int path_misses = 0;
    std::span<const Vec2> held_path;  // valid until the next step
    bool held_passage = false;        // the held path runs in M''
    bool route_chosen = false;        // a route was chosen for the goal (GlobalPathPlanner::RouteChoice)
    bool route_in_passage = false;    // ... in M''
  };
  Memory memory() const;
  // A recorded memory back in place (replay only: a held path beyond the reserved capacity
  // is not held). The searches are left as they are.
  void restoreMemory(const Memory& memory);
  // No search has run since the cycle was made or its goal set.
  bool searchesFresh() const { return searches_fresh_; }
  // How many times setGoal or clearGoal was called (the recorder notes each change).
  std::uint64_t goalChanges() const { return goal_changes_; }

  const LocalMap& localMap() const { return local_; }
  const GlobalPathPlanner& pathPlanner() const { return path_; }
  std::span<const Vec2> lastPath() const { return last_path_; }
  // STAA*, the default local controller (also while another one runs).
  StaaStar& planner() { return staa_.planner(); }
  // The local controller the cycle runs: STAA* unless replaced (the paper's baselines); null
  // restores STAA*. The controller must outlive the cycle.
  void setLocalController(LocalController* controller) { controller_ = controller != nullptr ? controller : &staa_; }
  const LocalController& localController() const { return *controller_; }

  const ControlConfig& config() const { return config_; }
  std::size_t obstacleCapacity() const { return config_.max_moving_obstacles; }
  const RobotProfile& robot() const { return robot_; }
  double inflation() const { return inflation_; }
  double dynamicInflation() const { return dynamic_inflation_; }

 private:
  CycleOutput stop(const UnicycleState& robot, CycleState state);
  // Stopping from speed without a path: the local controller's safe stop on this cycle's
  // local map, or the brake at the limits.
  CycleOutput safeStop(const UnicycleState& robot, const DynamicObstacleSet& obstacles, const Pose2& goal,
                       CycleState state);
  static GlobalPathOptions pathOptions(const ControlConfig& config, const RobotProfile& robot, double inflation);
  // Whether the route up to G~ runs where the local paths' own obstacles L are closed (a
  // passage of M''): then the heuristic plans its local paths in M'' this cycle.
  bool routeNeedsPassage(std::span<const Vec2> route) const;
  // The command clamped to the robot's limits.
  CycleOutput command(const LocalCommand& cmd, CycleState state) const;
  // The blind-corner limit applied to a driving command (speed_cap, speed_capped).
  void limitForBlindCorners(const UnicycleState& robot, CycleOutput& out) const;
  LocalContext context(const UnicycleState& robot, std::span<const Vec2> route,
                       const DynamicObstacleSet& obstacles, const Pose2& goal, PlannerBudget budget) const;

  ControlConfig config_;
  RobotProfile robot_;
  double inflation_;
  double dynamic_inflation_;
  double local_inflation_;
  GlobalPathPlanner path_;
  std::vector<Polygon> local_obstacles_;  // L: the real obstacles grown by local_inflation_
  PolygonSet local_obstacle_set_;         // L, indexed (only with a passage map)
  LocalMap local_;
  StaaController staa_;
  LocalController* controller_;  // &staa_ or a baseline
  BlindCorners blind_corners_;
  ClockFn clock_;
  DynamicObstacleSet empty_obstacles_;
  std::optional<Pose2> goal_;
  CycleState state_ = CycleState::kIdle;
  std::vector<FixedPolygon> inflated_;  // D' for the global path, obstacleCapacity() each
  std::vector<PolygonView> views_;
  std::span<const Vec2> last_path_;
  // The last path found, held for path_hold_s (capacity reserved at construction; a longer
  // path is not held), and how many cycles in a row the query has failed.
  std::vector<Vec2> held_path_;
  bool held_valid_ = false;
  bool held_passage_ = false;
  int path_misses_ = 0;
  bool searches_fresh_ = true;
  std::uint64_t goal_changes_ = 0;
};

}  // namespace staa
