#pragma once
// Short-Term Aborting A* (paper, Sec. III-E): an A* over acceleration commands from the
// robot's current state towards the intermediate goal G~ that always returns within its
// budget: on abort it returns the first action towards the state with the lowest heuristic
// seen, it finishes early when a popped state is within h < 0.1 of G~, and it brakes when no
// collision-free successor exists at all.
//
// All memory (node pool, queue, closed table) belongs to the planner and is sized at
// construction; plan() allocates nothing.

#include "robot/robot_profile.hpp"
#include "local/dynamic_obstacles.hpp"
#include "local/local_map.hpp"
#include "planner/budget.hpp"
#include "planner/collision.hpp"
#include "planner/heuristic.hpp"
#include "robot/unicycle.hpp"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace staa {

struct StaaConfig {
  std::size_t notches = 7;          // Eq. (1): n, 49 actions
  double dt = 0.3;                  // prediction time per step (s)
  // A slow robot (the HSR: 0.3 m/s^2, 0.5 rad/s^2) moves less than a closed-table cell in
  // 0.3 s from standstill, and the search cannot tell its first steps apart: dt is raised to
  // the time the robot needs to cross a cell at full acceleration,
  // max(dt, sqrt(2 closed_xy_m / a_max), sqrt(2 closed_theta_rad / b_max)). The paper's
  // agent (2 m/s^2, 6 rad/s^2) keeps 0.3 s; the HSR gets 0.63 s.
  bool adapt_dt = true;
  double closed_xy_m = 0.05;        // closed table: cell size ...
  double closed_theta_rad = 0.1;    // ... and heading resolution
  int prediction_depth = 3;         // D(t) is checked and costed up to this depth
  double w_static = 1.0;            // Eq. (3): w_s, weight of the costmap C'
  double w_dynamic = 1.0;           // Eq. (3): w_d, weight of the proximity to D(t)
  double proximity_range_m = 1.0;   // Eq. (3): delta = max(1 - dist / range, 0)
  double finish_h = 0.1;            // early finish below this h
  bool check_swept = true;          // check the motion between poses, not only the end pose
  std::size_t max_nodes = 100000;   // node pool (the search stops pushing when it is full)
  HeuristicConfig heuristic;
  // Compute h when a state is popped instead of when it is generated (queued under a lower
  // bound meanwhile). The order of expansions is that of true f; most generated states are
  // never popped, so far fewer heuristic queries are made. The lowest-h state an aborted
  // search returns is then chosen among the evaluated states only. Off: the paper's way.
  bool lazy_heuristic = false;
  // Braking safety (ours; the paper has no such rule; docs/results.md says why we added it): a
  // first action is allowed only
  // when the robot can brake to a stop after it without touching the map or the moving
  // obstacles predicted under the braking hypothesis (each keeps its velocity for
  // obstacle_reaction_s, then brakes at obstacle_brake_decel: what another robot, or a person,
  // does when it sees us). When no first action passes, the least bad ones are allowed: those after which braking
  // meets something latest (slowing down or turning away; what a person does too).
  bool brake_safety = true;
  // A stricter tier of the same rule, preferred whenever some first action passes it: the
  // robot can brake to a stop after the action before any moving obstacle, kept at constant
  // velocity, reaches its path (passive safety: the robot does not drive into anything that
  // keeps going), so two robots that each expect the other to brake do not both keep their
  // speed (docs/results.md).
  bool passive_safety = true;
  // The passive tier grows each moving obstacle by this angle (rad) times the distance it has
  // moved: its heading is known only roughly, it may turn. A slow obstacle barely grows (a
  // closing door at 0.4 m/s: 8 cm after a second). 0: the straight line. The value's trade-off
  // (contacts against goals) is measured in docs/results.md.
  double passive_heading_spread = 0.2;
  // Both braking checks also predict each obstacle that turns on its circle (its turn rate
  // comes through the perception seam: the simulation's agents have their w, depth
  // perception estimates one per track): braking along its circle in the first, keeping its
  // speed along it in the passive one; the stop must be clear of the straight and the
  // circular prediction (docs/results.md: the contacts it removed).
  bool predict_turning = true;
  double obstacle_reaction_s = 0.3;
  double obstacle_brake_decel = 2.0;  // m/s^2
  double brake_step_s = 0.15;         // the braking manoeuvre is checked in steps of this
  // A robot standing in contact with a moving obstacle (or with a perceived outline that
  // reaches into it) finds every motion a collision: it would brake and stay, and two agents
  // in contact would stay so for good. When a plan from standstill finds no free motion, it
  // is planned again without the moving obstacles the start touches, its first action kept
  // to those that take the robot's centre farther from theirs; the search plans on against
  // the others. A robot that is still moving is never given this (it brakes first). Off by
  // default: it ends standoffs but lets agents that parted touch again (docs/results.md,
  // "Agents that stay stopped: standoffs").
  bool separate_contacts = false;
};

struct PlanStats {
  std::uint32_t pops = 0;         // queue pops, a pop of an already closed cell included
  std::uint32_t expansions = 0;   // pops that expanded a node
  std::uint32_t successors = 0;   // child states generated and checked (49 per expansion)
  std::uint32_t collisions = 0;   // successors discarded by a collision
  std::uint32_t heuristic_calls = 0;
  std::int64_t heuristic_ns = 0;  // time in the heuristic (wall clock; 0 unless timing is on)
  std::int64_t collision_ns = 0;
  std::int64_t total_ns = 0;
};

struct PlanResult {
  enum class Outcome : std::uint8_t {
    kFinished,  // a popped state reached h < finish_h
    kAborted,   // the budget ran out; the lowest-h state was taken
    kExhausted, // the queue ran empty; the lowest-h state was taken
    kBrake,     // no collision-free successor of the start at all: brake
  };
  Outcome outcome = Outcome::kBrake;
  Action first_action;        // to apply until the next cycle
  UnicycleState best;         // the state the plan leads to
  double best_h = 0.0;
  std::uint32_t brake_safe_actions = 0;  // first actions allowed by the braking check (at tier 0: the least bad)
  std::uint8_t brake_safety_tier = 0;    // 2: passive safety, 1: braking hypothesis, 0: none passed
  std::uint8_t contacts = 0;  // moving obstacles the start touched (StaaConfig::separate_contacts)
  int depth = 0;              // depth of that state
  PlanStats stats;
  std::span<const UnicycleState> trajectory;  // root .. best, valid until the next plan()
};

const char* toString(PlanResult::Outcome outcome);

// The deceleration at the limits towards standstill from (v, w): the brake.
Action brakeAction(const UnicycleState& s, const MotionLimits& limits, double dt);

class StaaStar {
 public:
  // `max_obstacles`: the cycle's moving-obstacle capacity (ControlConfig::max_moving_obstacles).
  StaaStar(const StaaConfig& config, const RobotProfile& robot, const std::vector<Polygon>& inflated_static,
           const LocalMapConfig& local, std::size_t max_obstacles = kDefaultMovingObstacleCapacity);

  // Plans from `start` (in the local map's frame: world) to the local map's G~. The local map
  // must be updated for this cycle. `obstacles` holds D at the cycle's time (t = 0).
  PlanResult plan(const UnicycleState& start, const LocalMap& map, const DynamicObstacleSet& obstacles,
                  PlannerBudget budget);

  // A stop that steers clear: among the first actions that pass the braking check (the
  // strictest tier any passes), the one that slows the robot most; the plain brake when none
  // passes. For when there is no path to follow but the robot is still moving (braking
  // straight ahead can run into what the plan was steering around). `map` must be updated
  // for this cycle. No allocation.
  Action safeStop(const UnicycleState& start, const LocalMap& map, const DynamicObstacleSet& obstacles);

  // Visits the search tree of the last plan (parent, child) for drawing.
  template <typename Visitor>
  void forEachEdge(Visitor&& visit) const {
    for (std::size_t i = 1; i < nodes_.size(); ++i) visit(nodes_[static_cast<std::size_t>(nodes_[i].parent)].s, nodes_[i].s);
  }

  const StaaConfig& config() const { return config_; }
  const ActionSet& actions() const { return actions_; }
  Heuristic& heuristic() { return heuristic_; }
  // Forgets what the heuristic's searches kept from earlier cycles.
  void forgetSearches() { heuristic_.forgetSearches(); }
  void setTiming(bool on) { timing_ = on; }

 private:
  struct Node {
    UnicycleState s;
    double g = 0.0;
    double h = 0.0;
    double f = 0.0;
    std::int32_t parent = -1;
    std::uint16_t depth = 0;
    std::uint8_t action = 0;
    bool evaluated = true;  // h is the true heuristic (false: a lower bound, lazy mode)
    // How far every point of the robot may move from this pose without touching the grid
    // (CollisionChecker::fastPoseFreeStatic's slack); -1 until looked up.
    double slack = -1.0;
  };
  struct QueueEntry {
    double f;
    double h;
    std::int32_t node;
  };

  bool closedIndex(double x, double y, double theta, std::size_t& index) const;
  // Braking at the limits from `s` (at time t0) to a stop, and standing there until every
  // obstacle has stopped: +infinity when it stays free of the map and of `obstacles`, else the
  // time (from the plan's start, to a brake step) at which it first touches something.
  // With `stand` false only the braking is checked. heading_spread and turning: as
  // CollisionChecker::poseFreeDynamic. `start_slack`: the clearance of `s` from the grid when
  // known (0: not known); `check_static` false when this stop is known clear of the grid.
  double brakeClearTime(const UnicycleState& s, double t0, const DynamicObstacleSet& obstacles, bool stand,
                        double heading_spread = 0.0, bool turning = false, double start_slack = 0.0,
                        bool check_static = true) const;
  // Fills root_ok_ with each first action's tier (0..2) from `start`, root_clear_ and
  // root_allowed_ (the best tier's actions, or the least bad ones); returns the best tier any
  // action reached (braking_obstacles_ must hold this cycle's copy).
  std::uint8_t markBrakeSafe(const UnicycleState& start, const DynamicObstacleSet& obstacles);
  void push(std::int32_t node);
  std::int32_t pop();
  // plan()'s steps: the box, collision grid, heuristic and the root; the first actions'
  // braking check; a lazily queued state's true h; one expansion (its successors, their
  // velocities and rotations, collision check and cost g); the result from the best state.
  void beginSearch(const UnicycleState& start, const LocalMap& map, const DynamicObstacleSet& obstacles,
                   const Deadline& deadline);
  void restrictRoot(const UnicycleState& start, const DynamicObstacleSet& obstacles, PlanResult& result);
  // One search within `budget` (started) into `result` (its stats carried on).
  void search(const UnicycleState& start, const LocalMap& map, const DynamicObstacleSet& obstacles,
              PlannerBudget& budget, PlanResult& result);
  // StaaConfig::separate_contacts: `obstacles`, or escape_obstacles_ (a copy without those
  // the start touches, whose centres now and after dt go to contact_now_ / contact_next_).
  const DynamicObstacleSet& separateContacts(const UnicycleState& start, const DynamicObstacleSet& obstacles);
  // Keeps, of the allowed first actions, those that move away from every contact (of the best
  // tier among them); none when none does.
  void restrictToSeparation(const UnicycleState& start);
  void evaluateLazily(std::int32_t id, std::int32_t& best, PlanStats& st);
  void expand(std::int32_t id, const DynamicObstacleSet& obstacles, std::int32_t& best, PlanStats& st);
  void rotationsFor(const UnicycleState& s);
  bool motionFree(const Node& node, const ArcMotion& motion, const ArcVelocities& vel,
                  const DynamicObstacleSet& obstacles, bool predict, double disc, double& end_slack,
                  PlanStats& st) const;
  double pathCost(const UnicycleState& child, int depth, const DynamicObstacleSet& obstacles, bool predict) const;
  void finish(const UnicycleState& start, std::int32_t best, PlanResult& result);
  // The phase timing's clock reading (the budget's clock), 0 while timing is off.
  std::int64_t now() const { return timing_ ? clock_() : 0; }

  StaaConfig config_;
  MotionLimits limits_;
  ActionSet actions_;
  CollisionChecker collision_;
  Heuristic heuristic_;
  const LocalMap* map_ = nullptr;
  std::vector<Node> nodes_;
  std::vector<QueueEntry> queue_;
  // The closed table: one bit per (x, y, theta) cell, the headings of one (x, y) cell next to
  // each other (a node's 49 successors touch a few words of a 200 KB table, not 49 cache lines
  // of 6 MB), and the words this plan set, cleared before the next one.
  std::vector<std::uint64_t> closed_;
  std::vector<std::uint32_t> closed_words_;
  bool closed_overflow_ = false;  // more words set than listed: clear the whole table
  bool isClosed(std::size_t cell) const { return ((closed_[cell >> 6] >> (cell & 63)) & 1U) != 0; }
  void close(std::size_t cell);
  int closed_w_ = 0, closed_h_ = 0, closed_t_ = 0;
  double inv_closed_xy_ = 20.0, inv_two_pi_ = 0.0;
  // This cycle's box (the closed table's frame), rounded as it always was here (see
  // CollisionChecker::prepare on why not LocalMap::frameAt).
  double box_x_ = 0.0, box_y_ = 0.0, box_c_ = 1.0, box_s_ = 0.0, box_behind_ = 0.0, box_side_ = 0.0;
  // Per expansion: for each angular acceleration, the end and mid angular velocities and the
  // cosine and sine of the rotation over dt; for each linear one, the end and mid velocities.
  std::array<double, ActionSet::kMaxNotches> rot_w_end_{}, rot_w_mid_{}, rot_c_{}, rot_s_{};
  std::array<double, ActionSet::kMaxNotches> lin_v_end_{}, lin_v_mid_{};
  std::vector<UnicycleState> trajectory_;
  // Braking safety: the obstacles under the braking hypothesis (a copy per plan, no
  // allocation) and which first actions passed.
  DynamicObstacleSet braking_obstacles_;
  std::vector<std::uint8_t> root_ok_;
  std::vector<double> root_clear_;           // brakeClearTime after each first action (0: it collides itself)
  std::vector<std::uint8_t> root_allowed_;   // the first actions the search may take
  // Contacts (separateContacts): the obstacles left out, the set without them, and the
  // first kMaxContacts ones' centres.
  static constexpr std::size_t kMaxContacts = 8;
  std::vector<std::uint8_t> contact_;
  DynamicObstacleSet escape_obstacles_;
  std::array<Vec2, kMaxContacts> contact_now_{}, contact_next_{};
  std::size_t contacts_ = 0;
  std::vector<std::uint8_t> root_away_;
  // Per expansion: the moving obstacles its motions can come near (CollisionChecker::
  // nearObstacles).
  CollisionChecker::NearObstacles near_;
  bool timing_ = false;
  ClockFn clock_ = &steadyClockNs;  // the current plan's budget's clock
};

}  // namespace staa
