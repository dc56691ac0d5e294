#pragma once
// The global path of the control cycle (paper, Sec. III-B): the shortest path in the
// inflated map M' (static), or in M' united with the inflated moving obstacles D' (dynamic),
// falling back to the static path when D' closes every way (a person in a door).
//
// A robot that is not round (issue 16) also gets a route through passages M' closes: M' is
// grown by the circumradius, so a door or a slot the footprint fits through lengthwise is
// closed in it. The planner then also searches the passage map M'' (grown by the footprint's
// inscribed radius plus a margin: only what no heading can pass is closed) and weighs the two
// routes the way a costmap's inflation layer does: lethal within the inscribed radius, a cost
// per metre in the band out to the circumradius. The route through M'' is taken when its
// length plus that cost is lower (or when M' has no route at all); the exact footprint checks
// of the local planner decide what is driven. See GlobalPathOptions::passage_inflation_m.

#include "map/polygon_map.hpp"
#include "path/minimal_construct.hpp"

#include <limits>
#include <optional>
#include <span>
#include <vector>

namespace staa {

struct GlobalPathOptions {
  double inflation_radius_m = 0.3;  // at least the robot's radius
  // Chord error allowed on the inflated round corners. The polygons are grown by the radius
  // plus this tolerance, so that they contain the exact inflated shape (chords lie inside an
  // arc). Coarser is faster (fewer corners): 3 cm keeps a 90-degree corner to 3 vertices.
  double arc_tolerance_m = 0.03;
  // A start inside M' whose nearest free point has no path tries points around it, out to
  // the inflation radius (see GlobalPathPlanner::run). Off: such a start is kNoPath.
  bool nudge_start = true;
  // The passage map M'' (issue 16): the obstacles grown by this radius (the footprint's
  // inscribed radius plus a small margin; polygons grown by it plus passage_arc_tolerance_m),
  // searched beside M'. 0: M' only, and its failure is kNoPath (no footprint is known). From
  // inflation_radius_m up (a round robot: inscribed = circumscribed) M' is the footprint's own
  // map: M' only, as without it, but its failure is kNoPassage.
  double passage_inflation_m = 0.0;
  double passage_arc_tolerance_m = 0.01;
  // The band's cost: a route through M'' costs its length plus band_cost times its length in
  // the band (the part of it inside M', nearer an obstacle than inflation_radius_m); it is
  // taken when that is less than the length of the route in M'. 3: a door whose band is
  // 0.8 m long is worth a detour of 2.4 m.
  double band_cost = 3.0;
  // Once a route is chosen for a goal, the other map's route must be cheaper by this much
  // (metres of cost) to replace it: near a tie the route would flip as the robot moves.
  double route_hysteresis_m = 0.5;
  MinimalConstruct::Options search;
};

enum class PathStatus : std::uint8_t {
  kFound,
  kNoPath,           // start and goal are not connected in M'
  kGoalInObstacle,   // the goal lies inside a real (uninflated) obstacle or outside the bounds
  kStartBlocked,     // no free point near the start
  kAborted,          // the deadline passed before the static path was found (the search
                     // resumes where it stopped on the next query to the same goal)
  kNoPassage,        // start and goal are not connected in the footprint's own map (the
                     // passage map M'', or M' for a round robot): no way is wide enough
};

const char* toString(PathStatus status);

struct GlobalPath {
  PathStatus status = PathStatus::kNoPath;
  std::span<const Vec2> path;  // valid until the next query
  double length = 0.0;
  bool dynamic = false;        // found in M' ∪ D' (false: static, or the static fallback)
  bool start_moved = false;
  // The nearest free point to the start had no path; one from a point around the start had
  // (GlobalPathPlanner::run): the path runs from the start through that point.
  bool start_nudged = false;
  bool goal_moved = false;
  // The route runs in the passage map M'' (through a passage M' closes, or cheaper than the
  // route in M' with the band's cost), and its length in the band (inside M') where the two
  // routes were weighed (0 when M' had none: GlobalPathPlanner::bandLength tells it).
  bool passage = false;
  double band_m = 0.0;
  std::uint32_t expansions = 0;
  std::uint32_t edge_checks = 0;
};

class GlobalPathPlanner {
 public:
  // Builds M' from the map's obstacles and bounds (load time: allocates).
  GlobalPathPlanner(const PolygonMap& map, const GlobalPathOptions& options);

  // Static path in M'. Both plans give up at `deadline` (kAborted; a dynamic search cut
  // short gives the static path instead).
  GlobalPath plan(const Vec2& start, const Vec2& goal, const Deadline& deadline = {});
  // Dynamic path in M' ∪ D' (D': already inflated), else the static path. No allocation.
  // When the static path already avoids D' it is also the dynamic shortest path (obstacles
  // only lengthen paths), and it is returned without a second search.
  GlobalPath plan(const Vec2& start, const Vec2& goal, std::span<const PolygonView> dynamic_inflated,
                  const Deadline& deadline = {});

  // The inflated obstacles M' as simple polygons (for the local map and for drawing).
  const std::vector<Polygon>& inflatedObstacles() const { return inflated_; }
  // The passage map M'' (empty without one: options' passage_inflation_m 0 or a round robot).
  bool hasPassageMap() const { return !passage_.empty(); }
  const std::vector<Polygon>& passageObstacles() const { return passage_; }
  // The real obstacles including the walls that stand for the map's bounds.
  const std::vector<Polygon>& realObstacles() const { return real_; }
  const GlobalPathOptions& options() const { return options_; }
  const PolygonSet& realObstacleSet() const { return real_set_; }
  // True when p lies strictly inside a real obstacle or outside the bounds.
  bool insideRealObstacle(const Vec2& p) const;
  // The length of a path inside M' (for a route in M'': its length in the band), sampled
  // every 5 cm at most; counting stops once it passes `limit_m`. No allocation.
  double bandLength(std::span<const Vec2> path, double limit_m = std::numeric_limits<double>::infinity()) const;
  // Forgets what the searches kept from earlier queries (MinimalConstruct::forgetGoal), the
  // passage map's included, and the route chosen between M' and M'' (its hysteresis).
  void forgetSearches() {
    static_search_.forgetGoal();
    dynamic_search_.forgetGoal();
    if (hasPassageMap()) {
      passage_static_.forgetGoal();
      passage_dynamic_.forgetGoal();
    }
    route_goal_set_ = false;
    route_in_passage_ = false;
  }
  // The route chosen for a goal between M' and M'' (the hysteresis' state, carried from
  // query to query): for ControlCycle::Memory, so that a replay restores it.
  struct RouteChoice {
    bool chosen = false;     // a route was chosen for `goal`
    bool in_passage = false; // ... in M''
    Vec2 goal{0.0, 0.0};
  };
  RouteChoice routeChoice() const { return {route_goal_set_, route_in_passage_, route_goal_}; }
  void restoreRouteChoice(const RouteChoice& choice) {
    route_goal_set_ = choice.chosen;
    route_in_passage_ = choice.in_passage;
    route_goal_ = choice.goal;
  }

 private:
  // One search's query; a failed start inside the map is nudged out to `nudge_radius` (0: not
  // nudged), its path written to `nudged`.
  GlobalPath run(MinimalConstruct& search, std::vector<Vec2>& nudged, double nudge_radius, const Vec2& start,
                 const Vec2& goal, bool with_dynamic, const Deadline& deadline);
  // The static route: M' alone, or the cheaper of M' and M'' (see the header comment).
  GlobalPath planStatic(const Vec2& start, const Vec2& goal, const Deadline& deadline);
  static bool pathFreeOfDynamic(const MinimalConstruct& search, std::span<const Vec2> path);

  GlobalPathOptions options_;
  std::vector<Polygon> real_;
  std::vector<Polygon> inflated_;
  PolygonSet real_set_;
  std::optional<Box> bounds_;
  // Two searches: the static one keeps its tree from cycle to cycle (same goal, same M'); the
  // dynamic one is rebuilt whenever D' changes, so it must not wipe the static tree.
  MinimalConstruct static_search_;
  MinimalConstruct dynamic_search_;
  std::vector<Vec2> nudged_path_;  // a nudged start's path with the start in front (reserved)
  // The passage map M'' and its searches (built only when it differs from M').
  std::vector<Polygon> passage_;
  MinimalConstruct passage_static_;
  MinimalConstruct passage_dynamic_;
  std::vector<Vec2> passage_nudged_;
  // The route chosen for route_goal_ (the hysteresis between M' and M'').
  bool route_in_passage_ = false;
  bool route_goal_set_ = false;
  Vec2 route_goal_{0.0, 0.0};
};

// Walls standing for "outside the bounds is blocked": four slabs of `thickness` around the box.
std::vector<Polygon> boundsWalls(const Box& bounds, double thickness);

}  // namespace staa
