#include "world/sim_laser_scan.hpp"

#include "geometry/polygon.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace staa::hal {
namespace {

[[noreturn]] void badScan(const char* field, double value, const char* rule) {
  throw std::invalid_argument(std::string("sim laser scanner: config.") + field + " must be " + rule + ", got " +
                              std::to_string(value));
}

const SimScanConfig& validatedScan(const SimScanConfig& c) {
  const auto finite = [](double v) { return std::isfinite(v); };
  if (!finite(c.mount.x) || !finite(c.mount.y) || !finite(c.mount.yaw)) badScan("mount", c.mount.x, "finite");
  if (!(c.mount.z > 0.0) || !finite(c.mount.z)) badScan("mount.z", c.mount.z, "finite and > 0 (m)");
  if (c.beams < 2 || c.beams > static_cast<int>(LaserScan::kMaxBeams)) {
    badScan("beams", c.beams, "in 2..2048");
  }
  if (!(c.angle_min >= -kPi && c.angle_max <= kPi && c.angle_max > c.angle_min)) {
    badScan("angle_max", c.angle_max, "> angle_min, both within [-pi, pi] (rad)");
  }
  if (!(c.range_min >= 0.0) || !finite(c.range_min)) badScan("range_min", c.range_min, "finite and >= 0 (m)");
  if (!(c.range_max > c.range_min) || !finite(c.range_max)) badScan("range_max", c.range_max, "finite and > range_min (m)");
  if (!(c.noise_m >= 0.0) || !finite(c.noise_m)) badScan("noise_m", c.noise_m, "finite and >= 0 (m)");
  if (!(c.dropout >= 0.0 && c.dropout < 1.0)) badScan("dropout", c.dropout, "in [0, 1) (a fraction of the beams)");
  return c;
}

}  // namespace

ScanRenderer::ScanRenderer(const PolygonMap& map, const SimScanConfig& config)
    : config_(validatedScan(config)),
      increment_((config.angle_max - config.angle_min) / (config.beams - 1)),
      static_(map),
      range_(static_cast<std::size_t>(config.beams), 0.0),
      local_(static_cast<std::size_t>(config.beams), Vec2::Zero()),
      direction_(static_cast<std::size_t>(config.beams), Vec2::Zero()),
      rng_(config.seed) {
  for (std::size_t i = 0; i < local_.size(); ++i) {
    const double bearing = config_.mount.yaw + config_.angle_min + increment_ * static_cast<double>(i);
    local_[i] = Vec2(std::cos(bearing), std::sin(bearing));
  }
}

void ScanRenderer::castEdge(const Vec2& a_map, const Vec2& b_map, const Vec2& sensor, double zero_bearing) {
  Vec2 a = a_map - sensor, b = b_map - sensor;
  const Vec2 e0 = b - a;
  // The sensor on the segment's line sees it edge-on: no return from it.
  if (std::abs(a.x() * b.y() - a.y() * b.x()) <= 1e-12 * (a.norm() + b.norm()) * e0.norm()) return;
  if (a.x() * b.y() - a.y() * b.x() < 0.0) std::swap(a, b);  // a to b counter-clockwise
  const Vec2 e = b - a;
  // Bearings from beam 0, in [0, 2 pi): the segment covers [from, from + span], span < pi.
  const double two_pi = 2.0 * kPi;
  const double bearing_a = std::atan2(a.y(), a.x());
  double from = bearing_a - zero_bearing;
  from -= two_pi * std::floor(from / two_pi);
  double span = std::atan2(b.y(), b.x()) - bearing_a;
  span -= two_pi * std::floor(span / two_pi);
  const int n = config_.beams;
  const double cross_ae = a.x() * e.y() - a.y() * e.x();
  // Two windows: the bearings as they are, and one turn lower (a segment across beam 0's
  // direction behind the scanner's gap wraps).
  for (const double shift : {0.0, -two_pi}) {
    const double lo = from + shift, hi = from + span + shift;
    const int i0 = std::max(0, static_cast<int>(std::ceil(lo / increment_ - 1e-9)));
    const int i1 = std::min(n - 1, static_cast<int>(std::floor(hi / increment_ + 1e-9)));
    for (int i = i0; i <= i1; ++i) {
      const double dx = direction_[static_cast<std::size_t>(i)].x(), dy = direction_[static_cast<std::size_t>(i)].y();
      // The ray t * d meets a + u e where t = (a x e) / (d x e).
      const double denom = dx * e.y() - dy * e.x();
      if (denom <= 0.0) continue;
      const double t = cross_ae / denom;
      if (t > 0.0 && t < range_[static_cast<std::size_t>(i)]) range_[static_cast<std::size_t>(i)] = t;
    }
  }
}

void ScanRenderer::render(const Pose2& robot, std::span<const PrismView> movers, LaserScan& out) {
  const Vec2 sensor = robot.transform(Vec2(config_.mount.x, config_.mount.y));
  const double zero_bearing = robot.theta + config_.mount.yaw + config_.angle_min;
  const double none = config_.range_max + 1.0;
  std::fill(range_.begin(), range_.end(), none);
  const double c = std::cos(robot.theta), s = std::sin(robot.theta);
  for (std::size_t i = 0; i < local_.size(); ++i) {
    direction_[i] = Vec2(c * local_[i].x() - s * local_[i].y(), s * local_[i].x() + c * local_[i].y());
  }
  const double reach = config_.range_max;
  for (const StaticPrisms::Entry& sp : static_.entries) {
    const double dx = std::max({sp.box.min.x() - sensor.x(), 0.0, sensor.x() - sp.box.max.x()});
    const double dy = std::max({sp.box.min.y() - sensor.y(), 0.0, sensor.y() - sp.box.max.y()});
    if (sp.solid && dx * dx + dy * dy > reach * reach) continue;
    const std::span<const Vec2> p = static_.pointsOf(sp);
    for (std::size_t k = 0; k < p.size(); ++k) castEdge(p[k], p[(k + 1) % p.size()], sensor, zero_bearing);
  }
  for (const PrismView& m : movers) {
    if (m.shape.size() < 3 || m.shape.size() > kMaxMoverVertices || !(m.height_m > config_.mount.z)) continue;
    for (std::size_t k = 0; k < m.shape.size(); ++k) {
      castEdge(m.shape[k] + m.position, m.shape[(k + 1) % m.shape.size()] + m.position, sensor, zero_bearing);
    }
  }
  out.angle_min = config_.angle_min;
  out.angle_increment = increment_;
  out.range_min = config_.range_min;
  out.range_max = config_.range_max;
  out.count = static_cast<std::size_t>(config_.beams);
  for (std::size_t i = 0; i < out.count; ++i) {
    double r = range_[i];
    // One draw per beam whatever happens to it, so one beam's fate does not shift the rest.
    const double noise = rng_.normal();
    const bool dropped = config_.dropout > 0.0 && rng_.uniform() < config_.dropout;
    if (r < none) r += config_.noise_m * noise;
    out.ranges[i] = (dropped || r < config_.range_min || r > config_.range_max) ? 0.0F : static_cast<float>(r);
  }
}

}  // namespace staa::hal
