#pragma once
// The global path of the control cycle (paper, Sec. III-B): the shortest path in the
// inflated map M' (static), or in M' united with the inflated moving obstacles D' (dynamic),
// falling back to the static path when D' closes every way (a person in a door).

#include "map/polygon_map.hpp"
#include "path/minimal_construct.hpp"

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
  MinimalConstruct::Options search;
};

enum class PathStatus : std::uint8_t {
  kFound,
  kNoPath,           // start and goal are not connected in M'
  kGoalInObstacle,   // the goal lies inside a real (uninflated) obstacle or outside the bounds
  kStartBlocked,     // no free point near the start
  kAborted,          // the deadline passed before the static path was found (the search
                     // resumes where it stopped on the next query to the same goal)
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
  // The real obstacles including the walls that stand for the map's bounds.
  const std::vector<Polygon>& realObstacles() const { return real_; }
  const GlobalPathOptions& options() const { return options_; }
  const PolygonSet& realObstacleSet() const { return real_set_; }
  // True when p lies strictly inside a real obstacle or outside the bounds.
  bool insideRealObstacle(const Vec2& p) const;
  // Forgets what the searches kept from earlier queries (MinimalConstruct::forgetGoal).
  void forgetSearches() {
    static_search_.forgetGoal();
    dynamic_search_.forgetGoal();
  }

 private:
  GlobalPath run(MinimalConstruct& search, const Vec2& start, const Vec2& goal, bool with_dynamic,
                 const Deadline& deadline);
  bool pathFreeOfDynamic(std::span<const Vec2> path) const;

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
};

// Walls standing for "outside the bounds is blocked": four slabs of `thickness` around the box.
std::vector<Polygon> boundsWalls(const Box& bounds, double thickness);

}  // namespace staa
