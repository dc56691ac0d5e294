#include "world/multi_world.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "world/contact.hpp"
#include "world/footprint.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace staa {
using contact::kContactBisections;
using contact::kSampleSpacing;
using contact::kTouchMargin;
using contact::strictlyInside;

namespace {

Box grown(const Box& b, double r) { return Box{b.min - Vec2(r, r), b.max + Vec2(r, r)}; }

// The point of the polygon's boundary nearest to p.
Vec2 nearestBoundaryPoint(const Vec2& p, PolygonView poly) {
  Vec2 best = poly[0];
  double best_d = (p - best).squaredNorm();
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const Vec2 q = closestPointOnSegment(p, poly[k], poly[(k + 1) % poly.size()]);
    const double d = (p - q).squaredNorm();
    if (d < best_d) {
      best_d = d;
      best = q;
    }
  }
  return best;
}

}  // namespace

MultiWorld::MultiWorld(PolygonMap map, RobotProfile profile) : map_(std::move(map)), profile_(std::move(profile)) {
  obstacle_boxes_.reserve(map_.obstacles.size());
  for (const Polygon& o : map_.obstacles) obstacle_boxes_.push_back(boundingBox(o));
  obstacles_near_.reserve(map_.obstacles.size());
  start_obstacle_.reserve(map_.obstacles.size());
  start_ref_.reserve(map_.obstacles.size());
  start_ref_inside_.reserve(map_.obstacles.size());
  body_.reserve(profile_.footprint.size());
}

std::size_t MultiWorld::addAgent(const Pose2& start, AgentBody body) {
  Agent a;
  a.state.pose = start;
  a.body = body;
  placeFootprint(a);
  agents_.push_back(std::move(a));
  agents_near_.reserve(agents_.size());
  start_agent_.reserve(agents_.size());
  return agents_.size() - 1;
}

void MultiWorld::placeFootprint(Agent& a) {
  footprintAt(profile_.footprint, a.state.pose, a.footprint);
  a.box = boundingBox(a.footprint);
}

Vec2 MultiWorld::velocity(std::size_t i) const {
  const RobotState& s = agents_[i].state;
  return Vec2(s.v * std::cos(s.pose.theta), s.v * std::sin(s.pose.theta));
}

void MultiWorld::setAgentState(std::size_t i, const RobotState& state) {
  Agent& a = agents_[i];
  a.state = state;
  a.state.v = std::clamp(a.state.v, profile_.limits.v_min, profile_.limits.v_max);
  a.state.w = std::clamp(a.state.w, -profile_.limits.w_max, profile_.limits.w_max);
  placeFootprint(a);
}

bool MultiWorld::touchesMap(const Pose2& pose) const {
  footprintAt(profile_.footprint, pose, body_);
  if (map_.bounds) {
    for (const Vec2& p : body_) {
      if (!strictlyInside(*map_.bounds, p)) return true;
    }
  }
  const Box box = grown(boundingBox(body_), kTouchMargin);
  for (std::size_t k = 0; k < map_.obstacles.size(); ++k) {
    if (obstacle_boxes_[k].overlaps(box) && polygonsOverlap(body_, map_.obstacles[k])) return true;
  }
  return false;
}

bool MultiWorld::touchesAnything(const Pose2& pose) const {
  if (touchesMap(pose)) return true;  // leaves the footprint in body_
  const Box box = grown(boundingBox(body_), kTouchMargin);
  for (const Agent& a : agents_) {
    if (a.box.overlaps(box) && polygonsOverlap(body_, a.footprint)) return true;
  }
  return false;
}

bool MultiWorld::overlapping(std::size_t i, std::size_t j) const {
  return grown(agents_[i].box, kTouchMargin).overlaps(agents_[j].box) &&
         polygonsOverlap(agents_[i].footprint, agents_[j].footprint);
}

double MultiWorld::boundsViolation(const Box& b, PolygonView poly) {
  double worst = -1e300;
  for (const Vec2& p : poly) {
    worst = std::max({worst, b.min.x() - p.x(), p.x() - b.max.x(), b.min.y() - p.y(), p.y() - b.max.y()});
  }
  return worst;
}

MultiWorld::Contact MultiWorld::touchesCandidates(std::size_t self) const {
  Contact c;
  if (map_.bounds && !start_bounds_) {
    for (const Vec2& p : body_) {
      if (!strictlyInside(*map_.bounds, p)) {
        c.kind = Contact::Kind::kBounds;
        return c;
      }
    }
  }
  const Box box = grown(boundingBox(body_), kTouchMargin);
  for (std::size_t n = 0; n < obstacles_near_.size(); ++n) {
    const std::size_t k = obstacles_near_[n];
    if (start_obstacle_[n] || !obstacle_boxes_[k].overlaps(box)) continue;
    if (polygonsOverlap(body_, map_.obstacles[k])) {
      c.kind = Contact::Kind::kObstacle;
      c.index = k;
      return c;
    }
  }
  for (std::size_t n = 0; n < agents_near_.size(); ++n) {
    const std::size_t j = agents_near_[n];
    if (j == self || start_agent_[n] || !agents_[j].box.overlaps(box)) continue;
    if (polygonsOverlap(body_, agents_[j].footprint)) {
      c.kind = Contact::Kind::kAgent;
      c.index = j;
      return c;
    }
  }
  return c;
}

bool MultiWorld::sinksDeeper(const Pose2& from, const Pose2& to) const {
  const Vec2 a = from.position(), b = to.position();
  for (std::size_t n = 0; n < obstacles_near_.size(); ++n) {
    if (!start_obstacle_[n] || start_ref_inside_[n]) continue;  // deep inside: any way out
    if ((b - start_ref_[n]).norm() < (a - start_ref_[n]).norm()) return true;
  }
  for (std::size_t n = 0; n < agents_near_.size(); ++n) {
    if (!start_agent_[n]) continue;
    const Vec2 c = agents_[agents_near_[n]].state.pose.position();
    if ((b - c).norm() < (a - c).norm()) return true;
  }
  if (start_bounds_) {
    footprintAt(profile_.footprint, from, body_);
    const double before = boundsViolation(*map_.bounds, body_);
    footprintAt(profile_.footprint, to, body_);
    if (boundsViolation(*map_.bounds, body_) > before) return true;
  }
  return false;
}

void MultiWorld::moveSolid(std::size_t i, double dt) {
  Agent& a = agents_[i];
  const double v = a.state.v, w = a.state.w;
  const Pose2 from = a.state.pose;
  const double travel = (std::abs(v) + std::abs(w) * profile_.circumradius()) * dt;

  // Candidates: whatever the swept footprint can reach this step.
  const Box swept = grown(a.box, travel + kTouchMargin);
  obstacles_near_.clear();
  start_obstacle_.clear();
  start_ref_.clear();
  start_ref_inside_.clear();
  for (std::size_t k = 0; k < obstacle_boxes_.size(); ++k) {
    if (!obstacle_boxes_[k].overlaps(swept)) continue;
    obstacles_near_.push_back(k);
    const bool overlapped = polygonsOverlap(a.footprint, map_.obstacles[k]);
    start_obstacle_.push_back(overlapped);
    start_ref_.push_back(overlapped ? nearestBoundaryPoint(from.position(), map_.obstacles[k]) : Vec2::Zero());
    start_ref_inside_.push_back(overlapped && locatePoint(from.position(), map_.obstacles[k]) == Containment::kInside);
  }
  agents_near_.clear();
  start_agent_.clear();
  for (std::size_t j = 0; j < agents_.size(); ++j) {
    if (j == i || agents_[j].body != AgentBody::kSolid || !agents_[j].box.overlaps(swept)) continue;
    agents_near_.push_back(j);
    const bool overlapped = polygonsOverlap(a.footprint, agents_[j].footprint);
    start_agent_.push_back(overlapped);
    if (overlapped) {
      agents_[j].hit = true;
      agents_[j].touched = static_cast<int>(i);
      a.touched = static_cast<int>(j);
    }
  }
  start_bounds_ = false;
  if (map_.bounds) {
    for (const Vec2& p : a.footprint) start_bounds_ = start_bounds_ || !strictlyInside(*map_.bounds, p);
  }
  const bool overlapped_at_start = start_bounds_ ||
                                   std::find(start_obstacle_.begin(), start_obstacle_.end(), 1) != start_obstacle_.end() ||
                                   std::find(start_agent_.begin(), start_agent_.end(), 1) != start_agent_.end();
  if (overlapped_at_start) a.hit = true;

  // Swept motion against everything not overlapped at the start; the first contact is
  // refined by bisection to the last free point.
  double free_fraction = 1.0;
  bool blocked = false;
  Contact contact;
  if (travel > 0.0) {
    const int samples = std::max(1, static_cast<int>(std::ceil(travel / kSampleSpacing)));
    for (int k = 1; k <= samples && !blocked; ++k) {
      const double f = static_cast<double>(k) / samples;
      footprintAt(profile_.footprint, integrateArc(from, v, w, f * dt), body_);
      contact = touchesCandidates(i);
      if (!contact) continue;
      double lo = static_cast<double>(k - 1) / samples, hi = f;
      for (int it = 0; it < kContactBisections; ++it) {
        const double mid = 0.5 * (lo + hi);
        footprintAt(profile_.footprint, integrateArc(from, v, w, mid * dt), body_);
        const Contact c = touchesCandidates(i);
        if (c) {
          hi = mid;
          contact = c;
        } else {
          lo = mid;
        }
      }
      free_fraction = lo;
      blocked = true;
    }
  }
  if (!blocked && overlapped_at_start && sinksDeeper(from, integrateArc(from, v, w, dt))) {
    free_fraction = 0.0;
    blocked = true;
  }

  if (blocked) {
    if (free_fraction > 0.0) a.state.pose = integrateArc(from, v, w, free_fraction * dt);
    a.distance += std::abs(v) * dt * free_fraction;
    a.state.v = 0.0;
    a.state.w = 0.0;
    a.hit = true;
    // A new contact names what was hit; sinking deeper into what it overlapped at the start
    // keeps the name found then.
    if (contact) a.touched = contact.kind == Contact::Kind::kAgent ? static_cast<int>(contact.index) : -1;
    if (contact.kind == Contact::Kind::kAgent) {
      agents_[contact.index].hit = true;
      agents_[contact.index].touched = static_cast<int>(i);
    }
  } else {
    a.state.pose = integrateArc(from, v, w, dt);
    a.distance += std::abs(v) * dt;
  }
  placeFootprint(a);
}

bool MultiWorld::nearAnything(std::size_t i) const {
  const Agent& a = agents_[i];
  const double r = kContactRelease_m;
  if (map_.bounds) {
    const Box inner = grown(*map_.bounds, -r);
    for (const Vec2& p : a.footprint) {
      if (!strictlyInside(inner, p)) return true;
    }
  }
  const Box box = grown(a.box, r);
  for (std::size_t k = 0; k < map_.obstacles.size(); ++k) {
    if (obstacle_boxes_[k].overlaps(box) && polygonDistance(a.footprint, map_.obstacles[k]) < r) return true;
  }
  for (std::size_t j = 0; j < agents_.size(); ++j) {
    if (j == i || !agents_[j].box.overlaps(box)) continue;
    if (polygonDistance(a.footprint, agents_[j].footprint) < r) return true;
  }
  return false;
}

void MultiWorld::step(double dt, std::span<const AgentCommand> commands) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw std::invalid_argument("MultiWorld::step: dt must be finite and > 0");
  if (commands.size() != agents_.size()) {
    throw std::invalid_argument("MultiWorld::step: " + std::to_string(commands.size()) + " commands for " +
                                std::to_string(agents_.size()) + " agents");
  }
  for (std::size_t i = 0; i < commands.size(); ++i) {
    if (!std::isfinite(commands[i].v) || !std::isfinite(commands[i].w)) {
      throw std::invalid_argument("MultiWorld::step: agent " + std::to_string(i) + ": commands must be finite");
    }
  }
  const MotionLimits& lim = profile_.limits;
  time_ += dt;

  // 1. Velocities approach the (clamped) commands within the acceleration limits.
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    RobotState& s = agents_[i].state;
    const double v_target = std::clamp(commands[i].v, lim.v_min, lim.v_max);
    const double w_target = std::clamp(commands[i].w, -lim.w_max, lim.w_max);
    s.v = std::clamp(s.v + std::clamp(v_target - s.v, -lim.a_max * dt, lim.a_max * dt), lim.v_min, lim.v_max);
    s.w = std::clamp(s.w + std::clamp(w_target - s.w, -lim.b_max * dt, lim.b_max * dt), -lim.w_max, lim.w_max);
    agents_[i].hit = false;
    agents_[i].touched = -1;
  }

  // 2. Motion, agent by agent.
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    Agent& a = agents_[i];
    if (a.body == AgentBody::kSolid) {
      moveSolid(i, dt);
    } else {
      a.state.pose = integrateArc(a.state.pose, a.state.v, a.state.w, dt);
      a.distance += std::abs(a.state.v) * dt;
      placeFootprint(a);
    }
  }

  // 3. Overlaps with ghosts, then the contact episodes of the solid agents.
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    Agent& a = agents_[i];
    if (a.body != AgentBody::kSolid) continue;
    for (std::size_t j = 0; j < agents_.size() && !a.hit; ++j) {
      if (agents_[j].body == AgentBody::kGhost && overlapping(i, j)) {
        a.hit = true;
        a.touched = static_cast<int>(j);
      }
    }
  }
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    Agent& a = agents_[i];
    if (a.body != AgentBody::kSolid) continue;
    if (a.hit) {
      if (!a.in_contact) ++a.episodes;
      a.in_contact = true;
    } else if (a.in_contact) {
      a.in_contact = nearAnything(i);
    }
  }
}

}  // namespace staa
