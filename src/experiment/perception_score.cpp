#include "experiment/perception_score.hpp"

#include "geometry/polygon.hpp"
#include "world/footprint.hpp"
#include "world/multi_world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {
namespace {

// The area centroid of a polygon (its vertex mean when degenerate).
Vec2 centroidOf(PolygonView p) {
  double a = 0.0;
  Vec2 c(0.0, 0.0);
  for (std::size_t k = 0; k < p.size(); ++k) {
    const Vec2& u = p[k];
    const Vec2& v = p[(k + 1) % p.size()];
    const double w = u.x() * v.y() - v.x() * u.y();
    a += w;
    c += (u + v) * w;
  }
  if (std::abs(a) > 1e-12) return c / (3.0 * a);
  Vec2 mean(0.0, 0.0);
  for (const Vec2& v : p) mean += v;
  return p.empty() ? mean : Vec2(mean / static_cast<double>(p.size()));
}

}  // namespace

void ErrorHistogram::add(double value) {
  const double v = std::max(0.0, value);
  const auto bin = static_cast<std::size_t>(std::min<double>(std::floor(v / kBin), kBins));
  ++counts[bin];
  ++n;
  sum += v;
  max = std::max(max, v);
}

void ErrorHistogram::merge(const ErrorHistogram& o) {
  for (std::size_t k = 0; k <= kBins; ++k) counts[k] += o.counts[k];
  n += o.n;
  sum += o.sum;
  max = std::max(max, o.max);
}

double ErrorHistogram::percentile(double p) const {
  if (n == 0) return 0.0;
  const auto rank = static_cast<std::uint64_t>(std::ceil(std::clamp(p, 0.0, 1.0) * static_cast<double>(n)));
  std::uint64_t seen = 0;
  for (std::size_t k = 0; k <= kBins; ++k) {
    seen += counts[k];
    if (seen >= std::max<std::uint64_t>(rank, 1)) return k == kBins ? max : kBin * static_cast<double>(k + 1);
  }
  return max;
}

void PerceptionAccuracy::merge(const PerceptionAccuracy& o) {
  frames += o.frames;
  frames_lost += o.frames_lost;
  position_m.merge(o.position_m);
  velocity_mps.merge(o.velocity_mps);
  kept_position_m.merge(o.kept_position_m);
  kept_velocity_mps.merge(o.kept_velocity_mps);
  near_samples += o.near_samples;
  near_missed += o.near_missed;
  near_missed_in_view += o.near_missed_in_view;
  obstacles += o.obstacles;
  kept_obstacles += o.kept_obstacles;
  false_obstacles += o.false_obstacles;
  false_kept += o.false_kept;
  entries += o.entries;
  unsettled += o.unsettled;
  latency_s.insert(latency_s.end(), o.latency_s.begin(), o.latency_s.end());
  render_us_sum += o.render_us_sum;
  perception_us_sum += o.perception_us_sum;
}

PerceptionScorer::PerceptionScorer(std::size_t agents, const LineOfSight* sight, double sight_range_m)
    : n_(agents), sight_(sight), sight_range_m_(sight_range_m), pairs_(agents * agents) {}

void PerceptionScorer::score(const MultiWorld& world, std::size_t self, double time_s, const hal::ObstacleFrame& frame,
                             std::span<const std::size_t> others, std::span<const std::uint32_t> mover_pixels) {
  ++accuracy_.frames;
  const std::size_t count = frame.count;
  std::array<Box, hal::ObstacleFrame::kMaxObstacles> boxes{};
  std::array<Vec2, hal::ObstacleFrame::kMaxObstacles> centres{};
  std::array<bool, hal::ObstacleFrame::kMaxObstacles> covers{};
  for (std::size_t o = 0; o < count; ++o) {
    const PolygonView p(frame.obstacles[o].vertices.data(), frame.obstacles[o].n);
    boxes[o] = boundingBox(p);
    centres[o] = centroidOf(p);
    const bool kept = frame.obstacles[o].unseen_s > 0.0;
    ++accuracy_.obstacles;
    accuracy_.kept_obstacles += kept ? 1 : 0;
  }
  const Polygon& own = world.footprint(self);
  for (std::size_t m = 0; m < others.size(); ++m) {
    const std::size_t j = others[m];
    const Polygon& body = world.footprint(j);
    const Box box = boundingBox(body);
    const Vec2 centre = centroidOf(body);
    const Vec2 velocity = world.velocity(j);
    // Its track: the covering obstacle nearest its centroid.
    std::size_t best = count;
    double best_d = std::numeric_limits<double>::infinity();
    for (std::size_t o = 0; o < count; ++o) {
      if (boxDistance(box, boxes[o]) > kMatchM) continue;
      const PolygonView p(frame.obstacles[o].vertices.data(), frame.obstacles[o].n);
      if (polygonDistance(body, p) > kMatchM) continue;
      covers[o] = true;
      const double d = (centres[o] - centre).norm();
      if (d < best_d) {
        best_d = d;
        best = o;
      }
    }
    const std::uint32_t pixels = m < mover_pixels.size() ? mover_pixels[m] : 0u;
    if (best < count) {
      const double v_error = (frame.obstacles[best].velocity - velocity).norm();
      if (frame.obstacles[best].unseen_s > 0.0) {
        accuracy_.kept_position_m.add(best_d);
        accuracy_.kept_velocity_mps.add(v_error);
      } else {
        accuracy_.position_m.add(best_d);
        accuracy_.velocity_mps.add(v_error);
      }
    }
    if (polygonDistance(own, body) <= kNearM) {
      ++accuracy_.near_samples;
      if (best == count) {
        ++accuracy_.near_missed;
        accuracy_.near_missed_in_view += pixels > 0 ? 1 : 0;
      }
    }

    Pair& pair = pairs_[self * n_ + j];
    if (sight_ != nullptr && sight_->seesAny(world.agent(self).pose.position(), body, sight_range_m_)) {
      if (pair.in_sight_s < 0.0 || time_s - pair.last_in_sight_s > kSightingGapS) {
        pair.in_sight_s = time_s;
        pair.in_sight_m = polygonDistance(own, body);
      }
      pair.last_in_sight_s = time_s;
    }
    if (best < count) {
      const bool seen = frame.obstacles[best].unseen_s == 0.0;
      const bool on = pair.sighting_s >= 0.0 && time_s - pair.covered_s <= kSightingGapS;
      if (seen && !on) {
        pair.sighting_s = time_s;
        pair.sighting_m = polygonDistance(own, body);
      }
      pair.covered_s = time_s;
    }

    // Latency: entering the view, then settling.
    const bool in_view = pixels >= kEnterPixels;
    if (pair.entering) {
      if (best < count && frame.obstacles[best].unseen_s == 0.0 &&
          (frame.obstacles[best].velocity - velocity).norm() <= kSettledMps) {
        accuracy_.latency_s.push_back(time_s - pair.entered_s);
        pair.entering = false;
      } else if (!in_view) {
        ++accuracy_.unsettled;
        pair.entering = false;
      }
    } else if (in_view && time_s - pair.last_in_view_s >= kOutOfViewS && velocity.norm() >= kMovingMps) {
      ++accuracy_.entries;
      pair.entering = true;
      pair.entered_s = time_s;
      // Settled in this very frame: latency 0.
      if (best < count && frame.obstacles[best].unseen_s == 0.0 &&
          (frame.obstacles[best].velocity - velocity).norm() <= kSettledMps) {
        accuracy_.latency_s.push_back(0.0);
        pair.entering = false;
      }
    }
    if (in_view) pair.last_in_view_s = time_s;
  }
  for (std::size_t o = 0; o < count; ++o) {
    if (covers[o]) continue;
    // Not near any agent (the observer's own body is never rendered, so it counts too).
    ++accuracy_.false_obstacles;
    accuracy_.false_kept += frame.obstacles[o].unseen_s > 0.0 ? 1 : 0;
  }
}

PerceptionScorer::Sighting PerceptionScorer::sighting(std::size_t self, std::size_t other, double time_s) const {
  Sighting out;
  if (self >= n_ || other >= n_) return out;
  const Pair& pair = pairs_[self * n_ + other];
  out.covered = pair.covered_s >= 0.0;
  out.covered_before_s = out.covered ? time_s - pair.covered_s : 0.0;
  out.seen = pair.sighting_s >= 0.0 && out.covered && time_s - pair.covered_s <= kSightingGapS;
  if (out.seen) {
    out.seen_before_s = time_s - pair.sighting_s;
    out.seen_at_m = pair.sighting_m;
  }
  out.in_sight = pair.in_sight_s >= 0.0 && time_s - pair.last_in_sight_s <= kSightingGapS;
  if (out.in_sight) {
    out.in_sight_before_s = time_s - pair.in_sight_s;
    out.in_sight_at_m = pair.in_sight_m;
  }
  return out;
}

}  // namespace staa
