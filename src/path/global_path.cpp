#include "path/global_path.hpp"

#include "geometry/clipper_ops.hpp"
#include "geometry/simplify.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {

const char* toString(PathStatus status) {
  switch (status) {
    case PathStatus::kFound: return "found";
    case PathStatus::kNoPath: return "no path";
    case PathStatus::kGoalInObstacle: return "goal inside an obstacle";
    case PathStatus::kStartBlocked: return "no free space near the start";
    case PathStatus::kAborted: return "out of time";
    case PathStatus::kNoPassage: return "no passage wider than the footprint";
  }
  return "unknown";
}

std::vector<Polygon> boundsWalls(const Box& b, double t) {
  const double x0 = b.min.x(), y0 = b.min.y(), x1 = b.max.x(), y1 = b.max.y();
  return {
      {{x0 - t, y0 - t}, {x1 + t, y0 - t}, {x1 + t, y0}, {x0 - t, y0}},  // below
      {{x0 - t, y1}, {x1 + t, y1}, {x1 + t, y1 + t}, {x0 - t, y1 + t}},  // above
      {{x0 - t, y0 - t}, {x0, y0 - t}, {x0, y1 + t}, {x0 - t, y1 + t}},  // left
      {{x1, y0 - t}, {x1 + t, y0 - t}, {x1 + t, y1 + t}, {x1, y1 + t}},  // right
  };
}

GlobalPathPlanner::GlobalPathPlanner(const PolygonMap& map, const GlobalPathOptions& options)
    : options_(options), static_search_(options.search), dynamic_search_(options.search) {
  real_ = map.obstacles;
  bounds_ = map.bounds;
  if (map.bounds) {
    const auto walls = boundsWalls(*map.bounds, std::max(1.0, 2.0 * options.inflation_radius_m));
    real_.insert(real_.end(), walls.begin(), walls.end());
  }
  if (options.inflation_radius_m > 0.0) {
    inflated_ = inflateEachToSimple(real_, options.inflation_radius_m + options.arc_tolerance_m, options.arc_tolerance_m);
  } else {
    // Uninflated, a big polygon is simplified outwards all the same (inflation does it too).
    inflated_ = real_;
    for (Polygon& p : inflated_) {
      if (isBigPolygon(p)) p = simplifyIfBig(p);
    }
  }
  real_set_.assign(std::span<const Polygon>(real_), PolygonSet::Options{options.search.grid_cell_m});
  static_search_.setStaticObstacles(inflated_);
  dynamic_search_.setStaticObstacles(inflated_);
  // A path has at most every node of the search and its two moved ends, plus the start.
  std::size_t vertices = 0;
  for (const Polygon& p : inflated_) vertices += p.size();
  nudged_path_.reserve(vertices + options.search.max_dynamic_vertices + 5);
  if (options.passage_inflation_m > 0.0 && options.passage_inflation_m < options.inflation_radius_m) {
    passage_ = inflateEachToSimple(real_, options.passage_inflation_m + options.passage_arc_tolerance_m,
                                   options.passage_arc_tolerance_m);
    passage_static_ = MinimalConstruct(options.search);
    passage_dynamic_ = MinimalConstruct(options.search);
    passage_static_.setStaticObstacles(passage_);
    passage_dynamic_.setStaticObstacles(passage_);
    std::size_t passage_vertices = 0;
    for (const Polygon& p : passage_) passage_vertices += p.size();
    passage_nudged_.reserve(passage_vertices + options.search.max_dynamic_vertices + 5);
  }
}

bool GlobalPathPlanner::insideRealObstacle(const Vec2& p) const {
  if (bounds_ && !bounds_->contains(p)) return true;
  return real_set_.pointBlocked(p);
}

GlobalPath GlobalPathPlanner::plan(const Vec2& start, const Vec2& goal, const Deadline& deadline) {
  return planStatic(start, goal, deadline);
}

GlobalPath GlobalPathPlanner::plan(const Vec2& start, const Vec2& goal, std::span<const PolygonView> dynamic_inflated,
                                   const Deadline& deadline) {
  const GlobalPath fixed = planStatic(start, goal, deadline);
  if (fixed.status != PathStatus::kFound || dynamic_inflated.empty()) return fixed;
  // Around D' in the map the static route runs in.
  MinimalConstruct& search = fixed.passage ? passage_dynamic_ : dynamic_search_;
  search.setDynamicObstacles(dynamic_inflated);
  if (pathFreeOfDynamic(search, fixed.path)) {
    GlobalPath same = fixed;
    same.dynamic = true;
    return same;
  }
  GlobalPath path = fixed.passage ? run(search, passage_nudged_, options_.passage_inflation_m, start, goal, true, deadline)
                                  : run(search, nudged_path_, options_.inflation_radius_m, start, goal, true, deadline);
  if (path.status == PathStatus::kFound) {
    path.passage = fixed.passage;
    path.band_m = fixed.band_m;
    return path;
  }
  // A moving obstacle closes the way (or the time ran out finding the way around it):
  // follow the static path (paper, Sec. III-B), found above.
  return fixed;
}

GlobalPath GlobalPathPlanner::planStatic(const Vec2& start, const Vec2& goal, const Deadline& deadline) {
  const bool footprint = options_.passage_inflation_m > 0.0;
  if (!hasPassageMap()) {
    GlobalPath wide = run(static_search_, nudged_path_, options_.inflation_radius_m, start, goal, false, deadline);
    // A round robot: M' is the footprint's own map.
    if (footprint && wide.status == PathStatus::kNoPath) wide.status = PathStatus::kNoPassage;
    return wide;
  }
  // The passage map first: without a route there, the footprint fits through no way at all
  // (M' is closed wherever M'' is), and M' need not be asked.
  GlobalPath narrow = run(passage_static_, passage_nudged_, options_.passage_inflation_m, start, goal, false, deadline);
  if (narrow.status != PathStatus::kFound) {
    if (narrow.status == PathStatus::kNoPath) narrow.status = PathStatus::kNoPassage;
    return narrow;
  }
  narrow.passage = true;
  // M' without nudging: where its start is cut off, M'' has the route (nudging would ask
  // dozens of queries every cycle the robot stands in a passage).
  GlobalPath wide = run(static_search_, nudged_path_, 0.0, start, goal, false, deadline);
  const bool same_goal = route_goal_set_ && route_goal_ == goal;
  route_goal_set_ = true;
  route_goal_ = goal;
  narrow.expansions += wide.expansions;
  narrow.edge_checks += wide.edge_checks;
  if (wide.status != PathStatus::kFound) {
    route_in_passage_ = true;
    return narrow;  // band_m stays 0: nothing to weigh it against (bandLength() tells it)
  }
  // The route in M' runs in the band only where an end inside M' was moved out of it.
  wide.band_m = wide.start_moved || wide.goal_moved ? bandLength(wide.path) : 0.0;
  const double wide_cost = wide.length + options_.band_cost * wide.band_m;
  // M'' wins when cheaper, by the hysteresis margin against a route in M' chosen before.
  const double margin = !same_goal ? 0.0 : route_in_passage_ ? options_.route_hysteresis_m : -options_.route_hysteresis_m;
  const double limit = wide_cost + margin;
  const double band_limit = options_.band_cost > 0.0 ? (limit - narrow.length) / options_.band_cost
                                                     : std::numeric_limits<double>::infinity();
  narrow.band_m = narrow.length < limit ? bandLength(narrow.path, band_limit) : 0.0;
  const double narrow_cost = narrow.length + options_.band_cost * narrow.band_m;
  route_in_passage_ = narrow.length < limit && narrow_cost < limit;
  if (route_in_passage_) return narrow;
  wide.expansions = narrow.expansions;
  wide.edge_checks = narrow.edge_checks;
  return wide;
}

double GlobalPathPlanner::bandLength(std::span<const Vec2> path, double limit_m) const {
  // Sampled at most every 5 cm: the cost weighs routes against each other, a centimetre does
  // not matter. Segments that stay clear of M' (both ends free, the segment too) count 0 at
  // the price of one segment test.
  constexpr double kStep = 0.05;
  const PolygonSet& wide = static_search_.staticObstacles();
  double band = 0.0;
  for (std::size_t i = 1; i < path.size() && band <= limit_m; ++i) {
    const Vec2& a = path[i - 1];
    const Vec2& b = path[i];
    if (!wide.pointBlocked(a) && !wide.pointBlocked(b) && !wide.segmentBlocked(a, b)) continue;
    const double len = (b - a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / kStep)));
    for (int k = 0; k < n; ++k) {
      if (wide.pointBlocked(a + ((k + 0.5) / n) * (b - a))) band += len / n;
    }
  }
  return band;
}

bool GlobalPathPlanner::pathFreeOfDynamic(const MinimalConstruct& search, std::span<const Vec2> path) {
  const PolygonSet& d = search.dynamicObstacles();
  for (const Vec2& p : path) {
    if (d.pointBlocked(p)) return false;  // an end inside D' (the segment test needs free ends)
  }
  for (std::size_t i = 1; i < path.size(); ++i) {
    if (d.segmentBlocked(path[i - 1], path[i])) return false;
  }
  return true;
}

GlobalPath GlobalPathPlanner::run(MinimalConstruct& search, std::vector<Vec2>& nudged_path, double nudge_radius,
                                  const Vec2& start, const Vec2& goal, bool with_dynamic, const Deadline& deadline) {
  GlobalPath out;
  if (insideRealObstacle(goal)) {
    out.status = PathStatus::kGoalInObstacle;
    return out;
  }
  MinimalConstruct::Result r = search.query(start, goal, with_dynamic, deadline);
  std::uint32_t expansions = r.expansions, edge_checks = r.edge_checks;
  bool nudged = false;
  // A start inside M' (M' is grown by the circumradius: the robot's centre may well be inside
  // it where its footprint is free) goes to the nearest free point, and that point may lie in
  // a sliver of M''s free space cut off from the rest, where inflated obstacles nearly meet.
  // The robot would be told there is no path and stop for good, though it could drive out
  // (found in the depot map: two agents held there for the rest of a 300 s run). Then starts
  // around the robot are tried, nearest ring first, out to the inflation radius: the first
  // with a path gives it, the robot's own position put in front. Only the static search: a
  // dynamic search that fails falls back to the static path anyway.
  if (options_.nudge_start && nudge_radius > 0.0 && r.status == MinimalConstruct::Status::kNoPath && r.start_moved &&
      !with_dynamic) {
    constexpr int kDirections = 8;
    constexpr double kRing = 0.1;
    const int rings = static_cast<int>(std::ceil(nudge_radius / kRing - 1e-9));
    for (int ring = 1; ring <= rings && !nudged && r.status != MinimalConstruct::Status::kAborted; ++ring) {
      const double d = std::min(ring * kRing, nudge_radius);
      for (int k = 0; k < kDirections; ++k) {
        const double a = 2.0 * kPi * k / kDirections;
        const Vec2 q = start + d * Vec2(std::cos(a), std::sin(a));
        if (insideRealObstacle(q)) continue;
        const MinimalConstruct::Result rq = search.query(q, goal, false, deadline);
        expansions += rq.expansions;
        edge_checks += rq.edge_checks;
        if (rq.status == MinimalConstruct::Status::kFound || rq.status == MinimalConstruct::Status::kAborted) {
          r = rq;
          nudged = rq.status == MinimalConstruct::Status::kFound;
          break;
        }
      }
    }
  }
  if (nudged && r.path.size() + 1 <= nudged_path.capacity()) {
    // Within the capacity reserved at construction: no allocation. (A longer path goes
    // without the robot's position in front; it starts within the inflation radius of it.)
    nudged_path.clear();
    nudged_path.push_back(start);
    nudged_path.insert(nudged_path.end(), r.path.begin(), r.path.end());
    r.length += (r.path.front() - start).norm();
    r.path = nudged_path;
  }
  out.expansions = expansions;
  out.edge_checks = edge_checks;
  out.start_moved = r.start_moved || nudged;
  out.start_nudged = nudged;
  out.goal_moved = r.goal_moved;
  switch (r.status) {
    case MinimalConstruct::Status::kFound:
      out.status = PathStatus::kFound;
      out.path = r.path;
      out.length = r.length;
      out.dynamic = with_dynamic;
      break;
    case MinimalConstruct::Status::kNoPath: out.status = PathStatus::kNoPath; break;
    case MinimalConstruct::Status::kStartBlocked: out.status = PathStatus::kStartBlocked; break;
    case MinimalConstruct::Status::kGoalBlocked: out.status = PathStatus::kNoPath; break;
    case MinimalConstruct::Status::kAborted: out.status = PathStatus::kAborted; break;
  }
  return out;
}

}  // namespace staa
