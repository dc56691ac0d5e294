#include "control/dwa_controller.hpp"

#include "planner/staa_star.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {

DwaController::DwaController(const RobotProfile& robot, const LocalMapConfig& local, const DwaConfig& config)
    : config_(config), limits_(robot.limits), collision_(robot, local), no_obstacles_(1) {
  config_.notches = std::clamp<std::size_t>(config_.notches, 1, kMaxNotches);
  config_.arc_samples = std::max(1, config_.arc_samples);
  // The footprint's front corners and front centre (for C'), and its half-width (the
  // clearance to a mover is measured from the robot's centre).
  double front = -std::numeric_limits<double>::infinity();
  for (const Vec2& p : robot.footprint) front = std::max(front, p.x());
  double left = 0.0, right = 0.0;
  for (const Vec2& p : robot.footprint) {
    half_width_ = std::max(half_width_, std::abs(p.y()));
    if (p.x() >= front - 1e-9) {
      left = std::max(left, p.y());
      right = std::min(right, p.y());
    }
  }
  front_left_ = {front, left};
  front_right_ = {front, right};
  front_ = {front, 0.0};
}

DwaController::PathPoint DwaController::project(const Vec2& p) const {
  PathPoint best;
  if (path_.empty()) return best;
  best.foot = path_[0];
  best.lateral = (p - path_[0]).norm();
  double s = 0.0;
  for (std::size_t i = 0; i + 1 < path_.size(); ++i) {
    const Vec2 a = path_[i], d = path_[i + 1] - a;
    const double len2 = d.squaredNorm();
    const double len = std::sqrt(len2);
    const double u = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    const Vec2 foot = a + u * d;
    const double dist = (p - foot).norm();
    if (dist < best.lateral) best = PathPoint{s + u * len, dist, foot};
    s += len;
  }
  return best;
}

Vec2 DwaController::pointAt(double s) const {
  if (path_.empty()) return {0.0, 0.0};
  double at = 0.0;
  for (std::size_t i = 0; i + 1 < path_.size(); ++i) {
    const double len = (path_[i + 1] - path_[i]).norm();
    if (at + len >= s && len > 0.0) return path_[i] + (path_[i + 1] - path_[i]) * ((s - at) / len);
    at += len;
  }
  return path_.back();
}

std::size_t DwaController::notchesOf(double lo, double hi, std::array<double, kMaxNotches>& out) const {
  const std::size_t n = hi - lo < 1e-9 ? 1 : config_.notches;
  if (n == 1) {
    out[0] = 0.5 * (lo + hi);
    return 1;
  }
  std::size_t nearest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = lo + (hi - lo) * static_cast<double>(i) / static_cast<double>(n - 1);
    if (std::abs(out[i]) < std::abs(out[nearest])) nearest = i;
  }
  // Standing still and driving straight must be samples, not only nearly.
  if (lo <= 0.0 && hi >= 0.0) out[nearest] = 0.0;
  return n;
}

void DwaController::beginCycle(const LocalContext& ctx) {
  collision_.prepare(*ctx.map);
  obstacles_ = ctx.obstacles != nullptr ? ctx.obstacles : &no_obstacles_;
  path_ = ctx.path;
  path_length_ = 0.0;
  for (std::size_t i = 0; i + 1 < path_.size(); ++i) path_length_ += (path_[i + 1] - path_[i]).norm();
  const PathPoint now = project(ctx.robot.position());
  s0_ = now.s;
  to_go0_ = path_length_ - now.s + now.lateral;
  // Decided for the whole cycle, not per arc: a per-arc switch would make the arcs that reach
  // the goal's circle with the path's heading look worse than standing short of it.
  // There the way to go is the straight distance (the path's last piece may point elsewhere).
  const double to_goal = (ctx.robot.position() - ctx.goal.position()).norm();
  at_goal_ = to_goal < config_.carrot_distance_m;
  if (at_goal_) to_go0_ = to_goal;
  goal_closeness_ = at_goal_ ? 1.0 - to_goal / config_.carrot_distance_m : 0.0;
}

bool DwaController::canStop(const UnicycleState& from, double t0, bool& dynamic_free) const {
  // Brake at the limits in steps (v and w stop at different times); at most 2 m/s / a_max.
  constexpr double kStep = 0.2;
  UnicycleState s = from;
  double t = t0;
  dynamic_free = true;
  for (int k = 0; k < 12 && (std::abs(s.v) > 1e-3 || std::abs(s.w) > 1e-3); ++k) {
    const ArcVelocities vel = arcVelocities(s, brakeAction(s, limits_, kStep), kStep, limits_);
    if (!collision_.motionFreeStatic(s, vel, kStep)) return false;
    if (dynamic_free && !collision_.motionFreeDynamic(s, vel, kStep, *obstacles_, t)) dynamic_free = false;
    const Pose2 p = poseAlongArc(s, vel.v_mid, vel.w_mid, kStep);
    s = UnicycleState{p.x, p.y, p.theta, vel.v_end, vel.w_end};
    t += kStep;
  }
  return true;
}

DwaController::Evaluation DwaController::evaluate(const LocalContext& ctx, double v, double w) const {
  Evaluation e;
  const int n = config_.arc_samples;
  const double dt = config_.prediction_s / n;
  UnicycleState s = ctx.robot;
  double grid = 0.0, proximity = 0.0;
  for (int k = 0; k < n; ++k) {
    // Accelerate towards the target at the limits, then hold it.
    const Action act{std::clamp((v - s.v) / dt, -limits_.a_max, limits_.a_max),
                     std::clamp((w - s.w) / dt, -limits_.b_max, limits_.b_max)};
    const ArcVelocities vel = arcVelocities(s, act, dt, limits_);
    if (!collision_.motionFreeStatic(s, vel, dt)) return e;
    e.arc.free_static = k == n - 1;
    // Predictive: the movers where they will be while the robot drives this piece.
    if (!collision_.motionFreeDynamic(s, vel, dt, *obstacles_, k * dt)) {
      e.arc.free_static = true;  // (as far as it got; the caller only needs the verdict)
      e.arc.end = s;
      return e;
    }
    const Pose2 p = poseAlongArc(s, vel.v_mid, vel.w_mid, dt);
    s = UnicycleState{p.x, p.y, p.theta, vel.v_end, vel.w_end};
    // Clearance at this pose: C' under the front and the centre, the distance field's slack
    // to C, and the distance to the movers at this time.
    const double c = std::cos(p.theta), sn = std::sin(p.theta);
    auto world = [&](const Vec2& q) { return Vec2(p.x + c * q.x() - sn * q.y(), p.y + sn * q.x() + c * q.y()); };
    grid = std::max({grid, static_cast<double>(ctx.map->cost(p.position())),
                     static_cast<double>(ctx.map->cost(world(front_left_))),
                     static_cast<double>(ctx.map->cost(world(front_right_))),
                     static_cast<double>(ctx.map->cost(world(front_)))});
    double slack = 0.0;
    collision_.fastPoseFreeStatic(CollisionChecker::FastPose{p.x, p.y, c, sn}, &slack);
    proximity = std::max(proximity, 1.0 - slack / config_.static_range_m);
    if (obstacles_->size() > 0) {
      const double clearance = collision_.distanceToDynamic(p.position(), *obstacles_, (k + 1) * dt) - half_width_;
      proximity = std::max(proximity, 1.0 - clearance / config_.dynamic_range_m);
    }
  }
  e.arc.free_static = true;
  e.arc.free_dynamic = true;
  e.arc.end = s;
  bool stop_dynamic_free = true;
  e.arc.can_stop = canStop(s, config_.prediction_s, stop_dynamic_free);
  if (!e.arc.can_stop) return e;
  e.admissible = true;

  // Progress: how much shorter the way to the goal is from the arc's end (along the path from
  // the end's projection, plus the way back onto the path), and the heading towards the
  // carrot ahead of the end.
  const PathPoint end = project(s.position());
  const double to_go = at_goal_ ? (s.position() - ctx.goal.position()).norm() : path_length_ - end.s + end.lateral;
  const double progress = (to_go0_ - to_go) / (limits_.v_max * config_.prediction_s);
  double target = 0.0;
  bool aim = true;
  if (at_goal_) {
    target = ctx.goal.theta;  // at the goal: its heading
  } else {
    const Vec2 to = pointAt(end.s + config_.carrot_offset_m) - s.position();
    aim = to.squaredNorm() > 1e-6;
    target = std::atan2(to.y(), to.x());
  }
  // At the goal its heading weighs more the closer the robot is, so that the position comes
  // first (arrival wants 0.2 m) and the turn on the spot last.
  const double heading = (aim ? std::abs(wrapAngle(s.theta - target)) / kPi : 0.0) * (at_goal_ ? goal_closeness_ : 1.0);
  e.heading = heading;
  e.cost = -config_.w_progress * progress + config_.w_heading * heading + config_.w_path * end.lateral +
           config_.w_grid * grid + config_.w_geometric * proximity +
           (v < 0.0 && !at_goal_ ? config_.backwards_penalty * (-v) / std::max(1e-6, -limits_.v_min) : 0.0) +
           (stop_dynamic_free ? 0.0 : config_.w_stop_dynamic);
  return e;
}

DwaController::ArcCheck DwaController::checkArc(const LocalContext& ctx, double v, double w) {
  beginCycle(ctx);
  const Evaluation e = evaluate(ctx, v, w);
  return e.arc;
}

LocalCommand DwaController::compute(const LocalContext& ctx) {
  stats_ = Stats{};
  const UnicycleState& r = ctx.robot;
  const double period = ctx.period_s;
  LocalCommand brake{r.v + brakeAction(r, limits_, period).a * period, r.w + brakeAction(r, limits_, period).b * period};
  if (ctx.map == nullptr) {
    stats_.braking = true;
    return brake;
  }
  beginCycle(ctx);
  stats_.carrot = pointAt(s0_ + config_.carrot_offset_m);

  // The dynamic window, capped so that the robot can stop at the goal (a gentler deceleration
  // than the limit, so that the cap never asks for more than the robot can brake).
  const double tw = config_.window_s;
  const double to_go = std::max(0.0, to_go0_ - config_.goal_slack_m);
  const double v_cap = std::max(config_.creep_mps, std::sqrt(2.0 * config_.goal_decel_ratio * limits_.a_max * to_go));
  double v_lo = std::max(limits_.v_min, r.v - limits_.a_max * tw);
  double v_hi = std::min(limits_.v_max, r.v + limits_.a_max * tw);
  v_hi = std::max(v_lo, std::min(v_hi, v_cap));
  v_lo = std::min(v_hi, std::max(v_lo, -v_cap));
  const double w_lo = std::max(-limits_.w_max, r.w - limits_.b_max * tw);
  const double w_hi = std::min(limits_.w_max, r.w + limits_.b_max * tw);
  std::array<double, kMaxNotches> vs{}, ws{};
  const std::size_t nv = notchesOf(v_lo, v_hi, vs), nw = notchesOf(w_lo, w_hi, ws);

  double best = std::numeric_limits<double>::infinity();
  // Among the turns on the spot (v target 0): the one facing the carrot best, and staying.
  double turn_heading = std::numeric_limits<double>::infinity(), turn_w = 0.0, best_heading = 1.0;
  for (std::size_t i = 0; i < nv; ++i) {
    for (std::size_t j = 0; j < nw; ++j) {
      ++stats_.samples;
      const Evaluation e = evaluate(ctx, vs[i], ws[j]);
      if (!e.admissible) continue;
      ++stats_.admissible;
      if (e.cost < best) {
        best = e.cost;
        stats_.best_v = vs[i];
        stats_.best_w = ws[j];
        best_heading = e.heading;
      }
      if (vs[i] != 0.0) continue;
      if (e.heading < turn_heading) {
        turn_heading = e.heading;
        turn_w = ws[j];
      }
    }
  }
  if (stats_.admissible == 0) {
    stats_.braking = true;
    return brake;
  }
  stats_.best_cost = best;
  // A local minimum (turn_when_stuck): not driving, away from the goal, the best target does
  // not drive either, and a turn on the spot faces the carrot better (by more than 2 degrees:
  // no dithering). Not only at a standstill: the turn must go on in the next cycles.
  constexpr double kAtRest = 0.05, kBetter = 2.0 / 180.0;
  if (config_.turn_when_stuck && !at_goal_ && stats_.best_v == 0.0 && std::abs(r.v) < kAtRest &&
      turn_heading < best_heading - kBetter) {
    stats_.stuck_turn = true;
    stats_.best_w = turn_w;
  }
  LocalCommand cmd;
  cmd.v = std::clamp(r.v + std::clamp(stats_.best_v - r.v, -limits_.a_max * period, limits_.a_max * period),
                     limits_.v_min, limits_.v_max);
  cmd.w = std::clamp(r.w + std::clamp(stats_.best_w - r.w, -limits_.b_max * period, limits_.b_max * period),
                     -limits_.w_max, limits_.w_max);
  return cmd;
}

}  // namespace staa
