#include "local/dynamic_obstacles.hpp"

#include "geometry/convex.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace staa {
namespace {

Box boxOf(const Vec2* v, std::size_t n) {
  Box b{v[0], v[0]};
  for (std::size_t i = 1; i < n; ++i) {
    b.min = b.min.cwiseMin(v[i]);
    b.max = b.max.cwiseMax(v[i]);
  }
  return b;
}

// Reduces a counter-clockwise convex polygon to `target` (>= 4) vertices without losing any
// of it: each step removes the edge whose removal, by extending its two neighbouring edges to
// their intersection, adds the least area. Returns the new vertex count. When no edge can be
// removed (rounding), falls back to the bounding box.
std::size_t simplifyConvex(Vec2* v, std::size_t n, std::size_t target) {
  while (n > target) {
    std::size_t best = n;
    double best_area = 0.0;
    Vec2 best_point{0.0, 0.0};
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2& p0 = v[(i + n - 1) % n];
      const Vec2& a = v[i];
      const Vec2& b = v[(i + 1) % n];
      const Vec2& p3 = v[(i + 2) % n];
      const Vec2 e_prev = a - p0, e_next = p3 - b;
      const double turn = cross(e_prev, e_next);
      if (turn <= 0.0) continue;  // the neighbours' lines do not meet beyond the edge
      const double s = cross(b - a, e_next) / turn;
      if (!(s >= 0.0)) continue;
      const Vec2 x = a + s * e_prev;
      const double area = 0.5 * std::abs(cross(x - a, b - a));
      if (best == n || area < best_area) {
        best = i;
        best_area = area;
        best_point = x;
      }
    }
    if (best == n) {
      const Box bb = boxOf(v, n);
      v[0] = bb.min;
      v[1] = {bb.max.x(), bb.min.y()};
      v[2] = bb.max;
      v[3] = {bb.min.x(), bb.max.y()};
      return 4;
    }
    // v[best] becomes the intersection point, v[best + 1] goes.
    v[best] = best_point;
    const std::size_t gone = (best + 1) % n;
    for (std::size_t i = gone; i + 1 < n; ++i) v[i] = v[i + 1];
    --n;
  }
  return n;
}

}  // namespace

DynamicObstacleSet::DynamicObstacleSet(std::size_t max_obstacles)
    : obstacles_(max_obstacles),
      velocities_(max_obstacles, Vec2::Zero()),
      turn_rates_(max_obstacles, 0.0),
      hull_scratch_(kHullScratch),
      hull_out_(kHullScratch + 1) {}

void DynamicObstacleSet::clear() {
  count_ = 0;
  dropped_ = 0;
}

void DynamicObstacleSet::set(std::span<const PolygonView> polygons, std::span<const Vec2> velocities,
                             std::span<const double> turn_rates) {
  clear();
  for (std::size_t k = 0; k < polygons.size(); ++k) {
    if (count_ == obstacles_.size()) {
      dropped_ = polygons.size() - k;
      break;
    }
    hullInto(polygons[k], obstacles_[count_]);
    velocities_[count_] = k < velocities.size() ? velocities[k] : Vec2::Zero();
    const double w = k < turn_rates.size() ? turn_rates[k] : 0.0;
    turn_rates_[count_] = std::isfinite(w) ? w : 0.0;
    ++count_;
  }
}

// Hull(A u B) = Hull(Hull(A) u B): the polygon is hulled in chunks that fit the scratch, the
// running hull kept at most kMaxHullVertices so every chunk adds new points.
void DynamicObstacleSet::hullInto(PolygonView polygon, FixedPolygon& out) {
  std::size_t h = 0;     // running hull in hull_out_[0, h)
  std::size_t next = 0;  // next input vertex
  while (next < polygon.size()) {
    std::copy_n(hull_out_.begin(), h, hull_scratch_.begin());
    std::size_t m = h;
    for (; next < polygon.size() && m < kHullScratch; ++next) {
      const Vec2& p = polygon[next];
      if (std::isfinite(p.x()) && std::isfinite(p.y())) hull_scratch_[m++] = p;
    }
    if (m == h) break;  // nothing new (only non-finite points left)
    h = convexHullInPlace(std::span<Vec2>(hull_scratch_.data(), m), std::span<Vec2>(hull_out_.data(), m + 1));
    if (h > kMaxHullVertices) h = simplifyConvex(hull_out_.data(), h, kMaxHullVertices);
  }
  out.n = h;
  std::copy_n(hull_out_.begin(), h, out.v.begin());
  out.box = h > 0 ? boxOf(out.v.data(), h) : Box{};
}

void DynamicObstacleSet::copyFrom(const DynamicObstacleSet& other) {
  const std::size_t n = std::min(other.count_, obstacles_.size());
  for (std::size_t k = 0; k < n; ++k) {
    obstacles_[k] = other.obstacles_[k];
    velocities_[k] = other.velocities_[k];
    turn_rates_[k] = other.turn_rates_[k];
  }
  count_ = n;
  dropped_ = other.dropped_ + (other.count_ - n);
}

void DynamicObstacleSet::copyExcept(const DynamicObstacleSet& other, std::span<const std::uint8_t> drop) {
  std::size_t n = 0, skipped = 0;
  for (std::size_t k = 0; k < other.count_; ++k) {
    if (k < drop.size() && drop[k] != 0) {
      ++skipped;
      continue;
    }
    if (n == obstacles_.size()) break;
    obstacles_[n] = other.obstacles_[k];
    velocities_[n] = other.velocities_[k];
    turn_rates_[n] = other.turn_rates_[k];
    ++n;
  }
  count_ = n;
  dropped_ = other.dropped_ + (other.count_ - skipped - n);
}

void DynamicObstacleSet::predict(std::size_t k, double t, FixedPolygon& out) const {
  const FixedPolygon& o = obstacles_[k];
  const Vec2 shift = displacement(k, t);
  out.n = o.n;
  for (std::size_t i = 0; i < o.n; ++i) out.v[i] = o.v[i] + shift;
  out.box = o.n > 0 ? Box{o.box.min + shift, o.box.max + shift} : Box{};
}

void DynamicObstacleSet::predictTurning(std::size_t k, double t, FixedPolygon& out) const {
  const FixedPolygon& o = obstacles_[k];
  const Vec2 v = velocities_[k];
  const double speed = v.norm();
  const double w = turn_rates_[k];
  if (o.n == 0 || !(speed > 1e-9) || !(std::abs(w) > 1e-9)) {
    predict(k, t, out);
    return;
  }
  // The distance travelled along the path (constant speed, or the braking hypothesis) and the
  // angle the velocity has turned by then.
  const double d = displacement(k, t).norm();
  const double phi = w * d / speed;
  // The chord of the arc: length 2 (d / phi) sin(phi / 2), along the velocity turned by phi / 2.
  const double half = 0.5 * phi;
  const double chord = std::abs(phi) > 1e-9 ? 2.0 * (d / phi) * std::sin(half) : d;
  const Vec2 u = v / speed;
  const double ch = std::cos(half), sh = std::sin(half);
  const Vec2 shift = chord * Vec2{ch * u.x() - sh * u.y(), sh * u.x() + ch * u.y()};
  const Vec2 c = 0.5 * (o.box.min + o.box.max);
  const double cp = std::cos(phi), sp = std::sin(phi);
  out.n = o.n;
  Box box{Vec2::Constant(std::numeric_limits<double>::infinity()), Vec2::Constant(-std::numeric_limits<double>::infinity())};
  for (std::size_t i = 0; i < o.n; ++i) {
    const Vec2 r = o.v[i] - c;
    const Vec2 p = c + shift + Vec2{cp * r.x() - sp * r.y(), sp * r.x() + cp * r.y()};
    out.v[i] = p;
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  out.box = box;
}

void DynamicObstacleSet::predictInflated(std::size_t k, double t, double radius, int arc_steps,
                                         FixedPolygon& out) const {
  const FixedPolygon& o = obstacles_[k];
  const std::size_t n = o.n;
  if (n == 0 || !(radius > 0.0)) {
    predict(k, t, out);
    return;
  }
  const Vec2 shift = displacement(k, t);
  constexpr double kQuarter = 0.5 * kPi;

  // Per corner: the outward normal angle of the incoming edge and the turning angle (the
  // exterior angle, what the round corner's arc spans). They sum to 2 pi.
  std::array<double, FixedPolygon::kCapacity> start{}, turn{};
  std::array<int, FixedPolygon::kCapacity> steps{};
  const auto outwardNormal = [](const Vec2& e) { return Vec2{e.y(), -e.x()}; };  // CCW polygon
  int base_sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (n == 1) {
      start[i] = 0.0;
      turn[i] = 2.0 * kPi;
    } else {
      const Vec2 n_in = outwardNormal(o.v[i] - o.v[(i + n - 1) % n]);
      const Vec2 n_out = outwardNormal(o.v[(i + 1) % n] - o.v[i]);
      start[i] = std::atan2(n_in.y(), n_in.x());
      double phi = std::atan2(cross(n_in, n_out), n_in.dot(n_out));
      if (phi <= 0.0) phi += 2.0 * kPi;  // a segment's ends turn by pi (atan2 may say -pi)
      turn[i] = phi;
    }
    // No chord may span more than 90 degrees (its vertex would lie > sqrt(2) r out).
    steps[i] = std::max(1, static_cast<int>(std::ceil(turn[i] / kQuarter - 1e-9)));
    base_sum += steps[i];
  }
  // The budget: n * arc_steps, and at least 4 * arc_steps for the whole turn (so a point's
  // circle or a segment's ends are as fine as a box's corners), within the capacity;
  // base_sum <= n + 4 <= kCapacity always. The extra steps go one at a time to the corner
  // whose chords currently span the widest angle.
  const int capacity = static_cast<int>(FixedPolygon::kCapacity);
  const int per_corner = std::max(arc_steps, 1);
  const int total = std::clamp(std::max(static_cast<int>(n), 4) * per_corner, base_sum, capacity);
  for (int extra = total - base_sum; extra > 0; --extra) {
    std::size_t widest = 0;
    for (std::size_t i = 1; i < n; ++i) {
      if (turn[i] * steps[widest] > turn[widest] * steps[i]) widest = i;
    }
    ++steps[widest];
  }
  std::size_t m = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const int s = steps[i];
    const double delta = turn[i] / s;
    // Vertices where the tangents at start + j delta and start + (j + 1) delta meet: the
    // chords are tangent to the circle, so the polygon contains the exact round corner.
    const double reach = radius / std::cos(0.5 * delta);
    const Vec2 c = o.v[i] + shift;
    // Direction start + (j + 0.5) delta, stepped by a rotation (two sin/cos per corner).
    Vec2 dir{std::cos(start[i] + 0.5 * delta), std::sin(start[i] + 0.5 * delta)};
    const double cd = std::cos(delta), sd = std::sin(delta);
    for (int j = 0; j < s && m < FixedPolygon::kCapacity; ++j) {
      out.v[m++] = c + reach * dir;
      dir = Vec2{cd * dir.x() - sd * dir.y(), sd * dir.x() + cd * dir.y()};
    }
  }
  out.n = m;
  out.box = boxOf(out.v.data(), m);
}

}  // namespace staa
