#include "perception/depth_obstacles.hpp"

#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "io/config_rules.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace staa {
namespace {

// Grids beyond this many cells a side are a configuration mistake (4 million cells).
constexpr int kMaxGridSide = 2000;
constexpr std::int32_t kNoRow = std::numeric_limits<std::int32_t>::max();

// The grid reaches max_range_m from the camera: at most this many cells of it, so that the
// grid (2 * (cells + 1) a side) stays within kMaxGridSide.
constexpr double kMaxRangeCells = kMaxGridSide / 2 - 2;

constexpr const char* kOwner = "depth obstacles";

void require(const char* field, double value, const io::Range& range) { io::requireField(kOwner, field, value, range); }

void requireCount(const char* field, long long value, long long lo, long long hi, const char* note = "") {
  if (value < lo || value > hi) throw io::FieldError(kOwner, field, io::integerRange(lo, hi) + note, static_cast<double>(value));
}

std::string number(double v) { return io::numberText(v); }

}  // namespace

// The constant-velocity Kalman filter of a track (the same gain for x and y): predict over
// dt with white acceleration noise, then update with the measured centroid.
void DepthObstacleDetector::filterCentroid(Track& tr, const Vec2& measured, double dt, double noise_m,
                                           const Vec2& blind) const {
  const double q = config_.acceleration_mps2 * config_.acceleration_mps2;
  const double dt2 = dt * dt;
  const double p00 = tr.p00 + 2.0 * dt * tr.p01 + dt2 * tr.p11 + q * dt2 * dt2 / 4.0;
  const double p01 = tr.p01 + dt * tr.p11 + q * dt2 * dt / 2.0;
  const double p11 = tr.p11 + q * dt2;
  const double innovation_var = p00 + noise_m * noise_m;
  const double k0 = p00 / innovation_var, k1 = p01 / innovation_var;
  const Vec2 innovation = measured - (tr.centroid + tr.velocity * dt);
  tr.centroid += tr.velocity * dt + k0 * innovation;
  // A centroid moved by a cut across the beam (`blind`, a unit vector or 0) says nothing of the
  // velocity that way.
  tr.velocity += k1 * (innovation - blind * blind.dot(innovation));
  tr.p00 = (1.0 - k0) * p00;
  tr.p01 = (1.0 - k0) * p01;
  tr.p11 = p11 - k1 * p01;
  const double speed = tr.velocity.norm();
  if (speed > config_.max_speed_mps) tr.velocity *= config_.max_speed_mps / speed;
}

// A body cut off on one side only (findCuts) has a free end, its silhouette on the scan, which
// moves with the body while the centroid moves with the cut. Across the beam the free end is
// placed to the beams' spacing, along it (on a face seen at a grazing angle) hardly at all.
DepthObstacleDetector::FreeEnd DepthObstacleDetector::freeEnd(const Cluster& cl) const {
  FreeEnd end;
  if (cl.truncated || cl.cut_lo == cl.cut_hi) return end;
  end.side = cl.cut_lo ? 1 : -1;
  end.point = end.side > 0 ? cl.edge_hi : cl.edge_lo;
  const Vec2 beam = end.point - scan_sensor_;
  if (!(beam.norm() > 0.0)) return FreeEnd{};
  end.across = Vec2(-beam.y(), beam.x()).normalized();
  return end;
}

// The free end's displacement across the beam since the previous frame measures the velocity
// across, with a return's noise at either end (taken as the centroid's). The filter's
// covariance is the same in every direction and this measures one, so it is left as it was:
// the track gets no surer of the direction the scan did not measure.
void DepthObstacleDetector::followFreeEnd(Track& tr, const FreeEnd& end, rt::Nanos stamp) const {
  if (end.side == 0) {
    tr.edge_side = 0;
    return;
  }
  const double dt = static_cast<double>(stamp - tr.edge_seen) * 1e-9;
  if (tr.edge_side == end.side && dt > 0.0 && dt <= config_.max_frame_gap_s) {
    const double noise = std::sqrt(2.0) * config_.centroid_noise_m / dt;
    const double innovation = end.across.dot(end.point - tr.edge) / dt - end.across.dot(tr.velocity);
    const double s = tr.p11 + noise * noise;
    tr.centroid += (tr.p01 / s * innovation) * end.across;
    tr.velocity += (tr.p11 / s * innovation) * end.across;
    const double speed = tr.velocity.norm();
    if (speed > config_.max_speed_mps) tr.velocity *= config_.max_speed_mps / speed;
  }
  tr.edge = end.point;
  tr.edge_side = end.side;
  tr.edge_seen = stamp;
}

// The turn rate: how far the filtered velocity's direction turned over dt, smoothed with a
// first-order filter of time constant turn_rate_time_s. A slow track's direction is mostly
// the centroid's noise: its turn rate is 0.
void DepthObstacleDetector::filterTurnRate(Track& tr, const Vec2& before, double dt) const {
  const double slow = config_.turn_min_speed_mps;
  if (!(dt > 0.0) || before.norm() < slow || tr.velocity.norm() < slow) {
    tr.turn_rate = 0.0;
    return;
  }
  const double measured = std::atan2(cross(before, tr.velocity), before.dot(tr.velocity)) / dt;
  tr.turn_rate += dt / (config_.turn_rate_time_s + dt) * (measured - tr.turn_rate);
  tr.turn_rate = std::clamp(tr.turn_rate, -config_.max_turn_rate_rps, config_.max_turn_rate_rps);
}

void validateDepthObstaclesConfig(const DepthObstaclesConfig& c, double camera_offset_m) {
  using io::Range;
  requireCount("pixel_stride", c.pixel_stride, 1, 16, " (every n-th pixel of every n-th row)");
  require("min_depth_m", c.min_depth_m, Range::atLeast(0.0, "m"));
  require("max_range_m", c.max_range_m, Range::above(0.0, "m"));
  require("min_height_m", c.min_height_m, Range{});
  if (!std::isfinite(c.max_height_m) || !(c.max_height_m > c.min_height_m)) {
    throw io::FieldError(kOwner, "max_height_m", "> min_height_m (" + number(c.min_height_m) + " m)", c.max_height_m);
  }
  require("scan_range_m", c.scan_range_m, Range::atLeast(0.0, "m"));
  require("cell_m", c.cell_m, Range::above(0.0, "m"));
  const double reach = std::max(c.max_range_m, c.scan_range_m) + camera_offset_m;
  if (reach / c.cell_m > kMaxRangeCells) {
    throw io::FieldError(kOwner, "cell_m",
                         "large enough for max_range_m " + number(c.max_range_m) + " m and scan_range_m " +
                             number(c.scan_range_m) + " m (+ the camera's " + number(camera_offset_m) +
                             " m offset): at most 998 cells of range",
                         c.cell_m);
  }
  requireCount("min_points_per_cell", c.min_points_per_cell, 1, 65535);  // a cell counts in 16 bits
  requireCount("min_cluster_points", c.min_cluster_points, 1, 1'000'000);
  if (!(c.cluster_gap_m >= c.cell_m && c.cluster_gap_m <= 5.0 * c.cell_m)) {
    throw io::FieldError(kOwner, "cluster_gap_m",
                         "in [cell_m, 5 * cell_m] = [" + number(c.cell_m) + ", " + number(5.0 * c.cell_m) + "] m", c.cluster_gap_m);
  }
  require("static_margin_m", c.static_margin_m, Range::atLeast(0.0, "m"));
  requireCount("max_vertices", static_cast<long long>(std::min<std::size_t>(c.max_vertices, 1u << 30)), 4,
               static_cast<long long>(hal::ObstacleFrame::kMaxVertices), " (ObstacleFrame::kMaxVertices)");
  require("gate_m", c.gate_m, Range::above(0.0, "m"));
  require("centroid_noise_m", c.centroid_noise_m, Range::above(0.0, "m"));
  require("truncated_noise_m", c.truncated_noise_m, Range::above(0.0, "m"));
  require("acceleration_mps2", c.acceleration_mps2, Range::above(0.0, "m/s^2"));
  require("max_speed_mps", c.max_speed_mps, Range::above(0.0, "m/s"));
  require("turn_rate_time_s", c.turn_rate_time_s, Range::above(0.0, "s"));
  require("turn_min_speed_mps", c.turn_min_speed_mps, Range::atLeast(0.0, "m/s"));
  require("max_turn_rate_rps", c.max_turn_rate_rps, Range::atLeast(0.0, "rad/s"));
  requireCount("max_missed_frames", c.max_missed_frames, 0, 1000);
  require("keep_unseen_s", c.keep_unseen_s, Range::closed(0.0, 60.0, "s"));
  requireCount("confirm_frames", c.confirm_frames, 1, 1000);
  require("max_growth_m", c.max_growth_m, Range::closed(0.0, 10.0, "m"));
  require("hidden_depth_m", c.hidden_depth_m, Range::closed(0.0, 5.0, "m"));
  require("self_clearance_m", c.self_clearance_m, Range::closed(0.0, 5.0, "m"));
  require("uncertainty_horizon_s", c.uncertainty_horizon_s, Range::closed(0.0, 10.0, "s"));
  require("max_frame_gap_s", c.max_frame_gap_s, Range::above(0.0, "s"));
}

namespace {
const DepthObstaclesConfig& validated(const DepthObstaclesConfig& c, const hal::CameraMount& mount) {
  validateDepthObstaclesConfig(c, cameraOffset(mount));
  return c;
}
}  // namespace

DepthObstacleDetector::DepthObstacleDetector(const PolygonMap& map, const hal::CameraIntrinsics& intrinsics,
                                             const hal::CameraMount& mount, const DepthObstaclesConfig& config)
    : config_(validated(config, mount)),
      camera_(intrinsics, mount),
      mask_(map, config.cell_m, config.static_margin_m) {
  const std::size_t sampled =
      static_cast<std::size_t>((hal::DepthFrame::kWidth / config_.pixel_stride + 1) *
                               (hal::DepthFrame::kHeight / config_.pixel_stride + 1));
  const std::size_t edge_rays = 2 * static_cast<std::size_t>(hal::DepthFrame::kHeight / config_.pixel_stride + 1);
  for (Rays* r : {&rays_, &frame_rays_}) {
    r->rays.reserve(sampled);
    r->edge.reserve(edge_rays);
  }
  edge_cells_.reserve(edge_rays + 4);  // and a scan's two ends, two beams each
  fillRays(camera_.rotation(), camera_.position(), rays_);
  // The grid reaches max_range_m from the camera wherever the camera sits on the robot
  // (within kMaxGridSide: validated above).
  const double reach = std::max(config_.max_range_m, config_.scan_range_m) + cameraOffset(mount);
  n_ = 2 * (static_cast<int>(std::ceil(reach / config_.cell_m)) + 1);
  link_ = static_cast<int>(std::floor(config_.cluster_gap_m / config_.cell_m + 1e-9));
  const auto cells = static_cast<std::size_t>(n_) * static_cast<std::size_t>(n_);
  count_.assign(cells, 0);
  edge_.assign(cells, 0);
  sum_x_.assign(cells, 0.0F);
  sum_y_.assign(cells, 0.0F);
  label_.assign(cells, -1);
  queue_.assign(cells, 0);
  row_min_.assign(static_cast<std::size_t>(n_), kNoRow);
  row_max_.assign(static_cast<std::size_t>(n_), -1);
  rows_.assign(static_cast<std::size_t>(n_), 0);
  corners_.assign(4 * static_cast<std::size_t>(n_), Vec2::Zero());
  hull_.assign(std::max<std::size_t>(4 * static_cast<std::size_t>(n_) + 1, 2 * hal::ObstacleFrame::kMaxVertices + 1),
               Vec2::Zero());
  extended_.assign(2 * hal::ObstacleFrame::kMaxVertices, Vec2::Zero());
}

// The sampled rays and, per ray, the depths whose points are in the band and in range.
void DepthObstacleDetector::fillRays(const Eigen::Matrix3d& rotation, const Vec3& c, Rays& out) const {
  out.rays.clear();
  out.edge.clear();
  const int s = config_.pixel_stride;
  for (int v = s / 2; v < hal::DepthFrame::kHeight; v += s) {
    for (int u = s / 2; u < hal::DepthFrame::kWidth; u += s) {
      const Vec3 r = CameraModel::ray(camera_.intrinsics(), rotation, u, v);
      double lo = config_.min_depth_m;
      double hi = 65.535;  // the largest depth a frame can hold
      const double horizontal = std::hypot(r.x(), r.y());
      if (horizontal > 0.0) hi = std::min(hi, config_.max_range_m / horizontal);
      if (r.z() > 0.0) {
        lo = std::max(lo, (config_.min_height_m - c.z()) / r.z());
        hi = std::min(hi, (config_.max_height_m - c.z()) / r.z());
      } else if (r.z() < 0.0) {
        lo = std::max(lo, (config_.max_height_m - c.z()) / r.z());
        hi = std::min(hi, (config_.min_height_m - c.z()) / r.z());
      } else if (c.z() < config_.min_height_m || c.z() > config_.max_height_m) {
        continue;
      }
      const double lo_mm = std::max(1.0, std::ceil(lo * 1000.0));
      const double hi_mm = std::min(65535.0, std::floor(hi * 1000.0));
      if (lo_mm > hi_mm) continue;  // this pixel never sees anything in the band
      if (u < s || u >= hal::DepthFrame::kWidth - s) out.edge.push_back(static_cast<std::uint32_t>(out.rays.size()));
      out.rays.push_back(Ray{static_cast<float>(r.x()), static_cast<float>(r.y()),
                             static_cast<std::uint32_t>(v * hal::DepthFrame::kWidth + u),
                             static_cast<std::uint16_t>(lo_mm), static_cast<std::uint16_t>(hi_mm)});
    }
  }
}

// A frame's own mount: its rays, rebuilt only when it moved since the last frame.
void DepthObstacleDetector::useFrameMount(const hal::CameraMount& m) {
  if (frame_rays_built_ && m.x == frame_mount_.x && m.y == frame_mount_.y && m.z == frame_mount_.z &&
      m.roll == frame_mount_.roll && m.pitch == frame_mount_.pitch && m.yaw == frame_mount_.yaw) {
    return;
  }
  frame_mount_ = m;
  frame_rays_built_ = true;
  frame_position_ = Vec3(m.x, m.y, m.z);
  const bool finite = std::isfinite(m.x) && std::isfinite(m.y) && std::isfinite(m.z) && std::isfinite(m.roll) &&
                      std::isfinite(m.pitch) && std::isfinite(m.yaw);
  if (!finite || !(m.z > 0.0)) {
    frame_rays_.rays.clear();
    frame_rays_.edge.clear();
    return;
  }
  fillRays(CameraModel::rotationOf(m), frame_position_, frame_rays_);
}

void DepthObstacleDetector::resetTracks() {
  for (Track& t : tracks_) t = Track{};
  last_stamp_ = -1;
}

DepthObstaclesStats DepthObstacleDetector::process(const hal::DepthFrame& frame, const Pose2& robot,
                                                   hal::ObstacleFrame& out) {
  return process(frame, robot, out, ScanInput{});
}

DepthObstaclesStats DepthObstacleDetector::process(const hal::DepthFrame& frame, const Pose2& robot,
                                                   hal::ObstacleFrame& out, const ScanInput& scan) {
  DepthObstaclesStats stats;
  out.stamp = frame.stamp;
  out.sequence = frame.sequence;
  out.count = 0;
  out.dropped = 0;
  if (frame.has_mount) {
    useFrameMount(frame.mount);
    frame_rotation_ = CameraModel::rotationOf(frame.mount);
    frame_camera_ = frame_position_;
    backProject(frame, frame_rays_, frame_position_, robot, stats);
  } else {
    frame_rotation_ = camera_.rotation();
    frame_camera_ = camera_.position();
    backProject(frame, rays_, camera_.position(), robot, stats);
  }
  robot_ = robot.position();
  scan_ = nullptr;
  if (scan.scan != nullptr) addScan(scan, stats);
  findClusters(robot, stats);
  findCuts();
  outlineClusters(out);
  trackClusters(frame.stamp, out);
  out.dropped = stats.clusters - kept_;
  keepUnseenTracks(frame, robot, out);
  for (const Track& t : tracks_) stats.tracks += t.live ? 1 : 0;
  scan_ = nullptr;
  return stats;
}

// Step 1b: the scan's returns into the same cells, each weighing min_points_per_cell points.
void DepthObstacleDetector::addScan(const ScanInput& in, DepthObstaclesStats& stats) {
  const hal::LaserScan& scan = *in.scan;
  // Cheap guards for a scan that skipped hal::scanProblem: nothing is read past its beams.
  if (scan.count < 1 || scan.count > hal::LaserScan::kMaxBeams || !std::isfinite(scan.angle_min) ||
      !std::isfinite(scan.angle_increment) || scan.angle_increment == 0.0 || !std::isfinite(scan.range_max) ||
      !(scan.range_min >= 0.0) || !std::isfinite(in.robot.x) || !std::isfinite(in.robot.y) ||
      !std::isfinite(in.robot.theta) || !std::isfinite(in.mount.x) || !std::isfinite(in.mount.y) ||
      !std::isfinite(in.mount.yaw)) {
    return;
  }
  scan_ = &scan;
  scan_sensor_ = in.robot.transform(Vec2(in.mount.x, in.mount.y));
  scan_zero_ = in.robot.theta + in.mount.yaw + scan.angle_min;
  const double inv_cell = 1.0 / config_.cell_m;
  const double ax = (scan_sensor_.x() - origin_.x()) * inv_cell, ay = (scan_sensor_.y() - origin_.y()) * inv_cell;
  const double n = n_;
  const auto weight = static_cast<std::uint16_t>(config_.min_points_per_cell);
  // The beams' directions by a rotation per beam (two products, no sin or cos per beam).
  const double ci = std::cos(scan.angle_increment), si = std::sin(scan.angle_increment);
  double dx = std::cos(scan_zero_) * inv_cell, dy = std::sin(scan_zero_) * inv_cell;
  const bool full_turn = std::abs(scan.angle_increment) * static_cast<double>(scan.count) >= 2.0 * kPi - 1e-6;
  std::size_t points = 0;
  for (std::size_t i = 0; i < scan.count; ++i) {
    const double r = scan.ranges[i];
    const double x = dx, y = dy;
    dx = ci * x - si * y;
    dy = si * x + ci * y;
    if (!(r >= scan.range_min && r <= scan.range_max)) continue;
    const double gx = ax + r * x, gy = ay + r * y;
    if (!(gx >= 0.0 && gx < n && gy >= 0.0 && gy < n)) continue;
    const std::size_t k = static_cast<std::size_t>(gy) * static_cast<std::size_t>(n_) + static_cast<std::size_t>(gx);
    if (count_[k] > std::numeric_limits<std::uint16_t>::max() - weight) continue;
    count_[k] = static_cast<std::uint16_t>(count_[k] + weight);
    sum_x_[k] += static_cast<float>(weight * gx);
    sum_y_[k] += static_cast<float>(weight * gy);
    ++points;
    // The sweep's two ends cut a body off as the image's sides do.
    if (!full_turn && (i < 2 || i + 2 >= scan.count) && edge_[k] == 0 && edge_cells_.size() < edge_cells_.capacity()) {
      edge_[k] = 1;
      edge_cells_.push_back(static_cast<std::uint32_t>(k));
    }
  }
  stats.scan_points = points;
  stats.points += points;
}

bool DepthObstacleDetector::scanSees(const Vec2& p) const {
  if (scan_ == nullptr) return false;
  constexpr double kRangeMargin = 0.3;  // m, as inView's
  constexpr double kEdgeBeams = 4.0;    // a place this near the sweep's ends may be seen or not
  const hal::LaserScan& scan = *scan_;
  const Vec2 d = p - scan_sensor_;
  const double distance = d.norm();
  // Written so that NaN (a place or scan far beyond any sense) is "not seen".
  if (!(distance >= scan.range_min + kRangeMargin &&
        distance <= std::min(scan.range_max, std::max(config_.max_range_m, config_.scan_range_m)) - kRangeMargin)) {
    return false;
  }
  // The bearing from beam 0, wrapped to the sweep's side of it.
  double bearing = std::atan2(d.y(), d.x()) - scan_zero_;
  bearing -= 2.0 * kPi * std::floor(bearing / (2.0 * kPi));  // [0, 2 pi)
  if (scan.angle_increment < 0.0 && bearing > 0.0) bearing -= 2.0 * kPi;
  const double beam = bearing / scan.angle_increment;
  if (!(beam >= kEdgeBeams && beam <= static_cast<double>(scan.count - 1) - kEdgeBeams)) return false;
  const double r = scan.ranges[static_cast<std::size_t>(std::lround(beam))];
  // A return nearer than the place by more than the gate: something in front hides it.
  return !(r >= scan.range_min && r <= scan.range_max && r < distance - config_.gate_m);
}

// Step 1: pixels -> points in the band -> counts (and point sums) per grid cell.
void DepthObstacleDetector::backProject(const hal::DepthFrame& frame, const Rays& rays, const Vec3& camera_position,
                                        const Pose2& robot, DepthObstaclesStats& stats) {
  const double cell = config_.cell_m;
  gi0_ = mask_.cellIndex(robot.x) - n_ / 2;
  gj0_ = mask_.cellIndex(robot.y) - n_ / 2;
  origin_ = Vec2(static_cast<double>(gi0_) * cell, static_cast<double>(gj0_) * cell);
  std::fill(count_.begin(), count_.end(), std::uint16_t{0});
  for (const std::uint32_t k : edge_cells_) edge_[k] = 0;
  edge_cells_.clear();
  std::fill(sum_x_.begin(), sum_x_.end(), 0.0F);
  std::fill(sum_y_.begin(), sum_y_.end(), 0.0F);

  // In grid units: the camera's position, and each ray's turn by the robot's heading.
  const double inv_cell = 1.0 / cell;
  const Vec2 camera = robot.transform(camera_position.head<2>());
  camera_map_ = camera;
  const double ax = (camera.x() - origin_.x()) * inv_cell, ay = (camera.y() - origin_.y()) * inv_cell;
  const double c = std::cos(robot.theta) * inv_cell * 0.001, s = std::sin(robot.theta) * inv_cell * 0.001;
  const double n = n_;
  std::size_t points = 0;
  // The cell of ray r's point, or -1 when its depth is outside its band or the grid.
  const auto cellOf = [&](const Ray& r) -> std::ptrdiff_t {
    const std::uint16_t d_mm = frame.depth_mm[r.pixel];
    if (d_mm < r.min_mm || d_mm > r.max_mm) return -1;
    const double d = d_mm;
    const double gx = ax + d * (c * r.x - s * r.y);
    const double gy = ay + d * (s * r.x + c * r.y);
    if (!(gx >= 0.0 && gx < n && gy >= 0.0 && gy < n)) return -1;
    return static_cast<std::ptrdiff_t>(static_cast<std::size_t>(gy) * static_cast<std::size_t>(n_) +
                                       static_cast<std::size_t>(gx));
  };
  for (const Ray& r : rays.rays) {
    const std::uint16_t d_mm = frame.depth_mm[r.pixel];
    if (d_mm < r.min_mm || d_mm > r.max_mm) continue;
    const double d = d_mm;
    const double gx = ax + d * (c * r.x - s * r.y);
    const double gy = ay + d * (s * r.x + c * r.y);
    if (!(gx >= 0.0 && gx < n && gy >= 0.0 && gy < n)) continue;
    const std::size_t k = static_cast<std::size_t>(gy) * static_cast<std::size_t>(n_) + static_cast<std::size_t>(gx);
    if (count_[k] == std::numeric_limits<std::uint16_t>::max()) continue;
    ++count_[k];
    sum_x_[k] += static_cast<float>(gx);
    sum_y_[k] += static_cast<float>(gy);
    ++points;
  }
  // The cells of the points from the image's side columns (a few hundred rays): a cluster
  // with one of them is cut off by the edge.
  for (const std::uint32_t i : rays.edge) {
    const std::ptrdiff_t k = cellOf(rays.rays[i]);
    if (k < 0 || edge_[static_cast<std::size_t>(k)] != 0) continue;
    edge_[static_cast<std::size_t>(k)] = 1;
    edge_cells_.push_back(static_cast<std::uint32_t>(k));
  }
  stats.points = points;
}

// Step 2: occupied cells the map does not explain, linked into clusters (cells at most
// link_ cells apart along x and y).
void DepthObstacleDetector::findClusters(const Pose2& robot, DepthObstaclesStats& stats) {
  const int n = n_;
  for (int gy = 0; gy < n; ++gy) {
    for (int gx = 0; gx < n; ++gx) {
      const std::size_t k = static_cast<std::size_t>(gy) * static_cast<std::size_t>(n) + static_cast<std::size_t>(gx);
      label_[k] = -1;
      if (count_[k] < config_.min_points_per_cell) continue;
      ++stats.occupied_cells;
      if (mask_.blocked(gi0_ + gx, gj0_ + gy)) {
        ++stats.map_cells;
        continue;
      }
      label_[k] = 0;
    }
  }

  cluster_count_ = 0;
  std::uint32_t tail = 0;
  std::int32_t next_label = 1;
  for (std::uint32_t seed = 0; seed < static_cast<std::uint32_t>(n * n); ++seed) {
    if (label_[seed] != 0) continue;
    const std::int32_t id = next_label++;
    const std::uint32_t first = tail;
    label_[seed] = id;
    queue_[tail++] = seed;
    std::uint64_t points = 0;
    double sx = 0.0, sy = 0.0;
    bool truncated = false;
    for (std::uint32_t head = first; head < tail; ++head) {
      const std::uint32_t k = queue_[head];
      points += count_[k];
      truncated = truncated || edge_[k] != 0;
      sx += sum_x_[k];
      sy += sum_y_[k];
      const int gx = static_cast<int>(k % static_cast<std::uint32_t>(n));
      const int gy = static_cast<int>(k / static_cast<std::uint32_t>(n));
      for (int dy = -link_; dy <= link_; ++dy) {
        for (int dx = -link_; dx <= link_; ++dx) {
          const int x = gx + dx, y = gy + dy;
          if ((dx == 0 && dy == 0) || x < 0 || y < 0 || x >= n || y >= n) continue;
          const auto m = static_cast<std::uint32_t>(y * n + x);
          if (label_[m] != 0) continue;
          label_[m] = id;
          queue_[tail++] = m;
        }
      }
    }
    if (points < static_cast<std::uint64_t>(config_.min_cluster_points)) continue;
    ++stats.clusters;
    if (cluster_count_ == kMaxClusters) continue;  // counted, not measured
    Cluster& cl = clusters_[cluster_count_++];
    cl.first = first;
    cl.last = tail;
    cl.points = static_cast<std::uint32_t>(std::min<std::uint64_t>(points, UINT32_MAX));
    const double inv = 1.0 / static_cast<double>(points);
    cl.centroid = origin_ + config_.cell_m * Vec2(sx * inv, sy * inv);
    cl.distance = (cl.centroid - robot.position()).norm();
    cl.track = -1;
    cl.truncated = truncated;
    cl.label = id;
  }

  // The nearest kMaxObstacles, nearest first (ties in scan order, so the result is the same
  // on every run).
  for (std::size_t i = 0; i < cluster_count_; ++i) order_[i] = static_cast<std::uint16_t>(i);
  const auto nearer = [this](std::uint16_t a, std::uint16_t b) {
    if (clusters_[a].distance != clusters_[b].distance) return clusters_[a].distance < clusters_[b].distance;
    return a < b;
  };
  kept_ = std::min(cluster_count_, hal::ObstacleFrame::kMaxObstacles);
  const auto begin = order_.begin();
  const auto end = order_.begin() + static_cast<std::ptrdiff_t>(cluster_count_);
  if (cluster_count_ > kept_) std::nth_element(begin, begin + static_cast<std::ptrdiff_t>(kept_), end, nearer);
  std::sort(begin, begin + static_cast<std::ptrdiff_t>(kept_), nearer);
}

// Step 2b: the scan's first and last beam on each cluster, and whether a nearer return just
// beyond either (by more than two cells: nearer than the grid can place the body's own edge)
// hides the rest of the body there. Beams without a return, or past the sweep's ends, hide
// nothing (the sweep's ends truncate, as the image's edges do).
void DepthObstacleDetector::findCuts() {
  for (std::size_t c = 0; c < cluster_count_; ++c) {
    Cluster& cl = clusters_[c];
    cl.beam_lo = cl.beam_hi = -1;
    cl.cut_lo = cl.cut_hi = false;
  }
  if (scan_ == nullptr || cluster_count_ == 0) return;
  const hal::LaserScan& scan = *scan_;
  const double inv_cell = 1.0 / config_.cell_m;
  const double ax = (scan_sensor_.x() - origin_.x()) * inv_cell, ay = (scan_sensor_.y() - origin_.y()) * inv_cell;
  const double n = n_;
  const double ci = std::cos(scan.angle_increment), si = std::sin(scan.angle_increment);
  double dx = std::cos(scan_zero_) * inv_cell, dy = std::sin(scan_zero_) * inv_cell;
  const auto valid = [&scan](double r) { return r >= scan.range_min && r <= scan.range_max; };
  Cluster* const first = clusters_.data();
  Cluster* const last = first + cluster_count_;
  for (std::size_t i = 0; i < scan.count; ++i) {
    const double r = scan.ranges[i];
    const double x = dx, y = dy;
    dx = ci * x - si * y;
    dy = si * x + ci * y;
    if (!valid(r)) continue;
    const double gx = ax + r * x, gy = ay + r * y;
    if (!(gx >= 0.0 && gx < n && gy >= 0.0 && gy < n)) continue;
    const std::int32_t id =
        label_[static_cast<std::size_t>(gy) * static_cast<std::size_t>(n_) + static_cast<std::size_t>(gx)];
    if (id <= 0) continue;
    // Clusters are numbered in the order they were found: a binary search by id.
    Cluster* const cl = std::lower_bound(first, last, id, [](const Cluster& c, std::int32_t v) { return c.label < v; });
    if (cl == last || cl->label != id) continue;  // too few points to be a cluster
    const Vec2 end = origin_ + config_.cell_m * Vec2(gx, gy);
    if (cl->beam_lo < 0) {
      cl->beam_lo = static_cast<int>(i);
      cl->edge_lo = end;
    }
    cl->beam_hi = static_cast<int>(i);
    cl->edge_hi = end;
  }
  const double margin = 2.0 * config_.cell_m;
  const auto count = static_cast<int>(scan.count);
  const auto hidden = [&](int beam, int step) {
    const double r = static_cast<double>(scan.ranges[static_cast<std::size_t>(beam)]);
    for (int b = beam + step; b != beam + 3 * step; b += step) {
      if (b < 0 || b >= count) return false;
      const double beside = scan.ranges[static_cast<std::size_t>(b)];
      if (valid(beside) && beside < r - margin) return true;
    }
    return false;
  };
  for (Cluster* cl = first; cl != last; ++cl) {
    if (cl->beam_lo < 0) continue;
    cl->cut_lo = hidden(cl->beam_lo, -1);
    cl->cut_hi = hidden(cl->beam_hi, +1);
  }
}

// Step 3: a convex polygon per kept cluster.
void DepthObstacleDetector::outlineClusters(hal::ObstacleFrame& out) {
  out.count = 0;
  for (std::size_t i = 0; i < kept_; ++i) {
    hal::ObstacleFrame::Obstacle& o = out.obstacles[out.count++];
    o.n = outline(clusters_[order_[i]], o.vertices);
    o.velocity = Vec2::Zero();
    o.turn_rate = 0.0;
  }
}

std::size_t DepthObstacleDetector::outline(const Cluster& cluster, std::span<Vec2> out) {
  // Per grid row of the cluster, its leftmost and rightmost cell: the hull of those rows'
  // outer corners is the hull of every cell's corners.
  std::size_t rows = 0;
  for (std::uint32_t q = cluster.first; q < cluster.last; ++q) {
    const std::uint32_t k = queue_[q];
    const auto gx = static_cast<std::int32_t>(k % static_cast<std::uint32_t>(n_));
    const auto gy = static_cast<std::size_t>(k / static_cast<std::uint32_t>(n_));
    if (row_min_[gy] == kNoRow) rows_[rows++] = static_cast<std::int32_t>(gy);
    row_min_[gy] = std::min(row_min_[gy], gx);
    row_max_[gy] = std::max(row_max_[gy], gx);
  }
  const double cell = config_.cell_m;
  std::size_t m = 0;
  for (std::size_t r = 0; r < rows; ++r) {
    const auto gy = static_cast<std::size_t>(rows_[r]);
    const double x0 = origin_.x() + cell * row_min_[gy];
    const double x1 = origin_.x() + cell * (row_max_[gy] + 1);
    const double y0 = origin_.y() + cell * static_cast<double>(gy);
    const double y1 = y0 + cell;
    corners_[m++] = Vec2(x0, y0);
    corners_[m++] = Vec2(x1, y0);
    corners_[m++] = Vec2(x1, y1);
    corners_[m++] = Vec2(x0, y1);
    row_min_[gy] = kNoRow;
    row_max_[gy] = -1;
  }
  std::size_t hull_n = convexHullInPlace(std::span<Vec2>(corners_.data(), m), std::span<Vec2>(hull_));
  hull_n = growToFewerVertices(std::span<Vec2>(hull_), hull_n, config_.max_vertices);
  const Vec2 away = cluster.centroid - camera_map_;
  if (config_.hidden_depth_m > 0.0 && hull_n > 0 && away.norm() > 0.0) {
    // The side the camera cannot see: the outline and its copy shifted away from the camera.
    const Vec2 shift = away.normalized() * config_.hidden_depth_m;
    const std::size_t k = std::min(hull_n, extended_.size() / 2);
    for (std::size_t i = 0; i < k; ++i) {
      extended_[i] = hull_[i];
      extended_[k + i] = hull_[i] + shift;
    }
    hull_n = convexHullInPlace(std::span<Vec2>(extended_.data(), 2 * k), std::span<Vec2>(hull_));
    hull_n = growToFewerVertices(std::span<Vec2>(hull_), hull_n, config_.max_vertices);
  }
  hull_n = std::min(hull_n, out.size());
  std::copy_n(hull_.begin(), hull_n, out.begin());
  return hull_n;
}

// Step 4: clusters continue the nearest predicted track within the gate (greedy, closest
// pair first); a constant-velocity Kalman filter on the centroid gives the velocity.
void DepthObstacleDetector::trackClusters(rt::Nanos stamp, hal::ObstacleFrame& out) {
  if (last_stamp_ >= 0 && (stamp <= last_stamp_ ||
                           static_cast<double>(stamp - last_stamp_) * 1e-9 > config_.max_frame_gap_s)) {
    resetTracks();
  }
  const rt::Nanos previous_stamp = last_stamp_;  // -1 after a reset: no track is older
  last_stamp_ = stamp;

  std::array<Vec2, kMaxTracks> predicted{};
  std::array<bool, kMaxTracks> taken{};
  for (std::size_t t = 0; t < kMaxTracks; ++t) {
    if (!tracks_[t].live) continue;
    const double dt = static_cast<double>(stamp - tracks_[t].seen) * 1e-9;
    predicted[t] = tracks_[t].centroid + tracks_[t].velocity * dt;
  }
  for (std::size_t i = 0; i < kept_; ++i) clusters_[order_[i]].track = -1;

  // The gate: gate_m, grown with the uncertainty of a track unseen for a frame or more.
  std::array<double, kMaxTracks> gate2{};
  for (std::size_t t = 0; t < kMaxTracks; ++t) {
    if (!tracks_[t].live) continue;
    const double unseen = static_cast<double>(stamp - tracks_[t].seen) * 1e-9;
    const bool seen_last_frame = tracks_[t].seen >= previous_stamp;
    const double gate = config_.gate_m + (seen_last_frame ? 0.0 : growth(tracks_[t], unseen));
    gate2[t] = gate * gate;
  }
  for (;;) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_i = kept_, best_t = kMaxTracks;
    for (std::size_t i = 0; i < kept_; ++i) {
      const Cluster& cl = clusters_[order_[i]];
      if (cl.track >= 0) continue;
      for (std::size_t t = 0; t < kMaxTracks; ++t) {
        if (!tracks_[t].live || taken[t]) continue;
        const double d2 = (cl.centroid - predicted[t]).squaredNorm();
        if (d2 <= gate2[t] && d2 <= best) {
          best = d2;
          best_i = i;
          best_t = t;
        }
      }
    }
    if (best_i == kept_) break;
    Cluster& cl = clusters_[order_[best_i]];
    Track& tr = tracks_[best_t];
    taken[best_t] = true;
    cl.track = static_cast<int>(best_t);
    const double dt = static_cast<double>(stamp - tr.seen) * 1e-9;
    const Vec2 velocity_before = tr.velocity;
    const FreeEnd end = freeEnd(cl);
    filterCentroid(tr, cl.centroid, dt, cl.cut() ? config_.truncated_noise_m : config_.centroid_noise_m, end.across);
    followFreeEnd(tr, end, stamp);
    filterTurnRate(tr, velocity_before, dt);
    tr.seen = stamp;
    tr.missed = 0;
    ++tr.hits;
  }

  // New clusters start tracks at rest; every seen track keeps its outline.
  for (std::size_t i = 0; i < kept_; ++i) {
    Cluster& cl = clusters_[order_[i]];
    hal::ObstacleFrame::Obstacle& o = out.obstacles[i];
    if (cl.track < 0) {
      for (std::size_t t = 0; t < kMaxTracks; ++t) {
        if (tracks_[t].live) continue;
        // At rest, its position known to the centroid's noise, its velocity to about half the
        // largest speed.
        const double r = cl.cut() ? config_.truncated_noise_m : config_.centroid_noise_m;
        const double v = 0.5 * config_.max_speed_mps;
        tracks_[t] = Track{true, cl.centroid, Vec2::Zero(), r * r, 0.0, v * v, stamp, 0, 0.0, 1};
        followFreeEnd(tracks_[t], freeEnd(cl), stamp);
        cl.track = static_cast<int>(t);
        break;
      }
    }
    o.unseen_s = 0.0;
    if (cl.track < 0) {  // every track taken: reported, not tracked
      o.velocity = Vec2::Zero();
      o.turn_rate = 0.0;
      continue;
    }
    Track& tr = tracks_[static_cast<std::size_t>(cl.track)];
    o.velocity = tr.velocity;
    o.turn_rate = tr.turn_rate;
    tr.outline_n = std::min(o.n, tr.outline.size());
    for (std::size_t v = 0; v < tr.outline_n; ++v) tr.outline[v] = o.vertices[v] - tr.centroid;
    if (config_.uncertainty_horizon_s > 0.0) {
      const double r = std::min(config_.max_growth_m, std::sqrt(std::max(0.0, tr.p11)) * config_.uncertainty_horizon_s);
      growOutline(std::span<Vec2>(o.vertices.data(), o.n), clearOfSelf(std::span<const Vec2>(o.vertices.data(), o.n), r));
    }
  }
}

double DepthObstacleDetector::clearOfSelf(std::span<const Vec2> outline, double r) const {
  if (!(config_.self_clearance_m > 0.0) || outline.size() < 3) return r;
  const PolygonView poly(outline.data(), outline.size());
  const double away = locatePoint(robot_, poly) == Containment::kOutside ? distanceToEdges(robot_, poly) : 0.0;
  return std::max(0.0, std::min(r, away - config_.self_clearance_m));
}

double DepthObstacleDetector::growth(const Track& track, double t) const {
  const double sigma_v = std::sqrt(std::max(0.0, track.p11));
  return std::min(config_.max_growth_m, sigma_v * t + 0.5 * config_.acceleration_mps2 * t * t);
}

bool DepthObstacleDetector::inView(const hal::DepthFrame& frame, const Pose2& robot, const Vec2& p) const {
  if (scanSees(p)) return true;
  // Margins: a place this near an end of the range or an edge of the image may be seen or not.
  constexpr double kRangeMargin = 0.3;  // m
  constexpr double kEdgePixels = 8.0;
  const hal::CameraIntrinsics& k = camera_.intrinsics();
  const double c = std::cos(robot.theta), s = std::sin(robot.theta);
  const Vec2 d = p - robot.position();
  const Vec3 base(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), 0.0);
  const double horizontal = (base.head<2>() - frame_camera_.head<2>()).norm();
  if (horizontal > config_.max_range_m - kRangeMargin) return false;
  const int stride = config_.pixel_stride;
  // Two heights of a body standing there (people, robots, furniture reach 0.8 m): seen when
  // either is in the image and nothing nearer is in front of it.
  for (const double h : {0.3, 0.8}) {
    const double z = std::clamp(h, config_.min_height_m, config_.max_height_m);
    const Vec3 body = frame_rotation_.transpose() * (Vec3(base.x(), base.y(), z) - frame_camera_);
    const double depth = body.x();
    if (!(depth > config_.min_depth_m + kRangeMargin)) continue;
    const double u = k.cx - k.fx * body.y() / depth;
    const double v = k.cy - k.fy * body.z() / depth;
    if (!(u >= kEdgePixels && u < hal::DepthFrame::kWidth - kEdgePixels && v >= kEdgePixels &&
          v < hal::DepthFrame::kHeight - kEdgePixels)) {
      continue;
    }
    // The nearest pixel perception samples (stride / 2 + i * stride).
    const auto sampled = [stride](double x, int size) {
      const int i = static_cast<int>(std::lround((x - stride / 2) / stride));
      return std::clamp(stride / 2 + i * stride, 0, size - 1);
    };
    const int su = sampled(u, hal::DepthFrame::kWidth), sv = sampled(v, hal::DepthFrame::kHeight);
    const std::uint16_t mm = frame.depth_mm[static_cast<std::size_t>(sv) * hal::DepthFrame::kWidth +
                                            static_cast<std::size_t>(su)];
    if (mm != 0 && static_cast<double>(mm) * 1e-3 < depth - config_.gate_m) continue;  // hidden
    return true;
  }
  return false;
}

// Step 5: tracks not seen this frame. In view they are forgotten after max_missed_frames;
// out of view (confirmed ones) after keep_unseen_s, except a standing one in the camera's
// near blind zone, which stays while it is there (the robot beside it cannot see it, and has
// not left it). Until then they are reported at their predicted place, their outline grown
// with the uncertainty, but never over the robot itself (self_clearance_m from the base
// centre): an outline predicted into the robot is not there (the robot would have met it)
// and is forgotten.
void DepthObstacleDetector::keepUnseenTracks(const hal::DepthFrame& frame, const Pose2& robot,
                                             hal::ObstacleFrame& out) {
  constexpr double kNearZoneMargin = 0.3;  // m beyond min_depth_m: about where readings begin
  const rt::Nanos stamp = frame.stamp;
  for (Track& tr : tracks_) {
    if (!tr.live || tr.seen == stamp) continue;
    const double unseen = static_cast<double>(stamp - tr.seen) * 1e-9;
    const Vec2 predicted = tr.centroid + tr.velocity * unseen;
    const bool keep = config_.keep_unseen_s > 0.0 && tr.hits >= config_.confirm_frames;
    if (keep && !inView(frame, robot, predicted)) {
      const bool near_standing = tr.velocity.norm() < config_.turn_min_speed_mps &&
                                 (predicted - camera_map_).norm() < config_.min_depth_m + kNearZoneMargin;
      if (unseen > config_.keep_unseen_s && !near_standing) {
        tr = Track{};
        continue;
      }
    } else if (++tr.missed > config_.max_missed_frames) {
      tr = Track{};
      continue;
    }
    if (tr.outline_n < 3) continue;
    if (out.count == hal::ObstacleFrame::kMaxObstacles) {
      ++out.dropped;
      continue;
    }
    hal::ObstacleFrame::Obstacle& o = out.obstacles[out.count];
    o.n = tr.outline_n;
    for (std::size_t v = 0; v < o.n; ++v) o.vertices[v] = tr.outline[v] + predicted;
    double r = growth(tr, unseen);
    if (config_.self_clearance_m > 0.0) {
      const PolygonView outline(o.vertices.data(), o.n);
      const double away = locatePoint(robot.position(), outline) == Containment::kOutside
                              ? distanceToEdges(robot.position(), outline)
                              : 0.0;
      if (away < config_.self_clearance_m) {
        tr = Track{};
        continue;
      }
      r = std::min(r, away - config_.self_clearance_m);
    }
    growOutline(std::span<Vec2>(o.vertices.data(), o.n), r);
    o.velocity = tr.velocity;
    o.turn_rate = tr.turn_rate;
    o.unseen_s = unseen;
    ++out.count;
  }
}

void growOutline(std::span<Vec2> p, double r) {
  const std::size_t n = p.size();
  if (!(r > 0.0) || n < 3) return;
  // Each vertex moves to where its two edges, each moved out by r, meet (the mitre), at most
  // 4 r out (a corner sharper than about 30 degrees is cut there).
  std::array<Vec2, hal::ObstacleFrame::kMaxVertices> normal{};
  const std::size_t m = std::min(n, normal.size());
  for (std::size_t i = 0; i < m; ++i) {
    const Vec2 e = p[(i + 1) % m] - p[i];
    const double len = e.norm();
    normal[i] = len > 0.0 ? Vec2(Vec2(e.y(), -e.x()) / len) : Vec2(0.0, 0.0);
  }
  for (std::size_t i = 0; i < m; ++i) {
    const Vec2 a = normal[(i + m - 1) % m], b = normal[i];
    const Vec2 sum = a + b;
    const double denom = 1.0 + a.dot(b);
    // The mitre is r * |a + b| / (1 + a.b) out: more than 4 r when 1 + a.b < 1/8.
    Vec2 offset = sum * (r / std::max(denom, 1.0 / 8.0));
    if (denom < 1.0 / 8.0) {
      const double len = sum.norm();
      offset = len > 0.0 ? Vec2(sum * (4.0 * r / len)) : Vec2(a * r);
    }
    p[i] += offset;
  }
}

std::size_t growToFewerVertices(std::span<Vec2> p, std::size_t n, std::size_t max_n) {
  max_n = std::max<std::size_t>(max_n, 4);
  n = std::min(n, p.size());
  while (n > max_n) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_i = n;
    Vec2 best_point(0.0, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2& prev = p[(i + n - 1) % n];
      const Vec2& a = p[i];
      const Vec2& b = p[(i + 1) % n];
      const Vec2& next = p[(i + 2) % n];
      const Vec2 da = a - prev, db = next - b;
      const double den = cross(da, db);
      // The neighbours' lines must meet beyond the edge (together they turn less than pi).
      if (!(den > 1e-12 * da.norm() * db.norm())) continue;
      const double s = cross(b - a, db) / den;
      if (s < 0.0) continue;
      const Vec2 meet = a + s * da;
      const double added = 0.5 * std::abs(cross(b - a, meet - a));
      if (added < best) {
        best = added;
        best_i = i;
        best_point = meet;
      }
    }
    if (best_i == n) break;  // no edge can go (not for a convex polygon of > 4 vertices)
    p[best_i] = best_point;
    const std::size_t gone = (best_i + 1) % n;
    for (std::size_t k = gone; k + 1 < n; ++k) p[k] = p[k + 1];
    --n;
  }
  return n;
}

}  // namespace staa
