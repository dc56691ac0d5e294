#include "control/pd_controller.hpp"

#include "geometry/predicates.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {

namespace {

// Closest point to p on the segment [a, b].
Vec2 closestOnSegment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 <= 0.0) return a;
  const double t = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
  return a + t * ab;
}

// Even-odd point in polygon (boundary either way: callers treat d ~ 0 as touching).
bool insidePolygon(const Vec2& p, PolygonView poly) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) in = !in;
  }
  return in;
}

bool segmentsCross(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const int o1 = orientSign(a, b, c), o2 = orientSign(a, b, d), o3 = orientSign(c, d, a), o4 = orientSign(c, d, b);
  return ((o1 > 0) != (o2 > 0)) && ((o3 > 0) != (o4 > 0));
}

// Distance from p to the polygon (0 inside) and the polygon's point nearest to p.
double distanceToPolygon(const Vec2& p, PolygonView poly, Vec2& nearest) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec2 q = closestOnSegment(p, poly[j], poly[i]);
    const double d = (p - q).squaredNorm();
    if (d < best) {
      best = d;
      nearest = q;
    }
  }
  return insidePolygon(p, poly) ? 0.0 : std::sqrt(best);
}

// Distance between two polygons (0 when they overlap or touch) and the nearest points on
// each, robot side first.
double distanceBetween(PolygonView robot, PolygonView other, Vec2& on_robot, Vec2& on_other) {
  double best = std::numeric_limits<double>::infinity();
  Vec2 q{0.0, 0.0};
  for (const Vec2& p : robot) {
    const double d = distanceToPolygon(p, other, q);
    if (d < best) {
      best = d;
      on_robot = p;
      on_other = q;
    }
  }
  for (const Vec2& p : other) {
    const double d = distanceToPolygon(p, robot, q);
    if (d < best) {
      best = d;
      on_robot = q;
      on_other = p;
    }
  }
  if (best > 0.0) {
    for (std::size_t i = 0, j = robot.size() - 1; i < robot.size(); j = i++)
      for (std::size_t k = 0, l = other.size() - 1; k < other.size(); l = k++)
        if (segmentsCross(robot[j], robot[i], other[l], other[k])) return 0.0;
  }
  return best;
}

// ((range - d) / range)^2 for d < range, else 0.
double pushMagnitude(double d, double range) {
  if (!(range > 0.0) || d >= range) return 0.0;
  const double s = (range - std::max(d, 0.0)) / range;
  return s * s;
}

}  // namespace

PdController::PdController(const RobotProfile& robot, const PdConfig& config)
    : robot_(robot), config_(config), reach_(robot.circumradius()), footprint_world_(robot.footprint.size()) {}

void PdController::findCarrot(const LocalContext& ctx, Vec2& carrot, double& remaining) const {
  const Vec2 pos = ctx.robot.position();
  const std::span<const Vec2> path = ctx.path;
  if (path.size() < 2) {
    carrot = ctx.goal.position();
    remaining = (carrot - pos).norm();
    return;
  }
  // The closest point, looked for near the path's start only (the path begins at the robot;
  // a later stretch that passes close by, e.g. behind a wall, must not capture the carrot).
  const double search_m = 2.0 + config_.carrot_offset_m;
  std::size_t seg = 0;
  Vec2 closest = path[0];
  double best = (pos - path[0]).squaredNorm();
  double along = 0.0;
  for (std::size_t i = 0; i + 1 < path.size() && along <= search_m; ++i) {
    const Vec2 q = closestOnSegment(pos, path[i], path[i + 1]);
    const double d = (pos - q).squaredNorm();
    if (d < best) {
      best = d;
      closest = q;
      seg = i;
    }
    along += (path[i + 1] - path[i]).norm();
  }
  // Walk carrot_offset along the path from there; sum the rest for the goal slow-down.
  double left = config_.carrot_offset_m;
  bool placed = false;
  remaining = 0.0;
  Vec2 from = closest;
  for (std::size_t i = seg; i + 1 < path.size(); ++i) {
    const double len = (path[i + 1] - from).norm();
    remaining += len;
    if (!placed) {
      if (len >= left && len > 0.0) {
        carrot = from + (path[i + 1] - from) * (left / len);
        placed = true;
      } else {
        left -= len;
      }
    }
    from = path[i + 1];
  }
  if (!placed) carrot = path.back();
}

Vec2 PdController::staticForce(const LocalContext& ctx) const {
  const LocalMap& map = *ctx.map;
  const double range = config_.ff_static_range_m;
  if (!(range > 0.0)) return {0.0, 0.0};
  const Pose2 pose = ctx.robot.pose();
  int i0 = 0, j0 = 0;
  if (!map.cellOf(pose.position(), i0, j0)) return {0.0, 0.0};
  const double cell = map.config().cell_m;
  const int n = static_cast<int>(std::ceil((range + reach_) / cell)) + 1;
  const std::span<const std::uint8_t> grid = map.grid();
  const int width = map.width(), height = map.height();
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const PolygonView footprint = robot_.footprint;

  // The nearest occupied cell per bearing sector, like a laser scan of C.
  std::array<double, kSectors> nearest;
  std::array<Vec2, kSectors> push;
  nearest.fill(range);
  push.fill(Vec2(0.0, 0.0));
  const double half_cell = 0.5 * cell;
  for (int j = std::max(0, j0 - n); j <= std::min(height - 1, j0 + n); ++j) {
    for (int i = std::max(0, i0 - n); i <= std::min(width - 1, i0 + n); ++i) {
      if (grid[static_cast<std::size_t>(j) * static_cast<std::size_t>(width) + static_cast<std::size_t>(i)] == 0) continue;
      const Vec2 w = map.cellCenter(i, j);
      const double dx = w.x() - pose.x, dy = w.y() - pose.y;
      const Vec2 p{c * dx + s * dy, -s * dx + c * dy};  // robot frame
      if (p.norm() > range + reach_ + half_cell) continue;
      Vec2 q{0.0, 0.0};
      const double d = std::max(0.0, distanceToPolygon(p, footprint, q) - half_cell);
      if (d >= range) continue;
      double ang = std::atan2(p.y(), p.x());
      int k = static_cast<int>((ang + kPi) / (2.0 * kPi) * kSectors);
      k = std::clamp(k, 0, kSectors - 1);
      if (d < nearest[static_cast<std::size_t>(k)]) {
        nearest[static_cast<std::size_t>(k)] = d;
        // Away from the cell: from it to the footprint's nearest point (inside: to the centre).
        Vec2 dir = d > 0.0 && (q - p).norm() > 1e-9 ? Vec2(q - p) : Vec2(-p);
        const double len = dir.norm();
        push[static_cast<std::size_t>(k)] = len > 1e-9 ? Vec2(dir / len) : Vec2(-1.0, 0.0);
      }
    }
  }
  Vec2 f{0.0, 0.0};
  for (std::size_t k = 0; k < nearest.size(); ++k) f += pushMagnitude(nearest[k], range) * push[k];
  return f;
}

Vec2 PdController::dynamicForce(const LocalContext& ctx) {
  const double range = config_.ff_dynamic_range_m;
  if (ctx.obstacles == nullptr || ctx.obstacles->size() == 0 || !(range > 0.0)) return {0.0, 0.0};
  const UnicycleState& r = ctx.robot;
  const double c = std::cos(r.theta), s = std::sin(r.theta);
  const int steps = std::max(0, config_.ff_predict_steps);
  Vec2 f{0.0, 0.0};
  for (std::size_t k = 0; k < ctx.obstacles->size(); ++k) {
    // The strongest push over the predictions: the obstacle at its constant velocity, the
    // robot at its current (v, w), both t ahead, so that closing in fast pushes early.
    double best = 0.0;
    Vec2 best_dir{0.0, 0.0};
    for (int step = 0; step <= steps; ++step) {
      const double t = steps > 0 ? config_.ff_predict_s * step / steps : 0.0;
      const Pose2 pose = t > 0.0 ? poseAlongArc(r, r.v, r.w, t) : r.pose();
      const double pc = std::cos(pose.theta), ps = std::sin(pose.theta);
      for (std::size_t i = 0; i < footprint_world_.size(); ++i) {
        const Vec2& p = robot_.footprint[i];
        footprint_world_[i] = {pose.x + pc * p.x() - ps * p.y(), pose.y + ps * p.x() + pc * p.y()};
      }
      ctx.obstacles->predict(k, t, predicted_);
      if (predicted_.n < 1) continue;
      Vec2 on_robot{0.0, 0.0}, on_other{0.0, 0.0};
      const double d = distanceBetween(footprint_world_, predicted_.view(), on_robot, on_other);
      const double m = pushMagnitude(d, range);
      if (m <= best) continue;
      best = m;
      Vec2 dir = on_robot - on_other;
      if (d <= 0.0 || dir.norm() < 1e-9) {
        Vec2 centre{0.0, 0.0};
        for (std::size_t v = 0; v < predicted_.n; ++v) centre += predicted_.v[v];
        dir = pose.position() - centre / static_cast<double>(predicted_.n);
      }
      const double len = dir.norm();
      best_dir = len > 1e-9 ? Vec2(dir / len) : Vec2(-c, -s);
    }
    f += best * best_dir;
  }
  // Into the robot frame, turned by the vortex angle: a head-on push gets a sideways part,
  // so the robot gives way to one side (keep right) instead of only braking.
  const Vec2 local{c * f.x() + s * f.y(), -s * f.x() + c * f.y()};
  const double vc = std::cos(config_.ff_vortex_rad), vs = std::sin(config_.ff_vortex_rad);
  return {vc * local.x() - vs * local.y(), vs * local.x() + vc * local.y()};
}

LocalCommand PdController::compute(const LocalContext& ctx) {
  const MotionLimits& lim = robot_.limits;
  const UnicycleState& r = ctx.robot;
  const double dt = ctx.period_s > 0.0 ? ctx.period_s : 1.0 / 30.0;
  const Vec2 pos = r.position();

  Vec2 carrot{0.0, 0.0};
  double remaining = 0.0;
  findCarrot(ctx, carrot, remaining);
  const double dist_goal = (ctx.goal.position() - pos).norm();
  remaining = std::max(remaining, dist_goal);

  // At the goal: stop and turn to its heading. Hysteresis: stay aligning while within twice
  // the radius, so a small overshoot does not send the robot round to face the goal again.
  terms_.aligning = dist_goal <= config_.goal_align_radius_m || (terms_.aligning && dist_goal <= 2.0 * config_.goal_align_radius_m);

  double a = 0.0, b = 0.0, v_cap = lim.v_max;
  if (terms_.aligning) {
    terms_.heading_error = wrapAngle(ctx.goal.theta - r.theta);
    a = -r.v / dt;  // to standstill
    v_cap = 0.0;
  } else {
    const Vec2 to = carrot - pos;
    const double d = to.norm();
    terms_.heading_error = d > 1e-9 ? wrapAngle(std::atan2(to.y(), to.x()) - r.theta) : 0.0;
    a = config_.kp_lin * d + config_.kd_lin * r.v;
    const double turn = std::max(0.0, 1.0 - std::abs(terms_.heading_error) / config_.heading_stop_rad);
    v_cap = std::min(lim.v_max * turn, std::sqrt(2.0 * config_.goal_decel * remaining));
  }
  b = config_.kp_rot * terms_.heading_error + config_.kd_rot * r.w;

  // The force field, in the robot frame: the backward part brakes, the sideways part turns
  // away (in the direction of travel).
  const Vec2 force = ctx.map != nullptr ? Vec2(staticForce(ctx) + dynamicForce(ctx)) : dynamicForce(ctx);
  const double travel = r.v >= 0.0 ? 1.0 : -1.0;
  a += config_.ff_gain_lin * force.x();
  b += config_.ff_gain_rot * force.y() * travel;

  double v = r.v + std::clamp(a, -lim.a_max, lim.a_max) * dt;
  double w = r.w + std::clamp(b, -lim.b_max, lim.b_max) * dt;
  // Forward only, unless the force field pushes back.
  const double v_floor = force.x() < 0.0 ? -config_.ff_max_reverse * std::min(1.0, -force.x()) : 0.0;
  v = std::max(std::min(v, v_cap), v_floor);
  // One period's acceleration from the current velocities, then the limits.
  v = std::clamp(v, r.v - lim.a_max * dt, r.v + lim.a_max * dt);
  w = std::clamp(w, r.w - lim.b_max * dt, r.w + lim.b_max * dt);
  v = std::clamp(v, lim.v_min, lim.v_max);
  w = std::clamp(w, -lim.w_max, lim.w_max);

  terms_.carrot = carrot;
  terms_.remaining_m = remaining;
  terms_.force = force;
  return {v, w};
}

}  // namespace staa
