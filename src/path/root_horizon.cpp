#include "path/root_horizon.hpp"

#include "path/polygon_set.hpp"

#include <algorithm>
#include <cmath>

namespace staa {

namespace {

constexpr double kQuarter = static_cast<double>(RootHorizon::kSectors / 4);
// Absorbs the roundings of the relative coordinates and of the distances (about 1e-15 m for
// maps of kilometres; nothing a robot state is ever that close to).
constexpr double kMargin = 1e-9;

}  // namespace

// The pseudo-angle (0..4 counter-clockwise from +x, one per quadrant, monotonic in the angle):
// a division instead of atan2.
std::size_t RootHorizon::sectorOf(const Vec2& d) {
  const double x = d.x(), y = d.y();
  double pa = 0.0;
  if (y >= 0.0) {
    pa = x >= 0.0 ? (x + y > 0.0 ? y / (x + y) : 0.0) : 1.0 + (-x) / (y - x);
  } else {
    pa = x < 0.0 ? 2.0 + (-y) / (-x - y) : 3.0 + x / (x - y);
  }
  return std::min(kSectors - 1, static_cast<std::size_t>(pa * kQuarter));
}

Vec2 RootHorizon::sectorStart(std::size_t s) {
  s %= kSectors;
  const std::size_t q = s / (kSectors / 4);
  const double f = static_cast<double>(s % (kSectors / 4)) / kQuarter;
  switch (q) {
    case 0: return {1.0 - f, f};
    case 1: return {-f, 1.0 - f};
    case 2: return {-(1.0 - f), -f};
    default: return {f, -(1.0 - f)};
  }
}

void RootHorizon::build(const PolygonSet& set, const Vec2& root, const Box& region) {
  root_ = root;
  region_ = Box{region.min.cwiseMin(root), region.max.cwiseMax(root)};
  reach_ = 0.0;
  for (const Vec2& corner : {region_.min, region_.max, Vec2(region_.min.x(), region_.max.y()),
                             Vec2(region_.max.x(), region_.min.y())}) {
    reach_ = std::max(reach_, (corner - root).norm());
  }
  built_ = true;
  // A root inside an obstacle: a segment from it may cross no edge and still be blocked.
  if (set.pointBlocked(root)) {
    std::fill(bound_.begin(), bound_.end(), 0.0);
    return;
  }
  std::fill(bound_.begin(), bound_.end(), reach_);
  set.forEachEdgeInBox(region_, [&](std::size_t v) {
    addEdge(set.vertex(v) - root, set.vertex(set.nextVertex(v)) - root);
    return false;
  });
}

void RootHorizon::addEdge(const Vec2& c, const Vec2& d) {
  const Vec2 e = d - c;
  const double ee = e.squaredNorm();
  // The whole edge's distance first: far edges (most of them) change nothing.
  const double t_near = ee > 0.0 ? std::clamp(-c.dot(e) / ee, 0.0, 1.0) : 0.0;
  const double near = (c + e * t_near).norm() - kMargin;
  if (near >= reach_) return;
  if (near <= 0.0) {
    // Through the root (or as good as): nothing is certain in any direction.
    std::fill(bound_.begin(), bound_.end(), 0.0);
    return;
  }
  // The sectors from c's to d's, counter-clockwise the short way round (the edge misses the
  // root, so that way is under half a turn), two more at each end: one for the rounding of
  // an end's sector, one for the rounding of a query's.
  std::size_t from = sectorOf(c), to = sectorOf(d);
  if (cross(c, d) < 0.0) std::swap(from, to);
  const std::size_t span = (to + kSectors - from) % kSectors;
  if (span > kSectors / 2) {
    std::fill(bound_.begin(), bound_.end(), 0.0);  // cannot happen; stay safe
    return;
  }
  for (std::size_t k = 0; k <= span + 4; ++k) {
    const std::size_t s = (from + kSectors - 2 + k) % kSectors;
    // The edge's part within this sector and two on each side (a wedge of at most 2.3 degrees, so
    // no rounding of a direction or of the clip can leave out a point of the sector itself).
    const Vec2 lo = sectorStart(s + kSectors - 2), hi = sectorStart(s + 3);
    double t0 = 0.0, t1 = 1.0;
    // cross(lo, c + t e) >= 0 and cross(c + t e, hi) >= 0.
    const double f0 = cross(lo, c), f1 = cross(lo, e);
    const double g0 = cross(c, hi), g1 = cross(e, hi);
    bool empty = false;
    auto clip = [&](double v0, double v1) {
      if (v1 == 0.0) {
        if (v0 < 0.0) empty = true;
      } else if (v1 > 0.0) {
        t0 = std::max(t0, -v0 / v1);
      } else {
        t1 = std::min(t1, -v0 / v1);
      }
    };
    clip(f0, f1);
    clip(g0, g1);
    if (empty || t0 > t1) continue;
    const double t = std::clamp(t_near, t0, t1);
    const double dist = (c + e * t).norm() - kMargin;
    bound_[s] = std::min(bound_[s], std::max(dist, 0.0));
  }
}

bool RootHorizon::certifiesFree(const Vec2& p) const {
  if (!region_.contains(p)) return false;
  const Vec2 d = p - root_;
  if (d.x() == 0.0 && d.y() == 0.0) return false;
  const double b = bound_[sectorOf(d)];
  return d.squaredNorm() < b * b;
}

}  // namespace staa
