#include "world/world.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "world/contact.hpp"
#include "world/footprint.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace staa {

using contact::kContactBisections;
using contact::kSampleSpacing;
using contact::kTouchMargin;
using contact::strictlyInside;

World::World(PolygonMap map, RobotProfile profile, const Pose2& start, std::vector<Mover> movers)
    : map_(std::move(map)), profile_(std::move(profile)) {
  obstacle_boxes_.reserve(map_.obstacles.size());
  for (const Polygon& o : map_.obstacles) obstacle_boxes_.push_back(boundingBox(o));
  movers_.reserve(movers.size());
  for (Mover& spec : movers) {
    MoverTrack m;
    m.spec = std::move(spec);
    if (m.spec.waypoints.empty()) throw std::invalid_argument("World: a mover needs at least one waypoint");
    m.cumulative.push_back(0.0);
    for (std::size_t k = 1; k < m.spec.waypoints.size(); ++k) {
      m.cumulative.push_back(m.cumulative.back() + (m.spec.waypoints[k] - m.spec.waypoints[k - 1]).norm());
    }
    m.length = m.cumulative.back();
    m.box = boundingBox(m.spec.polygon);
    movers_.push_back(std::move(m));
  }
  // The scratch polygons reach their largest size here, once: a step never allocates (the
  // daemon's simulated base steps the world in a real-time thread).
  body_.reserve(profile_.footprint.size());
  std::size_t largest_mover = 0;
  for (const MoverTrack& m : movers_) largest_mover = std::max(largest_mover, m.spec.polygon.size());
  other_.reserve(largest_mover);
  robot_.pose = start;
  updateMovers();
  min_clearance_ = clearance();
}

World::World(const Scenario& scenario) : World(scenario.map, scenario.robot, scenario.start, scenario.movers) {}

void World::setRobotState(const RobotState& state) {
  robot_ = state;
  robot_.v = std::clamp(robot_.v, profile_.limits.v_min, profile_.limits.v_max);
  robot_.w = std::clamp(robot_.w, -profile_.limits.w_max, profile_.limits.w_max);
}

double World::moverPeriod(std::size_t i) const {
  const MoverTrack& m = movers_[i];
  return m.length > 0.0 && m.spec.speed > 0.0 ? 2.0 * m.length / m.spec.speed : 0.0;
}

void World::placeMover(MoverTrack& m) const {
  m.velocity = Vec2::Zero();
  m.position = m.spec.waypoints.front();
  if (m.length <= 0.0 || m.spec.speed <= 0.0) return;
  // Ping-pong: unfold the round trip into [0, 2L) and fold the way back onto the way out.
  // A function of the time alone, so no error accumulates over a long run.
  double s = std::fmod(m.spec.speed * time_, 2.0 * m.length);
  double direction = 1.0;
  if (s > m.length) {
    s = 2.0 * m.length - s;
    direction = -1.0;
  }
  // The segment holding arc length s (the last one at s = L).
  const auto it = std::upper_bound(m.cumulative.begin(), m.cumulative.end(), s);
  std::size_t k = static_cast<std::size_t>(it - m.cumulative.begin());
  k = std::clamp<std::size_t>(k, 1, m.cumulative.size() - 1);
  // Zero-length segments (repeated waypoints) never hold s strictly inside; skip back to one
  // with length so the velocity has a direction.
  while (k > 1 && m.cumulative[k] - m.cumulative[k - 1] <= 0.0) --k;
  const Vec2& a = m.spec.waypoints[k - 1];
  const Vec2& b = m.spec.waypoints[k];
  const double seg = m.cumulative[k] - m.cumulative[k - 1];
  if (seg <= 0.0) return;
  const double u = std::clamp((s - m.cumulative[k - 1]) / seg, 0.0, 1.0);
  m.position = a + u * (b - a);
  m.velocity = direction * m.spec.speed / seg * (b - a);
}

void World::updateMovers() {
  for (MoverTrack& m : movers_) placeMover(m);
}

Polygon World::moverPolygon(std::size_t i) const {
  Polygon out = movers_[i].spec.polygon;
  for (Vec2& p : out) p += movers_[i].position;
  return out;
}

Polygon World::footprint() const { return footprintAt(profile_.footprint, robot_.pose); }

bool World::collides(const Pose2& pose) const {
  footprintAt(profile_.footprint, pose, body_);
  if (map_.bounds) {
    for (const Vec2& p : body_) {
      if (!strictlyInside(*map_.bounds, p)) return true;  // on the boundary touches the outside
    }
  }
  Box box = boundingBox(body_);
  box.min -= Vec2(kTouchMargin, kTouchMargin);
  box.max += Vec2(kTouchMargin, kTouchMargin);
  for (std::size_t i = 0; i < map_.obstacles.size(); ++i) {
    if (obstacle_boxes_[i].overlaps(box) && polygonsOverlap(body_, map_.obstacles[i])) return true;
  }
  for (const MoverTrack& m : movers_) {
    const Box mbox{m.box.min + m.position, m.box.max + m.position};
    if (!mbox.overlaps(box)) continue;
    other_ = m.spec.polygon;
    for (Vec2& p : other_) p += m.position;
    if (polygonsOverlap(body_, other_)) return true;
  }
  return false;
}

double World::clearance() const {
  footprintAt(profile_.footprint, robot_.pose, body_);
  double best = std::numeric_limits<double>::infinity();
  if (map_.bounds) {
    // The footprint is inside the (convex) box, so its nearest point to the outside is a vertex.
    const Box& b = *map_.bounds;
    for (const Vec2& p : body_) {
      if (!strictlyInside(b, p)) return 0.0;
      best = std::min({best, p.x() - b.min.x(), b.max.x() - p.x(), p.y() - b.min.y(), b.max.y() - p.y()});
    }
  }
  const Box box = boundingBox(body_);
  for (std::size_t i = 0; i < map_.obstacles.size(); ++i) {
    if (boxDistance(box, obstacle_boxes_[i]) >= best) continue;  // cannot be nearer
    best = std::min(best, polygonDistance(body_, map_.obstacles[i]));
    if (best <= 0.0) return 0.0;
  }
  for (const MoverTrack& m : movers_) {
    const Box mbox{m.box.min + m.position, m.box.max + m.position};
    if (boxDistance(box, mbox) >= best) continue;
    other_ = m.spec.polygon;
    for (Vec2& p : other_) p += m.position;
    best = std::min(best, polygonDistance(body_, other_));
    if (best <= 0.0) return 0.0;
  }
  return best;
}

StepOutcome World::step(double dt, double v_cmd, double w_cmd) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw std::invalid_argument("World::step: dt must be finite and > 0");
  if (!std::isfinite(v_cmd) || !std::isfinite(w_cmd)) throw std::invalid_argument("World::step: commands must be finite");
  const MotionLimits& lim = profile_.limits;

  time_ += dt;
  updateMovers();

  // Velocities approach the (clamped) commands within the acceleration limits.
  const double v_target = std::clamp(v_cmd, lim.v_min, lim.v_max);
  const double w_target = std::clamp(w_cmd, -lim.w_max, lim.w_max);
  const double v = std::clamp(robot_.v + std::clamp(v_target - robot_.v, -lim.a_max * dt, lim.a_max * dt), lim.v_min, lim.v_max);
  const double w = std::clamp(robot_.w + std::clamp(w_target - robot_.w, -lim.b_max * dt, lim.b_max * dt), -lim.w_max, lim.w_max);

  // Swept motion: samples along the arc no farther apart than kSampleSpacing for any point
  // of the footprint; the first one in collision is refined to the contact by bisection.
  const Pose2 from = robot_.pose;
  StepOutcome out;
  double free_fraction = 1.0;
  if (collides(from)) {
    free_fraction = 0.0;  // a mover ran into the robot: it stays where it is
    out.collided = true;
  } else {
    const double travel = (std::abs(v) + std::abs(w) * profile_.circumradius()) * dt;
    const int samples = std::max(1, static_cast<int>(std::ceil(travel / kSampleSpacing)));
    for (int k = 1; k <= samples; ++k) {
      const double f = static_cast<double>(k) / samples;
      if (!collides(integrateArc(from, v, w, f * dt))) continue;
      double lo = static_cast<double>(k - 1) / samples, hi = f;
      for (int it = 0; it < kContactBisections; ++it) {
        const double mid = 0.5 * (lo + hi);
        (collides(integrateArc(from, v, w, mid * dt)) ? hi : lo) = mid;
      }
      free_fraction = lo;
      out.collided = true;
      break;
    }
  }

  if (out.collided) {
    if (free_fraction > 0.0) robot_.pose = integrateArc(from, v, w, free_fraction * dt);
    robot_.v = 0.0;
    robot_.w = 0.0;
    out.new_episode = !in_contact_;
    if (out.new_episode) ++episodes_;
    in_contact_ = true;
    min_clearance_ = 0.0;
  } else {
    robot_.pose = integrateArc(from, v, w, dt);
    robot_.v = v;
    robot_.w = w;
    in_contact_ = false;
    min_clearance_ = std::min(min_clearance_, clearance());
  }
  return out;
}

}  // namespace staa
