#include "planner/collision.hpp"

#include "geometry/clip.hpp"
#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "planner/distance_field.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace staa {

namespace {
constexpr float kFar = 1e9f;
}  // namespace

CollisionChecker::CollisionChecker(const RobotProfile& robot, const LocalMapConfig& local, double dynamic_clearance_m)
    : footprint_(robot.footprint), cell_(local.cell_m) {
  const double cell_m = local.cell_m;
  // The distance field covers the local grid: sized here, once.
  distance_.assign(LocalMap::gridSize(local).cells(), 0.0f);
  if (!isCounterClockwise(footprint_)) std::reverse(footprint_.begin(), footprint_.end());
  if (footprint_.size() > placed_.size()) {
    throw std::invalid_argument("robot footprint has " + std::to_string(footprint_.size()) + " vertices; at most " +
                                std::to_string(placed_.size()) + " are supported");
  }
  convex_ = isConvex(footprint_);
  circumradius_ = robot.circumradius();
  sample_step_ = 0.9 * cell_m;
  // The mitred offset of each vertex: along the sum of its edges' outward normals, scaled so
  // that both edges move out by the margin (the result contains the round offset).
  dynamic_margin_ = sample_step_ + std::max(0.0, dynamic_clearance_m);
  const std::size_t fn = footprint_.size();
  footprint_dynamic_.resize(fn);
  footprint_exact_.resize(fn);
  for (std::size_t i = 0; i < fn; ++i) {
    const Vec2& prev = footprint_[(i + fn - 1) % fn];
    const Vec2& cur = footprint_[i];
    const Vec2& next = footprint_[(i + 1) % fn];
    const Vec2 e1 = (cur - prev).normalized(), e2 = (next - cur).normalized();
    const Vec2 n1{e1.y(), -e1.x()}, n2{e2.y(), -e2.x()};  // outward for counter-clockwise
    const double denom = std::max(1.0 + n1.dot(n2), 0.25);  // caps the mitre of sharp corners
    footprint_dynamic_[i] = cur + dynamic_margin_ * (n1 + n2) / denom;
    footprint_exact_[i] = cur + kExactMargin * (n1 + n2) / denom;
  }

  // Outline points: every vertex plus points along each edge, no two more than a sample
  // step apart.
  const std::size_t n = footprint_.size();
  for (std::size_t i = 0; i < n && outline_count_ < kMaxOutline; ++i) {
    const Vec2& a = footprint_[i];
    const Vec2& b = footprint_[(i + 1) % n];
    const int pieces = std::max(1, static_cast<int>(std::ceil((b - a).norm() / sample_step_)));
    for (int k = 0; k < pieces && outline_count_ < kMaxOutline; ++k) {
      outline_[outline_count_++] = a + (b - a) * (static_cast<double>(k) / pieces);
    }
  }
  double area = 0.0;
  Vec2 c{0.0, 0.0};
  for (std::size_t i = 0; i < n; ++i) {
    const double cr = cross(footprint_[i], footprint_[(i + 1) % n]);
    area += cr;
    c += (footprint_[i] + footprint_[(i + 1) % n]) * cr;
  }
  centroid_ = std::abs(area) > 0.0 ? Vec2(c / (3.0 * area)) : footprint_[0];

  // Covering circles along the footprint's longer axis of its bounding box: each covers its
  // slab of the box, so together they cover the footprint (a conservative first test).
  const Box b = boundingBox(footprint_);
  const bool along_x = b.width() >= b.height();
  const double len = along_x ? b.width() : b.height();
  const double wid = along_x ? b.height() : b.width();
  const std::size_t k = std::clamp<std::size_t>(static_cast<std::size_t>(std::ceil(1.5 * len / std::max(wid, 1e-3))), 1, kMaxCircles);
  const double slab = len / static_cast<double>(k);
  for (std::size_t i = 0; i < k; ++i) {
    const double along = (along_x ? b.min.x() : b.min.y()) + (static_cast<double>(i) + 0.5) * slab;
    const double across = along_x ? 0.5 * (b.min.y() + b.max.y()) : 0.5 * (b.min.x() + b.max.x());
    circle_centers_[i] = along_x ? Vec2(along, across) : Vec2(across, along);
    circle_radii_[i] = std::hypot(0.5 * slab, 0.5 * wid);
  }
  circle_count_ = k;

  // Sort the outline points by the circle that covers them, so that a pose whose circles are
  // partly clear only checks the points of the others.
  std::array<Vec2, kMaxOutline> sorted{};
  std::size_t m = 0;
  for (std::size_t c = 0; c < circle_count_; ++c) {
    outline_begin_[c] = m;
    for (std::size_t q = 0; q < outline_count_; ++q) {
      std::size_t nearest = 0;
      for (std::size_t c2 = 1; c2 < circle_count_; ++c2) {
        if ((outline_[q] - circle_centers_[c2]).squaredNorm() < (outline_[q] - circle_centers_[nearest]).squaredNorm()) nearest = c2;
      }
      if (nearest == c) sorted[m++] = outline_[q];
    }
  }
  outline_begin_[circle_count_] = m;
  outline_ = sorted;
  // The distance from each outline point to the next one of its circle's group (robot frame;
  // a pose moves them rigidly): how far a clearance found at one point reaches along the group.
  for (std::size_t c = 0; c < circle_count_; ++c) {
    for (std::size_t q = outline_begin_[c]; q + 1 < outline_begin_[c + 1]; ++q) {
      outline_gap_[q] = (outline_[q + 1] - outline_[q]).norm();
    }
  }
  // Each circle must cover its points (it covers its slab of the bounding box; the nearest
  // centre of points on the box is that slab's): grow it if rounding says otherwise.
  for (std::size_t c = 0; c < circle_count_; ++c) {
    for (std::size_t q = outline_begin_[c]; q < outline_begin_[c + 1]; ++q) {
      circle_radii_[c] = std::max(circle_radii_[c], (outline_[q] - circle_centers_[c]).norm());
    }
  }
}

void CollisionChecker::prepare(const LocalMap& map) {
  map_ = &map;
  // World -> grid cells: into the box's frame (origin at the robot, x ahead), shift so that
  // the rear-right corner is (0, 0), divide by the cell size. Rounded as it always was here,
  // not as LocalMap::frame() rounds: the two differ in the last bits, and unifying them
  // changes expansion-budget runs (a change of its own, not of the re-layering).
  const Pose2& o = map.origin();
  const double c = std::cos(o.theta), sn = std::sin(o.theta), inv = 1.0 / map.config().cell_m;
  frame_.xx = c * inv;
  frame_.xy = sn * inv;
  frame_.x0 = (-c * o.x - sn * o.y + map.config().behind_m) * inv;
  frame_.yx = -sn * inv;
  frame_.yy = c * inv;
  frame_.y0 = (sn * o.x - c * o.y + map.config().side_m) * inv;
  grid_ = map.grid().data();
  exact_ = map.exactStatic() ? map.realObstacles() : nullptr;
  grid_w_ = map.width();
  grid_h_ = map.height();
  if (distance_.size() != map.grid().size()) {
    // A local map of another config than this checker's (not in a cycle set up from one
    // config): resize, which allocates, rather than write past the field.
    distance_.resize(map.grid().size());
  }
  conservativeDistanceField(map.grid(), map.width(), map.height(), cell_, distance_);
}

bool CollisionChecker::poseFreeStatic(const Pose2& pose) const {
  return fastPoseFreeStatic(FastPose{pose.x, pose.y, std::cos(pose.theta), std::sin(pose.theta)});
}

bool CollisionChecker::fastPoseFreeStatic(const FastPose& p, double* slack) const {
  // Robot frame -> grid: the pose's rotation and translation composed with the grid's map.
  const GridFrame& f = frame_;
  const double ax = f.xx * p.c + f.xy * p.s, ay = -f.xx * p.s + f.xy * p.c;  // robot x, y axes in grid x
  const double bx = f.yx * p.c + f.yy * p.s, by = -f.yx * p.s + f.yy * p.c;  // ... in grid y
  const double ox = gridX(p.x, p.y), oy = gridY(p.x, p.y);
  double margin = kFar;
  bool clear_all = true;
  std::array<bool, kMaxCircles> clear{};
  for (std::size_t k = 0; k < circle_count_; ++k) {
    const Vec2& q = circle_centers_[k];
    const std::ptrdiff_t cell = cellIndex(ox + ax * q.x() + ay * q.y(), oy + bx * q.x() + by * q.y());
    // Outside the box the grid knows nothing: free (and no slack is claimed there).
    if (cell < 0) {
      clear[k] = true;
      margin = 0.0;
      continue;
    }
    const double m = distance_[static_cast<std::size_t>(cell)] - circle_radii_[k];
    clear[k] = m >= 0.0;
    clear_all = clear_all && clear[k];
    margin = std::min(margin, m);
  }
  if (slack != nullptr) *slack = clear_all ? margin : 0.0;
  if (clear_all) return true;
  auto occupiedAt = [&](const Vec2& q) {
    const std::ptrdiff_t cell = cellIndex(ox + ax * q.x() + ay * q.y(), oy + bx * q.x() + by * q.y());
    return cell >= 0 && grid_[cell] != 0;
  };
  if (occupiedAt(centroid_)) return exactPoseFree(p);
  // Only the outline points of the circles that are not clear (a clear circle holds no
  // occupied cell, so neither do its points). A looked-up point's distance field value clears
  // the points after it within that distance (the field is 1-Lipschitz and conservative).
  for (std::size_t c = 0; c < circle_count_; ++c) {
    if (clear[c]) continue;
    double covered = -1.0;  // distance still cleared by the last looked-up point
    for (std::size_t k = outline_begin_[c]; k < outline_begin_[c + 1]; ++k) {
      if (k > outline_begin_[c]) covered -= outline_gap_[k - 1];
      if (covered >= 0.0) continue;
      const Vec2& q = outline_[k];
      const std::ptrdiff_t cell = cellIndex(ox + ax * q.x() + ay * q.y(), oy + bx * q.x() + by * q.y());
      covered = -1.0;  // outside the grid: free, but no clearance is claimed
      if (cell >= 0) {
        if (grid_[cell] != 0) return exactPoseFree(p);
        covered = distance_[static_cast<std::size_t>(cell)];
      }
    }
  }
  return true;
}

bool CollisionChecker::exactPoseFree(const FastPose& p) const {
  if (exact_ == nullptr) return false;
  // The grown footprint at the pose overlaps an obstacle's interior when one of its vertices
  // or edges enters one, or when an obstacle lies wholly inside it (one of its vertices does).
  const std::size_t n = footprint_exact_.size();
  Box box{{p.x, p.y}, {p.x, p.y}};
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& q = footprint_exact_[i];
    exact_placed_[i] = Vec2{p.x + p.c * q.x() - p.s * q.y(), p.y + p.s * q.x() + p.c * q.y()};
    box.min = box.min.cwiseMin(exact_placed_[i]);
    box.max = box.max.cwiseMax(exact_placed_[i]);
    if (exact_->pointBlocked(exact_placed_[i])) return false;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (exact_->segmentBlocked(exact_placed_[i], exact_placed_[(i + 1) % n])) return false;
  }
  const PolygonView robot{exact_placed_.data(), n};
  return !exact_->forEachEdgeInBox(box, [&](std::size_t v) { return pointInPolygon(exact_->vertex(v), robot); });
}

bool CollisionChecker::segmentClear(const Vec2& a, const Vec2& b, double radius) const {
  const Vec2 d = b - a;
  const double len = d.norm();
  double t = 0.0;
  for (int step = 0; step < 24; ++step) {
    const Vec2 p = len > 0.0 ? Vec2(a + d * (t / len)) : a;
    const double gx = gridX(p.x(), p.y()), gy = gridY(p.x(), p.y());
    const std::ptrdiff_t cell = cellIndex(gx, gy);
    if (cell < 0) return false;
    // The grid knows nothing of obstacles beyond the box: its edges count as obstacles.
    const double to_edge = std::min(std::min(gx, grid_w_ - gx), std::min(gy, grid_h_ - gy)) * cell_;
    const double slack = std::min<double>(distance_[static_cast<std::size_t>(cell)], to_edge) - radius;
    // Close to something the exact test decides faster than tiny steps would.
    if (slack <= 2.0 * cell_ && t < len) return false;
    if (slack <= 0.0) return false;
    if (t >= len) return true;
    // Every point within `slack` of p is still clear (the field is 1-Lipschitz and conservative).
    t = std::min(len, t + slack);
  }
  return false;
}

int CollisionChecker::samplesFor(const ArcVelocities& vel, double dt) const {
  // No outline point may move more than a sample step between two samples: translation plus
  // rotation times the farthest point's radius bounds that motion.
  const double travel = std::abs(vel.v_mid) * dt + std::abs(vel.w_mid) * dt * circumradius_;
  return std::max(1, static_cast<int>(std::ceil(travel / sample_step_)));
}

bool CollisionChecker::motionFreeStatic(const UnicycleState& from, const ArcVelocities& vel, double dt) const {
  const double dth = vel.w_mid * dt;
  return motionFreeStatic(makeArcMotion(from, std::cos(from.theta), std::sin(from.theta), vel.v_mid, vel.w_mid, dt,
                                        std::cos(dth), std::sin(dth)));
}

bool CollisionChecker::motionFreeStatic(const ArcMotion& m) const { return motionFreeStatic(m, 0.0, nullptr); }

bool CollisionChecker::motionFreeStatic(const ArcMotion& m, double start_slack, double* end_slack,
                                        double start_disc) const {
  // No point of the robot leaves the start pose's clearance, or the origin stays within the
  // start's disc clearance: the whole motion is free (every sample's lookups would say so
  // too; the field is 1-Lipschitz and conservative).
  const double travel = travelBound(m);
  const double origin_travel = std::abs(m.v_mid) * m.dt;
  if ((start_slack > 0.0 && travel <= start_slack) || (start_disc > 0.0 && origin_travel <= start_disc)) {
    if (end_slack != nullptr) *end_slack = -1.0;
    return true;
  }
  // Check the end pose first: most collisions show there, and it is the one the paper checks.
  double end_margin = 0.0;
  const bool end_free = fastPoseFreeStatic(FastPose{m.x1, m.y1, m.c1, m.s1}, &end_margin);
  if (end_slack != nullptr) *end_slack = end_margin;
  if (!end_free) return false;
  const ArcVelocities vel{0.0, 0.0, m.v_mid, m.w_mid};
  const int n = samplesFor(vel, m.dt);
  if (n <= 1) return true;
  // The samples in between, stepping the heading by a fixed rotation. A checked pose's
  // clearance margin lets the following samples within that much travel go unchecked: no
  // point of the robot moves farther than the travel bound per sample. The start's margin
  // covers the first samples, the end's the last ones.
  const double per_sample = travel / n;
  const double origin_per_sample = origin_travel / n;
  if (start_slack + end_margin >= travel) return true;
  const double step = m.w_mid * m.dt / n;
  double cs, ss;
  sinCos(step, cs, ss);
  const bool straight = std::abs(m.w_mid * m.dt) < 1e-6;
  const double r = straight ? 0.0 : m.v_mid / m.w_mid;
  double c = m.c0, sn = m.s0;
  double covered = start_slack > 0.0 ? start_slack : -1.0;  // travel still covered by the last checked pose's margin
  for (int k = 1; k < n; ++k) {
    const double nc = c * cs - sn * ss;
    sn = sn * cs + c * ss;
    c = nc;
    covered -= per_sample;
    if (covered >= 0.0) continue;
    if (start_disc > 0.0 && origin_per_sample * k <= start_disc) continue;
    // The rest lies within the end pose's margin.
    if (static_cast<double>(n - k) * per_sample <= end_margin) return true;
    FastPose p{0.0, 0.0, c, sn};
    if (straight) {
      const double d = m.v_mid * m.dt * k / n;
      p.x = m.x0 + d * m.c0;
      p.y = m.y0 + d * m.s0;
    } else {
      p.x = m.x0 + r * (sn - m.s0);
      p.y = m.y0 - r * (c - m.c0);
    }
    double margin = 0.0;
    if (!fastPoseFreeStatic(p, &margin)) return false;
    covered = margin;
  }
  return true;
}

bool CollisionChecker::obstacleHits(std::size_t k, const Pose2& pose, const DynamicObstacleSet& obstacles, double t,
                                    double heading_spread, bool turning, bool& placed) const {
  const Vec2 p = pose.position();
  const FixedPolygon& o = obstacles.observed(k);
  const Vec2 shift = obstacles.displacement(k, t);
  const Vec2 center = 0.5 * (o.box.min + o.box.max) + shift;
  const double r = 0.5 * (o.box.max - o.box.min).norm();
  const double spread = heading_spread > 0.0 ? heading_spread * shift.norm() : 0.0;
  // The grown polygon's rounded corners lie within sqrt(2) * spread of the outline.
  const double reach = r + circumradius_ + 2.0 * dynamic_margin_ + 1.5 * spread;
  const auto overlaps = [&](const FixedPolygon& obstacle) {
    if (!placed) {
      transformPolygon(footprint_dynamic_, pose, placed_);
      placed = true;
    }
    const PolygonView robot{placed_.data(), footprint_dynamic_.size()};
    return convex_ ? convexIntersect(robot, obstacle.view()) : polygonsOverlap(robot, obstacle.view());
  };
  if ((center - p).squaredNorm() <= reach * reach) {
    if (spread > 0.0) {
      obstacles.predictInflated(k, t, spread, 1, scratch_);
    } else {
      obstacles.predict(k, t, scratch_);
    }
    if (overlaps(scratch_)) return true;
  }
  // On its circle the obstacle's centre stays within the distance it has travelled of where
  // it was seen (a chord is no longer than its arc): far ones are skipped unpredicted.
  const Vec2 seen_center = 0.5 * (o.box.min + o.box.max);
  const double circle_reach = shift.norm() + r + circumradius_ + 2.0 * dynamic_margin_;
  if (turning && obstacles.turnRate(k) != 0.0 && (seen_center - p).squaredNorm() <= circle_reach * circle_reach) {
    obstacles.predictTurning(k, t, scratch_);
    const Vec2 turned_center = 0.5 * (scratch_.box.min + scratch_.box.max);
    const double turned_reach = 0.5 * (scratch_.box.max - scratch_.box.min).norm() + circumradius_ + 2.0 * dynamic_margin_;
    if ((turned_center - p).squaredNorm() <= turned_reach * turned_reach && overlaps(scratch_)) return true;
  }
  return false;
}

bool CollisionChecker::poseFreeDynamic(const Pose2& pose, const DynamicObstacleSet& obstacles, double t,
                                       double heading_spread, bool turning) const {
  bool placed = false;
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    if (obstacleHits(k, pose, obstacles, t, heading_spread, turning, placed)) return false;
  }
  return true;
}

bool CollisionChecker::motionFreeDynamic(const UnicycleState& from, const ArcVelocities& vel, double dt,
                                         const DynamicObstacleSet& obstacles, double t0, double heading_spread,
                                         bool turning) const {
  if (obstacles.size() == 0) return true;
  const NearObstacles near =
      nearObstacles(from.position(), std::abs(vel.v_mid) * dt, obstacles, t0, dt, heading_spread, turning);
  return motionFreeDynamic(from, vel, dt, obstacles, t0, near, heading_spread, turning);
}

CollisionChecker::NearObstacles CollisionChecker::nearObstacles(const Vec2& p0, double travel,
                                                                const DynamicObstacleSet& obstacles, double t0,
                                                                double dt, double heading_spread, bool turning) const {
  // Obstacle k's displacement at time t lies within speed * dt / 2 of its displacement at the
  // middle of the interval (it grows by at most its speed), the robot's origin within `travel`
  // of p0 (a chord is no longer than its arc); 1 nm covers the rounding of the samples' own
  // arithmetic.
  constexpr double kRounding = 1e-9;
  NearObstacles near;
  const double tm = t0 + 0.5 * dt;
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    const FixedPolygon& o = obstacles.observed(k);
    // Enough samples that neither the robot nor the fastest obstacle point moves more than a
    // sample step between two of them (a turning obstacle's corners also sweep round).
    const double linear = obstacles.velocity(k).norm();
    double speed = linear;
    if (turning) speed += std::abs(obstacles.turnRate(k)) * 0.5 * (o.box.max - o.box.min).norm();
    near.fastest = std::max(near.fastest, speed);
    if (k >= kMaskedObstacles) continue;
    const Vec2 shift = obstacles.displacement(k, tm);
    const double drift = 0.5 * linear * dt;
    const double shift_max = shift.norm() + drift;
    const double base = 0.5 * (o.box.max - o.box.min).norm() + circumradius_ + 2.0 * dynamic_margin_;
    const Vec2 seen_center = 0.5 * (o.box.min + o.box.max);
    // obstacleHits' straight test, its reach at its largest over the interval.
    const double spread = heading_spread > 0.0 ? heading_spread * shift_max : 0.0;
    const double far = base + 1.5 * spread + drift + travel + kRounding;
    bool close = (seen_center + shift - p0).squaredNorm() <= far * far;
    // Its test on the circle, about where the obstacle was seen.
    if (!close && turning && obstacles.turnRate(k) != 0.0) {
      const double circle_far = shift_max + base + travel + kRounding;
      close = (seen_center - p0).squaredNorm() <= circle_far * circle_far;
    }
    if (close) near.mask |= std::uint64_t{1} << k;
  }
  return near;
}

bool CollisionChecker::motionFreeDynamic(const UnicycleState& from, const ArcVelocities& vel, double dt,
                                         const DynamicObstacleSet& obstacles, double t0, const NearObstacles& near,
                                         double heading_spread, bool turning) const {
  const std::size_t count = obstacles.size();
  if (count == 0 || (near.mask == 0 && count <= kMaskedObstacles)) return true;
  const int n = std::max(samplesFor(vel, dt), static_cast<int>(std::ceil(near.fastest * dt / sample_step_)));
  for (int k = n; k >= 1; --k) {
    const double t = dt * k / n;
    const Pose2 pose = poseAlongArc(from, vel.v_mid, vel.w_mid, t);
    bool placed = false;
    for (std::uint64_t m = near.mask; m != 0; m &= m - 1) {
      const auto i = static_cast<std::size_t>(std::countr_zero(m));
      if (obstacleHits(i, pose, obstacles, t0 + t, heading_spread, turning, placed)) return false;
    }
    for (std::size_t i = kMaskedObstacles; i < count; ++i) {
      if (obstacleHits(i, pose, obstacles, t0 + t, heading_spread, turning, placed)) return false;
    }
  }
  return true;
}

double CollisionChecker::distanceToDynamic(const Vec2& p, const DynamicObstacleSet& obstacles, double t,
                                           double beyond) const {
  double best = beyond;
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    const FixedPolygon& o = obstacles.observed(k);
    const Vec2 shift = obstacles.displacement(k, t);
    // Box distance first: an obstacle whose box is farther than the best so far cannot win.
    const Vec2 lo = o.box.min + shift, hi = o.box.max + shift;
    const double dx = std::max({lo.x() - p.x(), 0.0, p.x() - hi.x()});
    const double dy = std::max({lo.y() - p.y(), 0.0, p.y() - hi.y()});
    if (dx * dx + dy * dy >= best * best) continue;
    obstacles.predict(k, t, scratch_);
    best = std::min(best, distanceToEdges(p, scratch_.view()));
  }
  return best;
}

}  // namespace staa
