#pragma once
// The predictive Dynamic Window Approach of Missura and Bennewitz (ICRA 2019), one of the
// paper's baselines (Sec. IV-B): it follows a "carrot" on the (dynamic) global path with
// velocity arcs sampled in the dynamic window, rejects the arcs that hit the collision grid C
// or the moving obstacles predicted at the matching times D(t), and takes the best of the rest.
//
// One sample is a target (v, w): the robot accelerates towards it at a_max / b_max and holds
// it until the prediction time (accelerate-then-hold, so the predicted arc is the motion the
// commands really produce). The window is every target reachable within the window time.
// An arc is admissible when its horizon is free of C and D(t) and the robot can still brake
// to a stop from its end without touching C (the classic DWA admissibility, Fox et al. 1997).
//
// compute() allocates nothing, takes no locks and throws nothing.

#include "control/local_controller.hpp"
#include "robot/robot_profile.hpp"
#include "local/local_map.hpp"
#include "planner/collision.hpp"

#include <array>
#include <cstddef>
#include <span>

namespace staa {

// Defaults are the tuned values. Start: the authors' published configuration (11 notches,
// 0.7 s with 5 samples, carrot distance 0.5 m, carrot offset 0.9 m, grid and geometric
// clearance weights 1 and 1, backwards penalty 0.35). Then one value at a time was varied,
// the others held, over the seven scenarios of tests/unit/control/scenarios.hpp, scored by
// arrival, collision episodes, time to goal and min clearance (test_dwa prints the table);
// the values tried are listed, the kept one first. Only the carrot distance and the static
// clearance range moved from where they started.
// Second round, on the multi-agent experiment (staa-sim experiment, office/apartment/clutter,
// 1 and 3 agents, both modes, 2 runs of 60 s, 1,000-expansion budget; total mean score over
// the 12 cells): the scenario-tuned weights stopped in front of every door it approached at
// an angle (a local minimum: any slow arc into the doorway cost more in proximity than it
// gained in progress), 39.5. Tried: w_progress 2 -> 101.0 (more collisions); w_geometric and
// w_grid 0.5 -> 104.0 (kept: fewest collisions); w_grid 0.3 -> 54.5; w_progress 1.5 with
// 0.7/0.7 -> 90.5, with 0.5/0.5 -> 99.5; 0.3/0.3 -> 93.5; w_progress 2 with 0.5/0.5 -> 82.0.
struct DwaConfig {
  std::size_t notches = 11;          // per velocity dimension (authors: 11; 15: 0.1-0.3 s slower)
  double prediction_s = 0.7;         // arc horizon (authors: 0.7)
  int arc_samples = 5;               // checked and scored poses along an arc (authors: 5)
  double window_s = 0.7;             // window: targets reachable within this (authors: the prediction)
  double carrot_offset_m = 0.9;      // carrot ahead along the path (authors: 0.9; 1.2: no change)
  // Once the robot is within this of the goal, the heading term aims at the goal's heading
  // (weighted by closeness) instead of the carrot, and the way to go is the straight distance
  // (the cycle wants the heading within 0.4 rad on arrival). Authors' "carrot distance" 0.5 m;
  // 0.3 (kept), 0.5, 0.8: only 0.3 backs onto the goal 2 m behind (goalBehind, 4.6 s) instead
  // of turning round and stopping 0.3 m short.
  double carrot_distance_m = 0.3;
  double w_progress = 1.0;           // per v_max * prediction_s of way to go saved (1; 2: cuts closer, a corridor collision)
  double w_heading = 0.6;            // per pi of heading error to the carrot at the arc's end (0.6; 0.3 slower)
  double w_path = 0.3;               // per metre of the arc end's distance from the path (0.3; 0.1 alike)
  double w_grid = 0.5;               // costmap C' (0..1) under the front and the centre (authors: 1; 0.5: second round)
  double w_geometric = 0.5;          // proximity to C and D(t) along the arc (authors: 1; 0.5: second round)
  // Proximity = max(0, 1 - clearance / range), the range for C (the footprint's slack in the
  // distance field) short: at 0.6 m a door 0.85 m wider than the robot already outweighs the
  // progress of a slow arc and the robot stops in front of it for good (doorTurn).
  double static_range_m = 0.25;      // 0.25; 0.6 traps in the door
  double dynamic_range_m = 0.6;      // to the movers (0.6; 0.45, 0.3: a corridor collision, less clearance)
  double backwards_penalty = 0.35;   // per |v_min| of backward speed, not at the goal (authors: 0.35; 0.2 alike)
  // An arc after which braking to a stop would run into a predicted mover is not rejected
  // (a mover walking at the robot would leave nothing) but costs this.
  double w_stop_dynamic = 0.5;       // 0.5; 1.0 alike; 0.2: a corridor collision
  double goal_decel_ratio = 0.6;     // slow down for the goal at this share of a_max
  double goal_slack_m = 0.05;        // ... so as to stand this short of it
  double creep_mps = 0.15;           // ... but never capped below this (arrival is at |v| <= 0.25)
  // A robot at rest whose best target is to stay at rest, away from the goal, is in a local
  // minimum of the cost when a turn on the spot would face the carrot better: found in the
  // depot map, where turning round after a goal brings a corner of the 0.8 m footprint within
  // 0.25 m of a post (the proximity term) before the heading term gains enough, and the agent
  // stood for the rest of the run (1 goal in 60 s; PD: 10). Then the admissible turn on the
  // spot that faces the carrot best is taken (collisions and the stop are still checked).
  bool turn_when_stuck = true;
};

class DwaController : public LocalController {
 public:
  static constexpr std::size_t kMaxNotches = 21;

  DwaController(const RobotProfile& robot, const LocalMapConfig& local, const DwaConfig& config = {});

  const char* name() const override { return "dwa"; }
  LocalCommand compute(const LocalContext& context) override;

  // What the last compute() saw (tests, tools).
  struct Stats {
    std::size_t samples = 0;     // (v, w) targets evaluated
    std::size_t admissible = 0;  // of them free of C and D(t) (and able to stop)
    bool braking = false;        // none was: braked at the limits
    bool stuck_turn = false;     // at rest in a local minimum: turning on the spot (turn_when_stuck)
    double best_v = 0.0, best_w = 0.0;  // the chosen target (before the per-period step)
    double best_cost = 0.0;
    Vec2 carrot{0.0, 0.0};
  };
  const Stats& stats() const { return stats_; }
  const DwaConfig& config() const { return config_; }

  // The predicted end of an accelerate-then-hold arc towards (v, w) over the horizon, with
  // whether it is admissible (for tests: what the controller believed about a sample).
  struct ArcCheck {
    bool free_static = false;
    bool free_dynamic = false;
    bool can_stop = false;
    UnicycleState end;
  };
  ArcCheck checkArc(const LocalContext& context, double v, double w);

 private:
  // Where a point projects onto the path, as path length from its start.
  struct PathPoint {
    double s = 0.0;        // arc length of the projection
    double lateral = 0.0;  // distance from the path
    Vec2 foot{0.0, 0.0};
  };
  PathPoint project(const Vec2& p) const;
  Vec2 pointAt(double s) const;
  // The window's notches in [lo, hi]; the one closest to 0 (standing, straight) is moved onto
  // 0 when 0 lies inside.
  std::size_t notchesOf(double lo, double hi, std::array<double, kMaxNotches>& out) const;
  // Per cycle: the map, the path and its length, the obstacles, the carrot.
  void beginCycle(const LocalContext& context);
  // One sample: the arc towards (v, w) checked and, when admissible, costed.
  struct Evaluation {
    bool admissible = false;
    double cost = 0.0;
    double heading = 1.0;  // the heading term (0..1: the error to the carrot at the arc's end / pi)
    ArcCheck arc;
  };
  Evaluation evaluate(const LocalContext& context, double v, double w) const;
  // Braking at the limits from `s` (reached at time t0) stays free of C; `dynamic_free`
  // says whether it also stays free of D(t).
  bool canStop(const UnicycleState& s, double t0, bool& dynamic_free) const;

  DwaConfig config_;
  MotionLimits limits_;
  CollisionChecker collision_;
  Vec2 front_left_{0.0, 0.0}, front_right_{0.0, 0.0}, front_{0.0, 0.0};
  double half_width_ = 0.0;
  DynamicObstacleSet no_obstacles_;
  // Per cycle (set by beginCycle).
  std::span<const Vec2> path_;
  double path_length_ = 0.0;
  const DynamicObstacleSet* obstacles_ = nullptr;
  double s0_ = 0.0;     // the robot's projection onto the path
  double to_go0_ = 0.0;  // the way to the goal from the robot: onto the path, then along it
  bool at_goal_ = false; // within the carrot distance of the goal: aim at its heading
  double goal_closeness_ = 0.0;  // 1 - distance / carrot distance there
  Stats stats_;
};

}  // namespace staa
