#include "planner/staa_star.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {

const char* toString(PlanResult::Outcome outcome) {
  switch (outcome) {
    case PlanResult::Outcome::kFinished: return "finished";
    case PlanResult::Outcome::kAborted: return "aborted";
    case PlanResult::Outcome::kExhausted: return "exhausted";
    case PlanResult::Outcome::kBrake: return "brake";
  }
  return "unknown";
}

Action brakeAction(const UnicycleState& s, const MotionLimits& limits, double dt) {
  // Decelerate at the limits, but not past zero within dt (no reversing out of a brake).
  auto towardsZero = [&](double vel, double acc_max) {
    if (dt <= 0.0) return 0.0;
    return std::clamp(-vel / dt, -acc_max, acc_max);
  };
  return Action{towardsZero(s.v, limits.a_max), towardsZero(s.w, limits.b_max)};
}

namespace {
StaaConfig adaptedConfig(StaaConfig c, const MotionLimits& limits) {
  if (c.adapt_dt) {
    if (limits.a_max > 0.0) c.dt = std::max(c.dt, std::sqrt(2.0 * c.closed_xy_m / limits.a_max));
    if (limits.b_max > 0.0) c.dt = std::max(c.dt, std::sqrt(2.0 * c.closed_theta_rad / limits.b_max));
  }
  return c;
}
}  // namespace

StaaStar::StaaStar(const StaaConfig& config, const RobotProfile& robot, const std::vector<Polygon>& inflated_static,
                   const LocalMapConfig& local, std::size_t max_obstacles)
    : config_(adaptedConfig(config, robot.limits)),
      limits_(robot.limits),
      actions_(robot.limits, config.notches),
      collision_(robot, local),
      heuristic_(config.heuristic, robot.limits, inflated_static, local, max_obstacles),
      braking_obstacles_(max_obstacles),
      contact_(max_obstacles, 0),
      escape_obstacles_(max_obstacles) {
  braking_obstacles_.setBraking(config_.obstacle_reaction_s, config_.obstacle_brake_decel);
  root_ok_.assign(actions_.size(), 1);
  root_clear_.assign(actions_.size(), 0.0);
  root_allowed_.assign(actions_.size(), 1);
  root_away_.assign(actions_.size(), 0);
  nodes_.reserve(config_.max_nodes);
  queue_.reserve(config_.max_nodes);
  trajectory_.reserve(config_.max_nodes > 1024 ? 1024 : config_.max_nodes);
  inv_closed_xy_ = 1.0 / config_.closed_xy_m;
  const GridSize closed_size = boxGridSize(local, config_.closed_xy_m);
  closed_w_ = closed_size.width;
  closed_h_ = closed_size.height;
  closed_t_ = static_cast<int>(std::ceil(2.0 * kPi / config_.closed_theta_rad));
  inv_two_pi_ = 1.0 / (2.0 * kPi);
  const std::size_t cells = static_cast<std::size_t>(closed_w_) * static_cast<std::size_t>(closed_h_) * static_cast<std::size_t>(closed_t_);
  closed_.assign((cells + 63) / 64, 0);
  closed_words_.reserve(config_.max_nodes);  // a word is listed when a pop closes its first cell
}

void StaaStar::close(std::size_t cell) {
  std::uint64_t& word = closed_[cell >> 6];
  if (word == 0) {
    if (closed_words_.size() < closed_words_.capacity()) {
      closed_words_.push_back(static_cast<std::uint32_t>(cell >> 6));
    } else {
      closed_overflow_ = true;
    }
  }
  word |= std::uint64_t{1} << (cell & 63);
}

// The closed table coincides with the local grid (paper, Sec. III-E-2): x and y in the box's
// frame, heading in 0.1 rad bins. False for states outside the box.
bool StaaStar::closedIndex(double x, double y, double theta, std::size_t& index) const {
  const double lx = box_c_ * (x - box_x_) + box_s_ * (y - box_y_);
  const double ly = -box_s_ * (x - box_x_) + box_c_ * (y - box_y_);
  const double fi = (lx + box_behind_) * inv_closed_xy_, fj = (ly + box_side_) * inv_closed_xy_;
  if (!(fi >= 0.0 && fj >= 0.0 && fi < closed_w_ && fj < closed_h_)) return false;
  double th = theta * inv_two_pi_;
  th = (th - std::floor(th)) * closed_t_;  // [0, closed_t_)
  const int t = std::min(static_cast<int>(th), closed_t_ - 1);
  index = (static_cast<std::size_t>(fj) * static_cast<std::size_t>(closed_w_) + static_cast<std::size_t>(fi)) *
              static_cast<std::size_t>(closed_t_) +
          static_cast<std::size_t>(t);
  return true;
}

void StaaStar::push(std::int32_t node) {
  const Node& n = nodes_[static_cast<std::size_t>(node)];
  queue_.push_back(QueueEntry{n.f, n.h, node});
  // Min-heap on f; ties go to the lower h (closer to the goal), then the older node.
  std::push_heap(queue_.begin(), queue_.end(), [](const QueueEntry& a, const QueueEntry& b) {
    if (a.f != b.f) return a.f > b.f;
    if (a.h != b.h) return a.h > b.h;
    return a.node > b.node;
  });
}

std::int32_t StaaStar::pop() {
  std::pop_heap(queue_.begin(), queue_.end(), [](const QueueEntry& a, const QueueEntry& b) {
    if (a.f != b.f) return a.f > b.f;
    if (a.h != b.h) return a.h > b.h;
    return a.node > b.node;
  });
  const std::int32_t n = queue_.back().node;
  queue_.pop_back();
  return n;
}

double StaaStar::brakeClearTime(const UnicycleState& from, double t0, const DynamicObstacleSet& obstacles,
                                bool stand, double heading_spread, bool turning, double start_slack,
                                bool check_static) const {
  constexpr double kClear = std::numeric_limits<double>::infinity();
  const double step = config_.brake_step_s;
  UnicycleState s = from;
  double t = t0;
  double slack = start_slack;  // the clearance of s, carried along the stop (0: not known)
  for (int k = 0; k < 64 && (std::abs(s.v) > 1e-3 || std::abs(s.w) > 1e-3); ++k) {
    const ArcVelocities vel = arcVelocities(s, brakeAction(s, limits_, step), step, limits_);
    if (check_static) {
      const double dth = vel.w_mid * step;
      const ArcMotion motion = makeArcMotion(s, std::cos(s.theta), std::sin(s.theta), vel.v_mid, vel.w_mid, step,
                                             std::cos(dth), std::sin(dth));
      double end_slack = -1.0;
      if (!collision_.motionFreeStatic(motion, slack, &end_slack)) return t;
      // Not looked up: the end is within the motion's travel of a start that far from the grid.
      slack = end_slack >= 0.0 ? end_slack : std::max(0.0, slack - collision_.travelBound(motion));
    }
    if (!collision_.motionFreeDynamic(s, vel, step, obstacles, t, heading_spread, turning)) return t;
    const Pose2 p = poseAlongArc(s, vel.v_mid, vel.w_mid, step);
    s = UnicycleState{p.x, p.y, p.theta, vel.v_end, vel.w_end};
    t += step;
  }
  if (!stand || obstacles.size() == 0) return kClear;
  // Standing there until the slowest obstacle has stopped too.
  double last_stop = t;
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    const double speed = obstacles.velocity(k).norm();
    if (config_.obstacle_brake_decel > 0.0) {
      last_stop = std::max(last_stop, config_.obstacle_reaction_s + speed / config_.obstacle_brake_decel);
    }
  }
  if (last_stop <= t) return kClear;
  // In steps, so that a collision while standing has a time too.
  const ArcVelocities stand_still{0.0, 0.0, 0.0, 0.0};
  for (; t < last_stop; t += step) {
    if (!collision_.motionFreeDynamic(s, stand_still, std::min(step, last_stop - t), obstacles, t, heading_spread,
                                      turning)) {
      return t;
    }
  }
  return kClear;
}

std::uint8_t StaaStar::markBrakeSafe(const UnicycleState& start, const DynamicObstacleSet& obstacles) {
  const double c0 = std::cos(start.theta), s0 = std::sin(start.theta);
  double start_slack = 0.0;
  if (!collision_.fastPoseFreeStatic({start.x, start.y, c0, s0}, &start_slack)) start_slack = 0.0;
  std::uint8_t best = 0;
  double latest = -1.0;  // among tier-0 actions: the latest time a collision begins
  for (std::size_t a = 0; a < actions_.size(); ++a) {
    const ArcVelocities vel = arcVelocities(start, actions_[a], config_.dt, limits_);
    const double c = std::cos(vel.w_mid * config_.dt), sn = std::sin(vel.w_mid * config_.dt);
    const ArcMotion motion = makeArcMotion(start, c0, s0, vel.v_mid, vel.w_mid, config_.dt, c, sn);
    const UnicycleState child{motion.x1, motion.y1, motion.theta1, vel.v_end, vel.w_end};
    std::uint8_t tier = 0;
    double clear = 0.0;  // the action itself collides
    double child_slack = -1.0;
    if (collision_.motionFreeStatic(motion, start_slack, &child_slack) &&
        collision_.motionFreeDynamic(start, vel, config_.dt, obstacles, 0.0)) {
      if (child_slack < 0.0) child_slack = std::max(0.0, start_slack - collision_.travelBound(motion));
      clear = brakeClearTime(child, config_.dt, braking_obstacles_, true, 0.0, config_.predict_turning, child_slack);
      if (std::isinf(clear)) {
        tier = 1;
        // Passive safety: the same stop against the obstacles at constant velocity (the map
        // along it was just found clear).
        if (config_.passive_safety &&
            (obstacles.size() == 0 ||
             std::isinf(brakeClearTime(child, config_.dt, obstacles, false, config_.passive_heading_spread,
                                       config_.predict_turning, 0.0, false)))) {
          tier = 2;
        }
      }
    }
    root_ok_[a] = tier;
    root_clear_[a] = clear;
    best = std::max(best, tier);
    if (tier == 0) latest = std::max(latest, clear);
  }
  // The allowed first actions: those of the best tier; when none passes, the least bad ones,
  // after which a braking robot would be hit latest (a robot that cannot stop in time any
  // more slows down or turns away rather than keep its speed: two agents that each went on
  // at full speed once no action was safe met head-on; docs/results.md).
  for (std::size_t a = 0; a < actions_.size(); ++a) {
    root_allowed_[a] = best > 0 ? root_ok_[a] == best : root_clear_[a] >= latest;
  }
  return best;
}

Action StaaStar::safeStop(const UnicycleState& start, const LocalMap& map, const DynamicObstacleSet& obstacles) {
  map_ = &map;
  collision_.prepare(map);
  braking_obstacles_.copyFrom(obstacles);
  markBrakeSafe(start, obstacles);
  // The allowed action that leaves the least speed (both velocities relative to their limits).
  double best_cost = 0.0;
  std::size_t best = actions_.size();
  for (std::size_t a = 0; a < actions_.size(); ++a) {
    if (!root_allowed_[a]) continue;
    const ArcVelocities vel = arcVelocities(start, actions_[a], config_.dt, limits_);
    const double cost = std::abs(vel.v_end) / std::max(limits_.v_max, -limits_.v_min) + std::abs(vel.w_end) / limits_.w_max;
    if (best == actions_.size() || cost < best_cost) {
      best_cost = cost;
      best = a;
    }
  }
  return actions_[best];
}

void StaaStar::beginSearch(const UnicycleState& start, const LocalMap& map, const DynamicObstacleSet& obstacles,
                           const Deadline& deadline) {
  map_ = &map;
  box_x_ = map.origin().x;
  box_y_ = map.origin().y;
  box_c_ = std::cos(map.origin().theta);
  box_s_ = std::sin(map.origin().theta);
  box_behind_ = map.config().behind_m;
  box_side_ = map.config().side_m;
  collision_.prepare(map);
  heuristic_.prepare(map.intermediateGoal().pose, obstacles, config_.dt, map, &collision_, deadline);
  nodes_.clear();
  queue_.clear();
  trajectory_.clear();
  if (closed_overflow_) {
    std::fill(closed_.begin(), closed_.end(), 0);
    closed_overflow_ = false;
  } else {
    for (const std::uint32_t w : closed_words_) closed_[w] = 0;
  }
  closed_words_.clear();
  Node root;
  root.s = start;
  root.h = heuristic_.evaluate(start, 0);
  root.f = root.h;
  nodes_.push_back(root);
  push(0);
}

void StaaStar::restrictRoot(const UnicycleState& start, const DynamicObstacleSet& obstacles, PlanResult& result) {
  braking_obstacles_.copyFrom(obstacles);
  result.brake_safety_tier = markBrakeSafe(start, obstacles);
  std::size_t allowed = 0;
  for (std::size_t a = 0; a < actions_.size(); ++a) allowed += root_allowed_[a] ? 1 : 0;
  result.brake_safe_actions = static_cast<std::uint32_t>(allowed);
}

const DynamicObstacleSet& StaaStar::separateContacts(const UnicycleState& start, const DynamicObstacleSet& obstacles) {
  contacts_ = 0;
  const std::size_t n = std::min(obstacles.size(), contact_.size());
  const Pose2 pose{start.x, start.y, start.theta};
  std::size_t touching = 0;
  for (std::size_t k = 0; k < n; ++k) {
    contact_[k] = collision_.touches(k, pose, obstacles, 0.0) ? 1 : 0;
    if (contact_[k] == 0) continue;
    ++touching;
    if (contacts_ < kMaxContacts) {
      const Box& box = obstacles.observed(k).box;
      contact_now_[contacts_] = 0.5 * (box.min + box.max);
      contact_next_[contacts_] = contact_now_[contacts_] + obstacles.displacement(k, config_.dt);
      ++contacts_;
    }
  }
  if (touching == 0) return obstacles;
  escape_obstacles_.copyExcept(obstacles, std::span<const std::uint8_t>(contact_.data(), n));
  return escape_obstacles_;
}

void StaaStar::restrictToSeparation(const UnicycleState& start) {
  std::uint8_t best = 0;
  double latest = -1.0;
  bool any = false;
  for (std::size_t a = 0; a < actions_.size(); ++a) {
    const ArcVelocities vel = arcVelocities(start, actions_[a], config_.dt, limits_);
    const Vec2 end = poseAlongArc(start, vel.v_mid, vel.w_mid, config_.dt).position();
    bool away = true;
    for (std::size_t c = 0; c < contacts_ && away; ++c) {
      away = (end - contact_next_[c]).norm() > (start.position() - contact_now_[c]).norm();
    }
    root_away_[a] = away ? 1 : 0;
    if (!away) continue;
    any = true;
    best = std::max(best, root_ok_[a]);
    if (root_ok_[a] == 0) latest = std::max(latest, root_clear_[a]);
  }
  for (std::size_t a = 0; a < actions_.size(); ++a) {
    // None moves away (a wall behind): none is allowed, the robot brakes and stays.
    root_allowed_[a] = any && root_away_[a] != 0 && (best > 0 ? root_ok_[a] == best : root_clear_[a] >= latest);
  }
}

void StaaStar::evaluateLazily(std::int32_t id, std::int32_t& best, PlanStats& st) {
  Node& n = nodes_[static_cast<std::size_t>(id)];
  const std::int64_t th = now();
  n.h = heuristic_.evaluate(n.s, n.depth);
  if (timing_) st.heuristic_ns += now() - th;
  ++st.heuristic_calls;
  n.f = n.g + n.h;
  n.evaluated = true;
  if (n.h < nodes_[static_cast<std::size_t>(best)].h) best = id;
  push(id);
}

void StaaStar::rotationsFor(const UnicycleState& s) {
  const std::size_t notches = actions_.notches();
  for (std::size_t j = 0; j < notches; ++j) {
    const ArcVelocities av = arcVelocities(s, actions_[j], config_.dt, limits_);
    rot_w_end_[j] = av.w_end;
    rot_w_mid_[j] = av.w_mid;
    sinCos(av.w_mid * config_.dt, rot_c_[j], rot_s_[j]);
    // The linear velocities of the actions with linear acceleration index j (arcVelocities
    // clamps v and w apart, so these are its values for every action of that row).
    const ArcVelocities lin = arcVelocities(s, actions_[j * notches], config_.dt, limits_);
    lin_v_end_[j] = lin.v_end;
    lin_v_mid_[j] = lin.v_mid;
  }
}

bool StaaStar::motionFree(const Node& node, const ArcMotion& motion, const ArcVelocities& vel,
                          const DynamicObstacleSet& obstacles, bool predict, double disc, double& end_slack,
                          PlanStats& st) const {
  const double t0 = node.depth * config_.dt;
  const std::int64_t tc = now();
  end_slack = -1.0;
  bool free = config_.check_swept ? collision_.motionFreeStatic(motion, node.slack, &end_slack, disc)
                                  : collision_.fastPoseFreeStatic({motion.x1, motion.y1, motion.c1, motion.s1});
  if (free && predict) {
    const Pose2 end{motion.x1, motion.y1, motion.theta1};
    if (!config_.check_swept) {
      free = collision_.poseFreeDynamic(end, obstacles, t0 + config_.dt);
    } else {
      free = collision_.motionFreeDynamic(node.s, vel, config_.dt, obstacles, t0, near_);
    }
  }
  if (timing_) st.collision_ns += now() - tc;
  return free;
}

double StaaStar::pathCost(const UnicycleState& child, int depth, const DynamicObstacleSet& obstacles,
                          bool predict) const {
  // Eq. (3): time, costmap at the state, proximity to the predicted obstacles.
  const double t = depth * config_.dt;
  double g = t + config_.w_static * map_->cost(child.position());
  if (predict && obstacles.size() > 0) {
    // Edges beyond the proximity range add nothing: they are not measured.
    const double beyond = config_.proximity_range_m > 0.0 ? config_.proximity_range_m : std::numeric_limits<double>::infinity();
    const double dist = collision_.distanceToDynamic(child.position(), obstacles, t, beyond);
    g += config_.w_dynamic * std::max(1.0 - dist / config_.proximity_range_m, 0.0);
  }
  return g;
}

void StaaStar::expand(std::int32_t id, const DynamicObstacleSet& obstacles, std::int32_t& best, PlanStats& st) {
  ++st.expansions;
  Node node = nodes_[static_cast<std::size_t>(id)];  // copy: the pool is appended below
  const int depth = node.depth + 1;
  const bool predict = depth <= config_.prediction_depth;
  const bool restrict_root = (config_.brake_safety || contacts_ > 0) && id == 0;
  // Per expansion, the trigonometry of the 7 x 7 actions: the heading's cosine and sine once,
  // and one rotation per angular acceleration (the linear ones do not rotate).
  const std::size_t notches = actions_.notches();
  const double c0 = std::cos(node.s.theta), s0 = std::sin(node.s.theta);
  rotationsFor(node.s);
  if (node.slack < 0.0 && config_.check_swept) {
    // The pose's clearance, for the swept checks of its 49 motions (not looked up when the
    // node was generated: its motion lay within its parent's clearance).
    const std::int64_t tc = now();
    double slack = 0.0;
    if (!collision_.fastPoseFreeStatic({node.s.x, node.s.y, c0, s0}, &slack)) slack = 0.0;
    node.slack = slack;
    nodes_[static_cast<std::size_t>(id)].slack = slack;
    if (timing_) st.collision_ns += now() - tc;
  }
  // The pose's clearance in any heading: motions whose origin stays within it are free.
  const double disc = config_.check_swept ? collision_.discSlack(node.s.x, node.s.y) : 0.0;
  // The moving obstacles these motions can come near: the others are not checked per sample.
  near_ = {};
  if (predict && config_.check_swept && obstacles.size() > 0) {
    const double v_lo = 0.5 * (node.s.v + limits_.v_min), v_hi = 0.5 * (node.s.v + limits_.v_max);
    const double travel = std::max(std::abs(v_lo), std::abs(v_hi)) * config_.dt;
    near_ = collision_.nearObstacles(node.s.position(), travel, obstacles, node.depth * config_.dt, config_.dt);
  }
  for (std::size_t a = 0; a < actions_.size(); ++a) {
    ++st.successors;
    if (restrict_root && !root_allowed_[a]) {
      ++st.collisions;  // could not brake safely after it
      continue;
    }
    const std::size_t i = a / notches, j = a % notches;  // actions are ordered (a index) * notches + (b index)
    const ArcVelocities vel{lin_v_end_[i], rot_w_end_[j], lin_v_mid_[i], rot_w_mid_[j]};
    const ArcMotion motion = makeArcMotion(node.s, c0, s0, vel.v_mid, rot_w_mid_[j], config_.dt, rot_c_[j], rot_s_[j]);
    const UnicycleState child{motion.x1, motion.y1, motion.theta1, vel.v_end, rot_w_end_[j]};
    std::size_t child_cell = 0;
    if (!closedIndex(child.x, child.y, child.theta, child_cell)) continue;  // outside the local map
    if (isClosed(child_cell)) continue;                                      // checked on push too
    double end_slack = -1.0;
    if (!motionFree(node, motion, vel, obstacles, predict, disc, end_slack, st)) {
      ++st.collisions;
      continue;
    }
    if (nodes_.size() == nodes_.capacity()) break;  // pool full: no more pushes
    Node c;
    c.slack = end_slack;
    c.evaluated = !config_.lazy_heuristic;
    c.s = child;
    c.g = pathCost(child, depth, obstacles, predict);
    if (config_.lazy_heuristic) {
      c.h = heuristic_.lowerBound(child);  // the true h when the state is popped
    } else {
      const std::int64_t th = now();
      c.h = heuristic_.evaluate(child, depth);
      if (timing_) st.heuristic_ns += now() - th;
      ++st.heuristic_calls;
    }
    c.f = c.g + c.h;
    c.parent = id;
    c.depth = static_cast<std::uint16_t>(depth);
    c.action = static_cast<std::uint8_t>(a);
    nodes_.push_back(c);
    const auto cid = static_cast<std::int32_t>(nodes_.size() - 1);
    push(cid);
    if (c.evaluated && c.h < nodes_[static_cast<std::size_t>(best)].h) best = cid;
  }
}

void StaaStar::finish(const UnicycleState& start, std::int32_t best, PlanResult& result) {
  if (best == 0 && result.outcome != PlanResult::Outcome::kFinished) {
    // Nothing beyond the start survived: every motion collides. Brake at the limits (the
    // original only did so near the root; this acts whatever the search saw).
    result.outcome = PlanResult::Outcome::kBrake;
  }
  const Node& b = nodes_[static_cast<std::size_t>(best)];
  result.best = b.s;
  result.best_h = b.h;
  result.depth = b.depth;
  // Follow the parents back to the first action; record the trajectory root..best.
  std::int32_t first = best;
  for (std::int32_t n = best; n != -1; n = nodes_[static_cast<std::size_t>(n)].parent) {
    if (nodes_[static_cast<std::size_t>(n)].parent == 0) first = n;
    if (trajectory_.size() < trajectory_.capacity()) trajectory_.push_back(nodes_[static_cast<std::size_t>(n)].s);
  }
  std::reverse(trajectory_.begin(), trajectory_.end());
  result.trajectory = trajectory_;
  if (best == 0) {
    // At the goal already (finished at the root) or braking: decelerate towards standstill.
    result.first_action = brakeAction(start, limits_, config_.dt);
  } else {
    result.first_action = actions_[nodes_[static_cast<std::size_t>(first)].action];
  }
}

PlanResult StaaStar::plan(const UnicycleState& start, const LocalMap& map, const DynamicObstacleSet& obstacles,
                          PlannerBudget budget) {
  PlanResult result;
  clock_ = budget.clock();
  const std::int64_t t_begin = now();
  budget.start();
  contacts_ = 0;
  search(start, map, obstacles, budget, result);
  // StaaConfig::separate_contacts: standing, and every motion collides. If that is a moving
  // obstacle the robot touches, plan again without it, first moving away from it (the pops
  // of both searches count against the one budget).
  constexpr double kStandingV = 0.05, kStandingW = 0.1;
  if (config_.separate_contacts && result.outcome == PlanResult::Outcome::kBrake && std::abs(start.v) <= kStandingV &&
      std::abs(start.w) <= kStandingW) {
    const DynamicObstacleSet& apart = separateContacts(start, obstacles);
    if (contacts_ > 0) {
      const PlanStats first = result.stats;
      result = PlanResult{};
      result.stats = first;
      result.contacts = static_cast<std::uint8_t>(contacts_);
      search(start, map, apart, budget, result);
    }
  }
  if (timing_) result.stats.total_ns = now() - t_begin;
  return result;
}

void StaaStar::search(const UnicycleState& start, const LocalMap& map, const DynamicObstacleSet& obstacles,
                      PlannerBudget& budget, PlanResult& result) {
  PlanStats& st = result.stats;
  beginSearch(start, map, obstacles, budget.deadline());
  std::int32_t best = 0;
  result.outcome = PlanResult::Outcome::kExhausted;
  // Braking safety of the first actions (see StaaConfig::brake_safety): only the actions of
  // the strictest tier that any action reaches are allowed; the least bad ones when none passes.
  if (config_.brake_safety) restrictRoot(start, obstacles, result);
  if (contacts_ > 0) restrictToSeparation(start);

  while (!queue_.empty()) {
    // Checked on every pop (paper, Sec. III-E-6).
    if (budget.exhausted(st.pops)) {
      result.outcome = PlanResult::Outcome::kAborted;
      break;
    }
    const std::int32_t id = pop();
    const Node& n = nodes_[static_cast<std::size_t>(id)];
    std::size_t cell = 0;
    const bool in_box = closedIndex(n.s.x, n.s.y, n.s.theta, cell);
    if (config_.lazy_heuristic && !n.evaluated) {
      // Lazy evaluation: the state was queued under a lower bound of h. A state whose cell is
      // closed meanwhile is dropped unevaluated; otherwise its true h is computed now and it
      // goes back into the queue under its true f (not counted as a pop: the paper's pop is
      // the one that closes or drops it).
      if (in_box && isClosed(cell)) {
        ++st.pops;
      } else {
        evaluateLazily(id, best, st);
      }
      continue;
    }
    ++st.pops;
    if (in_box) {
      if (isClosed(cell)) continue;  // its cell was closed by an earlier pop
      close(cell);
    }
    if (n.h < config_.finish_h) {
      best = id;
      result.outcome = PlanResult::Outcome::kFinished;
      break;
    }
    expand(id, obstacles, best, st);
  }
  finish(start, best, result);
}

}  // namespace staa
