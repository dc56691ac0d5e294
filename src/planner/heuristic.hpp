#pragma once
// The STAA* heuristics (paper, Sec. III-E-5 and IV-C):
//  - Path RTR: the shortest path from the state to G~ (among the inflated static obstacles,
//    plus the inflated predicted moving obstacles D'(t) for depths 1..3), driven as
//    rotate-translate-rotate motions, forward or backward (Eq. 4, 5);
//  - Path Euclidean: the same path's length over v_max;
//  - Dijkstra RTR: a grid Dijkstra map from G~ over the local grid, looked up per state.
//
// Speed: every query of one cycle goes to the same G~ among the same obstacles, so each of
// the four Minimal Construct searches (static, and t = 1, 2, 3 steps ahead) keeps its
// backward search tree from G~ for the whole cycle. A query then connects the state to the
// tree and rarely expands anything: the tree is the per-cycle structure all queries share.
// A point asked again in the same cycle (about one query in ten) is answered from a table
// of this cycle's paths, and the tree's segments keep their lengths and directions.
// The values are exactly the path-RTR values of the paper.

#include "robot/robot_profile.hpp"
#include "local/dynamic_obstacles.hpp"
#include "local/local_map.hpp"
#include "path/deadline.hpp"
#include "path/minimal_construct.hpp"
#include "planner/collision.hpp"
#include "robot/unicycle.hpp"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace staa {

enum class HeuristicKind : std::uint8_t { kPathRtr, kPathEuclid, kDijkstraRtr };
const char* toString(HeuristicKind kind);
bool parseHeuristicKind(const char* text, HeuristicKind& out);

struct HeuristicConfig {
  HeuristicKind kind = HeuristicKind::kPathRtr;
  int dynamic_depth = 3;           // D'(t) is used up to this depth (the paper: 3)
  double dynamic_inflation_m = 0.3;  // radius that grows D(t) into D'(t)
  double static_inflation_m = 0.5;   // the robot's radius (Dijkstra RTR: cells this close to C are blocked)
  // How far the local paths' obstacles (the polygons handed to the constructor) reach beyond
  // the real ones, at most; lets the collision grid's clearance vouch for free segments.
  // 0: no such shortcut.
  double local_reach_m = 0.0;
  int arc_steps = 4;               // chords per corner of an inflated moving obstacle
  double unreachable_penalty_s = 100.0;  // h when no path exists at all
  // At the final goal (G~ = G) the robot should stand, not drive through: add the extra time
  // that braking to a stop takes, so that "h < 0.1" also means "almost stopped". The
  // paper's experiment only counts a goal passed within 0.5 m and leaves this out.
  bool stop_at_goal = true;
};

// Rotate-translate-rotate time along a polyline from heading `start_theta` to final heading
// `goal_theta`, each segment driven forward (v_max) or backward (|v_min|), whichever is
// cheaper overall (a two-state dynamic programme over the segments).
double pathRtr(std::span<const Vec2> path, double start_theta, double goal_theta, const MotionLimits& limits);

class Heuristic {
 public:
  // `inflated_static` is M' (the path planner's inflated obstacles), indexed once here;
  // `max_obstacles` the cycle's moving-obstacle capacity (D'(t) is sized by it).
  Heuristic(const HeuristicConfig& config, const MotionLimits& limits, const std::vector<Polygon>& inflated_static,
            const LocalMapConfig& local, std::size_t max_obstacles = kDefaultMovingObstacleCapacity);

  // Per cycle: the intermediate goal, the moving obstacles at the cycle's start, the step dt,
  // and (for Dijkstra RTR) the local map. No allocation. The path heuristics' Minimal
  // Construct queries give up at `deadline` (the cycle's budget): a state whose query ran
  // out of time is ranked like one whose goal is unreachable, behind every state with a path.
  void prepare(const Pose2& goal, const DynamicObstacleSet& obstacles, double dt, const LocalMap& map,
               const CollisionChecker* clearance = nullptr, const Deadline& deadline = {});

  // The passage map M'' of the global path (issue 16): a second set of static obstacles for
  // the local paths, grown by `inflation_m` (load time: allocates). A cycle whose route runs
  // through a passage the first set closes uses it (usePassageObstacles, before prepare), so
  // that the local paths follow the route; any other cycle keeps the first set.
  void setPassageObstacles(const std::vector<Polygon>& passage, double inflation_m);
  void usePassageObstacles(bool on) { use_passage_ = on && has_passage_; }
  bool usingPassageObstacles() const { return use_passage_; }

  // h for a state at search depth `depth` (time depth * dt).
  double evaluate(const UnicycleState& s, int depth);
  // A lower bound of evaluate() for any depth, at the cost of a square root: the straight
  // distance at the faster of the two top speeds plus the net heading change (plus the same
  // braking term at the final goal).
  double lowerBound(const UnicycleState& s) const;
  // Whether the goal of this cycle is the final goal (set by prepare from the local map).
  bool finalGoal() const { return final_goal_; }

  const HeuristicConfig& config() const { return config_; }
  std::uint64_t queries() const { return queries_; }
  // The path of the last Path-RTR / Path-Euclid query (for drawing).
  std::span<const Vec2> lastPath() const { return last_path_; }
  // Forgets what the searches kept from earlier cycles (MinimalConstruct::forgetGoal).
  void forgetSearches() {
    advanceMemoStamp();
    static_search_.forgetGoal();
    for (MinimalConstruct& mc : dynamic_search_) mc.forgetGoal();
    passage_static_.forgetGoal();
    for (MinimalConstruct& mc : passage_dynamic_) mc.forgetGoal();
  }

 private:
  double evaluatePath(const UnicycleState& s, int depth);
  double evaluateDijkstra(const UnicycleState& s);
  void buildDijkstra(const LocalMap& map, const CollisionChecker* clearance);

  HeuristicConfig config_;
  MotionLimits limits_;
  Pose2 goal_;
  Deadline deadline_;
  bool final_goal_ = false;
  MinimalConstruct static_search_;
  std::array<MinimalConstruct, 3> dynamic_search_;
  MinimalConstruct::Options search_options_;
  // The passage map's searches, and the set this cycle uses.
  MinimalConstruct passage_static_;
  std::array<MinimalConstruct, 3> passage_dynamic_;
  bool has_passage_ = false;
  bool use_passage_ = false;       // asked for the next prepare()
  bool passage_active_ = false;    // this cycle's set (fixed at prepare())
  double passage_inflation_m_ = 0.0;
  MinimalConstruct& staticSearch() { return passage_active_ ? passage_static_ : static_search_; }
  MinimalConstruct& dynamicSearch(std::size_t k) { return passage_active_ ? passage_dynamic_[k] : dynamic_search_[k]; }
  std::array<bool, 3> has_dynamic_{};
  std::vector<FixedPolygon> inflated_;  // D'(t) at the three depths, max_obstacles each
  std::vector<PolygonView> views_;
  std::span<const Vec2> last_path_;
  std::uint64_t queries_ = 0;

  // This cycle's answers by exact start point and search (the static one, or the dynamic
  // one of a depth): STAA* asks the same point again for about one state in ten (states
  // reached by different actions, turns on the spot). A direct-mapped table sized at
  // construction (no allocation in the cycle), emptied by prepare() through the stamp; a
  // path longer than kMemoPath vertices, or an answer the deadline cut, is not kept.
  struct MemoEntry {
    std::uint64_t x_bits = 0, y_bits = 0;
    double length = 0.0;
    std::uint32_t stamp = 0;
    std::int32_t depth_key = 0;
    std::uint32_t count = 0;  // path vertices; 0: no path (unreachable G~)
  };
  static constexpr std::size_t kMemoSlots = 512;
  static constexpr std::size_t kMemoPath = 12;
  std::vector<MemoEntry> memo_;
  std::vector<Vec2> memo_path_;
  std::uint32_t memo_stamp_ = 1;
  // A new stamp empties the memo; at the wrap every entry's stamp is cleared too, so that no
  // entry from 2^32 stamps ago can match.
  void advanceMemoStamp() {
    if (++memo_stamp_ == 0) {
      for (MemoEntry& e : memo_) e.stamp = 0;
      memo_stamp_ = 1;
    }
  }
  double hFromPath(const UnicycleState& s, std::span<const Vec2> path, double length);
  // pathRtr to G~, with the lengths and directions of segments seen before looked up
  // (direct-mapped, sized at construction; the same values, bit for bit).
  struct SegmentEntry {
    std::uint64_t key[4] = {0, 0, 0, 0};  // the end points' bits
    double len = 0.0;
    double phi = 0.0;
    bool valid = false;
  };
  static constexpr std::size_t kSegmentSlots = 256;
  std::vector<SegmentEntry> segments_;
  double pathRtrCached(std::span<const Vec2> path, double start_theta);

  const CollisionChecker* clearance_ = nullptr;
  static bool clearSegment(const void* self, const Vec2& a, const Vec2& b);

  // Dijkstra RTR: distance (m) to G~ per local cell, and the descent direction per cell.
  const LocalMap* map_ = nullptr;
  std::vector<float> dijkstra_;
  std::vector<float> dijkstra_dir_;
  std::vector<std::uint32_t> heap_;
  std::vector<std::uint8_t> free_;
};

}  // namespace staa
