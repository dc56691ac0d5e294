#include "control/control_cycle.hpp"

#include "geometry/clipper_ops.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace staa {

const char* toString(CycleState state) {
  switch (state) {
    case CycleState::kIdle: return "idle";
    case CycleState::kDriving: return "driving";
    case CycleState::kReached: return "reached";
    case CycleState::kUnreachable: return "unreachable";
  }
  return "unknown";
}

GlobalPathOptions ControlCycle::pathOptions(const ControlConfig& config, const RobotProfile& robot, double inflation) {
  GlobalPathOptions o = config.path;
  o.inflation_radius_m = inflation;
  // At most the growth of M': a round robot's passage map would be M' itself (none is built).
  o.passage_inflation_m = config.passages ? std::min(robot.passageRadius(config.passage_margin_m), inflation) : 0.0;
  o.search.max_dynamic_polygons = config.max_moving_obstacles;
  o.search.max_dynamic_vertices = config.max_moving_obstacles * FixedPolygon::kCapacity;
  return o;
}

namespace {
const ControlConfig& checked(const ControlConfig& config) {
  if (config.max_moving_obstacles < 1 || config.max_moving_obstacles > kMaxMovingObstacleCapacity) {
    throw std::invalid_argument("max_moving_obstacles must be 1.." + std::to_string(kMaxMovingObstacleCapacity) +
                                ", got " + std::to_string(config.max_moving_obstacles));
  }
  const BlindCornerConfig& b = config.blind_corners;
  const auto bad = [](const char* key, double v, const char* want) {
    throw std::invalid_argument(std::string("blind_corners.") + key + " must be " + want + ", got " + std::to_string(v));
  };
  if (!(b.reaction_s >= 0.0 && b.reaction_s <= 5.0)) bad("reaction_s", b.reaction_s, "0..5 s");
  if (!(b.decel >= 0.0 && b.decel <= 100.0)) bad("decel", b.decel, "0..100 m/s^2 (0: the robot's a_max)");
  if (!(b.clearance_m >= 0.0 && b.clearance_m <= 10.0)) bad("clearance_m", b.clearance_m, "0..10 m (0: the circumradius)");
  if (!(b.min_speed >= 0.0 && b.min_speed <= 100.0)) bad("min_speed", b.min_speed, "0..100 m/s");
  if (!(b.range_m > 0.0 && b.range_m <= 100.0)) bad("range_m", b.range_m, "in (0, 100] m");
  if (!(b.lateral_m >= 0.0 && b.lateral_m <= 100.0)) bad("lateral_m", b.lateral_m, "0..100 m");
  return config;
}
constexpr std::size_t kHeldPathCapacity = 4096;
double inflationFor(const ControlConfig& config, const RobotProfile& robot) {
  return config.inflation_m > 0.0 ? config.inflation_m : robot.circumradius();
}
double dynamicInflationFor(const ControlConfig& config, const RobotProfile& robot) {
  if (config.dynamic_inflation_m > 0.0) return config.dynamic_inflation_m;
  double half_width = 0.0;
  for (const Vec2& p : robot.footprint) half_width = std::max(half_width, std::abs(p.y()));
  return half_width + 0.05;
}
StaaConfig staaFor(StaaConfig c, double inflation, double dynamic_inflation, double local_reach) {
  c.heuristic.static_inflation_m = inflation;
  c.heuristic.dynamic_inflation_m = dynamic_inflation;
  c.heuristic.local_reach_m = local_reach;
  return c;
}
}  // namespace

ControlCycle::ControlCycle(const PolygonMap& map, const RobotProfile& robot, const ControlConfig& config,
                           ClockFn clock)
    : config_(checked(config)),
      robot_(robot),
      inflation_(inflationFor(config, robot)),
      dynamic_inflation_(dynamicInflationFor(config, robot)),
      local_inflation_(config.local_inflation_m > 0.0 ? config.local_inflation_m : dynamic_inflation_),
      path_(map, pathOptions(config, robot, inflation_)),
      local_obstacles_(inflateEachToSimple(path_.realObstacles(), local_inflation_ + config.path.arc_tolerance_m,
                                           config.path.arc_tolerance_m)),
      local_(config.local),
      staa_(staaFor(config.staa, inflation_, dynamic_inflation_, local_inflation_ + config.path.arc_tolerance_m), robot,
            local_obstacles_, config.local, config.max_moving_obstacles),
      controller_(&staa_),
      blind_corners_(path_.realObstacles(), config.blind_corners,
                     config.blind_corners.clearance_m > 0.0 ? config.blind_corners.clearance_m : robot.circumradius(),
                     config.blind_corners.decel > 0.0 ? config.blind_corners.decel : robot.limits.a_max),
      clock_(clock),
      empty_obstacles_(1),
      inflated_(config.max_moving_obstacles),
      views_(config.max_moving_obstacles) {
  held_path_.reserve(kHeldPathCapacity);
  if (path_.hasPassageMap()) {
    local_obstacle_set_.assign(std::span<const Polygon>(local_obstacles_), PolygonSet::Options{config.path.search.grid_cell_m});
    staa_.planner().heuristic().setPassageObstacles(path_.passageObstacles(), path_.options().passage_inflation_m);
  }
}

bool ControlCycle::routeNeedsPassage(std::span<const Vec2> route) const {
  if (route.empty()) return false;
  const IntermediateGoal& g = local_.intermediateGoal();
  const std::size_t last = std::min(g.segment, route.size() - 1);
  // The route from the robot up to G~ (G~ lies on segment `last`); a point inside L (the
  // robot close to a wall) counts as closed: the segment test needs free ends.
  for (std::size_t i = 0; i <= last; ++i) {
    const Vec2& a = route[i];
    const Vec2 b = i == last || i + 1 >= route.size() ? g.pose.position() : route[i + 1];
    if (local_obstacle_set_.pointBlocked(a) || local_obstacle_set_.segmentBlocked(a, b)) return true;
  }
  return local_obstacle_set_.pointBlocked(g.pose.position());
}

void ControlCycle::setGoal(const Pose2& goal) {
  goal_ = goal;
  state_ = CycleState::kDriving;
  held_valid_ = false;
  path_misses_ = 0;
  // A new goal starts the searches afresh, so that a recording replays exactly from here.
  path_.forgetSearches();
  staa_.planner().forgetSearches();
  searches_fresh_ = true;
  ++goal_changes_;
}

ControlCycle::Memory ControlCycle::memory() const {
  Memory m{goal_, state_, held_valid_, path_misses_, held_path_};
  m.held_passage = held_passage_;
  const GlobalPathPlanner::RouteChoice route = path_.routeChoice();
  // The choice is for the goal the cycle drives to: a choice for another is none.
  m.route_chosen = route.chosen && goal_.has_value() && route.goal == goal_->position();
  m.route_in_passage = m.route_chosen && route.in_passage;
  return m;
}

void ControlCycle::restoreMemory(const Memory& memory) {
  goal_ = memory.goal;
  state_ = memory.state;
  path_misses_ = memory.path_misses;
  held_valid_ = memory.held_valid && memory.held_path.size() <= held_path_.capacity();
  if (held_valid_) held_path_.assign(memory.held_path.begin(), memory.held_path.end());
  held_passage_ = memory.held_passage;
  GlobalPathPlanner::RouteChoice route;
  route.chosen = memory.route_chosen && goal_.has_value();
  route.in_passage = route.chosen && memory.route_in_passage;
  if (route.chosen) route.goal = goal_->position();
  path_.restoreRouteChoice(route);
}

void ControlCycle::clearGoal() {
  goal_.reset();
  state_ = CycleState::kIdle;
  held_valid_ = false;
  path_misses_ = 0;
  ++goal_changes_;
}

CycleOutput ControlCycle::stop(const UnicycleState& robot, CycleState state) {
  // Decelerate at the limits towards standstill: the command for the next cycle.
  CycleOutput out;
  const double period = 1.0 / config_.rate_hz;
  const Action brake = brakeAction(robot, robot_.limits, period);
  out.v_cmd = robot.v + brake.a * period;
  out.w_cmd = robot.w + brake.b * period;
  out.state = state;
  return out;
}

CycleOutput ControlCycle::command(const LocalCommand& cmd, CycleState state) const {
  const MotionLimits& lim = robot_.limits;
  CycleOutput out;
  out.v_cmd = std::clamp(cmd.v, lim.v_min, lim.v_max);
  out.w_cmd = std::clamp(cmd.w, -lim.w_max, lim.w_max);
  out.state = state;
  return out;
}

void ControlCycle::limitForBlindCorners(const UnicycleState& robot, CycleOutput& out) const {
  out.speed_cap = blind_corners_.speedCap(robot.pose()).speed;
  if (!(out.v_cmd > out.speed_cap)) return;
  // Down to the cap, but no faster than the robot brakes, and along the planned arc (w
  // scaled with v) within the turn rate's own acceleration.
  const MotionLimits& lim = robot_.limits;
  const double period = 1.0 / config_.rate_hz;
  const double v = std::min(out.v_cmd, std::max(out.speed_cap, robot.v - lim.a_max * period));
  const double w = out.w_cmd * (v / out.v_cmd);
  const double lo = std::max(-lim.w_max, robot.w - lim.b_max * period);
  const double hi = std::min(lim.w_max, robot.w + lim.b_max * period);
  out.w_cmd = lo <= hi ? std::clamp(w, lo, hi) : w;
  out.v_cmd = v;
  out.speed_capped = true;
}

LocalContext ControlCycle::context(const UnicycleState& robot, std::span<const Vec2> route,
                                   const DynamicObstacleSet& obstacles, const Pose2& goal, PlannerBudget budget) const {
  LocalContext ctx;
  ctx.robot = robot;
  ctx.map = &local_;
  ctx.path = route;
  ctx.obstacles = &obstacles;
  ctx.goal = goal;
  ctx.period_s = 1.0 / config_.rate_hz;
  ctx.budget = budget;
  return ctx;
}

CycleOutput ControlCycle::safeStop(const UnicycleState& robot, const DynamicObstacleSet& obstacles, const Pose2& goal,
                                   CycleState state) {
  constexpr double kMoving = 1e-3;
  if (!controller_->hasSafeStop() || (std::abs(robot.v) < kMoving && std::abs(robot.w) < kMoving)) {
    return stop(robot, state);
  }
  // The local map around the robot (a path straight to the goal only places G~; the stop
  // needs the obstacles).
  const std::array<Vec2, 2> line{robot.position(), goal.position()};
  local_.update(robot.pose(), path_.realObstacleSet(), line, goal.theta);
  return command(controller_->safeStop(context(robot, {}, obstacles, goal, PlannerBudget{})), state);
}

CycleOutput ControlCycle::step(const CycleInputs& inputs, PlannerBudget budget) {
  const UnicycleState& robot = inputs.robot;
  const DynamicObstacleSet& obstacles = inputs.obstacles != nullptr ? *inputs.obstacles : empty_obstacles_;
  if (!goal_ || state_ == CycleState::kIdle) return stop(robot, CycleState::kIdle);
  const Pose2 goal = *goal_;

  // At the goal: stop and report (and stay stopped until a new goal).
  const double dist = (robot.position() - goal.position()).norm();
  const bool heading_ok = config_.goal_heading_tolerance > kPi ||
                          std::abs(wrapAngle(robot.theta - goal.theta)) <= config_.goal_heading_tolerance;
  const double speed_tolerance =
      config_.goal_speed_tolerance > 0.0 ? config_.goal_speed_tolerance : std::min(0.25, 0.2 * robot_.limits.v_max);
  const bool slow = !config_.staa.heuristic.stop_at_goal || std::abs(robot.v) <= speed_tolerance;
  if (state_ == CycleState::kReached || (dist <= config_.goal_tolerance_m && heading_ok && slow)) {
    state_ = CycleState::kReached;
    return stop(robot, state_);
  }

  // One budget for the whole cycle: its clock starts now, so the path queries, the local
  // map and STAA* all end by the budget (STAA*'s own start() is then a no-op).
  budget.start();
  const Deadline deadline = budget.deadline();

  CycleOutput out;
  // 1. Global path, around the inflated moving obstacles where possible.
  searches_fresh_ = false;
  std::int64_t t0 = clock_();
  const std::size_t n = std::min(obstacles.size(), views_.size());
  out.obstacles_dropped = obstacles.dropped() + (obstacles.size() - n);
  for (std::size_t i = 0; i < n; ++i) {
    obstacles.predictInflated(i, 0.0, dynamic_inflation_, config_.staa.heuristic.arc_steps, inflated_[i]);
    views_[i] = inflated_[i].view();
  }
  const GlobalPath path = n > 0 ? path_.plan(robot.position(), goal.position(), std::span<const PolygonView>(views_.data(), n), deadline)
                                : path_.plan(robot.position(), goal.position(), deadline);
  out.path_ns = clock_() - t0;
  out.path_status = path.status;
  out.path_dynamic = path.dynamic;
  out.path_length = path.length;
  out.path_passage = path.passage;
  std::span<const Vec2> route = path.path;
  if (path.status == PathStatus::kFound) {
    path_misses_ = 0;
    held_valid_ = path.path.size() <= held_path_.capacity();
    if (held_valid_) held_path_.assign(path.path.begin(), path.path.end());  // within capacity: no allocation
    held_passage_ = path.passage;
  } else {
    ++path_misses_;
    const double period = 1.0 / config_.rate_hz;
    const bool hold = path.status != PathStatus::kGoalInObstacle && held_valid_ &&
                      static_cast<double>(path_misses_) * period <= config_.path_hold_s;
    if (hold) {
      route = held_path_;
      out.path_held = true;
      out.path_passage = held_passage_;
    } else if (path.status == PathStatus::kAborted) {
      // Out of time on a cold query with nothing to hold: stop for now, the search resumes
      // where it stopped next cycle.
      CycleOutput stopped = safeStop(robot, obstacles, goal, CycleState::kDriving);
      stopped.path_status = path.status;
      stopped.path_ns = out.path_ns;
      return stopped;
    } else {
      state_ = CycleState::kUnreachable;
      CycleOutput stopped = safeStop(robot, obstacles, goal, state_);
      stopped.path_status = path.status;
      stopped.path_ns = out.path_ns;
      return stopped;
    }
  }
  last_path_ = route;

  // 2. Local map and the intermediate goal.
  t0 = clock_();
  // G~ counts a later piece of the path as reached through the box where the local paths can
  // get there: as far from C as their own obstacles (L, or M'' for a route through it).
  const double reach_clearance = out.path_passage ? path_.options().passage_inflation_m : local_inflation_;
  local_.update(robot.pose(), path_.realObstacleSet(), route, goal.theta, reach_clearance);
  // Through a passage only M'' leaves open, the local paths plan in M'' (they follow the
  // route) and the static collision checks are decided exactly where the grid rejects a pose.
  if (path_.hasPassageMap()) {
    const bool passage = out.path_passage && routeNeedsPassage(route);
    staa_.planner().heuristic().usePassageObstacles(passage);
    local_.setExactStatic(passage);
    out.passage_mode = passage;
  }
  out.local_ns = clock_() - t0;

  // 3. The local controller (STAA* unless a baseline replaced it), and 4. its command for
  // the next cycle.
  t0 = clock_();
  const LocalCommand cmd = controller_->compute(context(robot, route, obstacles, goal, budget));
  out.plan_ns = clock_() - t0;
  const CycleOutput commanded = command(cmd, CycleState::kDriving);
  out.v_cmd = commanded.v_cmd;
  out.w_cmd = commanded.w_cmd;
  if (blind_corners_.enabled()) limitForBlindCorners(robot, out);
  if (cmd.plan != nullptr) {
    out.plan = *cmd.plan;
    out.planned = true;
  }
  out.state = state_ = CycleState::kDriving;
  return out;
}

}  // namespace staa
