#include "planner/heuristic.hpp"

#include "geometry/polygon.hpp"
#include "planner/distance_field.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace staa {

const char* toString(HeuristicKind kind) {
  switch (kind) {
    case HeuristicKind::kPathRtr: return "path-rtr";
    case HeuristicKind::kPathEuclid: return "path-euclid";
    case HeuristicKind::kDijkstraRtr: return "dijkstra-rtr";
  }
  return "unknown";
}

bool parseHeuristicKind(const char* text, HeuristicKind& out) {
  for (HeuristicKind k : {HeuristicKind::kPathRtr, HeuristicKind::kPathEuclid, HeuristicKind::kDijkstraRtr}) {
    if (std::strcmp(text, toString(k)) == 0) {
      out = k;
      return true;
    }
  }
  return false;
}

namespace {

// How far beyond the local box STAA*'s states may be asked about (the root horizon's region).
constexpr double kRegionMargin = 1.0;

// Eq. (4, 5) over a polyline whose segment i (from path[i - 1] to path[i]) has the length
// and direction `segment(i, len, phi)` gives (phi only read for len >= 1e-9).
template <typename Segment>
double pathRtrOf(std::span<const Vec2> path, double start_theta, double goal_theta, const MotionLimits& limits,
                 Segment&& segment) {
  // Eq. (4, 5): RTR segments concatenated. Each segment is driven facing along it (forward,
  // v_max) or facing against it (backward, |v_min|); the two choices are the DP's states, so
  // turning around between segments costs its rotation like any other turn.
  const double inv_w = 1.0 / limits.w_max;
  const double inv_vf = 1.0 / limits.v_max;
  const double inv_vb = limits.v_min < 0.0 ? 1.0 / -limits.v_min : std::numeric_limits<double>::infinity();
  double cost_f = 0.0, cost_b = 0.0;  // best cost arriving at the current vertex facing fwd/bwd
  double head_f = start_theta, head_b = start_theta;
  bool first = true;
  for (std::size_t i = 1; i < path.size(); ++i) {
    double len, phi;
    segment(i, len, phi);
    if (len < 1e-9) continue;
    const double fwd = phi, bwd = phi + kPi;
    double nf, nb;
    if (first) {
      nf = std::abs(wrapAngle(fwd - start_theta)) * inv_w + len * inv_vf;
      nb = std::abs(wrapAngle(bwd - start_theta)) * inv_w + len * inv_vb;
      first = false;
    } else {
      nf = std::min(cost_f + std::abs(wrapAngle(fwd - head_f)) * inv_w, cost_b + std::abs(wrapAngle(fwd - head_b)) * inv_w) +
           len * inv_vf;
      nb = std::min(cost_f + std::abs(wrapAngle(bwd - head_f)) * inv_w, cost_b + std::abs(wrapAngle(bwd - head_b)) * inv_w) +
           len * inv_vb;
    }
    cost_f = nf;
    cost_b = nb;
    head_f = fwd;
    head_b = bwd;
  }
  if (first) return std::abs(wrapAngle(goal_theta - start_theta)) * inv_w;  // already there
  return std::min(cost_f + std::abs(wrapAngle(goal_theta - head_f)) * inv_w,
                  cost_b + std::abs(wrapAngle(goal_theta - head_b)) * inv_w);
}

void segmentOf(const Vec2& a, const Vec2& b, double& len, double& phi) {
  const Vec2 d = b - a;
  len = d.norm();
  phi = std::atan2(d.y(), d.x());
}

}  // namespace

double pathRtr(std::span<const Vec2> path, double start_theta, double goal_theta, const MotionLimits& limits) {
  return pathRtrOf(path, start_theta, goal_theta, limits,
                   [&](std::size_t i, double& len, double& phi) { segmentOf(path[i - 1], path[i], len, phi); });
}

double Heuristic::pathRtrCached(std::span<const Vec2> path, double start_theta) {
  // Beyond its first segment a path runs along the search tree, the same segments for many
  // states: their lengths and directions (a square root and an arc tangent each) are kept by
  // the segment's end points, a pure function of them.
  return pathRtrOf(path, start_theta, goal_.theta, limits_, [&](std::size_t i, double& len, double& phi) {
    const Vec2& a = path[i - 1];
    const Vec2& b = path[i];
    if (i == 1) {
      segmentOf(a, b, len, phi);
      return;
    }
    std::uint64_t key[4];
    std::memcpy(key, a.data(), 2 * sizeof(double));
    std::memcpy(key + 2, b.data(), 2 * sizeof(double));
    std::uint64_t hash = (key[0] * 0x9E3779B97F4A7C15ULL) ^ (key[1] * 0xC2B2AE3D27D4EB4FULL) ^
                         (key[2] * 0x165667B19E3779F9ULL) ^ (key[3] * 0x27D4EB2F165667C5ULL);
    hash ^= hash >> 31;
    SegmentEntry& e = segments_[static_cast<std::size_t>(hash) & (kSegmentSlots - 1)];
    if (e.valid && std::memcmp(e.key, key, sizeof key) == 0) {
      len = e.len;
      phi = e.phi;
      return;
    }
    segmentOf(a, b, len, phi);
    std::memcpy(e.key, key, sizeof key);
    e.len = len;
    e.phi = phi;
    e.valid = true;
  });
}

Heuristic::Heuristic(const HeuristicConfig& config, const MotionLimits& limits, const std::vector<Polygon>& inflated_static,
                     const LocalMapConfig& local, std::size_t max_obstacles)
    : config_(config),
      limits_(limits),
      inflated_(3 * max_obstacles),
      views_(max_obstacles),
      memo_(kMemoSlots),
      memo_path_(kMemoSlots * kMemoPath),
      segments_(kSegmentSlots) {
  config_.dynamic_depth = std::clamp(config_.dynamic_depth, 0, 3);
  MinimalConstruct::Options opt;
  opt.max_dynamic_polygons = views_.size();
  opt.max_dynamic_vertices = views_.size() * FixedPolygon::kCapacity;
  search_options_ = opt;
  static_search_ = MinimalConstruct(opt);
  static_search_.setStaticObstacles(inflated_static);
  for (MinimalConstruct& mc : dynamic_search_) {
    mc = MinimalConstruct(opt);
    mc.setStaticObstacles(inflated_static);
  }
  const std::size_t cells = LocalMap::gridSize(local).cells();
  if (config_.kind == HeuristicKind::kDijkstraRtr) {
    dijkstra_.assign(cells, 0.0f);
    dijkstra_dir_.assign(cells, 0.0f);
    free_.assign(cells, 0);
    heap_.reserve(8 * cells + 8);
  }
}

void Heuristic::setPassageObstacles(const std::vector<Polygon>& passage, double inflation_m) {
  passage_static_ = MinimalConstruct(search_options_);
  passage_static_.setStaticObstacles(passage);
  for (MinimalConstruct& mc : passage_dynamic_) {
    mc = MinimalConstruct(search_options_);
    mc.setStaticObstacles(passage);
  }
  passage_inflation_m_ = inflation_m;
  has_passage_ = true;
}

bool Heuristic::clearSegment(const void* self, const Vec2& a, const Vec2& b) {
  const auto* h = static_cast<const Heuristic*>(self);
  return h->clearance_->segmentClear(a, b, h->config_.local_reach_m);
}

void Heuristic::prepare(const Pose2& goal, const DynamicObstacleSet& obstacles, double dt, const LocalMap& map,
                        const CollisionChecker* clearance, const Deadline& deadline) {
  goal_ = goal;
  deadline_ = deadline;
  map_ = &map;
  advanceMemoStamp();
  // The collision grid's clearance (this cycle's) may vouch for free segments of the local
  // paths: their obstacles reach at most local_reach_m beyond the real ones.
  clearance_ = config_.local_reach_m > 0.0 ? clearance : nullptr;
  // (The passage map's obstacles reach less far than the first set's: still within it.)
  const MinimalConstruct::FreeSegmentOracle oracle = clearance_ != nullptr ? &Heuristic::clearSegment : nullptr;
  passage_active_ = use_passage_;
  staticSearch().setFreeSegmentOracle(oracle, this);
  for (std::size_t k = 0; k < 3; ++k) dynamicSearch(k).setFreeSegmentOracle(oracle, this);
  // The states STAA* evaluates lie in the local box, or a little beyond it.
  Box region = boundingBox(map.boxCorners());
  region.min -= Vec2(kRegionMargin, kRegionMargin);
  region.max += Vec2(kRegionMargin, kRegionMargin);
  staticSearch().setStartRegion(region);
  for (std::size_t k = 0; k < 3; ++k) dynamicSearch(k).setStartRegion(region);
  final_goal_ = map.intermediateGoal().is_final;
  const std::size_t n = std::min(obstacles.size(), views_.size());
  for (int k = 0; k < 3; ++k) {
    has_dynamic_[static_cast<std::size_t>(k)] = k < config_.dynamic_depth && n > 0;
    if (!has_dynamic_[static_cast<std::size_t>(k)]) continue;
    for (std::size_t i = 0; i < n; ++i) {
      FixedPolygon& f = inflated_[static_cast<std::size_t>(k) * views_.size() + i];
      obstacles.predictInflated(i, (k + 1) * dt, config_.dynamic_inflation_m, config_.arc_steps, f);
      views_[i] = f.view();
    }
    dynamicSearch(static_cast<std::size_t>(k)).setDynamicObstacles(std::span<const PolygonView>(views_.data(), n));
  }
  if (config_.kind == HeuristicKind::kDijkstraRtr) buildDijkstra(map, clearance);
}

double Heuristic::evaluate(const UnicycleState& s, int depth) {
  ++queries_;
  const double h = config_.kind == HeuristicKind::kDijkstraRtr ? evaluateDijkstra(s) : evaluatePath(s, depth);
  if (!(config_.stop_at_goal && final_goal_)) return h;
  // The time braking takes beyond covering the same distance at the top speed the RTR time
  // assumes: |v|/a - v^2/(2 a v_top). Zero when standing, v_top/(2a) at full speed.
  auto braking = [](double vel, double acc, double top) { return std::abs(vel) / acc - vel * vel / (2.0 * acc * top); };
  const double v_top = s.v >= 0.0 ? limits_.v_max : -limits_.v_min;
  return h + braking(s.v, limits_.a_max, v_top) + braking(s.w, limits_.b_max, limits_.w_max);
}

double Heuristic::lowerBound(const UnicycleState& s) const {
  const double fastest = std::max(limits_.v_max, -limits_.v_min);
  double h = (goal_.position() - s.position()).norm() / fastest + std::abs(wrapAngle(goal_.theta - s.theta)) / limits_.w_max;
  if (config_.kind == HeuristicKind::kPathEuclid) h = (goal_.position() - s.position()).norm() / limits_.v_max;
  if (!(config_.stop_at_goal && final_goal_)) return h;
  auto braking = [](double vel, double acc, double top) { return std::abs(vel) / acc - vel * vel / (2.0 * acc * top); };
  const double v_top = s.v >= 0.0 ? limits_.v_max : -limits_.v_min;
  return h + braking(s.v, limits_.a_max, v_top) + braking(s.w, limits_.b_max, limits_.w_max);
}

double Heuristic::hFromPath(const UnicycleState& s, std::span<const Vec2> path, double length) {
  if (path.empty()) {
    last_path_ = {};
    // Unreachable G~: rank states by straight-line RTR, far behind any reachable state.
    const Vec2 line[2] = {s.position(), goal_.position()};
    return config_.unreachable_penalty_s + pathRtr(line, s.theta, goal_.theta, limits_);
  }
  last_path_ = path;
  if (config_.kind == HeuristicKind::kPathEuclid) return length / limits_.v_max;
  return pathRtrCached(path, s.theta);
}

double Heuristic::evaluatePath(const UnicycleState& s, int depth) {
  const Vec2 p = s.position();
  const Vec2 g = goal_.position();
  const bool dynamic = depth >= 1 && depth <= config_.dynamic_depth && has_dynamic_[static_cast<std::size_t>(depth - 1)];
  // The answer depends on the point and on which searches answer it: a repeat is looked up.
  std::uint64_t x_bits, y_bits;
  std::memcpy(&x_bits, &p.x(), sizeof x_bits);
  std::memcpy(&y_bits, &p.y(), sizeof y_bits);
  const std::int32_t depth_key = dynamic ? depth : 0;
  std::uint64_t hash = (x_bits * 0x9E3779B97F4A7C15ULL) ^ (y_bits * 0xC2B2AE3D27D4EB4FULL) ^ static_cast<std::uint64_t>(depth_key);
  hash ^= hash >> 29;
  const std::size_t slot = static_cast<std::size_t>(hash) & (kMemoSlots - 1);
  MemoEntry& entry = memo_[slot];
  if (entry.stamp == memo_stamp_ && entry.x_bits == x_bits && entry.y_bits == y_bits && entry.depth_key == depth_key) {
    return hFromPath(s, std::span<const Vec2>(memo_path_).subspan(slot * kMemoPath, entry.count), entry.length);
  }
  // The static path first (its tree is shared by all depths). Where the predicted obstacles
  // D'(t) leave it untouched it is also the shortest path among them (obstacles only make
  // paths longer), so the depth's dynamic search runs only for paths that D'(t) cuts.
  MinimalConstruct::Result r = staticSearch().query(p, g, false, deadline_);
  bool keep = r.status != MinimalConstruct::Status::kAborted;
  if (dynamic && r.status == MinimalConstruct::Status::kFound) {
    MinimalConstruct& search = dynamicSearch(static_cast<std::size_t>(depth - 1));
    const PolygonSet& d = search.dynamicObstacles();
    bool clear = true;
    for (std::size_t i = 0; i < r.path.size() && clear; ++i) clear = !d.pointBlocked(r.path[i]);
    for (std::size_t i = 1; i < r.path.size() && clear; ++i) clear = !d.segmentBlocked(r.path[i - 1], r.path[i]);
    if (!clear) {
      const MinimalConstruct::Result around = search.query(p, g, true, deadline_);
      // No way around the predicted obstacles (a person in the door), or no time left to
      // find it: keep the static path.
      if (around.status == MinimalConstruct::Status::kFound) r = around;
      keep = keep && around.status != MinimalConstruct::Status::kAborted;
    }
  }
  const bool found = r.status == MinimalConstruct::Status::kFound;
  if (keep && r.path.size() <= kMemoPath && (found || r.path.empty())) {
    entry.x_bits = x_bits;
    entry.y_bits = y_bits;
    entry.depth_key = depth_key;
    entry.stamp = memo_stamp_;
    entry.length = r.length;
    entry.count = found ? static_cast<std::uint32_t>(r.path.size()) : 0;
    if (found) std::copy(r.path.begin(), r.path.end(), memo_path_.begin() + static_cast<std::ptrdiff_t>(slot * kMemoPath));
  }
  return hFromPath(s, found ? r.path : std::span<const Vec2>{}, r.length);
}

void Heuristic::buildDijkstra(const LocalMap& map, const CollisionChecker* clearance) {
  const int w = map.width(), h = map.height();
  // Free cells: farther from every occupied cell than the robot's radius.
  // The collision checker has this cycle's distance field already; compute one only without it.
  const std::span<const float> field = clearance != nullptr ? clearance->distanceField() : std::span<const float>{};
  if (field.size() == dijkstra_.size()) {
    std::copy(field.begin(), field.end(), dijkstra_.begin());
  } else {
    conservativeDistanceField(map.grid(), w, h, map.config().cell_m, dijkstra_);
  }
  const double radius = passage_active_ ? passage_inflation_m_ : config_.static_inflation_m;
  for (std::size_t i = 0; i < free_.size(); ++i) free_[i] = dijkstra_[i] >= radius ? 1 : 0;
  const float inf = std::numeric_limits<float>::infinity();
  std::fill(dijkstra_.begin(), dijkstra_.end(), inf);
  heap_.clear();
  int gi, gj;
  // G~ on the box boundary can round to just outside: the nearest cell, clamped into the grid.
  map.nearestCell(goal_.position(), gi, gj);
  const std::size_t start = static_cast<std::size_t>(gj) * static_cast<std::size_t>(w) + static_cast<std::size_t>(gi);
  dijkstra_[start] = 0.0f;
  dijkstra_dir_[start] = static_cast<float>(goal_.theta);
  auto greater = [&](std::uint32_t a, std::uint32_t b) { return dijkstra_[a] > dijkstra_[b]; };
  heap_.push_back(static_cast<std::uint32_t>(start));
  const float cell = static_cast<float>(map.config().cell_m);
  const int di[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  const int dj[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  const float step[8] = {1, 1, 1, 1, 1.41421356f, 1.41421356f, 1.41421356f, 1.41421356f};
  const double box_theta = map.origin().theta;
  // Lazy-deletion Dijkstra; each cell is pushed at most 8 times, which the reserve covers.
  // Pops whose key went stale are recognised by comparing with the stored distance.
  std::vector<float>& dist = dijkstra_;
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), greater);
    const std::uint32_t c = heap_.back();
    heap_.pop_back();
    const int ci = static_cast<int>(c % static_cast<std::uint32_t>(w)), cj = static_cast<int>(c / static_cast<std::uint32_t>(w));
    for (int k = 0; k < 8; ++k) {
      const int ni = ci + di[k], nj = cj + dj[k];
      if (ni < 0 || nj < 0 || ni >= w || nj >= h) continue;
      const std::size_t nc = static_cast<std::size_t>(nj) * static_cast<std::size_t>(w) + static_cast<std::size_t>(ni);
      if (!free_[nc]) continue;
      const float nd = dist[c] + step[k] * cell;
      if (nd < dist[nc] && heap_.size() < heap_.capacity()) {
        dist[nc] = nd;
        // The way to G~ from nc starts towards c: remember that heading (world frame).
        dijkstra_dir_[nc] = static_cast<float>(box_theta + std::atan2(static_cast<double>(-dj[k]), static_cast<double>(-di[k])));
        heap_.push_back(static_cast<std::uint32_t>(nc));
        std::push_heap(heap_.begin(), heap_.end(), greater);
      }
    }
  }
}

double Heuristic::evaluateDijkstra(const UnicycleState& s) {
  int i, j;
  const Vec2 line[2] = {s.position(), goal_.position()};
  if (map_ == nullptr || !map_->cellOf(s.position(), i, j)) {
    return config_.unreachable_penalty_s + pathRtr(line, s.theta, goal_.theta, limits_);
  }
  const std::size_t c = static_cast<std::size_t>(j) * static_cast<std::size_t>(map_->width()) + static_cast<std::size_t>(i);
  const float d = dijkstra_[c];
  if (!std::isfinite(d)) return config_.unreachable_penalty_s + pathRtr(line, s.theta, goal_.theta, limits_);
  // RTR on the Dijkstra path: turn towards its first step, drive its length, and turn to the
  // goal heading (the path's last heading is unknown to a lookup table; the goal's is used).
  const double dir = dijkstra_dir_[c];
  const double fwd = std::abs(wrapAngle(dir - s.theta)) / limits_.w_max + d / limits_.v_max +
                     std::abs(wrapAngle(goal_.theta - dir)) / limits_.w_max;
  const double bwd = limits_.v_min < 0.0 ? std::abs(wrapAngle(dir + kPi - s.theta)) / limits_.w_max + d / -limits_.v_min +
                                               std::abs(wrapAngle(goal_.theta - dir - kPi)) / limits_.w_max
                                         : fwd;
  return std::min(fwd, bwd);
}

}  // namespace staa
